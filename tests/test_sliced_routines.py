"""Routines emitted as slices (aggsym/codegen/slicing.py; issue 18, item 3): a routine of more work than the
threshold becomes static noinline functions, each a contiguous part of its statements, called in turn by the public
function, values crossing slices through a workspace.  Here the threshold is lowered (``SMALL``) so that small
models' routines are cut into many slices, which compiles in a second:

* the sliced C against the unsliced straight-line program evaluated on floats and against Pinocchio (UR5), against
  the same routines compiled unsliced and the numeric twin (a returned status, a time input, single precision),
  under -ffast-math, with and without the attributes for GCC (the same bits), and with an output that aliases an
  input;
* the workspace: every load reads the value last stored in its entry (entries are reused);
* slices only above the threshold, the routines below it printed exactly as unsliced; the default threshold slices
  Talos' C but not its A, b + g, inverse dynamics (which run slower sliced);
* byte-identical output across runs and hash seeds; --split's make builds libNAME.a exporting only the contract's
  functions."""
from __future__ import annotations

import ctypes
import json
import os
import platform
import re
import shlex
import subprocess
import sys
import warnings

import numpy as np
import pytest

import aggsym
from aggsym.codegen.check import random_inputs
from aggsym.codegen.compile import CLibrary, build_split, compile_shared, compiler, shared_from_archive
from aggsym.codegen.generate import generate, symbolic_routines, write
from aggsym.codegen.slicing import SLICE_THRESHOLD
from aggsym.contract import ROUTINES, select_routines, signature
from aggsym.errors import ModelWarning
from aggsym.twin import NumericTwin
from conftest import ROOT, model_path
from helpers import relative_error, robot_path
from pinocchio_reference import pin, crba, inertia_rate, pinocchio_model, pinocchio_q

pytestmark = pytest.mark.pinocchio

SMALL = (150, 60)  # (threshold, size): every routine of more than 150 work, in slices of about 60
TINY = (40, 20)  # for the smallest models
SLICE_CALL = re.compile(r"\b(\w+)_slice(\d+)\(")


def _write(model, folder, slicing=SMALL, **options):
    gen = generate(model, targets="c,numpy,manifest", slicing=slicing, **options)
    write(gen, folder)
    return gen


def _compile(model, folder, name="lib.so", extra=("-O2",), scalar="double"):
    manifest = json.loads((folder / f"{model.name}.json").read_text())
    return CLibrary(compile_shared(folder / f"{model.name}.c", folder / name, extra=extra, scalar=scalar), manifest)


def _tuple(x):
    return x if isinstance(x, tuple) else (x,)


@pytest.fixture(scope="module")
def ur5(tmp_path_factory):
    """UR5 with every routine sliced: (model, generated, C library compiled -O2 with -Werror)."""
    folder = tmp_path_factory.mktemp("ur5")
    model = aggsym.load(robot_path("ur5"))
    gen = _write(model, folder)
    return model, gen, _compile(model, folder)


@pytest.mark.compiler
def test_ur5_sliced_equals_its_program_and_pinocchio(ur5, rng):
    """Each sliced routine against its straight-line program evaluated on floats (1e-12 of the largest output), and
    A, b + g, g, inverse and forward dynamics, A^-1 and C (C qd = b, C + C^T = dM/dt) against Pinocchio (1e-9)."""
    model, gen, lib = ur5
    sliced = {r.routine.role for r in gen.routines if r.bodies["c"].sliced}
    assert {"inertia", "nonlinear_effects", "inverse_dynamics", "forward_dynamics", "inertia_inverse",
            "coriolis"} <= sliced
    assert all(len(r.bodies["c"].sliced.slices) >= 3 for r in gen.routines if r.bodies["c"].sliced)
    prog, outputs = symbolic_routines(model)
    pm = pinocchio_model(robot_path("ur5"))
    data = pm.createData()
    defaults = [float(p.value) for p in model.parameters]
    for _ in range(3):
        x = {"q": rng.uniform(-np.pi, np.pi, model.nq), "qd": rng.normal(size=model.nq),
             "qdd": rng.normal(size=model.nq), "tau": rng.normal(size=model.nq)}
        values = {key: (defaults[key[1]] if key[0] == "p" else x[key[0]][key[1]]) for key in prog.inputs
                  if key[0] in x or key[0] == "p"}
        got = {}
        for role in sliced:
            inputs = [k for k in signature(ROUTINES[role], model) if k != "p"]
            if not set(inputs) <= set(x):  # (a routine of other inputs, e.g. a frame's twist T)
                continue
            args = [x[k] for k in inputs]
            got[role] = _tuple(lib.call(role, *args))
            for c, flat in zip(got[role], outputs[role]):
                ref = np.array(prog.evaluate(flat, values), dtype=float)
                assert relative_error(np.ravel(c), ref, floor=1e-300) <= 1e-12, role
        Q = pinocchio_q(pm, x["q"])
        M = crba(pm, Q)
        nle = pin.nonLinearEffects(pm, data, Q, x["qd"])
        refs = {"inertia": M, "nonlinear_effects": nle, "gravity": pin.computeGeneralizedGravity(pm, data, Q),
                "inverse_dynamics": pin.rnea(pm, data, Q, x["qd"], x["qdd"]),
                "forward_dynamics": pin.aba(pm, data, Q, x["qd"], x["tau"]),
                "inertia_inverse": np.linalg.inv(M)}
        for role, ref in refs.items():
            c = got[role][0] if role in got else lib.call(role, *[x[k] for k in signature(ROUTINES[role], model)
                                                                  if k != "p"])
            assert relative_error(c, ref) <= 1e-9, role
        C = got["coriolis"][0]
        b = nle - refs["gravity"]
        assert relative_error(C @ x["qd"], b, floor=np.abs(M).max() * np.abs(x["qd"]).max() ** 2) <= 1e-9
        Mdot, tolerance = inertia_rate(pm, Q, x["qd"])
        assert relative_error(C + C.T, Mdot, floor=np.abs(M).max() * np.abs(x["qd"]).max()) <= tolerance


