"""The CasADi target (issue 54): NAME_casadi.py against the NumPy module (every routine, 1e-13) on a YAML model, a
URDF, a random tree with arbitrary axes, a free-flyer, a model with prescribed motions (t) and one with a status;
CasADi's AD against central differences, the attached derivative routines (custom_jacobian) against CasADi's AD and
against Pinocchio; inlining into SX and MX graphs; the module's imports, determinism and escaping; ``aggsym check``;
the swing-up example."""
from __future__ import annotations

import ast
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import casadi

import aggsym  # noqa: E402
from aggsym.cli import main  # noqa: E402
from aggsym.codegen.check import random_inputs  # noqa: E402
from aggsym.codegen.compile import import_module  # noqa: E402
from aggsym.codegen.generate import generate, write  # noqa: E402
from aggsym.codegen.targets import default_targets  # noqa: E402
from aggsym.contract import routines_for, select_routines  # noqa: E402
from aggsym.errors import ModelWarning  # noqa: E402
from conftest import ROOT, model_path  # noqa: E402
from helpers import central_differences  # noqa: E402
from random_trees import random_urdf  # noqa: E402

ca = casadi
DERIVATIVES = "default,inverse_dynamics_derivatives,forward_dynamics_derivatives"
URDF = ROOT / "models" / "arm3.urdf"
# name -> (path or URDF text, options): plain YAML, a URDF with its inertial parameters in p, a random tree with
# arbitrary axes, a quaternion free-flyer (tangent-space derivatives: none attached), prescribed motions (t) and a
# singular system's status (four_bar's constrained forward dynamics)
MODELS = {
    "double_pendulum": (model_path("double_pendulum"), {"routines": DERIVATIVES}),
    "arm3": (URDF, {"routines": DERIVATIVES, "inertial_parameters": "all"}),
    "random_tree": ("random", {"routines": DERIVATIVES, "armature": 0.01}),
    "free_flyer": (URDF, {"routines": DERIVATIVES, "floating_base": "quaternion"}),
    "gyroscope_spinning_rotor": (model_path("gyroscope_spinning_rotor"), {}),
    "four_bar": (model_path("four_bar"), {}),
}


@pytest.fixture(scope="session")
def generated(tmp_path_factory):
    """name -> (model, NumPy module, CasADi module, folder): each model generated once per session."""
    cache = {}

    def get(name):
        if name not in cache:
            path, options = MODELS[name]
            folder = tmp_path_factory.mktemp(f"casadi_{name}")
            if path == "random":
                path = folder / "tree.urdf"
                path.write_text(random_urdf(7, links=6))
            options = dict(options)
            routines = options.pop("routines", None)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ModelWarning)
                model = aggsym.load(path, **options)
            if routines:
                model = select_routines(model, routines.split(","))
            write(generate(model, targets="numpy,casadi,manifest"), folder)
            cache[name] = (model, import_module(folder / f"{model.name}.py"),
                           import_module(folder / f"{model.name}_casadi.py"), folder)
        return cache[name]
    return get


def perturbed(module, rng):
    """The module's PARAMETERS with every entry scaled by a random factor in [0.8, 1.25] (masses, lengths, ...)."""
    p = np.asarray(module.PARAMETERS.full()).ravel() if hasattr(module.PARAMETERS, "full") \
        else np.asarray(module.PARAMETERS, dtype=float)
    return p * rng.uniform(0.8, 1.25, p.size)


def evaluate(f, args):
    """A Function on numbers: its outputs as NumPy arrays."""
    return [x.full() for x in f.call([np.reshape(np.asarray(a, dtype=float), (-1, 1)) for a in args])]


def rel(a, b):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    scale = float(np.max(np.abs(b))) if b.size else 0.0
    return float(np.max(np.abs(a - b))) / (scale or 1.0) if b.size else 0.0


