"""Whether A(q) is regular, decided from the model's structure before any sample, and the same way for a fixed base
and a free-flyer of one file.

A(q) qd . qd = 2T is the kinetic energy, the sum of each body's V_b^T M_b V_b (its 6 x 6 spatial inertia M_b, an
added mass included) and of the rotor inertias a_j qd_j^2.  A is regular at q exactly when T = 0 forces qd = 0.
:func:`regularity` proves that for every q where the structure allows it, walking the tree from the world: a body
whose parent is at rest is at rest too when its spatial inertia is positive definite (then V_b = 0, and its pair's
motion subspace has full rank, :func:`full_rank`, so its rates vanish) or when every coordinate of its pair carries
a rotor inertia (then its rates vanish, and V_b = V_parent = 0); a pair without coordinates (welded, or a
prescribed spin) keeps it at rest.  When every body is reached, A is positive definite for all q (kind
``"everywhere"``).

Otherwise some body is degenerate (a point mass: M_b of rank 3; a massless body: rank 0; a rod: rank 5), possibly
chained through massless bodies (MJCF's bodies with several joints), and A may be singular: everywhere (a joint that
moves no mass, two coaxial hinges carrying a point mass) or on a set of configurations (a point mass carried by two
hinges stays still when the two velocities it gets from them are parallel: a neck pitch of 0 under a point-mass
head).
Which of the two is the generic rank of A: it is judged at :data:`SAMPLES` fixed configurations of the joints
(:func:`generic_configurations`: the same angles for coordinate k of the joints whatever the base, the base at
rest at the identity, since A's rank does not depend on where the base is), A singular everywhere only when it
is singular at all of them (kind ``"singular"``), else ``"sampled"``: regular at generic configurations, perhaps
singular on a set of them, what the structure leaves open named.  The angles are fixed numbers (not a random
draw), away from the multiples of pi/4 where singular sets of rotations lie, so the answer is the same in every
run.  A model not proved regular is not claimed singular
anywhere either (a planar arm of rods is regular everywhere, unproved here): the manifest says what kept the proof
from holding and whether A is singular at q = 0, where such sets pass (a point-mass head at a neck angle of 0).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..model.tree import Tree

SAMPLES = 3  # configurations at which a structurally degenerate model's generic rank is judged
TOLERANCE = 1e-12  # an eigenvalue below TOLERANCE of the largest entry of A (of M_b for a body) counts as zero
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


@dataclass(frozen=True)
class Regularity:
    """``kind``: "everywhere" (A positive definite for every q, proved from the structure), "sampled" (regular at
    the fixed configurations, so at generic ones; unproved elsewhere: it may be singular on a set), "singular"
    (singular at every configuration); ``degenerate``: (body, what) of the moving bodies whose spatial inertia is not
    positive definite; ``open``: what else kept the proof from holding (pairs of three rotations, rotors,
    couplings); ``zero``: the coordinates with A_ii = 0 (they move no mass) when singular."""

    kind: str
    degenerate: tuple = ()
    zero: tuple = ()
    open: tuple = ()

    @property
    def singular(self) -> bool:
        return self.kind == "singular"

    def describe(self, model) -> str:
        """One sentence for the manifest and the header."""
        if self.kind == "everywhere":
            return ("A(q) is positive definite at every configuration: every body has a positive definite spatial "
                    "inertia or rotor inertias on its coordinates (proved from the structure)")
        reasons = [f"{name} ({what})" for name, what in self.degenerate] + list(self.open)
        bodies = "; ".join(reasons)
        if self.kind == "sampled":
            return (f"A(q) is regular at generic configurations (full rank at {SAMPLES} fixed ones); not proved "
                    f"regular everywhere, it may be singular on a set of them: {bodies}")
        names = ", ".join(model.coordinates[i].name for i in self.zero)
        return (f"A(q) is singular at every configuration" + (f": coordinate(s) {names} move(s) no mass" if names
                                                              else f" (degenerate bodies: {bodies})"))


def _defaults(model) -> dict:
    return {p.symbol: float(p.value) for p in model.parameters}


def _number(x, values) -> float:
    """A model's number or expression at the parameters' ``values`` (never text: :func:`~aggsym.core.backend.as_expr`)."""
    from ..core.backend import as_expr

    return float(x) if isinstance(x, (int, float)) else float(as_expr(x).subs(values))


def spatial_inertia(body, values):
    """The 6 x 6 spatial inertia of ``body`` about its origin, (omega, v) order, at the parameter values ``values``
    (an added mass included); None for a massless body without one."""
    import numpy as np

    M = np.zeros((6, 6))
    if body.inertial is not None:
        m, h, theta = body.inertial.mises()
        h = [_number(x, values) for x in h]
        M[:3, :3] = [[_number(v, values) for v in row] for row in theta]
        cross = np.array([[0.0, -h[2], h[1]], [h[2], 0.0, -h[0]], [-h[1], h[0], 0.0]])
        M[:3, 3:], M[3:, :3], M[3:, 3:] = cross, cross.T, _number(m, values) * np.eye(3)
    if body.added_mass is not None:  # (v, w) order there
        L = np.array([[_number(v, values) for v in row] for row in body.added_mass])
        order = [3, 4, 5, 0, 1, 2]
        M += L[np.ix_(order, order)]
    return M if M.any() else None


def _degeneracy(M) -> str | None:
    """None when ``M`` is positive definite, else what it is."""
    import numpy as np

    if M is None:
        return "massless"
    eig = np.linalg.eigvalsh((M + M.T) / 2)
    rank = int(np.sum(eig > TOLERANCE * max(float(eig[-1]), 1e-300)))
    if rank == 6:
        return None
    return {3: "a point mass: no rotational inertia", 5: "a rod: no inertia about its axis"}.get(
        rank, f"its spatial inertia has rank {rank} of 6")


def full_rank(pair) -> bool:
    """Whether the pair's motion subspace has full rank at every configuration: a quaternion pair (its coordinates
    are the body's own velocity), or at most two rotations (about distinct axes, the second carried by the first:
    always independent) after translations; three rotations (an Euler-angle floating base) lose rank where two of
    their axes align."""
    return pair.quaternion or sum(c.kind == "rotation" for c in pair.coordinates) <= 2


def _unit_twists(model, tree, k, coords) -> list:
    """Body k's twists (omega, v) in its axes for a unit rate of each of ``coords`` alone, at one fixed
    configuration."""
    from ..core.backend import Numeric
    from ..mechanics.bound import bind
    from ..mechanics.kinematics import TreeKinematics

    kin = TreeKinematics(bind(model, Numeric()), [float(x) for x in generic_configurations(model, 1)[0]])
    out = []
    for i in coords:
        qd = [0.0] * tree.nv
        qd[i] = 1.0
        v = [float(x) for x in kin.velocities(qd)[k]]
        out.append(v[3:] + v[:3])
    return out


def _moves_mass(model, tree, k, M) -> bool:
    """Whether body k's own pair (one coordinate, or a quaternion pair: its motion subspace S is constant in the
    body's axes) moves mass in every direction of its rates: S^T M_b S positive definite (a rod turning about an
    axis across it, a point mass off a hinge's axis); then, its parent at rest, T = 0 forces its rates to 0."""
    import numpy as np

    pair = model.bodies[k].pair
    if M is None or not (pair.quaternion or len(pair.coordinates) == 1):
        return False
    S = np.array(_unit_twists(model, tree, k, tree.coords[k])).T
    G = S.T @ M @ S
    eig = np.linalg.eigvalsh((G + G.T) / 2)
    return bool(eig[0] > TOLERANCE * max(float(np.abs(M).max()) * float(np.abs(S).max()) ** 2, 1e-300))


