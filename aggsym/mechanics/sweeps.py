"""Inverse dynamics by the forward and backward sweeps, the wrench in every pair, and d(q, q') (2.39)-(2.46).

Forward sweep (Prop. 2.20): the quasi-velocities and quasi-accelerations of every body, in its own frame,

* ``V_lk = L^T V_parent + M F q'`` (2.39),
* ``V'_lk = Phi^T L^T V_parent + L^T V'_parent + (M F)' q' + M F q''`` (2.40)

(:func:`forward_sweep`, by :meth:`aggsym.kinematics.TreeKinematics.velocities` and ``.accelerations``).
Gravity enters as the acceleration ``(-g, 0)`` of the inertial frame E_10: every body then sees
``V'_lk - (g_lk, 0)``, and ``Theta (V' - (g_lk, 0)) = Theta V' - G_lk`` is exactly the gravity wrench
``G_lk = Theta (g_lk, 0)`` put into ``H_lk`` of (2.9), at no cost per body.

Backward sweep (Prop. 2.21): the wrench transmitted through the pair (mu,k-1; lk) from the parent to the body lk
and its subtree, in the body's frame E_lk about its origin O_lk,

* ``Z(mu,k-1; lk) = Theta V' + Phi Theta V + sum over children L^{lk}_{i,k+1} Z(lk; i,k+1) - (H + T)_lk`` (2.42),

with ``Z = R + U + N`` (2.9): reaction, control and friction together.  The generalized force of the pair is its
projection on the pair's mobility axes, ``u* = F^T M^T Z`` (2.15), (2.46) (``Psi^T Z`` here).

How it is computed.  The body equation (2.10) needs V and V' only through w, w' and ``a = v' + w x v``, the
acceleration of the origin O_lk: multiplied out, ``Theta V' + Phi Theta V = (m a + w' x h + w x (w x h),
h x a + theta w' + w x (theta w))`` (the term ``m v x v`` vanishes).  So the forward sweep runs (2.40) on
(w, w', a) (:func:`origin_sweep`) and never forms v; ``w x (theta w)`` and ``w x (w x d)`` are written on the
six products ``w_i w_j`` so that the zeros and equal entries of the model's constants fold, and equal
coefficients are factored out (:func:`lincomb`).  Bodies joined by pairs that move no origin share the
acceleration of that origin: their masses (and first moments, where that pays) are summed as the composite
bodies of (2.32) before they multiply it (:func:`generalized_forces_lumped`).  ``joint_wrenches`` runs the plain
recursion (2.42) (:func:`transmitted_wrenches`), which gives every Z; the two are tested against each other.

What "reaction" means.  Z is the *whole* wrench the parent exerts on the child through the pair.  For a pair with
one coordinate along a unit axis f_i of the child frame (every single-coordinate pair: Psi = f_i in E_lk, since
the pair's own rotation keeps its axis), the book's statement after (2.42) holds literally: the component i of Z
is u* (control plus friction, what an actuator supplies) and the other five components are the reaction R, the
constraint wrench that does no work.  For a pair with several coordinates (a ball joint, a free pair,
``M = diag(c^T, eps)``) the mobility axes Psi are in general not coordinate axes of E_lk; aggsym then reports Z
itself (nothing is subtracted) together with u* = Psi^T Z; the reaction is the part of Z that annihilates every
column of Psi, which is not a separate output.

d(q, q') is the same sweep with q'' = 0 (2.44)-(2.46), so that ``A(q) q'' + d(q, q') = u + n`` (2.45); with
gravity as the only external wrench, ``d = b - S (H + T) = b + g`` (2.52).
"""
from __future__ import annotations

from fractions import Fraction

from ..core.program import Node, fold, is_zero, normalize_const
from ..model.types import code_index
from .aggregates import Rigid
from .group import phi_force
from .kinematics import ZERO6, combine, project, world_frame_vectors
from .linalg import ZERO3, add, cross, dot, is_identity, mtv, mul, neg, scale, sub
from .tendon_armature import add_to_torques

__all__ = ["gravity_base", "gravity_wrenches", "forward_sweep", "Origin", "origin_sweep", "transport",
           "body_wrench", "body_wrench_rest", "body_wrenches", "backward_sweep", "transmitted_wrenches",
           "keeps_origin", "generalized_forces_lumped", "inverse_dynamics", "d_vector",
           "pair_bodies", "link_rotation", "joint_wrench_rows", "lincomb"]


