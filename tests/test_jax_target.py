"""The JAX target (issue 32, items 1, 2, 4): NAME_jax.py has every routine of the NumPy module with the same
names, arguments and shapes, equal to it in float64 (to 1e-12), over broadcast batch dimensions, the dtype
following the inputs; jit, vmap, grad, jacfwd, jacrev and hessian go through every routine, gradients in q, qd,
tau and p agree with central differences; a singular system gives NaN where NumPy raises; ``aggsym check`` has
a JAX column in float64 and float32; the module imports only jax and the standard library."""
from __future__ import annotations

import ast
import sys

import numpy as np
import pytest

import aggsym
from aggsym.cli import main
from aggsym.codegen.generate import generate
from aggsym.codegen.targets import TARGETS, default_targets
from aggsym.contract import select_routines
from conftest import model_path
from jax_support import (arguments, as_tuple, central_differences, float64, four_bar_dead_centre, jax, jnp, modules,
                         relative, routines)

SMALL = ["planar_2link", "four_bar", "gyroscope_spinning_rotor"]  # every routine; constraints; the time t


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """{name: (NumPy module, JAX module)}: planar_2link with every routine (derivatives and regressor too), the
    four-bar (constrained forward dynamics with its status), the spinning rotor (time-dependent)."""
    out = {}
    for name in SMALL:
        model = aggsym.load(model_path(name))
        if name == "planar_2link":
            model = select_routines(model, ["all"])
        out[name] = modules(model, tmp_path_factory.mktemp(name))
    return out


def test_jax_is_a_target_outside_the_default_set():
    assert TARGETS["jax"].column == "JAX"
    assert "jax" not in [t.name for t in default_targets()]


