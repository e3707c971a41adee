"""Checks of tests/constraint_reference.py (the Pinocchio-only reference for rigid constraints) against independent
computations: finite differences of phi and of J along q(t) = integrate(q, t v), the KKT equations themselves,
Pinocchio's rnea with external forces (the meaning of lam), Pinocchio's computeMinverse (the Delassus matrix) and
Pinocchio's own constraintDynamics (RigidConstraintModel, LOCAL_WORLD_ALIGNED and LOCAL)."""
from __future__ import annotations

import dataclasses
from functools import lru_cache

import numpy as np
import pytest

import constraint_reference as cr
from constraint_reference import Constraint
from helpers import robot_path
from pinocchio_reference import pin, pinocchio_model, pinocchio_q

pytestmark = pytest.mark.pinocchio

FEET = ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"]
SOLES = ["left_sole_link", "right_sole_link"]


@lru_cache(maxsize=None)
def model(name: str):
    return pinocchio_model(robot_path(name), floating_base=name in ("solo12", "talos"))


def rotation(rng) -> np.ndarray:
    return pin.exp3(rng.normal(size=3))


def scenario(name: str, rng):
    """(Pinocchio model, constraints) of a named case; constraints without at/orientation0."""
    if name == "solo12_feet":
        return model("solo12"), [Constraint(f, [0, 0, 0], [0, 1, 2]) for f in FEET]
    if name == "solo12_feet_rotated":
        return model("solo12"), [Constraint(f, [0.01, -0.02, 0.005], [0, 1, 2], rotation=rotation(rng)) for f in FEET]
    if name == "talos_soles":
        return model("talos"), [Constraint(f, [0.02, 0.01, 0.0], list(range(6))) for f in SOLES]
    if name == "talos_soles_rotated":
        return model("talos"), [Constraint(f, [0.02, 0.01, 0.0], list(range(6)), rotation=rotation(rng))
                                for f in SOLES]
    if name == "ur5_loop3":  # wrist_3 tied to the rotating upper arm
        return model("ur5"), [Constraint("wrist_3_link", [0.03, 0.05, -0.02], [0, 1, 2], medium="upper_arm_link",
                                         rotation=rotation(rng))]
    if name == "panda_loop6":  # link 7 welded to link 1 (six joints between them)
        return model("panda"), [Constraint("panda_link7", [0.02, -0.01, 0.1], list(range(6)), medium="panda_link1",
                                           rotation=rotation(rng))]
    if name == "talos_hands_loop6":  # both grippers welded, floating base, plus both feet on the ground
        return model("talos"), [Constraint("gripper_left_base_link", [0.0, 0.02, -0.05], list(range(6)),
                                           medium="gripper_right_base_link", rotation=rotation(rng)),
                                Constraint(SOLES[0], [0, 0, 0], [0, 1, 2]),
                                Constraint(SOLES[1], [0, 0, 0], [0, 1, 2])]
    if name == "solo12_feet_loop3":  # two feet tied to each other, a third on the ground
        return model("solo12"), [Constraint("FL_FOOT", [0, 0, 0], [0, 1, 2], medium="HR_FOOT", rotation=rotation(rng)),
                                 Constraint("FR_FOOT", [0, 0, 0], [0, 1, 2])]
    if name == "mixed_rows":  # rows Pinocchio has no model for: our functions only
        return model("panda"), [Constraint("panda_link7", [0.02, -0.01, 0.1], [0, 2, 3, 5], medium="panda_link2",
                                           rotation=rotation(rng)),
                                Constraint("panda_hand", [0.0, 0.01, 0.05], [1, 4], rotation=rotation(rng))]
    raise KeyError(name)


PINOCCHIO_CASES = ["solo12_feet", "solo12_feet_rotated", "talos_soles", "talos_soles_rotated", "ur5_loop3",
                   "panda_loop6", "talos_hands_loop6", "solo12_feet_loop3"]
ALL_CASES = PINOCCHIO_CASES + ["mixed_rows"]


def random_q(pm, rng, scale=1.0):
    return pinocchio_q(pm, scale * rng.uniform(-1, 1, pm.nv))