def _two_twists_independent(model, tree, k, coords) -> bool:
    """Whether the unit rates of the two coordinates ``coords`` (on the path from an ancestor at rest to body k)
    move body k by independent twists.  Constant in q: the second twist is the first pair's motion applied to its
    value at q = 0, and that motion leaves the first twist where it is, so the two are parallel everywhere or
    nowhere; judged at one configuration, relative to the larger twist."""
    import numpy as np

    s = np.linalg.svd(np.array(_unit_twists(model, tree, k, coords)), compute_uv=False)
    return bool(s[-1] > TOLERANCE * s[0])


def _at_rest(model, tree, solid, pinned, inertias) -> bool:
    """Whether every body is reached by the walk of the module's text; a solid body at the end of a chain of
    degenerate bodies (each the only child of the one before: MJCF's bodies with two joints) from one at rest pins
    the chain when the chain has at most two coordinates and their twists are independent
    (:func:`_two_twists_independent`)."""
    rest = [False] * len(tree)
    for k, (p, body) in enumerate(zip(tree.parent, model.bodies)):
        coords = tree.coords[k]
        parent_rest = p < 0 or rest[p]
        rest[k] = parent_rest and (not coords or (solid[k] and full_rank(body.pair))
                                   or all(pinned[i] for i in coords) or _moves_mass(model, tree, k, inertias[k]))
        if rest[k] or not solid[k] or not full_rank(body.pair):
            continue
        path, j = [k], p
        while j >= 0 and not rest[j] and not solid[j] and len(tree.children[j]) == 1:
            path.append(j)
            j = tree.parent[j]
        chain = [i for b in path for i in tree.coords[b]]
        if (j < 0 or rest[j]) and len(path) > 1 and len(chain) <= 2 and \
                (len(chain) < 2 or _two_twists_independent(model, tree, k, chain)):
            for b in path:
                rest[b] = True
    return all(rest)