def test_the_module_imports_only_jax_and_the_standard_library(small):
    _, jm = small["planar_2link"]
    tree = ast.parse(open(jm.__file__).read())
    roots = {alias.name.split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.Import) for alias in node.names}
    roots |= {node.module.split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert roots - set(sys.stdlib_module_names) == {"jax"}


def test_generation_is_deterministic():
    model = aggsym.load(model_path("double_pendulum"))
    first = generate(model, targets="jax").files
    assert first == generate(model, targets="jax").files
    assert list(first) == ["double_pendulum_jax.py"]


@pytest.mark.parametrize("name", SMALL)
def test_every_routine_equals_the_numpy_module(small, name, rng):
    """Same routines, constants, shapes; float64 values to 1e-12 relative, batched (2, 3) and unbatched."""
    npm, jm = small[name]
    assert routines(jm) == routines(npm)
    for const in ("NAME", "NQ", "NV", "COORDINATES", "JOINTS", "PARAMETER_NAMES"):
        assert getattr(jm, const) == getattr(npm, const)
    assert tuple(jm.PARAMETERS) == tuple(npm.PARAMETERS)
    with float64():
        for role in routines(npm):
            for batch in ((), (2, 3)):
                args = arguments(npm, role, rng, batch)
                try:
                    want = getattr(npm, role)(*args)
                except np.linalg.LinAlgError:
                    continue
                got = getattr(jm, role)(*args)
                assert [np.shape(x) for x in as_tuple(got)] == [np.shape(x) for x in as_tuple(want)], role
                assert all(x.dtype == jnp.float64 for x in as_tuple(got))
                assert relative(got, want) < 1e-12, role


def test_batch_dimensions_broadcast_like_numpy(small, rng):
    npm, jm = small["planar_2link"]
    q, qd, tau = rng.normal(size=(4, 1, 2)), rng.normal(size=(3, 2)), rng.normal(size=(2,))
    p = np.asarray(npm.PARAMETERS) * rng.uniform(0.5, 2.0, (3, 5))  # a batch of parameters too
    with float64():
        got = jm.forward_dynamics(q, qd, tau, p)
        assert got.shape == (4, 3, 2)
        assert relative(got, npm.forward_dynamics(q, qd, tau, p)) < 1e-12
        assert jm.kinetic_energy(q, qd).shape == npm.kinetic_energy(q, qd).shape == (4, 3)


def test_the_dtype_follows_the_inputs(small, rng):
    """float32 in, float32 out (x64 on or off), close to the float64 result; float64 in with x64: float64."""
    npm, jm = small["planar_2link"]
    q, qd, tau = (rng.normal(size=(5, 2)).astype(np.float32) for _ in range(3))
    for context in (float64, lambda: __import__("contextlib").nullcontext()):
        with context():
            qdd = jm.forward_dynamics(q, qd, tau)
            A = jm.inertia(jnp.asarray(q))
            assert qdd.dtype == A.dtype == jnp.float32
            assert relative(qdd, npm.forward_dynamics(q, qd, tau)) < 1e-5
    with float64():
        assert jm.forward_dynamics(q.astype(np.float64), qd, tau).dtype == jnp.float64
        assert jm.inertia([0.1, 0.2]).dtype == jnp.float64  # a list: x64's default float


def test_a_singular_system_gives_nan_where_numpy_raises(small):
    """The four-bar at its dead centre q = 0 (tests/test_constraints.py): NumPy raises LinAlgError; JAX, which
    cannot raise on a value under jit, returns NaN in every output of that state and only there."""
    npm, jm = small["four_bar"]
    q, qd, tau, p = four_bar_dead_centre(npm)
    with float64():
        for f in (jm.constrained_forward_dynamics, jax.jit(jm.constrained_forward_dynamics)):
            qdd, lam = f(q, qd, tau, p)
            assert np.isnan(qdd[1]).all() and np.isnan(lam[1]).all()
            want = npm.constrained_forward_dynamics(q[0], np.zeros(3), np.zeros(3), p)
            assert relative((qdd[0], lam[0]), want) < 1e-12


def _scalar_of(jm, role, args):
    """A scalar function of the routine's first input (the others fixed), through every output."""
    f = getattr(jm, role)

    def g(x):
        return sum(jnp.sum(jnp.sin(o)) for o in as_tuple(f(x, *args[1:])))
    return g


# the routines the transforms go through: every routine of planar_2link (all of the contract that apply to it),
# and those of the other small models that add something (a status; the time t)
THROUGH = {"planar_2link": None, "four_bar": ["constrained_forward_dynamics", "constraint_jacobian"],
           "gyroscope_spinning_rotor": ["forward_dynamics", "inverse_dynamics"]}
# the hessian (jacfwd of jacrev, both checked on every routine above) of a sample of planar_2link's routines: one
# of each kind (a matrix of q, the custom derivatives of both dynamics and of a derivative routine, frames, a
# regressor); of every routine it took a fifth of the suite's JAX time
HESSIAN = {"inertia", "inverse_dynamics", "forward_dynamics", "inverse_dynamics_derivatives", "frame_poses",
           "base_regressor"}


@pytest.mark.slow
@pytest.mark.parametrize("name", SMALL)
def test_jit_vmap_grad_jacfwd_jacrev_hessian_through_every_routine(small, name, rng):
    """Per routine: jit equals eager; vmap over a batch equals the batched call; jacfwd equals jacrev and central
    differences along the first input (q, or gamma); grad along p equals central differences; the hessian of a
    scalar of the outputs is finite and symmetric (on planar_2link, of a sample: HESSIAN)."""
    npm, jm = small[name]
    assert THROUGH[name] is not None or HESSIAN <= set(routines(jm))
    with float64():
        for role in THROUGH[name] or routines(jm):
            f = getattr(jm, role)
            args = arguments(npm, role, rng)
            assert relative(jax.jit(f)(*args), getattr(npm, role)(*args)) < 1e-12, role
            batch = arguments(npm, role, rng, (3,))
            assert relative(jax.jit(jax.vmap(f))(*batch), getattr(npm, role)(*batch)) < 1e-12, role
            fwd = as_tuple(jax.jit(jax.jacfwd(f))(*args))
            rev = as_tuple(jax.jit(jax.jacrev(f))(*args))
            x0 = np.asarray(args[0])
            flat = central_differences(lambda x: np.concatenate([np.ravel(o) for o in as_tuple(f(x, *args[1:]))]), x0)
            fd, start = [], 0
            for a in fwd:
                size = int(np.prod(a.shape[:-1]))
                fd.append(flat[start:start + size].reshape(a.shape))
                start += size
            for a, b, c in zip(fwd, rev, fd):
                assert relative(a, b) < 1e-10, role
                assert relative(a, c, floor=1.0) < 1e-6, role
            p = np.asarray(npm.PARAMETERS, dtype=float)
            if p.size:
                def of_p(p, args=args, f=f):
                    return sum(jnp.sum(o) for o in as_tuple(f(*args, p)))
                g = jax.jit(jax.grad(of_p))(p)
                assert relative(g, central_differences(lambda x: np.asarray(of_p(x)), p), floor=1.0) < 1e-6, role
            if THROUGH[name] is None and role not in HESSIAN:
                continue
            H = np.asarray(jax.jit(jax.hessian(_scalar_of(jm, role, args)))(x0))
            assert np.isfinite(H).all() and np.allclose(H, H.T, rtol=1e-10, atol=1e-10), role


def test_check_has_a_jax_column_in_float64_and_float32(capsys):
    """aggsym check: the JAX module against the numeric twin, float64 held to --tol, float32 to the float C's
    bounds (the manifest's float_tolerance), the NumPy module beside it."""
    model = str(model_path("double_pendulum"))
    assert main(["check", model, "--targets", "numpy,jax", "--trials", "3"]) == 0
    out = capsys.readouterr().out
    assert "JAX" in out.splitlines()[1] and "NumPy" in out.splitlines()[1] and "MISMATCH" not in out
    assert main(["check", model, "--targets", "jax", "--scalar", "float", "--trials", "3"]) == 0
    out = capsys.readouterr().out
    assert "JAX bound" in out.splitlines()[1] and "1e-04" in out


def test_a_quaternion_free_flyer_equals_the_numpy_module(tmp_path, rng):
    """nq = nv + 1, and integrate(q, v, dt) with its time step: every routine as the NumPy module's."""
    import warnings

    from aggsym.errors import ModelWarning
    from helpers import robot_path

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(robot_path("double_pendulum"), floating_base="quaternion")
    npm, jm = modules(model, tmp_path)
    assert jm.NQ == jm.NV + 1 and jm.VELOCITIES == npm.VELOCITIES and "integrate" in routines(jm)
    with float64():
        for role in routines(npm):
            args = arguments(npm, role, rng, (3,))
            args[0][..., 3:7] /= np.linalg.norm(args[0][..., 3:7], axis=-1, keepdims=True)
            want, got = getattr(npm, role)(*args), getattr(jm, role)(*args)
            assert [np.shape(x) for x in as_tuple(got)] == [np.shape(x) for x in as_tuple(want)], role
            assert relative(got, want) < 1e-12, role
