"""Exact coefficients of the base parameters: the regressor's straight-line program evaluated in rational
arithmetic at rational states, and each dependent column solved exactly as a combination of independent ones.

The base parameters are pi_b = pi[independent] + beta pi[dependent] (:func:`~.analyses.base_parameters`); beta is
what identification reports, so it is computed, never a least-squares value rounded to some digits.

* Rational states: a revolute coordinate enters the regressor only through its sine and cosine; at a rational
  point of the unit circle, (sin, cos) = (2t, 1 - t^2) / (1 + t^2), both are rational.  Rates, accelerations,
  translations, a free-flyer's unit quaternion (2v, 1 - |v|^2) / (1 + |v|^2), the time (0, as the numeric
  analyses take it) and the parameters' defaults are rational too, and the model's constants are doubles, i.e.
  dyadic rationals, kept as Fractions while the program is recorded (:class:`~aggsym.core.backend.ExactSymbolic`:
  constants folded without rounding): every value of the program is then the exact value of the model's
  equations at that state (:func:`exact_rows`).  An irrational root (a constant such as sqrt(3)) is the double
  the generated code computes; a program that needs anything else (a sine of another expression) raises
  :class:`Inexact`, and every relation is then judged on the floating-point samples alone.
* Coefficients (:func:`exact_coefficients`): the support of a dependent column (the independent columns it
  combines) is chosen from the floating-point least squares by a tolerance; on it, the square system of the exact
  rows that a pivoted QR picks is solved in rationals (first modulo a large prime and reconstructed, else by
  exact Gaussian elimination), and the relation is checked on every exact row: exact when every residual is
  exactly 0.
* Relations that are not exact: where the model's numbers are not exactly those of a rigid-body system (a
  constant rotation by an angle that is not right has rounded cosine and sine: UR5's 1.570796325 rad), a column
  has no exact relation and there is no exact value to compute.  It is reported with its residual on the
  floating-point samples, and keeps the first of the exact solution of the chosen rows, the least squares on its
  support, whose residual is below :data:`INEXACT_RESIDUAL`, else the least squares on every independent column.

The tolerances choose (the support, the rows, which solution); they replace no value.
"""
from __future__ import annotations

import math
from fractions import Fraction

SUPPORT_TOLERANCE = 1e-10  # a term of the least-squares relation below this times the largest is taken for a
# structural zero (its coefficient for the rounding of the least squares)
INEXACT_RESIDUAL = 1e-9  # a relation that is not exact keeps a solution on its support when the residual on the
# samples (relative to the largest column) is below this, else the least squares on every independent column


class Inexact(ArithmeticError):
    """The program needs a value that is not rational at a rational state."""


class _Angle:
    """A revolute coordinate at a rational point of the unit circle: its exact sine and cosine, nothing else."""

    __slots__ = ("sin", "cos")

    def __init__(self, t: Fraction):
        d = 1 + t * t
        self.sin, self.cos = 2 * t / d, (1 - t * t) / d


def _sqrt(x):
    """The exact root of a rational square; of any other rational, the double the generated code computes (its
    relations are then judged as not exact)."""
    if not isinstance(x, (int, Fraction)) or x < 0:
        raise Inexact("sqrt of a negative or non-rational value")
    x = Fraction(x)
    n, d = math.isqrt(x.numerator), math.isqrt(x.denominator)
    if n * n != x.numerator or d * d != x.denominator:
        return Fraction(math.sqrt(float(x)))
    return Fraction(n, d)


