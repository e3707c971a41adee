"""Constraints with the medium and closed loops (issue 16, chapter 4): residual, Jacobian, its rate term, the
Delassus matrix and the constrained forward dynamics.

References: Pinocchio's frame Jacobians (LOCAL_WORLD_ALIGNED), its classical frame accelerations and a dense KKT
solve with its crba and nonLinearEffects, on legged robots standing on point feet and a humanoid on welded feet;
finite differences of phi and J for the identities J qd = d phi/dt and gamma = dJ/dt qd; the KKT residuals; the
dense J A^-1 J^T; energy over time for the four-bar.
"""
import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

import aggsym
from aggsym.model.readers.side_files import load_constraints
from aggsym.twin import NumericTwin
from conftest import model_path
from helpers import consistent_state, generated_code, relative_error, rk4_step, robot_path, run_cli
from pinocchio_reference import pin, crba, pinocchio_model, pinocchio_q

pytestmark = pytest.mark.pinocchio

DATA = Path(__file__).parent / "data"

FEET = {
    "solo12": (["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"], "point"),
    "anymal": (["LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"], "point"),
    "hyq": (["lf_foot", "rf_foot", "lh_foot", "rh_foot"], "point"),
    "talos": (["left_sole_link", "right_sole_link"], "weld"),
}


def side_file(tmp_path, frames, kind, extra="") -> Path:
    path = tmp_path / "constraints.yaml"
    path.write_text("constraints:\n" + "".join(f"  - {{name: c{i}, body: {f}, block: {kind}}}\n"
                                               for i, f in enumerate(frames)) + extra)
    return path


def pinocchio_kkt(pm, Q, v, tau, frames, rows):
    """J (LOCAL_WORLD_ALIGNED frame Jacobians), gamma (classical frame accelerations at a = 0) and the dense KKT
    solution of M a + nle = tau + J^T lam, J a + gamma = 0."""
    data = pm.createData()
    pin.computeJointJacobians(pm, data, Q)
    pin.forwardKinematics(pm, data, Q, v, 0 * v)
    pin.updateFramePlacements(pm, data)
    Js, gs = [], []
    for f in frames:
        fid = pm.getFrameId(f)
        Js.append(pin.getFrameJacobian(pm, data, fid, pin.LOCAL_WORLD_ALIGNED)[rows])
        acc = pin.getFrameClassicalAcceleration(pm, data, fid, pin.LOCAL_WORLD_ALIGNED)
        gs.append(np.concatenate([acc.linear, acc.angular])[rows])
    J, gamma = np.vstack(Js), np.concatenate(gs)
    M = crba(pm, Q)
    nle = pin.nonLinearEffects(pm, pm.createData(), Q, v)
    m = J.shape[0]
    K = np.block([[M, -J.T], [J, np.zeros((m, m))]])
    sol = np.linalg.solve(K, np.concatenate([tau - nle, -gamma]))
    return J, gamma, sol[:pm.nv], sol[pm.nv:]


@pytest.mark.parametrize("robot", sorted(FEET))
def test_legged_robots_on_their_feet_equal_pinocchio(robot, tmp_path):
    frames, kind = FEET[robot]
    path = robot_path(robot)
    model = load_constraints(side_file(tmp_path, frames, kind), aggsym.load(path, floating_base=True))
    assert model.constraint_rows == len(frames) * (3 if kind == "point" else 6)
    pm = pinocchio_model(path, floating_base=True)
    twin = NumericTwin(model)
    rows = [0, 1, 2] if kind == "point" else list(range(6))
    rng = np.random.default_rng(7)
    for _ in range(3):
        q, v, tau = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        J, gamma, qdd, lam = pinocchio_kkt(pm, pinocchio_q(pm, q), v, tau, frames, rows)
        assert relative_error(twin.constraint_jacobian(q), J) < 1e-10
        assert relative_error(twin.constraint_bias(q, v), gamma, floor=1e-9) < 1e-10
        ours_qdd, ours_lam = twin.constrained_forward_dynamics(q, v, tau)
        assert relative_error(ours_qdd, qdd) < 1e-9
        assert relative_error(ours_lam, lam) < 1e-9
        A = twin.inertia(q)
        assert relative_error(twin.delassus(q), J @ np.linalg.solve(A, J.T)) < 1e-10


def loop_model():
    return aggsym.load(DATA / "constrained_quadruped.yaml")