def gravity_base(bound):
    """(-g, 0): the quasi-acceleration given to the inertial frame so that gravity needs no wrench (2.40)."""
    return tuple(neg(bound.gravity)) + ZERO3


def gravity_wrenches(bound, kin):
    """G_lk = Theta_lk (g_lk, 0), the gravity wrench of every body in its frame (2.9); ZERO6 when massless.

    Theta_lk is the body's own Mises matrix: gravity does not act on added masses (Prop. 2.8)."""
    g = world_frame_vectors(kin, bound.gravity)
    return [ZERO6 if b.rigid is None else b.rigid.apply(g[k] + ZERO3) for k, b in enumerate(bound.bodies)]


def forward_sweep(kin, qd, qdd, base=ZERO6):
    """V and V' of every body by (2.39), (2.40); ``base`` is the quasi-acceleration of E_10 (e.g. gravity_base)."""
    V = kin.velocities(qd)
    return V, kin.accelerations(qd, qdd, V, base)


class Origin:
    """The motion of one body's origin in its own axes: w, w', a = v' + w x v, and perp[i] = w_j^2 + w_k^2."""

    __slots__ = ("w", "wd", "a", "perp")

    def __init__(self, w, wd, a, perp):
        self.w, self.wd, self.a, self.perp = w, wd, a, perp


def origin_sweep(bound, kin, qd, qdd, base=ZERO3):
    """(2.40) for w, w' and the acceleration a = v' + w x v of every body origin, body axes; ``base``: a of E_10.

    With the pair's motion L = T(d) C(c) (d the origin of E_lk in the parent's axes), its relative rates
    ``(v_r, w_r) = M F q'`` (2.39) and ``(M F)' q'`` (2.19):
    ``w = c^T w_p + w_r``, ``w' = c^T w'_p + (c^T w_p) x w_r + (M F q'' + (M F)' q')_w``,
    ``a = c^T (a_p + w'_p x d + w_p x (w_p x d)) + 2 (c^T w_p) x v_r + (M F q'')_v``.
    A pair turning about one axis e_i of an unturned constructive frame keeps w_j^2 + w_k^2 (j, k != i) of
    its parent: those sums are carried, not recomputed.  Returns one :class:`Origin` per body."""
    out = []
    for k, p in enumerate(kin.tree.parent):
        L = kin.L[k]
        own = combine(kin.psi[k], [qdd[i] for i in kin.tree.coords[k]])
        rel = kin.relative_velocity(k, qd)  # M F q' (+ a rotor's prescribed U)
        turn = add(own[3:], kin.relative_acceleration(k, qd)[3:])  # (M F)' q' (+ U'; rotations only, (v) part 0)
        if p < 0:
            a = L.unrotate_free(base)
            w, wd = rel[3:], turn
            if kin.free[k]:
                # a free-flyer's v is its origin's velocity in its own turning axes: the classical acceleration of
                # the origin is v' + w x v (v' = own[:3], added below)
                a = add(a, cross(w, rel[:3]))
        else:
            par = out[p]
            wp = L.unrotate_free(par.w)
            a = L.unrotate_free(add(par.a, transport(par, L.o)))
            a = add(a, scale(2, cross(wp, rel[:3])))
            w = add(wp, rel[3:])
            wd = add(add(L.unrotate_free(par.wd), cross(wp, rel[3:])), turn)
        a = add(a, own[:3])
        P = _products(w)
        axis = _kept_axis(bound, k)
        perp = tuple((0 if p < 0 else out[p].perp[i]) if i == axis else P[(j, j)] + P[(m, m)]
                     for i, j, m in _CYCLIC)
        out.append(Origin(w, wd, a, perp))
    return out


def _kept_axis(bound, k):
    """i when pair k is one rotation about e_i after a constructive rotation that is structurally E, else None."""
    body = bound.bodies[k]
    if len(body.codes) != 1 or code_index(body.codes[0]) < 3:
        return None
    if is_identity(body.L0.c):
        return code_index(body.codes[0]) - 3
    return None


