"""Pinocchio as the tests' reference: its models of URDF files (fixed base, or the free root of six coordinates)
and of our models (:func:`pinocchio_tree`), its configuration vectors, and comparisons with it (:func:`compare`).

Where Pinocchio does not import, conftest.py does not collect the test modules that import this one, so the suite
still collects there; test modules take ``pin`` from here (``from pinocchio_reference import pin``) and carry the
``pinocchio`` marker.  The helpers that need no Pinocchio are in ``helpers.py``.
"""
from __future__ import annotations

import numpy as np

import aggsym
from helpers import TOLERANCE, relative_error
from reference import NumericModel

import pinocchio as pin  # (conftest.py leaves the modules importing this one out where it fails)


def free_root() -> "pin.JointModelComposite":
    """The root joint matching ``floating_base=True``: PX, PY, PZ, RX, RY, RZ in this order."""
    root = pin.JointModelComposite()
    for joint in (pin.JointModelPX(), pin.JointModelPY(), pin.JointModelPZ(), pin.JointModelRX(), pin.JointModelRY(),
                  pin.JointModelRZ()):
        root.addJoint(joint)
    return root


def pinocchio_model(path, floating_base: bool = False):
    """Pinocchio's model of a URDF file, fixed base or with :func:`free_root`."""
    if floating_base:
        return pin.buildModelFromUrdf(str(path), free_root())
    return pin.buildModelFromUrdf(str(path))


def pinocchio_q(pm, q) -> np.ndarray:
    """Pinocchio's configuration vector for our joint values q (continuous joints are (cos, sin))."""
    out = np.zeros(pm.nq)
    for j in range(1, pm.njoints):
        joint = pm.joints[j]
        v = q[joint.idx_v: joint.idx_v + joint.nv]
        if joint.nq == joint.nv:
            out[joint.idx_q: joint.idx_q + joint.nq] = v
        elif joint.nq == 2 and joint.nv == 1:  # unbounded revolute
            out[joint.idx_q: joint.idx_q + 2] = (np.cos(v[0]), np.sin(v[0]))
        else:
            raise ValueError(f"no conversion for Pinocchio joint {joint.shortname()}")
    return out


def joint_names(pm) -> list:
    """Pinocchio's joint names in q order, one per coordinate (the free root's six under its name)."""
    names = []
    for j in range(1, pm.njoints):
        names += [pm.names[j]] * pm.joints[j].nv
    return names


def has_composite_joint(pm) -> bool:
    return any(pm.joints[j].shortname() == "JointModelComposite" for j in range(1, pm.njoints))


def crba(pm, Q) -> np.ndarray:
    """Pinocchio's M(Q), both triangles (crba fills the upper one)."""
    M = pin.crba(pm, pm.createData(), Q)
    return np.triu(M) + np.triu(M, 1).T


def inertia_rate(pm, Q, v) -> tuple:
    """dM/dt along v and the relative tolerance to compare with it.

    From Pinocchio's computeCoriolisMatrix Cp: dM/dt = Cp + Cp^T (its Cp has dM/dt - 2 Cp skew).  Pinocchio 4.1's
    computeCoriolisMatrix is wrong on composite joints (the floating root of :func:`free_root`: its Cp + Cp^T
    differs from the rate of its own crba by a few per cent), so there dM/dt is the central difference of crba
    along v (relative error about 1e-10, compared to 1e-7).  A Coriolis matrix is not unique, but C qd = b and
    C + C^T = dM/dt pin down the class with the skew property (A' - 2C skew is C + C^T = A', A' symmetric)."""
    if has_composite_joint(pm):
        h = 1e-6
        return (crba(pm, pin.integrate(pm, Q, h * v)) - crba(pm, pin.integrate(pm, Q, -h * v))) / (2 * h), 1e-7
    Cp = pin.computeCoriolisMatrix(pm, pm.createData(), Q, v)
    return Cp + Cp.T, TOLERANCE


