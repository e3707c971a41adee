"""Hostile text and real compiler flags at the output end (issue 15): user text never escapes its place in the
generated C, Python and LaTeX; names that cannot name the code are refused with a hint; constants are exact
doubles; p == NULL means the defaults; -ffast-math keeps 1e-12; output folders that cannot be written are the
user's error, with the user's path and nothing half-written."""
import ctypes
import json
import os
import re

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.codegen.escape import c_comment, check_module_name, latex, py_doc
from aggsym.codegen.printing import _number
from conftest import model_path
from helpers import generated_code
from robot_builder import chain, segment

EVIL = [
    "*/ #define double float /*",
    "a\nb\r\n#include <stdio.h>",
    '"""; import os; os.system("touch /tmp/aggsym_pwned") #',
    "\\input{/etc/passwd} \\write18{ls} \\openin \\catcode`\\@=11",
    "??/ trigraph and \\ backslash-newline \\\n",
    "$ & # ^ _ % ~ { }",
    "\u202e bidi \u00e9 \U0001F600 \x00 \x1b[31m",
]


@pytest.mark.parametrize("text", EVIL)
def test_escapers_keep_text_in_its_place(text):
    c = c_comment(text)
    assert "*/" not in c and "/*" not in c and "\n" not in c and "\\" not in c and "??" not in c
    doc = py_doc(text)
    assert '"""' not in doc.replace('\\"', "") and all(32 <= ord(ch) < 127 for ch in doc)
    tex = latex(text)
    for command in ("\\input", "\\write", "\\openin", "\\catcode", "\\include"):
        assert command not in tex
    assert all(32 <= ord(ch) < 127 for ch in tex)


# one link and its joint, both named {joint}
URDF = chain("evil", segment("{joint}", "{joint}", axis="0 0 1", mass=1.0, com="0.1 0 0", inertia=(0.01, 0.02, 0.03)))


def xml_attribute(text: str) -> str:
    return (text.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;").replace(">", "&gt;")
            .replace("\n", "&#10;").replace("\r", "&#13;"))


@pytest.mark.compiler
@pytest.mark.parametrize("k", range(len(EVIL) - 1))  # the last one holds characters XML cannot carry
def test_hostile_joint_names_compile_import_and_typeset_safely(k, tmp_path):
    """A joint and its link (a frame of the frame routines) named with C, Python or LaTeX syntax: the header
    compiles with -Werror (no macro was injected), the NumPy module imports (and runs nothing: no marker file),
    JOINTS and FRAMES hold the names as given, LaTeX escapes them."""
    marker = "/tmp/aggsym_pwned"
    if os.path.exists(marker):
        os.remove(marker)
    path = tmp_path / "evil.urdf"
    path.write_text(URDF.format(joint=xml_attribute(EVIL[k])))
    model = aggsym.load(path)
    lib, module, manifest = generated_code(model, tmp_path / "out")
    header = (tmp_path / "out" / "evil.h").read_text()
    assert not re.search(r"^\s*#\s*(define double|include <stdio)", header, re.M)
    assert module.JOINTS == (model.coordinates[0].joint,) and not os.path.exists(marker)
    assert module.FRAMES == (EVIL[k],) == tuple(f["name"] for f in manifest["frames"])
    assert manifest["coordinates"][0]["joint"] == model.coordinates[0].joint
    q = np.array([0.3])
    assert np.allclose(lib.call("inertia", q), module.inertia(q))
    tex = aggsym.generate(model).files["evil.tex"]
    assert "\\input{" not in tex and "\\write18" not in tex


@pytest.mark.compiler
def test_hostile_description_in_a_yaml_model(tmp_path):
    text = model_path("planar_2link").read_text()
    lines = [line for line in text.splitlines() if not line.startswith("description:")]
    evil = '*/ #define double float /* """ import os \\input{/etc/passwd}'
    path = tmp_path / "evil2.yaml"
    path.write_text("\n".join(["name: evil2", f"description: {json.dumps(evil)}"]
                              + [line for line in lines if not line.startswith("name:")]) + "\n")
    model = aggsym.load(path)
    assert model.description == evil
    files = aggsym.generate(model).files
    assert "\\input{" not in files["evil2.tex"]
    lib, module, _ = generated_code(model, tmp_path / "out")
    assert module.__doc__ is not None
    assert not re.search(r"^\s*#\s*define double", (tmp_path / "out" / "evil2.h").read_text(), re.M)


@pytest.mark.parametrize("name", ["numpy", "np", "os", "sys", "math", "json", "class", "match"])
def test_model_names_that_cannot_name_a_module_are_refused_with_a_hint(name, tmp_path, capsys):
    path = tmp_path / "m.yaml"
    path.write_text(model_path("planar_2link").read_text().replace("name: planar_2link", f"name: {name}", 1))
    out = tmp_path / "out"
    code = cli.main(["generate", str(path), "-o", str(out)])
    err = capsys.readouterr().err
    assert check_module_name(name) is not None
    assert code == 2 and str(path) in err and "name" in err and "Traceback" not in err, err
    assert not out.exists()
    if name in ("class", "match"):  # keywords: the YAML reader refuses them as names of anything
        return
    assert "--name" in err, err
    assert cli.main(["generate", str(path), "-o", str(out), "--name", "arm2", "-q"]) == 0
    assert (out / "arm2.py").exists()


def test_bad_name_option_is_refused(tmp_path, capsys):
    assert cli.main(["generate", str(model_path("planar_2link")), "-o", str(tmp_path / "o"), "--name", "a-b"]) == 2
    assert "--name" in capsys.readouterr().err and not (tmp_path / "o").exists()


