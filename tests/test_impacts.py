"""Impacts, the derivatives of the constrained dynamics, and the damped solve (issue 34, items 1-3), without
Pinocchio (tests/test_impacts_pinocchio.py compares with it).

* The impact law itself: J qd+ = -r J qd-, A (qd+ - qd-) = J^T Lambda, and r = 1 keeps the kinetic energy.
* ``constrained_forward_dynamics_derivatives`` and ``impulse_dynamics_derivatives`` against central differences
  (fourth order, h = 1e-4: truncation about h^4, rounding about 1e-16 / h) of the routines themselves: the
  four-bar (a loop, Baumgarte terms, a medium that turns), the sliding double pendulum with viscous friction,
  a cart tied to a platform in prescribed motion, the rolling disc,
  and a small legged body (tests/data/impact_hopper.urdf) on a quaternion free-flyer with two point contacts
  (q moved on the manifold by our own ``integrate``).
* The generated C and NumPy module of the four-bar: the new routines against the numeric twin, the NumPy module's
  derivatives against its own central differences, the status where G is singular.
* The damped solve (``proximal:``): within its stated bound of the exact solve for a full-rank J; finite and
  within its bounds for redundant rows (the four-bar's o3, which repeats the planar motion's zero) and at the
  four-bar's dead point, where the exact solve returns nonzero; the YAML reader's checks.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import aggsym
from aggsym.contract import sample_configurations, select_routines
from aggsym.errors import AggsymError, ModelError
from aggsym.model.readers.side_files import load_constraints
from aggsym.twin import NumericTwin
from conftest import model_path
from helpers import generated_code, relative_error

NEW = ["constrained_forward_dynamics", "impulse_dynamics", "constrained_forward_dynamics_derivatives",
       "impulse_dynamics_derivatives", "constraint_jacobian", "inertia"]
H = 1e-4
DIFFERENCE_TOLERANCE = 1e-8  # the bound for derivatives against central differences


def with_routines(model, extra=()):
    return select_routines(model, NEW + (["integrate"] if model.nq != model.nv else []) + list(extra))


def stencil(f, n):
    """Columns of the fourth-order central difference of f along unit steps e_j (f takes the step vector)."""
    cols = []
    for j in range(n):
        e = np.zeros(n)
        e[j] = H
        cols.append((8 * (f(e) - f(-e)) - (f(2 * e) - f(-2 * e))) / (12 * H))
    return np.array(cols).T


def moved(twin, model, q, dv):
    """q (+) dv: on the manifold for a free-flyer (our integrate), q + dv otherwise."""
    return twin.integrate(q, dv, 1.0) if model.nq != model.nv else q + dv


def difference_errors(model, twin, q, qd, tau, r) -> dict:
    """The relative error of every derivative output against central differences of its routine."""
    n = model.nv

    def forward(qq, vv, tt):
        qdd, lam = twin.constrained_forward_dynamics(qq, vv, tt)
        return np.concatenate([qdd, twin.constraint_jacobian(qq).T @ lam])

    def impact(qq, vv):
        qd_plus, impulse, _ = twin.impulse_dynamics(qq, vv, r)
        return np.concatenate([qd_plus, impulse])

    D = twin.constrained_forward_dynamics_derivatives(q, qd, tau)
    Nq = stencil(lambda e: forward(moved(twin, model, q, e), qd, tau), n)
    Nv = stencil(lambda e: forward(q, qd + e, tau), n)
    Nt = stencil(lambda e: forward(q, qd, tau + e), n)
    I = twin.impulse_dynamics_derivatives(q, qd, r)
    Iq = stencil(lambda e: impact(moved(twin, model, q, e), qd), n)
    Iv = stencil(lambda e: impact(q, qd + e), n)
    pairs = {"dqdd_dq": (D[0], Nq[:n]), "dqdd_dqd": (D[1], Nv[:n]), "dqdd_dtau": (D[2], Nt[:n]),
             "dJtlambda_dq": (D[3], Nq[n:]), "dJtlambda_dqd": (D[4], Nv[n:]), "dJtlambda_dtau": (D[5], Nt[n:]),
             "dqd_plus_dq": (I[0], Iq[:n]), "dqd_plus_dqd_minus": (I[1], Iv[:n]),
             "dimpulse_dq": (I[2], Iq[n:]), "dimpulse_dqd_minus": (I[3], Iv[n:])}
    return {k: relative_error(a, b, floor=1.0) for k, (a, b) in pairs.items()}


def viscous_pendulum(tmp_path):
    """The sliding double pendulum of the seeds with viscous friction (c = 0.3) in place of Coulomb's."""
    text = model_path("double_pendulum_sliding_friction").read_text().replace("{coulomb: mu}", "{viscous: mu}")
    path = tmp_path / "viscous.yaml"
    path.write_text(text)
    return aggsym.load(path)


