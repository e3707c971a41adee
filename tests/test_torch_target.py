"""The PyTorch target (issue 32): NAME_torch.py against the NumPy module (every routine, float64 to 1e-12 and
float32 to the float C's bounds), batches, broadcasting, dtype and device, autograd through every routine
(torch.autograd.gradcheck in float64), the generated derivatives wired in as an autograd.Function (equal to
plain autograd, in vjp, jvp, vmap and jacrev), the NaN of a singular system, and ``aggsym check``."""
from __future__ import annotations

import ast
import sys
import warnings

import numpy as np
import pytest
import torch

import aggsym
from aggsym.cli import main
from aggsym.codegen.check import CONDITIONING, _inertia_condition, random_inputs
from aggsym.codegen.compile import import_module
from aggsym.codegen.generate import generate, write
from aggsym.codegen.targets import default_targets
from aggsym.contract import FLOAT_PER_CONDITION, FLOAT_TIME, FLOAT_TOLERANCE, FLOAT_TOLERANCE_DEFAULT, select_routines
from aggsym.errors import ModelWarning
from aggsym.twin import NumericTwin
from conftest import model_path
from helpers import BALL_BETWEEN_HINGES, central_differences, relative_error, robot_path

DERIVATIVES = "default,inverse_dynamics_derivatives,forward_dynamics_derivatives"
# small models that show a point each: plain, prescribed motions (t), a singular system's status (four_bar's
# constrained forward dynamics), the support problems (spacecraft)
SMALL = ["double_pendulum", "gyroscope_spinning_rotor", "four_bar", "spacecraft"]
ROUTINES_OF = {"spacecraft": "support_coefficients,support_direct,support_inverse"}  # (its others: as the rest)
_CACHE = {}


def modules(tmp_path_factory, path, routines="all", **options):
    """(model, NumPy module, PyTorch module) of a model generated with ``--targets numpy,torch,manifest``."""
    key = (str(path), routines, tuple(sorted(options.items())))
    if key not in _CACHE:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ModelWarning)
            model = aggsym.load(path, **options)
        model = select_routines(model, routines.split(","))
        folder = tmp_path_factory.mktemp(model.name)
        write(generate(model, targets="numpy,torch,manifest"), folder)
        _CACHE[key] = (model, import_module(folder / f"{model.name}.py"),
                       import_module(folder / f"{model.name}_torch.py"))
    return _CACHE[key]


def batch_inputs(model, role, rng, n=3):
    """n random states of a routine's inputs stacked (t: one per state)."""
    states = [random_inputs(model, role, rng) for _ in range(n)]
    return [np.array([s[k] for s in states]) for k in range(len(states[0]))]


def outputs(x):
    return x if isinstance(x, tuple) else (x,)


def numpy_per_state(module, role, args):
    """The NumPy module's outputs state by state, None where it raises LinAlgError (a singular system)."""
    out = []
    for k in range(len(args[0])):
        try:
            out.append(outputs(getattr(module, role)(*[a[k] for a in args])))
        except np.linalg.LinAlgError:
            out.append(None)
    return out