def compare(model, pm, rng, states: int = 3, tolerance: float = TOLERANCE) -> float:
    """Assert A, b + g, g and inverse dynamics equal Pinocchio's on random states, and that the Coriolis matrix C has
    C qd = b and C + C^T = dM/dt (:func:`inertia_rate`); returns the largest error."""
    assert model.nq == pm.nv
    twin = aggsym.NumericTwin(model)
    data = pm.createData()
    worst = 0.0
    for _ in range(states):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        qd, qdd = rng.normal(size=model.nq), rng.normal(size=model.nq)
        Q = pinocchio_q(pm, q)
        M = pin.crba(pm, data, Q)
        M = np.triu(M) + np.triu(M, 1).T  # crba fills the upper triangle
        errors = {
            "A vs crba": relative_error(twin.inertia(q), M),
            "b + g vs nonLinearEffects": relative_error(twin.bias(q, qd) + twin.gravity(q),
                                                        pin.nonLinearEffects(pm, data, Q, qd)),
            "g vs computeGeneralizedGravity": relative_error(twin.gravity(q),
                                                             pin.computeGeneralizedGravity(pm, data, Q)),
            "inverse_dynamics vs rnea": relative_error(twin.inverse_dynamics(q, qd, qdd),
                                                       pin.rnea(pm, data, Q, qd, qdd)),
        }
        if not model.time_dependent:
            C = twin.coriolis(q, qd)
            errors["C qd vs nonLinearEffects - g"] = relative_error(
                C @ qd, pin.nonLinearEffects(pm, data, Q, qd) - pin.computeGeneralizedGravity(pm, data, Q),
                floor=np.abs(M).max() * np.abs(qd).max() ** 2)
            Mdot, rate_tolerance = inertia_rate(pm, Q, qd)
            error = relative_error(C + C.T, Mdot, floor=np.abs(M).max() * np.abs(qd).max())
            assert error <= rate_tolerance, f"{model.name}: C + C^T vs dM/dt: relative error {error:.3g} at q={q.tolist()}"
        for what, error in errors.items():
            assert error <= tolerance, f"{model.name}: {what}: relative error {error:.3g} at q={q.tolist()}"
        worst = max(worst, *errors.values())
    return worst


def pinocchio_tree(model):
    """The model as a Pinocchio model, one joint per coordinate (multi-coordinate pairs as chains of joints with
    massless frames between, variant 1 of the book; welded bodies appended to their parent's joint).  The first
    joint of a pair is placed at SE3(R0, p) of the constructive configuration, so its frame after the joint
    motion is our body frame; inertias are given in it.  Returns the model and, per body, the index of the joint
    whose frame is the body frame (the parent's joint for a welded body, with the body's placement in it).
    Each body is also a Pinocchio frame of its name (for frame Jacobians, constraints)."""
    nm = NumericModel(model)
    pm = pin.Model()
    pm.gravity = pin.Motion(np.concatenate([nm.gravity, np.zeros(3)]))
    frame = []  # per body: (joint id, placement of the body frame in that joint's frame)
    kinds = {0: pin.JointModelPX, 1: pin.JointModelPY, 2: pin.JointModelPZ,
             3: pin.JointModelRX, 4: pin.JointModelRY, 5: pin.JointModelRZ}
    for b, body in zip(nm.bodies, model.bodies):
        parent, above = (0, pin.SE3.Identity()) if b["parent"] < 0 else frame[b["parent"]]
        placement = above * pin.SE3(b["R0"], b["p"])
        for j, (_, axis) in enumerate(b["coords"]):
            name = body.pair.name if j == len(b["coords"]) - 1 else f"{body.pair.name}_{j}"
            parent = pm.addJoint(parent, kinds[axis](), placement, name)
            placement = pin.SE3.Identity()
        frame.append((parent, placement))
        inertia = pin.Inertia(b["m"], b["c"], b["I"]) if "m" in b else pin.Inertia.Zero()
        pm.appendBodyToJoint(parent, inertia, placement)
        pm.addFrame(pin.Frame(body.name, parent, placement, pin.FrameType.OP_FRAME))
    assert pm.nq == model.nq
    joint_of = [j for j, _ in frame]
    return pm, joint_of
