"""Ball joints (issue 33, item 2): the ball pair, a unit quaternion in q and the angular velocity in the child's
axes in qd, anywhere in the tree, from YAML (``type: ball``), URDF (``type="spherical"``) and MJCF (``ball``).

References, each independent of the reader under test:

* Pinocchio's JointModelSpherical, in a model built here from the numbers of the file (the YAML model's through
  ``tests/reference.py``'s float reading, the URDF's from the values written into it): A (crba), b
  (nonLinearEffects - gravity), g, inverse and forward dynamics, A^-1, and the derivatives of inverse and forward
  dynamics (computeRNEADerivatives, computeABADerivatives, in Pinocchio's tangent space) on random states (random
  axes and placements, random unit quaternions, masses from 1e-3 to 1e2), <= 1e-9 relative; integrate against
  pin.integrate, the quaternion unit along a long walk;
* central differences on the manifold (through our own integrate) for the derivatives, and for the Jacobian and
  bias of a loop closed through ball pairs (its constrained forward dynamics against a dense KKT solve);
* MuJoCo itself for an MJCF model with ball joints (mj_fullM, qfrc_bias - qfrc_passive, qacc with contacts and
  limits disabled; ``benchmarks/mjcf/mujoco_reference.py``), <= 1e-9 relative;
* the generated C and NumPy module against the numeric twin (``aggsym check``) and against Pinocchio.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.contract import select_routines
from aggsym.errors import ModelError
from helpers import data_text, generated_code, relative_error, written
from pinocchio_reference import pin
from reference import NumericModel
from robot_builder import chain, root, segment

pytestmark = pytest.mark.pinocchio

TOLERANCE = 1e-9
ROLES = ("inertia", "bias", "gravity", "inverse_dynamics", "forward_dynamics", "inertia_inverse",
         "inverse_dynamics_derivatives", "forward_dynamics_derivatives")

# tests/data/ball_chain.yaml: a hinge, two chained balls below it, a hinge below the balls, a ball on a branch;
# masses over five decades, full inertia tensors, centres off the origins, constructive rotations by arbitrary angles
CHAIN = data_text("ball_chain.yaml")

# tests/data/ball_pendulum.yaml: a ball pair on the world (a spherical pendulum) carrying a hinge
PENDULUM = data_text("ball_pendulum.yaml")

KINDS = {0: pin.JointModelPX, 1: pin.JointModelPY, 2: pin.JointModelPZ, 3: pin.JointModelRX, 4: pin.JointModelRY,
         5: pin.JointModelRZ}


def yaml_model(tmp_path, text, name="model.yaml"):
    return aggsym.load(written(tmp_path / name, text))


def pinocchio_of_yaml(model):
    """Pinocchio's model of a YAML model with one-coordinate and ball pairs, from the float reading of
    ``tests/reference.py``: each pair a joint at SE3(R0, p), a ball pair JointModelSpherical."""
    nm = NumericModel(model)
    pm = pin.Model()
    pm.gravity = pin.Motion(np.concatenate([nm.gravity, np.zeros(3)]))
    joint = []
    for b, body in zip(nm.bodies, model.bodies):
        parent = 0 if b["parent"] < 0 else joint[b["parent"]]
        if body.pair.ball:
            kind = pin.JointModelSpherical()
        else:
            (_, axis), = b["coords"]
            kind = KINDS[axis]()
        joint.append(pm.addJoint(parent, kind, pin.SE3(b["R0"], b["p"]), body.pair.name))
        pm.appendBodyToJoint(joint[-1], pin.Inertia(b["m"], b["c"], b["I"]), pin.SE3.Identity())
    return pm


def random_quaternion(rng) -> np.ndarray:
    x = rng.normal(size=4)
    return x / np.linalg.norm(x)


def random_state(model, rng):
    """q with every quaternion a random unit one (x y z w) and the other coordinates uniform in [-pi, pi]; qd, qdd,
    tau normal."""
    q = rng.uniform(-np.pi, np.pi, model.nq)
    i = 0
    for b in model.bodies:
        n = len(b.pair.positions) if b.pair.quaternion else len(b.pair.coordinates)
        if b.pair.ball:
            q[i:i + 4] = random_quaternion(rng)
        i += n
    return q, rng.normal(size=model.nv), rng.normal(size=model.nv), rng.normal(size=model.nv)


def pinocchio_outputs(pm, q, v, a, tau) -> dict:
    d = pm.createData()
    M = pin.crba(pm, d, q).copy()
    out = {"inertia": np.triu(M) + np.triu(M, 1).T,
           "gravity": pin.computeGeneralizedGravity(pm, d, q).copy()}
    out["bias"] = pin.nonLinearEffects(pm, d, q, v).copy() - out["gravity"]
    out["inverse_dynamics"] = pin.rnea(pm, d, q, v, a).copy()
    out["forward_dynamics"] = pin.aba(pm, d, q, v, tau).copy()
    Minv = pin.computeMinverse(pm, d, q).copy()
    out["inertia_inverse"] = np.triu(Minv) + np.triu(Minv, 1).T
    pin.computeRNEADerivatives(pm, d, q, v, a)
    out["inverse_dynamics_derivatives"] = (d.dtau_dq.copy(), d.dtau_dv.copy())
    pin.computeABADerivatives(pm, d, q, v, tau)
    out["forward_dynamics_derivatives"] = (d.ddq_dq.copy(), d.ddq_dv.copy())
    return out


def arguments(role, q, v, a, tau):
    return {"bias": (q, v), "inverse_dynamics": (q, v, a), "inverse_dynamics_derivatives": (q, v, a),
            "forward_dynamics": (q, v, tau), "forward_dynamics_derivatives": (q, v, tau)}.get(role, (q,))


def worst_errors(model, call, pm, rng, states=3, roles=ROLES) -> dict:
    """The largest relative error (max |ours - theirs| / max |theirs|) of every role over random states."""
    worst = {}
    for _ in range(states):
        q, v, a, tau = random_state(model, rng)
        theirs = pinocchio_outputs(pm, q, v, a, tau)
        for role in roles:
            got, ref = call(role, *arguments(role, q, v, a, tau)), theirs[role]
            for g, r in (zip(got, ref) if isinstance(ref, tuple) else [(got, ref)]):
                g = np.asarray(g, dtype=float).reshape(np.shape(r))
                worst[role] = max(worst.get(role, 0.0), relative_error(g, r))
    return worst


@pytest.mark.parametrize("text", [CHAIN, PENDULUM], ids=["chain", "pendulum"])
def test_yaml_ball_pairs_equal_pinocchio_spherical(text, tmp_path, rng):
    model = yaml_model(tmp_path, text)
    pm = pinocchio_of_yaml(model)
    assert (model.nq, model.nv) == (pm.nq, pm.nv)
    worst = worst_errors(model, aggsym.NumericTwin(model).call, pm, rng, states=4)
    assert len(worst) == len(ROLES)
    assert max(worst.values()) <= TOLERANCE, worst


def test_yaml_names_and_layout(tmp_path):
    model = yaml_model(tmp_path, CHAIN)
    assert model.nq == model.nv + 3 == 14
    names = [n for n, _, _ in model.positions]
    assert names[:6] == ["q_yaw", "hip_qx", "hip_qy", "hip_qz", "hip_qw", "knee_qx"]
    assert [k for _, j, k in model.positions if j == "hip"] == ["quaternion"] * 4
    assert [c.name for c in model.coordinates][:4] == ["q_yaw", "hip_wx", "hip_wy", "hip_wz"]
    q0 = np.array([1.0 if n.endswith("_qw") else 0.0 for n in names])  # every quaternion the identity
    pm = pinocchio_of_yaml(model)
    assert np.array_equal(pin.neutral(pm), q0)
    A = aggsym.NumericTwin(model).inertia(q0)
    assert relative_error(A, pinocchio_outputs(pm, q0, *np.zeros((3, model.nv)))["inertia"]) <= TOLERANCE


# a URDF with spherical joints between revolute joints about random axes, written from the numbers below; its
# Pinocchio model is built from the same numbers (joint placements SE3(rpy, xyz), JointModelRevoluteUnaligned,
# JointModelSpherical, inertias rotated by the inertial origin's rpy)
def urdf_numbers(rng) -> dict:
    links = {}
    for k, name in enumerate(("base", "l1", "l2", "l3", "l4", "l5")):
        m = 10.0 ** (k - 3 + rng.uniform(0, 1))  # 1e-3 .. 1e3
        A = rng.normal(size=(3, 3)) * 0.1
        S = A @ A.T + np.eye(3) * 1e-3  # a second moment of the mass: J = m (tr S E - S) is physical
        J = m * (np.trace(S) * np.eye(3) - S)  # radii of gyration about 0.05 .. 0.3
        links[name] = (m, rng.normal(size=3) * 0.1, rng.uniform(-1, 1, 3), J)
    joints = []  # (name, type, parent, child, xyz, rpy, axis); children of a link in byte order of their names
    for name, jtype, parent, child in (("j1", "revolute", "base", "l1"), ("j2", "spherical", "l1", "l2"),
                                       ("j3", "spherical", "l2", "l3"), ("j4", "revolute", "l3", "l4"),
                                       ("j5", "spherical", "l1", "l5")):
        axis = rng.normal(size=3)
        joints.append((name, jtype, parent, child, rng.uniform(-0.5, 0.5, 3), rng.uniform(-1.5, 1.5, 3),
                       axis / np.linalg.norm(axis) if jtype == "revolute" else None))
    return {"links": links, "joints": joints}


def urdf_text(numbers) -> str:
    def body(name):
        m, c, rpy, J = numbers["links"][name]
        return dict(mass=m, com=c, com_rpy=rpy, inertia=(J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2]))
    return chain("balls", root("base", **body("base")),
                 *(segment(name, child, jtype, parent=parent, xyz=xyz, rpy=rpy, axis=axis,
                           limit=(-1, 1, 1, 1) if jtype == "revolute" else None, **body(child))
                   for name, jtype, parent, child, xyz, rpy, axis in numbers["joints"]), head="")


def pinocchio_of_urdf(numbers):
    pm = pin.Model()
    pm.gravity = pin.Motion(np.array([0.0, 0.0, -9.81, 0.0, 0.0, 0.0]))

    def inertia(link):
        m, c, rpy, J = numbers["links"][link]
        R = pin.rpy.rpyToMatrix(*rpy)
        return pin.Inertia(m, c, R @ J @ R.T)

    joint_of = {"base": 0}
    pm.appendBodyToJoint(0, inertia("base"), pin.SE3.Identity())  # (welded to the world: moves nothing)
    for name, jtype, parent, child, xyz, rpy, axis in sorted(numbers["joints"], key=lambda j: j[0]):
        kind = pin.JointModelSpherical() if jtype == "spherical" else pin.JointModelRevoluteUnaligned(axis)
        joint_of[child] = pm.addJoint(joint_of[parent], kind, pin.SE3(pin.rpy.rpyToMatrix(*rpy), xyz), name)
        pm.appendBodyToJoint(joint_of[child], inertia(child), pin.SE3.Identity())
    return pm


@pytest.mark.parametrize("seed", [4, 11])
def test_urdf_spherical_joints_equal_pinocchio(seed, tmp_path):
    rng = np.random.default_rng(seed)
    numbers = urdf_numbers(rng)
    path = tmp_path / "balls.urdf"
    path.write_text(urdf_text(numbers))
    model = aggsym.load(path)
    pm = pinocchio_of_urdf(numbers)
    assert (model.nq, model.nv) == (pm.nq, pm.nv) == (14, 11)
    assert [c.name for c in model.coordinates] == ["j1", "j2_wx", "j2_wy", "j2_wz", "j3_wx", "j3_wy", "j3_wz", "j4",
                                                   "j5_wx", "j5_wy", "j5_wz"]
    worst = worst_errors(model, aggsym.NumericTwin(model).call, pm, rng)
    assert max(worst.values()) <= TOLERANCE, worst


def test_integrate_keeps_the_quaternion_unit_and_equals_pinocchio(tmp_path, rng):
    """One step against pin.integrate at rotations from 0 to large; 2000 chained steps keep every |quat| within
    4e-16 of 1 (normalized at each step, as the routine says) and stay with Pinocchio's chained steps."""
    model = yaml_model(tmp_path, CHAIN)
    pm = pinocchio_of_yaml(model)
    twin = aggsym.NumericTwin(model)
    quats = [slice(i, i + 4) for i, (n, _, _) in enumerate(model.positions) if n.endswith("_qx")]
    assert len(quats) == 3
    for scale in (0.0, 1e-9, 1e-3, 1.0, 40.0):
        q, v, _, _ = random_state(model, rng)
        for dt in (0.01, 0.7):
            got = twin.integrate(q, v * scale, dt)
            assert np.abs(got - pin.integrate(pm, q, v * scale * dt)).max() < 1e-13, (scale, dt)
            for s in quats:
                assert abs(np.linalg.norm(got[s]) - 1) < 4e-16
    q, _, _, _ = random_state(model, rng)
    theirs = q.copy()
    for _ in range(2000):
        v = rng.normal(size=model.nv) * 5
        q, theirs = twin.integrate(q, v, 0.05), pin.integrate(pm, theirs, v * 0.05)
        assert max(abs(np.linalg.norm(q[s]) - 1) for s in quats) < 4e-16
    assert np.abs(q - theirs).max() < 1e-10
    v = np.zeros(model.nv)
    v[0] = 0.25  # only the hinge moves: the quaternions are kept (to the rounding of their normalization)
    got = twin.integrate(q, v, 2.0)
    assert got[0] == q[0] + 0.5 and np.abs(got[1:] - q[1:]).max() < 1e-16


