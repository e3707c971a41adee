"""The MJCF reader (issue 33, items 1, 2 hinge/slide/free, 3, 5): MuJoCo's compiled model onto the tree, checked
against MuJoCo itself, and hostile or unsupported files refused with exit 2.

The representative sample of the corpora (``benchmarks/mjcf/corpus.py`` walks all of them, with the comparison of ``benchmarks/mjcf/mujoco_reference.py``): a fixed-base arm with
damping (acrobot), a cart with a slide (cartpole), a planar runner whose root is three joints in one body and whose
joints have armature, damping and springs (cheetah), a hinge with qpos0 = pi/2 (finger), joints anchored off the
body origin with a slide root at qpos0 = 1.25 (gymnasium's walker2d), free-root walkers (gymnasium's ant, dm_control's
humanoid), and a scene of tests/data/scene.xml: two free bodies, one with armature and damping on its free joint and a hinge
child, a fixed-base arm whose body has two joints anchored off its origin (one with a spring and ref), a slide, a
site, and a tilted gravity.
"""
from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from aggsym import cli
from aggsym.model import load
from aggsym.model.readers import mjcf_source
from aggsym.twin import NumericTwin
from helpers import data_text, written

mujoco = pytest.importorskip("mujoco")
pytestmark = pytest.mark.mujoco

from benchmarks.mjcf.mujoco_reference import compare, mujoco_model, states, to_aggsym  # noqa: E402

SITE = Path(mujoco.__file__).resolve().parent.parent
SUITE = SITE / "dm_control" / "suite"
GYM = SITE / "gymnasium" / "envs" / "mujoco" / "assets"
SAMPLE = [SUITE / "acrobot.xml", SUITE / "cartpole.xml", SUITE / "cheetah.xml", SUITE / "finger.xml",
          SUITE / "humanoid.xml", GYM / "walker2d.xml", GYM / "ant.xml"]
TOLERANCE = 1e-9
SCENE = data_text("scene.xml")  # (test_mjcf_poses.py reads it too)


@pytest.fixture
def scene(tmp_path):
    return written(tmp_path / "scene.xml", SCENE)


@pytest.mark.parametrize("path", SAMPLE, ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_against_mujoco(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        worst = compare(path, samples=2)
    assert max(worst.values()) <= TOLERANCE, worst


def test_scene_against_mujoco(scene):
    worst = compare(scene, samples=3, seed=1)
    assert max(worst.values()) <= TOLERANCE, worst


def test_scene_structure(scene):
    """Two free bodies are two trees; the body with two joints is chained through a massless body; q is qpos."""
    model = load(scene)
    parents = {b.name: b.parent for b in model.bodies}
    assert parents == {"worldbody": "world", "upper_shoulder_y": "worldbody", "upper": "upper_shoulder_y",
                       "lower": "upper", "ball": "world", "box": "world", "lid": "box"}
    assert model.body("upper_shoulder_y").inertial is None
    assert [n for n, _, _ in model.positions][3:10] == ["ball_root_x", "ball_root_y", "ball_root_z", "ball_root_qx",
                                                        "ball_root_qy", "ball_root_qz", "ball_root_qw"]
    names = [p.name for p in model.parameters]
    assert names[:5] == ["armature_shoulder_y", "damping_shoulder_y", "stiffness_shoulder_x", "springref_shoulder_x",
                         "damping_slide"]
    assert names[-5:] == ["armature_box_root", "damping_box_root", "gravity_x", "gravity_y", "gravity_z"]
    assert model.parameter_values[-3:] == pytest.approx((0.3, -0.2, -9.5))
    assert not model.conservative  # damping
    meta = model.meta["mjcf"]
    assert meta["actuators"] == [{"name": "drive", "transmission": "joint", "target": "shoulder_y",
                                  "gear": [50.0, 0.0, 0.0, 0.0, 0.0, 0.0]}]
    assert meta["free_joints"] == ["ball_root", "box_root"]
    assert model.link_table.leaves == ("lower", "ball", "lid")


def test_parameters_change_the_equations(scene):
    """armature, damping, stiffness, springref and gravity are runtime parameters: set through p, MuJoCo with the
    same values agrees (masses of another decade too, through MuJoCo's own model)."""
    model = load(scene)
    twin = NumericTwin(model)
    values = dict(zip([p.name for p in model.parameters], model.parameter_values))
    values.update(armature_shoulder_y=0.5, damping_slide=4.0, stiffness_shoulder_x=7.0, springref_shoulder_x=-0.4,
                  armature_box_root=0.2, damping_box_root=0.9, gravity_x=-1.0, gravity_z=-3.0)
    p = [values[n.name] for n in model.parameters]
    m = mujoco_model(scene)
    j = {name: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name) for name in ("shoulder_y", "slide",
                                                                                  "shoulder_x", "box_root")}
    m.dof_armature[m.jnt_dofadr[j["shoulder_y"]]] = 0.5
    m.dof_damping[m.jnt_dofadr[j["slide"]]] = 4.0
    m.jnt_stiffness[j["shoulder_x"]] = 7.0
    m.qpos_spring[m.jnt_qposadr[j["shoulder_x"]]] = -0.4
    box = m.jnt_dofadr[j["box_root"]]
    m.dof_armature[box:box + 6] = 0.2
    m.dof_damping[box:box + 6] = 0.9
    m.opt.gravity[:] = (-1.0, -0.2, -3.0)
    data = mujoco.MjData(m)
    rng = np.random.default_rng(3)
    for _ in range(2):
        qpos, qvel, force = states(m, rng)
        data.qpos[:], data.qvel[:], data.qfrc_applied[:] = qpos, qvel, force
        mujoco.mj_forward(m, data)
        M = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, data, M)
        q, qd, tau, J, c = to_aggsym(m, qpos, qvel, force)
        assert np.allclose(twin.call("inertia", q, p=p), J.T @ M @ J, rtol=0, atol=1e-12)
        assert np.allclose(J @ twin.call("forward_dynamics", q, qd, tau, p=p) + c, data.qacc, rtol=0,
                           atol=1e-9 * np.max(np.abs(data.qacc)))
        assert np.allclose(twin.call("passive_forces", q, qd, p=p), J.T @ data.qfrc_passive, rtol=0, atol=1e-12)
        assert np.any(data.qfrc_passive != 0)


