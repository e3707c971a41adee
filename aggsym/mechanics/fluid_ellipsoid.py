"""MuJoCo's ellipsoid fluid model (``fluidshape="ellipsoid"`` on a geom, ``<option density viscosity wind>``): the
added mass, lift and drag of the medium on each such geom's equivalent ellipsoid, a passive force (MuJoCo's
``qfrc_passive``), term for term as MuJoCo's ``mj_ellipsoidFluidModel`` (``mj_addedMassForces``,
``mj_viscousForces``) computes it and its documentation states (computation/fluid: the ellipsoid model).

In the geom's frame, with v the velocity of its centre less the wind and w its angular velocity, s its semi-axes
(``mju_geomSemiAxes``), rho the density, beta the viscosity, m_v, I_v its virtual mass and inertia (per unit
density: MuJoCo's ``geom_fluid``), C_b, C_s, C_a, C_K, C_M its ``fluidcoef`` (blunt, slender, angular drag, Kutta,
Magnus lift), the medium exerts the force f and torque g (i, j, k a cyclic order; s_max >= s_mid >= s_min the
semi-axes sorted; mjMINVAL = 1e-15)

    added mass:  f += p x w,  g += p x v + h x w,   p = rho m_v o v,  h = rho I_v o w  (the velocity terms only:
                 MuJoCo leaves the acceleration's out),
    Magnus:      f += C_M rho (4/3 pi s_x s_y s_z) w x v,
    Kutta:       f += C_K rho cos_a A_p |v|^2 (n x u) x u,  n_i = a_i^2 u_i,
    linear drag: f -= (3 pi D beta + rho |v| (C_b A_p + C_s (pi s_max s_mid - A_p))) v,  D = 2/3 (s_x + s_y + s_z),
    angular:     g -= (pi D^3 beta + rho |m|) w,  m_i = w_i (C_a I_i + C_s (I_max - I_i)),
                 I_i = 8/15 pi s_i max(s_j, s_k)^4,  I_max = 8/15 pi s_mid s_max^4,

all times the geom's ``geom_fluid[0]`` (1), where, in the dimensionless form of MuJoCo 4 (semi-axes over s_max,
the velocity's direction u = v / |v|: a_i = s_j s_k / s_max^2),

    A_p = pi s_max^2 sqrt(P_d / P_n),  cos_a = P_n / P_d,  P_d = sum a_i^4 u_i^2,  P_n = sum (a_i u_i)^2,

while |v| > mjMINVAL, and A_p = 0 (no Kutta lift, the slender drag alone) while |v| <= mjMINVAL.  That is the
installed MuJoCo's behaviour, measured term by term (tests/test_fluid_ellipsoid.py): MuJoCo 3's
``mj_viscousForces`` took P_d, P_n of s and v themselves, guarded by max(mjMINVAL, .), which bit for small geoms
or slow ones (its Kutta lift then fell short of the v^2 law); its value is the same elsewhere.

Here v = c^T (v_k + w_k x r) - c^T R_k^T wind and w = c^T w_k from the body's quasi-velocity (v_k, w_k) (2.39), r
the geom's centre and c its axes in the body's, R_k the body's world rotation, as :mod:`aggsym.mechanics.fluid`
takes them for the inertia box; the wrench returns to the body's axes by c and acts at r, is carried to the root
(Prop. 2.19) and projected on the pairs' axes (2.46): its negative joins the left side (:func:`ellipsoid_forces`).
The straight line has no branch: the switch is the factor (sigma + |sigma|)/2, sigma = sign(|v| - mjMINVAL)
(1 above, 0 at and below), u = v / max(mjMINVAL, |v|), and max(f, x) is x + (d + |d|)/2, d = f - x (exactly x
where x > f).  The square roots |v|, |m|, that of A_p, and the divisions by P_n, P_d take max(1e-300, x) for x:
sqrt(0) has no derivative (the chain rule's 1/(2 sqrt x) is inf, inf 0 is NaN at a geom at rest, qd = 0), and P_n,
P_d vanish with v.  The values are MuJoCo's except where 0 < x < 1e-300 (|v| or |m| below 1e-150, or a geom whose
semi-axes span more than 37 decades), where a force differs from MuJoCo's by less than 1e-300 in absolute terms.
The medium dissipates energy: a model with it is not conservative.
"""
from __future__ import annotations

import math

from ..core.program import is_zero
from .fluid import Medium
from .linalg import add, cross, dot, mul, neg, scale

MINVAL = 1e-15  # MuJoCo's mjMINVAL
FLOOR = 1e-300  # the least argument of a square root here: sqrt(0) has no derivative (its rule's 1/(2 sqrt x) is inf)


def _cyclic(i: int) -> tuple:
    return (i + 1) % 3, (i + 2) % 3


def _fourth(x: float) -> float:
    return (x * x) * (x * x)


def _at_least(abs_, floor: float, x):
    """max(floor, x) in straight line: x + (d + |d|)/2, d = floor - x (exactly x where x > floor)."""
    d = floor - x
    return x + 0.5 * (d + abs_(d))


