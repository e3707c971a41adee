"""Frames for control (issue 17, part 1): frame poses, Jacobians and classical accelerations, the centre of mass,
its Jacobian and the centroidal map, against Pinocchio 4 (``forwardKinematics``, ``updateFramePlacements``,
``getFrameJacobian`` and ``getFrameClassicalAcceleration`` in LOCAL_WORLD_ALIGNED, ``centerOfMass``,
``jacobianCenterOfMass``, ``computeCentroidalMap``) on the suite's robots (fixed base: the compiled C and the
NumPy module; floating base as ``--floating-base`` builds it: the numeric twin), on random URDF trees (every link a
frame) and on a YAML model with declared frames; and the Jacobians against central differences of the poses (also
for coupled mimic joints, which Pinocchio does not model)."""
from __future__ import annotations

import json
import subprocess
import sys
import warnings

import numpy as np
import pytest

import aggsym
from aggsym.errors import AggsymError, ModelWarning
from aggsym.model.transforms.frames import catalog, select_frames
from aggsym.twin import NumericTwin
from conftest import model_path
from helpers import coupled_gripper, generated_code, reduction, relative_error, robot_path
from pinocchio_reference import pin, pinocchio_model, pinocchio_q, pinocchio_tree
from random_trees import random_urdf
from robot_builder import chain, root, segment

pytestmark = pytest.mark.pinocchio

TOLERANCE = 1e-9
LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def reference(pm, Q, v, a, names, frame_type=pin.FrameType.BODY):
    """Pinocchio's frame poses (origin, rotation), Jacobians, classical accelerations, centre of mass, its
    Jacobian and the centroidal map at (Q, v, a), in our layouts."""
    data = pm.createData()
    pin.forwardKinematics(pm, data, Q, v, a)
    pin.updateFramePlacements(pm, data)
    pin.computeJointJacobians(pm, data, Q)
    X, J, acc = [], [], []
    for name in names:
        fid = pm.getFrameId(name, frame_type)
        assert fid < pm.nframes, name
        M = data.oMf[fid]
        X.append(np.concatenate([M.translation, M.rotation.ravel()]))
        J.append(pin.getFrameJacobian(pm, data, fid, LWA))
        acc.append(pin.getFrameClassicalAcceleration(pm, data, fid, LWA).vector)
    mass = pm.createData()  # (kept alive: Pinocchio returns references into its Data)
    com = pin.centerOfMass(pm, mass, Q).copy()
    Jc = pin.jacobianCenterOfMass(pm, mass, Q).copy()
    Ag = pin.computeCentroidalMap(pm, mass, Q).copy()
    return {"frame_poses": np.array(X), "frame_jacobians": np.array(J), "frame_accelerations": np.array(acc),
            "center_of_mass": com, "com_jacobian": Jc, "centroidal_map": Ag}


def ours(code, model, q, v, a):
    """The outputs of a twin, a NumPy module or a C library (``call(role, *inputs)``)."""
    call = code.call if hasattr(code, "call") and not isinstance(code, NumericTwin) else None
    out = {}
    for role, inputs in (("frame_poses", (q,)), ("frame_jacobians", (q,)), ("frame_accelerations", (q, v, a)),
                         ("center_of_mass", (q,)), ("com_jacobian", (q,)), ("centroidal_map", (q,))):
        if role == "centroidal_map" and len(model.bodies[0].pair.coordinates) != 6:
            continue
        out[role] = np.asarray(call(role, *inputs) if call else getattr(code, role)(*inputs))
    return out


