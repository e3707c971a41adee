"""URDF <dynamics damping friction> as the routine joint_friction and <limit> in the manifest (issue 15, point 7):
tau_f,i = -d_i qd_i - f_i sign(qd_i), a generalized force on the right side, with d_i and f_i runtime parameters
damping_<joint> and friction_<joint> appended to p in joint order; defaults equal Pinocchio's model.damping and
model.friction of the same file."""
import numpy as np
import pytest

import aggsym
from helpers import generated_code, robot_path, written
from pinocchio_reference import pinocchio_model
from robot_builder import rubbing as rubbing_urdf

pytestmark = pytest.mark.pinocchio



@pytest.fixture
def rubbing(tmp_path):
    return written(tmp_path / "rubbing.urdf", rubbing_urdf())


@pytest.mark.compiler
def test_friction_parameters_and_routine(rubbing, tmp_path, rng):
    model = aggsym.load(rubbing)
    names = [p.name for p in model.parameters]
    assert names == ["damping_j1", "friction_j1", "damping_j3", "friction_j3"]
    assert [p.value for p in model.parameters] == [0.7, 0.2, 0.0, 1.5]
    pm = pinocchio_model(rubbing)
    assert np.allclose(pm.damping, [0.7, 0.0, 0.0]) and np.allclose(pm.friction, [0.2, 0.0, 1.5])
    lib, module, manifest = generated_code(model, tmp_path / "out")
    assert manifest["signatures"]["joint_friction"]["inputs"] == ["qd", "p"]
    for qd in (rng.normal(size=3), np.array([0.0, 1.0, -2.0])):
        expected = -pm.damping * qd - pm.friction * np.sign(qd)
        assert np.allclose(lib.call("joint_friction", qd), expected, rtol=1e-14, atol=0)
        assert np.allclose(module.joint_friction(qd), expected, rtol=1e-14, atol=0)
    p = np.array([1.0, 0.5, 2.0, 3.0])  # changed at run time
    qd = np.array([0.3, -0.2, -0.1])
    assert np.allclose(lib.call("joint_friction", qd, p=p), [-0.3 - 0.5, 0.0, -2.0 * -0.1 + 3.0])
    assert np.allclose(module.joint_friction(np.array([qd, qd]), p)[1], [-0.8, 0.0, 3.2])


def test_limits_in_the_manifest(rubbing, tmp_path):
    _, _, manifest = generated_code(aggsym.load(rubbing), tmp_path / "out", c=False)
    assert manifest["limits"] == [
        {"lower": -2.0, "upper": 2.5, "velocity": 4.0, "effort": 30.0},
        {"lower": None, "upper": None, "velocity": None, "effort": None},
        {"lower": 0.0, "upper": 0.3, "velocity": 0.5, "effort": 100.0}]


def test_yaml_models_have_no_friction_routine_and_null_limits(tmp_path):
    from conftest import model_path

    model = aggsym.load(model_path("planar_2link"))
    _, _, manifest = generated_code(model, tmp_path, c=False)
    assert "joint_friction" not in manifest["functions"]
    assert manifest["limits"] == [{"lower": None, "upper": None, "velocity": None, "effort": None}] * model.nq


def test_a_real_robots_friction_equals_pinocchios(rng):
    model = aggsym.load(robot_path("panda"))
    pm = pinocchio_model(robot_path("panda"))
    qd = rng.normal(size=model.nq)
    got = aggsym.NumericTwin(model).joint_friction(qd)
    assert np.allclose(got, -pm.damping * qd - pm.friction * np.sign(qd), rtol=1e-14, atol=0)
