"""Targets (issue 31, item 1): every output is one target of one registry; ``--targets`` chooses them, an unknown
name is exit 2 naming the known ones with nothing written, and a new target is one registration away."""
import json

import pytest

from aggsym.cli import main
from aggsym.codegen.targets import TARGETS, Target, register, unregister
from aggsym.codegen.targets.base import environment

MODEL = "models/double_pendulum.yaml"


class TextTarget(Target):
    """A small extra target: NAME.txt, one line per routine with its outputs' names and its C's operation count,
    and the number of named temporaries its straight line holds (printed per routine, the hook a real target
    prints its code in)."""

    name = "text"

    def file_names(self, job):
        return [f"{job.model.name}.txt"]

    def owns(self, name, file):
        return file == f"{name}.txt"

    def print_routine(self, model, prog, lines, emitted):
        return len(lines.sl.temps)

    def render(self, job):
        template = environment().from_string(
            "{% for r in routines %}{{ r.symbol }}: {{ r.routine.outputs | map(attribute='name') | join(', ') }}; "
            "ops {{ r.ops.mul + r.ops.add + r.ops.div + r.ops.call }}; temps {{ r.bodies.text }}\n{% endfor %}")
        return {f"{job.model.name}.txt": template.render(routines=job.emitted)}


@pytest.fixture
def text_target():
    target = register(TextTarget())
    yield target
    unregister(target.name)


def test_the_builtin_targets_are_registered():
    assert list(TARGETS)[:4] == ["c", "numpy", "manifest", "latex"]


def test_an_extra_target_is_one_registration(tmp_path, text_target):
    out = tmp_path / "dp"
    assert main(["generate", MODEL, "-q", "--targets", "text,manifest", "-o", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["double_pendulum.json", "double_pendulum.txt"]
    manifest = json.loads((out / "double_pendulum.json").read_text())
    lines = (out / "double_pendulum.txt").read_text().splitlines()
    assert len(lines) == len(manifest["functions"])
    first = lines[0]
    assert first.startswith("double_pendulum_inertia: A; ops ")
    ops = manifest["ops"]["inertia"]
    assert f"ops {ops['mul'] + ops['add'] + ops['div'] + ops['call']};" in first
    assert int(first.rsplit("temps ", 1)[1]) >= 0


def test_an_extra_target_is_not_in_the_default_set(tmp_path, text_target):
    out = tmp_path / "dp"
    assert main(["generate", MODEL, "-q", "--targets", "numpy", "-o", str(out)]) == 0
    assert [p.name for p in out.iterdir()] == ["double_pendulum.py"]


def test_targets_c_writes_only_the_c_files(tmp_path):
    out = tmp_path / "dp"
    assert main(["generate", MODEL, "-q", "--targets", "c", "-o", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["double_pendulum.c", "double_pendulum.h"]
    full = tmp_path / "full"
    assert main(["generate", MODEL, "-q", "-o", str(full)]) == 0
    for name in ("double_pendulum.c", "double_pendulum.h"):  # the same text as with every target
        assert (out / name).read_text() == (full / name).read_text()


def test_targets_c_with_split_writes_only_the_split_files(tmp_path):
    out = tmp_path / "dp"
    assert main(["generate", MODEL, "-q", "--split", "--targets", "c", "-o", str(out)]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert "Makefile" in names and "double_pendulum.h" in names and "double_pendulum_inertia.c" in names
    assert not [n for n in names if n.endswith((".py", ".json", ".tex")) or n == "double_pendulum.c"]


def test_targets_numpy_writes_only_the_module(tmp_path):
    out = tmp_path / "dp"
    assert main(["generate", MODEL, "-q", "--targets", "numpy", "-o", str(out)]) == 0
    assert [p.name for p in out.iterdir()] == ["double_pendulum.py"]
    full = tmp_path / "full"
    assert main(["generate", MODEL, "-q", "-o", str(full)]) == 0
    assert (out / "double_pendulum.py").read_text() == (full / "double_pendulum.py").read_text()


def test_numpy_alone_prints_the_module_of_float_c_alike(tmp_path):
    """The module shares the C's text only as an optimisation: with float C it is printed on its own, the same."""
    a, b = tmp_path / "a", tmp_path / "b"
    assert main(["generate", MODEL, "-q", "--targets", "numpy", "-o", str(a)]) == 0
    assert main(["generate", MODEL, "-q", "--targets", "numpy", "--scalar", "float", "-o", str(b)]) == 0
    assert (a / "double_pendulum.py").read_text() == (b / "double_pendulum.py").read_text()


@pytest.mark.parametrize("spec", ["bogus", "c,bogus", ""])
def test_an_unknown_target_is_exit_2_naming_the_known_ones(tmp_path, capsys, spec):
    out = tmp_path / "dp"
    assert main(["generate", MODEL, "-q", "--targets", spec, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "c, numpy, manifest, latex" in err and "--targets" in err
    assert not out.exists() and not list(tmp_path.iterdir())


def test_a_partial_generation_leaves_the_other_targets_files(tmp_path):
    out = tmp_path / "dp"
    assert main(["generate", MODEL, "-q", "--split", "-o", str(out)]) == 0
    assert main(["generate", MODEL, "-q", "--targets", "c", "-o", str(out)]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert "double_pendulum.c" in names and "double_pendulum_inertia.c" not in names  # stale split C removed
    assert {"double_pendulum.py", "double_pendulum.json", "double_pendulum.tex"} <= set(names)  # others kept


def test_check_has_one_column_per_target_run(capsys):
    assert main(["check", MODEL, "--trials", "2", "--targets", "numpy"]) == 0
    header = capsys.readouterr().out.splitlines()[1].split()
    assert header == ["routine", "NumPy"]
    assert main(["check", MODEL, "--trials", "2", "--targets", "bogus"]) == 2
