"""MJCF joint and fixed-tendon equalities that are no one-to-one coupling (joint-space constraint rows), the springs
and dampers of fixed tendons, and frictionloss as Coulomb friction on request.

References: MuJoCo itself.  The rows against a dense KKT solve built from MuJoCo's own data (``mj_fullM``, the
equality rows of its ``efc_J``, gamma by central differences of that J; :func:`benchmarks.mjcf.mujoco_reference.
compare_constrained`) <= 1e-8, and phi against MuJoCo's ``efc_pos``; the tendon forces against MuJoCo's
``qfrc_passive`` and ``qacc`` (:func:`benchmarks.mjcf.mujoco_reference.compare`) <= 1e-9.
"""
from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from aggsym import cli
from aggsym.errors import ModelError
from aggsym.model import load
from aggsym.twin import NumericTwin

mujoco = pytest.importorskip("mujoco")

from benchmarks.mjcf.mujoco_reference import (  # noqa: E402
    compare, compare_constrained, equality_model, mujoco_model, states,
)

# a chain of four hinges and a slide; the equalities are set per test
CHAIN = """<mujoco model="chain"><worldbody>
<body name="a"><joint name="j1" axis="0 1 0"/><geom type="capsule" size=".05" fromto="0 0 0 0 0 -.3"/>
<body name="b" pos="0 0 -.3"><joint name="j2" axis="0 1 0"/><geom type="capsule" size=".04" fromto="0 0 0 .2 0 -.3"/>
<body name="c" pos=".2 0 -.3"><joint name="j3" axis="1 0 0"/><geom size=".05"/>
<body name="d" pos="0 .1 -.1"><joint name="j4" axis="0 0 1"/><geom size=".04"/>
<body name="e" pos="0 .1 0"><joint name="j5" type="slide" axis="1 1 0"/><geom size=".03"/></body>
</body></body></body></body>
{free}</worldbody>{after}</mujoco>"""

FREE_BODY = ('<body name="f" pos="1 0 0"><freejoint name="fly"/><geom size=".1"/>'
             '<body name="g" pos="0 0 -.2"><joint name="k1" axis="1 0 0"/><geom size=".05"/></body></body>')

TRIPLE = ('<tendon><fixed name="tri"><joint joint="j1" coef=".4"/><joint joint="j2" coef="-1.2"/>'
          '<joint joint="j4" coef=".7"/></fixed></tendon><equality><tendon name="tie3" tendon1="tri" '
          'polycoef=".1 0 0 0 0"/></equality>')

EQUALITIES = {
    "three coordinates": TRIPLE,
    "nonlinear": '<equality><joint name="poly" joint1="j3" joint2="j2" polycoef=".05 -.7 .4 -.3 .2"/></equality>',
    "one coordinate": '<equality><joint name="lock" joint1="j5" polycoef=".02 0 0 0 0"/></equality>',
    "chained": ('<equality><joint name="e1" joint1="j2" joint2="j1" polycoef="0 .5 0 0 0"/>'
                '<joint name="e2" joint1="j3" joint2="j2" polycoef=".1 -2 0 0 0"/></equality>'),
    "tendon to tendon": ('<tendon><fixed name="t1"><joint joint="j1" coef="1"/><joint joint="j3" coef=".5"/></fixed>'
                         '<fixed name="t2"><joint joint="j4" coef="2"/><joint joint="j5" coef="-1"/></fixed></tendon>'
                         '<equality><tendon name="tt" tendon1="t1" tendon2="t2" polycoef="0 .8 -.3 0 0"/></equality>'),
    "beside a connect": ('<equality><joint name="e1" joint1="j2" joint2="j1" polycoef="0 .5 0 0 0"/>'
                         '<connect name="pin" body1="e" body2="world" anchor="0 0 0"/></equality>'),
}


