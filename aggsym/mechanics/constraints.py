"""Constraints with the medium and closed loops (chapter 4): residual, Jacobian D_lambda^T, its rate term, the
Delassus matrix by the transvective factors, and the constrained forward dynamics.

A constraint forbids some relative motions of a point P fixed on body k with respect to a reference frame fixed in
the medium m (the world, or another body of the tree: a closed loop), with constant axes ``R_ref`` (in the
medium's axes): the rows of (4.5)-(4.12) are the components of P's relative velocity (translations o1 o2 o3) and of
the relative angular velocity (rotations theta4 theta5 theta6) along the reference axes.  In world vectors, with
``B = R_ref^T R_m^T`` (R_m the medium's orientation, identity for the world)::

    translational rows: B (v_P - v_C),   v_C the velocity of the point of m that coincides with P
    rotational rows:    B (w_k - w_m)

so ``J qd`` is the relative motion; a coordinate on the common path of k and m moves both alike and drops out.
A column of J is the relative motion of a unit rate of one coordinate: for coordinate i of body s (its column
psi = (v, w) of M F in s's axes, (1.30)), ``w_i = B R_s w`` and ``v_i = B R_s v + w_i x B (P - p_s)``, with a
plus sign for the bodies on k's path and a minus sign on m's.  This is the row of the parastrophic matrix S of
(1.42) moved to the contact point (the columns of S^T are the bodies' quasi-velocities per unit rate).

``gamma = J' qd``: the relative acceleration at qdd = 0 (classical accelerations of points): with ``X = S'^T qd``
(2.37) the quasi-acceleration of every body at qdd = 0, P's acceleration is ``R_k (a + alpha x r + w x (v + w x
r))`` ((v, w), (a, alpha) body k's quasi-velocity and X, r = P in k's axes); against a moving medium,
``d/dt [R_m^T u] = R_m^T (u' - w_m x u)`` with ``u = v_P - v_m - w_m x (P - p_m)``,
``u' = a_P - a_m - alpha_m x (P - p_m) - w_m x (v_P - v_m)``; rotational rows ``alpha_k - alpha_m - w_m x
(w_k - w_m)``.

The residual phi: translational rows ``B (P - A)``, A the attachment point ``at`` fixed in the medium (by default
where P is at q = 0); rotational rows the rotation vector (log map) of ``Q = B R_k C0``, ``C0 = R_k0^T R_m0 R_ref``
(the body's orientation relative to the one it has at q = 0, in the reference axes; a constraint's own
``orientation`` replaces C0, an MJCF weld's relpose): ``phi = theta/sin(theta)
vee(Q - Q^T)/2`` with theta = atan2(|vee|, (tr Q - 1)/2), evaluated as ``(theta + eps)/(|vee| + eps)`` (exact in
doubles at theta = 0 and everywhere else, no branch).

A joint-space row (``Constraint.joint_row``: an MJCF joint or tendon equality) is one row whose phi, J and
gamma are those of a polynomial relation of linear forms of the coordinates (:mod:`aggsym.mechanics.joint_space`)
or of spatial tendons' lengths (:class:`~aggsym.mechanics.spatial_tendons.SpatialLength`, an MJCF equality on a
``<spatial>`` tendon, bound to these kinematics here); it has no point, axes, slip or friction, and enters G and
the constrained dynamics like any other row.

A prescribed motion of the world-side frame (``motion:``, Prop. 4.5-4.8) makes the world a moving medium with
known pose, velocity and acceleration (:class:`MovingFrame`): J is unchanged, the rows' relative velocity is
``J qd + F(t)`` (4.35) (:meth:`ConstraintKinematics.time_terms`), and gamma holds every time term.

The equations (4.25)-(4.28): ``A qdd + b + g + c = tau + J^T lambda``, ``J qdd + gamma = -(kd (J qd + F) + kp phi)``;
lambda is the wrench the medium exerts on body k about P in the reference axes (the medium body gets -lambda).
With the transvective factors (3.19), A^-1 = T^T D^-1 T: ``P = T J^T`` (one O(n) product per row,
:func:`~aggsym.mechanics.transvective.apply_T_tree`), ``G = J A^-1 J^T = P^T D^-1 P`` (the Delassus matrix),
``y = T (tau - b - g - c)`` from the sweeps, ``G lambda = -gamma - stab - P^T D^-1 y``,
``qdd = T^T D^-1 (y + P lambda)``; G by an LDL^T factorization of m x m (no n x n inverse or LU), or damped by
the model's ``proximal`` setting (:mod:`aggsym.mechanics.damped`).
"""
from __future__ import annotations

