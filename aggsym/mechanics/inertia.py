"""The inertia matrix A(q) = S A S^T: by composite bodies (2.32)-(2.34), and by S diag(Theta) S^T (2.30).

A model's armature (a rotor inertia on every coordinate, as Pinocchio's) adds to the diagonal.

Composite bodies (Prop. 2.16, 2.17): ``A+_lk = Theta_lk + sum over children L A+_child L^T`` (2.32),
``beta_lk = A+_lk M F`` (2.33), and the entry of rows st-alpha and columns lk-beta is ``s^{st-alpha}_{lk} beta``
when lk is in (st)+ (2.34), computed by carrying ``beta`` towards the root with the wrench motions L.
"""
from __future__ import annotations

from ..core.program import is_zero
from .linalg import dot
from .tendon_armature import add_to_inertia


def composite_inertias(bound, kin):
    """A+_lk for every body (2.32); None for a subtree without mass."""
    plus = [b.mises for b in bound.bodies]
    for k in range(len(plus) - 1, -1, -1):
        p = kin.tree.parent[k]
        if p >= 0 and plus[k] is not None:
            moved = kin.move_to_parent(k, plus[k])
            plus[p] = moved if plus[p] is None else plus[p] + moved
    return plus


def inertia_matrix(bound, kin, plus=None):
    """A(q) by (2.33)-(2.34), as an n x n list of rows (O(n d) blocks, d the tree depth)."""
    tree = kin.tree
    n = tree.nv
    A = [[0] * n for _ in range(n)]
    plus = composite_inertias(bound, kin) if plus is None else plus
    for k in range(len(tree)):
        if plus[k] is None:
            continue
        for j, col in zip(tree.coords[k], kin.psi[k]):
            beta = plus[k].apply(col)  # (2.33)
            for i, row in zip(tree.coords[k], kin.psi[k]):
                if i <= j:
                    A[i][j] = A[j][i] = dot(row, beta)
            a = k
            while tree.parent[a] >= 0:
                beta = kin.L[a].wrench(beta)  # s^{st}_{lk} beta = Psi_st^T L^{st}_{lk} beta
                a = tree.parent[a]
                for i, row in zip(tree.coords[a], kin.psi[a]):
                    A[i][j] = A[j][i] = dot(row, beta)
    return with_armature(bound, A)


def with_armature(bound, A):
    """A + armature E (plus each coordinate's own rotor inertia, ``model.dof_armature``, and the fixed tendons'
    armature a c c^T, :mod:`.tendon_armature`)."""
    if bound.has_rotors:
        for i in range(len(A)):
            if not is_zero(bound.rotor(i)):
                A[i][i] = A[i][i] + bound.rotor(i)
    if bound.model.tendons:
        A = add_to_inertia(bound, A)
    return A


def inertia_matrix_sas(bound, kin):
    """A(q) = S diag(Theta) S^T term by term (2.30): sum over common descendants p of s_p Theta_p s_p^T."""
    S = kin.parastrophic()
    n = len(S)
    A = [[0] * n for _ in range(n)]
    for i in range(n):
        for j in range(i, n):
            acc = 0
            for p, body in enumerate(bound.bodies):
                if body.mises is None or S[i][p] is None or S[j][p] is None:
                    continue
                acc = acc + dot(S[i][p], body.mises.apply(S[j][p]))
            A[i][j] = A[j][i] = acc
    return with_armature(bound, A)