def _apply(code, *x):
    """One operation of the program in rational arithmetic."""
    if code in ("sin", "cos"):
        a = x[0]
        if isinstance(a, _Angle):
            return a.sin if code == "sin" else a.cos
        if a == 0:  # (the time t = 0 of a prescribed spin)
            return Fraction(0) if code == "sin" else Fraction(1)
        raise Inexact(f"{code} of a value that is not a coordinate")
    if code == "sqrt":
        return _sqrt(x[0])
    if code == "sign":
        return Fraction((x[0] > 0) - (x[0] < 0))
    if any(isinstance(a, _Angle) for a in x):
        raise Inexact("a revolute coordinate used other than through its sine and cosine")
    if code == "+":
        return x[0] + x[1]
    if code == "-":
        return x[0] - x[1]
    if code == "*":
        return x[0] * x[1]
    if code == "/":
        return x[0] / x[1]
    if code == "neg":
        return -x[0]
    raise Inexact(f"the function {code}")


def _rational(rng, high: int = 5) -> Fraction:
    """A non-zero rational of small height (numerator and denominator up to ``high``) and random sign: small
    numbers keep the exact arithmetic short."""
    n = int(rng.integers(1, high + 1)) * (1 if rng.integers(0, 2) else -1)
    return Fraction(n, int(rng.integers(1, high + 1)))


def _state(model, tree, rng) -> dict:
    """Rational inputs: q (angles as :class:`_Angle`), qd, qdd."""
    q = [None] * model.nq
    for body, idx in zip(model.bodies, tree.positions):
        if body.pair.quaternion:
            v = [_rational(rng) / 4 for _ in range(3)]
            norm2 = sum(a * a for a in v)
            position = [_rational(rng) for _ in range(3)]
            quaternion = [2 * a / (1 + norm2) for a in v] + [(1 - norm2) / (1 + norm2)]  # exactly unit
            for i, x in zip(idx, position + quaternion):
                q[i] = x
            continue
        for c, i in zip(body.pair.coordinates, idx):
            q[i] = _Angle(_rational(rng)) if c.kind == "rotation" else _rational(rng)
    return {"q": q, "qd": [_rational(rng, 1) * int(rng.integers(1, 6)) for _ in range(model.nv)],
            "qdd": [_rational(rng, 1) * int(rng.integers(1, 6)) for _ in range(model.nv)]}


def exact_rows(model, role: str, count: int, seed: int) -> list:
    """The routine ``role`` (the regressor or the regressor with drives, n x P) at ``count`` rational states as
    exact rows: a list of count * n lists of P Fractions (states in turn, each its n rows)."""
    import numpy as np

    from ..core.backend import ExactSymbolic
    from ..mechanics.bound import bind
    from ..mechanics.kinematics import TreeKinematics
    from .registry import ROUTINES, input_length, run, signature

    routine = ROUTINES[role]
    backend = ExactSymbolic()
    prog = backend.program
    bound = bind(model, backend)
    x = {k: prog.vector(k, input_length(model, k, routine)) for k in signature(routine, model) if k not in ("p", "t")}
    flat = run(routine, bound, x, TreeKinematics(bound, x["q"]))[0]
    n = model.nv
    P = len(flat) // n if n else 0
    rng = np.random.default_rng(seed)
    params = [Fraction(float(v)) for v in model.parameter_values]
    rows = []
    for _ in range(count):
        state = _state(model, bound.tree, rng)

        def leaf(kind, i, state=state):
            if kind == "p":
                return params[i]
            if kind == "t":
                return Fraction(0)
            return state[kind][i]

        try:
            values = prog.interpret(flat, leaf, _apply, Fraction)
        except TypeError as e:  # (an _Angle met Python arithmetic through a constant operand)
            raise Inexact(str(e)) from None
        rows.extend([values[i * P:(i + 1) * P] for i in range(n)])
    return rows


