"""The routine of impulse dynamics (on request): the velocity after an impact on the model's constraints and the
impulse, Pinocchio's ``impulseDynamics`` (:mod:`aggsym.mechanics.impacts`)."""
from __future__ import annotations

from ..mechanics import impacts
from .registry import Output, Routine, register
from .routines_constraints import CONSTRAINT_FAILURE, constraint_row_labels
from .shapes import constraint_rows_vector, nq_vector, scalar


def _has_impacts(model) -> bool:
    """Constraints without Coulomb friction (an impulse through a Coulomb contact is not this law)."""
    return bool(model.constraints) and not any(c.friction is not None and c.friction[0] == "coulomb"
                                               for c in model.constraints)


def impulse_layout(model) -> dict:
    return {"qd_plus": "the velocity after the impact, in qd's layout",
            "impulse": "J^T Lambda, the joint-space impulse, in tau's layout: A (qd_plus - qd_minus)",
            "Lambda": {"rows": constraint_row_labels(model),
                       "meaning": "the impulse wrench per constraint row, as lambda of constrained_forward_dynamics"}}


def _impulse_dynamics(bound, kin, x):
    qd_plus, impulse, lam, status = impacts.impulse_dynamics(bound, kin, x["qd_minus"], x["r"][0])
    return qd_plus, impulse, lam, [status]


register(Routine("impulse_dynamics", ("q", "qd_minus", "r", "p"),
                 (Output("qd_plus", nq_vector), Output("impulse", nq_vector), Output("Lambda", constraint_rows_vector),
                  Output("status", scalar, returned=True, failure=CONSTRAINT_FAILURE)),
                 _impulse_dynamics,
                 "qd+ and the impulse J^T Lambda of an impact with restitution r: A (qd+ - qd-) = J^T Lambda, J qd+ "
                 "+ F = -r (J qd- + F) (ch. 4 as an impact law): G Lambda = -(1 + r)(J qd- + F) with G = P^T D^-1 P, "
                 "P = T J^T, then qd+ = qd- + T^T D^-1 P Lambda (3.19); returns nonzero when G is singular",
                 layout=impulse_layout, applies=_has_impacts, coupled=None, regular=True, on_request=True))
