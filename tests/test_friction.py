"""Sliding contacts with friction and a peer for the constrained dynamics (issue 16; chapter 4, (4.5), (4.33)-(4.34),
example 3): the double pendulum whose end slides on a plane with Coulomb (and viscous) friction, and the four-bar.

The reference is sympy.physics.mechanics, an independent formulation: its LagrangesMethod gives the tree's mass
matrix and forcing, the constraint and the contact point's velocity come from its own vector kinematics, and the
KKT system ``M qdd = F + tau + J^T lambda + Jf^T W``, ``J qdd + J' qd = -(kd J qd + kp phi)`` is solved here with
NumPy, trying both signs of lambda_n for Coulomb friction (a solution is consistent when its lambda_n has the sign
assumed).  Parameters, states and torques are random.
"""
import dataclasses
from functools import lru_cache

import numpy as np
import pytest
import sympy as sp
from sympy.physics import mechanics as me

import aggsym
from aggsym.twin import NumericTwin
from conftest import model_path
from helpers import consistent_state, generated_code, rk4_step

SLIDING = "double_pendulum_sliding_friction"


def with_friction(model, law):
    """The sliding model with another friction law on its one contact, same coefficient mu (None: frictionless)."""
    c = model.constraints[0]
    friction = None if law is None else (law, c.friction[1])
    return dataclasses.replace(model, constraints=(dataclasses.replace(c, friction=friction),))


# --------------------------------------------------------------------------------------------------------------
# the peer: sympy.physics.mechanics

def _body(name, frame, point, mass, inertia):
    centre = me.Point(f"{name}_c")
    centre.set_pos(point[0], point[1])
    return centre, me.RigidBody(name, centre, frame, mass, (me.inertia(frame, *inertia), centre))


@lru_cache(maxsize=None)
def sliding_peer():
    """The double pendulum of Fig. 1.4 (variant 2) written with sympy.physics.mechanics: functions of
    (q, qd, parameters) for M, F (LagrangesMethod's forcing), the constraint phi (e1 of the end less h), its
    row J, J' qd, and the end's velocity along e2, e3 (the slip velocities) with their rows Jf."""
    q = me.dynamicsymbols("o12 th15 th26")
    qd = [sp.diff(x, me.dynamicsymbols._t) for x in q]
    m2, m3, r21, r31, p21, l2, h, g = sp.symbols("m2 m3 r21 r31 p21 l2 h g")
    I2 = sp.symbols("I244 I255 I266")
    I3 = sp.symbols("I344 I355 I366")
    N = me.ReferenceFrame("N")
    A1 = N.orientnew("A1", "Axis", (q[1], N.y))
    A2 = A1.orientnew("A2", "Axis", (q[2], A1.z))
    O = me.Point("O")
    O.set_vel(N, 0)
    H = O.locatenew("H", q[0] * N.y)
    E = H.locatenew("E", p21 * A1.x)
    c1, arm1 = _body("arm1", A1, (H, r21 * A1.x), m2, I2)
    c2, arm2 = _body("arm2", A2, (E, r31 * A2.x), m3, I3)
    tip = E.locatenew("T", l2 * A2.x)
    for point in (H, E, c1, c2, tip):
        point.set_vel(N, point.pos_from(O).dt(N))
    L = me.Lagrangian(N, arm1, arm2)
    forces = [(c1, m2 * g * N.x), (c2, m3 * g * N.x)]
    lm = me.LagrangesMethod(L, q, forcelist=forces, frame=N)
    lm.form_lagranges_equations()
    phi = sp.Matrix([tip.pos_from(O).dot(N.x) - h])
    slip = sp.Matrix([tip.vel(N).dot(N.y), tip.vel(N).dot(N.z)])
    return _lambdified(q, qd, (m2, m3, r21, r31, p21, l2, h) + I2 + I3 + (g,), lm, phi, slip)


