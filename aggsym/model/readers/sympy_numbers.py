"""SymPy numbers from the doubles of a model file and back, without SymPy's general conversions.

The readers make a SymPy number of every number of a file and take the double of many of them again to validate
(a 2000-body chain: some 30,000 each way).  ``sp.Float(x)`` and ``float(e)`` go through SymPy's general
constructors (strings, decimals, tuples, NumPy types); these go straight to mpmath for a double, and give the
same numbers: the same mantissa, exponent and precision (53 bits), the same double back (tested).
"""
from __future__ import annotations

import math

import sympy as sp
from mpmath.libmp import from_float, round_nearest, to_float

PRECISION = 53  # the binary precision of Float(x) for a double x (15 decimal digits)


def float_number(value: float) -> sp.Expr:
    """``sp.Float(value)``: for a finite non-zero double straight from its bits (what Float's constructor does for
    a float, after its checks), anything else through the constructor."""
    if isinstance(value, float) and value and math.isfinite(value):
        return sp.Float._new(from_float(value, PRECISION, round_nearest), PRECISION, zero=False)
    return sp.Float(value)


def double(x) -> float:
    """``float(x)`` for a SymPy number: a Float of at most 53 bits and an Integer below 2^53 read directly (the
    same double: such a Float is its own 53-bit rounding, such an integer is exact), anything else by float()."""
    if type(x) is sp.Float and x._prec <= PRECISION:
        return to_float(x._mpf_)
    if isinstance(x, sp.Integer) and -2 ** 53 < x.p < 2 ** 53:
        return float(x.p)
    return float(x)