def test_derivatives_equal_central_differences_on_the_manifold(tmp_path, rng):
    """d tau/dq and d qdd/dq along the tangent directions by (f(q (+) h e_i) - f(q (+) -h e_i)) / 2h through our own
    integrate (h = 1e-5: truncation ~h^2, the 1e-9 reference is Pinocchio above)."""
    model = yaml_model(tmp_path, PENDULUM)
    twin = aggsym.NumericTwin(model)
    q, v, a, tau = random_state(model, rng)
    dq, _ = twin.inverse_dynamics_derivatives(q, v, a)
    fq, _ = twin.forward_dynamics_derivatives(q, v, tau)
    h = 1e-5
    for i in range(model.nv):
        e = np.zeros(model.nv)
        e[i] = 1
        plus, minus = twin.integrate(q, e, h), twin.integrate(q, e, -h)
        col = (twin.inverse_dynamics(plus, v, a) - twin.inverse_dynamics(minus, v, a)) / (2 * h)
        assert relative_error(dq[:, i], col, floor=np.abs(dq).max()) < 1e-7, i
        col = (twin.forward_dynamics(plus, v, tau) - twin.forward_dynamics(minus, v, tau)) / (2 * h)
        assert relative_error(fq[:, i], col, floor=np.abs(fq).max()) < 1e-7, i


