"""The URDF reader's errors: each names the file, the element, the line and what is wrong; and its mapping details."""
import re
import warnings

import numpy as np
import pytest
import sympy as sp

import aggsym
from aggsym.errors import ModelError, ModelWarning
from aggsym.model import load_urdf
from helpers import written
from robot_builder import INERTIAL, arm, chain, joint, link, robot, segment  # arm(): base -> upper -> lower


def line_of(text, fragment, occurrence=1):
    """1-based line of the n-th line containing fragment."""
    hits = [i + 1 for i, line in enumerate(text.splitlines()) if fragment in line]
    return hits[occurrence - 1]


def error(path, **options) -> ModelError:
    with pytest.raises(ModelError) as info:
        aggsym.load(path, **options)
    return info.value


def check(err, where, line, *fragments):
    assert err.where == where, str(err)
    assert err.line == line, str(err)
    for fragment in fragments:
        assert fragment in err.message, str(err)
    assert str(err).startswith(f"{err.file}:{line}: at {where}: ")


# the file -------------------------------------------------------------------------------------------------


def test_not_xml(write):
    text = arm().replace('<child link="lower"/>', '<child link="lower">')
    err = error(write(text))
    assert "not XML" in err.message and "mismatched tag" in err.message
    assert err.line == line_of(text, "</joint>", 2)


def test_empty_file_is_not_xml(write):
    err = error(write(""))
    assert "not XML" in err.message and err.line == 1


def test_not_a_robot(write):
    text = '<?xml version="1.0"?>\n<sdf version="1.6">\n  <model name="m"/>\n</sdf>\n'
    err = error(write(text))
    check(err, "<sdf>", 2, "not a URDF file", "<sdf>", "expected <robot>")


def test_robot_without_name(write):
    text = arm().replace('<robot name="r">', "<robot>")
    check(error(write(text)), "<robot>", 2, "missing attribute 'name'")


def test_robot_without_links(write):
    check(error(write(robot())), '<robot name="r">', 2, "no <link>")


def test_unreadable_file(tmp_path):
    err = error(tmp_path / "missing.urdf")
    assert "cannot read the file" in err.message and err.line is None


# names and references -----------------------------------------------------------------------------------


def test_joint_names_missing_parent_link(write):
    text = arm().replace('<parent link="upper"/>', '<parent link="uper"/>')
    check(error(write(text)), '<joint name="elbow"> <parent>', line_of(text, "uper\""),
          "parent link 'uper' is not defined")


def test_joint_names_missing_child_link(write):
    text = arm().replace('<child link="lower"/>', '<child link="hand"/>')
    check(error(write(text)), '<joint name="elbow"> <child>', line_of(text, '"hand"'),
          "child link 'hand' is not defined")


def test_joint_without_parent_element(write):
    text = arm().replace('    <parent link="upper"/>\n', "")
    check(error(write(text)), '<joint name="elbow">', line_of(text, 'name="elbow"'), "missing <parent> element")


def test_duplicate_link_name(write):
    text = arm(link("upper"))
    first = line_of(text, 'link name="upper"')
    check(error(write(text)), '<link name="upper">', line_of(text, 'link name="upper"', 2),
          "duplicate link name 'upper'", f"also on line {first}")


def test_duplicate_joint_name(write):
    text = arm(link("hand"), joint("elbow", "lower", "hand"))
    first = line_of(text, 'joint name="elbow"')
    check(error(write(text)), '<joint name="elbow">', line_of(text, 'joint name="elbow"', 2),
          "duplicate joint name 'elbow'", f"also on line {first}")


def test_link_with_two_parents(write):
    text = arm(joint("wrist", "base", "lower"))
    first = line_of(text, 'name="elbow"')
    check(error(write(text)), '<joint name="wrist">', line_of(text, 'name="wrist"'),
          "link 'lower' has two parents", "joint 'elbow'", f"line {first}")


