"""Identification with friction and drives (issue 34, item 4): the regressor with joint friction and armature,
tau = Y_f(q, qd, qdd) pi_f with pi_f = (the standard inertial parameters; viscous friction per joint; Coulomb
friction per joint; armature), against the torques of the generated inverse dynamics with URDF joint friction and
--armature (inverse_dynamics - joint_friction) on random states, in the compiled C and the NumPy module; the base
regressor with the recomputed base parameters reproduces them; the rigid columns against Pinocchio's
computeJointTorqueRegressor, the whole against Pinocchio's rnea with model.armature plus its damping and friction.
The base parameters' coefficients are exact (no rounding to a number of digits): a relation of the model's own
doubles comes out as those doubles."""
from __future__ import annotations

import dataclasses
import json
from fractions import Fraction

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.contract import ROUTINES, base_parameters, base_regressor_layout, select_routines
from aggsym.contract.routines_regressor import friction_regressor_layout
from aggsym.twin import NumericTwin
from conftest import model_path
from helpers import generated_code, relative_error, written
from pinocchio_reference import pin, pinocchio_model, pinocchio_q
from robot_builder import rubbing as rubbing_urdf

ARMATURE = 0.05


def arm_urdf(**j2_origin) -> str:
    """The arm of tests/test_joint_friction.py with products of inertia, centres off the axes and damping on j3
    too (j2's origin ``j2_xyz``, ``j2_rpy`` as given)."""
    return rubbing_urdf(a_com="0.1 0.02 0", a_inertia=(0.01, 0.02, 0.03, 0.001, 0, 0), b_com="0.1 0 0.01",
                        b_inertia=(0.015, 0.02, 0.03, 0, 0.0005, 0), j3_damping=0.1, **j2_origin)


URDF = arm_urdf()
ROLES = ["inverse_dynamics", "joint_friction", "regressor", "friction_regressor", "friction_base_regressor"]


@pytest.fixture(scope="module")
def rubbing_path(tmp_path_factory):
    return written(tmp_path_factory.mktemp("urdf") / "rubbing.urdf", URDF)


def rubbing(path, floating_base=None, armature=ARMATURE):
    model = aggsym.load(path, **({"floating_base": floating_base} if floating_base else {}))
    return select_routines(dataclasses.replace(model, armature=armature), ROLES)


def friction_parameters(model) -> np.ndarray:
    """pi_f from the manifest's layout: the blocks' values, then the drives' values."""
    layout = friction_regressor_layout(model)
    return np.array([v for block in layout["blocks"] for v in block["values"].values()]
                    + [d["value"] for d in layout["drives"]], dtype=float)


def base_values(model) -> np.ndarray:
    """pi_b of the friction base regressor from the manifest's combinations."""
    layout = friction_regressor_layout(model)
    names = [f"{p}_{b['body']}" for b in layout["blocks"] for p in layout["parameters"]]
    names += [d["name"] for d in layout["drives"]]
    value = dict(zip(names, friction_parameters(model)))
    return np.array([sum(c * value[n] for n, c in item["combination"].items())
                     for item in base_regressor_layout(model, "friction_regressor")["base_parameters"]])


def states(model, rng, count):
    """Random states; in every other one some rates exactly 0 (sign(0) = 0: no Coulomb force)."""
    for k in range(count):
        qd = rng.normal(size=model.nv)
        if k % 2:
            qd[::2] = 0.0
        yield rng.uniform(-1.5, 1.5, model.nq), qd, rng.normal(size=model.nv)


@pytest.fixture(scope="module")
def rubbing_code(rubbing_path, tmp_path_factory):
    model = rubbing(rubbing_path)
    lib, module, manifest = generated_code(model, tmp_path_factory.mktemp("rubbing"))
    return model, lib, module, manifest


