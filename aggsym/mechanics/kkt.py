"""The constrained system at one configuration (4.25)-(4.28), factored once and solved for any right-hand sides.

    A x - J^T lambda = f,    J x = h                 (the regularization: J x + epsilon lambda = h)

by the transvective factors (3.19), A^-1 = T^T D^-1 T: with ``P = T J^T`` (one O(n) product per row of J) and
``G = P^T D^-1 P`` (the Delassus matrix, :mod:`aggsym.mechanics.damped` factors it once, exactly or damped),

    y = T f,    G lambda = h - P^T D^-1 y,    x = T^T D^-1 (y + P lambda).

The constrained forward dynamics is this system with f = tau - b - g - c and h = -gamma - stabilization; an
impact (:mod:`aggsym.mechanics.impacts`) with f = 0 and h = -(1 + r) (J qd- + F); each column of their
derivatives (:mod:`aggsym.mechanics.constraint_derivatives`) is one more pair (f, h) on the same factors.
"""
from __future__ import annotations

from .constraints import ConstraintKinematics, _delassus, _projected, _transpose_times
from .damped import delassus_solver
from .linalg import dot, mul
from .transvective import apply_T_transpose_tree, apply_T_tree, articulated_factors


class ConstrainedSystem:
    """J, the factors of A, P = T J^T and the factored G of one configuration (``kin``)."""

    def __init__(self, bound, kin):
        self.bound, self.kin = bound, kin
        self.ck = ConstraintKinematics(bound, kin)
        self.J = self.ck.jacobian()
        self.fac = articulated_factors(bound, kin, arguments=False)
        self.P = _projected(kin, self.fac, self.J)
        self.solver = delassus_solver(bound, _delassus(self.fac, self.P))
        self.status = self.solver.status

    def solve_transvected(self, y, h) -> tuple:
        """(x, lambda) for y = T f already formed."""
        Dy = [mul(r, v) for r, v in zip(self.fac.recip, y)]
        lam = self.solver.solve([hi - dot(p, Dy) for hi, p in zip(h, self.P)])
        y = list(y)
        for p, l in zip(self.P, lam):
            y = [a + mul(b, l) for a, b in zip(y, p)]
        x = apply_T_transpose_tree(self.kin, self.fac, [mul(r, v) for r, v in zip(self.fac.recip, y)])
        return x, lam

    def solve(self, f, h) -> tuple:
        """(x, lambda) of A x - J^T lambda = f, J x = h (f: n entries, h: m entries)."""
        return self.solve_transvected(apply_T_tree(self.kin, self.fac, f), h)

    def joint_space(self, lam) -> list:
        """J^T lambda (n entries)."""
        if not self.J:
            return [0] * self.kin.tree.nv
        return _transpose_times(self.J, lam)


__all__ = ["ConstrainedSystem"]