def state(name, seed):
    """(pm, constraints with at/orientation0 from another configuration q0, q, v, tau)."""
    rng = np.random.default_rng(seed)
    pm, cs = scenario(name, rng)
    q0, q = random_q(pm, rng), random_q(pm, rng)
    cs = [cr.default_at(pm, q0, c) for c in cs]
    return pm, cs, q, rng.normal(size=pm.nv), rng.normal(size=pm.nv) * 3


def rel(a, b, floor=1e-300):
    return float(np.abs(np.asarray(a) - np.asarray(b)).max() / max(np.abs(np.asarray(b)).max(), floor))


def along(pm, q, v, t):
    return pin.integrate(pm, q, t * v)


def central(f, h):
    return (f(h) - f(-h)) / (2 * h)


def rows_of(cs):
    """(constraint index, row) of every row of J."""
    return [(i, r) for i, c in enumerate(cs) for r in c.rows]


# --------------------------------------------------------------------------------------------------------------
# kinematic identities


@pytest.mark.parametrize("name", ALL_CASES)
def test_jacobian_is_rate_of_residual(name):
    """Translational rows: J v = d phi/dt at any q.  Rotational rows: d phi/dt = Jlog3(E) E^T (J v), and = J v at
    q0 (where E = I)."""
    pm, cs, q, v, _ = state(name, 1)
    h = 1e-6
    rate = central(lambda t: cr.residual(pm, along(pm, q, v, t), cs), h)
    Jv = cr.jacobian(pm, q, cs) @ v
    expected = Jv.copy()
    k = 0
    for c in cs:
        rot = [j for j, r in enumerate(c.rows) if r >= 3]
        if rot:
            E = cr.rotation_error(pm, q, c)
            full = np.zeros(6)
            full[list(c.rows)] = Jv[k:k + len(c.rows)]
            if len(rot) < 3:  # the rate of any rotational row needs all three components of w
                full_c = dataclasses.replace(c, rows=(3, 4, 5))
                w = cr.jacobian(pm, q, [full_c]) @ v
            else:
                w = full[3:]
            full[3:] = pin.Jlog3(E) @ E.T @ w
            expected[k:k + len(c.rows)] = full[list(c.rows)]
        k += len(c.rows)
    assert rel(rate, expected) < 1e-7, (rate, expected)

    # at q0 itself the rotational rows have E = I: d phi/dt = J v exactly
    rng = np.random.default_rng(2)
    q0 = random_q(pm, rng)
    cs0 = [cr.default_at(pm, q0, dataclasses.replace(c, at=None, orientation0=None)) for c in cs]
    assert np.abs(cr.residual(pm, q0, cs0)).max() < 1e-12
    rate0 = central(lambda t: cr.residual(pm, along(pm, q0, v, t), cs0), h)
    assert rel(rate0, cr.jacobian(pm, q0, cs0) @ v) < 1e-7


@pytest.mark.parametrize("name", ALL_CASES)
def test_gamma_is_rate_of_J_qdot(name):
    """gamma = d/dt (J(q(t)) v) along q(t) = integrate(q, t v) (v constant, qdd = 0): central differences
    with Richardson extrapolation."""
    for seed in (3, 4):
        pm, cs, q, v, _ = state(name, seed)
        d1 = central(lambda t: cr.jacobian(pm, along(pm, q, v, t), cs) @ v, 1e-4)
        d2 = central(lambda t: cr.jacobian(pm, along(pm, q, v, t), cs) @ v, 5e-5)
        fd = (4 * d2 - d1) / 3
        assert rel(cr.bias(pm, q, v, cs), fd) < 1e-8


@pytest.mark.parametrize("name", ["panda_loop6", "mixed_rows", "talos_hands_loop6"])
def test_rotating_medium_terms_matter(name):
    """The omega_m terms of gamma are not negligible in these cases (else the loops would test little)."""
    pm, cs, q, v, _ = state(name, 5)
    fixed = [dataclasses.replace(c, medium=None) for c in cs]
    assert rel(cr.bias(pm, q, v, fixed), cr.bias(pm, q, v, cs)) > 1e-3


def test_delassus_with_computeMinverse():
    for name in ("talos_hands_loop6", "mixed_rows"):
        pm, cs, q, _, _ = state(name, 6)
        J = cr.jacobian(pm, q, cs)
        Minv = pin.computeMinverse(pm, pm.createData(), q)
        Minv = np.triu(Minv) + np.triu(Minv, 1).T
        D = cr.delassus(pm, q, cs)
        assert np.array_equal(D, D.T)
        assert rel(D, J @ Minv @ J.T) < 1e-9


