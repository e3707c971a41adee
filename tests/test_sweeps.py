"""Inverse dynamics by the forward and backward sweeps (2.39)-(2.46): tau, the wrench in every pair, d(q, q').

References: the assembled equations A q'' + b + g, the world-frame Newton-Euler of tests/reference.py (which
knows nothing of aggsym's spatial algebra), and Pinocchio's rnea and data.f on models built programmatically.
"""
import dataclasses

import numpy as np
import pytest

import aggsym
from aggsym.mechanics.aggregates import Rigid
from aggsym.core.backend import Numeric, Symbolic
from aggsym.mechanics.bound import bind
from aggsym.core.program import ADD, MUL, NEG, SUB
from aggsym.mechanics.group import phi_force
from aggsym.mechanics.kinematics import TreeKinematics, generalized, world_frame_vectors
from aggsym.mechanics.linalg import cross
from aggsym.contract import ROUTINES, joint_wrench_layout, run
from aggsym.mechanics.sweeps import (
    body_wrench, d_vector, forward_sweep, gravity_base, gravity_wrenches, inverse_dynamics,
    keeps_origin, origin_sweep, pair_bodies, transmitted_wrenches,
)
from conftest import MODELS, ROOT, model_path
from helpers import inverse_dynamics_by_equations, states as random_states
from pinocchio_reference import pin, pinocchio_tree
from reference import NumericModel, newton_euler_full, pair_wrenches, rot

pytestmark = pytest.mark.pinocchio

DATA = ROOT / "tests" / "data"
ALL_MODELS = MODELS + [DATA / "branching_tree.yaml", DATA / "shared_origins.yaml"]
TRIALS = 4


@pytest.fixture(params=ALL_MODELS, ids=lambda p: p.stem)
def model(request):
    return aggsym.load(request.param)


def states(model, rng, n=TRIALS):
    return random_states(model, rng, n)


def close(a, b, rel):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape
    scale = max(1.0, np.abs(b).max())
    err = np.abs(a - b).max() / scale
    assert err <= rel, f"relative error {err:.3g} > {rel:g}"


# tau ----------------------------------------------------------------------------------------------------------

def test_routines_are_the_sweeps(model, rng):
    """The contract's inverse_dynamics is the sweep (same signature) plus the springs C q of elastic pairs (2.27);
    bias and gravity are its d(q, q') without gravity and at rest (2.44)-(2.46), (2.52), and agree with the O(n)
    recursion (2.36)-(2.37) and -S G."""
    from aggsym.mechanics.bias import bias_vector, gravity_vector

    routine = ROUTINES["inverse_dynamics"]
    assert routine.inputs == ("q", "qd", "qdd", "p")
    assert [o.name for o in routine.outputs] == ["tau"]
    twin = aggsym.NumericTwin(model)
    bound = bind(model, Numeric())
    for q, qd, qdd in states(model, rng, 2):
        kin = TreeKinematics(bound, list(q))
        sweep = inverse_dynamics(bound, kin, list(qd), list(qdd))
        assert np.array_equal(twin.inverse_dynamics(q, qd, qdd), np.array(sweep, dtype=float) + twin.elastic(q))
        close(twin.bias(q, qd), bias_vector(bound, kin, list(qd)), 1e-10)
        close(twin.gravity(q), gravity_vector(bound, kin), 1e-10)


def test_sweep_equals_assembled_equations(model, rng):
    """u* by the sweeps equals A q'' + b + g (2.38) (+ C q on elastic pairs (2.27)) on random states."""
    twin = aggsym.NumericTwin(model)
    bound = bind(model, Numeric())
    for q, qd, qdd in states(model, rng):
        kin = TreeKinematics(bound, list(q))
        expected = inverse_dynamics_by_equations(bound, kin, list(qd), list(qdd))
        close(twin.inverse_dynamics(q, qd, qdd), expected, 1e-10)
        close(twin.inertia(q) @ qdd + twin.bias(q, qd) + twin.gravity(q) + twin.elastic(q), expected, 1e-10)


def test_origin_sweep_is_the_forward_sweep(model, rng):
    """(w, w', a) of the origin form are (2.39), (2.40) with a = v' + w x v, including the gravity base."""
    bound = bind(model, Numeric())
    for q, qd, qdd in states(model, rng, 2):
        kin = TreeKinematics(bound, list(q))
        V, A = forward_sweep(kin, list(qd), list(qdd), gravity_base(bound))
        for k, mo in enumerate(origin_sweep(bound, kin, list(qd), list(qdd), gravity_base(bound)[:3])):
            close(mo.w, V[k][3:], 1e-12)
            close(mo.wd, A[k][3:], 1e-12)
            close(mo.a, np.add(A[k][:3], cross(V[k][3:], V[k][:3])), 1e-12)
            w = np.array(mo.w, dtype=float)
            close(mo.perp, [w[1] ** 2 + w[2] ** 2, w[2] ** 2 + w[0] ** 2, w[0] ** 2 + w[1] ** 2], 1e-12)


