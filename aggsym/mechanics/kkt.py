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

from .bound import bind
from .constraints import ConstraintKinematics, _delassus, _projected, _transpose_times
from .damped import delassus_solver
from .linalg import dot, mul
from .transvective import apply_T, apply_T_transpose, apply_T_transpose_tree, apply_T_tree, articulated_factors


def arguments_pay(bound, kin, columns: int) -> bool:
    """Whether ``columns`` solves on one configuration take fewer operations with T applied through its arguments
    (formed once) than on the tree: on floats no (nothing to save); on a straight-line program both forms of
    ``T^T T f`` are counted for one and for two generic columns on one scratch program of the model (its
    kinematics and factors built once), so that ``cost(c) = cost(1) + (c - 1) (cost(2) - cost(1))`` holds the
    arguments' formation in the first and the per-column cost in the difference (Talos on its soles, 3n = 114
    columns: 286,000 operations against 317,000 for the constrained derivatives; solo12 88,000 against 93,000;
    Panda 26,000 against 30,000; a long unbranched chain, whose arguments grow as n^2, the other way)."""
    if not bound.backend.symbolic:
        return False
    backend = type(bound.backend)()
    scratch = bind(bound.model, backend, tree=bound.tree)
    program = backend.program
    try:
        k = type(kin)(scratch, program.vector("q", len(kin.q)))
        n = k.tree.nv
        fac = articulated_factors(scratch, k, arguments=True)
        f = [program.vector("tau", n), program.vector("qd", n)]

        def count(solve, c):
            seen = set()
            reached = [i for x in f[:c] for i in program.reach(solve(x), seen)]
            return sum(1 for i in reached if program.ops[i][0] not in ("in", "neg"))

        def by_arguments(x):
            return apply_T_transpose(fac, apply_T(fac, x))

        def on_tree(x):
            return apply_T_transpose_tree(k, fac, apply_T_tree(k, fac, x))

        cost = {}
        for name, solve in (("arguments", by_arguments), ("tree", on_tree)):
            one, two = count(solve, 1), count(solve, 2)
            cost[name] = one + (columns - 1) * (two - one)
    finally:
        program.release()
    return cost["arguments"] < cost["tree"]


class ConstrainedSystem:
    """J, the factors of A, P = T J^T and the factored G of one configuration (``kin``).

    ``arguments``: T and T^T applied through the arguments <t,k> (3.8)-(3.10), formed once (one multiply-add per
    transvection and column), instead of the 6-vectors summed on the tree (O(n) per column, nothing formed
    beforehand): the same values, the first cheaper where many columns share the arguments."""

    def __init__(self, bound, kin, arguments: bool = False):
        self.bound, self.kin = bound, kin
        self.ck = ConstraintKinematics(bound, kin)
        self.J = self.ck.jacobian()
        self.fac = articulated_factors(bound, kin, arguments=arguments)
        if arguments:
            self._T = lambda f: apply_T(self.fac, f)
            self._Tt = lambda z: apply_T_transpose(self.fac, z)
        else:
            self._T = lambda f: apply_T_tree(kin, self.fac, f)
            self._Tt = lambda z: apply_T_transpose_tree(kin, self.fac, z)
        self.P = [self._T(row) for row in self.J] if arguments else _projected(kin, self.fac, self.J)
        self.solver = delassus_solver(bound, _delassus(self.fac, self.P))
        self.status = self.solver.status

    def solve_transvected(self, y, h) -> tuple:
        """(x, lambda) for y = T f already formed."""
        Dy = [mul(r, v) for r, v in zip(self.fac.recip, y)]
        lam = self.solver.solve([hi - dot(p, Dy) for hi, p in zip(h, self.P)])
        y = list(y)
        for p, l in zip(self.P, lam):
            y = [a + mul(b, l) for a, b in zip(y, p)]
        x = self._Tt([mul(r, v) for r, v in zip(self.fac.recip, y)])
        return x, lam

    def solve(self, f, h) -> tuple:
        """(x, lambda) of A x - J^T lambda = f, J x = h (f: n entries, h: m entries)."""
        return self.solve_transvected(self._T(f), h)

    def joint_space(self, lam) -> list:
        """J^T lambda (n entries)."""
        if not self.J:
            return [0] * self.kin.tree.nv
        return _transpose_times(self.J, lam)


__all__ = ["ConstrainedSystem"]
