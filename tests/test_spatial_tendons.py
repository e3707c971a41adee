"""Spatial tendons through sites and pulleys (MJCF ``<spatial>`` without wrapping, aggsym/mechanics/spatial_tendons.py,
issue 53 item 4): their springs (a rest length or a dead band) and dampers as passive forces, equal to MuJoCo's
qfrc_passive (1e-12) through the twin, the generated C and NumPy, on a probe (a world site, a pulley, two branches
of the tree, a free body) and on random chains (random axes, sites and masses, angles with 5 digits); the length
against MuJoCo's ten_length; the spring's energy in U (grad U = g - passive); the derivatives against central
differences; wrapping around geoms refused by name."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import aggsym
from aggsym.core.backend import Numeric
from aggsym.mechanics.bound import bind
from aggsym.mechanics.kinematics import TreeKinematics
from aggsym.mechanics.spatial_tendons import tendon_length
from aggsym.twin import NumericTwin
from helpers import central_differences, generated_code

mujoco = pytest.importorskip("mujoco")
pytestmark = pytest.mark.mujoco

from benchmarks.mjcf.mujoco_reference import Module, compare, mujoco_model, to_aggsym  # noqa: E402

PROBE = Path(__file__).resolve().parent.parent / "benchmarks" / "mjcf" / "probes" / "spatial_tendons.xml"


def load(path, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return aggsym.load(path, **options)


def fixed_arm(tmp_path) -> Path:
    """The probe without its free body and tether: q is MuJoCo's qpos."""
    text = PROBE.read_text()
    start, end = text.index('    <body name="float"'), text.index("  </worldbody>")
    text = text[:start] + text[end:]
    start, end = text.index('    <spatial name="tether"'), text.index("  </tendon>")
    path = tmp_path / "arm.xml"
    path.write_text(text[:start] + text[end:])
    return path


