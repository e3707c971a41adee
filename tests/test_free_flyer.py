"""Pinocchio's free-flyer (issue 17, part 5): ``--floating-base quaternion``.

q = (x, y, z, qx, qy, qz, qw, joints) (nq = n + 7), velocities (v, w of the base in its own axes, joint rates)
(nv = n + 6).  Every routine against Pinocchio 4 built with ``buildModelFromUrdf(path, JointModelFreeFlyer())`` on
the same q and v: crba, nonLinearEffects, computeGeneralizedGravity, rnea, aba, computeMinverse, integrate,
computeRNEADerivatives, computeABADerivatives, the frame routines (oMf, LOCAL_WORLD_ALIGNED Jacobians and classical
accelerations), centerOfMass, jacobianCenterOfMass, computeCentroidalMap, computeJointTorqueRegressor and the
energies, on the suite's legged robots and humanoid, an arm on a free base and random URDF trees; the derivatives
also against central differences on the manifold (through our own integrate); the compiled C and the NumPy module
of one robot against Pinocchio; the manifest, header and module constants; the CLI's choices.
"""
from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.contract import ROUTINES, sample_configurations, select_routines
from aggsym.contract.regularity import regularity
from aggsym.errors import ModelWarning
from aggsym.twin import NumericTwin
from helpers import ROBOTS, generated_code, relative_error, robot_path
from pinocchio_reference import pin
from random_trees import random_urdf

pytestmark = pytest.mark.pinocchio

TOLERANCE = 1e-9
LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        return aggsym.load(path, floating_base="quaternion")


def free_flyer(path):
    return pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())


def pinocchio_configuration(pm, q) -> np.ndarray:
    """Pinocchio's q for ours: the free-flyer's seven entries as they are, then every joint (an unbounded revolute
    as (cos, sin)); our joint entries sit one after their velocity index (the quaternion's fourth number)."""
    out = np.zeros(pm.nq)
    for j in range(1, pm.njoints):
        joint = pm.joints[j]
        if joint.shortname() == "JointModelFreeFlyer":
            out[joint.idx_q: joint.idx_q + 7] = q[:7]
            continue
        x = q[joint.idx_v + 1: joint.idx_v + 1 + joint.nv]
        if joint.nq == joint.nv:
            out[joint.idx_q: joint.idx_q + joint.nq] = x
        else:
            out[joint.idx_q: joint.idx_q + 2] = (np.cos(x[0]), np.sin(x[0]))
    return out


def reference(pm, Q, v, a, tau, frames) -> dict:
    """Pinocchio's outputs at (Q, v, a) (tau for aba and its derivatives), in our layouts."""
    d = pm.createData()  # (kept alive: Pinocchio returns references into its Data)
    M = pin.crba(pm, d, Q).copy()
    out = {"inertia": np.triu(M) + np.triu(M, 1).T,
           "nonlinear_effects": pin.nonLinearEffects(pm, d, Q, v).copy(),
           "gravity": pin.computeGeneralizedGravity(pm, d, Q).copy(),
           "inverse_dynamics": pin.rnea(pm, d, Q, v, a).copy(),
           "forward_dynamics": pin.aba(pm, d, Q, v, tau).copy()}
    Minv = pin.computeMinverse(pm, d, Q).copy()
    out["inertia_inverse"] = np.triu(Minv) + np.triu(Minv, 1).T
    pin.computeRNEADerivatives(pm, d, Q, v, a)
    out["inverse_dynamics_derivatives"] = (d.dtau_dq.copy(), d.dtau_dv.copy())
    pin.computeABADerivatives(pm, d, Q, v, tau)
    out["forward_dynamics_derivatives"] = (d.ddq_dq.copy(), d.ddq_dv.copy())
    out["regressor"] = pin.computeJointTorqueRegressor(pm, d, Q, v, a).copy()
    k = pm.createData()
    pin.forwardKinematics(pm, k, Q, v, a)
    pin.updateFramePlacements(pm, k)
    pin.computeJointJacobians(pm, k, Q)
    X, J, acc = [], [], []
    for name in frames:
        fid = pm.getFrameId(name, pin.FrameType.BODY)
        X.append(np.concatenate([k.oMf[fid].translation, k.oMf[fid].rotation.ravel()]))
        J.append(pin.getFrameJacobian(pm, k, fid, LWA).copy())
        acc.append(pin.getFrameClassicalAcceleration(pm, k, fid, LWA).vector.copy())
    out.update(frame_poses=np.array(X), frame_jacobians=np.array(J), frame_accelerations=np.array(acc))
    m = pm.createData()
    out["center_of_mass"] = pin.centerOfMass(pm, m, Q).copy()
    out["com_jacobian"] = pin.jacobianCenterOfMass(pm, m, Q).copy()
    out["centroidal_map"] = pin.computeCentroidalMap(pm, m, Q).copy()
    e = pm.createData()
    out["kinetic_energy"] = np.array([pin.computeKineticEnergy(pm, e, Q, v)])
    out["potential_energy"] = np.array([pin.computePotentialEnergy(pm, e, Q)])
    return out


