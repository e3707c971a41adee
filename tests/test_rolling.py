"""A disc rolling without slipping on a plane (issue 16; chapter 4's wheel rolling over the medium's surface):
models/rolling_disc.yaml.

References, independent of aggsym's recursions: the disc's pose written here with NumPy (centre (x, y, z + r),
rotation Rz(yaw) Rx(lean) Ry(spin)), its angular velocity by central differences of the rotation, the contact
point ``C + r a x e`` (a the axle, e = a x z/|a x z|); the classic steady-precession condition derived in
:func:`steady_spin` by the balance of angular momentum about the centre; energy along simulated motion.
"""
import dataclasses

import numpy as np
import pytest

import aggsym
from aggsym.twin import NumericTwin
from conftest import model_path
from helpers import assert_model_error, generated_code, rk4_step

M, R, G = 0.5, 0.1, 9.81
A_DIAMETER, C_AXLE = M * R ** 2 / 4, M * R ** 2 / 2


@pytest.fixture(scope="module")
def disc(tmp_path_factory):
    model = aggsym.load(model_path("rolling_disc"))
    plain = dataclasses.replace(model, stabilization=(0, 0))
    lib, module, manifest = generated_code(plain, tmp_path_factory.mktemp("disc"), opt="-O1")
    _, stabilized, _ = generated_code(model, tmp_path_factory.mktemp("stab"), c=False)
    return model, lib, module, stabilized


def rotation(q):
    _, _, _, yaw, lean, spin = q
    cz, sz, cx, sx, cy, sy = np.cos(yaw), np.sin(yaw), np.cos(lean), np.sin(lean), np.cos(spin), np.sin(spin)
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    return Rz @ Rx @ Ry


def contact_point(q):
    centre = np.array([q[0], q[1], q[2] + R])
    a = rotation(q)[:, 1]
    e = np.cross(a, [0, 0, 1.0])
    e /= np.linalg.norm(e)
    return centre, centre + R * np.cross(a, e)


def material_velocity(q, qd, h=1e-6):
    """The velocity of the disc's material point at the contact: v_C + w x (P - C), w from the rotation's rate."""
    dR = (rotation(q + h * qd) - rotation(q - h * qd)) / (2 * h)
    W = dR @ rotation(q).T
    w = np.array([W[2, 1], W[0, 2], W[1, 0]])
    centre, P = contact_point(q)
    return qd[:3] + np.cross(w, P - centre)


def random_state(rng):
    q = rng.uniform(-1, 1, 6)
    q[4] = rng.uniform(-1.0, 1.0)  # lean away from flat
    return q, rng.normal(size=6)


@pytest.mark.compiler
def test_the_rows_are_the_contact_points_velocity(disc, rng):
    model, lib, module, _ = disc
    for _ in range(5):
        q, qd = random_state(rng)
        v = material_velocity(q, qd)
        J = module.constraint_jacobian(q)
        assert np.abs(J @ qd - v).max() <= 1e-8 * np.abs(v).max()
        assert np.allclose(lib.call("constraint_jacobian", q), J, rtol=0, atol=1e-14)
        h = 1e-6  # gamma = J' qd: the rate of J qd along qd at qdd = 0
        rate = (module.constraint_jacobian(q + h * qd) @ qd - module.constraint_jacobian(q - h * qd) @ qd) / (2 * h)
        gamma = module.constraint_bias(q, qd)
        assert np.abs(gamma - rate).max() <= 1e-7 * max(np.abs(rate).max(), 1.0)
        phi = module.constraint_residual(q)
        _, P = contact_point(q)
        assert phi[0] == 0 and phi[1] == 0 and abs(phi[2] - P[2]) <= 1e-14  # the height is the holonomic row


def steady_spin(lean, omega):
    """The disc's spin omega3 = w . axle for steady rolling with constant lean (from the vertical) and precession
    rate omega about the vertical.  With e the rolling direction, u = axle x e (centre to contact), w = omega z +
    s axle, rolling gives v_C = r omega3 e; the contact force is m (a_C + g z); in the frame turning with omega,
    dH/dt = omega z x H with H = A (w - omega3 axle) + C omega3 axle about the centre; the torque of the contact
    force about the centre balances it when

        A omega^2 sin(lean) cos(lean) - (C + m r^2) omega omega3 cos(lean) - m g r sin(lean) = 0."""
    s, c = np.sin(lean), np.cos(lean)
    return (A_DIAMETER * omega ** 2 * s * c - M * G * R * s) / ((C_AXLE + M * R ** 2) * omega * c)