def worst_error(model, code, pm, rng, states=3, frame_type=pin.FrameType.BODY) -> dict:
    names = [f.name for f in model.frames]
    worst = {}
    for _ in range(states):
        q, v, a = rng.uniform(-1.5, 1.5, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        theirs = reference(pm, pinocchio_q(pm, q), v, a, names, frame_type)
        for role, value in ours(code, model, q, v, a).items():
            ref = theirs[role].reshape(value.shape)
            worst[role] = max(worst.get(role, 0.0), relative_error(value, ref, floor=1.0))
    return worst


@pytest.mark.compiler
def test_frames_of_the_generated_c_and_numpy_equal_pinocchio(robot_code, rng):
    """Every robot of the suite, fixed base, its default frames (the links without a child: tool flanges, feet,
    fingertips, sensors), through the compiled C and the NumPy module."""
    name, model, lib, module, pm = robot_code
    assert model.frames, name
    for code in (lib, module):
        worst = worst_error(model, code, pm, rng)
        assert set(worst) == {"frame_poses", "frame_jacobians", "frame_accelerations", "center_of_mass",
                              "com_jacobian"}
        assert max(worst.values()) < TOLERANCE, (name, worst)


@pytest.mark.parametrize("name", ["solo12", "hyq", "anymal", "talos"])
def test_floating_base_frames_and_centroidal_map_equal_pinocchio(name, rng):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(robot_path(name), floating_base=True)
    pm = pinocchio_model(robot_path(name), floating_base=True)
    worst = worst_error(model, NumericTwin(model), pm, rng, states=2)
    assert "centroidal_map" in worst
    assert max(worst.values()) < TOLERANCE, (name, worst)


@pytest.mark.parametrize("seed", [3, 8, 21])
@pytest.mark.parametrize("floating", [False, True])
def test_every_link_of_random_trees_equals_pinocchio(seed, floating, tmp_path):
    path = tmp_path / "tree.urdf"
    path.write_text(random_urdf(seed))
    model = aggsym.load(path, floating_base=floating)
    model = select_frames(model, list(catalog(model)))  # every link, merged ones included
    assert len(model.frames) == len(model.links.frames)
    pm = pinocchio_model(path, floating_base=floating)
    worst = worst_error(model, NumericTwin(model), pm, np.random.default_rng(seed), states=2)
    assert max(worst.values()) < TOLERANCE, (seed, floating, worst)


def _declared_frame_pinocchio(model):
    """Pinocchio's tree of a YAML model with its declared frames added as OP frames."""
    pm, joint_of = pinocchio_tree(model)
    index = {b.name: k for k, b in enumerate(model.bodies)}
    for f in model.link_table.declared:
        k = index[f.body]
        body = pm.frames[pm.getFrameId(f.body, pin.FrameType.OP_FRAME)]
        R = np.eye(3)
        for axis, angle in f.rotation:
            c, s = np.cos(float(angle)), np.sin(float(angle))
            e = [np.array([[1, 0, 0], [0, c, -s], [0, s, c]]), np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
                 np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])][axis - 1]
            R = R @ e
        local = pin.SE3(R, np.array([float(x) for x in f.point]))
        pm.addFrame(pin.Frame(f.name, joint_of[k], body.placement * local, pin.FrameType.OP_FRAME))
    return pm


def test_declared_frames_of_a_yaml_model_equal_pinocchio(rng):
    """manipulator6's tool frame (a point on the last link, axes turned by elementary rotations) and its last
    link, through the numeric twin, against Pinocchio's tree of the same model."""
    model = aggsym.load(model_path("manipulator6"))
    assert [f.name for f in model.frames] == ["link6", "tool"]
    pm = _declared_frame_pinocchio(model)
    worst = worst_error(model, NumericTwin(model), pm, rng, frame_type=pin.FrameType.OP_FRAME)
    assert max(worst.values()) < TOLERANCE, worst


def test_centroidal_map_of_a_yaml_spacecraft_equals_pinocchio(rng):
    """The support paper's spacecraft (a free base, a ball-jointed antenna, a 3-link arm) as a YAML tree."""
    model = aggsym.load(model_path("spacecraft"))
    model = select_frames(model, [b.name for b in model.bodies])
    pm, _ = pinocchio_tree(model)
    worst = worst_error(model, NumericTwin(model), pm, rng, frame_type=pin.FrameType.OP_FRAME)
    assert "centroidal_map" in worst
    assert max(worst.values()) < TOLERANCE, worst


def _rotation_rate(R_plus, R_minus, R, h):
    """The angular velocity (world axes) of R along a direction, from central differences: vee(R' R^T)."""
    W = (R_plus - R_minus) / (2 * h) @ R.T
    return np.array([W[2, 1], W[0, 2], W[1, 0]])