def inputs(role, q, v, a, tau):
    return {"frame_accelerations": (q, v, a), "inverse_dynamics": (q, v, a), "inverse_dynamics_derivatives": (q, v, a),
            "regressor": (q, v, a), "forward_dynamics": (q, v, tau), "forward_dynamics_derivatives": (q, v, tau),
            "nonlinear_effects": (q, v), "kinetic_energy": (q, v)}.get(role, (q,))


def worst_errors(model, call, pm, rng, states=2, roles=None) -> dict:
    """The largest relative error of every routine of the comparison over random states (those defined only where
    A(q) is regular left out where a joint moves no mass: the generator omits them there too)."""
    frames = [f.name for f in model.frames]
    singular = regularity(model).singular
    worst = {}
    for _ in range(states):
        q = sample_configurations(model, rng)
        v, a, tau = rng.normal(size=model.nv), rng.normal(size=model.nv), rng.normal(size=model.nv)
        theirs = reference(pm, pinocchio_configuration(pm, q), v, a, tau, frames)
        for role, ref in theirs.items():
            if (singular and ROUTINES[role].regular) or (roles is not None and role not in roles):
                continue
            got = call(role, *inputs(role, q, v, a, tau))
            pairs = zip(got, ref) if isinstance(ref, tuple) else [(got, ref)]
            for g, r in pairs:
                g = np.asarray(g).reshape(np.shape(r))
                worst[role] = max(worst.get(role, 0.0), relative_error(g, r, floor=1.0))
    return worst


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_every_routine_equals_pinocchio_free_flyer(name, rng):
    """Every robot of the suite on a free base: the legged robots, the humanoid, the arms, the double pendulum (the
    numeric twin runs the same recursions the generated code is printed from)."""
    model = load(robot_path(name))
    pm = free_flyer(robot_path(name))
    assert model.nv == pm.nv and model.nq == model.nv + 1  # (Pinocchio: (cos, sin) of a continuous joint)
    twin = NumericTwin(model)
    worst = worst_errors(model, twin.call, pm, rng)
    assert len(worst) == 17
    assert max(worst.values()) < TOLERANCE, (name, worst)


@pytest.mark.parametrize("seed", [3, 8, 21])
def test_random_trees_equal_pinocchio_free_flyer(seed, tmp_path):
    path = tmp_path / "tree.urdf"
    path.write_text(random_urdf(seed))
    model = load(path)
    pm = free_flyer(path)
    worst = worst_errors(model, NumericTwin(model).call, pm, np.random.default_rng(seed))
    assert max(worst.values()) < TOLERANCE, (seed, worst)


def test_integrate_equals_pinocchio_and_is_exact_at_zero_rotation(rng):
    model = load(robot_path("solo12"))
    pm = free_flyer(robot_path("solo12"))
    twin = NumericTwin(model)
    for scale in (1.0, 1e-3, 1e-9, 0.0, 5.0):
        q = sample_configurations(model, rng)
        v = rng.normal(size=model.nv) * scale
        for dt in (0.01, 0.7):
            got = twin.integrate(q, v, dt)
            assert np.abs(got - pin.integrate(pm, q, v * dt)).max() < 1e-13, (scale, dt)
            assert abs(np.linalg.norm(got[3:7]) - 1) < 1e-15
    q = sample_configurations(model, rng)
    v = np.zeros(model.nv)
    v[:3] = (0.3, -0.2, 0.5)  # a pure translation of the base: exactly along its axes
    got = twin.integrate(q, v, 2.0)
    R = pin.Quaternion(q[6], *q[3:6]).toRotationMatrix()
    assert np.array_equal(got[3:7], q[3:7] / np.linalg.norm(q[3:7])) or np.abs(got[3:7] - q[3:7]).max() < 1e-16
    assert np.abs(got[:3] - (q[:3] + R @ v[:3] * 2.0)).max() < 1e-15


