"""MJCF tendon equalities on spatial tendons (through sites and pulleys): joint-space constraint rows with
phi = (L1 - L1_0) - P(L2 - L2_0), L a spatial tendon's length, J = dL1/dq - P'(x) dL2/dq and gamma its rate term
(:class:`aggsym.mechanics.spatial_tendons.SpatialLength`).

References: MuJoCo itself.  The constrained forward dynamics against the dense KKT solve from MuJoCo's ``mj_fullM``,
``qfrc_bias``, the equality rows of its ``efc_J`` and gamma by central differences of that J
(:func:`benchmarks.mjcf.mujoco_reference.compare_constrained`, MuJoCo's own equalities being soft) <= 1e-9; phi
against ``efc_pos`` and the tendon lengths ``ten_length``; J against ``efc_J`` and the combination of ``ten_J``;
gamma against central differences (Richardson-extrapolated) of aggsym's J along qd.
"""
from __future__ import annotations

import warnings

import mujoco
import numpy as np
import pytest

from aggsym.errors import ModelError
from aggsym.model import load
from aggsym.twin import NumericTwin

from benchmarks.mjcf.mujoco_reference import compare_constrained, equality_model, states

# three hinges with skew axes; sites on the world, on a and on c
ARM = """<mujoco model="arm"><option gravity="0.2 -0.4 -9.81"><flag contact="disable"/></option><worldbody>
<site name="w0" pos="0.11 -0.23 0.31"/><site name="w1" pos="-0.17 0.29 -0.05"/>
<body name="a"><joint name="j1" axis="0.31416 0.71828 -0.21130" damping=".2"/>
 <geom type="capsule" fromto="0 0 0 .3 0 0" size=".03"/><site name="s1" pos=".2 .05 .01"/>
 <body name="b" pos=".3 0 0"><joint name="j2" axis="-0.41421 0.17321 0.90000" armature=".03"/>
  <geom type="capsule" fromto="0 0 0 .25 .05 0" size=".03"/><site name="s2" pos=".12 -.04 .03"/>
  <body name="c" pos=".25 .05 0"><joint name="j3" axis="0.52358 -0.33333 0.12345"/><geom size=".05"/>
   <site name="s3" pos=".03 -.02 .07"/><site name="s4" pos="-.04 .06 .02"/>
   <body name="d" pos="0 .1 -.05"><joint name="j4" type="slide" axis="0.27183 0.5 -0.31831"/><geom size=".03"/>
    <site name="s5" pos=".02 .01 -.03"/></body></body></body></body>
</worldbody>{after}</mujoco>"""

TENDONS = {
    "held at its length": (
        '<tendon><spatial name="t1"><site site="w0"/><site site="s1"/><site site="s3"/></spatial></tendon>'
        '<equality><tendon name="hold" tendon1="t1"/></equality>'),
    "two spatial, a pulley": (
        '<tendon><spatial name="t1"><site site="w0"/><site site="s1"/><site site="s3"/></spatial>'
        '<spatial name="t2"><site site="w1"/><site site="s2"/><pulley divisor="2"/><site site="s4"/>'
        '<site site="s5"/></spatial></tendon>'
        '<equality><tendon name="tie" tendon1="t1" tendon2="t2" polycoef=".01 .7 -.4 0 0"/></equality>'),
    "fixed to spatial": (
        '<tendon><fixed name="f1"><joint joint="j1" coef=".4"/><joint joint="j3" coef="-1.2"/></fixed>'
        '<spatial name="t2"><site site="s1"/><site site="s2"/><site site="s5"/></spatial></tendon>'
        '<equality><tendon name="tie" tendon1="f1" tendon2="t2" polycoef="0 1.3 .6 -.2 .1"/></equality>'),
    "spatial to fixed": (
        '<tendon><fixed name="f1"><joint joint="j2" coef=".8"/><joint joint="j4" coef="2"/></fixed>'
        '<spatial name="t2"><site site="w1"/><site site="s3"/><site site="s5"/></spatial></tendon>'
        '<equality><tendon name="tie" tendon1="t2" tendon2="f1" polycoef="0 -.5 .3 0 0"/></equality>'),
}

FREE = ('<body name="f" pos=".5 .5 .2"><freejoint name="fly"/><geom type="box" size=".1 .05 .08"/>'
        '<site name="sf" pos=".05 -.03 .06"/><body name="g" pos="0 0 -.2"><joint name="k1" axis="1 0 0"/>'
        '<geom size=".04"/><site name="sg" pos=".01 .02 -.03"/></body></body>')
FREE_TENDON = ('<tendon><spatial name="t1"><site site="s1"/><site site="sf"/><site site="sg"/></spatial>'
               '<spatial name="t2"><site site="w0"/><site site="s3"/></spatial></tendon>'
               '<equality><tendon name="tie" tendon1="t1" tendon2="t2" polycoef="0 .5 .2 0 0"/></equality>')


def arm(tmp_path, case):
    path = tmp_path / "arm.xml"
    if case == "free body":
        path.write_text(ARM.replace("</worldbody>", FREE + "</worldbody>").format(after=FREE_TENDON))
    else:
        path.write_text(ARM.format(after=TENDONS[case]))
    return path


def quiet_load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load(path)