@pytest.mark.parametrize("name", SMALL)
def test_every_routine_equals_the_numpy_module(name, tmp_path_factory, rng):
    """float64: every output of every routine equal to the NumPy module's to 1e-12 (relative to the largest value
    the routine returns), batched and for one state, same shapes; float32: within the float C's bound of the
    manifest (FLOAT_TOLERANCE, times cond(A) for the routines that solve with A)."""
    model, np_module, module = modules(tmp_path_factory, model_path(name), ROUTINES_OF.get(name, "all"))
    twin = NumericTwin(model)
    for role in [r.role for r in aggsym.contract.routines_for(model)]:
        args = batch_inputs(model, role, rng)
        want = numpy_per_state(np_module, role, args)
        got64 = outputs(getattr(module, role)(*[torch.tensor(a) for a in args]))
        got32 = outputs(getattr(module, role)(*[torch.tensor(a, dtype=torch.float32) for a in args]))
        assert all(g.dtype == torch.float64 for g in got64) and all(g.dtype == torch.float32 for g in got32)
        bound = FLOAT_TOLERANCE.get(role, FLOAT_TOLERANCE_DEFAULT) * (FLOAT_TIME if model.time_dependent else 1)
        for k, ref in enumerate(want):
            if ref is None:  # singular here: NaN in every output of this state
                assert all(torch.isnan(g[k]).all() for g in got64)
                continue
            one = outputs(getattr(module, role)(*[torch.tensor(a[k]) for a in args]))
            scale = max(float(np.max(np.abs(r))) if np.size(r) else 0.0 for r in ref) or 1.0
            if role in CONDITIONING:  # a solve: rounding grows with its matrix's condition number (as aggsym check)
                scale *= CONDITIONING[role](twin, role, [a[k] for a in args])
            cond = _inertia_condition(twin, role, [a[k] for a in args]) if role in FLOAT_PER_CONDITION else 1.0
            for r, g, g1, g32 in zip(ref, got64, one, got32):
                assert tuple(g.shape[1:]) == np.shape(r) and tuple(g1.shape) == np.shape(r), role
                assert relative_error(g[k].numpy(), r, scale) < 1e-12, role
                assert relative_error(g1.numpy(), r, scale) < 1e-12, role
                assert relative_error(g32[k].double().numpy(), r, scale) < bound * cond, role


def test_batch_dimensions_broadcast_p_included(tmp_path_factory, rng):
    model, np_module, module = modules(tmp_path_factory, model_path("double_pendulum"), DERIVATIVES)
    n = model.nq
    q, qd, qdd = rng.normal(size=(2, 1, n)), rng.normal(size=(3, n)), rng.normal(size=n)
    p = np_module.PARAMETERS * rng.uniform(0.5, 2.0, size=(2, 1, len(np_module.PARAMETERS)))
    for analytic in (True, False):
        tau = module.inverse_dynamics(*map(torch.tensor, (q, qd, qdd, p)), analytic=analytic)
        assert tau.shape == (2, 3, n)
        for i in range(2):
            for j in range(3):
                assert relative_error(tau[i, j].numpy(), np_module.inverse_dynamics(q[i, 0], qd[j], qdd, p[i, 0])) \
                    < 1e-12
    A = module.inertia(torch.tensor(q[:, 0]))  # a routine of q and p alone
    assert A.shape == (2, n, n)


def test_dtype_and_device_follow_the_inputs(tmp_path_factory):
    """float32 in, float32 out; float32 q with float64 p: float64 (torch's promotion); lists and NumPy arrays are
    accepted; on the meta device (no data: a stand-in for any device) the outputs, and the default p made inside,
    are there too: nothing in the module names a device."""
    model, np_module, module = modules(tmp_path_factory, model_path("double_pendulum"), DERIVATIVES)
    n = model.nq
    q32 = torch.zeros(4, n, dtype=torch.float32)
    assert module.forward_dynamics(q32, q32, q32).dtype == torch.float32
    assert module.forward_dynamics(q32, q32, q32, module.PARAMETERS).dtype == torch.float64
    assert module.inertia([0.1] * n).dtype == torch.get_default_dtype()
    assert module.inertia(np.zeros(n)).dtype == torch.float64
    meta = torch.empty(5, n, device="meta", dtype=torch.float64)
    for role, args in (("forward_dynamics", (meta, meta, meta)), ("inertia", (meta,)), ("kinetic_energy", (meta, meta))):
        out = getattr(module, role)(*args)
        assert out.device.type == "meta" and out.shape[0] == 5
    text = (module.__file__ and open(module.__file__, encoding="utf-8").read())
    assert "cpu" not in text and "cuda" not in text and "device=device" in text


