"""The book's two constrained examples (Konoplev 1996, chapter 4, Examples 1 and 2) as models:
models/walking_machine_on_ground.yaml (Fig. 1.6 on six point supports O_i4, Prop. 4.7) and
models/test_bench_constrained.yaml (Fig. 1.7 closed by a spherical joint on each support's lever and a cylinder
joint on its last link, Prop. 4.7-4.8; the YAML says why this reading).

Checked through the NumPy modules generated from the models (once with the model's Baumgarte terms, once with
``stabilization = (0, 0)``):

* the counts of section 1.2.1 and of the examples: n coordinates, m rows, rank J = D_lambda^T (4.26)-(4.27) and
  n - rank J degrees of freedom, at the default q = 0 and at three random consistent states (Newton on phi, then
  qd projected on the null space of J);
* the equations (4.25)-(4.28) at consistent states, without stabilization: the residuals of
  A qdd + b + g - tau - J^T lambda and J qdd + gamma, with A and b + g from the modules' ``inertia`` and
  ``nonlinear_effects``, and qdd, lambda from ``constrained_forward_dynamics``;
* J against phi independently: J qd equals the central-difference rate of phi along qd for the translational
  rows; for the cylinder joints' rotational rows (phi the rotation vector of the relative orientation Q, J the
  relative angular velocity omega, both in the reference axes), J's rows equal omega from our own forward
  kinematics of the printed pairs, and phi's rate equals (alpha/2)(cot(alpha/2) omega_perp - e3 x omega_perp),
  alpha the turn about the free axis (the log map's derivative at Q = c_3(alpha));
* one RK4 run (step 1e-3; 1 s for the walking machine, 0.5 s for the test bench) from a consistent state, the
  joints held by conservative springs about it: the constraint drift with the model's stabilization, and the
  energy without stabilization.

Every check has a counterpart that must fail (the reactions left out, the naive rate of a rotational row, the
unconstrained tree's drift), so that none holds vacuously.

Measured (walking machine / test bench): rank J at q = 0 16 / 42 (sigma_min / sigma_max of the kept values 1.2e-2 /
1.2e-2; the walking machine's next 4e-17), at the random states 18 / 42 (down to 3.8e-2 / 5.2e-3); the residual of
A qdd + b + g - tau - J^T lambda 5.1e-16 / 5.5e-16, of J qdd + gamma 2.0e-16 / 2.1e-14 (cond J A^-1 J^T up to 9 /
9e3); J qd against the rate of phi 5.1e-11 / 7.5e-11, the cylinder rows against our kinematics 1.5e-11 and the log
map 1.2e-11 (turns alpha within +-0.11); RK4 drift 2.6e-12 / 9.4e-13, energy 1.1e-9 / 1.2e-10 of T(0); the
unconstrained counterpart opens by 4e-2 / 0.25 within 50 steps.
"""
import dataclasses

import numpy as np
import pytest

import aggsym
from conftest import model_path
from helpers import consistent_state, generated_code, rk4_step

# name: (n coordinates, m rows, rank J at the default q = 0, RK4 run length in steps of 1e-3 s)
BOOK = {
    # 24 coordinates, 18 rows (six points, Prop. 4.7), 24 -> 6 degrees of freedom; rank 16 at q = 0 (stretched knees)
    "walking_machine_on_ground": (24, 18, 16, 1000),
    # 48 coordinates, 42 rows (six supports x (3 + 4)), 6 degrees of freedom, regular at q = 0
    "test_bench_constrained": (48, 42, 42, 500),
}
DOF = 6
STEP = 1e-3
RANK_TOL = 1e-9  # singular values below RANK_TOL * sigma_max count as zero


@pytest.fixture(scope="module", params=sorted(BOOK))
def book(request, tmp_path_factory):
    """(name, model, module with the model's stabilization, module with stabilization (0, 0))."""
    name = request.param
    model = aggsym.load(model_path(name))
    folder = tmp_path_factory.mktemp(name)
    _, stabilized, _ = generated_code(model, folder / "stabilized", c=False)
    _, plain, _ = generated_code(dataclasses.replace(model, stabilization=(0, 0)), folder / "plain", c=False)
    return name, model, stabilized, plain


def nominal(name, n):
    """A posture to start Newton from: the walking machine's knees bent (hip pitch 0.5, knee -1.0, the trunk
    lowered), the test bench at q = 0 (every support stretched, itself consistent)."""
    q = np.zeros(n)
    if name == "walking_machine_on_ground":
        q[2] = -0.1
        for leg in range(6):
            q[6 + 3 * leg + 1], q[6 + 3 * leg + 2] = 0.5, -1.0
    return q


def random_states(name, module, n, count=3, seed=11):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        q, qd = consistent_state(module, nominal(name, n) + rng.uniform(-0.3, 0.3, n), rng.normal(size=n),
                                 steps=60, tolerance=1e-14)  # (least-squares steps: J has more columns than rows)
        assert np.abs(module.constraint_residual(q)).max() < 1e-13
        out.append((q, qd))
    return out


