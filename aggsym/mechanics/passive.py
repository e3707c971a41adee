"""The passive joint forces on the left side of the equations of motion: the springs of elastic pairs (2.27),
viscous joint damping (MuJoCo's ``stiffness``/``springref`` and ``damping``; URDF ``<dynamics damping>`` under
``--passive include``) and Coulomb joint friction (URDF ``<dynamics friction>`` under ``--passive include``).

With all three, the equations read

    A(q) q'' + b(q, q') + g(q) + C (q - q0) + D q' + F sign(q') = tau,

D and F diagonal (``model.damping``, ``model.coulomb``: one entry per coordinate, expressions of the model), sign(0)
= 0.  :func:`left_forces` is C (q - q0) + D q' + F sign(q') (what forward and inverse dynamics move to the left,
and what their derivatives differentiate: sign has no tangent), :func:`passive_forces` its negative: the force on
the right side, MuJoCo's ``qfrc_passive`` sign.  Without damping and friction :func:`left_forces` is exactly
:func:`~.elastic.elastic_forces` (the same scalars: models without them give the same programs).
"""
from __future__ import annotations

from ..core.program import is_zero
from .elastic import elastic_forces
from .linalg import mul


def damping_forces(bound, qd) -> list:
    """D q' + F sign(q'): per coordinate its damping times its rate plus its Coulomb friction times the rate's sign
    (0 where there is none)."""
    out = [0] * len(qd)
    if bound.damping:
        out = [0 if is_zero(d) else mul(d, rate) for d, rate in zip(bound.damping, qd)]
    if bound.coulomb:
        out = [x if is_zero(f) else (_coulomb(bound, f, rate) if is_zero(x) else x + _coulomb(bound, f, rate))
               for x, f, rate in zip(out, bound.coulomb, qd)]
    return out


def _coulomb(bound, f, rate):
    """f sign(rate): the Coulomb force on the left side (0 when the rate is 0)."""
    return mul(f, bound.backend.call("sign", rate))


def left_forces(bound, q, qd) -> list:
    """C (q - q0) + D q' + F sign(q'): the passive forces on the left side of the equations of motion."""
    c = elastic_forces(bound, q)
    if not bound.damping and not bound.coulomb:
        return c
    return [x if is_zero(f) else (f if is_zero(x) else x + f) for x, f in zip(c, damping_forces(bound, qd))]


def passive_forces(bound, q, qd) -> list:
    """-(C (q - q0) + D q'): the passive forces as a generalized force on the right side (MuJoCo's sign)."""
    return [0 if is_zero(x) else -x for x in left_forces(bound, q, qd)]


def has_passive(model) -> bool:
    """Whether the model has springs, damping or friction: some elastic pair, or a damping or Coulomb friction not
    exactly zero."""
    return model.has_damping or any(b.pair.elastic for b in model.bodies)


__all__ = ["damping_forces", "has_passive", "left_forces", "passive_forces"]
