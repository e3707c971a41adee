"""Internal body frames chosen for the recursion (modified-DH-like re-framing) and the inertia grouped along the
joint axes: the same dynamics A(q), b(q,q'), g(q) at fewer operations.

The book's recursions (2.30)-(2.46), (3.7)-(3.20) hold in any body frames: a pair is any constant motion
followed by the functional one (1.24)-(1.27).  A URDF fixes a frame per link (the joint's ``<origin>``), whose
constant rotation to the next joint is in general a full 3x3 (or, as in xarm7, a rotation about x by an angle a
few micro-radians off pi/2) and whose translation has up to three components.  :func:`reframe` returns an
*internal* model of the same tree and the same coordinates (same order, same q, same sense), whose body frames are
chosen as follows (x_B = R_k x' + o_k in the original body frame B of body k):

* the joint axis is e3 and the origin is on the axis, at the foot of the common normal with the parent's axis
  (the incoming normal); the x axis lies along the common normal to the axis of the body's main child (the child
  with the largest subtree): the pair's constant motion is then ``T((a, 0, d)) C(c1(alpha))`` (the parameters
  of the modified Denavit-Hartenberg convention, with the distance d taken on the parent's axis), and the turn of
  the child's x axis about its own axis is an ``offset`` added to the coordinate (q + theta0, a revolute joint
  only: the functional rotation is c3(q + theta0), one addition; a pair's own offset, an MJCF joint's -ref, is
  added to it, and a prismatic pair keeps its own);
* other children (branches), children of a floating root and bodies after a prismatic joint (whose x axis is
  fixed by its parent, no offset) get ``T((a cos g, a sin g, d)) C(c3(g) c1(alpha))``;
* the root keeps its frame; a leaf's x axis points to its centre of mass.

The Mises matrices (2.3) are re-expressed in the internal frames (constants: no run-time cost for numeric
inertias; expressions in p otherwise), then grouped: for a revolute joint about e3 through the origin, the part
``(m, (0, 0, h3), diag(theta_yy, theta_yy, 0))`` of the body's Mises matrix is a mass distribution on the axis
that the joint's rotation does not move (its columns along f6 vanish and it is invariant under c3), so it has the
same kinetic and potential energy carried by the parent: it is moved to the parent by the pair's constant motion
(2.7) (the grouping of the base inertial parameters; a prismatic joint likewise hands its parent the whole
rotational part (0, 0, theta_O)).  The body keeps m = 0, h3 = 0, theta_yy = 0.  This changes the bodies'
individual wrenches (the joint reactions), not A, b, g, the energies or anything computed from them.

So the internal model is used only for the routines whose outputs depend on the coordinates alone
(``Routine.frame_free`` in :mod:`aggsym.contract`: inertia, bias, gravity, inverse and forward dynamics, A^-1,
the energies, the derivatives of the dynamics); routines whose outputs are in body or link frames (joint wrenches,
frames and Jacobians, the regressor, momentum, centre of mass) run on the model as read.

Exactness: the tolerances here only choose (which axes count as parallel, which origin a frame takes); every
constant motion and Mises matrix is then computed from the frames chosen.  The only values replaced are those
within :data:`ROUND_OFF` (relative) of 0, +-1 or a multiple of pi/2, the round-off of this computation; the file's
own angles are not snapped here (xarm7's 1.5708 stays what it is).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import sympy as sp

from .inertials import mises_in_frame, moved_mises
from ..tree import Tree
from ..types import Inertial, Model, code_index

ROUND_OFF = 1e-14  # a value computed here within this (relative to its scale) of 0, of +-1 or of a multiple of pi/2
# is the round-off of this computation (a few dozen units in the last place of double precision) and is taken
# exactly; so is an entry of a body's grouped Mises matrix below this times its largest entry (the exact
# arithmetic of SymPy gave 0 there, where products of lengths and masses cancel).  Nothing larger is ever rounded:
# the internal model is the model as read, to round-off.
PARALLEL = 0.1  # two axes whose angle has a sine below this are taken as parallel when the frames are chosen: the
# common normal of nearly parallel axes lies far off (at about the distance / sin), where its foot, exact in
# exact arithmetic, would carry lengths that cancel in the recursion and cost (1/sin)^2 of the digits.  A choice
# only: the constant motions are computed from the frames chosen, whatever they are.
MAX_CANDIDATES = 8  # origins tried per body by _origins (the first ones): parallel axes pass every candidate of the
# parent on as a projection, so without a bound a chain of n parallel axes had n candidates per body and the choice
# took O(n^3) (a 200-link planar chain: 16 s); the arms of the benchmark have at most 4

__all__ = ["reframe", "eligible", "internal_frames"]


def eligible(model: Model) -> bool:
    """Whether :func:`reframe` applies: a URDF model (its pairs hold one coordinate each below the root), numeric
    constant configurations, no constraints, support, couplings, prescribed motions, added masses or ball pairs, no
    gravity compensation (its weights are per body, and grouping moves mass between bodies) and no spatial tendons
    (their sites are points in the bodies' frames) and no fluid model (its boxes are the bodies' own)."""
    if not model.link_table.from_file or model.constraints or model.support or model.couplings or model.gravcomp \
            or model.spatial_tendons or model.has_fluid:
        return False
    for k, b in enumerate(model.bodies):
        if b.pair.prescribed or b.added_mass is not None or b.pair.ball:
            return False
        if k and len(b.pair.coordinates) != 1:
            return False
        if any(getattr(x, "free_symbols", None) for x in b.pair.translation):
            return False
        if any(getattr(a, "free_symbols", None) for _, a in b.pair.rotation):
            return False
    return True


def _exact_angle(x: float) -> sp.Expr:
    k = round(x / (math.pi / 2))
    if abs(x - k * math.pi / 2) < ROUND_OFF * max(1, abs(k)):
        return sp.Integer(k) * sp.pi / 2 if k else sp.Integer(0)
    return sp.Float(x)


def _length(x: float, scale: float) -> sp.Expr:
    """A length computed here from lengths of size ``scale`` (relative: a millimetre robot keeps its digits)."""
    return sp.Integer(0) if x == 0 or abs(x) < ROUND_OFF * scale else sp.Float(x)


def _unit(x: float) -> sp.Expr:
    for target in (0, 1, -1):
        if abs(x - target) < ROUND_OFF:
            return sp.Integer(target)
    return sp.Float(x)


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _perp(z):
    """A unit vector orthogonal to the unit z (deterministic)."""
    e = np.eye(3)[int(np.argmin(np.abs(z)))]
    x = e - np.dot(e, z) * z
    return x / np.linalg.norm(x)


def _foot(o, z, t, u):
    """The feet of the common normal of the lines (o, z) and (t, u) (unit directions), and its direction n (unit,
    from the first line to the second; None for coincident lines).  Parallel lines: the foot on the first line is
    o itself."""
    w = np.cross(z, u)
    sw = np.linalg.norm(w)
    if sw > PARALLEL:
        # o + s z and t + r u closest: (o + s z - t - r u) . z = 0, . u = 0
        d = t - o
        zu = np.dot(z, u)
        den = 1 - zu * zu
        s = (np.dot(d, z) - zu * np.dot(d, u)) / den
        r = (zu * np.dot(d, z) - np.dot(d, u)) / den
        P, Q = o + s * z, t + r * u
        n = Q - P
        dist = np.linalg.norm(n)
        n = n / dist if dist > 1e-9 * np.linalg.norm(d) else w / sw
        return P, Q, n
    r = np.dot(o - t, u)
    Q = t + r * u
    n = Q - o
    dist = np.linalg.norm(n)
    return o, Q, (n / dist if dist > 1e-9 * np.linalg.norm(t - o) else None)


def _line(k, c0, t0, axis):
    """Body k's joint axis as a line (point, unit direction) in its parent's original frame."""
    return t0[k], c0[k][:, axis[k]]


def _axes(model, tree, t0, c0, axis, revolute, main, normals) -> list:
    """The internal axes of every body, columns in its original frame: z on the joint axis, x along the common
    normal to the main child's axis (revolute), the incoming normal (prismatic: it takes no offset), towards the
    centre of mass (a leaf), or the URDF frame's next axis (``normals`` false); the root keeps its axes."""
    N = len(tree)
    R = [np.eye(3) for _ in range(N)]
    for k in range(1, N):
        p = tree.parent[k]
        if axis[k] is None:
            continue
        z = np.eye(3)[axis[k]]
        x = None
        if not normals:
            x = np.eye(3)[(axis[k] + 1) % 3]
        elif not revolute[k] and p >= 0:  # no offset: x follows the parent's normal (or x)
            n = None
            if axis[p] is not None:
                n = _foot(np.zeros(3), R[p][:, 2], *_line(k, c0, t0, axis))[2]
            x = c0[k].T @ (n if n is not None else R[p][:, 0])
        elif main[k] is not None and axis[main[k]] is not None:
            x = _foot(np.zeros(3), z, *_line(main[k], c0, t0, axis))[2]
        elif main[k] is None:  # a leaf: x towards the centre of mass
            inertial = model.bodies[k].inertial
            if inertial is not None:
                h = inertial.mises()[1]
                if not any(getattr(v, "free_symbols", None) for v in h):
                    x = np.array([float(v) for v in h])
                    x = x / np.linalg.norm(x) if np.any(x) else None  # (a direction, whatever the robot's size)
        if x is not None:
            x = x - np.dot(x, z) * z
        x = x / np.linalg.norm(x) if x is not None and np.linalg.norm(x) > 1e-9 else _perp(z)
        R[k] = np.column_stack([x, np.cross(z, x), z])
    return R


