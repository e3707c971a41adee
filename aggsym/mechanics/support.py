"""Support dynamics (Konoplev 1989, the support paper): the equation of motion of a free support carrying a
mechanism, (3.1), and its direct and inverse problems (3.4).

The support is the root body on a free pair; its six coordinates are q (o1 o2 o3 theta4 theta5 theta6, whose
rates give the support's quasi-velocity ``V = M q'`` with ``M = M_11^10``, the columns psi of (1.30)), the others
are the mechanism's coordinates gamma (k of them).  The first six equations of (2.7), with the left factor M^T
cancelled, are the support equation (3.1)::

    A q'' + B q' + I gamma'' + J gamma' + g = L T

a wrench balance at the support's origin, in its axes:

* ``A = A+_11 M`` (6 x 6): the composite inertia of the whole system (2.32) times M;
* ``I`` (6 x k): column beta of coordinate beta of body lk, ``I_beta = L^11_lk A+_lk M_lk f_beta`` (3.3): the
  composite inertia of lk's subtree applied to the joint's motion, carried to the support (as in (2.33)-(2.34),
  before the projection);
* ``B`` (6 x 6) and ``J`` (6 x k): the velocity terms, split by columns: column j is the support-side wrench of
  column j of the book's B(q, q') of (2.17) (``B q' = b``, :func:`aggsym.mechanics.bias.coriolis_wrenches`),
  before its projection M^T; so ``B q' + J gamma'`` is the bias wrench at the support and ``M^T`` of it is the
  support rows of b.  (The split of velocity terms between B and J is not unique; this one takes each column
  from the rate it multiplies, as (3.1)-(3.3) do with K+ and M'.)
* ``g`` (6): the weight of every body carried to the support, with aggsym's sign (on the left, ``M^T g`` is the
  support rows of g(q));
* ``L`` (6 x 6): T is the external wrench on the support, (f, mu) about the world origin in world axes (as the
  momentum routine's), and L moves it to the support's origin and axes (the first block of L+_11 of (3.1)):
  ``f_s = R^T f``, ``mu_s = R^T (mu - o x f)``.

Hence ``M^T (A q'' + B q' + I gamma'' + J gamma' + g - L T)`` are the support rows of
``A(q) q'' + b + g - tau`` of the whole system with tau the generalized force of T: the test.  The direct
problem: ``q'' = A^-1 (L T - g - B q' - I gamma'' - J gamma')``; the inverse problem (3.4) 2°: the gamma'' that
gives a wanted q'': ``I gamma'' = r`` with ``r = L T - g - A q'' - B q' - J gamma'``, minimum-norm
``gamma'' = I^T (I I^T)^-1 r`` when k >= 6, least squares ``(I^T I)^-1 I^T r`` when k < 6, and the residual
``r - I gamma''``.
"""
from __future__ import annotations

from .bias import coriolis_wrenches, gravity_wrenches
from .constraints import ldl_solve, lu_solve
from .inertia import composite_inertias
from .kinematics import ZERO6, TreeKinematics
from .linalg import cross, dot, mtv, mul, sub

SIZE = 6  # the support's coordinates


def full_state(x, name, mechanism):
    """The full vector (support's six, then gamma's k) of an input pair, e.g. ("q", "gamma")."""
    return list(x[name][:SIZE]) + list(x[mechanism])


def _columns(bound, kin) -> list:
    """Per coordinate j: the wrench L^11_lk A+_lk psi_j at the support (its origin and axes)."""
    tree = kin.tree
    plus = composite_inertias(bound, kin)
    cols = []
    for j in range(tree.nv):
        k = tree.body_of[j]
        psi = kin.psi[k][tree.coords[k].index(j)]
        beta = ZERO6 if plus[k] is None else plus[k].apply(psi)
        a = k
        while tree.parent[a] >= 0:
            beta = kin.L[a].wrench(beta)
            a = tree.parent[a]
        cols.append(list(beta))
    return cols


def _rows(cols) -> list:
    """6 x len(cols) rows from columns."""
    return [[c[r] for c in cols] for r in range(SIZE)]