from dataclasses import dataclass

from ..core.program import is_zero
from ..model.types import WORLD, code_index
from .bound import constant_axes
from .damped import DelassusSolver, model_proximal
from .group import Motion, rotation
from .joint_space import BoundJointRow, bind_joint_row, places
from .kinematics import TreeKinematics, point_motion, point_rows, world_poses
from .linalg import EYE3, add, cross, dot, ldl_factor, mm, mtv, mul, mv, scale, sub, transpose
from .spatial_tendons import SpatialLength
from .transvective import apply_T_transpose_tree, apply_T_tree, articulated_factors, transvected_forces

EPS = 1e-30  # the log map's guard at theta = 0: (theta + EPS) / (|s| + EPS) is theta/sin(theta) (relative error
# below EPS/theta, i.e. none a double sees where theta/sin(theta) differs from 1 at all); a normal number in float
SINGULAR = 1e-12  # a pivot of G below SINGULAR * trace(G) / m makes constrained_forward_dynamics return nonzero
SLIP = 1e-9  # Coulomb friction acts where the slip speed |w| is at least SLIP (m/s), and is zero below


@dataclass
class BoundConstraint:
    """One constraint's data as backend scalars."""

    k: int  # the constrained body
    m: int  # the medium's body, -1 for the world
    r: tuple  # P in k's axes
    at: tuple | None  # the attachment point in m's axes (world for the world), None: P at q = 0
    R_ref: tuple  # 3x3: the reference axes in m's axes (columns)
    rows: tuple  # indices 0..5 (o1 o2 o3 theta4 theta5 theta6)
    free: tuple  # indices 0..2 of the free translations (the slip directions)
    law: str | None  # friction: "viscous", "coulomb" or None
    coefficient: object  # its c or mu
    normal: int | None  # the normal row's place among this constraint's rows (Coulomb)
    wheel: tuple | None = None  # (radius, axle in k's axes) of a rolling disc, its centre at r
    frame: "MovingFrame | None" = None  # the world-side frame's prescribed motion (motion:), None: at rest
    C0: tuple | None = None  # 3x3: the rotational residual's C0 when given (Constraint.orientation), None: q = 0's


def bind_constraints(bound) -> list:
    index = {name: k for k, name in enumerate(bound.tree.names)}
    out = []
    where = None
    for c in bound.model.constraints:
        if c.joint_row is not None:  # a joint-space row (aggsym.mechanics.joint_space)
            where = places(bound) if where is None else where
            out.append(bind_joint_row(bound, c.joint_row, where))
            continue
        R = constant_axes(bound, c.medium_axes, c.rotation)
        R = EYE3 if R is None else R
        out.append(BoundConstraint(
            k=index[c.body], m=-1 if c.medium == WORLD else index[c.medium],
            r=tuple(bound.scalar(x) for x in c.point),
            at=None if c.at is None else tuple(bound.scalar(x) for x in c.at),
            R_ref=R, rows=tuple(code_index(code) for code in c.rows),
            free=tuple(code_index(code) for code in c.free_translations),
            law=None if c.friction is None else c.friction[0],
            coefficient=None if c.friction is None else bound.scalar(c.friction[1]),
            normal=None if c.normal is None else c.rows.index(c.normal),
            wheel=None if c.wheel is None else (bound.scalar(c.wheel[0]), tuple(bound.scalar(x) for x in c.wheel[1])),
            frame=None if not c.motion else MovingFrame(bound, c.motion),
            C0=None if c.orientation is None else tuple(tuple(bound.scalar(x) for x in r) for r in c.orientation)))
    return out


class MovingFrame:
    """The prescribed functional motion of a constraint's world-side frame (``motion:``, Prop. 4.5-4.8):
    ``F(t) = T(o(t)) C(c1(theta4) c2(theta5) c3(theta6))`` as a pair's functional motion (1.30); its pose, the
    velocity and classical acceleration of its origin and its angular velocity and acceleration (world axes),
    from SymPy's derivatives of the model's expressions in t (``omega = vee(C' C^T)``), at the bound time, and
    its pose at t = 0 (the default attachment)."""

    def __init__(self, bound, motion):
        import sympy as sp

        from ..model.types import TIME

        o = sp.zeros(3, 1)
        C = sp.eye(3)
        for code, expr in motion:
            i = code_index(code)
            if i < 3:
                o[i] = expr
            else:
                C = C * sp.Matrix(rotation(i - 2, sp.cos(expr), sp.sin(expr)))
        W = C.diff(TIME) * C.T
        w = sp.Matrix([W[2, 1], W[0, 2], W[1, 0]])

        def vector(m):
            return tuple(bound.scalar(x) for x in m)

        def pose(at_zero):
            c, x = (C.subs(TIME, 0), o.subs(TIME, 0)) if at_zero else (C, o)
            return Motion(tuple(tuple(bound.scalar(c[r, k]) for k in range(3)) for r in range(3)), vector(x))

        self.pose, self.pose0 = pose(False), pose(True)
        self.v, self.a = vector(o.diff(TIME)), vector(o.diff(TIME, 2))
        self.w, self.alpha = vector(w), vector(w.diff(TIME))