def test_joint_with_same_parent_and_child(write):
    text = arm(joint("spin", "lower", "lower"))
    check(error(write(text)), '<joint name="spin">', line_of(text, 'name="spin"'),
          "'lower' is both the parent and the child")


def test_loop(write):
    text = robot(link("base"), link("a"), link("b"), link("c"), joint("j0", "base", "a"), joint("j1", "b", "c"),
                 joint("j2", "c", "b"))
    err = error(write(text))
    assert "loop in the kinematic tree" in err.message and "'j1'" in err.message and "'j2'" in err.message
    name = {'<joint name="j1">': "j1", '<joint name="j2">': "j2"}[err.where]
    assert err.line == line_of(text, f'joint name="{name}"')


def test_no_root(write):
    text = robot(link("a"), link("b"), joint("j1", "a", "b"), joint("j2", "b", "a"))
    check(error(write(text)), '<robot name="r">', 2, "no root link", "loop")


def test_two_roots(write):
    text = arm(link("tool"))
    check(error(write(text)), '<link name="tool">', line_of(text, 'name="tool"'),
          "two root links 'base'", "'tool'", "exactly one link")


# joints ---------------------------------------------------------------------------------------------------


def test_zero_axis(write):
    text = arm().replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>', 1)
    check(error(write(text)), '<joint name="shoulder"> <axis>', line_of(text, 'xyz="0 0 0"'),
          'axis xyz="0 0 0" has zero length')


@pytest.mark.parametrize("jtype, says", [("ball", "unknown joint type 'ball'"),
                                         ("universal", "unknown joint type 'universal'")])
def test_unsupported_joint_types(write, jtype, says):
    text = arm(link("hand"), joint("wrist", "lower", "hand", jtype=jtype))
    check(error(write(text)), '<joint name="wrist">', line_of(text, 'name="wrist"'), f"'{jtype}'", says)


def test_joint_without_type(write):
    text = arm().replace('name="elbow" type="revolute"', 'name="elbow"')
    check(error(write(text)), '<joint name="elbow">', line_of(text, 'name="elbow"'), "missing attribute 'type'")


def test_joint_without_name(write):
    text = arm().replace('name="elbow" type', "type")
    check(error(write(text)), "<joint>", line_of(text, "<joint type"), "missing attribute 'name'")


def test_parent_without_link_attribute(write):
    text = arm().replace('<parent link="upper"/>', "<parent/>")
    check(error(write(text)), '<joint name="elbow"> <parent>', line_of(text, "<parent/>"),
          "missing attribute 'link'")


@pytest.mark.parametrize("xyz, says", [("0 a 0", "'a' is not a number"),
                                       ("0 0", "must be 3 numbers"),
                                       ("0 0 nan", "'nan' is not a number"),
                                       ("0 0 1e999", "'1e999' is not finite"),
                                       ("0 0 ${l}", "unexpanded xacro")])
def test_non_numeric_attribute(write, xyz, says):
    text = arm().replace('<axis xyz="0 0 1"/>', f'<origin xyz="{xyz}"/><axis xyz="0 0 1"/>', 1)
    check(error(write(text)), '<joint name="shoulder"> <origin>', line_of(text, "<origin"), f'xyz="{xyz}"', says)


def test_two_origins(write):
    text = arm().replace('<axis xyz="0 0 1"/>', '<origin xyz="0 0 1"/><origin xyz="0 0 2"/><axis xyz="0 0 1"/>', 1)
    check(error(write(text)), '<joint name="shoulder"> <origin>', line_of(text, "<origin"), "a second <origin>")


def test_no_movable_joint(write):
    text = robot(link("base"), link("tool"), joint("weld", "base", "tool", jtype="fixed"))
    check(error(write(text)), '<robot name="r">', 2, "no movable joint", "floating_base=True")
    assert aggsym.load(write(text), floating_base=True).nq == 6


# links ----------------------------------------------------------------------------------------------------


