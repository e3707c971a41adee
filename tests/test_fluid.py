"""MuJoCo's inertia-box fluid model (aggsym/mechanics/fluid.py, issue 53 item 5): the drag of density, viscosity and
wind on each body's equivalent inertia box, among the passive forces, equal to MuJoCo's qfrc_passive (1e-12) through
the twin, the generated C and NumPy: dm_control's swimmer and fish and a probe (a free glider with a tilted inertial
frame, a welded body's own box, a chain with oblique axes, masses over six decades); the medium's runtime
parameters; the derivatives against central differences; a body of the ellipsoid model has no box."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import aggsym
from aggsym.twin import NumericTwin
from helpers import central_differences, generated_code

mujoco = pytest.importorskip("mujoco")
pytestmark = pytest.mark.mujoco

from benchmarks.mjcf.mujoco_reference import Module, compare, mujoco_model, states, to_aggsym  # noqa: E402

PROBE = Path(__file__).resolve().parent.parent / "benchmarks" / "mjcf" / "probes" / "fluid_inertia_box.xml"
SUITE = Path(mujoco.__file__).resolve().parent.parent / "dm_control" / "suite"


def load(path, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return aggsym.load(path, **options)


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    model = load(PROBE)
    library, module, manifest = generated_code(model, tmp_path_factory.mktemp("fluid"))
    return model, library, module, manifest


def test_the_probe_against_mujoco(probe):
    model, library, module, manifest = probe
    assert len(model.fluid) == 6 and not model.conservative
    worst = compare(PROBE, model=model, samples=6, seed=2, evaluators=[library, Module(module)])
    assert worst["passive"] <= 1e-12 and max(worst.values()) <= 1e-9, worst
    fluid = manifest["mjcf"]["fluid"]
    assert fluid["density"] == 1.225 and fluid["viscosity"] == 0.0185 and fluid["ellipsoid_geoms"] == []
    assert {"fluid_density", "fluid_viscosity", "wind_x", "wind_y", "wind_z"} <= {p["name"] for p in
                                                                                manifest["parameters"]}


@pytest.mark.parametrize("name", ["swimmer", "fish"])
def test_the_suites_swimmers_against_mujoco(name):
    path = SUITE / f"{name}.xml"
    model = load(path)
    assert model.fluid
    worst = compare(path, model=model, samples=3, seed=4)
    assert worst["passive"] <= 1e-12 and max(worst.values()) <= 1e-9, worst


def test_the_fruit_fly_against_mujoco():
    """dm_control's fruit fly (108 dofs, its wings and body in the inertia-box fluid)."""
    path = SUITE.parent / "locomotion" / "walkers" / "assets" / "fruitfly_v2" / "fruitfly.xml"
    model = load(path)
    assert len(model.fluid) > 60 and model.nv == 108
    worst = compare(path, model=model, samples=2, seed=1, internal=False)
    assert worst["passive"] <= 1e-12 and max(worst.values()) <= 1e-9, worst


def test_the_medium_is_a_runtime_parameter(probe):
    model, _, module, _ = probe
    names = [p.name for p in model.parameters]
    m = mujoco_model(PROBE, fluid=True)
    p = np.array(module.PARAMETERS, dtype=float)
    m.opt.density, p[names.index("fluid_density")] = 1000.0, 1000.0
    m.opt.viscosity, p[names.index("fluid_viscosity")] = 1.3e-3, 1.3e-3
    m.opt.wind[:] = [-2.0, 0.5, 1.0]
    for axis, value in zip("xyz", m.opt.wind):
        p[names.index(f"wind_{axis}")] = value
    data = mujoco.MjData(m)
    rng = np.random.default_rng(9)
    for _ in range(3):
        qpos, qvel, force = states(m, rng)
        data.qpos[:], data.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, data)
        q, qd, _, J, _ = to_aggsym(m, qpos, qvel, force)
        ref = J.T @ data.qfrc_passive
        assert np.max(np.abs(module.passive_forces(q, qd, p) - ref)) <= 1e-12 * max(1.0, np.max(np.abs(ref)))


def test_the_derivatives_carry_the_drag(tmp_path):
    """d qdd/d(q, qd) of the chain (the probe's free glider taken away: q is qpos) against central differences."""
    text = PROBE.read_text()
    start, end = text.index('    <body name="glider"'), text.index('    <body name="arm"')
    path = tmp_path / "chain.xml"
    path.write_text(text[:start] + text[end:])
    model = load(path, routines=["all"])
    twin = NumericTwin(model)
    rng = np.random.default_rng(1)
    n = model.nv
    q, qd, tau = rng.normal(size=(3, n))
    dq, dqd = (np.asarray(a).reshape(n, n) for a in twin.call("forward_dynamics_derivatives", q, qd, tau))
    fq = central_differences(lambda y: np.asarray(twin.call("forward_dynamics", y, qd, tau)), q).reshape(n, n)
    fqd = central_differences(lambda y: np.asarray(twin.call("forward_dynamics", q, y, tau)), qd).reshape(n, n)
    assert np.max(np.abs(dq - fq)) <= 1e-7 * np.max(np.abs(fq))
    assert np.max(np.abs(dqd - fqd)) <= 1e-7 * np.max(np.abs(fqd))


def test_a_body_with_an_ellipsoid_geom_has_no_box(tmp_path):
    """MuJoCo's mj_fluid: a body some geom of which has fluidshape="ellipsoid" is in the ellipsoid model
    (tests/test_fluid_ellipsoid.py), not in the inertia box; no warning."""
    path = tmp_path / "wing.xml"
    path.write_text('<mujoco><option density="1.2"/><worldbody><body name="wing"><joint name="j" axis="0 1 0"/>'
                    '<geom type="ellipsoid" size="0.1 0.02 0.005" mass="0.01" fluidshape="ellipsoid"/></body>'
                    '<body name="plate" pos="0.3 0 0"><joint name="k"/><geom type="box" size="0.1 0.05 0.01" '
                    'mass="0.02"/></body></worldbody></mujoco>')
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = aggsym.load(path)
    assert [b.body for b in model.fluid] == ["plate"] and not model.conservative
    assert [e.body for e in model.fluid_ellipsoids] == ["wing"]
    assert model.meta["mjcf"]["fluid"]["ellipsoid_geoms"] == ["geom0"]
    worst = compare(path, model=model, samples=3, seed=2)
    assert worst["passive"] <= 1e-12 and max(worst.values()) <= 1e-11, worst