def test_derivatives_equal_central_differences_on_the_manifold(rng):
    """d tau/dq and d qdd/dq along the tangent directions, by (f(q (+) h e_i) - f(q (+) -h e_i)) / 2h with our own
    integrate; d/dqd by plain differences (h = 1e-5: truncation ~h^2, rounding ~1e-16 |f| / h; the 1e-9 reference
    is Pinocchio above)."""
    model = load(robot_path("solo12"))
    twin = NumericTwin(model)
    q = sample_configurations(model, rng)
    v, a, tau = rng.normal(size=model.nv), rng.normal(size=model.nv), rng.normal(size=model.nv)
    dq, dv = twin.inverse_dynamics_derivatives(q, v, a)
    fq, fv = twin.forward_dynamics_derivatives(q, v, tau)
    h = 1e-5
    for i in range(model.nv):
        e = np.zeros(model.nv)
        e[i] = 1
        plus, minus = twin.integrate(q, e, h), twin.integrate(q, e, -h)
        col = (twin.inverse_dynamics(plus, v, a) - twin.inverse_dynamics(minus, v, a)) / (2 * h)
        assert relative_error(dq[:, i], col, floor=np.abs(dq).max()) < 1e-6, i
        col = (twin.forward_dynamics(plus, v, tau) - twin.forward_dynamics(minus, v, tau)) / (2 * h)
        assert relative_error(fq[:, i], col, floor=np.abs(fq).max()) < 1e-6, i
        col = (twin.inverse_dynamics(q, v + h * e, a) - twin.inverse_dynamics(q, v - h * e, a)) / (2 * h)
        assert relative_error(dv[:, i], col, floor=np.abs(dv).max()) < 1e-6, i
        col = (twin.forward_dynamics(q, v + h * e, tau) - twin.forward_dynamics(q, v - h * e, tau)) / (2 * h)
        assert relative_error(fv[:, i], col, floor=np.abs(fv).max()) < 1e-6, i


@pytest.fixture(scope="module")
def solo_code(tmp_path_factory):
    # the routines compared with Pinocchio, less the derivatives (solo12's are 0.8 MB of C, 50 s to compile; their
    # program is the twin's, compared with Pinocchio above, and its C printing is the other routines')
    compared = ["inertia", "nonlinear_effects", "gravity", "inverse_dynamics", "forward_dynamics", "inertia_inverse",
                "regressor", "frame_poses", "frame_jacobians", "frame_accelerations", "center_of_mass",
                "com_jacobian", "centroidal_map", "kinetic_energy", "potential_energy", "integrate"]
    model = select_routines(load(robot_path("solo12")), compared)
    lib, module, manifest = generated_code(model, tmp_path_factory.mktemp("solo_ff"), opt="-O2")
    return model, lib, module, manifest


@pytest.mark.compiler
def test_generated_c_and_numpy_equal_pinocchio(solo_code, rng):
    model, lib, module, manifest = solo_code
    pm = free_flyer(robot_path("solo12"))
    for call in (lib.call, lambda role, *args: getattr(module, role)(*args)):
        worst = worst_errors(model, call, pm, rng, states=2, roles=manifest["functions"])
        assert len(worst) == 15
        assert max(worst.values()) < TOLERANCE, worst
    q = sample_configurations(model, rng)
    v = rng.normal(size=model.nv)
    for got in (lib.call("integrate", q, v, [0.05]), module.integrate(q, v, 0.05)):
        assert np.abs(got - pin.integrate(pm, q, 0.05 * v)).max() < 1e-13


def test_manifest_header_and_module_describe_positions_and_velocities(solo_code, tmp_path):
    model, _, module, manifest = solo_code
    assert (manifest["nq"], manifest["nv"]) == (19, 18)
    kinds = [c["kind"] for c in manifest["coordinates"]]
    assert kinds[:7] == ["translation"] * 3 + ["quaternion"] * 4 and len(kinds) == 19
    assert [c["name"] for c in manifest["coordinates"][:7]] == ["base_x", "base_y", "base_z", "base_qx", "base_qy",
                                                                 "base_qz", "base_qw"]
    assert [c["name"] for c in manifest["velocities"][:6]] == ["base_vx", "base_vy", "base_vz", "base_wx",
                                                                "base_wy", "base_wz"]
    assert manifest["velocities"][6]["name"] == manifest["coordinates"][7]["name"] == "FL_HAA"
    sig = manifest["signatures"]
    assert sig["inertia"]["input_sizes"]["q"] == 19 and sig["inertia"]["outputs"][0]["shape"] == [18, 18]
    assert sig["integrate"]["inputs"] == ["q", "v", "dt"] and sig["integrate"]["input_sizes"] == {"q": 19, "v": 18,
                                                                                                  "dt": 1}
    assert sig["frame_jacobians"]["outputs"][0]["shape"][-1] == 18
    assert (module.NQ, module.NV) == (19, 18) and module.VELOCITIES[0] == "base_vx"
    assert cli.main(["generate", str(robot_path("solo12")), "--floating-base", "quaternion", "-o", str(tmp_path),
                     "-q"]) == 0
    header = (tmp_path / "solo12.h").read_text()  # (named after solo12.urdf, not its <robot name="solo">)
    assert "#define SOLO12_NQ 19" in header and "#define SOLO12_NV 18" in header
    assert "void solo12_integrate(const double *q, const double *v, const double *dt, double *q_next);" in header
    assert "qd[0]  base_vx" in header
    assert json.loads((tmp_path / "solo12.json").read_text())["functions"]["integrate"] == "solo12_integrate"


