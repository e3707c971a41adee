"""Real robot files are accepted (issue 15, item 7): every URDF that example-robot-data ships and Pinocchio's
buildModelFromUrdf loads is read by aggsym.load (warnings allowed); physical validity is judged on each moving
body after its welded links are merged, on the motions its joints allow; <dynamics> and <limit> are kept per
coordinate; <mimic> joints are announced as independent.

The robot files are loaded once per module (:func:`robots`), with the warnings recorded.
"""
import math
import warnings

import numpy as np
import pytest

import aggsym
from aggsym.errors import ModelError, ModelWarning
from aggsym.model.types import JointDynamics, JointLimits
from aggsym.model.readers.builder import MAX_ROTATIONS
from helpers import robots_directory
from pinocchio_reference import pin, compare, joint_names, pinocchio_model

pytestmark = pytest.mark.pinocchio

ALL_URDFS = sorted(str(p.relative_to(robots_directory())) for p in robots_directory().rglob("*.urdf"))
# Pinocchio's fixed-base model of these has no joint (nv = 0): no equations of motion until the base is free.
FREE_BODIES = {"hector_description/robots/quadrotor_base.urdf", "iris_description/robots/iris_simple.urdf"}
# Pinocchio refuses it: <robot> has no name.
PINOCCHIO_REFUSES = {"ur_description/urdf/ur3.urdf"}


def load_recording(path, **options):
    """(model or ModelError, warning messages)."""
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always", ModelWarning)
        try:
            model = aggsym.load(path, **options)
        except ModelError as exc:
            model = exc
    return model, [str(w.message) for w in record if issubclass(w.category, ModelWarning)]


def pinocchio_loads(path, floating_base=False):
    try:
        return pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer()) if floating_base else \
            pin.buildModelFromUrdf(str(path))
    except (RuntimeError, ValueError):
        return None


@pytest.fixture(scope="module")
def robots():
    """Per file of example-robot-data: Pinocchio's fixed-base model (or None), ours as aggsym.load reads it (with
    floating_base=True for the free bodies), and the warnings."""
    out = {}
    for rel in ALL_URDFS:
        path = robots_directory() / rel
        pm = pinocchio_loads(path)
        model, messages = load_recording(path, floating_base=rel in FREE_BODIES)
        out[rel] = (pm, model, messages)
    return out


@pytest.mark.parametrize("rel", ALL_URDFS)
def test_every_urdf_pinocchio_loads_is_accepted(robots, rel):
    pm, model, messages = robots[rel]
    if pm is None:
        assert rel in PINOCCHIO_REFUSES
        return
    assert not isinstance(model, ModelError), str(model)
    free = 6 if rel in FREE_BODIES else 0
    assert model.nq == pm.nv + free
    names = [c.joint for c in model.coordinates][free:]
    assert names == joint_names(pm)
    for message in messages:
        assert message.startswith(str(robots_directory() / rel) + ":"), message


def test_count_of_accepted_files(robots):
    loaded = [rel for rel, (pm, _, _) in robots.items() if pm is not None]
    accepted = [rel for rel in loaded if not isinstance(robots[rel][1], ModelError)]
    print(f"\nexample-robot-data: {len(ALL_URDFS)} URDF files, Pinocchio loads {len(loaded)}, aggsym accepts "
          f"{len(accepted)} ({len(FREE_BODIES)} of them, without joints, with floating_base=True)")
    assert len(ALL_URDFS) >= 69 and len(loaded) >= 68 and accepted == loaded


def test_free_bodies_need_a_floating_base():
    for rel in sorted(FREE_BODIES):
        model, _ = load_recording(robots_directory() / rel)
        assert isinstance(model, ModelError)
        assert "no movable joint" in model.message and "floating_base" in model.message


def test_every_urdf_with_a_free_base():
    """With floating_base=True every file Pinocchio loads with a free flyer is accepted, but one: romeo_laas_small's
    torso ('body', merged into base_link) is far from positive semi-definite (-0.021 against 0.099), and a free
    base can move it along that direction: its kinetic energy would be negative.  (Fixed, the torso never moves;
    its hips only turn about the hip's centre, where they are positive.)"""
    refused = {}
    for rel in ALL_URDFS:
        path = robots_directory() / rel
        if pinocchio_loads(path, floating_base=True) is None:
            continue
        model, _ = load_recording(path, floating_base=True)
        if isinstance(model, ModelError):
            refused[rel] = model
    assert list(refused) == ["romeo_description/urdf/romeo_laas_small.urdf"]
    err = refused["romeo_description/urdf/romeo_laas_small.urdf"]
    assert err.where == '<link name="base_link">' and "body 'base_link'" in err.message
    assert "'body'" in err.message and "kinetic energy is negative" in err.message


