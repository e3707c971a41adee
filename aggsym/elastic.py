"""Hooke elasticity: the stiffness C of elastic pairs, the generalized elastic force C q and its energy,
(1.32)-(1.33), (2.27), Prop. 2.13.

An elastic pair (Def. 1.10) is a pair whose coordinates are deformations of the parent element; the model gives
its stiffness, a symmetric positive semi-definite k x k matrix over the pair's coordinates, and optionally the
rest position q0 (default 0).  C is block diagonal over the pairs, and the equations (2.27) read

    A(q) q'' + b(q, q') + g(q) + C (q - q0) = tau,

the elastic generalized force on the left beside gravity, with the energy ``1/2 (q - q0)^T C (q - q0)`` added to
the potential energy.  Sign convention: C is the stiffness itself (positive), so C (q - q0) on the left is a
restoring force.  (The book's example after (2.28) prints C = -[[c22, c25, 0], [c52, c55, 0], [0, 0, 0]] and
the terms "- c22 delta12 - c25 delta15" on the left; there c_ij are the coefficients of the elastic wrench acting
on the body, i.e. minus our stiffness, see ``tests/test_elastic.py``.)
"""
from __future__ import annotations

from .codegen.program import is_zero


def is_elastic(model) -> bool:
    """True when some pair of the model has a stiffness."""
    return any(b.pair.elastic for b in model.bodies)


def stiffness_matrix(bound) -> list:
    """C as n x n rows of backend scalars: block diagonal over the elastic pairs (2.27)."""
    tree = bound.tree
    n = tree.nq
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
    out = [0] * bound.tree.nq
    for k, body in enumerate(bound.bodies):
        if body.stiffness is None:
            continue
        for i, r in zip(bound.tree.coords[k], body.rest):
            out[i] = q[i] - r
    return out


def elastic_forces(bound, q) -> list:
    """C (q - q0), the generalized elastic force on the left side of (2.27): n scalars (0 off elastic pairs)."""
    tree = bound.tree
    d = deformations(bound, q)
    out = [0] * tree.nq
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