@pytest.mark.compiler
def test_ur5_sliced_under_fast_math(ur5, tmp_path, rng):
    """Compiled with -O2 -ffast-math, the sliced routines equal the -O2 ones to 1e-9 of the largest output."""
    model, gen, lib = ur5
    folder = tmp_path / "fast"
    write(gen, folder)
    fast = _compile(model, folder, "fast.so", extra=("-O2", "-ffast-math"))
    for r in gen.routines:
        for _ in range(2):
            args = random_inputs(model, r.routine.role, rng)
            for a, b in zip(_tuple(fast.call(r.routine.role, *args)), _tuple(lib.call(r.routine.role, *args))):
                assert relative_error(a, b, floor=1e-300) <= 1e-9, r.routine.role


def _gcc_on_x86() -> bool:
    version = subprocess.run([*shlex.split(compiler()), "-v"], capture_output=True, text=True).stderr
    return "gcc version" in version and "clang" not in version.lower() and platform.machine() in ("x86_64", "i686")


@pytest.mark.compiler
def test_the_gcc_attributes_give_the_same_bits(ur5, tmp_path, rng):
    """GCC on x86 compiles the slices for size (AGGSYM_SLICE: optimize("Os")) and A and A^-1 without its basic-block
    vectorizer (AGGSYM_SCALAR_STORES), which run faster than its -O2 code of them; defining AGGSYM_AS_COMPILED gives
    every function the command line's -O2.  The code differs (under GCC on x86) and every output is the same, bit
    for bit."""
    model, gen, lib = ur5
    folder = tmp_path / "as_compiled"
    write(gen, folder)
    plain = _compile(model, folder, "plain.so", extra=("-O2", "-DAGGSYM_AS_COMPILED"))
    own = tmp_path / "own.so"
    compile_shared(folder / f"{model.name}.c", own, extra=("-O2",))
    differs = own.read_bytes() != (folder / "plain.so").read_bytes()
    assert differs == _gcc_on_x86()
    for r in gen.routines:
        for _ in range(3):
            args = random_inputs(model, r.routine.role, rng)
            for a, b in zip(_tuple(plain.call(r.routine.role, *args)), _tuple(lib.call(r.routine.role, *args))):
                assert np.array_equal(a, b), r.routine.role


def test_an_output_may_alias_an_input(ur5, rng):
    """Sliced inverse dynamics writing tau over qdd, and forward dynamics writing qdd over tau, give what they give
    into separate arrays (every input is read in the first slice, before any output is written)."""
    model, gen, lib = ur5
    n = model.nq
    ptr = ctypes.POINTER(ctypes.c_double)
    q, qd, u = rng.uniform(-np.pi, np.pi, n), rng.normal(size=n), rng.normal(size=n)
    for role in ("inverse_dynamics", "forward_dynamics"):
        expected = lib.call(role, q, qd, u)
        fn = getattr(lib.lib, gen.routines[[r.routine.role for r in gen.routines].index(role)].symbol)
        fn.restype = None
        shared = np.array(u)
        p = np.array([float(x.value) for x in model.parameters]) if model.parameters else None
        fn(q.ctypes.data_as(ptr), qd.ctypes.data_as(ptr), shared.ctypes.data_as(ptr),
           p.ctypes.data_as(ptr) if p is not None else None, shared.ctypes.data_as(ptr))
        assert np.array_equal(shared, expected), role


