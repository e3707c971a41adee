"""MuJoCo's ellipsoid fluid model (aggsym/mechanics/fluid_ellipsoid.py): the added mass, Magnus and Kutta lifts and
the drags of density, viscosity and wind on each geom with fluidshape="ellipsoid", among the passive forces, equal to
MuJoCo's qfrc_passive (1e-12) through the twin, the generated C and NumPy, and forward dynamics equal to its qacc: a
probe (benchmarks/mjcf/probes/fluid_ellipsoid.xml: a free glider and a chain of hinges, ellipsoid, box, cylinder,
capsule and sphere geoms offset and turned in their bodies, their own fluidcoef, a geom without fluidshape, a welded
body), geoms at rest (MuJoCo's guards at v = 0) and at speeds below them, a model with both fluid models, the
medium's runtime parameters, the derivatives against central differences (at rest too: finite)."""
from __future__ import annotations

import warnings
from pathlib import Path

import mujoco
import numpy as np
import pytest

import aggsym
from benchmarks.mjcf.mujoco_reference import Module, compare, mujoco_model, states, to_aggsym
from fluid_support import chain_of, derivative_errors, medium_at_runtime
from helpers import generated_code

pytestmark = pytest.mark.mujoco

PROBES = Path(__file__).resolve().parent.parent / "benchmarks" / "mjcf" / "probes"
PROBE = PROBES / "fluid_ellipsoid.xml"
GEOMS = ["hull", "fin", "pod", "upper", "fore", "knob", "paddle"]


def load(path, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (no warning: both fluid models are in the equations)
        return aggsym.load(path, **options)


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    model = load(PROBE)
    library, module, manifest = generated_code(model, tmp_path_factory.mktemp("ellipsoid"))
    return model, library, module, manifest


def test_the_probe_against_mujoco(probe):
    model, library, module, manifest = probe
    assert [e.geom for e in model.fluid_ellipsoids] == GEOMS and model.fluid == () and not model.conservative
    assert [e.body for e in model.fluid_ellipsoids[:3]] == ["glider"] * 3  # (the welded pod's geom: the glider's)
    worst = compare(PROBE, model=model, samples=8, seed=3, evaluators=[library, Module(module)])
    assert worst["passive"] <= 1e-12 and worst["qdd"] <= 1e-11 and max(worst.values()) <= 1e-11, worst
    fluid = manifest["mjcf"]["fluid"]
    assert fluid["density"] == 1.3 and fluid["viscosity"] == 0.021 and fluid["ellipsoid_geoms"] == GEOMS
    assert {"fluid_density", "fluid_viscosity", "wind_x", "wind_y", "wind_z"} <= {p["name"] for p in
                                                                                manifest["parameters"]}


def passive_against_mujoco(module, model, m, cases, wind=None) -> float:
    """The largest |aggsym - MuJoCo| / max |MuJoCo| of the passive forces at the MuJoCo states ``cases`` ((qpos,
    qvel) pairs), the wind (MuJoCo's and the parameters') set to ``wind`` unless None."""
    names = [p.name for p in model.parameters]
    p = np.array(module.PARAMETERS, dtype=float)
    if wind is not None:
        m.opt.wind[:] = wind
        for axis, value in zip("xyz", wind):
            p[names.index(f"wind_{axis}")] = value
    data = mujoco.MjData(m)
    worst = 0.0
    for qpos, qvel in cases:
        data.qpos[:], data.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, data)
        q, qd, _, J, _ = to_aggsym(m, qpos, qvel, np.zeros(m.nv))
        ref = J.T @ data.qfrc_passive
        worst = max(worst, float(np.max(np.abs(module.passive_forces(q, qd, p) - ref)) / np.max(np.abs(ref))))
    return worst


def test_geoms_at_rest_and_below_the_guards(probe):
    """MuJoCo's max(mjMINVAL, .) guards: the knob (centred on its hinge's axis) and the bodies before it at rest
    (v = 0) while the hand turns, no wind; the whole probe at rest in the wind (v = -wind, w = 0); speeds of 1e-9
    and 1e-12 (the projected-area guard P_n < mjMINVAL for every geom)."""
    model, _, module, _ = probe
    m = mujoco_model(PROBE, fluid=True)
    rng = np.random.default_rng(5)
    qpos, _, _ = states(m, rng)
    turning = np.zeros(m.nv)
    turning[-1] = 2.3  # (a3: the hand alone)
    assert passive_against_mujoco(module, model, m, [(qpos, turning)], wind=[0.0, 0.0, 0.0]) <= 1e-12
    slow = [(qpos, rng.normal(size=m.nv) * scale) for scale in (1e-3, 1e-9, 1e-12, 1e-17)]
    assert passive_against_mujoco(module, model, m, slow, wind=[0.0, 0.0, 0.0]) <= 1e-12
    still = [(states(m, rng)[0], np.zeros(m.nv)) for _ in range(2)]
    assert passive_against_mujoco(module, model, m, still + slow, wind=[0.4, -0.25, 0.13]) <= 1e-12