def test_identities_of_a_model_with_a_loop_a_rotated_reference_and_mixed_rows():
    model = loop_model()
    twin = NumericTwin(model)
    rng = np.random.default_rng(3)
    h = 1e-6
    zero = np.zeros(model.nq)
    for trial in range(4):
        q = zero if trial == 0 else rng.uniform(-1, 1, model.nq)
        qd, tau = rng.normal(size=model.nq), rng.normal(size=model.nq)
        J = twin.constraint_jacobian(q)
        rate = (twin.constraint_residual(q + h * qd) - twin.constraint_residual(q - h * qd)) / (2 * h)
        # every row at q = 0 (phi's rotational rows are zero there), the translational rows everywhere
        rows = range(model.constraint_rows) if trial == 0 else [0, 1, 2, 3, 5]
        assert np.abs(rate - J @ qd)[list(rows)].max() < 1e-8 * max(1.0, np.abs(J @ qd).max())
        Jdot = (twin.constraint_jacobian(q + h * qd) - twin.constraint_jacobian(q - h * qd)) / (2 * h)
        assert relative_error(twin.constraint_bias(q, qd), Jdot @ qd, floor=1.0) < 1e-8
        stab = dataclasses.replace(model, stabilization=(0, 0))
        plain = NumericTwin(stab)
        qdd, lam = plain.constrained_forward_dynamics(q, qd, tau)
        A, d = plain.inertia(q), plain.nonlinear_effects(q, qd)
        scale = np.abs(tau).max() + np.abs(d).max()
        assert np.abs(A @ qdd + d - tau - J.T @ lam).max() < 1e-12 * scale
        gamma = plain.constraint_bias(q, qd)
        assert np.abs(J @ qdd + gamma).max() < 1e-12 * max(1.0, np.abs(gamma).max(), np.abs(J).max())
        assert relative_error(plain.delassus(q), J @ np.linalg.solve(A, J.T)) < 1e-12
        # with the Baumgarte terms of the model (kp = 4, kd = 3)
        qdd, lam = twin.constrained_forward_dynamics(q, qd, tau)
        phi = twin.constraint_residual(q)
        assert np.abs(J @ qdd + gamma + 3 * (J @ qd) + 4 * phi).max() < 1e-11 * max(1.0, np.abs(gamma).max())
    assert np.abs(twin.constraint_residual(zero)[[0, 1, 2, 3, 4]]).max() < 1e-15  # default attachments