@pytest.mark.compiler
def test_friction_regressor_times_the_parameters_is_the_generated_inverse_dynamics_with_friction(rubbing_code, rng):
    """Y_f pi_f = inverse_dynamics - joint_friction (URDF damping and friction, --armature) in the C and the NumPy
    module, and Yb pi_b the same with the recomputed base parameters."""
    model, lib, module, manifest = rubbing_code
    assert list(manifest["functions"]) == ROLES
    pi = friction_parameters(model)
    pi_b = base_values(model)
    assert len(pi) == manifest["layouts"]["friction_regressor"]["Y"]["shape"][1] == 10 * 3 + 3 * 3
    for q, qd, qdd in states(model, rng, 6):
        for call in (lambda role, *a: lib.call(role, *a), lambda role, *a: getattr(module, role)(*a)):
            tau = call("inverse_dynamics", q, qd, qdd) - call("joint_friction", qd)
            Y = np.asarray(call("friction_regressor", q, qd, qdd))
            assert relative_error(Y @ pi, tau, floor=1.0) < 1e-13
            Yb = np.asarray(call("friction_base_regressor", q, qd, qdd))
            assert relative_error(Yb @ pi_b, tau, floor=1.0) < 1e-12
            assert relative_error(Y[:, :30], np.asarray(call("regressor", q, qd, qdd)), floor=1.0) < 1e-15


def test_the_friction_columns_are_qd_sign_qd_and_qdd_of_each_joint(rubbing_path, rng):
    """Columns 30..38: diag(qd), diag(sign qd) (0 at qd = 0), diag(qdd); named fv_, fc_, ia_ with the model's
    values (the URDF damping and friction as the parameters' expressions, the armature)."""
    model = rubbing(rubbing_path)
    twin = NumericTwin(model)
    q, qd, qdd = rng.normal(size=3), np.array([0.4, 0.0, -2.0]), rng.normal(size=3)
    Y = twin.friction_regressor(q, qd, qdd)
    assert np.array_equal(Y[:, 30:33], np.diag(qd))
    assert np.array_equal(Y[:, 33:36], np.diag([1.0, 0.0, -1.0]))
    assert np.array_equal(Y[:, 36:39], np.diag(qdd))
    drives = friction_regressor_layout(model)["drives"]
    assert [(d["name"], d["column"], d["value"]) for d in drives] == [
        ("fv_j1", 30, 0.7), ("fv_j2", 31, 0.0), ("fv_j3", 32, 0.1), ("fc_j1", 33, 0.2), ("fc_j2", 34, 0.0),
        ("fc_j3", 35, 1.5), ("ia_j1", 36, ARMATURE), ("ia_j2", 37, ARMATURE), ("ia_j3", 38, ARMATURE)]
    assert drives[0]["expression"] == "damping_j1" and drives[5]["expression"] == "friction_j3"


@pytest.mark.pinocchio
def test_against_pinocchio_rnea_with_armature_damping_and_friction(rubbing_path, rng):
    """The rigid columns equal computeJointTorqueRegressor; Y_f pi_f equals Pinocchio's rnea with model.armature,
    plus model.damping qd + model.friction sign(qd) (Pinocchio's values of the same file)."""
    model = rubbing(rubbing_path)
    twin = NumericTwin(model)
    pm = pinocchio_model(rubbing_path)
    pm.armature[:] = ARMATURE
    data = pm.createData()
    pi = friction_parameters(model)
    for q, qd, qdd in states(model, rng, 4):
        Y = twin.friction_regressor(q, qd, qdd)
        Q = pinocchio_q(pm, q)
        theirs = pin.computeJointTorqueRegressor(pm, data, Q, qd, qdd).copy()
        assert relative_error(Y[:, :30], theirs, floor=1.0) < 1e-12
        tau = pin.rnea(pm, data, Q, qd, qdd) + pm.damping * qd + pm.friction * np.sign(qd)
        assert relative_error(Y @ pi, tau, floor=1.0) < 1e-12


