"""The passive joint forces on the left side of the equations of motion: the springs of elastic pairs (2.27),
viscous joint damping (MuJoCo's ``stiffness``/``springref`` and ``damping``), the springs and dampers of fixed
tendons (:func:`~.joint_space.tendon_forces`) and of spatial tendons through sites
(:func:`~.spatial_tendons.spatial_tendon_forces`), MuJoCo's inertia-box fluid drag (:func:`~.fluid.fluid_forces`)
and its ellipsoid model (:func:`~.fluid_ellipsoid.ellipsoid_forces`),
gravity compensation (MuJoCo's ``gravcomp``:
:func:`~.gravcomp.compensation_forces`, -tau_s) and, on request, Coulomb joint friction (MuJoCo's ``frictionloss``
taken as ``f sign(q')``; URDF ``<dynamics damping friction>`` under ``--passive include``).

With them, the equations read

    A(q) q'' + b(q, q') + g(q) + C (q - q0) + D q' + t(q, q') + F sign(q') = tau,

D and F diagonal (``model.damping``, ``model.coulomb``: one entry per coordinate, expressions of the model),
t the tendons' ``-c f`` (fixed) and ``-J^T f`` (spatial), and, where a model has them, the fluid's drag and the
lifts of gravity compensation moved to the left as well.  :func:`left_forces` is the sum of these passive terms (what forward and inverse dynamics
move to the left, and what their derivatives differentiate), :func:`passive_forces` its negative: the force on
the right side, MuJoCo's ``qfrc_passive`` sign (which holds no Coulomb term: MuJoCo's frictionloss is a
constraint).  Without damping, tendons, friction, fluid and gravity compensation :func:`left_forces` is exactly
:func:`~.elastic.elastic_forces` (the same scalars: such models give the same programs).
"""
from __future__ import annotations

from ..core.program import is_zero
from .elastic import elastic_forces
from .fluid import fluid_forces
from .fluid_ellipsoid import ellipsoid_forces
from .gravcomp import compensation_forces
from .joint_space import tendon_forces
from .spatial_tendons import spatial_tendon_forces
from .linalg import mul


def damping_forces(bound, qd) -> list:
    """D q': per coordinate its damping times its rate (0 where there is none)."""
    if not bound.damping:
        return [0] * len(qd)
    return [0 if is_zero(d) else mul(d, rate) for d, rate in zip(bound.damping, qd)]


def coulomb_forces(bound, qd) -> list:
    """F sign(q'): per coordinate its Coulomb friction times the sign of its rate (0 where there is none, and at a
    rate of exactly 0)."""
    if not bound.coulomb:
        return [0] * len(qd)
    return [0 if is_zero(f) else mul(f, bound.backend.call("sign", rate)) for f, rate in zip(bound.coulomb, qd)]


def _plus(a: list, b: list) -> list:
    return [x if is_zero(f) else (f if is_zero(x) else x + f) for x, f in zip(a, b)]


def left_forces(bound, q, qd) -> list:
    """C (q - q0) + D q' + t(q, q') + F sign(q'): the passive forces on the left side of the equations of
    motion."""
    c = elastic_forces(bound, q)
    if bound.damping:
        c = _plus(c, damping_forces(bound, qd))
    if bound.model.tendons:
        c = _plus(c, tendon_forces(bound, q, qd))
    if bound.coulomb:
        c = _plus(c, coulomb_forces(bound, qd))
    if bound.model.spatial_tendons:
        c = _plus(c, spatial_tendon_forces(bound, q, qd))
    if bound.gravcomp:
        c = _plus(c, compensation_forces(bound, q))
    if bound.model.fluid:
        c = _plus(c, fluid_forces(bound, q, qd))
    if bound.model.fluid_ellipsoids:
        c = _plus(c, ellipsoid_forces(bound, q, qd))
    return c


def passive_forces(bound, q, qd) -> list:
    """-(C (q - q0) + D q' + t + F sign(q')): the passive forces as a generalized force on the right side
    (MuJoCo's sign)."""
    return [0 if is_zero(x) else -x for x in left_forces(bound, q, qd)]


def has_passive(model) -> bool:
    """Whether the model has springs, damping, tendon forces, Coulomb friction or gravity compensation: some elastic
    pair, a damping not exactly zero, a tendon with a spring or damper, a friction, a compensated body."""
    return model.has_damping or any(b.pair.elastic for b in model.bodies) or bool(model.tendons) or \
        bool(model.coulomb) or bool(model.gravcomp) or bool(model.spatial_tendons) or model.has_fluid


__all__ = ["coulomb_forces", "damping_forces", "has_passive", "left_forces", "passive_forces"]
