"""The derivatives of the dynamics (on request): d tau / d(q, qd) by forward-mode differentiation of the sweeps,
d qdd / d(q, qd) through A^-1 by the transvective factors."""
from __future__ import annotations

from ..mechanics import derivatives, passive
from .registry import Output, Routine, flat, minus, register
from .shapes import nq_square


def _inverse_dynamics_derivatives(bound, kin, x):
    dq, dqd = derivatives.inverse_dynamics_derivatives(bound, kin, x["qd"], x["qdd"])
    return flat(dq), flat(dqd)


def _forward_dynamics_derivatives(bound, kin, x):
    dq, dqd = derivatives.forward_dynamics_derivatives(
        bound, kin, x["qd"], minus(x["tau"], passive.left_forces(bound, kin.q, x["qd"])))
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
