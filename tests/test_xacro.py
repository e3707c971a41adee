"""The xacro reader: two xacro robots of tests/data/xacro expanded and generated, equal to the URDF the xacro
package's own command line expands them to; its errors (exit 2, the xacro file named); hostile files refused.

* ``arm.urdf.xacro``: a macro per link, the upper arm's length an argument without default (``--xacro-arg
  length:=...``), the names prefixed by the argument ``prefix``.
* ``scara/robot.urdf.xacro``: its macros included from ``$(find parts)`` (``--package-path parts=...``, or
  ``ROS_PACKAGE_PATH``).
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import aggsym
from aggsym.cli import main
from aggsym.codegen.compile import import_module
from helpers import relative_error

pytest.importorskip("xacro")

DATA = Path(__file__).parent / "data" / "xacro"
ARM = DATA / "arm.urdf.xacro"
SCARA = DATA / "scara" / "robot.urdf.xacro"
PARTS = DATA / "parts"
TOL = 1e-12


def xacro_command(source: Path, out: Path, *mappings) -> Path:
    """The URDF the xacro package's command line writes (unpatched: no find, no checks), as the reference."""
    subprocess.run([sys.executable, "-c", "import sys, xacro; sys.argv[0] = 'xacro'; xacro.main()", str(source),
                    *mappings, "-o", str(out)], check=True, capture_output=True, timeout=60)
    return out


def same_dynamics(model, reference, seed=0):
    """A(q), b + g and the forward dynamics of the two models agree at random states."""
    a, b, rng = aggsym.NumericTwin(model), aggsym.NumericTwin(reference), np.random.default_rng(seed)
    assert model.nq == reference.nq
    for _ in range(3):
        q, qd, tau = rng.uniform(-np.pi, np.pi, (3, model.nq))
        assert relative_error(a.inertia(q), b.inertia(q)) <= TOL
        assert relative_error(a.bias(q, qd) + a.gravity(q), b.bias(q, qd) + b.gravity(q)) <= TOL
        assert relative_error(a.forward_dynamics(q, qd, tau), b.forward_dynamics(q, qd, tau)) <= TOL


@pytest.fixture
def scara_expanded(tmp_path):
    """The scara expanded by the package's command line, ``$(find parts)`` written out beforehand."""
    text = SCARA.read_text().replace("$(find parts)", str(PARTS.resolve()))
    source = tmp_path / "robot.urdf.xacro"
    source.write_text(text)
    return xacro_command(source, tmp_path / "scara.urdf")


def test_arm_with_argument_equals_the_expanded_urdf(tmp_path):
    model = aggsym.load(ARM, xacro_args={"length": "0.45"})
    reference = aggsym.load(xacro_command(ARM, tmp_path / "arm.urdf", "length:=0.45"))
    assert [c.name for c in model.coordinates] == ["arm_yaw", "arm_shoulder", "arm_elbow"]
    same_dynamics(model, reference)
    other = aggsym.load(ARM, xacro_args={"length": "0.3", "prefix": "left_"})
    assert [c.name for c in other.coordinates] == ["left_yaw", "left_shoulder", "left_elbow"]
    q = np.full(3, 0.7)
    assert not np.allclose(aggsym.NumericTwin(other).inertia(q), aggsym.NumericTwin(model).inertia(q))


def test_scara_with_package_path_equals_the_expanded_urdf(scara_expanded):
    model = aggsym.load(SCARA, package_paths={"parts": str(PARTS)})
    same_dynamics(model, aggsym.load(scara_expanded), seed=1)


def test_scara_with_ros_package_path(scara_expanded, monkeypatch):
    monkeypatch.setenv("ROS_PACKAGE_PATH", os.pathsep.join(["/nonexistent", str(DATA)]))
    same_dynamics(aggsym.load(SCARA), aggsym.load(scara_expanded), seed=2)


def test_generate_arm_numpy(tmp_path, capsys):
    """``aggsym generate`` with --xacro-arg and a URDF option: the NumPy module's A equals the expanded URDF's."""
    out = tmp_path / "out"
    assert main(["generate", str(ARM), "--xacro-arg", "length:=0.45", "--floating-base", "--targets", "numpy",
                 "-o", str(out), "-q"]) == 0
    module = import_module(out / "arm.py")  # (named after arm.urdf.xacro, not its <robot name="xacro_arm">)
    reference = aggsym.NumericTwin(aggsym.load(xacro_command(ARM, tmp_path / "arm.urdf", "length:=0.45"),
                                               floating_base=True))
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = rng.uniform(-np.pi, np.pi, 9)
        assert relative_error(np.asarray(module.inertia(q)).reshape(9, 9), reference.inertia(q)) <= TOL


