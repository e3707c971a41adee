"""Chapter 3 against Pinocchio on URDF files: forward dynamics by the transvective Cauchy form (3.20) against
``pin.aba`` and A(q)^-1 = T^T diag(1/(beta,beta)) T (3.19) against ``pin.computeMinverse``.

Through the numeric twin on example-robot-data's robots (fixed base; free base for the legged ones) and on random
branching trees (:mod:`random_trees`), and, for the robots, through the generated C and NumPy module.  Relative
error: max |ours - Pinocchio| / max |Pinocchio| <= 1e-9.  computeMinverse fills the upper triangle; it is
mirrored.  The C is compiled with -O0 (the warning flags stay; -O2 is exercised by test_codegen), which keeps
talos' compile to seconds.
"""
import numpy as np
import pytest

import aggsym
from aggsym.model.tree import Tree
from helpers import ROBOTS, TOLERANCE, relative_error, robot_path
from pinocchio_reference import pin, pinocchio_model, pinocchio_q
from random_trees import random_urdf

pytestmark = [pytest.mark.pinocchio, pytest.mark.filterwarnings("ignore::aggsym.errors.ModelWarning")]

# The first 22 seeds whose trees are regular (see moves_mass); the others, e.g. 0, 2, 3, 5, have a massless bud on a
# joint (or only a massless, spinning body beyond a prismatic joint): A(q) is singular there for every q.
RANDOM_SEEDS = (1, 4, 6, 7, 8, 9, 10, 12, 14, 16, 17, 20, 21, 22, 24, 25, 27, 28, 29, 31, 34, 35)
FLOATING_SEEDS = (1, 9, 17, 25, 34)
STATES = 3


def moves_mass(model) -> bool:
    """Every coordinate moves mass: its pair's subtree holds a body of nonzero mass, or, for a rotation, at least
    a nonzero inertia tensor.  Otherwise A(q) has a zero row and column whatever q is."""
    tree = Tree(model)
    for k, coords in enumerate(tree.coords):
        inertials = [model.bodies[j].inertial for j in tree.subtrees[k] if model.bodies[j].inertial is not None]
        massive = any(i.mass != 0 for i in inertials)
        spinning = any(x != 0 for i in inertials for row in i.inertia for x in row)
        if not all(massive or (c.kind == "rotation" and spinning) for c in model.bodies[k].pair.coordinates):
            return False
    return True


def states(model, rng, n=STATES):
    """Random (q, q', tau): angles and displacements in [-pi, pi], rates and forces normal.  A free base's
    second angle (RY) stays in [-1.2, 1.2]: at +-pi/2 the angles RX RY RZ, and A(q), are singular, and near it
    any two exact solutions differ by about cond(A) * 1e-16."""
    free = [i for i, c in enumerate(model.coordinates) if c.name == "base_ry"]
    for _ in range(n):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        q[free] = rng.uniform(-1.2, 1.2, len(free))
        yield q, rng.normal(size=model.nq), rng.normal(size=model.nq)


def upper_mirrored(M):
    return np.triu(M) + np.triu(M, 1).T


def pinocchio_reference(pm, data, q, qd, tau):
    """(aba, computeMinverse mirrored) at our (q, q', tau)."""
    Q = pinocchio_q(pm, q)
    return pin.aba(pm, data, Q, qd, tau), upper_mirrored(pin.computeMinverse(pm, data, Q))


def check_twin(model, pm, rng, n=STATES) -> float:
    """forward_dynamics and inertia_inverse of the numeric twin against Pinocchio; returns the largest error."""
    assert model.nq == pm.nv
    twin = aggsym.NumericTwin(model)
    data = pm.createData()
    worst = 0.0
    for q, qd, tau in states(model, rng, n):
        qdd, Minv = pinocchio_reference(pm, data, q, qd, tau)
        errors = {"forward_dynamics vs aba": relative_error(twin.forward_dynamics(q, qd, tau), qdd),
                  "inertia_inverse vs computeMinverse": relative_error(twin.inertia_inverse(q), Minv)}
        for what, error in errors.items():
            assert error <= TOLERANCE, f"{model.name}: {what}: relative error {error:.3g} at q={q.tolist()}"
        worst = max(worst, *errors.values())
    return worst


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_robot_twin_against_pinocchio(robot, rng):
    path = robot_path(robot)
    check_twin(aggsym.load(path), pinocchio_model(path), rng)


