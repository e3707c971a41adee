"""URDF joint damping and friction in the equations of motion: ``aggsym generate robot.urdf --passive include``.

A URDF joint's ``<dynamics damping= friction=>`` is always in p (``damping_<joint>``, ``friction_<joint>``, defaults
from the file, :func:`aggsym.model.readers.urdf_reader.friction_parameters`) and in the routine ``joint_friction``
(tau_f = -d qd - f sign(qd)).  By default (``--passive exclude``, what Pinocchio's rnea and aba compute) forward and
inverse dynamics leave them out, and the header and the manifest say so next to those routines.  With ``--passive
include`` they enter the left side of the equations of motion beside the elastic forces
(:mod:`aggsym.mechanics.passive`):

    A(q) qdd + b(q, qd) + g(q) + D qd + F sign(qd) = tau,

D and F diagonal, their entries the same runtime parameters (0 for a joint without ``<dynamics>``), sign(0) = 0.
Inverse dynamics then returns the torque that overcomes them, forward dynamics the acceleration they slow, and the
manifest says ``"conservative": false``.  Coulomb friction as f sign(qd) is discontinuous at qd = 0 and holds no
joint at rest (no stiction): a model for simulation, not for an identification of friction.
"""
from __future__ import annotations

import dataclasses

import sympy as sp

from ..types import Model

PASSIVE_MODES = ("exclude", "include")
INCLUDED_IN = ("inverse_dynamics", "forward_dynamics", "nonlinear_effects")  # the routines --passive concerns


def with_passive_included(model: Model) -> Model:
    """The model with every coordinate's URDF damping and Coulomb friction (its parameters ``damping_<coordinate>``,
    ``friction_<coordinate>``) on the left side of its equations of motion; unchanged when no joint has a
    ``<dynamics>`` element."""
    if not model.has_joint_dynamics:
        return model
    names = {p.name: p.symbol for p in model.parameters}
    damping, coulomb = [], []
    for c in model.pair_coordinates:
        given = c.dynamics.given
        damping.append(names[f"damping_{c.name}"] if given else sp.Integer(0))
        coulomb.append(names[f"friction_{c.name}"] if given else sp.Integer(0))
    return dataclasses.replace(model, damping=tuple(damping), coulomb=tuple(coulomb))


def passive_entry(model: Model) -> dict | None:
    """What forward and inverse dynamics hold of the joints' damping and friction (the manifest's ``passive``, the
    header's notes): None when the model has neither."""
    if model.has_damping:
        damping, friction = _nonzero(model.damping), _nonzero(model.coulomb)
        terms = " and ".join(t for t, there in (("viscous damping D qd", damping),
                                                 ("Coulomb friction F sign(qd) (sign(0) = 0)", friction)) if there)
        return {"mode": "include",
                "equation": f"A(q) qdd + b(q, qd) + g(q){_springs(model)} + D qd" + (" + F sign(qd)" if friction
                                                                                   else "") + " = tau",
                "damping": damping, "friction": friction,
                "included_in": list(INCLUDED_IN),
                "note": f"the joints' {terms} are on the left side of inverse_dynamics, forward_dynamics and "
                        f"nonlinear_effects (and of their derivatives); passive_forces gives their negative"
                        + (" (with the springs' -c(q))" if _springs(model) else "")}
    if model.has_joint_dynamics:
        given = [c for c in model.coordinates if c.dynamics.given]
        return {"mode": "exclude",
                "equation": f"A(q) qdd + b(q, qd) + g(q){_springs(model)} = tau + tau_f, tau_f = joint_friction(qd, p)",
                "damping": [f"damping_{c.name}" for c in given], "friction": [f"friction_{c.name}" for c in given],
                "excluded_from": list(INCLUDED_IN),
                "note": "URDF <dynamics damping/friction> are in p and in joint_friction (tau_f = -d qd - "
                        "f sign(qd)), not in inverse_dynamics, forward_dynamics or nonlinear_effects (as "
                        "Pinocchio's rnea and aba): add tau_f to tau yourself, or generate with --passive include"}
    return None


def routine_notes(model) -> dict:
    """{role: one line} for the routines of :data:`INCLUDED_IN`: what each holds of the joints' damping and friction
    (the header's comment next to its declaration); empty when the model has neither."""
    entry = passive_entry(model)
    if entry is None:
        return {}
    if entry["mode"] == "include":
        return {role: f"joint damping and friction included: {entry['equation']}" for role in INCLUDED_IN}
    head = "joint damping and friction (URDF <dynamics>) NOT included"
    tail = "or generate with --passive include"
    return {"inverse_dynamics": f"{head}: the torque to apply is this tau minus tau_f from joint_friction; {tail}",
            "nonlinear_effects": f"{head}: with them, this d minus tau_f from joint_friction; {tail}",
            "forward_dynamics": f"{head}: pass tau plus tau_f from joint_friction; {tail}"}


def _springs(model) -> str:
    """' + c(q)' when the model has Hooke-elastic pairs (2.27)."""
    return " + c(q)" if any(b.pair.elastic for b in model.bodies) else ""


def _nonzero(values) -> list:
    """The names of the parameters (or the expressions) that are not exactly zero, per coordinate in tree order."""
    return [str(v) for v in values if not (getattr(v, "is_zero", False) or v == 0)]


__all__ = ["INCLUDED_IN", "PASSIVE_MODES", "passive_entry", "routine_notes", "with_passive_included"]