def _slices_in_call_order(text, symbol):
    """The bodies (lists of lines) of SYMBOL's slices, in the order its public function calls them."""
    bodies = {}
    for m in re.finditer(r"^static AGGSYM_SLICE void (\w+)\([^)]*\)\n\{\n(.*?)^\}", text, re.M | re.S):
        bodies[m.group(1)] = [line.strip() for line in m.group(2).splitlines()]
    public = re.search(rf"^(?:AGGSYM_SCALAR_STORES )?\w+ {symbol}\([^)]*\)\n\{{\n(.*?)^\}}", text, re.M | re.S).group(1)
    return [bodies[f"{name}_slice{k}"] for name, k in SLICE_CALL.findall(public)]


def test_the_workspace_holds_what_each_slice_loads(ur5):
    """Walking the slices in call order: every load of w[k] reads the name last stored there (entries are reused, so
    a wrong reuse would hand a slice another value), every store happens before any load of its entry, and the
    workspace is smaller than the number of values that cross (reuse happens)."""
    model, gen, _ = ur5
    text = gen.files[f"{model.name}.c"]
    store = re.compile(r"^w\[(\d+)\] = (\w+);$")
    load = re.compile(r"^const double (\w+) = w\[(\d+)\];$")
    for r in gen.routines:
        if not r.bodies["c"].sliced:
            continue
        held, crossing = {}, set()
        for body in _slices_in_call_order(text, r.symbol):
            for line in body:
                m = store.match(line)
                if m:
                    held[int(m.group(1))] = m.group(2)
                    crossing.add(m.group(2))
                m = load.match(line)
                if m:
                    assert held.get(int(m.group(2))) == m.group(1), (r.routine.role, line)
        assert max(held, default=-1) + 1 == r.bodies["c"].sliced.workspace, r.routine.role
        if r.routine.role == "coriolis":
            assert r.bodies["c"].sliced.workspace < len(crossing)
        sliced = r.bodies["c"].sliced
        assert f"double w[{sliced.workspace}];" in sliced.entry or not sliced.workspace


@pytest.mark.parametrize("name, scalar", [("four_bar", "double"), ("gyroscope_spinning_rotor", "double"),
                                          ("manipulator6", "float")])
@pytest.mark.compiler
def test_sliced_equals_unsliced_and_the_twin(name, scalar, tmp_path, rng):
    """A returned status (four_bar's constrained dynamics), a time input (the spinning rotor), single precision
    (-Wdouble-promotion -Wfloat-conversion -Werror): every routine sliced against the same routine compiled as one
    function (equal to rounding: the same statements in the same order) and against the numeric twin."""
    model = aggsym.load(model_path(name))
    gen = _write(model, tmp_path / "sliced", slicing=TINY, scalar=scalar)
    assert sum(1 for r in gen.routines if r.bodies["c"].sliced) >= 3
    assert not any(r.bodies["c"].sliced for r in _write(model, tmp_path / "plain", slicing=None, scalar=scalar).routines)
    sliced = _compile(model, tmp_path / "sliced", scalar=scalar)
    plain = _compile(model, tmp_path / "plain", scalar=scalar)
    twin = NumericTwin(model)
    rounding, tolerance = (1e-12, 1e-9) if scalar == "double" else (1e-5, 1e-3)
    statuses = 0
    for r in gen.routines:
        role = r.routine.role
        for _ in range(3):
            args = random_inputs(model, role, rng)
            try:
                ref = _tuple(twin.call(role, *args))
            except np.linalg.LinAlgError:
                continue
            try:
                a = _tuple(sliced.call(role, *args))
            except np.linalg.LinAlgError:
                with pytest.raises(np.linalg.LinAlgError):
                    plain.call(role, *args)
                continue
            statuses += r.routine.status is not None
            b = _tuple(plain.call(role, *args))
            scale = max(float(np.max(np.abs(x))) if np.size(x) else 0.0 for x in ref) or 1.0
            for x, y, z in zip(a, b, ref):
                assert np.max(np.abs(x - y), initial=0.0) <= rounding * scale, role
                assert np.max(np.abs(x - np.asarray(z, dtype=float)), initial=0.0) <= tolerance * scale, role
    assert statuses > 0 or not any(r.routine.status for r in gen.routines)


