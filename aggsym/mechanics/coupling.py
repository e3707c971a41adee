"""Coordinates tied to others (URDF ``<mimic>`` joints loaded with ``mimic="couple"``): the contract's routines of
the remaining coordinates, computed on the whole tree.

A coupled coordinate ``q_d = k q_m + o`` leaves q.  With J the n_tree x n matrix of ``q_tree = J q + o`` (the unit
columns of q's coordinates, and k at row d of column m):

* inputs expand: ``q_tree = J q + o``, ``q'_tree = J q'``, ``q''_tree = J q''``; the forces ``tau_tree`` are tau on
  q's coordinates and 0 on the coupled ones (a coupled joint is driven by the coupling, not by an actuator);
* generalized forces reduce by J^T (b, g, d, tau, c): their virtual work along q; A reduces to J^T A J; the energies
  and the joint wrenches are the tree's;
* q'' is the tree's under the coupling, a holonomic constraint ``C q''_tree = 0`` with the rows ``e_d - k e_m`` of C:
  as with the constraints of chapter 4 ((4.1)-(4.7)), ``A q''_tree = tau_tree - d + C^T lambda``, so
  ``q''_tree = a0 + Y lambda`` with ``a0 = A^-1 (tau_tree - d)``, ``Y = A^-1 C^T`` (each column by the transvective
  Cauchy form (3.20) in O(n)) and ``(C Y) lambda = -C a0``, a small dense system; q'' is q's part of q''_tree;
* ``A_q^-1`` is q's block of ``A^-1 - Y (C Y)^-1 Y^T`` (which equals ``J (J^T A J)^-1 J^T``).

The transvective factors and the elastic partition belong to the tree; they are not emitted for coupled models.
"""
from __future__ import annotations

from . import passive, transvective


class Coupler:
    """The map between q and the tree's coordinates for a model with couplings."""

    def __init__(self, model, tree):
        index = {c.name: i for i, c in enumerate(model.pair_coordinates)}
        self.n_tree = tree.nv
        self.free = [index[c.name] for c in model.coordinates]  # q's coordinates in the tree
        position = {t: i for i, t in enumerate(self.free)}
        self.coupled = [(index[c.coordinate], position[index[c.master]], index[c.master], c.multiplier, c.offset)
                        for c in model.couplings]  # (tree index d, q index of m, tree index of m, k, offset)

    def expand(self, x: dict) -> dict:
        """Tree vectors from q's: q_tree = J q + o, q'_tree = J q', q''_tree = J q'', tau_tree = (tau, 0)."""
        out = {}
        for kind, v in x.items():
            if kind == "t":
                out[kind] = v
                continue
            full = [0] * self.n_tree
            for i, t in enumerate(self.free):
                full[t] = v[i]
            if kind != "tau":
                for d, m, _, k, offset in self.coupled:
                    full[d] = k * v[m] + (offset if kind == "q" else 0)
            out[kind] = full
        return out

    def reduce(self, v: list) -> list:
        """J^T v for a vector of generalized forces on the tree."""
        out = [v[t] for t in self.free]
        for d, m, _, k, _ in self.coupled:
            out[m] = out[m] + k * v[d]
        return out

    def reduce_matrix(self, M: list) -> list:
        """J^T M J for an n_tree x n_tree matrix given as rows."""
        rows = [self.reduce(col) for col in zip(*M)]  # (J^T M)^T's rows are J^T applied to M's columns
        return [self.reduce(list(r)) for r in zip(*rows)]

    def constraint_columns(self) -> list:
        """The columns of C^T: e_d - k e_m for every coupling."""
        cols = []
        for d, _, m_tree, k, _ in self.coupled:
            col = [0] * self.n_tree
            col[d] = 1
            col[m_tree] = -k
            cols.append(col)
        return cols

    def apply_C(self, v: list) -> list:
        return [v[d] - k * v[m_tree] for d, _, m_tree, k, _ in self.coupled]

    def forward_dynamics(self, bound, kin, x: dict) -> list:
        """q'' under the coupling: the constraint form above, with A^-1 applied by (3.20) in O(n)."""
        c = passive.left_forces(bound, kin.q, x["qd"])
        a0 = transvective.forward_dynamics(bound, kin, [t - ci for t, ci in zip(x["tau"], c)], x["qd"])
        fac = transvective.articulated_factors(bound, kin, arguments=False)
        Y = [transvective.cauchy_solve_tree(kin, fac, col) for col in self.constraint_columns()]
        S = [self.apply_C(y) for y in Y]  # S[j][i] = (C Y)_ij; C Y is symmetric
        lam = solve_small(S, [-r for r in self.apply_C(a0)])
        qdd = list(a0)
        for y, l in zip(Y, lam):
            qdd = [a + l * b for a, b in zip(qdd, y)]
        return [qdd[t] for t in self.free]

    def inertia_inverse(self, bound, kin) -> list:
        """A_q^-1: q's block of A^-1 - Y (C Y)^-1 Y^T, rows."""
        inv = transvective.inertia_inverse(bound, kin)
        Y = [[inv[r][d] - k * inv[r][m_tree] for r in range(self.n_tree)] for d, _, m_tree, k, _ in self.coupled]
        S = [self.apply_C(y) for y in Y]
        n = len(self.coupled)
        Sinv = [solve_small(S, [1 if i == j else 0 for i in range(n)]) for j in range(n)]  # columns of S^-1
        out = []
        for a in self.free:
            row = []
            for b in self.free:
                corr = 0
                for i in range(n):
                    for j in range(n):
                        corr = corr + Y[i][a] * Sinv[j][i] * Y[j][b]
                row.append(inv[a][b] - corr)
            out.append(row)
        return out


def solve_small(S: list, r: list) -> list:
    """x with S x = r for a small symmetric positive definite S (Gaussian elimination, pivots on the diagonal)."""
    n = len(r)
    M = [list(S[i]) + [r[i]] for i in range(n)]
    for k in range(n):
        for i in range(k + 1, n):
            f = M[i][k] / M[k][k]
            M[i] = [a - f * b for a, b in zip(M[i], M[k])]
    x = [0] * n
    for i in range(n - 1, -1, -1):
        acc = M[i][n]
        for j in range(i + 1, n):
            acc = acc - M[i][j] * x[j]
        x[i] = acc / M[i][i]
    return x