def test_negative_mass(write):
    text = arm().replace('<link name="lower"><inertial><mass value="1"/>',
                         '<link name="lower"><inertial><mass value="-2"/>')
    check(error(write(text)), '<link name="lower"> <inertial> <mass>', line_of(text, '"-2"'), "negative mass -2")


def test_inertial_without_mass(write):
    text = arm().replace('<link name="lower"><inertial><mass value="1"/>', '<link name="lower"><inertial>')
    check(error(write(text)), '<link name="lower"> <inertial>', line_of(text, 'link name="lower"'),
          "missing <mass> element")


def test_inertia_missing_attribute(write):
    text = arm().replace('iyz="0" izz="0.1"/></inertial></link>\n  <link name="lower">',
                         'iyz="0"/></inertial></link>\n  <link name="lower">')
    check(error(write(text)), '<link name="upper"> <inertial> <inertia>', line_of(text, 'name="upper"'),
          "missing attribute 'izz'")


def test_inertia_not_positive_semidefinite_where_the_joints_see_it(write):
    """Judged on the body, on the motions its joints allow: 'upper' turns about z only, where ixy does not matter
    (a warning naming the link); with a free base it can move any way, and its kinetic energy can be negative."""
    text = arm().replace('<link name="upper"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0"',
                         '<link name="upper"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0.5"')
    path = write(text)
    with pytest.warns(ModelWarning, match="not positive semi-definite") as record:
        model = aggsym.load(path)
    assert '<link name="upper"> <inertial> <inertia>' in str(record[0].message)
    assert model.body("upper").inertial.inertia[0][1] == sp.Float(0.5)
    err = error(path, floating_base=True)
    check(err, '<link name="upper">', line_of(text, 'name="upper"'), "non-physical inertia of body 'upper'",
          "not positive semi-definite", "kinetic energy is negative")


def test_inertia_negative_about_the_joint_axis(write):
    text = arm().replace('<link name="upper"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" '
                         'iyy="0.1" iyz="0" izz="0.1"/>',
                         '<link name="upper"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" '
                         'iyy="0.1" iyz="0" izz="-0.1"/>')
    check(error(write(text)), '<link name="upper">', line_of(text, 'name="upper"'),
          "non-physical inertia of body 'upper'", "kinetic energy is negative", "link 'upper'")


def test_inertia_violating_triangle_inequality_warns(write):
    text = arm().replace('<link name="upper"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" '
                         'iyy="0.1" iyz="0" izz="0.1"/>',
                         '<link name="upper"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" '
                         'iyy="0.1" iyz="0" izz="0.3"/>')
    path = write(text)
    with pytest.warns(ModelWarning, match="triangle inequality") as record:
        model = aggsym.load(path)
    message = str(record[0].message)
    line = line_of(text, 'izz="0.3"')
    assert f'{path}:{line}: at <link name="upper"> <inertial> <inertia>:' in message
    assert message in model.meta["warnings"]
    assert model.body("upper").inertial.inertia[2][2] == sp.Float(0.3)


def test_zero_mass_keeps_rotational_inertia_like_pinocchio(write):
    """Pinocchio keeps the rotational inertia of a mass-0 link (and drops its centre of mass); so do we."""
    text = arm().replace('<link name="lower"><inertial><mass value="1"/>',
                         '<link name="lower"><inertial><origin xyz="1 2 3"/><mass value="0"/>')
    model = aggsym.load(write(text))
    lower = model.body("lower").inertial
    assert lower.mass == 0 and lower.inertia[2][2] == sp.Float(0.1) and tuple(lower.com) == (0, 0, 0)
    massless = text.replace('<mass value="0"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>',
                            '<mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>')
    assert aggsym.load(write(massless)).body("lower").inertial is None


def test_link_without_inertial_is_massless(write):
    text = robot(link("base"), link("hinge", inertial=""), link("arm"), joint("j1", "base", "hinge"),
                 joint("j2", "hinge", "arm", jtype="revolute", inner='<axis xyz="1 0 0"/>'))
    model = aggsym.load(write(text))
    assert model.body("hinge").inertial is None and model.body("arm").inertial is not None