def test_constants_print_as_exact_finite_doubles():
    assert _number(3) == "3" and _number(2 ** 70) == repr(float(2 ** 70)) and float(_number(2 ** 64)) == 2.0 ** 64
    assert float(_number(0.1)) == 0.1 and _number(2.0) == "2.0"
    for bad in (float("nan"), float("inf")):
        with pytest.raises(ValueError):
            _number(bad)


@pytest.mark.compiler
def test_null_p_means_the_defaults(tmp_path, rng):
    model = aggsym.load(model_path("double_pendulum"))
    lib, _, manifest = generated_code(model, tmp_path)
    fn = getattr(lib.lib, manifest["functions"]["inverse_dynamics"])
    fn.restype = None
    q, qd, qdd = (np.ascontiguousarray(rng.normal(size=3)) for _ in range(3))
    out = np.zeros(3)
    ptr = lambda a: a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))  # noqa: E731
    fn(ptr(q), ptr(qd), ptr(qdd), None, ptr(out))
    assert np.array_equal(out, lib.call("inverse_dynamics", q, qd, qdd))
    assert np.allclose(out, aggsym.NumericTwin(model).inverse_dynamics(q, qd, qdd), rtol=1e-13)


@pytest.mark.compiler
@pytest.mark.parametrize("name", ["manipulator6", "flywheel_on_body"])
def test_fast_math_keeps_every_routine_within_1e12_at_large_angles(name, tmp_path, monkeypatch):
    """Compiled -O3 -ffast-math (CFLAGS, as `aggsym check` honours it), every routine agrees with the NumPy module to
    1e-12 relative for angles up to 1e6 rad."""
    monkeypatch.setenv("CFLAGS", "-O3 -ffast-math")
    model = aggsym.load(model_path(name))
    lib, module, manifest = generated_code(model, tmp_path)
    rng = np.random.default_rng(5)
    for role, sig in manifest["signatures"].items():
        for scale in (1.0, 1e3, 1e6):
            args = [rng.uniform(-scale, scale, model.nq) if n == "q" else float(rng.uniform(0, 10)) if n == "t"
                    else rng.normal(size=model.nq) for n in sig["inputs"] if n != "p"]
            got = lib.call(role, *args)
            ref = getattr(module, role)(*args)
            for g, r in zip(got if isinstance(got, tuple) else (got,), ref if isinstance(ref, tuple) else (ref,)):
                top = max(np.abs(r).max(), 1e-300)
                assert np.abs(g - r).max() <= 1e-12 * top, (role, scale)


@pytest.mark.compiler
def test_check_honours_cc_and_cflags(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("CFLAGS", "-fno-such-flag-for-aggsym")
    assert cli.main(["check", str(model_path("planar_2link")), "--trials", "1"]) == 2
    assert "-fno-such-flag-for-aggsym" in capsys.readouterr().err
    monkeypatch.delenv("CFLAGS")
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    assert cli.main(["check", str(model_path("planar_2link")), "--trials", "1"]) == 2


@pytest.mark.parametrize("where", ["file", "proc", "long"])
def test_output_folders_that_cannot_be_written(where, tmp_path, capsys):
    target = {"file": tmp_path / "afile", "proc": "/proc/aggsym-out", "long": tmp_path / ("x" * 300)}[where]
    if where == "file":
        target.write_text("keep me")
    code = cli.main(["generate", str(model_path("planar_2link")), "-o", str(target), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and str(target) in err and "Traceback" not in err and "internal error" not in err, err
    if where == "file":
        assert target.read_text() == "keep me"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".aggsym-")]


def test_a_model_name_too_long_for_the_file_system_is_exit_2(tmp_path, capsys):
    path = tmp_path / "long.yaml"
    path.write_text(model_path("planar_2link").read_text().replace("name: planar_2link", "name: " + "n" * 300, 1))
    out = tmp_path / "out"
    assert cli.main(["generate", str(path), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert str(out) in err and "Traceback" not in err and not out.exists()


@pytest.mark.compiler
def test_a_hostile_file_name_stays_in_its_docstring_and_comment(tmp_path):
    """The model's file name reaches the NumPy docstring and the C comments escaped."""
    folder = tmp_path / 'x"""; __import__("pathlib").Path("aggsym_pwned_marker").touch() #*'
    folder.mkdir()
    path = folder / 'evil *\\ """ name.yaml'
    path.write_text(model_path("planar_2link").read_text())
    model = aggsym.load(path)
    lib, module, _ = generated_code(model, tmp_path / "out")
    assert not os.path.exists("aggsym_pwned_marker") and module.NQ == model.nq


def test_a_massless_floating_root_is_a_warning_not_an_internal_error(tmp_path, capsys):
    path = tmp_path / "floater.urdf"
    path.write_text(URDF.format(joint="j").replace('<link name="base"/>', '<link name="base"/>'))
    out = tmp_path / "out"
    assert cli.main(["generate", str(path), "--floating-base", "-o", str(out), "-q"]) == 0
    err = capsys.readouterr().err
    assert "singular" in err and "internal error" not in err
    manifest = json.loads((out / "floater.json").read_text())  # (named after the file, not <robot name="evil">)
    assert "forward_dynamics" in manifest["omitted"] and "inverse_dynamics" in manifest["functions"]


def test_a_true_bug_is_exit_3_with_a_request_to_report_it(monkeypatch, capsys, tmp_path):
    import aggsym.codegen.generate as generate_module

    def broken(*args, **kwargs):
        raise RuntimeError("simulated bug")

    monkeypatch.setattr(generate_module, "generate", broken)
    assert cli.main(["generate", str(model_path("planar_2link")), "-o", str(tmp_path / "o")]) == 3
    err = capsys.readouterr().err
    assert "internal error: RuntimeError: simulated bug" in err and "please report it" in err
    assert "Traceback" not in err and not (tmp_path / "o").exists()