@lru_cache(maxsize=None)
def four_bar_peer():
    """The four-bar (crank, coupler, rocker) with sympy.physics.mechanics; the rocker's end pinned at (d, 0)."""
    q = me.dynamicsymbols("q1 q2 q3")
    qd = [sp.diff(x, me.dynamicsymbols._t) for x in q]
    a, b, c, d = sp.symbols("a b c d")
    N = me.ReferenceFrame("N")
    frames = [N.orientnew("A1", "Axis", (q[0], N.z))]
    frames.append(frames[0].orientnew("A2", "Axis", (q[1], frames[0].z)))
    frames.append(frames[1].orientnew("A3", "Axis", (q[2], frames[1].z)))
    O = me.Point("O")
    O.set_vel(N, 0)
    masses, inertias = (0.2, 0.5, 0.4), ((1e-5, 2e-4, 2e-4), (2e-5, 4e-3, 4e-3), (2e-5, 2e-3, 2e-3))
    joints, bodies, forces, origin = [], [], [], O
    for k, (frame, length) in enumerate(zip(frames, (a, b, c))):
        centre, body = _body(f"link{k}", frame, (origin, length / 2 * frame.x), masses[k], inertias[k])
        joints.append((origin, centre))
        bodies.append(body)
        forces.append((centre, -masses[k] * 9.81 * N.y))
        origin = origin.locatenew(f"J{k}", length * frame.x)
    for pair in joints:
        for point in pair:
            point.set_vel(N, point.pos_from(O).dt(N))
    origin.set_vel(N, origin.pos_from(O).dt(N))
    lm = me.LagrangesMethod(me.Lagrangian(N, *bodies), q, forcelist=forces, frame=N)
    lm.form_lagranges_equations()
    end = origin.pos_from(O)
    phi = sp.Matrix([end.dot(N.x) - d, end.dot(N.y)])
    return _lambdified(q, qd, (a, b, c, d), lm, phi, sp.zeros(0, 1))


def _lambdified(q, qd, params, lm, phi, slip):
    u, v = sp.symbols(f"u0:{len(q)}"), sp.symbols(f"v0:{len(q)}")
    subs = dict(zip(qd, v)) | dict(zip(q, u))
    M = lm.mass_matrix.subs(subs)
    F = lm.forcing.subs(subs)
    phi = phi.subs(subs)
    J = phi.jacobian(u)
    gamma = (J * sp.Matrix(v)).jacobian(u) * sp.Matrix(v)
    slip = slip.subs(subs)
    Jf = slip.jacobian(v) if slip.rows else sp.zeros(0, len(q))
    args = (u, v, params)
    return {name: sp.lambdify(args, expr, "numpy") for name, expr in
            (("M", M), ("F", F), ("phi", phi), ("J", J), ("gamma", gamma), ("Jf", Jf), ("w", slip))}


def peer_dynamics(peer, q, qd, tau, params, kp=0.0, kd=0.0, law=None, coefficient=0.0):
    """(qdd, lambda) from the peer's KKT system.  For Coulomb friction the sign s of lambda_n is tried both ways:
    the list of consistent solutions (s lambda_n >= 0) is returned, empty or with two entries in Painleve's
    cases; otherwise the one solution."""
    M, F = np.array(peer["M"](q, qd, params), float), np.array(peer["F"](q, qd, params), float).ravel()
    J, gamma = np.array(peer["J"](q, qd, params), float), np.array(peer["gamma"](q, qd, params), float).ravel()
    phi = np.array(peer["phi"](q, qd, params), float).ravel()
    n, m = len(q), len(phi)
    force = F + tau
    columns = J.T.copy()
    if law is not None:
        Jf = np.array(peer["Jf"](q, qd, params), float)
        w = Jf @ qd
        if law == "viscous":
            force = force - coefficient * Jf.T @ w
    rhs = -gamma - kd * J @ qd - kp * phi
    found = []
    for s in ((1.0, -1.0) if law == "coulomb" else (None,)):
        H = columns.copy()
        if s is not None:
            H[:, 0] -= coefficient * s * Jf.T @ (w / np.linalg.norm(w))
        K = np.block([[M, -H], [J, np.zeros((m, m))]])
        x = np.linalg.solve(K, np.concatenate([force, rhs]))
        if s is None:
            return x[:n], x[n:]
        if s * x[n] >= 0:
            found.append((x[:n], x[n:]))
    return found


def random_parameters(model, rng, spread=0.3):
    """The model's defaults, each scaled by a random factor in [1 - spread, 1 + spread]."""
    defaults = np.array([float(p.value) for p in model.parameters])
    return defaults * rng.uniform(1 - spread, 1 + spread, defaults.size)


def sliding_arguments(model, p):
    """The peer's parameters (m2, m3, r21, r31, p21, l2, h, I2.., I3.., g) from aggsym's p."""
    value = {par.name: x for par, x in zip(model.parameters, p)}
    names = ("m2", "m3", "r21", "r31", "p21", "l2", "h", "I244", "I255", "I266", "I344", "I355", "I366", "g")
    return tuple(value[k] for k in names)