def _nonzeros(v, scale) -> int:
    return sum(1 for x in v if x != 0 and abs(x) >= ROUND_OFF * scale)


def _origins(tree, t0, c0, axis, main, R, fewest=True) -> list:
    """Every body's internal origin on its joint axis (original frame): among the URDF origin, the feet of the
    common normals with the parent's and with the main child's axes (and, for parallel axes, the projections of
    the parent's choices), the choice with the fewest non-zero components of the pairs' translations in the internal
    frames (a pair whose parent is welded to the world is free: everything it moves is constant), by a
    bottom-up dynamic programme over the tree.  Not ``fewest``: each at the foot of the normal with the parent's
    axis (the projection of the parent's origin for parallel axes and below the root)."""
    N = len(tree)
    moving = tree.moving
    cand = [[np.zeros(3)] for _ in range(N)]
    for k in range(1, N):
        if axis[k] is None:
            continue
        e = np.eye(3)[axis[k]]
        p = tree.parent[k]
        t, u = _line(k, c0, t0, axis)
        points = []
        if axis[p] is not None:
            P, Q, n = _foot(np.zeros(3), R[p][:, 2], t, u)
            points += [Q] if np.linalg.norm(np.cross(R[p][:, 2], u)) > PARALLEL else \
                [t + np.dot(op - t, u) * u for op in cand[p]]
        else:
            points += [t + np.dot(op - t, u) * u for op in cand[p]]
        c = main[k]
        if c is not None and axis[c] is not None:
            P, _, _ = _foot(np.zeros(3), e, *_line(c, c0, t0, axis))
            cand[k].append(e * P[axis[k]])
        for Q in points:
            cand[k].append(e * np.dot(c0[k].T @ (Q - t), e))
        unique = []
        for x in cand[k]:
            if all(np.linalg.norm(x - y) > 1e-12 * (np.linalg.norm(x) + np.linalg.norm(y)) for y in unique):
                unique.append(x)
                if len(unique) == MAX_CANDIDATES:
                    break
        cand[k] = unique

    def cost(k, op, ok):
        p = tree.parent[k]
        if not moving[p]:
            return 0
        tr = R[p].T @ (c0[k] @ ok + t0[k] - op)
        return _nonzeros(tr, np.linalg.norm(t0[k]) + np.linalg.norm(ok) + np.linalg.norm(op))

    if not fewest:
        o = [np.zeros(3) for _ in range(N)]
        for k in range(1, N):
            if axis[k] is None:
                continue
            p = tree.parent[k]
            t, u = _line(k, c0, t0, axis)
            Q = _foot(o[p], R[p][:, 2], t, u)[1] if axis[p] is not None else t + np.dot(o[p] - t, u) * u
            e = np.eye(3)[axis[k]]
            o[k] = e * np.dot(c0[k].T @ (Q - t), e)
        return o
    best = [[0] * len(cand[k]) for k in range(N)]
    for k in range(N - 1, -1, -1):
        for i, ok in enumerate(cand[k]):
            best[k][i] = sum(min(cost(c, ok, oc) + best[c][j] for j, oc in enumerate(cand[c]))
                             for c in tree.children[k])
    choice = [0] * N
    for k in range(1, N):
        p = tree.parent[k]
        op = cand[p][choice[p]]
        scores = [cost(k, op, ok) + best[k][j] for j, ok in enumerate(cand[k])]
        choice[k] = int(np.argmin(scores))
    return [cand[k][choice[k]] for k in range(N)]