def tendon_jacobian(m, d):
    """MuJoCo's ten_J as a dense ntendon x nv array (stored dense, or sparse with the model's row structure)."""
    raw = np.array(d.ten_J, dtype=float).ravel()
    if raw.size == m.ntendon * m.nv:
        return raw.reshape(m.ntendon, m.nv)
    out = np.zeros((m.ntendon, m.nv))
    for t in range(m.ntendon):
        start = int(m.ten_J_rowadr[t])
        for k in range(int(m.ten_J_rownnz[t])):
            out[t, int(m.ten_J_colind[start + k])] = raw[start + k]
    return out


CASES = sorted(TENDONS) + ["free body"]


@pytest.mark.parametrize("case", CASES)
def test_constrained_dynamics_against_a_dense_kkt_solve_from_mujoco(tmp_path, case):
    """q'' and lambda of aggsym's constrained forward dynamics, A and J, against the KKT solve of MuJoCo's data."""
    path = arm(tmp_path, case)
    model = quiet_load(path)
    rows = [c for c in model.constraints if c.joint_row is not None]
    assert len(rows) == 1 and not model.couplings
    row = rows[0].joint_row
    assert row.first_sites or row.second_sites
    worst = compare_constrained(path, model=model, samples=4, seed=11)
    assert max(worst.values()) <= 1e-9, (case, worst)


@pytest.mark.parametrize("case", sorted(TENDONS))
def test_residual_and_jacobian_are_mujocos(tmp_path, case):
    """phi = MuJoCo's efc_pos and (L1 - L1_0) - P(L2 - L2_0) of its ten_length; J = its efc_J and
    ten_J[1] - P'(x) ten_J[2]; at random states (hinges and slides: q is qpos, qd is qvel)."""
    path = arm(tmp_path, case)
    model = quiet_load(path)
    twin = NumericTwin(model)
    m = equality_model(path)
    d = mujoco.MjData(m)
    e = 0
    t1, t2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
    poly = np.array(m.eq_data[e][:5])
    rng = np.random.default_rng(5)
    for _ in range(5):
        qpos, _, _ = states(m, rng)
        d.qpos[:] = qpos
        mujoco.mj_forward(m, d)
        eq = np.array(d.efc_type[:d.nefc]) == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)
        phi = np.array(twin.call("constraint_residual", qpos))
        J = np.array(twin.call("constraint_jacobian", qpos)).reshape(1, model.nv)
        assert np.max(np.abs(phi - np.array(d.efc_pos[:d.nefc])[eq])) <= 1e-12
        ten_J = tendon_jacobian(m, d)
        x = d.ten_length[t2] - m.tendon_length0[t2] if t2 >= 0 else 0.0
        P = sum(poly[k] * x ** k for k in range(5)) if t2 >= 0 else poly[0]
        dP = sum(k * poly[k] * x ** (k - 1) for k in range(1, 5))
        assert abs(phi[0] - (d.ten_length[t1] - m.tendon_length0[t1] - P)) <= 1e-12
        J_ten = ten_J[t1] - (dP * ten_J[t2] if t2 >= 0 else 0.0)
        J_efc = np.array(d.efc_J[:d.nefc * m.nv]).reshape(d.nefc, m.nv)[eq]
        for ref in (J_ten[None, :], J_efc):
            assert np.max(np.abs(J - ref)) <= 1e-12 * max(1.0, np.max(np.abs(ref)))


@pytest.mark.parametrize("case", sorted(TENDONS))
def test_rate_term_by_central_differences_of_j(tmp_path, case):
    """gamma = d/dt (J) qd at qdd = 0: (J(q + h qd) - J(q - h qd)) qd / 2h, Richardson-extrapolated over h and h/2."""
    model = quiet_load(arm(tmp_path, case))
    twin = NumericTwin(model)
    rng = np.random.default_rng(9)
    worst = 0.0
    for _ in range(4):
        q, qd = rng.uniform(-np.pi, np.pi, model.nq), rng.normal(size=model.nv)

        def central(h):
            J = [np.array(twin.call("constraint_jacobian", q + s * h * qd)).reshape(1, -1) for s in (1, -1)]
            return (J[0] - J[1]) @ qd / (2 * h)

        fd = (4 * central(5e-4) - central(1e-3)) / 3
        gamma = np.array(twin.call("constraint_bias", q, qd))
        assert np.any(gamma != 0.0)
        worst = max(worst, float(np.max(np.abs(gamma - fd)) / max(1.0, np.max(np.abs(fd)))))
    assert worst <= 1e-8, (case, worst)


def test_a_wrapping_geom_is_refused(tmp_path):
    """A spatial tendon wrapping around a geom: the equality is refused by name."""
    text = ARM.format(after=(
        '<tendon><spatial name="t1"><site site="w0"/><geom geom="ball"/><site site="s3"/></spatial></tendon>'
        '<equality><tendon name="hold" tendon1="t1"/></equality>')).replace(
        '<geom size=".05"/>', '<geom name="ball" size=".05"/>', 1)
    path = tmp_path / "wrap.xml"
    path.write_text(text)
    with pytest.raises(ModelError, match="wrapping around a geom"):
        quiet_load(path)


def test_manifest_lists_the_spatial_row(tmp_path):
    """The equality's manifest entry names the spatial tendon."""
    model = quiet_load(arm(tmp_path, "two spatial, a pulley"))
    (entry,) = model.meta["mjcf"]["equalities"]
    assert "spatial tendon 't1'" in entry["became"] and "spatial tendon 't2'" in entry["became"]
