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

from .program import Node, is_zero


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
        if not isinstance(x, Dual):
            return self.base.sin(x)
        c = self.base.cos(x.v)
        return lift(self.base.sin(x.v), {k: _mul(c, y) for k, y in x.d.items()})

    def cos(self, x):
        if not isinstance(x, Dual):
            return self.base.cos(x)
        s = self.base.sin(x.v)
        return lift(self.base.cos(x.v), {k: -_mul(s, y) for k, y in x.d.items()})

    def sqrt(self, x):
        if not isinstance(x, Dual):
            return self.base.sqrt(x)
        r = self.base.sqrt(x.v)
        half = self.base.rational(1, 2) / r
        return lift(r, {k: _mul(half, y) for k, y in x.d.items()})

    def call(self, name, *args):
        if not any(isinstance(a, Dual) for a in args):
            return self.base.call(name, *args)
        if name == "sin":
            return self.sin(args[0])
        if name == "cos":
            return self.cos(args[0])
        if name == "sqrt":
            return self.sqrt(args[0])
        if name == "sign":  # piecewise constant: no tangent
            return self.base.call("sign", _parts(args[0])[0])
        if name == "abs":
            v, d = _parts(args[0])
            s = self.base.call("sign", v)
            return lift(self.base.call("abs", v), {k: _mul(s, y) for k, y in d.items()})
        if name == "atan2":  # d atan2(y, x) = (x dy - y dx) / (x^2 + y^2)
            (y, dy), (x, dx) = _parts(args[0]), _parts(args[1])
            r = 1 / (x * x + y * y)
            d = _combine({k: _mul(x, t) for k, t in dy.items()}, {k: _mul(y, t) for k, t in dx.items()}, -1)
            return lift(self.base.call("atan2", y, x), {k: _mul(r, t) for k, t in d.items()})
        raise NotImplementedError(f"no derivative of {name!r} for forward-mode differentiation")


__all__ = ["Dual", "DualBackend", "lift", "tangent"]