# inertia judged where the dynamics sees it ---------------------------------------------------------------


@pytest.mark.parametrize("rel", ["tiago_description/robots/tiago_no_hand.urdf", "tiago_description/robots/tiago.urdf",
                                 "tiago_description/robots/tiago_dual.urdf"])
def test_tiago_antenna_is_a_warning_naming_the_link(robots, rel):
    _, model, messages = robots[rel]
    assert not isinstance(model, ModelError)
    antenna = [m for m in messages if '<link name="base_antenna_left_link"> <inertial> <inertia>' in m]
    assert len(antenna) == 1
    assert "not positive semi-definite" in antenna[0] and "its body 'base_footprint'" in antenna[0]
    lines = (robots_directory() / rel).read_text().splitlines()
    line = int(antenna[0].split(f"{robots_directory() / rel}:")[1].split(":")[0])
    assert "<inertia" in lines[line - 1]
    assert model.meta["links"]["base_antenna_left_link"] == model.meta["links"]["base_link"]
    assert any(m in model.meta["warnings"] for m in antenna)


def test_romeo_laas_small_hips_are_seen_only_turning_about_the_hip(robots):
    _, model, messages = robots["romeo_description/urdf/romeo_laas_small.urdf"]
    assert not isinstance(model, ModelError)
    hip = [m for m in messages if '<link name="LHipPitch_link">' in m]
    assert len(hip) == 1 and "non-negative kinetic energy for every motion its joints allow" in hip[0]
    torso = [m for m in messages if '<link name="body">' in m]
    assert len(torso) == 1 and "welded to the world" in torso[0]


INERTIA = '<inertia ixx="{0}" iyy="{1}" izz="{2}" ixy="{3}" ixz="0" iyz="0"/>'


def made_up(plate="0.01 0.01 0.01 0", plate_mass="0.5", arm="0.1 0.1 0.1 0", axis="0 0 1"):
    """base -(shoulder, revolute about axis)- arm =(weld, fixed)= plate -(wrist)- hand."""
    def inertial(mass, moments):
        return f'<inertial><mass value="{mass}"/>{INERTIA.format(*moments.split())}</inertial>'
    return f"""<?xml version="1.0"?>
<robot name="madeup">
  <link name="base">{inertial(1, "1 1 1 0")}</link>
  <link name="arm">{inertial(2, arm)}</link>
  <link name="plate">{inertial(plate_mass, plate)}</link>
  <link name="hand">{inertial(1, "0.01 0.01 0.01 0")}</link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="{axis}"/></joint>
  <joint name="weld" type="fixed"><parent link="arm"/><child link="plate"/><origin xyz="0.3 0 0"/></joint>
  <joint name="wrist" type="revolute"><parent link="plate"/><child link="hand"/><origin xyz="0.1 0 0"/>
    <axis xyz="0 1 0"/></joint>
</robot>
"""


def test_merged_body_that_is_not_physical_is_an_error_naming_it_and_its_links(write):
    """The plate's izz = -1 outweighs everything about the shoulder's axis: body 'arm' (arm + plate) would have a
    negative kinetic energy turning about z."""
    path = write(made_up(plate="0.01 0.01 -1 0"))
    with pytest.raises(ModelError) as info:
        aggsym.load(path)
    err = info.value
    assert err.where == '<link name="arm">' and err.line == 4
    assert "non-physical inertia of body 'arm' (links 'arm', 'plate')" in err.message
    assert "kinetic energy is negative" in err.message and "link 'plate'" in err.message
    assert "(line 5)" in err.message


def test_link_not_physical_in_a_physical_body_is_a_warning(write):
    """The plate alone is not positive semi-definite (ixy = 0.02 > 0.01), but welded to the heavy arm 0.3 m away
    the merged body is physical: a warning naming the plate and its body; the plate is used as given."""
    path = write(made_up(plate="0.01 0.01 0.01 0.02"))
    model, messages = load_recording(path)
    assert not isinstance(model, ModelError), str(model)
    (message,) = messages
    assert '<link name="plate"> <inertial> <inertia>' in message and "not positive semi-definite" in message
    assert "its body 'arm' (links 'arm', 'plate') is physical" in message
    plain, _ = load_recording(write(made_up(plate="0.01 0.01 0.01 0"), "plain.urdf"))
    difference = np.array(model.body("arm").inertial.inertia, dtype=float) - \
        np.array(plain.body("arm").inertial.inertia, dtype=float)
    assert np.allclose(difference, [[0, 0.02, 0], [0.02, 0, 0], [0, 0, 0]], atol=1e-15)  # as given


