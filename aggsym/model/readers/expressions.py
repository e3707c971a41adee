"""Numbers and expressions in model files: our own small grammar, parsed into SymPy from a whitelist.

A model file is data from a stranger, so no text of it ever reaches Python's or SymPy's parser (no ``eval``,
``sympify`` or ``parse_expr``).  The grammar::

    expression := sum ['deg']                     a trailing 'deg' converts the whole sum from degrees
    sum        := product (('+'|'-') product)*
    product    := unary (('*'|'/') unary)*
    unary      := ('+'|'-') unary | power           so -2^2 = -4
    power      := atom [('^'|'**') unary]           right associative; the exponent a constant (below)
    atom       := NUMBER | NAME | FUNCTION '(' expression [',' expression] ')' | '(' expression ')'

NAME is a declared parameter (and ``t`` where the time is allowed), or a constant: ``pi``, ``deg`` (pi/180).
FUNCTION is one of :data:`FUNCTIONS`.  There is no attribute access, subscript, string, keyword or call of
anything else.  Every resource is bounded, each bound a clear :class:`ExpressionError`: the length of the text
(:data:`MAX_LENGTH`), the nesting of parentheses and calls (:data:`MAX_NESTING`), the size of integer literals
(:data:`MAX_INTEGER_DIGITS`), function calls (:data:`MAX_CALLS`), exponents (constants, integer or half-integer, at most :data:`MAX_EXPONENT` in
magnitude, also after SymPy combines powers of powers) and exact rational values met while folding constants
(:data:`MAX_BITS`).  Sums and products are read by loops, so a long sum costs no recursion; the result's
constants are folded by us with these bounds before SymPy sees them.

:func:`evaluate` computes a value in doubles by an iterative walk (no ``sympy.N``, no arbitrary precision),
:func:`check_supported` says whether an expression (e.g. a derivative of a prescribed motion) uses only what the
code generator can emit.
"""
from __future__ import annotations

import keyword
import functools
import math
import re
from fractions import Fraction

import sympy as sp

from ...core.functions import GRAMMAR, by_sympy
from .sympy_numbers import double, float_number

MAX_LENGTH = 100_000  # characters of one expression
MAX_CALLS = 1_000  # function calls in one expression (SymPy takes up to a millisecond for each)
MAX_NESTING = 100  # parentheses and function calls inside each other
MAX_INTEGER_DIGITS = 30  # digits of an integer literal (larger: write it as a float, 1.5e40)
MAX_EXPONENT = 64  # |exponent| of a power, constant integer or half-integer
MAX_BITS = 2048  # numerator and denominator of an exact constant met while folding

# the functions of the grammar (a model file may call them): name -> Function (its SymPy form and arity)
FUNCTIONS = GRAMMAR
CONSTANTS = {"pi": sp.pi, "deg": sp.pi / 180}
# SymPy's functions an accepted expression (or a derivative of one) may hold -> Function (its value in doubles)
SYMPY_FUNCTIONS = by_sympy()
RESERVED = frozenset({"world", "t", "E", "I", "S", "N", "O", "Q", "oo", "nan"} | set(FUNCTIONS)
                     | set(CONSTANTS))

_IDENT = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
_TOKEN = re.compile(r"\s*(?:(?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)|(?P<name>[A-Za-z_][A-Za-z0-9_]*)"
                    r"|(?P<op>\*\*|[-+*/^(),]))")
_SPACE = re.compile(r"\s*")


class ExpressionError(ValueError):
    pass


def check_identifier(name) -> str | None:
    """Why ``name`` cannot name a body, coordinate or parameter, or None when it can."""
    if not isinstance(name, str) or not _IDENT.match(name):
        return f"{name!r} is not a name (letters, digits and _, starting with a letter)"
    if keyword.iskeyword(name) or name in RESERVED:
        return f"{name!r} is reserved"
    return None


@functools.lru_cache(maxsize=4096)
def _float_expr(value: float) -> sp.Expr:
    """A finite float as a SymPy number (an Integer where it is one); cached: a model repeats its numbers (SymPy
    numbers are immutable), and a file of distinct numbers only misses the bounded cache."""
    return sp.Integer(int(value)) if value.is_integer() and abs(value) < 1e15 else float_number(value)