def test_slices_only_above_the_threshold():
    """With the threshold at the median work of manipulator6's routines, exactly those above it are sliced, and the
    others are printed exactly as without slicing; the default threshold slices none of a small model."""
    model = aggsym.load(model_path("manipulator6"))
    plain = generate(model, targets="c,numpy,manifest", slicing=None)
    works = {r.routine.role: r.work for r in plain.routines}
    threshold = sorted(works.values())[len(works) // 2]
    gen = generate(model, targets="c,numpy,manifest", slicing=(threshold, 100))
    text, plain_text = gen.files["manipulator6.c"], plain.files["manipulator6.c"]
    above = {role for role, w in works.items() if w > threshold}
    assert above and len(above) < len(works)
    for r in gen.routines:
        role = r.routine.role
        assert (r.bodies["c"].sliced is not None) == (role in above), role
        assert (f"{r.symbol}_slice0(" in text) == (role in above), role
        if role not in above:
            function = "\n".join([r.prototype, "{"] + [f"    {line}" for line in r.bodies["c"].lines] + ["}"])
            assert function in text and function in plain_text, role
    assert generate(model, targets="c,numpy,manifest").files == plain.files
    assert "slice" not in plain_text and "AGGSYM_SLICE" in text


def test_the_default_threshold_on_talos():
    """Talos' default routines: C(q, qd) (17,650 operations: 25 s to compile as one function at -O2) is sliced;
    A, b + g, g and inverse dynamics (about 4,300 work, 5-10 % slower sliced) are not."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)  # talos' <mimic> on fixed joints
        model = aggsym.load(robot_path("talos"))
    roles = ["inertia", "nonlinear_effects", "gravity", "inverse_dynamics", "coriolis"]
    gen = generate(select_routines(model, roles), targets="c,numpy,manifest")
    sliced = {r.routine.role for r in gen.routines if r.bodies["c"].sliced}
    assert sliced == {"coriolis"}
    assert all(r.work <= SLICE_THRESHOLD for r in gen.routines if r.routine.role != "coriolis")


def _generate_in_subprocess(folder, seed, split):
    code = ("import sys, aggsym; from aggsym.codegen.generate import generate, write; "
            f"write(generate(aggsym.load(sys.argv[1]), targets='c,numpy,manifest', slicing={SMALL!r}, split={split}), sys.argv[2])")
    env = dict(os.environ, PYTHONHASHSEED=str(seed))
    subprocess.run([sys.executable, "-c", code, str(model_path("manipulator6")), str(folder)], check=True, env=env,
                   capture_output=True)
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.mark.parametrize("split", [False, True])
def test_sliced_output_is_deterministic(split, tmp_path):
    """Two runs under different hash seeds write the same bytes, one file or --split."""
    a = _generate_in_subprocess(tmp_path / "a", 1, split)
    b = _generate_in_subprocess(tmp_path / "b", 4242, split)
    assert a == b
    assert any(b"_slice0(" in text for text in a.values())


@pytest.mark.compiler
def test_split_make_builds_the_library_with_sliced_routines(tmp_path, rng):
    """--split with every routine sliced: make -j2 with -Werror builds libNAME.a, one object per routine; its
    global symbols are exactly the contract's functions (the slices are static, and not inlined back); the library
    equals the twin."""
    model = aggsym.load(model_path("manipulator6"))
    folder = tmp_path / "split"
    gen = _write(model, folder, split=True)
    assert sum(1 for r in gen.routines if r.bodies["c"].sliced) >= 3
    archive = build_split(folder, cflags="-O2 -std=c99 -fPIC -Wall -Wextra -Wpedantic -Werror")
    manifest = json.loads((folder / "manipulator6.json").read_text())
    members = subprocess.run(["ar", "t", str(archive)], capture_output=True, text=True, check=True).stdout.split()
    assert sorted(members) == sorted(f"manipulator6_{role}.o" for role in manifest["functions"])
    symbols = subprocess.run(["nm", "-g", "--defined-only", str(archive)], capture_output=True, text=True,
                             check=True).stdout
    exported = {line.split()[-1] for line in symbols.splitlines() if len(line.split()) == 3}
    assert exported == set(manifest["functions"].values())
    # the slices are local symbols of the objects: not inlined back into the public function (AGGSYM_SLICE)
    assert " t manipulator6_coriolis_slice0\n" in subprocess.run(["nm", str(archive)], capture_output=True, text=True,
                                                                 check=True).stdout
    lib = CLibrary(shared_from_archive(archive, tmp_path / "split.so"), manifest)
    twin = NumericTwin(model)
    for role in manifest["functions"]:
        args = random_inputs(model, role, rng)
        ref = _tuple(twin.call(role, *args))
        got = _tuple(lib.call(role, *args))
        scale = max(float(np.max(np.abs(r))) if np.size(r) else 0.0 for r in ref) or 1.0
        for x, r in zip(got, ref):
            assert np.max(np.abs(x - np.asarray(r, dtype=float)), initial=0.0) <= 1e-10 * scale, role
