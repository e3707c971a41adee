"""Analytical derivatives (issue 17, part 2): d tau/d(q, qd) of inverse dynamics and d qdd/d(q, qd) of forward
dynamics, by forward-mode differentiation of the sweeps, against Pinocchio 4's computeRNEADerivatives and
computeABADerivatives (robots of the suite; floating bases against a Pinocchio tree whose root is six one-axis joints
joined by massless links, since Pinocchio 4.1's derivatives disagree with finite differences on a composite joint;
random URDF trees) and against central differences of the generated functions (YAML models, elastic pairs,
rotors, coupled mimic joints).  The compiled C and the NumPy module are checked on two robots."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import aggsym
from aggsym.contract import select_routines
from aggsym.errors import ModelWarning
from aggsym.twin import NumericTwin
from conftest import model_path
from helpers import coupled_gripper, generated_code, reduction, relative_error, robot_path
from pinocchio_reference import pin, pinocchio_model, pinocchio_q, pinocchio_tree
from random_trees import random_urdf

pytestmark = pytest.mark.pinocchio

TOLERANCE = 1e-9
ROLES = ["inverse_dynamics_derivatives", "forward_dynamics_derivatives"]


def pinocchio_derivatives(pm, Q, v, a, tau):
    """(dtau/dq, dtau/dv) of RNEA at (Q, v, a) and (dqdd/dq, dqdd/dv) of ABA at (Q, v, tau)."""
    data = pm.createData()  # (kept alive: Pinocchio returns references into its Data)
    rnea = [x.copy() for x in pin.computeRNEADerivatives(pm, data, Q, v, a)[:2]]
    data = pm.createData()
    aba = [x.copy() for x in pin.computeABADerivatives(pm, data, Q, v, tau)[:2]]
    return rnea, aba


def compare(model, code, pm, rng, states=3, q_of=None):
    """Worst relative error of code's derivatives against Pinocchio's at random states."""
    q_of = q_of or (lambda q: pinocchio_q(pm, q))
    worst = 0.0
    for _ in range(states):
        q, v, a, tau = (rng.uniform(-1.5, 1.5, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq),
                        rng.normal(size=model.nq))
        (dq, dv), (fq, fv) = pinocchio_derivatives(pm, q_of(q), v, a, tau)
        ours_id = code.inverse_dynamics_derivatives(q, v, a)
        ours_fd = code.forward_dynamics_derivatives(q, v, tau)
        for got, want in zip(ours_id + ours_fd, (dq, dv, fq, fv)):
            worst = max(worst, relative_error(np.reshape(got, want.shape), want, floor=1.0))
    return worst


@pytest.mark.parametrize("name", ["ur5", "panda", "kinova", "double_pendulum", "talos"])
def test_fixed_base_derivatives_equal_pinocchio(name, rng):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(robot_path(name))
    assert compare(model, NumericTwin(model), pinocchio_model(robot_path(name)), rng, states=2) < TOLERANCE


@pytest.mark.parametrize("name", ["solo12", "hyq"])
def test_floating_base_derivatives_equal_pinocchio_with_a_six_joint_root(name, rng):
    """Our Euler root (o1 o2 o3 theta4 theta5 theta6) against Pinocchio's tree of the same model, one joint per
    coordinate (pinocchio_tree: PX, PY, PZ, RX, RY, RZ joined by massless frames)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(robot_path(name), floating_base=True)
    pm, _ = pinocchio_tree(model)
    assert compare(model, NumericTwin(model), pm, rng, states=2, q_of=lambda q: q) < TOLERANCE


@pytest.mark.parametrize("seed", [8, 10, 21, 29])  # trees with A regular (massless leaves in others)
def test_derivatives_of_random_trees_equal_pinocchio(seed, tmp_path):
    path = tmp_path / "tree.urdf"
    path.write_text(random_urdf(seed))
    model = aggsym.load(path)
    pm = pinocchio_model(path)
    twin = NumericTwin(model)
    assert compare(model, twin, pm, np.random.default_rng(seed), states=2) < TOLERANCE


@pytest.fixture(scope="module", params=["ur5", "panda"])
def derivative_code(request, tmp_path_factory):
    name = request.param
    model = select_routines(aggsym.load(robot_path(name)), ROLES + ["inverse_dynamics", "forward_dynamics"])
    lib, module, manifest = generated_code(model, tmp_path_factory.mktemp(name), opt="-O2")
    assert list(manifest["functions"]) == ["inverse_dynamics", "forward_dynamics"] + ROLES
    return model, lib, module, pinocchio_model(robot_path(name))


@pytest.mark.compiler
def test_generated_c_and_numpy_derivatives_equal_pinocchio(derivative_code, rng):
    model, lib, module, pm = derivative_code

    class C:
        def __getattr__(self, role):
            return lambda *args: lib.call(role, *args)

    for code in (C(), module):
        assert compare(model, code, pm, rng) < TOLERANCE


def central_differences(f, x, h=1e-6):
    """Columns d f / d x_j by central differences."""
    return np.stack([(f(x + h * e) - f(x - h * e)) / (2 * h) for e in np.eye(len(x))], axis=-1)


@pytest.mark.parametrize("source", ["manipulator6", "double_pendulum_elastic_stand", "gyroscope", "walking_machine",
                                    "flywheel_on_body", "mimic"])
