"""Closed chains (chapter 4, Prop. 4.9: the medium of a constraint is a body of the tree) against Pinocchio.

* A two-finger gripper holding a box between its fingertips (tests/data/gripper_box.yaml, a YAML model): the
  same tree built through Pinocchio's API (:func:`helpers.pinocchio_tree`), the two pad contacts as CONTACT_3D
  RigidConstraintModels between finger and box, solved by ``constraintDynamics``: qdd and lambda of our twin, C
  and NumPy module at random states.
* Random branching URDF trees (tests/random_trees.py) with random loop closures (point or weld, between two
  links or a link and the world, at random points, with random reference rotations): J, gamma, phi against the
  Pinocchio-only reference of tests/constraint_reference.py and qdd, lambda against ``constraintDynamics``.
* The delta robot (models/delta_robot.yaml): its rows ([theta4, theta6] of the parallelogram) have no Pinocchio
  constraint type, so the reference is the dense KKT solve from Pinocchio's crba, nonLinearEffects, frame
  Jacobians and classical accelerations; the mechanism's own facts: q = 0 is closed, rank J = 8 (three degrees of
  freedom), the travelling plate never turns, and the stabilized motion stays closed.
Tolerances: 1e-9 relative (the issue's), measured errors are 1e-13 to 1e-11.
"""
from __future__ import annotations

import numpy as np
import pytest

import aggsym
import constraint_reference as cr
from aggsym.model.readers.side_files import load_constraints
from aggsym.twin import NumericTwin
from conftest import model_path
from constraint_reference import Constraint
from helpers import consistent_state, generated_code, relative_error, rk4_step
from pinocchio_reference import pin, pinocchio_q, pinocchio_tree
from random_trees import random_urdf

pytestmark = pytest.mark.pinocchio

DATA = model_path("four_bar").parent.parent / "tests" / "data"
TOLERANCE = 1e-9


def plain(model):
    """The model without its Baumgarte terms (Pinocchio's differ from ours)."""
    import dataclasses
    return dataclasses.replace(model, stabilization=(0, 0))


def reference_constraints(model, pm, q0):
    """Our model's constraints as reference Constraints on the Pinocchio frames of helpers.pinocchio_tree (frames
    named by body), attached where the model attaches them (``at``, or the point's place at q0)."""
    out = []
    values = dict(zip(model.parameter_symbols, model.parameter_values))
    for c in model.constraints:
        point = [float(x.subs(values)) for x in c.point]
        at = None if c.at is None else [float(x.subs(values)) for x in c.at]
        rows = ["o1", "o2", "o3", "theta4", "theta5", "theta6"]
        ref = Constraint(c.body, point, [rows.index(r) for r in c.rows],
                         medium=None if c.medium == "world" else c.medium, at=at)
        out.append(cr.default_at(pm, q0, ref))
    return out


# --------------------------------------------------------------------------------------------------------------
# the gripper holding a box


@pytest.mark.compiler
def test_gripper_holding_a_box_equals_pinocchio(tmp_path):
    model = plain(aggsym.load(DATA / "gripper_box.yaml"))
    assert (model.nq, model.constraint_rows) == (10, 6)
    pm, _ = pinocchio_tree(model)
    cs = reference_constraints(model, pm, np.zeros(model.nq))
    twin = NumericTwin(model)
    lib, module, manifest = generated_code(model, tmp_path, opt="-O2")
    assert [c["name"] for c in manifest["constraints"]["constraints"]] == ["grip_left", "grip_right"]
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(4):
        q, v, tau = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        J = cr.jacobian(pm, q, cs)
        assert np.linalg.matrix_rank(J) == 6
        assert relative_error(twin.constraint_jacobian(q), J) < TOLERANCE
        assert relative_error(twin.constraint_bias(q, v), cr.bias(pm, q, v, cs), floor=1e-9) < TOLERANCE
        assert relative_error(twin.constraint_residual(q), cr.residual(pm, q, cs), floor=1e-9) < TOLERANCE
        qdd, lam = cr.pinocchio_constraint_dynamics(pm, q, v, tau, cs)
        for got_qdd, got_lam in (twin.constrained_forward_dynamics(q, v, tau),
                                 lib.call("constrained_forward_dynamics", q, v, tau),
                                 module.constrained_forward_dynamics(q, v, tau)):
            worst = max(worst, relative_error(got_qdd, qdd), relative_error(got_lam, lam))
    assert worst < TOLERANCE, worst


def test_the_gripper_reference_sees_a_wrong_contact(tmp_path):
    """The comparison can fail: the right pad moved by 1 mm in Pinocchio's constraint only."""
    model = plain(aggsym.load(DATA / "gripper_box.yaml"))
    pm, _ = pinocchio_tree(model)
    cs = reference_constraints(model, pm, np.zeros(model.nq))
    import dataclasses
    cs[1] = dataclasses.replace(cs[1], point=cs[1].point + [0.0, 0.0, 1e-3])
    rng = np.random.default_rng(12)
    q, v, tau = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
    qdd, _ = cr.pinocchio_constraint_dynamics(pm, q, v, tau, cs)
    assert relative_error(NumericTwin(model).constrained_forward_dynamics(q, v, tau)[0], qdd) > 1e-4