WORLD_POSE = Motion(EYE3, (0, 0, 0))


class ConstraintKinematics:
    """The constraints of a bound model at one configuration: poses, points, reference axes."""

    def __init__(self, bound, kin, rest: bool = False):
        self.bound, self.kin, self.rest = bound, kin, rest
        self.items = bind_constraints(bound)
        self.poses = world_poses(kin)
        self.items = [c.on(lambda branches: SpatialLength(bound, kin, branches, self.poses))
                      if isinstance(c, BoundJointRow) else c for c in self.items]  # (spatial lengths: these poses)
        self.P, self.B, self.discs = [], [], []
        for c in self.items:
            if isinstance(c, BoundJointRow):
                self.P.append(None)
                self.B.append(None)
                self.discs.append(None)
                continue
            pose = self.poses[c.k]
            B = transpose(mm(self.medium_pose(c).c, c.R_ref))  # world vector -> reference axes
            self.B.append(B)
            centre = add(pose.o, mv(pose.c, c.r))
            disc = None if c.wheel is None else Disc(bound.backend, c.wheel[0], mv(pose.c, c.wheel[1]), B[2])
            self.discs.append(disc)
            self.P.append(centre if disc is None else add(centre, disc.offset))

    def medium_pose(self, c):
        """The medium's pose: a body's, the world's, or the moving frame's (at t = 0 for the rest kinematics)."""
        if c.m >= 0:
            return self.poses[c.m]
        if c.frame is None:
            return WORLD_POSE
        return c.frame.pose0 if self.rest else c.frame.pose

    def motion_rows(self, c, P, B) -> list:
        """The six rows (o1 o2 o3 theta4 theta5 theta6, n entries each) of the relative motion of constraint c."""
        return point_rows(self.kin, self.poses, c.k, P, B, c.m)

    def jacobian(self) -> list:
        """J (D_lambda^T of (4.27)): one row (n entries) per blocked motion, constraints in order."""
        return [row for c, P, B in zip(self.items, self.P, self.B)
                for row in ([c.jacobian(self.kin.q)] if isinstance(c, BoundJointRow) else
                            self._selected(self.motion_rows(c, P, B), c.rows))]

    def slip_jacobians(self) -> list:
        """Per constraint, the rows of its free translations (D_k+^T of (4.33)-(4.34): the permitted motions)."""
        return [[] if isinstance(c, BoundJointRow) else self._selected(self.motion_rows(c, P, B), c.free)
                for c, P, B in zip(self.items, self.P, self.B)]

    @staticmethod
    def _selected(rows, indices) -> list:
        return [rows[j] for j in indices]

    def bias(self, qd) -> list:
        """gamma = J' qd: the relative acceleration of every row at qdd = 0."""
        V = self.kin.velocities(qd)
        X = self.kin.velocity_products(qd, V)
        out = []
        for c, P, B, disc in zip(self.items, self.P, self.B, self.discs):
            if isinstance(c, BoundJointRow):
                out.append(c.bias(self.kin.q, qd))
                continue
            vP, aP, wk, alk = self._point_motion(c.k, c.r, V, X)
            if disc is not None:  # the material point at the contact: d/dt (v_C + w x r u) at qdd = 0
                lin, ang = add(add(aP, cross(alk, disc.offset)), cross(wk, disc.offset_rate(wk))), alk
            elif c.m < 0 and c.frame is None:
                lin, ang = aP, alk
            else:  # relative to a moving medium: d/dt of B (v_P - v_m - w_m x (P - p_m)) and of B (w_k - w_m)
                pm = self.medium_pose(c)
                if c.frame is not None:
                    vm, am, wm, alm = c.frame.v, c.frame.a, c.frame.w, c.frame.alpha
                else:
                    vm, am, wm, alm = self._point_motion(c.m, (0, 0, 0), V, X)
                d = sub(P, pm.o)
                dv = sub(vP, vm)
                u = sub(dv, cross(wm, d))
                du = sub(sub(sub(aP, am), cross(alm, d)), cross(wm, dv))
                lin = sub(du, cross(wm, u))
                dw = sub(wk, wm)
                ang = sub(sub(alk, alm), cross(wm, dw))
            row = mv(B, lin) + mv(B, ang)
            out.extend(row[j] for j in c.rows)
        return out

    def time_terms(self) -> list:
        """F(t) of (4.35): per row, the part of the relative velocity that the frame's prescribed motion makes,
        so that the rows' relative velocity is J qd + F: ``-B (v_F + w_F x (P - o_F))``, ``-B w_F``; 0 at rest."""
        out = []
        for c, P, B in zip(self.items, self.P, self.B):
            if c.frame is None:
                out.extend(0 for _ in c.rows)
                continue
            f = c.frame
            lin = mv(B, add(f.v, cross(f.w, sub(P, f.pose.o))))
            row = tuple(-x for x in lin) + tuple(-x for x in mv(B, f.w))
            out.extend(row[j] for j in c.rows)
        return out

    def _point_motion(self, k, r, V, X):
        """(velocity, classical acceleration at qdd = 0) of the point r of body k, and the body's angular velocity
        and acceleration, all in world axes."""
        return point_motion(self.poses[k].c, V[k], X[k], r)

    def residual(self, rest: "ConstraintKinematics") -> list:
        """phi, with ``rest`` the same constraints at q = 0 (the default attachment and orientation)."""
        backend = self.bound.backend
        out = []
        for c, P, B, P0 in zip(self.items, self.P, self.B, rest.P):
            if isinstance(c, BoundJointRow):
                out.append(c.residual(self.kin.q))
                continue
            pm, pm0 = self.medium_pose(c), rest.medium_pose(c)
            local = c.at if c.at is not None else mtv(pm0.c, sub(P0, pm0.o))  # A in the medium's axes
            lin = mv(B, sub(P, add(pm.o, mv(pm.c, local))))
            ang = (0, 0, 0)
            if any(j >= 3 for j in c.rows):
                C0 = c.C0 if c.C0 is not None else mm(transpose(rest.poses[c.k].c), mm(pm0.c, c.R_ref))
                Q = mm(B, mm(self.poses[c.k].c, C0))
                s = scale(backend.rational(1, 2), (Q[2][1] - Q[1][2], Q[0][2] - Q[2][0], Q[1][0] - Q[0][1]))
                cos = (Q[0][0] + Q[1][1] + Q[2][2] - 1) * backend.rational(1, 2)
                norm = backend.sqrt(dot(s, s))
                theta = backend.call("atan2", norm, cos)
                ang = scale((theta + EPS) / (norm + EPS), s)
            if c.wheel is not None:  # rolling: only the height of the contact point over the plane is holonomic
                lin = (0, 0, lin[2])
            row = tuple(lin) + tuple(ang)
            out.extend(row[j] for j in c.rows)
        return out