def test_generate_scara_is_deterministic(tmp_path):
    for folder in ("a", "b"):
        assert main(["generate", str(SCARA), "--package-path", f"parts={PARTS}", "--targets", "numpy,manifest",
                     "-o", str(tmp_path / folder), "-q"]) == 0
    for name in ("robot.py", "robot.json"):  # (named after robot.urdf.xacro)
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


# errors ---------------------------------------------------------------------------------------------------------


def refused(capsys, args, *words):
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "internal error" not in err
    for word in words:
        assert word in err, err
    return err


def write(folder: Path, name: str, body: str) -> Path:
    path = folder / name
    path.write_text('<?xml version="1.0"?>\n<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="r">\n'
                    + body + "\n</robot>\n")
    return path


def test_missing_argument(capsys):
    refused(capsys, ["ops", str(ARM)], str(ARM), "Undefined substitution argument length", "macro 'rod'")


def test_unknown_macro(tmp_path, capsys):
    path = write(tmp_path, "m.urdf.xacro", '<link name="a"/>\n<xacro:nothing name="x"/>')
    refused(capsys, ["ops", str(path)], str(path), "unknown macro name: xacro:nothing")


def test_unknown_package(tmp_path, capsys):
    refused(capsys, ["ops", str(SCARA)], str(SCARA), "$(find parts): package 'parts' not found",
            "--package-path parts=DIR")


def test_warnings_of_the_package_are_model_warnings(tmp_path):
    path = write(tmp_path, "w.urdf.xacro", '<xacro:property name="pi" value="3.14"/><link name="a"/><link name="b"/>'
                 '<joint name="j" type="revolute"><parent link="a"/><child link="b"/></joint>')
    with pytest.warns(aggsym.errors.ModelWarning) as record:
        aggsym.load(path)
    messages = [str(w.message) for w in record]
    assert len(messages) == 1 and "redefining global symbol: pi" in messages[0] and str(path) in messages[0]


def test_missing_include(tmp_path, capsys):
    path = write(tmp_path, "i.urdf.xacro", '<xacro:include filename="missing.xacro"/>')
    refused(capsys, ["ops", str(path)], str(path), f"cannot read {tmp_path / 'missing.xacro'}: No such file")


def test_package_path_not_a_folder(tmp_path, capsys):
    refused(capsys, ["ops", str(SCARA), "--package-path", f"parts={tmp_path / 'none'}"], "no such folder")


def test_malformed_xml_gives_the_line(tmp_path, capsys):
    path = write(tmp_path, "bad.urdf.xacro", '<link name="a">\n<link name="b"/>')
    refused(capsys, ["ops", str(path)], f"{path}:5", "malformed XML: mismatched tag")


def test_malformed_included_file_named(tmp_path, capsys):
    (tmp_path / "part.xacro").write_text("<robot>\n<oops>\n</robot>\n")
    path = write(tmp_path, "inc.urdf.xacro", '<xacro:include filename="part.xacro"/>')
    refused(capsys, ["ops", str(path)], str(tmp_path / "part.xacro"), "included from", "malformed XML")


def test_error_of_the_expanded_urdf(tmp_path, capsys):
    path = write(tmp_path, "u.urdf.xacro", '<link name="a"/><link name="b"/>'
                 '<joint name="j" type="revolute"><parent link="a"/><child link="c"/></joint>')
    refused(capsys, ["ops", str(path)], f"{path} (expanded by xacro)", "child link 'c' is not defined")


def test_option_of_another_reader(capsys):
    refused(capsys, ["ops", "models/double_pendulum.yaml", "--xacro-arg", "a:=1"], "does not accept --xacro-arg")
    refused(capsys, ["ops", "models/double_pendulum.yaml", "--package-path", "a=."], "does not accept --package-path")
    for option, value, says in (("--xacro-arg", "length", "expected NAME:=VALUE"),
                                ("--package-path", "parts", "expected PKG=DIR")):
        with pytest.raises(SystemExit) as exit_:
            main(["ops", str(ARM), option, value])
        assert exit_.value.code == 2 and says in capsys.readouterr().err


# hostile files --------------------------------------------------------------------------------------------------

# (a format string holds braces, which ${...} cannot: it comes from a property)
FORMAT = '<xacro:property name="f" value="{0.__class__}"/>'
ESCAPES = [
    "${f.format(1)}",
    "${f.format_map}",
    "${().__class__}",
    "${[x for x in (lambda: 0).__globals__]}",
    "${(i for i in []).gi_frame}",
    "$(eval 'a'.format)",
]


