"""Expressions as breakable LaTeX pieces (:class:`~aggsym.codegen.latex_layout.Piece`) for the document's
equations: aggsym's expression trees of the intermediate form (:mod:`.printing`) and SymPy's closed forms.

The intermediate form prints the program as built, with the obvious simplifications a reader expects and that
change no value: equal terms of a sum gathered (``x + x`` is ``2 x``, ``x - x`` vanishes), equal factors of a
product written as a power (``q q`` is ``q^2``).  Constants are shown to six significant digits (the generated
code holds them exactly; the document says so).  Parentheses are sized by what they hold
(:func:`~aggsym.codegen.latex_layout.paren`), so that a line may break inside them.

Closed forms are SymPy's LaTeX term by term; a term too wide for a line is opened: its denominator first as
``\\frac{1}{...}``, then its factors, a factor that is a sum in breakable parentheses.
"""
from __future__ import annotations

import sympy as sp

from .latex_layout import Piece, joined, paren, width
from ..core.program import normalize_const
from .printing import LinComb, Num, Prod, Ratio, Ref

_FUNCTIONS = {"sin": "\\sin", "cos": "\\cos", "tan": "\\tan", "exp": "\\exp", "log": "\\log", "asin": "\\arcsin",
              "acos": "\\arccos", "atan": "\\arctan", "atan2": "\\operatorname{atan2}",
              "sign": "\\operatorname{sign}"}


class TreePieces:
    """The printer of the intermediate form's trees: ``print(tree)`` -> ([Piece], height) where height is the
    depth of parentheses inside."""

    def __init__(self):
        self._numbers = {}

    def number(self, value) -> str:
        text = self._numbers.get((value.__class__, value))
        if text is None:
            text = self._numbers[(value.__class__, value)] = sp.latex(
                sp.nsimplify(value) if not isinstance(value, float) else sp.Float(value, 6))
        return text

    def print(self, e):
        cls = e.__class__
        if cls is Ref:
            return [Piece(str(e.symbol))], 0
        if cls is Num:
            return [Piece(self.number(e.value))], 0
        if cls is LinComb:
            return self._sum(e.terms)
        if cls is Prod:
            return self._product(e.sign, e.factors)
        if cls is Ratio:
            num, h1 = self.print(e.num)
            den, h2 = self.print(e.den)
            return [Piece(f"\\frac{{{joined(num)}}}{{{joined(den)}}}")], max(h1, h2)
        return self._call(e)

    def _gather(self, terms):
        """[(count, pieces, height, term)]: the signed terms printed, equal ones (by their text) gathered at the
        place of the first, those that cancel dropped."""
        order, count, printed = [], {}, {}
        for sign, term in terms:
            pieces, h = self.print(term)
            if term.__class__ in (Prod, Num) and pieces[0].text.startswith("-"):  # its sign moves out
                pieces = [Piece(pieces[0].text[1:].lstrip(), pieces[0].brk)] + pieces[1:]
                sign = -sign
                term = Prod(1, term.factors) if term.__class__ is Prod else Num(-term.value)
            key = joined(pieces)
            if key not in count:
                order.append(key)
                count[key] = 0
                printed[key] = (pieces, h, term)
            count[key] += sign
        return [(count[key],) + printed[key] for key in order if count[key] != 0]

    def _sum(self, terms, gathered=None):
        """Signed terms, equal ones gathered (``x + x`` is ``2 x``)."""
        out, height = [], 0
        for c, pieces, h, term in gathered if gathered is not None else self._gather(terms):
            height = max(height, h)
            if term.__class__ is LinComb and (len(term.terms) > 1 or abs(c) != 1 or out):
                pieces, h = _wrap(pieces, h)
                height = max(height, h)
            if abs(c) != 1:
                glue = " \\cdot " if pieces[0].text[:1].isdigit() else " "
                pieces = [Piece(f"{abs(c)}{glue}{pieces[0].text}")] + pieces[1:]
            sign = "-" if c < 0 else "+"
            first = pieces[0].text
            if out:
                pieces = [Piece(f"{sign} {first}", True)] + pieces[1:]
            elif sign == "-":
                pieces = [Piece(f"-{first}")] + pieces[1:]
            out.extend(pieces)
        return out or [Piece("0")], height

    def _product(self, sign, factors):
        """The factors, equal ones as powers (at the place of the first), constants after the first as
        ``\\cdot c``, sums in parentheses; a sum that gathers into one term (``x + x``) gives its count to the
        product's constant (``c (x + x)`` is ``2c x``)."""
        multiple, plain = 1, []
        for f in factors:
            if f.__class__ is LinComb:
                gathered = self._gather(f.terms)
                if len(gathered) == 1 and gathered[0][3].__class__ is not LinComb:
                    c, _, _, term = gathered[0]
                    multiple *= c
                    plain.append(term)
                    continue
            plain.append(f)
        if multiple != 1:
            constants = [k for k, f in enumerate(plain) if f.__class__ is Num]
            if constants:
                plain[constants[0]] = Num(normalize_const(plain[constants[0]].value * abs(multiple)))
            else:
                plain.insert(0, Num(abs(multiple)))
            sign = -sign if multiple < 0 else sign
        order, count, printed = [], {}, {}
        for f in plain:
            pieces, h = self.print(f)
            if f.__class__ is LinComb or (f.__class__ is Prod and f.sign < 0):
                pieces, h = _wrap(pieces, h)
            key = joined(pieces)
            if key not in count:
                order.append(key)
                count[key] = 0
                printed[key] = (pieces, h, f)
            count[key] += 1
        out, height = [], 0
        for k, key in enumerate(order):
            pieces, h, f = printed[key]
            height = max(height, h)
            if count[key] > 1:
                last = pieces[-1].text
                base = last if f.__class__ is not Ref or "^" not in last else f"{{{last}}}"
                pieces = pieces[:-1] + [Piece(f"{base}^{{{count[key]}}}", pieces[-1].brk)]
            if k and f.__class__ is Num:
                pieces = [Piece(f"\\cdot {pieces[0].text}")] + pieces[1:]
            out.extend(pieces)
        if sign < 0:
            out[0] = Piece(f"-{out[0].text}", out[0].brk)
        return out, height

    def _call(self, e):
        args = [self.print(a) for a in e.args]
        height = max(h for _, h in args)
        text = ", ".join(joined(p) for p, _ in args)
        if e.name == "sqrt":
            return [Piece(f"\\sqrt{{{text}}}")], height
        if e.name == "abs":
            return [Piece(f"\\lvert {text}\\rvert")], height
        left, right = paren(height)
        return [Piece(f"{_FUNCTIONS[e.name]}{left}{text}{right}")], height + 1


