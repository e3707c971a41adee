"""MuJoCo's inertia-box fluid model (aggsym/mechanics/fluid.py, issue 53 item 5): the drag of density, viscosity and
wind on each body's equivalent inertia box, among the passive forces, equal to MuJoCo's qfrc_passive (1e-12) through
the twin, the generated C and NumPy: dm_control's swimmer and fish and a probe (a free glider with a tilted inertial
frame, a welded body's own box, a chain with oblique axes, masses over six decades); the medium's runtime
parameters; the derivatives against central differences; a body of the ellipsoid model has no box."""
from __future__ import annotations

import warnings
from pathlib import Path

import mujoco
import pytest

import aggsym
from benchmarks.mjcf.mujoco_reference import Module, compare
from fluid_support import chain_of, derivative_errors, medium_at_runtime
from helpers import generated_code

pytestmark = pytest.mark.mujoco

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
    for error, scale in medium_at_runtime(PROBE, model, module):
        assert error <= 1e-12 * max(1.0, scale)


def test_the_derivatives_carry_the_drag(tmp_path):
    """d qdd/d(q, qd) of the chain (the probe's free glider taken away: q is qpos) against central differences."""
    path = tmp_path / "chain.xml"
    path.write_text(chain_of(PROBE))
    assert max(derivative_errors(load(path, routines=["all"]))) <= 1e-7


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