def parse_value(value, symbols: dict) -> sp.Expr:
    """A YAML number or expression string as a SymPy expression over the given symbols (name -> Symbol).

    Raises :class:`ExpressionError` with the reason and, for text, the column."""
    if isinstance(value, bool):
        raise ExpressionError(f"expected a number or an expression, got {value!r}")
    if isinstance(value, int):
        if len(str(abs(value))) > MAX_INTEGER_DIGITS:
            raise ExpressionError(f"the integer {_short(str(value))} is too large (more than {MAX_INTEGER_DIGITS} "
                                  f"digits; write it as a float, e.g. 1.5e40)")
        return sp.Integer(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ExpressionError(f"{value!r} is not a finite number")
        return _float_expr(value)
    if not isinstance(value, str):
        raise ExpressionError(f"expected a number or an expression, got {type(value).__name__} {_short(repr(value))}")
    if len(value) > MAX_LENGTH:
        raise ExpressionError(f"the expression is too long ({len(value)} characters, at most {MAX_LENGTH})")
    expr = _Parser(value, symbols).parse()
    if expr.has(sp.I, sp.zoo, sp.oo, sp.nan, -sp.oo):
        raise ExpressionError(f"{_short(repr(value))} is not a real finite value")
    return expr


def _short(text: str, n: int = 60) -> str:
    return text if len(text) <= n else text[:n] + "..."


class _Parser:
    """Recursive descent over the tokens; recursion only for parentheses, calls and unary signs (bounded)."""

    def __init__(self, text: str, symbols: dict):
        self.text, self.symbols = text, symbols
        self.tokens = []  # (kind, text, column)
        pos, end = 0, len(text)
        while True:
            pos = _SPACE.match(text, pos).end()
            if pos >= end:
                break
            m = _TOKEN.match(text, pos)
            if not m:
                raise self.error(f"unexpected character {text[pos]!r}", pos)
            kind = m.lastgroup
            self.tokens.append((kind, m.group(kind), m.start(kind)))
            pos = m.end()
        self.tokens.append(("end", "", end))
        self.i = 0
        self.depth = 0
        self.calls = 0
        self.undefined = None

    def error(self, why: str, column: int) -> ExpressionError:
        return ExpressionError(f"cannot parse {_short(repr(self.text))}: {why} (column {column + 1})")

    def peek(self):
        return self.tokens[self.i]

    def take(self):
        tok = self.tokens[self.i]
        self.i += 1
        return tok

    def expect(self, op: str):
        kind, text, col = self.take()
        if (kind, text) != ("op", op):
            raise self.error(f"expected {op!r}, found {_describe(kind, text)}", col)

    def parse(self) -> sp.Expr:
        if self.peek()[0] == "end":
            raise ExpressionError("an empty expression: give a number or an expression")
        out = self.expression()
        kind, text, col = self.peek()
        if kind != "end":
            raise self.error(f"unexpected {_describe(kind, text)}", col)
        if self.undefined is not None:
            raise ExpressionError(f"undefined parameter {self.undefined!r} in {_short(repr(self.text))} "
                                  f"(declare it under 'parameters')")
        return out

    def nest(self, col: int):
        self.depth += 1
        if self.depth > MAX_NESTING:
            raise self.error(f"nested too deeply (at most {MAX_NESTING} levels of parentheses, calls and signs)", col)

    def expression(self) -> sp.Expr:
        out = self.sum()
        kind, text, col = self.peek()
        if kind == "name" and text == "deg":  # "30 deg", "(a + b) deg", "sin(30 deg)"
            self.take()
            out = _product([out, sp.pi / 180], col, self)
        return out

    def sum(self) -> sp.Expr:
        terms = [self.product()]
        while True:
            kind, text, col = self.peek()
            if kind == "op" and text in ("+", "-"):
                self.take()
                term = self.product()
                terms.append(term if text == "+" else _product([sp.Integer(-1), term], col, self))
            else:
                return _sum(terms, col, self)

    def product(self) -> sp.Expr:
        factors = [self.unary()]
        while True:
            kind, text, col = self.peek()
            if kind == "op" and text in ("*", "/"):
                self.take()
                f = self.unary()
                if text == "/":
                    if f == 0:
                        raise self.error("division by zero", col)
                    f = _power(f, sp.Integer(-1), col, self)
                factors.append(f)
            else:
                return _product(factors, col, self)

    def unary(self) -> sp.Expr:
        """A sign binds less tightly than a power: -2^2 is -4."""
        kind, text, col = self.peek()
        if kind == "op" and text in ("+", "-"):
            self.take()
            self.nest(col)
            inner = self.unary()
            self.depth -= 1
            return inner if text == "+" else _product([sp.Integer(-1), inner], col, self)
        return self.power()

    def power(self) -> sp.Expr:
        base = self.atom()
        kind, text, col = self.peek()
        if kind == "op" and text in ("^", "**"):  # right associative: 2^3^2 = 2^9
            self.take()
            self.nest(col)
            exponent = self.unary()
            self.depth -= 1
            return _power(base, exponent, col, self)
        return base

    def atom(self) -> sp.Expr:
        kind, text, col = self.take()
        if kind == "num":
            return self.number(text, col)
        if kind == "op" and text == "(":
            self.nest(col)
            out = self.expression()
            self.expect(")")
            self.depth -= 1
            return out
        if kind == "name":
            nxt = self.peek()
            if text in FUNCTIONS:
                if nxt[:2] != ("op", "("):
                    raise self.error(f"{text} is a function: write {text}(...)", col)
                self.take()
                self.nest(col)
                self.calls += 1
                if self.calls > MAX_CALLS:
                    raise self.error(f"too many function calls (at most {MAX_CALLS})", col)
                func, arity = FUNCTIONS[text].sympy, FUNCTIONS[text].arity
                args = [self.expression()]
                while len(args) < arity:
                    self.expect(",")
                    args.append(self.expression())
                self.expect(")")
                self.depth -= 1
                return _call(text, func, args, col, self)
            if nxt[:2] == ("op", "("):
                raise self.error(f"unknown function {text!r} (the functions are {', '.join(FUNCTIONS)})", col)
            if text in self.symbols:
                return self.symbols[text]
            if text in CONSTANTS:
                return CONSTANTS[text]
            if text == "t":
                raise self.error("the time t is not allowed here", col)
            if self.undefined is None:  # reported once the text is known to parse
                self.undefined = text
            return sp.Dummy(text, real=True)
        raise self.error(f"unexpected {_describe(kind, text)}", col)

    def number(self, text: str, col: int) -> sp.Expr:
        if re.fullmatch(r"\d+", text):
            if len(text.lstrip("0")) > MAX_INTEGER_DIGITS:
                raise self.error(f"the integer is too large (more than {MAX_INTEGER_DIGITS} digits; write it as a "
                                 f"float, e.g. 1.5e40)", col)
            return sp.Integer(int(text))
        x = float(text)
        if not math.isfinite(x):
            raise self.error(f"the number {_short(text)} is not finite", col)
        return sp.Float(x)


def _describe(kind: str, text: str) -> str:
    return "the end" if kind == "end" else repr(text)


def _split_numbers(args):
    exact, floats, rest = [], [], []
    for a in args:
        if a.is_Rational:
            exact.append(Fraction(int(a.p), int(a.q)))
        elif a.is_Float:
            floats.append(float(a))
        else:
            rest.append(a)
    return exact, floats, rest


def _fold(exact, floats, start, step, col, parser) -> sp.Expr:
    """Fold numbers with a bound at every step (so no long sum or product of constants grows without end)."""
    q = Fraction(start)
    for x in exact:
        q = step(q, x)
        if q.numerator.bit_length() > MAX_BITS or q.denominator.bit_length() > MAX_BITS:
            raise parser.error(f"a constant grows too large (more than {MAX_BITS} bits)", col)
    if not floats:
        return sp.Rational(q.numerator, q.denominator)
    try:
        x = float(q)
        for f in floats:
            x = step(x, f)
    except OverflowError:
        x = math.inf
    if not math.isfinite(x):
        raise parser.error("a constant is not finite", col)
    return sp.Float(x)


def _sum(terms, col, parser) -> sp.Expr:
    if len(terms) == 1:
        return terms[0]
    exact, floats, rest = _split_numbers(terms)
    const = _fold(exact, floats, 0, lambda a, b: a + b, col, parser)
    return sp.Add(const, *rest)


def _product(factors, col, parser) -> sp.Expr:
    exact, floats, rest = _split_numbers(factors)
    const = _fold(exact, floats, 1, lambda a, b: a * b, col, parser)
    out = sp.Mul(const, *rest) if rest else const
    return _checked(out, col, parser)


def _power(base, exponent, col, parser) -> sp.Expr:
    if not exponent.is_number or not (exponent.is_Rational or exponent.is_Float):
        raise parser.error(f"the exponent {_short(str(exponent))} must be a constant number", col)
    e = Fraction(float(exponent)) if exponent.is_Float else Fraction(int(exponent.p), int(exponent.q))
    if e.denominator not in (1, 2) or abs(e) > MAX_EXPONENT:
        raise parser.error(f"the exponent {_short(str(exponent))} must be an integer or half-integer of magnitude at "
                           f"most {MAX_EXPONENT}", col)
    if base == 0 and e < 0:
        raise parser.error("division by zero", col)
    if base.is_Rational:
        bits = max(int(base.p).bit_length(), int(base.q).bit_length())
        if bits * abs(e) > MAX_BITS:
            raise parser.error(f"a constant grows too large (more than {MAX_BITS} bits)", col)
    elif base.is_Float:
        try:
            x = float(base) ** float(e)
        except (OverflowError, ZeroDivisionError):
            x = math.inf
        if isinstance(x, complex) or not math.isfinite(x):
            raise parser.error("a constant is not finite or not real", col)
    return _checked(sp.Pow(base, sp.Rational(e.numerator, e.denominator)), col, parser)


def _call(name, func, args, col, parser) -> sp.Expr:
    if name == "log" and args[0] == 0:
        raise parser.error("log(0) is not finite", col)
    if name == "atan2" and args[0] == 0 and args[1] == 0:
        raise parser.error("atan2(0, 0) is undefined", col)
    return _checked(func(*args), col, parser)


def _checked(expr, col, parser) -> sp.Expr:
    """Refuse what SymPy's own simplification made too large: combined exponents, huge exact constants."""
    for p in (expr, *expr.args):  # SymPy combines powers at the top: (a^64)^64 = a^4096, a^64 a^64 = a^128
        if p.is_Pow and p.exp.is_Number and abs(p.exp) > MAX_EXPONENT:
            raise parser.error(f"the exponent grows too large ({_short(str(p.exp))}, at most {MAX_EXPONENT})", col)
        if p.is_Rational and max(int(p.p).bit_length(), int(p.q).bit_length()) > MAX_BITS:
            raise parser.error(f"a constant grows too large (more than {MAX_BITS} bits)", col)
    if expr.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
        raise parser.error("the value is not finite", col)
    return expr


def check_supported(expr) -> str | None:
    """Why the code generator cannot emit ``expr``, or None: sums, products, numbers, symbols, pi and e, powers with
    integer or half-integer exponents, and :data:`SYMPY_FUNCTIONS`."""
    for e in sp.preorder_traversal(expr):
        if e.is_Add or e.is_Mul or e.is_Number or e.is_Symbol or e.is_NumberSymbol:
            continue
        if e.is_Pow:
            if not (e.exp.is_Rational and e.exp.q in (1, 2)):
                return f"the power {e} (exponents must be constant integers or half-integers)"
            continue
        if e.func in SYMPY_FUNCTIONS:
            continue
        return f"{e.func.__name__} in {e}"
    return None


def evaluate(expr, values: dict) -> float:
    """The value of an expression in doubles, with symbols at the given values; iterative (no depth limit).

    Raises ValueError when it has no real finite value (a domain error, an overflow, a missing symbol)."""
    if isinstance(expr, (int, float)) and not isinstance(expr, bool):
        return float(expr)
    if expr.is_Number:  # the common case: a plain number of the model
        out = double(expr)
        if not math.isfinite(out):
            raise ValueError(f"{_short(str(expr))} is not finite")
        return out
    done: dict = {}
    stack = [(expr, False)]
    while stack:
        e, ready = stack.pop()
        if e in done:
            continue
        if e.is_Number or e.is_NumberSymbol:
            done[e] = float(e)
        elif e.is_Symbol:
            if e not in values:
                raise ValueError(f"{e} has no value")
            done[e] = float(values[e])
        elif not ready:
            stack.append((e, True))
            stack.extend((a, False) for a in e.args if a not in done)
        else:
            done[e] = _value(e, [done[a] for a in e.args])
    out = done[expr]
    if not math.isfinite(out):
        raise ValueError(f"{_short(str(expr))} is not finite")
    return out


def _value(e, args) -> float:
    try:
        if e.is_Add:
            return math.fsum(args)
        if e.is_Mul:
            return math.prod(args)
        if e.is_Pow:
            x = args[0] ** args[1]
            if isinstance(x, complex):
                raise ValueError(f"{_short(str(e))} has no real value")
            return x
        if e.func in SYMPY_FUNCTIONS:
            return float(SYMPY_FUNCTIONS[e.func].value(*args))
    except OverflowError:
        return math.inf
    except ValueError:
        raise ValueError(f"{_short(str(e))} has no real value") from None
    except ZeroDivisionError:
        raise ValueError(f"{_short(str(e))} divides by zero") from None
    raise ValueError(f"{_short(str(e))} cannot be evaluated")