def random_chain(seed: int) -> str:
    """A chain of 4 to 6 bodies with hinges and slides about random axes, sites at random points (angles and
    lengths written with 5 digits), masses over six decades, and two spatial tendons through random sites (one with
    a pulley, one with a dead band), a world site among them."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 7))
    r5 = lambda v: " ".join(f"{x:.5f}" for x in v)  # noqa: E731
    body, close, sites = "", "", ["world0"]
    for k in range(n):
        axis = rng.normal(size=3)
        kind = "slide" if rng.random() < 0.25 else "hinge"
        mass = 10.0 ** rng.uniform(-3, 3)
        body += (f'<body name="b{k}" pos="{r5(rng.uniform(-0.3, 0.3, 3))}" euler="{r5(rng.uniform(-3, 3, 3))}">'
                 f'<joint name="j{k}" type="{kind}" axis="{r5(axis)}"/>'
                 f'<geom type="sphere" size="0.05" pos="{r5(rng.uniform(-0.1, 0.1, 3))}" mass="{mass!r}"/>'
                 f'<site name="s{k}" pos="{r5(rng.uniform(-0.2, 0.2, 3))}"/>')
        sites.append(f"s{k}")
        close += "</body>"
    picks = [str(s) for s in rng.choice(sites, size=4, replace=False)]
    first = "".join(f'<site site="{s}"/>' for s in picks[:2]) + '<pulley divisor="1.7"/>' + \
        "".join(f'<site site="{s}"/>' for s in picks[2:])
    second = "".join(f'<site site="{s}"/>' for s in rng.choice(sites[1:], size=3, replace=False))
    return (f'<mujoco model="chain{seed}"><option gravity="0 0 -9.81"/><worldbody>'
            f'<site name="world0" pos="{r5(rng.uniform(-0.5, 0.5, 3))}"/>{body}{close}</worldbody><tendon>'
            f'<spatial name="pulled" stiffness="{rng.uniform(1, 20):.5f}" damping="{rng.uniform(0.1, 2):.5f}">'
            f'{first}</spatial>'
            f'<spatial name="band" stiffness="{rng.uniform(1, 20):.5f}" springlength="0.05 0.15">{second}</spatial>'
            f'</tendon></mujoco>')


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    model = load(PROBE)
    library, module, manifest = generated_code(model, tmp_path_factory.mktemp("spatial"))
    return model, library, module, manifest


def test_the_probe_against_mujoco(probe):
    model, library, module, manifest = probe
    assert [t.name for t in model.spatial_tendons] == ["spring", "damped", "band", "tether"]
    worst = compare(PROBE, model=model, samples=6, seed=5, evaluators=[library, Module(module)])
    assert worst["passive"] <= 1e-12 and max(worst.values()) <= 1e-9, worst
    tendons = {t["tendon"]: t for t in manifest["mjcf"]["tendons"]}
    assert all(t["type"] == "spatial" and t["in_the_equations"] for t in tendons.values())
    assert manifest["conservative"] is False  # (dampers)


@pytest.mark.parametrize("seed", range(6))
def test_random_chains_against_mujoco(seed, tmp_path):
    path = tmp_path / f"chain{seed}.xml"
    path.write_text(random_chain(seed))
    model = load(path)
    worst = compare(path, model=model, samples=3, seed=seed)
    assert worst["passive"] <= 1e-12 and max(worst.values()) <= 1e-9, worst
    # the length itself, against MuJoCo's ten_length
    m = mujoco_model(path)
    data = mujoco.MjData(m)
    bound = bind(model, Numeric())
    rng = np.random.default_rng(seed)
    for _ in range(2):
        data.qpos[:] = np.round(rng.uniform(-2, 2, m.nq), 5)
        mujoco.mj_forward(m, data)
        q = to_aggsym(m, data.qpos, data.qvel, np.zeros(m.nv))[0]
        kin = TreeKinematics(bound, [float(x) for x in q])
        for t, tendon in enumerate(model.spatial_tendons):
            assert abs(float(tendon_length(bound, kin, tendon)) - data.ten_length[t]) <= 1e-14 * max(
                1.0, abs(data.ten_length[t]))


def test_the_springs_energy_is_in_the_potential(tmp_path):
    model = load(fixed_arm(tmp_path))
    twin = NumericTwin(model)
    rng = np.random.default_rng(4)
    zero = np.zeros(model.nv)
    for _ in range(3):
        q = np.round(rng.uniform(-2, 2, model.nq), 5)
        grad = central_differences(lambda x: np.atleast_1d(twin.call("potential_energy", x)), q).ravel()
        expected = np.asarray(twin.call("gravity", q)) - np.asarray(twin.call("passive_forces", q, zero))
        assert np.max(np.abs(grad - expected)) <= 1e-7 * max(1.0, np.max(np.abs(expected)))


def test_the_parameters_change_the_tendons(tmp_path, probe):
    model, _, module, _ = probe
    names = [p.name for p in model.parameters]
    m = mujoco_model(PROBE)
    p = np.array(module.PARAMETERS, dtype=float)
    for t, (k, d) in enumerate(((30.1, 0.0), (1.5, 2.25), (0.5, 0.0), (9.0, 1.0))):
        tag = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TENDON, t)
        m.tendon_stiffness[t], p[names.index(f"tendon_stiffness_{tag}")] = k, k
        if f"tendon_damping_{tag}" in names:
            m.tendon_damping[t], p[names.index(f"tendon_damping_{tag}")] = d, d
    data = mujoco.MjData(m)
    rng = np.random.default_rng(8)
    for _ in range(3):
        data.qpos[:] = rng.uniform(-1, 1, m.nq)
        data.qpos[-4:] /= np.linalg.norm(data.qpos[-4:])
        data.qvel[:] = rng.normal(size=m.nv)
        mujoco.mj_forward(m, data)
        q, qd, _, J, _ = to_aggsym(m, data.qpos, data.qvel, np.zeros(m.nv))
        ref = J.T @ data.qfrc_passive
        assert np.max(np.abs(module.passive_forces(q, qd, p) - ref)) <= 1e-12 * max(1.0, np.max(np.abs(ref)))


def test_the_derivatives_carry_the_tendons(tmp_path):
    model = load(fixed_arm(tmp_path), routines=["all"])
    twin = NumericTwin(model)
    rng = np.random.default_rng(6)
    n = model.nv
    q, qd, x = rng.normal(size=(3, n))
    for role, value in (("forward_dynamics_derivatives", "forward_dynamics"),
                        ("inverse_dynamics_derivatives", "inverse_dynamics")):
        dq, dqd = (np.asarray(a).reshape(n, n) for a in twin.call(role, q, qd, x))
        fq = central_differences(lambda y: np.asarray(twin.call(value, y, qd, x)), q).reshape(n, n)
        fqd = central_differences(lambda y: np.asarray(twin.call(value, q, y, x)), qd).reshape(n, n)
        assert np.max(np.abs(dq - fq)) <= 1e-7 * np.max(np.abs(fq)), role
        assert np.max(np.abs(dqd - fqd)) <= 1e-7 * max(1.0, np.max(np.abs(fqd))), role


def test_wrapping_around_a_geom_is_refused_by_name(tmp_path, capsys):
    from aggsym import cli

    path = tmp_path / "wrap.xml"
    path.write_text('<mujoco><worldbody><site name="a" pos="0 0 1"/><geom name="pulley_geom" type="cylinder" '
                    'size="0.05 0.1" pos="0.2 0 0.8"/><body name="b"><joint name="j"/><geom size=".1"/>'
                    '<site name="s" pos="0.3 0 0"/></body></worldbody><tendon><spatial name="wrapped" stiffness="3">'
                    '<site site="a"/><geom geom="pulley_geom"/><site site="s"/></spatial></tendon></mujoco>')
    code = cli.main(["generate", str(path), "-o", str(tmp_path / "out"), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and '<tendon name="wrapped">' in err and "wrapping around a geom" in err, err
    assert "Traceback" not in err and not (tmp_path / "out").exists()
