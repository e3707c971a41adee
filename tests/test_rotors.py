"""Rotors (2.1.1, Prop. 2.7, (2.13)): bodies carrying dynamically unbalanced, asymmetric rotating bodies.

* spin as a generalized coordinate: the gyroscope of Fig. 1.2 against sympy.physics.mechanics (KanesMethod);
* prescribed spin: the same Kane equations with the spin's row removed and theta, theta', theta'' of the time
  substituted (the carrier's motion does not act on the spin; the motor holds it);
* the book's carrier equation (2.13) itself, A V' + B V = Z + H + T with A = Theta + sum L Theta_s L^T,
  B = Phi A + A', T = sum L G_s - sum (I_s theta'' + J_s theta'), written here with 6x6 NumPy matrices from the
  model's data, against the generated routines' numeric twin;
* energy: a prescribed spin feeds energy in; the balance d(T + U)/dt = (the motor's torque) theta' holds along
  simulated motion, and the manifest says the model is not conservative.
"""
import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import aggsym
from aggsym.core.backend import Numeric
from aggsym.mechanics.bound import bind
from aggsym.codegen.compile import import_module
from aggsym.codegen.generate import generate, write
from aggsym.errors import ModelError
from aggsym.mechanics.kinematics import TreeKinematics
from aggsym.model.types import TIME, Coordinate
from aggsym.mechanics.sweeps import forward_sweep
from conftest import model_path
from helpers import assert_model_error, rk4_step_in_time
from reference import rot
from test_peer_kane import kane

DATA = Path(__file__).parent / "data"


def spins_as_coordinates(model):
    """The same system with every prescribed spin made a generalized coordinate (theta6 of the rotor's pair).

    Returns the model and, per prescribed rotor, (coordinate index, angle expression in t)."""
    bodies, spins, i = [], [], 0
    for b in model.bodies:
        if b.pair.prescribed:
            (code, expr), = b.pair.prescribed
            pair = dataclasses.replace(b.pair, coordinates=(Coordinate(f"{b.name}_spin", code, b.pair.name),),
                                       prescribed=())
            b = dataclasses.replace(b, pair=pair)
            spins.append((i, expr))
        bodies.append(b)
        i += len(b.pair.coordinates)
    return dataclasses.replace(model, bodies=tuple(bodies)), spins


def spin_values(model, expr, t):
    """theta, theta', theta'' of a prescribed spin at time t, by SymPy, parameters at their defaults."""
    values = dict(zip(model.parameter_symbols, model.parameter_values))
    return [float(sp.diff(expr, TIME, k).subs(values).subs(TIME, t)) for k in range(3)]


def full_state(model, spins, q, qd, qdd, t):
    """(q, q', q'') of the spins-as-coordinates model: the prescribed values inserted at their indices."""
    q, qd, qdd = list(q), list(qd), list(qdd)
    for i, expr in spins:
        th, thd, thdd = spin_values(model, expr, t)
        q.insert(i, th)
        qd.insert(i, thd)
        qdd.insert(i, thdd)
    return np.array(q), np.array(qd), np.array(qdd)


def test_gyroscope_with_spin_coordinate_equals_kanes_method(rng):
    """models/gyroscope.yaml (rotor = a body with the theta6 pair of the coordinate theta36) against KanesMethod."""
    model = aggsym.load(model_path("gyroscope"))
    assert [c.name for c in model.coordinates] == ["theta14", "theta25", "theta36"]
    M, forcing = kane(model)
    twin = aggsym.NumericTwin(model)
    for _ in range(5):
        q, u, qdd = rng.uniform(-np.pi, np.pi, 3), rng.normal(size=3) * [1, 1, 50], rng.normal(size=3)
        Mk = np.array(M(q, u), dtype=float)
        fk = np.array(forcing(q, u), dtype=float).ravel()
        assert np.allclose(twin.inertia(q), Mk, rtol=1e-12, atol=1e-14)
        assert np.allclose(twin.inverse_dynamics(q, u, qdd), Mk @ qdd - fk, rtol=1e-11, atol=1e-11)


