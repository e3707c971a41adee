"""T + U along simulated free motion (tau = 0), through the generated NumPy module of every model in models/.

The manifest's ``conservative`` is true exactly for the models without prescribed motions; for those, one second
of motion by classical RK4 with a fixed step, q'' = forward_dynamics(q, q', 0) of the module generated into a
temporary folder, keeps E = kinetic_energy + potential_energy (gravity, springs of elastic pairs; the medium's
kinetic energy with added masses) to

    max_t |E(t) - E(0)| / (T(0) + |U(0)|) <= 1e-8.

RK4's energy error shrinks like dt^4; the steps below leave a margin of at least ten.  Measured (initial state of
:func:`initial_state`): added_mass_body_in_fluid 1.3e-13, delta_robot (its tree, unconstrained: three arms and
their parallelograms falling free; 1.02e-6 at 1e-3, 5.2e-9 at 2.5e-4) 3.3e-10, double_pendulum 3.6e-12, double_pendulum_elastic_stand
4.7e-10, double_pendulum_variant2 3.6e-12, four_bar (its tree, unconstrained: a fast triple pendulum) 3.1e-10,
gyroscope 7.9e-13, manipulator6 3.0e-11, planar_2link 1.6e-10, planar_3link 3.9e-10, spacecraft 4.1e-14, test_bench 5.6e-10,
walking_machine 6.1e-14.
The check can fail: the elastic stand integrated without its springs in forward_dynamics (but with their energy
in U) drifts by far more.  (Models with prescribed spins are covered by test_rotors.py's energy balance.)
"""
import numpy as np
import pytest

import aggsym
from conftest import MODELS
from helpers import generated_code, rk4_step

TOLERANCE = 1e-8
STEP = {"delta_robot": 1.25e-4, "double_pendulum_elastic_stand": 5e-4, "four_bar": 1.25e-4, "planar_2link": 5e-4,
        "planar_3link": 5e-4,
        "test_bench": 2e-3, "walking_machine": 2e-3}  # others: 1e-3
CONSERVATIVE = [p for p in MODELS if aggsym.load(p).conservative]


def rk4(f, q, v, dt, steps, energy):
    """Classical RK4 for q'' = f(q, q'); returns the worst |E - E(0)| seen at the steps."""
    E0, worst = energy(q, v), 0.0
    for _ in range(steps):
        q, v = rk4_step(f, q, v, dt)
        worst = max(worst, abs(energy(q, v) - E0))
    return worst


def initial_state(model):
    rng = np.random.default_rng(7)
    return rng.uniform(-1, 1, model.nq), 0.5 * rng.normal(size=model.nq)


def test_conservative_is_the_models_without_prescribed_motion():
    flags = {p.stem: aggsym.load(p).conservative for p in MODELS}
    assert flags["flywheel_on_body"] is False and flags["gyroscope_spinning_rotor"] is False
    assert all(flags[name] for name in ("double_pendulum_elastic_stand", "added_mass_body_in_fluid", "gyroscope",
                                        "test_bench"))
    assert {p.stem for p in CONSERVATIVE} == {n for n, f in flags.items() if f}


@pytest.mark.parametrize("path", CONSERVATIVE, ids=lambda p: p.stem)
def test_energy_is_conserved_along_free_motion(path, tmp_path):
    model = aggsym.load(path)
    _, mod, manifest = generated_code(model, tmp_path, c=False)
    assert manifest["conservative"] is True
    q, v = initial_state(model)
    zero = np.zeros(model.nq)

    def energy(q, v):
        return mod.kinetic_energy(q, v) + mod.potential_energy(q)

    scale = mod.kinetic_energy(q, v) + abs(mod.potential_energy(q))
    dt = STEP.get(model.name, 1e-3)
    worst = rk4(lambda q, v: mod.forward_dynamics(q, v, zero), q, v, dt, round(1 / dt), energy)
    assert worst / scale <= TOLERANCE, f"{model.name}: relative drift {worst / scale:.3g}"


def test_the_drift_check_can_fail(tmp_path):
    """The elastic stand with its springs left out of the dynamics (forward_dynamics given tau = c(q)) but kept in
    U drifts by orders of magnitude more than the tolerance within 0.1 s."""
    model = aggsym.load(CONSERVATIVE[0].parent / "double_pendulum_elastic_stand.yaml")
    _, mod, _ = generated_code(model, tmp_path, c=False)
    q, v = initial_state(model)

    def energy(q, v):
        return mod.kinetic_energy(q, v) + mod.potential_energy(q)

    scale = mod.kinetic_energy(q, v) + abs(mod.potential_energy(q))
    worst = rk4(lambda q, v: mod.forward_dynamics(q, v, mod.elastic(q)), q, v, 5e-4, 200, energy)
    assert worst / scale > 1e3 * TOLERANCE