def write(tmp_path, text, name="m.xml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def quiet_load(path, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load(path, **options)


@pytest.mark.parametrize("case", sorted(EQUALITIES))
def test_rows_against_a_dense_kkt_solve_from_mujoco(tmp_path, case):
    """Each equality that is no coupling becomes a joint-space row; A, J, q'' and lambda against the dense KKT solve
    of MuJoCo's M, equality rows and gamma (central differences) <= 1e-8; with a free body beside the chain too."""
    for free in ("", FREE_BODY):
        path = write(tmp_path, CHAIN.format(free=free, after=EQUALITIES[case]))
        model = quiet_load(path)
        assert not model.couplings
        rows = [c for c in model.constraints if c.joint_row is not None]
        assert rows and all(c.kind == "joint" and c.rows == ("joint",) for c in rows)
        worst = compare_constrained(path, model=model, samples=3, seed=7)
        assert max(worst.values()) <= 1e-8, (case, free, worst)
        # the unconstrained equations are MuJoCo's as before
        assert max(compare(path, model=model, samples=2).values()) <= 1e-9


@pytest.mark.parametrize("case", ["three coordinates", "nonlinear", "tendon to tendon", "one coordinate"])
def test_residual_is_mujocos_efc_pos(tmp_path, case):
    """phi of a joint-space row equals MuJoCo's equality residual (efc_pos) at random states, and J its efc_J."""
    path = write(tmp_path, CHAIN.format(free="", after=EQUALITIES[case]))
    model = quiet_load(path)
    twin = NumericTwin(model)
    m = equality_model(path)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(3)
    for _ in range(4):
        qpos, _, _ = states(m, rng)
        d.qpos[:] = qpos
        mujoco.mj_forward(m, d)
        eq = np.array(d.efc_type[:d.nefc]) == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)
        phi = twin.call("constraint_residual", qpos)
        J = np.array(twin.call("constraint_jacobian", qpos)).reshape(model.constraint_rows, model.nv)
        assert np.max(np.abs(phi - np.array(d.efc_pos[:d.nefc])[eq])) <= 1e-12
        J_ref = np.array(d.efc_J[:d.nefc * m.nv]).reshape(d.nefc, m.nv)[eq]
        assert np.max(np.abs(J - J_ref)) <= 1e-12 * max(1.0, np.max(np.abs(J_ref)))


def test_a_linear_row_has_no_rate_term(tmp_path):
    """gamma = J' qd of a linear row is exactly 0 (its J is constant)."""
    model = quiet_load(write(tmp_path, CHAIN.format(free="", after=TRIPLE)))
    rng = np.random.default_rng(1)
    gamma = NumericTwin(model).call("constraint_bias", rng.normal(size=model.nq), rng.normal(size=model.nv))
    assert np.all(gamma == 0.0)


def test_nonlinear_rate_term_by_central_differences(tmp_path):
    """gamma of the polynomial row equals d/dt (J) qd by central differences of the routine's own J."""
    model = quiet_load(write(tmp_path, CHAIN.format(free="", after=EQUALITIES["nonlinear"])))
    twin = NumericTwin(model)
    rng = np.random.default_rng(2)
    q, qd = rng.normal(size=model.nq), rng.normal(size=model.nv)
    h = 1e-6
    J = [np.array(twin.call("constraint_jacobian", q + s * h * qd)).reshape(1, -1) for s in (1, -1)]
    fd = (J[0] - J[1]) @ qd / (2 * h)
    assert np.allclose(twin.call("constraint_bias", q, qd), fd, rtol=1e-7, atol=1e-9)


def _suite(name):
    from pathlib import Path

    dm_control = pytest.importorskip("dm_control")
    return Path(dm_control.__file__).parent / "suite" / name


def test_quadruped_loads_with_its_three_joint_tendon_equalities():
    """dm_control's quadruped: four fixed tendons tying three joints each, held at their length (a free body): four
    joint-space rows; constrained q'' and lambda against the dense KKT solve from MuJoCo <= 1e-8, and the
    unconstrained equations against MuJoCo <= 1e-9."""
    path = _suite("quadruped.xml")
    model = quiet_load(path)
    assert [c.kind for c in model.constraints] == ["joint"] * 4 and not model.couplings
    assert all(len(c.joint_row.first) == 3 and not c.joint_row.second for c in model.constraints)
    worst = compare_constrained(path, model=model, samples=2, seed=5)
    assert max(worst.values()) <= 1e-8, worst
    assert max(compare(path, model=model, samples=1).values()) <= 1e-9


