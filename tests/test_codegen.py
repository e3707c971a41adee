"""Rung 5: the artifacts.  Every model generates; its C compiles warning-free (-Werror) and, with the NumPy
module, matches the numeric twin; output is deterministic and reproducible; the LaTeX compiles."""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.codegen.check import check_generated
from aggsym.codegen.compile import compile_shared, import_module
from aggsym.codegen.generate import generate, write
from aggsym.codegen.printing import count_ops
from conftest import MODELS, ROOT, model_path

TOLERANCE = 1e-12


# the five largest models' C (0.4 to 5.5 MB; with -ffast-math, a minute and a half of the suite's compiling) is
# built without CFLAGS only; the sixteen others (one to eleven coordinates: loops, rolling, rotors, elasticity,
# friction, a moving platform) carry every construct of the C into -ffast-math
LARGEST = {"spacecraft", "walking_machine", "walking_machine_on_ground", "test_bench", "test_bench_constrained"}
BUILDS = ([(path, "") for path in MODELS]
          + [(path, "-ffast-math") for path in MODELS if path.stem not in LARGEST])


@pytest.mark.compiler
@pytest.mark.parametrize("path,cflags", BUILDS, ids=lambda x: x.stem if isinstance(x, Path) else x)
def test_model_compiles_warning_free_and_matches_twin(path, cflags, tmp_path, monkeypatch):
    """Every model's C with -O3 -Wall -Wextra -Wpedantic -Werror, and with CFLAGS=-ffast-math too (all but the
    largest), agrees with the twin (the robots are compiled -O2 by tests/conftest.py); the 48-coordinate test bench
    at -O0 (its -O3 compile alone takes about two minutes: checked by hand, see the closing notes)."""
    monkeypatch.setenv("CFLAGS", cflags)
    model = aggsym.load(path)
    gen = generate(model, targets="c,numpy,manifest")
    opt = "-O0" if model.nq > 40 else "-O3"
    results = check_generated(model, gen.files, trials=5, seed=1, workdir=tmp_path, opt=opt)
    roles = {r.role for r in results}
    assert {"inertia", "bias", "gravity", "inverse_dynamics", "kinetic_energy", "potential_energy"} <= roles
    for r in results:
        assert r.c_error <= TOLERANCE and r.py_error <= TOLERANCE, (r.role, r.c_error, r.py_error)


def test_generated_folder_is_reproducible():
    """generated/NAME/ holds the outputs of every model in models/, byte for byte (make generate)."""
    for path in MODELS:
        model = aggsym.load(path)
        folder = ROOT / "generated" / model.name
        gen = generate(model)
        assert sorted(p.name for p in folder.iterdir()) == sorted(gen.files), model.name
        for name, text in gen.files.items():
            assert (folder / name).read_text(encoding="utf-8") == text, f"{model.name}/{name} differs"


def run_generate(model, out, seed):
    env = dict(os.environ, PYTHONHASHSEED=str(seed))
    subprocess.run([sys.executable, "-m", "aggsym", "generate", str(model), "-o", str(out), "-q"],
                   check=True, env=env, capture_output=True)
    return {p.name: p.read_bytes() for p in sorted(out.iterdir())}


@pytest.mark.parametrize("name", ["double_pendulum", "walking_machine"])
def test_output_is_deterministic_across_hash_seeds(name, tmp_path):
    a = run_generate(model_path(name), tmp_path / "a", 1)
    b = run_generate(model_path(name), tmp_path / "b", 4242)
    assert a.keys() == b.keys() and len(a) == 5
    for k in a:
        assert a[k] == b[k], k


def pdflatex(tex: Path):
    return subprocess.run(["pdflatex", "-halt-on-error", "-interaction=nonstopmode", tex.name],
                          cwd=tex.parent, capture_output=True, text=True)


@pytest.mark.parametrize("name", ["double_pendulum", "planar_3link", "manipulator6", "spacecraft", "four_bar",
                                  "double_pendulum_sliding_friction"])
