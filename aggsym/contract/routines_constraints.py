"""The routines of the constraints (chapter 4): the residual phi, the Jacobian J, the bias gamma, the slip
velocities, the Delassus matrix G and the constrained forward dynamics; with their layouts."""
from __future__ import annotations

from ..mechanics import constraints, passive
from .registry import Output, Routine, flat, minus, register
from .shapes import (
    constraint_jacobian_shape, constraint_rows_vector, constraint_square, nq_vector, scalar, slip_vector,
)


def constraint_row_labels(model) -> list:
    return [f"{c.name}.{code}" for c in model.constraints for code in c.rows]


def constraint_layout(model) -> dict:
    return {"rows": constraint_row_labels(model), "columns": [c.name for c in model.coordinates],
            "order": "row-major", "convention": "see the manifest's 'constraints'"}


def _has_constraints(model) -> bool:
    return bool(model.constraints)


def slip_labels(model) -> list:
    return [f"{c.name}.{code}" for c in model.constraints for code in c.free_translations]


def slip_layout(model) -> dict:
    return {"rows": slip_labels(model), "order": "constraints in order, each one's free translations (o1 o2 o3 "
            "not blocked) in the axes of its reference frame"}


def _has_slip(model) -> bool:
    return model.slip_rows > 0


CONSTRAINT_FAILURE = ("the constraints are singular (J A^-1 J^T has a pivot below 1e-12 of its mean diagonal, or "
                      "is not finite), or Coulomb friction has no consistent solution")


def _constrained_forward_dynamics(bound, kin, x):
    qdd, lam, status = constraints.constrained_forward_dynamics(
        bound, kin, x["qd"], minus(x["tau"], passive.left_forces(bound, kin.q, x["qd"])))
    return qdd, lam, [status]


register(Routine("constraint_residual", ("q", "p"), (Output("phi", constraint_rows_vector),),
                 lambda bound, kin, x: (constraints.residual(bound, kin),),
                 "phi(q): the constraints' holonomic residual, m rows (ch. 4): the contact point's offset from its "
                 "attachment and the rotation vector of the relative orientation, in the reference axes",
                 layout=constraint_layout, applies=_has_constraints, coupled=None))
register(Routine("constraint_jacobian", ("q", "p"), (Output("J", constraint_jacobian_shape),),
                 lambda bound, kin, x: (flat(constraints.jacobian(bound, kin)),),
                 "J(q) = D_lambda^T, m*n row-major: the forbidden relative motions per unit rate of each "
                 "coordinate, rows of the parastrophic matrix S moved to the contact points (4.5)-(4.12)",
                 layout=constraint_layout, applies=_has_constraints, coupled=None))
register(Routine("constraint_bias", ("q", "qd", "p"), (Output("gamma", constraint_rows_vector),),
                 lambda bound, kin, x: (constraints.bias(bound, kin, x["qd"]),),
                 "gamma(q, qd) = J' qd: the relative accelerations at qdd = 0 (S'^T qd of (2.37) at the contact "
                 "points), so that J qdd + gamma is the constraints' acceleration",
                 layout=constraint_layout, applies=_has_constraints, coupled=None))
register(Routine("slip_velocities", ("q", "qd", "p"), (Output("w", slip_vector),),
                 lambda bound, kin, x: (constraints.slip_velocities(bound, kin, x["qd"]),),
                 "w(q, qd) = D_k+^T V (4.33)-(4.34): each contact point's velocity relative to the medium along "
                 "the free translations of its constraint (the sliding velocities friction acts on)",
                 layout=slip_layout, applies=_has_slip, coupled=None))
register(Routine("delassus", ("q", "p"), (Output("G", constraint_square),),
                 lambda bound, kin, x: (flat(constraints.delassus(bound, kin)),),
                 "G = J A^-1 J^T, m*m row-major, by the transvective factors: P = T J^T, G = P^T diag(1/(beta,beta)) "
                 "P (3.19)", applies=_has_constraints, coupled=None, regular=True))
register(Routine("constrained_forward_dynamics", ("q", "qd", "tau", "p"),
                 (Output("qdd", nq_vector), Output("lambda", constraint_rows_vector),
                  Output("status", scalar, returned=True, failure=CONSTRAINT_FAILURE)),
                 _constrained_forward_dynamics,
                 "qdd and lambda of A qdd + b + g + c = tau + J^T lambda, J qdd + gamma = -(kd J qd + kp phi) "
                 "(4.25)-(4.28): G lambda = -gamma - stab - P^T D^-1 T F with P = T J^T, then qdd = T^T D^-1 "
                 "(T F + P lambda) (3.20); friction on sliding contacts from the slip velocities (4.5), (4.33); "
                 "returns nonzero when G is singular (or Coulomb friction has no consistent solution)",
                 applies=_has_constraints, coupled=None, regular=True))
