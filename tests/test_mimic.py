"""URDF <mimic> joints coupled to their masters (mimic="couple") against Pinocchio's models with mimic=True:
A vs crba, tau vs rnea, d vs nonLinearEffects, g vs computeGeneralizedGravity; q'' against A_q q'' = tau - d
(Pinocchio's aba does not take mimic joints) and A_q^-1 against inv(crba); through the numeric twin, the
generated C and the NumPy module."""
import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.codegen.compile import CLibrary, compile_shared, import_module
from aggsym.codegen.generate import generate, write
from aggsym.errors import ModelError
from helpers import GRIPPER, reduction, relative_error, written
from pinocchio_reference import pin, inertia_rate, pinocchio_q
from random_trees import random_urdf

pytestmark = pytest.mark.pinocchio

TOLERANCE = 1e-9


def with_mimics(seed: int) -> str:
    """A random tree of tests/random_trees.py with two of its revolute or prismatic joints made to mimic a third
    that comes before them in Pinocchio's order (Pinocchio's requirements: a mimicked joint already in the tree,
    and configuration spaces of one size, so no continuous joint)."""
    root = ET.fromstring(random_urdf(seed))
    pm = pin.buildModelFromXML(ET.tostring(root, encoding="unicode"))
    joints = {j.get("name"): j for j in root.iter("joint")}
    movable = [pm.names[j] for j in range(1, pm.njoints) if joints[pm.names[j]].get("type") in ("revolute", "prismatic")]
    rng = np.random.default_rng(seed)
    master, *followers = [movable[i] for i in sorted(rng.choice(len(movable), size=3, replace=False))]
    for follower in followers:
        ET.SubElement(joints[follower], "mimic", joint=master, multiplier=f"{rng.uniform(-2, 2):.6f}",
                      offset=f"{rng.uniform(-1, 1):.6f}")
    return ET.tostring(root, encoding="unicode")


def references(model, path, q, qd, qdd):
    """The reduced equations from Pinocchio's standard algorithms on the full (mimic=False) model of the same
    file: A_q = J^T M J, tau = J^T rnea(J q + o, J qd, J qdd), d = J^T nle, g = J^T g_full, A_q' = J^T M' J (for
    C + C^T of the Coriolis matrix); q'' and A_q^-1 from them.  (J is constant, so q''_tree = J q''.)"""
    pm = pin.buildModelFromUrdf(str(path))
    J, o = reduction(model)
    Q = pinocchio_q(pm, J @ q + o)
    M = pin.crba(pm, pm.createData(), Q)
    A = J.T @ (np.triu(M) + np.triu(M, 1).T) @ J
    tau = J.T @ pin.rnea(pm, pm.createData(), Q, J @ qd, J @ qdd)
    nle = J.T @ pin.nonLinearEffects(pm, pm.createData(), Q, J @ qd)
    g = J.T @ pin.computeGeneralizedGravity(pm, pm.createData(), Q)
    Adot = J.T @ inertia_rate(pm, Q, J @ qd)[0] @ J
    return [("coriolis + transpose", (q, qd), Adot), ("inertia", (q,), A), ("inverse_dynamics", (q, qd, qdd), tau), ("nonlinear_effects", (q, qd), nle),
            ("gravity", (q,), g), ("forward_dynamics", (q, qd, tau), qdd), ("inertia_inverse", (q,), np.linalg.inv(A))]


def compare(model, path, call, states=3):
    """Every routine through ``call(role, *args)`` against :func:`references`."""
    rng = np.random.default_rng(3)
    for _ in range(states):
        q = rng.uniform(-1.5, 1.5, model.nq)
        qd, qdd = rng.normal(size=model.nq), rng.normal(size=model.nq)
        checks = references(model, path, q, qd, qdd)
        for role, args, ref in checks:
            if role == "coriolis + transpose":
                C = np.asarray(call("coriolis", *args)).reshape(model.nq, model.nq)
                got = C + C.T
            else:
                got = call(role, *args)
            floor = np.abs(checks[1][2]).max() * np.abs(qd).max() if role == "coriolis + transpose" else 1e-300
            assert relative_error(got, ref, floor) <= TOLERANCE, (role, relative_error(got, ref, floor))
        nle = checks[3][2]
        C = np.asarray(call("coriolis", q, qd)).reshape(model.nq, model.nq)
        floor = np.abs(checks[1][2]).max() * np.abs(qd).max() ** 2
        assert relative_error(C @ qd, nle - checks[4][2], floor) <= TOLERANCE
        assert relative_error(call("bias", q, qd) + call("gravity", q), nle) <= TOLERANCE