def test_sites_and_bodies_are_frames(scene, tmp_path):
    """Every body and site is a frame (--frames): their poses are MuJoCo's xpos/xmat and site_xpos/site_xmat."""
    from aggsym.model.transforms.frames import select_frames

    names = ["world", "base", "upper", "lower", "ball", "lid", "origin_mark", "elbow_site", "lid_corner"]
    model = select_frames(load(scene), names)
    twin = NumericTwin(model)
    m = mujoco_model(scene)
    data = mujoco.MjData(m)
    qpos, qvel, force = states(m, np.random.default_rng(5))
    data.qpos[:] = qpos
    mujoco.mj_forward(m, data)
    q = to_aggsym(m, qpos, qvel, force)[0]
    poses = np.asarray(twin.call("frame_poses", q)).reshape(len(names), -1)
    for name, pose in zip(names, poses):
        site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, name)
        if site >= 0:
            x, R = data.site_xpos[site], data.site_xmat[site].reshape(3, 3)
        else:
            b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
            x, R = data.xpos[b], data.xmat[b].reshape(3, 3)
        assert np.allclose(pose[:3], x, atol=1e-12), name  # (origin, then R row-major)
        assert np.allclose(pose[3:].reshape(3, 3), R, atol=1e-12), name


def test_damping_derivatives_against_central_differences(scene):
    """The derivatives of forward and inverse dynamics carry the damping D qd (central differences of the twin)."""
    model = load(scene)
    twin = NumericTwin(model)
    m = mujoco_model(scene)
    qpos, qvel, force = states(m, np.random.default_rng(7))
    q, qd, tau, _, _ = to_aggsym(m, qpos, qvel, force)
    qdd = twin.call("forward_dynamics", q, qd, tau)
    _, dtau_dqd = twin.call("inverse_dynamics_derivatives", q, qd, qdd)
    _, dqdd_dqd = twin.call("forward_dynamics_derivatives", q, qd, tau)
    h = 1e-6
    for j in range(model.nv):
        e = np.zeros(model.nv)
        e[j] = h
        fd_tau = (twin.call("inverse_dynamics", q, qd + e, qdd) - twin.call("inverse_dynamics", q, qd - e, qdd)) / (2 * h)
        fd_qdd = (twin.call("forward_dynamics", q, qd + e, tau) - twin.call("forward_dynamics", q, qd - e, tau)) / (2 * h)
        assert np.allclose(np.asarray(dtau_dqd).reshape(model.nv, -1)[:, j], fd_tau, atol=1e-6)
        assert np.allclose(np.asarray(dqdd_dqd).reshape(model.nv, -1)[:, j], fd_qdd, atol=1e-6)