HOPPER = Path(__file__).parent / "data" / "impact_hopper.urdf"


def hopper(tmp_path, side="constraints:\n  - {name: foot, body: foot, block: point}\n"
                           "  - {name: edge, body: base, point: [0.2, 0.1, 0.05], block: point}\n"):
    """tests/data/impact_hopper.urdf on a quaternion free-flyer (nv = 9), its foot and a point of its base on the
    ground (six rows)."""
    path = tmp_path / "contacts.yaml"
    path.write_text(side)
    return load_constraints(path, aggsym.load(HOPPER, floating_base="quaternion"))


# --------------------------------------------------------------------------------------------------------------
# the impact law


@pytest.mark.parametrize("r", [0.0, 0.35, 1.0])
def test_the_impact_law_holds(r, rng):
    model = with_routines(aggsym.load(model_path("four_bar")))
    twin = NumericTwin(model)
    for _ in range(3):
        q, qd = rng.uniform(-np.pi, np.pi, 3), rng.normal(size=3)
        qd_plus, impulse, Lam = twin.impulse_dynamics(q, qd, r)
        J, A = twin.constraint_jacobian(q), twin.inertia(q)
        assert relative_error(J @ qd_plus, -r * (J @ qd), floor=np.abs(J @ qd).max()) < 1e-12
        assert relative_error(A @ (qd_plus - qd), impulse) < 1e-12
        assert relative_error(J.T @ Lam, impulse) < 1e-12
        if r == 1.0:  # an elastic impact on a scleronomic constraint keeps T
            assert abs(qd_plus @ A @ qd_plus - qd @ A @ qd) < 1e-12 * (qd @ A @ qd)
    assert model.constraint_rows == 2 and twin.impulse_dynamics(q, qd, r)[2].shape == (2,)


def test_routines_are_on_request_and_not_for_coulomb_friction():
    model = aggsym.load(model_path("four_bar"))
    from aggsym.contract import routines_for
    assert not {r.role for r in routines_for(model)} & set(NEW[1:4])  # the default set is unchanged
    coulomb = aggsym.load(model_path("double_pendulum_sliding_friction"))
    for role in NEW[1:4]:
        with pytest.raises(AggsymError, match="does not apply"):
            select_routines(coulomb, [role])


# --------------------------------------------------------------------------------------------------------------
# derivatives against central differences of the routines


def test_derivatives_of_a_loop_with_baumgarte_terms(rng):
    model = with_routines(aggsym.load(model_path("four_bar")))
    assert model.stabilization != (0, 0)
    twin = NumericTwin(model)
    for _ in range(2):
        q, qd, tau = rng.uniform(-np.pi, np.pi, 3), rng.normal(size=3), rng.normal(size=3)
        errors = difference_errors(model, twin, q, qd, tau, r=0.4)
        assert max(errors.values()) < DIFFERENCE_TOLERANCE, errors


