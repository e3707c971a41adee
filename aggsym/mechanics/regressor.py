"""The identification regressor: tau = Y(q, qd, qdd) pi, linear in the bodies' standard inertial parameters.

The dynamic wrench of a rigid body about its origin (the left side of (2.10), in the form of
:meth:`~aggsym.mechanics.aggregates.Rigid.dynamic_wrench`) with w, alpha its angular velocity and acceleration and
a the classical acceleration of its origin (gravity included as the base's acceleration -g, (2.40)) is

    f  = m a + alpha x h + w x (w x h),      mu = h x a + Theta alpha + w x (Theta w),

linear in pi = (m, h_x, h_y, h_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz) (h = m r_c, Theta the inertia about the origin:
Pinocchio's order): a 6 x 10 matrix Phi(w, alpha, a) with f = Phi pi.  The generalized forces are the wrenches
projected by the parastrophic matrix, tau = S Z (2.15), (2.30): the block of Y for body k and coordinate i is
s_{i,k}^T Phi_k, s_{i,k} the row of S (1.42)-(1.43) at body k (the motion of k per unit rate of i, in k's
axes), zero where k is not moved by i (one motion transform per pair (i, k) and ten sparse dot products, where
carrying the ten columns up the tree as wrenches would take ten transforms).  A URDF body's parameters are in its
link frame (Pinocchio's joint frame): Phi is built from the motion in link axes and its columns turned to the
body's (x_body = R x_link).  One block per moving body (a body welded to the
world has none), bodies in tree order (the order of the coordinates); links welded by fixed joints are in their
body, as Pinocchio merges them.

With friction and drives (:func:`friction_regressor`, issue 34): the generalized force a motor supplies against
joint friction and its own rotor is tau = Y pi + diag(qd) f_v + diag(sign qd) f_c + diag(qdd) I_a (the columns
SymPyBotics and OpenSYMORO append per joint: viscous friction FV, Coulomb friction FS, rotor inertia IA): the
friction of ``joint_friction`` moved to the left (tau = inverse dynamics - tau_f) and the armature on the joint's
own axis (Pinocchio's ``armature``, ``--armature``; MJCF's ``armature``; MJCF's viscous ``damping`` is in f_v).
The joints are the coordinates of pairs that are not free (a free root's six coordinates have no drive); a free
root's coordinate gets an armature column only where the model gives it an armature.
"""
from __future__ import annotations

from ..model.tree import Tree
from .kinematics import moving_bodies
from .linalg import add, cross, dot, mtv, mv, neg
from .sweeps import link_rotation, origin_sweep

PARAMETERS = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
_INERTIA_ENTRIES = ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2))  # Ixx, Ixy, Iyy, Ixz, Iyz, Izz


def blocks(model) -> list:
    """The bodies with a block of the regressor, in order (indices into model.bodies): those that move."""
    return [k for k, moves in enumerate(Tree.of(model).moving) if moves]


def _unit(j):
    return tuple(1 if i == j else 0 for i in range(3))


def wrench_columns(w, alpha, a) -> list:
    """Phi(w, alpha, a): the 10 wrenches (f, mu) of the unit parameters, in the axes of w, alpha, a."""
    cols = [tuple(a) + (0, 0, 0)]
    for j in range(3):
        e = _unit(j)
        cols.append(add(cross(alpha, e), cross(w, cross(w, e))) + cross(e, a))
    for i, j in _INERTIA_ENTRIES:
        # Theta = E_ij + E_ji (or E_ii): Theta x picks x_j into row i and x_i into row j
        def theta(x, i=i, j=j):
            out = [0, 0, 0]
            out[i] = x[j]
            if i != j:
                out[j] = x[i]
            return tuple(out)
        cols.append((0, 0, 0) + add(theta(alpha), cross(w, theta(w))))
    return cols