def test_body_equation_multiplied_out(model, rng):
    """body_wrench (Newton and Euler about the origin) equals Theta V' + Phi Theta V of (2.10)."""
    bound = bind(model, Numeric())
    q, qd, qdd = next(states(model, rng, 1))
    kin = TreeKinematics(bound, list(q))
    V, A = forward_sweep(kin, list(qd), list(qdd), gravity_base(bound))
    origins = origin_sweep(bound, kin, list(qd), list(qdd), gravity_base(bound)[:3])
    for k, body in enumerate(bound.bodies):
        if isinstance(body.mises, Rigid):  # a General aggregate (added masses) is used in the book's form itself
            th = body.mises
            close(body_wrench(th, origins[k]), np.add(th.apply(A[k]), phi_force(V[k], th.apply(V[k]))), 1e-12)


def test_lumped_projection_equals_plain_backward_sweep(model, rng):
    """u* with the bodies on shared origins lumped equals Psi^T Z of the plain recursion (2.42), with and without
    gravity and with arbitrary external wrenches H."""
    bound = bind(model, Numeric())
    for q, qd, qdd in states(model, rng, 2):
        kin = TreeKinematics(bound, list(q))
        H = [tuple(x) for x in rng.normal(size=(len(model.bodies), 6))]
        for gravity, h in ((True, None), (False, H)):
            plain = generalized(kin, transmitted_wrenches(bound, kin, list(qd), list(qdd), h, gravity))
            close(inverse_dynamics(bound, kin, list(qd), list(qdd), h, gravity), plain, 1e-12)


def test_symbolic_programs_evaluate_like_the_numeric_twin(model, rng):
    """The straight-line programs of inverse_dynamics and joint_wrenches (parameters as inputs) give the twin's
    numbers."""
    back = Symbolic()
    prog = back.program
    bound = bind(model, back)
    x = {k: prog.vector(k, model.nq) for k in ("q", "qd", "qdd")}
    twin = aggsym.NumericTwin(model)
    q, qd, qdd = next(states(model, rng, 1))
    values = {("p", i): v for i, v in enumerate(model.parameter_values)}
    values[("t", 0)] = 0.0  # the time of prescribed spins (the twin's default)
    for name, vec in (("q", q), ("qd", qd), ("qdd", qdd)):
        values.update({(name, i): float(v) for i, v in enumerate(vec)})
    for role in ("inverse_dynamics", "joint_wrenches"):
        (out,) = run(ROUTINES[role], bound, x)
        got = np.array(prog.evaluate(out, values, np), dtype=float)
        close(got, np.ravel(twin.call(role, q, qd, qdd)), 1e-12)


def op_count(model, role=None):
    back = Symbolic()
    prog = back.program
    bound = bind(model, back)
    x = {k: prog.vector(k, model.nq) for k in ("q", "qd", "qdd")}
    if role is None:
        out = inverse_dynamics_by_equations(bound, TreeKinematics(bound, x["q"]), x["qd"], x["qdd"])
    else:
        out = [v for o in run(ROUTINES[role], bound, x) for v in o]
    ops = [prog.ops[i][0] for i in prog.reachable(out)]
    return ops.count(MUL), ops.count(ADD) + ops.count(SUB) + ops.count(NEG)


def test_operation_count_of_the_six_link_arm():
    """manipulator6: at most half the book's sweep count (2.41) + (2.43), 648 at n = 6, and below Featherstone's
    RNEA (450 mul + 386 add); the old A q'' + b + g path is far above."""
    model = aggsym.load(model_path("manipulator6"))
    mul, add = op_count(model, "inverse_dynamics")
    assert mul + add <= 324 and mul < 450 and add < 386
    old_mul, old_add = op_count(model)
    assert old_mul + old_add > 2 * (mul + add)


def test_lumping_is_structural(rng):
    """Only pairs that move no origin are lumped: the arm's wrist and shoulder, not its elbow."""
    model = aggsym.load(model_path("manipulator6"))
    bound = bind(model, Numeric())
    kin = TreeKinematics(bound, list(rng.normal(size=model.nq)))
    assert [keeps_origin(kin, k) for k in range(6)] == [False, True, False, False, True, True]


# joint wrenches -----------------------------------------------------------------------------------------------