def test_base_parameters_group_the_armatures_with_the_links_inertia_about_their_axes(rubbing_path):
    """j1 turns about the vertical through a's origin: its armature and a's Izz are one column, grouped with
    coefficient exactly 1 (OpenSYMORO's ZZ1R = ZZ1 + IA1); likewise j2 turns b (and c, which slides along b's z
    axis) about b's y axis through b's origin: ia_j2, Iyy_b and Iyy_c are one base parameter, each with coefficient
    exactly 1.  A group's name is any of its equal columns: which one the pivoting takes first depends on how the
    processor's matrix-vector products round them (ia_j2 on one host, Iyy_b on another).  Every friction parameter
    and the prismatic j3's armature are identifiable; the relations hold exactly (the model's rotations are right
    angles)."""
    layout = base_regressor_layout(rubbing(rubbing_path), "friction_regressor")
    groups = {b["name"]: b["combination"] for b in layout["base_parameters"]}
    holding = {drive: [name for name, c in groups.items() if drive in c] for drive in ("ia_j1", "ia_j2", "ia_j3")}
    assert holding["ia_j3"] == ["ia_j3"] and len(holding["ia_j1"]) == len(holding["ia_j2"]) == 1
    first = groups[holding["ia_j1"][0]]
    assert first["Izz_a"] == first["ia_j1"] == 1.0
    assert holding["ia_j2"][0] in {"Iyy_b", "Iyy_c", "ia_j2"}
    assert groups[holding["ia_j2"][0]] == {"Iyy_b": 1.0, "Iyy_c": 1.0, "ia_j2": 1.0}
    assert {f"{p}_j{i}" for p in ("fv", "fc") for i in (1, 2, 3)} <= set(groups)
    assert layout["inexact"] == []


def test_base_parameters_are_exact_not_rounded(tmp_path, rng):
    """A link offset of 16 significant digits: b's mass joins a's inertia about j1's axis and j1's armature with
    the square of that offset, the double nearest the exact square of the file's double (rounding beta to 12 digits
    gave another); Y[:, dependent] = Y[:, independent] beta to rounding on random states."""
    length = 0.3141592653589793
    path = tmp_path / "arm.urdf"
    path.write_text(arm_urdf(j2_xyz=f"{length!r} 0 0"))
    model = rubbing(path)
    layout = base_regressor_layout(model, "friction_regressor")
    assert layout["inexact"] == [] and layout["inexact_residual"] == 0.0
    grouped = next(b["combination"] for b in layout["base_parameters"] if "ia_j1" in b["combination"])
    exact = float(Fraction(length) ** 2)
    assert grouped["m_b"] == exact and exact != float(f"{length * length:.12g}")
    independent, dependent, beta, _, _, _ = base_parameters(model, "friction_regressor")
    twin = NumericTwin(model)
    for q, qd, qdd in states(model, rng, 3):
        Y = twin.friction_regressor(q, qd, qdd)
        assert np.abs(Y[:, list(dependent)] - Y[:, list(independent)] @ beta).max() < 1e-13


def test_the_planar_arm_groups_as_the_closed_forms_do():
    """planar_2link (link 0.6 m): ZZ1R = ZZ1 + IA1 + 0.6^2 M2 and MX1R = MX1 + 0.6 M2, every relation exact."""
    model = select_routines(aggsym.load(model_path("planar_2link")), ["friction_regressor"])
    layout = base_regressor_layout(model, "friction_regressor")
    assert layout["inexact"] == []
    grouped = [b["combination"] for b in layout["base_parameters"] if len(b["combination"]) > 1]
    assert {"mcx_link1": 1.0, "m_link2": 0.6} in grouped
    assert {"Izz_link1": 1.0, "m_link2": float(Fraction(0.6) ** 2), "ia_theta1": 1.0} in grouped


def test_inexact_relations_are_named_and_hold_to_rounding(rubbing_path, tmp_path, rng):
    """j2 placed with a constant rotation of 0.3 rad (its cosine and sine rounded doubles): the relation of b's
    first moment cannot hold exactly in the model's numbers; it is named, with its residual on the samples, and
    the base regressor still reproduces the torques."""
    path = tmp_path / "tilted.urdf"
    path.write_text(arm_urdf(j2_rpy="0.3 0 0"))
    model = rubbing(path)
    layout = base_regressor_layout(model, "friction_regressor")
    assert layout["inexact"] == ["mcy_b"] and 0 < layout["inexact_residual"] < 1e-15
    assert base_regressor_layout(rubbing(rubbing_path), "friction_regressor")["inexact"] == []
    twin = NumericTwin(model)
    pi_b = base_values(model)
    for q, qd, qdd in states(model, rng, 3):
        tau = twin.inverse_dynamics(q, qd, qdd) - twin.joint_friction(qd)
        assert relative_error(twin.friction_base_regressor(q, qd, qdd) @ pi_b, tau, floor=1.0) < 1e-12


