"""The model bound to a backend: its SymPy expressions turned into scalars once (:func:`bind`).

Masses, centres of mass, constructive configurations, gravity, added masses, stiffnesses and prescribed spins
become backend scalars (:mod:`aggsym.core.backend`), so that the recursions only see scalars.  Parameters are
the program inputs ``p[i]`` on the symbolic backend, numbers on the numeric one.  A model with prescribed motions
(rotors, (2.13)) is bound at a time t: the program input ``t[0]`` on the symbolic backend, a number on the numeric
one; the prescribed rotation then belongs to the pair's q-independent part ``L0``, and its rates to ``spin``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from ..core.backend import Backend, to_scalar
from ..core.program import fold, is_zero
from ..model.tree import Tree
from ..model.types import TIME, Model, code_index
from .aggregates import General, Rigid
from .group import Motion, rotation
from .kinematics import combine, pair_functional, pair_velocity_product
from .linalg import EYE3, add, mm


@dataclass
class BoundBody:
    """One body's constant data as backend scalars."""

    L0: Motion  # the pair's part that does not depend on q: constructive L^{mu,k-1}_{lkk} = T(p) C(c), then the
    # prescribed rotation at time t for a rotor's pair
    codes: tuple  # the pair's coordinate codes in f order
    mises: Rigid | General | None  # the aggregate A_lk that multiplies accelerations: Theta_lk (2.3) at the
    # body origin, or Theta + Lambda (a General) with added masses (Prop. 2.8); None when it is zero
    rigid: Rigid | None = None  # Theta_lk alone: what gravity acts on (None for a massless frame)
    spin: tuple | None = None  # (U, U'): the prescribed relative quasi-velocity and quasi-acceleration of the
    # pair at time t (child frame): f theta', f theta'' (2.13); None for pairs with coordinates
    stiffness: tuple | None = None  # k x k scalars: Hooke stiffness C of the pair (2.27)
    rest: tuple | None = None  # k scalars: q0 of C (q - q0)
    offset: tuple | None = None  # k scalars added to the coordinates in the functional motion (Pair.offset)
    steps: tuple | None = None  # the constructive rotation as elementary rotations (axis, cos, sin), in order,
    # where one of them turns by an angle that is not a multiple of pi/2 (numeric angles only); None otherwise


@dataclass
class Bound:
    """A model bound to a backend: the tree, per-body constants and gravity."""

    model: Model
    tree: Tree
    backend: Backend
    bodies: list
    gravity: tuple  # in the world frame
    params: list  # the backend scalars of p
    t: object = None  # the time (models with prescribed motions), a backend scalar
    armature: object = 0  # the rotor inertia added on every coordinate's own axis (model.armature)
    rotors: tuple = ()  # per coordinate: armature plus its own (model.dof_armature); empty: armature on every one
    damping: tuple = ()  # per coordinate: the viscous damping (model.damping); empty: none
    coulomb: tuple = ()  # per coordinate: the Coulomb friction (model.coulomb); empty: none
    gravcomp: tuple = ()  # per body: (m_s, h_s) of its compensated weight (model.gravcomp) or None; empty: none

    def rotor(self, j: int):
        """The rotor inertia on coordinate j's own axis (the diagonal entry it adds to A)."""
        return self.rotors[j] if self.rotors else self.armature

    @property
    def has_rotors(self) -> bool:
        """Whether some coordinate has a rotor inertia (an armature) that is not exactly zero."""
        return any(not is_zero(r) for r in self.rotors) if self.rotors else not is_zero(self.armature)

    def rational(self, num: int, den: int):
        """num/den as an exact constant on the symbolic backend, a float on the numeric one."""
        return self.backend.rational(num, den)

    def scalar(self, expr):
        """A SymPy expression of the model (parameters, the time) as a scalar of this binding's backend."""
        values = dict(zip(self.model.parameter_symbols, self.params))
        if self.t is not None:
            values[TIME] = self.t
        return to_scalar(expr, values, self.backend)


def parameter_scalars(model: Model, backend, p=None) -> list:
    if backend.symbolic:
        return backend.inputs("p", len(model.parameters))
    if p is None:
        p = model.parameter_values
    p = [float(x) for x in p] if np.ndim(p) == 1 or len(p) == 0 else p
    if len(p) != len(model.parameters):
        raise ValueError(f"{model.name}: p has {len(p)} entries, the model has {len(model.parameters)} parameters")
    return list(p)


def time_scalar(model: Model, backend, t=None):
    """The time as a backend scalar: the program input t[0] (symbolic), the given number or 0 (numeric); None for
    a model without prescribed motions."""
    if not model.time_dependent:
        return None
    if backend.symbolic:
        return backend.inputs("t", 1)[0] if t is None else t
    return 0.0 if t is None else t


