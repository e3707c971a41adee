"""``aggsym generate --routines ... --split`` (issue 18, item 3): only the named routines and what they need, one
.c per routine, the helpers in NAME_helpers.h (static inline), a Makefile building libNAME.a with make -j2, the
manifest listing the files; without --split the output is NAME.c as before.

The split library (make -j2 CC=cc, linked into a shared object for ctypes) is compared with the one-file C and with
the numeric twin (an independent evaluation of the same mechanics, no generated code)."""
from __future__ import annotations

import json
import re
import subprocess

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.codegen.check import random_inputs
from aggsym.codegen.compile import CLibrary, build_split, compile_shared, shared_from_archive
from aggsym.contract import select_routines
from aggsym.twin import NumericTwin
from conftest import model_path

FILES = {".h", ".py", ".json", ".tex"}


def _generate(tmp_path, name, *options, folder="out"):
    out = tmp_path / folder
    code = cli.main(["generate", str(model_path(name)), "-o", str(out), "-q", *options])
    return code, out


@pytest.mark.compiler
@pytest.mark.parametrize("name", ["manipulator6", "double_pendulum_sliding_friction"])
def test_split_library_equals_the_one_file_c_and_the_twin(name, tmp_path, rng):
    """Every default routine: make -j2 CC=cc in the split folder, the library's functions against NAME.c compiled
    the usual way (equal to rounding) and against the numeric twin (1e-10 of the largest output)."""
    code, split = _generate(tmp_path, name, "--split", folder="split")
    assert code == 0
    code, single = _generate(tmp_path, name, folder="single")
    assert code == 0
    manifest = json.loads((split / f"{name}.json").read_text())
    proc = subprocess.run(["make", "-j2", "CC=cc", "CFLAGS=-O2 -std=c99 -fPIC -Wall -Wextra -Wpedantic -Werror"],
                          cwd=split, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    archive = split / f"lib{name}.a"
    members = subprocess.run(["ar", "t", str(archive)], capture_output=True, text=True, check=True).stdout.split()
    assert sorted(members) == sorted(f"{name}_{role}.o" for role in manifest["functions"])
    lib_split = CLibrary(shared_from_archive(archive, tmp_path / "split.so"), manifest)
    lib_single = CLibrary(compile_shared(single / f"{name}.c", tmp_path / "single.so"),
                          json.loads((single / f"{name}.json").read_text()))
    model = aggsym.load(model_path(name))
    twin = NumericTwin(model)
    for role in manifest["functions"]:
        for _ in range(3):
            args = random_inputs(model, role, rng)
            try:
                ref = twin.call(role, *args)
            except np.linalg.LinAlgError:
                continue
            refs = ref if isinstance(ref, tuple) else (ref,)
            a, b = lib_split.call(role, *args), lib_single.call(role, *args)
            a, b = (a if isinstance(a, tuple) else (a,)), (b if isinstance(b, tuple) else (b,))
            scale = max(float(np.max(np.abs(r))) if np.size(r) else 0.0 for r in refs) or 1.0
            for x, y, r in zip(a, b, refs):
                assert np.max(np.abs(x - y), initial=0.0) <= 1e-13 * scale, role
                assert np.max(np.abs(x - np.asarray(r, dtype=float)), initial=0.0) <= 1e-10 * scale, role
    subprocess.run(["make", "clean"], cwd=split, check=True, capture_output=True)
    assert not list(split.glob("*.o")) and not archive.exists()


def test_only_the_named_routines_and_what_they_need(tmp_path):
    """--routines inertia,forward_dynamics --split: two .c files, the header declaring (and sizing) only those, the
    NumPy module and manifest with only those, the manifest's split entry naming exactly the files written."""
    code, out = _generate(tmp_path, "manipulator6", "--routines", "inertia,forward_dynamics", "--split")
    assert code == 0
    written = sorted(p.name for p in out.iterdir())
    manifest = json.loads((out / "manipulator6.json").read_text())
    assert list(manifest["functions"]) == ["inertia", "forward_dynamics"]
    entry = manifest["split"]
    assert sorted(entry["files"]) == written
    assert entry["sources"] == {"inertia": "manipulator6_inertia.c",
                                "forward_dynamics": "manipulator6_forward_dynamics.c"}
    assert entry["helpers"] == "manipulator6_helpers.h" and entry["library"] == "libmanipulator6.a"
    assert entry["header"] == "manipulator6.h" and entry["makefile"] == "Makefile"
    assert sorted(p for p in written if p.endswith(".c")) == sorted(entry["sources"].values())
    assert "manipulator6.c" not in written
    header = (out / "manipulator6.h").read_text()
    assert re.findall(r"\bvoid (manipulator6_\w+)\(", header) == ["manipulator6_inertia",
                                                                   "manipulator6_forward_dynamics"]
    assert re.findall(r"#define (MANIPULATOR6_[A-Z_]+_SIZE) ", header) == ["MANIPULATOR6_INERTIA_SIZE",
                                                                         "MANIPULATOR6_FORWARD_DYNAMICS_SIZE"]
    module = (out / "manipulator6.py").read_text()
    assert re.findall(r"^def ([a-z]\w*)\(", module, re.M) == ["inertia", "forward_dynamics"]  # (public ones)
    for source in entry["sources"].values():  # each file defines its one routine, and calls only helpers it includes
        text = (out / source).read_text()
        assert len(re.findall(r"^(?:AGGSYM_SCALAR_STORES )?void manipulator6_\w+\(", text, re.M)) == 1
        assert ("aggsym_sincos" in text) == ('#include "manipulator6_helpers.h"' in text)
    helpers = (out / "manipulator6_helpers.h").read_text()
    assert "static inline void aggsym_sincos(double" in helpers and "aggsym_sign" not in helpers


def test_helpers_header_only_where_a_routine_calls_a_helper(tmp_path):
    """spacecraft: its gravity and potential energy call no helper (no NAME_helpers.h, nothing in the Makefile);
    with its inertia (sin and cos) the header appears and only the inertia's file and object depend on it."""
    code, out = _generate(tmp_path, "spacecraft", "--routines", "gravity,potential_energy", "--split")
    assert code == 0
    assert json.loads((out / "spacecraft.json").read_text())["split"]["helpers"] is None
    assert not list(out.glob("*_helpers.h")) and "helpers" not in (out / "Makefile").read_text()
    assert subprocess.run(["make", "-j2", "CC=cc"], cwd=out, capture_output=True).returncode == 0
    code, out = _generate(tmp_path, "spacecraft", "--routines", "inertia,gravity", "--split", folder="mixed")
    assert code == 0
    assert '#include "spacecraft_helpers.h"' in (out / "spacecraft_inertia.c").read_text()
    assert "helpers" not in (out / "spacecraft_gravity.c").read_text()
    makefile = (out / "Makefile").read_text()
    assert "spacecraft_inertia.o: spacecraft_inertia.c spacecraft.h spacecraft_helpers.h\n" in makefile
    assert "spacecraft_gravity.o: spacecraft_gravity.c spacecraft.h\n" in makefile
    assert subprocess.run(["make", "-j2", "CC=cc"], cwd=out, capture_output=True).returncode == 0


def test_without_split_the_layout_is_one_file(tmp_path):
    """No --split: NAME.c, no Makefile, no helpers header, and no 'split' in the manifest (as before)."""
    code, out = _generate(tmp_path, "double_pendulum", "--routines", "inertia")
    assert code == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(f"double_pendulum{e}" for e in FILES | {".c"})
    assert "split" not in json.loads((out / "double_pendulum.json").read_text())


@pytest.mark.parametrize("routines, words", [
    ("inertia,nosuch", ["no routine named 'nosuch'"]),
    ("support_direct", ["'support_direct' does not apply"]),
])
def test_bad_routine_names_exit_2_and_write_nothing(routines, words, tmp_path, capsys):
    code, out = _generate(tmp_path, "double_pendulum", "--routines", routines, "--split")
    err = capsys.readouterr().err
    assert code == 2 and not out.exists() and "Traceback" not in err
    assert all(w in err for w in words) and "double_pendulum.yaml" in err


def test_a_routine_the_model_leaves_out_is_an_error_when_named(tmp_path, capsys):
    """The regressor of an elastic model is left out (tau = Y pi does not hold): naming it is an error saying
    why (exit 2, nothing written); through 'all' it is only listed in the manifest's omitted, as before."""
    code, out = _generate(tmp_path, "double_pendulum_elastic_stand", "--routines", "inertia,regressor", "--split")
    err = capsys.readouterr().err
    assert code == 2 and not out.exists() and "Traceback" not in err
    assert "'regressor' is left out" in err and "elastic" in err
    code, out = _generate(tmp_path, "double_pendulum_elastic_stand", "--routines", "all", "--split", folder="all")
    assert code == 0
    manifest = json.loads((out / "double_pendulum_elastic_stand.json").read_text())
    assert "regressor" in manifest["omitted"] and "regressor" not in manifest["split"]["sources"]


def test_list_routines_with_a_selection(capsys):
    """--list-routines with --routines: the named ones first; the others marked not selected (or on request)."""
    assert cli.main(["generate", str(model_path("double_pendulum")), "--routines", "gravity", "--list-routines"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("double_pendulum_gravity ")
    assert any("(not selected: --routines inertia)" in line for line in lines)
    assert any("(on request: --routines regressor)" in line for line in lines)


def test_select_routines_keeps_the_contract_order():
    model = select_routines(aggsym.load(model_path("double_pendulum")), ["forward_dynamics", "inertia"])
    assert model.routines == ("forward_dynamics", "inertia")


def test_float_split_builds_warning_free(tmp_path):
    """--scalar float --split: the float helpers in NAME_helpers.h, every file clean under -Wdouble-promotion
    -Wfloat-conversion -Werror (the flags of the float build)."""
    code, out = _generate(tmp_path, "manipulator6", "--routines", "inertia,gravity", "--scalar", "float", "--split")
    assert code == 0
    assert "static inline void aggsym_sincos(float x" in (out / "manipulator6_helpers.h").read_text()
    proc = subprocess.run(["make", "-j2", "CC=cc", "CFLAGS=-O2 -std=c99 -Wall -Wextra -Wpedantic -Wdouble-promotion "
                           "-Wfloat-conversion -Werror"], cwd=out, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr


def test_switching_layouts_in_one_folder_leaves_no_stale_sources(tmp_path):
    """Generating again into the same folder removes what the earlier generation wrote and this one does not:
    NAME.c after a switch to --split, the routine files, helpers header and Makefile after a switch back or to
    fewer routines; files aggsym did not write stay, whatever the old manifest says."""
    out = tmp_path / "out"
    assert _generate(tmp_path, "double_pendulum", "--routines", "inertia,gravity")[0] == 0
    (out / "notes.txt").write_text("mine")
    (out / "double_pendulum_mine.c").write_text("int mine;")
    assert _generate(tmp_path, "double_pendulum", "--routines", "inertia,gravity", "--split")[0] == 0
    names = {p.name for p in out.iterdir()}
    assert "double_pendulum.c" not in names
    assert {"double_pendulum_inertia.c", "double_pendulum_gravity.c", "Makefile", "notes.txt",
            "double_pendulum_mine.c"} <= names
    assert _generate(tmp_path, "double_pendulum", "--routines", "inertia", "--split")[0] == 0
    names = {p.name for p in out.iterdir()}
    assert "double_pendulum_gravity.c" not in names and "double_pendulum_inertia.c" in names
    assert _generate(tmp_path, "double_pendulum", "--routines", "inertia")[0] == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [f"double_pendulum{e}" for e in FILES | {".c"}] + ["notes.txt", "double_pendulum_mine.c"])


@pytest.mark.parametrize("listed", [["../victim.c"], ["/tmp/victim.c"], ["notes.txt"], ["double_pendulum_x.txt"],
                                    "double_pendulum.c", [["double_pendulum.c"]], [7]])
def test_a_tampered_manifest_deletes_nothing_outside_what_aggsym_writes(listed, tmp_path):
    """The old manifest is data in a user's folder: its file list only ever names our own output forms."""
    out = tmp_path / "out"
    victim = tmp_path / "victim.c"
    victim.write_text("keep")
    assert _generate(tmp_path, "double_pendulum", "--routines", "inertia")[0] == 0
    (out / "notes.txt").write_text("mine")
    (out / "double_pendulum_x.txt").write_text("mine")
    manifest = json.loads((out / "double_pendulum.json").read_text())
    manifest["split"] = {"files": listed}
    (out / "double_pendulum.json").write_text(json.dumps(manifest))
    assert _generate(tmp_path, "double_pendulum", "--routines", "inertia", "--split")[0] == 0
    assert victim.read_text() == "keep"
    assert (out / "notes.txt").exists() and (out / "double_pendulum_x.txt").exists()
    # a manifest whose file list is malformed or does not name NAME.c leaves NAME.c where it is
    assert (out / "double_pendulum.c").exists()


@pytest.mark.compiler
def test_check_split_runs_the_makefiles_library(tmp_path, capsys):
    """aggsym check --split builds the --split output with its Makefile and checks that library: the command
    passes on a model, and a routine file changed after generation (an entry of the gravity zeroed) is caught."""
    from aggsym.codegen.check import check_generated
    from aggsym.codegen.generate import generate

    assert cli.main(["check", str(model_path("double_pendulum")), "--split", "--trials", "2"]) == 0
    assert "ok: every routine" in capsys.readouterr().out
    model = select_routines(aggsym.load(model_path("double_pendulum")), ["inertia", "gravity"])
    files = dict(generate(model, targets="c,numpy,manifest", split=True).files)
    assert "double_pendulum.c" not in files
    results = {r.role: r for r in check_generated(model, files, trials=2, workdir=tmp_path)}
    assert results["gravity"].c_error < 1e-12 and results["inertia"].c_error < 1e-12
    source = files["double_pendulum_gravity.c"]
    body = source.rindex("}")
    files["double_pendulum_gravity.c"] = source[:body] + "    g[1] = 0.0;\n" + source[body:]
    results = {r.role: r for r in check_generated(model, files, trials=2, workdir=tmp_path)}
    assert results["gravity"].c_error > 1e-6 and results["inertia"].c_error < 1e-12