@pytest.fixture(scope="module")
def sliding(tmp_path_factory):
    """The sliding model's NumPy modules: Coulomb (as in models/), viscous, frictionless; stabilization zero."""
    model = aggsym.load(model_path(SLIDING))
    plain = dataclasses.replace(model, stabilization=(0, 0))
    out = {}
    for law in ("coulomb", "viscous", None):
        variant = with_friction(plain, law)
        out[law] = generated_code(variant, tmp_path_factory.mktemp(str(law)), c=False)[1]
    out["model"] = model
    return out


@pytest.mark.parametrize("law", ["coulomb", "viscous", None])
def test_the_sliding_pendulum_matches_sympy_mechanics(sliding, law, rng):
    model, module, peer = sliding["model"], sliding[law], sliding_peer()
    mu_index = [par.name for par in model.parameters].index("mu")
    checked = 0
    for _ in range(12):
        p = random_parameters(model, rng)
        q, qd, tau = rng.uniform(-0.8, 0.8, 3), rng.normal(size=3), rng.normal(size=3)
        ref = peer_dynamics(peer, q, qd, tau, sliding_arguments(model, p), law=law, coefficient=p[mu_index])
        if law == "coulomb":
            if len(ref) != 1:  # Painleve's cases: the other test
                continue
            ref = ref[0]
        qdd, lam = module.constrained_forward_dynamics(q, qd, tau, p)
        scale = np.abs(ref[0]).max()
        assert np.abs(qdd - ref[0]).max() <= 1e-10 * scale, (q, qd, tau, qdd, ref[0])
        assert np.abs(lam - ref[1]).max() <= 1e-10 * np.abs(ref[1]).max()
        w = np.array(sliding_peer()["w"](q, qd, sliding_arguments(model, p)), float).ravel()
        assert np.allclose(module.slip_velocities(q, qd, p), w, rtol=1e-12, atol=1e-14)
        checked += 1
    assert checked >= 8


def test_friction_changes_the_motion(sliding, rng):
    """The three laws give different qdd where the end slides (the check above could not tell them apart if
    friction were ignored)."""
    q, qd, tau = np.array([0.1, 0.4, -0.5]), np.array([0.3, -0.7, 0.9]), np.zeros(3)
    results = [sliding[law].constrained_forward_dynamics(q, qd, tau)[0] for law in ("coulomb", "viscous", None)]
    assert np.abs(results[0] - results[2]).max() > 1e-2 and np.abs(results[1] - results[2]).max() > 1e-2


def test_painleve_states_are_refused_exactly_where_no_solution_exists(sliding, rng):
    """One Coulomb contact: the generated code takes the sign of lambda_n from the frictionless solution; where
    that sign is inconsistent, no sign is (Sherman-Morrison), so the refusals are exactly the states without a
    consistent solution; where two exist (Painleve's non-uniqueness) it returns one of them, the one continuous
    with the frictionless sign.  Upside-down states with a large mu produce every case."""
    model, peer = sliding["model"], sliding_peer()
    module = sliding["coulomb"]
    mu_index = [p.name for p in model.parameters].index("mu")
    refused = solved = ambiguous = 0
    for _ in range(200):
        p = random_parameters(model, rng)
        p[mu_index] = rng.uniform(0.5, 3.0)
        q, qd, tau = rng.uniform(-np.pi, np.pi, 3), rng.normal(size=3), rng.normal(size=3)
        ref = peer_dynamics(peer, q, qd, tau, sliding_arguments(model, p), law="coulomb", coefficient=p[mu_index])
        try:
            qdd, _ = module.constrained_forward_dynamics(q, qd, tau, p)
        except np.linalg.LinAlgError:
            assert not ref, (q, qd, tau, p)
            refused += 1
            continue
        assert any(np.abs(qdd - r[0]).max() <= 1e-8 * np.abs(r[0]).max() for r in ref), (q, qd, tau, p)
        solved += 1
        ambiguous += len(ref) > 1
    assert refused >= 5 and solved >= 100 and ambiguous >= 1, (refused, solved, ambiguous)


