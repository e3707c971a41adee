"""dtau/d(q, qd) from the composites of the tree (issue 52, :mod:`aggsym.mechanics.spatial_derivatives`): against
Pinocchio's computeRNEADerivatives (random trees with arbitrary axes and masses over six decades, fixed and with a
quaternion free-flyer), against the dual-number sweep (an independent path: tangents of every intermediate) and
central differences (a ball pair, springs and dampers), and the straight-line program's choice between the two forms
by their operation counts."""
from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import aggsym
from aggsym.codegen.generate import internal_model
from aggsym.core.backend import Numeric, Symbolic
from aggsym.errors import ModelWarning
from aggsym.mechanics import derivatives, spatial_derivatives
from aggsym.mechanics.aggregates import Rigid
from aggsym.mechanics.bound import bind, scratch_operations
from aggsym.mechanics.group import phi_force, phi_motion
from aggsym.mechanics.kinematics import TreeKinematics
from aggsym.model.tree import Tree
from conftest import model_path
from helpers import BALL_BETWEEN_HINGES, relative_error, robot_path
from pinocchio_reference import pin
from random_trees import random_urdf

TOLERANCE = 1e-9


def six_decades(text: str, rng) -> str:
    """The URDF with every link's mass and inertia scaled by its own 10^k, k uniform in [-3, 3]."""
    def scaled(match):
        s = 10.0 ** rng.uniform(-3, 3)
        inertial = re.sub(r'(value|ixx|ixy|ixz|iyy|iyz|izz)="([^"]+)"',
                          lambda m: f'{m.group(1)}="{float(m.group(2)) * s!r}"', match.group(0))
        return inertial
    return re.sub(r"<inertial>.*?</inertial>", scaled, text, flags=re.S)


def state(model, rng):
    """q with its angles written with 5 digits (a unit quaternion where there is a free pair), qd, qdd."""
    q = np.round(rng.uniform(-2, 2, model.nq), 5)
    tree = Tree.of(model)
    for body, idx in zip(model.bodies, tree.positions):
        if body.pair.quaternion:
            x = rng.normal(size=4)
            q[list(idx[-4:])] = x / np.linalg.norm(x)
    return q, rng.normal(size=model.nv), rng.normal(size=model.nv)


def both_forms(model, q, qd, qdd):
    bound = bind(model, Numeric())
    kin = TreeKinematics(bound, list(q))
    return [[np.array(m, float) for m in derivatives.inverse_dynamics_derivatives(bound, kin, list(qd), list(qdd),
                                                                                    form=form)]
            for form in ("spatial", "dual")]


def pinocchio_ff_q(pm, q):
    """Pinocchio's q for ours with a quaternion free-flyer first: its seven entries as they are, then the joints."""
    out = np.zeros(pm.nq)
    out[:7] = q[:7]
    for j in range(2, pm.njoints):
        joint = pm.joints[j]
        v = q[joint.idx_v + 1: joint.idx_v + 1 + joint.nv]
        if joint.nq == joint.nv:
            out[joint.idx_q: joint.idx_q + joint.nq] = v
        else:  # unbounded revolute: (cos, sin)
            out[joint.idx_q: joint.idx_q + 2] = (np.cos(v[0]), np.sin(v[0]))
    return out


@pytest.mark.pinocchio
@pytest.mark.parametrize("seed,base", [(3, None), (8, None), (21, None), (5, "quaternion"), (10, "quaternion"),
                                       (29, "quaternion")])
def test_random_trees_equal_pinocchio_and_the_dual_sweep(seed, base, tmp_path):
    rng = np.random.default_rng(seed)
    path = tmp_path / "tree.urdf"
    path.write_text(six_decades(random_urdf(seed), rng))
    model = aggsym.load(path, floating_base=base)
    if base:
        pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
        convert = lambda q: pinocchio_ff_q(pm, q)  # noqa: E731
    else:
        from pinocchio_reference import pinocchio_q
        pm = pin.buildModelFromUrdf(str(path))
        convert = lambda q: pinocchio_q(pm, q)  # noqa: E731
    bound = bind(model, Numeric())
    assert spatial_derivatives.covers(bound)
    for _ in range(2):
        q, qd, qdd = state(model, rng)
        spatial, dual = both_forms(model, q, qd, qdd)
        data = pm.createData()
        want = [x.copy() for x in pin.computeRNEADerivatives(pm, data, convert(q), qd, qdd)[:2]]
        for got, other, ref in zip(spatial, dual, want):
            assert relative_error(got, ref, floor=1.0) < TOLERANCE
            assert relative_error(got, other, floor=1.0) < TOLERANCE


def _tangent_step(model, q, d):
    """q moved along the velocity direction d (a ball's quaternion by quat exp(d w), the rest by + d)."""
    out = np.array(q, float)
    tree = Tree.of(model)
    for body, idx, coords in zip(model.bodies, tree.positions, tree.coords):
        if not body.pair.quaternion:
            for p, i in zip(idx, coords):
                out[p] += d[i]
            continue
        w = np.array([d[i] for i in coords[-3:]])
        angle = np.linalg.norm(w)
        e = np.concatenate([np.sin(angle / 2) * w / angle, [np.cos(angle / 2)]]) if angle else np.array([0, 0, 0, 1.])
        x, y, z, s = q[list(idx[-4:])]
        a, b, c, t = e
        out[list(idx[-4:])] = (s * a + x * t + y * c - z * b, s * b - x * c + y * t + z * a,
                                     s * c + x * b - y * a + z * t, s * t - x * a - y * b - z * c)
    return out