def test_body_welded_to_the_world_is_never_judged(write):
    text = made_up().replace('<link name="base"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1"',
                             '<link name="base"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="-5"')
    path = write(text)
    model, messages = load_recording(path)
    assert not isinstance(model, ModelError)
    (message,) = messages
    assert '<link name="base">' in message and "welded to the world" in message
    with pytest.raises(ModelError, match="non-physical inertia of body 'base'"):
        aggsym.load(path, floating_base=True)


@pytest.mark.parametrize("excess, judged", [(1e-8, False), (1e-7, False), (1e-5, True), (1e-3, True)])
def test_tolerance_is_relative_to_the_largest_principal_moment(write, excess, judged):
    """izz = ixx + iyy + excess * izz: a violation of the triangle inequality by `excess` relative to the largest
    principal moment is noticed above 1e-6 (a warning: triangle violations keep the energy positive)."""
    izz = 0.2 / (1 - excess)
    model, messages = load_recording(write(made_up(arm=f"0.1 0.1 {izz!r} 0")))
    assert not isinstance(model, ModelError)
    assert bool(messages) == judged
    if judged:
        assert "triangle inequality" in messages[0] and '<link name="arm">' in messages[0]


def test_negative_semidefinite_within_tolerance_is_accepted_silently(write):
    model, messages = load_recording(write(made_up(arm="0.1 0.1 -1e-9 0")))
    assert not isinstance(model, ModelError) and messages == []


def test_long_fixed_chain_equals_pinocchio(write, rng):
    """Fourteen welded links with general rpy between two revolute joints: their rotations are folded into one rpy
    as they pile up (so merging stays linear); the model still equals Pinocchio's."""
    links = "".join(f'<link name="w{i}"><inertial><origin xyz="0.01 0.02 {0.01 * i}" rpy="0.1 0.2 0.3"/>'
                    f'<mass value="0.1"/>{INERTIA.format(0.001, 0.002, 0.0025, 0.0001)}</inertial></link>'
                    for i in range(14))
    joints = "".join(f'<joint name="f{i}" type="fixed"><parent link="{"a" if i == 0 else f"w{i - 1}"}"/>'
                     f'<child link="w{i}"/><origin xyz="0.05 0.01 0.02" rpy="{0.3 + 0.1 * i} {0.2 - 0.05 * i} '
                     f'{0.7 * i}"/></joint>' for i in range(14))
    text = f"""<robot name="welded">
  <link name="base"/>
  <link name="a"><inertial><mass value="1"/>{INERTIA.format(0.01, 0.02, 0.025, 0)}</inertial></link>
  <link name="tip"><inertial><origin xyz="0.1 0 0"/><mass value="0.5"/>{INERTIA.format(0.01, 0.01, 0.01, 0)}
    </inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-3" upper="3" velocity="1" effort="1"/></joint>
  {links}{joints}
  <joint name="j2" type="revolute"><parent link="w13"/><child link="tip"/><origin xyz="0.1 0 0" rpy="0.4 0.5 0.6"/>
    <axis xyz="1 0 0"/><limit lower="-3" upper="3" velocity="1" effort="1"/></joint>
</robot>"""
    path = write(text)
    model = aggsym.load(path)
    assert len(model.bodies) == 3
    assert len(model.body("tip").pair.rotation) <= MAX_ROTATIONS + 3  # not the 3 x 14 + 3 of the whole chain
    assert all(x.is_Float for x in model.body("tip").pair.translation)  # numbers, not growing expressions
    compare(model, pinocchio_model(path), rng, states=3)


# <dynamics> and <limit> ----------------------------------------------------------------------------------


