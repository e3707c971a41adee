"""Derivatives of the constrained forward dynamics and of impulse dynamics (chapter 4), by implicit
differentiation of the constrained system with forward-mode tangents of its terms (:mod:`aggsym.core.dual`).

Both solve ``A x - J^T lambda = f``, ``J x (+ epsilon lambda) = h`` (:mod:`aggsym.mechanics.kkt`).  Along any
input direction s, holding x and lambda at their solution,

    E1 = A(q) x + (b + g + c + friction)(q, qd) - J(q)^T lambda - tau,     E2 = J(q) x - h(q, qd)

have tangents E1', E2' (one forward-mode sweep of the recursions on dual numbers, seeded on q or qd); the
derivatives (x', lambda') solve the same system with ``f = -E1'``, ``h = -E2'`` on the same factors, and
``(J^T lambda)' = (J')^T lambda + J^T lambda'`` (the first term is E1's part from J^T lambda).  A tau direction
has ``f = e_j``, ``h = 0``.

* Constrained forward dynamics: x = qdd, lambda its multipliers, ``E1 = u*(q, qd, qdd) + C (q - q0) + D qd +
  c_v Jf^T Jf qd - J^T lambda`` (viscous friction on the slip rows), ``E2 = J qdd + gamma + kd (J qd + F) + kp
  phi``.  Outputs d qdd / d(q, qd, tau) and d (J^T lambda) / d(q, qd, tau).
* Impulse dynamics: x = qd+ - qd-, lambda = Lambda, ``E1 = A(q) x - J^T Lambda`` (A x by the sweeps at qd = 0
  without gravity), ``E2 = J x + (1 + r)(J qd- + F)``.  Outputs d qd+ / d q, d qd+ / d qd- (= E + x'), and
  d (J^T Lambda) / d(q, qd-).

With a free-flyer the q directions are Pinocchio's tangent space (:func:`~.derivatives.tangent_seeds`:
``q (+) d``, d in the base's own axes), as ``computeConstraintDynamicsDerivatives`` and
``computeImpulseDynamicsDerivatives`` define them.  With the damped solve (:mod:`aggsym.mechanics.damped`) every
column goes through the same damped inverse of G as the value (what Pinocchio's derivatives do with its proximal
settings): the derivatives of the exact solution where J has full row rank, to the solve's stated bound.

On a straight-line program the tangents are made one direction at a time (as
:func:`~.derivatives.inverse_dynamics_derivatives` does), on floats all at once; the 2n or 3n solves apply T
through its arguments where that takes fewer operations than the tree sweeps (:func:`~.kkt.arguments_pay`, counted).

Where the operations go (Talos on two welded soles, n = 38, m = 12, tree sweeps: 317,000 for the constrained
derivatives): the value 16,000, the tangents of E1 (the inverse dynamics' derivatives at the constrained q'')
59,000, those of J^T lambda and E2 9,000, the 3n solves the rest, about 2,000 each.
"""
from __future__ import annotations

import dataclasses

from ..core.columns import COLUMN_F, COLUMN_H, COLUMN_T, ColumnMap, Run
from ..core.dual import Dual, DualBackend, lift, tangent
from ..core.program import is_zero
from .constraints import ConstraintKinematics, _transpose_times, constrained_forward_dynamics, rest_kinematics
from . import spatial_derivatives
from .derivatives import cheaper_form, inverse_dynamics_derivatives, tangent_seeds
from .impacts import impact_rhs
from .kinematics import TreeKinematics
from .kkt import ConstrainedSystem, arguments_pay
from .linalg import dot, mul
from .passive import left_forces
from .sweeps import inverse_dynamics


def _dual_state(bound, kin, qd, directions):
    """The bound model on dual numbers, its kinematics at q and the rates qd, seeded along ``directions`` (q's
    tangent directions 0..n-1, qd's n..2n-1)."""
    n = kin.tree.nv
    dual = dataclasses.replace(bound, backend=DualBackend(bound.backend))
    q = [lift(x.v, {k: t for k, t in x.d.items() if k in directions}) if isinstance(x, Dual) else x
         for x in tangent_seeds(kin)]
    rates = [lift(x, {n + i: 1} if n + i in directions else {}) for i, x in enumerate(qd)]
    return dual, TreeKinematics(dual, q), q, rates


def _batches(bound, n, count):
    """The direction sets of the dual sweeps: one per direction on a program, all at once on floats."""
    if bound.backend.symbolic:
        return [(d,) for d in range(count)]
    return [tuple(range(count))]


