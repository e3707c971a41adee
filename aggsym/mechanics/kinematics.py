"""Kinematics of pairs and of the tree: L, M F, quasi-velocities, S, and X = dS^T/dt q' .

Per pair (mu,k-1; lk) (Prop. 1.17, 1.18):

* ``L^{mu,k-1}_{lk} = L_constructive L_functional`` with ``L_functional = T(o) C(c1(theta4) c2(theta5) c3(theta6))``
  (absent coordinates are zero);
* the columns of ``M F`` (1.30), (1.31), called ``Psi`` here: for a translation ``o_i`` the column
  ``(c^T e_i, 0)``, for a rotation ``theta_j`` the column ``(0, eps_j)`` with ``eps = [c3^T c2^T e1 | c3^T e2 | e3]``;
  a pair with one coordinate (variant 1 of the book) has ``M F = f_i``;
* ``(M F)' q'`` (2.19), computed by running the forward sweep (2.40) through the pair's own elementary frames.

For the tree (1.34)-(1.43): ``V_lk = L^T V_parent + M F q'`` (2.39), the rows of the parastrophic matrix
``s^{st}_{lk} = s^{st}_{parent} L^{parent}_{lk}`` (1.43), and the column ``X = S'^T q'`` by (2.37):
``X_lk = L^T X_parent + L'^T V_parent + (M F)' q'`` where ``L'^T V_parent = Phi-action(L^T V_parent, V_pair)``.

A free-flyer pair (Pinocchio's JointModelFreeFlyer, :attr:`aggsym.model.types.Pair.positions`) is placed by seven
entries of q, the origin (x, y, z) in the parent's axes and a unit quaternion (qx, qy, qz, qw), ``L = T(x) C(R(quat))``;
its six coordinates are the body's quasi-velocity (v, w) itself (Def. 1.9), so ``M F`` is the unit matrix and
``(M F)' q' = 0``: the recursions take the velocity as it is.  A ball pair (Pinocchio's JointModelSpherical) is
the same without the translation: four entries of q, the unit quaternion (qx, qy, qz, qw), ``L = C(R(quat))``, and
three coordinates, the body's angular velocity relative to its parent in its own axes, ``M F = (0; E)``.

A pair with a prescribed motion (a rotor's spin (2.13)) has no coordinate; its relative quasi-velocity U = f theta'
and quasi-acceleration U' = f theta'' are known at the bound time (``BoundBody.spin``) and enter wherever the
pair's own M F q' and (M F)' q' + M F q'' do: V, X (so X is the quasi-acceleration at q'' = 0) and V'.

All 6-vectors are in the body's own frame, (v, w) order.
"""
from __future__ import annotations

from ..model.types import code_index
from .aggregates import Rigid
from ..core.program import is_zero
from .group import Chain, Motion, phi_motion, rotation
from .linalg import EYE3, ZERO3, add, cross, dot, mm, mtv, mv, scale, sub

ZERO6 = (0, 0, 0, 0, 0, 0)


def pair_functional(codes, qv, backend):
    """The functional motion of a pair and its Psi = M F columns (1.30)-(1.31).

    Returns ``(motion, psi, rotations)``: ``motion = T(o) C(c)`` with ``c = c1(theta4) c2(theta5) c3(theta6)``,
    ``psi`` one 6-vector per coordinate (child frame), and the elementary rotations in order as
    ``(axis, matrix)`` for :func:`pair_velocity_product`.
    """
    o = [0, 0, 0]
    rots = []
    for code, x in zip(codes, qv):
        i = code_index(code)
        if i < 3:
            o[i] = x
        else:
            rots.append((i - 2, rotation(i - 2, backend.cos(x), backend.sin(x))))
    c = EYE3
    for _, m in rots:
        c = mm(c, m)
    psi = []
    r = 0
    for code in codes:
        i = code_index(code)
        if i < 3:
            psi.append(tuple(c[i]) + ZERO3)  # c^T e_i is the i-th row of c
        else:
            axis, _ = rots[r]
            e = tuple(1 if j == axis - 1 else 0 for j in range(3))
            for _, m in rots[r + 1:]:
                e = mtv(m, e)
            psi.append(ZERO3 + e)
            r += 1
    return Motion(c, tuple(o)), psi, rots


def quaternion_rotation(x, y, z, w):
    """The rotation of the unit quaternion (x, y, z, w) = (sin(a/2) e, cos(a/2)): the axes of the turned frame in the
    fixed one, ``E + 2 w hat(v) + 2 hat(v)^2`` with v = (x, y, z) (the form Pinocchio and Eigen use; it assumes
    a unit quaternion)."""
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
    return ((1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy)),
            (2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx)),
            (2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy)))