@pytest.mark.parametrize("robot", ["solo12", "hyq", "talos"])
def test_floating_base_robot_twin_against_pinocchio(robot, rng):
    """A free pair of six coordinates at the root: 15 transvections among its own coordinates (see the module
    doc of aggsym.transvective) against Pinocchio's PX, PY, PZ, RX, RY, RZ root."""
    path = robot_path(robot)
    check_twin(aggsym.load(path, floating_base=True), pinocchio_model(path, floating_base=True), rng, n=2)


def tree_file(tmp_path, seed):
    path = tmp_path / f"tree_{seed}.urdf"
    path.write_text(random_urdf(seed))
    return path


@pytest.mark.parametrize("seed", RANDOM_SEEDS)
def test_random_tree_against_pinocchio(seed, tmp_path):
    path = tree_file(tmp_path, seed)
    model = aggsym.load(path)
    assert moves_mass(model)
    check_twin(model, pinocchio_model(path), np.random.default_rng(1000 + seed))


@pytest.mark.parametrize("seed", FLOATING_SEEDS)
def test_random_tree_floating_base_against_pinocchio(seed, tmp_path):
    path = tree_file(tmp_path, seed)
    check_twin(aggsym.load(path, floating_base=True), pinocchio_model(path, floating_base=True),
               np.random.default_rng(2000 + seed), n=2)


@pytest.mark.parametrize("seed", [0, 13])
def test_singular_tree_is_refused(seed, tmp_path):
    """Where a coordinate moves no mass the pivot (beta,beta) of (3.11) vanishes: the twin raises (Pinocchio's
    aba returns NaN there)."""
    path = tree_file(tmp_path, seed)
    model = aggsym.load(path)
    assert not moves_mass(model)
    q = np.random.default_rng(seed).uniform(-np.pi, np.pi, model.nq)
    pm = pinocchio_model(path)
    assert np.isnan(pin.aba(pm, pm.createData(), pinocchio_q(pm, q), np.zeros(model.nq), np.ones(model.nq))).any()
    with pytest.raises(ZeroDivisionError):
        aggsym.NumericTwin(model).forward_dynamics(q, np.zeros(model.nq), np.ones(model.nq))


# --------------------------------------------------------------------------------------------------------------
# the generated C and NumPy module


@pytest.mark.compiler
def test_generated_code_against_pinocchio(robot_code, rng):
    name, model, lib, module, pm = robot_code
    data = pm.createData()
    for q, qd, tau in states(model, rng):
        qdd, Minv = pinocchio_reference(pm, data, q, qd, tau)
        for kind, fd, inv in (("C", lib.call("forward_dynamics", q, qd, tau), lib.call("inertia_inverse", q)),
                              ("NumPy", module.forward_dynamics(q, qd, tau), module.inertia_inverse(q))):
            assert relative_error(fd, qdd) <= TOLERANCE, (name, kind, "forward_dynamics", relative_error(fd, qdd))
            assert relative_error(inv, Minv) <= TOLERANCE, (name, kind, "inertia_inverse", relative_error(inv, Minv))
        batch = np.stack([q, q[::-1]]), np.stack([qd, -qd]), np.stack([tau, 2 * tau])  # NumPy: a batch of states
        got = module.forward_dynamics(*batch)
        for row, (Q, QD, TAU) in enumerate(zip(*batch)):
            assert relative_error(got[row], pinocchio_reference(pm, data, Q, QD, TAU)[0]) <= TOLERANCE
