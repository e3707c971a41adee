"""Support dynamics (issue 16; the support paper (3.1)-(3.4)): the support equation's coefficients, the direct and
the inverse problem.

References: Pinocchio's rnea with an external force on the free root (solo12 with --floating-base --support): for
the q'' that support_direct returns under a wrench T, with the mechanism's gamma'' given, the support's six
generalized forces vanish (the support is not actuated); the same for the gamma'' that support_inverse returns
for a wanted q''.  The spacecraft of the paper's section 6 (k = 6): momentum conserved along free flight while the
manipulator follows a prescribed gamma(t) through support_direct, support_inverse giving back the gamma'' used.
A support with fewer than six mechanism coordinates: least squares, the residual orthogonal to I's columns.
"""
import dataclasses

import numpy as np
import pytest

import aggsym
from conftest import model_path
from helpers import generated_code, rk4_step, rk4_step_in_time, robot_path, run_cli
from pinocchio_reference import pin, pinocchio_model, pinocchio_q

pytestmark = pytest.mark.pinocchio


@pytest.fixture(scope="module")
def solo(tmp_path_factory):
    out = tmp_path_factory.mktemp("solo")
    code, err = run_cli(["generate", str(robot_path("solo12")), "--floating-base", "--support", "-o", str(out), "-q"])
    assert code == 0, err
    from aggsym.codegen.compile import CLibrary, compile_shared, import_module
    import json
    manifest = json.loads((out / "solo12.json").read_text())  # (named after solo12.urdf)
    lib = CLibrary(compile_shared(out / "solo12.c", out / "libsolo12.so", extra=("-O2",)), manifest)
    return lib, import_module(out / "solo12.py"), manifest


def support_forces(pm, q, qd, qdd, T):
    """Pinocchio's generalized forces of the free root under the world wrench T (about the world origin) on it:
    zero when the motion is one the unactuated support makes."""
    data = pm.createData()
    Q = pinocchio_q(pm, q)
    pin.forwardKinematics(pm, data, Q)
    fext = [pin.Force.Zero() for _ in range(pm.njoints)]
    fext[1] = data.oMi[1].actInv(pin.Force(T[:3], T[3:]))
    return pin.rnea(pm, data, Q, qd, qdd, pin.StdVec_Force(fext))[:6]


@pytest.mark.compiler
def test_direct_and_inverse_problems_against_pinocchio(solo, rng):
    lib, module, manifest = solo
    pm = pinocchio_model(robot_path("solo12"), True)
    assert manifest["layouts"]["support_direct"]["support"] == "base_link"
    k = manifest["nq"] - 6
    for _ in range(4):
        q, qd = rng.uniform(-1, 1, 6 + k), rng.normal(size=6 + k)
        gammadd, T = rng.normal(size=k), 10 * rng.normal(size=6)
        for call in (module.support_direct, lambda *a: lib.call("support_direct", *a)):
            qdd_s = call(q[:6], qd[:6], q[6:], qd[6:], gammadd, T)
            forces = support_forces(pm, q, qd, np.concatenate([qdd_s, gammadd]), T)
            assert np.abs(forces).max() <= 1e-9 * np.abs(T).max(), forces
        wanted = rng.normal(size=6)
        for call in (module.support_inverse, lambda *a: lib.call("support_inverse", *a)):
            gdd, residual = call(q[:6], qd[:6], wanted, q[6:], qd[6:], T)
            assert np.abs(residual).max() <= 1e-9 * np.abs(T).max()  # k = 12 > 6: exact
            forces = support_forces(pm, q, qd, np.concatenate([wanted, gdd]), T)
            assert np.abs(forces).max() <= 1e-8 * np.abs(T).max(), forces
            A, B, I, J, L, g = module.support_coefficients(q[:6], qd[:6], q[6:], qd[6:])
            y = np.linalg.lstsq(I.T, gdd, rcond=None)[0]  # minimum norm: gamma'' in the row space of I
            assert np.abs(I.T @ y - gdd).max() <= 1e-9 * np.abs(gdd).max()


def test_the_coefficients_are_the_support_rows_of_the_equations(solo, rng):
    """M^T (A qdd + B qd + I gammadd + J gammad + g) equals the support rows of the full inverse dynamics (rnea),
    with M the free root's motion subspace from Pinocchio; L T equals Pinocchio's wrench in the root frame."""
    _, module, manifest = solo
    pm = pinocchio_model(robot_path("solo12"), True)
    data = pm.createData()
    k = manifest["nq"] - 6
    q, qd, qdd = rng.uniform(-1, 1, 6 + k), rng.normal(size=6 + k), rng.normal(size=6 + k)
    A, B, I, J, L, g = module.support_coefficients(q[:6], qd[:6], q[6:], qd[6:])
    Q = pinocchio_q(pm, q)
    pin.forwardKinematics(pm, data, Q, qd)
    M = data.joints[1].S  # columns: the root's motion per unit rate of its six coordinates, in its frame
    lhs = M.T @ (A @ qdd[:6] + B @ qd[:6] + I @ qdd[6:] + J @ qd[6:] + g)
    tau = pin.rnea(pm, data, Q, qd, qdd)[:6]
    assert np.abs(lhs - tau).max() <= 1e-9 * np.abs(tau).max()
    assert np.allclose(M.T @ (A @ qdd[:6]), M.T @ A @ qdd[:6])
    T = rng.normal(size=6)
    local = data.oMi[1].actInv(pin.Force(T[:3], T[3:]))
    assert np.allclose(L @ T, np.concatenate([local.linear, local.angular]), rtol=0, atol=1e-12 * np.abs(T).max())
    # B qd + J gammad is the bias: the support rows of nonLinearEffects less gravity
    bias = pin.nonLinearEffects(pm, data, Q, qd)[:6] - pin.computeGeneralizedGravity(pm, data, Q)[:6]
    assert np.abs(M.T @ (B @ qd[:6] + J @ qd[6:]) - bias).max() <= 1e-9 * np.abs(bias).max()


