"""Whether A(q) is regular, decided from the model's structure (aggsym/contract/regularity.py, issue 53 item 2):
a tree of bodies with positive definite spatial inertias is certified regular everywhere without a sample; a model
with point masses or massless bodies is judged at fixed configurations, the same for its fixed base and its
free-flyer, singular everywhere only where A is singular at all of them.  A point-mass head (a humanoid's, zero
inertia tensor, A singular wherever the neck's pitch is 0) gets forward dynamics for both bases, and it agrees with
Pinocchio where A is well conditioned; the manifest names the degenerate bodies and the singular home pose."""
from __future__ import annotations

import json

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.codegen.compile import import_module
import aggsym.contract.regularity as regularity_module
from aggsym.contract.regularity import generic_configurations, regularity
from aggsym.twin import NumericTwin
from helpers import relative_error
from pinocchio_reference import pin, pinocchio_model, pinocchio_q
from random_trees import random_urdf

INERTIA = '<inertia ixx="{0!r}" ixy="0" ixz="0" iyy="{1!r}" iyz="0" izz="{2!r}"/>'


def head_urdf(mass=1.3421, inertia=(0.0, 0.0, 0.0)) -> str:
    """A torso on a hip joint, a massless neck on a yaw joint, a head of ``mass`` with ``inertia`` (a point mass by
    default) 0.1532 above the pitch joint, which lies on the yaw axis: the head's velocity from the two neck rates
    is (0, L sin(pitch) yaw_rate, 0) + pitch_rate (L cos(pitch), 0, -L sin(pitch)) in the neck's axes, dependent
    exactly where sin(pitch) = 0."""
    joint = ('<joint name="{0}" type="revolute"><parent link="{1}"/><child link="{2}"/><origin xyz="{3}" rpy="{4}"/>'
             '<axis xyz="{5}"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>')
    return ('<?xml version="1.0"?><robot name="head">'
            '<link name="pelvis"><inertial><mass value="12.3"/>' + INERTIA.format(0.31, 0.27, 0.19) + '</inertial></link>'
            '<link name="torso"><inertial><origin xyz="0.011 -0.02 0.21" rpy="0.1 0.2 0.3"/><mass value="18.72"/>'
            + INERTIA.format(0.61, 0.52, 0.23) + '</inertial></link>'
            '<link name="neck"/>'
            f'<link name="head"><inertial><origin xyz="0 0 0.1532"/><mass value="{mass!r}"/>'
            + INERTIA.format(*inertia) + '</inertial></link>'
            + joint.format("torso_roll", "pelvis", "torso", "0 0 0.1", "0 0 0", "1 0 0")
            + joint.format("neck_yaw", "torso", "neck", "0.01 0 0.43", "1.5708 0 -1.5708", "0 1 0")
            + joint.format("neck_pitch", "neck", "head", "0 0 0", "-1.5708 0 0", "0 1 0")
            + "</robot>\n")


@pytest.fixture(scope="module")
def head(tmp_path_factory):
    path = tmp_path_factory.mktemp("head") / "head.urdf"
    path.write_text(head_urdf())
    return path


def test_solid_trees_are_certified_without_a_sample(tmp_path, monkeypatch):
    """Random URDF trees (arbitrary axes, masses over six decades, 5-digit angles) whose links all have a positive
    definite spatial inertia: regular everywhere from the structure alone (no A evaluated), and A from Pinocchio's
    crba is positive definite at random configurations."""
    def evaluated(*args):
        raise AssertionError("A was evaluated")

    monkeypatch.setattr(regularity_module, "_smallest", evaluated)
    rng = np.random.default_rng(5)
    checked = 0
    for seed in range(40):
        path = tmp_path / f"t{seed}.urdf"
        path.write_text(random_urdf(seed))
        model = aggsym.load(path)
        if any(b.inertial is None or b.inertial.mass == 0 for b in model.bodies if b.pair.coordinates):
            continue  # (the trees have massless links and a link of mass 0 now and then: not these)
        for base in (None, "quaternion"):
            model = aggsym.load(path, floating_base=base) if base else model
            r = regularity(model)
            if r.degenerate:
                continue
            assert r.kind == "everywhere", (seed, r)
            pm = pinocchio_model(path, floating_base=base is not None)
            data = pm.createData()
            for _ in range(2):
                q = pin.randomConfiguration(pm, -np.pi * np.ones(pm.nq), np.pi * np.ones(pm.nq))
                M = pin.crba(pm, data, q)
                M = np.triu(M) + np.triu(M, 1).T
                assert np.linalg.eigvalsh(M)[0] > 0
            checked += 1
    assert checked >= 10


