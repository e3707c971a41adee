"""A(q)^-1 in O(n^2) from the generators of the transvective factors (aggsym.mechanics.transvective,
inverse_by_generators), against Pinocchio's computeMinverse and numpy.linalg.inv of Pinocchio's crba.

The numeric twin runs the generators; the straight-line program of the generators is evaluated directly (the
routine emits it or the explicit factors, whichever program is smaller), and the emitted code of a long chain,
where the generators win, is compiled and run."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import aggsym
from aggsym.contract import select_routines
from aggsym.core.backend import Numeric, Symbolic
from aggsym.mechanics import transvective
from aggsym.mechanics.bound import bind
from aggsym.mechanics.kinematics import TreeKinematics
from helpers import generated_code, relative_error
from pinocchio_reference import pin, pinocchio_model, pinocchio_q, pinocchio_tree
from random_trees import random_urdf

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks.harness.chain import chain_model  # noqa: E402

pytestmark = pytest.mark.pinocchio

TOL = 1e-9
SEEDS = (1, 4, 9, 17, 25, 34)  # regular trees of tests/test_transvective_pinocchio.py


def mirrored(M):
    return np.triu(M) + np.triu(M, 1).T


def generators_numeric(model, q):
    bound = bind(model, Numeric())
    return np.array(transvective.inverse_by_generators(bound, TreeKinematics(bound, list(q))), float)


def generators_program(model):
    """A function q -> A^-1 evaluating the straight-line program of inverse_by_generators."""
    back = Symbolic()
    bound = bind(model, back)
    q = back.program.vector("q", model.nq)
    rows = transvective.inverse_by_generators(bound, TreeKinematics(bound, q))
    flat = [x for row in rows for x in row]

    def run(qv):
        values = {("q", i): float(x) for i, x in enumerate(qv)}
        return np.array(back.program.evaluate(flat, values), float).reshape(model.nq, model.nq)
    return run


def references(pm, Q):
    data = pm.createData()
    M = mirrored(pin.crba(pm, data, Q))
    return mirrored(pin.computeMinverse(pm, pm.createData(), Q)), np.linalg.inv(M)


def _branching(model) -> bool:
    parents = [b.parent for b in model.bodies]
    return len(set(parents)) < len(parents)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("floating", [False, True])
def test_random_tree_against_pinocchio(seed, floating, tmp_path, rng):
    """Branching trees with revolute, prismatic and fixed joints, massless links, fixed or free (6-coordinate
    Euler) base: both the float run and the program of the generators equal computeMinverse and inv(crba)."""
    path = tmp_path / f"tree_{seed}.urdf"
    path.write_text(random_urdf(seed))
    model = aggsym.load(path, floating_base=True) if floating else aggsym.load(path)
    assert _branching(model)
    pm = pinocchio_model(path, floating_base=floating)
    program = generators_program(model)
    for _ in range(2):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        if floating:
            q[4] = rng.uniform(-1.2, 1.2)  # away from the RY singularity of the Euler angles
        Minv, inv = references(pm, pinocchio_q(pm, q))
        for ours in (generators_numeric(model, q), program(q)):
            assert relative_error(ours, Minv) <= TOL
            assert relative_error(ours, inv) <= TOL


def test_quaternion_free_flyer_against_pinocchio(rng):
    """Pinocchio's free-flyer root (q = x, y, z, quaternion, joints) on a humanoid: many branches below a
    6-coordinate pair whose columns are fixed in the body."""
    from helpers import robot_path
    path = robot_path("talos")
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = aggsym.load(path, floating_base="quaternion")
    pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    n = pm.nv
    for _ in range(2):
        joints = rng.uniform(-1, 1, n - 6)
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        Q = np.concatenate([rng.normal(size=3), quat, np.zeros(pm.nq - 7)])
        for j in range(2, pm.njoints):
            jm = pm.joints[j]
            Q[jm.idx_q] = joints[jm.idx_v - 6]
        Minv, inv = references(pm, Q)
        ours = generators_numeric(model, list(Q))
        assert ours.shape == (n, n)
        assert relative_error(ours, Minv) <= TOL
        assert relative_error(ours, inv) <= TOL


def test_long_chain_against_pinocchio(rng, tmp_path):
    """The benchmark's 3-D chain of 40 links: the program of the generators against computeMinverse."""
    model = chain_model(40, tmp_path)
    pm, _ = pinocchio_tree(model)
    program = generators_program(model)
    for _ in range(2):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        Minv, inv = references(pm, q)
        assert relative_error(program(q), Minv) <= TOL
        assert relative_error(generators_numeric(model, q), inv) <= TOL


@pytest.mark.compiler
def test_emitted_chain_is_quadratic_and_exact(rng, tmp_path):
    """The emitted inertia_inverse of the 24-link chain: the generators' program (its operations within
    20 n^2 + 400 n, where the explicit factors take about 33 n^2 at this n and grow as n^3), run as C and as
    NumPy against computeMinverse."""
    n = 24
    model = chain_model(n, tmp_path / "model")
    model = select_routines(model, ["inertia_inverse"])
    lib, module, manifest = generated_code(model, tmp_path / "code")
    ops = manifest["ops"]["inertia_inverse"]
    total = ops["mul"] + ops["add"] + ops["div"] + ops["call"]
    assert total <= 20 * n * n + 400 * n, total
    pm, _ = pinocchio_tree(model)
    for _ in range(2):
        q = rng.uniform(-np.pi, np.pi, n)
        Minv, _ = references(pm, q)
        assert relative_error(np.asarray(lib.call("inertia_inverse", q)).reshape(n, n), Minv) <= TOL
        assert relative_error(np.asarray(module.inertia_inverse(q)).reshape(n, n), Minv) <= TOL