def free_flyer(qv):
    """The functional motion of a quaternion pair from its positions, and its unit M F columns: a free-flyer's
    seven (origin, quaternion; the six columns f_1..f_6) or a ball's four (quaternion; the rotations f_4..f_6)."""
    if len(qv) == 4:
        return Motion(quaternion_rotation(*qv), ZERO3), [tuple(1 if j == i else 0 for j in range(6))
                                                          for i in range(3, 6)], []
    motion = Motion(quaternion_rotation(*qv[3:7]), tuple(qv[:3]))
    psi = [tuple(1 if j == i else 0 for j in range(6)) for i in range(6)]
    return motion, psi, []


def pair_velocity_product(codes, qdv, rots):
    """(M F)' q' of (2.19): the pair's relative quasi-acceleration at zero q'' (:func:`pair_velocity_bilinear`
    with w = u); zero for a single coordinate."""
    return pair_velocity_bilinear(codes, qdv, qdv, rots)


def pair_velocity_bilinear(codes, u, w, rots):
    """(M F)'(u) w: the rate of change of the pair's M F w at a fixed w while its coordinates move with rates u
    (2.19).

    The pair is run as a chain of its elementary frames (translations o1..o3, then rotations theta4..theta6)
    through the forward sweep (2.40) with zero acceleration: the velocity is built from w, the frames turn with
    u, ``A <- c^T A + phi(c^T V_w, (0, u_r e))``."""
    v = [0, 0, 0]
    rates_u, rates_w = [], []
    for code, x, y in zip(codes, u, w):
        i = code_index(code)
        if i < 3:
            v[i] = y
        else:
            rates_u.append(x)
            rates_w.append(y)
    V = tuple(v) + ZERO3
    A = ZERO6
    for (axis, m), ru, rw in zip(rots, rates_u, rates_w):
        Vr = mtv(m, V[:3]) + mtv(m, V[3:])
        Ar = mtv(m, A[:3]) + mtv(m, A[3:])
        A = add(Ar, phi_motion(Vr, ZERO3 + tuple(ru if j == axis - 1 else 0 for j in range(3))))
        V = add(Vr, ZERO3 + tuple(rw if j == axis - 1 else 0 for j in range(3)))
    return A


def combine(psi, rates):
    """Psi rates: the 6-vector sum of columns times scalars (M F q' of (1.31))."""
    out = ZERO6
    for col, x in zip(psi, rates):
        out = add(out, scale(x, col))
    return out


def project(psi, F):
    """F^T M^T F_body: the generalized components of a wrench along the pair's axes (2.15), (2.46)."""
    return [dot(col, F) for col in psi]


def generalized(kin, Z):
    """F^T M^T Z: the projection of every body's wrench on its pair's axes, in coordinate order (2.15), (2.46)."""
    out = [0] * kin.tree.nv
    for k in range(len(kin.tree)):
        for i, x in zip(kin.tree.coords[k], project(kin.psi[k], Z[k])):
            out[i] = x
    return out


