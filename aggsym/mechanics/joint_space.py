"""Linear forms in joint space: MuJoCo's fixed tendons ``L = sum c q`` on hinge and slide coordinates, as the
rows of joint-space constraints (:class:`~aggsym.model.types.JointRow`, chapter 4's machinery with a row that is
not the motion of a body point) and as the springs and dampers along a tendon (:class:`~aggsym.model.types.Tendon`,
passive forces beside (2.27)).

A coordinate of a scalar pair has one entry in q (its position index) and one in qd (its coordinate index); a
form's value is ``sum c q[position]``, its rate ``sum c qd[coordinate]``.

Joint-space row (one constraint row; ``x = L2 - ref2``, P the polynomial y0 + a1 x + ... + a4 x^4)::

    phi = (L1 - ref1) - P(x),   J = c1 - P'(x) c2,   gamma = J' qd = -P''(x) (c2 . qd)^2

A length is any object with ``value(q)``, ``rate(qd)``, ``add_to(row, factor)`` (its Jacobian row times factor added
to a row) and ``curvature(qd)`` (d^2 L/dt^2 at qdd = 0): a :class:`LinearForm` (curvature 0), or a spatial tendon's
:class:`~aggsym.mechanics.spatial_tendons.SpatialLength` (an MJCF tendon equality on a ``<spatial>`` tendon; bound to
the kinematics by :meth:`BoundJointRow.on`).  In general ``phi'' = L1'' - P''(x) L2'^2 - P'(x) L2''``, so::

    J = dL1/dq - P'(x) dL2/dq,   gamma = L1''_0 - P''(x) (L2')^2 - P'(x) L2''_0     (''_0: at qdd = 0)

Tendon spring, damper and (on request) Coulomb friction (force along the tendon on the right side, ``lower <=
upper`` its dead band)::

    f = -k (min(L - lower, 0) + max(L - upper, 0)) - d L' - F sign(L'),   on the left of the equations: -c f

with ``min(x, 0) = (x - |x|)/2`` and ``max(x, 0) = (x + |x|)/2`` (exact; a spring without dead band,
lower = upper, is the linear ``-k (L - lower)``); its energy ``1/2 k (min(L - lower, 0)^2 + max(L - upper, 0)^2)``.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from ..core.program import is_zero
from .linalg import mul


def places(bound) -> dict:
    """{coordinate name: (coordinate index, position index)} for the coordinates of scalar (non-quaternion) pairs
    of the bound tree."""
    out = {}
    tree = bound.tree
    for k, body in enumerate(bound.model.bodies):
        if body.pair.quaternion:
            continue
        for c, i, j in zip(body.pair.coordinates, tree.coords[k], tree.positions[k]):
            out[c.name] = (i, j)
    return out


@dataclass
class LinearForm:
    """``sum c q``: per term (coordinate index, position index, coefficient scalar)."""

    terms: tuple

    def value(self, q):
        acc = 0
        for _, j, c in self.terms:
            acc = acc + mul(c, q[j])
        return acc

    def rate(self, qd):
        acc = 0
        for i, _, c in self.terms:
            acc = acc + mul(c, qd[i])
        return acc

    def curvature(self, qd):
        """d^2 L/dt^2 at qdd = 0: 0 (L is linear in q)."""
        return 0

    def add_to(self, row: list, factor=1) -> list:
        """row + factor c (a list of n scalars, a new list)."""
        out = list(row)
        for i, _, c in self.terms:
            term = c if (type(factor) is int and factor == 1) else mul(factor, c)
            out[i] = term if is_zero(out[i]) else out[i] + term
        return out


def linear_form(bound, terms, where: dict | None = None) -> LinearForm:
    """The bound form of ((coordinate name, coefficient expression), ...)."""
    where = places(bound) if where is None else where
    return LinearForm(tuple((*where[name], bound.scalar(c)) for name, c in terms))


@dataclass(frozen=True)
class Sites:
    """A spatial tendon's length before the kinematics are known: its branches (``SpatialTendon.branches``)."""

    branches: tuple