def test_a_row_without_coordinates_is_left_out_with_a_warning(tmp_path):
    """t1 = j1 + j2 held at twice t2 = (j1 + j2)/2: the row's coefficients cancel."""
    text = CHAIN.format(free="", after='<tendon><fixed name="t1"><joint joint="j1" coef="1"/>'
                                       '<joint joint="j2" coef="1"/></fixed><fixed name="t2"><joint joint="j1" coef=".5"/><joint joint="j2" '
                                       'coef=".5"/></fixed></tendon><equality><tendon name="self" tendon1="t1" '
                                       'tendon2="t2" polycoef="0 2 0 0 0"/></equality>')
    with pytest.warns(UserWarning, match="no coordinate appears in its row"):
        model = load(write(tmp_path, text))
    assert not model.constraints and not model.couplings
    assert model.meta["mjcf"]["equalities"][0]["became"].startswith("nothing (no coordinate")


def test_the_manifest_describes_the_rows(tmp_path):
    path = write(tmp_path, CHAIN.format(free="", after=TRIPLE))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert cli.main(["generate", str(path), "-o", str(tmp_path / "out"), "-q", "--targets", "manifest"]) == 0
    manifest = json.loads((tmp_path / "out" / "m.json").read_text())
    (row,) = manifest["constraints"]["constraints"]
    assert row["kind"] == "joint" and row["lambda"] == [0, 1]
    assert [name for name, _ in row["first"]] == ["j1", "j2", "j4"]
    assert "joint-space row" in manifest["mjcf"]["equalities"][0]["became"]


def test_generated_numpy_module_agrees_with_the_twin(tmp_path):
    """aggsym check (NumPy target) on a model with rows, a nonlinear row, tendon springs and dampers."""
    after = ('<tendon><fixed name="tri"><joint joint="j1" coef=".4"/><joint joint="j2" coef="-1.2"/>'
             '<joint joint="j4" coef=".7"/></fixed>'
             '<fixed name="s" stiffness="3" springlength="-.1 .2" damping=".5"><joint joint="j3" coef="1"/>'
             '<joint joint="j5" coef="-2"/></fixed></tendon>'
             '<equality><tendon name="tie3" tendon1="tri"/>'
             '<joint name="poly" joint1="j3" joint2="j2" polycoef=".05 -.7 .4 -.3 .2"/></equality>')
    path = write(tmp_path, CHAIN.format(free="", after=after))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = cli.main(["check", str(path), "--targets", "numpy", "--trials", "3"])
    assert code == 0


# tendon springs and dampers ---------------------------------------------------------------------------------------
TENDONS = ('<tendon><fixed name="spring" stiffness="3" springlength=".4" damping=".7"><joint joint="j1" coef=".5"/>'
           '<joint joint="j2" coef="-1.5"/><joint joint="j5" coef="2"/></fixed>'
           '<fixed name="band" stiffness="5" springlength="-.2 .3"><joint joint="j2" coef="1"/>'
           '<joint joint="j3" coef=".8"/></fixed>'
           '<fixed name="damper" damping="1.1"><joint joint="j3" coef="1"/><joint joint="j4" coef="-1"/></fixed>'
           '</tendon>')


def _passive_against_mujoco(path, model, qpos_list, qvel_list):
    twin = NumericTwin(model)
    m = mujoco_model(path)
    d = mujoco.MjData(m)
    worst = 0.0
    for qpos, qvel in zip(qpos_list, qvel_list):
        d.qpos[:], d.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, d)
        ref = np.array(d.qfrc_passive)
        worst = max(worst, float(np.max(np.abs(twin.call("passive_forces", qpos, qvel) - ref)) /
                         max(np.max(np.abs(ref)), 1e-300)))
    return worst