def regressor(bound, kin, qd, qdd) -> list:
    """Y: n rows of 10 * (number of blocks) entries (kept in ``kin.memo`` for the same rate vectors, so that the
    base regressor of the same run reuses it)."""
    key = ("regressor", id(qd), id(qdd))
    if key not in kin.memo:
        kin.memo[key] = (qd, qdd, _regressor(bound, kin, qd, qdd))  # (the vectors kept alive with their ids)
    return kin.memo[key][2]


def _regressor(bound, kin, qd, qdd) -> list:
    tree = kin.tree
    ks = [k for k, moves in enumerate(moving_bodies(bound)) if moves]
    rows = [[0] * (10 * len(ks)) for _ in range(tree.nv)]
    origins = origin_sweep(bound, kin, qd, qdd, neg(bound.gravity))
    S = kin.parastrophic()
    for b, k in enumerate(ks):
        o = origins[k]
        R = link_rotation(bound, k)
        if R is None:
            cols = wrench_columns(o.w, o.wd, o.a)
        else:  # in link axes, then the wrenches back to the body's
            cols = [mv(R, c[:3]) + mv(R, c[3:]) for c in wrench_columns(mtv(R, o.w), mtv(R, o.wd), mtv(R, o.a))]
        for i, row in enumerate(S):
            if row[k] is not None:
                for j, c in enumerate(cols):
                    rows[i][10 * b + j] = dot(row[k], c)
    return rows


def _free(model) -> list:
    """Per velocity coordinate (tree order): whether it is one of a free pair's six (a floating base)."""
    return [len(b.pair.coordinates) == 6 for b in model.bodies for _ in b.pair.coordinates]


def _nonzero(x) -> bool:
    return not (getattr(x, "is_zero", False) is True or (isinstance(x, (int, float)) and x == 0))


def drives(model) -> tuple:
    """(joints, rotors): the velocity coordinates with friction columns (every coordinate of a pair that is not
    free) and those with an armature column (the joints, and a free pair's coordinates where the model gives them
    an armature: ``armature``, ``dof_armature``)."""
    free = _free(model)
    joints = [j for j, f in enumerate(free) if not f]
    own = list(model.dof_armature) or [0] * len(free)
    rotors = [j for j, f in enumerate(free) if not f or _nonzero(model.armature) or _nonzero(own[j])]
    return joints, rotors


def friction_regressor(bound, kin, qd, qdd) -> list:
    """[Y | diag(qd) | diag(sign qd) | diag(qdd)]: n rows of 10 B + 2 J + R entries (J joints, R rotors of
    :func:`drives`), sign(0) = 0 (branch-free in every target: the table's ``sign``)."""
    joints, rotors = drives(bound.model)
    Y = regressor(bound, kin, qd, qdd)
    sign = [bound.backend.call("sign", qd[j]) for j in joints]
    out = []
    for i, row in enumerate(Y):
        out.append(list(row) + [qd[i] if j == i else 0 for j in joints]
                   + [s if j == i else 0 for j, s in zip(joints, sign)]
                   + [qdd[i] if j == i else 0 for j in rotors])
    return out


def standard_parameters(model) -> list:
    """pi of the model as SymPy expressions (its own inertial data), block by block: (m, m c, Theta about the
    origin in link axes) in :data:`PARAMETERS` order."""
    import sympy as sp

    out = []
    for k in blocks(model):
        body = model.bodies[k]
        if body.inertial is None:
            out.extend([sp.Integer(0)] * 10)
            continue
        m, h, J = body.inertial.mises()
        h, J = sp.Matrix(h), sp.Matrix(J)
        if body.link_rotation is not None:
            R = sp.Matrix(body.link_rotation)
            h, J = R.T * h, R.T * J * R
        out.append(m)
        out.extend(sp.expand(h[i]) for i in range(3))
        out.extend(sp.expand(J[i, j]) for i, j in _INERTIA_ENTRIES)
    return out


__all__ = ["PARAMETERS", "blocks", "drives", "friction_regressor", "regressor", "standard_parameters",
           "wrench_columns"]
