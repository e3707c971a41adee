"""Independent references for the tests: a world-frame Newton-Euler written from scratch.

Nothing here uses aggsym's spatial algebra; it reads only the model's data (evaluated with NumPy) and walks
every pair as its elementary motions in the world frame: poses (R, p), angular velocity and acceleration,
origin velocity and acceleration, then Newton's and Euler's laws about each centre of mass, and the projection
of the wrench transmitted into each subtree on the world axis of each coordinate.  ``pair_wrenches`` gives those
transmitted wrenches themselves, re-expressed in each body's frame about its origin with plain rotation matrices.
"""
from __future__ import annotations

import numpy as np
import sympy as sp

AXIS = {1: np.array([1.0, 0, 0]), 2: np.array([0, 1.0, 0]), 3: np.array([0, 0, 1.0])}


def rot(axis: int, a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    if axis == 1:
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == 2:
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


class NumericModel:
    """The model's data as floats at given parameter values."""

    def __init__(self, model, p=None):
        self.model = model
        values = dict(zip(model.parameter_symbols, model.parameter_values if p is None else p))

        def f(x):
            return float(sp.N(sp.sympify(x).subs(values)))

        self.gravity = np.array([f(x) for x in model.gravity])
        self.bodies = []
        index = {b.name: k for k, b in enumerate(model.bodies)}
        i = 0
        for b in model.bodies:
            pair = b.pair
            entry = {
                "parent": index.get(b.parent, -1),
                "p": np.array([f(x) for x in pair.translation]),
                "R0": np.eye(3),
                "coords": [],
            }
            for axis, angle in pair.rotation:
                entry["R0"] = entry["R0"] @ rot(axis, f(angle))
            for c in pair.coordinates:
                entry["coords"].append((i, c.axis))
                i += 1
            if b.inertial is not None:
                entry["m"] = f(b.inertial.mass)
                entry["c"] = np.array([f(x) for x in b.inertial.com])
                entry["I"] = np.array([[f(x) for x in row] for row in b.inertial.inertia])
            self.bodies.append(entry)
        self.nq = i


def newton_euler(nm: NumericModel, q, qd, qdd, gravity=True):
    """tau = A q'' + b + g by world-frame Newton-Euler; also returns T and U."""
    out = newton_euler_full(nm, q, qd, qdd, gravity)
    return out["tau"], out["T"], out["U"]


def newton_euler_full(nm: NumericModel, q, qd, qdd, gravity=True):
    """World-frame Newton-Euler with everything it computes: a dict with ``tau``, ``T``, ``U``, the body poses
    ``R``, ``P`` (axes and origin of every body frame in the world frame), and ``force``, ``moment``: for every
    body k the wrench transmitted from its parent into the subtree rooted at k (the sum over the subtree of
    m (a_c - g) and of the moments of those forces and of the bodies' rates of angular momentum), world axes,
    moment about the world origin."""
    q, qd, qdd = (np.asarray(x, dtype=float) for x in (q, qd, qdd))
    g = nm.gravity if gravity else np.zeros(3)
    n = len(nm.bodies)
    R = [None] * n
    P = [None] * n
    W = [None] * n
    DW = [None] * n
    V = [None] * n
    A = [None] * n
    axes = {}  # coordinate -> (kind, world axis, world point, body)
    for k, b in enumerate(nm.bodies):
        if b["parent"] < 0:
            Rk, pk, w, dw, v, a = np.eye(3), np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
        else:
            j = b["parent"]
            Rk, pk, w, dw, v, a = R[j], P[j], W[j], DW[j], V[j], A[j]
        # constructive translation then rotation
        d = Rk @ b["p"]
        pk = pk + d
        v = v + np.cross(w, d)
        a = a + np.cross(dw, d) + np.cross(w, np.cross(w, d))
        Rk = Rk @ b["R0"]
        # functional translations o1..o3 (all in the constructive frame), then rotations theta4..theta6
        for i, axis in b["coords"]:
            if axis < 3:
                u = Rk @ AXIS[axis + 1]
                axes[i] = ("t", u, None, k)
                d = u * q[i]
                pk = pk + d
                v = v + np.cross(w, d) + u * qd[i]
                a = a + np.cross(dw, d) + np.cross(w, np.cross(w, d)) + 2 * np.cross(w, u * qd[i]) + u * qdd[i]
        for i, axis in b["coords"]:
            if axis >= 3:
                u = Rk @ AXIS[axis - 2]
                axes[i] = ("r", u, pk.copy(), k)
                dw = dw + u * qdd[i] + np.cross(w, u * qd[i])
                w = w + u * qd[i]
                Rk = Rk @ rot(axis - 2, q[i])
        R[k], P[k], W[k], DW[k], V[k], A[k] = Rk, pk, w, dw, v, a
    # body wrenches about the world origin
    force = [np.zeros(3) for _ in range(n)]
    moment = [np.zeros(3) for _ in range(n)]
    T = U = 0.0
    moves = []  # a body welded to the world has a constant potential, left out of U (as Pinocchio does)
    for b in nm.bodies:
        moves.append(bool(b["coords"]) or (b["parent"] >= 0 and moves[b["parent"]]))
    for k, b in enumerate(nm.bodies):
        if "m" not in b:
            continue
        rc = R[k] @ b["c"]
        c = P[k] + rc
        vc = V[k] + np.cross(W[k], rc)
        ac = A[k] + np.cross(DW[k], rc) + np.cross(W[k], np.cross(W[k], rc))
        Iw = R[k] @ b["I"] @ R[k].T
        f = b["m"] * (ac - g)
        nc = Iw @ DW[k] + np.cross(W[k], Iw @ W[k])
        force[k] = f
        moment[k] = nc + np.cross(c, f)
        T += 0.5 * b["m"] * vc @ vc + 0.5 * W[k] @ Iw @ W[k]
        U += -b["m"] * g @ c if moves[k] else 0.0
    for k in range(n - 1, -1, -1):
        j = nm.bodies[k]["parent"]
        if j >= 0:
            force[j] = force[j] + force[k]
            moment[j] = moment[j] + moment[k]
    tau = np.zeros(nm.nq)
    for i, (kind, u, point, k) in axes.items():
        if kind == "t":
            tau[i] = u @ force[k]
        else:
            tau[i] = u @ (moment[k] - np.cross(point, force[k]))
    return {"tau": tau, "T": T, "U": U, "R": R, "P": P, "force": force, "moment": moment}


def pair_wrenches(nm: NumericModel, q, qd, qdd, gravity=True):
    """For every body, the wrench transmitted from its parent into its subtree, as (f, mu) in the body's own
    axes with the moment about the body origin: an N x 6 array (rows of massless or coordinate-free pairs
    included)."""
    out = newton_euler_full(nm, q, qd, qdd, gravity)
    rows = []
    for R, P, f, m in zip(out["R"], out["P"], out["force"], out["moment"]):
        rows.append(np.concatenate([R.T @ f, R.T @ (m - np.cross(P, f))]))
    return np.array(rows)


def mass_matrix(nm: NumericModel, q):
    n = nm.nq
    z = np.zeros(n)
    return np.column_stack([newton_euler(nm, q, z, np.eye(n)[j], gravity=False)[0] for j in range(n)])