@pytest.mark.parametrize("expression", ESCAPES)
def test_expressions_that_could_run_code_are_refused(tmp_path, capsys, expression):
    path = write(tmp_path, "x.urdf.xacro", f'{FORMAT}<link name="{expression}"/>')
    refused(capsys, ["ops", str(path)], str(path), "refused here")


@pytest.mark.parametrize("expression", ["${python.vars(python.type)}", "${python.type(1)}"])
def test_type_and_vars_are_removed(tmp_path, capsys, expression):
    path = write(tmp_path, "x.urdf.xacro", f'<link name="{expression}"/>')
    refused(capsys, ["ops", str(path)], str(path), "is not defined")


def test_the_package_itself_would_evaluate_them(tmp_path):
    """Why the checks: without them the package walks attributes inside a format string, and has type and vars."""
    path = write(tmp_path, "x.urdf.xacro", f'{FORMAT}<link name="${{f.format(1)}}"/><link name="${{python.vars}}"/>')
    text = xacro_command(path, tmp_path / "x.urdf").read_text()
    assert "class 'int'" in text and "built-in function vars" in text
    # every class of the interpreter (object.__subclasses__()), the usual road out of an eval: refused here
    walk = write(tmp_path, "walk.urdf.xacro", WALK)
    assert '<link name="' in xacro_command(walk, tmp_path / "walk.urdf").read_text()
    with pytest.raises(aggsym.ModelError, match="is not defined"):
        aggsym.load(walk)


WALK = """<xacro:property name="s" value="__subclasses__"/>
<xacro:property name="b" value="__base__"/>
<xacro:property name="g" value="__get__"/>
<xacro:property name="d" value="${python.vars(python.type)[b]}"/>
<xacro:property name="obj" value="${python.vars(python.type(d))[g](d, python.int)}"/>
<link name="${len(python.vars(python.type)[s](obj))}"/>"""


def test_include_outside_the_folder_is_refused(tmp_path, capsys):
    outside = tmp_path / "outside.xacro"
    outside.write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="secret"/></robot>')
    (tmp_path / "model").mkdir()
    path = write(tmp_path / "model", "x.urdf.xacro", '<xacro:include filename="../outside.xacro"/>')
    refused(capsys, ["ops", str(path)], "outside the model's folder")
    absolute = write(tmp_path / "model", "y.urdf.xacro", f'<xacro:include filename="{outside}"/>')
    refused(capsys, ["ops", str(absolute)], "outside the model's folder")
    # the package path opens it
    assert main(["ops", str(path), "--package-path", f"p={tmp_path}"]) == 2  # (read: no joints, a URDF error)
    assert "no movable joint" in capsys.readouterr().err


def test_load_yaml_outside_the_folder_is_refused(tmp_path, capsys):
    secret = tmp_path / "secret.yaml"
    secret.write_text("key: 1\n")
    (tmp_path / "model").mkdir()
    path = write(tmp_path / "model", "x.urdf.xacro", f'<link name="${{xacro.load_yaml(\'{secret}\')}}"/>')
    refused(capsys, ["ops", str(path)], "outside the model's folder")


def test_symlink_out_of_the_folder_is_refused(tmp_path, capsys):
    (tmp_path / "outside.xacro").write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro"/>')
    (tmp_path / "model").mkdir()
    (tmp_path / "model" / "link.xacro").symlink_to(tmp_path / "outside.xacro")
    path = write(tmp_path / "model", "x.urdf.xacro", '<xacro:include filename="link.xacro"/>')
    refused(capsys, ["ops", str(path)], "outside the model's folder")


def test_entities_are_refused(tmp_path, capsys):
    path = tmp_path / "e.urdf.xacro"
    path.write_text('<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY a "aaaaaaaaaa">]>\n<robot name="&a;"/>\n')
    refused(capsys, ["ops", str(path)], "entity declaration")


def test_recursion_is_an_error(tmp_path, capsys):
    path = write(tmp_path, "r.urdf.xacro", '<xacro:macro name="m" params=""><xacro:m/></xacro:macro><xacro:m/>')
    refused(capsys, ["ops", str(path)], str(path))


def test_package_state_restored(tmp_path):
    import xacro
    from xacro import substitution_args

    before = (xacro.parse, xacro.safe_eval, substitution_args._eval_find, substitution_args._eval,
              substitution_args._eval_dict["find"])
    with pytest.raises(aggsym.ModelError):
        aggsym.load(SCARA)
    aggsym.load(SCARA, package_paths={"parts": str(PARTS)})
    assert before == (xacro.parse, xacro.safe_eval, substitution_args._eval_find, substitution_args._eval,
                      substitution_args._eval_dict["find"])