def test_a_loop_closed_through_ball_pairs(tmp_path, rng):
    """A point constraint on the tip of two chained ball pairs (a closed loop): its Jacobian against central
    differences of the residual along the tangent directions (through integrate), its bias gamma against the
    central difference of J(q (+) v t) v, and the constrained forward dynamics against a dense KKT solve."""
    text = CHAIN.split("  - name: foot")[0] + """constraints:
  - name: tip
    body: lower
    point: [0, 0, -0.4]
    medium: world
    at: [0.3, 0.2, 0.1]
    block: [o1, o2, o3]
"""
    model = yaml_model(tmp_path, text)
    twin = aggsym.NumericTwin(model)
    q, v, _, tau = random_state(model, rng)
    n, h = model.nv, 1e-6

    def jacobian(x):
        return np.asarray(twin.call("constraint_jacobian", x), dtype=float).reshape(3, n)

    def residual(x):
        return np.asarray(twin.call("constraint_residual", x), dtype=float)

    J = jacobian(q)
    columns = [(residual(twin.integrate(q, e, h)) - residual(twin.integrate(q, e, -h))) / (2 * h) for e in np.eye(n)]
    assert relative_error(J, np.array(columns).T) < 1e-8
    gamma = np.asarray(twin.call("constraint_bias", q, v), dtype=float)
    rate = (jacobian(twin.integrate(q, v, h)) @ v - jacobian(twin.integrate(q, v, -h)) @ v) / (2 * h)
    assert relative_error(gamma, rate) < 1e-7
    qdd = np.asarray(twin.call("constrained_forward_dynamics", q, v, tau)[0], dtype=float)
    A, d = twin.inertia(q), twin.bias(q, v) + twin.gravity(q)
    kkt = np.linalg.solve(np.block([[A, J.T], [J, np.zeros((3, 3))]]), np.concatenate([tau - d, -gamma]))
    assert relative_error(qdd, kkt[:n]) < 1e-12


