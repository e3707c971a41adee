"""Gravity compensation (MuJoCo's ``gravcomp`` on a body): an upward force at the centre of mass of each compensated
body, a fraction s of its weight, among the passive forces (MuJoCo's ``qfrc_passive``; ``qfrc_bias`` and g(q) keep
the whole weight).

A compensated body carries its *compensated weight* ``(m_s, h_s)`` (:attr:`aggsym.model.types.Model.gravcomp`): the
mass s m and its first moment s m r_c about the body origin in body axes, summed over the links merged into the body
(each link its own s).  Gravity acts on a body only through m and h (the Mises matrix applied to the fictitious
acceleration (-g, 0), (2.9), (2.40)), so the lift is the generalized gravity of these weights alone,

    tau_s(q) = F^T M^T L (Theta_s (-g_lk, 0))       (the gravity vector g(q) of (2.40) with Theta_lk -> Theta_s),

a generalized force on the right side (+tau_s: it holds the fraction s of g(q)); on the left of the equations of
motion ``-tau_s`` (:func:`compensation_forces`).  It is the gradient of a potential: U_s = sum m_s height + (-g).h_s,
subtracted from the potential energy (:func:`compensated_potential`), so T + U stays conserved.
"""
from __future__ import annotations

from .aggregates import Rigid
from .bias import gravity_accelerations
from .kinematics import ZERO6, TreeKinematics, generalized
from .linalg import dot

ZERO33 = ((0, 0, 0), (0, 0, 0), (0, 0, 0))


def weights(bound) -> list:
    """Per body the compensated weight as a Mises matrix of mass m_s and moment h_s (no rotational part), or None."""
    return [None if w is None else Rigid(w[0], w[1], ZERO33) for w in bound.gravcomp]


def lift(bound, kin) -> list:
    """tau_s(q): the generalized force of the compensating lifts, n scalars (the right side's sign)."""
    gam = gravity_accelerations(bound, kin)  # (-g in body axes, 0)
    Y = [ZERO6 if w is None else w.apply(gam[k]) for k, w in enumerate(weights(bound))]
    return generalized(kin, kin.backward(Y))


def compensation_forces(bound, q) -> list:
    """-tau_s(q): the lifts on the left side of the equations of motion (:func:`lift`), at the configuration q
    (its kinematics built here; on the symbolic backend they are the same nodes as the routine's own)."""
    return [0 if x == 0 else -x for x in lift(bound, TreeKinematics(bound, q))]


def compensated_potential(bound, kin):
    """U_s = sum over the compensated bodies of m_s height + (-g_lk) . h_s: the potential of the lifts, the part of
    the weight's potential energy that gravity compensation takes away."""
    gam = [g[:3] for g in gravity_accelerations(bound, kin)]
    minus_g = tuple(-x for x in bound.gravity)
    height, acc = [], 0
    for k, p in enumerate(kin.tree.parent):
        up = minus_g if p < 0 else gam[p]
        h = dot(up, kin.L[k].o)
        height.append(h if p < 0 else height[p] + h)
        w = bound.gravcomp[k]
        if w is not None:
            acc = acc + w[0] * height[k] + dot(gam[k], w[1])
    return acc


__all__ = ["compensated_potential", "compensation_forces", "lift", "weights"]
