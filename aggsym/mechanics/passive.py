"""The passive joint forces on the left side of the equations of motion: the springs of elastic pairs (2.27) and
viscous joint damping (MuJoCo's ``stiffness``/``springref`` and ``damping``).

With both, the equations read

    A(q) q'' + b(q, q') + g(q) + C (q - q0) + D q' = tau,

D diagonal (``model.damping``, one entry per coordinate, expressions of the model).  :func:`left_forces` is
C (q - q0) + D q' (what forward and inverse dynamics move to the left, and what their derivatives differentiate),
:func:`passive_forces` its negative: the force on the right side, MuJoCo's ``qfrc_passive`` sign.  Without damping
:func:`left_forces` is exactly :func:`~.elastic.elastic_forces` (the same scalars: models without damping give the
same programs).
"""
from __future__ import annotations

from ..core.program import is_zero
from .elastic import elastic_forces
from .linalg import mul


def damping_forces(bound, qd) -> list:
    """D q': per coordinate its damping times its rate (0 where there is none)."""
    if not bound.damping:
        return [0] * len(qd)
    return [0 if is_zero(d) else mul(d, rate) for d, rate in zip(bound.damping, qd)]


def left_forces(bound, q, qd) -> list:
    """C (q - q0) + D q': the passive forces on the left side of the equations of motion."""
    c = elastic_forces(bound, q)
    if not bound.damping:
        return c
    return [x if is_zero(f) else (f if is_zero(x) else x + f) for x, f in zip(c, damping_forces(bound, qd))]


def passive_forces(bound, q, qd) -> list:
    """-(C (q - q0) + D q'): the passive forces as a generalized force on the right side (MuJoCo's sign)."""
    return [0 if is_zero(x) else -x for x in left_forces(bound, q, qd)]


def has_passive(model) -> bool:
    """Whether the model has springs or damping: some elastic pair, or a damping not exactly zero."""
    return model.has_damping or any(b.pair.elastic for b in model.bodies)


__all__ = ["damping_forces", "has_passive", "left_forces", "passive_forces"]
