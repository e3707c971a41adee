"""The readers' fast number paths give exactly what SymPy's general ones give: ``float_number`` and ``double``
(aggsym.model.readers.sympy_numbers) against ``sp.Float`` and ``float``, and the URDF reader's tuple arithmetic
(aggsym.model.readers.link_numbers) against SymPy's ``Matrix`` operations, entry for entry (same value, same type, same
precision)."""
from __future__ import annotations

import math
import random

import sympy as sp

from aggsym.model.readers import link_numbers as ln
from aggsym.model.readers.sympy_numbers import double, float_number

EDGE_DOUBLES = [5e-324, -5e-324, 2.2250738585072014e-308, 1.7976931348623157e308, -1.7976931348623157e308, 0.1,
                1.0, -3.0, 2.0 ** 53, 2.0 ** 53 + 2, 1e15, 1e-15, 0.0, -0.0, math.inf, -math.inf]


def same(a, b) -> bool:
    """Same SymPy number: type, value, and for floats mantissa, exponent and precision."""
    return (type(a) is type(b) and a == b and getattr(a, "_mpf_", None) == getattr(b, "_mpf_", None)
            and getattr(a, "_prec", None) == getattr(b, "_prec", None))


def test_float_number_is_sympy_float():
    rng = random.Random(7)
    values = EDGE_DOUBLES + [rng.uniform(-10, 10) * 10.0 ** rng.randint(-300, 300) for _ in range(5000)]
    for v in values:
        assert same(float_number(v), sp.Float(v)), v


def test_double_is_float():
    rng = random.Random(8)
    numbers = [sp.Float(v) for v in EDGE_DOUBLES if math.isfinite(v)]
    numbers += [sp.Float(rng.uniform(-10, 10) * 10.0 ** rng.randint(-300, 300)) for _ in range(5000)]
    numbers += [sp.Integer(p) for p in (0, 1, -1, 2 ** 53 - 1, -(2 ** 53) + 1, 2 ** 53, 2 ** 53 + 1, 3 ** 40, 10 ** 400)]
    numbers += [sp.Float("0.1", 30), sp.Float("0.1", 10), sp.Float(0.0), sp.Rational(1, 3), sp.pi]
    for x in numbers:
        a, b = float(x), double(x)
        assert a == b and math.copysign(1, a) == math.copysign(1, b), x


def _entry(rng):
    """Entries as the reader meets them: exact 0, +-1, integers, and floats (some cancelling)."""
    kind = rng.random()
    if kind < 0.3:
        return sp.S.Zero
    if kind < 0.45:
        return rng.choice([sp.S.One, sp.S.NegativeOne])
    if kind < 0.55:
        return sp.Integer(rng.randint(-3, 3))
    return sp.Float(rng.choice([0.5, -0.5, 0.25, rng.uniform(-2, 2)]))


def _matrix(rng):
    return tuple(tuple(_entry(rng) for _ in range(3)) for _ in range(3))


def _rows(M) -> tuple:
    return tuple(tuple(M[i, j] for j in range(M.cols)) for i in range(M.rows))


def test_matrix_operations_match_sympy_matrix():
    rng = random.Random(9)
    for _ in range(400):
        a, b = _matrix(rng), _matrix(rng)
        v, w = tuple(_entry(rng) for _ in range(3)), tuple(_entry(rng) for _ in range(3))
        for got, want in ((ln.matvec(a, v), tuple(sp.Matrix(a) * sp.Matrix(v))),
                          (ln.add(v, w), tuple(sp.Matrix(v) + sp.Matrix(w)))):
            assert all(same(x, y) for x, y in zip(got, want)), (a, v, w, got, want)
        # product and turn: the sum of the non-zero products (SymPy's Add of them), as the reader always formed it
        rows, cols = a, tuple(zip(*b))
        want = tuple(tuple(sp.Add(*[x * y for x, y in zip(r, c) if x is not sp.S.Zero and y is not sp.S.Zero])
                           for c in cols) for r in rows)
        assert all(same(x, y) for x, y in zip(sum(ln.product(a, b), ()), sum(want, ()))), (a, b)
        want_v = tuple(sp.Add(*[x * y for x, y in zip(r, v) if x is not sp.S.Zero and y is not sp.S.Zero])
                       for r in rows)
        assert all(same(x, y) for x, y in zip(ln.turn(a, v), want_v))


def test_rotation_matrix_matches_elementary_rotations():
    from aggsym.model.types import _snap, elementary_rotation

    rng = random.Random(10)
    angles = [sp.S.Zero, sp.pi / 2, sp.pi, -sp.pi / 2, sp.Float(0.3), sp.Float(-1.2), sp.Float(2.5)]
    for _ in range(100):
        rotation = [(rng.randint(1, 3), rng.choice(angles)) for _ in range(rng.randint(0, 4))]
        want = sp.eye(3)
        for axis, angle in rotation:
            want = want * elementary_rotation(axis, angle)
        got = ln.rotation_matrix(rotation)
        want = want.applyfunc(_snap)
        for i in range(3):
            for j in range(3):
                assert abs(float(got[i][j]) - float(want[i, j])) < 1e-15, (rotation, got, want)
                if not isinstance(want[i, j], sp.Float):  # exact entries stay exact
                    assert got[i][j] == want[i, j]