def test_joint_wrenches_equal_world_frame_newton_euler(model, rng):
    """Each row of W is the wrench into the child subtree by the independent Newton-Euler, in the child frame."""
    twin = aggsym.NumericTwin(model)
    nm = NumericModel(model)
    rows = pair_bodies(model)
    assert len(rows) == sum(1 for b in model.bodies if b.pair.coordinates)
    for q, qd, qdd in states(model, rng):
        W = twin.joint_wrenches(q, qd, qdd)
        assert W.shape == (len(rows), 6)
        close(W, pair_wrenches(nm, q, qd, qdd)[rows], 1e-10)


def test_tau_is_the_projection_of_the_joint_wrench(model, rng):
    """u* = F^T M^T Z (2.15): tau is W projected on each pair's mobility axes (child frame)."""
    twin = aggsym.NumericTwin(model)
    bound = bind(model, Numeric())
    for q, qd, qdd in states(model, rng, 2):
        kin = TreeKinematics(bound, list(q))
        W = twin.joint_wrenches(q, qd, qdd)
        tau = twin.inverse_dynamics(q, qd, qdd) - twin.elastic(q)  # an elastic pair's spring is in W too
        for row, k in zip(W, pair_bodies(model)):
            for i, col in zip(kin.tree.coords[k], kin.psi[k]):
                assert row @ np.array(col, dtype=float) == pytest.approx(tau[i], rel=1e-12, abs=1e-12)


def test_single_coordinate_pair_reaction_is_the_rest_of_the_wrench(rng):
    """For a one-coordinate pair the axis is a coordinate axis of the child frame: that component is tau."""
    model = aggsym.load(model_path("manipulator6"))
    twin = aggsym.NumericTwin(model)
    q, qd, qdd = rng.normal(size=(3, model.nq))
    W, tau = twin.joint_wrenches(q, qd, qdd), twin.inverse_dynamics(q, qd, qdd)
    for i, c in enumerate(model.coordinates):
        assert W[i, c.axis] == pytest.approx(tau[i], rel=1e-13)
        assert np.abs(np.delete(W[i], c.axis)).max() > 1e-3  # the reaction is not trivially zero


def test_joint_wrenches_in_the_link_frame(rng):
    """With link_rotation R set (x_body = R x_link) the row is R^T W; tau does not change."""
    model = aggsym.load(model_path("manipulator6"))
    angles = rng.uniform(-3, 3, size=(len(model.bodies), 3))
    R = [rot(1, a) @ rot(2, b) @ rot(3, c) for a, b, c in angles]
    turned = dataclasses.replace(model, bodies=tuple(
        dataclasses.replace(b, link_rotation=tuple(map(tuple, R[k]))) if k % 2 == 0 else b
        for k, b in enumerate(model.bodies)))
    t0, t1 = aggsym.NumericTwin(model), aggsym.NumericTwin(turned)
    q, qd, qdd = rng.normal(size=(3, model.nq))
    W0, W1 = t0.joint_wrenches(q, qd, qdd), t1.joint_wrenches(q, qd, qdd)
    for k in range(len(model.bodies)):
        Rk = R[k] if k % 2 == 0 else np.eye(3)
        close(W1[k], np.concatenate([Rk.T @ W0[k, :3], Rk.T @ W0[k, 3:]]), 1e-13)
    close(t1.inverse_dynamics(q, qd, qdd), t0.inverse_dynamics(q, qd, qdd), 1e-14)
    assert [r["frame"] for r in joint_wrench_layout(turned)["W"]["rows"]] == ["link", "body"] * 3


def test_joint_wrench_layout(model):
    layout = joint_wrench_layout(model)["W"]
    assert ROUTINES["joint_wrenches"].layout is joint_wrench_layout
    assert layout["shape"] == [len(pair_bodies(model)), 6]
    assert layout["columns"] == ["fx", "fy", "fz", "mx", "my", "mz"]
    names = [name for row in layout["rows"] for name in row["coordinates"]]
    assert names == [c.name for c in model.coordinates]
    for row in layout["rows"]:
        body = model.body(row["body"])
        assert body.pair.name == row["joint"] and body.pair.coordinates


# d(q, q') ------------------------------------------------------------------------------------------------------

def parastrophic_matrix(kin):
    """S (1.42) as an n x 6N NumPy array."""
    rows = kin.parastrophic()
    return np.array([[x for block in row for x in (block if block is not None else (0.0,) * 6)] for row in rows],
                    dtype=float)


def test_d_by_the_sweep_with_zero_acceleration(model, rng):
    """(2.45): A q'' + d(q, q') = u + n, d by the sweep with q'' = 0 (2.44), (2.46)."""
    twin = aggsym.NumericTwin(model)
    bound = bind(model, Numeric())
    for q, qd, qdd in states(model, rng):
        kin = TreeKinematics(bound, list(q))
        d = np.array(d_vector(bound, kin, list(qd)), dtype=float)
        close(twin.inertia(q) @ qdd + d + twin.elastic(q), twin.inverse_dynamics(q, qd, qdd), 1e-10)
        close(d, twin.bias(q, qd) + twin.gravity(q), 1e-10)