def _own_offset(pair) -> sp.Expr:
    """The constant a pair of the model as read adds to its one coordinate (:attr:`~.types.Pair.offset`), 0 if none."""
    return pair.offset[0] if pair.offset else sp.Integer(0)


def _float3(m) -> np.ndarray:
    return np.array([[float(m[i, j]) for j in range(3)] for i in range(3)])


def reframe(model: Model, normals: bool = True, fewest: bool = True) -> Model:
    """The internal model of :mod:`this module <aggsym.model.transforms.reframe>`: same tree, same coordinates, internal body
    frames, grouped Mises matrices.  ``normals``: each body's x axis along the common normal to its main child's
    axis (else the next axis of the URDF's frame after the joint axis); ``fewest``: the origins by
    :func:`_origins` (else each at the foot of the common normal with its parent's axis).  A model that is not :func:`eligible` is
    returned as it is."""
    return _reframed(model, normals, fewest)[0]


def internal_frames(model: Model, normals: bool = True, fewest: bool = True) -> tuple:
    """(:func:`reframe` ``(model, normals, fewest)``, where it puts each body's internal frame): per body (R, o),
    floats, x_B = R x' + o in the body frame B of the model as read (the frames the internal model's kinematics
    places, so that a test can set them against the poses of the model as read); (model, None) for a model that is
    not :func:`eligible`."""
    internal, axes, places = _reframed(model, normals, fewest)
    if axes is None:
        return model, None
    return internal, tuple((tuple(tuple(float(a[i, j]) for j in range(3)) for i in range(3)),
                            tuple(float(x) for x in o)) for a, o in zip(axes, places))