class Disc:
    """A disc of radius r about the unit axle a (world axes) touching the plane with unit normal n (world axes):
    the contact point is the centre plus ``r u`` with ``u = a x e``, ``e = (a x n)/|a x n|`` the direction of
    rolling (u points from the centre towards the plane, in the disc's plane).  Not defined for a disc lying flat
    (a parallel to n)."""

    def __init__(self, backend, radius, a, n):
        self.radius, self.a, self.n = radius, a, n
        b = cross(a, n)
        self.s = backend.sqrt(dot(b, b))
        self.e = scale(1 / self.s, b)
        self.offset = scale(radius, cross(a, self.e))

    def offset_rate(self, w) -> tuple:
        """d/dt (r u) for the disc turning with angular velocity w (world axes), the plane fixed: a' = w x a,
        e' = (b' - e (e . b'))/|b| with b = a x n, u' = a' x e + a x e'."""
        da = cross(w, self.a)
        db = cross(da, self.n)
        de = scale(1 / self.s, sub(db, scale(dot(self.e, db), self.e)))
        return scale(self.radius, add(cross(da, self.e), cross(self.a, de)))


def rest_kinematics(bound) -> ConstraintKinematics:
    """The constraints at q = 0 (a free-flyer's unit quaternion: the identity) and t = 0 (constants, or expressions in the parameters)."""
    kin0 = TreeKinematics(bound, bound.tree.neutral)
    return ConstraintKinematics(bound, kin0, rest=True)


