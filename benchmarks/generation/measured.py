"""Section 1: generation time and peak memory of a full ``aggsym generate``, and KanesMethod beside it.

Each ``aggsym generate MODEL -o OUT`` (every routine; C, NumPy, LaTeX and the manifest) runs in a fresh
``python -m aggsym`` process: the wall time includes the interpreter's start and the imports, as a user sees
it; the CPU time and the peak resident set are the child's own (``os.wait4``).  The stage times (recursions,
printing, templates, latex) are the ones ``aggsym generate`` reports on stderr.
"""
from __future__ import annotations

import json
import re
from pathlib import Path

from ..harness.generate import aggsym_generate
from ..harness.measure import child_env, python, run_measured

STAGE = re.compile(r"^aggsym: [^:]+: (recursions|printing|templates|latex): ([0-9.]+) s$")
TOTAL = re.compile(r"^aggsym: [^:]+: wrote \d+ files to .* in ([0-9.]+) s$")


def generate_measured(label: str, model_path, outdir, timeout: float | None = None,
                      routines: str | None = None, options=()) -> dict:
    """One full ``aggsym generate`` in a fresh process; returns its measurements and the manifest.  ``routines``:
    the value of ``--routines`` (default: none given, the default set); ``options``: further arguments (e.g.
    ``--floating-base quaternion --name ur5_ff``)."""
    outdir = Path(outdir)
    extra = (["--routines", routines] if routines else []) + list(options)
    if "--name" not in extra:  # the code named after the label (the CLI names a URDF robot's after its file)
        extra += ["--name", label]
    run = aggsym_generate(model_path, outdir, *extra, timeout=timeout)
    stages, internal = {}, None
    for line in run.stderr.splitlines():
        m = STAGE.match(line)
        if m:
            stages[m.group(1)] = float(m.group(2))
        m = TOTAL.match(line)
        if m:
            internal = float(m.group(1))
    result = {"label": label, "model": str(model_path), "outdir": str(outdir), "routines": routines, "ok": run.ok,
              "timed_out": run.timed_out, "returncode": run.returncode, "wall_seconds": run.wall_seconds,
              "cpu_seconds": run.cpu_seconds, "maxrss_kib": run.maxrss_kib, "stages": stages,
              "internal_seconds": internal}
    if not run.ok:
        result["stderr"] = run.stderr[-2000:]
        return result
    manifests = list(outdir.glob("*.json"))
    manifest = json.loads(manifests[0].read_text())
    result.update({"name": manifest["name"], "nq": manifest["nq"], "bodies": manifest.get("bodies"),
                   "ops": manifest["ops"], "functions": manifest["functions"],
                   "c_bytes": sum(p.stat().st_size for p in outdir.glob("*.c")),
                   "files": sorted(p.name for p in outdir.iterdir())})
    return result


def kane_measured(model_path, out_json, timeout: float, hard_timeout: float | None = None) -> dict:
    """KanesMethod + CSE on one model in a fresh process (``python -m benchmarks.generation.kane``).

    The timeout applies to the timed part (equations and CSE); once the child has written its timing, the
    untimed operation count and check may go on until ``hard_timeout``."""
    out_json = Path(out_json)
    out_json.parent.mkdir(parents=True, exist_ok=True)
    out_json.unlink(missing_ok=True)

    def timed_part_done(_elapsed):
        try:
            return "seconds" in json.loads(out_json.read_text())
        except (OSError, ValueError):
            return False

    run = run_measured([python(), "-m", "benchmarks.generation.kane", str(model_path), str(out_json)],
                       timeout=timeout, env=child_env(), poll=timed_part_done,
                       hard_timeout=hard_timeout if hard_timeout is not None else 3 * timeout)
    try:
        data = json.loads(out_json.read_text())
    except (OSError, ValueError):
        data = {}
    finished = "seconds" in data and data["seconds"] <= timeout
    crashed = not data and not run.timed_out  # ended without a timing: an error, not the timeout
    result = {"model": str(model_path), "finished": finished, "wall_seconds": run.wall_seconds,
              "cpu_seconds": run.cpu_seconds, "process_maxrss_kib": run.maxrss_kib, "timeout": timeout,
              "killed": run.timed_out, **data}
    if not finished:
        result["exceeded"] = not crashed
        result["failed"] = crashed
        if not data:
            result["seconds"] = None
    if run.returncode not in (0, None) and not run.timed_out:
        result["stderr"] = run.stderr[-2000:]
    return result