@pytest.mark.parametrize("name", SMALL)
def test_gradcheck_through_every_routine(name, tmp_path_factory, rng):
    """torch.autograd.gradcheck (float64) of every routine along every input, p (and t) included."""
    model, _, module = modules(tmp_path_factory, model_path(name), ROUTINES_OF.get(name, "all"))
    for role in [r.role for r in aggsym.contract.routines_for(model)]:
        args = [torch.tensor(a, dtype=torch.float64, requires_grad=True) for a in random_inputs(model, role, rng)]
        p = module.PARAMETERS.clone().requires_grad_()
        takes_p = "p" in aggsym.contract.signature(aggsym.contract.ROUTINES[role], model)
        inputs = tuple(args) + ((p,) if takes_p else ())
        # (central differences of step 1e-5: the regressors of a spinning rotor reach 500, their differences
        # lose 1e-6 to rounding at the default step 1e-6)
        assert torch.autograd.gradcheck(getattr(module, role), inputs, eps=1e-5, atol=1e-5, rtol=1e-4,
                                        fast_mode=len(inputs[0]) > 3), role


def jacobians(module, role, args, analytic):
    """vmap(jacrev) of a routine along its three state inputs and p, per state of the batch."""
    def f(a, b, c, p):
        return getattr(module, role)(a, b, c, p, analytic=analytic)
    return torch.func.vmap(torch.func.jacrev(f, argnums=(0, 1, 2, 3)), in_dims=(0, 0, 0, None))(*args)


@pytest.mark.parametrize("robot", ["double_pendulum", "panda"])
def test_analytic_derivatives_equal_plain_autograd(robot, tmp_path_factory, rng):
    """inverse and forward dynamics: vmap(jacrev) along q, qd, qdd|tau and p through the generated derivatives
    equals plain autograd of the traced routine (a double pendulum, and Panda: 7 arm joints and 2 fingers); so do
    a vjp of a batch, jacfwd (the Function's jvp) and the Hessian along q (the derivative routines differentiated
    in turn)."""
    path = model_path(robot) if robot == "double_pendulum" else robot_path(robot)
    model, np_module, module = modules(tmp_path_factory, path, DERIVATIVES if robot == "double_pendulum" else
                                       "inertia,inverse_dynamics,forward_dynamics,inertia_inverse,"
                                       "inverse_dynamics_derivatives,forward_dynamics_derivatives")
    n = model.nq
    q, qd, u = (torch.tensor(rng.uniform(-1.5, 1.5, size=(3, n))) for _ in range(3))
    p = module.PARAMETERS * torch.tensor(rng.uniform(0.5, 2.0, size=module.PARAMETERS.shape))
    for role in ("inverse_dynamics", "forward_dynamics", "inverse_dynamics_derivatives",
                 "forward_dynamics_derivatives"):  # the values: the NumPy module's
        got = outputs(getattr(module, role)(q, qd, u, p))
        want = outputs(getattr(np_module, role)(q.numpy(), qd.numpy(), u.numpy(), p.numpy()))
        for a, b in zip(got, want):
            assert relative_error(a.numpy(), b) < 1e-12, role
    for role in ("inverse_dynamics", "forward_dynamics"):
        fast, plain = (jacobians(module, role, (q, qd, u, p), a) for a in (True, False))
        for a, b in zip(fast, plain):
            assert relative_error(a.numpy(), b.numpy()) < 1e-11, role
        x = [t.clone().requires_grad_() for t in (q, qd, u, p)]
        w = torch.tensor(rng.normal(size=(3, n)))
        grads = [torch.autograd.grad((getattr(module, role)(*x, analytic=a) * w).sum(), x, allow_unused=True,
                                     materialize_grads=True) for a in (True, False)]
        for a, b in zip(*grads):
            assert relative_error(a.numpy(), b.numpy()) < 1e-11, role
        f = getattr(module, role)
        jf = [torch.func.jacfwd(lambda z: f(z, qd[0], u[0], p, analytic=a))(q[0]) for a in (True, False)]
        assert relative_error(jf[0].numpy(), jf[1].numpy()) < 1e-11
        if robot == "double_pendulum":
            h = [torch.func.hessian(lambda z: f(z, qd[0], u[0], p, analytic=a).sum())(q[0]) for a in (True, False)]
            assert relative_error(h[0].numpy(), h[1].numpy()) < 1e-10