def _matrix(columns, n):
    """n x len(columns) rows from columns."""
    return [[c[i] for c in columns] for i in range(n)]


def _forward_terms(bound, kin, qd, qdd, lam, directions, sweeps=True):
    """(E1 without the J^T lambda term, J^T lambda, E2) of the constrained forward dynamics on duals; without
    ``sweeps`` E1 leaves out the inverse dynamics and the passive forces (their tangents come from
    :func:`~.derivatives.inverse_dynamics_derivatives`)."""
    dual, dkin, q, rates = _dual_state(bound, kin, qd, directions)
    ck = ConstraintKinematics(dual, dkin)
    J = ck.jacobian()
    e1 = [a + b for a, b in zip(inverse_dynamics(dual, dkin, rates, qdd), left_forces(dual, q, rates))] if sweeps \
        else [0] * len(qd)
    if bound.model.has_friction:
        for c, Jf in zip(ck.items, ck.slip_jacobians()):
            if c.law == "viscous":
                w = [mul(c.coefficient, dot(row, rates)) for row in Jf]
                e1 = [a + b for a, b in zip(e1, _transpose_times(Jf, w))]
    jt = _transpose_times(J, lam) if J else [0] * len(qd)
    e2 = [dot(row, qdd) + g for row, g in zip(J, ck.bias(rates))]
    kp, kd = (dual.scalar(x) for x in bound.model.stabilization)
    if not is_zero(kd):
        e2 = [e + mul(kd, dot(row, rates) + f) for e, row, f in zip(e2, J, ck.time_terms())]
    if not is_zero(kp):
        e2 = [e + mul(kp, f) for e, f in zip(e2, ck.residual(rest_kinematics(dual)))]
    return e1, jt, e2


def _impulse_terms(bound, kin, qd, x, lam, r, directions, sweeps=True):
    """(A x, J^T Lambda, E2) of the impact on duals (A x left out without ``sweeps``)."""
    dual, dkin, q, rates = _dual_state(bound, kin, qd, directions)
    ck = ConstraintKinematics(dual, dkin)
    J = ck.jacobian()
    n = len(qd)
    zero = [0] * n
    ax = inverse_dynamics(dual, dkin, zero, x, gravity=False) if sweeps else zero
    if sweeps and bound.model.time_dependent:  # prescribed spins make terms at qd = 0 that are no part of A x
        ax = [a - b for a, b in zip(ax, inverse_dynamics(dual, dkin, zero, zero, gravity=False))]
    jt = _transpose_times(J, lam) if J else zero
    h = impact_rhs(J, ck.time_terms(), rates, r)
    e2 = [dot(row, x) - hi for row, hi in zip(J, h)]
    return ax, jt, e2


def _columns(system, terms, directions, count, known=None):
    """Per direction d of ``directions``: (x', (J^T lambda)', its column's values (f, h, (J')^T lambda)) from the
    tangents of ``terms`` = (E1 less J^T lambda, J^T lambda, E2); ``known``: rows of E1's tangents along every
    direction that the terms leave out (the inverse dynamics' derivatives in the spatial form), or None."""
    e1, jt, e2 = terms
    out = {}
    for d in directions:
        tj = [tangent(v, d) for v in jt]
        f = [tv - tangent(v, d) for v, tv in zip(e1, tj)]
        if known is not None:
            f = [x - row[d] for x, row in zip(f, known)]
        h = [-tangent(v, d) for v in e2]
        out[d] = (*_solved(system, f, h, tj), (f, h, tj))
    return out


def _solved(system, f, h, tj) -> tuple:
    """(x, tj + J^T lambda) of the system at (f, h): one column, and the body of :func:`_column_map`."""
    x, lam = system.solve(f, h)
    return x, [a + b for a, b in zip(tj, system.joint_space(lam))]


def _column_map(system, n, m, columns, offsets=()):
    """The solves as one body applied to columns (:mod:`aggsym.core.columns`), for a straight-line program:
    ``columns``: per block (output of x', output of (J^T lambda)', its n columns' values)."""
    program = system.bound.backend.program
    f, h, t = (program.vector(kind, k) for kind, k in ((COLUMN_F, n), (COLUMN_H, m), (COLUMN_T, n)))
    x, y = _solved(system, f, h, t)
    cmap = ColumnMap([f, h, t], [x, y], offsets=list(offsets))
    for ox, oy, values in columns:
        cmap.runs.append(Run(list(values), [(ox, 0, 1, n), (oy, 0, 1, n)]))
    return cmap


def _known(dq, dqd):
    """The rows [dq | dqd] (n x 2n): E1's tangents along q's directions, then qd's."""
    return [list(a) + list(b) for a, b in zip(dq, dqd)]