@pytest.mark.parametrize("name", list(MODELS))
def test_every_routine_equals_the_numpy_module(name, generated, rng):
    """Every output of every routine equals the NumPy module's to 1e-13 (relative to the routine's largest value)
    at random states and perturbed parameters, in CasADi's shapes (SHAPES: the NumPy module's), names and input
    order as the NumPy module's."""
    model, np_module, module, _ = generated(name)
    functions = module.functions()
    assert list(functions) == [r.role for r in routines_for(model)] == list(module.ROUTINES)
    for role, f in functions.items():
        numpy_f = getattr(np_module, role)
        names = [f.name_in(k) for k in range(f.n_in())]
        assert names == list(numpy_f.__code__.co_varnames[:f.n_in()])
        for _ in range(3):
            args = random_inputs(model, role, rng) + ([perturbed(np_module, rng)] if "p" in names else [])
            try:
                want = numpy_f(*args)
            except np.linalg.LinAlgError:
                assert evaluate(f, args)[-1].item() != 0.0
                continue
            want = want if isinstance(want, tuple) else (want,)
            got = evaluate(f, args)
            if role in module.STATUS:
                assert got.pop().item() == 0.0
            scale = max(float(np.max(np.abs(w))) if np.size(w) else 0.0 for w in want) or 1.0
            assert len(got) == len(want)
            for g, w, shape in zip(got, want, module.SHAPES[role]):
                w = np.reshape(w, shape)  # (a scalar input given as one entry, dt: the NumPy module's batch of 1)
                assert g.shape == ((np.size(w), 1) if len(shape) < 2 else (int(np.prod(shape[:-1])), shape[-1]))
                assert np.max(np.abs(np.reshape(g, shape) - w), initial=0.0) <= 1e-13 * scale, role


@pytest.mark.parametrize("name", ["double_pendulum", "random_tree", "free_flyer", "gyroscope_spinning_rotor"])
def test_casadi_ad_equals_central_differences(name, generated, rng):
    """casadi.jacobian of the SX graph (the Function called on SX symbols, its graph inlined) of the forward and
    inverse dynamics along every input equals central differences of the NumPy module (to 1e-7 relative, the
    differences' own error); on the free-flyer along q's nq entries (the quaternion's too)."""
    model, np_module, module, _ = generated(name)
    for role in ("forward_dynamics", "inverse_dynamics"):
        f = module.functions(analytic=False)[role]
        symbols = [ca.SX.sym(f.name_in(k), f.sparsity_in(k)) for k in range(f.n_in())]
        out = f(*symbols)
        out = out[0] if isinstance(out, (tuple, list)) else out
        assert isinstance(out, ca.SX)
        J = ca.Function("J", symbols, [ca.jacobian(out, x) for x in symbols])
        args = random_inputs(model, role, rng) + [perturbed(np_module, rng)]
        got = evaluate(J, args)
        for k, a in enumerate(args):
            a = np.atleast_1d(np.asarray(a, dtype=float))
            if not a.size:  # (a model without parameters)
                continue
            cd = central_differences(lambda x: getattr(np_module, role)(
                *[x if j == k else (args[j] if np.ndim(args[j]) else args[j]) for j in range(len(args))]), a)
            cd = np.reshape(cd, (-1, a.size))
            assert got[k].shape == cd.shape
            assert np.max(np.abs(got[k] - cd), initial=0.0) <= 1e-7 * max(1.0, float(np.max(np.abs(cd)))), \
                (role, f.name_in(k))


@pytest.mark.parametrize("name", ["double_pendulum", "arm3", "random_tree"])
def test_attached_jacobians_are_the_derivative_routines(name, generated, rng):
    """Forward and inverse dynamics carry the derivative routines as their Jacobian: casadi.jacobian through an MX
    call gives the derivative routines' matrices (and A^-1 / A along tau / qdd) to rounding, and CasADi's own AD
    (analytic=False) agrees with them to 1e-10."""
    model, np_module, module, _ = generated(name)
    assert module.ANALYTIC == {"inverse_dynamics": "inverse_dynamics_derivatives",
                               "forward_dynamics": "forward_dynamics_derivatives"}
    for role, derivative, matrix in (("forward_dynamics", "forward_dynamics_derivatives", "inertia_inverse"),
                                     ("inverse_dynamics", "inverse_dynamics_derivatives", "inertia")):
        analytic, plain = module.functions()[role], module.functions(analytic=False)[role]
        args = random_inputs(model, role, rng) + [perturbed(np_module, rng)]
        d_q, d_qd = getattr(np_module, derivative)(*args)
        m = getattr(np_module, matrix)(args[0], args[-1])
        for f in (analytic, plain):
            symbols = [ca.MX.sym(f.name_in(k), f.sparsity_in(k)) for k in range(f.n_in())]
            out = f(*symbols)
            J = ca.Function("J", symbols, [ca.jacobian(out, x) for x in symbols])
            got = evaluate(J, args)
            tol = 1e-13 if f is analytic else 1e-10
            for g, w in zip(got, (d_q, d_qd, m)):
                assert rel(g, w) <= tol, (role, f is analytic)
        # along p: CasADi's AD of the graph in both
        if model.parameters:
            assert rel(evaluate(J, args)[-1], evaluate(ca.Function("K", symbols, [ca.jacobian(out, symbols[-1])]),
                                                       args)[0]) <= 1e-13


