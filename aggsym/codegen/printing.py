"""From a straight-line program to printed assignments: the one infix printer, expression trees, operation counts.

:func:`aggsym.core.program.straight_line` decides which nodes of a routine's program get a name.  :class:`Infix`
prints each named right-hand side straight from the program, exactly as built (no reordering, no distribution
of ``2*(a+b)``), spelled by a target's :class:`Spelling` (its function names and literals: the C target's
``c_spelling``, the NumPy target's ``NUMPY``).  The LaTeX document has its own printer (:mod:`.latex`), of the
small expression trees built here by :class:`Converter` (:class:`LinComb`, :class:`Prod`, :class:`Ratio`,
:class:`Call`, :class:`Ref`, :class:`Num`).  The printed expressions are shallow: the naming bounds the depth of
what is inlined (:data:`aggsym.core.program.INLINE_DEPTH`), so printing needs no raised recursion limit whatever
the program.

:func:`count_ops` counts the operations of emitted C text: ``*`` multiplications, ``/`` divisions, binary ``+``
and ``-`` additions (subtractions count as additions), and function calls; unary minus is not counted.
"""
from __future__ import annotations

import re
import struct
from dataclasses import dataclass
from fractions import Fraction

from ..core.program import ADD, DIV, FUNCTIONS, INPUT, MUL, NEG, SUB, Node, is_zero, normalize_const


class Num:
    """A constant (int, Fraction or float)."""

    __slots__ = ("value",)

    def __init__(self, value):
        self.value = value


class Ref:
    """A named value: an input entry or a named intermediate."""

    __slots__ = ("symbol",)

    def __init__(self, symbol):
        self.symbol = symbol


class LinComb:
    """A sum of signed terms: ``[(+1 or -1, expr), ...]``."""

    __slots__ = ("terms",)

    def __init__(self, terms):
        self.terms = terms


class Prod:
    """A signed product of factors."""

    __slots__ = ("sign", "factors")

    def __init__(self, sign, factors):
        self.sign = sign
        self.factors = factors


class Ratio:
    __slots__ = ("num", "den")

    def __init__(self, num, den):
        self.num = num
        self.den = den


class Call:
    """A function of :data:`aggsym.core.functions.FUNCTIONS` applied to its arguments."""

    __slots__ = ("name", "args")

    def __init__(self, name, args):
        self.name = name
        self.args = args


class Converter:
    """The right-hand side of an assignment as a small expression tree (:class:`LinComb`, :class:`Prod`, ...)
    with chains of inlined additions and multiplications flattened; named nodes appear as :class:`Ref`.

    One pass over the inlined nodes (each is inlined into its single use, so a statement costs its own size);
    the flattening appends to one list per chain instead of concatenating partial lists."""

    def __init__(self, program, names: dict):
        self.program = program
        self.names = names  # node id -> name (a str; inputs and named temps)
        self.calls = 0  # the Call nodes built so far (a tree without one prints alike in C and NumPy)
        self.refs = []  # the names of the Ref nodes built so far (what a statement uses; the caller clears it)

    def __call__(self, x, top: bool = True):
        if x.__class__ is not Node:
            return Num(x)
        ident = x.id
        if not top and ident in self.names:
            return self._ref(self.names[ident])
        entry = self.program.ops[ident]
        code = entry[0]
        if code == INPUT:
            return self._ref(self.names[ident])
        if code == ADD or code == SUB:
            terms = []
            self._terms(x, True, 1, terms)
            return LinComb(_merge_constants(terms))
        if code == MUL:
            factors = []
            sign = self._factors(x, True, 1, factors)
            return Prod(sign, factors)
        if code == NEG:
            inner = self(entry[1], False)
            if inner.__class__ is Prod:
                return Prod(-inner.sign, inner.factors)
            return LinComb([(-1, inner)])
        if code == DIV:
            return Ratio(self(entry[1], False), self(entry[2], False))
        if code in FUNCTIONS:
            self.calls += 1
            return Call(code, tuple(self(a, False) for a in entry[1:]))
        raise ValueError(code)

    def _terms(self, x, top, sign, out):
        """Append the signed terms of a chain of inlined additions, subtractions and negations to ``out``."""
        if x.__class__ is Node and (top or x.id not in self.names):
            entry = self.program.ops[x.id]
            code = entry[0]
            if code == ADD or code == SUB:
                self._terms(entry[1], False, sign, out)
                self._terms(entry[2], False, sign if code == ADD else -sign, out)
                return
            if code == NEG:
                self._terms(entry[1], False, -sign, out)
                return
        if x.__class__ is not Node:
            out.append((sign, Num(x)))
            return
        name = self.names.get(x.id)
        if name is not None:  # (inputs are always named)
            out.append((sign, self._ref(name)))
            return
        term = self(x, False)
        if term.__class__ is Prod and term.sign < 0:
            out.append((-sign, Prod(1, term.factors)))
        else:
            out.append((sign, term))

    def _factors(self, x, top, sign, out):
        """Append the factors of a chain of inlined products (and negations) to ``out``; returns the sign."""
        if x.__class__ is Node and (top or x.id not in self.names):
            entry = self.program.ops[x.id]
            code = entry[0]
            if code == MUL:
                sign = self._factors(entry[1], False, sign, out)
                return self._factors(entry[2], False, sign, out)
            if code == NEG:
                return self._factors(entry[1], False, -sign, out)
        if x.__class__ is not Node:
            out.append(Num(x))
        else:
            name = self.names.get(x.id)
            out.append(self._ref(name) if name is not None else self(x, False))
        return sign

    def _ref(self, name):
        self.refs.append(name)
        return Ref(name)