@pytest.mark.parametrize("name", ["cart_on_moving_platform", "rolling_disc"])
def test_derivatives_with_a_moving_frame_and_a_rolling_wheel(name, rng):
    """A constraint to a frame in prescribed motion (F(t) of (4.35), at t = 0) and a rolling disc (its contact
    point moves on the wheel)."""
    model = with_routines(aggsym.load(model_path(name)))
    twin = NumericTwin(model)
    q, qd, tau = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nv), rng.normal(size=model.nv)
    errors = difference_errors(model, twin, q, qd, tau, r=0.5)
    assert max(errors.values()) < DIFFERENCE_TOLERANCE, errors


def test_derivatives_with_viscous_friction(tmp_path, rng):
    model = with_routines(viscous_pendulum(tmp_path))
    twin = NumericTwin(model)
    q, qd, tau = rng.uniform(-0.5, 0.5, 3), rng.normal(size=3), rng.normal(size=3)
    errors = difference_errors(model, twin, q, qd, tau, r=0.7)
    assert max(errors.values()) < DIFFERENCE_TOLERANCE, errors
    frictionless = NumericTwin(with_routines(dataclasses.replace(model, constraints=tuple(
        dataclasses.replace(c, friction=None) for c in model.constraints))))
    assert relative_error(frictionless.constrained_forward_dynamics_derivatives(q, qd, tau)[1],
                          twin.constrained_forward_dynamics_derivatives(q, qd, tau)[1]) > 1e-3  # friction counts


def test_derivatives_on_a_quaternion_free_flyer(tmp_path, rng):
    """A free-flyer with two point contacts: q's directions are the tangent space (q (+) d, d in the base's own
    axes)."""
    model = with_routines(hopper(tmp_path))
    assert (model.nq, model.nv, model.constraint_rows) == (10, 9, 6)
    twin = NumericTwin(model)
    q = sample_configurations(model, rng)
    qd, tau = rng.normal(size=model.nv), rng.normal(size=model.nv)
    errors = difference_errors(model, twin, q, qd, tau, r=0.2)
    assert max(errors.values()) < DIFFERENCE_TOLERANCE, errors


# --------------------------------------------------------------------------------------------------------------
# the generated code


@pytest.mark.compiler
def test_generated_c_and_numpy_of_the_new_routines(tmp_path, rng):
    model = with_routines(aggsym.load(model_path("four_bar")))
    lib, module, manifest = generated_code(model, tmp_path, opt="-O1")
    assert manifest["signatures"]["impulse_dynamics"]["inputs"] == ["q", "qd_minus", "r", "p"]
    assert manifest["signatures"]["impulse_dynamics"]["input_sizes"]["r"] == 1
    twin = NumericTwin(model)
    p = np.array([x["value"] for x in manifest["parameters"]])
    for _ in range(3):
        q, qd, tau, r = rng.uniform(-np.pi, np.pi, 3), rng.normal(size=3), rng.normal(size=3), rng.uniform()
        for role, args in (("impulse_dynamics", (q, qd, r)), ("impulse_dynamics_derivatives", (q, qd, r)),
                           ("constrained_forward_dynamics_derivatives", (q, qd, tau))):
            want = getattr(twin, role)(*args)
            for got in (lib.call(role, *args), getattr(module, role)(*args)):
                for g, w in zip(got, want):
                    assert relative_error(g, w, floor=1.0) < 1e-12, role

        def impact(qq, vv):
            return np.concatenate(module.impulse_dynamics(qq, vv, r, p)[:2])

        D = module.impulse_dynamics_derivatives(q, qd, r, p)
        assert relative_error(D[0], stencil(lambda e: impact(q + e, qd), 3)[:3], floor=1.0) < DIFFERENCE_TOLERANCE
        assert relative_error(D[3], stencil(lambda e: impact(q, qd + e), 3)[3:], floor=1.0) < DIFFERENCE_TOLERANCE
        F = module.constrained_forward_dynamics_derivatives(q, qd, tau, p)
        N = stencil(lambda e: module.constrained_forward_dynamics(q + e, qd, tau, p)[0], 3)
        assert relative_error(F[0], N, floor=1.0) < DIFFERENCE_TOLERANCE
    batch = module.impulse_dynamics(np.stack([q, q + 0.1]), np.stack([qd, qd]), np.array([0.0, 1.0]), p)
    assert batch[0].shape == (2, 3) and relative_error(batch[0][0], twin.impulse_dynamics(q, qd, 0.0)[0]) < 1e-12
    dead = np.zeros(3)  # the four-bar's dead point: G singular, the exact solve fails
    for role, args in (("impulse_dynamics", (dead, qd, 0.5)), ("impulse_dynamics_derivatives", (dead, qd, 0.5)),
                       ("constrained_forward_dynamics_derivatives", (dead, qd, tau))):
        with pytest.raises(np.linalg.LinAlgError):
            lib.call(role, *args)
        with pytest.raises(np.linalg.LinAlgError):
            getattr(module, role)(*args, p)


