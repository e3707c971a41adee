"""dtau/dq and dtau/dqd from the spatial structure of the tree: composite quantities and one walk to the root.

The derivation (Carpentier and Mansard, RSS 2018, in the form below derived again for the book's frames).  Write
every quantity in one fixed frame: S_j the mobility column of coordinate j (constant in its body's frame, as every
column of M F (1.30) of a one-coordinate, ball or free pair is), v_k and a_k the quasi-velocity and
quasi-acceleration of body k (2.39), (2.40) with the world's ``(-g, 0)`` (so that gravity needs no wrench),
I_k its Mises matrix (2.3), f_k = I_k a_k + v_k x* I_k v_k, F_i = sum of f_k over the subtree of body i (the Z of
(2.42)), tau_i = S_i . F_i.  A change of q_j moves the subtree of j's body rigidly by S_j: every S, I, v - v_lam,
a - a_lam of the subtree turns with it (lam: j's parent), so v_k gains psi'_j = v_lam x S_j and a_k gains
psi'_j x v_k + psi''_j, psi''_j = a_lam x S_j + v_lam x psi'_j.  A change of qd_j adds S_j to every v_k of the
subtree and ``S_j x v_k + c_j`` to every a_k, c_j = psi'_j + v_j x S_j.  With the composite sums over the subtree
of body i

    I^c_i (inertia, a Mises matrix),   Idot^c_i (its rate, sum of v_k x* I_k - I_k v_k x: a Mises matrix of mass 0),
    h^c_i (momentum, sum of I_k v_k),   F_i,

the force change of the subtree is ``B^c dv + I^c da`` with ``B^c x = Idot^c x + x x* h^c``, and (x* pairing with
x as its negative transpose)

* i in the subtree of j's body (j's body an ancestor of i's, or the same):
  ``dtau_i/dqd_j = rho_i . S_j + sigma_i . c_j``,  ``dtau_i/dq_j = rho_i . psi'_j + sigma_i . psi''_j``, with
  ``rho_i = Idot^c_i S_i - S_i x* h^c_i`` and ``sigma_i = I^c_i S_i``;
* i's body a strict ancestor of j's: ``dtau_i/dqd_j = S_i . X_j``,  ``dtau_i/dq_j = S_i . Y_j``, with
  ``X_j = Idot^c_j S_j + S_j x* h^c_j + I^c_j c_j`` and ``Y_j = S_j x* F_j + Idot^c_j psi'_j + psi'_j x* h^c_j
  + I^c_j psi''_j``;
* zero otherwise.

How it is computed.  The dot products are frame-free, so none of it is written in the world: every composite is
summed in the bodies' own frames by the congruence (2.7) that the composite bodies (2.32) use
(:meth:`~.kinematics.TreeKinematics.move_to_parent`), rho, sigma, X, Y are formed in the body's frame (where a
column of M F is a unit vector, so that they are read off the composites), and each coordinate's four vectors walk
once to the root by ``L F`` (1.13), meeting every ancestor's columns in the ancestor's frame.  The work is one
backward sweep of composites and four force transfers per (body, ancestor) pair, against a tangent forward and
backward sweep per direction on dual numbers (:mod:`.derivatives`); which is smaller depends on the tree's depth and
on how cheap a transfer is (a free-flyer's six columns and three rotations share one walk), so both are counted.

Free-flyer and ball pairs: their columns are the unit columns in the body's axes and a change of q along them is
Pinocchio's ``q (+) d = q exp(d)`` (d in the body's axes), the tangent space :func:`~.derivatives.tangent_seeds`
seeds: the two paths give the same matrices.  Armature and rotor inertia on the coordinates' own axes are constant
terms a q'' (no derivative along q or qd); the passive forces (springs, dampers, tendons) are differentiated on dual
numbers by the caller.  Bodies with added masses (a General aggregate), prescribed spins and pairs whose columns turn
with their own coordinates (a rotation and any other coordinate in one pair: the parent-fixed axes of T(o) C(c) do
not turn with c) are not covered (:func:`covers`).
"""
from __future__ import annotations

from ..model.types import code_index
from .aggregates import Rigid
from .group import phi_force, phi_motion
from .kinematics import ZERO6
from .linalg import add, cross, dot, mul, mv, scale, sub
from .sweeps import gravity_base, transmitted_wrenches


def covers(bound) -> bool:
    """Whether the model is one this formulation is written for (see the module's text)."""
    if bound.model.couplings:
        return False
    for k, body in enumerate(bound.bodies):
        if body.spin is not None or not (body.mises is None or isinstance(body.mises, Rigid)):
            return False
        if not bound.model.bodies[k].pair.quaternion and len(body.codes) > 1 and \
                any(code_index(c) >= 3 for c in body.codes):  # (translations alone keep their axes)
            return False
    return True