def _solve(A: list, B: list):
    """X with A X = B for a square matrix of Fractions and right-hand sides B (rows of values, one per right-hand
    side), by Gaussian elimination with exact pivots skipping zero entries; None when A is singular."""
    size = len(A)
    M = [list(row) + list(b) for row, b in zip(A, B)]
    width = len(M[0]) if M else 0
    for c in range(size):
        pivot = next((r for r in range(c, size) if M[r][c] != 0), None)
        if pivot is None:
            return None
        M[c], M[pivot] = M[pivot], M[c]
        top = M[c]
        nonzero = [k for k in range(c + 1, width) if top[k] != 0]
        for r in range(c + 1, size):
            row = M[r]
            if row[c] != 0:
                f = row[c] / top[c]
                for k in nonzero:
                    row[k] -= f * top[k]
    X = [[Fraction(0)] * (width - size) for _ in range(size)]
    for r in range(size - 1, -1, -1):
        row = M[r]
        for k in range(width - size):
            value = row[size + k]
            for j in range(r + 1, size):
                if row[j] != 0:
                    value -= row[j] * X[j][k]
            X[r][k] = value / row[r]
    return X


MODULUS = 2 ** 521 - 1  # a Mersenne prime: the candidate solutions are found modulo it


def _modular_candidate(A: list, B: list):
    """A candidate for X with A X = B (Fractions): the solution modulo :data:`MODULUS` turned back into
    rationals by rational reconstruction (numerators and denominators below about 2^260: the model's coefficients,
    products of a few doubles, are).  None when that fails; a candidate is only a candidate until it is verified
    exactly (:func:`exact_coefficients`)."""
    P = MODULUS
    size, width = len(A), len(B[0]) if B else 0
    M = [[v.numerator * pow(v.denominator, -1, P) % P for v in list(row) + list(b)] for row, b in zip(A, B)]
    for c in range(size):
        pivot = next((r for r in range(c, size) if M[r][c]), None)
        if pivot is None:
            return None
        M[c], M[pivot] = M[pivot], M[c]
        inv = pow(M[c][c], -1, P)
        top = M[c] = [v * inv % P for v in M[c]]
        for r in range(size):
            if r != c and M[r][c]:
                f = M[r][c]
                M[r] = [(a - f * b) % P for a, b in zip(M[r], top)]
    out = [[None] * width for _ in range(size)]
    for r in range(size):
        for k in range(width):
            value = _reconstruct(M[r][size + k], P)
            if value is None:
                return None
            out[r][k] = value
    return out


