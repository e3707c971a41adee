"""Independent references for the tests: a world-frame Newton-Euler written from scratch.

Nothing here uses aggsym's spatial algebra; it reads only the model's data (evaluated with NumPy) and walks
every pair as its elementary motions in the world frame: poses (R, p), angular velocity and acceleration,
origin velocity and acceleration, then Newton's and Euler's laws about each centre of mass, and the projection
of the wrench transmitted into each subtree on the world axis of each coordinate.  ``pair_wrenches`` gives those
transmitted wrenches themselves, re-expressed in each body's frame about its origin with plain rotation matrices.

The body features of chapter 2 are written the classical way, also in the world frame: a rotor with a prescribed
spin is a body whose pair rotation, rate and acceleration are known functions of t (evaluated by SymPy, not by
aggsym); added masses Lambda (about the body origin O, body axes) are Kirchhoff's fluid impulse
(P, K_O) = X Lambda X^T (v_O, w) with X = diag(R, R), whose reaction on the body is (-dP/dt, -(dK_O/dt + v_O x P))
(Lamb, Hydrodynamics, ch. VI); an elastic pair adds C (q - q0) to tau and 1/2 (q - q0)^T C (q - q0) to U.
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


TIME = sp.Symbol("t", real=True)


class NumericModel:
    """The model's data as floats at given parameter values (and at time t for prescribed motions)."""

    def __init__(self, model, p=None, t=0.0):
        self.model = model
        values = dict(zip(model.parameter_symbols, model.parameter_values if p is None else p))

        def f(x):
            return float(sp.N(sp.sympify(x).subs(values)))

        def f_t(x, k):
            return float(sp.N(sp.diff(sp.sympify(x), TIME, k).subs(values).subs(TIME, t)))

        self.gravity = np.array([f(x) for x in model.gravity])
        self.bodies = []
        stiffness = []
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
            first = i
            for c in pair.coordinates:
                entry["coords"].append((i, c.axis))
                i += 1
            entry["spin"] = [({"theta4": 3, "theta5": 4, "theta6": 5}[code], f_t(e, 0), f_t(e, 1), f_t(e, 2))
                             for code, e in pair.prescribed]
            if pair.stiffness is not None:
                rest = np.array([f(x) for x in pair.rest]) if pair.rest is not None else np.zeros(i - first)
                stiffness.append((list(range(first, i)), np.array([[f(x) for x in r] for r in pair.stiffness]), rest))
            if b.inertial is not None:
                entry["m"] = f(b.inertial.mass)
                entry["c"] = np.array([f(x) for x in b.inertial.com])
                entry["I"] = np.array([[f(x) for x in row] for row in b.inertial.inertia])
            if b.added_mass is not None:
                entry["Lambda"] = np.array([[f(x) for x in row] for row in b.added_mass])
            self.bodies.append(entry)
        self.nq = i
        self.C = np.zeros((i, i))  # Hooke stiffness (2.27) and rest position
        self.q0 = np.zeros(i)
        for idx, K, rest in stiffness:
            self.C[np.ix_(idx, idx)] = K
            self.q0[idx] = rest


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
        for axis, angle, rate, accel in b["spin"]:  # a prescribed rotation: known angle, rate, acceleration
            u = Rk @ AXIS[axis - 2]
            dw = dw + u * accel + np.cross(w, u * rate)
            w = w + u * rate
            Rk = Rk @ rot(axis - 2, angle)
        R[k], P[k], W[k], DW[k], V[k], A[k] = Rk, pk, w, dw, v, a
    # body wrenches about the world origin
    force = [np.zeros(3) for _ in range(n)]
    moment = [np.zeros(3) for _ in range(n)]
    T = U = 0.0
    moves = []  # a body welded to the world has a constant potential, left out of U (as Pinocchio does)
    for b in nm.bodies:
        moves.append(bool(b["coords"]) or (b["parent"] >= 0 and moves[b["parent"]]))
    for k, b in enumerate(nm.bodies):
        if "Lambda" in b:  # Kirchhoff: the fluid's impulse about the moving origin, and its rate of change
            X = np.kron(np.eye(2), R[k])
            Lw = X @ b["Lambda"] @ X.T
            Om = np.kron(np.eye(2), hat(W[k]))
            Vw = np.concatenate([V[k], W[k]])
            imp = Lw @ Vw
            dimp = (Om @ Lw - Lw @ Om) @ Vw + Lw @ np.concatenate([A[k], DW[k]])
            force[k] = force[k] + dimp[:3]
            moment[k] = moment[k] + dimp[3:] + np.cross(V[k], imp[:3]) + np.cross(P[k], dimp[:3])
            T += 0.5 * Vw @ imp
        if "m" not in b:
            continue
        rc = R[k] @ b["c"]
        c = P[k] + rc
        vc = V[k] + np.cross(W[k], rc)
        ac = A[k] + np.cross(DW[k], rc) + np.cross(W[k], np.cross(W[k], rc))
        Iw = R[k] @ b["I"] @ R[k].T
        f = b["m"] * (ac - g)
        nc = Iw @ DW[k] + np.cross(W[k], Iw @ W[k])
        force[k] = force[k] + f
        moment[k] = moment[k] + nc + np.cross(c, f)
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
    spring = nm.C @ (q - nm.q0)  # the elastic pairs: the actuators also hold the springs
    tau = tau + spring
    U += 0.5 * (q - nm.q0) @ spring
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


def hat(x):
    return np.array([[0, -x[2], x[1]], [x[2], 0, -x[0]], [-x[1], x[0], 0]])


def mass_matrix(nm: NumericModel, q):
    """A(q) column by column: tau(q, 0, e_j) - tau(q, 0, 0) (prescribed spins and springs cancel)."""
    n = nm.nq
    z = np.zeros(n)
    rest = newton_euler(nm, q, z, z, gravity=False)[0]
    return np.column_stack([newton_euler(nm, q, z, np.eye(n)[j], gravity=False)[0] - rest for j in range(n)])