def _reframed(model: Model, normals: bool, fewest: bool) -> tuple:
    """(the internal model, its frames' axes, their origins) of :func:`reframe`; (model, None, None) when the model
    is not :func:`eligible`."""
    if not eligible(model):
        return model, None, None
    tree = Tree.of(model)
    N = len(tree)
    bodies = model.bodies
    t0 = [np.array([float(x) for x in b.pair.translation]) for b in bodies]
    c0 = [_float3(b.pair.constructive_rotation()) for b in bodies]
    axis = [None] * N  # index of the joint axis in the original body frame
    revolute = [False] * N
    for k in range(1, N):
        i = code_index(bodies[k].pair.codes[0])
        axis[k], revolute[k] = i % 3, i >= 3
    size = [1] * N
    for k in range(N - 1, 0, -1):
        if tree.parent[k] >= 0:
            size[tree.parent[k]] += size[k]
    main = [max(tree.children[k], key=lambda c: (size[c], -c)) if tree.children[k] else None for k in range(N)]
    R = _axes(model, tree, t0, c0, axis, revolute, main, normals)
    o = _origins(tree, t0, c0, axis, main, R, fewest)
    pairs = [b.pair for b in bodies]
    motions = [None] * N  # the new constant motion (C, p) of each pair, floats
    for k in range(1, N):
        p = tree.parent[k]
        if p < 0:
            continue
        C, tr, gamma_x, alpha_x, theta0 = _constant_motion(R[p], c0[k], R[k], t0[k], o[k], o[p])
        offset = _exact_angle(theta0)
        if revolute[k] and offset != 0 and not isinstance(offset, sp.Float):  # a right angle: turn the frame
            quarter = -round(theta0 / (math.pi / 2)) % 4
            R[k] = R[k] @ _quarter(quarter)
            C, tr, gamma_x, alpha_x, theta0 = _constant_motion(R[p], c0[k], R[k], t0[k], o[k], o[p])
            offset = _exact_angle(theta0)
        scale = float(np.linalg.norm(t0[k])) + float(np.linalg.norm(o[k])) + float(np.linalg.norm(o[p]))
        translation = tuple(_length(float(x), scale) for x in tr)
        turn = 0 if revolute[k] else offset  # a prismatic pair has no angle to take the turn: it stays constant
        rotation = tuple((a, v) for a, v in ((3, gamma_x), (1, alpha_x), (3, turn)) if v != 0)
        # the pair's own offset (MJCF: -qpos0, a hinge's or a slide's ref) is carried as it is: the pair turns about
        # (slides along) the same line by q + offset, and the internal frames, fixed on that line, commute with it
        offset = (offset if revolute[k] else 0) + _own_offset(pairs[k])
        code = "theta6" if revolute[k] else "o3"
        coords = tuple(dataclasses.replace(c, code=code) for c in pairs[k].coordinates)
        pairs[k] = dataclasses.replace(pairs[k], translation=translation, rotation=rotation, coordinates=coords,
                                       offset=(offset,) if offset != 0 else ())
        Cx = pairs[k].constructive_rotation()
        motions[k] = (Cx, sp.Matrix(translation))
    axes = [sp.Matrix(3, 3, lambda i, j: _unit(float(R[k][i, j]))) for k in range(N)]
    places = [sp.Matrix([_length(float(x), float(np.linalg.norm(o[k]))) for x in o[k]]) for k in range(N)]
    forms = [None if b.inertial is None else b.inertial.mises() for b in bodies]
    grouped = _grouped_numbers if all(f is None or _numeric(f) for f in forms) else _grouped_symbols
    mises = grouped(tree, forms, axes, places, motions, revolute)
    new = []
    for k, b in enumerate(bodies):
        inertial = None
        if mises[k] is not None:
            m, h, th = mises[k]
            zero = (sp.Integer(0),) * 3
            inertial = Inertial(m, zero, (zero,) * 3, origin=(m, h, th))
        new.append(dataclasses.replace(b, pair=pairs[k], inertial=inertial, link_rotation=None))
    internal = dataclasses.replace(model, bodies=tuple(new), frames=(), meta={**model.meta, "reframed": True})
    return internal, axes, places