def finite_difference_jacobians(twin, q, h=1e-6):
    X = twin.frame_poses(q)
    nf, n = X.shape[0], len(q)
    J = np.zeros((nf, 6, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = h
        Xp, Xm = twin.frame_poses(q + e), twin.frame_poses(q - e)
        for f in range(nf):
            J[f, :3, i] = (Xp[f, :3] - Xm[f, :3]) / (2 * h)
            J[f, 3:, i] = _rotation_rate(Xp[f, 3:].reshape(3, 3), Xm[f, 3:].reshape(3, 3), X[f, 3:].reshape(3, 3),
                                         h)
    return J


def finite_difference_acceleration(twin, q, v, a, h=1e-5):
    """d/dt of the frames' (v, w) along q(t) = q + v t + a t^2/2, by central differences at t = 0: the classical
    acceleration of the origin and the angular acceleration."""
    def twists(t):
        qt, vt = q + v * t + a * t * t / 2, v + a * t
        return np.einsum("fij,j->fi", twin.frame_jacobians(qt), vt)
    return (twists(h) - twists(-h)) / (2 * h)


@pytest.mark.parametrize("source", ["mimic", "manipulator6", "walking_machine"])
def test_jacobians_and_accelerations_are_the_rates_of_the_poses(source, tmp_path, rng):
    """J = d(pose)/dq and a = d/dt (J qd) by central differences: a check that needs no Pinocchio, on a robot with
    mimic joints coupled (Pinocchio does not model them) and on YAML trees."""
    if source == "mimic":
        model, _ = coupled_gripper(tmp_path)
    else:
        model = aggsym.load(model_path(source))
    twin = NumericTwin(model)
    for _ in range(2):
        q, v, a = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        J = twin.frame_jacobians(q)
        assert relative_error(J, finite_difference_jacobians(twin, q), floor=1.0) < 1e-7
        acc = twin.frame_accelerations(q, v, a)
        assert relative_error(acc, finite_difference_acceleration(twin, q, v, a), floor=1.0) < 1e-6
        Jc = twin.com_jacobian(q)
        h = 1e-6
        fd = np.array([(twin.center_of_mass(q + h * e) - twin.center_of_mass(q - h * e)) / (2 * h)
                       for e in np.eye(model.nq)]).T
        assert relative_error(Jc, fd, floor=1.0) < 1e-7


def test_frames_with_coupled_mimic_joints_equal_pinocchio(tmp_path, rng):
    """A gripper whose second finger and fingertip mimic other joints, coupled (q holds only the masters): poses,
    accelerations and the centre of mass at the tree's q_tree = K q + o, Jacobians K-reduced, against Pinocchio's
    full model of the same file."""
    model, path = coupled_gripper(tmp_path)
    model = select_frames(model, ["tip", "right", "palm"])
    pm = pin.buildModelFromUrdf(str(path))
    K, o = reduction(model)
    twin = NumericTwin(model)
    for _ in range(3):
        q, v, a = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        theirs = reference(pm, pinocchio_q(pm, K @ q + o), K @ v, K @ a, ["tip", "right", "palm"])
        assert relative_error(twin.frame_poses(q), theirs["frame_poses"], floor=1.0) < TOLERANCE
        assert relative_error(twin.frame_jacobians(q), theirs["frame_jacobians"] @ K, floor=1.0) < TOLERANCE
        assert relative_error(twin.frame_accelerations(q, v, a), theirs["frame_accelerations"], floor=1.0) < TOLERANCE
        assert relative_error(twin.center_of_mass(q), theirs["center_of_mass"], floor=1.0) < TOLERANCE
        assert relative_error(twin.com_jacobian(q), theirs["com_jacobian"] @ K, floor=1.0) < TOLERANCE


def test_frame_routines_in_the_manifest_and_selected_by_name(tmp_path):
    out = tmp_path / "ur5"
    cmd = [sys.executable, "-m", "aggsym", "generate", str(robot_path("ur5")), "-o", str(out), "-q", "--frames",
           "tool0,shoulder_link, base_link"]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    manifest = json.loads((out / "ur5_robot.json").read_text())  # (named after ur5_robot.urdf)
    assert [f["name"] for f in manifest["frames"]] == ["tool0", "shoulder_link", "base_link"]
    assert manifest["signatures"]["frame_jacobians"]["outputs"] == [{"name": "J", "shape": [3, 6, 6]}]
    assert manifest["layouts"]["frame_poses"]["frames"] == ["tool0", "shoulder_link", "base_link"]
    assert "centroidal_map" not in manifest["functions"]  # fixed base
    header = (out / "ur5_robot.h").read_text()
    assert "UR5_ROBOT_FRAME_POSES_SIZE 36" in header


def test_default_frames():
    model = aggsym.load(robot_path("ur5"))
    assert [f.name for f in model.frames] == ["base", "ee_link", "tool0"]  # the links without a child link
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        solo = aggsym.load(robot_path("solo12"), floating_base=True)
    assert [f.name for f in solo.frames] == ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"]
    walker = aggsym.load(model_path("walking_machine"))
    assert [f.name for f in walker.frames] == [f"shank{i}" for i in range(1, 7)]


def test_unknown_frame_is_a_clear_error(tmp_path):
    model = aggsym.load(robot_path("ur5"))
    with pytest.raises(AggsymError, match="no link named 'hand'"):
        select_frames(model, ["tool0", "hand"])
    with pytest.raises(AggsymError, match="named twice"):
        select_frames(model, ["tool0", "tool0"])
    run = subprocess.run([sys.executable, "-m", "aggsym", "generate", str(robot_path("ur5")), "-o",
                          str(tmp_path / "out"), "--frames", "tool0,nope"], capture_output=True, text=True)
    assert run.returncode == 2
    assert "ur5_robot.urdf: --frames: no link named 'nope'" in run.stderr
    assert "Traceback" not in run.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("frames, where, words", [
    ("[{name: tip, body: nowhere}]", "frames[0].body", "unknown body 'nowhere'"),
    ("[{name: tip, body: b1}, {name: tip, body: b1}]", "frames[1].name", "duplicate frame name 'tip'"),
    ("[{name: b1, body: b1}]", "frames[0].name", "is a body's name"),
    ("[{name: 'a b', body: b1}]", "frames[0].name", "frame name"),
    ("[{name: tip, body: b1, rotation: [[w, 1]]}]", "frames[0].rotation[0][0]", "rotation axis"),
    ("[{name: tip, body: b1, point: [1, 2]}]", "frames[0].point", "3"),
    ("[{name: tip, body: b1, point: [__import__, 0, 0]}]", "frames[0].point[0]", ""),
    ("[{name: tip, body: b1, colour: red}]", "frames[0].colour", "unknown key"),
    ("{name: tip}", "frames", "list"),
])
def test_bad_frames_in_yaml_are_clear_errors(frames, where, words, tmp_path):
    from helpers import assert_model_error
    path = tmp_path / "m.yaml"
    path.write_text("name: m\nbodies:\n  - {name: b1, parent: world, pair: {name: j1, functional: {theta4: q1}}, "
                    f"mass: 1}}\nframes: {frames}\n")
    assert_model_error(path, where, [words] if words else [])


@pytest.mark.compiler
def test_readme_controller_example_compiles_runs_and_tracks(tmp_path):
    """The computed-torque controller of docs/generated-code.md of the UR5, compiled with -Werror against the UR5's generated code: it
    tracks its reference to 1e-4 rad in the second second, and the tool0 position it prints from frame_poses is
    Pinocchio's at the final q it prints."""
    import os
    import re

    from conftest import ROOT
    text = (ROOT / "docs/generated-code.md").read_text()
    source = re.search(r"```c\n(/\* ctc\.c.*?)```", text, re.S).group(1)
    (tmp_path / "ctc.c").write_text(source)
    model = aggsym.load(robot_path("ur5"), name="ur5")  # (as the text says: --name ur5)
    folder = tmp_path / "ur5"
    generated_code(model, folder, c=False)
    exe = tmp_path / "ctc"
    subprocess.run([os.environ.get("CC", "cc"), "-std=c99", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-I",
                    str(folder), str(tmp_path / "ctc.c"), str(folder / "ur5.c"), "-lm", "-o", str(exe)],
                   check=True, capture_output=True, text=True)
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    worst = float(re.search(r"second second: (\S+) rad", out).group(1))
    q = np.array([float(x) for x in re.search(r"q = (.*)", out).group(1).split()])
    tool = np.array([float(x) for x in re.search(r"tool0 = (.*)", out).group(1).split()])
    assert worst < 1e-4
    pm = pinocchio_model(robot_path("ur5"))
    data = pm.createData()
    pin.framesForwardKinematics(pm, data, pinocchio_q(pm, q))
    assert np.abs(tool - data.oMf[pm.getFrameId("tool0", pin.FrameType.BODY)].translation).max() < 1e-8


def test_a_robot_whose_moving_links_are_massless_generates_without_the_mass_routines(tmp_path):
    """Every body that moves is massless: the centre of mass and its Jacobian are left out (they would divide by
    zero) and generation ends in exit 0, not an internal error; the frames are emitted."""
    path = tmp_path / "massless.urdf"
    path.write_text(chain("massless", root("base", mass=1, inertia=(1, 1, 1)),
                          segment("j", "arm", axis="0 0 1", limit=(-1, 1, 1, 1))))
    run = subprocess.run([sys.executable, "-m", "aggsym", "generate", str(path), "-o", str(tmp_path / "out"), "-q",
                          "--routines", "default,regressor,base_regressor"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    manifest = json.loads((tmp_path / "out" / "massless.json").read_text())
    assert "frame_poses" in manifest["functions"] and "center_of_mass" not in manifest["functions"]
    base = manifest["layouts"]["base_regressor"]["base_parameters"]  # the regressor is kinematic: the arm's Izz
    assert [b["name"] for b in base] == ["Izz_arm"]  # can be identified, even though the file gives it 0