# tests/data/ballman.xml, an MJCF model: a free torso with a ball hip (armature, damping, anchored off the body
# origin), a hinge knee about a tilted axis, a hinge then a ball in one body, a ball pendulum with a heavy ball bob
MJCF = data_text("ballman.xml")


@pytest.mark.mujoco
def test_mjcf_ball_joints_equal_mujoco(tmp_path):
    pytest.importorskip("mujoco")
    from benchmarks.mjcf.mujoco_reference import compare

    path = tmp_path / "ballman.xml"
    path.write_text(MJCF)
    model = aggsym.load(path)
    assert (model.nq, model.nv) == (25, 20)
    names = [n for n, _, _ in model.positions]
    assert names[7:11] == ["hip_qx", "hip_qy", "hip_qz", "hip_qw"] and names[11:13] == ["knee", "ankle_y"]
    assert [p.name for p in model.parameters][:2] == ["armature_hip_wx", "damping_hip_wx"]
    assert {"joint": "hip", "type": "ball", "body": "thigh", "range": [0.0, math.radians(60)]} in \
        model.meta["mjcf"]["joints"]
    assert model.has_damping  # (so that the comparison includes MuJoCo's qfrc_passive)
    worst = compare(path, model=model, samples=4, seed=3)
    assert max(worst.values()) <= TOLERANCE, worst


