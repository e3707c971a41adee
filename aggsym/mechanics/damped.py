"""The Delassus system ``G x = b`` of the constrained dynamics (chapter 4), solved exactly or damped.

``G = J A^-1 J^T`` (plus the model's explicit ``regularization`` epsilon E, (4.25)-(4.28)) is factored once as
L D L^T (no pivoting: G is symmetric positive semidefinite) and reused for every right-hand side: the
multipliers of the constrained forward dynamics or of an impact, and the 2n or 3n columns of their derivatives.

Exact solve (the default): ``x = G^-1 b``; the status counts the pivots below ``SINGULAR * trace(G) / m``
(nonzero: G singular, redundant or not finite; the outputs then hold no NaN only by the caller's guard).

Damped solve (``proximal: {mu, iterations}`` of the model, Pinocchio's ``ProximalSettings(accuracy, mu,
max_iter)`` without its convergence test): the proximal-point iteration

    x_0 = 0,    (G + mu E) x_{k+1} = b + mu x_k,    k = 0 .. N-1

with a fixed N and G + mu E factored once, so the program is straight-line and never divides by anything
smaller than mu (every pivot of G + mu E is at least mu when G is positive semidefinite).  Stated bounds, with
``rho = mu / (sigma_min(G) + mu)``:

* J of full row rank (G regular): ``|x_N - G^-1 b| <= rho^N |G^-1 b|``, exact to rounding once rho^N is below
  the precision (e.g. mu = 1e-9 times the smallest eigenvalue and N = 2);
* G singular and b in its range (redundant rows with consistent right-hand sides): x_N tends to the minimum-norm
  solution, ``|x_N| <= |G^+ b|``, and the error along the range is as above with the smallest nonzero eigenvalue;
* any b: ``|x_N| <= N |b| / mu`` (each step adds at most |b| / mu and damps the rest by ``mu (G + mu E)^-1``,
  whose norm is at most 1).

The damped status counts the pivots of ``G + mu E`` not above mu / 2: zero unless some entry is not finite.
"""
from __future__ import annotations

from ..core.program import is_zero
from .linalg import ldl_factor, mul

SINGULAR = 1e-12  # as aggsym.mechanics.constraints.SINGULAR: an exact pivot below SINGULAR * trace(G) / m is singular


def _sign_count(backend, tol, pivots):
    """The number of pivots not above tol, counted branch-free by sign() (a NaN pivot counts)."""
    status = 0
    for d in pivots:
        status = status + (backend.call("sign", tol - d) + 1)
    return status


class DelassusSolver:
    """G (m x m rows, symmetric) factored once; :meth:`solve` applies the exact or the damped inverse.

    ``proximal``: None (exact) or (mu, iterations) as backend scalar and int."""

    def __init__(self, G, backend, proximal=None):
        self.backend, self.m = backend, len(G)
        self.mu, self.iterations = (None, 0) if proximal is None else proximal
        if self.mu is not None:
            G = [[g + self.mu if i == j else g for j, g in enumerate(row)] for i, row in enumerate(G)]
        self.L, self.d = ldl_factor(G)
        self.recip = [1 / d for d in self.d]
        if self.mu is None:
            trace = 0
            for j in range(self.m):
                trace = trace + G[j][j]
            self.status = _sign_count(backend, trace * (SINGULAR / self.m), self.d) if self.m else 0
        else:
            self.status = _sign_count(backend, self.mu * backend.rational(1, 2), self.d) if self.m else 0

    def _apply(self, b):
        """(L D L^T)^-1 b."""
        m, L = self.m, self.L
        y = list(b)
        for i in range(m):
            for k in range(i):
                y[i] = y[i] - mul(L[i][k], y[k])
        x = [mul(y[i], self.recip[i]) for i in range(m)]
        for i in range(m - 1, -1, -1):
            for k in range(i + 1, m):
                x[i] = x[i] - mul(L[k][i], x[k])
        return x

    def solve(self, b) -> list:
        """x = G^-1 b (exact), or the N-th proximal iterate from x_0 = 0 (damped)."""
        if self.mu is None:
            return self._apply(b)
        x = self._apply(b)  # x_1 (x_0 = 0)
        for _ in range(self.iterations - 1):
            x = self._apply([bi + mul(self.mu, xi) for bi, xi in zip(b, x)])
        return x


def model_proximal(bound):
    """The model's damped-solve setting as (mu scalar, iterations), or None for the exact solve."""
    setting = bound.model.proximal
    if not setting:
        return None
    mu, iterations = setting
    return bound.scalar(mu), int(iterations)


def delassus_solver(bound, G, regularization=True) -> DelassusSolver:
    """The solver of the model's Delassus system: G plus the explicit regularization epsilon E (when the model
    has one), exact or damped by the model's ``proximal`` setting."""
    if regularization:
        eps = bound.scalar(bound.model.regularization)
        if not is_zero(eps):
            G = [[g + eps if i == j else g for j, g in enumerate(row)] for i, row in enumerate(G)]
    return DelassusSolver(G, bound.backend, model_proximal(bound))


__all__ = ["DelassusSolver", "delassus_solver", "model_proximal"]