def test_analytic_derivatives_pass_gradcheck(tmp_path_factory, rng):
    model, _, module = modules(tmp_path_factory, model_path("double_pendulum"), DERIVATIVES)
    x = [torch.tensor(rng.normal(size=(2, model.nq)), requires_grad=True) for _ in range(3)]
    p = module.PARAMETERS.clone().requires_grad_()
    for role in ("inverse_dynamics", "forward_dynamics"):
        assert torch.autograd.gradcheck(getattr(module, role), (*x, p))
        assert torch.autograd.gradgradcheck(lambda *a: getattr(module, role)(*a), (*x, p))


@pytest.mark.parametrize("robot", ["free_flyer", "ball"])
def test_quaternion_pairs_gradient_along_q_is_exact(robot, tmp_path_factory, rng, monkeypatch):
    """Quaternion pairs, where the derivative routines are in the tangent space: a free-flyer (a double pendulum on
    it, nq = nv + 1) and a ball between two hinges (its quaternion in the middle of q).  Along q the Function takes
    the coordinates' columns from the derivative routine and generated columns along the quaternion entries that
    the routine reads (a free-flyer's four, not its origin; all four of a ball's): vmap(jacrev), jacfwd and a
    Jacobian row by row equal plain autograd and central differences of the NumPy module, and gradcheck passes
    along the free-flyer's raw entries.  Row by row, the first backward pass makes the matrices and the later ones
    reuse them."""
    if robot == "free_flyer":
        model, np_module, module = modules(tmp_path_factory, robot_path("double_pendulum"), DERIVATIVES,
                                           floating_base="quaternion")
        reads = {3: 0, 4: 1, 5: 2, 6: 3}  # the quaternion's entries: their columns; the origin (0, 1, 2): zero
    else:
        path = tmp_path_factory.mktemp("ball") / "ball.yaml"
        path.write_text(BALL_BETWEEN_HINGES)
        model, np_module, module = modules(tmp_path_factory, path, DERIVATIVES)
        reads = {1: 0, 2: 1, 3: 2, 4: 3}
    n, nq = model.nv, model.nq
    assert nq == n + 1
    for role in ("inverse_dynamics", "forward_dynamics"):
        entries = getattr(module, f"_{role.upper()}_ENTRIES")
        quaternion = [i for i in range(nq) if entries[i] >= n]
        assert {i: entries[i] - n for i in quaternion if entries[i] < n + 4} == reads, role
    k = min(reads)
    q = rng.normal(size=(2, nq))
    q[:, k:k + 4] /= np.linalg.norm(q[:, k:k + 4], axis=1, keepdims=True)
    q, qd, u = torch.tensor(q), *(torch.tensor(rng.normal(size=(2, n))) for _ in range(2))
    p = module.PARAMETERS
    for role in ("inverse_dynamics", "forward_dynamics"):
        f = getattr(module, role)
        fast, plain = (jacobians(module, role, (q, qd, u, p), a) for a in (True, False))
        assert fast[0].shape == (2, n, nq)
        for a, b in zip(fast, plain):  # (along p: none for the ball's model, which has no parameter)
            assert b.numel() == 0 or relative_error(a.numpy(), b.numpy()) < 1e-11, role
        jf = torch.func.jacfwd(lambda z: f(z, qd[0], u[0], p))(q[0])
        assert relative_error(jf.numpy(), plain[0][0].numpy()) < 1e-11, role
        cd = central_differences(lambda z: getattr(np_module, role)(z, qd[0].numpy(), u[0].numpy()), q[0].numpy())
        assert relative_error(fast[0][0].numpy(), cd, floor=1.0) < 1e-6, role
        made = []
        derivative = getattr(module, f"_{role}_derivatives")
        monkeypatch.setattr(module, f"_{role}_derivatives", lambda *a: made.append(1) or derivative(*a))
        x = [t.clone().requires_grad_() for t in (q, qd)]
        out = f(*x, u)
        rows = [torch.autograd.grad(out[:, i].sum(), x, retain_graph=True) for i in range(n)]
        assert len(made) == 1, role  # the first pass made the matrices, the other n - 1 reused them
        for j in range(2):
            got = torch.stack([r[j] for r in rows], -2)
            assert relative_error(got.numpy(), plain[j].numpy()) < 1e-11, role
        monkeypatch.undo()
        # (not the ball: its tip of 0.35 g reaches 8e6 in forward dynamics, where differences of gradcheck's step
        # lose 1e-3 to rounding)
        if robot == "free_flyer":
            x = [t.clone().requires_grad_() for t in (q, qd, u)]
            assert torch.autograd.gradcheck(f, tuple(x))


