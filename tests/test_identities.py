"""Rung 1 on every model: identities, and agreement with the independent Newton-Euler of reference.py."""
import numpy as np
import pytest

import aggsym
from aggsym.core.backend import Numeric
from aggsym.mechanics.bound import bind
from aggsym.mechanics.inertia import inertia_matrix, inertia_matrix_sas
from aggsym.mechanics.kinematics import TreeKinematics
from conftest import MODELS
from helpers import states as random_states
from reference import NumericModel, mass_matrix, newton_euler

TRIALS = 5


@pytest.fixture(params=MODELS, ids=lambda p: p.stem)
def model(request):
    return aggsym.load(request.param)


def states(model, rng, n=TRIALS):
    return random_states(model, rng, n)


def test_composite_bodies_equal_s_a_st(model, rng):
    """A by composite bodies (2.32)-(2.34) equals S diag(Theta) S^T (2.30)."""
    bound = bind(model, Numeric())
    for q, _, _ in states(model, rng):
        kin = TreeKinematics(bound, list(q))
        A1 = np.array(inertia_matrix(bound, kin), dtype=float)
        A2 = np.array(inertia_matrix_sas(bound, kin), dtype=float)
        assert np.allclose(A1, A2, rtol=1e-12, atol=1e-12 * np.abs(A1).max())


def test_inertia_symmetric_positive_definite(model, rng):
    twin = aggsym.NumericTwin(model)
    for q, _, _ in states(model, rng):
        A = twin.inertia(q)
        assert np.array_equal(A, A.T)
        assert np.linalg.eigvalsh(A)[0] > 0


def test_equations_equal_independent_newton_euler(model, rng):
    """A q'' + b + g + c equals a world-frame Newton-Euler written independently (tests/reference.py), with the
    rotors' prescribed spins (at t = 0), added masses and springs of the model."""
    twin = aggsym.NumericTwin(model)
    nm = NumericModel(model)
    for q, qd, qdd in states(model, rng):
        tau, T, U = newton_euler(nm, q, qd, qdd)
        lhs = twin.inertia(q) @ qdd + twin.bias(q, qd) + twin.gravity(q) + twin.elastic(q)
        scale = max(1.0, np.abs(tau).max())
        assert np.abs(lhs - tau).max() <= 1e-11 * scale
        assert np.abs(twin.inverse_dynamics(q, qd, qdd) - tau).max() <= 1e-11 * scale
        assert np.allclose(mass_matrix(nm, q), twin.inertia(q), rtol=1e-11, atol=1e-11 * scale)
        assert twin.kinetic_energy(q, qd)[0] == pytest.approx(T, rel=1e-11, abs=1e-12)
        assert twin.potential_energy(q)[0] == pytest.approx(U, rel=1e-11, abs=1e-9)


def test_kinetic_energy_is_quadratic_form(model, rng):
    """T = 1/2 q'^T A q' (Def. 2.4); with prescribed spins T also has terms of degree 1 and 0 in q', and its
    quadratic part T(q') + T(-q') - 2 T(0) is still q'^T A q'."""
    twin = aggsym.NumericTwin(model)
    for q, qd, _ in states(model, rng):
        if not model.time_dependent:
            assert twin.kinetic_energy(q, qd)[0] == pytest.approx(0.5 * qd @ twin.inertia(q) @ qd, rel=1e-12)
        even = twin.kinetic_energy(q, qd)[0] + twin.kinetic_energy(q, -qd)[0] - 2 * twin.kinetic_energy(q, 0 * qd)[0]
        assert even == pytest.approx(qd @ twin.inertia(q) @ qd, rel=1e-9, abs=1e-12)


def test_gravity_is_gradient_of_potential(model, rng):
    """g + c = dU/dq: gravity and the springs of elastic pairs are the potential forces."""
    twin = aggsym.NumericTwin(model)
    for q, _, _ in states(model, rng, 2):
        h = 1e-6
        grad = np.array([(twin.potential_energy(q + h * e)[0] - twin.potential_energy(q - h * e)[0]) / (2 * h)
                         for e in np.eye(model.nq)])
        assert np.allclose(twin.gravity(q) + twin.elastic(q), grad, rtol=1e-6,
                           atol=1e-6 * max(1.0, np.abs(grad).max()))


