"""Rung 4: URDF models against Pinocchio: example-robot-data's robots and random branching trees.

For each file: the coordinates in Pinocchio's order, then on random states A vs ``crba``, b + g vs
``nonLinearEffects``, g vs ``computeGeneralizedGravity`` and inverse dynamics vs ``rnea``, to 1e-9 relative to
the largest entry; fixed base (``pin.buildModelFromUrdf(path)``) and free base (our ``floating_base=True``
against Pinocchio's root PX, PY, PZ, RX, RY, RZ).  Also the URDF link frames (``Body.link_rotation``) against
Pinocchio's frame placements.
"""
import re
import warnings

import numpy as np
import pytest

import aggsym
from aggsym.errors import ModelWarning
from aggsym.model.types import elementary_rotation
from helpers import ROBOTS, robot_path
from pinocchio_reference import pin, compare, joint_names, pinocchio_model, pinocchio_q
from random_trees import random_urdf

pytestmark = pytest.mark.pinocchio

RANDOM_SEEDS = range(25)
FLOATING_SEEDS = range(0, 25, 3)


def load(path, **options):
    """Our model, accepting the dummy-link inertias some robot files have (tested on their own below)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        return aggsym.load(path, **options)


def coordinate_joints(model) -> list:
    return [c.joint for c in model.coordinates]


def write_tree(tmp_path, seed):
    path = tmp_path / f"tree_{seed}.urdf"
    path.write_text(random_urdf(seed))
    return path


def link_poses(model, q) -> dict:
    """World rotation and origin of each body's URDF link frame: forward kinematics over the model's pairs."""
    poses, out = {}, {}
    i = 0
    for body in model.bodies:
        pair = body.pair
        R, p = poses.get(body.parent, (np.eye(3), np.zeros(3)))
        p = p + R @ np.array([float(x) for x in pair.translation])
        R = R @ np.array(pair.constructive_rotation().evalf(), dtype=float)
        values = {}
        for c in pair.coordinates:
            values[c.code] = q[i]
            i += 1
        for k, code in enumerate(("o1", "o2", "o3")):
            p = p + R[:, k] * values.get(code, 0.0)
        for axis, code in ((1, "theta4"), (2, "theta5"), (3, "theta6")):
            R = R @ np.array(elementary_rotation(axis, values.get(code, 0.0)).evalf(), dtype=float)
        poses[body.name] = (R, p)
        lr = np.eye(3) if body.link_rotation is None else np.array(body.link_rotation, dtype=float)
        out[body.name] = (R @ lr, p)
    return out


def check_link_frames(model, pm, rng):
    """Each body's link frame (body frame turned by link_rotation) equals Pinocchio's frame of the URDF link."""
    data = pm.createData()
    q = rng.uniform(-np.pi, np.pi, model.nq)
    pin.framesForwardKinematics(pm, data, pinocchio_q(pm, q))
    ours = link_poses(model, q)
    body_link = {body: link for link, body in model.meta["links"].items()
                 if model.body(body).where == f'<link name="{link}">'}
    for body in model.bodies[1:]:
        frame = data.oMf[pm.getFrameId(body_link[body.name], pin.BODY)]
        R, p = ours[body.name]
        assert np.allclose(R, frame.rotation, atol=1e-9), body.name  # URDF angles within 1e-9 rad of k pi/2 are taken as exact
        assert np.allclose(p, frame.translation, atol=1e-9), body.name


@pytest.mark.parametrize("robot", list(ROBOTS))
def test_robot_against_pinocchio(robot, rng):
    path = robot_path(robot)
    model = load(path)
    pm = pinocchio_model(path)
    assert coordinate_joints(model) == joint_names(pm)
    compare(model, pm, rng, states=3)


def test_talos_reduced_has_32_coordinates():
    model = load(robot_path("talos"))
    assert model.nq == 32 == pinocchio_model(robot_path("talos")).nv


def test_continuous_joints_are_one_angle():
    """kinova's continuous joints: Pinocchio stores (cos, sin), we the angle; velocities agree one to one."""
    model = load(robot_path("kinova"))
    pm = pinocchio_model(robot_path("kinova"))
    assert pm.nq == 9 and pm.nv == model.nq == 6