def _merge_constants(terms: list) -> list:
    """One constant term in place of several (``c1 + x - c2`` -> ``x + (c1 - c2)`` at the first constant's place):
    the program folds constants only when they meet in one operation, and a flattened chain of additions can hold
    several, e.g. the parameters of bodies lumped together."""
    constants = [k for k, (_, term) in enumerate(terms) if isinstance(term, Num)]
    if len(constants) < 2:
        return terms
    total = normalize_const(sum(terms[k][0] * terms[k][1].value for k in constants))
    out = []
    for k, term in enumerate(terms):
        if k == constants[0] and not is_zero(total):
            out.append((1, Num(total)) if total > 0 else (-1, Num(normalize_const(-total))))
        elif k not in constants:
            out.append(term)
    return out or [(1, Num(0))]


_TREE = (Num, Ref, LinComb, Prod, Ratio, Call)

SCALARS = ("double", "float")  # the C types of the generated code (--scalar); the NumPy module is always double


class LiteralError(ValueError):
    """A constant that the scalar type cannot hold (not finite; a float's overflow or underflow to 0)."""


def _float_literal(value: float, scalar: str = "double") -> str:
    """A literal that reads back as exactly ``value`` (Python's repr is the shortest round-trip form); for
    ``float`` the same decimal with the suffix ``f``, which the compiler rounds straight to the nearest float (a
    ValueError when that overflows, or is 0 for a nonzero ``value``)."""
    value = float(value)
    if value != value or value in (float("inf"), float("-inf")):
        raise LiteralError(f"the constant {value!r} is not a finite double")
    text = repr(value)
    text = text if ("." in text or "e" in text) else text + ".0"
    if scalar == "double":
        return text
    try:
        single = struct.unpack("f", struct.pack("f", value))[0]
    except OverflowError:
        single = float("inf")
    if single in (float("inf"), float("-inf")) or (single == 0.0 and value != 0.0):
        raise LiteralError(f"the constant {value!r} {'overflows' if single else 'underflows to 0 in'} a float "
                         f"(single precision holds magnitudes from about 1.4e-45 to 3.4e+38)")
    return text + "f"


def _number(value, scalar: str = "double") -> str:
    """A constant as C/NumPy source: small integers as they are, everything else as an exact literal of the
    scalar type (integers beyond 2^53, or 2^24 for float, are not exact in it: an integer literal of 2^64 or more
    is undefined in C)."""
    if type(value) is int and abs(value) < 2 ** (53 if scalar == "double" else 24):
        return str(value)
    if isinstance(value, Fraction):
        return _float_literal(value.numerator / value.denominator, scalar)
    return _float_literal(value, scalar)


