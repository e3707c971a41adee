"""MJCF equalities (issue 33, item 4): ``connect`` and ``weld`` as loop and weld constraints, linear ``joint`` and
fixed-tendon equalities as couplings (those that are no coupling become joint-space rows:
``tests/test_mjcf_tendons.py``; on spatial tendons through sites: ``tests/test_mjcf_spatial_equalities.py``),
equalities on spatial tendons wrapping around a geom refused by name.

MuJoCo's equalities are soft (solref/solimp), so its ``qacc`` is not the reference: the reference is a dense KKT
solve written here from MuJoCo's own mass matrix (``mj_fullM``, armature included), ``qfrc_bias`` and
``qfrc_passive``, and the constraint's Jacobian from ``mj_jac`` / ``mj_jacDot`` (the hard constraint):
``[M J^T; J 0] [qacc; -lambda] = [f - bias + passive; -J' qd]``, at states where the constraint holds (positions by
Newton on MuJoCo's own residual ``efc_pos``, velocities in the null space of its ``efc_J``)."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from aggsym import cli
from aggsym.model import load
from aggsym.twin import NumericTwin

mujoco = pytest.importorskip("mujoco")

from benchmarks.mjcf.mujoco_reference import to_aggsym  # noqa: E402

# a spatial four-bar: crank a (hinge y), coupler b (hinges y, x), rocker c (hinge y); b's end tied to c's by connect
FOUR_BAR = """<mujoco model="fourbar"><option gravity="0.3 -1 -9.81"><flag contact="disable"/></option><worldbody>
<body name="a"><joint name="crank" axis="0 1 0" damping="0.3" armature="0.05"/><geom type="capsule" fromto="0 0 0 .3 0 0" size=".02"/>
 <body name="b" pos=".3 0 0"><joint name="cy" axis="0 1 0"/><joint name="cx" axis="1 0 0" stiffness="2" springref=".1"/>
  <geom type="capsule" fromto="0 0 0 .5 0 .4" size=".03"/></body></body>
<body name="c" pos=".9 0 0"><joint name="rocker" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 -.1 0 .4" size=".02" mass="0.7"/></body>
</worldbody><equality><connect name="loop" body1="b" body2="c" anchor=".5 0 .4"/></equality></mujoco>"""

# two chains welded: b (four joints) onto c (three joints), a given relpose, anchor and torquescale
WELD = """<mujoco model="welded"><option><flag contact="disable"/></option><worldbody>
<body name="a"><joint name="a1" axis="0 0 1"/><joint name="a2" axis="0 1 0" damping=".2"/><geom size=".1" mass="2"/>
 <body name="b" pos=".4 0 0"><joint name="b1" type="slide" axis="1 0 0"/><joint name="b2" axis="1 0 0"/>
  <geom type="box" size=".2 .1 .05" mass="1.5"/></body></body>
<body name="c" pos="0 .8 .1" euler="10 -20 30"><joint name="c1" axis="0 1 0"/><joint name="c2" axis="0 0 1" armature=".1"/>
 <joint name="c3" type="slide" axis="0 0 1"/><geom type="box" size=".1 .3 .05" mass=".8"/></body>
</worldbody><equality><weld name="glue" body1="b" body2="c" anchor=".05 .1 -.02" relpose=".1 .2 .3 .9 .2 .3 .1" torquescale="2"/>
</equality></mujoco>"""

# a weld to the world (body1 the world: the sides swap)
WORLD_WELD = """<mujoco model="worldweld"><worldbody>
<body name="a"><joint name="a1" axis="0 0 1"/><joint name="a2" axis="0 1 0"/><joint name="a3" axis="1 0 0"/><geom size=".1"/>
 <body name="b" pos=".4 .1 0"><joint name="b1" type="slide" axis="1 0 0"/><joint name="b2" type="slide" axis="0 1 0"/>
  <joint name="b3" type="slide" axis="0 0 1"/><joint name="b4" axis="0 1 0"/><geom type="box" size=".2 .1 .05"/></body></body>