def inertia_rate(th: Rigid, V) -> Rigid:
    """V x* Theta - Theta V x: the rate of the Mises matrix Theta of a body moving with quasi-velocity V = (u, w),
    seen from a fixed frame that coincides with the body's; again a Mises matrix, of mass 0:
    ``h' = m u + w x h``, ``theta' = hat(w) theta - theta hat(w) + 2 (h . u) E - u h^T - h u^T``."""
    u, w = V[:3], V[3:]
    h, t = th.h, th.theta
    hd = add(scale(th.m, u), cross(w, h))
    wt = [mv(t, col) for col in ((1, 0, 0), (0, 1, 0), (0, 0, 1))]  # theta's columns
    hu = dot(h, u)
    rows = [[0] * 3 for _ in range(3)]
    for a in range(3):
        for b in range(a, 3):
            # (hat(w) theta)_ab - (theta hat(w))_ab = (w x theta e_b)_a + (w x theta e_a)_b (theta symmetric)
            x = cross(w, wt[b])[a] + cross(w, wt[a])[b]
            x = x - mul(u[a], h[b]) - mul(h[a], u[b])
            if a == b:
                x = x + 2 * hu
            rows[a][b] = rows[b][a] = x
    return Rigid(0, hd, tuple(tuple(r) for r in rows))


def _composites(bound, kin, V):
    """I^c, Idot^c (Rigid) and h^c (6-vectors) of every body's subtree, in the body's frame."""
    n = len(kin.tree)
    Ic, Id, hc = [None] * n, [None] * n, [ZERO6] * n
    for k, body in enumerate(bound.bodies):
        th = body.mises
        if th is not None:
            Ic[k], Id[k], hc[k] = th, inertia_rate(th, V[k]), th.apply(V[k])
    for k in range(n - 1, -1, -1):
        p = kin.tree.parent[k]
        if p < 0 or Ic[k] is None:
            continue
        moved, rate = kin.move_to_parent(k, Ic[k]), kin.move_to_parent(k, Id[k])
        Ic[p] = moved if Ic[p] is None else Ic[p] + moved
        Id[p] = rate if Id[p] is None else Id[p] + rate
        hc[p] = add(hc[p], kin.L[k].wrench(hc[k]))
    return Ic, Id, hc


def _apply(th, x):
    return ZERO6 if th is None else th.apply(x)


def inverse_dynamics_derivatives(bound, kin, qd, qdd, gravity=True) -> tuple:
    """(dtau/dq, dtau/dqd) of the sweeps' u* (:func:`~.sweeps.inverse_dynamics`, without the passive forces; without
    gravity where ``gravity`` is False) as n x n rows, by the composites of the module's text."""
    tree = kin.tree
    n = tree.nv
    V = kin.velocities(qd)
    base = gravity_base(bound) if gravity else ZERO6
    A = kin.accelerations(qd, qdd, V, base)
    F = transmitted_wrenches(bound, kin, qd, qdd, gravity=gravity)
    Ic, Id, hc = _composites(bound, kin, V)
    cols = {}  # coordinate -> (S, c, psi', psi'') in its body's frame
    for k, p in enumerate(tree.parent):
        L = kin.L[k]
        vl = ZERO6 if p < 0 else L.twist(V[p])
        al = L.twist(base if p < 0 else A[p])
        for i, S in zip(tree.coords[k], kin.psi[k]):
            d1 = phi_motion(vl, S)
            d2 = add(phi_motion(al, S), phi_motion(vl, d1))
            cols[i] = (S, add(d1, phi_motion(V[k], S)), d1, d2)

    def rows(k, i):
        """(rho, sigma, X, Y) of coordinate i of body k, in its frame (made just before its walk, so that the
        program holds one coordinate's four at a time)."""
        S, c, d1, d2 = cols[i]
        IdS = _apply(Id[k], S)
        return (sub(IdS, phi_force(S, hc[k])), _apply(Ic[k], S),
                add(add(IdS, phi_force(S, hc[k])), _apply(Ic[k], c)),
                add(add(add(phi_force(S, F[k]), _apply(Id[k], d1)), phi_force(d1, hc[k])), _apply(Ic[k], d2)))

    dq = [[0] * n for _ in range(n)]
    dqd = [[0] * n for _ in range(n)]
    above = [False] * len(tree)  # whether some strict ancestor of the body carries a coordinate
    for k, p in enumerate(tree.parent):
        above[k] = p >= 0 and (above[p] or bool(tree.coords[p]))
    for b in range(len(tree)):
        for i in tree.coords[b]:
            rho, sigma, X, Y = rows(b, i)
            a = b
            while True:
                for j in tree.coords[a]:
                    S, c, d1, d2 = cols[j]
                    dqd[i][j] = dot(rho, S) + dot(sigma, c)
                    dq[i][j] = dot(rho, d1) + dot(sigma, d2)
                    if a != b:
                        dqd[j][i] = dot(S, X)
                        dq[j][i] = dot(S, Y)
                if not above[a]:
                    break
                L = kin.L[a]
                rho, sigma, X, Y = L.wrench(rho), L.wrench(sigma), L.wrench(X), L.wrench(Y)
                a = tree.parent[a]
    return dq, dqd


__all__ = ["covers", "inertia_rate", "inverse_dynamics_derivatives"]