def test_the_medium_is_a_runtime_parameter(probe):
    model, _, module, _ = probe
    for error, scale in medium_at_runtime(PROBE, model, module):
        assert error <= 1e-12 * scale


def test_both_fluid_models_in_one_model(tmp_path):
    """The inertia-box probe with fluidshape="ellipsoid" on the flap's geom and the paddle's: the flap and the
    paddle in the ellipsoid model, the tab welded to the flap (merged into it in aggsym) and the others in boxes."""
    text = (PROBES / "fluid_inertia_box.xml").read_text()
    text = text.replace('pos="0.05 0 0" mass="0.0123"/>', 'pos="0.05 0 0" mass="0.0123" fluidshape="ellipsoid" '
                                                          'fluidcoef="0.6 0.2 1.3 1.1 0.9"/>')
    text = text.replace('pos="0.1 0 0" mass="412.5"/>', 'pos="0.1 0 0" euler="3.4567 -8.7654 1.2345" '
                                                        'mass="412.5" fluidshape="ellipsoid"/>')
    path = tmp_path / "mixed.xml"
    path.write_text(text)
    model = load(path)
    assert [e.body for e in model.fluid_ellipsoids] == ["flap", "paddle"] and len(model.fluid) == 4
    library, module, _ = generated_code(model, tmp_path / "code")
    worst = compare(path, model=model, samples=6, seed=7, evaluators=[library, Module(module)])
    assert worst["passive"] <= 1e-12 and worst["qdd"] <= 1e-11 and max(worst.values()) <= 1e-11, worst


def test_the_derivatives_carry_the_medium(tmp_path):
    """d qdd/d(q, qd) of the probe's chain (q is qpos) against central differences at a random state, and at rest
    with no wind (every geom at v = w = 0): finite there (the square roots' floor), and equal to those of the
    medium without density (every term of rho is at least quadratic in the velocities: its derivative is 0 at rest;
    central differences would err by O(h) on |v| v there)."""
    chain = chain_of(PROBE)
    path = tmp_path / "chain.xml"
    path.write_text(chain)
    model = load(path, routines=["all"])
    assert max(derivative_errors(model)) <= 1e-7
    n = model.nv
    q, _, tau = np.random.default_rng(1).normal(size=(3, n))  # (the state derivative_errors takes)

    path.write_text(chain.replace('wind="0.4 -0.25 0.13"', ""))
    model = load(path, routines=["all"])
    _, module, _ = generated_code(model, tmp_path / "code", c=False)
    p = np.array(module.PARAMETERS, dtype=float)
    still = p.copy()
    still[[x.name for x in model.parameters].index("fluid_density")] = 0.0
    rest = np.zeros(n)
    with np.errstate(all="raise"):
        got = [np.asarray(a) for a in module.forward_dynamics_derivatives(q, rest, tau, p)]
        ref = [np.asarray(a) for a in module.forward_dynamics_derivatives(q, rest, tau, still)]
    for mine, theirs in zip(got, ref):
        assert np.max(np.abs(mine - theirs)) <= 1e-13 * np.max(np.abs(theirs))


def test_small_and_slender_geoms_at_low_speeds(tmp_path):
    """A needle (a capsule 200 times longer than wide), a disc and a millimetre grain on a free body, at speeds
    from 1 down to 1e-12 m/s and below mjMINVAL: MuJoCo 4's dimensionless projections (where MuJoCo 3's guards
    max(mjMINVAL, .) would have cut the Kutta lift and the projected area)."""
    path = tmp_path / "slender.xml"
    path.write_text('<mujoco><option density="1000" viscosity="0.0013" wind="0 0 0"/><worldbody>'
                    '<body name="raft" pos="0 0 1" euler="10.123 20.246 -5.0617"><freejoint/>'
                    '<geom name="needle" type="capsule" fromto="-0.5 0 0 0.5 0 0" size="0.0025" mass="0.02" '
                    'fluidshape="ellipsoid"/>'
                    '<geom name="disc" type="cylinder" size="0.1 0.0005" pos="0 0.2 0" euler="30.000 0 12.345" '
                    'mass="0.003" fluidshape="ellipsoid" fluidcoef="0.5 0.25 1.5 1.7 1.0"/>'
                    '<geom name="grain" type="ellipsoid" size="0.001 0.0007 0.0004" pos="0.1 -0.1 0.01" '
                    'mass="1e-6" fluidshape="ellipsoid"/></body></worldbody></mujoco>')
    model = load(path)
    _, module, _ = generated_code(model, tmp_path / "code", c=False)
    m = mujoco_model(path, fluid=True)
    rng = np.random.default_rng(11)
    qpos, _, _ = states(m, rng)
    cases = [(qpos, rng.normal(size=m.nv) * scale) for scale in (1.0, 1e-3, 1e-6, 1e-9, 1e-12, 1e-17)]
    assert passive_against_mujoco(module, model, m, cases) <= 1e-12