# --------------------------------------------------------------------------------------------------------------
# dynamics


@pytest.mark.parametrize("name", ALL_CASES)
def test_kkt_solves_both_equations(name):
    pm, cs, q, v, tau = state(name, 7)
    for kp, kd in ((0.0, 0.0), (30.0, 4.0)):
        qdd, lam = cr.kkt_forward_dynamics(pm, q, v, tau, cs, kp=kp, kd=kd)
        M = cr.mass_matrix(pm, q)
        nle = pin.nonLinearEffects(pm, pm.createData(), q, v)
        J = cr.jacobian(pm, q, cs)
        lhs, rhs = M @ qdd + nle, tau + J.T @ lam
        assert rel(lhs, rhs, floor=np.abs(tau).max()) < 1e-10
        g, phi = cr.bias(pm, q, v, cs), cr.residual(pm, q, cs)
        lhs, rhs = J @ qdd + g, -(kd * (J @ v) + kp * phi)
        assert rel(lhs, rhs, floor=np.abs(J @ qdd).max()) < 1e-10


def external_forces(pm, q, cs, lam):
    """Pinocchio's fext (per joint, joint frame, about the joint origin) for lam = the medium's wrench on body k
    about P in the reference axes, and its opposite on the medium."""
    data = pm.createData()
    pin.forwardKinematics(pm, data, q)
    pin.updateFramePlacements(pm, data)
    fext = [pin.Force.Zero() for _ in range(pm.njoints)]
    k = 0
    for c in cs:
        part = np.zeros(6)
        part[list(c.rows)] = lam[k:k + len(c.rows)]
        k += len(c.rows)
        Rm = np.eye(3) if c.medium is None else data.oMf[pm.getFrameId(c.medium)].rotation
        A = Rm @ c.rotation  # reference axes in the world
        fk = pm.getFrameId(c.frame)
        p = data.oMf[fk].act(c.point)
        wrench = pin.Force(A @ part[:3], A @ part[3:])  # world axes, about P
        world_at_origin = pin.SE3(np.eye(3), p).act(wrench)  # world axes, about the world origin
        for fid, sign in ((fk, 1.0), (None if c.medium is None else pm.getFrameId(c.medium), -1.0)):
            if fid is None:
                continue
            j = pm.frames[fid].parentJoint
            fext[j] += sign * data.oMi[j].actInv(world_at_origin)
    return pin.StdVec_Force(fext) if hasattr(pin, "StdVec_Force") else fext


@pytest.mark.parametrize("name", ALL_CASES)
def test_lambda_is_the_wrench_on_the_body(name):
    """rnea(q, v, qdd, fext) = tau with fext built from lam by hand (force and moment about P in the reference
    axes on body k, the opposite on the medium's body): the meaning of lam, independently of J."""
    pm, cs, q, v, tau = state(name, 8)
    qdd, lam = cr.kkt_forward_dynamics(pm, q, v, tau, cs)
    out = pin.rnea(pm, pm.createData(), q, v, qdd, external_forces(pm, q, cs, lam))
    assert rel(out, tau) < 1e-10


@pytest.mark.parametrize("name", PINOCCHIO_CASES)
def test_against_pinocchio_constraint_dynamics(name):
    """Any v: Pinocchio with our velocity terms.  Consistent v (J v = 0): Pinocchio's own equations, in
    LOCAL_WORLD_ALIGNED and LOCAL."""
    pm, cs, q, v, tau = state(name, 9)
    qdd, lam = cr.kkt_forward_dynamics(pm, q, v, tau, cs)
    pqdd, plam = cr.pinocchio_constraint_dynamics(pm, q, v, tau, cs)
    assert rel(pqdd, qdd) < 1e-8 and rel(plam, lam) < 1e-8, (rel(pqdd, qdd), rel(plam, lam))

    v0 = cr.consistent_velocity(pm, q, v, cs)
    assert np.abs(cr.jacobian(pm, q, cs) @ v0).max() < 1e-10 * np.abs(v0).max()
    qdd, lam = cr.kkt_forward_dynamics(pm, q, v0, tau, cs)
    for frame in (pin.ReferenceFrame.LOCAL_WORLD_ALIGNED, pin.ReferenceFrame.LOCAL):
        pqdd, plam = cr.pinocchio_constraint_dynamics(pm, q, v0, tau, cs, velocity_terms="pinocchio",
                                                      reference_frame=frame)
        assert rel(pqdd, qdd) < 1e-8 and rel(plam, lam) < 1e-8, (frame, rel(pqdd, qdd), rel(plam, lam))