def test_generate_writes_the_mjcf_manifest(scene, tmp_path):
    """``aggsym generate scene.xml`` picks the reader by content; the manifest states the conventions."""
    out = tmp_path / "out"
    assert cli.main(["generate", str(scene), "-o", str(out), "-q", "--targets", "numpy,manifest"]) == 0
    manifest = json.loads((out / "scene.json").read_text())
    assert manifest["conservative"] is False
    assert "passive_forces" in manifest["functions"]
    assert "qfrc_passive" in manifest["mjcf"]["in_the_equations"]
    assert "R^T v_world" in manifest["mjcf"]["convention"]
    assert "frictionloss" in manifest["mjcf"]["not_in_the_equations"]


# refused: what is not supported, what MuJoCo's compiler refuses, and hostile files ---------------------------------

def run(tmp_path, capsys, text, name="model.xml", options=()):
    path = tmp_path / name
    if text is not None:
        path.write_text(text)
    out = tmp_path / "out"
    code = cli.main(["generate", str(path), "-o", str(out), "-q", *options])
    err = capsys.readouterr().err
    return code, err, out, path


def refused(tmp_path, capsys, text, fragments, name="model.xml", options=()):
    code, err, out, path = run(tmp_path, capsys, text, name, options)
    assert code == 2, err
    assert "Traceback" not in err and err.startswith(f"aggsym: error: {path}"), err
    for fragment in fragments:
        assert fragment in err, f"{fragment!r} not in {err!r}"
    assert not out.exists()


ARM = """<mujoco model="arm"><worldbody><body name="a"><joint name="j1" {attrs}/><geom size=".1"/>
{extra}</body></worldbody>{after}</mujoco>"""

