"""The derivatives of the dynamics (on request): d tau / d(q, qd) by forward-mode differentiation of the sweeps,
d qdd / d(q, qd) through A^-1 by the transvective factors; those of the constrained forward dynamics and of
impulse dynamics by implicit differentiation of their constrained system."""
from __future__ import annotations

from ..mechanics import constraint_derivatives, derivatives, passive
from .registry import Output, Routine, flat, minus, register
from .routines_constraints import CONSTRAINT_FAILURE
from .shapes import nq_square, scalar


def _recorded(bound, role, columns):
    """The solves' :class:`~aggsym.core.columns.ColumnMap` kept on the straight-line program (none on floats)."""
    if columns:
        bound.backend.program.columns[role] = columns[0]


def _inverse_dynamics_derivatives(bound, kin, x):
    dq, dqd = derivatives.inverse_dynamics_derivatives(bound, kin, x["qd"], x["qdd"])
    return flat(dq), flat(dqd)


def _forward_dynamics_derivatives(bound, kin, x):
    columns = []
    dq, dqd = derivatives.forward_dynamics_derivatives(
        bound, kin, x["qd"], minus(x["tau"], passive.left_forces(bound, kin.q, x["qd"])), columns)
    _recorded(bound, "forward_dynamics_derivatives", columns)
    return flat(dq), flat(dqd)


register(Routine("inverse_dynamics_derivatives", ("q", "qd", "qdd", "p"),
                 (Output("dtau_dq", nq_square), Output("dtau_dqd", nq_square)), _inverse_dynamics_derivatives,
                 "d tau / d q and d tau / d qd, n*n row-major (entry (i, j): d tau_i / d x_j; d tau / d qdd is A): "
                 "the sweeps (2.39)-(2.46) differentiated in forward mode, reusing their intermediates",
                 coupled="matrix", on_request=True, frame_free=True, slice_size=80))
register(Routine("forward_dynamics_derivatives", ("q", "qd", "tau", "p"),
                 (Output("dqdd_dq", nq_square), Output("dqdd_dqd", nq_square)), _forward_dynamics_derivatives,
                 "d qdd / d q and d qdd / d qd, n*n row-major (d qdd / d tau is A^-1): -A^-1 d tau_ID / d x at the "
                 "forward dynamics' qdd, A^-1 applied column by column by the transvective factors (3.19)-(3.20)",
                 coupled=None, regular=True, on_request=True, frame_free=True, slice_size=80))


def _no_coulomb(model) -> bool:
    return bool(model.constraints) and not any(c.friction is not None and c.friction[0] == "coulomb"
                                               for c in model.constraints)


def _constrained_forward_dynamics_derivatives(bound, kin, x):
    columns = []
    *mats, status = constraint_derivatives.constrained_forward_dynamics_derivatives(bound, kin, x["qd"], x["tau"],
                                                                                    columns)
    _recorded(bound, "constrained_forward_dynamics_derivatives", columns)
    return (*(flat(m) for m in mats), [status])


def _impulse_dynamics_derivatives(bound, kin, x):
    columns = []
    *mats, status = constraint_derivatives.impulse_dynamics_derivatives(bound, kin, x["qd_minus"], x["r"][0],
                                                                        columns)
    _recorded(bound, "impulse_dynamics_derivatives", columns)
    return (*(flat(m) for m in mats), [status])


register(Routine("constrained_forward_dynamics_derivatives", ("q", "qd", "tau", "p"),
                 tuple(Output(f"d{y}_d{v}", nq_square) for y in ("qdd", "Jtlambda") for v in ("q", "qd", "tau"))
                 + (Output("status", scalar, returned=True, failure=CONSTRAINT_FAILURE),),
                 _constrained_forward_dynamics_derivatives,
                 "d qdd / d(q, qd, tau) and d (J^T lambda) / d(q, qd, tau) of constrained_forward_dynamics, n*n "
                 "row-major: the system (4.25)-(4.28) differentiated implicitly, its terms' tangents by forward mode, "
                 "each column one more solve on the same factors (3.19) and G; q in the tangent space",
                 applies=_no_coulomb, coupled=None, regular=True, on_request=True))
register(Routine("impulse_dynamics_derivatives", ("q", "qd_minus", "r", "p"),
                 (Output("dqd_plus_dq", nq_square), Output("dqd_plus_dqd_minus", nq_square),
                  Output("dimpulse_dq", nq_square), Output("dimpulse_dqd_minus", nq_square),
                  Output("status", scalar, returned=True, failure=CONSTRAINT_FAILURE)),
                 _impulse_dynamics_derivatives,
                 "d qd+ / d(q, qd-) and d (J^T Lambda) / d(q, qd-) of impulse_dynamics, n*n row-major: the impact "
                 "law differentiated implicitly on the factors of its solve; q in the tangent space",
                 applies=_no_coulomb, coupled=None, regular=True, on_request=True))