@pytest.mark.parametrize("path", [p for p in MODELS if not aggsym.load(p).time_dependent], ids=lambda p: p.stem)
def test_bias_is_coriolis_of_inertia(path, rng):
    """b = A' q' - 1/2 d/dq (q'^T A q'), differentiating A(q) numerically along q' (models without prescribed
    spins; with them A(q, t) turns with the rotors, see test_bias_is_lagrange_of_kinetic_energy)."""
    model = aggsym.load(path)
    twin = aggsym.NumericTwin(model)
    for q, qd, _ in states(model, rng, 2):
        h = 1e-6
        Adot = (twin.inertia(q + h * qd) - twin.inertia(q - h * qd)) / (2 * h)
        dT = np.array([(qd @ twin.inertia(q + h * e) @ qd - qd @ twin.inertia(q - h * e) @ qd) / (2 * h)
                       for e in np.eye(model.nq)])
        expected = Adot @ qd - 0.5 * dT
        assert np.allclose(twin.bias(q, qd), expected, rtol=1e-6, atol=1e-6 * max(1.0, np.abs(expected).max()))


@pytest.mark.parametrize("path", [p for p in MODELS if not aggsym.load(p).time_dependent], ids=lambda p: p.stem)
def test_coriolis_matrix_is_skew_consistent(path, rng):
    """The coriolis routine: C q' = b, C linear in q', and A' - 2C skew with A' by a central difference of A(q)
    along q' (the book's B of (2.17) has B q' = b but not the skew property; the test tells them apart)."""
    model = aggsym.load(path)
    twin = aggsym.NumericTwin(model)
    for q, qd, _ in states(model, rng, 2):
        C = twin.coriolis(q, qd)
        b = twin.bias(q, qd)
        scale = max(1.0, np.abs(C).max())
        assert np.abs(C @ qd - b).max() <= 1e-12 * max(1.0, np.abs(b).max())
        assert np.allclose(twin.coriolis(q, 2 * qd), 2 * C, rtol=1e-12, atol=1e-12 * scale)
        h = 1e-6
        Adot = (twin.inertia(q + h * qd) - twin.inertia(q - h * qd)) / (2 * h)
        K = Adot - 2 * C
        assert np.abs(K + K.T).max() <= 1e-6 * max(1.0, np.abs(Adot).max())


def test_bias_is_lagrange_of_kinetic_energy(model, rng):
    """b = d/dt dT/dq' - dT/dq at q'' = 0 (Lagrange), from the kinetic_energy routine alone, by finite differences.

    This holds for every model here: the prescribed spins are ideal rheonomic constraints (T = T(q, q', t)) and the
    body + medium system with added masses is Lagrangian (Kirchhoff).  T is quadratic in q', so dT/dq' by a
    central difference is exact up to rounding; the time derivative runs along (q', 1) in (q, t)."""
    twin = aggsym.NumericTwin(model)
    n = model.nq
    for q, qd, _ in states(model, rng, 2):
        t = float(rng.uniform(0, 2))

        def T(q_, qd_, t_):
            return twin.kinetic_energy(q_, qd_, t=t_)[0]

        def momentum(q_, t_):
            return np.array([(T(q_, qd + e, t_) - T(q_, qd - e, t_)) / 2 for e in np.eye(n)])

        h = 1e-5
        dp = (momentum(q + h * qd, t + h) - momentum(q - h * qd, t - h)) / (2 * h)
        dq = np.array([(T(q + h * e, qd, t) - T(q - h * e, qd, t)) / (2 * h) for e in np.eye(n)])
        expected = dp - dq
        assert np.allclose(twin.bias(q, qd, t=t), expected, rtol=1e-6, atol=1e-6 * max(1.0, np.abs(expected).max()))