def test_latex_compiles(name, tmp_path):
    """Closed forms (small models) and the intermediate-variable form (larger ones) compile with pdflatex."""
    model = aggsym.load(model_path(name))
    tex = tmp_path / f"{name}.tex"
    tex.write_text(generate(model).files[tex.name])
    proc = pdflatex(tex)
    assert proc.returncode == 0, proc.stdout[-2000:]
    assert (tmp_path / f"{name}.pdf").stat().st_size > 1000


def test_latex_shows_the_constraints_of_small_models():
    """The four-bar's D_lambda^T is the rate of its rocker's end (a cos q1 + b cos(q1 + q2) + c cos(q1 + q2 + q3),
    a sin q1 + ...) per coordinate: its entries in closed form, and the constrained equations (4.25)-(4.28)."""
    text = generate(aggsym.load(model_path("four_bar"))).files["four_bar.tex"]
    assert r"\section*{Constraints (chapter 4)}" in text and r"D_\lambda \lambda" in text
    assert r"(D_\lambda^T)_{13} &= - c \sin{\left(q_{1} + q_{2} + q_{3} \right)}" in text
    assert r"(D_\lambda^T)_{21} &= a \cos{\left(q_{1} \right)} + b \cos{\left(q_{1} + q_{2} \right)} + c \cos{" in text
    assert "pin & rocker & world & o1 o2" in text
    sliding = generate(aggsym.load(model_path("double_pendulum_sliding_friction"))).files[
        "double_pendulum_sliding_friction.tex"]
    assert "foot & arm2 & world & o1 & coulomb mu" in sliding


def test_broken_latex_fails_the_same_check(tmp_path):
    """The LaTeX check can fail: a document with an unbalanced brace is rejected."""
    model = aggsym.load(model_path("double_pendulum"))
    text = generate(model).files["double_pendulum.tex"].replace(r"\ddot{o}_{12}", r"\ddot{o_{12}", 1)
    tex = tmp_path / "broken.tex"
    tex.write_text(text)
    assert pdflatex(tex).returncode != 0


def test_count_ops_counts_the_c_text():
    code = "const double x0 = a*b + c/d - sin(e);\nA[0] = -x0*q[1] - (x0 - 2.5e-3);\n(void)p;"
    assert count_ops(code) == {"mul": 2, "add": 4, "div": 1, "call": 1}  # the leading minus is unary


def test_manifest_follows_the_contract():
    model = aggsym.load(model_path("double_pendulum"))
    m = json.loads(generate(model, targets="c,numpy,manifest").files["double_pendulum.json"])
    assert m["name"] == "double_pendulum" and m["nq"] == 3
    assert [c["name"] for c in m["coordinates"]] == ["o12", "theta25", "theta36"]
    assert [c["kind"] for c in m["coordinates"]] == ["translation", "rotation", "rotation"]
    assert [c["joint"] for c in m["coordinates"]] == ["slide", "shoulder", "elbow"]
    assert m["parameters"][0] == {"name": "m2", "value": 1.0}
    assert m["functions"]["inertia"] == "double_pendulum_inertia"
    assert m["conservative"] is True
    for role, ops in m["ops"].items():
        assert set(ops) == {"mul", "add", "div", "call"}, role


def test_header_declares_the_contract_signatures():
    model = aggsym.load(model_path("double_pendulum"))
    h = generate(model, targets="c,numpy,manifest").files["double_pendulum.h"]
    for sig in ["void double_pendulum_inertia(const double *q, const double *p, double *A);",
                "void double_pendulum_bias(const double *q, const double *qd, const double *p, double *b);",
                "void double_pendulum_gravity(const double *q, const double *p, double *g);",
                "void double_pendulum_inverse_dynamics(const double *q, const double *qd, const double *qdd, "
                "const double *p, double *tau);",
                "void double_pendulum_kinetic_energy(const double *q, const double *qd, const double *p, double *T);",
                "void double_pendulum_potential_energy(const double *q, const double *p, double *U);"]:
        assert sig in h, sig