_COMMENT = re.compile(r"/\*.*?\*/", re.S)
# a chunk of an output's zero entries (targets.c._zero_chunks): a store, no operation
_ZEROS = re.compile(r"\bAGGSYM_ZEROS\([^;]*\);")
# a numeric literal (not the digits of a name): one value token, whatever signs its exponent holds
_LITERAL = re.compile(r"(?<![A-Za-z_0-9.])(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
# a binary + or -: one that follows a value (a name, a literal, a closing bracket), spaces between
_BINARY = re.compile(r"[\w)\]]\s*[+-]")
# a call: a name followed by an opening parenthesis
_CALL = re.compile(r"([A-Za-z_]\w*)\s*\(")
_KEYWORDS = frozenset(("if", "for", "while", "return", "sizeof"))
_ANGLES = {"aggsym_sincos2": 2}  # sin and cos of two angles in one call: counted as two calls, one per angle


def count_ops(c_code: str) -> dict:
    """Operation counts of C statements: mul, add (incl. subtractions), div, call (unary minus not counted; one
    call per angle of aggsym_sincos2).

    A ``+`` or ``-`` is an addition when it follows a value (a name, a number, ``)`` or ``]``), as in C's grammar;
    numeric literals are read as one token first, so the sign of an exponent (``2.5e-3``) is not an operation.
    AGGSYM_ZEROS (a chunk of zero entries) holds none.  Regular expressions over the whole text: linear, with no
    Python work per token."""
    code = _LITERAL.sub("0", _ZEROS.sub(" ", _COMMENT.sub(" ", c_code)))
    calls = sum(_ANGLES.get(m.group(1), 1) for m in _CALL.finditer(code) if m.group(1) not in _KEYWORDS)
    return {"mul": code.count("*"), "add": len(_BINARY.findall(code)), "div": code.count("/"), "call": calls}


# the operand kinds of :class:`Infix` (what it decides parentheses by)
_K_REF, _K_NUM, _K_NEGNUM, _K_LIN, _K_PROD, _K_NEGPROD, _K_RATIO, _K_CALL = range(8)


@dataclass(frozen=True)
class Spelling:
    """How a target writes an expression: ``functions`` the callee of each function of
    :data:`aggsym.core.functions.FUNCTIONS` by name, ``number`` a constant's literal (int, Fraction or float ->
    text).  The operators (``+ - * /``, parentheses) are the same in every infix target."""

    functions: dict
    number: object


class Infix:
    """The infix text of an assignment's right-hand side straight from the program, spelled by a target's
    :class:`Spelling`: chains of inlined additions and multiplications flattened (no reordering, no distribution
    of ``2*(a+b)``), several constants of one sum merged, parentheses only where the grammar needs them, the names
    used appended to ``refs`` in the order printed, the operations printed counted into ``counts`` (one binary
    ``*``, ``+``/``-`` or ``/`` between every two factors, terms or operands, one call per function: what
    :func:`count_ops` reads back from C text; signs of first terms and of negative constants are unary).
    :attr:`calls` counts the function calls printed (a text without one is the same in every target whose
    literals agree)."""

    def __init__(self, program, names: dict, spelling: Spelling, counts: dict | None = None,
                 refs: list | None = None):
        self.ops = program.ops
        self.names = names
        self.counts = counts if counts is not None else {"mul": 0, "add": 0, "div": 0, "call": 0}
        self.refs = refs if refs is not None else []
        self.functions = spelling.functions
        self.number = spelling.number
        self.calls = 0  # the function calls printed so far

    def __call__(self, x, top: bool = True) -> str:
        return self._expr(x, top)[0]

    def _number(self, value):
        return (self.number(value),
                _K_NEGNUM if not isinstance(value, Fraction) and value < 0 else _K_NUM)

    def _expr(self, x, top):
        """(text, kind) of ``x`` (``top``: print its definition even when it has a name)."""
        if x.__class__ is not Node:
            return self._number(x)
        ident = x.id
        names = self.names
        if not top and ident in names:
            name = names[ident]
            self.refs.append(name)
            return name, _K_REF
        entry = self.ops[ident]
        code = entry[0]
        if code == INPUT:
            name = names[ident]
            self.refs.append(name)
            return name, _K_REF
        if code == ADD or code == SUB:
            terms = []
            self._terms(x, True, 1, terms)
            return self._lincomb(terms)
        if code == MUL:
            factors = []
            sign = self._factors(x, True, 1, factors)
            return self._prod(sign, factors)
        if code == NEG:
            text, kind = self._expr(entry[1], False)
            if kind == _K_PROD:
                return "-" + text, _K_NEGPROD
            if kind == _K_NEGPROD:
                return text[1:], _K_PROD
            if kind == _K_LIN:
                text = f"({text})"
            return "-" + text, _K_LIN  # a LinComb of one negated term
        if code == DIV:
            num, num_kind = self._expr(entry[1], False)
            den, den_kind = self._expr(entry[2], False)
            self.counts["div"] += 1
            if num_kind == _K_LIN or num_kind == _K_NEGPROD or num_kind == _K_NEGNUM:
                num = f"({num})"
            if den_kind not in (_K_REF, _K_NUM, _K_NEGNUM, _K_CALL):
                den = f"({den})"
            return f"{num}/{den}", _K_RATIO
        if code in FUNCTIONS:
            self.calls += 1
            args = [self._expr(a, False)[0] for a in entry[1:]]
            self.counts["call"] += 1
            return f"{self.functions[code]}({', '.join(args)})", _K_CALL
        raise ValueError(code)

    def _terms(self, x, top, sign, out):
        """The signed terms of a chain of inlined additions, subtractions and negations appended to ``out``:
        (sign, text, kind, constant) per term, the constant for a constant term (text None)."""
        if x.__class__ is not Node:
            out.append((sign, None, _K_NUM, x))
            return
        names = self.names
        if top or x.id not in names:
            entry = self.ops[x.id]
            code = entry[0]
            if code == ADD or code == SUB:
                self._terms(entry[1], False, sign, out)
                self._terms(entry[2], False, sign if code == ADD else -sign, out)
                return
            if code == NEG:
                self._terms(entry[1], False, -sign, out)
                return
        name = names.get(x.id)
        if name is not None:
            self.refs.append(name)
            out.append((sign, name, _K_REF, None))
            return
        text, kind = self._expr(x, False)
        if kind == _K_NEGPROD:
            out.append((-sign, text[1:], _K_PROD, None))
        else:
            out.append((sign, text, kind, None))

    def _factors(self, x, top, sign, out):
        """The operand texts of a chain of inlined products (and negations) appended to ``out``; returns the sign."""
        if x.__class__ is not Node:
            text, kind = self._number(x)
            out.append(f"({text})" if kind == _K_NEGNUM else text)
            return sign
        names = self.names
        if top or x.id not in names:
            entry = self.ops[x.id]
            code = entry[0]
            if code == MUL:
                sign = self._factors(entry[1], False, sign, out)
                return self._factors(entry[2], False, sign, out)
            if code == NEG:
                return self._factors(entry[1], False, -sign, out)
        name = names.get(x.id)
        if name is not None:
            self.refs.append(name)
            out.append(name)
            return sign
        text, kind = self._expr(x, False)
        out.append(f"({text})" if kind == _K_LIN or kind == _K_NEGPROD or kind == _K_NEGNUM else text)
        return sign

    def _prod(self, sign, factors):
        self.counts["mul"] += len(factors) - 1
        body = "*".join(factors)
        return ("-" + body, _K_NEGPROD) if sign < 0 else (body, _K_PROD)

    def _lincomb(self, terms):
        constants = [k for k, term in enumerate(terms) if term[3] is not None]
        if len(constants) >= 2:  # as _merge_constants
            total = normalize_const(sum(terms[k][0] * terms[k][3] for k in constants))
            merged = []
            for k, term in enumerate(terms):
                if k == constants[0] and not is_zero(total):
                    merged.append((1, None, _K_NUM, total) if total > 0
                                  else (-1, None, _K_NUM, normalize_const(-total)))
                elif k not in constants:
                    merged.append(term)
            terms = merged or [(1, None, _K_NUM, 0)]
        self.counts["add"] += len(terms) - 1
        parts = []
        first = True
        for sign, text, kind, value in terms:
            if text is None:
                text = self.number(value)
            elif kind == _K_LIN:
                text = f"({text})"  # (a LinComb term is always parenthesized where the tree printer would:
                # it is the one negated term of a negation, so it comes first with a minus)
            if first:
                parts.append("-" + text if sign < 0 else text)
                first = False
            else:
                parts.append(" - " + text if sign < 0 else " + " + text)
        return "".join(parts), _K_LIN
