"""Physical checks shared by the readers: masses, inertia tensors, the shape of the tree.

Inertia where the dynamics sees it (2.3), (2.30): a body enters A(q) = S A S^T only through the kinetic
energy 1/2 V^T Theta V of the quasi-velocities V its pairs let it have (1.28), (1.34).  :func:`motion_space`
finds the span W of those velocities over all configurations, pair by pair from the root, and
:func:`kinetic_energy_problem` says whether Theta is positive semi-definite on W.  A body welded to the world has
W = {0} and is never judged; a body that can move freely has W = R^6, where the test is that of the inertia
tensor itself.
"""
from __future__ import annotations

import functools

import math

import numpy as np

from ...suggest import did_you_mean

TOL = 1e-9
PHYSICAL_TOL = 1e-6  # relative to the largest principal moment: how far a body's inertia may be from physical


def mass_problem(mass: float) -> str | None:
    if not np.isfinite(mass):
        return f"mass {mass!r} is not finite"
    if mass <= 0:
        return f"mass must be positive, got {mass:g} (omit mass and inertia for a massless frame)"
    return None


def inertia_problem(inertia, triangle: bool = True, tol: float = TOL) -> str | None:
    """Why a 3x3 inertia tensor about the centre of mass is not physical, or None.

    It must be symmetric, positive semi-definite, and (unless ``triangle`` is False) its principal moments
    must satisfy the triangle inequality (each at most the sum of the other two).  ``tol`` is relative to the
    largest entry (at least 1).  (Cached on the numbers: models repeat their links.)
    """
    return _inertia_problem(tuple(float(x) for row in inertia for x in row), triangle, tol)


@functools.lru_cache(maxsize=4096)
def _inertia_problem(entries: tuple, triangle: bool, tol: float) -> str | None:
    J = np.array(entries, dtype=float).reshape(3, 3)
    if not np.all(np.isfinite(J)):
        return "inertia has non-finite entries"
    scale = max(1.0, float(np.max(np.abs(J))))
    if np.max(np.abs(J - J.T)) > tol * scale:
        return f"inertia is not symmetric: {J.tolist()}"
    moments = np.linalg.eigvalsh((J + J.T) / 2)
    if moments[0] < -tol * scale:
        return f"inertia is not positive semi-definite (principal moments {_fmt(moments)})"
    a, b, c = moments
    if triangle and c > a + b + tol * scale:
        return f"principal moments {_fmt(moments)} violate the triangle inequality ({c:g} > {a:g} + {b:g})"
    return None


def principal_problem(inertia, tol: float = PHYSICAL_TOL) -> str | None:
    """Why a symmetric 3x3 inertia tensor about the centre of mass is not physical, judged relative to its largest
    principal moment: negative moments or a violated triangle inequality by more than ``tol`` of it.  (Cached on
    the numbers: a URDF reader asks it of a link's tensor and again of the body that is that link alone.)"""
    return _principal_problem(tuple(np.asarray(inertia, dtype=float).ravel().tolist()), tol)


@functools.lru_cache(maxsize=4096)
def _principal_problem(entries: tuple, tol: float) -> str | None:
    J = np.array(entries, dtype=float).reshape(3, 3)
    if not np.all(np.isfinite(J)):
        return "inertia has non-finite entries"
    moments = np.linalg.eigvalsh((J + J.T) / 2)
    scale = float(np.max(np.abs(moments)))
    if scale == 0.0:
        return None
    a, b, c = moments
    if a < -tol * scale:
        return f"not positive semi-definite (principal moments {_fmt(moments)})"
    if c > a + b + tol * scale:
        return f"principal moments {_fmt(moments)} violate the triangle inequality ({c:g} > {a:g} + {b:g})"
    return None


def _fmt(values) -> str:
    return ", ".join(f"{v:g}" for v in values)


# where the dynamics sees a body -----------------------------------------------------------------------------