def test_fixed_and_euler_bases_keep_their_layout(tmp_path):
    """A bare --floating-base stays the six-coordinate Euler root (nq = nv, no integrate); a fixed base has NV = NQ."""
    assert cli.main(["generate", str(robot_path("ur5")), "--floating-base", "-o", str(tmp_path / "e"), "-q"]) == 0
    euler = json.loads((tmp_path / "e" / "ur5_robot.json").read_text())  # (named after ur5_robot.urdf)
    assert euler["nq"] == euler["nv"] == 12 and "integrate" not in euler["functions"]
    assert euler["coordinates"][3]["name"] == "base_rx"
    assert cli.main(["generate", str(robot_path("ur5")), "--floating-base", "euler", "-o", str(tmp_path / "f"),
                     "-q"]) == 0
    assert json.loads((tmp_path / "f" / "ur5_robot.json").read_text())["nq"] == 12
    assert cli.main(["generate", "--floating-base", str(robot_path("ur5")), "-o", str(tmp_path / "h"), "-q"]) == 0
    assert json.loads((tmp_path / "h" / "ur5_robot.json").read_text())["nq"] == 12  # the path is not read as the kind
    assert cli.main(["generate", str(robot_path("ur5")), "-o", str(tmp_path / "g"), "-q"]) == 0
    assert "#define UR5_ROBOT_NV 6  /* velocities: the length of qd, qdd, tau (= NQ) */" in \
        (tmp_path / "g" / "ur5_robot.h").read_text()


@pytest.mark.parametrize("extra, words", [
    (["--support"], "--support takes the Euler base"),
    (["--mimic", "couple"], "--mimic couple with --floating-base quaternion is not supported"),
])
def test_combinations_that_are_not_supported_are_refused(extra, words, tmp_path, capsys):
    code = cli.main(["generate", str(robot_path("solo12")), "--floating-base", "quaternion", *extra, "-o",
                     str(tmp_path / "out"), "-q"])
    assert code == 2 and words in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_load_rejects_an_unknown_floating_base():
    with pytest.raises(TypeError, match="floating_base must be"):
        aggsym.load(robot_path("ur5"), floating_base="euler-zyx")


@pytest.mark.parametrize("robot, frames, kind", [
    ("solo12", ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"], "point"),
    ("talos", ["left_sole_link", "right_sole_link"], "weld"),
])
def test_contacts_on_a_free_flyer_equal_pinocchio(robot, frames, kind, tmp_path, rng):
    """Feet on the ground (constraints of chapter 4 from a side file): J, gamma, q'' and lambda against the dense KKT
    system of Pinocchio's free-flyer model (crba, nonLinearEffects, LOCAL_WORLD_ALIGNED frame Jacobians and classical
    accelerations)."""
    from aggsym.model.readers.side_files import load_constraints
    from test_constraints import pinocchio_kkt, side_file

    model = load_constraints(side_file(tmp_path, frames, kind), load(robot_path(robot)))
    pm = free_flyer(robot_path(robot))
    twin = NumericTwin(model)
    rows = [0, 1, 2] if kind == "point" else list(range(6))
    for _ in range(2):
        q = sample_configurations(model, rng)
        v, tau = rng.normal(size=model.nv), rng.normal(size=model.nv)
        J, gamma, qdd, lam = pinocchio_kkt(pm, pinocchio_configuration(pm, q), v, tau, frames, rows)
        assert relative_error(twin.constraint_jacobian(q), J) < TOLERANCE
        assert relative_error(twin.constraint_bias(q, v), gamma, floor=1e-9) < TOLERANCE
        ours_qdd, ours_lam = twin.constrained_forward_dynamics(q, v, tau)
        assert relative_error(ours_qdd, qdd) < TOLERANCE
        assert relative_error(ours_lam, lam) < TOLERANCE