def _wrap(pieces, height):
    """The pieces in parentheses sized by their height; a break may fall inside."""
    left, right = paren(height)
    out = list(pieces)
    out[0] = Piece(left + out[0].text, False)
    out[-1] = Piece(out[-1].text + right, out[-1].brk)
    return out, height + 1


# --------------------------------------------------------------------------------------------------------------
# SymPy's closed forms


def sympy_latex(expr, names) -> str:
    return sp.latex(expr, symbol_names=names, long_frac_ratio=2, mul_symbol=None)


def sympy_terms(expr, names, room: float) -> list:
    """The pieces of a SymPy expression: its top-level terms (a break before each), and inside any term wider
    than ``room`` pt its factors (:func:`_opened`)."""
    terms = sp.Add.make_args(expr) if expr.is_Add else (expr,)
    out = []
    for t in terms:
        negative = t.could_extract_minus_sign()
        body = -t if negative else t
        text = sympy_latex(body, names)
        pieces = [Piece(text)] if width(text) <= room else _opened(body, names, room)
        sign = "- " if negative else "+ "
        out.append(Piece(sign + pieces[0].text, True))
        out.extend(pieces[1:])
    return out or [Piece("0")]


def _opened(term, names, room: float) -> list:
    """A product too wide for a line as pieces: 1/denominator, the coefficient, then each factor, sums (and
    powers of sums) in breakable parentheses."""
    num, den = sp.fraction(term)
    out = []
    if den != 1:
        text = sympy_latex(den, names)
        if width(text) <= room / 2:
            out.append(Piece(f"\\frac{{1}}{{{text}}}"))
        else:  # a denominator too wide for a fraction: (den)^{-1}, broken like a factor
            out.extend(_factor_pieces(den, -1, names, room) if den.is_Add else
                       [Piece(f"\\left({text}\\right)^{{-1}}")])
    coeff, rest = num.as_coeff_Mul()
    if coeff != 1:
        out.append(Piece(sympy_latex(coeff, names)))
    for f in (rest.as_ordered_factors() if rest.is_Mul else [rest]):
        base, exp = (f.base, f.exp) if f.is_Pow and f.base.is_Add and f.exp.is_Integer else (f, None)
        if base.is_Add:
            out.extend(_factor_pieces(base, exp, names, room))
        else:
            out.append(Piece(sympy_latex(f, names)))
    return out


def _factor_pieces(base, exp, names, room: float) -> list:
    """A sum as a factor, (base)^exp, in breakable parentheses."""
    inner = sympy_terms(base, names, room)
    left, right = paren(1)
    first = inner[0].text[2:] if inner[0].text.startswith("+ ") else inner[0].text
    inner[0] = Piece(left + first)
    power = f"^{{{sympy_latex(exp, names)}}}" if exp is not None and exp != 1 else ""
    inner[-1] = Piece(inner[-1].text + right + power, inner[-1].brk)
    return inner