@pytest.mark.compiler
def test_the_generated_c_and_numpy_equal_the_twin(tmp_path):
    model = loop_model()
    lib, module, manifest = generated_code(model, tmp_path, opt="-O2")
    twin = NumericTwin(model)
    rng = np.random.default_rng(5)
    for _ in range(5):
        q, qd, tau = rng.uniform(-2, 2, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        for role, args in [("constraint_residual", (q,)), ("constraint_jacobian", (q,)),
                           ("constraint_bias", (q, qd)), ("delassus", (q,)),
                           ("constrained_forward_dynamics", (q, qd, tau))]:
            want = twin.call(role, *args)
            tol = 1e-12 * (np.linalg.cond(twin.delassus(q)) if role == "constrained_forward_dynamics" else 1)
            for got in (lib.call(role, *args), getattr(module, role)(*args)):
                for a, b in zip(got if isinstance(got, tuple) else (got,), want if isinstance(want, tuple) else (want,)):
                    assert relative_error(np.reshape(a, np.shape(b)), b) < tol, role
    entry = manifest["constraints"]
    assert [c["name"] for c in entry["constraints"]] == ["foot", "skid", "loop"]
    assert [c["lambda"] for c in entry["constraints"]] == [[0, 3], [3, 5], [5, 7]]
    assert entry["constraints"][1]["rows"] == ["o3", "theta4"]
    assert manifest["signatures"]["constrained_forward_dynamics"]["returns"].startswith("int")
    assert manifest["layouts"]["constraint_jacobian"]["rows"][:4] == ["foot.o1", "foot.o2", "foot.o3", "skid.o3"]
    header = (tmp_path / "constrained_quadruped.h").read_text()
    assert "int constrained_quadruped_constrained_forward_dynamics(const double *q, const double *qd, " \
           "const double *tau, const double *p, double *qdd, double *lambda);" in header
    # a batch through NumPy: (qdd, lambda) per state
    Q, QD, TAU = rng.normal(size=(4, model.nq)), rng.normal(size=(4, model.nq)), rng.normal(size=(4, model.nq))
    qdd, lam = module.constrained_forward_dynamics(Q, QD, TAU)
    assert qdd.shape == (4, model.nq) and lam.shape == (4, 7)
    assert relative_error(lam[2], twin.constrained_forward_dynamics(Q[2], QD[2], TAU[2])[1]) < 1e-12


@pytest.mark.compiler
def test_singular_constraints_return_nonzero_in_c_and_raise_in_numpy(tmp_path):
    """At q = 0 the four-bar is at a dead centre (every link along x): the pin's o1 row of J vanishes, J A^-1 J^T
    is singular there and only there."""
    model = aggsym.load(model_path("four_bar"))
    lib, module, _ = generated_code(model, tmp_path, opt="-O1")
    p = np.array([0.1, 0.3, 0.25, 0.3])
    q_dead = np.array([0.0, 0.0, 0.0])
    J = module.constraint_jacobian(q_dead, p)
    assert np.linalg.matrix_rank(J) < 2
    with pytest.raises(np.linalg.LinAlgError, match=r"states \(1,\)"):
        module.constrained_forward_dynamics(np.stack([q_dead + 0.3, q_dead]), np.zeros((2, 3)), np.zeros((2, 3)), p)
    with pytest.raises(np.linalg.LinAlgError, match="at the state$"):  # one state, not a batch
        module.constrained_forward_dynamics(q_dead, np.zeros(3), np.zeros(3), p)
    with pytest.raises(np.linalg.LinAlgError):
        lib.call("constrained_forward_dynamics", q_dead, np.zeros(3), np.zeros(3))
    nan = np.array([np.nan, 0.3, 0.3])  # a NaN in the state is a failure too, in C as in NumPy
    with pytest.raises(np.linalg.LinAlgError):
        lib.call("constrained_forward_dynamics", nan, np.zeros(3), np.zeros(3))
    with pytest.raises(np.linalg.LinAlgError):
        module.constrained_forward_dynamics(nan, np.zeros(3), np.zeros(3), p)


def test_the_four_bar_conserves_energy_and_stays_closed(tmp_path):
    model = aggsym.load(model_path("four_bar"))
    plain = dataclasses.replace(model, stabilization=(0, 0))
    _, module, _ = generated_code(plain, tmp_path / "plain", c=False)
    _, stabilized, _ = generated_code(model, tmp_path / "stab", c=False)
    twin = NumericTwin(model)
    q, qd = consistent_state(twin, np.array([1.2, -0.9, 2.0]), np.array([2.0, 0.0, 0.0]))
    zero = np.zeros(3)

    def energy(q, qd):
        return module.kinetic_energy(q, qd) + module.potential_energy(q)

    for mod, name in ((module, "plain"), (stabilized, "stabilized")):
        x, v = q.copy(), qd.copy()
        e0 = energy(x, v)
        for _ in range(1000):
            x, v = rk4_step(lambda a, b: mod.constrained_forward_dynamics(a, b, zero)[0], x, v, 1e-3)
        drift = np.abs(mod.constraint_residual(x)).max()
        assert abs(energy(x, v) - e0) < 1e-8 * abs(e0), name
        assert drift < (1e-8 if name == "stabilized" else 1e-6), (name, drift)


# --------------------------------------------------------------------------------------------------------------
# the model format: bad input is exit 2 with the place

BASE = (DATA / "constrained_quadruped.yaml").read_text().split("constraints:")[0]
BAD = {
    "contacts_key": ("contacts: [{name: a}]\n", "contacts", ["'constraints'"]),
    "loops_key": ("loops: [{name: a}]\n", "loops", ["'constraints'"]),
    "unknown_body": ("constraints: [{name: a, body: hand, block: point}]\n", "constraints[0].body",
                     ["unknown body 'hand'"]),
    "world_body": ("constraints: [{name: a, body: world, block: point}]\n", "constraints[0].body", ["unknown body"]),
    "self_loop": ("constraints: [{name: a, body: shin, medium: shin, block: point}]\n", "constraints[0].medium",
                  ["the constrained body itself"]),
    "unknown_medium": ("constraints: [{name: a, body: shin, medium: floor, block: point}]\n",
                       "constraints[0].medium", ["unknown medium 'floor'"]),
    "unknown_kind": ("constraints: [{name: a, body: shin, block: glue}]\n", "constraints[0].block",
                     ["unknown constraint kind 'glue'", "weld"]),
    "rolling": ("constraints: [{name: a, body: shin, block: rolling}]\n", "constraints[0]", ["needs 'wheel"]),
    "friction_on_a_point": ("constraints: [{name: a, body: shin, block: point, friction: {viscous: 1}}]\n",
                            "constraints[0].friction", ["blocks all three"]),
    "coulomb_two_normals": ("constraints: [{name: a, body: shin, block: [o1, o3], friction: {coulomb: 0.5}}]\n",
                            "constraints[0].friction.coulomb", ["exactly one blocked translation", "o1, o3"]),
    "coulomb_no_normal": ("constraints: [{name: a, body: shin, block: [theta4], friction: {coulomb: 0.5}}]\n",
                          "constraints[0].friction.coulomb", ["exactly one blocked translation", "none"]),
    "negative_friction": ("constraints: [{name: a, body: shin, block: normal, friction: {viscous: -2}}]\n",
                          "constraints[0].friction.viscous", ["must not be negative"]),
    "two_laws": ("constraints: [{name: a, body: shin, block: normal, friction: {viscous: 1, coulomb: 1}}]\n",
                 "constraints[0].friction", ["one friction law"]),
    "unknown_law": ("constraints: [{name: a, body: shin, block: normal, friction: {stribeck: 1}}]\n",
                    "constraints[0].friction.stribeck", ["unknown key", "coulomb, viscous"]),
    "friction_code": ("constraints: [{name: a, body: shin, block: normal, friction: {coulomb: 'exp(__import__)'}}]\n",
                      "constraints[0].friction.coulomb", ["__import__"]),
    "duplicate": ("constraints: [{name: a, body: shin, block: point}, {name: a, body: leg, block: point}]\n",
                  "constraints[1].name", ["duplicate constraint name 'a'"]),
    "bad_name": ("constraints: [{name: 'a b', body: shin, block: point}]\n", "constraints[0].name",
                 ["constraint name"]),
    "empty_block": ("constraints: [{name: a, body: shin, block: []}]\n", "constraints[0].block", ["at least one"]),
    "twice": ("constraints: [{name: a, body: shin, block: [o1, o1]}]\n", "constraints[0].block[1]",
              ["listed twice"]),
    "bad_code": ("constraints: [{name: a, body: shin, block: [o4]}]\n", "constraints[0].block[0]", ["o1, o2"]),
    "point_length": ("constraints: [{name: a, body: shin, point: [0, 1], block: point}]\n", "constraints[0].point",
                     ["expected 3 entries"]),
    "point_expression": ("constraints: [{name: a, body: shin, point: [0, 'os.system(1)', 0], block: point}]\n",
                         "constraints[0].point[1]", ["unexpected character"]),
    "missing_block": ("constraints: [{name: a, body: shin}]\n", "constraints[0]", ["missing field 'block'"]),
    "unknown_key": ("constraints: [{name: a, body: shin, block: point, stiff: 1}]\n", "constraints[0].stiff",
                    ["unknown key"]),
    "negative_gain": ("constraints: [{name: a, body: shin, block: point}]\nstabilization: {kp: -1}\n",
                      "stabilization.kp", ["must not be negative"]),
    "gain_alone": ("stabilization: {kp: 1}\n", "stabilization", ["no constraints"]),
    "not_a_list": ("constraints: {name: a}\n", "constraints", ["expected a list"]),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_constraints_are_reported_with_the_place(case, tmp_path):
    text, where, words = BAD[case]
    path = tmp_path / f"{case}.yaml"
    path.write_text(BASE + text)
    with pytest.raises(aggsym.ModelError) as info:
        aggsym.load(path)
    err = info.value
    assert err.where == where, str(err)
    assert err.line is not None, str(err)
    for w in words:
        assert w in str(err), str(err)


def test_redundant_rows_are_an_error_with_a_hint(tmp_path):
    text = model_path("four_bar").read_text().replace("block: [o1, o2]", "block: point")
    path = tmp_path / "four_bar.yaml"
    path.write_text(text)
    code, err = run_cli(["generate", str(path), "-o", str(tmp_path / "out"), "-q"])
    assert code == 2 and "constraints[0]" in err and "o3" in err and "[o1, o2]" in err, err
    assert not (tmp_path / "out").exists()


def test_redundancy_is_found_when_the_dependent_row_changes_with_q(tmp_path):
    """J = [[0, -sin q1], [0, cos q1]] (a revolute about e2 carried by a revolute about e3; theta4 and theta5 of
    the outer body blocked) has rank 1 everywhere, but which row a scan in order finds dependent changes: theta4
    at q = 0 (a zero row), theta5 elsewhere.  The check calls it redundant all the same."""
    path = tmp_path / "turning.yaml"
    path.write_text("name: turning\ngravity: [0, 0, -9.81]\nbodies:\n"
                    "  - {name: b1, parent: world, pair: {functional: {theta6: q1}}, mass: 1, "
                    "inertia: {xx: 1, yy: 1, zz: 1}}\n"
                    "  - {name: b2, parent: b1, pair: {translation: [0, 0, 1], functional: {theta5: q2}}, mass: 1, "
                    "com: [0.1, 0, 0], inertia: {xx: 1, yy: 2, zz: 3}}\n"
                    "constraints:\n  - {name: c, body: b2, block: [theta4, theta5]}\n")
    code, err = run_cli(["generate", str(path), "-o", str(tmp_path / "out"), "-q"])
    assert code == 2 and "constraints[0]" in err and "row(s) theta5 depend" in err, err
    assert not (tmp_path / "out").exists()


def test_an_explicit_regularization_allows_redundant_rows(tmp_path):
    """The four-bar closed by a full point (its o3 row is zero: redundant) with regularization: 1e-10 generates,
    and its qdd is the one of the independent rows [o1, o2]: (G + eps E) lambda = rhs gives lambda_o3 = 0."""
    text = model_path("four_bar").read_text().replace("block: [o1, o2]", "block: point")
    path = tmp_path / "four_bar.yaml"
    path.write_text(text + "regularization: 1e-10\n")
    model = aggsym.load(path)
    _, regular, manifest = generated_code(model, tmp_path / "reg", c=False)
    assert manifest["constraints"]["regularization"] == "1.00000000000000e-10"
    _, plain, _ = generated_code(aggsym.load(model_path("four_bar")), tmp_path / "plain", c=False)
    q, qd, tau = np.array([1.2, -0.9, 2.0]), np.array([0.3, -0.2, 0.5]), np.array([0.1, 0.0, -0.2])
    qdd, lam = regular.constrained_forward_dynamics(q, qd, tau)
    ref, ref_lam = plain.constrained_forward_dynamics(q, qd, tau)
    assert np.abs(qdd - ref).max() <= 1e-6 * np.abs(ref).max() and abs(lam[2]) <= 1e-12
    assert np.abs(lam[:2] - ref_lam).max() <= 1e-6 * np.abs(ref_lam).max()
    path.write_text(text + "regularization: -1\n")
    with pytest.raises(aggsym.ModelError, match="must not be negative"):
        aggsym.load(path)


def test_a_urdf_side_file_names_links_and_is_checked(tmp_path):
    urdf = robot_path("solo12")
    out = tmp_path / "out"
    bad = side_file(tmp_path, ["FL_FOOT", "NO_SUCH_LINK"], "point")
    code, err = run_cli(["generate", str(urdf), "--floating-base", "--constraints", str(bad), "-o", str(out), "-q"])
    assert code == 2 and f"{bad}:3:" in err and "constraints[1].body" in err and "NO_SUCH_LINK" in err, err
    assert not out.exists()
    code, err = run_cli(["generate", str(model_path("four_bar")), "--constraints", str(bad), "-o", str(out)])
    assert code == 2 and "(URDF, xacro and MJCF models only" in err
    good = side_file(tmp_path, FEET["solo12"][0], "point", extra="stabilization: {kp: 10, kd: 5}\n")
    code, err = run_cli(["generate", str(urdf), "--floating-base", "--constraints", str(good), "-o", str(out), "-q"])
    assert code == 0, err
    manifest = json.loads((out / "solo12.json").read_text())  # (named after solo12.urdf)
    assert [c["link"] for c in manifest["constraints"]["constraints"]] == FEET["solo12"][0]
    assert manifest["constraints"]["m"] == 12 and manifest["constraints"]["stabilization"] == {"kp": "10", "kd": "5"}
