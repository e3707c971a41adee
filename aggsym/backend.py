"""The two backends the recursions run on, and the model bound to one of them.

* :class:`Symbolic` records a straight-line program (:mod:`aggsym.codegen.program`); parameters are the
  program inputs ``p[i]``.
* :class:`Numeric` computes with floats or NumPy arrays (the numeric twin); parameters are numbers.

:func:`bind` turns the model's SymPy expressions (masses, centres of mass, constructive configurations,
gravity) into scalars of the backend once, so that the recursions only see scalars.
"""
from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np
import sympy as sp

from .aggregates import Rigid
from .codegen.program import Program, normalize_const
from .group import Motion
from .model.tree import Tree
from .model.types import Model


class Symbolic:
    """Record operations into a :class:`Program`."""

    symbolic = True

    def __init__(self, program: Program | None = None):
        self.program = program or Program()
        self.sin = self.program.sin
        self.cos = self.program.cos
        self.sqrt = self.program.sqrt

    def inputs(self, kind: str, n: int) -> list:
        return self.program.vector(kind, n)


class Numeric:
    """Compute with floats (or NumPy arrays, element-wise over a batch)."""

    symbolic = False
    sin = staticmethod(np.sin)
    cos = staticmethod(np.cos)
    sqrt = staticmethod(np.sqrt)


_FUNCS = {sp.sin: "sin", sp.cos: "cos"}


def to_scalar(expr, values: dict, backend):
    """A SymPy expression over parameter symbols as a backend scalar; ``values`` maps symbols to scalars."""
    expr = sp.sympify(expr)
    if expr.is_Integer:
        return int(expr)
    if expr.is_Rational:
        q = Fraction(int(expr.p), int(expr.q))
        return q if backend.symbolic else float(q)
    if expr.is_Number or expr.is_NumberSymbol:
        return normalize_const(float(expr))
    if expr.is_Symbol:
        return values[expr]
    args = [to_scalar(a, values, backend) for a in expr.args]
    if expr.is_Add:
        acc = args[0]
        for a in args[1:]:
            acc = acc + a
        return acc
    if expr.is_Mul:
        acc = args[0]
        for a in args[1:]:
            acc = acc * a
        return acc
    if expr.is_Pow:
        base, exponent = args[0], expr.args[1]
        if exponent == sp.Rational(1, 2):
            return backend.sqrt(base)
        if exponent.is_Integer:
            n = int(exponent)
            out = _power(base, abs(n))
            return 1 / out if n < 0 else out
        raise ValueError(f"unsupported power {expr}")
    if expr.func in _FUNCS:
        return getattr(backend, _FUNCS[expr.func])(args[0])
    if expr.func == sp.sqrt:
        return backend.sqrt(args[0])
    raise ValueError(f"unsupported expression {expr}")


def _power(x, n: int):
    out, base = 1, x
    while n:
        if n & 1:
            out = out * base
        n >>= 1
        if n:
            base = base * base
    return out


@dataclass
class BoundBody:
    """One body's constant data as backend scalars."""

    L0: Motion  # constructive part of the pair, L^{mu,k-1}_{lkk} = T(p) C(c)
    codes: tuple  # the pair's coordinate codes in f order
    mises: Rigid | None  # Theta_lk (2.3) at the body origin, or None for a massless frame


@dataclass
class Bound:
    """A model bound to a backend: the tree, per-body constants and gravity."""

    model: Model
    tree: Tree
    backend: object
    bodies: list
    gravity: tuple  # in the world frame
    params: list  # the backend scalars of p

    def rational(self, num: int, den: int):
        """num/den as an exact constant on the symbolic backend, a float on the numeric one."""
        q = Fraction(num, den)
        return q if self.backend.symbolic else float(q)


def parameter_scalars(model: Model, backend, p=None) -> list:
    if backend.symbolic:
        return backend.inputs("p", len(model.parameters))
    if p is None:
        p = model.parameter_values
    p = [float(x) for x in p] if np.ndim(p) == 1 or len(p) == 0 else p
    if len(p) != len(model.parameters):
        raise ValueError(f"{model.name}: p has {len(p)} entries, the model has {len(model.parameters)} parameters")
    return list(p)


def bind(model: Model, backend, p=None, tree: Tree | None = None) -> Bound:
    """Evaluate the model's constant expressions on a backend (parameters symbolic or numeric)."""
    tree = tree or Tree(model)
    params = parameter_scalars(model, backend, p)
    values = dict(zip(model.parameter_symbols, params))

    def s(expr):
        return to_scalar(expr, values, backend)

    bodies = []
    for body in model.bodies:
        pair = body.pair
        c0 = pair.constructive_rotation()
        L0 = Motion(tuple(tuple(s(c0[i, j]) for j in range(3)) for i in range(3)), tuple(s(x) for x in pair.translation))
        mises = None
        if body.inertial is not None:
            m, h, theta = body.inertial.mises()
            mises = Rigid(s(m), tuple(s(x) for x in h), tuple(tuple(s(x) for x in row) for row in theta))
        bodies.append(BoundBody(L0, pair.codes, mises))
    gravity = tuple(s(x) for x in model.gravity)
    return Bound(model, tree, backend, bodies, gravity, params)

