"""The URDF reader's exact arithmetic on a link's placement and inertial data (1.24)-(1.27), (2.3).

Rotations R (x_body = R x_link + t) and inertia tensors are 3x3 tuples of rows, translations and centres of mass
3-tuples, every entry a SymPy number (exact where the file is: integers, right angles).  The operations give the
entries SymPy's ``Matrix`` operations give (the same terms added in the same order, a sum that comes out zero
made the exact 0), without building a ``Matrix`` per link: reading a 2000-link chain spent most of its time there.

* :func:`product`, :func:`turn`: a b and R v, adding the products of non-zero entries (a zero entry is
  ``S.Zero``, never a zero float);
* :func:`matvec`, :func:`add`: ``Matrix(R) * Matrix(v)`` and ``Matrix(a) + Matrix(b)`` entry for entry;
* :func:`rotation_matrix`: the product of elementary rotations (Prop. 1.17), entries near 0, +-1 snapped;
* :func:`round_off`: entries that are round-off relative to the largest of their vector or tensor made 0;
* :func:`combine`: one rigid body from the (mass, centre of mass, inertia about it) of its links.
"""
from __future__ import annotations

import functools

import sympy as sp

from .sympy_numbers import double, float_number
from ..types import Inertial, elementary_entries
from ..types import _snap as snap

ZERO, ONE = sp.S.Zero, sp.S.One
IDENTITY = ((ONE, ZERO, ZERO), (ZERO, ONE, ZERO), (ZERO, ZERO, ONE))
ORIGIN = (ZERO, ZERO, ZERO)


@functools.lru_cache(maxsize=4096)
def exact(value: float) -> sp.Expr:
    """A float from the file as a SymPy number, integers exact (so structural zeros fold) while a double holds
    them exactly (below 2^53; larger ones stay floats, not huge exact integers).  Cached: files repeat their
    numbers, an inertia tensor its products (SymPy numbers are immutable)."""
    value = float(value)
    return sp.Integer(int(value)) if value.is_integer() and abs(value) < 2 ** 53 else float_number(value)


def _terms(row, col) -> list:
    """The products of the non-zero entries of a row and a column, in order (1 x is x itself)."""
    return [y if x is ONE else x if y is ONE else x * y
            for x, y in zip(row, col) if x is not ZERO and y is not ZERO]


def product(a, b) -> tuple:
    """a b for 3x3 matrices of numbers, skipping the zero terms."""
    cols = tuple(zip(*b))
    out = []
    for row in a:
        line = []
        for col in cols:
            terms = _terms(row, col)
            line.append(terms[0] if len(terms) == 1 else sp.Add(*terms))
        out.append(tuple(line))
    return tuple(out)


def turn(R, v) -> tuple:
    """R v for a 3x3 matrix and a 3-vector, adding the non-zero products as :func:`product` does."""
    out = []
    for row in R:
        terms = _terms(row, v)
        out.append(terms[0] if len(terms) == 1 else sp.Add(*terms))
    return tuple(out)


def matvec(R, v) -> tuple:
    """R v for a 3x3 matrix and a 3-vector, as ``Matrix(R) * Matrix(v)`` gives it (a zero sum is ``S.Zero``)."""
    out = []
    for row in R:
        terms = _terms(row, v)
        s = terms[0] if len(terms) == 1 else sp.Add(*terms)
        out.append(s if s else ZERO)
    return tuple(out)


def add(a, b) -> tuple:
    """a + b for 3-vectors, as ``Matrix(a) + Matrix(b)`` gives it (a zero sum is ``S.Zero``)."""
    out = []
    for x, y in zip(a, b):
        s = y if x is ZERO else x if y is ZERO else x + y
        out.append(s if s else ZERO)
    return tuple(out)


def snapped(m) -> tuple:
    """Every entry of a 3-vector or 3x3 matrix through :func:`~aggsym.model.types._snap`."""
    return tuple(snapped(x) if isinstance(x, tuple) else snap(x) for x in m)


def transpose(m) -> tuple:
    return tuple(zip(*m))


def rotation_matrix(rotation) -> tuple:
    """The product of elementary rotations [(axis, angle), ...] (Prop. 1.17), entries snapped."""
    c = None
    for axis, angle in rotation:
        e = elementary_entries(axis, angle)
        c = e if c is None else product(c, e)
    return IDENTITY if c is None else snapped(c)


ROUND_OFF = 1e-14  # an entry of a translation, centre of mass or inertia tensor computed here (through rotations)
# below this times the largest entry of its vector or tensor is round-off: 0.  Relative, so that a millimetre robot
# with milligram links keeps every digit of its own.


def _is_zero(x: sp.Expr) -> bool:
    """x.is_zero, for a number without SymPy's assumption system (tens of microseconds for each new Float)."""
    return not x if isinstance(x, (sp.Float, sp.Integer)) else bool(x.is_zero)


def _expanded(x: sp.Expr) -> sp.Expr:
    return x if isinstance(x, sp.Number) else sp.expand(x)  # (a number is its own expansion)


def round_off(m) -> tuple:
    """``m`` (a 3-vector or a 3x3 matrix of numbers, expanded) with the entries below :data:`ROUND_OFF` of its
    largest set to 0."""
    if isinstance(m[0], tuple):
        rows = tuple(tuple(_expanded(x) for x in row) for row in m)
        flat = [x for row in rows for x in row]
    else:
        rows = None
        flat = [_expanded(x) for x in m]
    tiny = ROUND_OFF * max((abs(double(x)) for x in flat if x.is_Number), default=0.0)
    flat = [ZERO if x.is_Number and abs(double(x)) < tiny else x for x in flat]
    return tuple(flat) if rows is None else (tuple(flat[0:3]), tuple(flat[3:6]), tuple(flat[6:9]))


def combine(parts) -> Inertial | None:
    """One rigid body from several (mass, centre of mass, inertia about it), all in body axes."""
    if not parts:
        return None
    if len(parts) == 1:  # nothing to move
        mass, com, J = parts[0]
        com, J = round_off(com), round_off(J)
        if _is_zero(mass):
            com = ORIGIN
            if all(_is_zero(x) for row in J for x in row):
                return None
        return Inertial(mass, com, J)
    mass = sum((m for m, _, _ in parts), sp.Integer(0))
    if _is_zero(mass):
        com = sp.zeros(3, 1)
    else:
        com = sum((m * sp.Matrix(c) for m, c, _ in parts), sp.zeros(3, 1)) / mass
    J = sp.zeros(3, 3)
    for m, c, Jk in parts:
        d = sp.Matrix(c) - com
        J += sp.Matrix(Jk) + m * (d.dot(d) * sp.eye(3) - d * d.T)
    J = round_off(tuple(tuple(J[i, j] for j in range(3)) for i in range(3)))
    com = round_off(tuple(com))
    if _is_zero(mass) and all(_is_zero(x) for row in J for x in row):
        return None
    return Inertial(mass, com, J)