def constrained_forward_dynamics_derivatives(bound, kin, qd, tau, columns=None, form=None) -> tuple:
    """(dqdd/dq, dqdd/dqd, dqdd/dtau, d(J^T lambda)/dq, .../dqd, .../dtau) as n x n rows, and the status of the
    solve (``tau`` as the routine receives it: the passive forces are taken here).  ``columns``: a list, to which
    the solves are appended as a :class:`~aggsym.core.columns.ColumnMap` on a straight-line program.  ``form``
    (``"spatial"``, ``"dual"``, None: :func:`~.derivatives.cheaper_form` of the whole routine chooses): how E1's
    inverse dynamics is differentiated, by the composites of :mod:`.spatial_derivatives` or within the dual
    sweeps."""
    n = kin.tree.nv
    if form is None:
        form = cheaper_form(bound, kin, "constrained_forward_dynamics_derivatives",
                     lambda b, k, u, way: constrained_forward_dynamics_derivatives(
                         b, k, u, b.backend.program.vector("tau", n), form=way)[:-1])
    qdd, lam, status = constrained_forward_dynamics(
        bound, kin, qd, [t - c for t, c in zip(tau, left_forces(bound, kin.q, qd))])
    system = ConstrainedSystem(bound, kin, arguments=arguments_pay(bound, kin, 3 * n))
    sweeps = form == "dual"
    known = None if sweeps else _known(*inverse_dynamics_derivatives(bound, kin, qd, qdd, form="spatial"))
    cols = {}
    for batch in _batches(bound, n, 2 * n):
        cols.update(_columns(system, _forward_terms(bound, kin, qd, qdd, lam, set(batch), sweeps), batch, 2 * n,
                             known))
    m = len(lam)
    for j in range(n):
        values = ([1 if i == j else 0 for i in range(n)], [0] * m, [0] * n)
        cols[2 * n + j] = (*_solved(system, *values), values)
    mats = []
    for part in (0, 1):
        for block in range(3):
            mats.append(_matrix([cols[block * n + j][part] for j in range(n)], n))
    if columns is not None and bound.backend.symbolic:
        columns.append(_column_map(system, n, m, [(b, 3 + b, [cols[b * n + j][2] for j in range(n)])
                                                  for b in range(3)]))
    return (*mats, status)


def impulse_dynamics_derivatives(bound, kin, qd, r, columns=None, form=None) -> tuple:
    """(dqd+/dq, dqd+/dqd-, d(J^T Lambda)/dq, d(J^T Lambda)/dqd-) as n x n rows, and the status of the solve;
    ``columns`` and ``form`` as for :func:`constrained_forward_dynamics_derivatives` (the spatial form gives the
    tangents of A x as those of the inverse dynamics at qd = 0, qdd = x, without gravity)."""
    n = kin.tree.nv
    if form is None:
        form = cheaper_form(bound, kin, "impulse_dynamics_derivatives",
                     lambda b, k, u, way: impulse_dynamics_derivatives(
                         b, k, u, b.backend.program.vector("r", 1)[0], form=way)[:-1])
    system = ConstrainedSystem(bound, kin, arguments=arguments_pay(bound, kin, 2 * n))
    x, lam = system.solve_transvected([0] * n, impact_rhs(system.J, system.ck.time_terms(), qd, r))
    sweeps = form == "dual"
    known = None
    if not sweeps:
        dq, _ = spatial_derivatives.inverse_dynamics_derivatives(bound, kin, [0] * n, x, gravity=False)
        known = _known(dq, [[0] * n for _ in range(n)])
    cols = {}
    for batch in _batches(bound, n, 2 * n):
        cols.update(_columns(system, _impulse_terms(bound, kin, qd, x, lam, r, set(batch), sweeps), batch, 2 * n,
                             known))
    dq = _matrix([cols[j][0] for j in range(n)], n)
    dqd = _matrix([cols[n + j][0] for j in range(n)], n)
    for i in range(n):
        dqd[i][i] = dqd[i][i] + 1
    if columns is not None and bound.backend.symbolic:
        columns.append(_column_map(system, n, len(lam), [(b, 2 + b, [cols[b * n + j][2] for j in range(n)])
                                                         for b in range(2)], [(1, i * n + i, 1) for i in range(n)]))
    return (dq, dqd, _matrix([cols[j][1] for j in range(n)], n), _matrix([cols[n + j][1] for j in range(n)], n),
            system.status)


__all__ = ["constrained_forward_dynamics_derivatives", "impulse_dynamics_derivatives"]