</worldbody><equality><weld name="pin" body1="world" body2="b" anchor=".1 0 0"/></equality></mujoco>"""

# a free body carrying an arm whose hand is held on a world point (connect to the world: a contact)
FREE_HELD = """<mujoco model="held"><option gravity="0 0 -9.81"/><worldbody>
<body name="f" pos="0 0 1"><freejoint name="fj"/><geom type="box" size=".2 .1 .05" mass="3"/>
 <body name="a" pos=".2 0 0"><joint name="j1" axis="0 1 0" damping=".4"/><geom type="capsule" fromto="0 0 0 .3 0 .1" size=".03"/>
  <body name="h" pos=".3 0 .1"><joint name="j2" axis="1 0 0"/><geom size=".04" mass=".05"/></body></body></body>
</worldbody><equality><connect name="hold" body1="h" body2="world" anchor="0 0 .04"/></equality></mujoco>"""

# a linear joint equality and a fixed-tendon equality on a chain of four hinges
COUPLED = """<mujoco model="coupled"><option gravity="0 0 -9.81"/><worldbody>
<body name="a"><joint name="j1" axis="0 1 0" damping=".1"/><geom type="capsule" fromto="0 0 0 .3 0 0" size=".03"/>
 <body name="b" pos=".3 0 0"><joint name="j2" axis="0 1 0" armature=".02"/><geom type="capsule" fromto="0 0 0 .3 0 0" size=".03"/>
  <body name="c" pos=".3 0 0"><joint name="j3" axis="1 0 0" ref=".2"/><geom type="capsule" fromto="0 0 0 .2 .1 0" size=".03"/>
   <body name="d" pos=".2 .1 0"><joint name="j4" axis="0 0 1" stiffness="1"/><geom type="capsule" fromto="0 0 0 .2 0 0" size=".03"/>
</body></body></body></body></worldbody>
<tendon><fixed name="t"><joint joint="j1" coef="0.4"/><joint joint="j4" coef="-1.6"/></fixed></tendon>
<equality><joint name="gear" joint1="j3" joint2="j2" polycoef=".05 -.7 0 0 0"/><tendon name="tie" tendon1="t" polycoef=".1 0 0 0 0"/>
</equality></mujoco>"""


def write(tmp_path, text, name="m.xml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def compiled(path):
    m = mujoco.MjModel.from_xml_path(str(path))
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    m.opt.jacobian = int(mujoco.mjtJacobian.mjJAC_DENSE)  # efc_J as a dense nefc x nv matrix
    return m


def efc_jacobian(m, d):
    """MuJoCo's constraint Jacobian efc_J as a dense nefc x nv matrix (stored sparse or dense)."""
    if d.efc_J.size == d.nefc * m.nv and not mujoco.mj_isSparse(m):
        return d.efc_J[:d.nefc * m.nv].reshape(d.nefc, m.nv).copy()
    J = np.zeros((d.nefc, m.nv))
    for i in range(d.nefc):
        a, n = d.efc_J_rowadr[i], d.efc_J_rownnz[i]
        J[i, d.efc_J_colind[a:a + n]] = d.efc_J[a:a + n]
    return J


def consistent_state(m, rng, spread=0.3):
    """(qpos, qvel) where MuJoCo's equality residual is zero (Newton on efc_pos) and its velocity too."""
    d = mujoco.MjData(m)
    d.qpos[:] = m.qpos0
    mujoco.mj_integratePos(m, d.qpos, rng.uniform(-spread, spread, m.nv), 1.0)
    for _ in range(100):
        mujoco.mj_forward(m, d)
        J, r = efc_jacobian(m, d), d.efc_pos[:d.nefc]
        if np.max(np.abs(r)) < 1e-15:
            break
        mujoco.mj_integratePos(m, d.qpos, -np.linalg.lstsq(J, r, rcond=None)[0], 1.0)
    assert np.max(np.abs(r)) < 1e-13
    null = np.linalg.svd(J)[2][np.linalg.matrix_rank(J):]
    return d.qpos.copy(), null.T @ rng.normal(size=null.shape[0])


def reference(m, qpos, qvel, force, jacobian):
    """The hard-constrained qacc and lambda from MuJoCo's M, qfrc_bias and qfrc_passive (constraints disabled),
    with ``jacobian(m, d) -> (J, J' qd)``."""
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:], d.qfrc_applied[:] = qpos, qvel, force
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    J, Jdqd = jacobian(m, d)
    k = J.shape[0]
    K = np.block([[M, J.T], [J, np.zeros((k, k))]])
    x = np.linalg.solve(K, np.concatenate([force - d.qfrc_bias + d.qfrc_passive, -Jdqd]))
    m.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    return x[:m.nv], -x[m.nv:]