def residual(bound, kin) -> list:
    return ConstraintKinematics(bound, kin).residual(rest_kinematics(bound))


def jacobian(bound, kin) -> list:
    return ConstraintKinematics(bound, kin).jacobian()


def bias(bound, kin, qd) -> list:
    return ConstraintKinematics(bound, kin).bias(qd)


def slip_velocities(bound, kin, qd) -> list:
    """w (4.33): the contact points' velocities relative to the medium along each constraint's free translations,
    constraints in order."""
    return [dot(row, qd) for rows in ConstraintKinematics(bound, kin).slip_jacobians() for row in rows]


def _projected(kin, fac, J) -> list:
    """P = T J^T, one column (an n-list) per row of J (3.9), in O(n) each."""
    return [apply_T_tree(kin, fac, row) for row in J]


def _delassus(fac, P) -> list:
    """G = P^T D^-1 P (m x m, symmetric)."""
    m = len(P)
    G = [[0] * m for _ in range(m)]
    for i in range(m):
        scaled = [mul(r, x) for r, x in zip(fac.recip, P[i])]
        for j in range(i, m):
            G[i][j] = G[j][i] = dot(scaled, P[j])
    return G


def delassus(bound, kin) -> list:
    """G = J A^-1 J^T = (T J^T)^T D^-1 (T J^T) by the transvective factors (3.19), rows."""
    fac = articulated_factors(bound, kin, arguments=False)
    return _delassus(fac, _projected(kin, fac, jacobian(bound, kin)))


def ldl_solve(G, b, backend):
    """x with G x = b for a small symmetric G by L D L^T (no pivoting), and the status: the number of pivots
    below SINGULAR * trace(G) / m counted by sign() (nonzero when G is singular or not finite)."""
    m = len(b)
    L, d = ldl_factor(G)
    y = list(b)
    for i in range(m):
        for k in range(i):
            y[i] = y[i] - mul(L[i][k], y[k])
    x = [y[i] / d[i] for i in range(m)]
    for i in range(m - 1, -1, -1):
        for k in range(i + 1, m):
            x[i] = x[i] - mul(L[k][i], x[k])
    trace = 0
    for j in range(m):
        trace = trace + G[j][j]
    tol = trace * (SINGULAR / m)
    status = 0
    for j in range(m):
        status = status + (backend.call("sign", tol - d[j]) + 1)
    return x, status


def _above(backend, x):
    """1 where x > 0, else 0 (sign(x) + sign(x)^2)/2, exact at x = 0."""
    s = backend.call("sign", x)
    return (s + mul(s, s)) * backend.rational(1, 2)


def lu_solve(M, b, backend):
    """x with M x = b for a small square M by Gaussian elimination with partial pivoting (a row exchange is a
    blend by :func:`_above`, so the program stays straight-line), and the status: the number of pivots below
    SINGULAR * sum|M_ii| / m."""
    m = len(b)
    a = [list(row) + [r] for row, r in zip(M, b)]
    pivots = []
    for j in range(m):
        for i in range(j + 1, m):
            swap = _above(backend, backend.call("abs", a[i][j]) - backend.call("abs", a[j][j]))
            for col in range(j, m + 1):
                x, y = a[j][col], a[i][col]
                change = mul(swap, y - x)
                a[j][col], a[i][col] = x + change, y - change
        pivots.append(a[j][j])
        inv = 1 / a[j][j]
        for i in range(j + 1, m):
            f = mul(a[i][j], inv)
            for col in range(j + 1, m + 1):
                a[i][col] = a[i][col] - mul(f, a[j][col])
    x = [0] * m
    for i in range(m - 1, -1, -1):
        acc = a[i][m]
        for k in range(i + 1, m):
            acc = acc - mul(a[i][k], x[k])
        x[i] = acc / a[i][i]
    size = 0
    for j in range(m):
        size = size + backend.call("abs", M[j][j])
    tol = size * (SINGULAR / m)
    status = 0
    for piv in pivots:
        status = status + _above(backend, tol - backend.call("abs", piv))
    return x, status


def _direction(backend, w):
    """w/|w|, and 0 where |w| < SLIP (Coulomb friction's direction, (4.5) with (4.33))."""
    norm = backend.sqrt(dot(w, w))
    on = _above(backend, norm - SLIP)
    return [mul(on, x) / (norm + 1 - on) for x in w]


