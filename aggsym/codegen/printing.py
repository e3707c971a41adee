"""From a straight-line program to printed assignments: naming (CSE), SymPy printers, operation counts.

A routine's outputs are nodes of a :class:`~aggsym.codegen.program.Program`.  :func:`straight_line` decides which
nodes get a name: every node used twice or more (common subexpressions, already shared by value numbering) and
every function call (sin/cos of each angle, named once); the rest is inlined into its single use.  Each named
right-hand side is converted to an unevaluated SymPy expression (so SymPy neither distributes ``2*(a+b)`` nor
reorders terms) and printed by :class:`CPrinter` or :class:`NumPyPrinter`, both SymPy code-printer subclasses.

:func:`count_ops` counts the operations of emitted C text: ``*`` multiplications, ``/`` divisions, binary ``+``
and ``-`` additions (subtractions count as additions), and function calls; unary minus is not counted.
"""
from __future__ import annotations

import re
import sys
from collections import Counter
from dataclasses import dataclass
from fractions import Fraction

import sympy as sp
from sympy.printing.c import C99CodePrinter
from sympy.printing.numpy import NumPyPrinter as _SympyNumPyPrinter

from .program import ADD, COS, DIV, FUNCTIONS, INPUT, MUL, NEG, SIN, SQRT, SUB, Node

sys.setrecursionlimit(max(sys.getrecursionlimit(), 20000))


@dataclass
class StraightLine:
    """Assignments ``temps`` (node ids in order) and per-output lists of nodes or constants."""

    program: object
    temps: list
    outputs: list  # list (per output argument) of flat lists of scalars
    inputs: list  # (kind, index) used, sorted


def straight_line(program, outputs) -> StraightLine:
    """Name the nodes that need a name; ``outputs`` is a list of flat lists of scalars."""
    flat = [x for out in outputs for x in out]
    ids = program.reachable(flat)
    uses: Counter = Counter()
    for i in ids:
        for a in program.operands(i):
            if isinstance(a, Node):
                uses[a.id] += 1
    for x in flat:
        if isinstance(x, Node):
            uses[x.id] += 1
    temps, inputs = [], []
    for i in ids:
        code = program.ops[i][0]
        if code == INPUT:
            inputs.append(program.ops[i][1:])
        elif uses[i] >= 2 or code in FUNCTIONS:
            temps.append(i)
    return StraightLine(program, temps, outputs, sorted(inputs))


def constant(x) -> sp.Expr:
    if type(x) is int:
        return sp.Integer(x)
    if isinstance(x, Fraction):
        return sp.Rational(x.numerator, x.denominator)
    return sp.Float(x, 17) if x != int(x) else sp.Integer(int(x))


class Converter:
    """Unevaluated SymPy expressions for the right-hand sides of a straight-line program."""

    def __init__(self, program, names: dict):
        self.program = program
        self.names = names  # node id -> sp.Symbol (inputs and named temps)

    def __call__(self, x, top: bool = True):
        if not isinstance(x, Node):
            return constant(x)
        if not top and x.id in self.names:
            return self.names[x.id]
        entry = self.program.ops[x.id]
        code = entry[0]
        if code == INPUT:
            return self.names[x.id]
        if code == NEG:
            return sp.Mul(-1, self(entry[1], False), evaluate=False)
        if code in FUNCTIONS:
            f = {SIN: sp.sin, COS: sp.cos, SQRT: sp.sqrt}[code]
            return f(self(entry[1], False), evaluate=False)
        if code in (ADD, SUB):
            return sp.Add(*self._terms(x, top), evaluate=False)
        if code == MUL:
            return sp.Mul(*self._factors(x, top), evaluate=False)
        if code == DIV:
            num, den = self(entry[1], False), self(entry[2], False)
            return sp.Mul(num, sp.Pow(den, -1, evaluate=False), evaluate=False)
        raise ValueError(code)

    def _inlined(self, x, top):
        return isinstance(x, Node) and (top or x.id not in self.names)

    def _terms(self, x, top, sign=1):
        """Flatten a chain of inlined additions and subtractions into signed terms."""
        if self._inlined(x, top) and self.program.ops[x.id][0] in (ADD, SUB):
            code, a, b = self.program.ops[x.id]
            return self._terms(a, False, sign) + self._terms(b, False, sign if code == ADD else -sign)
        term = self(x, False)
        return [term if sign > 0 else sp.Mul(-1, term, evaluate=False)]

    def _factors(self, x, top):
        if self._inlined(x, top) and self.program.ops[x.id][0] == MUL:
            _, a, b = self.program.ops[x.id]
            return self._factors(a, False) + self._factors(b, False)
        return [self(x, False)]


def _float_literal(value: float) -> str:
    text = repr(float(value))
    return text if ("." in text or "e" in text or "n" in text) else text + ".0"


class _Common:
    def _print_Float(self, expr):
        return _float_literal(float(expr))

    def _print_Rational(self, expr):
        return _float_literal(float(expr.p) / float(expr.q))

    def _print_Pow(self, expr):
        base, exp = expr.args
        if exp == -1:
            return f"1.0/{self.parenthesize(base, 50)}"
        if exp.is_Integer and 1 < exp <= 4:
            b = self.parenthesize(base, 50)
            return "*".join([b] * int(exp))
        return super()._print_Pow(expr)


class CPrinter(_Common, C99CodePrinter):
    """C99 for aggsym: round-trip float literals, x*x for small powers, no pow() for reciprocals."""

    def __init__(self):
        super().__init__({"order": "none", "strict": False})


class NumPyPrinter(_Common, _SympyNumPyPrinter):
    """NumPy for aggsym: np.sin etc., element-wise so that inputs may carry a leading batch dimension."""

    def __init__(self):
        super().__init__({"order": "none", "fully_qualified_modules": False})

    def _module_format(self, fqn, register=True):
        if fqn.startswith("numpy."):
            return "np." + fqn[len("numpy."):]
        return super()._module_format(fqn, register)


_TOKEN = re.compile(r"\s*(?:(?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)|(?P<name>[A-Za-z_]\w*)|(?P<op>.))")


def count_ops(c_code: str) -> dict:
    """Operation counts of C statements: mul, add (incl. subtractions), div, call (unary minus not counted)."""
    code = re.sub(r"/\*.*?\*/", " ", c_code, flags=re.S)
    counts = {"mul": 0, "add": 0, "div": 0, "call": 0}
    prev = None  # kind of the previous token: 'value', 'open', 'op', or None
    tokens = list(_TOKEN.finditer(code))
    for k, m in enumerate(tokens):
        if m.group("num"):
            prev = "value"
        elif m.group("name"):
            nxt = tokens[k + 1].group("op") if k + 1 < len(tokens) else None
            if nxt == "(" and m.group("name") not in ("if", "for", "while", "return", "sizeof"):
                counts["call"] += 1
            prev = "value"
        else:
            op = m.group("op")
            if op.isspace():
                continue
            if op in ")]":
                prev = "value"
            elif op in "([,;=":
                prev = "open"
            elif op == "*":
                counts["mul"] += 1
                prev = "op"
            elif op == "/":
                counts["div"] += 1
                prev = "op"
            elif op in "+-":
                if prev == "value":
                    counts["add"] += 1
                prev = "op"
            else:
                prev = "op"
    return counts