def test_mjcf_ball_joint_q_is_mujocos_quaternion_reordered(tmp_path):
    """The quaternion of MuJoCo's qpos (w x y z) is q's (x y z w): the body's world rotation agrees."""
    mujoco = pytest.importorskip("mujoco")
    path = tmp_path / "ballman.xml"
    path.write_text(MJCF)
    model = aggsym.load(path)
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    rng = np.random.default_rng(5)
    j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "pivot")
    a = m.jnt_qposadr[j]
    d.qpos[a:a + 4] = random_quaternion(rng)
    mujoco.mj_kinematics(m, d)
    q = np.array([d.qpos[a + 1], d.qpos[a + 2], d.qpos[a + 3], d.qpos[a]])
    R = pin.Quaternion(q[3], *q[:3]).toRotationMatrix()  # (Eigen's constructor: w, x, y, z)
    body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "pendulum")
    assert np.abs(d.xmat[body].reshape(3, 3) - R).max() < 1e-15  # (the pendulum hangs from the world unturned)
    i = [n for n, _, _ in model.positions].index("pivot_qx")
    assert model.positions[i + 3][0] == "pivot_qw"


@pytest.mark.parametrize("pair, says", [
    ("{name: hip, type: hinge}", "unknown pair type 'hinge'"),
    ("{name: hip, type: ball, functional: {theta4: a}}", "a ball pair takes no 'functional'"),
    ("{name: hip, type: ball, stiffness: [1, 1, 1]}", "a ball pair takes no 'stiffness'"),
])
def test_yaml_ball_mistakes_are_precise_errors(pair, says, tmp_path):
    text = PENDULUM.replace("{name: pivot, type: ball}", pair)
    with pytest.raises(ModelError, match=says):
        yaml_model(tmp_path, text)


def test_yaml_ball_names_clash_with_a_coordinate(tmp_path):
    text = PENDULUM.replace("q_spin", "pivot_wz")
    with pytest.raises(ModelError, match=r"duplicate coordinate name 'pivot_wz' \(also bodies\[0\]\.pair\.type\)"):
        yaml_model(tmp_path, text)


def test_urdf_mimic_couple_with_a_spherical_joint_is_refused(tmp_path):
    numbers = urdf_numbers(np.random.default_rng(4))
    text = urdf_text(numbers).replace('<child link="l4"/>', '<child link="l4"/><mimic joint="j1" multiplier="2"/>')
    path = tmp_path / "balls.urdf"
    path.write_text(text)
    with pytest.raises(ModelError, match="spherical joint is not supported"):
        aggsym.load(path, mimic="couple")


@pytest.mark.compiler
def test_generated_c_and_numpy_equal_pinocchio(tmp_path, rng):
    """The pendulum's C and NumPy module, derivatives included, against Pinocchio; integrate against
    pin.integrate."""
    model = select_routines(yaml_model(tmp_path, PENDULUM), list(ROLES) + ["integrate"])
    lib, module, manifest = generated_code(model, tmp_path / "out")
    assert manifest["nq"] == 5 and [c["kind"] for c in manifest["coordinates"]] == ["quaternion"] * 4 + ["rotation"]
    pm = pinocchio_of_yaml(model)
    for call in (lib.call, lambda role, *args: getattr(module, role)(*args)):
        worst = worst_errors(model, call, pm, rng, states=2)
        assert len(worst) == len(ROLES) and max(worst.values()) <= TOLERANCE, worst
        q, v, _, _ = random_state(model, rng)
        got = np.asarray(call("integrate", q, v, [0.3] if call is lib.call else 0.3))
        assert np.abs(got - pin.integrate(pm, q, 0.3 * v)).max() < 1e-13


@pytest.mark.compiler
def test_check_runs_the_c_and_numpy_targets(tmp_path, capsys):
    path = tmp_path / "ball_pendulum.yaml"
    path.write_text(PENDULUM)
    routines = ",".join(list(ROLES) + ["integrate", "frame_jacobians"])
    assert cli.main(["check", str(path), "--routines", routines, "--targets", "c,numpy", "--trials", "3"]) == 0
    out = capsys.readouterr().out
    for role in ROLES + ("integrate",):
        assert role in out
    assert "ok: every routine within" in out