@pytest.mark.pinocchio
def test_jacobians_equal_pinocchio_analytical_derivatives(tmp_path_factory, rng):
    """Panda: vmap(jacrev) of the PyTorch forward and inverse dynamics along (q, qd) through the generated
    derivatives equals Pinocchio's computeABADerivatives and computeRNEADerivatives to 1e-9."""
    from pinocchio_reference import pin, pinocchio_model, pinocchio_q

    model, _, module = modules(tmp_path_factory, robot_path("panda"),
                               "inertia,inverse_dynamics,forward_dynamics,inertia_inverse,"
                               "inverse_dynamics_derivatives,forward_dynamics_derivatives")
    pm = pinocchio_model(robot_path("panda"))
    n = model.nq
    q, qd, u = (torch.tensor(rng.uniform(-1.5, 1.5, size=(2, n))) for _ in range(3))
    fd = jacobians(module, "forward_dynamics", (q, qd, u, module.PARAMETERS), True)
    inv = jacobians(module, "inverse_dynamics", (q, qd, u, module.PARAMETERS), True)
    for k in range(2):
        Q, v, a = pinocchio_q(pm, q[k].numpy()), qd[k].numpy(), u[k].numpy()
        data = pm.createData()  # (kept alive: Pinocchio returns references into its Data)
        dq, dv = (x.copy() for x in pin.computeRNEADerivatives(pm, data, Q, v, a)[:2])
        data = pm.createData()
        fq, fv = (x.copy() for x in pin.computeABADerivatives(pm, data, Q, v, a)[:2])
        for ours, theirs in ((inv[0][k], dq), (inv[1][k], dv), (fd[0][k], fq), (fd[1][k], fv)):
            assert relative_error(ours.numpy(), theirs, floor=1.0) < 1e-9


def test_singular_system_gives_nan_at_those_states(tmp_path_factory):
    """four_bar at q = 0 is at a dead centre (J A^-1 J^T singular): the NumPy module raises; the PyTorch function
    returns NaN at that state of the batch and the other state's values; under vmap too."""
    model, np_module, module = modules(tmp_path_factory, model_path("four_bar"))
    p = torch.tensor([0.1, 0.3, 0.25, 0.3], dtype=torch.float64)
    q = torch.tensor([[0.3, 0.3, 0.3], [0.0, 0.0, 0.0]], dtype=torch.float64)
    zero = torch.zeros(2, 3, dtype=torch.float64)
    for qdd, lam in (module.constrained_forward_dynamics(q, zero, zero, p),
                     torch.func.vmap(module.constrained_forward_dynamics, in_dims=(0, 0, 0, None))(q, zero, zero, p)):
        assert torch.isnan(qdd[1]).all() and torch.isnan(lam[1]).all()
        want = np_module.constrained_forward_dynamics(q[0].numpy(), zero[0].numpy(), zero[0].numpy(), p.numpy())
        assert relative_error(qdd[0].numpy(), want[0]) < 1e-12 and relative_error(lam[0].numpy(), want[1]) < 1e-12
    with pytest.raises(np.linalg.LinAlgError):
        np_module.constrained_forward_dynamics(q[1].numpy(), zero[1].numpy(), zero[1].numpy(), p.numpy())