# --------------------------------------------------------------------------------------------------------------
# the damped (proximal) solve


def damped(model, mu, iterations):
    import sympy as sp
    return dataclasses.replace(model, proximal=(sp.Float(mu), iterations))


def delassus_system(twin, q, qd, tau):
    """(G, b) of G lambda = b, the constrained forward dynamics' multipliers (no Baumgarte terms), dense."""
    J, A = twin.constraint_jacobian(q), twin.inertia(q)
    free = np.linalg.solve(A, tau - twin.nonlinear_effects(q, qd))
    return J @ np.linalg.solve(A, J.T), -twin.constraint_bias(q, qd) - J @ free


def test_the_damped_solve_equals_the_exact_one_for_a_full_rank_jacobian(tmp_path, rng):
    model = hopper(tmp_path)
    model = with_routines(model, ["constraint_bias", "nonlinear_effects"])
    exact = NumericTwin(model)
    mu, N = 1e-9, 3
    twin = NumericTwin(damped(model, mu, N))
    for _ in range(2):
        q = sample_configurations(model, rng)
        qd, tau = rng.normal(size=model.nv), rng.normal(size=model.nv)
        G, _ = delassus_system(exact, q, qd, tau)
        rho = mu / (np.linalg.eigvalsh(G)[0] + mu)
        assert rho ** N < 1e-16  # the stated bound: exact to rounding here
        for role, args in (("constrained_forward_dynamics", (q, qd, tau)), ("impulse_dynamics", (q, qd, 0.5)),
                           ("constrained_forward_dynamics_derivatives", (q, qd, tau)),
                           ("impulse_dynamics_derivatives", (q, qd, 0.5))):
            for a, b in zip(getattr(twin, role)(*args), getattr(exact, role)(*args)):
                assert relative_error(a, b, floor=1.0) < 1e-9, role