class TreeKinematics:
    """Configuration-dependent kinematics of every pair: L^{parent}_{k}, Psi_k = M_k F_k."""

    def __init__(self, bound, q):
        self.bound = bound
        self.tree = bound.tree
        self.q = q
        self.L = []
        self.psi = []
        self.functional = []  # the functional motion of each pair, T(o) C(c1 c2 c3)
        self.rotations = []  # its elementary rotations in order, (axis, matrix)
        self.memo = {}  # whole-tree results that several routines of one run share (the regressor)
        self.free = [b.pair.quaternion for b in bound.model.bodies]  # free-flyer and ball pairs: constant M F
        for k, body in enumerate(bound.bodies):
            qv = [q[i] for i in self.tree.positions[k]]
            if body.offset is not None:  # internal frames (aggsym.model.transforms.reframe): c(q + offset)
                qv = [x + d for x, d in zip(qv, body.offset)]
            if self.free[k]:
                functional, psi, rots = free_flyer(qv)
            else:
                functional, psi, rots = pair_functional(body.codes, qv, bound.backend)
            L = body.L0.compose(functional)
            if body.steps is not None and rots:  # a constant rotation by an angle not a multiple of pi/2
                L = Chain(L.c, L.o, [rotation(a, c, s) for a, c, s in body.steps] + [m for _, m in rots])
            self.L.append(L)
            self.psi.append(psi)
            self.functional.append(functional)
            self.rotations.append(rots)

    def move_to_parent(self, k, X):
        """L X L^T (2.7) for a symmetric 6x6 X (Rigid or General) of body k, L = L_constructive T(o) C(c1 c2 c3):
        the elementary rotations one at a time within their planes (``rotated``), then the functional
        translation, then the constant constructive motion.  Through a pair without rotations a Mises matrix
        moves by L at once (its parallel-axis form costs about the same for any o), a general block by the
        functional translation first (along one axis its translated form skips most products).  The one congruence through a pair: composite
        bodies (2.32) and the articulated blocks of (3.7) both move by it."""
        if not self.rotations[k] and (isinstance(X, Rigid) or self.free[k]):
            return X.moved(self.L[k])
        for axis, rot in reversed(self.rotations[k]):
            i = axis % 3  # the plane's first axis: rot[i][i] = cos, rot[(i + 1) % 3][i] = sin
            c, s = rot[i][i], rot[(i + 1) % 3][i]
            X = X.rotated(axis, c, s, s * s, s * c)
        X = X.moved(Motion(EYE3, self.functional[k].o))
        body = self.bound.bodies[k]
        if body.steps is None:
            return X.moved(body.L0)
        for axis, c, s in reversed(body.steps):  # the constructive rotation plane by plane, then its translation
            if is_zero(c) or is_zero(s):
                X = X.moved(Motion(rotation(axis, c, s), ZERO3))
            else:  # (cos^2 given: near a right angle the diagonal turns by it, see Rigid.rotated)
                X = X.rotated(axis, c, s, s * s, s * c, c * c)
        return X.moved(Motion(EYE3, body.L0.o))

    def pair_rates(self, k, qd):
        return [qd[i] for i in self.tree.coords[k]]

    def relative_velocity(self, k, qd):
        """M F q' of pair k (1.31), plus the prescribed U = f theta' of a rotor's pair: its quasi-velocity relative
        to the parent (child frame)."""
        own = combine(self.psi[k], self.pair_rates(k, qd))
        spin = self.bound.bodies[k].spin
        return own if spin is None else add(own, spin[0])

    def relative_acceleration(self, k, qd):
        """(M F)' q' of pair k (2.19), plus the prescribed U' of a rotor's pair: its relative quasi-acceleration
        at zero q'' (child frame)."""
        if self.free[k]:
            return ZERO6
        out = pair_velocity_product(self.bound.bodies[k].codes, self.pair_rates(k, qd), self.rotations[k])
        spin = self.bound.bodies[k].spin
        return out if spin is None else add(out, spin[1])

    def relative_acceleration_bilinear(self, k, u, w):
        """(M F)'(u) w of pair k, u and w rate vectors of all coordinates (see :func:`pair_velocity_bilinear`)."""
        if self.free[k]:
            return ZERO6
        return pair_velocity_bilinear(self.bound.bodies[k].codes, self.pair_rates(k, u), self.pair_rates(k, w),
                                      self.rotations[k])

    def velocities(self, qd):
        """Quasi-velocities V_lk of every body (2.39)."""
        V = []
        for k, p in enumerate(self.tree.parent):
            own = self.relative_velocity(k, qd)
            V.append(own if p < 0 else add(self.L[k].twist(V[p]), own))
        return V

    def velocity_products(self, qd, V):
        """X = S'^T q' by the recurrence (2.37), including each pair's own (M F)' q' term (2.19) (and a
        prescribed pair's U': X is every body's quasi-acceleration at q'' = 0)."""
        X = []
        for k, p in enumerate(self.tree.parent):
            x = self.relative_acceleration(k, qd)
            if p >= 0:
                Vp = self.L[k].twist(V[p])
                x = add(x, add(self.L[k].twist(X[p]), phi_motion(Vp, self.relative_velocity(k, qd))))
            X.append(x)
        return X

    def accelerations(self, qd, qdd, V, base):
        """Quasi-accelerations V'_lk of the forward sweep (2.40); ``base`` is the world frame's (e.g. -gravity)."""
        A = []
        for k, p in enumerate(self.tree.parent):
            own = combine(self.psi[k], [qdd[i] for i in self.tree.coords[k]])
            a = add(self.relative_acceleration(k, qd), own)
            parent_V = ZERO6 if p < 0 else V[p]
            parent_A = base if p < 0 else A[p]
            Vp = self.L[k].twist(parent_V)
            a = add(a, add(self.L[k].twist(parent_A), phi_motion(Vp, self.relative_velocity(k, qd))))
            A.append(a)
        return A

    def backward(self, Y):
        """Z = L Y by the bud-to-root recurrence of Prop. 2.19: Z_k = Y_k + sum over children L Z_child."""
        Z = list(Y)
        for k in range(len(Z) - 1, -1, -1):
            p = self.tree.parent[k]
            if p >= 0:
                Z[p] = add(Z[p], self.L[k].wrench(Z[k]))
        return Z

    def parastrophic(self):
        """The rows of S (1.42), (1.43): ``S[i][k]`` is s^{st-alpha}_{lk} for coordinate i and body k (None
        where k is not in the subtree of i's pair)."""
        tree = self.tree
        rows = []
        for st in range(len(tree)):
            for col in self.psi[st]:
                row = [None] * len(tree)
                row[st] = col
                for lk in tree.subtrees[st][1:]:
                    row[lk] = self.L[lk].twist(row[tree.parent[lk]])
                rows.append(row)
        return rows