def singular_values(J):
    s = np.linalg.svd(J, compute_uv=False)
    return s, int((s > RANK_TOL * s[0]).sum())


def test_counts_rank_and_degrees_of_freedom(book):
    """Section 1.2.1 and the examples: n, m and n - rank J = 6 at random consistent states; at q = 0 the
    walking machine's stretched knees drop the rank to 16, the test bench is regular.  The gap in the singular
    values (sigma_min / sigma_max above 1e-4 where regular, below 1e-12 where not) makes the rank unambiguous."""
    name, model, module, _ = book
    n, m, default_rank, _ = BOOK[name]
    assert (model.nq, model.constraint_rows, module.NQ) == (n, m, n)
    zero = np.zeros(n)
    assert np.abs(module.constraint_residual(zero)).max() < 1e-15  # q = 0 is consistent (default attachments)
    s, rank = singular_values(module.constraint_jacobian(zero))
    assert rank == default_rank, (name, rank)
    if default_rank < m:
        assert s[default_rank - 1] > 1e-3 * s[0] and s[default_rank] < 1e-12 * s[0]
    for q, qd in random_states(name, module, n):
        J = module.constraint_jacobian(q)
        s, rank = singular_values(J)
        assert rank == m and n - rank == DOF and s[-1] > 1e-4 * s[0], (name, rank, s[-1] / s[0])
        assert np.abs(J @ qd).max() < 1e-12 * np.abs(J).max() * np.abs(qd).max()
    if name == "test_bench_constrained":
        # the supports' 42 x 42 block is regular: the six free motions are the platform's (a bench that imitates
        # free motion), each support's seven coordinates follow from it
        assert np.linalg.matrix_rank(J[:, 6:], tol=RANK_TOL * np.abs(J).max()) == m


def test_equations_of_motion_at_consistent_states(book):
    """(4.25)-(4.28) without stabilization: A qdd + b + g - tau - J^T lambda and J qdd + gamma to 1e-12 of their
    terms (the largest term; for J qdd the largest entry of |J| |qdd|); and the reactions matter: without
    J^T lambda the first residual is of the order of its terms."""
    name, model, _, plain = book
    n = model.nq
    rng = np.random.default_rng(5)
    for q, qd in random_states(name, plain, n, seed=23):
        tau = rng.normal(size=n)
        qdd, lam = plain.constrained_forward_dynamics(q, qd, tau)
        A, d, J = plain.inertia(q), plain.nonlinear_effects(q, qd), plain.constraint_jacobian(q)
        gamma = plain.constraint_bias(q, qd)
        terms = [A @ qdd, d, tau, J.T @ lam]
        scale = max(np.abs(t).max() for t in terms)
        dynamics = np.abs(A @ qdd + d - tau - J.T @ lam).max() / scale
        # J qdd is a sum of products: its rounding is relative to |J| |qdd|, which here exceeds |J qdd| by up to
        # 100 (the supports' accelerations cancel at the closures); the solve through J A^-1 J^T (condition up to
        # 1e4 at these states) adds its own
        closure = np.abs(J @ qdd + gamma).max() / max((np.abs(J) @ np.abs(qdd)).max(), np.abs(gamma).max())
        assert dynamics < 1e-12 and closure < 1e-12, (name, dynamics, closure)
        assert np.abs(A @ qdd + d - tau).max() / scale > 1e-3  # the counterpart: J^T lambda is not negligible


def model_rows(model):
    """The row labels 'constraint.code' in J's order."""
    return [f"{c.name}.{code}" for c in model.constraints for code in c.rows]


def rotation(axis, angle):
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def last_link_orientation(q, i):
    """Our own forward kinematics of the test bench's printed pairs (section 1.2.1): the orientation of support
    i's last link i13 in world axes, c1(t4) c2(t5) c3(t6) (the platform) c1(q_i7) c3(q_i8) c1(q_i9) c2(q_i10)
    c3(q_i11) c3(q_i12) (the slider i13 does not turn)."""
    R = rotation(0, q[3]) @ rotation(1, q[4]) @ rotation(2, q[5])
    k = 6 + 7 * i
    for axis, angle in zip((0, 2, 0, 1, 2, 2), q[k:k + 6]):
        R = R @ rotation(axis, angle)
    return R


