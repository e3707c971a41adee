"""A time-varying constraint (issue 16; Prop. 4.5-4.8): models/cart_on_moving_platform.yaml, a cart with a
pendulum held on a heaving and rocking platform.

References: the residual phi(q, t) itself, differentiated numerically: along q(s) = q + s qd, t + s (qdd = 0) its
second derivative is gamma, its first derivative the relative velocity J qd + F(t) (F = d phi/dt at fixed q);
the work-energy balance dE/dt = lambda . (J qd) = -lambda . F on the constraint manifold with tau = 0 (the
platform's force is the only one that works); drift along simulated motion; every routine takes t.
"""
import numpy as np
import pytest

import aggsym
from conftest import model_path
from helpers import assert_model_error, generated_code, rk4_step_in_time

H = 1e-4


@pytest.fixture(scope="module")
def platform(tmp_path_factory):
    model = aggsym.load(model_path("cart_on_moving_platform"))
    lib, module, manifest = generated_code(model, tmp_path_factory.mktemp("platform"), opt="-O1")
    import dataclasses
    _, plain, _ = generated_code(dataclasses.replace(model, stabilization=(0, 0)),
                                 tmp_path_factory.mktemp("plain"), c=False)
    return model, lib, module, plain, manifest


def time_rate(module, q, t, h=1e-6):
    """F(t) = d phi/dt at fixed q."""
    return (module.constraint_residual(q, t + h) - module.constraint_residual(q, t - h)) / (2 * h)


@pytest.mark.compiler
def test_every_routine_takes_the_time_and_the_manifest_says_why(platform):
    model, _, _, _, manifest = platform
    assert model.time_dependent and not model.has_prescribed_spins and model.conservative is False
    assert all("t" in s["inputs"] for s in manifest["signatures"].values())
    assert manifest["time"]["constraint_motions"] == [
        {"constraint": "deck", "motion": {"o3": "heave*sin(t*w)", "theta4": "roll*sin(t*w/2)"}}]
    assert "coriolis" in manifest["functions"]  # the tree itself does not depend on t


@pytest.mark.compiler
def test_gamma_holds_every_time_term(platform, rng):
    _, lib, module, _, _ = platform
    for _ in range(5):
        q, qd, t = rng.uniform(-1, 1, 4), rng.normal(size=4), float(rng.uniform(0, 5))
        phi = [module.constraint_residual(q + s * qd, t + s) for s in (-H, 0.0, H)]
        second = (phi[0] - 2 * phi[1] + phi[2]) / H ** 2
        gamma = module.constraint_bias(q, qd, t)
        assert np.abs(gamma - second).max() <= 1e-5 * max(np.abs(gamma).max(), 1.0), (gamma, second)
        first = (phi[2] - phi[0]) / (2 * H)
        J = module.constraint_jacobian(q, t)
        assert np.abs(J @ qd + time_rate(module, q, t) - first).max() <= 1e-7 * max(np.abs(first).max(), 1.0)
        assert np.allclose(lib.call("constraint_bias", q, qd, np.array([t])), gamma, rtol=1e-12, atol=1e-14)


def consistent(module, q, qd, t):
    """Newton on phi(q, t) = 0, then qd with J qd + F(t) = 0 (the least change)."""
    for _ in range(50):
        phi = module.constraint_residual(q, t)
        if np.abs(phi).max() < 1e-15:
            break
        q = q - np.linalg.lstsq(module.constraint_jacobian(q, t), phi, rcond=None)[0]
    J = module.constraint_jacobian(q, t)
    return q, qd - np.linalg.lstsq(J, J @ qd + time_rate(module, q, t), rcond=None)[0]


@pytest.mark.compiler
def test_the_platform_works_on_the_cart(platform, rng):
    """dE/dt = (J^T lambda) . qd = -lambda . F(t) with tau = 0, at consistent states (central differences of E
    along (qd, qdd) of the generated constrained forward dynamics)."""
    _, _, _, plain, _ = platform
    for _ in range(4):
        t = float(rng.uniform(0, 5))
        q, qd = consistent(plain, rng.uniform(-0.5, 0.5, 4), rng.normal(size=4), t)
        qdd, lam = plain.constrained_forward_dynamics(q, qd, np.zeros(4), t)

        def energy(x, v):
            return plain.kinetic_energy(x, v, t) + plain.potential_energy(x, t)

        h = 1e-6
        rate = (energy(q + h * qd, qd + h * qdd) - energy(q - h * qd, qd - h * qdd)) / (2 * h)
        expected = -lam @ time_rate(plain, q, t)
        assert abs(expected) > 1e-3  # the platform does work
        assert abs(rate - expected) <= 1e-6 * max(abs(expected), 1.0), (rate, expected)


@pytest.mark.compiler
def test_the_cart_stays_on_the_moving_platform(platform):
    _, _, module, _, _ = platform
    t, dt = 0.3, 1e-3
    q, qd = consistent(module, np.array([0.1, 0.0, 0.0, 0.4]), np.array([0.5, 0.0, 0.0, -1.0]), t)

    def f(t, q, qd):
        return module.constrained_forward_dynamics(q, qd, np.zeros(4), t)[0]

    for _ in range(1000):
        q, qd = rk4_step_in_time(f, t, q, qd, dt)
        t += dt
    assert np.abs(module.constraint_residual(q, t)).max() <= 1e-8
    J = module.constraint_jacobian(q, t)
    assert np.abs(J @ qd + time_rate(module, q, t)).max() <= 1e-7
    assert abs(q[2]) > 1e-3  # it heaved with the platform


BASE = model_path("cart_on_moving_platform").read_text().split("constraints:")[0]
BAD = {
    "medium_body": ("constraints: [{name: a, body: pendulum, medium: cart, block: [o3], motion: {o3: t}}]\n",
                    "constraints[0].motion", ["not supported yet"]),
    "empty": ("constraints: [{name: a, body: cart, block: [o3], motion: {}}]\n", "constraints[0].motion",
              ["empty motion"]),
    "unknown_code": ("constraints: [{name: a, body: cart, block: [o3], motion: {o7: t}}]\n",
                     "constraints[0].motion.o7", ["unknown key"]),
    "twice": ("constraints: [{name: a, body: cart, block: [o3], motion: {theta4: t, θ4: t}}]\n",
              "constraints[0].motion.θ4", ["given twice"]),
    "code_in_motion": ("constraints: [{name: a, body: cart, block: [o3], motion: {o3: '__import__(t)'}}]\n",
                       "constraints[0].motion.o3", ["__import__"]),
    "not_finite": ("constraints: [{name: a, body: cart, block: [o3], motion: {o3: 'log(t - t)'}}]\n",
                   "constraints[0].motion.o3", ["not finite"]),
    "not_finite_then": ("constraints: [{name: a, body: cart, block: [o3], motion: {o3: 'sqrt(t - 0.37)'}}]\n",
                        "constraints[0].motion.o3", ["t = 0.37"]),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_motions_are_reported_with_the_place(case, tmp_path):
    text, where, words = BAD[case]
    path = tmp_path / f"{case}.yaml"
    path.write_text(BASE + text)
    assert_model_error(path, where, words)