# mimic ----------------------------------------------------------------------------------------------------


def mimic_arm(master="shoulder", extra=""):
    return arm(link("finger"), joint("slide", "lower", "finger", jtype="prismatic",
                                     inner=f'<axis xyz="0 1 0"/><mimic joint="{master}" {extra}/>'))


def test_mimic_is_independent_and_recorded(write):
    with pytest.warns(ModelWarning, match="'slide' mimics 'shoulder' .* keeps an independent coordinate.*couple"):
        model = aggsym.load(write(mimic_arm(extra='multiplier="-2" offset="0.5"')))
    assert [c.name for c in model.coordinates] == ["shoulder", "elbow", "slide"]
    assert model.meta["mimic"] == [{"joint": "slide", "master": "shoulder", "multiplier": -2.0, "offset": 0.5}]


def test_mimic_couple_ties_the_coordinate(write):
    """mimic="couple": the mimic joint's coordinate leaves q and is recorded as a coupling (tests/test_mimic.py
    checks the equations against Pinocchio)."""
    import aggsym

    model = aggsym.load(write(mimic_arm()), mimic="couple")
    (coupling,) = model.couplings
    assert coupling.coordinate == "slide" and coupling.coordinate not in [c.name for c in model.coordinates]
    assert model.nq == len(model.pair_coordinates) - 1


def test_mimic_of_missing_joint(write):
    """A dangling <mimic> is only a warning while the joint stays independent; mimic='couple' needs it."""
    text = mimic_arm(master="wrist")
    with pytest.warns(ModelWarning, match="mimics joint 'wrist', which is not defined"):
        model = aggsym.load(write(text))
    assert model.nq == 3 and model.meta["mimic"] == []
    check(error(write(text), mimic="couple"), '<joint name="slide"> <mimic>', line_of(text, "<mimic"),
          "mimics joint 'wrist', which is not defined")


def test_mimic_on_fixed_joint_is_ignored_with_a_warning(write):
    text = arm(link("finger"), joint("weld", "lower", "finger", jtype="fixed", inner='<mimic joint="elbow"/>'))
    with pytest.warns(ModelWarning, match="'weld' is fixed"):
        model = aggsym.load(write(text))
    assert model.meta["mimic"] == []


def test_bad_options(write):
    path = write(arm())
    with pytest.raises(ValueError, match="mimic must be one of"):
        aggsym.load(path, mimic="coupled")
    with pytest.raises(TypeError):
        aggsym.load(path, floating=True)
    with pytest.raises(TypeError):
        aggsym.load(path, floating_base="yes")


# the mapping ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("axis, code, rotation", [
    ("1 0 0", "theta4", ()), ("-1 0 0", "theta4", ((3, sp.pi),)),
    ("0 2 0", "theta5", ()), ("0 -1 0", "theta5", ((1, sp.pi),)),
    ("0 0 1", "theta6", ()), ("0 0 -0.5", "theta6", ((1, sp.pi),)),
])
def test_exact_axes(write, axis, code, rotation):
    """Axes along +-x, +-y, +-z: the functional coordinate about e_i, with an exact half turn for a minus sign."""
    text = robot(link("base"), link("arm"), joint("j", "base", "arm", inner=f'<axis xyz="{axis}"/>'))
    model = load_urdf(write(text))
    pair = model.body("arm").pair
    assert pair.codes == (code,) and pair.rotation == rotation
    lr = model.body("arm").link_rotation
    assert (lr is None) == (not rotation)
    if lr is not None:
        R = sp.Matrix(lr)
        assert R == pair.constructive_rotation().T and all(x in (-1, 0, 1) for x in R)


