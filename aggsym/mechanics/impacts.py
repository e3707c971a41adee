"""Impulse dynamics: the velocities just after an impact on the constraints (chapter 4's constraints as an
impact law, Pinocchio's ``impulseDynamics``).

Over the impact the positions do not move and every finite force (gravity, the bias, tau, springs, friction of
viscous law) gives no impulse; the constraints' impulse Lambda changes the momentum and sets the rows' relative
velocity to ``-r`` times the one before (Newton's restitution law, r in [0, 1]):

    A(q) (qd+ - qd-) = J^T Lambda,      J qd+ + F = -r (J qd- + F)

(F(t) the rows' velocity that a prescribed frame motion makes (4.35), zero at rest).  With x = qd+ - qd- this is
the constrained system of :mod:`aggsym.mechanics.kkt` with f = 0 and h = -(1 + r)(J qd- + F):
``G Lambda = h``, ``x = T^T D^-1 P Lambda``.  Lambda has the layout of the constrained forward dynamics' lambda
(the impulse wrench the medium gives body k about the contact point, reference axes); ``J^T Lambda`` is the
joint-space impulse, independent of the rows' axes.  The solve is the model's (exact, or damped by its
``proximal`` setting: :mod:`aggsym.mechanics.damped`).
"""
from __future__ import annotations

from .kkt import ConstrainedSystem
from .linalg import dot, mul


def impact_rhs(J, F, qd, r) -> list:
    """h = -(1 + r) (J qd + F): the jump the rows' relative velocity must make (J rows, F the time terms)."""
    scale = -(1 + r)
    return [mul(scale, dot(row, qd) + f) for row, f in zip(J, F)]


def impulse_dynamics(bound, kin, qd, r) -> tuple:
    """(qd+, J^T Lambda, Lambda, status) at configuration ``kin`` for the velocity ``qd`` before the impact and the
    restitution coefficient r (a scalar)."""
    system = ConstrainedSystem(bound, kin)
    x, lam = system.solve_transvected([0] * kin.tree.nv, impact_rhs(system.J, system.ck.time_terms(), qd, r))
    return [a + b for a, b in zip(qd, x)], system.joint_space(lam), lam, system.status


__all__ = ["impulse_dynamics", "impact_rhs"]