@pytest.mark.slow
@pytest.mark.parametrize("base", ["fixed", "quaternion"])
def test_torch_compile(base, tmp_path_factory, rng):
    """torch.compile of the forward dynamics (the analytic Function inside) gives the eager values and gradients;
    on a quaternion free-flyer too (the Function's generated columns along the quaternion's entries)."""
    if base == "fixed":
        model, _, module = modules(tmp_path_factory, model_path("double_pendulum"), DERIVATIVES)
    else:
        model, _, module = modules(tmp_path_factory, robot_path("double_pendulum"), DERIVATIVES,
                                   floating_base="quaternion")
    q = rng.normal(size=(4, model.nq))
    if base == "quaternion":
        q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1, keepdims=True)
    x = [torch.tensor(q, requires_grad=True)] + [torch.tensor(rng.normal(size=(4, model.nv)), requires_grad=True)
                                                 for _ in range(2)]
    compiled = torch.compile(module.forward_dynamics)
    got, want = compiled(*x), module.forward_dynamics(*x)
    assert relative_error(got.detach().numpy(), want.detach().numpy()) < 1e-12
    for a, b in zip(torch.autograd.grad(got.sum(), x), torch.autograd.grad(want.sum(), x)):
        assert relative_error(a.numpy(), b.numpy()) < 1e-12


def test_the_module_imports_torch_alone_and_is_deterministic(tmp_path):
    """Not in the default set; the module imports only torch; the same input gives the same bytes."""
    assert "torch" not in [t.name for t in default_targets()]
    model = select_routines(aggsym.load(model_path("double_pendulum")), DERIVATIVES.split(","))
    texts = [generate(model, targets="torch").files["double_pendulum_torch.py"] for _ in range(2)]
    assert texts[0] == texts[1]
    tree = ast.parse(texts[0])
    imported = {alias.name.split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.Import)
                for alias in node.names}
    imported |= {node.module.split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert imported == {"torch"} or imported - {"torch"} <= set(sys.stdlib_module_names)


def test_check_compares_the_module_in_float64_and_float32(capsys):
    assert main(["check", str(model_path("double_pendulum")), "--trials", "3", "--targets", "torch"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[1].split() == ["routine", "PyTorch"] and "ok: every routine within 1e-12" in out
    assert main(["check", str(model_path("double_pendulum")), "--trials", "3", "--targets", "numpy,torch",
                 "--scalar", "float"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[1].split() == ["routine", "NumPy", "PyTorch", "PyTorch", "bound"]
    assert "its float bound (PyTorch) and 1e-12 (NumPy)" in out


def test_each_temporary_is_freed_after_its_last_read():
    """In every function of the module, each temporary no output reads is deleted right after the statement that
    last reads it, never read after, and the only ones left when the outputs are stacked are those the outputs read
    (Panda's A(q) would otherwise hold all of its 300 temporaries at once: time per state grew with B)."""
    import re

    from aggsym.codegen.targets.torch import freed

    assert freed(["q_0 = q[..., 0]", "x0 = q_0*2.0", "x1 = x0 + 1.0", "x2 = x1*x0", "x3 = x2 - q_0"],
                 [["x3", "x0"]], {"x0", "x1", "x2", "x3"}) == \
        ["q_0 = q[..., 0]", "x0 = q_0*2.0", "x1 = x0 + 1.0", "x2 = x1*x0", "del x1", "x3 = x2 - q_0", "del x2"]
    temp = re.compile(r"x\d+")
    checked = 0
    for name, routines in (("double_pendulum", DERIVATIVES), ("four_bar", "all")):
        model = select_routines(aggsym.load(model_path(name)), routines.split(","))
        tree = ast.parse(generate(model, targets="torch").files[f"{model.name}_torch.py"])
        for f in (node for node in tree.body if isinstance(node, ast.FunctionDef)):
            assigned, deleted, stacked = set(), set(), set()
            for statement in f.body:
                loads = {n.id for n in ast.walk(statement) if isinstance(n, ast.Name) and temp.fullmatch(n.id)
                         and isinstance(n.ctx, ast.Load)}
                assert not loads & deleted, (f.name, loads & deleted)
                if isinstance(statement, ast.Delete):
                    names = {t.id for t in statement.targets}
                    assert names <= assigned - deleted, f.name
                    deleted |= names
                elif not isinstance(statement, ast.Assign):
                    continue
                elif isinstance(statement.value, ast.Call) and getattr(statement.value.func, "id", None) == "_stack":
                    stacked |= loads
                else:
                    assigned |= {t.id for t in statement.targets if isinstance(t, ast.Name) and temp.fullmatch(t.id)}
            if stacked:
                assert assigned - deleted == stacked, f.name
                checked += bool(deleted)
    assert checked >= 10