def point_rows(m, d, b1, b2, point, rotations):
    """J and J' qd of the relative motion of body b1's and body b2's material points at ``point`` (world), and of
    their angular velocities when ``rotations``."""
    out, rates = [], []
    for b, sign in ((b1, 1), (b2, -1)):
        if b == 0:
            continue
        jp, jr, dp, dr = (np.zeros((3, m.nv)) for _ in range(4))
        mujoco.mj_jac(m, d, jp, jr, point, b)
        mujoco.mj_jacDot(m, d, dp, dr, point, b)
        out.append(sign * (np.vstack([jp, jr]) if rotations else jp))
        rates.append(sign * (np.vstack([dp, dr]) if rotations else dp) @ d.qvel)
    return sum(out), sum(rates)


def check_against_kkt(path, body1, body2, rotations, seeds=(1, 2, 3)):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = load(path)
    twin = NumericTwin(model)
    m = compiled(path)
    b1, b2 = (mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, n) for n in (body1, body2))
    sites = m.eq_objtype[0] == mujoco.mjtObj.mjOBJ_SITE
    worst = 0.0
    for seed in seeds:
        rng = np.random.default_rng(seed)
        qpos, qvel = consistent_state(m, rng)
        force = rng.normal(size=m.nv) * 3

        def jacobian(m, d):
            anchor = m.eq_data[0][0:3] if m.eq_type[0] == 0 else m.eq_data[0][3:6]
            point = d.site_xpos[m.eq_obj1id[0]] if sites else d.xpos[b1] + d.xmat[b1].reshape(3, 3) @ anchor
            return point_rows(m, d, b1, b2, point, rotations)

        qacc, _ = reference(m, qpos, qvel, force, jacobian)
        q, qd, tau, conversion, c = to_aggsym(m, qpos, qvel, force)  # (free joints: MuJoCo's qvel = conversion qd)
        assert np.max(np.abs(twin.call("constraint_residual", q))) < 1e-12  # holds where MuJoCo's does
        qdd, lam = twin.call("constrained_forward_dynamics", q, qd, tau)
        worst = max(worst, np.max(np.abs(conversion @ qdd + c - qacc)) / np.max(np.abs(qacc)))
        # the multipliers: A qdd + d = tau + J^T lambda with aggsym's own J
        J = twin.call("constraint_jacobian", q)
        A = twin.call("inertia", q)
        d = twin.call("nonlinear_effects", q, qd)
        assert np.allclose(A @ qdd + d, tau + J.T @ lam, rtol=0, atol=1e-10 * np.max(np.abs(tau)))
    assert worst <= 1e-8, worst
    return model


def test_connect_closes_a_four_bar(tmp_path):
    model = check_against_kkt(write(tmp_path, FOUR_BAR), "b", "c", rotations=False)
    (c,) = model.constraints
    assert (c.name, c.body, c.medium, c.rows) == ("loop", "b", "c", ("o1", "o2", "o3"))
    assert model.meta["mjcf"]["equalities"] == [
        {"equality": "loop", "type": "connect", "became": "constraint 'loop' (point: b on c)"}]


def test_weld_between_two_chains(tmp_path):
    model = check_against_kkt(write(tmp_path, WELD), "b", "c", rotations=True)
    (c,) = model.constraints
    assert c.kind == "weld" and len(c.rows) == 6
    assert "torquescale 2" in model.meta["mjcf"]["equalities"][0]["became"]


def test_weld_between_sites(tmp_path):
    """site1's frame welded on site2's (MuJoCo's site semantics: no anchor, no relpose)."""
    text = (WELD.replace('<geom type="box" size=".2 .1 .05" mass="1.5"/>',
                         '<geom type="box" size=".2 .1 .05" mass="1.5"/><site name="s1" pos=".1 .2 .3" euler="5 15 25"/>')
            .replace('<geom type="box" size=".1 .3 .05" mass=".8"/>',
                     '<geom type="box" size=".1 .3 .05" mass=".8"/><site name="s2" pos="-.1 .05 .2" euler="-30 10 5"/>')
            .replace('body1="b" body2="c" anchor=".05 .1 -.02" relpose=".1 .2 .3 .9 .2 .3 .1" torquescale="2"',
                     'site1="s1" site2="s2"'))
    model = check_against_kkt(write(tmp_path, text), "b", "c", rotations=True)
    assert model.constraints[0].kind == "weld"