@dataclass
class BoundJointRow:
    """A joint-space constraint row bound to a backend (see the module's text); ``rows``, ``free``, ``law``,
    ``frame`` as a point constraint's, so that the constrained dynamics treat it as one row without friction."""

    first: object  # a length (the module's text): LinearForm, Sites until bound by on(), SpatialLength
    second: object
    ref1: object
    ref2: object
    poly: tuple  # (y0, a1, a2, a3, a4) scalars
    n: int
    rows: tuple = (0,)
    free: tuple = ()
    law: str | None = None
    frame: object = None
    coefficient: object = None
    normal: int | None = None

    def on(self, make) -> "BoundJointRow":
        """This row with its spatial lengths (:class:`Sites`) bound: ``make(branches)`` the length (itself when it
        has none)."""
        if not isinstance(self.first, Sites) and not isinstance(self.second, Sites):
            return self
        first, second = (make(f.branches) if isinstance(f, Sites) else f for f in (self.first, self.second))
        return replace(self, first=first, second=second)

    def _x(self, q):
        return self.second.value(q) - self.ref2

    def derivative(self, q):
        """P'(x) (0 without a second form)."""
        if self.second is None:
            return 0
        a = self.poly
        if all(is_zero(c) for c in a[2:]):
            return a[1]
        x = self._x(q)
        return a[1] + mul(2 * a[2], x) + mul(3 * a[3], x * x) + mul(4 * a[4], x * x * x)

    def jacobian(self, q) -> list:
        """J (one row, n scalars): c1 - P'(x) c2."""
        row = self.first.add_to([0] * self.n)
        if self.second is not None:
            d = self.derivative(q)
            if not is_zero(d):
                row = self.second.add_to(row, -d)
        return row

    def bias(self, q, qd):
        """gamma = L1''_0 - P''(x) L2'^2 - P'(x) L2''_0 (fixed tendons: -P''(x) (c2 . qd)^2)."""
        out = self.first.curvature(qd)
        if self.second is None:
            return out
        curved = self.second.curvature(qd)
        if not is_zero(curved):
            out = out - mul(self.derivative(q), curved)
        a = self.poly
        if all(is_zero(c) for c in a[2:]):
            return out
        x = self._x(q)
        second = 0
        for k, c in ((2, a[2]), (3, a[3]), (4, a[4])):
            if not is_zero(c):
                term = k * (k - 1) * c
                second = second + (term if k == 2 else mul(term, x if k == 3 else x * x))
        r = self.second.rate(qd)
        return -(second * (r * r)) if is_zero(out) else out - second * (r * r)

    def residual(self, q):
        """phi = (L1 - ref1) - P(x)."""
        a = self.poly
        out = self.first.value(q) - self.ref1 - a[0]
        if self.second is None:
            return out
        x = self._x(q)
        power = 1
        for k in range(1, 5):
            power = x if k == 1 else power * x
            if not is_zero(a[k]):
                out = out - mul(a[k], power)
        return out


def bind_joint_row(bound, row, where: dict | None = None) -> BoundJointRow:
    """A :class:`~aggsym.model.types.JointRow` bound to ``bound``'s backend."""
    where = places(bound) if where is None else where
    first = Sites(row.first_sites) if row.first_sites else linear_form(bound, row.first, where)
    second = (Sites(row.second_sites) if row.second_sites else
              linear_form(bound, row.second, where) if row.second else None)
    return BoundJointRow(first, second, bound.scalar(row.reference[0]),
                         bound.scalar(row.reference[1]), tuple(bound.scalar(a) for a in row.polynomial),
                         bound.tree.nv)


def _stretch(bound, tendon, L):
    """min(L - lower, 0) + max(L - upper, 0): the spring's stretch beyond its dead band (L - lower without one)."""
    lower = bound.scalar(tendon.lower)
    if not tendon.deadband:
        return L - lower
    upper = bound.scalar(tendon.upper)
    below, above = L - lower, L - upper
    half = bound.rational(1, 2)
    return mul(half, below - bound.backend.call("abs", below)) + mul(half, above + bound.backend.call("abs", above))


def tendon_forces(bound, q, qd) -> list:
    """sum over the tendons of -c f (n scalars, 0 where no tendon acts): their passive forces on the left side."""
    n = bound.tree.nv
    out = [0] * n
    if not bound.model.tendons:
        return out
    where = places(bound)
    for tendon in bound.model.tendons:
        form = linear_form(bound, tendon.terms, where)
        k, d, fr = bound.scalar(tendon.stiffness), bound.scalar(tendon.damping), bound.scalar(tendon.friction)
        left = 0  # -f = k stretch + d L' + F sign(L')
        if not is_zero(k):
            left = mul(k, _stretch(bound, tendon, form.value(q)))
        if not (is_zero(d) and is_zero(fr)):
            rate = form.rate(qd)
            if not is_zero(d):
                left = left + mul(d, rate)
            if not is_zero(fr):
                left = left + mul(fr, bound.backend.call("sign", rate))
        if not is_zero(left):
            out = form.add_to(out, left)
    return out


def spring_energy(bound, tendons, length) -> object:
    """1/2 k stretch^2 summed over the springs of ``tendons`` (fixed or spatial), ``length(tendon)`` their length."""
    acc = 0
    for tendon in tendons:
        k = bound.scalar(tendon.stiffness)
        if is_zero(k):
            continue
        s = _stretch(bound, tendon, length(tendon))
        acc = acc + mul(k, s * s)
    return 0 if is_zero(acc) else bound.rational(1, 2) * acc


def tendon_energy(bound, q):
    """1/2 k stretch^2 summed over the fixed tendons' springs."""
    where = places(bound) if bound.model.tendons else None
    return spring_energy(bound, bound.model.tendons, lambda t: linear_form(bound, t.terms, where).value(q))


__all__ = ["BoundJointRow", "LinearForm", "Sites", "bind_joint_row", "linear_form", "places", "spring_energy", "tendon_energy",
           "tendon_forces"]
