"""Added masses of an inertial medium (2.1.2, Prop. 2.8): Theta is replaced by Theta + Lambda.

* A(q) = A_rigid(q) + sum_k s_k Lambda_k s_k^T with the rows s of the parastrophic matrix S (1.42), (2.30);
* tau against Kirchhoff's equations in the world frame (tests/reference.py), with gravity on the bodies' masses
  only, on a branching tree with full (non-diagonal) Lambda on several bodies;
* the spheroid of models/added_mass_body_in_fluid.yaml: Kirchhoff's impulse (world frame) is conserved along
  free motion, and the Munk moment turns a body moving obliquely;
* validation: not symmetric, not positive semi-definite, wrong shape, each with the YAML path and line.
"""
import dataclasses
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import aggsym
from aggsym.core.backend import Numeric
from aggsym.mechanics.bound import bind
from aggsym.errors import ModelError
from aggsym.mechanics.kinematics import TreeKinematics
from conftest import model_path
from helpers import rk4_step
from reference import NumericModel, newton_euler, rot

DATA = Path(__file__).parent / "data"


def with_added_masses(model, rng, every=1):
    """The model with a random symmetric positive semi-definite 6x6 Lambda on every ``every``-th body."""
    bodies = []
    for k, b in enumerate(model.bodies):
        if k % every == 0:
            X = rng.normal(size=(6, 6)) * 0.3
            Lam = X @ X.T
            Lam[5] = Lam[:, 5] = 0  # semi-definite: no added inertia about e3
            b = dataclasses.replace(b, added_mass=tuple(tuple(sp.Float(x) for x in row) for row in Lam))
        bodies.append(b)
    return dataclasses.replace(model, bodies=tuple(bodies))


def parastrophic_blocks(model, q):
    bound = bind(model, Numeric())
    kin = TreeKinematics(bound, list(q))
    return [[None if blk is None else np.array(blk, dtype=float) for blk in row] for row in kin.parastrophic()]


@pytest.mark.parametrize("name", ["branching_tree", "added_mass_body_in_fluid"])
def test_inertia_is_rigid_plus_lambda_through_s(name, rng):
    """A(q) = A_rigid(q) + sum_k s_k Lambda_k s_k^T (2.30) with Theta_k -> Theta_k + Lambda_k."""
    if name == "branching_tree":
        model = with_added_masses(aggsym.load(DATA / "branching_tree.yaml"), rng, every=2)
    else:
        model = aggsym.load(model_path(name))
    rigid = dataclasses.replace(model, bodies=tuple(dataclasses.replace(b, added_mass=None) for b in model.bodies))
    t_all, t_rigid = aggsym.NumericTwin(model), aggsym.NumericTwin(rigid)
    values = dict(zip(model.parameter_symbols, model.parameter_values))
    Lams = [None if b.added_mass is None else np.array(sp.Matrix(b.added_mass).subs(values), dtype=float)
            for b in model.bodies]
    assert sum(L is not None for L in Lams) >= 1
    for _ in range(4):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        S = parastrophic_blocks(model, q)
        extra = np.zeros((model.nq, model.nq))
        for k, Lam in enumerate(Lams):
            if Lam is None:
                continue
            sk = np.array([np.zeros(6) if row[k] is None else row[k] for row in S])  # n x 6
            extra += sk @ Lam @ sk.T
        A = t_all.inertia(q)
        assert not np.allclose(extra, 0)
        assert np.allclose(A, t_rigid.inertia(q) + extra, rtol=1e-12, atol=1e-12 * np.abs(A).max())
        # gravity acts on the bodies, not on the medium
        assert np.allclose(t_all.gravity(q), t_rigid.gravity(q), rtol=1e-13, atol=1e-13)
        assert t_all.potential_energy(q)[0] == pytest.approx(t_rigid.potential_energy(q)[0], rel=1e-13, abs=1e-13)


