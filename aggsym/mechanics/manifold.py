"""Integration on the configuration manifold: q (+) v dt, Pinocchio's ``integrate``.

A coordinate moves by its rate: ``q_next = q + v dt``.  A free-flyer pair (seven positions: the origin x and a unit
quaternion, six velocities: the body's own quasi-velocity (v, w) of Def. 1.9, body axes) moves along the screw
that a constant (v, w) describes for the time dt, ``M_next = M exp((v, w) dt)`` in SE(3):

* rotation: ``quat_next = quat * (sin(theta/2) u, cos(theta/2))`` with ``w dt = theta u``, |u| = 1, normalized
  (the quaternion of ``R exp(hat(w dt))``, the same sign as quat: Pinocchio picks it so);
* origin: ``x_next = x + R V (v dt)``, ``V = E + (1 - cos theta)/theta^2 hat(w dt) + (theta - sin theta)/theta^3
  hat(w dt)^2`` (the left Jacobian of SO(3): the screw's displacement, (1.13) integrated at constant V).

A ball pair (four positions: the unit quaternion, three velocities: the angular velocity w in the body's axes)
turns as the free-flyer's rotation does, ``quat_next = quat * exp(w dt)`` normalized (Pinocchio's spherical joint).

The three ratios are written without a branch: theta^2 = |w dt|^2 + 1e-30, so that at theta = 0 they take their
limits (sin(theta/2)/theta = 1/2 exactly; the other two multiply hat(w dt) and hat(w dt)^2, which vanish).  They
are smooth functions of theta^2, so the added 1e-30 moves them by about 1e-31 (nothing a double or a float sees),
and 1e-30 stays a normal number in single precision too.  ``1 - cos theta = 2 sin^2(theta/2)`` avoids the
cancellation, and the rounding error of ``(1 - sin(theta)/theta)/theta^2`` near 0 is multiplied by |w dt|^2.
"""
from __future__ import annotations

from .kinematics import quaternion_rotation
from .linalg import add, cross, dot, mv, scale

TINY = 1e-30  # added to theta^2 (see the module's text)


def integrate(bound, q, v, dt) -> list:
    """q (+) v dt: the configuration reached from q by the constant velocity v (length nv) after dt."""
    tree, backend = bound.tree, bound.backend
    out = list(q)
    for k, (idx, coords) in enumerate(zip(tree.positions, tree.coords)):
        if not bound.model.bodies[k].pair.quaternion:
            for p, i in zip(idx, coords):
                out[p] = q[p] + v[i] * dt
            continue
        ball = len(idx) == 4
        x, quat = [q[p] for p in idx[:-4]], [q[p] for p in idx[-4:]]
        nu = [v[i] * dt for i in coords[:-3]]
        w = [v[i] * dt for i in coords[-3:]]
        theta2 = dot(w, w) + TINY
        theta = backend.sqrt(theta2)
        s, c = backend.sin(theta / 2), backend.cos(theta / 2)
        k_half = s / theta  # sin(theta/2)/theta
        e = scale(k_half, w) + (c,)  # the quaternion of exp(hat(w dt)), (vector, scalar)
        turned = _product(quat, e)
        norm = 1 / backend.sqrt(dot(turned, turned))
        unit = tuple(norm * t for t in turned)
        if ball:
            for p, value in zip(idx, unit):
                out[p] = value
            continue
        a = 2 * k_half * k_half  # (1 - cos theta)/theta^2
        b = (1 - 2 * s * c / theta) / theta2  # (theta - sin theta)/theta^3
        wn = cross(w, nu)
        step = add(add(nu, scale(a, wn)), scale(b, cross(w, wn)))
        moved = add(x, mv(quaternion_rotation(*quat), step))
        for p, value in zip(idx, moved + unit):
            out[p] = value
    return out


def _product(p, r) -> tuple:
    """The quaternion product p r, both as (x, y, z, w)."""
    pv, rv = p[:3], r[:3]
    vector = add(add(scale(p[3], rv), scale(r[3], pv)), cross(pv, rv))
    return vector + (p[3] * r[3] - dot(pv, rv),)


__all__ = ["integrate"]