# --------------------------------------------------------------------------------------------------------------
# random trees with random loop closures

AXES = {"z": 3, "y": 2, "x": 1}


def _rotation(angles):
    """R = c3(a) c2(b) c1(c): the product of a YAML rotation [[z, a], [y, b], [x, c]] in order."""
    a, b, c = angles
    return pin.utils.rotate("z", a) @ pin.utils.rotate("y", b) @ pin.utils.rotate("x", c)


def random_closures(pm, q_samples, rng, kinds):
    """Random constraints of the given ``kinds`` ("point" or "weld") between links of a Pinocchio model (the
    second of a pair may be the world), at random points and reference rotations, chosen so that J keeps full row
    rank at every sample (a weld across too few joints would be redundant, which aggsym refuses: tested
    elsewhere).  Returns [(Constraint, rotation angles)]."""
    links = [f.name for f in pm.frames if f.type == pin.FrameType.BODY and f.parentJoint > 0]
    chosen = []
    for _ in range(500):
        if len(chosen) == len(kinds):
            break
        body = links[rng.integers(len(links))]
        medium = None if rng.random() < 0.3 else links[rng.integers(len(links))]
        if medium is not None and pm.frames[pm.getFrameId(medium, pin.FrameType.BODY)].parentJoint == \
                pm.frames[pm.getFrameId(body, pin.FrameType.BODY)].parentJoint:
            continue
        angles = tuple(float(x) for x in rng.uniform(-np.pi, np.pi, 3))
        rows = (0, 1, 2) if kinds[len(chosen)] == "point" else tuple(range(6))
        c = Constraint(body, rng.uniform(-0.2, 0.2, 3), rows, rotation=_rotation(angles), medium=medium)
        trial = chosen + [(cr.default_at(pm, pin.neutral(pm), c), angles)]
        cs = [t for t, _ in trial]
        if all(np.linalg.matrix_rank(cr.jacobian(pm, q, cs), tol=1e-8) == sum(len(t.rows) for t in cs)
               for q in q_samples):
            chosen = trial
    assert len(chosen) == len(kinds), "no full-rank closures found"
    return chosen


def side_file(path, closures):
    lines = ["constraints:"]
    for i, (c, angles) in enumerate(closures):
        point = ", ".join(repr(float(x)) for x in c.point)
        rotation = ", ".join(f"[{axis}, {angle!r}]" for axis, angle in zip("zyx", angles))
        lines.append(f"  - name: loop{i}")
        lines.append(f"    body: {c.frame!r}")
        lines.append(f"    medium: {c.medium!r}" if c.medium else "    medium: world")
        lines.append(f"    point: [{point}]")
        lines.append(f"    rotation: [{rotation}]")
        lines.append(f"    block: {'point' if len(c.rows) == 3 else 'weld'}")
    path.write_text("\n".join(lines) + "\n")
    return path


CLOSURES = {6: ("point", "point"), 10: ("weld", "point"), 37: ("point", "weld"), 46: ("weld",)}


@pytest.mark.parametrize("seed", sorted(CLOSURES))  # trees with A(q) regular (massless leaves in others)
def test_random_trees_with_random_loop_closures_equal_pinocchio(seed, tmp_path):
    urdf = tmp_path / "tree.urdf"
    urdf.write_text(random_urdf(seed, links=12))
    pm = pin.buildModelFromUrdf(str(urdf))
    rng = np.random.default_rng(seed)
    model = aggsym.load(urdf)
    assert model.nq == pm.nv
    samples = [pinocchio_q(pm, rng.uniform(-1, 1, pm.nv)) for _ in range(3)]
    closures = random_closures(pm, samples, rng, CLOSURES[seed])
    cs = [c for c, _ in closures]
    model = load_constraints(side_file(tmp_path / "loops.yaml", closures), model)
    assert model.constraint_rows == sum(len(c.rows) for c in cs)
    twin = NumericTwin(model)
    worst = {}
    for _ in range(3):
        q, v, tau = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        Q = pinocchio_q(pm, q)
        checks = {"J": (twin.constraint_jacobian(q), cr.jacobian(pm, Q, cs), 1e-300),
                  "gamma": (twin.constraint_bias(q, v), cr.bias(pm, Q, v, cs), 1e-9),
                  "phi": (twin.constraint_residual(q), cr.residual(pm, Q, cs), 1e-9)}
        qdd, lam = cr.pinocchio_constraint_dynamics(pm, Q, v, tau, cs)
        ours_qdd, ours_lam = twin.constrained_forward_dynamics(q, v, tau)
        checks.update(qdd=(ours_qdd, qdd, 1e-300), lam=(ours_lam, lam, 1e-300))
        for name, (ours, theirs, floor) in checks.items():
            worst[name] = max(worst.get(name, 0.0), relative_error(ours, theirs, floor=floor))
    assert max(worst.values()) < TOLERANCE, worst