def power(module, q, qd, qdd, eps=1e-6):
    """dE/dt along (q, qd, qdd), E = kinetic + potential energy, by central differences."""
    def energy(x, v):
        return module.kinetic_energy(x, v) + module.potential_energy(x)
    return (energy(q + eps * qd, qd + eps * qdd) - energy(q - eps * qd, qd - eps * qdd)) / (2 * eps)


@pytest.mark.parametrize("law", ["coulomb", "viscous"])
def test_friction_dissipates_exactly_its_power(sliding, law, rng):
    """On the constraint manifold (J qd = 0) with tau = 0, dE/dt = w . W: -mu |lambda_n| |w| or -c |w|^2."""
    model, module = sliding["model"], sliding[law]
    twin = NumericTwin(with_friction(dataclasses.replace(model, stabilization=(0, 0)), law))
    mu = float(model.parameters[[p.name for p in model.parameters].index("mu")].value)
    for _ in range(5):
        q, qd = consistent_state(twin, rng.uniform(-0.6, 0.6, 3), rng.normal(size=3))
        qdd, (lam,) = module.constrained_forward_dynamics(q, qd, np.zeros(3))  # one row: lambda has one entry
        w = module.slip_velocities(q, qd)
        expected = -mu * abs(lam) * np.linalg.norm(w) if law == "coulomb" else -mu * w @ w
        assert expected < 0
        assert abs(power(module, q, qd, qdd) - expected) <= 1e-6 * abs(expected)


def test_energy_decreases_along_sliding_motion(tmp_path, rng):
    """RK4, step 1e-3 s, 1 s, with the model's stabilization: E never increases by more than the integration
    error and falls overall; the end stays on the plane (drift <= 1e-8)."""
    model = aggsym.load(model_path(SLIDING))
    _, module, _ = generated_code(model, tmp_path, c=False)
    twin = NumericTwin(model)
    q, qd = consistent_state(twin, np.array([0.2, 0.5, -0.9]), np.array([1.0, 0.5, 1.5]))
    zero = np.zeros(3)

    def energy(x, v):
        return module.kinetic_energy(x, v) + module.potential_energy(x)

    e0 = energy(q, qd)
    e = [e0]
    for _ in range(1000):
        q, qd = rk4_step(lambda a, b: module.constrained_forward_dynamics(a, b, zero)[0], q, qd, 1e-3)
        e.append(energy(q, qd))
    rises = np.diff(e)
    assert rises.max() <= 1e-9 * abs(e0), rises.max()
    assert e[-1] < e0 - 1e-3 * abs(e0)
    assert np.abs(module.constraint_residual(q)).max() <= 1e-8


def test_the_four_bar_matches_sympy_mechanics(tmp_path, rng):
    model = aggsym.load(model_path("four_bar"))
    plain = dataclasses.replace(model, stabilization=(0, 0))
    _, module, _ = generated_code(plain, tmp_path, c=False)
    _, stabilized, _ = generated_code(model, tmp_path / "stab", c=False)
    peer = four_bar_peer()
    for _ in range(8):
        p = random_parameters(model, rng, spread=0.1)
        q, qd, tau = rng.uniform(-np.pi, np.pi, 3), rng.normal(size=3), rng.normal(size=3)
        for mod, kp, kd in ((module, 0.0, 0.0), (stabilized, 100.0, 20.0)):
            ref = peer_dynamics(peer, q, qd, tau, tuple(p), kp=kp, kd=kd)
            qdd, lam = mod.constrained_forward_dynamics(q, qd, tau, p)
            cond = np.linalg.cond(mod.delassus(q, p))
            assert np.abs(qdd - ref[0]).max() <= 1e-12 * cond * np.abs(ref[0]).max()
            assert np.abs(lam - ref[1]).max() <= 1e-12 * cond * np.abs(ref[1]).max()
        assert np.allclose(module.constraint_residual(q, p),
                           np.array(peer["phi"](q, qd, tuple(p)), float).ravel(), rtol=0, atol=1e-13)


def test_the_manifest_describes_friction_and_slip(sliding, tmp_path):
    model = aggsym.load(model_path(SLIDING))
    _, _, manifest = generated_code(model, tmp_path, c=False)
    entry = manifest["constraints"]["constraints"][0]
    assert entry["free"] == ["o2", "o3"] and entry["friction"] == {"coulomb": "mu"} and entry["rows"] == ["o1"]
    assert manifest["layouts"]["slip_velocities"]["rows"] == ["foot.o2", "foot.o3"]
    assert manifest["conservative"] is False
