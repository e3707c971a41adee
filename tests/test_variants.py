"""The two indexing variants of the book (one elementary motion per frame; multi-coordinate pairs with
M = diag(c^T, eps)) give the same equations."""
import numpy as np
import sympy as sp

import aggsym
from conftest import model_path


def test_double_pendulum_variants_give_the_same_equations():
    e1 = aggsym.equations(aggsym.load(model_path("double_pendulum")))
    e2 = aggsym.equations(aggsym.load(model_path("double_pendulum_variant2")))
    rename = dict(zip(list(e2.q) + list(e2.qd), list(e1.q) + list(e1.qd)))
    rename[sp.Symbol("p21", real=True)] = sp.Symbol("p31", real=True)
    for name in ("A", "b", "g"):
        diff = sp.simplify(getattr(e2, name).subs(rename) - getattr(e1, name))
        assert diff == sp.zeros(*diff.shape), name


def chain_of_elementary_frames(model):
    """The same system in variant 1: every multi-coordinate pair split into massless frames, one motion each."""
    from aggsym.model.types import Body, Model, Pair

    bodies = []
    for body in model.bodies:
        pair = body.pair
        if len(pair.coordinates) <= 1:
            bodies.append(body)
            continue
        parent = body.parent
        coords = pair.coordinates
        for j, c in enumerate(coords):
            last = j == len(coords) - 1
            name = body.name if last else f"{body.name}__{c.code}"
            p = Pair(f"{pair.name}__{c.code}" if not last else pair.name,
                     pair.translation if j == 0 else (0, 0, 0), pair.rotation if j == 0 else (), (c,))
            bodies.append(Body(name, parent, p, body.inertial if last else None))
            parent = name
    return Model(model.name + "_v1", tuple(bodies), model.gravity, model.parameters)


def test_multi_coordinate_pairs_equal_chains_of_frames(rng):
    """Free 6-coordinate pairs (walking machine, spacecraft) and the ball joint equal their variant-1 chains."""
    for name in ("walking_machine", "spacecraft", "double_pendulum_variant2"):
        model = aggsym.load(model_path(name))
        split = chain_of_elementary_frames(model)
        t1, t2 = aggsym.NumericTwin(model), aggsym.NumericTwin(split)
        assert len(split.bodies) > len(model.bodies)
        for _ in range(3):
            q, qd, qdd = rng.normal(size=(3, model.nq))
            for role, args in (("inertia", (q,)), ("bias", (q, qd)), ("gravity", (q,)),
                               ("inverse_dynamics", (q, qd, qdd))):
                a, b = t1.call(role, *args), t2.call(role, *args)
                assert np.allclose(a, b, rtol=1e-12, atol=1e-12 * max(1, np.abs(a).max())), (name, role)