def test_casadi_jacobian_takes_the_attached_routines(generated, rng):
    """The Jacobian CasADi takes is the attached one: with a derivative routine replaced by twice its value (in a
    fresh copy of the module) casadi.jacobian through an MX call, and IPOPT's, gives twice the matrices along q and
    qd and the same along tau."""
    model, np_module, _, folder = generated("double_pendulum")
    module = import_module(folder / "double_pendulum_casadi.py")
    d = module.forward_dynamics_derivatives
    symbols = [ca.SX.sym(d.name_in(k), d.sparsity_in(k)) for k in range(d.n_in())]
    module._BUILT[("forward_dynamics_derivatives", False)] = ca.Function(
        "forward_dynamics_derivatives", symbols, [2 * x for x in d(*symbols)], d.name_in(), d.name_out())
    f = module.forward_dynamics
    mx = [ca.MX.sym(f.name_in(k), f.sparsity_in(k)) for k in range(f.n_in())]
    J = ca.Function("J", mx, [ca.jacobian(f(*mx), x) for x in mx[:3]])
    args = random_inputs(model, "forward_dynamics", rng) + [np_module.PARAMETERS]
    d_q, d_qd = np_module.forward_dynamics_derivatives(*args)
    got = evaluate(J, args)
    assert rel(got[0], 2 * d_q) <= 1e-13 and rel(got[1], 2 * d_qd) <= 1e-13
    assert rel(got[2], np_module.inertia_inverse(args[0])) <= 1e-13


def test_free_flyer_jacobians_along_q_entries(generated, rng):
    """Quaternion pairs: the derivative routines are in the tangent space (nv columns, q has nq entries); the
    attached Jacobian along q takes their columns at the hinges' entries and CasADi's AD along the free-flyer's
    seven: equal to CasADi's AD of the whole graph (analytic=False) to 1e-10 along q, qd and tau, at states with a
    unit quaternion and with the quaternion's entries perturbed (the graph's derivative, off the unit sphere too)."""
    model, np_module, module, _ = generated("free_flyer")
    assert model.nq == model.nv + 1 and set(module.ANALYTIC) == {"inverse_dynamics", "forward_dynamics"}
    assert "tangent space" in module.__doc__
    for role in ("forward_dynamics", "inverse_dynamics"):
        got = []
        for f in (module.functions()[role], module.functions(analytic=False)[role]):
            symbols = [ca.MX.sym(f.name_in(k), f.sparsity_in(k)) for k in range(f.n_in())]
            got.append(ca.Function("J", symbols, [ca.jacobian(f(*symbols), x) for x in symbols[:3]]))
        for scale in (1.0, 1.3):
            args = random_inputs(model, role, rng) + [perturbed(np_module, rng)]
            args[0] = np.array(args[0], dtype=float)
            args[0][3:7] *= scale
            analytic, plain = evaluate(got[0], args), evaluate(got[1], args)
            for a, b in zip(analytic, plain):
                assert a.shape == b.shape and rel(a, b) <= 1e-10, role


@pytest.mark.pinocchio
def test_jacobians_equal_pinocchio(generated, rng):
    """arm3: casadi.jacobian (through the attached routines) of forward and inverse dynamics along q and qd equals
    Pinocchio's computeABADerivatives and computeRNEADerivatives to 1e-9."""
    from pinocchio_reference import pin, pinocchio_model, pinocchio_q

    model, np_module, module, _ = generated("arm3")
    pm = pinocchio_model(URDF)
    p = np.asarray(module.PARAMETERS.full()).ravel()
    for role, pinocchio in (("forward_dynamics", pin.computeABADerivatives),
                            ("inverse_dynamics", pin.computeRNEADerivatives)):
        f = module.functions()[role]
        symbols = [ca.MX.sym(f.name_in(k), f.sparsity_in(k)) for k in range(f.n_in())]
        J = ca.Function("J", symbols, [ca.jacobian(f(*symbols), x) for x in symbols[:2]])
        for _ in range(2):
            q, qd, u = (rng.uniform(-1.5, 1.5, model.nq) for _ in range(3))
            got = evaluate(J, [q, qd, u, p])
            data = pm.createData()
            want = [x.copy() for x in pinocchio(pm, data, pinocchio_q(pm, q), qd, u)[:2]]
            for g, w in zip(got, want):
                assert rel(g, w) <= 1e-9


