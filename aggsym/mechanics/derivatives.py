"""Analytical derivatives of inverse and forward dynamics.

dtau/d(q, qd) takes one of two forms, whichever reaches fewer operations on the straight-line program
(:func:`derivative_form`): the composites of the tree (:mod:`.spatial_derivatives`: cheaper on general geometry and
deep trees, Panda 4111 operations against 6545, Talos with its free-flyer 26015 against 50397) or the sweeps on dual
numbers below (cheaper where parallel and orthogonal axes fold the tangents: UR5, HyQ), which also covers the
models the first does not (added masses, prescribed spins, pairs whose axes turn with their own coordinates).

The sweeps (2.39)-(2.46) run on dual numbers (:mod:`aggsym.core.dual`) seeded with unit tangents on q (directions
0..n-1) and qd (directions n..2n-1): every intermediate of the straight-line program of tau = u* gets its
derivatives beside it, so that ``dtau/dq`` and ``dtau/dqd`` reuse the kinematics and the wrenches of the sweeps
(the elastic force C (q - q0) of (2.27) and a joint damping D qd are differentiated the same way); ``dtau/dqdd`` is A(q).

Forward dynamics: q'' solves A(q) q'' + d(q, qd) = tau, so along any input x (q or qd) at fixed tau
``A dq''/dx + dtau_ID/dx (q, qd, q'') = 0``, i.e. ``dq''/dx = -A^-1 dtau_ID/dx`` evaluated at the forward
dynamics' own q'' (and dq''/dtau = A^-1).  A^-1 is applied column by column with the transvective factors,
``A^-1 v = T^T diag(1/(beta,beta)) T v`` (3.19)-(3.20), by their arguments or on the tree
(:func:`forward_dynamics_derivatives`): no dense inverse.

With a free-flyer root the directions along q are Pinocchio's tangent space (nv of them, not nq): the root moves
as ``q (+) d = (M exp(d))``, d = (dv, dw) in the body's axes, whose first-order change of the seven positions is
``dx = R dv`` and ``dquat = quat * (dw/2, 0)`` (quaternion product; ``d R = R hat(dw)``): those are the seeds.  A
ball pair moves as the free-flyer's rotation, ``quat (+) dw = quat exp(dw)`` (Pinocchio's spherical joint): its
four positions get the seeds ``quat * (dw/2, 0)`` along its three directions.
"""
from __future__ import annotations

import dataclasses

from ..core.columns import COLUMN_F, ColumnMap, Run
from ..core.dual import Dual, DualBackend, lift, tangent
from . import spatial_derivatives
from .bound import scratch_operations
from .passive import has_passive, left_forces
from .kinematics import TreeKinematics
from .sweeps import inverse_dynamics
from .transvective import articulated_factors, cauchy_solve, cauchy_solve_tree, forward_dynamics


def _dual_inverse_dynamics(bound, kin, qd, qdd, directions=None) -> tuple:
    """tau (duals) at (kin.q, qd, qdd) with tangents along q (0..n-1) and qd (n..2n-1), or only along the
    ``directions`` given."""
    n = kin.tree.nv
    dual = dataclasses.replace(bound, backend=DualBackend(bound.backend))
    q = tangent_seeds(kin)
    rates = [Dual(x, {n + i: 1}) for i, x in enumerate(qd)]
    if directions is not None:
        q = [lift(x.v, {k: t for k, t in x.d.items() if k in directions}) if isinstance(x, Dual) else x for x in q]
        rates = [lift(x.v, {k: t for k, t in x.d.items() if k in directions}) for x in rates]
    dkin = TreeKinematics(dual, q)
    tau = inverse_dynamics(dual, dkin, rates, qdd)
    return [a + b for a, b in zip(tau, left_forces(dual, q, rates))]


