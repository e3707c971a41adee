"""The pipeline from a model file to the model generated from (aggsym/pipeline.py): ``aggsym.load(path, **options)``
then ``aggsym.generate`` writes what ``aggsym generate path --options`` writes; the routine selection judges the
model every other option made (``--armature`` with ``--routines``); one table of options builds the command line and
says which readers take what; the file is sniffed once and a model's tree built once per generation."""
import filecmp
import subprocess
import sys

import numpy as np
import pytest

import aggsym
from aggsym import cli, pipeline
from aggsym.codegen.generate import generate, write
from aggsym.errors import AggsymError
from aggsym.model.readers import registry
from aggsym.model.tree import Tree
from conftest import model_path
from helpers import TOLERANCE, relative_error, robot_path, run_cli
from pinocchio_reference import pin, pinocchio_model, pinocchio_q

HAND = model_path("double_pendulum").parent.parent / "tests" / "data" / "massless_finger.urdf"
XACRO = HAND.parent / "xacro" / "arm.urdf.xacro"


def _flags(options: dict) -> list:
    """The command line of ``options`` (aggsym.load's keywords), through the pipeline's table."""
    out = []
    for name, value in options.items():
        flag = pipeline.BY_NAME[name].flag
        if value is True:
            out.append(flag)
        elif isinstance(value, dict):
            sep = ":=" if name == "xacro_args" else "="
            for k, v in value.items():
                out += [flag, f"{k}{sep}{v}"]
        else:
            out += [flag, ",".join(value) if isinstance(value, list) else str(value)]
    return out


CASES = {
    "urdf": (lambda: robot_path("ur5"), {"floating_base": "quaternion", "armature": 0.01, "payload": "tool0",
                                         "gravity_parameter": True, "frames": ["tool0", "base_link"],
                                         "routines": ["inertia", "forward_dynamics", "frame_poses"]}),
    "xacro": (lambda: XACRO, {"xacro_args": {"length": "0.41237", "prefix": "left_"}, "floating_base": "euler",
                              "passive": "include", "armature": 0.125,
                              "routines": "default"}),
    "yaml": (lambda: model_path("double_pendulum"), {"armature": 0.0625, "name": "swing"}),
}


@pytest.mark.parametrize("case", CASES)
def test_the_python_api_writes_what_the_command_line_writes(case, tmp_path):
    """The same options by keyword and by flag give the same files, byte for byte (the names included: a URDF's
    code is named after its file, whatever its ``<robot name>``)."""
    path, options = CASES[case][0](), CASES[case][1]
    code, err = run_cli(["generate", str(path), *_flags(options), "-q", "-o", str(tmp_path / "cli")])
    assert code == 0, err
    prepared = pipeline.prepare(path, **options)
    write(generate(prepared.model), tmp_path / "api", prepared.name_origin)
    files = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert files == sorted(p.name for p in (tmp_path / "api").iterdir()) and len(files) >= 4
    match, mismatch, errors = filecmp.cmpfiles(tmp_path / "cli", tmp_path / "api", files, shallow=False)
    assert not mismatch and not errors, (mismatch, errors)
    assert aggsym.load(path, **options) == prepared.model  # (aggsym.load: the pipeline's model)


