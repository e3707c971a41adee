"""Physical checks shared by the readers: masses, inertia tensors, the shape of the tree."""
from __future__ import annotations

import numpy as np

TOL = 1e-9


def mass_problem(mass: float) -> str | None:
    if not np.isfinite(mass):
        return f"mass {mass!r} is not finite"
    if mass <= 0:
        return f"mass must be positive, got {mass:g} (omit mass and inertia for a massless frame)"
    return None


def inertia_problem(inertia, triangle: bool = True) -> str | None:
    """Why a 3x3 inertia tensor about the centre of mass is not physical, or None.

    It must be symmetric, positive semi-definite, and (unless ``triangle`` is False) its principal moments
    must satisfy the triangle inequality (each at most the sum of the other two).
    """
    J = np.asarray(inertia, dtype=float)
    if not np.all(np.isfinite(J)):
        return "inertia has non-finite entries"
    scale = max(1.0, float(np.max(np.abs(J))))
    if np.max(np.abs(J - J.T)) > TOL * scale:
        return f"inertia is not symmetric: {J.tolist()}"
    moments = np.linalg.eigvalsh((J + J.T) / 2)
    if moments[0] < -TOL * scale:
        return f"inertia is not positive semi-definite (principal moments {_fmt(moments)})"
    a, b, c = moments
    if triangle and c > a + b + TOL * scale:
        return f"principal moments {_fmt(moments)} violate the triangle inequality ({c:g} > {a:g} + {b:g})"
    return None


def _fmt(values) -> str:
    return ", ".join(f"{v:g}" for v in values)


def order_tree(names: list, parents: list, world: str):
    """Order bodies parents-first, keeping the given order where it allows.

    Returns ``(order, problem, index)``: ``order`` a list of indices, or ``problem`` (a message) and the index
    of the body it concerns.  Detects unknown parents, several roots, no root, and cycles.
    """
    index = {n: i for i, n in enumerate(names)}
    roots = [i for i, p in enumerate(parents) if p == world]
    for i, p in enumerate(parents):
        if p != world and p not in index:
            return None, f"unknown parent {p!r} (no body has that name; the root's parent is {world!r})", i
        if p == names[i]:
            return None, f"body {names[i]!r} is its own parent", i
    for i in range(len(names)):  # a cycle: following parents from i comes back to a body already seen
        chain, j = [], i
        while parents[j] != world and j not in chain:
            chain.append(j)
            j = index[parents[j]]
        if parents[j] != world:
            loop = chain[chain.index(j):] + [j]
            return None, ("cycle in the tree: " + " -> ".join(names[k] for k in loop)
                          + " (each is the child of the next)"), loop[0]
    if not roots:
        return None, "no root: exactly one body must have parent 'world'", 0
    if len(roots) > 1:
        a, b = names[roots[0]], names[roots[1]]
        return None, (f"two roots: {a!r} and {b!r} both attach to {world!r}; exactly one body may "
                      f"(attach the others to it)"), roots[1]
    placed: list[int] = []
    done: set[int] = set()
    remaining = list(range(len(names)))
    while remaining:  # stable: each pass places, in file order, the bodies whose parent is placed
        for i in list(remaining):
            p = parents[i]
            if p == world or index[p] in done:
                placed.append(i)
                done.add(i)
                remaining.remove(i)
    return placed, None, None