def test_spacecraft_free_flight_with_a_prescribed_manipulator(tmp_path):
    """The paper's example: the manipulator and the antenna follow gamma(t); the support moves by (3.4) 1° with
    T = 0; the momentum of the whole system stays constant (to 1e-10); support_inverse gives back gamma''."""
    model = aggsym.load(model_path("spacecraft"))
    assert model.support == "support" and model.mechanism_coordinates == 6
    _, module, _ = generated_code(model, tmp_path, c=False)
    amplitude, omega, phase = np.array([0.3, -0.2, 0.4, 0.8, -0.6, 1.0]), np.array([1.0, 2.0, 1.5, 3.0, 2.5, 4.0]), \
        np.array([0.1, 0.5, 0.9, 0.2, 0.0, 1.3])

    def gamma(t):
        s = omega * t + phase
        return amplitude * np.sin(s), amplitude * omega * np.cos(s), -amplitude * omega ** 2 * np.sin(s)

    T = np.zeros(6)
    q, qd = np.array([0.1, -0.2, 0.3, 0.2, -0.1, 0.4]), np.array([0.01, 0.02, -0.01, 0.005, 0.01, -0.02])
    t, dt = 0.0, 1e-3

    def accel(t, q, qd):
        g, gd, gdd = gamma(t)
        return module.support_direct(q, qd, g, gd, gdd, T)

    def momentum(t, q, qd):
        g, gd, _ = gamma(t)
        return module.momentum(np.concatenate([q, g]), np.concatenate([qd, gd]))

    h0 = momentum(t, q, qd)
    assert np.abs(h0[3:]).max() > 1.0
    worst = 0.0
    for step in range(1000):  # RK4 with the time in the right-hand side
        q, qd = rk4_step_in_time(accel, t, q, qd, dt)
        t += dt
        worst = max(worst, np.abs(momentum(t, q, qd) - h0).max())
        if step % 250 == 0:
            g, gd, gdd = gamma(t)
            back, residual = module.support_inverse(q, qd, accel(t, q, qd), g, gd, T)
            assert np.abs(back - gdd).max() <= 1e-9 * np.abs(gdd).max() and np.abs(residual).max() <= 1e-9
    assert worst <= 1e-10 * np.abs(h0).max(), worst


def test_fewer_than_six_mechanism_coordinates_give_least_squares(tmp_path, rng):
    text = model_path("spacecraft").read_text()
    cut = text.index("  - name: antenna")
    end = text.index("  - name: link22")
    path = tmp_path / "small_spacecraft.yaml"
    path.write_text(text[:cut] + text[end:])
    model = aggsym.load(path)
    assert model.mechanism_coordinates == 3
    twin = aggsym.NumericTwin(model)
    for _ in range(3):
        q, qd, wanted, T = rng.uniform(-1, 1, 9), rng.normal(size=9), rng.normal(size=6), rng.normal(size=6)
        gdd, residual = twin.support_inverse(q[:6], qd[:6], wanted, q[6:], qd[6:], T)
        A, B, I, J, L, g = twin.support_coefficients(q[:6], qd[:6], q[6:], qd[6:])
        r = L @ T - g - A @ wanted - B @ qd[:6] - J @ qd[6:]
        expected = np.linalg.lstsq(I, r, rcond=None)[0]
        assert np.allclose(gdd, expected, rtol=1e-9, atol=1e-12)
        assert np.allclose(residual, r - I @ gdd, atol=1e-12)
        assert np.abs(I.T @ residual).max() <= 1e-9 * np.abs(r).max()
        assert np.abs(residual).max() > 1e-6  # three rates cannot steer six: the residual is real


BAD = {
    "unknown": ("support: hull\n", ["unknown body 'hull'"]),
    "not_root": ("support: link23\n", ["one body on the world", "parent is 'link22'"]),
    "not_free": (None, ["must be free", "o1, o2, o3"]),
    "not_text": ("support: [support]\n", ["expected a body name"]),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_supports_are_reported_with_the_place(case, tmp_path):
    text = model_path("spacecraft").read_text().replace("support: support\n", "")
    addition, words = BAD[case]
    if addition is None:
        text = text.replace("functional: {o1: x11, o2: y11, o3: z11, theta4: a11, theta5: b11, theta6: c11}",
                            "functional: {o1: x11, o2: y11, o3: z11}") + "support: support\n"
    else:
        text += addition
    path = tmp_path / f"{case}.yaml"
    path.write_text(text)
    with pytest.raises(aggsym.ModelError) as info:
        aggsym.load(path)
    assert info.value.where == "support" and info.value.line is not None, str(info.value)
    for w in words:
        assert w in str(info.value), str(info.value)


def test_support_options_on_the_command_line(tmp_path):
    urdf = str(robot_path("solo12"))
    code, err = run_cli(["generate", urdf, "--support", "-o", str(tmp_path / "a")])
    assert code == 2 and "--support needs --floating-base" in err
    code, err = run_cli(["generate", str(model_path("spacecraft")), "--support", "-o", str(tmp_path / "b")])
    assert code == 2 and "does not accept --support (URDF and xacro models only" in err
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()
    model = aggsym.load(model_path("spacecraft"))
    without = dataclasses.replace(model, support=None)
    roles = {r.role for r in aggsym.contract.routines_for(without)}
    assert not roles & {"support_coefficients", "support_direct", "support_inverse"}