def test_inlined_into_sx_and_mx_graphs(generated, rng):
    """Called on SX symbols a Function's graph joins the caller's (an SX expression, no call node); on MX it is a
    call; both evaluate to the numbers; an RK4 step of the forward dynamics composes (used by the example)."""
    model, np_module, module, _ = generated("double_pendulum")
    fd = module.forward_dynamics
    n = model.nq
    x, u = ca.SX.sym("x", 2 * n), ca.SX.sym("u", n)
    qdd = fd(x[:n], x[n:], u, module.PARAMETERS)
    assert isinstance(qdd, ca.SX) and qdd.shape == (n, 1)
    step = ca.Function("step", [x, u], [ca.vertcat(x[n:], qdd)])
    assert step.n_instructions() > 0 and not step.has_free()
    xm, um = ca.MX.sym("x", 2 * n), ca.MX.sym("u", n)
    mx = ca.Function("step_mx", [xm, um], [ca.vertcat(xm[n:], fd(xm[:n], xm[n:], um, module.PARAMETERS))])
    q, qd, tau = (rng.normal(size=n) for _ in range(3))
    want = np_module.forward_dynamics(q, qd, tau)
    for f in (step, mx):
        got = f(np.concatenate([q, qd]), tau).full().ravel()
        assert rel(got[n:], want) <= 1e-13 and rel(got[:n], qd) == 0.0


def test_status_output_of_a_singular_system(generated):
    """four_bar at q = 0 is at a dead centre: the NumPy module raises; the Function's status output is nonzero
    there and zero at a regular state."""
    model, np_module, module, _ = generated("four_bar")
    f = module.constrained_forward_dynamics
    assert f.name_out(f.n_out() - 1) == "status" and "constrained_forward_dynamics" in module.STATUS
    p = [0.1, 0.3, 0.25, 0.3]
    zero = np.zeros(3)
    assert evaluate(f, [np.zeros(3), zero, zero, p])[-1].item() != 0.0
    assert evaluate(f, [np.full(3, 0.3), zero, zero, p])[-1].item() == 0.0
    with pytest.raises(np.linalg.LinAlgError), np.errstate(all="ignore"):
        np_module.constrained_forward_dynamics(np.zeros(3), zero, zero, np.array(p))


