"""Line breaking of the LaTeX document's displayed equations, without TeX at generation time.

The document is meant to be printed: no displayed line may run into the margin.  The texlive base set that
the tests install has no ``breqn``, so the breaking is done here: an equation's right-hand side is a list of
*pieces* (LaTeX text), each marked where a line may break before it (before a ``+`` or ``-`` at any depth of
parentheses); :func:`align_rows` fills ``align*`` lines greedily up to the text width, continuation lines
indented by ``\\quad``.  Parentheses that a break may fall between are written ``\\bigl(``/``\\bigr)`` (sized by
hand, :func:`paren`), never ``\\left``/``\\right``, which must close on their own line.

The width of a piece is estimated from its text (:func:`width`): glyph widths of Computer Modern at 10 pt,
scripts at 70 %, fractions as their wider part, TeX's spacing around binary operators and relations.  The
estimates were checked against pdflatex's own boxes (``tests/test_latex_document.py`` compiles a 7-DOF robot
and reads its log: no overfull box).  Everything here is pure text processing, so the output is deterministic.
"""
from __future__ import annotations

import re

TEXT_WIDTH = 483.0  # pt: A4 paper with 2 cm margins (the template's geometry), less nothing
SAFETY = 0.93  # the share of the text width lines are filled to (the estimates are not exact)
QUAD = 10.0  # pt, \quad at 10 pt

_LOWER = dict(zip("abcdefghijklmnopqrstuvwxyz",
                  (5.3, 4.3, 4.4, 5.2, 4.7, 4.9, 4.8, 5.8, 3.5, 4.2, 5.3, 3.0, 8.8, 6.0, 4.9, 5.1, 4.5, 4.6, 4.7,
                   3.7, 5.8, 5.0, 7.3, 5.8, 5.0, 4.7)))
_UPPER = 7.7  # an average capital (cmmi10: A 7.5, I 4.4, M 9.7, W 9.5)
_DIGIT = 5.0
_BINARY = 7.8 + 2 * 2.3  # + - \cdot with medium spaces either side
_RELATION = 7.8 + 2 * 2.8  # = with thick spaces either side
_FUNCTIONS = {"sin": 13.0, "cos": 13.4, "tan": 14.0, "exp": 15.0, "log": 12.6, "arcsin": 26.0, "arccos": 26.4,
              "arctan": 27.0, "sign": 17.0, "atan2": 24.0}
_WIDTHS = {"quad": QUAD, "qquad": 2 * QUAD, ",": 1.7, ";": 2.8, ":": 2.2, "!": -1.7, "cdot": _BINARY,
           "langle": 3.9, "rangle": 3.9, "ldots": 13.0, "cdots": 13.0, "infty": 10.0, "partial": 5.7,
           "{": 5.0, "}": 5.0, "$": 5.0, "&": 7.8, "#": 8.3, "_": 5.0, "%": 8.3,
           # a sized delimiter: what it adds to the delimiter's own width (counted as the next character)
           "left": 2.0, "right": 2.0, "bigl": 1.0, "bigr": 1.0, "Bigl": 1.5, "Bigr": 1.5, "big": 1.0, "Big": 1.5}
_IGNORED = {"displaystyle", "nonumber", "limits", "mathopen", "mathclose"}
_GROUPED = {"dot", "ddot", "hat", "tilde", "bar", "vec", "mathrm", "mathit", "mathbf", "operatorname", "text",
            "textrm", "boldsymbol", "overline"}
_COMMAND = re.compile(r"\\([A-Za-z]+|.)")


def _group(text: str, k: int) -> tuple[str, int]:
    """The group starting at text[k] ({...} or one token) and the index after it."""
    while k < len(text) and text[k] == " ":
        k += 1
    if k >= len(text):
        return "", k
    if text[k] == "{":
        depth, j = 0, k
        while j < len(text):
            if text[j] == "\\":
                j += 2
                continue
            if text[j] == "{":
                depth += 1
            elif text[j] == "}":
                depth -= 1
                if depth == 0:
                    return text[k + 1:j], j + 1
            j += 1
        return text[k + 1:], len(text)
    if text[k] == "\\":
        m = _COMMAND.match(text, k)
        return m.group(), m.end()
    return text[k], k + 1