def test_weld_to_the_world(tmp_path):
    model = check_against_kkt(write(tmp_path, WORLD_WELD), "b", "world", rotations=True)
    (c,) = model.constraints
    assert (c.body, c.medium) == ("b", "world")


def test_connect_to_the_world_on_a_free_body(tmp_path):
    """A free-flyer's arm held at a world point (masses over two decades: 3 kg, 0.05 kg), free joint converted."""
    model = check_against_kkt(write(tmp_path, FREE_HELD), "h", "world", rotations=False)
    (c,) = model.constraints
    assert (c.body, c.medium) == ("h", "world")


def test_residual_translation_is_mujocos(tmp_path):
    """Away from the constraint, the translational residual is MuJoCo's efc_pos in body2's axes (connect)."""
    path = write(tmp_path, FOUR_BAR)
    twin = NumericTwin(load(path))
    m = compiled(path)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(5)
    for _ in range(3):
        d.qpos[:] = rng.uniform(-2, 2, m.nq)
        mujoco.mj_forward(m, d)
        R2 = d.xmat[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "c")].reshape(3, 3)
        assert np.allclose(twin.call("constraint_residual", d.qpos), R2.T @ d.efc_pos[:3], rtol=0, atol=1e-13)


def test_joint_and_tendon_equalities_are_couplings(tmp_path):
    """j3 = -0.7 j2 + (ref3 + 0.05 + 0.7 ref2); the tendon 0.4 j1 - 1.6 j4 held at length0 + 0.1: j4 = 0.25 j1 + c.
    The coupled forward dynamics equals the KKT solve with the constant rows; A is J^T M J."""
    path = write(tmp_path, COUPLED)
    model = load(path)
    assert [(c.coordinate, c.master) for c in model.couplings] == [("j3", "j2"), ("j4", "j1")]
    assert [c.multiplier for c in model.couplings] == pytest.approx([-0.7, 0.25], rel=1e-15)
    became = [e["became"] for e in model.meta["mjcf"]["equalities"]]
    assert became[0].startswith("coupling j3 = ") and became[1].startswith("coupling j4 = ")
    twin = NumericTwin(model)
    m = compiled(path)
    free = [0, 1]  # j1, j2: q's coordinates
    for seed in (1, 2, 3):
        rng = np.random.default_rng(seed)
        qpos, qvel = consistent_state(m, rng, spread=1.0)
        force = rng.normal(size=m.nv) * 2
        force[2:] = 0  # the coupled coordinates carry no actuator of their own
        C = np.zeros((2, m.nv))
        C[0, [2, 1]] = 1, 0.7
        C[1, [0, 3]] = 0.4, -1.6
        qacc, _ = reference(m, qpos, qvel, force, lambda m, d: (C, np.zeros(2)))
        qdd = twin.call("forward_dynamics", qpos[free], qvel[free], force[free])
        assert np.max(np.abs(qdd - qacc[free])) <= 1e-12 * np.max(np.abs(qacc))
        Jc = np.zeros((m.nv, 2))
        Jc[0, 0] = Jc[1, 1] = 1
        Jc[2, 1], Jc[3, 0] = -0.7, 0.25
        assert np.allclose(Jc @ qvel[free], qvel, rtol=0, atol=1e-14)
        d = mujoco.MjData(m)
        d.qpos[:] = qpos
        mujoco.mj_forward(m, d)
        M = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M)
        assert np.max(np.abs(twin.call("inertia", qpos[free]) - Jc.T @ M @ Jc)) <= 1e-13 * np.max(np.abs(M))


ARM = """<mujoco><worldbody><body name="a"><joint name="j1"/><geom size=".1"/><site name="s1"/>
<body name="b" pos="0 0 -.3"><joint name="j2"/><joint name="j3" axis="1 0 0"/><geom size=".1"/><site name="s2"/></body></body>
<body name="c" pos="1 0 0"><joint name="j4" type="ball"/><geom size=".1"/></body>
<body name="w" pos="0 1 0"><geom name="ball" size=".1"/></body></worldbody>{after}</mujoco>"""