def test_imports_casadi_alone_deterministic_lazy(generated):
    """Not in the default set; the module imports only casadi (and the standard library); the same input gives
    the same bytes; importing builds no Function (they are built on first use)."""
    assert "casadi" not in [t.name for t in default_targets()]
    model, _, module, folder = generated("double_pendulum")
    texts = [generate(model, targets="casadi").files["double_pendulum_casadi.py"] for _ in range(2)]
    assert texts[0] == texts[1] == (folder / "double_pendulum_casadi.py").read_text()
    tree = ast.parse(texts[0])
    imported = {alias.name.split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.Import)
                for alias in node.names}
    imported |= {node.module.split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert "casadi" in imported and imported - {"casadi"} <= set(sys.stdlib_module_names)
    fresh = import_module(folder / "double_pendulum_casadi.py")
    assert fresh._BUILT == {} and isinstance(fresh.inertia, ca.Function) and list(fresh._BUILT) == [("inertia", False)]
    with pytest.raises(AttributeError):
        fresh.no_such_routine


def test_hostile_names_stay_strings(tmp_path):
    """A joint named with Python syntax and a hostile file name: the module imports and runs nothing (no marker
    file), JOINTS holds the name as given."""
    marker = Path("/tmp/aggsym_pwned_casadi")
    if marker.exists():
        marker.unlink()
    evil = '"""; import os; os.system("touch /tmp/aggsym_pwned_casadi") #\' \\'
    text = URDF.read_text().replace('name="shoulder"', 'name="' + evil.replace('"', "&quot;") + '"')
    path = tmp_path / 'evil """ name.urdf'
    path.write_text(text)
    model = aggsym.load(path, name="evil")
    assert evil in [c.joint for c in model.coordinates]
    write(generate(model, targets="casadi,numpy,manifest"), tmp_path / "out")
    module = import_module(tmp_path / "out" / "evil_casadi.py")
    assert evil in module.JOINTS and not marker.exists()
    assert module.inertia(np.zeros(3), module.PARAMETERS).shape == (3, 3)


def test_check_has_a_casadi_column_with_derivatives(capsys):
    assert main(["check", str(model_path("double_pendulum")), "--trials", "3", "--targets", "casadi"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[1].split()[:2] == ["routine", "CasADi"] and "d forward_dynamics" in out
    assert "ok: every routine within" in out


def _example(name, folder, *args):
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": str(ROOT)}
    run = subprocess.run([sys.executable, str(ROOT / "examples" / name), *args], cwd=folder, env=env,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    return run.stdout


def test_swing_up_example_converges(tmp_path):
    """examples/casadi_swing_up.py (a few seconds): IPOPT's status Solve_Succeeded, its iterations printed, the
    plot written into the current folder."""
    out = _example("casadi_swing_up.py", tmp_path)
    assert "return status: Solve_Succeeded" in out and "iter" in out and "objective" in out
    assert (tmp_path / "casadi_swing_up.png").stat().st_size > 0


@pytest.mark.compiler
def test_codegen_example_compiles_and_agrees(tmp_path):
    """examples/casadi_codegen.py: CasADi's C of the RK4 step and its Jacobian compiles, loads and gives the
    virtual machine's values (to rounding)."""
    out = _example("casadi_codegen.py", tmp_path, "--batch", "50", "--folder", str(tmp_path / "build"))
    lines = [line for line in out.splitlines() if "per state" in line]
    assert len(lines) == 2
    assert all(float(line.rsplit("difference ", 1)[1].rstrip(")")) < 1e-12 for line in lines)


@pytest.mark.parametrize("name", ["random_tree", "arm3"])
def test_shared_reciprocals_stay_one_division(name, generated):
    """CasADi folds y*(1/d) into y/d: a reciprocal the straight line shares is written 2/(2*d), so the Functions
    of forward dynamics and A^-1 divide no more often than the generated code does (the manifest's counts)."""
    import json

    model, _, module, folder = generated(name)
    ops = json.loads((folder / f"{model.name}.json").read_text())["ops"]
    for role in ("forward_dynamics", "inertia_inverse"):
        f = module.functions(analytic=False)[role]
        codes = [f.instruction_id(k) for k in range(f.n_instructions())]
        divisions = sum(c in (ca.OP_DIV, ca.OP_INV) for c in codes)
        assert 0 < divisions <= ops[role]["div"], (role, divisions, ops[role]["div"])


def test_routines_with_a_status_carry_the_derivative_routines_too(tmp_path, rng):
    """A point-mass head (A(q) singular where the neck pitch is 0: forward dynamics has a status output): the
    attached Jacobian is the derivative routines' (and A^-1 along tau) to rounding, CasADi's AD agrees to 1e-10, and
    the status output's Jacobian is zero."""
    from test_regularity import head_urdf

    path = tmp_path / "head.urdf"
    path.write_text(head_urdf())
    model = select_routines(aggsym.load(path), DERIVATIVES.split(","))
    write(generate(model, targets="numpy,casadi,manifest"), tmp_path / "out")
    np_module = import_module(tmp_path / "out" / "head.py")
    module = import_module(tmp_path / "out" / "head_casadi.py")
    assert "forward_dynamics" in module.STATUS and module.ANALYTIC["forward_dynamics"] == "forward_dynamics_derivatives"
    f, plain = module.functions()["forward_dynamics"], module.functions(analytic=False)["forward_dynamics"]
    q, qd, tau = rng.uniform(0.2, 1.2, 3), rng.normal(size=3), rng.normal(size=3)
    d_q, d_qd = np_module.forward_dynamics_derivatives(q, qd, tau)
    for g, tol in ((f, 1e-13), (plain, 1e-10)):
        symbols = [ca.MX.sym(g.name_in(k), g.sparsity_in(k)) for k in range(g.n_in())]
        qdd, status = g(*symbols)
        J = ca.Function("J", symbols, [ca.jacobian(qdd, x) for x in symbols[:3]]
                        + [ca.jacobian(status, x) for x in symbols[:3]])
        got = evaluate(J, [q, qd, tau, module.PARAMETERS])
        for a, b in zip(got, (d_q, d_qd, np_module.inertia_inverse(q))):
            assert rel(a, b) <= tol
        assert all(not np.any(s) for s in got[3:])
