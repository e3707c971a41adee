"""The README's quickstart (issue 35, item 1): its shell commands run verbatim in a fresh clone of the repository,
and the controller they build, ``examples/controller.c`` (shown in the README as it is on disk), ends where a
simulation of the same loop on Pinocchio's model of ``models/arm3.urdf`` ends."""
import json
import os
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

from conftest import ROOT

README = ROOT / "README.md"
CONTROLLER = ROOT / "examples" / "controller.c"
TARGET = np.array([0.5, -0.8, 1.2])


def quickstart_commands() -> str:
    """The first ``sh`` block of the README's section "Quickstart"."""
    section = README.read_text().split("## Quickstart", 1)[1].split("\n## ", 1)[0]
    return re.search(r"```sh\n(.*?)```", section, re.S).group(1)


def printed_q(out: str) -> np.ndarray:
    return np.array([float(x) for x in re.findall(r"q\[\d\] = *(-?[\d.]+)", out)])


def pinocchio_run() -> np.ndarray:
    """The controller's loop written again in Python on Pinocchio's model (the same PD law, gravity from
    ``computeGeneralizedGravity``, the damping from ``model.damping``, ``aba``, semi-implicit Euler)."""
    import pinocchio as pin

    pm = pin.buildModelFromUrdf(str(ROOT / "models" / "arm3.urdf"))
    data = pm.createData()
    q, qd, dt = np.zeros(3), np.zeros(3), 1e-3
    for _ in range(3000):
        tau = pin.computeGeneralizedGravity(pm, data, q) + 60.0 * (TARGET - q) - 12.0 * qd
        qdd = pin.aba(pm, data, q, qd, tau - pm.damping * qd)
        qd = qd + dt * qdd
        q = q + dt * qd
    return q


def test_the_readme_shows_the_controller_as_it_is_on_disk():
    assert CONTROLLER.read_text() in README.read_text()


def test_the_quickstart_python_lines_run(tmp_path):
    """The README's Python snippet, against arm3 generated into the folder it names."""
    import aggsym
    from aggsym.codegen.generate import write

    write(aggsym.generate(aggsym.load(ROOT / "models" / "arm3.urdf")), tmp_path / "build" / "arm3")
    section = README.read_text().split("## Quickstart", 1)[1].split("\n## ", 1)[0]
    snippet = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    out = subprocess.run([sys.executable, "-c", snippet + "\nimport json; print(json.dumps(qdd.tolist()))"], cwd=tmp_path,
                         check=True, capture_output=True, text=True).stdout
    assert np.abs(np.array(json.loads(out.strip().splitlines()[-1]))).max() < 1e-12


@pytest.mark.slow
@pytest.mark.compiler
@pytest.mark.pinocchio
def test_the_quickstart_commands_run_verbatim_in_a_fresh_clone(tmp_path):
    """``git clone`` of this repository, then the README's commands as written (``make install`` included: a
    new .venv), under ``bash -e``: the controller holds the arm at its target, where Pinocchio's simulation of the
    same loop ends (1e-8; the program prints 9 decimals)."""
    if not (ROOT / ".git").exists():
        pytest.fail("the quickstart test clones the repository: run it from a git checkout")
    clone = tmp_path / "aggsym"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    # the working tree's README and example, so that an uncommitted edit is what is tested
    shutil.copy(README, clone / "README.md")
    shutil.copy(CONTROLLER, clone / "examples" / "controller.c")
    shutil.copy(ROOT / "models" / "arm3.urdf", clone / "models" / "arm3.urdf")
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH")}
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep) if "/.venv" not in p)
    run = subprocess.run(["bash", "-euo", "pipefail", "-c", quickstart_commands()], cwd=clone, env=env,
                         capture_output=True, text=True, timeout=1200)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-4000:]
    assert (clone / ".venv" / "bin" / "aggsym").exists()
    q = printed_q(run.stdout)
    assert q.shape == (3,)
    assert np.abs(q - TARGET).max() < 1e-5
    assert np.abs(q - pinocchio_run()).max() < 1e-8