def small_arm(extra_shoulder='<dynamics damping="0.5" friction="0.25"/>'
                             '<limit lower="-1.5" upper="2" velocity="3" effort="40"/>'):
    """Joints listed out of Pinocchio's order: 'b_elbow' (file first) is the child of 'a_shoulder'."""
    return f"""<robot name="small">
  <link name="base"/>
  <link name="upper"><inertial><mass value="1"/>{INERTIA.format(0.1, 0.1, 0.1, 0)}</inertial></link>
  <link name="lower"><inertial><mass value="1"/>{INERTIA.format(0.1, 0.1, 0.1, 0)}</inertial></link>
  <link name="hand"><inertial><mass value="1"/>{INERTIA.format(0.1, 0.1, 0.1, 0)}</inertial></link>
  <link name="tool"/>
  <joint name="c_wrist" type="continuous"><parent link="lower"/><child link="hand"/><origin xyz="0.3 0 0"/>
    <axis xyz="1 0 0"/><dynamics damping="0.125"/><limit effort="7" velocity="8"/></joint>
  <joint name="b_elbow" type="prismatic"><parent link="upper"/><child link="lower"/><axis xyz="0 0 -1"/>
    <dynamics friction="2"/><limit lower="0" upper="0.2" velocity="0.5" effort="100"/></joint>
  <joint name="a_shoulder" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 0 1"/>
    {extra_shoulder}</joint>
  <joint name="weld" type="fixed"><parent link="hand"/><child link="tool"/>
    <dynamics damping="9" friction="9"/><limit lower="1" upper="2" velocity="3" effort="4"/></joint>
</robot>"""


def test_dynamics_and_limits_per_coordinate_in_q_order(write):
    model = aggsym.load(write(small_arm()))
    assert [c.joint for c in model.coordinates] == ["a_shoulder", "b_elbow", "c_wrist"]
    assert model.joint_dynamics == (JointDynamics(0.5, 0.25), JointDynamics(None, 2.0), JointDynamics(0.125, None))
    assert model.has_joint_dynamics
    assert model.limits == (
        {"lower": -1.5, "upper": 2.0, "velocity": 3.0, "effort": 40.0},
        {"lower": 0.0, "upper": 0.2, "velocity": 0.5, "effort": 100.0},
        {"lower": None, "upper": None, "velocity": 8.0, "effort": 7.0},
    )
    assert model.coordinates[1].limits == JointLimits(0.0, 0.2, 0.5, 100.0)
    model.limits[0]["lower"] = 99.0  # fresh dicts: the model does not change
    assert model.limits[0]["lower"] == -1.5


def test_absent_dynamics_and_limits_are_none(write):
    model = aggsym.load(write(small_arm(extra_shoulder="")), floating_base=True)
    assert model.joint_dynamics[:7] == (JointDynamics(),) * 7  # six of the free base, then the shoulder
    assert model.limits[6] == {"lower": None, "upper": None, "velocity": None, "effort": None}
    no_dynamics = small_arm(extra_shoulder="").replace('<dynamics damping="0.125"/>', "").replace(
        '<dynamics friction="2"/>', "")
    assert not aggsym.load(write(no_dynamics)).has_joint_dynamics


def test_coupled_mimic_leaves_the_limits_in_q_order(write):
    text = small_arm().replace('<dynamics damping="0.125"/>', '<dynamics damping="0.125"/><mimic joint="a_shoulder"/>')
    model = aggsym.load(write(text), mimic="couple")
    assert [c.joint for c in model.coordinates] == ["a_shoulder", "b_elbow"]
    assert len(model.limits) == len(model.joint_dynamics) == 2


@pytest.mark.parametrize("element, says", [
    ('<dynamics damping="-0.5"/>', 'damping="-0.5" is negative'),
    ('<dynamics friction="-1"/>', 'friction="-1" is negative'),
    ('<dynamics damping="nan"/>', "'nan' is not a number"),
    ('<dynamics damping="1e400"/>', "is not finite"),
    ('<limit lower="x" upper="1" velocity="1" effort="1"/>', "'x' is not a number"),
    ('<dynamics damping="1"/><dynamics damping="2"/>', "a second <dynamics>"),
])
def test_bad_dynamics_and_limits(write, element, says):
    text = small_arm(extra_shoulder=element)
    with pytest.raises(ModelError) as info:
        aggsym.load(write(text))
    assert says in info.value.message and info.value.where.startswith('<joint name="a_shoulder">')
    shoulder = next(i + 1 for i, line in enumerate(text.splitlines()) if 'name="a_shoulder"' in line)
    assert info.value.line == shoulder + 1  # the line of the shoulder's <dynamics> and <limit>