def test_spin_given_as_rotor_coordinate_is_the_gyroscope(rng, tmp_path):
    """``rotors: [{spin: {coordinate: theta36}}]`` on the inner gimbal reads as gyroscope.yaml's rotor body."""
    text = model_path("gyroscope_spinning_rotor").read_text()
    assert "spin: {prescribed: Omega*t}" in text
    path = tmp_path / "gyro.yaml"
    path.write_text(text.replace("spin: {prescribed: Omega*t}", "spin: {coordinate: theta36}"))
    ours = aggsym.load(path)
    ref = aggsym.load(model_path("gyroscope"))
    assert not ours.time_dependent and [c.name for c in ours.coordinates] == ["theta14", "theta25", "theta36"]
    a, b = aggsym.NumericTwin(ours), aggsym.NumericTwin(ref)
    for _ in range(3):
        q, qd, qdd = rng.normal(size=(3, 3))
        assert np.allclose(a.inverse_dynamics(q, qd, qdd), b.inverse_dynamics(q, qd, qdd), rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("name", ["gyroscope_spinning_rotor", "flywheel_on_body"])
def test_prescribed_spin_is_kane_with_the_spin_row_removed(name, rng):
    """With a prescribed spin, A(q, t), tau and the other routines are those of the system with the spin as a
    coordinate (KanesMethod), the spin's row removed and theta(t), theta'(t), theta''(t) substituted."""
    model = aggsym.load(model_path(name))
    assert model.time_dependent and not model.conservative
    full, spins = spins_as_coordinates(model)
    M, forcing = kane(full)
    keep = [i for i in range(full.nq) if i not in {j for j, _ in spins}]
    twin = aggsym.NumericTwin(model)
    for _ in range(3):
        q, qd, qdd = rng.uniform(-1.5, 1.5, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        t = float(rng.uniform(0, 3))
        Q, U, Udd = full_state(model, spins, q, qd, qdd, t)
        Mk = np.array(M(Q, U), dtype=float)
        fk = np.array(forcing(Q, U), dtype=float).ravel()
        tau = (Mk @ Udd - fk)[keep]
        scale = max(1.0, np.abs(tau).max())
        assert np.abs(twin.inverse_dynamics(q, qd, qdd, t) - tau).max() <= 1e-10 * scale
        assert np.allclose(twin.inertia(q, t), Mk[np.ix_(keep, keep)], rtol=1e-12, atol=1e-13)
        Q0, U0, Udd0 = full_state(model, spins, q, 0 * qd, 0 * qdd, t)
        rest = (np.array(M(Q0, U0), dtype=float) @ Udd0 - np.array(forcing(Q0, U0), dtype=float).ravel())[keep]
        twin_rest = twin.bias(q, 0 * qd, t) + twin.gravity(q, t)
        assert np.abs(twin_rest - rest).max() <= 1e-10 * max(1.0, np.abs(rest).max())
        assert np.abs(twin.forward_dynamics(q, qd, tau, t) - qdd).max() <= 1e-9


def mises(inertial, values):
    """The Mises matrix (2.3) [[m E, -hat(h)], [hat(h), theta_O]] as a NumPy 6x6."""
    m, h, theta = inertial.mises()
    f = lambda x: float(sp.sympify(x).subs(values))
    m, h, theta = f(m), np.array([f(x) for x in h]), np.array([[f(x) for x in r] for r in theta])
    H = hat(h)
    return np.block([[m * np.eye(3), -H], [H, theta]])


def hat(x):
    return np.array([[0, -x[2], x[1]], [x[2], 0, -x[0]], [-x[1], x[0], 0]])


def motion(c, o):
    """L = T(o) C(c) (1.13)-(1.14) as a 6x6 acting on wrenches (f, mu)."""
    return np.block([[c, np.zeros((3, 3))], [hat(o) @ c, c]])


def phi(V):
    """Phi(V) of (1.22): Phi(V) F = (w x f, v x f + w x mu)."""
    v, w = V[:3], V[3:]
    return np.block([[hat(w), np.zeros((3, 3))], [hat(v), hat(w)]])


def test_carrier_equation_is_the_book_2_13(rng):
    """tau of a free carrier with two unbalanced asymmetric rotors equals Psi^T of (2.13) solved for Z:
    Z = A V' + B V - H - T, H = G (the carrier's weight), everything built here from the model's numbers."""
    model = aggsym.load(DATA / "free_body_two_rotors.yaml")
    assert [b.name for b in model.bodies] == ["carrier", "wheel1", "wheel2"] and model.nq == 6
    values = dict(zip(model.parameter_symbols, model.parameter_values))
    twin = aggsym.NumericTwin(model)
    carrier = model.bodies[0]
    e3 = np.array([0.0, 0, 1])
    E3 = np.kron(np.eye(2), hat(e3))  # [e3] = diag(hat e3, hat e3) of (2.13)
    f6 = np.array([0, 0, 0, 0, 0, 1.0])
    g_world = np.array([float(x) for x in model.gravity])
    for _ in range(4):
        q, qd, qdd = rng.uniform(-1.2, 1.2, 6), rng.normal(size=6), rng.normal(size=6)
        t = float(rng.uniform(0, 3))
        bound = bind(model, Numeric(), t=t)
        kin = TreeKinematics(bound, list(q))
        V, Vd = (np.array(x[0], dtype=float) for x in forward_sweep(kin, list(qd), list(qdd)))
        psi = np.array(kin.psi[0], dtype=float)  # M F of the free pair (1.30), columns
        R = rot(1, q[3]) @ rot(2, q[4]) @ rot(3, q[5])  # the carrier's axes in the world
        g = R.T @ g_world
        Theta = mises(carrier.inertial, values)
        A, Adot, T = Theta.copy(), np.zeros((6, 6)), np.zeros(6)
        for rotor in model.bodies[1:]:
            (_, expr), = rotor.pair.prescribed
            th, thd, thdd = spin_values(model, expr, t)
            c0 = np.array(rotor.pair.constructive_rotation().subs(values), dtype=float)
            p = np.array([float(sp.sympify(x).subs(values)) for x in rotor.pair.translation])
            c = c0 @ rot(3, th)
            L = motion(c, p)  # L^{lk}_s = L_sk L^s_s
            Ts = mises(rotor.inertial, values)
            A += L @ Ts @ L.T
            Adot += L @ (E3 @ Ts - Ts @ E3) @ L.T * thd
            Gs = Ts @ np.concatenate([c.T @ g, np.zeros(3)])
            Is = L @ Ts @ f6
            Js = (phi(V) @ L + L @ E3 * thd) @ Ts @ f6
            T += L @ Gs - (Is * thdd + Js * thd)
        B = phi(V) @ A + Adot
        H = Theta @ np.concatenate([g, np.zeros(3)])
        Z = A @ Vd + B @ V - H - T
        tau = psi @ Z
        assert np.abs(twin.inverse_dynamics(q, qd, qdd, t) - tau).max() <= 1e-11 * max(1.0, np.abs(tau).max())
        # A of (2.13) is the carrier's composite aggregate: A(q) = Psi^T A Psi for a single body
        assert np.allclose(twin.inertia(q, t), psi @ A @ psi.T, rtol=1e-12, atol=1e-13)


def test_the_spin_does_not_depend_on_the_carrier(rng):
    """Changing the carrier's state changes neither the rotor's relative motion nor its pair's placement: the
    rotor's angular velocity relative to the carrier is (0, 0, theta') in its axes, whatever q, q' are."""
    model = aggsym.load(model_path("flywheel_on_body"))
    (_, expr), = model.bodies[1].pair.prescribed
    t = 0.8
    th, thd, _ = spin_values(model, expr, t)
    bound = bind(model, Numeric(), t=t)
    for _ in range(3):
        q, qd = rng.normal(size=(2, 3))
        kin = TreeKinematics(bound, list(q))
        V = kin.velocities(list(qd))
        rel = np.array(V[1], dtype=float) - np.array(kin.L[1].twist(V[0]), dtype=float)
        assert np.allclose(rel, [0, 0, 0, 0, 0, thd], atol=1e-12)
        c = np.array(kin.L[1].c, dtype=float)
        c0 = np.array(model.bodies[1].pair.constructive_rotation(), dtype=float)
        assert np.allclose(c, c0 @ rot(3, th), atol=1e-14)


def rk4(f, q, v, t, dt, steps):
    """``steps`` RK4 steps of q'' = f(q, q', t) from time t: (q, q', t) at the end."""
    for _ in range(steps):
        q, v = rk4_step_in_time(lambda t, q, v: f(q, v, t), t, q, v, dt)
        t = t + dt
    return q, v, t


@pytest.mark.parametrize("name", ["gyroscope_spinning_rotor", "flywheel_on_body"])
def test_energy_balance_of_the_motor(name, tmp_path, rng):
    """Along free motion (tau = 0) through the generated NumPy module, T + U changes by the motor's work
    int tau_s theta' dt, tau_s the spin row of the spins-as-coordinates model's inverse dynamics; and the
    manifest says conservative: false with t in every signature."""
    model = aggsym.load(model_path(name))
    write(generate(model, targets="c,numpy,manifest"), tmp_path)
    mod = import_module(tmp_path / f"{name}.py")
    manifest = json.loads((tmp_path / f"{name}.json").read_text())
    assert manifest["conservative"] is False
    assert all(sig["inputs"][-2:] == ["t", "p"] for sig in manifest["signatures"].values())
    assert manifest["time"]["prescribed"][0]["carrier"] == model.bodies[-1].parent
    full, spins = spins_as_coordinates(model)
    (i, expr), = spins
    ftwin = aggsym.NumericTwin(full)
    zero = np.zeros(model.nq)

    def acc(q, v, t):
        return mod.forward_dynamics(q, v, zero, t)

    def energy(q, v, t):
        return mod.kinetic_energy(q, v, t) + mod.potential_energy(q, t)

    def power(q, v, t):
        Q, U, Udd = full_state(model, spins, q, v, acc(q, v, t), t)
        return ftwin.inverse_dynamics(Q, U, Udd)[i] * U[i]

    q, v, t = rng.uniform(-0.5, 0.5, model.nq), rng.normal(size=model.nq), 0.2
    E0, work, dt = energy(q, v, t), 0.0, 2e-4
    for _ in range(5):  # Simpson's rule on each 40-step stretch
        p0 = power(q, v, t)
        qm, vm, tm = rk4(acc, q, v, t, dt, 20)
        q, v, t = rk4(acc, qm, vm, tm, dt, 20)
        work += 40 * dt / 6 * (p0 + 4 * power(qm, vm, tm) + power(q, v, t))
    change = energy(q, v, t) - E0
    tol = 1e-7 * max(abs(E0), abs(work))
    assert abs(work) > 100 * tol  # the motor does work: T + U alone is not conserved
    assert abs(change - work) <= tol


BAD = {
    # name: (rotor entry, expected YAML path, words)
    "both_spins": ("spin: {coordinate: s, prescribed: 't'}", "bodies[0].rotors[0].spin", ["exactly one of"]),
    "no_time": ("spin: {prescribed: '3*m'}", "bodies[0].rotors[0].spin.prescribed", ["does not depend on the time"]),
    "unknown_symbol": ("spin: {prescribed: 'w*t'}", "bodies[0].rotors[0].spin.prescribed",
                       ["undefined parameter 'w'", "time t"]),
    "bad_function": ("spin: {prescribed: 'floor(t)'}", "bodies[0].rotors[0].spin.prescribed", ["unknown function 'floor'"]),
    "no_mass": ("spin: {prescribed: 't'}\n        com: [0, 0, 0]", "bodies[0].rotors[0]", ["com given without mass"]),
    "no_inertial": ("spin: {prescribed: 't'}", "bodies[0].rotors[0]", ["a rotor needs mass properties"]),
    "unknown_key": ("spin: {prescribed: 't'}\n        colour: red", "bodies[0].rotors[0].colour",
                    ["unknown key 'colour'"]),
    "spin_key": ("spin: {rate: 3}", "bodies[0].rotors[0].spin.rate", ["unknown key 'rate'"]),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_rotor_is_reported_precisely(case, tmp_path):
    entry, where, words = BAD[case]
    text = ("name: x\nparameters: {m: 1.0}\nbodies:\n  - name: arm\n    pair: {functional: {theta6: q1}}\n"
            "    mass: 1.0\n    rotors:\n      - name: wheel\n        " + entry + "\n")
    if case not in ("no_mass", "no_inertial"):
        text += "        mass: 0.5\n"
    path = tmp_path / f"{case}.yaml"
    path.write_text(text)
    assert_model_error(path, where, words)


def test_rotor_name_must_be_a_new_body_name(tmp_path):
    path = tmp_path / "dup.yaml"
    path.write_text("name: x\nbodies:\n  - name: arm\n    mass: 1.0\n    rotors:\n"
                    "      - name: arm\n        spin: {prescribed: t}\n        mass: 0.5\n")
    with pytest.raises(ModelError) as info:
        aggsym.load(path)
    assert info.value.where == "bodies[0].rotors[0].name" and info.value.line == 6
    assert "duplicate body name 'arm'" in str(info.value)