def _world_to_support(kin) -> list:
    """L: (f, mu) about the world origin in world axes -> about the support's origin in its axes (6 x 6 rows)."""
    R, o = kin.L[0].c, kin.L[0].o
    rows = []
    for r in range(3):  # f_s = R^T f
        rows.append([R[0][r], R[1][r], R[2][r], 0, 0, 0])
    for r in range(3):  # mu_s = R^T mu - R^T (o x f): column c of the f block is -R^T (o x e_c)
        row = []
        for c in range(3):
            e = [1 if i == c else 0 for i in range(3)]
            row.append(-mtv(R, cross(o, e))[r])
        rows.append(row + [R[0][r], R[1][r], R[2][r]])
    return rows


def coefficients(bound, kin, qd) -> dict:
    """A, B, I, J, L (rows) and g of (3.1) at the full state (q, gamma), (q', gamma')."""
    cols = _columns(bound, kin)
    Z = [list(w[0]) for w in coriolis_wrenches(bound, kin, qd)]
    return {"A": _rows(cols[:SIZE]), "I": _rows(cols[SIZE:]), "B": _rows(Z[:SIZE]), "J": _rows(Z[SIZE:]),
            "L": _world_to_support(kin), "g": list(gravity_wrenches(bound, kin)[0])}


def _times(rows, x) -> list:
    return [dot(row, x) for row in rows]


def _rest(c, qd, gammad, T) -> list:
    """L T - g - B q' - J gamma'."""
    out = sub(_times(c["L"], T), c["g"])
    out = sub(out, _times(c["B"], qd))
    return list(sub(out, _times(c["J"], gammad))) if gammad else list(out)


def _kinematics(bound, x):
    q = full_state(x, "q", "gamma")
    qd = full_state(x, "qd", "gammad")
    return TreeKinematics(bound, q), qd


def support_coefficients(bound, x) -> dict:
    kin, qd = _kinematics(bound, x)
    return coefficients(bound, kin, qd)


def support_direct(bound, x) -> tuple:
    """(q'', status) of (3.4) 1°: A q'' = L T - g - B q' - I gamma'' - J gamma', by elimination with partial
    pivoting (A = A+ M is not symmetric); status nonzero where A is singular (M at a singularity of the free
    pair's angles)."""
    kin, qd = _kinematics(bound, x)
    c = coefficients(bound, kin, qd)
    r = sub(_rest(c, x["qd"][:SIZE], list(x["gammad"]), x["T"]), _times(c["I"], list(x["gammadd"])))
    return lu_solve(c["A"], list(r), bound.backend)


def support_inverse(bound, x) -> tuple:
    """(gamma'', residual, status) of (3.4) 2°: I gamma'' = r, r = L T - g - A q'' - B q' - J gamma'; minimum norm
    for k >= 6, least squares for k < 6; status nonzero where I I^T (k >= 6) or I^T I (k < 6) is singular."""
    kin, qd = _kinematics(bound, x)
    c = coefficients(bound, kin, qd)
    r = list(sub(_rest(c, x["qd"][:SIZE], list(x["gammad"]), x["T"]), _times(c["A"], x["qdd"][:SIZE])))
    I = c["I"]
    k = len(I[0])
    if k >= SIZE:  # I I^T y = r, gamma'' = I^T y
        G = [[dot(I[a], I[b]) for b in range(SIZE)] for a in range(SIZE)]
        y, status = ldl_solve(G, r, bound.backend)
        gammadd = [sum((mul(I[a][j], y[a]) for a in range(1, SIZE)), mul(I[0][j], y[0])) for j in range(k)]
    else:  # (I^T I) gammadd = I^T r
        cols = [[I[a][j] for a in range(SIZE)] for j in range(k)]
        G = [[dot(cols[i], cols[j]) for j in range(k)] for i in range(k)]
        gammadd, status = ldl_solve(G, [dot(col, r) for col in cols], bound.backend)
    residual = list(sub(r, _times(I, gammadd)))
    return gammadd, residual, status