@pytest.mark.parametrize("element, says", [
    ('<limit lower="2" upper="1" velocity="1" effort="1"/>', "lower=2 is above upper=1"),
    ('<limit lower="0" upper="1" velocity="-1" effort="1"/>', "velocity=-1 is negative"),
    ('<limit lower="0" upper="1" velocity="1" effort="-3"/>', "effort=-3 is negative"),
])
def test_odd_limits_are_kept_with_a_warning(write, element, says):
    with pytest.warns(ModelWarning, match=says):
        model = aggsym.load(write(small_arm(extra_shoulder=element)))
    assert model.limits[0] == {k: float(v) for k, v in
                               zip(("lower", "upper", "velocity", "effort"), element.split('"')[1::2])}


@pytest.mark.parametrize("rel", ["talos_data/robots/talos_reduced.urdf", "tiago_description/robots/tiago.urdf",
                                 "panda_description/urdf/panda.urdf", "centauro_description/urdf/centauro.urdf"])
def test_dynamics_and_limits_of_real_robots_equal_pinocchios(robots, rel):
    """Where the file gives a value it is Pinocchio's (damping, friction, velocityLimit, effortLimit, and the
    position limits of one-variable joints); where it gives none Pinocchio has 0 damping and friction."""
    pm, model, _ = robots[rel]
    given = 0
    for c, dynamics, limits in zip(model.coordinates, model.joint_dynamics, model.limits):
        joint = pm.joints[pm.getJointId(c.joint)]
        iv, iq = joint.idx_v, joint.idx_q
        assert (dynamics.damping or 0.0) == pm.damping[iv] and (dynamics.friction or 0.0) == pm.friction[iv]
        pinocchio = {"velocity": pm.velocityLimit[iv], "effort": pm.effortLimit[iv]}
        if joint.nq == joint.nv:
            pinocchio.update(lower=pm.lowerPositionLimit[iq], upper=pm.upperPositionLimit[iq])
        for key, value in pinocchio.items():
            if limits[key] is not None:
                assert limits[key] == value, (c.joint, key)
                given += 1
    assert given >= 2 * model.nq


def test_talos_dynamics_values(robots):
    pm, model, _ = robots["talos_data/robots/talos_reduced.urdf"]
    assert model.has_joint_dynamics and all(d.damping is not None for d in model.joint_dynamics)
    assert all(math.isfinite(limits["effort"]) for limits in model.limits)


# <mimic> -------------------------------------------------------------------------------------------------


def test_panda_mimic_warns_that_it_is_independent(robots):
    _, model, messages = robots["panda_description/urdf/panda.urdf"]
    (message,) = [m for m in messages if "<mimic>" in m]
    assert '<joint name="panda_finger_joint2"> <mimic>' in message
    assert "keeps an independent coordinate" in message and "mimic='couple'" in message
    assert model.nq == 9


def test_dangling_mimic_is_a_warning_unless_coupling_needs_it(robots):
    rel = "alex_description/urdf/alex_psyonic_hands.urdf"
    _, model, messages = robots[rel]
    assert not isinstance(model, ModelError)
    dangling = [m for m in messages if "which is not defined" in m]
    assert dangling and all("ignored" in m and "<mimic>" in m for m in dangling)
    assert any('<joint name="Left_index_q2"> <mimic>' in m and "'index_q1'" in m for m in dangling)
    with pytest.raises(ModelError) as info:
        aggsym.load(robots_directory() / rel, mimic="couple")
    assert info.value.where.endswith("<mimic>") and "which is not defined" in info.value.message
    assert "mimic='couple'" in info.value.message


@pytest.mark.parametrize("target, couple_fails", [("a_shoulder", False), ("nothing", True), ("c_wrist", True)])
def test_mimic_warnings(write, target, couple_fails):
    """A usable <mimic> warns while independent and couples on request; a dangling one and one naming its own
    joint warn while independent and are errors when coupling needs them."""
    text = small_arm().replace('<dynamics damping="0.125"/>', f'<dynamics damping="0.125"/><mimic joint="{target}"/>')
    path = write(text)
    with pytest.warns(ModelWarning, match=r"<joint name=\"c_wrist\"> <mimic>"):
        model = aggsym.load(path)
    assert model.nq == 3
    if couple_fails:
        with pytest.raises(ModelError, match="mimic='couple'"):
            aggsym.load(path, mimic="couple")
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("error", ModelWarning)
            assert aggsym.load(path, mimic="couple").nq == 2
