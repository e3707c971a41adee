"""The equations of motion as SymPy matrices: ``aggsym.equations(model)``.

``A(q) q'' + b(q, q') + g(q) + c(q) = tau`` (2.17), (2.27), (2.29) with g = -S G moved to the left and c = C (q - q0)
the force of the elastic pairs.  The matrices are built from
the straight-line programs of the recursions and converted to SymPy; ``simplify=True`` simplifies every entry
(meant for small models: the double pendulum comes out as (2.23)-(2.26)).
"""
from __future__ import annotations

from functools import cached_property

import sympy as sp
from sympy.simplify.fu import TR10i

from .core.backend import Symbolic
from .core.program import to_sympy
from .errors import AggsymError
from .mechanics.bias import bias_vector, gravity_vector
from .mechanics.bound import bind
from .mechanics.elastic import elastic_forces
from .mechanics.passive import has_passive, left_forces
from .mechanics.inertia import inertia_matrix
from .mechanics.kinematics import TreeKinematics
from .mechanics.sweeps import inverse_dynamics
from .mechanics.transvective import articulated_factors
from .model.tree import Tree
from .model.types import TIME


def coordinate_symbols(model):
    """(q, qd, qdd) as lists of real SymPy symbols named after the coordinates: x, x_d, x_dd (q: the entries of q,
    a free-flyer's seven positions included, :attr:`aggsym.model.types.Model.positions`)."""
    q = [sp.Symbol(name, real=True) for name, _, _ in model.positions]
    qd = [sp.Symbol(c.name + "_d", real=True) for c in model.coordinates]
    qdd = [sp.Symbol(c.name + "_dd", real=True) for c in model.coordinates]
    return q, qd, qdd


class Equations:
    """SymPy form of a model's equations: ``S``, ``A``, ``b``, ``g``, coordinate symbols ``q``, ``qd``."""

    def __init__(self, model, simplify: bool = False):
        if model.couplings:
            raise AggsymError(f"{model.name}: the SymPy equations of a model with coupled coordinates are not "
                              f"built; use the numeric twin or the generated code")
        self.model = model
        self.tree = Tree.of(model)
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
        self._qd = prog.vector("qd", model.nv)
        self._qdd = prog.vector("qdd", model.nv)
        self._kin = TreeKinematics(self._bound, self._q)
        self._symbols = {("p", i): s for i, s in enumerate(model.parameter_symbols)}
        self._symbols[("t", 0)] = TIME  # the time of prescribed motions (rotors)
        for i in range(model.nq):
            self._symbols[("q", i)] = q[i]
        for i in range(model.nv):
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
        return self._matrix([x for row in A for x in row], self.model.nv, self.model.nv)

    @cached_property
    def b(self) -> sp.Matrix:
        return self._matrix(bias_vector(self._bound, self._kin, self._qd), self.model.nv, 1)

    @cached_property
    def g(self) -> sp.Matrix:
        return self._matrix(gravity_vector(self._bound, self._kin), self.model.nv, 1)

    @cached_property
    def u_star(self) -> sp.Matrix:
        """The preplanned control u* = tau for the motion (q, q', q'') by the forward and backward sweeps
        (2.39)-(2.42), without assembling A, b, g; with the elastic forces C (q - q0) of (2.27) where there are
        springs, and the damping D qd, the fixed tendons' springs and dampers and the Coulomb friction asked for where
        the model has them (MJCF)."""
        tau = self._matrix(inverse_dynamics(self._bound, self._kin, self._qd, self._qdd), self.model.nv, 1)
        if has_passive(self.model):  # C (q - q0), and a joint damping D qd, tendon forces, friction (MJCF) too
            tau = tau + self._matrix(left_forces(self._bound, self._q, self._qd), self.model.nv, 1)
        return tau

    @cached_property
    def c(self) -> sp.Matrix:
        """C (q - q0), the elastic generalized force of (2.27) (zero without elastic pairs)."""
        c = to_sympy(self._backend.program, elastic_forces(self._bound, self._q), self._symbols)
        return sp.Matrix(self.model.nv, 1, [sp.expand(x) for x in c])

    def transvective_factors(self, simplify: bool = False):
        """The Cauchy form (3.20) as SymPy objects: ``(T_factors, diag)``.

        ``T_factors`` are the n x n matrices ``t_tk^-1(<t,k>) = E - <t,k> E_tk`` in product order, so that
        ``T = T_factors[0] * T_factors[1] * ...``; factors whose argument is zero (structurally, or after
        simplification when ``simplify``) are left out.  ``diag`` is the diagonal matrix of the pivots
        (beta,beta)^k, so ``A^-1 = T^T diag^-1 T`` and ``q'' = T^T diag^-1 T F`` (3.19), (3.20)."""
        fac = articulated_factors(self._bound, self._kin)
        args = to_sympy(self._backend.program, fac.arguments(), self._symbols)
        diag = to_sympy(self._backend.program, list(fac.diag), self._symbols)
        if simplify:
            args = [sp.simplify(a) for a in args]
            diag = [sp.simplify(d) for d in diag]
        n = self.model.nv
        factors = []
        for (t, k), a in zip(fac.pairs, args):
            if a == 0:
                continue
            m = sp.eye(n)
            m[t, k] = -a
            factors.append(m)
        return factors, sp.diag(*diag)

    def lhs(self) -> sp.Matrix:
        """A q'' + b + g + c (2.27)."""
        return self.A * self.qdd + self.b + self.g + self.c


def equations(model, simplify: bool = False) -> Equations:
    """The equations of motion of a model (or a path to one) as SymPy matrices."""
    if not hasattr(model, "bodies"):
        from .model import load

        model = load(model)
    return Equations(model, simplify=simplify)


def factored_form(model, simplify: bool = False):
    """The transvective factors of a model (or a path to one) as SymPy matrices: see
    :meth:`Equations.transvective_factors`."""
    return equations(model).transvective_factors(simplify)