@pytest.mark.parametrize("base", [None, "quaternion"])
def test_a_point_mass_head_gets_forward_dynamics_for_both_bases(head, base, tmp_path, capsys):
    model = aggsym.load(head, floating_base=base) if base else aggsym.load(head)
    r = regularity(model)
    assert r.kind == "sampled", r
    assert dict(r.degenerate) == {"neck": "massless", "head": "a point mass: no rotational inertia"}
    out = tmp_path / "out"
    args = ["generate", str(head), "-o", str(out), "-q", "--targets", "numpy,manifest"]
    code = cli.main(args + (["--floating-base", base] if base else []))
    assert code == 0, capsys.readouterr().err
    manifest = json.loads((out / "head.json").read_text())
    assert "forward_dynamics" in manifest["functions"] and "inertia_inverse" in manifest["functions"]
    assert not manifest["omitted"]
    entry = manifest["mass_matrix"]
    assert entry["regular"] == "sampled" and entry["singular_at_neutral"] is True
    assert {b["body"] for b in entry["degenerate_bodies"]} == {"neck", "head"}
    module = import_module(out / "head.py")
    pm = pin.buildModelFromUrdf(str(head), pin.JointModelFreeFlyer()) if base else pinocchio_model(head)
    data = pm.createData()

    def pinocchio_configuration(q):  # (Pinocchio's free-flyer q: the same seven entries, then the hinges)
        return q if base else pinocchio_q(pm, q)
    rng = np.random.default_rng(17)
    compared = 0
    while compared < 6:
        q = rng.uniform(-np.pi, np.pi, model.nq)
        if base:
            q[3:7] /= np.linalg.norm(q[3:7])
        Q = pinocchio_configuration(q)
        M = pin.crba(pm, data, Q)
        M = np.triu(M) + np.triu(M, 1).T
        if np.linalg.cond(M) > 1e6:
            continue
        qd, tau = rng.normal(size=(2, model.nv))
        assert relative_error(module.forward_dynamics(q, qd, tau), pin.aba(pm, data, Q, qd, tau)) <= 1e-9
        assert relative_error(module.inertia(q), M) <= 1e-12
        compared += 1
    # where the pitch is 0 A is singular (Pinocchio agrees): the set the manifest reports at the home pose
    q = np.array(model_neutral(model))
    Q = pinocchio_configuration(q)
    M = pin.crba(pm, data, Q)
    M = np.triu(M) + np.triu(M, 1).T
    assert np.linalg.eigvalsh(M)[0] <= 1e-14 * np.abs(M).max()
    pitch = [c.name for c in model.coordinates].index("neck_pitch")
    q[pitch if not base else pitch + 1] = 0.31416
    assert np.linalg.eigvalsh(module.inertia(q))[0] > 1e-6


def model_neutral(model):
    from aggsym.model.tree import Tree

    return [float(x) for x in Tree.of(model).neutral]


def test_the_judgement_is_the_same_for_both_bases_and_every_run(head):
    fixed, free = aggsym.load(head), aggsym.load(head, floating_base="quaternion")
    a, b = generic_configurations(fixed), generic_configurations(free)
    assert [q for q in a] == [q[7:] for q in b]  # the joints at the same angles; the free-flyer at rest
    assert all(q[:7] == [0.0] * 6 + [1.0] for q in b)
    assert regularity(fixed) == regularity(aggsym.load(head))
    # away from the multiples of pi/4, where the singular sets of rotations lie
    for q in a:
        assert min(abs(x / (np.pi / 4) - round(x / (np.pi / 4))) for x in q) * np.pi / 4 > 0.01