UNSUPPORTED = {
    "ball-spring": (ARM.format(attrs='type="ball" stiffness="2"', extra="", after=""),
                    ['<joint name="j1">', "stiffness=2 on a ball joint", "not supported"]),
    "ball-before-slide": (ARM.format(attrs='type="ball"', extra="", after="").replace(
        '<geom size=".1"/>', '<joint name="j2" type="slide"/><geom size=".1"/>', 1),
                          ['<joint name="j1">', "a ball joint followed by other joints", "last joint"]),
    "equality": (ARM.format(attrs="", extra='<site name="s1"/><body name="b" pos="0 0 -.5"><joint name="j2"/>'
                                            '<geom size=".1"/><site name="s2"/></body>',
                            after='<tendon><spatial name="rope"><site site="s1"/><site site="s2"/></spatial></tendon>'
                                  '<equality><tendon name="tie" tendon1="rope"/></equality>'),
                 # (s2 on j2's axis: the rope's length never changes, so its row's J is zero everywhere)
                 ['<tendon name="tie">', "constraint 'tie'", "rank-deficient at every configuration"]),
    "tendon-wrap": (ARM.format(attrs="", extra='<site name="s1"/><geom name="w" type="sphere" size=".05" pos="0 .2 -.25"/>'
                                               '<body name="b" pos="0 0 -.5"><joint name="j2"/>'
                                               '<geom size=".1"/><site name="s2"/></body>',
                               after='<tendon><spatial name="t" stiffness="3"><site site="s1"/><geom geom="w"/>'
                                     '<site site="s2"/></spatial></tendon>'),
                    ['<tendon name="t">', "wrapping around a geom", "not supported"]),
    "tendon-armature-coupled": (ARM.format(attrs="", extra='<body name="b" pos="0 0 -.5"><joint name="j2"/>'
                                                        '<geom size=".1"/></body>',
                                           after='<tendon><fixed name="t" armature="3"><joint joint="j1" coef="1"/>'
                                                 '<joint joint="j2" coef="1"/></fixed></tendon><equality>'
                                                 '<joint joint1="j2" joint2="j1"/></equality>'),
                                ['<tendon name="t">', "armature with coupled coordinates", "not supported"]),
    "actuatorgravcomp": (ARM.replace('<body name="a">', '<body name="a" gravcomp="1">').format(
        attrs='actuatorgravcomp="true"', extra="", after=""), ['<joint name="j1">', "actuatorgravcomp", "not supported"]),
    "parameter-clash": ('<mujoco><worldbody><body name="f"><joint name="a-b" type="free" damping="1"/><geom size=".1"/>'
                        '</body><body name="h"><joint name="a_b" damping="1"/><geom size=".1"/></body></worldbody>'
                        '</mujoco>', ["runtime parameter the name 'damping_a_b'", "rename one"]),
    "no-joint": ('<mujoco><worldbody><body name="a"><geom size=".1"/></body></worldbody></mujoco>', ["no joint"]),
    "compiler": ('<mujoco><worldbody><body name="a"><joint name="j" bogus="1"/><geom size=".1"/></body></worldbody>'
                 '</mujoco>', ["MuJoCo's compiler refuses the file", "bogus"]),
    "not-xml": ("<mujoco><worldbody></mujoco>", ["not XML: mismatched tag"]),
    "entity": ('<?xml version="1.0"?>\n<!DOCTYPE mujoco [<!ENTITY a "aaaaaaaa">]>\n<mujoco model="&a;"/>',
               ["<!DOCTYPE>", "entity declaration"]),
    "external-dtd": ('<?xml version="1.0"?>\n<!DOCTYPE mujoco SYSTEM "http://example.com/x.dtd">\n<mujoco/>',
                     ["external DTD"]),
    "include-outside": ('<mujoco><include file="../outside.xml"/><worldbody/></mujoco>',
                        ['<include file="../outside.xml">', "outside the model's folder"]),
    "include-absolute": ('<mujoco><include file="/etc/hostname"/><worldbody/></mujoco>',
                         ['<include file="/etc/hostname">', "resolves to /etc/hostname, outside the model's folder",
                          "--model-root / admits it"]),
}


@pytest.mark.parametrize("case", sorted(UNSUPPORTED))
def test_refused(tmp_path, capsys, case):
    text, fragments = UNSUPPORTED[case]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        refused(tmp_path, capsys, text, fragments)


def test_include_inside_is_read_and_a_nested_include_outside_refused(tmp_path, capsys):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "arm.xml").write_text('<mujoco><worldbody><body name="a"><joint name="j"/>'
                                                '<geom size=".1"/></body></worldbody></mujoco>')
    text = '<mujoco model="m"><include file="parts/arm.xml"/></mujoco>'
    (tmp_path / "m.xml").write_text(text)
    assert load(tmp_path / "m.xml").nv == 1
    (tmp_path / "parts" / "arm.xml").write_text('<mujoco><include file="../../evil.xml"/></mujoco>')
    code, err, out, path = run(tmp_path, capsys, None, name="m.xml")
    assert code == 2 and "outside the model's folder" in err and str(tmp_path / "parts" / "arm.xml") in err


def test_oversized_file(tmp_path, capsys):
    with open(tmp_path / "big.xml", "wb") as f:
        f.write(b"<mujoco><!--")
        f.seek(mjcf_source.MAX_BYTES)
        f.write(b"--></mujoco>\n")  # a sparse file just over the limit
    refused(tmp_path, capsys, None, ["larger than 64 MiB"], name="big.xml")


def test_the_inertia_box_fluid_is_in_the_equations(tmp_path):
    """(tests/test_fluid.py has the rest.)  No warning: the bodies' boxes are in the passive forces."""
    path = tmp_path / "m.xml"
    path.write_text('<mujoco><option density="1000"/>' + ARM.format(attrs="", extra="", after="")[8:])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = load(path)
    assert model.fluid and "this model has some" not in model.meta["mjcf"]["not_in_the_equations"]


def test_compiler_warnings_become_model_warnings(tmp_path, monkeypatch):
    """MuJoCo's warnings (cheetah's deprecated settotalmass) are ModelWarnings, not text on stdout and a log file."""
    monkeypatch.chdir(tmp_path)
    with pytest.warns(UserWarning, match="MuJoCo's compiler warns: compiler attribute 'settotalmass'"):
        load(SUITE / "cheetah.xml")
    assert not list(tmp_path.iterdir())