def test_tendon_springs_and_dampers_against_mujoco(tmp_path):
    """A linear spring with a damper, a spring with a dead band (lengths below, inside and above it) and a pure
    damper on three fixed tendons: passive_forces against MuJoCo's qfrc_passive, and A, b + g - passive and q''
    against MuJoCo's <= 1e-9; runtime parameters named after the tendons; not conservative (dampers)."""
    path = write(tmp_path, CHAIN.format(free=FREE_BODY, after=TENDONS))
    model = quiet_load(path)
    names = [p.name for p in model.parameters if p.name.startswith("tendon_")]
    assert names == ["tendon_stiffness_spring", "tendon_springlength_spring", "tendon_damping_spring",
                     "tendon_stiffness_band", "tendon_springlower_band", "tendon_springupper_band",
                     "tendon_damping_damper"]
    assert not model.conservative
    m = mujoco_model(path)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(4)
    band = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, "band")
    qpos_list, qvel_list, where = [], [], set()
    for scale in (1.0, 0.05, 0.5, 1.0, 0.1, 2.0):
        for _ in range(4):
            qpos, qvel, _ = states(m, rng)
            a, b = m.jnt_qposadr[1], m.jnt_qposadr[2]  # j2, j3 (the band)
            qpos[a], qpos[b] = scale * qpos[a], scale * qpos[b]
            d.qpos[:] = qpos
            mujoco.mj_forward(m, d)
            length = d.ten_length[band]
            where.add("below" if length < -.2 else "above" if length > .3 else "inside")
            qpos_list.append(qpos)
            qvel_list.append(qvel)
    assert where == {"below", "inside", "above"}
    assert _passive_against_mujoco(path, model, qpos_list, qvel_list) <= 1e-12
    worst = compare(path, model=model, samples=4, seed=2)
    assert max(worst.values()) <= 1e-9, worst


def test_fish_tendon_spring_against_mujoco():
    """dm_control's fish: its tendon spring (fins_sym) and joint dampers against MuJoCo's qfrc_passive and qacc."""
    path = _suite("fish.xml")
    model = quiet_load(path)
    assert [t.name for t in model.tendons] == ["fins_sym"]
    worst = compare(path, model=model, samples=4, seed=1)  # (passive: passive_forces against qfrc_passive)
    assert max(worst.values()) <= 1e-9, worst


def test_tendon_spring_energy_is_the_potential_of_its_force(tmp_path):
    """With springs only (no damper): conservative, and the gradient of U (gravity, joint and tendon springs, the
    dead band included) by central differences is the left-side force at rest, nonlinear_effects(q, 0)."""
    text = CHAIN.format(free="", after=TENDONS.replace(' damping=".7"', "").replace(
        '<fixed name="damper" damping="1.1"><joint joint="j3" coef="1"/><joint joint="j4" coef="-1"/></fixed>', ""))
    model = quiet_load(write(tmp_path, text.replace('<joint name="j3" axis="1 0 0"/>',
                                                    '<joint name="j3" axis="1 0 0" stiffness="2" springref=".3"/>')))
    assert model.conservative
    twin = NumericTwin(model)
    rng = np.random.default_rng(6)
    h = 1e-6
    for _ in range(3):
        q = rng.normal(size=model.nq)
        grad = np.array([(twin.call("potential_energy", q + h * e) - twin.call("potential_energy", q - h * e)) / (2 * h)
                         for e in np.eye(model.nq)]).reshape(-1)
        assert np.allclose(grad, twin.call("nonlinear_effects", q, np.zeros(model.nv)), rtol=1e-6, atol=1e-7)


def test_disabled_springs_and_dampers_leave_the_tendons_out(tmp_path):
    text = CHAIN.format(free="", after=TENDONS).replace("<worldbody>",
                                                        '<option><flag spring="disable" damper="disable"/></option>'
                                                        '<worldbody>', 1)
    model = quiet_load(write(tmp_path, text))
    assert model.tendons == () and not [p for p in model.parameters if p.name.startswith("tendon_")]


