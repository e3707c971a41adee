"""The identification regressor (issue 17, part 3): tau = Y(q, qd, qdd) pi with the 10 standard inertial
parameters per moving body in Pinocchio's order and frames, against Pinocchio 4's computeJointTorqueRegressor
(the compiled C and the NumPy module of every robot of the suite, the floating bases as ``--floating-base`` builds
them, random URDF trees); Y pi equals inverse dynamics with the model's own parameters (robots, every YAML model
that has it, coupled mimic joints); the base parameters: their count is the rank of Pinocchio's stacked regressor
samples, Yb has full column rank and Yb pi_b = tau."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import aggsym
from aggsym.contract import ROUTINES, base_regressor_layout, omitted_routines, regressor_layout, select_routines
from aggsym.errors import ModelWarning
from aggsym.twin import NumericTwin
from conftest import MODELS
from helpers import coupled_gripper, generated_code, reduction, relative_error, robot_path
from pinocchio_reference import pin, pinocchio_model, pinocchio_q
from random_trees import random_urdf

pytestmark = pytest.mark.pinocchio

TOLERANCE = 1e-9


def standard(model) -> np.ndarray:
    """pi of the model, from the manifest's layout (the values of every block)."""
    return np.array([v for block in regressor_layout(model)["blocks"] for v in block["values"].values()], dtype=float)


def base(model) -> np.ndarray:
    """pi_b from the manifest's combinations of standard parameters."""
    layout = regressor_layout(model)
    names = [f"{p}_{b['body']}" for b in layout["blocks"] for p in layout["parameters"]]
    value = dict(zip(names, standard(model)))
    return np.array([sum(c * value[n] for n, c in item["combination"].items())
                     for item in base_regressor_layout(model)["base_parameters"]])


def pinocchio_regressor(pm, q, v, a):
    data = pm.createData()  # (kept alive: Pinocchio returns a reference into its Data)
    return pin.computeJointTorqueRegressor(pm, data, pinocchio_q(pm, q), v, a).copy()


@pytest.fixture(scope="module", params=["ur5", "panda", "kinova", "hyq", "double_pendulum"])
def regressor_code(request, tmp_path_factory):
    """A robot's regressor and base regressor (routines on request: --routines), compiled -O2 with the -Werror
    flags, and its NumPy module."""
    name = request.param
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = select_routines(aggsym.load(robot_path(name)), ["regressor", "base_regressor"])
    lib, module, manifest = generated_code(model, tmp_path_factory.mktemp(name), opt="-O2")
    assert list(manifest["functions"]) == ["regressor", "base_regressor"]
    return name, model, lib, module, pinocchio_model(robot_path(name))


