"""The routines of support dynamics (the support paper, (3.1)-(3.4)): q is the support's six coordinates, gamma
the mechanism's k; the coefficients of the support equation, its direct and its inverse problem."""
from __future__ import annotations

from ..mechanics import support
from .registry import Output, Routine, flat, register
from .shapes import mechanism_vector, scalar, six, support_block, support_lengths


def _has_support(model) -> bool:
    return model.support is not None


SUPPORT_OUTPUTS = (("support_A", "6"), ("support_B", "6"), ("support_I", "k"), ("support_J", "k"),
                   ("support_L", "6"))
SUPPORT_FAILURE = "the support's A = A+ M is singular (its pair's angles at a singularity: cos theta5 = 0)"


def support_layout(model) -> dict:
    support = next(b for b in model.bodies if b.name == model.support)
    return {"support": model.support, "q": [c.name for c in support.pair.coordinates],
            "gamma": [c.name for c in model.coordinates[6:]],
            "equation": "support_A qdd + support_B qd + support_I gammadd + support_J gammad + support_g = "
                        "support_L T (3.1): a wrench balance at the support's origin, its axes",
            "T": "the external wrench on the support: (f, mu) about the world origin, world axes",
            "B_J": "column j of B (of J) is the support-side wrench of column j of the book's B(q, qd) (2.17) "
                   "(B qd = b), before the projection M^T: B multiplies the support's rates, J the mechanism's",
            "order": "row-major"}


def _support_coefficients(bound, kin, x):
    c = support.support_coefficients(bound, x)
    return flat(c["A"]), flat(c["B"]), flat(c["I"]), flat(c["J"]), flat(c["L"]), c["g"]


def _support_direct(bound, kin, x):
    qdd, status = support.support_direct(bound, x)
    return qdd, [status]


def _support_inverse(bound, kin, x):
    gammadd, residual, status = support.support_inverse(bound, x)
    return gammadd, residual, [status]


register(Routine("support_coefficients", ("q", "qd", "gamma", "gammad", "p"),
                 tuple(Output(name, support_block(cols)) for name, cols in SUPPORT_OUTPUTS) +
                 (Output("support_g", six),), _support_coefficients,
                 "the coefficients of the support equation A qdd + B qd + I gammadd + J gammad + g = L T (3.1)-(3.3): "
                 "A = A+_11 M, I_beta = L A+_lk M f_beta, B and J the support-side columns of B(q, qd) (2.17), g "
                 "the weights at the support, L the world wrench T moved to the support",
                 layout=support_layout, applies=_has_support, coupled=None, input_lengths=support_lengths))
register(Routine("support_direct", ("q", "qd", "gamma", "gammad", "gammadd", "T", "p"),
                 (Output("qdd", six), Output("status", scalar, returned=True, failure=SUPPORT_FAILURE)),
                 _support_direct,
                 "the direct problem (3.4) 1: the support's qdd from its state, the mechanism's motion gamma(t) and "
                 "the external wrench T", layout=support_layout, applies=_has_support, coupled=None,
                 input_lengths=support_lengths))
register(Routine("support_inverse", ("q", "qd", "qdd", "gamma", "gammad", "T", "p"),
                 (Output("gammadd", mechanism_vector), Output("residual", six),
                  Output("status", scalar, returned=True,
                         failure="I (6 x k) is rank-deficient at the point (I I^T singular when k >= 6, I^T I when "
                                 "k < 6)")),
                 _support_inverse,
                 "the inverse problem (3.4) 2: the mechanism's gammadd that gives the support a wanted qdd: exact "
                 "(minimum norm when k > 6) when rank I = 6, least squares with the 6-residual when k < 6",
                 layout=support_layout, applies=_has_support, coupled=None, input_lengths=support_lengths))
