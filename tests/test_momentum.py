"""The momentum routine (issue 16): total linear momentum and angular momentum about the world origin, world axes.

References: Pinocchio's computeCentroidalMomentum (momentum about the centre of mass, world axes) moved to the
world origin with its centre of mass (L_O = L_G + c x p), on fixed and floating robots; conservation along free
flight of the spacecraft (no gravity, tau = 0: RK4 step 1e-3 s for 1 s keeps h to 1e-10 relative), and its
change under gravity alone for a floating robot (dp/dt = m g, dL/dt = c x m g).
"""
import numpy as np
import pytest

import aggsym
from conftest import model_path
from helpers import generated_code, rk4_step, robot_path
from pinocchio_reference import pin, pinocchio_model, pinocchio_q

pytestmark = pytest.mark.pinocchio

CASES = [("ur5", False), ("solo12", True), ("talos", True), ("panda", False)]


@pytest.mark.parametrize("name, floating", CASES, ids=[c[0] for c in CASES])
def test_momentum_against_pinocchio(name, floating, rng):
    model = aggsym.load(robot_path(name), floating_base=floating)
    pm = pinocchio_model(robot_path(name), floating)
    data = pm.createData()
    twin = aggsym.NumericTwin(model)
    for _ in range(3):
        q, qd = rng.uniform(-np.pi, np.pi, model.nq), rng.normal(size=model.nq)
        Q = pinocchio_q(pm, q)
        hg = pin.computeCentroidalMomentum(pm, data, Q, qd)
        c = data.com[0]
        p = hg.linear
        expected = np.concatenate([p, hg.angular + np.cross(c, p)])
        h = twin.momentum(q, qd)
        assert np.abs(h - expected).max() <= 1e-9 * np.abs(expected).max(), (name, h, expected)


def test_free_flight_conserves_momentum(tmp_path, rng):
    model = aggsym.load(model_path("spacecraft"))
    _, module, _ = generated_code(model, tmp_path, c=False)
    q, qd = rng.uniform(-1, 1, model.nq), 0.3 * rng.normal(size=model.nq)
    zero = np.zeros(model.nq)
    h0 = module.momentum(q, qd)
    assert np.abs(h0).max() > 1.0  # moving, so the check below can fail
    worst = 0.0
    for _ in range(1000):
        q, qd = rk4_step(lambda a, b: module.forward_dynamics(a, b, zero), q, qd, 1e-3)
        worst = max(worst, np.abs(module.momentum(q, qd) - h0).max())
    assert worst <= 1e-10 * np.abs(h0).max(), worst


def test_gravity_changes_momentum_by_the_weight(tmp_path, rng):
    """A floating quadruped falling with tau = 0: dh/dt = (m g, c x m g), by central differences of h along
    (qd, qdd) of forward dynamics; c, m from Pinocchio."""
    path = robot_path("solo12")
    model = aggsym.load(path, floating_base=True)
    twin = aggsym.NumericTwin(model)
    pm = pinocchio_model(path, True)
    data = pm.createData()
    g = np.array([0.0, 0.0, -9.81])
    mass = sum(pm.inertias[j].mass for j in range(pm.njoints))
    q, qd = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq)
    qdd = twin.forward_dynamics(q, qd, np.zeros(model.nq))
    eps = 1e-6
    rate = (twin.momentum(q + eps * qd, qd + eps * qdd) - twin.momentum(q - eps * qd, qd - eps * qdd)) / (2 * eps)
    c = pin.centerOfMass(pm, data, pinocchio_q(pm, q))
    expected = np.concatenate([mass * g, np.cross(c, mass * g)])
    assert np.abs(rate - expected).max() <= 1e-6 * np.abs(expected).max(), (rate, expected)
