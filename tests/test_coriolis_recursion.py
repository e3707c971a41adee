"""The Coriolis matrix by its O(n^2) recursion (aggsym.mechanics.bias.coriolis_by_recursion) against Pinocchio.

A Coriolis matrix is not unique; C q' = b (Pinocchio's nonLinearEffects minus its gravity) and C + C^T = dM/dt
(helpers.inertia_rate) pin down the class with the skew property the routine promises.  The book's B
(``skew=False``) has B q' = b, and B - C = -sum J^T I phi(v) J is checked through the column form (the
expanded reference kept for prescribed spins)."""
from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import aggsym
from aggsym.contract import select_routines
from aggsym.core.backend import Numeric, Symbolic
from aggsym.mechanics import bias
from aggsym.mechanics.bound import bind
from aggsym.mechanics.kinematics import TreeKinematics
from helpers import generated_code, relative_error, robot_path
from pinocchio_reference import pin, crba, inertia_rate, pinocchio_model, pinocchio_q, pinocchio_tree
from random_trees import random_urdf

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks.harness.chain import chain_model  # noqa: E402

pytestmark = pytest.mark.pinocchio

TOL = 1e-9
SEEDS = (1, 4, 9, 17, 25, 34)


def numeric(model, q, qd, skew):
    bound = bind(model, Numeric())
    return np.array(bias.coriolis_by_recursion(bound, TreeKinematics(bound, list(q)), list(qd), skew), float)


def columns(model, q, qd, skew):
    bound = bind(model, Numeric())
    return np.array(bias.coriolis_by_columns(bound, TreeKinematics(bound, list(q)), list(qd), skew), float)


def program(model, skew=True):
    """(q, qd) -> C from the straight-line program of coriolis_by_recursion."""
    back = Symbolic()
    bound = bind(model, back)
    n = bound.tree.nv
    q = back.program.vector("q", model.nq)
    qd = back.program.vector("qd", n)
    flat = [x for row in bias.coriolis_by_recursion(bound, TreeKinematics(bound, q), qd, skew) for x in row]

    def run(qv, qdv):
        values = {("q", i): float(x) for i, x in enumerate(qv)}
        values.update({("qd", i): float(x) for i, x in enumerate(qdv)})
        return np.array(back.program.evaluate(flat, values), float).reshape(n, n)
    return run


def check(C, pm, Q, v, B=None):
    data = pm.createData()
    b = pin.nonLinearEffects(pm, data, Q, v) - pin.computeGeneralizedGravity(pm, data, Q)
    M = crba(pm, Q)
    assert relative_error(C @ v, b, floor=np.abs(M).max() * np.abs(v).max() ** 2) <= TOL
    Mdot, tol = inertia_rate(pm, Q, v)
    assert relative_error(C + C.T, Mdot, floor=np.abs(M).max() * np.abs(v).max()) <= max(tol, TOL)
    if B is not None:
        assert relative_error(B @ v, b, floor=np.abs(M).max() * np.abs(v).max() ** 2) <= TOL


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("floating", [False, True])
def test_random_tree_against_pinocchio(seed, floating, tmp_path, rng):
    """Branching trees (revolute, prismatic, fixed joints, massless links), fixed or 6-coordinate Euler base:
    the recursion's C and B, as floats and as a program, against Pinocchio's identities, and equal to the
    column form."""
    path = tmp_path / f"tree_{seed}.urdf"
    path.write_text(random_urdf(seed))
    model = aggsym.load(path, floating_base=True) if floating else aggsym.load(path)
    pm = pinocchio_model(path, floating_base=floating)
    run = program(model)
    for _ in range(2):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        if floating:
            q[4] = rng.uniform(-1.2, 1.2)
        v = rng.normal(size=model.nq)
        Q = pinocchio_q(pm, q)
        C, B = numeric(model, q, v, True), numeric(model, q, v, False)
        check(C, pm, Q, v, B)
        check(run(q, v), pm, Q, v)
        assert relative_error(C, columns(model, q, v, True), floor=1e-6) <= TOL
        assert relative_error(B, columns(model, q, v, False), floor=1e-6) <= TOL


