"""The one table of the functions a program can call (sin, atan2, ...): the only place a function is spelled.

Each :class:`Function` holds its name (the program's operation code), its number of arguments, its value on
Python floats (constant folding, :meth:`aggsym.core.program.Program.evaluate`, the model's
:func:`aggsym.model.readers.expressions.evaluate`), its NumPy and SymPy forms (the numeric backend, ``to_sympy``, the
conversion of a model's SymPy expressions), whether a model file may call it (the expression grammar) and its
derivative rule (the dual numbers, :mod:`aggsym.core.dual`).  The printed spelling of each function is its
target's (``aggsym/codegen/targets/``), keyed by these names.  NumPy and SymPy are imported only when a form is
first asked for.

A derivative rule ``rule(backend, *values)`` returns ``(value, coefficients, common)`` for the function at the
values of its arguments: the tangent is ``common * sum(sign_i * coefficient_i * tangent_i)`` over the arguments,
``coefficients`` holding ``(coefficient_i, sign_i)`` (None: the argument's tangent does not count), ``common``
None for 1, ``value`` None for one computed after the tangent's sum (the order in which the rule's operations are
recorded into a program).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property


def _d_sin(b, x):
    c = b.cos(x)
    return b.sin(x), ((c, 1),), None


def _d_cos(b, x):
    s = b.sin(x)
    return b.cos(x), ((s, -1),), None


def _d_sqrt(b, x):
    r = b.sqrt(x)
    return r, ((b.rational(1, 2) / r, 1),), None


def _d_sign(b, x):  # piecewise constant: no tangent
    return b.call("sign", x), (), None


def _d_abs(b, x):
    s = b.call("sign", x)
    return b.call("abs", x), ((s, 1),), None


def _d_atan2(b, y, x):  # d atan2(y, x) = (x dy - y dx) / (x^2 + y^2)
    return None, ((x, 1), (y, -1)), 1 / (x * x + y * y)


@dataclass(frozen=True)
class Function:
    """One function: ``name`` (the program's code), ``arity``, ``value`` on floats, the names of its NumPy and SymPy
    forms, ``grammar`` (a model file may call it), ``derivative`` (the rule of the module's text, or None)."""

    name: str
    arity: int
    value: object
    numpy_name: str
    sympy_name: str
    grammar: bool = True
    derivative: object = None

    @cached_property
    def numpy(self):
        """The NumPy ufunc (element-wise over a batch)."""
        import numpy as np
        return getattr(np, self.numpy_name)

    @cached_property
    def sympy(self):
        """The SymPy function class."""
        import sympy as sp
        return getattr(sp, self.sympy_name)


SIN, COS, SQRT = "sin", "cos", "sqrt"

# in the order of the program's operation codes (:data:`aggsym.core.program._CODE_INDEX`) and the grammar's list
FUNCTIONS = {f.name: f for f in (
    Function(SIN, 1, math.sin, "sin", "sin", derivative=_d_sin),
    Function(COS, 1, math.cos, "cos", "cos", derivative=_d_cos),
    Function(SQRT, 1, math.sqrt, "sqrt", "sqrt", derivative=_d_sqrt),
    Function("tan", 1, math.tan, "tan", "tan"),
    Function("exp", 1, math.exp, "exp", "exp"),
    Function("log", 1, math.log, "log", "log"),
    Function("abs", 1, abs, "abs", "Abs", derivative=_d_abs),
    Function("asin", 1, math.asin, "arcsin", "asin"),
    Function("acos", 1, math.acos, "arccos", "acos"),
    Function("atan", 1, math.atan, "arctan", "atan"),
    Function("atan2", 2, math.atan2, "arctan2", "atan2", derivative=_d_atan2),
    Function("sign", 1, lambda x: (x > 0) - (x < 0), "sign", "sign", grammar=False, derivative=_d_sign),
)}

# the functions a model file's expressions may call (sign only arises from derivatives of abs)
GRAMMAR = {name: f for name, f in FUNCTIONS.items() if f.grammar}


def by_sympy() -> dict:
    """SymPy's function class -> :class:`Function` (what a model's SymPy expressions may hold)."""
    return {f.sympy: f for f in FUNCTIONS.values()}


__all__ = ["Function", "FUNCTIONS", "GRAMMAR", "SIN", "COS", "SQRT", "by_sympy"]