@pytest.mark.parametrize("source", ["ball", "damped", "manipulator6", "cart_on_moving_platform"])
def test_spatial_form_equals_central_differences(source, tmp_path, rng):
    """A ball pair in the middle of q (masses over six decades), a random tree with joint damping and Coulomb
    friction (--passive include: their derivatives on dual numbers), the book's manipulator and a cart."""
    if source == "ball":
        path = tmp_path / "ball.yaml"
        path.write_text(BALL_BETWEEN_HINGES)
    elif source == "damped":
        path = tmp_path / "damped.urdf"
        text = re.sub(r"(  </joint>)", r'    <dynamics damping="0.37" friction="0.05"/>\n\1', random_urdf(21))
        path.write_text(text.replace('type="fixed">\n', 'type="fixed">\n<!-- -->\n'))
    else:
        path = model_path(source)
    model = aggsym.load(path, passive="include") if source == "damped" else aggsym.load(path)
    bound = bind(model, Numeric())
    assert spatial_derivatives.covers(bound)
    if source == "damped":
        assert bound.damping and bound.coulomb
    from aggsym.mechanics.passive import left_forces
    from aggsym.mechanics.sweeps import inverse_dynamics

    def tau(q, qd, qdd):
        kin = TreeKinematics(bound, list(q))
        return np.array([a + b for a, b in zip(inverse_dynamics(bound, kin, list(qd), list(qdd)),
                                                  left_forces(bound, list(q), list(qd)))], float)

    q, qd, qdd = state(model, rng)
    (dq, dqd), (eq, eqd) = both_forms(model, q, qd, qdd)
    n, h = model.nv, 1e-6
    for j in range(n):
        e = np.eye(n)[j] * h
        fq = (tau(_tangent_step(model, q, e), qd, qdd) - tau(_tangent_step(model, q, -e), qd, qdd)) / (2 * h)
        fv = (tau(q, qd + e, qdd) - tau(q, qd - e, qdd)) / (2 * h)
        assert relative_error(dq[:, j], fq, floor=1.0) < 1e-6
        assert relative_error(dqd[:, j], fv, floor=1.0) < 1e-6
    assert relative_error(dq, eq, floor=1.0) < TOLERANCE and relative_error(dqd, eqd, floor=1.0) < TOLERANCE


def test_covers_balls_but_not_added_masses_rotors_or_pairs_whose_axes_turn(tmp_path):
    """Not covered (the dual form is taken): added masses, a prescribed spin, and the elastic stand's pair of a
    rotation and a translation (T(o) C(c): the translation's axis is fixed in the parent, not in the body)."""
    (tmp_path / "ball.yaml").write_text(BALL_BETWEEN_HINGES)
    for path, covered in ((tmp_path / "ball.yaml", True), (model_path("manipulator6"), True),
                          (model_path("double_pendulum_elastic_stand"), False),
                          (model_path("added_mass_body_in_fluid"), False),
                          (model_path("gyroscope_spinning_rotor"), False)):
        bound = bind(aggsym.load(path), Numeric())
        assert spatial_derivatives.covers(bound) is covered, path
        kin = TreeKinematics(bound, [0.1] * bound.model.nq)
        assert derivatives.derivative_form(bound, kin) == ("spatial" if covered else "dual")


def test_the_inertia_rate_is_the_matrix_rate(rng):
    """inertia_rate(Theta, V) applied to any U equals V x* (Theta U) - Theta (V x U)."""
    for _ in range(5):
        R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        theta = R @ np.diag(rng.uniform(0.1, 2, 3)) @ R.T
        th = Rigid(rng.uniform(0.1, 5), tuple(rng.normal(size=3)), tuple(map(tuple, theta)))
        V, U = tuple(rng.normal(size=6)), tuple(rng.normal(size=6))
        want = np.subtract(phi_force(V, th.apply(U)), th.apply(phi_motion(V, U)))
        assert np.allclose(spatial_derivatives.inertia_rate(th, V).apply(U), want, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("name,chosen", [("panda", "spatial"), ("ur5", "dual")])
def test_the_program_takes_the_form_of_fewer_operations(name, chosen):
    """On the straight-line program the form is the one whose outputs reach fewer operations (Panda's general
    axes: the composites; UR5's parallel axes: the dual sweep, whose tangents fold)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = internal_model(aggsym.load(robot_path(name)))  # (the frames the routines are built in)
    back = Symbolic()
    bound = bind(model, back)
    kin = TreeKinematics(bound, back.program.vector("q", model.nq))
    n = model.nv

    def count(form):
        return scratch_operations(bound, kin, lambda b, k, u: [
            [x for row in m for x in row] for m in derivatives.inverse_dynamics_derivatives(
                b, k, u, b.backend.program.vector("qdd", n), by_direction=False, form=form)])

    counts = {form: count(form) for form in ("spatial", "dual")}
    assert derivatives.derivative_form(bound, kin) == chosen == min(counts, key=counts.get)
