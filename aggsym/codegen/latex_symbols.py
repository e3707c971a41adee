"""The LaTeX document's notation: short symbols for the coordinates and the parameters, and the tables that
map them back to the model's names.

A model written after the book names its coordinates and parameters as the book prints them (``o12``,
``theta25``, ``m2``, ``I244``: a Latin letter or a Greek letter's name, then digits), and the document keeps
those symbols (:math:`o_{12}`, :math:`\\theta_{25}`), so that the double pendulum reads as (2.23)-(2.26).  Any
other name, a URDF joint such as ``panda_joint1`` above all, would print as a product of italic letters with a
stray subscript; then every coordinate is written :math:`q_1 \\dots q_n` (in q order, velocities
:math:`\\dot q_i`; a free-flyer's six velocities, which are no position's rate, :math:`v_1 \\dots v_6`), and the
coordinate table maps them to the joints.

Parameters keep a book-style name; the ones the readers add get a short symbol after their kind: URDF joint
damping and friction :math:`d_i`, :math:`f_i` (i: the coordinate's index), MJCF armature, stiffness and spring
reference :math:`I^a_i`, :math:`k_i`, :math:`q^0_i`, gravity :math:`g_x`, a link's inertial parameters
:math:`m_\\ell`, :math:`(m c_x)_\\ell`, :math:`I_{xx,\\ell}` (ℓ numbering the links in the order p holds them; a
payload's ℓ is P); anything else is :math:`p_k`, its index in p.  A symbol met twice falls back to
:math:`p_k`.  Nothing of a user's name reaches the LaTeX except through these fixed forms or, in the tables,
through the escaping filter (:func:`aggsym.codegen.escape.latex`).
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import sympy as sp

from ..symbolic import coordinate_symbols

_GREEK = ("alpha beta gamma delta epsilon varepsilon zeta eta theta vartheta iota kappa lambda mu nu xi pi "
          "varpi rho varrho sigma varsigma tau upsilon phi varphi chi psi omega Gamma Delta Theta Lambda Xi Pi "
          "Sigma Upsilon Phi Psi Omega").split()
BOOK_NAME = re.compile(r"^(?:[A-Za-z]|%s)(?:\d+(?:_\d+)*)?$" % "|".join(_GREEK))
_INERTIAL = {"m": "m_{%s}", "mcx": "(m c_{x})_{%s}", "mcy": "(m c_{y})_{%s}", "mcz": "(m c_{z})_{%s}",
             "Ixx": "I_{xx,%s}", "Ixy": "I_{xy,%s}", "Iyy": "I_{yy,%s}", "Ixz": "I_{xz,%s}", "Iyz": "I_{yz,%s}",
             "Izz": "I_{zz,%s}"}
_INERTIAL_WHAT = {"m": "mass", "mcx": "mass times centre of mass, x", "mcy": "mass times centre of mass, y",
                  "mcz": "mass times centre of mass, z", "Ixx": "inertia xx", "Ixy": "inertia xy",
                  "Iyy": "inertia yy", "Ixz": "inertia xz", "Iyz": "inertia yz", "Izz": "inertia zz"}
_PER_COORDINATE = {"damping": ("d_{%d}", "viscous damping of $%s$"),
                   "friction": ("f_{%d}", "Coulomb friction of $%s$"),
                   "armature": ("I^{a}_{%d}", "rotor inertia (armature) of $%s$"),
                   "stiffness": ("k_{%d}", "stiffness of $%s$"),
                   "springref": ("q^{0}_{%d}", "spring reference position of $%s$")}
INTERMEDIATE_LETTERS = ("x", "w", "z", "\\xi", "\\zeta")  # the first not used by the model's own symbols


@dataclass(frozen=True)
class CoordinateRow:
    symbol: str  # LaTeX (ours)
    name: str  # the model's identifier (user text: escape it)
    joint: str  # the joint's name in the file (user text: escape it)
    kind: str  # rotation | translation | quaternion | velocity


@dataclass(frozen=True)
class ParameterRow:
    symbol: str  # LaTeX (ours)
    name: str  # the parameter's name (user text: escape it)
    value: str  # repr of its default
    what: str  # what it is, LaTeX of ours ('' when the model does not say)
    whose: str  # the link or joint it belongs to (user text: escape it; '' for none)


class Notation:
    """The symbols of one model's document: ``names`` {SymPy symbol: LaTeX} for q, q', q'' and p (what SymPy's
    printer and the intermediate form use), the coordinate and parameter tables, the intermediates' letter."""

    def __init__(self, model):
        q, qd, qdd = coordinate_symbols(model)
        positions = [name for name, _, _ in model.positions]
        self.own = all(BOOK_NAME.match(n) for n in positions) and all(
            BOOK_NAME.match(c.name) for c in model.coordinates)
        self.names = {}
        self.coordinates = []
        index = {}  # coordinate name -> the index (1-based) its symbol carries
        for k, (s, (name, joint, kind)) in enumerate(zip(q, model.positions)):
            text = sp.latex(s) if self.own else f"q_{{{k + 1}}}"
            self.names[s] = text
            index[name] = k + 1
            self.coordinates.append(CoordinateRow(text, name, joint, kind))
        self.velocities = []  # the rates that are no position's (a free-flyer's v)
        self.rates, self.accelerations = [], []
        for j, (c, d, dd) in enumerate(zip(model.coordinates, qd, qdd)):
            if c.name in index:
                base = self.names[q[positions.index(c.name)]]
                self.names[d], self.names[dd] = _accent(base, "dot"), _accent(base, "ddot")
            else:
                base = sp.latex(sp.Symbol(c.name)) if self.own else f"v_{{{j + 1}}}"
                self.names[d], self.names[dd] = base, _accent(base, "dot")
                self.velocities.append(CoordinateRow(base, c.name, c.joint, "velocity"))
            self.rates.append(self.names[d])
            self.accelerations.append(self.names[dd])
        taken = set(self.names.values())
        self.parameters = []
        links = {}  # link identifier -> its number
        for k, p in enumerate(model.parameters):
            symbol, what, whose = self._parameter(p.name, index, links)
            if symbol is None or symbol in taken:
                symbol, what, whose = self._fallback(k, taken), what or "", whose
            taken.add(symbol)
            self.names[p.symbol] = symbol
            self.parameters.append(ParameterRow(symbol, p.name, repr(p.value), what, whose))
        bases = {_base(t) for t in taken}
        self.letter = next(x for x in INTERMEDIATE_LETTERS if x not in bases)

    def _parameter(self, name, index, links):
        """(symbol, what, whose) of a parameter by its name's form, or (None, '', '')."""
        if BOOK_NAME.match(name):
            return sp.latex(sp.Symbol(name)), "", ""
        head, _, tail = name.partition("_")
        if head in _PER_COORDINATE and tail in index:
            form, what = _PER_COORDINATE[head]
            k = index[tail]  # (the coordinate table names its joint)
            return form % k, what % self.coordinates[k - 1].symbol, ""
        if head == "gravity" and tail in ("x", "y", "z"):
            return f"g_{{{tail}}}", f"gravity, {tail} component (world axes)", ""
        if head == "payload" and tail in _INERTIAL:
            return _INERTIAL[tail] % "P", _INERTIAL_WHAT[tail] + " of the payload", ""
        if head in _INERTIAL and tail:
            number = links.setdefault(tail, len(links) + 1)
            return _INERTIAL[head] % number, _INERTIAL_WHAT[head] + " of link", tail
        return None, "", ""

    @staticmethod
    def _fallback(k, taken):
        for form in ("p_{%d}", "\\varpi_{%d}", "\\mathrm{p}_{%d}"):
            if form % (k + 1) not in taken:
                return form % (k + 1)
        raise ValueError(f"no free symbol for parameter {k + 1}")  # (three forms cannot all be taken twice)


def _accent(base: str, accent: str) -> str:
    """\\dot{x}_{12} from x_{12} (the accent on the letter, not on its subscript)."""
    letter, sep, sub = base.partition("_")
    return f"\\{accent}{{{letter}}}{sep}{sub}"


def _base(symbol: str) -> str:
    """The letter a symbol is written with (x of x_{3}, \\theta of \\theta_{2})."""
    return re.split(r"[_^{]", symbol, maxsplit=1)[0] or symbol