def _numeric(form) -> bool:
    """Whether a Mises matrix (m, h, theta) holds numbers only (no parameter of p)."""
    m, h, th = form
    return all(getattr(x, "is_Number", False) for x in (m, *h, *(x for row in th for x in row)))


def _group_part(m, h, th, revolute):
    """The part of a body's Mises matrix (internal frame) moved to its parent, and the part it keeps: for a
    revolute joint about e3, (m, (0, 0, h3), diag(yy, yy, 0)) goes and (0, (h1, h2, 0), theta - diag(yy, yy, 0))
    stays; for a prismatic one the rotational part theta goes and (m, h, 0) stays (see the module's text)."""
    if revolute:
        yy = th[1][1]
        zero = 0 * yy
        part = (m, (zero, zero, h[2]), ((yy, zero, zero), (zero, yy, zero), (zero, zero, zero)))
        kept = (0 * m, (h[0], h[1], zero),
                tuple(tuple(th[i][j] - (yy if i == j and i < 2 else zero) for j in range(3)) for i in range(3)))
        return part, kept
    zero = 0 * m
    zeros = ((zero,) * 3,) * 3
    return (zero, (zero,) * 3, th), (m, h, zeros)


def _grouped(tree, forms, motions, revolute, in_frame, moved, kept_form, finish) -> list:
    """The bodies' Mises matrices in their internal frames, grouped along the joint axes: ``in_frame(k, form)``
    re-expresses body k's (m, h, theta) in its internal frame, then from the buds to the root each body hands its
    parent the part of :func:`_group_part`, moved by ``moved(part, motion)`` (2.7), and keeps ``kept_form(kept)``;
    each result goes out as ``finish(m, h, theta)`` (None for a body without inertia).  The arithmetic is the
    callables' (SymPy or NumPy)."""
    mises = [None if f is None else in_frame(k, f) for k, f in enumerate(forms)]
    moving = tree.moving
    for k in range(len(tree) - 1, 0, -1):
        p = tree.parent[k]
        if p < 0 or mises[k] is None or motions[k] is None or not moving[p]:
            continue  # (a body welded to the world takes nothing: its energy is left out of U)
        m, h, th = mises[k]
        part, kept = _group_part(m, tuple(h), th.tolist(), revolute[k])
        mises[k] = kept_form(kept)
        here = moved(part, motions[k])
        mises[p] = here if mises[p] is None else tuple(a + b for a, b in zip(mises[p], here))
    return [None if f is None else finish(*f) for f in mises]


