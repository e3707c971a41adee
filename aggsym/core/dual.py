"""Forward-mode differentiation of the recursions: dual numbers over the backends' scalars.

A :class:`Dual` is a value ``v`` (a program node, a number or a NumPy array: any scalar of a backend) with its
tangent ``d``, a sparse map direction -> derivative.  Running a recursion (the sweeps, the kinematics) on duals
seeded with unit tangents on some inputs (``Dual(q_i, {i: 1})``) records, beside every intermediate of the straight-
line program, its derivatives along those directions: the derivative program reuses the intermediates and never
expands a closed form.  Values without a tangent stay plain scalars (so the recursions' structural zeros and
constants fold as before); a result's tangent entries that fold to exact zeros are dropped.

:class:`DualBackend` wraps a backend so that its ``sin``, ``cos``, ``sqrt`` and functions take duals (chain rule).

Dual subclasses :class:`~aggsym.core.program.Node` only so that ``node + dual`` reaches ``Dual.__radd__`` first
(Python tries the right operand's reflected method first when its type subclasses the left one's); it is never
recorded into a program.
"""
from __future__ import annotations

from .functions import COS, FUNCTIONS, SIN, SQRT
from .program import Node, arithmetic, is_zero


def lift(v, d: dict):
    """``v`` with tangent ``d`` (exact-zero entries dropped): a Dual, or ``v`` itself when no direction is left."""
    d = {k: x for k, x in d.items() if not is_zero(x)}
    return Dual(v, d) if d else v


def _parts(x):
    return (x.v, x.d) if isinstance(x, Dual) else (x, {})


def _mul(a, b):
    return 0 if is_zero(a) or is_zero(b) else a * b


def _combine(a: dict, b: dict, sign: int = 1) -> dict:
    out = dict(a)
    for k, y in b.items():
        if k in out:
            out[k] = out[k] + y if sign > 0 else out[k] - y
        else:
            out[k] = y if sign > 0 else -y
    return out


class Dual(Node):
    """A value and its tangent (see the module's text)."""

    __slots__ = ("v", "d")
    __array_ufunc__ = None  # NumPy defers to our reflected operators (the numeric twin's arrays)

    def __init__(self, v, d: dict):  # noqa: D107 (Node's program and id are not used)
        self.v = v
        self.d = d

    def __add__(self, other):
        ov, od = _parts(other)
        return lift(self.v + ov, _combine(self.d, od))

    __radd__ = __add__

    def __sub__(self, other):
        ov, od = _parts(other)
        return lift(self.v - ov, _combine(self.d, od, -1))

    def __rsub__(self, other):
        ov, od = _parts(other)
        return lift(ov - self.v, _combine(od, self.d, -1))

    def __mul__(self, other):
        ov, od = _parts(other)
        d = {k: _mul(x, ov) for k, x in self.d.items()}
        return lift(_mul(self.v, ov), _combine(d, {k: _mul(self.v, y) for k, y in od.items()}))

    __rmul__ = __mul__

    def __truediv__(self, other):
        ov, od = _parts(other)
        value = self.v / ov
        inv = 1 / ov
        # (a/b)' = (a' - (a/b) b') / b
        return lift(value, {k: _mul(x, inv) for k, x in _combine(self.d, {k: _mul(value, y) for k, y in od.items()},
                                                                -1).items()})

    def __rtruediv__(self, other):
        ov, od = _parts(other)
        value = ov / self.v
        inv = 1 / self.v
        return lift(value, {k: _mul(x, inv) for k, x in _combine(od, {k: _mul(value, y) for k, y in self.d.items()},
                                                                -1).items()})

    def __neg__(self):
        return Dual(-self.v, {k: -x for k, x in self.d.items()})

    def __pos__(self):
        return self

    def __hash__(self):
        return id(self)

    def __eq__(self, other):
        return other is self

    def __bool__(self):
        raise TypeError("a dual value has no truth value")

    def __repr__(self):
        return f"Dual({self.v!r}, {self.d!r})"


def tangent(x, k):
    """The derivative of ``x`` along direction k (0 for a plain value)."""
    return x.d.get(k, 0) if isinstance(x, Dual) else 0


class DualBackend:
    """A backend whose functions take duals: the chain rule over the wrapped backend's functions (a
    :class:`~aggsym.core.backend.Backend`; its scalars are duals, not one program's nodes: ``program`` is None)."""

    program = None

    def __init__(self, base):
        self.base = base
        self.symbolic = base.symbolic
        self.rational = base.rational

    def sin(self, x):
        return self.call(SIN, x)

    def cos(self, x):
        return self.call(COS, x)

    def sqrt(self, x):
        return self.call(SQRT, x)

    def call(self, name, *args):
        """``name`` of :data:`aggsym.core.functions.FUNCTIONS` on duals: the chain rule with its derivative rule."""
        if not any(isinstance(a, Dual) for a in args):
            return self.base.call(name, *args)
        rule = FUNCTIONS[name].derivative
        if rule is None:
            raise NotImplementedError(f"no derivative of {name!r} for forward-mode differentiation")
        parts = [_parts(a) for a in args]
        value, coefficients, common = rule(self.base, *(v for v, _ in parts))
        d = {}
        for (coefficient, sign), (_, tangent) in zip(coefficients, parts):
            d = _combine(d, {k: _mul(coefficient, t) for k, t in tangent.items()}, sign)
        if value is None:
            value = self.base.call(name, *(v for v, _ in parts))
        if common is not None:
            d = {k: _mul(common, t) for k, t in d.items()}
        return lift(value, d)


def along_inputs(program, outputs, directions) -> list:
    """The derivatives of ``outputs`` (a flat list of nodes of ``program`` or constants) along the inputs
    ``directions`` (a list of (kind, index)), as new nodes of the program: forward mode on the straight line itself
    (interpreted on duals seeded with a unit tangent on each of those inputs), for a routine whose derivatives
    along some raw inputs no recursion gives (a quaternion's entries, where the derivative routines are in the
    tangent space).  [[d out / d input for input in directions] for out in outputs], 0 where out does not
    depend on the input."""
    from .backend import Symbolic

    backend = DualBackend(Symbolic(program))
    seed = {key: k for k, key in enumerate(directions)}

    def leaf(kind, index):
        x = program.input(kind, index)
        k = seed.get((kind, index))
        return x if k is None else Dual(x, {k: 1})

    def apply(code, *x):
        return arithmetic(code, x, lambda name: lambda *a: backend.call(name, *a))

    values = program.interpret(outputs, leaf, apply)
    return [[tangent(v, k) for k in range(len(directions))] for v in values]


__all__ = ["Dual", "DualBackend", "along_inputs", "lift", "tangent"]