def transport(mo, d):
    """w' x d + w x (w x d): the acceleration of a point fixed at d relative to an origin at rest (body axes)."""
    P = _products(mo.w)
    return tuple(lincomb(_transport_terms(mo, P, d, i)) for i in range(3))


def _transport_terms(mo, P, d, i):
    """Component i of w' x d + w x (w x d) as signed terms (sign, coefficient, variable), P the products w_i w_j:
    (w x (w x d))_i = d_j w_i w_j + d_k w_i w_k - d_i (w_j^2 + w_k^2)."""
    _, j, k = _CYCLIC[i]
    return [(1, d[k], mo.wd[j]), (-1, d[j], mo.wd[k]), (1, d[j], P[_pk(i, j)]), (1, d[k], P[_pk(i, k)]),
            (-1, d[i], mo.perp[i])]


def _rotational_terms(th, mo, P, i):
    """Component i of theta w' + w x (theta w) as signed terms, w x (theta w) on the six products w_i w_j."""
    _, j, k = _CYCLIC[i]
    theta = th.theta
    terms = [(1, theta[i][l], mo.wd[l]) for l in range(3)]
    for l in range(3):  # w_j (theta w)_k - w_k (theta w)_j
        terms += [(1, theta[k][l], P[_pk(j, l)]), (-1, theta[j][l], P[_pk(k, l)])]
    return terms


def body_wrench(th, mo):
    """Theta V' + Phi Theta V of (2.10) multiplied out for a Mises matrix (2.3) [[m E, -hat h], [hat h, theta]].

    With a = v' + w x v, the terms m v x v cancel and the Jacobi identity joins the rest:
    ``f = m a + w' x h + w x (w x h)``, ``mu = h x a + theta w' + w x (theta w)`` (Newton and Euler about the
    body origin); w x (theta w) is written on the six products w_i w_j, so that zero and equal entries of
    theta fold.  Body axes, moment about the origin."""
    P = _products(mo.w)
    a, h = mo.a, th.h
    f = tuple(lincomb([(1, th.m, a[i])] + _transport_terms(mo, P, h, i)) for i in range(3))
    mu = tuple(lincomb([(1, h[j], a[k]), (-1, h[k], a[j])] + _rotational_terms(th, mo, P, i))
               for i, j, k in _CYCLIC)
    return f + mu


def body_wrench_rest(th, mo):
    """body_wrench less Theta (a, 0) = (m a, h x a): the part that does not depend on the origin's acceleration."""
    P = _products(mo.w)
    return (tuple(lincomb(_transport_terms(mo, P, th.h, i)) for i in range(3))
            + tuple(lincomb(_rotational_terms(th, mo, P, i)) for i in range(3)))


_CYCLIC = ((0, 1, 2), (1, 2, 0), (2, 0, 1))


def _gravity(bound, gravity):
    return neg(bound.gravity) if gravity else ZERO3


def body_wrenches(bound, kin, qd, qdd, H=None, gravity=True, origins=None, rest=False):
    """Theta V' + Phi Theta V - H of every body, the left side of (2.10) less the external wrench, body frame.

    Gravity enters as the acceleration -g of E_10 (see the module docstring).  With ``rest`` the part
    Theta (a, 0) of every rigid body is left out (see :func:`generalized_forces_lumped`)."""
    mo = origin_sweep(bound, kin, qd, qdd, _gravity(bound, gravity)) if origins is None else origins
    spatial = weights = None
    Y = []
    for k, body in enumerate(bound.bodies):
        th = body.mises
        if th is None:
            y = ZERO6
        elif isinstance(th, Rigid):
            y = body_wrench_rest(th, mo[k]) if rest else body_wrench(th, mo[k])
        else:  # a general aggregate (Theta + Lambda, added masses (2.8)): the book's form (2.10), (2.13), with
            # the quasi-velocities of (2.39), (2.40) without gravity, and the weight of Theta alone subtracted
            if spatial is None:
                spatial = forward_sweep(kin, qd, qdd)
                weights = gravity_wrenches(bound, kin) if gravity else None
            V, A = spatial[0][k], spatial[1][k]
            y = add(th.apply(A), phi_force(V, th.apply(V)))
            if weights is not None:
                y = sub(y, weights[k])
        Y.append(y if H is None else sub(y, H[k]))
    return Y