def bind(model: Model, backend, p=None, tree: Tree | None = None, t=None) -> Bound:
    """Evaluate the model's constant expressions on a backend (parameters symbolic or numeric), at time ``t``
    for a model with prescribed motions (default: the input t[0] on the symbolic backend, 0 on the numeric)."""
    tree = tree or Tree.of(model)
    params = parameter_scalars(model, backend, p)
    values = dict(zip(model.parameter_symbols, params))
    t = time_scalar(model, backend, t)
    if t is not None:
        values[TIME] = t

    def s(expr):
        return to_scalar(expr, values, backend)

    bodies = []
    for body in model.bodies:
        pair = body.pair
        c0 = pair.constructive_rotation()
        L0 = Motion(tuple(tuple(s(c0[i, j]) for j in range(3)) for i in range(3)), tuple(s(x) for x in pair.translation))
        rigid = None
        if body.inertial is not None:
            m, h, theta = body.inertial.mises()
            rigid = Rigid(s(m), tuple(s(x) for x in h), tuple(tuple(s(x) for x in row) for row in theta))
        mises = rigid
        if body.added_mass is not None:
            X = [[s(x) for x in row] for row in body.added_mass]
            added = General(tuple(tuple(X[i][j] for j in range(3)) for i in range(3)),
                            tuple(tuple(X[i][j] for j in range(3, 6)) for i in range(3)),
                            tuple(tuple(X[i][j] for j in range(3, 6)) for i in range(3, 6)))
            mises = added if rigid is None else rigid + added
        spin = None
        if pair.prescribed:
            L0, spin = _prescribed(pair, L0, s, backend)
        stiffness = rest = None
        if pair.stiffness is not None:
            stiffness = tuple(tuple(s(x) for x in row) for row in pair.stiffness)
            rest = tuple(s(x) for x in pair.rest) if pair.rest is not None else (0,) * len(pair.coordinates)
        offset = tuple(s(x) for x in pair.offset) if pair.offset else None
        bodies.append(BoundBody(L0, pair.codes, mises, rigid, spin, stiffness, rest, offset,
                                _steps(pair.rotation, s) if not pair.prescribed else None))
    gravity = tuple(s(x) for x in model.gravity)
    armature = fold(model.armature) if backend.symbolic else float(model.armature)
    rotors = tuple(s(a + model.armature if model.armature else a) for a in model.dof_armature)
    damping = tuple(s(d) for d in model.damping)
    coulomb = tuple(s(f) for f in model.coulomb)
    gravcomp = ()
    if model.gravcomp:
        lifted = {name: (s(m), tuple(s(x) for x in h)) for name, m, h in model.gravcomp}
        gravcomp = tuple(lifted.get(b.name) for b in model.bodies)
    return Bound(model, tree, backend, bodies, gravity, params, t, armature, rotors, damping, coulomb, gravcomp)


def _steps(rotation, s):
    """The constructive rotation's elementary rotations as (axis, cos, sin) scalars when some angle is a number that
    is not a multiple of pi/2 (then turning a 6x6 block by them one plane at a time is cheaper than the congruence
    with their product), else None."""
    if not rotation or any(getattr(a, "free_symbols", None) for _, a in rotation):
        return None
    if all(sp.simplify(a / (sp.pi / 2)).is_integer for _, a in rotation):
        return None
    return tuple((axis, s(sp.cos(a)), s(sp.sin(a))) for axis, a in rotation)


def _prescribed(pair, L0, s, backend):
    """The prescribed rotations of a pair at time t: L0 extended by them, and (U, U') = (f theta',
    f theta'' + (M F)' theta') in the child frame (1.31), (2.19).  Derivatives in t are taken by SymPy."""
    if pair.coordinates:
        raise ValueError(f"pair {pair.name!r}: a pair has either coordinates or a prescribed motion, not both")
    items = sorted(pair.prescribed, key=lambda item: code_index(item[0]))
    codes = tuple(code for code, _ in items)
    if any(code_index(c) < 3 for c in codes):
        raise ValueError(f"pair {pair.name!r}: only rotations (theta4..theta6) can be prescribed")
    angle = [s(expr) for _, expr in items]
    rate = [s(sp.diff(expr, TIME)) for _, expr in items]
    accel = [s(sp.diff(expr, TIME, 2)) for _, expr in items]
    motion, psi, rots = pair_functional(codes, angle, backend)
    U = combine(psi, rate)
    Ud = add(combine(psi, accel), pair_velocity_product(codes, rate, rots))
    return L0.compose(motion), (U, Ud)


def constant_axes(bound, axes, steps):
    """Constant axes as backend scalars: ``axes`` (3x3 expressions, columns the axes; None: the identity) turned by
    the elementary rotations ``steps`` ((axis, angle expression), ..., Prop. 1.17) in order; None when both are
    absent (a frame's or a constraint's reference axes)."""
    R = None if axes is None else tuple(tuple(bound.scalar(x) for x in row) for row in axes)
    for axis, angle in steps:
        a = bound.scalar(angle)
        R = mm(EYE3 if R is None else R, rotation(axis, bound.backend.cos(a), bound.backend.sin(a)))
    return R


def scratch_operations(bound, kin, build, budget: int | None = None) -> int:
    """The arithmetic operations (negations and inputs free) of ``build(bound, kin, qd)``'s outputs on a fresh
    straight-line program of the same model (kinematics included), so that two forms of one routine can be
    counted apart and only the smaller enters the program emitted (the inverse inertia, the Coriolis matrix).

    ``build`` gives its outputs as an iterable of rows (or columns); they are counted as they come, each node
    once, and with a ``budget`` the building stops as soon as the count reaches it (the count returned is then
    at least ``budget``, not the whole): a form already known to lose is not built to the end."""
    backend = type(bound.backend)()
    scratch = bind(bound.model, backend, tree=bound.tree)
    program = backend.program
    return program_operations(program, lambda: build(scratch, type(kin)(scratch, program.vector("q", len(kin.q))),
                                                      program.vector("qd", kin.tree.nv)), budget)


def program_operations(program, rows, budget: int | None = None) -> int:
    """The arithmetic operations (negations and inputs free) that the outputs of ``rows()`` (an iterable of lists
    of outputs) reach on a scratch ``program``, each node counted once, stopping as soon as the count reaches
    ``budget``; the program is released after (:meth:`~aggsym.core.program.Program.release`: the cyclic collector
    is paused while generating)."""
    ops = program.ops
    seen: set = set()
    count = 0
    try:
        for row in rows():
            count += sum(1 for i in program.reach(row, seen) if ops[i][0] not in ("in", "neg"))
            if budget is not None and count >= budget:
                break
    finally:
        program.release()
    return count