def _transpose_times(rows, x) -> list:
    """rows^T x for rows of equal length (n), x one entry per row."""
    out = [0] * len(rows[0])
    for row, xi in zip(rows, x):
        out = [o + mul(r, xi) for o, r in zip(out, row)]
    return out


def constrained_forward_dynamics(bound, kin, qd, tau) -> tuple:
    """(qdd, lambda, status) of (4.25)-(4.28) with the Baumgarte terms and friction, ``tau`` already less the
    elastic force.

    Friction acts on the free translations of a sliding contact ((4.5), W from the slip velocities w of (4.33)):
    viscous ``W = -c w`` is a known generalized force ``-c Jf^T w``; Coulomb ``W = -mu |lambda_n| w/|w|`` adds to
    lambda_n's column of J^T the column ``-mu s Jf^T w/|w|`` with s the sign of lambda_n, which makes the m x m
    system ``J A^-1 H^T lambda = ...`` non-symmetric (solved by :func:`lu_solve`).  s is taken from the
    frictionless solution (by the LDL^T of G); for one Coulomb contact this is exact: by Sherman-Morrison the
    friction scales lambda_n by 1/(1 + mu s kappa), so either that sign is consistent or no solution exists
    (Painleve's case).  Where the sign of the result disagrees with s, the status is nonzero."""
    backend = bound.backend
    ck = ConstraintKinematics(bound, kin)
    J = ck.jacobian()
    fac = articulated_factors(bound, kin, arguments=False)
    P = _projected(kin, fac, J)
    G = _delassus(fac, P)
    eps = bound.scalar(bound.model.regularization)
    if not is_zero(eps):  # the explicit regularization: G + epsilon E (redundant rows share lambda)
        G = [[g + eps if i == j else g for j, g in enumerate(row)] for i, row in enumerate(G)]
    slips = ck.slip_jacobians() if bound.model.has_friction else [()] * len(ck.items)
    force = list(tau)
    for c, Jf in zip(ck.items, slips):
        if c.law == "viscous":
            w = [dot(row, qd) for row in Jf]
            force = [f - x for f, x in zip(force, _transpose_times(Jf, [mul(c.coefficient, v) for v in w]))]
    y = transvected_forces(bound, kin, fac, force, qd)
    Dy = [mul(r, v) for r, v in zip(fac.recip, y)]
    rhs = [-g - dot(p, Dy) for g, p in zip(ck.bias(qd), P)]
    kp, kd = (bound.scalar(x) for x in bound.model.stabilization)
    if not is_zero(kd):  # the relative velocity J qd + F(t)
        rhs = [x - mul(kd, dot(row, qd) + f) for x, row, f in zip(rhs, J, ck.time_terms())]
    if not is_zero(kp):
        rhs = [x - mul(kp, f) for x, f in zip(rhs, ck.residual(rest_kinematics(bound)))]
    proximal = model_proximal(bound)
    if proximal is None:
        lam, status = ldl_solve(G, rhs, backend)
    else:  # the damped solve (aggsym.mechanics.damped): N proximal iterations on G + mu E
        solver = DelassusSolver(G, backend, proximal)
        lam, status = solver.solve(rhs), solver.status
    coulomb, offset = [], 0
    for c, Jf in zip(ck.items, slips):
        if c.law == "coulomb":
            j = offset + c.normal
            s = backend.call("sign", lam[j])
            column = _transpose_times(Jf, _direction(backend, [dot(row, qd) for row in Jf]))
            coulomb.append((j, s, apply_T_tree(kin, fac, [mul(-mul(c.coefficient, s), x) for x in column])))
        offset += len(c.rows)
    if coulomb:
        scaled = [[mul(r, x) for r, x in zip(fac.recip, p)] for p in P]  # D^-1 T J^T: the rows of J A^-1 T^-1
        P = list(P)
        for j, _, extra in coulomb:
            P[j] = add(P[j], extra)  # T H^T: lambda_n's column carries the friction it causes
        H = [[dot(scaled[i], P[j]) + (eps if i == j else 0) for j in range(len(P))]
             for i in range(len(P))]  # J A^-1 H^T (+ epsilon E)
        lam, status = lu_solve(H, rhs, backend)
        for j, s, _ in coulomb:
            status = status + _above(backend, -mul(s, lam[j]))
    for p, l in zip(P, lam):
        y = [f + mul(x, l) for f, x in zip(y, p)]
    qdd = apply_T_transpose_tree(kin, fac, [mul(r, v) for r, v in zip(fac.recip, y)])
    return qdd, lam, status
