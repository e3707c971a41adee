"""MuJoCo's inertia-box fluid model (``<option density viscosity wind>``): the drag of the medium on each body's
equivalent inertia box, a passive force (MuJoCo's ``qfrc_passive``), as MuJoCo's ``mj_inertiaBoxFluidModel`` computes
it and its documentation states (computation/fluid: the inertia model).

For a body of mass M and principal moments I (its inertial frame), the box has the full dimensions
b_i = sqrt(6 max(1e-15, I_j + I_k - I_i) / M) and the equivalent sphere the diameter d = (b_x + b_y + b_z) / 3.
With v the velocity of its centre of mass less the wind and w its angular velocity, both in its inertial frame,
the medium exerts there (i, j, k a cyclic order; rho the density, beta the viscosity)

    force_i  = -3 pi d beta v_i  - 1/2 rho b_j b_k |v_i| v_i,
    torque_i = -pi d^3 beta w_i  - rho b_i (b_j^4 + b_k^4) |w_i| w_i / 64.

Here v = c^T (v_k + w_k x r_c) - c^T R_k^T wind and w = c^T w_k, from the body's quasi-velocity (v_k, w_k) (2.39),
c the inertial frame's axes in the body's, R_k the body's world rotation; the force and torque return to the body's
axes by c and act at r_c, so its wrench about the origin is (c f, c g + r_c x c f); carried to the root (Prop. 2.19)
and projected on the pairs' axes (2.46) they are the generalized force, on the right side; its negative joins the
left side (:func:`fluid_forces`).  |x| x is C1: the straight line holds it with one ``fabs``.  The medium dissipates
energy: a model with it is not conservative.
"""
from __future__ import annotations

import math

from ..core.program import is_zero
from .kinematics import ZERO6, TreeKinematics, generalized, world_poses
from .linalg import add, cross, mtv, mul, mv, neg, scale


def _cyclic(i: int) -> tuple:
    return (i + 1) % 3, (i + 2) % 3


class Medium:
    """What the fluid models share at one state: the density ``rho``, viscosity ``beta`` and wind of
    ``model.fluid_medium`` as scalars, the kinematics and body velocities, and the wrenches ``Y`` on the bodies (the
    left side's) that :meth:`act` collects; :meth:`forces` is their generalized force."""

    def __init__(self, bound, q, qd):
        density, viscosity, wind = bound.model.fluid_medium
        self.rho, self.beta = bound.scalar(density), bound.scalar(viscosity)
        self.wind = tuple(bound.scalar(x) for x in wind)
        self.kin = TreeKinematics(bound, q)  # (on the symbolic backend the same nodes as the routine's kinematics)
        self.V = self.kin.velocities(qd)
        self.poses = world_poses(self.kin) if any(not is_zero(x) for x in self.wind) else None
        self.index = {name: k for k, name in enumerate(bound.tree.names)}
        self.scalar = bound.scalar
        self.Y = [ZERO6] * len(bound.tree)

    def frame(self, body, origin, axes) -> tuple:
        """(k, r, c): the index of ``body`` and a frame of it given by its ``origin`` and ``axes`` (the model's
        numbers) as the program's scalars."""
        return (self.index[body], tuple(self.scalar(x) for x in origin),
                tuple(tuple(self.scalar(x) for x in row) for row in axes))

    def velocity(self, k, r, c) -> tuple:
        """(v, w) of the frame at ``r`` with axes ``c`` (in body k's), in those axes: v less the wind."""
        v_k, w_k = self.V[k][:3], self.V[k][3:]
        v = mtv(c, add(v_k, cross(w_k, r)))
        if self.poses is not None:
            v = add(v, neg(mtv(c, mtv(self.poses[k].c, self.wind))))
        return v, mtv(c, w_k)

    def act(self, k, r, c, force, torque) -> None:
        """The medium's force and torque at that frame (its axes) added to body k, as the left side's wrench."""
        f, g = mv(c, force), mv(c, torque)
        self.Y[k] = add(self.Y[k], neg(f) + neg(add(g, cross(r, f))))

    def forces(self) -> list:
        return generalized(self.kin, self.kin.backward(self.Y))


def fluid_forces(bound, q, qd) -> list:
    """Minus the generalized force of the medium's drag on every body of ``model.fluid`` (n scalars, the left
    side's)."""
    model = bound.model
    if not model.fluid:
        return [0] * bound.tree.nv
    medium = Medium(bound, q, qd)
    rho, beta = medium.rho, medium.beta
    abs_ = lambda x: bound.backend.call("abs", x)  # noqa: E731
    for part in model.fluid:
        k, r, c = medium.frame(part.body, part.com, part.axes)
        b = [float(x) for x in part.box]
        v, w = medium.velocity(k, r, c)
        diameter = (b[0] + b[1] + b[2]) / 3.0
        force, torque = [0, 0, 0], [0, 0, 0]
        for i in range(3):
            j, l = _cyclic(i)
            linear = mul(-3.0 * math.pi * diameter, beta)
            angular = mul(-math.pi * diameter * diameter * diameter, beta)
            force[i] = mul(linear, v[i]) - mul(mul(0.5 * b[j] * b[l], rho), mul(abs_(v[i]), v[i]))
            fourth = b[j] * b[j] * b[j] * b[j] + b[l] * b[l] * b[l] * b[l]
            torque[i] = mul(angular, w[i]) - mul(mul(b[i] * fourth / 64.0, rho), mul(abs_(w[i]), w[i]))
        medium.act(k, r, c, force, torque)
    return medium.forces()


__all__ = ["Medium", "fluid_forces"]