@pytest.mark.compiler
def test_regressor_of_the_generated_c_and_numpy_equals_pinocchio(regressor_code, rng):
    name, model, lib, module, pm = regressor_code
    twin = NumericTwin(model)
    pi = standard(model)
    pi_b = base(model)
    for _ in range(3):
        q, v, a = rng.uniform(-1.5, 1.5, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        theirs = pinocchio_regressor(pm, q, v, a)
        tau = twin.inverse_dynamics(q, v, a)
        for Y, Yb in ((lib.call("regressor", q, v, a), lib.call("base_regressor", q, v, a)),
                      (module.regressor(q, v, a), module.base_regressor(q, v, a))):
            assert relative_error(Y, theirs, floor=1.0) < TOLERANCE, name
            assert relative_error(Y @ pi, tau, floor=1.0) < 1e-12, name
            assert relative_error(Yb @ pi_b, tau, floor=1.0) < 1e-9, name


@pytest.mark.parametrize("name", ["solo12", "hyq", "anymal", "talos"])
def test_floating_base_regressor_and_base_parameters_equal_pinocchio(name, rng):
    """The free root is one block (Pinocchio's composite PX..RZ joint is one joint); the base-parameter count is the
    rank of Pinocchio's stacked regressor at as many random states as we sampled."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(robot_path(name), floating_base=True)
    pm = pinocchio_model(robot_path(name), floating_base=True)
    twin = NumericTwin(model)
    q, v, a = rng.uniform(-1.5, 1.5, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
    assert relative_error(twin.regressor(q, v, a), pinocchio_regressor(pm, q, v, a), floor=1.0) < TOLERANCE
    layout = base_regressor_layout(model)
    stacked = np.vstack([pinocchio_regressor(pm, rng.uniform(-np.pi, np.pi, model.nq), rng.normal(size=model.nq),
                                             rng.normal(size=model.nq)) for _ in range(layout["samples"])])
    assert len(layout["base_parameters"]) == np.linalg.matrix_rank(stacked)
    columns = [item["column"] for item in layout["base_parameters"]]
    assert np.linalg.matrix_rank(stacked[:, columns]) == len(columns)  # Yb (Pinocchio's columns) full column rank
    tau = twin.inverse_dynamics(q, v, a)
    assert relative_error(twin.base_regressor(q, v, a) @ base(model), tau, floor=1.0) < 1e-9


@pytest.mark.parametrize("seed", [3, 8, 21])
def test_regressor_of_random_trees_equals_pinocchio(seed, tmp_path):
    path = tmp_path / "tree.urdf"
    path.write_text(random_urdf(seed))
    model = aggsym.load(path)
    pm = pinocchio_model(path)
    twin = NumericTwin(model)
    rng = np.random.default_rng(seed)
    for _ in range(2):
        q, v, a = rng.uniform(-1.5, 1.5, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        Y = twin.regressor(q, v, a)
        assert relative_error(Y, pinocchio_regressor(pm, q, v, a), floor=1.0) < TOLERANCE
        assert relative_error(Y @ standard(model), twin.inverse_dynamics(q, v, a), floor=1.0) < 1e-12


def test_regressor_with_coupled_mimic_joints(tmp_path, rng):
    """q holds the masters only: Y_q = K^T Y_tree (tau_q = K^T tau_tree), against Pinocchio's full model."""
    model, path = coupled_gripper(tmp_path)
    pm = pin.buildModelFromUrdf(str(path))
    K, o = reduction(model)
    twin = NumericTwin(model)
    for _ in range(3):
        q, v, a = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        Y = twin.regressor(q, v, a)
        theirs = K.T @ pinocchio_regressor(pm, K @ q + o, K @ v, K @ a)
        assert relative_error(Y, theirs, floor=1.0) < TOLERANCE
        assert relative_error(Y @ standard(model), twin.inverse_dynamics(q, v, a), floor=1.0) < 1e-12
    assert "base_regressor" not in [r.role for r in ROUTINES.values() if r.exists_for(model)]


@pytest.mark.parametrize("path", MODELS, ids=lambda p: p.stem)
def test_regressor_times_the_parameters_is_inverse_dynamics_on_every_model(path, rng):
    """Every YAML model: tau = Y pi (and Yb pi_b) where it holds (rotors with a coordinate or a prescribed spin are
    bodies with blocks), and the manifest says why it is left out where it does not (elastic pairs, added masses)."""
    model = select_routines(aggsym.load(path), ["all"])
    omitted = omitted_routines(model)
    if "regressor" in omitted:
        assert any(model_feature in omitted["regressor"] for model_feature in ("elastic", "added masses"))
        assert any(b.pair.elastic or b.added_mass is not None for b in model.bodies)
        return
    twin = NumericTwin(model)
    for _ in range(2):
        q, v, a = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        tau = twin.inverse_dynamics(q, v, a)
        assert relative_error(twin.regressor(q, v, a) @ standard(model), tau, floor=1.0) < 1e-12, path.stem
        assert relative_error(twin.base_regressor(q, v, a) @ base(model), tau, floor=1.0) < 1e-9, path.stem


def test_with_an_armature_tau_is_y_pi_plus_the_armature_term(rng):
    """The armature is no body: tau = Y pi + a qdd (as Pinocchio's regressor leaves model.armature out)."""
    import dataclasses

    model = select_routines(dataclasses.replace(aggsym.load(robot_path("ur5")), armature=0.1), ["regressor"])
    assert omitted_routines(model) == {}
    twin = NumericTwin(model)
    q, v, a = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
    tau = twin.inverse_dynamics(q, v, a)
    assert relative_error(twin.regressor(q, v, a) @ standard(model) + 0.1 * a, tau, floor=1.0) < 1e-12


def test_base_parameters_of_ur5_in_the_manifest():
    """UR5: 36 base parameters (the rank of the stacked regressor), each a combination of standard parameters
    named PARAM_BODY; e.g. the upper arm's first moment along its length lumps the masses the arm carries at its
    end, 0.425 m out (the classical grouping of Khalil and Gautier)."""
    model = aggsym.load(robot_path("ur5"))
    layout = base_regressor_layout(model)
    assert len(layout["base_parameters"]) == 36
    item = next(b for b in layout["base_parameters"] if b["name"] == "mcz_upper_arm_link")
    assert item["combination"] == {"mcz_upper_arm_link": 1.0, "m_forearm_link": 0.425, "m_wrist_1_link": 0.425,
                                   "m_wrist_2_link": 0.425, "m_wrist_3_link": 0.425}
    assert "m_shoulder_link" in layout["unidentifiable"]  # the first link's mass does no work
