"""The bias b(q, q') = B(q, q') q' in O(n) (2.36)-(2.37), Prop. 2.19, the matrix B(q, q'), and the gravity g(q).

``b = F^T M^T Z`` with ``Z = L Y`` accumulated from the buds to the root (Prop. 2.19),
``Y_lk = Theta_lk X_lk + Phi_lk Theta_lk V_lk`` (2.36), X from (2.37) (see :mod:`aggsym.kinematics`).

Gravity enters the book's right-hand side as ``S H`` with the gravity wrench ``G_lk`` in H (2.9), (2.29); aggsym
moves it to the left: ``g(q) = -S G``.  Since ``G_lk = Theta_lk (g_lk, 0)`` with g_lk the gravity vector in the
body's axes, ``g = F^T M^T L Y_g`` with ``Y_g = Theta (-g_lk, 0)``: the same backward recurrence.  Theta is the
body's own Mises matrix, without added masses (gravity acts on the body, not on the medium, Prop. 2.8).
"""
from __future__ import annotations

from .group import phi_force, phi_motion
from .kinematics import ZERO6, generalized, world_frame_vectors
from .linalg import add, neg


def bias_vector(bound, kin, qd, V=None):
    """b(q, q') (2.36)-(2.37), Prop. 2.19: a list of n scalars."""
    V = kin.velocities(qd) if V is None else V
    X = kin.velocity_products(qd, V)
    Y = []
    for k, body in enumerate(bound.bodies):
        th = body.mises
        Y.append(ZERO6 if th is None else th.dynamic_wrench(X[k], V[k]))
    return generalized(kin, kin.backward(Y))


def gravity_accelerations(bound, kin):
    """(-g_lk, 0) for every body: minus gravity in the body's axes, as a fictitious quasi-acceleration."""
    return [x + (0, 0, 0) for x in world_frame_vectors(kin, neg(bound.gravity))]


def gravity_vector(bound, kin):
    """g(q) = -S G (see the module docstring): a list of n scalars."""
    return generalized(kin, gravity_wrenches(bound, kin))


def gravity_wrenches(bound, kin):
    """-G accumulated towards the root, Z = L Y_g (before the projection F^T M^T): Z[0] at the root."""
    gam = gravity_accelerations(bound, kin)
    Y = [ZERO6 if b.rigid is None else b.rigid.apply(gam[k]) for k, b in enumerate(bound.bodies)]
    return kin.backward(Y)


def coriolis_matrix(bound, kin, qd, skew=False):
    """A matrix B(q, q') with ``B q' = b`` (2.36), linear in q'.

    ``skew=False``: the book's ``B = S Phi(V) A S^T + S A S'^T`` of (2.17),
    (2.31) (A = diag A_lk of (2.13)).  Column j is ``S (Phi(V) A V(e_j) + A X(q', e_j))`` with
    ``V(e_j) = S^T e_j`` (row j of S, (1.43)) and ``X(u, e_j) = S'^T(u) e_j`` carried down the subtree of j's
    pair like (2.37): ``X_k = L^T X_parent + phi(L^T V_parent(e_j), M F u)``, starting from the pair's own
    (M F)'(u) e_j (2.19).  Summed along the path this is the time derivative of the column S^T e_j in body k's
    axes.  So ``B q' = S (Phi A V + A X) = b``.  This B is not a Christoffel-consistent matrix: A' - 2B is not
    skew in general.

    ``skew=True``: ``C = B + S A phi(V) S^T = S (Phi(V) A + A phi(V)) S^T + S A S'^T``, where ``phi(V)`` is
    the motion cross product (1.22) (``Phi(V) = -phi(V)^T``).  The body block ``Phi(V) A + A phi(V)`` is skew
    because A_lk is symmetric, and it maps V to ``Phi(V) A V`` since ``phi(V) V = 0``; hence ``C q' = b`` still,
    and with ``A = S A S^T`` (2.30), ``A' = S' A S^T + S A S'^T``:
    ``A' - 2C = (S' A S^T - S A S'^T) - 2 S (Phi A + A phi) S^T`` is skew: the passivity property that
    controllers (Slotine-Li, passivity-based) need.  DESIGN's rung 1.  Computed as
    ``Y_k = Phi(V_k) A_lk V_k(e_j) + A_lk D_k`` with ``D = X + phi(V) V(e_j)``, the rate of the column in the
    inertial axes: D is constant along the subtree up to the frame change, ``D_k = L^T D_parent``, which saves
    the phi of (2.37) and one product with A_lk per body.

    O(n) per column; n x n rows.  For models without prescribed motions: a prescribed spin's terms in b are not
    of the form B q' (the partition and coriolis routines are not emitted for them)."""
    n = kin.tree.nv
    B = [[0] * n for _ in range(n)]
    for j, Z in enumerate(coriolis_wrenches(bound, kin, qd, skew)):
        col = generalized(kin, Z)
        for i in range(n):
            B[i][j] = col[i]
    return B


def coriolis_wrenches(bound, kin, qd, skew=False):
    """Per column j of :func:`coriolis_matrix`, the wrenches Z = L Y accumulated towards the root (before the
    projection F^T M^T): Z[0] is the column's wrench at the root, in the root's axes."""
    tree = kin.tree
    n = tree.nv
    V = kin.velocities(qd)
    S = kin.parastrophic()
    for j in range(n):
        st = tree.body_of[j]
        W = S[j]
        X = [None] * len(tree)
        Y = [ZERO6] * len(tree)
        unit = [1 if i == j else 0 for i in range(n)]
        for k in tree.subtrees[st]:
            if k == st:
                x = kin.relative_acceleration_bilinear(k, qd, unit)
                if skew:
                    x = add(x, phi_motion(V[k], W[k]))
            elif skew:
                x = kin.L[k].twist(X[tree.parent[k]])
            else:
                p = tree.parent[k]
                x = add(kin.L[k].twist(X[p]), phi_motion(kin.L[k].twist(W[p]), kin.relative_velocity(k, qd)))
            X[k] = x
            th = bound.bodies[k].mises
            if th is not None:
                Y[k] = add(phi_force(V[k], th.apply(W[k])), th.apply(x))
        yield kin.backward(Y)
