"""An independent reference for rigid bilateral constraints, built from Pinocchio alone (nothing from aggsym).

A constraint ties a point P fixed on body k (the body of a Pinocchio frame) to the medium: the world, or the body
of another frame of the same tree (a closed loop).  All functions take Pinocchio's configuration ``q`` (length
``pm.nq``) and work in Pinocchio's velocity space (``v``, ``tau``, ``qdd`` of length ``pm.nv``).  None of them
changes the caller's model.

Notation (all vectors in world axes unless said otherwise)
---------------------------------------------------------
``R_k``, ``o_k``: rotation and origin of the frame ``c.frame``; ``p_P = o_k + R_k c.point``.
``R_m``, ``o_m``: rotation and origin of the frame ``c.medium`` (identity and 0 for the world).
``omega_k``, ``omega_m``: world angular velocities; ``alpha_k``, ``alpha_m`` their rates at qdd = 0.
``v_P``, ``a_P``: velocity and classical acceleration (at qdd = 0) of P; ``v_m``, ``a_m`` those of ``o_m``.
``d = p_P - o_m``; ``v_C = v_m + omega_m x d`` the velocity of the medium's point coincident with P;
``u = v_P - v_C``; ``T = R_ref^T R_m^T`` (per 3-vector).

Rows of a constraint, in ``c.rows`` order (0, 1, 2 translations o1 o2 o3; 3, 4, 5 rotations theta4..6):

* Jacobian:     translational  T (v_P - v_C);             rotational  T (omega_k - omega_m).
* gamma = Jdot qdot (the value of d/dt (J qdot) at qdd = 0):
                translational  T (du/dt - omega_m x u),  du/dt = a_P - a_m - alpha_m x d - omega_m x (v_P - v_m);
                rotational     T (alpha_k - alpha_m - omega_m x (omega_k - omega_m)).
* residual phi: translational  T (p_P - p_at), with p_at = o_m + R_m c.at (c.at in the medium frame's axes, or
                world coordinates for the world);
                rotational     log3(E), E = R_ref^T R_m^T R_k orientation0^T, with the constraint's
                ``orientation0 = R_ref^T R_m0^T R_k0`` (the value of R_ref^T R_m^T R_k at q0), i.e.
                E = R_ref^T (R_m^T R_k)(R_m0^T R_k0)^T R_ref: the rotation of body k relative to the medium since
                q0, as a rotation vector in the reference axes.  Its rate: dE/dt = [w]x E with w = the rotational
                rows of J qdot, so d phi/dt = Jlog3(E) E^T w (equal to w where E = I, e.g. at q0).
* Equations:    M qdd + nle = tau + J^T lam,   J qdd + gamma = -(kd J qdot + kp phi).
                lam = (f, mu) in the rows' order: the force and the moment about P that the medium exerts on body
                k, in the reference axes (R_m R_ref in the world); the medium's body receives -lam.

Pinocchio's RigidConstraintModel (checked in tests/test_constraint_reference.py and by reading
pinocchio/src/constraints/contact-info.hxx and algorithm/constrained-dynamics.hxx, Pinocchio 4.1)
--------------------------------------------------------------------------------------------------
joint1 = body k (c1 placed at P), joint2 = the medium's joint or 0 (c2 placed where P is at the current q).  It
solves M a = tau - nle + J_pin^T lambda_c, with lambda_c = ``data.lambda_c`` = ``cdata.contact_force``:

* LOCAL_WORLD_ALIGNED: J_pin rows are (v_P - v_C) (CONTACT_3D: v_c1 - v_c2 of the two placed points) and, for
  CONTACT_6D, (v_P - v_C, omega_k - omega_m), in world axes; so lambda_c is the force (and the moment about P) on
  body k in world axes, and our lam = T lambda_c (blockwise).  Body k (joint1) receives +lambda_c, joint2 -lambda_c.
* LOCAL: the same quantities in the axes of c1 (the frame placed on joint1): with c1's axes set to R_m R_ref at the
  current q, our lam = lambda_c.
* Its drift (acceleration at a = 0) is not always d/dt (J_pin v): LOCAL_WORLD_ALIGNED CONTACT_3D uses
  a_P - a_C (classical accelerations of the two placed points), CONTACT_6D uses the spatial accelerations at P
  (a_P - omega_k x v_P for body k; no angular term).  These differ from our gamma (rotated to world axes) by terms
  that vanish when J v = 0.  :func:`pinocchio_constraint_dynamics` adds the difference through
  ``contact_acceleration_desired`` (``velocity_terms="ours"``) or leaves Pinocchio's own equation
  (``velocity_terms="pinocchio"``, which agrees with ours only at constraint-consistent velocities J v = 0).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

from pinocchio_reference import pin  # skips the importing test module where Pinocchio is missing

TRANSLATION_ROWS = (0, 1, 2)
ALL_ROWS = (0, 1, 2, 3, 4, 5)


@dataclass(frozen=True)
class Constraint:
    """A rigid bilateral constraint of the point ``point`` (in the axes and from the origin of the Pinocchio frame
    ``frame``) with the world (``medium=None``) or with the body of the frame ``medium``.

    rows: sorted subset of 0..5 (o1 o2 o3 theta4 theta5 theta6).  rotation: R_ref, columns = reference axes in the
    medium frame's axes.  at: the medium's point the contact is attached to, in the medium frame's axes (world
    coordinates for the world).  orientation0: R_ref^T R_m0^T R_k0 at q0 (needed by rotational residual rows).
    :func:`default_at` fills both from a configuration q0."""
    frame: str
    point: Sequence[float]
    rows: Sequence[int]
    rotation: Optional[np.ndarray] = None
    medium: Optional[str] = None
    at: Optional[Sequence[float]] = None
    orientation0: Optional[np.ndarray] = None

    def __post_init__(self):
        rows = [int(r) for r in self.rows]
        if not rows or sorted(set(rows)) != rows or rows[0] < 0 or rows[-1] > 5:
            raise ValueError(f"rows must be a sorted non-empty subset of 0..5, got {self.rows!r}")
        object.__setattr__(self, "rows", tuple(rows))
        object.__setattr__(self, "point", np.array(self.point, dtype=float).reshape(3))
        R = np.eye(3) if self.rotation is None else np.array(self.rotation, dtype=float).reshape(3, 3)
        if np.abs(R.T @ R - np.eye(3)).max() > 1e-9 or np.linalg.det(R) < 0:
            raise ValueError("rotation must be a proper rotation matrix")
        object.__setattr__(self, "rotation", R)
        if self.at is not None:
            object.__setattr__(self, "at", np.array(self.at, dtype=float).reshape(3))
        if self.orientation0 is not None:
            object.__setattr__(self, "orientation0", np.array(self.orientation0, dtype=float).reshape(3, 3))


def _frame_id(pm, name: str) -> int:
    for kind in (pin.FrameType.BODY, pin.FrameType.OP_FRAME):  # a URDF link, or a frame added by name
        if pm.existFrame(name, kind):
            return pm.getFrameId(name, kind)
    raise ValueError(f"the model has no link or operational frame {name!r}")


class _Point:
    """World kinematics of one constraint at (q, v), qdd = 0: placements, velocities, accelerations, Jacobians."""

    def __init__(self, pm, data, c: Constraint, with_motion: bool):
        fk = _frame_id(pm, c.frame)
        oMk = data.oMf[fk]
        self.Rk, self.ok = oMk.rotation.copy(), oMk.translation.copy()
        self.p = self.ok + self.Rk @ c.point
        r = self.p - self.ok
        Jk = pin.getFrameJacobian(pm, data, fk, pin.LOCAL_WORLD_ALIGNED)  # (v of o_k, omega_k), world axes
        self.JP = Jk[:3] - pin.skew(r) @ Jk[3:]
        self.Jwk = Jk[3:].copy()
        if c.medium is None:
            self.Rm, self.om = np.eye(3), np.zeros(3)
            self.JC = np.zeros_like(self.JP)
            self.Jwm = np.zeros_like(self.Jwk)
        else:
            fm = _frame_id(pm, c.medium)
            oMm = data.oMf[fm]
            self.Rm, self.om = oMm.rotation.copy(), oMm.translation.copy()
            Jm = pin.getFrameJacobian(pm, data, fm, pin.LOCAL_WORLD_ALIGNED)
            self.JC = Jm[:3] - pin.skew(self.p - self.om) @ Jm[3:]  # the medium's point coincident with P
            self.Jwm = Jm[3:].copy()
        if not with_motion:
            return
        vk = pin.getFrameVelocity(pm, data, fk, pin.LOCAL_WORLD_ALIGNED)
        ak = pin.getFrameClassicalAcceleration(pm, data, fk, pin.LOCAL_WORLD_ALIGNED)
        self.wk, self.alk = vk.angular.copy(), ak.angular.copy()
        self.vP = vk.linear + np.cross(self.wk, r)
        self.aP = ak.linear + np.cross(self.alk, r) + np.cross(self.wk, np.cross(self.wk, r))
        if c.medium is None:
            self.wm = self.alm = self.vm = self.am = np.zeros(3)
        else:
            vm = pin.getFrameVelocity(pm, data, fm, pin.LOCAL_WORLD_ALIGNED)
            am = pin.getFrameClassicalAcceleration(pm, data, fm, pin.LOCAL_WORLD_ALIGNED)
            self.vm, self.wm = vm.linear.copy(), vm.angular.copy()
            self.am, self.alm = am.linear.copy(), am.angular.copy()
        d = self.p - self.om
        self.vC = self.vm + np.cross(self.wm, d)
        self.u = self.vP - self.vC


def _kinematics(pm, q, v=None):
    data = pm.createData()
    q = np.asarray(q, dtype=float)
    if v is None:
        pin.forwardKinematics(pm, data, q)
    else:
        v = np.asarray(v, dtype=float)
        pin.forwardKinematics(pm, data, q, v, np.zeros(pm.nv))
    pin.computeJointJacobians(pm, data, q)
    pin.updateFramePlacements(pm, data)
    return data


def _T(c: Constraint, pt: _Point) -> np.ndarray:
    """R_ref^T R_m^T: world axes -> reference axes."""
    return c.rotation.T @ pt.Rm.T


def default_at(pm, q0, c: Constraint) -> Constraint:
    """The constraint with ``at`` = where P is at q0 (medium frame's axes, or world coordinates) and
    ``orientation0`` = R_ref^T R_m0^T R_k0 (unless already given)."""
    data = _kinematics(pm, q0)
    pt = _Point(pm, data, c, with_motion=False)
    at = pt.Rm.T @ (pt.p - pt.om)
    o0 = c.rotation.T @ pt.Rm.T @ pt.Rk
    return dataclasses.replace(c, at=at if c.at is None else c.at,
                               orientation0=o0 if c.orientation0 is None else c.orientation0)


def jacobian(pm, q, constraints) -> np.ndarray:
    """J (m x nv): the constraints' rows stacked in order."""
    data = _kinematics(pm, q)
    blocks = []
    for c in constraints:
        pt = _Point(pm, data, c, with_motion=False)
        T = _T(c, pt)
        full = np.vstack([T @ (pt.JP - pt.JC), T @ (pt.Jwk - pt.Jwm)])
        blocks.append(full[list(c.rows)])
    return np.vstack(blocks) if blocks else np.zeros((0, pm.nv))


def _gamma_world(pt: _Point) -> np.ndarray:
    """gamma of the six rows in world axes, before T: (du/dt - omega_m x u, alpha_k - alpha_m - omega_m x dw)."""
    d = pt.p - pt.om
    du = pt.aP - pt.am - np.cross(pt.alm, d) - np.cross(pt.wm, pt.vP - pt.vm)
    lin = du - np.cross(pt.wm, pt.u)
    ang = pt.alk - pt.alm - np.cross(pt.wm, pt.wk - pt.wm)
    return np.concatenate([lin, ang])


def bias(pm, q, v, constraints) -> np.ndarray:
    """gamma = Jdot qdot (m): d/dt (J qdot) at qdd = 0."""
    data = _kinematics(pm, q, v)
    out = []
    for c in constraints:
        pt = _Point(pm, data, c, with_motion=True)
        T = _T(c, pt)
        g = _gamma_world(pt)
        out.append(np.concatenate([T @ g[:3], T @ g[3:]])[list(c.rows)])
    return np.concatenate(out) if out else np.zeros(0)


def residual(pm, q, constraints) -> np.ndarray:
    """phi (m).  Needs ``at`` for translational rows and ``orientation0`` for rotational rows (see
    :func:`default_at`)."""
    data = _kinematics(pm, q)
    out = []
    for c in constraints:
        pt = _Point(pm, data, c, with_motion=False)
        T = _T(c, pt)
        full = np.full(6, np.nan)
        if any(r < 3 for r in c.rows):
            if c.at is None:
                raise ValueError(f"constraint on {c.frame!r}: residual needs 'at' (see default_at)")
            p_at = pt.om + pt.Rm @ c.at
            full[:3] = T @ (pt.p - p_at)
        if any(r >= 3 for r in c.rows):
            if c.orientation0 is None:
                raise ValueError(f"constraint on {c.frame!r}: rotational residual needs 'orientation0' (default_at)")
            E = T @ pt.Rk @ c.orientation0.T
            full[3:] = pin.log3(E)
        out.append(full[list(c.rows)])
    return np.concatenate(out) if out else np.zeros(0)


def rotation_error(pm, q, c: Constraint) -> np.ndarray:
    """E = R_ref^T R_m^T R_k orientation0^T of one constraint (for checks of the rotational residual's rate)."""
    data = _kinematics(pm, q)
    pt = _Point(pm, data, c, with_motion=False)
    return _T(c, pt) @ pt.Rk @ c.orientation0.T


def mass_matrix(pm, q) -> np.ndarray:
    """Pinocchio's crba M(q), both triangles."""
    M = pin.crba(pm, pm.createData(), np.asarray(q, dtype=float))
    return np.triu(M) + np.triu(M, 1).T


def delassus(pm, q, constraints) -> np.ndarray:
    """J M^-1 J^T (dense, symmetric)."""
    J = jacobian(pm, q, constraints)
    D = J @ np.linalg.solve(mass_matrix(pm, q), J.T)
    return (D + D.T) / 2


def kkt_forward_dynamics(pm, q, v, tau, constraints, kp: float = 0.0, kd: float = 0.0):
    """(qdd, lam) of M qdd + nle = tau + J^T lam, J qdd + gamma = -(kd J v + kp phi), by a dense KKT solve."""
    q, v, tau = (np.asarray(x, dtype=float) for x in (q, v, tau))
    M = mass_matrix(pm, q)
    nle = pin.nonLinearEffects(pm, pm.createData(), q, v)
    J = jacobian(pm, q, constraints)
    rhs_c = -bias(pm, q, v, constraints) - kd * (J @ v)
    if kp != 0.0:
        rhs_c = rhs_c - kp * residual(pm, q, constraints)
    m = J.shape[0]
    K = np.block([[M, J.T], [J, np.zeros((m, m))]])
    x = np.linalg.solve(K, np.concatenate([tau - nle, rhs_c]))
    return x[:pm.nv], -x[pm.nv:]


def _pinocchio_type(c: Constraint):
    if tuple(c.rows) == TRANSLATION_ROWS:
        return pin.ContactType.CONTACT_3D
    if tuple(c.rows) == ALL_ROWS:
        return pin.ContactType.CONTACT_6D
    raise ValueError(f"Pinocchio's RigidConstraintModel has no constraint with rows {list(c.rows)} "
                     "(only [0, 1, 2] as CONTACT_3D and [0..5] as CONTACT_6D)")


def pinocchio_constraint_dynamics(pm, q, v, tau, constraints, velocity_terms: str = "ours",
                                  reference_frame=pin.ReferenceFrame.LOCAL_WORLD_ALIGNED, accuracy: float = 1e-14,
                                  max_iter: int = 100):
    """(qdd, lam in our convention) from Pinocchio's constraintDynamics with one RigidConstraintModel per
    constraint (CONTACT_3D for rows [0, 1, 2], CONTACT_6D for all six; world contacts and two-body loops).

    velocity_terms="ours" (LOCAL_WORLD_ALIGNED only) sets each constraint data's contact_acceleration_desired to
    Pinocchio's drift minus our gamma (in world axes), so that Pinocchio solves our equation J qdd + gamma = 0 at
    any v; "pinocchio" keeps Pinocchio's own drift, which equals ours only where J v = 0 for that constraint.
    reference_frame LOCAL places c1 with the reference axes R_m R_ref (at the current q) so lambda_c needs no
    rotation; it requires velocity_terms="pinocchio".  No Baumgarte terms (Pinocchio's differ from ours)."""
    if velocity_terms not in ("ours", "pinocchio"):
        raise ValueError("velocity_terms must be 'ours' or 'pinocchio'")
    local = reference_frame == pin.ReferenceFrame.LOCAL
    if not local and reference_frame != pin.ReferenceFrame.LOCAL_WORLD_ALIGNED:
        raise ValueError("reference_frame must be LOCAL or LOCAL_WORLD_ALIGNED")
    if local and velocity_terms == "ours":
        raise ValueError("velocity_terms='ours' is implemented for LOCAL_WORLD_ALIGNED only")
    q, v, tau = (np.asarray(x, dtype=float) for x in (q, v, tau))
    kin = _kinematics(pm, q, v)
    models = pin.StdVec_RigidConstraintModel()
    points, types = [], []
    for c in constraints:
        ctype = _pinocchio_type(c)
        fk = _frame_id(pm, c.frame)
        pt = _Point(pm, kin, c, with_motion=True)
        j1 = pm.frames[fk].parentJoint
        # c1 at P; its axes: those of the frame (LOCAL_WORLD_ALIGNED ignores them) or R_m R_ref (LOCAL)
        R1 = pt.Rk if not local else pt.Rm @ c.rotation
        oMc1 = pin.SE3(R1, pt.p)
        j1Mc1 = kin.oMi[j1].actInv(oMc1)
        if c.medium is None:
            cm = pin.RigidConstraintModel(ctype, pm, j1, j1Mc1, 0, oMc1, reference_frame)
        else:
            j2 = pm.frames[_frame_id(pm, c.medium)].parentJoint
            if j2 == j1:
                raise ValueError(f"{c.frame!r} and {c.medium!r} are on the same body")
            cm = pin.RigidConstraintModel(ctype, pm, j1, j1Mc1, j2, kin.oMi[j2].actInv(oMc1), reference_frame)
        models.append(cm)
        points.append(pt)
        types.append(ctype)
    datas = pin.StdVec_RigidConstraintData()
    for cm in models:
        datas.append(cm.createData())
    data = pm.createData()
    pin.initConstraintDynamics(pm, data, models, datas)
    if velocity_terms == "ours":
        for i, (pt, ctype) in enumerate(zip(points, types)):
            ours = _gamma_world(pt)
            if ctype == pin.ContactType.CONTACT_3D:
                # Pinocchio: a_P - a_C (classical accelerations of P and of the medium's point at P)
                a_C = pt.am + np.cross(pt.alm, pt.p - pt.om) + np.cross(pt.wm, pt.vC - pt.vm)
                theirs = np.concatenate([pt.aP - a_C, np.zeros(3)])
            else:
                # Pinocchio: spatial accelerations at P of body k minus medium: (a - omega x v_point, alpha)
                theirs = np.concatenate([pt.aP - np.cross(pt.wk, pt.vP)
                                         - (pt.am + np.cross(pt.alm, pt.p - pt.om) + np.cross(pt.wm, pt.vC - pt.vm)
                                            - np.cross(pt.wm, pt.vC)),
                                         pt.alk - pt.alm])
            datas[i].contact_acceleration_desired = pin.Motion(theirs[:3] - ours[:3], theirs[3:] - ours[3:])
    settings = pin.ProximalSettings(accuracy, 0.0, max_iter)
    qdd = pin.constraintDynamics(pm, data, q, v, tau, models, datas, settings).copy()
    lam_c = np.array(data.lambda_c).copy()
    lam, row = [], 0
    for c, pt, ctype in zip(constraints, points, types):
        n = 3 if ctype == pin.ContactType.CONTACT_3D else 6
        block = lam_c[row:row + n]
        row += n
        if local:
            lam.append(block)
        else:
            T = _T(c, pt)
            lam.append(np.concatenate([T @ block[:3]] + ([T @ block[3:]] if n == 6 else [])))
    return qdd, (np.concatenate(lam) if lam else np.zeros(0))


def consistent_velocity(pm, q, v, constraints) -> np.ndarray:
    """v projected (in the Euclidean metric) onto the null space of J(q): a velocity with J v = 0."""
    J = jacobian(pm, q, constraints)
    return v - np.linalg.pinv(J) @ (J @ v)
