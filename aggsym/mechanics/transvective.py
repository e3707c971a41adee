"""The transvective factors of A(q) and of its inverse, and the Cauchy form of the equations, (3.7)-(3.20).

Gauss elimination of A(q) starting from its last row is a product of transvections ``t_tk(a) = E + a E_tk``
(3.4), one for every coordinate t above coordinate k on k's path to the root (branch-induced sparsity: no
transvection ever joins two coordinates of different branches):

* ``T = prod_k prod_{t above k} t_tk^-1(<t,k>)``, k ascending, t ascending (3.9); ``t_tk^-1(a) = E - a E_tk``;
* ``T A(q) T^T = diag (beta,beta)^k`` (3.11), (3.16);
* ``A(q) = T^-1 diag (beta,beta)^k T^-T`` (3.18) and ``A(q)^-1 = T^T diag 1/(beta,beta)^k T`` (3.19);
* the Cauchy form ``q'' = T^T diag 1/(beta,beta)^k T F``, ``F = tau - b(q,q') - g(q)`` (3.20).

The argument of a transvection is an inner product like the entries (3.2) of A(q):
``<t,k> = s^{t}_k betabar^k = psi_t^T L^t_k betabar^k`` (3.8), (3.17), ``betabar^k = beta^k / (beta,beta)^k``,
where ``beta^k`` is the column of a 6x6 matrix that already accounts for the eliminated coordinates below k.
The book gives two recurrences for it; both are here:

* the Delta form (3.7)-(3.11), :func:`articulated_factors`: a one-step recurrence of 6x6 matrices,
  ``A^Delta_k = A_kk + sum_{children p} L^k_p (A^Delta_p - beta^p beta^p,T / (beta,beta)^p) L^k,T_p`` (3.7), and
  ``beta^k = A^Delta_k psi_k`` (these are articulated-body inertias);
* the delta form (3.12)-(3.17), :func:`corrected_factors`: the composite columns ``beta^k+ = A^k+ psi_k`` of (3.3)
  corrected by a multi-step sum over all descendants, ``beta^k = beta^k+ - delta^k+``,
  ``delta^k+ = sum_{p below k} L(k,p) L(k,p)^T psi_k (beta,beta)^p`` with ``L(k,p) = L^k_p betabar^p`` (3.15),
  i.e. ``delta^k+ = sum_p <k,p> L^k_p beta^p``.

The routines emit the Delta form.  It costs one 6x6 congruence per body (O(n)), where the delta form needs
O(n d) moved columns and O(n d) 6-vector corrections (d the depth); and most of its 6x6 work folds away: the
eliminated unit axis e_m makes row and column m of ``A^Delta - beta beta^T/(beta,beta)`` exactly zero, and the
congruence with the pair's elementary rotation about that same axis is done in the rotation's plane with
4 products per 2x2 block, and the translations reuse the off-diagonal block (the one congruence through a pair,
:meth:`aggsym.mechanics.kinematics.TreeKinematics.move_to_parent`).  Six-link arm (``models/manipulator6.yaml``), arithmetic nodes of the straight-line
program: factors 246 (Delta) against 423 (delta); q'' 551 in the O(n) order below against 596 transvection by
transvection.  ``tests/test_transvective.py`` checks that both forms give the same arguments, pivots and columns.

A pair with several coordinates is eliminated one coordinate at a time, last coordinate first, inside the
pair's own frame: the coordinates of one pair are a chain, and T then holds transvections between coordinates
of the same pair too (their L is the identity).  "Coordinate t is above coordinate k" means: t belongs to a
pair on the path from k's pair to the root, or to k's own pair and comes before k.

The vector F = tau - b - g of (3.20) takes b + g from the sweeps at q'' = 0 (d(q, q') of (2.44)-(2.46), (2.52),
:mod:`aggsym.sweeps`).  The product (3.20) is evaluated in two orders, both exact:

* transvection by transvection with the explicit arguments (:func:`apply_T`, :func:`apply_T_transpose`,
  :func:`cauchy_solve`): 2 operations per transvection, but forming the arguments moves every betabar^k to
  every pair above it, O(n d) 6-vector motions;
* in O(n) (:func:`apply_T_tree`, :func:`apply_T_transpose_tree`, :func:`cauchy_solve_tree`), the arguments
  never formed.  In ``(T F)_t = F_t - sum_{k below t} <t,k> (T F)_k`` the sum is ``psi_t^T W``,
  ``W = sum_{k below t} L^t_k betabar^k (T F)_k``, one 6-vector per body summed from the buds to the root with
  the wrench motions L (like Z of Prop. 2.19); in ``(T^T z)_k = z_k - sum_{t above k} <t,k> (T^T z)_t`` the sum
  is ``betabar^k,T U``, ``U = sum_{t above k} L^t_k,T psi_t (T^T z)_t``, one 6-vector per body carried from the
  root to the buds with the quasi-velocity motions L^T (like (2.39)).  Inside a pair the coordinates go in
  the elimination order: last first for T (``(T F)_t = F_t - psi_t^T W``, then ``W += betabar^t (T F)_t``),
  first first for T^T (``x_t = z_t - betabar^t,T U``, then ``U += psi_t x_t``); L is the identity there.

``forward_dynamics`` (emitted) is the O(n) order with the sum W riding on the sweeps' backward pass inside the
transmitted wrench Z (:func:`transvected_forces`: both move by the same L, so T F costs no motion of its own),
then T^T by :func:`apply_T_transpose_tree`.  ``transvective_factors`` emits the explicit arguments (they are
its output, in the layout of :func:`layout`).

Everything runs on both backends (floats and straight-line-program nodes): the only divisions are by the
pivots (beta,beta)^k, and the only branching is on structural zeros and ones.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..core.program import is_one, is_zero
from .aggregates import General
from .inertia import composite_inertias
from .bound import scratch_operations
from .kinematics import world_poses
from .linalg import dot, mul, mv, scale, sub
from .tendon_armature import armature_rows, corrected_inverse, corrected_solution

__all__ = [
    "Factors", "coordinate_parents", "coordinates_above", "transvection_pairs", "articulated_factors",
    "corrected_factors", "apply_T", "apply_T_transpose", "cauchy_solve",
    "transvect_pair", "apply_T_tree", "apply_T_transpose_tree", "cauchy_solve_tree", "transvected_forces",
    "PairBasis", "unit_bases", "forward_dynamics_in_bases", "T_columns", "inverse_from_factors", "world_generators", "inverse_by_generators", "forward_dynamics", "inertia_inverse", "factor_outputs",
]


# --------------------------------------------------------------------------------------------------------------
# the coordinate tree (backend-free)


def coordinate_parents(tree) -> list[int]:
    """For each coordinate, the coordinate just above it on its root path (-1 for none), see the module doc."""
    parent = [-1] * tree.nv
    last = [-1] * len(tree)  # the last coordinate on the path from the root to body k, k included
    for k, p in enumerate(tree.parent):
        prev = -1 if p < 0 else last[p]
        for i in tree.coords[k]:
            parent[i] = prev
            prev = i
        last[k] = prev
    return parent


def coordinates_above(tree) -> list[list[int]]:
    """For each coordinate k, the coordinates t above it on its root path, root first (so t < k ascending)."""
    parent = coordinate_parents(tree)
    above: list[list[int]] = []
    for k, p in enumerate(parent):
        above.append([] if p < 0 else above[p] + [p])
    return above


def transvection_pairs(tree) -> list[tuple[int, int]]:
    """The (t, k) of every transvection t_tk^-1(<t,k>) in the order of the product T (3.9).

    k ascending, and for each k the coordinates above it root first.  Their number is the sum over the
    coordinates of the number of coordinates above them on their root path.
    """
    return [(t, k) for k, above in enumerate(coordinates_above(tree)) for t in above]


def _unit_axis(psi):
    """m when the 6-vector psi is structurally the unit vector e_m, else None."""
    m = None
    for i, x in enumerate(psi):
        if is_zero(x):
            continue
        if is_one(x) and m is None:
            m = i
        else:
            return None
    return m


# --------------------------------------------------------------------------------------------------------------
# the factors


@dataclass
class Factors:
    """The transvective factors of A(q): T by its arguments, and the diagonal.

    ``pairs``: the (t, k) in product order (3.9); ``args[(t, k)] = <t,k>`` (3.8), (3.17) (empty when the
    arguments were not asked for); ``diag[k] = (beta,beta)^k`` and ``recip[k]`` its reciprocal; ``beta[k]`` the
    column beta^k and ``betabar[k] = beta^k / (beta,beta)^k`` (3.13) (6-vectors, axes of k's body).
    """

    pairs: list
    args: dict
    diag: list
    recip: list
    beta: list
    betabar: list

    def arguments(self) -> list:
        """The arguments <t,k> in product order."""
        return [self.args[pk] for pk in self.pairs]


def _pivot(beta, psi, armature=0):
    """(beta,beta) = psi^T beta (3.12) (plus the armature's rotor inertia on the coordinate's own axis), its
    reciprocal and betabar = beta / (beta,beta) (3.13)."""
    d = dot(psi, beta) + armature
    r = 1 / d
    return d, r, scale(r, beta)


def _eliminate(X, psi, armature=0):
    """One step of (3.7) inside a body: beta = X psi, and X - beta beta^T / (beta,beta) as a General.

    Returns ``(beta, d, r, betabar, X')``.  When psi is the unit axis e_m (and there is no armature),
    ``betabar_m = 1`` and row and column m of X' are exactly zero (X' psi = beta - beta (psi^T beta)/(beta,beta)
    = 0); both are set structurally.
    """
    beta = X.apply(psi)
    d, r, bbar = _pivot(beta, psi, armature)
    m = _unit_axis(psi) if is_zero(armature) else None
    if m is not None:
        bbar = tuple(1 if i == m else x for i, x in enumerate(bbar))
    M = X.general().matrix()
    out = [[0] * 6 for _ in range(6)]
    for i in range(6):
        for j in range(i, 6):
            if i == m or j == m:
                continue
            out[i][j] = out[j][i] = M[i][j] - mul(beta[i], bbar[j])
    return beta, d, r, bbar, General.from_rows(out)


def _record_arguments(tree, kin, args, k, pos, bbar, reach):
    """<t,j> = psi_t^T L^t_k betabar^j (3.8) for every coordinate t above j = coords[k][pos]: the earlier
    coordinates of the pair, then betabar carried towards the root with the wrench motions L, as far as
    ``reach[a]`` says coordinates remain above body a."""
    j = tree.coords[k][pos]
    for t, psi in zip(tree.coords[k][:pos], kin.psi[k][:pos]):
        args[(t, j)] = dot(psi, bbar)
    w, a = bbar, k
    while reach[a]:
        w = kin.L[a].wrench(w)
        a = tree.parent[a]
        for t, psi in zip(tree.coords[a], kin.psi[a]):
            args[(t, j)] = dot(psi, w)


def _coordinates_above_body(tree) -> list[bool]:
    """For every body, whether some pair strictly above it (on its path to the root) has coordinates."""
    out = []
    for p in tree.parent:
        out.append(p >= 0 and (bool(tree.coords[p]) or out[p]))
    return out


def articulated_factors(bound, kin, arguments: bool = True) -> Factors:
    """The factors by the Delta form (3.7)-(3.11): one-step recurrence of A^Delta_k from the buds to the root.

    With ``arguments=False`` the arguments <t,k> (3.8) are not formed (``args`` is empty): the O(n) evaluation
    of (3.19), (3.20) (:func:`apply_T_tree`, :func:`apply_T_transpose_tree`) needs only the columns betabar."""
    tree = kin.tree
    n = tree.nv
    diag, recip, beta, betabar = [0] * n, [0] * n, [None] * n, [None] * n
    args: dict = {}
    acc = [b.mises for b in bound.bodies]  # A_kk, then + sum over children L (A^Delta - beta beta^T/(.,.)) L^T
    reach = _coordinates_above_body(tree)
    for k in range(len(tree) - 1, -1, -1):
        X = acc[k]
        coords = tree.coords[k]
        for pos in range(len(coords) - 1, -1, -1):
            j = coords[pos]
            if X is None:  # nothing moves beyond this axis: only the armature's rotor has inertia there
                if is_zero(bound.rotor(j)):
                    raise ZeroDivisionError(f"coordinate {coords[pos]} moves no mass: A(q) is singular")
                X = General.from_rows([[0] * 6 for _ in range(6)])
            beta[j], diag[j], recip[j], bbar, X = _eliminate(X, kin.psi[k][pos], bound.rotor(j))
            betabar[j] = bbar
            if arguments:
                _record_arguments(tree, kin, args, k, pos, bbar, reach)
        p = tree.parent[k]
        if p >= 0 and X is not None:
            moved = kin.move_to_parent(k, X)
            acc[p] = moved if acc[p] is None else acc[p] + moved
    return Factors(transvection_pairs(tree), args, diag, recip, beta, betabar)


def corrected_factors(bound, kin) -> Factors:
    """The factors by the delta form (3.12)-(3.17): composite columns beta^k+ (3.3) minus the corrections (3.15).

    ``beta^j = beta^j+ - sum_{p below j} <j,p> L^k_p beta^p`` where the moved columns ``L^k_p beta^p`` and
    ``L(k,p) = L^k_p betabar^p`` are carried up from p's pair one motion at a time, L(k,p) = L^k_k+1 L(k+1,p).
    """
    tree = kin.tree
    n = tree.nv
    plus = composite_inertias(bound, kin)
    body_of = tree.body_of
    below = [[] for _ in range(n)]
    for t, k in transvection_pairs(tree):
        below[t].append(k)
    diag, recip, beta, betabar = [0] * n, [0] * n, [None] * n, [None] * n
    args: dict = {}
    moved: dict = {}  # (body a, coordinate p) -> L^a_{body(p)} beta^p
    reach = _coordinates_above_body(tree)
    for j in range(n - 1, -1, -1):
        k = body_of[j]
        pos = tree.coords[k].index(j)
        psi = kin.psi[k][pos]
        if plus[k] is None and is_zero(bound.rotor(j)):
            raise ZeroDivisionError(f"coordinate {j} moves no mass: A(q) is singular")
        col = (0,) * 6 if plus[k] is None else plus[k].apply(psi)  # beta^j+ (3.3)
        for p in below[j]:  # delta^j+ (3.15)
            col = sub(col, scale(args[(j, p)], moved[(k, p)]))
        beta[j] = col
        diag[j], recip[j], bbar = _pivot(col, psi, bound.rotor(j))
        betabar[j] = bbar
        _record_arguments(tree, kin, args, k, pos, bbar, reach)
        w, a = col, k
        moved[(a, j)] = w
        while reach[a]:
            w = kin.L[a].wrench(w)
            a = tree.parent[a]
            moved[(a, j)] = w
    return Factors(transvection_pairs(tree), args, diag, recip, beta, betabar)


# --------------------------------------------------------------------------------------------------------------
# applying the factors


def apply_T(fac: Factors, F) -> list:
    """T F (3.9): the transvections applied right to left, k descending: F_t -= <t,k> F_k for t above k."""
    y = list(F)
    for t, k in reversed(fac.pairs):
        a = fac.args[(t, k)]
        if not (is_zero(a) or is_zero(y[k])):
            y[t] = y[t] - a * y[k]
    return y


def apply_T_transpose(fac: Factors, z) -> list:
    """T^T z (3.10): x_k = z_k - sum_{t above k} <t,k> x_t, k ascending."""
    x = list(z)
    for t, k in fac.pairs:
        a = fac.args[(t, k)]
        if not (is_zero(a) or is_zero(x[t])):
            x[k] = x[k] - a * x[t]
    return x


def cauchy_solve(fac: Factors, F) -> list:
    """q'' = T^T diag 1/(beta,beta)^k T F (3.20), in O(number of transvections) scalar operations."""
    y = apply_T(fac, F)
    return apply_T_transpose(fac, [r * x for r, x in zip(fac.recip, y)])


# --------------------------------------------------------------------------------------------------------------
# the same products in O(n): the arguments summed on the tree


def _axpy(acc, x, v):
    """acc + x v for a 6-vector v (acc None: nothing accumulated yet); products with structural zeros skipped."""
    xv = tuple(mul(x, e) for e in v)
    return xv if acc is None else tuple(a + b for a, b in zip(acc, xv))


def _sum6(a, b):
    """a + b for 6-vectors, None standing for an empty sum."""
    if a is None:
        return b
    if b is None:
        return a
    return tuple(x + y for x, y in zip(a, b))


def transvect_pair(kin, fac, k, F, W=None):
    """The rows of T F (3.9) for the coordinates of body k's pair, given the moved sum W of the buds' columns.

    ``W = sum_{j below the pair} L^k_{body j} betabar^j (T F)_j`` (k's axes; None when empty).  The pair's
    coordinates are taken last first, as they were eliminated: ``(T F)_t = F_t - psi_t^T W`` and then
    ``W += betabar^t (T F)_t``, so a later coordinate of the same pair enters through ``psi_t^T betabar^j =
    <t, j>`` (L is the identity inside a pair).  Returns ``({t: (T F)_t}, W)``, W now including the pair."""
    out = {}
    for pos in range(len(kin.tree.coords[k]) - 1, -1, -1):
        t = kin.tree.coords[k][pos]
        y = F[t] if W is None else F[t] - dot(kin.psi[k][pos], W)
        out[t] = y
        W = _axpy(W, y, fac.betabar[t])
    return out, W


def apply_T_tree(kin, fac: Factors, F) -> list:
    """T F (3.9) in O(n) 6-vector operations, the arguments never formed.

    ``(T F)_t = F_t - sum_{k below t} <t,k> (T F)_k`` (the transvections applied k descending, as in
    :func:`apply_T`), and with <t,k> = psi_t^T L^t_k betabar^k (3.8) the sum is ``psi_t^T W_t``,
    ``W = sum_{k below t} L^t_k betabar^k (T F)_k``: one 6-vector per body, summed from the buds to the root and
    moved by the wrench motions L (like Z of Prop. 2.19); see :func:`transvect_pair` for a pair's own
    coordinates.  This is an evaluation order of the same product T."""
    tree = kin.tree
    y = list(F)
    W = [None] * len(tree)
    reach = _coordinates_above_body(tree)
    for k in range(len(tree) - 1, -1, -1):
        rows, w = transvect_pair(kin, fac, k, F, W[k])
        for t, v in rows.items():
            y[t] = v
        p = tree.parent[k]
        if reach[k] and w is not None:
            W[p] = _sum6(W[p], kin.L[k].wrench(w))
    return y


def apply_T_transpose_tree(kin, fac: Factors, z) -> list:
    """T^T z (3.10) in O(n) 6-vector operations, the arguments never formed.

    ``(T^T z)_k = z_k - sum_{t above k} <t,k> (T^T z)_t`` (k ascending, as in :func:`apply_T_transpose`), and
    the sum is ``betabar^k,T U_k``, ``U_k = sum_{t above k} L^t_k,T psi_t (T^T z)_t``: one 6-vector per body,
    carried from the root to the buds by the quasi-velocity motions L^T (like (2.39)); inside a pair, first
    coordinate first, ``U += psi_t (T^T z)_t`` after each."""
    tree = kin.tree
    x = list(z)
    U = [None] * len(tree)
    for k, p in enumerate(tree.parent):
        u = None if p < 0 or U[p] is None else kin.L[k].twist(U[p])
        for t, psi in zip(tree.coords[k], kin.psi[k]):
            if u is not None:
                x[t] = z[t] - dot(fac.betabar[t], u)
            u = _axpy(u, x[t], psi)
        U[k] = u
    return x


def cauchy_solve_tree(kin, fac: Factors, F) -> list:
    """q'' = T^T diag 1/(beta,beta)^k T F (3.20) by :func:`apply_T_tree` and :func:`apply_T_transpose_tree`."""
    y = apply_T_tree(kin, fac, F)
    return apply_T_transpose_tree(kin, fac, [mul(r, v) for r, v in zip(fac.recip, y)])


def T_columns(fac: Factors, n: int) -> list[dict]:
    """The entries of T column by column, ``cols[i][t] = T_ti`` for t above i and t = i (all others are zero).

    ``T^-1 = E + sum <t,k> E_tk`` (the product (3.9) inverted: its factors commute into a sum), so T U = E with
    U = T^-1 gives ``T_ti = -sum_j T_tj <j,i>`` over the j above i that t is above or equal to."""
    above: list[list[int]] = [[] for _ in range(n)]
    for t, k in fac.pairs:
        above[k].append(t)
    cols: list[dict] = []
    for i in range(n):
        col = {i: 1}
        for t in above[i]:
            acc = 0
            for j in above[i]:
                if j < t:
                    continue
                acc = acc - mul(1 if j == t else cols[j][t], fac.args[(j, i)])
            col[t] = acc
        cols.append(col)
    return cols


def inverse_from_factors(fac: Factors, n: int) -> list:
    """A(q)^-1 = T^T diag 1/(beta,beta)^k T (3.19) as n x n rows: entry (i, j) is the sum of T_ki T_kj /
    (beta,beta)^k over the coordinates k above or equal to both i and j (symmetric: computed for i <= j)."""
    out = [[0] * n for _ in range(n)]
    for i, row in enumerate(_factor_rows(fac, n)):
        for j, x in enumerate(row, start=i):
            out[i][j] = out[j][i] = x
    return out


def _factor_rows(fac: Factors, n: int):
    """The entries (i, j >= i) of :func:`inverse_from_factors`, one row i at a time."""
    cols = T_columns(fac, n)
    for i in range(n):
        scaled = {k: mul(fac.recip[k], x) for k, x in cols[i].items()}
        row = []
        for j in range(i, n):
            acc = 0
            for k, x in scaled.items():
                y = cols[j].get(k)
                if y is not None:
                    acc = acc + mul(x, y)
            row.append(acc)
        yield row


# --------------------------------------------------------------------------------------------------------------
# the routines' outputs


def transvected_forces(bound, kin, fac: Factors, tau, qd) -> list:
    """T F = T (tau - b - g) (3.9), (3.20), with the sum W of :func:`apply_T_tree` carried by the sweeps'
    backward pass: the pair's d_t = psi_t^T Z_k (2.46) arrives, ``(T F)_t = tau_t - d_t - psi_t^T W`` is formed
    (:func:`transvect_pair`) and W travels to the root inside Z_k (both move by the same L).  The same product
    T F as ``apply_T_tree(kin, fac, tau - d_vector(...))``, one wrench motion per body fewer."""
    from .sweeps import inverse_dynamics

    def transvect(k, d):
        F = {t: tau[t] - x for t, x in zip(kin.tree.coords[k], d)}
        rows, W = transvect_pair(kin, fac, k, F)
        return [rows[t] for t in kin.tree.coords[k]], W

    return inverse_dynamics(bound, kin, qd, [0] * kin.tree.nv, transvect=transvect)


def forward_dynamics(bound, kin, tau, qd, fac=None):
    """q'' = T^T diag(1/(beta,beta)) T (tau - b - g) (3.20) in O(n): T F by :func:`transvected_forces` on the
    sweeps (b + g = d(q, q') (2.52)), then T^T by :func:`apply_T_transpose_tree`; the arguments <t,k> are never
    formed (``fac``: the factors, when the caller has them).

    Without ``fac``, a pair whose columns Psi span body axes (:func:`unit_bases`: the Euler floating base, a
    spherical pair) is solved in those axes (:func:`forward_dynamics_in_bases`)."""
    if bound.model.tendons and armature_rows(bound):  # (the fixed tendons' armature: A' = A + sum a c c^T)
        tree_fac = articulated_factors(bound, kin, arguments=False) if fac is None else fac
        return corrected_solution(bound, kin, _tree_forward_dynamics(bound, kin, tau, qd, fac),
                                  lambda v: cauchy_solve_tree(kin, tree_fac, v))
    return _tree_forward_dynamics(bound, kin, tau, qd, fac)


def _tree_forward_dynamics(bound, kin, tau, qd, fac):
    """:func:`forward_dynamics` with the tree's A (no tendon armature)."""
    if fac is None:
        bases = unit_bases(bound, kin)
        if bases:
            return forward_dynamics_in_bases(bound, kin, tau, qd, bases)
    fac = articulated_factors(bound, kin, arguments=False) if fac is None else fac
    y = transvected_forces(bound, kin, fac, tau, qd)
    return apply_T_transpose_tree(kin, fac, [mul(r, v) for r, v in zip(fac.recip, y)])


# --------------------------------------------------------------------------------------------------------------
# a pair of several coordinates solved in body axes


@dataclass(frozen=True)
class PairBasis:
    """A pair whose columns Psi (1.30) span body axes: ``Psi = E_S M^T`` with ``E_S`` the unit columns of the axes S
    and M square (block diagonal: translations, rotations), so that the pair's quasi-velocity along S is
    ``u = M^T q'`` and its generalized forces are ``tau = M u*`` for the wrench components u* along S.

    ``axes[i]``: the body axis paired with the pair's i-th coordinate (its unit column in the solve);
    ``blocks``: ``(positions, axes, M, r)`` per block, ``M[i][j] = psi_{positions[i]}[axes[j]]``, ``r`` None when M
    is orthogonal (translations: M is a block of the pair's rotation c^T, M^-1 = M^T) else the reciprocal of
    det M (rotations: M^-1 = adj(M) r)."""

    axes: tuple
    blocks: tuple

    def unit_psi(self) -> list:
        return [tuple(1 if j == a else 0 for j in range(6)) for a in self.axes]

    def forces(self, F) -> list:
        """M^-1 F (F in the pair's coordinate order): the components along the axes, in the same order."""
        out = list(F)
        for positions, axes, M, r in self.blocks:
            inv = _transpose(M) if r is None else _adjugate(M)
            for i, p in enumerate(positions):  # positions[i] carries axes[i]
                x = dot(inv[i], [F[q] for q in positions])
                out[p] = x if r is None else mul(r, x)
        return out

    def rates(self, x) -> list:
        """M^-T x (x: the components along the axes, in the pair's coordinate order): the pair's q''."""
        out = list(x)
        for positions, axes, M, r in self.blocks:
            inv_t = M if r is None else _transpose(_adjugate(M))
            for i, p in enumerate(positions):
                y = dot(inv_t[i], [x[q] for q in positions])
                out[p] = y if r is None else mul(r, y)
        return out


def _transpose(M):
    return [list(col) for col in zip(*M)]


def _adjugate(M):
    """adj(M) of a 1x1, 2x2 or 3x3 matrix (products with structural zeros skipped)."""
    n = len(M)
    if n == 1:
        return [[1]]
    if n == 2:
        return [[M[1][1], -M[0][1]], [-M[1][0], M[0][0]]]
    adj = [[0] * 3 for _ in range(3)]
    for i in range(3):
        for j in range(3):
            r, c = [x for x in range(3) if x != j], [x for x in range(3) if x != i]
            minor = mul(M[r[0]][c[0]], M[r[1]][c[1]]) - mul(M[r[0]][c[1]], M[r[1]][c[0]])
            adj[i][j] = minor if (i + j) % 2 == 0 else -minor
    return adj


def _determinant(M, adj):
    """det M by the first column of M and the first row of adj(M)."""
    return dot(adj[0], [row[0] for row in M])


def unit_bases(bound, kin) -> dict:
    """{body: :class:`PairBasis`} for the pairs of several coordinates whose Psi columns span body axes but are not
    themselves unit columns: the translations' columns c^T e_i (1.30) have no angular part and span as many body
    axes as there are translations (c restricted to them is orthogonal), the rotations' columns no linear part
    and span as many axes as there are rotations (structurally: the rows where some column is not an exact
    zero).  The Euler floating base (o1 o2 o3 theta4 theta5 theta6) and a spherical pair qualify; a universal
    pair (two rotations span three axes) does not.  None with an armature (it is diagonal in the coordinates,
    not in the axes)."""
    if bound.has_rotors:
        return {}
    out = {}
    for k, psi in enumerate(kin.psi):
        if len(psi) < 2 or all(_unit_axis(col) is not None for col in psi):
            continue
        linear = [p for p, col in enumerate(psi) if all(is_zero(x) for x in col[3:])]
        angular = [p for p, col in enumerate(psi) if all(is_zero(x) for x in col[:3]) and p not in linear]
        if len(linear) + len(angular) != len(psi):
            continue
        axes, blocks = [None] * len(psi), []
        for positions, half in ((linear, 0), (angular, 3)):
            if not positions:
                continue
            rows = sorted({half + r for p in positions for r in range(3) if not is_zero(psi[p][half + r])})
            if len(rows) != len(positions):
                break
            M = [[psi[p][a] for a in rows] for p in positions]
            for p, a in zip(positions, rows):
                axes[p] = a
            r = None
            if half == 3 and not all(_unit_axis(psi[p]) is not None for p in positions):  # (unit: M permutes)
                det = _determinant(M, _adjugate(M))
                if is_zero(det):
                    break
                r = 1 / det
            blocks.append((tuple(positions), tuple(rows), M, r))
        else:
            out[k] = PairBasis(tuple(axes), tuple(blocks))
    return out


class _InBases:
    """The kinematics with the unit columns of :func:`unit_bases` in place of those pairs' Psi (everything else,
    the motions L included, is the kinematics' own)."""

    def __init__(self, kin, bases):
        self._kin = kin
        self.psi = [bases[k].unit_psi() if k in bases else psi for k, psi in enumerate(kin.psi)]

    def __getattr__(self, name):
        return getattr(self._kin, name)


def forward_dynamics_in_bases(bound, kin, tau, qd, bases) -> list:
    """:func:`forward_dynamics` with the pairs of ``bases`` solved in body axes: a change of coordinates of A(q) on
    those pairs, A' = N^T A N with N = M^-T on the pair (M of :class:`PairBasis`) and the identity elsewhere.  The sweeps run in the pair's own coordinates (b + g = d(q, q'), their velocity products
    included); the pair's row of F = tau - d goes to the axes as ``M^-1 F`` (with ``d = Psi^T Z``: tau's
    components along the axes less the wrench Z itself), T and T^T are those of A' (3.9), (3.19), the pairs' unit
    columns making their elimination as cheap as a free-flyer's (:func:`_eliminate`), and the result along the
    axes returns to the coordinates as ``q'' = M^-T x``.  Exact: q'' solves A q'' = F.  Solo12 with the Euler base:
    2683 operations (15 divisions: det M of the rotations is one) against 2808 (14) with the base's six
    q-dependent columns eliminated in its own coordinates."""
    from .sweeps import inverse_dynamics

    tree = kin.tree
    inner = _InBases(kin, bases)
    fac = articulated_factors(bound, inner, arguments=False)

    def transvect(k, d):
        coords = tree.coords[k]
        F = [tau[t] - x for t, x in zip(coords, d)]
        if k in bases:
            F = bases[k].forces(F)
        rows, W = transvect_pair(inner, fac, k, dict(zip(coords, F)))
        return [rows[t] for t in coords], W

    y = inverse_dynamics(bound, kin, qd, [0] * tree.nv, transvect=transvect)
    x = apply_T_transpose_tree(inner, fac, [mul(r, v) for r, v in zip(fac.recip, y)])
    for k, basis in bases.items():
        coords = tree.coords[k]
        for t, v in zip(coords, basis.rates([x[t] for t in coords])):
            x[t] = v
    return x


def world_generators(bound, kin, fac: Factors):
    """The generators of (3.8) in the world's axes: ``p_t`` (psi_t as a motion of the world origin) and ``b_k``
    (betabar^k as a wrench about the world origin), so that ``<t,k> = psi_t^T L^t_k betabar^k = p_t . b_k``
    for t above k: composing the motions L along the path is moving both to the root (Prop. 1.8)."""
    tree = kin.tree
    P, B = [None] * tree.nv, [None] * tree.nv
    poses = world_poses(kin)
    for k, coords in enumerate(tree.coords):
        for j, psi in zip(coords, kin.psi[k]):
            P[j] = poses[k].motion(psi)
            B[j] = poses[k].wrench(fac.betabar[j])
    return P, B


def inverse_by_generators(bound, kin, fac: Factors = None) -> list:
    """A(q)^-1 = T^T diag(1/(beta,beta)) T (3.19) as n x n rows in O(n^2), entry by entry from 6-vectors.

    With the generators ``p_t``, ``b_k`` of :func:`world_generators` the transvections' arguments are
    ``<t,k> = p_t . b_k`` (3.8), and T = (E + sum <t,k> E_tk)^-1 has the entries ``T_tk = -p_t . Phi(t,k) b_k``
    for t above k, ``Phi(t,k)`` the product of the projections ``E - b_m p_m^T`` over the coordinates m strictly
    between t and k, root side first (the substitution ``x_t = z_t - p_t . S_t``, ``S = sum_{m below t} b_m x_m``,
    unrolled along the path).  So the entry (3.19) ``(A^-1)_ij = sum_k T_ki T_kj / (beta,beta)^k``, k above or
    equal to both, splits at a coordinate a above or equal to both into ``v_ai^T M'_a v_aj`` where
    ``v_aj = Phi(a,j) b_j`` carries column j up to a and the symmetric 6x6

    * ``M_i = sum_{k above i} r_k r_k^T / (beta,beta)^k``, ``r_k = -Phi(k,i)^T p_k``, runs from the root to the
      buds: ``M_child = M'_i = (E - p_i b_i^T) M_i (E - b_i p_i^T) + p_i p_i^T / (beta,beta)^i``
      ``= M_i - p_i c_i^T - g_i p_i^T`` with ``g_i = M_i b_i``, ``E_i = b_i . g_i + 1/(beta,beta)^i`` and
      ``c_i = g_i - E_i p_i`` (O(n) 6x6 work);
    * ``(A^-1)_ii = E_i``; for i above j, ``(A^-1)_ij = c_i . v_ij`` (the k = i term is ``-p_i . v_ij /
      (beta,beta)^i``); for i and j on different branches below a coordinate a, ``(A^-1)_ij = v_ai . M'_a v_aj``;
      for coordinates with nothing above both (a fixed root with several branches), 0.

    Column j climbs from j to the root with ``v <- v - (p_i . v) b_i`` (the projection at i), one dot product
    for the entry and one for the projection: 34 operations per pair i above j (a serial chain: about
    17 n^2 in all), against the O(n^3) products of :func:`inverse_from_factors`.  Exact on both backends: the
    only divisions are the pivots' (in the factors)."""
    tree = kin.tree
    n = tree.nv
    fac = articulated_factors(bound, kin, arguments=False) if fac is None else fac
    P, B = world_generators(bound, kin, fac)
    parent = coordinate_parents(tree)
    children = [[] for _ in range(n)]
    for j, p in enumerate(parent):
        if p >= 0:
            children[p].append(j)
    out = [[0] * n for _ in range(n)]
    M = [None] * n  # M_i, None for zero
    C = [None] * n
    Mpast = [None] * n  # M'_i at branch points (several children)
    for i in range(n):
        if M[i] is None:
            g, h = (0,) * 6, 0
        else:
            g = mv(M[i], B[i])
            h = dot(B[i], g)
        E = h + fac.recip[i]
        out[i][i] = E
        C[i] = sub(g, scale(E, P[i]))
        if not children[i]:
            continue
        Mn = [[0] * 6 for _ in range(6)]
        for a in range(6):
            for b in range(a, 6):
                x = 0 if M[i] is None else M[i][a][b]
                Mn[a][b] = Mn[b][a] = x - mul(P[i][a], C[i][b]) - mul(g[a], P[i][b])
        Mn = tuple(tuple(r) for r in Mn)
        for ch in children[i]:
            M[ch] = Mn
        if len(children[i]) > 1:
            Mpast[i] = Mn
    # the columns climb: v_ij at every coordinate i above j
    arrived = {}  # (branch point a, j) -> v_aj
    for j in range(n):
        v, i = B[j], parent[j]
        while i >= 0:
            out[i][j] = out[j][i] = dot(C[i], v)
            if Mpast[i] is not None:
                arrived[(i, j)] = v
            if parent[i] < 0:
                break
            v = sub(v, scale(dot(P[i], v), B[i]))
            i = parent[i]
    # pairs on different branches below a branch point a: v_ai . (M'_a v_aj)
    subtree = [[j] for j in range(n)]
    for j in range(n - 1, -1, -1):
        if parent[j] >= 0:
            subtree[parent[j]] = subtree[parent[j]] + subtree[j]
    for a in range(n):
        if Mpast[a] is None:
            continue
        groups = [subtree[ch] for ch in children[a]]
        widest = max(range(len(groups)), key=lambda g: len(groups[g]))
        moved = {j: mv(Mpast[a], arrived[(a, j)])
                 for g, grp in enumerate(groups) if g != widest for j in grp}
        for g1 in range(len(groups)):
            for g2 in range(g1 + 1, len(groups)):
                for i in groups[g1]:
                    for j in groups[g2]:
                        if j in moved:
                            x = dot(arrived[(a, i)], moved[j])
                        else:
                            x = dot(moved[i], arrived[(a, j)])
                        out[i][j] = out[j][i] = x
    return out


def _factor_product_floor(tree) -> int:
    """A floor on the multiplications of :func:`inverse_from_factors` (with :func:`T_columns`): one per term of
    every sum, whatever folds structurally; O(n^2) to evaluate from the coordinate tree alone."""
    above = coordinates_above(tree)
    n = tree.nv
    count = sum(len(a) * (len(a) + 1) // 2 for a in above)  # T_columns: T_tj <j,i> for j from t to i's parent
    sets = [set(a) | {i} for i, a in enumerate(above)]
    for i in range(n):
        for j in range(i, n):
            count += len(sets[i] & sets[j])  # (3.19): T_ki T_kj / (beta,beta)^k over k above or equal to both
    return count


def inertia_inverse(bound, kin):
    """A(q)^-1 = T^T diag(1/(beta,beta)) T (3.19), as rows: the O(n^2) :func:`inverse_by_generators`, or the
    entry-by-entry product of the explicit factors (:func:`inverse_from_factors`) where that program is smaller.

    The generators' program has a fixed cost per coordinate (the poses, the 6x6 recursion of M, about 360
    operations per coordinate on the benchmark's 3-D chains) and 34 per pair i above j; the explicit factors
    stay local and sparse (unit psi, elementary rotations), so they win on small and on shallow trees (the
    six-link arm, the delta robot) and lose as n^3 on deep ones.  On the straight-line program both are counted
    on scratch programs of the same model (the explicit factors only when a floor on their products does not
    already exceed the generators' count) and the one with fewer operations is emitted; on floats the generators
    are used (both are exact).
    Operation counts of the emitted C on the benchmark chains (``benchmarks/harness/chain.py``), mul + add + div + call:
    n = 6: 1087 (factors), 12: 4205 (factors), 24: 17660, 48: 55748, 96: about 17 n^2 + 360 n (generators),
    against 710297 for the factors at n = 96."""
    if bound.model.tendons and armature_rows(bound):  # (the fixed tendons' armature: Sherman-Morrison)
        return corrected_inverse(bound, _tree_inertia_inverse(bound, kin))
    return _tree_inertia_inverse(bound, kin)


def _tree_inertia_inverse(bound, kin):
    """:func:`inertia_inverse` of the tree's A (no tendon armature)."""
    if not bound.backend.symbolic or bound.backend.program is None:  # floats, duals: nothing to count on
        return inverse_by_generators(bound, kin)
    fast = scratch_operations(bound, kin, lambda b, k, _: inverse_by_generators(b, k))
    if _factor_product_floor(kin.tree) >= fast:
        return inverse_by_generators(bound, kin)
    slow = scratch_operations(bound, kin, lambda b, k, _: _factor_rows(articulated_factors(b, k), k.tree.nv), fast)
    if slow < fast:
        return inverse_from_factors(articulated_factors(bound, kin), kin.tree.nv)
    return inverse_by_generators(bound, kin)


def factor_outputs(bound, kin):
    """(targs, diag): the arguments <t,k> in the order of :func:`transvection_pairs` and the pivots."""
    fac = articulated_factors(bound, kin)
    return fac.arguments(), list(fac.diag)