def backward_sweep(kin, Y):
    """Z(mu,k-1; lk) of (2.42): Y_lk plus the children's Z moved by L, from the buds to the root."""
    return kin.backward(Y)


def transmitted_wrenches(bound, kin, qd, qdd, H=None, gravity=True):
    """Z of every pair (2.39)-(2.42), body frame, (f, mu) about the body origin; gravity by the base (-g, 0)."""
    return backward_sweep(kin, body_wrenches(bound, kin, qd, qdd, H, gravity))


def keeps_origin(kin, k):
    """True when pair k moves no origin: L = C(c) with d = 0 and no translation coordinate, so a_k = c^T a_parent."""
    return all(is_zero(x) for x in kin.L[k].o) and all(is_zero(x) for col in kin.psi[k] for x in col[:3])


def generalized_forces_lumped(bound, kin, origins, rest, transvect=None):
    """u* = F^T M^T Z (2.42), (2.15), with the bodies that share an origin lumped as composite bodies (2.32).

    Write Z_k = Theta+_k (a_k, 0) + E_k, with Theta+_k (a, 0) = (m+ a, h+ x a) for a mass m+ and a first moment
    h+, and E_k everything else (``rest``: each body's own E from :func:`body_wrenches` with ``rest=True``).
    When pair k keeps its origin (L = C(c), a_k = c^T a_p), moving Z_k to the parent by (2.7) gives
    ``(m+_k a_p, (c h+_k) x a_p) + c E_k``: the masses are summed towards the root like the composite bodies of
    (2.32) and multiplied by an acceleration only where an origin moves, and u*_k is read as
    ``(c Psi)^T (m+_k a_p, (c h+_k) x a_p) + Psi^T E_k`` (L = diag(c, c) is orthogonal).  The first moment goes
    along when that is free (c h+ = h+, h+ on the pair's axis) or when nothing else needs a_k (every child keeps
    its origin too); otherwise h+ x a_k is added to E_k there.  The decisions read structural zeros only, never
    runtime values.

    ``transvect(k, u)``, when given, is called with the pair's u* (coordinate order) and returns new values for
    them and a wrench W (k's axes, or None) that joins Z_k on its way to the root: this is how the transvections
    of (3.20) ride on the backward sweep (:func:`aggsym.transvective.transvected_forces`)."""
    tree = kin.tree
    mass = [b.mises.m if isinstance(b.mises, Rigid) else 0 for b in bound.bodies]
    first = [b.mises.h if isinstance(b.mises, Rigid) else ZERO3 for b in bound.bodies]
    E = list(rest)
    tau = [0] * tree.nv
    for k in range(len(tree) - 1, -1, -1):
        p = tree.parent[k]
        L = kin.L[k]
        if p >= 0 and keeps_origin(kin, k):
            axis = _kept_axis(bound, k)
            free = all(is_zero(x) for j, x in enumerate(first[k]) if j != axis)  # then c h+ = h+
            a_needed = any(not keeps_origin(kin, c) for c in tree.children[k])
            if a_needed and not free:
                E[k] = E[k][:3] + add(E[k][3:], cross(first[k], origins[k].a))
                first[k] = ZERO3
            h = L.rotate_free(first[k])
            a = origins[p].a
            lumped = scale(mass[k], a) + cross(h, a)  # L Theta+_k (a_k, 0), parent frame
            u = [dot(L.wrench(col), lumped) + dot(col, E[k]) for col in kin.psi[k]]  # L = diag(c, c): L^T L = E
            if transvect is not None:
                u, W = transvect(k, u)
                if W is not None:
                    E[k] = add(E[k], W)
            for i, x in zip(tree.coords[k], u):
                tau[i] = x
            mass[p] = fold(mass[p] + mass[k])
            first[p] = tuple(fold(x) for x in add(first[p], h))
            E[p] = add(E[p], L.wrench(E[k]))
        else:
            a = origins[k].a
            Z = add(scale(mass[k], a), E[k][:3]) + add(cross(first[k], a), E[k][3:])
            u = project(kin.psi[k], Z)
            if transvect is not None:
                u, W = transvect(k, u)
                if W is not None:
                    Z = add(Z, W)
            for i, x in zip(tree.coords[k], u):
                tau[i] = x
            if p >= 0:
                E[p] = add(E[p], L.wrench(Z))
    return tau