def generic_configurations(model, samples: int = SAMPLES) -> list:
    """``samples`` fixed configurations q: coordinate k of the joints (the base's own excluded) at an angle of the
    golden-ratio sequence, the same for a fixed base and a free-flyer of one file; a free-flyer at the origin with
    the identity quaternion; a ball pair's quaternion a fixed rotation about a fixed oblique axis."""
    out = []
    for s in range(samples):
        value, k = {}, 0  # (by name: a coupled coordinate leaves q, its master stays)
        for body in model.bodies:
            pair = body.pair
            if pair.free_flyer:
                value.update(zip(pair.positions, [0.0] * 6 + [1.0]))
                continue
            if pair.quaternion:
                angle = 0.5 + 0.9 * ((s + 1) * GOLDEN % 1.0)
                half = math.sin(angle / 2)
                value.update(zip(pair.positions, [a * half for a in (0.48, -0.6, 0.64)] + [math.cos(angle / 2)]))
                k += 1
                continue
            for c in pair.coordinates:
                k += 1
                # in (-pi, pi), irrational steps: no multiple of pi/4 nearer than a few hundredths of a radian
                value[c.name] = -math.pi + 2 * math.pi * ((k * GOLDEN + (s + 1) * math.sqrt(2.0) / 7.0) % 1.0)
        out.append([value[name] for name, _, _ in model.positions])
    return out


def _smallest(model, bound, q) -> float:
    """A(q)'s smallest eigenvalue over its largest entry."""
    import numpy as np

    from .registry import ROUTINES, run

    n = model.nv
    A = np.array(run(ROUTINES["inertia"], bound, {"q": q})[0], dtype=float).reshape(n, n)
    return float(np.linalg.eigvalsh(A)[0]) / max(float(np.abs(A).max()), 1e-300), A


def mass_matrix_entry(model) -> dict | None:
    """The manifest's ``mass_matrix`` for a model whose A(q) is not proved regular everywhere: the kind, why, the
    degenerate bodies and whether A is singular at q = 0 (the neutral configuration, a robot's home pose); None
    when A is positive definite everywhere."""
    from ..core.backend import Numeric
    from ..mechanics.bound import bind

    regular = regularity(model)
    if regular.kind == "everywhere":
        return None
    neutral = [float(x) for x in Tree.of(model).neutral]
    ratio, _ = _smallest(model, bind(model, Numeric()), neutral)
    return {"regular": regular.kind, "why": regular.describe(model),
            "degenerate_bodies": [{"body": name, "inertia": what} for name, what in regular.degenerate],
            "not_proved_by": list(regular.open),
            "singular_at_neutral": bool(ratio <= TOLERANCE),
            "tolerance": f"an eigenvalue below {TOLERANCE:g} of A's largest entry counts as zero"}


def regularity(model) -> Regularity:
    """The regularity of A(q) at the default parameters (the module's text), judged once per model (kept on the
    model object: the routines of :mod:`.singular_states` ask for it wherever a model's routines are listed)."""
    cached = model.__dict__.get("_regularity")
    if cached is None:
        cached = _judged(model)
        object.__setattr__(model, "_regularity", cached)  # (a frozen dataclass; not a field: replace() judges anew)
    return cached


def _judged(model) -> Regularity:
    import numpy as np

    from ..core.backend import Numeric
    from ..mechanics.bound import bind

    n = model.nv
    if n == 0:
        return Regularity("everywhere")
    tree = Tree.of(model)
    values = _defaults(model)
    inertias = [spatial_inertia(b, values) for b in model.bodies]
    degenerate = [(b.name, _degeneracy(M)) for b, M in zip(model.bodies, inertias)]
    solid = [what is None for _, what in degenerate]
    armature = _number(model.armature, values) if model.armature else 0.0
    own = [_number(a, values) for a in model.dof_armature] or [0.0] * n
    pinned = [armature + a > 0 for a in own]
    named = tuple((name, what) for (name, what), k in zip(degenerate, range(len(tree))) if what is not None
                  and tree.moving[k])
    open_ = tuple(f"{b.pair.name or b.name}: a pair of three rotations (its axes can align)" for k, b in
                  enumerate(model.bodies) if tree.coords[k] and not full_rank(b.pair))
    open_ += ("rotors carried by bodies",) if any(b.carrier for b in model.bodies) else ()
    open_ += ("coupled coordinates",) if model.couplings else ()
    simple = not model.couplings and not any(b.carrier for b in model.bodies)
    if simple and _at_rest(model, tree, solid, pinned, inertias):
        return Regularity("everywhere")
    bound = bind(model, Numeric())
    zero, singular = set(range(n)), True
    for q in generic_configurations(model):
        ratio, A = _smallest(model, bound, q)
        scale = max(float(np.abs(A).max()), 1e-300)
        zero &= {i for i in range(n) if abs(A[i, i]) <= TOLERANCE * scale}
        singular = singular and ratio <= TOLERANCE
    if singular:
        return Regularity("singular", named, tuple(sorted(zero)), open_)
    return Regularity("sampled", named, (), open_)


__all__ = ["Regularity", "regularity", "mass_matrix_entry", "full_rank", "generic_configurations", "spatial_inertia",
           "SAMPLES", "TOLERANCE"]