def test_a_spatial_tendon_spring_is_read_beside_the_fixed_ones(tmp_path):
    """A spatial tendon through two sites (tests/test_spatial_tendons.py has the rest): a SpatialTendon, not a
    fixed one, and its passive force is MuJoCo's."""
    text = CHAIN.format(free="", after='<tendon><spatial name="rope" stiffness="1"><site site="s1"/><site site="s2"/>'
                                       '</spatial></tendon>').replace(
        '<geom size=".05"/>', '<geom size=".05"/><site name="s1"/>', 1).replace(
        '<geom size=".03"/>', '<geom size=".03"/><site name="s2"/>', 1)
    path = write(tmp_path, text)
    model = quiet_load(path)
    assert [t.name for t in model.spatial_tendons] == ["rope"] and not model.tendons
    worst = compare(path, model=model, samples=3)
    assert worst["passive"] <= 1e-12 and max(worst.values()) <= 1e-9, worst


# frictionloss ----------------------------------------------------------------------------------------------------
FRICTION = CHAIN.replace('<joint name="j2" axis="0 1 0"/>',
                         '<joint name="j2" axis="0 1 0" frictionloss=".8"/>').replace(
    '<joint name="j5" type="slide" axis="1 1 0"/>', '<joint name="j5" type="slide" axis="1 1 0" frictionloss="1.5"/>')
FRICTION_TENDON = ('<tendon><fixed name="rub" frictionloss=".6"><joint joint="j1" coef="1"/>'
                   '<joint joint="j4" coef="-.5"/></fixed></tendon>')


def test_frictionloss_is_listed_and_left_out_by_default(tmp_path):
    path = write(tmp_path, FRICTION.format(free="", after=FRICTION_TENDON))
    model = quiet_load(path)
    assert not model.coulomb and not model.tendons and model.conservative
    joints = {j["joint"]: j for j in model.meta["mjcf"]["joints"]}
    assert joints["j2"]["frictionloss"] == 0.8 and joints["j5"]["frictionloss"] == 1.5
    assert model.meta["mjcf"]["tendons"] == [{"tendon": "rub", "type": "fixed", "in_the_equations": False,
                                              "frictionloss": 0.6}]
    assert model.meta["mjcf"]["frictionloss"] == "list"
    assert "frictionloss (a constraint in MuJoCo" in model.meta["mjcf"]["not_in_the_equations"]