def _hat(v) -> np.ndarray:
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def _elementary(axis: int, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    if axis == 1:
        return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    if axis == 2:
        return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _orth(vectors: np.ndarray) -> np.ndarray:
    """An orthonormal basis (6 x d) of the span of the columns."""
    if vectors.shape[1] == 0:
        return vectors
    u, s, _ = np.linalg.svd(vectors, full_matrices=False)
    if s[0] == 0.0:
        return vectors[:, :0]
    return u[:, s > 1e-10 * s[0]]


def motion_space(parent_space: np.ndarray, translation, rotation, codes) -> np.ndarray:
    """The span W (orthonormal 6 x d basis, (v, w) in the body's axes) of the quasi-velocities a body can have,
    from its parent's and its pair (1.24)-(1.28).

    The body frame is the parent's translated by ``translation`` (parent axes), turned by the elementary rotations
    ``rotation`` ([(axis 1..3, angle)]), then moved by the pair's coordinates ``codes`` in order.  A frame at p with
    axes R sees the velocity (R^T (v + w x p), R^T w).  A coordinate moving the frame by exp(q G) mixes what reaches
    it over all q into the Krylov space of G (the span of an orbit is that of its derivatives), and adds its own
    unit column f_i (1.29).  Parent space None means the world (W = {0}).
    """
    W = np.zeros((6, 0)) if parent_space is None else parent_space
    if W.shape[1] == 6:
        return W
    R = np.eye(3)
    for axis, angle in rotation:
        R = R @ _elementary(axis, float(angle))
    p = np.array([float(x) for x in translation])
    X = np.zeros((6, 6))
    X[:3, :3] = R.T
    X[:3, 3:] = -R.T @ _hat(p)
    X[3:, 3:] = R.T
    W = X @ W
    for code in codes:
        i = ("o1", "o2", "o3", "theta4", "theta5", "theta6").index(code)
        e = np.zeros(3)
        e[i % 3] = 1.0
        G = np.zeros((6, 6))
        if i < 3:  # translation by q along e: v' = v - q [e] w
            G[:3, 3:] = -_hat(e)
        else:  # rotation about e: both parts turn by R^T = exp(-q [e])
            G[:3, :3] = -_hat(e)
            G[3:, 3:] = -_hat(e)
        column = np.zeros((6, 1))
        column[i, 0] = 1.0
        krylov = [W]
        block = W
        for _ in range(6):
            block = G @ block
            krylov.append(block)
        W = _orth(np.hstack(krylov + [column]))
        if W.shape[1] == 6:
            return np.eye(6)
    return W


def kinetic_energy_problem(mass: float, com, inertia, space: np.ndarray, tol: float = PHYSICAL_TOL) -> str | None:
    """Why the kinetic energy 1/2 V^T Theta V (2.3) of a body can be negative for the velocities V in ``space``, or
    None.

    Theta = m B^T B + diag(0, J_c) with B V = v + w x c: only the inertia J_c about the centre of mass can make it
    negative.  J_c is first raised by ``tol`` times its largest principal moment (the tolerance), then Theta is
    tested on ``space`` in units where a length is the body's radius of gyration (so that the translational and
    rotational parts weigh alike).
    """
    if space.shape[1] == 0:
        return None
    m = float(mass)
    c = np.array([float(x) for x in com])
    J = np.array(inertia, dtype=float)
    J = (J + J.T) / 2
    moments = np.linalg.eigvalsh(J)
    largest = float(np.max(np.abs(moments)))
    if largest == 0.0:
        return None
    J = J + tol * largest * np.eye(3)
    B = np.hstack([np.eye(3), _hat(c).T])
    theta = m * B.T @ B
    theta[3:, 3:] += J
    length = math.sqrt(largest / m) if m > 0 else 1.0
    D = np.diag([length] * 3 + [1.0] * 3)
    scaled = D @ theta @ D
    basis = _orth(np.linalg.solve(D, space))
    reduced = basis.T @ scaled @ basis
    values, vectors = np.linalg.eigh((reduced + reduced.T) / 2)
    if values[0] >= -TOL * max(largest, float(values[-1])):
        return None
    worst = D @ basis @ vectors[:, 0]
    worst = worst / np.max(np.abs(worst))
    v, w = ", ".join(f"{x:.3g}" for x in worst[:3]), ", ".join(f"{x:.3g}" for x in worst[3:])
    return f"its kinetic energy is negative for a velocity its joints allow (v = ({v}), w = ({w}) in its axes)"


# the shape of the tree ------------------------------------------------------------------------------------


def order_tree(names: list, parents: list, world: str):
    """Order bodies parents-first, keeping the given order where it allows.

    Returns ``(order, problem, index)``: ``order`` a list of indices, or ``problem`` (a message) and the index
    of the body it concerns.  Detects unknown parents, several roots, no root, and cycles.

    The order is that of passes over the list, each placing in list order the bodies whose parent is placed: a
    body is in its parent's pass when it comes after its parent in the list, in the next pass when before.  So a
    body's pass is known from its parent's, and the order is sorted by (pass, position): O(n log n).
    """
    n = len(names)
    index = {name: i for i, name in enumerate(names)}
    roots = [i for i, p in enumerate(parents) if p == world]
    for i, p in enumerate(parents):
        if p != world and p not in index:
            return None, (f"unknown parent {p!r}{did_you_mean(p, list(names) + [world])} (no body has that name; the "
                          f"root's parent is {world!r})"), i
        if p == names[i]:
            return None, f"body {names[i]!r} is its own parent", i
    parent = [-1 if p == world else index[p] for p in parents]
    state = [0] * n  # 0 unseen, 1 reaches the world, 2 + i: on the walk started at i
    for i in range(n):  # a cycle: following parents from i comes back to a body of the same walk
        chain, j = [], i
        while j >= 0 and state[j] == 0:
            state[j] = 2 + i
            chain.append(j)
            j = parent[j]
        if j >= 0 and state[j] == 2 + i:
            loop = chain[chain.index(j):] + [j]
            return None, ("cycle in the tree: " + " -> ".join(names[k] for k in loop)
                          + " (each is the child of the next)"), loop[0]
        for k in chain:
            state[k] = 1
    if not roots:
        return None, "no root: exactly one body must have parent 'world'", 0
    if len(roots) > 1:
        a, b = names[roots[0]], names[roots[1]]
        return None, (f"two roots: {a!r} and {b!r} both attach to {world!r}; exactly one body may "
                      f"(attach the others to it)"), roots[1]
    children: list[list[int]] = [[] for _ in range(n)]
    for i, p in enumerate(parent):
        if p >= 0:
            children[p].append(i)
    passes = [0] * n
    stack = list(roots)
    while stack:
        k = stack.pop()
        for child in children[k]:
            passes[child] = passes[k] + (1 if k > child else 0)
            stack.append(child)
    return sorted(range(n), key=lambda i: (passes[i], i)), None, None


SUPPORT_CODES = ("o1", "o2", "o3", "theta4", "theta5", "theta6")


def support_problem(model, name: str) -> str | None:
    """Why body ``name`` cannot be the support of the support paper's equation (3.1), or None: it must be the one
    root of the tree, on a free pair (the six coordinates o1 o2 o3 theta4 theta5 theta6, first in q), carry at
    least one other coordinate, and the model must have no prescribed motions, coupled coordinates or
    constraints (not supported with a support yet)."""
    bodies = {b.name: b for b in model.bodies}
    if name not in bodies:
        return f"unknown body {name!r}"
    body = bodies[name]
    roots = [b.name for b in model.bodies if b.parent == "world"]
    if body.parent != "world" or roots != [name]:
        return (f"the support must be the one body on the world (the root of the tree), and {name!r} is not"
                + (f" (the roots are {', '.join(roots)})" if body.parent == "world" else f" (its parent is "
                                                                                         f"{body.parent!r})"))
    if tuple(body.pair.codes) != SUPPORT_CODES:
        return (f"the support's pair must be free: the six coordinates o1 o2 o3 theta4 theta5 theta6, and "
                f"{name!r} has {', '.join(body.pair.codes) or 'none'}")
    if body.pair.quaternion:
        return ("the support's pair must be the Euler free pair (--floating-base euler): the support equation (3.1) "
                "is written in its six coordinates, which a quaternion free-flyer does not have")
    if body.pair.stiffness is not None:
        return "the support's pair cannot be elastic"
    if model.nv <= 6:
        return "the support carries no mechanism (no coordinate besides its six)"
    if model.time_dependent:
        return "a support with prescribed motions (rotors with a prescribed spin) is not supported yet"
    if model.couplings:
        return "a support with coupled (mimic) coordinates is not supported yet"
    if model.constraints:
        return "a support with constraints is not supported yet"
    return None