@pytest.mark.parametrize("name", ["talos_soles", "ur5_loop3", "panda_loop6"])
def test_pinocchio_drift_differs_off_the_constraint(name):
    """Documents why velocity_terms='ours' exists: at a velocity with J v != 0, Pinocchio's own drift for 6D
    contacts and loops is not d/dt (J v) in our axes, and its answer differs from ours."""
    pm, cs, q, v, tau = state(name, 10)
    qdd, _ = cr.kkt_forward_dynamics(pm, q, v, tau, cs)
    pqdd, _ = cr.pinocchio_constraint_dynamics(pm, q, v, tau, cs, velocity_terms="pinocchio")
    assert rel(pqdd, qdd) > 1e-6


def test_point_contacts_need_no_velocity_terms():
    """World point contacts (LOCAL_WORLD_ALIGNED CONTACT_3D): Pinocchio's drift is ours at any v."""
    for name in ("solo12_feet", "solo12_feet_rotated"):
        pm, cs, q, v, tau = state(name, 11)
        qdd, lam = cr.kkt_forward_dynamics(pm, q, v, tau, cs)
        pqdd, plam = cr.pinocchio_constraint_dynamics(pm, q, v, tau, cs, velocity_terms="pinocchio")
        assert rel(pqdd, qdd) < 1e-8 and rel(plam, lam) < 1e-8


@pytest.mark.parametrize("base", ["solo12_feet", "talos_soles"])
def test_rotated_reference(base):
    """A reference rotation R per contact: J and gamma rotate by R^T, qdd is unchanged and lam = R^T lam0 (block
    per 3 rows); the rotated answer also equals Pinocchio's."""
    rng = np.random.default_rng(12)
    pm, cs, q, v, tau = state(base, 12)
    Rs = [rotation(rng) for _ in cs]
    rcs = [dataclasses.replace(c, rotation=R) for c, R in zip(cs, Rs)]
    T = np.zeros((sum(len(c.rows) for c in cs),) * 2)
    k = 0
    for c, R in zip(cs, Rs):
        for b in range(len(c.rows) // 3):
            T[k + 3 * b:k + 3 * b + 3, k + 3 * b:k + 3 * b + 3] = R.T
        k += len(c.rows)
    assert rel(cr.jacobian(pm, q, rcs), T @ cr.jacobian(pm, q, cs)) < 1e-12
    assert rel(cr.bias(pm, q, v, rcs), T @ cr.bias(pm, q, v, cs)) < 1e-12
    qdd0, lam0 = cr.kkt_forward_dynamics(pm, q, v, tau, cs)
    qdd, lam = cr.kkt_forward_dynamics(pm, q, v, tau, rcs)
    assert rel(qdd, qdd0) < 1e-9 and rel(lam, T @ lam0) < 1e-9
    pqdd, plam = cr.pinocchio_constraint_dynamics(pm, q, v, tau, rcs)
    assert rel(pqdd, qdd0) < 1e-8 and rel(plam, T @ lam0) < 1e-8


def test_unsupported_rows_and_model_untouched():
    pm, cs, q, v, tau = state("mixed_rows", 13)
    with pytest.raises(ValueError, match="rows"):
        cr.pinocchio_constraint_dynamics(pm, q, v, tau, cs)
    with pytest.raises(ValueError):
        Constraint("panda_link7", [0, 0, 0], [2, 1])
    with pytest.raises(ValueError, match="at"):
        cr.residual(pm, q, [Constraint("panda_link7", [0, 0, 0], [0, 1, 2])])
    pm, cs, q, v, tau = state("panda_loop6", 13)
    nframes = pm.nframes
    cr.pinocchio_constraint_dynamics(pm, q, v, tau, cs)
    cr.jacobian(pm, q, cs)
    assert pm.nframes == nframes