def test_panda_mimic_is_recorded_and_independent():
    model = load(robot_path("panda"))
    assert model.nq == 9
    assert model.meta["mimic"] == [{"joint": "panda_finger_joint2", "master": "panda_finger_joint1",
                                    "multiplier": 1.0, "offset": 0.0}]


def test_dummy_link_inertias_warn_with_their_lines():
    """hyq's massless-looking dummy links have inertias [[1,1,1]...]e-6: PSD, not physical; we warn, as we load."""
    path = robot_path("hyq")
    with pytest.warns(ModelWarning) as record:
        aggsym.load(path)
    lines = path.read_text().splitlines()
    messages = [str(w.message) for w in record]
    assert any('<link name="base_link"> <inertial> <inertia>' in m and "triangle inequality" in m for m in messages)
    for m in messages:
        line = int(m.split(f"{path}:")[1].split(":")[0])
        assert "<inertia" in lines[line - 1]


@pytest.mark.parametrize("robot", ["solo12", "hyq", "talos"])
def test_floating_base_robot(robot, rng):
    path = robot_path(robot)
    model = load(path, floating_base=True)
    pm = pinocchio_model(path, floating_base=True)
    assert [c.name for c in model.coordinates[:6]] == ["base_x", "base_y", "base_z", "base_rx", "base_ry", "base_rz"]
    assert [c.code for c in model.coordinates[:6]] == ["o1", "o2", "o3", "theta4", "theta5", "theta6"]
    assert coordinate_joints(model)[6:] == joint_names(pm)[6:]
    compare(model, pm, rng, states=2)


@pytest.mark.parametrize("robot", ["panda", "kinova", "talos"])
def test_robot_link_frames(robot, rng):
    path = robot_path(robot)
    check_link_frames(load(path), pinocchio_model(path), rng)


@pytest.mark.parametrize("seed", RANDOM_SEEDS)
def test_random_tree_against_pinocchio(seed, tmp_path, rng):
    path = write_tree(tmp_path, seed)
    model = aggsym.load(path)
    pm = pinocchio_model(path)
    assert coordinate_joints(model) == joint_names(pm)
    compare(model, pm, rng, states=3)
    check_link_frames(model, pm, rng)


@pytest.mark.parametrize("seed", FLOATING_SEEDS)
def test_random_tree_floating_base(seed, tmp_path, rng):
    path = write_tree(tmp_path, seed)
    model = aggsym.load(path, floating_base=True)
    pm = pinocchio_model(path, floating_base=True)
    assert coordinate_joints(model)[6:] == joint_names(pm)[6:]
    compare(model, pm, rng, states=2)


def test_random_trees_cover_the_features(tmp_path):
    """The generator really produces what the comparisons above are meant to exercise."""
    joined = "\n".join(random_urdf(seed) for seed in RANDOM_SEEDS)
    for jtype in ("revolute", "continuous", "prismatic", "fixed"):
        assert f'type="{jtype}"' in joined
    for axis in ("-1.0 0.0 0.0", "0.0 -1.0 0.0", "0.0 0.0 -1.0", "0.0 0.0 2.0"):
        assert f'<axis xyz="{axis}"/>' in joined
    assert '<mass value="0.0"/>' in joined
    assert 'rpy="1.5707963267948966' in joined and 'quat_xyzw=' in joined
    general_axis = merged = branching = reordered = 0
    for seed in range(8):
        model = aggsym.load(write_tree(tmp_path, seed))
        general_axis += sum(b.link_rotation is not None and any(not x.is_Rational for row in b.link_rotation for x in row)
                            for b in model.bodies)
        merged += len(model.meta["links"]) - len(model.bodies)
        parents = [b.parent for b in model.bodies]
        branching += any(parents.count(b.name) > 1 for b in model.bodies)
        joints = coordinate_joints(model)
        reordered += joints != [j for j in file_order(write_tree(tmp_path, seed)) if j in joints]
    assert general_axis and merged and branching >= 4 and reordered >= 4


def file_order(path) -> list:
    """Joint names in the order the file lists them."""
    return re.findall(r'<joint name="([^"]+)"', path.read_text())
