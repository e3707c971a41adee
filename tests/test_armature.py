"""Singular inertia and the armature (issue 15): a coordinate that moves no mass leaves forward dynamics, A^-1 and
the factors out (listed in the manifest's 'omitted', with a warning naming the joint) while A, b, g, inverse
dynamics and the joint wrenches are emitted; --armature adds Pinocchio's armature and makes everything defined.
Against Pinocchio with model.armature set."""
import dataclasses
import json
import re
import warnings

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.contract import omitted_routines
from aggsym.errors import ModelWarning
from helpers import TOLERANCE, generated_code, relative_error, robot_path, robots_directory, written
from pinocchio_reference import pin, crba, pinocchio_model, pinocchio_q
from robot_builder import chain, segment

pytestmark = pytest.mark.pinocchio

# a palm on a wrist carrying two massless links (a finger and its tip)
HAND = chain("hand",
             segment("wrist", "palm", axis="0 0 1", limit=(-3, 3, 10, 5), mass=1.0, com="0.05 0.01 0",
                     inertia=(0.01, 0.02, 0.03, 0.001, 0, 0)),
             segment("finger_joint", "finger", xyz="0.1 0 0", axis="0 1 0", limit=(-3, 3, 10, 5)),
             segment("tip_joint", "tip", "prismatic", xyz="0.03 0 0", axis="1 0 0", limit=(-3, 3, 10, 5)))


@pytest.fixture
def hand(tmp_path):
    return written(tmp_path / "hand.urdf", HAND)


@pytest.mark.compiler
def test_massless_joints_leave_the_undefined_routines_out(hand, tmp_path, rng):
    model = aggsym.load(hand)
    omitted = omitted_routines(model)
    assert set(omitted) == {"forward_dynamics", "inertia_inverse", "transvective_factors"}
    assert "finger_joint" in omitted["forward_dynamics"] and "tip_joint" in omitted["forward_dynamics"]
    assert "wrist" not in omitted["forward_dynamics"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        lib, module, manifest = generated_code(model, tmp_path / "out")
    assert any(issubclass(w.category, ModelWarning) and "finger_joint" in str(w.message) for w in caught)
    assert manifest["omitted"] == omitted and not set(omitted) & set(manifest["functions"])
    pm, data = pinocchio_model(hand), None
    data = pm.createData()
    for _ in range(3):
        q, qd, qdd = rng.normal(size=(3, model.nq))
        Q = pinocchio_q(pm, q)
        assert relative_error(lib.call("inertia", q), crba(pm, Q)) <= TOLERANCE
        assert relative_error(module.inverse_dynamics(q, qd, qdd), pin.rnea(pm, data, Q, qd, qdd)) <= TOLERANCE


def test_cli_lists_and_warns_about_the_left_out_routines(hand, tmp_path, capsys):
    assert cli.main(["generate", str(hand), "--list-routines"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"^hand_forward_dynamics +\(left out: A\(q\) is singular", out, re.M)
    assert cli.main(["generate", str(hand), "-o", str(tmp_path / "o")]) == 0
    err = capsys.readouterr().err
    assert "warning" in err and "finger_joint" in err and "--armature" in err


@pytest.mark.compiler
@pytest.mark.parametrize("case", ["hand", "ur5"])
def test_armature_equals_pinocchios(case, hand, tmp_path, rng):
    """With --armature every routine is emitted and equals Pinocchio's model with the same armature: crba, rnea,
    aba, computeMinverse; and the C agrees with the twin."""
    path = hand if case == "hand" else robot_path("ur5")
    value = 0.01 if case == "hand" else 0.25
    assert cli.main(["check", str(path), "--armature", str(value), "--trials", "3"]) == 0
    model = dataclasses.replace(aggsym.load(path), armature=value)
    assert omitted_routines(model) == {}
    lib, module, manifest = generated_code(model, tmp_path / "out")
    assert manifest["armature"] == value and "forward_dynamics" in manifest["functions"]
    pm = pinocchio_model(path)
    pm.armature = np.full(pm.nv, value)
    data = pm.createData()
    for _ in range(3):
        q, qd, qdd, tau = rng.normal(size=(4, model.nq))
        Q = pinocchio_q(pm, q)
        M = crba(pm, Q)
        assert relative_error(lib.call("inertia", q), M) <= TOLERANCE
        assert relative_error(lib.call("inverse_dynamics", q, qd, qdd), pin.rnea(pm, data, Q, qd, qdd)) <= TOLERANCE
        assert relative_error(lib.call("forward_dynamics", q, qd, tau), pin.aba(pm, data, Q, qd, tau)) <= TOLERANCE
        Minv = pin.computeMinverse(pm, data, Q)
        Minv = np.triu(Minv) + np.triu(Minv, 1).T
        assert relative_error(module.inertia_inverse(q), Minv) <= TOLERANCE
        assert abs(module.kinetic_energy(q, qd) - 0.5 * qd @ M @ qd) <= 1e-12 * (qd @ M @ qd)


@pytest.mark.parametrize("bad", ["-1", "nan", "inf", "x"])
def test_bad_armature_is_a_usage_error(bad, capsys):
    with pytest.raises(SystemExit) as info:
        cli.main(["generate", "whatever.urdf", "--armature", bad])
    assert info.value.code == 2 and "armature" in capsys.readouterr().err


def test_romeo_with_massless_fingers_generates(tmp_path, capsys, rng):
    """example-robot-data's romeo.urdf (massless finger joints) generates: A, b, g, inverse dynamics emitted and
    equal to Pinocchio's; the routines that need A^-1 listed as omitted (it used to end in an internal error)."""
    path = robots_directory() / "romeo_description/urdf/romeo.urdf"
    out = tmp_path / "romeo"
    assert cli.main(["generate", str(path), "-o", str(out), "-q"]) == 0
    assert "LFinger21" in capsys.readouterr().err
    manifest = json.loads((out / "romeo.json").read_text())
    assert "LFinger21" in manifest["omitted"]["forward_dynamics"] and "inverse_dynamics" in manifest["functions"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(path)
    twin, pm = aggsym.NumericTwin(model), pinocchio_model(path)
    data = pm.createData()
    q, qd, qdd = rng.uniform(-1, 1, size=(3, model.nq))
    Q = pinocchio_q(pm, q)
    assert relative_error(twin.inertia(q), crba(pm, Q)) <= TOLERANCE
    assert relative_error(twin.inverse_dynamics(q, qd, qdd), pin.rnea(pm, data, Q, qd, qdd)) <= TOLERANCE
