"""The states where A(q) is singular, reported by the routines that solve with it.

Where A(q) is regular at generic configurations but not proved regular at every one (:func:`~.regularity.regularity`
of kind ``"sampled"``: a point-mass head whose neck pitch can be 0, an Euler-angle base at gimbal lock), forward
dynamics, A^-1, the transvective factors and the derivatives of forward dynamics are generated as everywhere, with
one more output: a returned status (the C function's ``int``, the NumPy module's ``LinAlgError``, NaN in the JAX
and PyTorch modules), as the constrained routines have (docs/generated-code.md).

The status counts the coordinates whose pivot is at or below :data:`PIVOT` of the mean pivot,
``(beta,beta)^k <= PIVOT * sum_j (beta,beta)^j / n``, as the constrained routines judge their pivots against
trace(G) / m.  The pivot (beta,beta)^k = psi_k^T A^Delta_k psi_k (3.7), (3.12) is the Schur complement of A_kk over
the coordinates eliminated before k (those of k's subtree), so ``0 < (beta,beta)^k <= A_kk`` where A is positive
definite and ``det A = prod_k (beta,beta)^k``: A is singular exactly where a pivot is zero, and a nonzero status
means cond(A) >= 1 / PIVOT (lambda_min <= (beta,beta)^k, and the mean pivot is at most trace(A) / n <=
lambda_max).  The scale is the whole matrix's, not A_kk's: at a point-mass head's singular set it is A_kk itself
that vanishes (the head on the yaw axis), its Schur complement staying close to it.  Past a zero pivot the later
ones are infinite or NaN, so the mean is too and the status stays nonzero (sign(NaN) is NaN).  The pivots are the
forward dynamics' own (the program numbers equal operations once): the status adds 2n operations and n calls of
sign, except where the forward dynamics solves a pair in body axes (an Euler-angle base, a spherical pair:
:func:`~aggsym.mechanics.transvective.forward_dynamics_in_bases`), whose pivots are not those of A.

Left without a status: models with coupled coordinates (their forward dynamics solves the coupled system, not the
tree's) and with a tendon's armature (A is the tree's plus a c c^T, regular where the tree's is not)."""
from __future__ import annotations

import dataclasses

from ..mechanics import transvective
from .registry import EMITTED_AS, ROUTINES, Output, Routine
from .shapes import scalar

PIVOT = 1e-12  # a pivot (beta,beta)^k at or below PIVOT times the mean pivot makes the status nonzero (cond >= 1e12)
ROLES = ("forward_dynamics", "inertia_inverse", "transvective_factors", "forward_dynamics_derivatives")
FAILURE = (f"A(q) is singular or nearly so: a pivot (beta,beta)^k of its transvective factors (3.12) is at or below "
           f"{PIVOT:g} of their mean (cond(A) >= {1 / PIVOT:g}); the manifest's mass_matrix names the bodies")
_VARIANTS: dict = {}


def reports_singular_states(model) -> bool:
    """Whether the model's routines of :data:`ROLES` carry the status: A(q) regular at generic configurations but
    not proved regular everywhere, no coupled coordinates, no tendon armature."""
    from .regularity import regularity

    if model.couplings or any(not _zero(t.armature) for t in model.tendons):
        return False
    return regularity(model).kind == "sampled"


def _zero(x) -> bool:
    return getattr(x, "is_zero", False) is True or x == 0


def routine_of(model, role: str) -> Routine:
    """The routine ``role`` as this model emits it: with the status output where :func:`reports_singular_states`."""
    routine = ROUTINES[role]
    if role not in ROLES or not reports_singular_states(model):
        return routine
    return with_status(routine)


def with_status(routine: Routine) -> Routine:
    """The routine with the status of :func:`singular_pivots` as one more, returned, output (one per role)."""
    variant = _VARIANTS.get(routine.role)
    if variant is None or variant[0] is not routine:
        build = routine.build

        def built(bound, kin, x):
            return (*build(bound, kin, x), [singular_pivots(bound, kin)])

        status = Output("status", scalar, returned=True, failure=FAILURE)
        variant = _VARIANTS[routine.role] = (routine, dataclasses.replace(
            routine, outputs=routine.outputs + (status,), build=built))
    return variant[1]


def singular_pivots(bound, kin):
    """The number of coordinates k with ``(beta,beta)^k <= PIVOT * sum_j (beta,beta)^j / n``, each counted by
    sign() + 1 (1 at equality, 2 below; NaN where a pivot is NaN): zero exactly where A(q) is, by this measure,
    regular."""
    backend = bound.backend
    diag = transvective.articulated_factors(bound, kin, arguments=False).diag
    total = 0
    for d in diag:
        total = total + d
    tol = total * (PIVOT / len(diag))
    status = 0
    for d in diag:
        status = status + (backend.call("sign", tol - d) + 1)
    return status


def status_entry(routines) -> dict:
    """For the manifest's ``mass_matrix`` (and the header): the emitted routines that report A(q)'s singular states
    and what their nonzero status means; empty when none does."""
    reporting = [r.role for r in routines if r.role in ROLES and r.status is not None]
    return {"reported_by": reporting, "status": f"nonzero where {FAILURE}"} if reporting else {}


def mass_matrix_note(model, routines) -> str | None:
    """The header's paragraph where A(q) is not proved regular everywhere (None where it is): why, and which
    routines return nonzero at its singular states."""
    from .regularity import regularity

    regular = regularity(model)
    if regular.kind == "everywhere":
        return None
    reporting = status_entry(routines).get("reported_by")
    return regular.describe(model) + (f". {', '.join(reporting)} return nonzero where {FAILURE}" if reporting else "")


EMITTED_AS[0] = routine_of  # (registry.routines_for lists each routine as the model emits it)

__all__ = ["PIVOT", "ROLES", "FAILURE", "reports_singular_states", "routine_of", "with_status", "singular_pivots",
           "status_entry", "mass_matrix_note"]