def test_a_head_with_inertia_is_certified(tmp_path):
    """The same robot with an inertia tensor on the head and mass on the neck: every body solid."""
    text = head_urdf(inertia=(0.0071, 0.0063, 0.0052)).replace(
        '<link name="neck"/>', '<link name="neck"><inertial><mass value="0.21"/>' + INERTIA.format(1e-4, 2e-4, 3e-4)
        + '</inertial></link>')
    path = tmp_path / "solid_head.urdf"
    path.write_text(text)
    assert regularity(aggsym.load(path)).kind == "everywhere"
    assert regularity(aggsym.load(path, floating_base="quaternion")).kind == "everywhere"


def test_massless_joints_are_singular_everywhere_for_both_bases():
    from pathlib import Path

    hand = Path(__file__).parent / "data" / "massless_finger.urdf"
    for base in (None, "quaternion"):
        model = aggsym.load(hand, floating_base=base) if base else aggsym.load(hand)
        r = regularity(model)
        assert r.singular and [model.coordinates[i].name for i in r.zero] == ["finger_joint", "tip_joint"], r
        assert regularity(aggsym.load(hand, armature=0.01) if not base else
                          aggsym.load(hand, floating_base=base, armature=0.01)).kind == "everywhere"


def test_two_coaxial_hinges_under_a_point_mass_are_singular_everywhere(tmp_path):
    """No coordinate moves no mass, yet the two rates along one line cancel: singular at every configuration."""
    text = head_urdf().replace('<origin xyz="0 0 0" rpy="-1.5708 0 0"/>', '<origin xyz="0 0 0" rpy="0 0 0"/>')
    path = tmp_path / "coaxial.urdf"
    path.write_text(text)
    model = aggsym.load(path)
    r = regularity(model)
    assert r.singular and not r.zero, r
    from aggsym.contract import omitted_routines

    assert "forward_dynamics" in omitted_routines(model)
    twin = NumericTwin(model)
    A = np.asarray(twin.call("inertia", np.array([0.3, -1.2, 0.7])))
    assert np.linalg.eigvalsh(A)[0] <= 1e-12 * np.abs(A).max()


def test_an_euler_floating_base_is_not_certified(tmp_path):
    """Three rotation coordinates in one pair lose rank where two axes align (theta5 = pi/2): the structure alone
    proves nothing, and A is indeed singular there."""
    path = tmp_path / "solid_head.urdf"
    path.write_text(head_urdf(inertia=(0.0071, 0.0063, 0.0052)).replace(
        '<link name="neck"/>', '<link name="neck"><inertial><mass value="0.21"/>' + INERTIA.format(1e-4, 2e-4, 3e-4)
        + '</inertial></link>'))
    model = aggsym.load(path, floating_base="euler")
    assert regularity(model).kind == "sampled"
    twin = NumericTwin(model)
    q = np.array([0.1, 0.2, 0.3, 0.4, np.pi / 2, 0.6, 0.7, 0.8, 0.9])
    A = np.asarray(twin.call("inertia", q))
    assert np.linalg.eigvalsh(A)[0] <= 1e-12 * np.abs(A).max()


def test_rods_turned_across_their_axes_are_certified():
    """planar_2link's links have no inertia about their own axis (a rod's spatial inertia, rank 5), but their hinge
    turns them across it: S^T M S > 0, so each is pinned once its parent is."""
    from pathlib import Path

    model = aggsym.load(Path(__file__).parent.parent / "models" / "planar_2link.yaml")
    assert all(b.inertial is not None for b in model.bodies)
    assert regularity(model).kind == "everywhere"


MJCF_BODY = ('<mujoco><worldbody><body name="base"><joint name="z0" axis="0 0 1"/><geom size=".1" mass="2"/>'
             '<body name="limb" pos="0.3 0 0">{joints}<geom type="box" size=".1 .05 .02" pos=".1 0 0" mass="1.5"/>'
             '</body></body></worldbody></mujoco>')