def inverse_dynamics(bound, kin, qd, qdd, H=None, gravity=True, transvect=None):
    """u* by the sweeps (2.39)-(2.42), (2.15) in coordinate order; equals A q'' + b + g when H = 0.

    ``transvect``: see :func:`generalized_forces_lumped`."""
    origins = origin_sweep(bound, kin, qd, qdd, _gravity(bound, gravity))
    rest = body_wrenches(bound, kin, qd, qdd, H, gravity, origins=origins, rest=True)
    tau = generalized_forces_lumped(bound, kin, origins, rest, transvect)
    if bound.model.tendons and transvect is None:  # the fixed tendons' armature: + a c (c . q'')
        tau = add_to_torques(bound, tau, qdd)
    if bound.rotors:  # each coordinate's own rotor: + a_j q''_j
        return [t + mul(bound.rotor(j), a) for j, (t, a) in enumerate(zip(tau, qdd))]
    return [t + mul(bound.armature, a) for t, a in zip(tau, qdd)]  # a rotor on every axis: + armature q


def d_vector(bound, kin, qd, H=None, gravity=True):
    """d(q, q') = F^T M^T Z_o by the sweeps with q'' = 0 (2.44)-(2.46); with gravity only, d = b + g (2.52)."""
    return inverse_dynamics(bound, kin, qd, [0] * kin.tree.nv, H, gravity)


# scalar helpers -------------------------------------------------------------------------------------------

def _number(x) -> bool:
    """A Python (or NumPy scalar) number, not a node nor an array."""
    return isinstance(x, (int, float, Fraction)) and not isinstance(x, bool)


def _pk(i, j):
    return (i, j) if i <= j else (j, i)


def _products(w):
    """The six products w_i w_j (i <= j), structural zeros kept as 0."""
    return {(i, j): mul(w[i], w[j]) for i in range(3) for j in range(i, 3)}


def _ident(x):
    return ("n", x.id) if type(x) is Node else ("o", id(x))  # (a dual value: by identity)


def lincomb(terms):
    """sum s c x over (s, c, x) triples, s = +-1: zeros skipped, equal x merged, then equal |c| factored out.

    The coefficients c are model constants (numbers, or expressions in the parameters); the factoring is what
    turns ``h w_x w_y - h w'_z`` into one product, ``h (w_x w_y - w'_z)``."""
    merged = {}
    for s, c, x in terms:
        if is_zero(c) or is_zero(x):
            continue
        key = _ident(x)
        if key in merged:
            s0, c0, _ = merged[key]
            c = c0 + c if s0 == s else c0 - c
            s = s0
            if _number(c):
                c = normalize_const(c)
        merged[key] = (s, c, x)
    groups = {}
    for s, c, x in merged.values():
        if is_zero(c):
            continue
        if _number(c) and c < 0:
            c, s = normalize_const(-c), -s
        key = ("c", c) if _number(c) else _ident(c)
        if key not in groups:
            groups[key] = [c, 0]
        acc = groups[key][1]
        groups[key][1] = acc + x if s > 0 else acc - x
    out = 0
    for c, acc in groups.values():
        out = out + c * acc
    return out


# joint wrenches as an output -----------------------------------------------------------------------------

def pair_bodies(model):
    """Indices of the bodies whose pair carries at least one coordinate, in coordinate order."""
    return [k for k, b in enumerate(model.bodies) if b.pair.coordinates]


def link_rotation(bound, k):
    """The body's link_rotation R (x_body = R x_link) as backend scalars, or None."""
    R = bound.model.bodies[k].link_rotation
    if R is None:
        return None
    return tuple(tuple(bound.scalar(R[i][j]) for j in range(3)) for i in range(3))


def joint_wrench_rows(bound, Z):
    """Z of every coordinate-bearing pair as (f, mu), in the source file's link frame where one is given."""
    rows = []
    for k in pair_bodies(bound.model):
        z = Z[k]
        R = link_rotation(bound, k)
        if R is not None:
            z = mtv(R, z[:3]) + mtv(R, z[3:])
        rows.append(tuple(z))
    return rows