def test_jacobian_against_the_rate_of_phi(book):
    """J qd against phi along a random (not projected) qd at consistent states, by central differences (h =
    1e-6), to 1e-7 of |J qd|: the translational rows directly; the test bench's cylinder rows (theta4, theta5 of
    c1(psi4)-turned axes) against the angular velocity of our own kinematics, and phi's rate against the log map's
    derivative at the turn alpha of the last link about the cylinder's axis.  The counterpart: the naive identity
    rate = J qd for those rows misses by about alpha / 2."""
    name, model, module, _ = book
    n = model.nq
    rows = model_rows(model)
    h = 1e-6
    rng = np.random.default_rng(17)
    turned = 0.0
    for q, _ in random_states(name, module, n, seed=29):
        qd = rng.normal(size=n)
        J = module.constraint_jacobian(q)
        Jqd = J @ qd
        rate = (module.constraint_residual(q + h * qd) - module.constraint_residual(q - h * qd)) / (2 * h)
        tol = 1e-7 * np.abs(Jqd).max()
        translational = [r for r, label in enumerate(rows) if label.split(".")[1].startswith("o")]
        assert np.abs(rate - Jqd)[translational].max() < tol, name
        if name != "test_bench_constrained":
            assert len(translational) == len(rows)
            continue
        psi4 = float(module.PARAMETERS[module.PARAMETER_NAMES.index("psi4")])
        R_ref = rotation(0, psi4)
        for i in range(6):
            r4 = rows.index(f"end{i + 1}.theta4")
            R = last_link_orientation(q, i)
            Rdot = (last_link_orientation(q + h * qd, i) - last_link_orientation(q - h * qd, i)) / (2 * h)
            W = Rdot @ R.T  # [omega] in world axes
            omega = R_ref.T @ np.array([W[2, 1], W[0, 2], W[1, 0]])
            assert np.abs(Jqd[r4:r4 + 2] - omega[:2]).max() < tol, (i, Jqd[r4:r4 + 2], omega[:2])
            Q = R_ref.T @ R @ R_ref  # relative to q = 0, where every orientation is the identity
            alpha = np.arctan2(Q[1, 0], Q[0, 0])
            assert np.abs(Q - rotation(2, alpha)).max() < 1e-12  # consistent: a turn about the axis e3 only
            w1, w2 = Jqd[r4:r4 + 2]
            half = alpha / 2
            expected = half * np.array([w1 / np.tan(half) + w2, w2 / np.tan(half) - w1]) if alpha else Jqd[r4:r4 + 2]
            assert np.abs(rate[r4:r4 + 2] - expected).max() < tol, (i, alpha)
            if abs(alpha) > 0.05:
                assert np.abs(rate[r4:r4 + 2] - Jqd[r4:r4 + 2]).max() > 100 * tol  # the counterpart
            turned = max(turned, abs(alpha))
    if name == "test_bench_constrained":
        assert turned > 0.05  # the log map's correction was exercised


def test_rk4_drift_and_energy(book):
    """RK4 (step 1e-3) from a consistent state, the joints held by springs about it: tau = tau0 - k (q - q0),
    tau0 = g(q0) - J^T lambda0 the generalized forces that hold q0 at rest (the least-squares lambda0), k = 100.
    Left to gravity alone (tau = 0) both machines collapse within 0.3 s through near-singular configurations
    (joint rates of 30 rad/s), which measures the step, not the equations.  The springs' forces are
    conservative, with the energy E = T + U - tau0 q + k |q - q0|^2 / 2.  With the model's Baumgarte terms the
    drift max |phi| stays below 1e-8; without them E stays within 1e-8 of T(0).  The counterpart: the
    unconstrained tree's forward dynamics leaves the constraints within 50 steps."""
    name, model, stabilized, plain = book
    n = model.nq
    steps = BOOK[name][3]
    (q0, qd0), = random_states(name, stabilized, n, count=1, seed=41)
    J = plain.constraint_jacobian(q0)
    g = plain.gravity(q0)
    tau0 = g - J.T @ np.linalg.lstsq(J.T, g, rcond=None)[0]
    assert np.abs(plain.constrained_forward_dynamics(q0, np.zeros(n), tau0)[0]).max() < 1e-10  # at rest
    k = 100.0

    def tau(q):
        return tau0 - k * (q - q0)

    def energy(q, qd):
        return float(plain.kinetic_energy(q, qd) + plain.potential_energy(q) - tau0 @ q + k / 2 * (q - q0) @ (q - q0))

    T0 = float(plain.kinetic_energy(q0, qd0))
    results = {}
    for label, module in (("stabilized", stabilized), ("plain", plain)):
        q, qd = q0.copy(), qd0.copy()
        E0, drift, worst = energy(q, qd), 0.0, 0.0
        for _ in range(steps):
            q, qd = rk4_step(lambda a, b: module.constrained_forward_dynamics(a, b, tau(a))[0], q, qd, STEP)
            drift = max(drift, np.abs(module.constraint_residual(q)).max())
            worst = max(worst, abs(energy(q, qd) - E0))
        results[label] = (drift, worst / T0)
    assert results["stabilized"][0] < 1e-8, (name, results)
    assert results["plain"][1] < 1e-8, (name, results)
    q, qd = q0.copy(), qd0.copy()
    for _ in range(50):
        q, qd = rk4_step(lambda a, b: plain.forward_dynamics(a, b, tau(a)), q, qd, STEP)
    assert np.abs(plain.constraint_residual(q)).max() > 1e-4  # the counterpart: without the reactions it opens