def test_a_body_with_two_joints_is_certified_and_one_with_three_is_not(tmp_path):
    """MuJoCo's bodies with several joints are chains through massless bodies here: two joints have independent
    twists at every configuration (certified, checked at one); three can align (gimbal lock), and A is singular
    there, which the judgement leaves open."""
    pytest.importorskip("mujoco")
    two = tmp_path / "two.xml"
    two.write_text(MJCF_BODY.format(joints='<joint name="a" axis="1 0 0"/><joint name="b" axis="0 1 0"/>'))
    assert regularity(aggsym.load(two)).kind == "everywhere"
    three = tmp_path / "three.xml"
    three.write_text(MJCF_BODY.format(joints='<joint name="a" axis="1 0 0"/><joint name="b" axis="0 1 0"/>'
                                             '<joint name="c" axis="0 0 1"/>'))
    model = aggsym.load(three)
    r = regularity(model)
    assert r.kind == "sampled" and {name for name, _ in r.degenerate} == {"limb_a", "limb_b"}, r
    twin = NumericTwin(model)
    A = np.asarray(twin.call("inertia", np.array([0.3, 0.7, np.pi / 2, -0.4])))
    assert np.linalg.eigvalsh(A)[0] <= 1e-12 * np.abs(A).max()
    coaxial = tmp_path / "coaxial.xml"  # (two joints about one line: singular everywhere)
    coaxial.write_text(MJCF_BODY.format(joints='<joint name="a" axis="1 0 0"/><joint name="b" axis="-2 0 0"/>'))
    assert regularity(aggsym.load(coaxial)).singular


SOLVES = ("forward_dynamics", "inertia_inverse", "transvective_factors", "forward_dynamics_derivatives")


def _solves(module, q):
    """Which of SOLVES raise LinAlgError at q (the NumPy module's report of a nonzero status)."""
    nv = len(module.VELOCITIES) if hasattr(module, "VELOCITIES") else len(q)
    raised = set()
    for role in SOLVES:
        args = [q] + ([np.zeros(nv), np.ones(nv)] if role.startswith("forward") else [])
        try:
            with np.errstate(all="ignore"):
                getattr(module, role)(*args)
        except np.linalg.LinAlgError:
            raised.add(role)
    return raised


@pytest.mark.compiler
@pytest.mark.parametrize("base", [None, "quaternion"])
def test_the_point_mass_heads_singular_states_are_reported(head, base, tmp_path):
    """Issue 53, item 2: A(q) is singular wherever the neck pitch is 0; forward dynamics, A^-1, the factors and the
    derivatives of forward dynamics are generated with a status (C int, NumPy LinAlgError), nonzero at the home
    pose and near it, zero where Pinocchio's M is well conditioned, and a nonzero one only where Pinocchio's M
    has cond >= 1e11; the header and the manifest say so."""
    from aggsym.contract import select_routines
    from helpers import generated_code

    model = aggsym.load(head, floating_base=base) if base else aggsym.load(head)
    model = select_routines(model, ["default", "forward_dynamics_derivatives"])
    lib, module, manifest = generated_code(model, tmp_path)
    for role in SOLVES:
        assert manifest["signatures"][role]["returns"].startswith("int: 0, or nonzero when A(q) is singular")
    assert manifest["signatures"]["inertia"]["returns"] == "void"
    assert manifest["mass_matrix"]["reported_by"] == list(SOLVES)
    header = (tmp_path / "head.h").read_text()
    assert "int head_forward_dynamics(" in header and "head (a point mass: no rotational inertia)" in header
    pm = pin.buildModelFromUrdf(str(head), pin.JointModelFreeFlyer()) if base else pinocchio_model(head)
    data = pm.createData()
    pitch = [c.name for c in model.coordinates].index("neck_pitch") + (1 if base else 0)
    neutral = np.array(model_neutral(model))
    for angle in (0.0, 3e-7, -2e-7):
        q = neutral.copy()
        q[pitch] = angle
        assert _solves(module, q) == set(SOLVES), angle
        with pytest.raises(np.linalg.LinAlgError), np.errstate(all="ignore"):
            lib.call("forward_dynamics", q, np.zeros(model.nv), np.ones(model.nv))
    rng = np.random.default_rng(5)
    for k in range(24):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        if base:
            q[3:7] /= np.linalg.norm(q[3:7])
        if k % 3 == 0:  # (a third of them near the singular set)
            q[pitch] = float(f"{rng.uniform(-1, 1) * 10.0 ** -rng.integers(2, 9):.5g}")
        Q = q if base else pinocchio_q(pm, q)
        M = pin.crba(pm, data, Q)
        cond = np.linalg.cond(np.triu(M) + np.triu(M, 1).T)
        raised = _solves(module, q)
        assert raised in (set(), set(SOLVES)), raised
        if raised:
            assert cond >= 1e11, (q[pitch], cond)
        elif cond <= 1e6:
            qd, tau = rng.normal(size=(2, model.nv))
            assert relative_error(lib.call("forward_dynamics", q, qd, tau), pin.aba(pm, data, Q, qd, tau)) <= 1e-9
        if cond <= 1e10:
            assert not raised, (q[pitch], cond)