def test_the_damped_solve_is_finite_for_redundant_rows(tmp_path, rng):
    """The four-bar with o3 blocked too (it repeats the planar motion's zero: J has rank 2 of 3 everywhere): the
    exact model is refused, the damped one is generated; its multipliers are finite and within the stated bounds
    (|x_N| <= N |b| / mu for any b; the right-hand side is consistent here, so also |x_N| <= |G^+ b|), its q''
    the unique one (that of the two independent rows), and the exact J A^-1 J^T is singular."""
    text = model_path("four_bar").read_text().replace("block: [o1, o2]", "block: [o1, o2, o3]")
    text = text.replace("stabilization: {kp: 100, kd: 20}", "")
    path = tmp_path / "four_bar_o3.yaml"
    path.write_text(text)
    with pytest.raises(ModelError, match="proximal"):
        aggsym.generate(aggsym.load(path), targets="c,numpy,manifest")
    mu, N = 1e-3, 4
    (tmp_path / "with.yaml").write_text(text + f"proximal: {{mu: {mu}, iterations: {N}}}\n")
    model = with_routines(aggsym.load(tmp_path / "with.yaml"), ["constraint_bias", "nonlinear_effects"])
    assert model.proximal[1] == N
    aggsym.generate(model, targets="c,numpy,manifest")  # accepted
    twin = NumericTwin(model)
    plain = NumericTwin(with_routines(dataclasses.replace(aggsym.load(model_path("four_bar")), stabilization=(0, 0))))
    for _ in range(3):
        q, qd, tau = rng.uniform(-np.pi, np.pi, 3), rng.normal(size=3), rng.normal(size=3)
        G, b = delassus_system(twin, q, qd, tau)
        eig = np.linalg.eigvalsh(G)
        assert abs(eig[0]) < 1e-12 * eig[-1] and eig[1] > 1e-6 * eig[-1]  # rank 2 of 3
        qdd, lam = twin.constrained_forward_dynamics(q, qd, tau)
        assert np.isfinite(qdd).all() and np.isfinite(lam).all()
        assert np.linalg.norm(lam) <= N * np.linalg.norm(b) / mu
        best = np.linalg.pinv(G) @ b  # the minimum-norm multipliers
        assert np.linalg.norm(lam) <= np.linalg.norm(best) * (1 + 1e-9)
        rho = mu / (eig[1] + mu)
        assert np.linalg.norm(lam - best) <= (rho ** N + 1e-10) * np.linalg.norm(best)
        exact_qdd, exact_lam = plain.constrained_forward_dynamics(q, qd, tau)
        assert relative_error(lam[:2], exact_lam) <= rho ** N * 2 + 1e-10
        assert relative_error(qdd, exact_qdd) <= rho ** N * 1e3 + 1e-10
        for role, args in (("impulse_dynamics", (q, qd, 0.5)), ("constrained_forward_dynamics_derivatives",
                                                               (q, qd, tau)), ("impulse_dynamics_derivatives",
                                                                               (q, qd, 0.5))):
            assert all(np.isfinite(x).all() for x in getattr(twin, role)(*args)), role


def test_the_damped_solve_at_a_singular_configuration():
    """The four-bar's dead point q = 0 (J loses a rank): the exact solve reports it, the damped one returns finite
    values."""
    model = with_routines(aggsym.load(model_path("four_bar")))
    zero, qd, tau = np.zeros(3), np.array([0.3, -0.2, 0.1]), np.array([0.1, 0.2, 0.3])
    with pytest.raises(np.linalg.LinAlgError):
        NumericTwin(model).constrained_forward_dynamics(zero, qd, tau)
    twin = NumericTwin(damped(model, 1e-6, 3))
    for role, args in (("constrained_forward_dynamics", (zero, qd, tau)), ("impulse_dynamics", (zero, qd, 1.0)),
                       ("constrained_forward_dynamics_derivatives", (zero, qd, tau)),
                       ("impulse_dynamics_derivatives", (zero, qd, 1.0))):
        assert all(np.isfinite(x).all() for x in getattr(twin, role)(*args)), role


@pytest.mark.parametrize("value, words", [
    ("{mu: 0, iterations: 3}", "mu must be positive"),
    ("{mu: 1e-6, iterations: 0}", "iterations must be a whole number"),
    ("{mu: 1e-6, iterations: 2.5}", "iterations must be a whole number"),
    ("{mu: 1e-6}", "missing field 'iterations'"),
    ("{mu: 1e-6, iterations: 2, tol: 1}", "unknown key 'tol'"),
])
def test_the_reader_checks_the_proximal_setting(tmp_path, value, words):
    path = tmp_path / "m.yaml"
    path.write_text(model_path("four_bar").read_text() + f"proximal: {value}\n")
    with pytest.raises(ModelError, match=words):
        aggsym.load(path)


def test_the_manifest_states_the_damped_solve(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(model_path("four_bar").read_text() + "proximal: {mu: 1e-8, iterations: 3}\n")
    import json
    manifest = json.loads(aggsym.generate(aggsym.load(path), targets="c,numpy,manifest").files["four_bar.json"])
    entry = manifest["constraints"]["proximal"]
    assert entry["iterations"] == 3 and float(entry["mu"]) == 1e-8 and "sigma_min" in entry["solve"]