def tangent_seeds(kin) -> list:
    """q as duals with unit tangents along the velocity directions 0..nv-1 (a free-flyer's seven positions along
    its six directions, a ball's four along its three, see the module's text)."""
    q = list(kin.q)
    for k, (idx, coords) in enumerate(zip(kin.tree.positions, kin.tree.coords)):
        if not kin.free[k]:
            for p, i in zip(idx, coords):
                q[p] = Dual(kin.q[p], {i: 1})
            continue
        if len(idx) == 7:
            R = kin.functional[k].c
            for a in range(3):  # the origin: R dv
                q[idx[a]] = lift(kin.q[idx[a]], {coords[j]: R[a][j] for j in range(3)})
        quat, turns = idx[-4:], coords[-3:]  # the quaternion and the directions of the angular velocity
        x, y, z, w = (kin.q[p] for p in quat)
        half = (x / 2, y / 2, z / 2, w / 2)
        # quat * (e_j/2, 0) = (w e_j + v x e_j, -v_j) / 2 for v = (x, y, z)
        cross = ((0, half[2], -half[1]), (-half[2], 0, half[0]), (half[1], -half[0], 0))  # v x e_j / 2, by j
        for a in range(3):
            q[quat[a]] = lift(kin.q[quat[a]], {turns[j]: (half[3] if a == j else 0) + cross[j][a] for j in range(3)})
        q[quat[3]] = lift(kin.q[quat[3]], {turns[j]: -half[j] for j in range(3)})
    return q


def inverse_dynamics_derivatives(bound, kin, qd, qdd, by_direction=None, form=None) -> tuple:
    """(dtau/dq, dtau/dqd) as n x n rows (entry (i, j): d tau_i / d q_j).

    ``form``: ``"spatial"`` (the composites of :mod:`.spatial_derivatives`, with the passive forces' derivatives on
    dual numbers), ``"dual"`` (the whole sweep on dual numbers, below), or None: :func:`derivative_form` chooses.

    ``by_direction`` (the dual form; the default on a straight-line program, not on numbers): one dual sweep per
    direction, q_j then qd_j for each coordinate j.  The sweeps share the primal values (value numbering) and each
    direction's tangents are the nodes that one sweep of all directions makes, so the operations are the same; but the nodes
    are made, and the C is emitted, direction by direction, so that only one direction's tangents are live at a
    time instead of every tangent of the forward sweep waiting for the backward one (Talos: 3852 values kept
    across the slices of the C against 909; dtau 6 % and dqdd 5 % faster, 12 % and 10 % with slices of 80)."""
    n = kin.tree.nv
    if (form or derivative_form(bound, kin)) == "spatial":
        dq, dqd = spatial_derivatives.inverse_dynamics_derivatives(bound, kin, qd, qdd)
        if has_passive(bound.model):
            left = _dual_left_forces(bound, kin, qd)
            dq = [[a + tangent(t, j) for j, a in enumerate(row)] for row, t in zip(dq, left)]
            dqd = [[a + tangent(t, n + j) for j, a in enumerate(row)] for row, t in zip(dqd, left)]
        return dq, dqd
    if by_direction is None:
        by_direction = bound.backend.symbolic
    if not by_direction:
        tau = _dual_inverse_dynamics(bound, kin, qd, qdd)
        return ([[tangent(t, j) for j in range(n)] for t in tau],
                [[tangent(t, n + j) for j in range(n)] for t in tau])
    dq = [[0] * n for _ in range(n)]
    dqd = [[0] * n for _ in range(n)]
    for j in range(n):
        for d, rows in ((j, dq), (n + j, dqd)):
            for i, t in enumerate(_dual_inverse_dynamics(bound, kin, qd, qdd, (d,))):
                rows[i][j] = tangent(t, d)
    return dq, dqd


def _dual_left_forces(bound, kin, qd) -> list:
    """The passive forces C (q - q0) + D qd + ... (:func:`~.passive.left_forces`) as duals along q and qd."""
    n = kin.tree.nv
    dual = dataclasses.replace(bound, backend=DualBackend(bound.backend))
    return left_forces(dual, tangent_seeds(kin), [Dual(x, {n + i: 1}) for i, x in enumerate(qd)])