def test_gimbal_lock_of_an_euler_base_is_reported():
    """The spacecraft's free flight in Euler angles: A(q) singular where the middle angle is pi/2 (gimbal lock),
    where forward dynamics and A^-1 now report it (before: a silent garbage q''); regular elsewhere."""
    from conftest import model_path

    twin = NumericTwin(aggsym.load(model_path("spacecraft")))
    rng = np.random.default_rng(11)
    q = rng.uniform(-1.2, 1.2, 12)
    for middle, singular in ((np.pi / 2, True), (-np.pi / 2, True), (1.5707, False), (0.31416, False)):
        q[4] = middle
        assert (np.linalg.cond(twin.inertia(q)) > 1e12) == singular
        for role, args in (("forward_dynamics", (q, np.zeros(12), np.ones(12))), ("inertia_inverse", (q,))):
            if singular:
                with pytest.raises(np.linalg.LinAlgError, match="singular or nearly so"), np.errstate(all="ignore"):
                    twin.call(role, *args)
            else:
                twin.call(role, *args)


def test_a_certified_model_has_no_status(tmp_path):
    """A model proved regular everywhere keeps the contract's void forward dynamics, and no mass_matrix entry."""
    from aggsym.codegen.generate import generate

    text = head_urdf(inertia=(0.0071, 0.0063, 0.0052)).replace(
        '<link name="neck"/>', '<link name="neck"><inertial><mass value="0.21"/>' + INERTIA.format(1e-4, 2e-4, 3e-4)
        + '</inertial></link>')
    path = tmp_path / "solid_head.urdf"
    path.write_text(text)
    files = generate(aggsym.load(path), targets="c,manifest").files
    manifest = json.loads(files["solid_head.json"])
    assert "mass_matrix" not in manifest
    assert all(manifest["signatures"][role]["returns"] == "void" for role in ("forward_dynamics", "inertia_inverse"))
    assert "void solid_head_forward_dynamics(" in files["solid_head.h"]


def test_pytorch_forward_dynamics_is_nan_at_the_heads_singular_states_with_and_without_gradients(head, tmp_path):
    """The traced PyTorch module (no kernels) with the derivative routines: forward dynamics holds NaN at the
    states where A(q) is singular whether or not a gradient is asked (the analytic autograd.Function as the plain
    call), and the NumPy module's values elsewhere."""
    import torch
    from aggsym.codegen.generate import generate, write
    from aggsym.contract import select_routines

    model = select_routines(aggsym.load(head), ["default", "inverse_dynamics_derivatives",
                                                 "forward_dynamics_derivatives"])
    write(generate(model, targets="numpy,torch"), tmp_path)
    npm = import_module(tmp_path / "head.py")
    tm = import_module(tmp_path / "head_torch.py")
    pitch = [c.name for c in model.coordinates].index("neck_pitch")
    rng = np.random.default_rng(3)
    q = rng.uniform(-1.5, 1.5, (3, model.nq)).round(5)
    q[1, pitch] = 3e-7  # (near the singular set: a finite but meaningless q'' without the status)
    qd, tau = rng.normal(size=(2, 3, model.nv))
    for grad in (False, True):
        x = torch.tensor(q, requires_grad=grad)
        out = tm.forward_dynamics(x, torch.tensor(qd), torch.tensor(tau)).detach().numpy()
        assert np.isnan(out[1]).all() and not np.isnan(out[[0, 2]]).any(), grad
        for k in (0, 2):
            assert relative_error(out[k], npm.forward_dynamics(q[k], qd[k], tau[k])) < 1e-13