@pytest.mark.compiler
@pytest.mark.parametrize("lean, omega", [(0.3, 4.0), (-0.5, 2.5), (0.8, -6.0)])
def test_steady_precession_matches_the_closed_form(disc, lean, omega):
    _, _, module, _ = disc
    omega3 = steady_spin(lean, omega)
    spin_rate = omega3 - omega * np.sin(lean)  # w . axle = omega sin(lean) + spin rate
    speed = R * omega3
    q = np.array([0.0, 0.0, R * np.cos(lean) - R, 0.0, lean, 0.7])
    qd = np.array([speed, 0.0, 0.0, omega, 0.0, spin_rate])
    assert np.abs(module.constraint_jacobian(q) @ qd).max() <= 1e-14  # rolling
    qdd, _ = module.constrained_forward_dynamics(q, qd, np.zeros(6))
    expected = np.array([0.0, omega * speed, 0.0, 0.0, 0.0, 0.0])  # the centre turns on its circle, nothing else
    assert np.abs(qdd - expected).max() <= 1e-10 * np.abs(expected).max(), qdd
    wrong = qd.copy()  # the check can fail: 1 % more spin and the disc starts to rise or fall
    wrong[5] *= 1.01
    wrong[0] = R * (wrong[5] + omega * np.sin(lean))
    qdd, _ = module.constrained_forward_dynamics(q, wrong, np.zeros(6))
    assert abs(qdd[4]) > 1e-3


@pytest.mark.compiler
def test_rolling_conserves_energy_and_stays_on_the_plane(disc, rng):
    model, _, module, stabilized = disc
    twin = NumericTwin(dataclasses.replace(model, stabilization=(0, 0)))
    q = np.array([0.0, 0.0, 0.0, 0.2, 0.3, 0.0])
    q[2] = R * np.cos(q[4]) - R
    qd = np.array([0.0, 0.0, 0.0, 1.5, 0.4, 8.0])
    J = twin.constraint_jacobian(q)
    qd = qd - np.linalg.lstsq(J, J @ qd, rcond=None)[0]  # rolling at the start
    zero = np.zeros(6)

    def energy(x, v):
        return module.kinetic_energy(x, v) + module.potential_energy(x)

    for mod, name in ((module, "plain"), (stabilized, "stabilized")):
        x, v = q.copy(), qd.copy()
        e0, worst = energy(x, v), 0.0
        for _ in range(1000):
            x, v = rk4_step(lambda a, b: mod.constrained_forward_dynamics(a, b, zero)[0], x, v, 1e-3)
            worst = max(worst, abs(energy(x, v) - e0))
        assert worst <= 1e-8 * abs(e0), (name, worst / abs(e0))
        drift = max(np.abs(mod.constraint_residual(x)).max(), np.abs(mod.constraint_jacobian(x) @ v).max())
        assert drift <= (1e-8 if name == "stabilized" else 1e-6), (name, drift)
        assert abs(x[3] - q[3]) > 0.5  # it really turned


BASE = model_path("rolling_disc").read_text().split("constraints:")[0]
BAD = {
    "wheel_without_rolling": ("constraints: [{name: a, body: disc, block: point, wheel: {radius: r, axle: 2}}]\n",
                              "constraints[0].wheel", ["not 'block: rolling'"]),
    "rolling_without_wheel": ("constraints: [{name: a, body: disc, block: rolling}]\n", "constraints[0]",
                              ["needs 'wheel"]),
    "radius": ("constraints: [{name: a, body: disc, block: rolling, wheel: {radius: -r, axle: 2}}]\n",
               "constraints[0].wheel.radius", ["must be positive"]),
    "axle": ("constraints: [{name: a, body: disc, block: rolling, wheel: {radius: r, axle: 4}}]\n",
             "constraints[0].wheel.axle", ["expected 1, 2, 3"]),
    "medium": ("constraints: [{name: a, body: disc, medium: carriage, block: rolling, wheel: {radius: r, axle: 2}}]\n",
               "constraints[0].medium", ["not supported yet"]),
    "missing_axle": ("constraints: [{name: a, body: disc, block: rolling, wheel: {radius: r}}]\n",
                     "constraints[0].wheel", ["missing field 'axle'"]),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_wheels_are_reported_with_the_place(case, tmp_path):
    text, where, words = BAD[case]
    path = tmp_path / f"{case}.yaml"
    path.write_text(BASE + text)
    assert_model_error(path, where, words)