def test_tau_is_kirchhoff_in_the_world_frame(rng):
    """Inverse dynamics, forward dynamics and T with full added-mass matrices on a branching tree under gravity
    against the world-frame Newton-Euler with Kirchhoff's fluid impulse (tests/reference.py)."""
    model = with_added_masses(aggsym.load(DATA / "branching_tree.yaml"), rng, every=1)
    twin = aggsym.NumericTwin(model)
    nm = NumericModel(model)
    assert any(g != 0 for g in nm.gravity)
    for _ in range(4):
        q, qd, qdd = rng.uniform(-np.pi, np.pi, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        tau, T, _ = newton_euler(nm, q, qd, qdd)
        scale = max(1.0, np.abs(tau).max())
        assert np.abs(twin.inverse_dynamics(q, qd, qdd) - tau).max() <= 1e-11 * scale
        assert np.abs(twin.inertia(q) @ qdd + twin.nonlinear_effects(q, qd) - tau).max() <= 1e-11 * scale
        assert np.abs(twin.forward_dynamics(q, qd, tau) - qdd).max() <= 1e-9
        assert twin.kinetic_energy(q, qd)[0] == pytest.approx(T, rel=1e-12)


def impulse(model, twin, q, qd):
    """Kirchhoff's impulse of body + fluid in the world frame: (P, K about the world origin)."""
    bound = bind(model, Numeric())
    kin = TreeKinematics(bound, list(q))
    V = np.array(kin.velocities(list(qd))[0], dtype=float)
    X = np.array(bound.bodies[0].mises.matrix(), dtype=float)  # Theta + Lambda about the body origin
    Pb = X @ V
    R = rot(1, q[3]) @ rot(2, q[4]) @ rot(3, q[5])
    P = R @ Pb[:3]
    return P, R @ Pb[3:] + np.cross(q[:3], P)


def test_spheroid_keeps_kirchhoffs_impulse_and_turns_by_the_munk_moment():
    """Free motion of the spheroid (tau = 0): T, the world impulse and angular impulse stay constant, while the
    body, started moving obliquely without rotation, starts turning (the Munk moment of lambda22 != lambda11)."""
    model = aggsym.load(model_path("added_mass_body_in_fluid"))
    twin = aggsym.NumericTwin(model)
    q = np.array([0, 0, 0, 0.1, 0.2, 0.3])
    qd = np.zeros(6)
    R = rot(1, q[3]) @ rot(2, q[4]) @ rot(3, q[5])
    qd[:3] = R @ np.array([1.0, 0.7, 0])  # velocity 45 deg off the axis, no rotation
    P0, K0 = impulse(model, twin, q, qd)
    T0 = twin.kinetic_energy(q, qd)[0]
    zero, dt = np.zeros(6), 2e-3
    f = lambda q, v: twin.forward_dynamics(q, v, zero)
    for _ in range(100):
        q, qd = rk4_step(f, q, qd, dt)
    P, K = impulse(model, twin, q, qd)
    assert np.abs(P - P0).max() <= 1e-9 * np.abs(P0).max()
    assert np.abs(K - K0).max() <= 1e-9 * max(np.abs(K0).max(), np.abs(P0).max())
    assert twin.kinetic_energy(q, qd)[0] == pytest.approx(T0, rel=1e-10)
    assert np.abs(qd[3:]).max() > 0.05  # it turned


BAD = {
    "not_symmetric": ("[[1,0,0,0,0,0],[0,1,0,0,0,0],[0,0,1,0,0,0],[0,0,0,1,0,0],[0,0,0,0,1,0],[0.5,0,0,0,0,1]]",
                      "bodies[0].added_mass", 6, ["not symmetric", "[5][0] = 0.5", "[0][5] = 0"]),
    "not_psd": ("[1, 1, 1, 1, -0.2, 1]", "bodies[0].added_mass", 6,
                ["not positive semi-definite", "-0.2"]),
    "indefinite_coupling": ("[[1,0,0,0,0,2],[0,1,0,0,0,0],[0,0,1,0,0,0],[0,0,0,1,0,0],[0,0,0,0,1,0],[2,0,0,0,0,1]]",
                            "bodies[0].added_mass", 6, ["not positive semi-definite"]),
    "wrong_shape": ("[[1, 0], [0, 1]]", "bodies[0].added_mass", 6, ["expected 6 entries, got 2"]),
    "wrong_row": ("[[1,0,0,0,0,0],[0,1,0,0,0],[0,0,1,0,0,0],[0,0,0,1,0,0],[0,0,0,0,1,0],[0,0,0,0,0,1]]",
                  "bodies[0].added_mass[1]", 6, ["expected 6 entries, got 5"]),
    "not_a_number": ("[1, 1, heavy, 1, 1, 1]", "bodies[0].added_mass[2]", 6, ["undefined parameter 'heavy'"]),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_added_mass_is_reported_precisely(case, tmp_path):
    value, where, line, words = BAD[case]
    path = tmp_path / f"{case}.yaml"
    path.write_text("name: x\nbodies:\n  - name: a\n    pair: {functional: {o1: x}}\n    mass: 1.0\n"
                    f"    added_mass: {value}\n")
    with pytest.raises(ModelError) as info:
        aggsym.load(path)
    err = info.value
    assert err.where == where, str(err)
    assert err.line == line, str(err)
    assert str(err).startswith(f"{path}:{line}:")
    for w in words:
        assert w in str(err), str(err)
