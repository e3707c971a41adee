"""A fixed tendon's armature (MuJoCo's ``<fixed armature>``): an inertia a along the tendon, so the kinetic energy
gains 1/2 a L'^2 with L' = c . q', and the mass matrix the rank-one term a c c^T:

    A'(q) = A(q) + sum_t a_t c_t c_t^T        (c_t constant: the bias b(q, q') is unchanged).

A, the inverse dynamics (+ sum a c (c . q'')) and the kinetic energy add it directly.  A' is not the mass matrix of
a tree (its extra terms couple coordinates of different branches), so the transvective factors (3.19) are A's; the
solve with A' applies the Sherman-Morrison formula once per tendon to A's own:

    A_t^-1 r = A_{t-1}^-1 r - u_t a_t (c_t . A_{t-1}^-1 r) / (1 + a_t c_t . u_t),    u_t = A_{t-1}^-1 c_t,

exact (A_{t-1} + a_t c_t c_t^T times the right side is r), O(n) per tendon on top of the tree's solve
(:func:`corrected_solution`, in :func:`~.transvective.forward_dynamics`), and the inverse
A_t^-1 = A_{t-1}^-1 - a_t u_t u_t^T / (1 + a_t c_t . u_t) (:func:`corrected_inverse`).  The routines that use the
tree's factors themselves (the factors, the constrained and impulse routines, d qdd) are not emitted for such a
model (:func:`~aggsym.contract.selection.omitted_routines`).
"""
from __future__ import annotations

from ..core.program import is_zero
from .linalg import dot, mul


def armature_rows(bound) -> list:
    """[(c as n scalars, a)] of the fixed tendons with an armature."""
    from .joint_space import linear_form, places

    tendons = [t for t in bound.model.tendons if not is_zero(bound.scalar(t.armature))]
    if not tendons:
        return []
    where, n = places(bound), bound.tree.nv
    out = []
    for tendon in tendons:
        c = linear_form(bound, tendon.terms, where).add_to([0] * n)
        out.append((c, bound.scalar(tendon.armature)))
    return out


def add_to_inertia(bound, A) -> list:
    """A + sum a c c^T, in place (rows)."""
    for c, a in armature_rows(bound):
        for i, ci in enumerate(c):
            if is_zero(ci):
                continue
            for j, cj in enumerate(c):
                if not is_zero(cj):
                    A[i][j] = A[i][j] + mul(a, mul(ci, cj))
    return A


def add_to_torques(bound, tau, qdd) -> list:
    """tau + sum a c (c . q'')."""
    rows = armature_rows(bound)
    if not rows:
        return tau
    tau = list(tau)
    for c, a in rows:
        along = mul(a, dot(c, qdd))
        tau = [t if is_zero(ci) else t + mul(ci, along) for t, ci in zip(tau, c)]
    return tau


def kinetic(bound, qd):
    """sum a (c . q')^2 (twice the tendons' kinetic energy)."""
    acc = 0
    for c, a in armature_rows(bound):
        rate = dot(c, qd)
        acc = acc + mul(a, mul(rate, rate))
    return acc


def corrected_solution(bound, kin, x, solve) -> list:
    """A'^-1 r from x = A^-1 r (the module's text); ``solve(v)``: A^-1 v by the tree's factors."""
    rows = armature_rows(bound)
    if not rows:
        return x
    done = []  # (c, a, u, 1 + a c.u) of the tendons applied so far

    def apply(v):
        for c, a, u, s in done:
            v = [vi - mul(ui, mul(a, dot(c, v)) / s) for vi, ui in zip(v, u)]
        return v

    for c, a in rows:
        u = apply(solve(c))
        done.append((c, a, u, 1 + mul(a, dot(c, u))))
    return apply(list(x))


def corrected_inverse(bound, Ainv) -> list:
    """A'^-1 from A^-1 (rows), one rank-one correction per tendon."""
    rows = armature_rows(bound)
    if not rows:
        return Ainv
    M = [list(r) for r in Ainv]
    for c, a in rows:
        u = [dot(r, c) for r in M]
        s = 1 + mul(a, dot(c, u))
        M = [[M[i][j] - mul(mul(a, u[i]), u[j]) / s for j in range(len(u))] for i in range(len(u))]
    return M


__all__ = ["add_to_inertia", "add_to_torques", "armature_rows", "corrected_inverse", "corrected_solution",
           "kinetic"]