def test_gripper_equals_pinocchios_mimic_model(tmp_path):
    """The same against Pinocchio's own mimic joints (mimic=True), a fresh Data for every call: Pinocchio 4.1's
    crba on a model with mimic joints returns wrong entries when a Data is reused, and differs from J^T M J when a
    mimic joint carries a subtree (neither is the case here)."""
    path = written(tmp_path / "gripper.urdf", GRIPPER)
    model = aggsym.load(path, mimic="couple")
    pm = pin.buildModelFromUrdf(str(path), mimic=True)
    twin = aggsym.NumericTwin(model)
    rng = np.random.default_rng(5)
    for _ in range(3):
        q, qd, qdd = rng.uniform(-1.5, 1.5, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        Q = pinocchio_q(pm, q)
        M = pin.crba(pm, pm.createData(), Q)
        assert relative_error(twin.inertia(q), np.triu(M) + np.triu(M, 1).T) <= TOLERANCE
        assert relative_error(twin.inverse_dynamics(q, qd, qdd), pin.rnea(pm, pm.createData(), Q, qd, qdd)) <= TOLERANCE
        assert relative_error(twin.nonlinear_effects(q, qd), pin.nonLinearEffects(pm, pm.createData(), Q, qd)) <= TOLERANCE


@pytest.mark.compiler
def test_gripper_twin_c_and_numpy_equal_the_reduced_pinocchio_model(tmp_path):
    path = written(tmp_path / "gripper.urdf", GRIPPER)
    model = aggsym.load(path, mimic="couple")
    assert [c.name for c in model.coordinates] == ["shoulder", "wrist", "finger_left"]
    assert len(model.pair_coordinates) == 5
    twin = aggsym.NumericTwin(model)
    compare(model, path, lambda role, *a: twin.call(role, *a))
    gen = generate(model)
    write(gen, tmp_path / "out")
    manifest = json.loads((tmp_path / "out" / "gripper.json").read_text())
    assert manifest["nq"] == 3 and len(manifest["couplings"]) == 2
    assert "transvective_factors" not in manifest["functions"]
    lib = CLibrary(compile_shared(tmp_path / "out" / "gripper.c", tmp_path / "lib.so"), manifest)
    module = import_module(tmp_path / "out" / "gripper.py")
    compare(model, path, lambda role, *a: lib.call(role, *a))
    compare(model, path, lambda role, *a: getattr(module, role)(*a))


@pytest.mark.parametrize("seed", [1, 4, 6, 7, 8, 9, 10, 12, 14, 16, 17, 20])  # trees whose A(q) is regular
def test_random_trees_with_mimics_equal_the_reduced_pinocchio_model(seed, tmp_path):
    path = tmp_path / "tree.urdf"
    path.write_text(with_mimics(seed))
    model = aggsym.load(path, mimic="couple")
    assert len(model.couplings) == 2
    twin = aggsym.NumericTwin(model)
    compare(model, path, lambda role, *a: twin.call(role, *a))


def test_independent_mimics_keep_their_coordinates(tmp_path):
    path = written(tmp_path / "gripper.urdf", GRIPPER)
    model = aggsym.load(path)
    assert model.nq == 5 and not model.couplings and len(model.meta["mimic"]) == 2


def test_chained_mimic_is_refused(tmp_path):
    path = tmp_path / "chain.urdf"
    path.write_text(GRIPPER.replace('<mimic joint="wrist"', '<mimic joint="finger_right"'))
    with pytest.raises(ModelError, match="mimics another joint itself"):
        aggsym.load(path, mimic="couple")


@pytest.mark.compiler
def test_cli_couples_mimics(tmp_path, capsys):
    path = written(tmp_path / "gripper.urdf", GRIPPER)
    assert cli.main(["check", str(path), "--mimic", "couple", "--trials", "3", "--opt=-O0"]) == 0
    assert "ok: every routine" in capsys.readouterr().out
    yaml_model = tmp_path / "x.yaml"
    yaml_model.write_text("name: x\nbodies:\n  - name: a\n    pair: {functional: {theta6: q}}\n    mass: 1\n")
    assert cli.main(["generate", str(yaml_model), "--mimic", "couple"]) == 2


def test_the_twin_refuses_a_routine_the_coupled_model_does_not_have(tmp_path):
    """joint_friction is not emitted with coupled coordinates (it has no coupled form): asked of the twin, it names
    the routine and why, instead of failing inside the coupled evaluation."""
    path = tmp_path / "gripper.urdf"
    path.write_text(GRIPPER.replace('<axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>',
                                    '<axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/>'
                                    '<dynamics damping="0.3" friction="0.05"/></joint>', 1))
    model = aggsym.load(path, mimic="couple")
    assert model.has_joint_dynamics
    with pytest.raises(ValueError, match="joint_friction is not a routine of gripper: its coordinates are coupled"):
        aggsym.NumericTwin(model).joint_friction(np.ones(model.nq))
    independent = aggsym.load(path)
    assert aggsym.NumericTwin(independent).joint_friction(np.ones(independent.nq)).shape == (independent.nq,)