def test_frictionloss_as_coulomb_friction_on_request(tmp_path):
    """--frictionloss coulomb: F sign(qd) on the left (joints) and -F sign(L') along the tendon, in inverse and
    forward dynamics and passive_forces; parameters friction_<coordinate>, tendon_friction_<tendon>; not
    conservative; recorded in the manifest."""
    path = write(tmp_path, FRICTION.format(free="", after=FRICTION_TENDON))
    model = quiet_load(path, frictionloss="coulomb")
    assert [p.name for p in model.parameters if "friction" in p.name] == ["friction_j2", "friction_j5",
                                                                          "tendon_friction_rub"]
    assert not model.conservative and model.meta["mjcf"]["frictionloss"] == "coulomb"
    plain = NumericTwin(quiet_load(path))
    twin = NumericTwin(model)
    rng = np.random.default_rng(8)
    for _ in range(3):
        q, qd, qdd = rng.normal(size=model.nq), rng.normal(size=model.nv), rng.normal(size=model.nv)
        expected = np.zeros(model.nv)
        expected[1] = 0.8 * np.sign(qd[1])
        expected[4] = 1.5 * np.sign(qd[4])
        c = np.array([1, 0, 0, -.5, 0])
        expected += c * 0.6 * np.sign(c @ qd)
        assert np.allclose(twin.call("passive_forces", q, qd), -expected, rtol=1e-14, atol=1e-14)
        tau = twin.call("inverse_dynamics", q, qd, qdd)
        assert np.allclose(tau, plain.call("inverse_dynamics", q, qd, qdd) + expected, rtol=1e-12, atol=1e-12)
        assert np.allclose(twin.call("forward_dynamics", q, qd, tau), qdd, rtol=1e-9, atol=1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert cli.main(["generate", str(path), "-o", str(tmp_path / "out"), "-q", "--targets", "manifest",
                         "--frictionloss", "coulomb"]) == 0
    manifest = json.loads((tmp_path / "out" / "m.json").read_text())
    assert manifest["conservative"] is False and manifest["mjcf"]["frictionloss"] == "coulomb"
    assert "friction_j2" in [p["name"] for p in manifest["parameters"]]


def test_frictionloss_option_is_for_mjcf_only(tmp_path, capsys):
    from pathlib import Path

    yaml = Path(__file__).resolve().parent.parent / "models" / "double_pendulum.yaml"
    code = cli.main(["generate", str(yaml), "-o", str(tmp_path / "o"), "-q",
                     "--frictionloss", "coulomb"])
    assert code == 2 and "--frictionloss" in capsys.readouterr().err


def test_latex_lists_a_joint_space_row(tmp_path, capsys):
    path = write(tmp_path, CHAIN.format(free="", after=TRIPLE))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert cli.main(["latex", str(path)]) == 0
    assert r"tie3 & (joint space) &  & row in j1, j2, j4" in capsys.readouterr().out


def test_tendon_parameters_are_runtime_parameters(tmp_path):
    """Stiffness, rest lengths and damping of the tendons changed through p (over decades) give MuJoCo's
    qfrc_passive with the same values set in its compiled model."""
    path = write(tmp_path, CHAIN.format(free="", after=TENDONS))
    model = quiet_load(path)
    twin = NumericTwin(model)
    m = mujoco_model(path)
    d = mujoco.MjData(m)
    index = {p.name: i for i, p in enumerate(model.parameters)}
    spring, band, damper = (mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, n) for n in ("spring", "band", "damper"))
    rng = np.random.default_rng(9)
    for k_scale, d_scale in ((1e-3, 1e2), (1e2, 1e-3), (10.0, 10.0)):
        p = np.array(model.parameter_values)
        values = {"tendon_stiffness_spring": 3 * k_scale, "tendon_springlength_spring": -.25,
                  "tendon_damping_spring": .7 * d_scale, "tendon_stiffness_band": 5 * k_scale,
                  "tendon_springlower_band": -.05, "tendon_springupper_band": .15,
                  "tendon_damping_damper": 1.1 * d_scale}
        for name, value in values.items():
            p[index[name]] = value
        m.tendon_stiffness[spring], m.tendon_lengthspring[spring] = values["tendon_stiffness_spring"], (-.25, -.25)
        m.tendon_damping[spring] = values["tendon_damping_spring"]
        m.tendon_stiffness[band], m.tendon_lengthspring[band] = values["tendon_stiffness_band"], (-.05, .15)
        m.tendon_damping[damper] = values["tendon_damping_damper"]
        for _ in range(3):
            qpos, qvel, _ = states(m, rng)
            d.qpos[:], d.qvel[:] = qpos, qvel
            mujoco.mj_forward(m, d)
            ref = np.array(d.qfrc_passive)
            mine = twin.call("passive_forces", qpos, qvel, p=p)
            assert np.max(np.abs(mine - ref)) <= 1e-12 * np.max(np.abs(ref)), (k_scale, d_scale)


def test_coulomb_frictionloss_on_a_free_joint_is_refused(tmp_path):
    text = CHAIN.format(free=FREE_BODY.replace('<freejoint name="fly"/>', '<joint name="fly" type="free" '
                                                                         'frictionloss="1"/>'), after="")
    with pytest.raises(ModelError, match=r'<joint name="fly">.*frictionloss on a free joint'):
        quiet_load(write(tmp_path, text), frictionloss="coulomb")
    assert quiet_load(write(tmp_path, text)).meta["mjcf"]["frictionloss"] == "list"