@pytest.mark.pinocchio
def test_armature_with_named_routines_is_judged_after_it(tmp_path):
    """A(q) singular at the default parameters: ``--routines forward_dynamics`` is refused with the hint to add
    ``--armature VALUE``; with it, forward dynamics is generated and equals Pinocchio's ``aba`` with that armature
    (the selection used to run before the armature was applied, and refused either way)."""
    code, err = run_cli(["generate", str(HAND), "--routines", "forward_dynamics", "-o", str(tmp_path / "no")])
    assert code == 2 and "--armature VALUE" in err and "finger_joint" in err
    assert not (tmp_path / "no").exists()
    value = 0.0123
    code, err = run_cli(["generate", str(HAND), "--routines", "forward_dynamics,inertia", "--armature", str(value),
                         "--targets", "numpy,manifest", "-q", "-o", str(tmp_path / "yes")])
    assert code == 0, err
    from aggsym.codegen.compile import import_module

    module = import_module(tmp_path / "yes" / "massless_finger.py")
    pm = pinocchio_model(HAND)
    pm.armature = np.full(pm.nv, value)
    data = pm.createData()
    rng = np.random.default_rng(11)
    for _ in range(4):
        q, qd, tau = rng.normal(size=(3, pm.nv))
        Q = pinocchio_q(pm, q)
        assert relative_error(module.forward_dynamics(q, qd, tau), pin.aba(pm, data, Q, qd, tau)) <= TOLERANCE
    with pytest.raises(AggsymError, match="--armature VALUE"):
        aggsym.load(HAND, routines=["forward_dynamics"])
    assert aggsym.load(HAND, routines=["forward_dynamics"], armature=value).routines == ("forward_dynamics",)


def test_the_table_builds_the_command_line_and_the_readers_options():
    """Every option of the table is a flag of each command, whose help opens with the readers that take it; a
    reader takes an option of its load exactly when its load names it."""
    parser = cli._parser()
    for command in ("generate", "latex", "check", "ops"):
        sub = parser._subparsers._group_actions[0].choices[command]
        flags = {f for a in sub._actions for f in a.option_strings}
        assert {o.flag for o in pipeline.OPTIONS} <= flags
    for option in pipeline.OPTIONS:
        who = pipeline.takers(option)
        for reader in registry.READERS:
            assert pipeline.accepts(reader, option) == (who is None or reader.name in who)
            if option.readers == pipeline.READ:
                assert pipeline.accepts(reader, option) == (option.name in reader.options)
    assert pipeline.takers(pipeline.BY_NAME["xacro_args"]) == ["xacro"]
    assert pipeline.takers(pipeline.BY_NAME["frictionloss"]) == ["MJCF"]
    assert pipeline.takers(pipeline.BY_NAME["armature"]) is None


@pytest.mark.parametrize("option", [o for o in pipeline.OPTIONS if pipeline.takers(o) is not None
                                    and "YAML" not in pipeline.takers(o)])
def test_each_option_a_reader_does_not_take_is_refused_by_name(option):
    """An option the YAML reader does not take, on the command line: exit 2 naming the reader and the flag."""
    value = {"store_true": []}.get(option.cli.get("action"))
    args = [option.flag] if value is not None else [option.flag, _a_value(option)]
    proc = subprocess.run([sys.executable, "-m", "aggsym", "ops", str(model_path("double_pendulum")), *args],
                          capture_output=True, text=True)
    assert proc.returncode == 2 and f"the YAML reader does not accept {option.flag}" in proc.stderr, proc.stderr
    assert "Traceback" not in proc.stderr


def _a_value(option) -> str:
    if "choices" in option.cli:
        return list(option.cli["choices"])[-1]
    return {"--snap-angles": "1e-4", "--xacro-arg": "a:=1", "--package-path": "p=/tmp"}.get(option.flag, "x")


def test_the_file_is_sniffed_once_and_the_tree_built_once(tmp_path, monkeypatch):
    """A ``.xml`` URDF: its reader sniffs it once; one generation builds one tree per model object (the internal
    models of the recursions have trees of their own)."""
    urdf = tmp_path / "arm.xml"
    urdf.write_bytes(robot_path("ur5").read_bytes())
    sniffed = []
    monkeypatch.setattr(registry, "READERS", [
        registry.Reader(r.name, r.suffixes, r.load, r.options, r.sniffed,
                        None if r.sniff is None else (lambda head, f=r.sniff: sniffed.append(1) or f(head)), r.note)
        for r in registry.READERS])
    model = aggsym.load(urdf, armature=0.5)
    assert len(sniffed) == 1 and model.name == "arm"
    built = []
    real = Tree.__init__

    def counting(self, m):
        built.append(id(m))
        real(self, m)
    monkeypatch.setattr(Tree, "__init__", counting)
    generate(model, targets="c,numpy,manifest")
    assert built.count(id(model)) == 1, len(built)
