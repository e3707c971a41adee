"""The JAX target's custom derivatives (issue 32, item 2): where the module holds the derivative routines, forward
and inverse dynamics carry them as a jax.custom_jvp; jacfwd and jacrev then apply the generated matrices (the
derivative routine is called, not traced through), agree with plain tracing of the straight line, with central
differences, and on a robot with Pinocchio's computeABADerivatives / computeRNEADerivatives.  With a quaternion
free-flyer the q direction is traced (the routines are in the tangent space), and is still the exact derivative
along the entries of q as passed."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import aggsym
from aggsym.contract import select_routines
from aggsym.errors import ModelWarning
from conftest import model_path
from helpers import BALL_BETWEEN_HINGES, robot_path
from jax_support import central_differences, float64, jax, jnp, modules, relative

DERIVATIVES = ["inertia", "inertia_inverse", "inverse_dynamics", "forward_dynamics", "inverse_dynamics_derivatives",
               "forward_dynamics_derivatives"]


def _plain(jm, role):
    """The routine traced through its straight line (no custom JVP), p explicit."""
    private = getattr(jm, f"_{role}")
    return lambda *args: private(*(jnp.asarray(a, jnp.float64) for a in args))[0]


def traced_entries(module, monkeypatch) -> list:
    """The list to which every call of the module's _entries (the entries of q traced by the custom JVP) appends
    its entries."""
    traced, entries = [], module._entries

    def recorded(f, primals, k, index, tangent):
        traced.append(index)
        return entries(f, primals, k, index, tangent)
    monkeypatch.setattr(module, "_entries", recorded)
    return traced


class Counting:
    """Counts the calls of a module's private routine (the custom JVP rule calls it while tracing)."""

    def __init__(self, module, name, monkeypatch):
        self.calls = 0
        original = getattr(module, name)

        def counted(*args):
            self.calls += 1
            return original(*args)
        monkeypatch.setattr(module, name, counted)


@pytest.fixture(scope="module")
def planar(tmp_path_factory):
    model = select_routines(aggsym.load(model_path("planar_3link")), DERIVATIVES)
    return modules(model, tmp_path_factory.mktemp("planar_3link"))


@pytest.mark.slow
@pytest.mark.parametrize("role", ["forward_dynamics", "inverse_dynamics"])
def test_custom_and_plain_derivatives_agree_with_each_other_and_central_differences(planar, role, rng, monkeypatch):
    npm, jm = planar
    f, plain = getattr(jm, role), _plain(jm, role)
    n = jm.NV
    x = [rng.uniform(-1.5, 1.5, n), rng.normal(size=n), rng.normal(size=n), np.asarray(jm.PARAMETERS)]
    counter = Counting(jm, f"_{role}_derivatives", monkeypatch)
    with float64():
        for k in range(4):
            custom_fwd = jax.jacfwd(f, k)(*x)
            custom_rev = jax.jacrev(f, k)(*x)
            want = jax.jacfwd(plain, k)(*x)
            fd = central_differences(lambda v, k=k: getattr(npm, role)(*x[:k], v, *x[k + 1:]), x[k])
            assert relative(custom_fwd, want, floor=1.0) < 1e-12
            assert relative(custom_rev, want, floor=1.0) < 1e-12
            assert relative(want, fd, floor=1.0) < 1e-6
        assert counter.calls == 4  # q and qd, forward and reverse: the generated routine, not a trace through it
        # the derivative routine's own matrices are what jacfwd returns along q and qd
        dq, dqd = getattr(jm, f"{role}_derivatives")(*x[:3])
        assert relative(jax.jacfwd(f, 0)(*x[:3]), dq, floor=1.0) < 1e-14
        assert relative(jax.jacfwd(f, 1)(*x[:3]), dqd, floor=1.0) < 1e-14
        # batched: vmap of jacfwd, and jit of it
        X = [rng.uniform(-1.5, 1.5, (4, n)), rng.normal(size=(4, n)), rng.normal(size=(4, n))]
        J = jax.jit(jax.vmap(jax.jacfwd(f, (0, 1, 2))))(*X)
        for k in range(3):
            assert relative(J[k], jax.vmap(jax.jacfwd(plain, k))(*X, jnp.broadcast_to(x[3], (4, x[3].size))),
                            floor=1.0) < 1e-12
        # second order goes through the rule too
        H = jax.hessian(lambda q: jnp.sum(f(q, *x[1:3]) ** 2))(x[0])
        assert relative(H, jax.hessian(lambda q: jnp.sum(plain(q, *x[1:]) ** 2))(x[0]), floor=1.0) < 1e-10


def test_without_derivative_routines_the_functions_are_plain(tmp_path):
    model = select_routines(aggsym.load(model_path("double_pendulum")), ["forward_dynamics", "inverse_dynamics"])
    _, jm = modules(model, tmp_path)
    assert not hasattr(jm, "_forward_dynamics_custom") and not hasattr(jm, "_inverse_dynamics_custom")