def test_general_axis(write):
    """A general axis a: R_a = c3(phi) c2(theta) with R_a e3 = a/|a|; theta6; link_rotation = R_a^T."""
    text = robot(link("base"), link("arm"), joint("j", "base", "arm", jtype="prismatic", inner='<axis xyz="1 2 2"/>'))
    body = load_urdf(write(text)).body("arm")
    assert body.pair.codes == ("o3",) and [a for a, _ in body.pair.rotation] == [3, 2]
    Ra = np.array(body.pair.constructive_rotation().evalf(), dtype=float)
    assert np.allclose(Ra @ [0, 0, 1], np.array([1, 2, 2]) / 3, atol=1e-15)
    assert np.allclose(np.array(body.link_rotation, dtype=float), Ra.T, atol=1e-15)


def test_default_axis_is_x(write):
    text = robot(link("base"), link("arm"), joint("j", "base", "arm", inner=""))
    assert load_urdf(write(text)).coordinates[0].code == "theta4"


def test_origin_rpy_is_z_y_x(write):
    text = robot(link("base"), link("arm"),
                 joint("j", "base", "arm", inner='<origin xyz="1 2 3" rpy="0.1 0.2 0.3"/><axis xyz="0 0 1"/>'))
    pair = load_urdf(write(text)).body("arm").pair
    assert pair.translation == (1, 2, 3)
    assert pair.rotation == ((3, sp.Float(0.3)), (2, sp.Float(0.2)), (1, sp.Float(0.1)))


def test_quaternion_origin_needs_version_1_1(write):
    inner = '<origin xyz="0 0 1" quat_xyzw="0 0 0.7071067811865476 0.7071067811865476"/><axis xyz="1 0 0"/>'
    text = robot(link("base"), link("arm"), joint("j", "base", "arm", inner=inner))
    check(error(write(text)), '<joint name="j"> <origin>', line_of(text, "quat_xyzw"), 'version="1.1"')
    quat = load_urdf(write(text.replace('<robot name="r">', '<robot name="r" version="1.1">')))
    rpy = load_urdf(write(text.replace('quat_xyzw="0 0 0.7071067811865476 0.7071067811865476"',
                                       'rpy="0 0 1.5707963267948966"')))
    assert np.allclose(np.array(quat.bodies[1].pair.constructive_rotation().evalf(), dtype=float),
                       np.array(rpy.bodies[1].pair.constructive_rotation().evalf(), dtype=float), atol=1e-15)


def test_fixed_joints_merge_into_the_parent(write):
    """Two unit masses welded 2 m apart along the rotated x axis: one body, mass 2, com midway, parallel axes."""
    text = robot(link("base"), link("arm"), link("tip"), joint("j", "base", "arm", inner='<axis xyz="0 0 -1"/>'),
                 joint("weld", "arm", "tip", jtype="fixed", inner='<origin xyz="2 0 0" rpy="0 0 1.5707963267948966"/>'),
                 link("hand"), joint("wrist", "tip", "hand", inner='<origin xyz="1 0 0"/><axis xyz="0 1 0"/>'))
    model = load_urdf(write(text))
    assert [b.name for b in model.bodies] == ["base", "arm", "hand"]
    assert model.meta["links"] == {"base": "base", "arm": "arm", "tip": "arm", "hand": "hand"}
    arm = model.body("arm").inertial
    # body axes = arm link axes turned by a half turn about x (axis -z): link x -> body x, link y -> body -y
    assert arm.mass == 2 and tuple(arm.com) == (1, 0, 0)
    assert np.allclose(np.array(arm.inertia, dtype=float), np.diag([0.2, 2.2, 2.2]))
    hand = model.body("hand").pair
    assert np.allclose(np.array(hand.translation, dtype=float), [2, -1, 0])  # tip x = arm y = body -y
    c = np.array(hand.constructive_rotation().evalf(), dtype=float)
    assert np.allclose(c, [[0, -1, 0], [-1, 0, 0], [0, 0, -1]], atol=1e-15)  # c1(-pi) c3(pi/2)


