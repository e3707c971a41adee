"""The two backends the recursions run on, and the conversion of the model's SymPy expressions to their scalars.

* :class:`Symbolic` records a straight-line program (:mod:`aggsym.core.program`).
* :class:`Numeric` computes with floats or NumPy arrays (the numeric twin).
* :class:`Backend` names what the mechanics may ask of either (and of :class:`~aggsym.core.dual.DualBackend`).

Both offer ``call(name, *args)`` for the functions of :data:`aggsym.core.functions.FUNCTIONS` and the shortcuts
``sin``, ``cos``, ``sqrt``; :func:`to_scalar` turns a SymPy expression (a mass, a constructive angle, a
parameter expression) into a scalar of either.
"""
from __future__ import annotations

import numbers
from fractions import Fraction
from typing import Protocol

import numpy as np
import sympy as sp

from .functions import FUNCTIONS, by_sympy
from .program import Program, normalize_const


class Backend(Protocol):
    """What the mechanics may ask of a backend; they probe no other attribute.

    ``symbolic``: its scalars are exact (program nodes, Fractions for the constants), so that the mechanics may
    choose a form by counting operations; False for floats.  ``program``: the :class:`Program` its scalars are
    nodes of, or None where they are not one program's nodes (floats; duals, which pair a value with tangents)."""

    symbolic: bool
    program: Program | None

    def call(self, name: str, *args): ...

    def sin(self, x): ...

    def cos(self, x): ...

    def sqrt(self, x): ...

    def rational(self, num: int, den: int): ...


class Symbolic:
    """Record operations into a :class:`Program` (a :class:`Backend`)."""

    symbolic = True

    def __init__(self, program: Program | None = None):
        self.program = program or Program()
        self.call = self.program.call
        self.sin = self.program.sin
        self.cos = self.program.cos
        self.sqrt = self.program.sqrt

    def inputs(self, kind: str, n: int) -> list:
        return self.program.vector(kind, n)

    def rational(self, num: int, den: int):
        """num/den as an exact constant."""
        return Fraction(num, den)


class ExactSymbolic(Symbolic):
    """A :class:`Symbolic` backend whose constants are the model's doubles as exact Fractions, so that the program
    folds them without rounding (the exact relations of :mod:`aggsym.contract.exact_relations`); never printed."""

    exact = True


class Numeric:
    """Compute with floats (or NumPy arrays, element-wise over a batch); a :class:`Backend`."""

    symbolic = False
    program = None
    sin = staticmethod(np.sin)
    cos = staticmethod(np.cos)
    sqrt = staticmethod(np.sqrt)

    @staticmethod
    def call(name: str, *args):
        return FUNCTIONS[name].numpy(*args)

    @staticmethod
    def rational(num: int, den: int):
        return num / den


# SymPy's functions that a model's expressions may hold -> the table's functions
_SYMPY_FUNCTIONS = by_sympy()


def as_expr(x) -> sp.Expr:
    """A number or expression of a model as a SymPy expression, without ever parsing text (what ``sympify`` would do
    with a string): SymPy values as they are, integers as Integers, fractions as Rationals, floats as Floats of their
    exact binary value."""
    if isinstance(x, sp.Basic):
        return x
    if isinstance(x, bool) or not isinstance(x, numbers.Number):
        raise TypeError(f"not a number or a SymPy expression: {x!r}")
    if isinstance(x, numbers.Integral):
        return sp.Integer(int(x))
    if isinstance(x, numbers.Rational):
        return sp.Rational(int(x.numerator), int(x.denominator))
    return sp.Float(float(x))


def to_scalar(expr, values: dict, backend):
    """A SymPy expression over parameter symbols as a backend scalar; ``values`` maps symbols to scalars.

    Iterative (an explicit post-order stack), so the depth of the expression is no limit; sums and products are
    folded left to right.  Powers: integer and half-integer exponents (sqrt)."""
    if isinstance(expr, (int, float, Fraction)) and not isinstance(expr, bool):
        return normalize_const(expr) if backend.symbolic else float(expr)
    if not isinstance(expr, sp.Basic):
        raise TypeError(f"not a SymPy expression: {type(expr).__name__}")
    done: dict = {}
    stack = [(expr, False)]
    while stack:
        e, expanded = stack.pop()
        if e in done:
            continue
        leaf = _leaf(e, values, backend)
        if leaf is not None:
            done[e] = leaf
        elif not expanded:
            stack.append((e, True))
            stack.extend((a, False) for a in reversed(e.args) if a not in done)
        else:
            done[e] = _node(e, [done[a] for a in e.args], backend)
    return done[expr]



def _leaf(e, values, backend):
    """The scalar of a number or symbol, or None for a compound expression."""
    if e.is_Integer:
        return int(e)
    if e.is_Rational:
        q = Fraction(int(e.p), int(e.q))
        return q if backend.symbolic else float(q)
    if e.is_Number or e.is_NumberSymbol:  # (a backend that keeps constants exact: the double as a Fraction)
        return Fraction(float(e)) if getattr(backend, "exact", False) else normalize_const(float(e))
    if e.is_Symbol:
        return values[e]
    return None


def _node(expr, args, backend):
    """A compound expression from the scalars of its arguments."""
    if expr.is_Add:
        acc = args[0]
        for a in args[1:]:
            acc = acc + a
        return acc
    if expr.is_Mul:
        acc = args[0]
        for a in args[1:]:
            acc = acc * a
        return acc
    if expr.is_Pow:
        base, exponent = args[0], expr.args[1]
        if exponent == sp.Rational(1, 2):
            return backend.sqrt(base)
        if exponent.is_Integer:
            n = int(exponent)
            out = _power(base, abs(n))
            return 1 / out if n < 0 else out
        if exponent.is_Rational and exponent.q == 2:  # x^(k/2) = sqrt(x)^k (derivatives of sqrt)
            n = int(exponent.p)
            out = _power(backend.sqrt(base), abs(n))
            return 1 / out if n < 0 else out
        raise ValueError(f"unsupported power {expr}")
    if expr.func in _SYMPY_FUNCTIONS:
        return backend.call(_SYMPY_FUNCTIONS[expr.func].name, *args)
    raise ValueError(f"unsupported expression {expr}")


def _power(x, n: int):
    out, base = 1, x
    while n:
        if n & 1:
            out = out * base
        n >>= 1
        if n:
            base = base * base
    return out