def _reconstruct(a: int, m: int):
    """The fraction n/d with n = a d (mod m) and |n|, d below sqrt(m/2), or None (Wang's rational reconstruction)."""
    bound = math.isqrt(m // 2)
    r0, r1, s0, s1 = m, a % m, 0, 1
    while r1 > bound:
        q = r0 // r1
        r0, r1, s0, s1 = r1, r0 - q * r1, s1, s0 - q * s1
    if s1 == 0 or abs(s1) > bound:
        return None
    return Fraction(r1, s1)


def _residual_is_zero(rows, support, d, x) -> bool:
    for row in rows:
        value = row[d]
        for j, xj in zip(support, x):
            if row[j]:
                value -= row[j] * xj
        if value != 0:
            return False
    return True


def candidate_supports(beta, independent, dependent, Y) -> list:
    """Per dependent column (of the least-squares ``beta``, r x d, on the samples ``Y``) its support: the
    independent columns (indices into the regressor) whose term |beta_jd| |Y_j| is above :data:`SUPPORT_TOLERANCE`
    times |Y_d| (the others are the rounding of the least squares)."""
    import numpy as np

    norms = np.linalg.norm(Y, axis=0)
    out = []
    for k in range(beta.shape[1]):
        terms = np.abs(beta[:, k]) * norms[list(independent)]
        scale = max(float(norms[dependent[k]]), float(terms.max()) if terms.size else 0.0)
        out.append([independent[r] for r in range(len(independent)) if terms[r] > SUPPORT_TOLERANCE * scale])
    return out


def exact_coefficients(rows: list, Y, independent, dependent, beta) -> tuple:
    """(beta, r x d lists of Fractions where exact and floats elsewhere; the dependent columns whose relation is
    not exact; the largest residual of those on the floating-point samples ``Y``, relative to Y's largest column).  Each dependent column
    is solved in rationals on its support (:func:`candidate_supports`, ``rows`` the exact rows) and kept where the
    relation holds exactly on every exact row (``rows`` None: no exact rows, every column judged on the samples).
    A column without an exact relation has no exact value to compute: it keeps the first of the exact solution of
    the chosen rows, the least squares on its support, whose residual on the samples is below
    :data:`INEXACT_RESIDUAL` times Y's largest column, else the least squares on every independent column."""
    import numpy as np

    floats = np.array([[float(v) for v in row] for row in rows], dtype=float) if rows else None
    scale = max(float(np.linalg.norm(Y, axis=0).max()) if Y.size else 0.0, 1e-300)
    position = {j: r for r, j in enumerate(independent)}
    out = [[Fraction(0)] * len(dependent) for _ in independent]
    groups: dict = {}  # the dependent columns of one support are solved together
    for k, support in enumerate(candidate_supports(beta, independent, dependent, Y)):
        groups.setdefault(tuple(support), []).append(k)
    inexact, worst = [], 0.0

    def residual(d, support, x):
        x = np.array([float(v) for v in x])
        return float(np.linalg.norm(Y[:, d] - (Y[:, list(support)] @ x if len(support) else 0.0))) / scale

    for support, ks in groups.items():
        xs, exact = [[] for _ in ks], [rows is not None] * len(ks)
        if support and rows is not None:
            picked = pivoted_columns(floats[:, list(support)].T)[:len(support)]
            A = [[rows[i][j] for j in support] for i in picked]
            B = [[rows[i][dependent[k]] for k in ks] for i in picked]
            X = _modular_candidate(A, B) or _solve(A, B)  # (the second: large numbers, or no exact relation)
            if X is None:
                xs, exact = [None] * len(ks), [False] * len(ks)
            else:
                xs = [[X[r][n] for r in range(len(support))] for n in range(len(ks))]
        if rows is not None:
            exact = [holds and _residual_is_zero(rows, support, dependent[k], x)
                     for k, x, holds in zip(ks, xs, exact)]
        for k, x, holds in zip(ks, xs, exact):
            d = dependent[k]
            if not holds:
                inexact.append(d)
                # the first of: the exact solution of the chosen rows, the least squares on the support, the least
                # squares on every independent column, whose residual on the samples is below INEXACT_RESIDUAL
                local = np.linalg.lstsq(Y[:, list(support)], Y[:, d], rcond=None)[0] if support else []
                tried = ([(support, x)] if x is not None and rows is not None else []) + [(support, list(local))]
                for candidate, values in tried:
                    size = residual(d, candidate, values)
                    if size <= INEXACT_RESIDUAL:
                        support, x = candidate, values
                        break
                else:
                    support, x = list(independent), list(beta[:, k])
                    size = residual(d, support, x)
                worst = max(worst, size)
            for j, v in zip(support, x):
                out[position[j]][k] = v
    return out, sorted(inexact), worst


def pivoted_columns(Y) -> list:
    """The column order of a Householder QR factorization of Y with column pivoting (at each step the column of
    largest norm in the remaining rows first): its first r entries are r well-conditioned independent columns."""
    import numpy as np

    R = np.array(Y, dtype=float, copy=True)
    rows, cols = R.shape
    order = list(range(cols))
    for k in range(min(rows, cols)):
        norms = np.einsum("ij,ij->j", R[k:, k:], R[k:, k:])
        j = k + int(np.argmax(norms))
        R[:, [k, j]] = R[:, [j, k]]
        order[k], order[j] = order[j], order[k]
        x = R[k:, k]
        alpha = -np.copysign(np.linalg.norm(x), x[0]) if x[0] != 0 else -np.linalg.norm(x)
        v = x.copy()
        v[0] -= alpha
        vv = v @ v
        if vv > 0:
            R[k:, k:] -= np.outer(v, (2.0 / vv) * (v @ R[k:, k:]))
    return order


__all__ = ["Inexact", "SUPPORT_TOLERANCE", "candidate_supports", "exact_coefficients", "exact_rows",
           "pivoted_columns"]