def world_poses(kin) -> list:
    """Every body's pose in the world: Motion(R_k, p_k), x_world = R_k x_body + p_k (the L of (1.13) composed
    from the root, Prop. 1.8)."""
    poses = []
    for k, p in enumerate(kin.tree.parent):
        poses.append(kin.L[k] if p < 0 else poses[p].compose(kin.L[k]))
    return poses


def moving_bodies(bound) -> list:
    """Per body: whether it moves (:attr:`aggsym.model.tree.Tree.moving`); the others are welded to the world."""
    return bound.tree.moving


def point_rows(kin, poses, k, P, B=None, m=-1) -> list:
    """The six rows (n entries each) of the motion of the point P (world) fixed on body k relative to body m (-1:
    the world): the velocity of P relative to the point of m that coincides with it, then the relative angular
    velocity, per unit rate of each coordinate, in the axes B (a 3x3 map from world axes; None: world axes).  For
    coordinate i of body s on k's path and not on m's, with psi = (v, w) its column of M F (1.30) in s's axes
    (R_s, o_s s's world pose): ``w_i = B R_s w``, ``v_i = B R_s v + w_i x B (P - o_s)``; minus that on m's path
    and not on k's.  These are the columns of the parastrophic matrix S (1.42) moved to the point: for m = -1
    and B = None, the frame Jacobian (LOCAL_WORLD_ALIGNED)."""
    tree = kin.tree
    n = tree.nv
    lin, ang = [[0] * n for _ in range(3)], [[0] * n for _ in range(3)]
    on_k = set(tree.ancestors(k))
    on_m = set(tree.ancestors(m)) if m >= 0 else set()
    for s in sorted(on_k ^ on_m):
        sign = 1 if s in on_k else -1
        pose = poses[s]
        M = pose.c if B is None else mm(B, pose.c)
        d = sub(P, pose.o) if B is None else mv(B, sub(P, pose.o))
        for i, psi in zip(tree.coords[s], kin.psi[s]):
            w = mv(M, psi[3:])
            v = add(mv(M, psi[:3]), cross(w, d))
            for a in range(3):
                lin[a][i] = v[a] if sign > 0 else -v[a]
                ang[a][i] = w[a] if sign > 0 else -w[a]
    return lin + ang


def point_motion(R, V, A, r) -> tuple:
    """(velocity, classical acceleration) of the point r (body axes) of a body with world rotation R,
    quasi-velocity V = (v, w) and quasi-acceleration A = (a, alpha), and the body's angular velocity and
    acceleration, all in world axes: ``R (v + w x r)``, ``R (a + alpha x r + w x (v + w x r))`` (the classical
    acceleration of the origin is a + w x v)."""
    v, w, a, al = V[:3], V[3:], A[:3], A[3:]
    vb = add(v, cross(w, r))
    ab = add(add(a, cross(al, r)), cross(w, vb))
    return mv(R, vb), mv(R, ab), mv(R, w), mv(R, al)


def world_frame_vectors(kin, vec_world):
    """A free vector given in the world frame, in every body's axes: c_k^T x (used for gravity)."""
    out = []
    for k, p in enumerate(kin.tree.parent):
        parent = vec_world if p < 0 else out[p]
        out.append(kin.L[k].unrotate_free(parent))
    return out


__all__ = ["TreeKinematics", "pair_functional", "pair_velocity_product", "pair_velocity_bilinear", "combine",
           "project", "world_frame_vectors", "quaternion_rotation", "free_flyer", "world_poses", "generalized", "moving_bodies", "point_rows",
           "point_motion", "ZERO6"]
