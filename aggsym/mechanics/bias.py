"""The bias b(q, q') = B(q, q') q' in O(n) (2.36)-(2.37), Prop. 2.19, the matrix B(q, q'), and the gravity g(q).

``b = F^T M^T Z`` with ``Z = L Y`` accumulated from the buds to the root (Prop. 2.19),
``Y_lk = Theta_lk X_lk + Phi_lk Theta_lk V_lk`` (2.36), X from (2.37) (see :mod:`aggsym.kinematics`).

Gravity enters the book's right-hand side as ``S H`` with the gravity wrench ``G_lk`` in H (2.9), (2.29); aggsym
moves it to the left: ``g(q) = -S G``.  Since ``G_lk = Theta_lk (g_lk, 0)`` with g_lk the gravity vector in the
body's axes, ``g = F^T M^T L Y_g`` with ``Y_g = Theta (-g_lk, 0)``: the same backward recurrence.  Theta is the
body's own Mises matrix, without added masses (gravity acts on the body, not on the medium, Prop. 2.8).
"""
from __future__ import annotations

from .bound import scratch_operations
from .group import phi_force, phi_motion
from .kinematics import ZERO6, generalized, world_frame_vectors, world_poses
from .linalg import add, dot, mv, neg, scale


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


COLUMNS_DEPTH = 4.5  # above this mean subtree size per coordinate the Coriolis columns are not even counted


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

    Computed by :func:`coriolis_by_recursion`: the same matrix from O(n) 6-vectors and 6x6 sums, then one or two
    dot products per entry (O(n^2) in all), or by the columns (:func:`coriolis_by_columns`, O(n) 6-vector
    motions per column) where their straight-line program is smaller, and always with prescribed spins.
    n x n rows.  The column form pays one 6-vector motion and one product with A_lk per body of each column's
    subtree, the recursion one or two dot products there: it wins on shallow trees (on the suite's models and
    robots where the subtrees average at most 3.5 bodies per coordinate, and it loses from 4.9 on: Panda,
    Talos at 4.9, the 48-coordinate test bench at 9.2, and by 1.8x on the 12-link chain at 6.5), so it is only
    counted (on a scratch program) where they average at most :data:`COLUMNS_DEPTH` bodies.  For models without
    prescribed motions: a prescribed spin's terms in b are not of the form B q' (the partition and coriolis
    routines are not emitted for them)."""
    if any(b.spin is not None for b in bound.bodies):
        return coriolis_by_columns(bound, kin, qd, skew)
    tree = kin.tree
    if sum(len(tree.subtrees[tree.body_of[j]]) for j in range(tree.nv)) > COLUMNS_DEPTH * tree.nv:
        return coriolis_by_recursion(bound, kin, qd, skew)
    if bound.backend.symbolic:
        by_recursion = scratch_operations(bound, kin, lambda b, k, u: coriolis_by_recursion(b, k, u, skew))
        by_columns = scratch_operations(bound, kin, lambda b, k, u: coriolis_columns(b, k, u, skew), by_recursion)
        if by_columns < by_recursion:
            return coriolis_by_columns(bound, kin, qd, skew)
    return coriolis_by_recursion(bound, kin, qd, skew)


def _columns(M):
    return [tuple(row[c] for row in M) for c in range(6)]


def _matvec_t(M, v):
    return tuple(dot(col, v) for col in _columns(M))


def coriolis_by_recursion(bound, kin, qd, skew=False):
    """B(q, q') (``skew=False``) or C(q, q') (``skew=True``) of :func:`coriolis_matrix` in O(n^2), entry by entry.

    Everything moves to the world's axes once (Prop. 1.8): the column of coordinate j of S^T (1.43) is the
    constant 6-vector ``p_j`` (psi_j seen from the world origin) on every body of its subtree, its rate is
    ``p_j' = phi(v_{<j}) p_j`` (1.22) with ``v_{<j}`` the world velocity of the frame that carries j's axis
    (the parent's, plus the pair's earlier coordinates; the body's own velocity for a free flyer, whose columns
    are fixed in the body), and the Mises matrix of body k is ``I_k = L Theta_lk L^T`` (2.7) with the body's pose
    L.  The body blocks of :func:`coriolis_matrix` moved to the world are

    * ``C``: ``S (Phi(V) A + A phi(V)) S^T + S A S'^T`` becomes ``sum_k J_k^T (Phi(v_k) I_k J_k + I_k J_k')``
      (J_k the world columns p of k's path: the world rate of a column is the body rate plus ``phi(v) p``,
      which cancels the ``A phi(V)``);
    * ``B``: ``S Phi(V) A S^T + S A S'^T`` becomes ``sum_k J_k^T ((Phi(v_k) I_k - I_k phi(v_k)) J_k + I_k J_k')``.

    With the subtree sums ``I+_s = sum I_k`` and ``N+_s = sum Phi(v_k) I_k (- I_k phi(v_k))`` over the bodies
    below and at s (like the composite bodies of (2.32)), an entry with i on the path of j (body s of j) is
    ``C_ij = p_i . F_j``, ``F_j = N+_s p_j + I+_s p_j'``, and ``C_ji = G_j . p_i + H_j . p_i'`` with
    ``G_j = N+_s^T p_j``, ``H_j = I+_s p_j``; entries of coordinates on different branches are zero.  On a
    serial chain: 34 operations per pair of coordinates (about 17 n^2) plus O(n) 6x6 work."""
    tree = kin.tree
    n = tree.nv
    poses = world_poses(kin)
    nb = len(tree)
    P, Pd = [None] * n, [None] * n
    V = [None] * nb
    for k, par in enumerate(tree.parent):
        v = ZERO6 if par < 0 else V[par]
        coords = tree.coords[k]
        cols = [poses[k].motion(psi) for psi in kin.psi[k]]
        if kin.free[k]:
            for j, col in zip(coords, cols):
                v = add(v, scale(qd[j], col))
            for j, col in zip(coords, cols):
                P[j], Pd[j] = col, phi_motion(v, col)
        else:
            for j, col in zip(coords, cols):
                P[j], Pd[j] = col, phi_motion(v, col)
                v = add(v, scale(qd[j], col))
        V[k] = v
    Iplus = [None] * nb
    Nplus = [None] * nb
    for k in range(nb - 1, -1, -1):
        th = bound.bodies[k].mises
        if th is not None:
            Iw = th.moved(poses[k])
            cols = [Iw.apply(tuple(1 if r == c else 0 for r in range(6))) for c in range(6)]
            ncols = [phi_force(V[k], col) for col in cols]
            if not skew:
                ncols = [tuple(a - b for a, b in zip(x, Iw.apply(phi_motion(V[k], tuple(1 if r == c else 0
                                                                                       for r in range(6))))))
                         for c, x in enumerate(ncols)]
            N = [[ncols[c][r] for c in range(6)] for r in range(6)]
            Iplus[k] = Iw if Iplus[k] is None else Iplus[k] + Iw
            Nplus[k] = N if Nplus[k] is None else [[a + b for a, b in zip(x, y)] for x, y in zip(Nplus[k], N)]
        p = tree.parent[k]
        if p >= 0 and Iplus[k] is not None:
            Iplus[p] = Iplus[k] if Iplus[p] is None else Iplus[p] + Iplus[k]
            Nplus[p] = Nplus[k] if Nplus[p] is None else [[a + b for a, b in zip(x, y)]
                                                          for x, y in zip(Nplus[p], Nplus[k])]
    out = [[0] * n for _ in range(n)]
    for s in range(nb):
        if Iplus[s] is None:
            continue
        path = [c for a in tree.ancestors(s) if a != s for c in tree.coords[a]]
        for j in tree.coords[s]:
            F = add(mv(Nplus[s], P[j]), Iplus[s].apply(Pd[j]))
            for i in tree.coords[s]:
                out[i][j] = dot(P[i], F)
            if not path:
                continue
            G, H = _matvec_t(Nplus[s], P[j]), Iplus[s].apply(P[j])
            for i in path:
                out[i][j] = dot(P[i], F)
                out[j][i] = dot(G, P[i]) + dot(H, Pd[i])
    return out


def coriolis_by_columns(bound, kin, qd, skew=False):
    """:func:`coriolis_matrix` column by column from :func:`coriolis_wrenches` (O(n) motions per column)."""
    n = kin.tree.nv
    B = [[0] * n for _ in range(n)]
    for j, col in enumerate(coriolis_columns(bound, kin, qd, skew)):
        for i in range(n):
            B[i][j] = col[i]
    return B


def coriolis_columns(bound, kin, qd, skew=False):
    """The columns of :func:`coriolis_by_columns` one at a time (so that a count can stop early)."""
    for Z in coriolis_wrenches(bound, kin, qd, skew):
        yield generalized(kin, Z)


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
