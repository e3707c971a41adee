"""Hooke elasticity: the stiffness C of elastic pairs, the generalized elastic force C q, its energy, and the
slow/fast partition of the equations, (1.32)-(1.33), (2.27), Prop. 2.13, Prop. 2.14.

An elastic pair (Def. 1.10) is a pair whose coordinates are deformations of the parent element; the model gives
its stiffness, a symmetric positive semi-definite k x k matrix over the pair's coordinates, and optionally the
rest position q0 (default 0).  C is block diagonal over the pairs, and the equations (2.27) read

    A(q) q'' + b(q, q') + g(q) + C (q - q0) = tau,

the elastic generalized force on the left beside gravity, with the energy ``1/2 (q - q0)^T C (q - q0)`` added to
the potential energy.  Sign convention: C is the stiffness itself (positive), so C (q - q0) on the left is a
restoring force.  (The book's example after (2.28) prints C = -[[c22, c25, 0], [c52, c55, 0], [0, 0, 0]] and
the terms "- c22 delta12 - c25 delta15" on the left; there c_ij are the coefficients of the elastic wrench acting
on the body, i.e. minus our stiffness, see ``tests/test_elastic.py``.)

Prop. 2.14: the coordinates of elastic pairs are the fast ones (-), the others the slow ones (+).  The
permutation P puts the slow coordinates first (each group in q order), and

    P A(q) P^T = [[A++, A-+], [A+-, A--]],  P B P^T = [[B++, B-+], [B+-, B--]],  P C P^T = [[O, O], [O, C--]]

in the book's notation D^{upper}_{lower} = "contribution of the upper motion to the lower one's equation": A-+
has the rows of the slow coordinates and the columns of the fast ones.  The emitted names are A_pp, A_mp, A_pm,
A_mm (p = +, m = -, upper index first) and likewise for B; B is :func:`aggsym.bias.coriolis_matrix`
(b = B q').
"""
from __future__ import annotations

from ..core.program import is_zero
from .bias import coriolis_matrix
from .inertia import inertia_matrix


def is_elastic(model) -> bool:
    """True when some pair of the model has a stiffness."""
    return any(b.pair.elastic for b in model.bodies)


def stiffness_matrix(bound) -> list:
    """C as n x n rows of backend scalars: block diagonal over the elastic pairs (2.27)."""
    tree = bound.tree
    n = tree.nv
    C = [[0] * n for _ in range(n)]
    for k, body in enumerate(bound.bodies):
        if body.stiffness is None:
            continue
        idx = tree.coords[k]
        for a, i in enumerate(idx):
            for b, j in enumerate(idx):
                C[i][j] = body.stiffness[a][b]
    return C


def deformations(bound, q) -> list:
    """q - q0 on the elastic pairs' coordinates, 0 elsewhere."""
    out = [0] * bound.tree.nv
    for k, body in enumerate(bound.bodies):
        if body.stiffness is None:
            continue
        for i, j, r in zip(bound.tree.coords[k], bound.tree.positions[k], body.rest):
            out[i] = q[j] - r
    return out


def elastic_forces(bound, q) -> list:
    """C (q - q0), the generalized elastic force on the left side of (2.27): n scalars (0 off elastic pairs)."""
    tree = bound.tree
    d = deformations(bound, q)
    out = [0] * tree.nv
    for k, body in enumerate(bound.bodies):
        if body.stiffness is None:
            continue
        idx = tree.coords[k]
        for a, i in enumerate(idx):
            acc = 0
            for b, j in enumerate(idx):
                c = body.stiffness[a][b]
                acc = acc + c * d[j]
            out[i] = acc
    return out


def elastic_energy(bound, q):
    """1/2 (q - q0)^T C (q - q0), the potential energy of the elastic pairs."""
    d = deformations(bound, q)
    acc = 0
    for x, f in zip(d, elastic_forces(bound, q)):
        if not (is_zero(x) or is_zero(f)):
            acc = acc + x * f
    return 0 if is_zero(acc) else bound.rational(1, 2) * acc


def fast_slow(model) -> tuple:
    """(slow, fast): coordinate indices of the non-elastic and the elastic motions, each in q order (Prop. 2.14)."""
    fast = list(model.elastic_coordinates)
    slow = [i for i in range(model.nv) if i not in set(fast)]
    return slow, fast


BLOCKS = (("A_pp", "A", "slow", "slow"), ("A_mp", "A", "slow", "fast"), ("A_pm", "A", "fast", "slow"),
          ("A_mm", "A", "fast", "fast"), ("B_pp", "B", "slow", "slow"), ("B_mp", "B", "slow", "fast"),
          ("B_pm", "B", "fast", "slow"), ("B_mm", "B", "fast", "fast"), ("C_mm", "C", "fast", "fast"))


def partition(bound, kin, qd) -> tuple:
    """The blocks of Prop. 2.14 in the order of :data:`BLOCKS`, each flattened row-major."""
    slow, fast = fast_slow(bound.model)
    groups = {"slow": slow, "fast": fast}
    mats = {"A": inertia_matrix(bound, kin), "B": coriolis_matrix(bound, kin, qd), "C": stiffness_matrix(bound)}
    return tuple([mats[m][i][j] for i in groups[rows] for j in groups[cols]] for _, m, rows, cols in BLOCKS)
