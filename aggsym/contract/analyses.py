"""Numerical analyses of a model at generation, on the numeric twin: random configurations, structurally redundant
constraint rows (whether A(q) is regular: :mod:`.regularity`), why the regressor does not hold, and the
base-parameter reduction of the regressor (its exact coefficients: :mod:`.exact_relations`)."""
from __future__ import annotations

import functools

from ..mechanics import elastic
from ..model.tree import Tree
from .exact_relations import candidate_supports, pivoted_columns
from .registry import ROUTINES, run


def sample_configurations(model, rng, size=None):
    """Random configurations q (shape (nq,), or (nq, size)): each coordinate uniform in [-pi, pi]; a free-flyer's
    position uniform in [-pi, pi]^3 and its (or a ball pair's) quaternion a random unit quaternion (the samples of the checks, the
    base parameters and the redundancy tests)."""
    import numpy as np

    shape = (model.nq,) if size is None else (model.nq, size)
    q = rng.uniform(-np.pi, np.pi, shape)
    for idx, b in zip(Tree.of(model).positions, model.bodies):
        if b.pair.quaternion:
            quat = rng.normal(size=(4,) + shape[1:])
            q[idx[-4]:idx[-4] + 4] = quat / np.linalg.norm(quat, axis=0)
    return q


def redundant_constraints(model, samples: int = 2, tolerance: float = 1e-9) -> list:
    """The constraints with rows that depend on other rows when J is rank-deficient at q = 0 and at ``samples``
    fixed random configurations, all of them (a structural redundancy, such as a planar four-bar closed by a point
    constraint, and not a singular configuration): [(constraint, [codes])].  Which rows are named is a choice
    (any row of a dependent set could go): those a greedy scan in row order finds dependent at the last sample.
    A model whose J has full rank at any one of the samples has no structural redundancy: []."""
    import numpy as np

    from ..core.backend import Numeric
    from ..mechanics.bound import bind

    if not model.constraints:
        return []
    bound = bind(model, Numeric())
    rng = np.random.default_rng(0)
    dependent = set()
    for q in [bound.tree.neutral] + [sample_configurations(model, rng) for _ in range(samples)]:
        J = np.array(run(ROUTINES["constraint_jacobian"], bound, {"q": [float(x) for x in q]})[0], dtype=float)
        J = J.reshape(model.constraint_rows, model.nv)
        scale = max(float(np.abs(J).max()), 1e-300)
        dependent, kept = set(), []
        for r in range(J.shape[0]):
            trial = kept + [J[r]]
            if np.linalg.matrix_rank(np.array(trial), tol=tolerance * scale) > len(kept):
                kept.append(J[r])
            else:
                dependent.add(r)
        if not dependent:
            return []
    out, start = [], 0
    for c in model.constraints:
        codes = [code for r, code in enumerate(c.rows, start) if r in dependent]
        if codes:
            out.append((c, codes))
        start += len(c.rows)
    return out


def regressor_problem(model) -> str | None:
    """Why tau = Y pi does not hold for a model (the regressor is then omitted), or None."""
    if model.tendons or model.spatial_tendons:
        return "the tendons' springs and dampers act in tau and are not inertial parameters"
    if model.has_fluid:
        return "the fluid's drag acts in tau and is not linear in the inertial parameters"
    if model.gravcomp:
        return "gravity compensation (gravcomp) lifts a fraction of some bodies' weight; it is not in the regressor"
    if elastic.is_elastic(model):
        return "the elastic force C (q - q0) of (2.27) is in tau and not linear in the inertial parameters"
    if any(b.added_mass is not None for b in model.bodies):
        return "added masses (Prop. 2.8) act in tau and are not among the inertial parameters"
    if model.has_damping:
        return ("the joints' damping D qd and friction F sign(qd) are in tau and are not inertial parameters "
                "(a URDF robot: generate with --passive exclude, the default, for the regressor)")
    return None


BASE_SEED = 0  # the random states of the base-parameter reduction (the exact ones: BASE_SEED + 1)
BASE_RANK_TOLERANCE = "max(rows, columns) * 2.2e-16 * the largest singular value (numpy.linalg.matrix_rank's)"


@functools.lru_cache(maxsize=8)
def base_parameters(model, role: str = "regressor") -> tuple:
    """The base-parameter reduction of the regressor ``role`` (``regressor``, or ``friction_regressor`` with the
    friction and armature columns) at the default parameters: (independent columns, dependent columns, beta,
    samples, inexact, residual) such that ``Y[:, dependent] = Y[:, independent] beta`` on every state, so that tau = Y_b pi_b
    with ``Y_b = Y[:, independent]`` and ``pi_b = pi[independent] + beta pi[dependent]``.

    Which columns: as identification practice does, Y at ``samples`` random states (seed :data:`BASE_SEED`: q
    uniform in [-pi, pi], qd and qdd standard normal) stacked, its rank r with the tolerance of
    :data:`BASE_RANK_TOLERANCE`, and the first r pivots of a QR factorization with column pivoting (Householder,
    largest remaining column first: Gautier's choice), listed in column order.  beta: exact rationals
    (:mod:`.exact_relations`: the program in rational arithmetic at rational states, each dependent column solved
    on a support that the least squares chooses), given as the doubles nearest them; ``inexact`` lists the
    dependent columns whose relation is not exact in the model's own numbers (their coefficients are then the
    least squares on the samples), ``residual`` the largest relative residual of those on the samples."""
    import numpy as np

    from ..core.backend import Numeric
    from ..mechanics.bound import bind
    from .exact_relations import Inexact, exact_coefficients, exact_rows

    n, P = ROUTINES[role].outputs[0].shape(model)
    samples = max(8, -(-4 * P // max(n, 1)))
    rng = np.random.default_rng(BASE_SEED)
    bound = bind(model, Numeric())
    x = {"q": list(sample_configurations(model, rng, samples)), "qd": list(rng.normal(size=(n, samples))),
         "qdd": list(rng.normal(size=(n, samples)))}
    flat = run(ROUTINES[role], bound, x)[0]
    Y = np.stack([np.broadcast_to(np.asarray(v, dtype=float), (samples,)) for v in flat]).reshape(n, P, samples)
    Y = Y.transpose(2, 0, 1).reshape(samples * n, P)
    sv = np.linalg.svd(Y, compute_uv=False)
    tol = sv[0] * max(Y.shape) * np.finfo(float).eps if sv.size else 0.0
    rank = int((sv > tol).sum())
    independent = sorted(pivoted_columns(Y)[:rank])
    dependent = [j for j in range(P) if j not in set(independent)]
    if not (rank and dependent):  # nothing to express, or nothing identifiable (moving bodies that do no work)
        return tuple(independent), tuple(dependent), np.zeros((rank, len(dependent))), samples, (), 0.0
    least = np.linalg.lstsq(Y[:, independent], Y[:, dependent], rcond=None)[0]
    largest = max((len(s) for s in candidate_supports(least, independent, dependent, Y)), default=0)
    try:
        rows = exact_rows(model, role, max(3, -(-3 * (largest + 1) // max(n, 1))), BASE_SEED + 1)
    except Inexact:  # (the program needs a value that is not rational: every relation judged on the samples)
        rows = None
    exact, inexact, residual = exact_coefficients(rows, Y, independent, dependent, least)
    beta = np.array([[float(v) for v in row] for row in exact], dtype=float).reshape(rank, len(dependent))
    return tuple(independent), tuple(dependent), beta, samples, tuple(inexact), residual