def test_inactive_equality_is_a_warning(tmp_path):
    path = tmp_path / "m.xml"
    path.write_text(ARM.format(attrs="", extra='<body name="b"><joint name="j2"/><geom size=".1"/></body>',
                               after='<equality><joint name="tie" joint1="j1" joint2="j2" active="false"/>'
                                     '</equality>'))
    with pytest.warns(UserWarning, match="inactive joint equality is not in the equations"):
        model = load(path)
    assert model.meta["mjcf"]["inactive_equalities"] == ["tie"]


def test_urdf_options_are_refused(scene, capsys, tmp_path):
    code = cli.main(["generate", str(scene), "-o", str(tmp_path / "o"), "-q", "--floating-base", "quaternion"])
    assert code == 2 and "the MJCF reader does not accept --floating-base" in capsys.readouterr().err


def test_inertial_parameters_of_a_body_against_mujoco(scene):
    """--inertial-parameters on an MJCF body: its mass set tenfold and to a hundredth through p equals MuJoCo with
    that body_mass (inertia about the centre of mass kept, as MuJoCo keeps body_inertia).  (A hundredfold mass
    makes A's condition number 3e4 and the test's own float arithmetic of the parameters, I about the origin from
    I about the centre of mass, loses 1e-13: beyond 1e-9 in q''.)"""
    from aggsym.model.transforms.inertials import with_inertial_parameters

    model = with_inertial_parameters(load(scene), ["lid"])
    twin = NumericTwin(model)
    names = [p.name for p in model.parameters]
    for scale in (10.0, 0.01):
        values = dict(zip(names, model.parameter_values))
        m0 = values["m_lid"]
        c = np.array([values[f"mc{a}_lid"] for a in "xyz"]) / m0
        I0 = np.array([[values["Ixx_lid"], values["Ixy_lid"], values["Ixz_lid"]],
                       [values["Ixy_lid"], values["Iyy_lid"], values["Iyz_lid"]],
                       [values["Ixz_lid"], values["Iyz_lid"], values["Izz_lid"]]])
        shift = lambda mass: mass * (c @ c * np.eye(3) - np.outer(c, c))  # noqa: E731
        m1 = scale * m0
        I1 = I0 - shift(m0) + shift(m1)
        values.update(m_lid=m1, mcx_lid=m1 * c[0], mcy_lid=m1 * c[1], mcz_lid=m1 * c[2], Ixx_lid=I1[0, 0],
                      Ixy_lid=I1[0, 1], Ixz_lid=I1[0, 2], Iyy_lid=I1[1, 1], Iyz_lid=I1[1, 2], Izz_lid=I1[2, 2])
        p = [values[n] for n in names]
        mj = mujoco_model(scene)
        mj.body_mass[mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_BODY, "lid")] = m1
        data = mujoco.MjData(mj)
        qpos, qvel, force = states(mj, np.random.default_rng(11))
        data.qpos[:], data.qvel[:], data.qfrc_applied[:] = qpos, qvel, force
        mujoco.mj_forward(mj, data)
        M = np.zeros((mj.nv, mj.nv))
        mujoco.mj_fullM(mj, data, M)
        q, qd, tau, J, cc = to_aggsym(mj, qpos, qvel, force)
        assert np.max(np.abs(twin.call("inertia", q, p=p) - J.T @ M @ J)) <= 1e-12 * np.max(np.abs(M))
        qacc = J @ twin.call("forward_dynamics", q, qd, tau, p=p) + cc
        assert np.max(np.abs(qacc - data.qacc)) <= 1e-9 * np.max(np.abs(data.qacc)), np.abs(qacc - data.qacc)


def test_energy_holds_the_rotors_and_a_constraint_on_a_body(scene, tmp_path):
    """T = 1/2 qd^T A qd with the armature (a free joint's too) in A; a --constraints side file names MJCF bodies."""
    from aggsym.model.readers.side_files import load_constraints

    model = load(scene)
    twin = NumericTwin(model)
    q, qd, _, _, _ = to_aggsym(mujoco_model(scene), *states(mujoco_model(scene), np.random.default_rng(13)))
    A = twin.call("inertia", q)
    assert twin.call("kinetic_energy", q, qd) == pytest.approx(0.5 * qd @ A @ qd, rel=1e-12)
    side = tmp_path / "contact.yaml"
    side.write_text("constraints:\n  - name: lid_tip\n    body: lid\n    point: [0.1, 0.2, 0.02]\n    block: point\n")
    constrained = load_constraints(side, model)
    assert constrained.constraint_rows == 3 and constrained.constraints[0].body == "lid"