def test_quaternion_free_flyer_against_pinocchio(rng):
    """Pinocchio's free flyer (columns fixed in the base body, not in an intermediate frame) on talos."""
    path = robot_path("talos")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = aggsym.load(path, floating_base="quaternion")
    pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    quat = rng.normal(size=4)
    quat /= np.linalg.norm(quat)
    Q = np.concatenate([rng.normal(size=3), quat, rng.uniform(-1, 1, pm.nq - 7)])
    v = rng.normal(size=pm.nv)
    C = numeric(model, Q, v, True)
    check(C, pm, Q, v, numeric(model, Q, v, False))
    assert relative_error(C, columns(model, Q, v, True), floor=1e-6) <= TOL


@pytest.mark.parametrize("name", ["manipulator6", "walking_machine", "spacecraft", "gyroscope"])
def test_bundled_models_against_pinocchio(name, rng):
    """Multi-coordinate pairs (the spacecraft's and gyroscope's rotations about three axes, whose columns turn
    inside the pair), branches (the walking machine), against a Pinocchio model built joint by joint."""
    model = aggsym.load(Path(__file__).resolve().parents[1] / "models" / f"{name}.yaml")
    pm, _ = pinocchio_tree(model)
    for _ in range(2):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        v = rng.normal(size=model.nq)
        check(numeric(model, q, v, True), pm, q, v, numeric(model, q, v, False))


@pytest.mark.compiler
def test_emitted_chain_is_quadratic_and_exact(rng, tmp_path):
    """The emitted coriolis of the benchmark's 24-link chain: within 20 n^2 + 600 n operations (the column form
    took about 100 n^2), and exact as C and as NumPy."""
    n = 24
    model = select_routines(chain_model(n, tmp_path / "model"), ["coriolis"])
    lib, module, manifest = generated_code(model, tmp_path / "code")
    ops = manifest["ops"]["coriolis"]
    total = ops["mul"] + ops["add"] + ops["div"] + ops["call"]
    assert total <= 20 * n * n + 600 * n, total
    pm, _ = pinocchio_tree(model)
    for _ in range(2):
        q, v = rng.uniform(-np.pi, np.pi, n), rng.normal(size=n)
        check(np.asarray(lib.call("coriolis", q, v)).reshape(n, n), pm, q, v)
        check(np.asarray(module.coriolis(q, v)).reshape(n, n), pm, q, v)


def test_a_budgeted_count_stops_early_and_leaves_the_choice_as_it_was(tmp_path):
    """scratch_operations counts a form's outputs as they are built: without a budget it counts every node the
    outputs reach once (as Program.reachable of all of them does), with a budget it stops at the first column
    that reaches it, so that the column form of a long chain is not built to the end only to lose; the
    emitted form is the one the whole counts choose."""
    from aggsym.mechanics.bound import scratch_operations

    model = chain_model(12, tmp_path)
    back = Symbolic()
    bound = bind(model, back)
    kin = TreeKinematics(bound, back.program.vector("q", model.nq))
    columns_form = lambda b, k, u: bias.coriolis_columns(b, k, u, True)  # noqa: E731
    whole = scratch_operations(bound, kin, columns_form)
    rows = bias.coriolis_by_columns(bound, kin, back.program.vector("qd", bound.tree.nv), True)
    flat = [x for row in rows for x in row]
    assert whole == sum(1 for i in back.program.reachable(flat) if back.program.ops[i][0] not in ("in", "neg"))

    built = []

    def counted(b, k, u):
        for col in bias.coriolis_columns(b, k, u, True):
            built.append(col)
            yield col

    budget = whole // 4
    stopped = scratch_operations(bound, kin, counted, budget)
    assert budget <= stopped < whole and len(built) < bound.tree.nv
    recursion = scratch_operations(bound, kin, lambda b, k, u: bias.coriolis_by_recursion(b, k, u, True))
    assert recursion < whole  # a 12-link chain: the recursion wins, and the budget (its count) stops the columns
    assert scratch_operations(bound, kin, columns_form, recursion) >= recursion