def test_numpy_module_accepts_a_batch_and_parameters(tmp_path, rng):
    model = aggsym.load(model_path("planar_3link"))
    write(generate(model, targets="c,numpy,manifest"), tmp_path)
    mod = import_module(tmp_path / "planar_3link.py")
    twin = aggsym.NumericTwin(model)
    q, qd = rng.normal(size=(2, 4, 3))
    p = np.array(mod.PARAMETERS) * 1.1
    A = mod.inertia(q, p)
    b = mod.bias(q, qd, p)
    T = mod.kinetic_energy(q, qd)
    assert A.shape == (4, 3, 3) and b.shape == (4, 3) and T.shape == (4,)
    for k in range(4):
        assert np.allclose(A[k], twin.inertia(q[k], p=p), rtol=1e-13)
        assert np.allclose(b[k], twin.bias(q[k], qd[k], p=p), rtol=1e-13)
    assert isinstance(mod.kinetic_energy(q[0], qd[0]), float)


@pytest.mark.compiler
def test_check_exits_1_on_mismatch(monkeypatch, capsys):
    import aggsym.codegen.generate as g

    real = g.generate

    def corrupted(model, **kw):
        gen = real(model, **kw)
        name = f"{model.name}.c"
        gen.files[name] = gen.files[name].replace("A[0] = ", "A[0] = 1e-9 + ", 1)
        return gen

    monkeypatch.setattr(g, "generate", corrupted)
    rc = cli.main(["check", str(model_path("planar_2link")), "--trials", "2"])
    out = capsys.readouterr()
    assert rc == 1
    assert "MISMATCH" in out.out and "inertia" in out.err


def test_every_command_has_help_with_an_example():
    for command in ("generate", "latex", "check", "ops"):
        proc = subprocess.run([sys.executable, "-m", "aggsym", command, "--help"], capture_output=True, text=True)
        assert proc.returncode == 0 and "example:" in proc.stdout and "aggsym " + command in proc.stdout