REFUSED = {  # (nonlinear, one-coordinate, three-coordinate, chained, free-joint and mixed equalities are joint-space
    # constraint rows: tests/test_mjcf_tendons.py)
    "spatial": ('<tendon><spatial name="rope"><site site="s1"/><geom geom="ball"/><site site="s2"/></spatial>'
                '</tendon><equality><tendon name="len" tendon1="rope"/></equality>',
                ['<tendon name="len">', "'rope' is a spatial tendon wrapping around a geom"]),
    "on-free": ('<equality><joint name="b" joint1="j4" joint2="j1"/></equality>',
                ["only HINGE and SLIDE joint allowed in constraint"]),  # (MuJoCo's compiler refuses it)
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_refused(tmp_path, capsys, case):
    after, fragments = REFUSED[case]
    text = ARM.format(after=after)
    text = text.replace('<joint name="j4" type="ball"/>', '<freejoint name="j4"/>' if case == "on-free" else
                        '<joint name="j4"/>')
    path = write(tmp_path, text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = cli.main(["generate", str(path), "-o", str(tmp_path / "out"), "-q"])
    err = capsys.readouterr().err
    assert code == 2
    for fragment in fragments:
        assert fragment in err, f"{fragment!r} not in {err!r}"


def test_an_equality_within_one_rigid_body_is_left_out_with_a_warning(tmp_path):
    text = ARM.format(after='<equality><connect name="self" body1="w" body2="world" anchor="0 0 0"/></equality>')
    path = write(tmp_path, text.replace('<joint name="j4" type="ball"/>', '<joint name="j4"/>'))
    with pytest.warns(UserWarning, match="connect equality joins two points of one rigid body"):
        model = load(path)
    assert not model.constraints
    assert model.meta["mjcf"]["equalities"][0]["became"].startswith("nothing (joins two points of one rigid body")


def test_inactive_equality_stays_listed(tmp_path):
    path = write(tmp_path, FOUR_BAR.replace('anchor=".5 0 .4"', 'anchor=".5 0 .4" active="false"'))
    with pytest.warns(UserWarning, match="inactive connect equality"):
        model = load(path)
    assert not model.constraints
    assert model.meta["mjcf"]["equalities"] == [{"equality": "loop", "type": "connect", "became": "nothing (inactive)"}]


def test_generate_writes_the_equalities_in_the_manifest(tmp_path):
    import json

    path = write(tmp_path, FOUR_BAR)
    assert cli.main(["generate", str(path), "-o", str(tmp_path / "out"), "-q", "--targets", "manifest"]) == 0
    manifest = json.loads((tmp_path / "out" / "m.json").read_text())  # (named after m.xml)
    assert "constraint 'loop'" in json.dumps(manifest)


def _suite(name):
    dm_control = pytest.importorskip("dm_control")
    from pathlib import Path

    return Path(dm_control.__file__).parent / "suite" / name


def test_manipulator_loads_with_its_tendon_coupling():
    """dm_control's manipulator: the tendon equality 'coupling' (-0.5 thumb + 0.5 finger held at 0) is the coupling
    finger = thumb; A, the forces and q'' (the hard coupling, dense KKT from MuJoCo's M and bias) agree <= 1e-9."""
    from benchmarks.mjcf.mujoco_reference import compare

    path = _suite("manipulator.xml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = load(path)
    assert [(c.coordinate, c.master, c.multiplier, c.offset) for c in model.couplings] == [
        ("finger", "thumb", 1.0, 0.0)]
    worst = compare(path, model=model, samples=2, seed=3)
    assert max(worst.values()) <= 1e-9, worst


def test_a_side_file_adds_to_the_equalities(tmp_path):
    """--constraints on an MJCF model with a connect: the side file's constraints come after the file's own (none
    dropped); a name the file already uses is refused."""
    from aggsym.errors import ModelError
    from aggsym.model.readers.side_files import load_constraints

    model = load(write(tmp_path, FOUR_BAR))
    side = write(tmp_path, "constraints:\n  - name: tip\n    body: a\n    point: [0.3, 0, 0]\n    block: normal\n",
                 "side.yaml")
    both = load_constraints(side, model)
    assert [c.name for c in both.constraints] == ["loop", "tip"] and both.constraint_rows == 4
    side.write_text("constraints:\n  - name: loop\n    body: a\n    block: normal\n")
    with pytest.raises(ModelError, match="already has a constraint named 'loop'"):
        load_constraints(side, model)