def test_a_free_root_has_no_friction_columns_and_armature_only_where_given(rubbing_path, rng):
    """Floating base (Pinocchio's free-flyer): friction per joint (3), armature per joint, and on the six free
    coordinates only when the model gives them one (--armature adds it on every coordinate)."""
    for armature, rotors in ((0.0, 3), (ARMATURE, 9)):
        model = rubbing(rubbing_path, floating_base="quaternion", armature=armature)
        twin = NumericTwin(model)
        layout = friction_regressor_layout(model)
        assert layout["Y"]["shape"] == [9, 10 * 4 + 2 * 3 + rotors]
        assert [d["name"] for d in layout["drives"]][:6] == ["fv_j1", "fv_j2", "fv_j3", "fc_j1", "fc_j2", "fc_j3"]
        pi = friction_parameters(model)
        for q, qd, qdd in states(model, rng, 2):
            q = np.concatenate([q[:3], q[3:7] / np.linalg.norm(q[3:7]), q[7:]])
            tau = twin.inverse_dynamics(q, qd, qdd) - twin.joint_friction(qd)
            assert relative_error(twin.friction_regressor(q, qd, qdd) @ pi, tau, floor=1.0) < 1e-12


def test_on_request_through_the_command_line(rubbing_path, tmp_path):
    """--routines friction_regressor,friction_base_regressor: not in the default set; the manifest documents the
    layout and the base parameters; the header's comment gives the column order."""
    assert ROUTINES["friction_regressor"].on_request and ROUTINES["friction_base_regressor"].on_request
    out = tmp_path / "out"
    assert cli.main(["generate", str(rubbing_path), "-o", str(out), "-q", "--armature", "0.05", "--routines",
                     "inverse_dynamics,joint_friction,friction_regressor,friction_base_regressor"]) == 0
    manifest = json.loads((out / "rubbing.json").read_text())
    assert list(manifest["functions"]) == ["inverse_dynamics", "joint_friction", "friction_regressor",
                                           "friction_base_regressor"]
    assert manifest["layouts"]["friction_regressor"]["drives"][6]["name"] == "ia_j1"
    assert "viscous friction" in (out / "rubbing.h").read_text()
    assert cli.main(["generate", str(rubbing_path), "-o", str(tmp_path / "plain"), "-q"]) == 0
    assert "friction_regressor" not in json.loads((tmp_path / "plain" / "rubbing.json").read_text())["functions"]


def test_sign_is_branch_free_and_zero_at_rest_in_jax_and_pytorch(rubbing_path, tmp_path, rng):
    """The Coulomb column is the table's sign in every target: the C calls aggsym_sign (no branch in the routine),
    and the JAX and PyTorch modules equal the NumPy module's, sign(0) = 0 included."""
    jax = pytest.importorskip("jax")
    torch = pytest.importorskip("torch")
    from aggsym.codegen.compile import import_module
    from aggsym.codegen.generate import generate, write

    model = select_routines(rubbing(rubbing_path), ["friction_regressor"])
    write(generate(model, targets=["numpy", "jax", "torch", "manifest", "c"]), tmp_path)
    npm = import_module(tmp_path / "rubbing.py")
    jm = import_module(tmp_path / "rubbing_jax.py")
    tm = import_module(tmp_path / "rubbing_torch.py")
    jax.config.update("jax_enable_x64", True)
    q, qd, qdd = rng.normal(size=(4, 3)), rng.normal(size=(4, 3)), rng.normal(size=(4, 3))
    qd[1] = 0.0
    qd[2, 1] = 0.0
    c = (tmp_path / "rubbing.c").read_text()
    body = c[c.index("void rubbing_friction_regressor("):]
    body = body[:body.index("\n}\n")]
    assert body.count("aggsym_sign(") == 3 and "if" not in body.replace("aggsym_", "")  # one call per joint, no branch
    expected = npm.friction_regressor(q, qd, qdd)
    assert np.array_equal(expected[1][:, 33:36], np.zeros((3, 3)))
    got = np.asarray(jax.jit(jm.friction_regressor)(q, qd, qdd))
    assert np.abs(got - expected).max() < 1e-13
    got = tm.friction_regressor(torch.tensor(q), torch.tensor(qd), torch.tensor(qdd)).numpy()
    assert np.abs(got - expected).max() < 1e-13
