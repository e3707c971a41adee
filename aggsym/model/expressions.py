"""Numbers and expressions in model files: parsed with SymPy, restricted to parameters and a few functions."""
from __future__ import annotations

import keyword
import re

import sympy as sp
from sympy.parsing.sympy_parser import convert_xor, parse_expr, standard_transformations

_ALLOWED = re.compile(r"^[A-Za-z0-9_.+\-*/^() \t]*$")
_IDENT = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
_DEG = re.compile(r"^(.*?)\s*deg$")
RESERVED = {"pi", "sin", "cos", "tan", "sqrt", "deg", "world", "t", "E", "I", "S", "N", "O", "Q", "oo", "nan"}
_FUNCTIONS = {"pi": sp.pi, "sin": sp.sin, "cos": sp.cos, "tan": sp.tan, "sqrt": sp.sqrt}
_TRANSFORMS = standard_transformations + (convert_xor,)


class ExpressionError(ValueError):
    pass


def check_identifier(name) -> str | None:
    """Why ``name`` cannot name a body, coordinate or parameter, or None when it can."""
    if not isinstance(name, str) or not _IDENT.match(name):
        return f"{name!r} is not a name (letters, digits and _, starting with a letter)"
    if keyword.iskeyword(name) or name in RESERVED:
        return f"{name!r} is reserved"
    return None


def parse_value(value, symbols: dict) -> sp.Expr:
    """A YAML number or expression string as a SymPy expression over the given parameter symbols.

    Strings may use + - * / ^ ** ( ), pi, sin, cos, tan, sqrt, the parameters, and a trailing ``deg`` that
    converts degrees to radians (``"90 deg"``).  Raises :class:`ExpressionError` with the reason.
    """
    if isinstance(value, bool):
        raise ExpressionError(f"expected a number or an expression, got {value!r}")
    if isinstance(value, int):
        return sp.Integer(value)
    if isinstance(value, float):
        if value != value or value in (float("inf"), float("-inf")):
            raise ExpressionError(f"{value!r} is not a finite number")
        return sp.Integer(int(value)) if value.is_integer() else sp.Float(value)
    if not isinstance(value, str):
        raise ExpressionError(f"expected a number or an expression, got {type(value).__name__} {value!r}")
    text = value.strip()
    scale = sp.Integer(1)
    m = _DEG.match(text)
    if m:
        text, scale = m.group(1), sp.pi / 180
    if not text or not _ALLOWED.match(text) or "__" in text:
        raise ExpressionError(f"{value!r} is not an expression (numbers, parameters, + - * / ^, pi, sin, cos, sqrt)")
    local = dict(symbols)
    try:
        expr = parse_expr(text, local_dict=local, global_dict=_global_dict(), transformations=_TRANSFORMS)
    except Exception as exc:  # SymPy raises many kinds on malformed input
        raise ExpressionError(f"cannot parse {value!r}: {exc.__class__.__name__}") from None
    if not isinstance(expr, sp.Expr):
        raise ExpressionError(f"{value!r} is not an expression")
    unknown = sorted(str(s) for s in expr.free_symbols if s not in set(symbols.values()))
    if unknown:
        raise ExpressionError(f"undefined parameter {unknown[0]!r} in {value!r} (declare it under 'parameters')")
    if any(isinstance(f, sp.core.function.AppliedUndef) for f in expr.atoms(sp.Function)):
        raise ExpressionError(f"unknown function in {value!r}")
    if expr.has(sp.I, sp.zoo, sp.oo, sp.nan):
        raise ExpressionError(f"{value!r} is not a real finite value")
    return expr * scale


def _global_dict() -> dict:
    g = {"Integer": sp.Integer, "Float": sp.Float, "Rational": sp.Rational, "Symbol": sp.Symbol,
         "Function": sp.Function}
    g.update(_FUNCTIONS)
    return g


def evaluate(expr: sp.Expr, values: dict) -> float:
    """The float value of an expression with parameters at their given values."""
    out = expr.subs(values) if values else expr
    return float(sp.N(out))