# --------------------------------------------------------------------------------------------------------------
# the delta robot


@pytest.fixture(scope="module")
def delta():
    model = aggsym.load(model_path("delta_robot"))
    pm, _ = pinocchio_tree(model)
    return model, pm, reference_constraints(model, pm, np.zeros(model.nq))


def closed_state(twin, q, qd):
    """Newton on phi(q) = 0 from q (to 1e-14), then qd projected on the null space of J."""
    q, qd = consistent_state(twin, q, qd, tolerance=1e-14)
    assert np.abs(twin.constraint_residual(q)).max() < 1e-13
    return q, qd


def test_delta_robot_is_closed_at_zero_with_three_degrees_of_freedom_and_a_plate_that_never_turns(delta):
    model, pm, cs = delta
    twin = NumericTwin(model)
    assert (model.nq, model.constraint_rows) == (11, 8)
    assert np.abs(twin.constraint_residual(np.zeros(model.nq))).max() < 1e-15
    assert np.abs(cr.residual(pm, np.zeros(model.nq), cs)).max() < 1e-15
    rng = np.random.default_rng(4)
    plate = pm.getFrameId("plate")
    motors = [[c.name for c in model.coordinates].index(n) for n in ("q1", "q2", "q3")]
    for _ in range(4):
        q, qd = closed_state(twin, 0.15 * rng.normal(size=model.nq), rng.normal(size=model.nq))
        J = twin.constraint_jacobian(q)
        s = np.linalg.svd(J, compute_uv=False)
        assert s[-1] > 1e-3 * s[0]  # rank 8
        N = np.linalg.svd(J)[2][8:].T  # the 3 velocities the loops allow
        assert np.linalg.matrix_rank(N[motors], tol=1e-8) == 3  # set by the three motor rates
        data = pm.createData()
        pin.framesForwardKinematics(pm, data, q)
        assert np.abs(data.oMf[plate].rotation - np.eye(3)).max() < 1e-12


@pytest.mark.compiler
def test_delta_robot_dynamics_equal_the_pinocchio_kkt(delta, tmp_path):
    model, pm, cs = delta
    model = plain(model)
    twin = NumericTwin(model)
    lib, module, _ = generated_code(model, tmp_path, opt="-O2")
    rng = np.random.default_rng(5)
    worst = 0.0
    for _ in range(4):
        q, v, tau = 0.3 * rng.normal(size=model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)
        assert relative_error(twin.constraint_jacobian(q), cr.jacobian(pm, q, cs)) < TOLERANCE
        assert relative_error(twin.constraint_bias(q, v), cr.bias(pm, q, v, cs), floor=1e-9) < TOLERANCE
        qdd, lam = cr.kkt_forward_dynamics(pm, q, v, tau, cs)
        for got_qdd, got_lam in (twin.constrained_forward_dynamics(q, v, tau),
                                 lib.call("constrained_forward_dynamics", q, v, tau),
                                 module.constrained_forward_dynamics(q, v, tau)):
            worst = max(worst, relative_error(got_qdd, qdd), relative_error(got_lam, lam))
    assert worst < TOLERANCE, worst


def test_delta_robot_stays_closed_over_a_second(delta, tmp_path):
    """RK4, step 1e-3 s, 1 s, from a closed state with random consistent velocities, the motors holding their
    start angles by a PD law (tau = -20 (q - q0) - 2 qd on q1..q3): the model's Baumgarte terms keep |phi| <= 1e-8
    (measured 2.2e-11); without them the drift is far larger (8e-10; the check can fail).  Unpowered, the delta
    falls through its workspace at up to 9 rad/s and RK4's own error at this step leaves phi at 1.6e-7 even with
    the stabilization (4e-8 with kp = 2500, kd = 100): a smaller step is the remedy there, not the gains."""
    model, _, _ = delta
    twin = NumericTwin(model)
    q0, v0 = closed_state(twin, 0.1 * np.random.default_rng(6).normal(size=model.nq),
                          np.random.default_rng(7).normal(size=model.nq))
    motors = [[c.name for c in model.coordinates].index(n) for n in ("q1", "q2", "q3")]
    drift = {}
    for label, m in (("stabilized", model), ("plain", plain(model))):
        _, module, _ = generated_code(m, tmp_path / label, c=False)

        def acceleration(q, v):
            tau = np.zeros(model.nq)
            tau[motors] = -20 * (q[motors] - q0[motors]) - 2 * v[motors]
            return module.constrained_forward_dynamics(q, v, tau)[0]

        q, v, worst = q0, v0, 0.0
        for _ in range(1000):
            q, v = rk4_step(acceleration, q, v, 1e-3)
            worst = max(worst, float(np.abs(module.constraint_residual(q)).max()))
        drift[label] = worst
    assert drift["stabilized"] <= 1e-8, drift
    assert drift["plain"] > 10 * drift["stabilized"], drift