@pytest.mark.slow
def test_quaternion_free_flyer_differentiates_along_the_entries_of_q(tmp_path, rng, monkeypatch):
    """nq = nv + 1: d qdd / d q along the entries of q as passed: the joints' columns from the generated routine,
    the quaternion's four entries traced one at a time, the origin's three not (the dynamics never read them: their
    columns are zero); d qdd / d qd by the generated routine; jacfwd and jacrev equal central differences of the
    NumPy module and plain tracing."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(robot_path("double_pendulum"), floating_base="quaternion")
    npm, jm = modules(select_routines(model, DERIVATIVES), tmp_path)
    assert jm.NQ == jm.NV + 1
    quat = rng.normal(size=4)
    q = np.concatenate([rng.normal(size=3), quat / np.linalg.norm(quat), rng.uniform(-1, 1, jm.NQ - 7)])
    qd, tau = rng.normal(size=jm.NV), rng.normal(size=jm.NV)
    counter = Counting(jm, "_forward_dynamics_derivatives", monkeypatch)
    traced = traced_entries(jm, monkeypatch)
    with float64():
        for k, x in enumerate((q, qd, tau)):
            got = jax.jacfwd(jm.forward_dynamics, k)(q, qd, tau)
            assert got.shape == (jm.NV, x.size)
            fd = central_differences(lambda v, k=k: npm.forward_dynamics(*[v if j == k else y
                                                                          for j, y in enumerate((q, qd, tau))]), x)
            assert relative(got, fd, floor=1.0) < 1e-5
            plain = jax.jacfwd(_plain(jm, "forward_dynamics"), k)(q, qd, tau, jm.PARAMETERS)
            assert relative(got, plain, floor=1.0) < 1e-12
            assert relative(jax.jacrev(jm.forward_dynamics, k)(q, qd, tau), plain, floor=1.0) < 1e-12
    assert counter.calls == 4  # along q and qd, by jacfwd and by jacrev
    assert traced == [(3, 4, 5, 6)] * 2  # along q, by jacfwd and by jacrev


@pytest.mark.slow
def test_a_ball_between_hinges_differentiates_along_the_entries_of_q(tmp_path, rng, monkeypatch):
    """A ball pair's quaternion in the middle of q (hinge, ball, hinge: nq = 6, nv = 5): the hinges' columns from
    the generated routine, the quaternion's four entries traced; jacfwd and jacrev along q equal plain tracing and
    central differences of the NumPy module."""
    (tmp_path / "ball.yaml").write_text(BALL_BETWEEN_HINGES)
    npm, jm = modules(select_routines(aggsym.load(tmp_path / "ball.yaml"), DERIVATIVES), tmp_path)
    assert (jm.NQ, jm.NV) == (6, 5)
    quat = rng.normal(size=4)
    q = np.concatenate([[0.7312], quat / np.linalg.norm(quat), [-1.2047]])
    qd, tau = rng.normal(size=5), rng.normal(size=5)
    counter = Counting(jm, "_forward_dynamics_derivatives", monkeypatch)
    traced = traced_entries(jm, monkeypatch)
    with float64():
        plain = jax.jacfwd(_plain(jm, "forward_dynamics"))(q, qd, tau, jm.PARAMETERS)
        fd = central_differences(lambda v: npm.forward_dynamics(v, qd, tau), q)
        for jac in (jax.jacfwd, jax.jacrev):
            got = jax.jit(jac(jm.forward_dynamics))(q, qd, tau)
            assert got.shape == (5, 6)
            assert relative(got, plain, floor=1.0) < 1e-12
            assert relative(got, fd, floor=1.0) < 1e-5  # (central differences' own error: masses over six decades)
    assert counter.calls == 2
    assert traced == [(1, 2, 3, 4)] * 2  # the ball's quaternion, all read


@pytest.mark.pinocchio
@pytest.mark.slow
def test_jax_derivatives_of_a_robot_equal_pinocchio(tmp_path, rng):
    """Panda (example-robot-data: 7 arm joints and 2 finger slides, fixed base): the float64 values equal the
    NumPy module's to 1e-12; jacfwd of forward dynamics and jacrev of inverse dynamics equal Pinocchio's
    computeABADerivatives and computeRNEADerivatives to 1e-8."""
    from pinocchio_reference import pin, pinocchio_model, pinocchio_q

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = select_routines(aggsym.load(robot_path("panda")), DERIVATIVES)
    npm, jm = modules(model, tmp_path)
    pm = pinocchio_model(robot_path("panda"))
    n = jm.NV
    q, v, a, tau = rng.uniform(-1.5, 1.5, n), rng.normal(size=n), rng.normal(size=n), rng.normal(size=n)
    with float64():
        for role, args in (("forward_dynamics", (q, v, tau)), ("inverse_dynamics", (q, v, a)), ("inertia", (q,))):
            assert relative(getattr(jm, role)(*args), getattr(npm, role)(*args)) < 1e-12
        fq, fv, ftau = jax.jacfwd(jm.forward_dynamics, (0, 1, 2))(q, v, tau)
        dq, dv, da = jax.jacrev(jm.inverse_dynamics, (0, 1, 2))(q, v, a)
    Q = pinocchio_q(pm, q)
    data = pm.createData()
    rnea = [x.copy() for x in pin.computeRNEADerivatives(pm, data, Q, v, a)[:3]]
    data = pm.createData()
    aba = [x.copy() for x in pin.computeABADerivatives(pm, data, Q, v, tau)[:3]]
    for ours, theirs in zip((dq, dv, da, fq, fv, ftau), rnea + aba):
        theirs = np.triu(theirs) + np.triu(theirs, 1).T if ours is da or ours is ftau else theirs
        assert relative(ours, theirs, floor=1.0) < 1e-8