def width(text: str, scale: float = 1.0) -> float:
    """The estimated width in pt of LaTeX math ``text`` at 10 pt (``scale``: 0.7 in scripts)."""
    total, k, n = 0.0, 0, len(text)
    while k < n:
        ch = text[k]
        if ch == "\\":
            m = _COMMAND.match(text, k)
            name, k = m.group(1), m.end()
            if name in _IGNORED:
                continue
            if name in _FUNCTIONS:
                total += (_FUNCTIONS[name] + 1.7) * scale
            elif name in _WIDTHS:
                total += _WIDTHS[name] * scale
            elif name in _GROUPED:
                inner, k = _group(text, k)
                total += width(inner, scale) * (1.1 if name in ("mathrm", "operatorname", "text") else 1.0)
            elif name in ("frac", "dfrac", "tfrac"):
                num, k = _group(text, k)
                den, k = _group(text, k)
                total += max(width(num, scale), width(den, scale)) + 2.4 * scale
            elif name == "sqrt":
                inner, k = _group(text, k)
                total += width(inner, scale) + 8.4 * scale
            elif name[0].isalpha():  # Greek letters and other symbols
                total += 6.2 * scale
            else:  # an escaped character: \{ \} \_ ...
                total += _WIDTHS.get(name, 5.0) * scale
            continue
        k += 1
        if ch in "_^":
            inner, k = _group(text, k)
            total += width(inner, scale * 0.8 if scale > 0.6 else scale)
        elif ch == "{":
            inner, k = _group(text, k - 1)
            total += width(inner, scale)
        elif ch in " }&":
            continue
        elif ch in "+-":
            total += _BINARY * scale
        elif ch in "=<>":
            total += _RELATION * scale
        elif ch in "()[]|":
            total += 3.9 * scale
        elif ch == ",":
            total += 4.5 * scale  # the comma and the space after it
        elif ch == ".":
            total += 2.8 * scale
        elif ch == "'":
            total += 2.8 * scale
        elif ch == "*":
            total += 5.0 * scale
        elif ch.isdigit():
            total += _DIGIT * scale
        elif ch.islower():
            total += _LOWER.get(ch, 5.5) * scale
        elif ch.isupper():
            total += _UPPER * scale
        else:
            total += 5.5 * scale
    return total


class Piece:
    """Text of a right-hand side; ``brk``: a line may break before it (it starts with ``+`` or ``-``, or is a
    factor of a product of matrices); ``size``: its width in pt where the text does not tell (a matrix)."""

    __slots__ = ("text", "brk", "size")

    def __init__(self, text: str, brk: bool = False, size: float | None = None):
        self.text = text
        self.brk = brk
        self.size = size

    def __repr__(self):
        return f"Piece({self.text!r}, {self.brk})"


def joined(pieces) -> str:
    """The pieces as one line of text."""
    return _spaced(p.text for p in pieces)


def matrix(entries) -> Piece:
    """A pmatrix of LaTeX ``entries`` (rows of texts) as one piece, a break allowed before it."""
    body = " \\\\ ".join(" & ".join(row) for row in entries)
    columns = [max(width(row[j]) for row in entries) for j in range(len(entries[0]))]
    return Piece(f"\\begin{{pmatrix}} {body} \\end{{pmatrix}}", True, sum(columns) + 10.0 * len(columns) + 8.0)


def _spaced(texts) -> str:
    out = ""
    for t in texts:
        if out and t and not out.endswith(("(", "{", " ")) and not t.startswith((")", "}", "^", "_", " ")):
            out += " "
        out += t
    return out


def paren(height: int) -> tuple[str, str]:
    """The parentheses around a sum holding ``height`` levels of parentheses itself: (), \\bigl( \\bigr),
    \\Bigl( \\Bigr); fixed sizes, so that a line may break between them."""
    if height <= 0:
        return "(", ")"
    if height == 1:
        return "\\bigl(", "\\bigr)"
    return "\\Bigl(", "\\Bigr)"


def _segments(pieces) -> list:
    """The pieces grouped into unbreakable runs, each run starting where a break is allowed."""
    runs = []
    for p in pieces:
        if p.brk and runs and runs[-1]:
            runs.append([p])
        elif runs:
            runs[-1].append(p)
        else:
            runs.append([p])
    return runs


def fill(pieces, first: float, rest: float) -> list[str]:
    """The pieces on lines of at most ``first`` pt (the first line) and ``rest`` pt (the others), broken only
    before pieces marked ``brk``; a run wider than a line stays whole on its own line."""
    lines, current, used = [], [], 0.0
    for run in _segments(pieces):
        w = sum(p.size for p in run if p.size is not None) + width(joined(p for p in run if p.size is None))
        budget = first if not lines else rest
        if current and used + w > budget:
            lines.append(joined(current))
            current, used = [], 0.0
        current.extend(run)
        used += w
    if current or not lines:
        lines.append(joined(current))
    return lines


def align_rows(rows, text_width: float = TEXT_WIDTH) -> list[str]:
    """The rows of one ``align*`` block, broken to the text width.

    ``rows``: (lhs, pieces, tail): ``lhs &= pieces`` when ``lhs`` is not None, else ``&pieces tail`` (tail e.g.
    ``= \\tau_{1}``, kept on the last line).  All rows share the block's left column, as wide as its widest
    ``lhs``; continuation lines start at the alignment point with ``\\quad``.  Returns the rows' text, each
    possibly several lines joined by ``\\\\``."""
    left = max((width(lhs) for lhs, _, _ in rows if lhs is not None), default=0.0)
    room = text_width * SAFETY - left
    out = []
    for lhs, pieces, tail in rows:
        pieces = list(pieces) or [Piece("0")]
        if pieces[0].text.startswith("+ "):
            pieces[0] = Piece(pieces[0].text[2:], pieces[0].brk)
        if tail:
            pieces.append(Piece(tail))
        first = room - (_RELATION if lhs is not None else 0.0)
        lines = fill(pieces, first, room - QUAD - _BINARY)
        head = f"{lhs} &= {lines[0]}" if lhs is not None else f"&{lines[0]}"
        out.append(" \\\\\n".join([head] + [f"&\\quad {line}" for line in lines[1:]]))
    return out