def cheaper_form(bound, kin, role, build) -> str:
    """The form (``"spatial"`` or ``"dual"``) a routine differentiates the inverse dynamics in: ``"dual"`` where
    :func:`~.spatial_derivatives.covers` does not hold; else on a straight-line program the one whose outputs
    (``build(bound, kin, qd, form)``'s matrices) reach fewer operations, both counted on scratch programs of the
    model (the dual one only up to the spatial count; the spatial one of equals); on numbers the spatial one (also
    the faster in Python).  Kept in ``kin.memo`` under ``role``."""
    key = f"{role} form"
    if key not in kin.memo:
        form = "spatial" if spatial_derivatives.covers(bound) else "dual"
        if form == "spatial" and bound.backend.symbolic:
            def rows(way):
                return lambda b, k, u: [[x for row in m for x in row] for m in build(b, k, u, way)]

            ours = scratch_operations(bound, kin, rows("spatial"))
            if scratch_operations(bound, kin, rows("dual"), ours) < ours:
                form = "dual"
        kin.memo[key] = form
    return kin.memo[key]


def derivative_form(bound, kin) -> str:
    """Which form :func:`inverse_dynamics_derivatives` takes (:func:`cheaper_form` of its own matrices)."""
    n = kin.tree.nv
    return cheaper_form(bound, kin, "inverse_dynamics_derivatives", lambda b, k, u, way: inverse_dynamics_derivatives(
        b, k, u, b.backend.program.vector("qdd", n), by_direction=False, form=way))


def forward_dynamics_derivatives(bound, kin, qd, tau, columns=None) -> tuple:
    """(dqdd/dq, dqdd/dqd) as n x n rows, at q'' = forward dynamics (tau already less the elastic force);
    ``columns``: a list, to which the 2n solves are appended as one body applied to columns (a
    :class:`~aggsym.core.columns.ColumnMap`) on a straight-line program.

    Each column of ``-dtau_ID/dx`` goes through A^-1 = T^T diag(1/(beta,beta)) T (3.19) in one of two ways:
    with the arguments <t,k> formed once (:func:`~.transvective.cauchy_solve`, (3.8)-(3.10): two sparse
    triangular sweeps per column, one multiply-add per transvection) or without them
    (:func:`~.transvective.cauchy_solve_tree`: 6-vectors summed on the tree, O(n) per column).  The 2n columns
    share the arguments, so the first is smaller on the suite's robots (UR5 2238 operations against 2794, Panda
    10330 against 12320, HyQ 3508 against 4276, Talos 49307 against 66495); on the straight-line program both
    are counted on scratch programs and the smaller is emitted, on floats the first is used."""
    solve = _with_arguments
    way = derivative_form(bound, kin)
    if bound.backend.symbolic:
        n = kin.tree.nv

        def form(solver):
            def build(b, k, u):  # (counted: one sweep of all directions makes the same operations, faster)
                return [[x for row in m for x in row]
                        for m in _forward_dynamics_derivatives(b, k, u, b.backend.program.vector("tau", n), solver,
                                                               by_direction=False, form=way)]
            return build

        with_arguments = scratch_operations(bound, kin, form(_with_arguments))
        if scratch_operations(bound, kin, form(_on_the_tree), with_arguments) < with_arguments:
            solve = _on_the_tree
    return _forward_dynamics_derivatives(bound, kin, qd, tau, solve, columns=columns, form=way)


def _with_arguments(kin, fac, columns):
    return [cauchy_solve(fac, c) for c in columns]


def _on_the_tree(kin, fac, columns):
    return [cauchy_solve_tree(kin, fac, c) for c in columns]


def _forward_dynamics_derivatives(bound, kin, qd, tau, solve, by_direction=None, columns=None, form=None) -> tuple:
    n = kin.tree.nv
    fac = articulated_factors(bound, kin, arguments=solve is _with_arguments)
    qdd = forward_dynamics(bound, kin, tau, qd, fac)
    dq, dqd = inverse_dynamics_derivatives(bound, kin, qd, qdd, by_direction, form)
    out, runs = [], []
    for k, rows in enumerate((dq, dqd)):
        values = [[-rows[i][j] for i in range(n)] for j in range(n)]
        cols = solve(kin, fac, values)
        out.append([[cols[j][i] for j in range(n)] for i in range(n)])
        runs.append(Run([[v] for v in values], [(k, 0, 1, n)]))
    if columns is not None and bound.backend.symbolic:
        f = bound.backend.program.vector(COLUMN_F, n)
        columns.append(ColumnMap([f], [solve(kin, fac, [f])[0]], runs))
    return tuple(out)


__all__ = ["cheaper_form", "derivative_form", "inverse_dynamics_derivatives", "forward_dynamics_derivatives"]