def _grouped_symbols(tree, forms, axes, places, motions, revolute) -> list:
    """:func:`_grouped` with SymPy (inertias that hold parameters of p; axes, places: x = R x' + o in the original
    body frame); entries expanded."""
    def in_frame(k, f):
        return mises_in_frame(f[0], sp.Matrix(f[1]), sp.Matrix(f[2]), axes[k], places[k])

    def moved(part, motion):
        return moved_mises(part[0], sp.Matrix(part[1]), sp.Matrix(part[2]), *motion)

    def kept_form(kept):
        return kept[0], sp.Matrix(kept[1]), sp.Matrix(kept[2])

    def finish(m, h, th):
        return (sp.expand(m), tuple(sp.expand(x) for x in h),
                tuple(tuple(sp.expand(th[i, j]) for j in range(3)) for i in range(3)))
    return _grouped(tree, forms, motions, revolute, in_frame, moved, kept_form, finish)


def _grouped_numbers(tree, forms, axes, places, motions, revolute) -> list:
    """:func:`_grouped` in double precision, for numeric inertias (the common case: SymPy's matrices cost most of
    the choice of frames): :func:`mises_in_frame` and :func:`moved_mises` on NumPy arrays; entries back as SymPy
    numbers, exact where integers (0, the right angles' 1), and 0 below :data:`ROUND_OFF` of the body's largest."""
    def f3(v):
        return np.array([float(x) for x in v])

    def f33(M):
        return np.array([[float(x) for x in row] for row in (M.tolist() if hasattr(M, "tolist") else M)])

    def in_frame(k, f):
        return mises_in_frame(float(f[0]), f3(f[1]), f33(f[2]), f33(axes[k]), f3(places[k]))

    def moved(part, motion):
        return moved_mises(part[0], np.array(part[1]), np.array(part[2]), f33(motion[0]), f3(motion[1]))

    def kept_form(kept):
        return kept[0], np.array(kept[1]), np.array(kept[2])

    def finish(m, h, th):
        th = (th + th.T) / 2  # symmetric exactly: the two round-offs of one product of inertia are one number
        tiny = ROUND_OFF * max(abs(float(x)) for x in (m, *h, *th.flat))

        def number(x):
            x = float(x)
            if abs(x) <= tiny:
                return sp.Integer(0)
            return sp.Integer(int(x)) if x.is_integer() else sp.Float(x)
        return (number(m), tuple(number(x) for x in h),
                tuple(tuple(number(th[i][j]) for j in range(3)) for i in range(3)))
    return _grouped(tree, forms, motions, revolute, in_frame, moved, kept_form, finish)


def _quarter(k: int) -> np.ndarray:
    """c3(k pi/2), exactly."""
    c, s = ((1, 0), (0, 1), (-1, 0), (0, -1))[k % 4]
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=float)


def _constant_motion(Rp, c0, Rk, t0, ok, op):
    """The pair's constant motion between internal frames, C = Rp^T c0 Rk and its translation, with C written as
    c3(gamma) c1(alpha) c3(theta0): (C, translation, gamma, alpha (exact where right angles), theta0)."""
    C = Rp.T @ c0 @ Rk
    tr = Rp.T @ (c0 @ ok + t0 - op)
    u = C[:, 2]
    alpha = math.atan2(math.hypot(u[0], u[1]), u[2])
    gamma = 0.0 if math.hypot(u[0], u[1]) < ROUND_OFF else math.atan2(u[0], -u[1])
    if abs(abs(gamma) - math.pi) < ROUND_OFF:
        gamma, alpha = 0.0, -alpha
    if abs(gamma) < ROUND_OFF:
        gamma = 0.0
    gamma_x, alpha_x = _exact_angle(gamma), _exact_angle(alpha)
    rest = _rx(-float(alpha_x)) @ _rz(-float(gamma_x)) @ C
    return C, tr, gamma_x, alpha_x, math.atan2(rest[1, 0], rest[0, 0])