def test_generate_reports_stage_timings_and_writes_the_five_files(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "aggsym", "generate", str(model_path("gyroscope")), "-o",
                           str(tmp_path / "g")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "recursions:" in proc.stderr and "printing:" in proc.stderr
    assert sorted(p.name for p in (tmp_path / "g").iterdir()) == [
        "gyroscope.c", "gyroscope.h", "gyroscope.json", "gyroscope.py", "gyroscope.tex"]


def test_failed_generation_leaves_the_output_folder_as_it_was(tmp_path, monkeypatch):
    import aggsym.codegen.generate as g

    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("old")

    def fail(*a, **k):
        raise RuntimeError("boom in the middle of generation")

    monkeypatch.setattr(g, "emit_routine", fail)
    rc = cli.main(["generate", str(model_path("gyroscope")), "-o", str(out), "-q"])
    assert rc == 3
    assert [p.name for p in out.iterdir()] == ["keep.txt"]


@pytest.mark.compiler
def test_emitted_sincos_is_accurate(tmp_path):
    """aggsym_sincos in the generated C (Cody-Waite reduction, minimax series) against libm through NumPy: within
    a few units in the last place over small, large, negative and quadrant-boundary angles; nan and inf as libm."""
    import ctypes
    import re

    source = generate(aggsym.load(model_path("double_pendulum")), targets="c,numpy,manifest").files["double_pendulum.c"]
    helper = re.search(r"/\* sin\(x\) and cos\(x\) together,.*?static inline void aggsym_sincos\(double.*?\n}\n",
                       source, re.S).group(0)
    (tmp_path / "s.c").write_text("#include <math.h>\n" + helper + "#undef AGGSYM_KEEP\n" + """
void many(const double *x, double *s, double *c, int n) { for (int i = 0; i < n; i++) aggsym_sincos(x[i], s + i, c + i); }
""")
    lib = ctypes.CDLL(str(compile_shared(tmp_path / "s.c", tmp_path / "s.so")))
    rng = np.random.default_rng(7)
    k = np.arange(-40, 41)
    x = np.concatenate([rng.uniform(-4, 4, 20000), rng.uniform(-2000, 2000, 20000), rng.uniform(-9e5, 9e5, 2000),
                        k * np.pi / 2, np.nextafter(k * np.pi / 4, 0), k * np.pi / 4, [0.0, -0.0, 1e-300, 2e6, -3e7]])
    s, c = np.empty_like(x), np.empty_like(x)
    p = ctypes.POINTER(ctypes.c_double)
    lib.many(x.ctypes.data_as(p), s.ctypes.data_as(p), c.ctypes.data_as(p), ctypes.c_int(len(x)))
    ulp = np.spacing(1.0)
    assert np.max(np.abs(s - np.sin(x))) <= 4 * ulp and np.max(np.abs(c - np.cos(x))) <= 4 * ulp
    special = np.array([np.nan, np.inf, -np.inf])
    lib.many(special.ctypes.data_as(p), s.ctypes.data_as(p), c.ctypes.data_as(p), ctypes.c_int(3))
    assert np.all(np.isnan(s[:3])) and np.all(np.isnan(c[:3]))


@pytest.mark.compiler
def test_outputs_may_alias_inputs(tmp_path, rng):
    """Every input is read before any output is written, so a routine may write its result over an input
    (e.g. q'' over tau in place)."""
    import ctypes

    model = aggsym.load(model_path("manipulator6"))
    write(generate(model, targets="c,numpy,manifest"), tmp_path)
    lib = ctypes.CDLL(str(compile_shared(tmp_path / "manipulator6.c", tmp_path / "m.so")))
    p = ctypes.POINTER(ctypes.c_double)
    q, qd, tau = rng.normal(size=(3, 6))
    separate = np.zeros(6)
    args = [a.ctypes.data_as(p) for a in (q, qd, tau)]
    lib.manipulator6_forward_dynamics(*args, None, separate.ctypes.data_as(p))
    inplace = tau.copy()
    lib.manipulator6_forward_dynamics(q.ctypes.data_as(p), qd.ctypes.data_as(p), inplace.ctypes.data_as(p), None,
                                      inplace.ctypes.data_as(p))
    assert np.array_equal(inplace, separate)


def test_closed_forms_only_where_their_expansion_is_small(tmp_path):
    """The LaTeX closed forms are chosen by a bound on the expanded size (deterministic): the seeds' small systems
    get them, a general 3-D four-link arm (whose expansion SymPy does not finish) the intermediate-variable form."""
    from aggsym.codegen.latex import CLOSED_FORM_MAX_TERMS
    from aggsym.core.program import expanded_terms
    from aggsym.codegen.generate import symbolic_routines
    from benchmarks.harness.chain import chain_model

    def terms(model):
        prog, outs = symbolic_routines(model, roles=("inertia", "bias", "gravity"))
        return expanded_terms(prog, [x for o in outs.values() for out in o for x in out])

    assert terms(aggsym.load(model_path("double_pendulum"))) == 12
    assert terms(aggsym.load(model_path("planar_3link"))) <= CLOSED_FORM_MAX_TERMS
    arm = chain_model(4, tmp_path)
    assert terms(arm) > CLOSED_FORM_MAX_TERMS
    tex = generate(arm).files[f"{arm.name}.tex"]
    assert "Intermediate-variable form" in tex
    assert "Intermediate-variable form" not in generate(aggsym.load(model_path("planar_3link"))).files["planar_3link.tex"]


def test_check_opt_takes_the_level_with_or_without_its_dash():
    """``--opt O0`` (argparse reads ``--opt -O0`` as two options, so the dash is optional), ``--opt=-O3``; a level
    that is not one of O0-O3 is a usage error (exit 2)."""
    parser = cli._parser()
    base = ["check", str(model_path("planar_2link"))]
    assert parser.parse_args(base + ["--opt", "O0"]).opt == "-O0"
    assert parser.parse_args(base + ["--opt=-O3"]).opt == "-O3"
    assert parser.parse_args(base).opt == "-O2"
    with pytest.raises(SystemExit) as exc:
        parser.parse_args(base + ["--opt", "O9"])
    assert exc.value.code == 2


@pytest.mark.compiler
def test_readme_c_example_compiles_and_runs(tmp_path):
    """The complete C program of docs/generated-code.md, compiled against the committed generated/double_pendulum with -Werror,
    prints tau = A qdd + b + g and recovers qdd by forward dynamics, with the run-time parameter change applied."""
    import re

    text = (ROOT / "docs/generated-code.md").read_text()
    source = re.search(r"```c\n(/\* main\.c.*?)```", text, re.S).group(1)
    (tmp_path / "main.c").write_text(source)
    folder = ROOT / "generated" / "double_pendulum"
    exe = tmp_path / "main"
    cc = os.environ.get("CC", "cc")
    subprocess.run([cc, "-std=c99", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-I", str(folder),
                    str(tmp_path / "main.c"), str(folder / "double_pendulum.c"), "-lm", "-o", str(exe)],
                   check=True, capture_output=True, text=True)
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    rows = [[float(x) for x in re.findall(r"= *(-?[\d.]+)", line)] for line in out.strip().splitlines()]
    model = aggsym.load(model_path("double_pendulum"))
    p = np.array(model.parameter_values)
    p[[x.name for x in model.parameters].index("m3")] = 1.2
    twin = aggsym.NumericTwin(model)
    q, qd, qdd = np.array([0.1, 0.4, -0.3]), np.array([0.0, 1.0, -0.5]), np.array([0.2, -1.0, 0.5])
    tau = twin.inverse_dynamics(q, qd, qdd, p=p)
    A = twin.inertia(q, p=p)
    assert np.allclose([r[0] for r in rows], tau, atol=2e-6)
    assert np.allclose([r[1] for r in rows], qdd, atol=2e-6)
    assert np.allclose([r[2] for r in rows], np.diag(A), atol=2e-6)


def test_header_size_and_index_macros(tmp_path):
    """The header defines NQ, NP, an index per parameter and a size per output array, equal to the manifest's."""
    import re

    model = aggsym.load(model_path("double_pendulum_elastic_stand"))
    gen = generate(model, targets="c,numpy,manifest")
    header = gen.files[f"{model.name}.h"]
    manifest = json.loads(gen.files[f"{model.name}.json"])
    macros = dict(re.findall(r"#define (\w+) (\d+)", header))
    up = model.name.upper()
    assert int(macros[f"{up}_NQ"]) == model.nq and int(macros[f"{up}_NP"]) == len(model.parameters)
    for i, p in enumerate(manifest["parameters"]):
        assert int(macros[f"{up}_P_{p['name']}"]) == i
    for role, sig in manifest["signatures"].items():
        for o in sig["outputs"]:
            name = f"{up}_{role.upper()}" + (f"_{o['name'].upper()}" if len(sig["outputs"]) > 1 else "") + "_SIZE"
            assert int(macros[name]) == int(np.prod(o["shape"])), name
    assert f"{up}_JOINT_WRENCHES_SIZE" in macros and f"{up}_TRANSVECTIVE_FACTORS_TARGS_SIZE" in macros


def test_quiet_generate_prints_nothing_and_list_routines_writes_nothing(tmp_path, capsys):
    out = tmp_path / "out"
    assert cli.main(["generate", str(model_path("planar_2link")), "-o", str(out), "-q"]) == 0
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""
    assert (out / "planar_2link.c").exists()
    other = tmp_path / "other"
    assert cli.main(["generate", str(model_path("planar_2link")), "-o", str(other), "--list-routines"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    manifest = json.loads((out / "planar_2link.json").read_text())
    emitted = [line for line in lines if "(on request:" not in line]
    assert [line.split()[0] for line in emitted] == list(manifest["functions"].values())
    assert [line.split()[0] for line in lines if line not in emitted] == \
        [f"planar_2link_{role}" for role in manifest["not_emitted"]]
    assert all(len(line.split(None, 1)[1]) > 10 for line in lines) and not other.exists()


def test_version_flag(capsys):
    with pytest.raises(SystemExit) as info:
        cli.main(["--version"])
    assert info.value.code == 0 and capsys.readouterr().out.strip() == f"aggsym {aggsym.__version__}"


def test_latex_closed_forms_need_the_programs_that_size_them():
    """With A, b or g not emitted (--routines without them) the closed forms are not attempted: their size is
    measured on those programs, and without them SymPy once spent many minutes on a 4-link chain's derivatives
    alone.  The document then shows the intermediate-variable form of what was emitted."""
    from aggsym.contract import select_routines

    model = aggsym.load(model_path("double_pendulum"))
    full = generate(model).files["double_pendulum.tex"]
    only = generate(select_routines(model, ["inverse_dynamics_derivatives"])).files["double_pendulum.tex"]
    assert r"Inertia matrix $A(q)$" in full
    assert r"Inertia matrix $A(q)$" not in only and r"\section*{Equations of motion}" in only