def test_disable_flags_are_honoured(tmp_path):
    """<flag spring/damper/gravity="disable">: those terms leave the equations (and their parameters) as MuJoCo's."""
    path = tmp_path / "flags.xml"
    path.write_text(SCENE.replace('<option gravity="0.3 -0.2 -9.5"/>',
                                  '<option gravity="0.3 -0.2 -9.5"><flag spring="disable" damper="disable" '
                                  'gravity="disable"/></option>'))
    model = load(path)
    names = [p.name for p in model.parameters]
    assert not any(n.startswith(("damping_", "stiffness_", "springref_")) for n in names)
    assert model.parameter_values[-3:] == (0.0, 0.0, 0.0) and model.conservative
    worst = compare(path, model=model, samples=2)
    assert max(worst.values()) <= TOLERANCE, worst


def test_symbolic_equations_hold_the_damping(scene):
    """aggsym.symbolic's u* = A qdd + b + g + C (q - q0) + D qd for a model with joint damping."""
    import sympy as sp

    from aggsym.symbolic import Equations

    path = SUITE / "acrobot.xml"
    eq = Equations(load(path))
    D = sp.diag(*[sp.Symbol(f"damping_{n}", real=True) for n in ("shoulder", "elbow")])
    residual = eq.u_star - (eq.A * eq.qdd + eq.b + eq.g + eq.c + D * eq.qd)
    assert all(sp.simplify(x) == 0 for x in residual)


def test_unnamed_elements_get_distinct_names(tmp_path):
    path = tmp_path / "unnamed.xml"
    path.write_text('<mujoco><worldbody><body name="body2"><joint/><geom size=".1"/><body><joint/><geom size=".1"/>'
                    '<site/></body></body></worldbody></mujoco>')
    model = load(path)
    assert [f.name for f in model.link_table.frames] == ["world", "body2", "body2_", "site0"]
    assert [c.joint for c in model.coordinates] == ["joint0", "joint1"]


@pytest.mark.compiler
@pytest.mark.slow
def test_check_runs_every_routine_of_the_scene(scene, capsys):
    """``aggsym check`` on the scene (two free-flyers: integrate, the derivatives, the passive forces, the frames):
    the generated C and NumPy equal the numeric twin; ``ops`` and ``latex`` read it too."""
    assert cli.main(["check", str(scene), "--routines", "all", "--trials", "3"]) == 0
    out = capsys.readouterr().out
    assert "passive_forces" in out and "integrate" in out and "forward_dynamics_derivatives" in out
    assert cli.main(["ops", str(scene)]) == 0
    assert cli.main(["latex", str(scene)]) == 0 and "\\begin{document}" in capsys.readouterr().out


def test_unusual_names_are_escaped(tmp_path):
    """Quotes, comment ends, backslashes and newlines in MJCF names reach the generated Python only escaped: the
    module imports and keeps the original joint name."""
    import importlib.util

    path = tmp_path / "evil.xml"
    path.write_text('<mujoco model="e&quot;&quot;&quot;vil"><worldbody><body name="b&quot;&quot;&quot; */ \\n">'
                    '<joint name="j\'\'\'&quot;&quot;&quot;\\input{x} */" damping="1"/><geom size=".1"/>'
                    '<site name="s&#10;&quot;&quot;&quot;"/></body></worldbody></mujoco>')
    out = tmp_path / "out"
    assert cli.main(["generate", str(path), "-o", str(out), "-q", "--targets", "numpy,manifest"]) == 0
    module_path = next(out.glob("*.py"))
    spec = importlib.util.spec_from_file_location("evil_module", module_path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.JOINTS == ('j\'\'\'"""\\input{x} */',)
    assert module.passive_forces([0.0], [2.0]).tolist() == [-2.0]  # (n = 1: a vector of one entry, as A is 1 x 1)