def test_d_equals_b_minus_s_times_external_wrenches(model, rng):
    """(2.52): d = b - S (H + T), with H the gravity wrenches G_lk (2.9) and an arbitrary wrench on every body."""
    twin = aggsym.NumericTwin(model)
    bound = bind(model, Numeric())
    for q, qd, _ in states(model, rng):
        kin = TreeKinematics(bound, list(q))
        S = parastrophic_matrix(kin)
        G = gravity_wrenches(bound, kin)
        extra = [tuple(x) for x in rng.normal(size=(len(model.bodies), 6))]
        H = [tuple(np.add(g, e)) for g, e in zip(G, extra)]
        d = np.array(d_vector(bound, kin, list(qd), H=H, gravity=False), dtype=float)
        close(d, twin.bias(q, qd) - S @ np.concatenate(H), 1e-10)
        # gravity as the base acceleration (-g, 0) is the gravity wrench in H
        d_base = np.array(d_vector(bound, kin, list(qd), H=extra), dtype=float)
        close(d_base, d, 1e-10)


def test_gravity_wrench_is_weight_at_the_centre_of_mass(rng):
    """G_lk = Theta (g_lk, 0) is m g_lk at the centre of mass: (m g, m r_c x g) in the body frame."""
    model = aggsym.load(DATA / "branching_tree.yaml")
    bound = bind(model, Numeric())
    kin = TreeKinematics(bound, list(rng.normal(size=model.nq)))
    g = world_frame_vectors(kin, bound.gravity)
    for k, (G, body) in enumerate(zip(gravity_wrenches(bound, kin), model.bodies)):
        m = float(body.inertial.mass.subs(dict(zip(model.parameter_symbols, model.parameter_values))))
        r = np.array([float(x) for x in body.inertial.com])
        gk = np.array(g[k], dtype=float)
        close(G, np.concatenate([m * gk, np.cross(r, m * gk)]), 1e-14)


# Pinocchio -----------------------------------------------------------------------------------------------------

PINOCCHIO_MODELS = [model_path(n) for n in (
    "manipulator6", "planar_3link", "gyroscope", "test_bench", "double_pendulum", "double_pendulum_variant2",
    "walking_machine", "spacecraft")] + [DATA / "branching_tree.yaml", DATA / "shared_origins.yaml"]


@pytest.mark.parametrize("path", PINOCCHIO_MODELS, ids=lambda p: p.stem)
def test_against_pinocchio_rnea_and_joint_forces(path, rng):
    """rnea equals our inverse_dynamics and data.f (joint frame, linear first) equals our joint_wrenches."""
    model = aggsym.load(path)
    twin = aggsym.NumericTwin(model)
    nm = NumericModel(model)
    pm, joint_of = pinocchio_tree(model)
    data = pm.createData()
    for q, qd, qdd in states(model, rng, 3):
        tau = pin.rnea(pm, data, q, qd, qdd)
        close(twin.inverse_dynamics(q, qd, qdd), tau, 1e-9)
        ours = twin.joint_wrenches(q, qd, qdd)
        theirs = np.array([np.concatenate([data.f[joint_of[k]].linear, data.f[joint_of[k]].angular])
                           for k in pair_bodies(model)])
        close(ours, theirs, 1e-9)
        # the frames coincide: Pinocchio's joint placement in the world equals the pose of our body frame
        pin.forwardKinematics(pm, data, q)
        ref = newton_euler_full(nm, q, qd, qdd)
        for k in pair_bodies(model):
            close(data.oMi[joint_of[k]].rotation, ref["R"][k], 1e-12)
            close(data.oMi[joint_of[k]].translation, ref["P"][k], 1e-12)


def test_pinocchio_frames_sanity():
    """A check of the comparison itself: a wrong placement (rotation dropped) must show in data.f."""
    model = aggsym.load(model_path("gyroscope"))
    pm, joint_of = pinocchio_tree(model)
    pm.jointPlacements[1] = pin.SE3(np.eye(3), pm.jointPlacements[1].translation)
    data = pm.createData()
    q = np.array([0.3, -0.4, 0.5])
    qd, qdd = np.array([0.2, 0.1, 3.0]), np.array([0.5, -0.2, 1.0])
    pin.rnea(pm, data, q, qd, qdd)
    ours = aggsym.NumericTwin(model).joint_wrenches(q, qd, qdd)
    assert np.abs(ours[0] - np.concatenate([data.f[1].linear, data.f[1].angular])).max() > 1e-3