def test_names_become_identifiers(write):
    text = robot(link("base-link"), link("1st"), link("pi"), link("world"),
                 joint("elbow-1", "base-link", "1st"), joint("elbow_2", "1st", "pi"), joint("if", "pi", "world"),
                 name="my robot")
    model = load_urdf(write(text))
    assert model.name == "my_robot"
    assert [b.name for b in model.bodies] == ["base_link", "link_1st", "pi_", "world_"]
    assert [c.name for c in model.coordinates] == ["elbow_1", "elbow_2", "if_"]
    assert [c.joint for c in model.coordinates] == ["elbow-1", "elbow_2", "if"]
    assert model.bodies[0].where == '<link name="base-link">'


def test_names_that_become_one_identifier(write):
    """Two distinct names never become one identifier: an error names both (was: a silent _2 suffix)."""
    text = robot(link("base-link"), link("1st"), link("pi"), joint("elbow-1", "base-link", "1st"),
                 joint("elbow_1", "1st", "pi"))
    first = line_of(text, 'name="elbow-1"')
    check(error(write(text)), '<joint name="elbow_1">', line_of(text, 'name="elbow_1"'),
          f"joint names 'elbow-1' (line {first}) and 'elbow_1' both become the identifier 'elbow_1'")


def test_floating_base_pair(write):
    model = aggsym.load(write(arm()), floating_base=True)
    root = model.bodies[0].pair
    assert root.codes == ("o1", "o2", "o3", "theta4", "theta5", "theta6") and root.name == "root_joint"
    assert model.nq == 8 and model.meta["floating_base"] is True


def test_gravity_and_no_parameters(write):
    model = aggsym.load(write(arm()))
    assert tuple(float(g) for g in model.gravity) == (0.0, 0.0, -9.81) and model.parameters == ()


def test_ignores_what_dynamics_does_not_need(write):
    extra = ('  <transmission name="t"><type>x</type></transmission>\n  <gazebo reference="base"><sensor type="imu"/>'
             '</gazebo>\n  <material name="blue"><color rgba="0 0 1 1"/></material>\n')
    text = arm(extra).replace(INERTIAL, INERTIAL + '<visual><geometry><mesh filename="a.stl"/></geometry></visual>'
                                                   '<collision><geometry><box size="1 1 1"/></geometry></collision>')
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert aggsym.load(write(text)).nq == 2


def test_messages_have_no_placeholders(write):
    text = arm().replace('<parent link="upper"/>', '<parent link="uper"/>')
    assert not re.search(r"\{|\}", str(error(write(text))))


def test_right_angles_are_exact_only_to_round_off(tmp_path):
    """rpy="1.5707963267948966 0 -3.141592653589793" (pi/2 and -pi to double precision) is taken as (pi/2, 0, -pi):
    the constant rotation has exact zeros and ones, so they fold in the generated code.  "1.57079632679" and
    "-3.14159265359" (5e-12 and 2e-12 off) are the file's own angles and stay floats, as Pinocchio reads them;
    ``snap_angles=1e-9`` (on request) takes them as exact and records both."""
    import aggsym

    def rotation(rpy, **options):
        text = chain("r", segment("j", "b", xyz="0 0 0.1", rpy=rpy, axis="0 0 1", limit=(-1, 1, 1, 1), mass=1,
                                  inertia=(1, 1, 1)), base="a")
        model = aggsym.load(written(tmp_path / "r.urdf", text), **options)
        return model.bodies[-1].pair.constructive_rotation(), model

    c, _ = rotation("1.5707963267948966 0 -3.141592653589793")
    assert all(x in (0, 1, -1) for x in c), c
    c, model = rotation("1.57079632679 0 -3.14159265359")
    assert not all(x in (0, 1, -1) for x in c), c
    assert "snapped_angles" not in model.meta
    c, model = rotation("1.57079632679 0 -3.14159265359", snap_angles=1e-9)
    assert all(x in (0, 1, -1) for x in c), c
    assert [a["angle"] for a in model.meta["snapped_angles"]["angles"]] == ["roll", "yaw"]
