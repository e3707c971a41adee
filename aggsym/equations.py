"""The equations of motion as SymPy matrices: ``aggsym.equations(model)``.

``A(q) q'' + b(q, q') + g(q) = tau`` (2.17), (2.29) with g = -S G moved to the left.  The matrices are built from
the straight-line programs of the recursions and converted to SymPy; ``simplify=True`` simplifies every entry
(meant for small models: the double pendulum comes out as (2.23)-(2.26)).
"""
from __future__ import annotations

from functools import cached_property

import sympy as sp
from sympy.simplify.fu import TR10i

from .backend import Symbolic, bind
from .bias import bias_vector, gravity_vector
from .codegen.program import Node
from .inertia import inertia_matrix
from .kinematics import TreeKinematics
from .model.tree import Tree


def coordinate_symbols(model):
    """(q, qd, qdd) as lists of real SymPy symbols named after the coordinates: x, x_d, x_dd."""
    q = [sp.Symbol(c.name, real=True) for c in model.coordinates]
    qd = [sp.Symbol(c.name + "_d", real=True) for c in model.coordinates]
    qdd = [sp.Symbol(c.name + "_dd", real=True) for c in model.coordinates]
    return q, qd, qdd


def to_sympy(program, outputs, symbols: dict):
    """SymPy expressions of program outputs; ``symbols[(kind, i)]`` names the inputs."""
    from .codegen.program import ADD, COS, DIV, INPUT, MUL, NEG, SIN, SQRT, SUB

    memo: dict[int, sp.Expr] = {}

    def conv(x):
        if isinstance(x, Node):
            return memo[x.id]
        return sp.nsimplify(x) if isinstance(x, float) and x.is_integer() else sp.sympify(x)

    for i in program.reachable(outputs):
        entry = program.ops[i]
        code = entry[0]
        if code == INPUT:
            memo[i] = symbols[(entry[1], entry[2])]
        elif code == NEG:
            memo[i] = -conv(entry[1])
        elif code == SIN:
            memo[i] = sp.sin(conv(entry[1]))
        elif code == COS:
            memo[i] = sp.cos(conv(entry[1]))
        elif code == SQRT:
            memo[i] = sp.sqrt(conv(entry[1]))
        else:
            a, b = conv(entry[1]), conv(entry[2])
            memo[i] = {ADD: a + b, SUB: a - b, MUL: a * b}[code] if code != DIV else a / b
    return [conv(o) for o in outputs]


class Equations:
    """SymPy form of a model's equations: ``S``, ``A``, ``b``, ``g``, coordinate symbols ``q``, ``qd``."""

    def __init__(self, model, simplify: bool = False):
        self.model = model
        self.tree = Tree(model)
        self.simplify = simplify
        q, qd, qdd = coordinate_symbols(model)
        self.q = sp.Matrix(q)
        self.qd = sp.Matrix(qd)
        self.qdd = sp.Matrix(qdd)
        self.parameters = sp.Matrix(list(model.parameter_symbols))
        self._backend = Symbolic()
        prog = self._backend.program
        self._bound = bind(model, self._backend, tree=self.tree)
        self._q = prog.vector("q", model.nq)
        self._qd = prog.vector("qd", model.nq)
        self._qdd = prog.vector("qdd", model.nq)
        self._kin = TreeKinematics(self._bound, self._q)
        self._symbols = {("p", i): s for i, s in enumerate(model.parameter_symbols)}
        for i in range(model.nq):
            self._symbols[("q", i)] = q[i]
            self._symbols[("qd", i)] = qd[i]
            self._symbols[("qdd", i)] = qdd[i]

    def _matrix(self, values, rows, cols):
        exprs = to_sympy(self._backend.program, values, self._symbols)
        M = sp.Matrix(rows, cols, exprs)
        return M.applyfunc(self.closed_form) if self.simplify else M

    def closed_form(self, expr):
        """A readable closed form of one entry.

        Expanded, sin^2 -> 1 - cos^2, products of sines and cosines of different angles gathered into sines and
        cosines of sums (TR10i), collected by velocities and parameters, and each coefficient kept factored
        where that is shorter, with 1 - cos^2 written back as sin^2.  Every step is an identity; this is much
        faster than ``sympy.simplify`` and gives the seeds' forms (Tokad's C23, the book's m3 (p31 + r31 c)^2).
        """
        e = sp.expand(expr)
        e = sp.expand(e.subs({sp.sin(s) ** 2: 1 - sp.cos(s) ** 2 for s in self.q}))
        e = TR10i(e)
        back = {1 - sp.cos(s) ** 2: sp.sin(s) ** 2 for s in self.q}
        parts = sp.collect(e, list(self.qd) + list(self.parameters), evaluate=False)
        terms = []
        for key, coeff in parts.items():
            plain = coeff.subs(back)
            factored = sp.factor(coeff).subs(back)
            terms.append(key * (factored if sp.count_ops(factored) < sp.count_ops(plain) else plain))
        return sp.Add(*terms)

    @cached_property
    def S(self) -> sp.Matrix:
        """The parastrophic matrix (1.42): n x 6N, row i the projections on coordinate i's axis."""
        rows = self._kin.parastrophic()
        flat = [x for row in rows for block in row for x in (block if block is not None else (0,) * 6)]
        return self._matrix(flat, len(rows), 6 * len(self.tree))

    @cached_property
    def A(self) -> sp.Matrix:
        A = inertia_matrix(self._bound, self._kin)
        return self._matrix([x for row in A for x in row], self.model.nq, self.model.nq)

    @cached_property
    def b(self) -> sp.Matrix:
        return self._matrix(bias_vector(self._bound, self._kin, self._qd), self.model.nq, 1)

    @cached_property
    def g(self) -> sp.Matrix:
        return self._matrix(gravity_vector(self._bound, self._kin), self.model.nq, 1)

    @cached_property
    def u_star(self) -> sp.Matrix:
        """The preplanned control u* = tau for the motion (q, q', q'') by the forward and backward sweeps
        (2.39)-(2.42), without assembling A, b, g."""
        from .sweeps import inverse_dynamics

        return self._matrix(inverse_dynamics(self._bound, self._kin, self._qd, self._qdd), self.model.nq, 1)

    def lhs(self) -> sp.Matrix:
        """A q'' + b + g."""
        return self.A * self.qdd + self.b + self.g


def equations(model, simplify: bool = False) -> Equations:
    """The equations of motion of a model (or a path to one) as SymPy matrices."""
    if not hasattr(model, "bodies"):
        from .model import load

        model = load(model)
    return Equations(model, simplify=simplify)