def _root(bound, abs_, x):
    """sqrt(max(FLOOR, x)): sqrt(x) exactly where x > FLOOR (a sum of squares, a ratio of them), and a finite
    derivative (0) at x = 0, where the value is 1e-150 instead of 0."""
    return bound.backend.sqrt(_at_least(abs_, FLOOR, x))


def _projected_area(bound, abs_, part, s, speed, v, rho, force):
    """A_p of the geom ``part`` (semi-axes ``s``) at the velocity ``v`` (|v| = ``speed``), 0 while |v| <= mjMINVAL;
    adds the Kutta lift to ``force`` (a list, in place)."""
    big = max(s)
    sigma = bound.backend.call("sign", speed - MINVAL)
    moving = 0.5 * (sigma + abs_(sigma))  # 1 where |v| > mjMINVAL, else 0
    u = scale(1.0 / _at_least(abs_, MINVAL, speed), v)
    a = [(s[j] / big) * (s[k] / big) for j, k in map(_cyclic, range(3))]
    along = tuple(mul(x, x) for x in u)
    denominator = dot([_fourth(x) for x in a], along)
    numerator = 0
    for i in range(3):
        t = mul(a[i], u[i])
        numerator = numerator + mul(t, t)
    area = moving * (math.pi * big * big) * _root(bound, abs_, denominator / _at_least(abs_, FLOOR, numerator))
    if part.kutta:
        cosine = numerator / _at_least(abs_, FLOOR, denominator)
        normal = tuple(mul(a[i] * a[i], u[i]) for i in range(3))
        lift = mul(mul(part.kutta, rho), cosine) * area * (speed * speed)
        force[:] = add(force, scale(lift, cross(cross(normal, u), u)))
    return area


def _medium_wrench(bound, part, v, w, rho, beta) -> tuple:
    """(force, torque) of the medium on the geom ``part`` (its frame) at the velocity (v, w) (its frame)."""
    abs_ = lambda x: bound.backend.call("abs", x)  # noqa: E731
    s = [float(x) for x in part.semiaxes]
    force, torque = [0, 0, 0], [0, 0, 0]
    if not is_zero(rho):
        p = tuple(mul(mul(rho, float(part.virtual_mass[i])), v[i]) for i in range(3))
        h = tuple(mul(mul(rho, float(part.virtual_inertia[i])), w[i]) for i in range(3))
        force = list(add(force, cross(p, w)))
        torque = list(add(torque, add(cross(p, v), cross(h, w))))
    big, small = max(s), min(s)
    mid = s[0] + s[1] + s[2] - big - small
    diameter = 2.0 / 3.0 * (s[0] + s[1] + s[2])
    drag = mul(3.0 * math.pi * diameter, beta)  # the linear drag's coefficient, and the angular one's
    spin = mul(math.pi * diameter * diameter * diameter, beta)
    if not is_zero(rho) and any(not is_zero(x) for x in v):
        volume = 4.0 / 3.0 * math.pi * s[0] * s[1] * s[2]
        if part.magnus:
            force = list(add(force, scale(mul(part.magnus * volume, rho), cross(w, v))))
        squares = tuple(mul(x, x) for x in v)
        speed = _root(bound, abs_, squares[0] + squares[1] + squares[2])
        area = _projected_area(bound, abs_, part, s, speed, v, rho, force) if big > 0 else 0
        drag = drag + mul(rho, speed) * (area * part.blunt + part.slender * (math.pi * big * mid - area))
    if not is_zero(rho) and any(not is_zero(x) for x in w):
        peak = 8.0 / 15.0 * math.pi * mid * _fourth(big)
        moments = [8.0 / 15.0 * math.pi * s[i] * _fourth(max(s[j], s[k]))
                   for i, (j, k) in enumerate(map(_cyclic, range(3)))]
        m = [mul(w[i], part.angular * moments[i] + part.slender * (peak - moments[i])) for i in range(3)]
        spin = spin + mul(rho, _root(bound, abs_, dot(m, m)))
    force = list(add(force, neg(scale(drag, v))))
    torque = list(add(torque, neg(scale(spin, w))))
    if part.interaction != 1.0:
        force, torque = scale(float(part.interaction), force), scale(float(part.interaction), torque)
    return tuple(force), tuple(torque)


def ellipsoid_forces(bound, q, qd) -> list:
    """Minus the generalized force of the medium on every geom of ``model.fluid_ellipsoids`` (n scalars, the left
    side's)."""
    model = bound.model
    if not model.fluid_ellipsoids:
        return [0] * bound.tree.nv
    medium = Medium(bound, q, qd)
    for part in model.fluid_ellipsoids:
        k, r, c = medium.frame(part.body, part.centre, part.axes)
        v, w = medium.velocity(k, r, c)
        medium.act(k, r, c, *_medium_wrench(bound, part, v, w, medium.rho, medium.beta))
    return medium.forces()


__all__ = ["ellipsoid_forces"]