def test_derivatives_are_the_rates_of_the_dynamics(source, tmp_path, rng):
    """Central differences of the twin's inverse and forward dynamics, on YAML trees (with elastic pairs, rotors
    with a coordinate, a prescribed spin, a free root) and on a gripper whose mimic joints are coupled (no Pinocchio
    reference for those)."""
    if source == "mimic":
        model, _ = coupled_gripper(tmp_path)
    else:
        model = aggsym.load(model_path(source))
    twin = NumericTwin(model)
    q, v, a, tau = (rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq),
                    rng.normal(size=model.nq))
    dq, dv = twin.inverse_dynamics_derivatives(q, v, a)
    assert relative_error(dq, central_differences(lambda x: twin.inverse_dynamics(x, v, a), q), floor=1.0) < 1e-7
    assert relative_error(dv, central_differences(lambda x: twin.inverse_dynamics(q, x, a), v), floor=1.0) < 1e-7
    if source == "mimic":  # forward dynamics' derivatives are not emitted for coupled models
        return
    fq, fv = twin.forward_dynamics_derivatives(q, v, tau)
    assert relative_error(fq, central_differences(lambda x: twin.forward_dynamics(x, v, tau), q), floor=1.0) < 1e-6
    assert relative_error(fv, central_differences(lambda x: twin.forward_dynamics(q, x, tau), v), floor=1.0) < 1e-6


def test_coupled_derivatives_equal_pinocchio(tmp_path, rng):
    """Mimic joints coupled: d tau_q / d q = K^T (d tau / d q_tree) K against Pinocchio's full model."""
    model, path = coupled_gripper(tmp_path)
    pm = pin.buildModelFromUrdf(str(path))
    K, o = reduction(model)
    twin = NumericTwin(model)
    for _ in range(3):
        q, v, a = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        (dq, dv), _ = pinocchio_derivatives(pm, pinocchio_q(pm, K @ q + o), K @ v, K @ a, np.zeros(len(o)))
        ours_q, ours_v = twin.inverse_dynamics_derivatives(q, v, a)
        assert relative_error(ours_q, K.T @ dq @ K, floor=1.0) < TOLERANCE
        assert relative_error(ours_v, K.T @ dv @ K, floor=1.0) < TOLERANCE


@pytest.mark.parametrize("name", ["ur5", "panda", "talos"])
def test_both_ways_of_applying_the_factors_equal_pinocchio(name, rng):
    """dq''/dx = -A^-1 dtau/dx with A^-1 applied by the arguments <t,k> (cauchy_solve, the form emitted on the
    suite's robots) and on the tree without them (cauchy_solve_tree, emitted where its program is smaller): each
    against Pinocchio's computeABADerivatives on the floats, and the straight-line program's choice is the smaller
    count."""
    from aggsym.core.backend import Numeric, Symbolic
    from aggsym.mechanics import derivatives
    from aggsym.mechanics.bound import bind, scratch_operations
    from aggsym.mechanics.kinematics import TreeKinematics

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(robot_path(name))
    pm = pinocchio_model(robot_path(name))
    bound = bind(model, Numeric())
    n = bound.tree.nv
    for _ in range(2):
        q, v, tau = rng.uniform(-1.5, 1.5, model.nq), rng.normal(size=n), rng.normal(size=n)
        _, (fq, fv) = pinocchio_derivatives(pm, pinocchio_q(pm, q), v, np.zeros(n), tau)
        kin = TreeKinematics(bound, list(q))
        for solve in (derivatives._with_arguments, derivatives._on_the_tree):
            got = derivatives._forward_dynamics_derivatives(bound, kin, list(v), list(tau), solve)
            for g, want in zip(got, (fq, fv)):
                assert relative_error(np.array(g, float), want, floor=1.0) < TOLERANCE
    back = Symbolic()
    sym = bind(model, back)
    kin = TreeKinematics(sym, back.program.vector("q", model.nq))

    def count(solve):
        return scratch_operations(sym, kin, lambda b, k, u: [
            [x for row in m for x in row]
            for m in derivatives._forward_dynamics_derivatives(b, k, u, b.backend.program.vector("tau", n), solve)])

    assert count(derivatives._with_arguments) < count(derivatives._on_the_tree)


@pytest.mark.parametrize("robot,base", [("ur5", False), ("solo12", "quaternion")])
def test_one_sweep_per_direction_makes_the_same_operations(robot, base):
    """The dual form's straight-line program of dtau/d(q, qd) is built one dual sweep per direction (so that the C keeps few
    tangents live at a time): its outputs reach exactly as many operations as one sweep of all directions, and
    its entries are those of that sweep at a random state."""
    from aggsym.core.backend import Symbolic
    from aggsym.mechanics.bound import bind
    from aggsym.mechanics.derivatives import inverse_dynamics_derivatives
    from aggsym.mechanics.kinematics import TreeKinematics

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(robot_path(robot), floating_base=base)
    rng = np.random.default_rng(3)
    values = {("q", i): x for i, x in enumerate(rng.normal(size=model.nq))}
    values.update({(k, i): x for k in ("qd", "qdd") for i, x in enumerate(rng.normal(size=model.nv))})
    counts, numbers = [], []
    for by_direction in (False, True):
        backend = Symbolic()
        prog = backend.program
        bound = bind(model, backend)
        kin = TreeKinematics(bound, prog.vector("q", model.nq))
        dq, dqd = inverse_dynamics_derivatives(bound, kin, prog.vector("qd", model.nv), prog.vector("qdd", model.nv),
                                               by_direction=by_direction, form="dual")
        flat = [x for m in (dq, dqd) for row in m for x in row]
        counts.append(sum(1 for i in prog.reachable(flat) if prog.ops[i][0] not in ("in", "neg")))
        numbers.append(np.array([float(x) for x in prog.evaluate(flat, values)]))
    assert counts[0] == counts[1] > 0
    assert np.allclose(numbers[0], numbers[1], rtol=1e-12, atol=1e-12)
