"""Impacts and the derivatives of constrained dynamics (issue 34, items 1-3) against Pinocchio 4.1:
``impulseDynamics``, ``computeImpulseDynamicsDerivatives``, ``constraintDynamics`` with
``computeConstraintDynamicsDerivatives``, one ``RigidConstraintModel`` per constraint (CONTACT_3D for a point,
CONTACT_6D for a weld, LOCAL_WORLD_ALIGNED: its rows are ours for a contact with the world).

Robots: solo12 (quadruped) on a quaternion free-flyer standing on four point feet, with two feet welded (6D), and
on one welded foot, one point foot and a point off a third foot (its C, looped);
Talos (humanoid, slow) on its two welded soles; Panda (fixed base) welded at its hand; a closed loop (a three-link
spatial chain whose tip is pinned to a cart on a rail: the loop's medium translates only, so Pinocchio's
constraint rows and drift are ours at every state); the damped solve on Panda welded at the hand plus a point
of the hand (rank-deficient J) against Pinocchio's ``ProximalSettings(0, mu, N)`` (accuracy 0: it runs N iterations).

What is compared (ours: the numeric twin, which the generated code is checked against):

* impulse_dynamics: qd+ against ``dq_after``, Lambda against ``impulse_c``, J^T Lambda against M (qd+ - qd-);
  tolerance 1e-9.  On the loop Pinocchio 4.1's impulseDynamics breaks its own law (seen: J qd+ + r J qd- has
  -1.42 in the row along the cart's rail, as if the medium's velocity were left out; its constraintDynamics is
  right there), so the loop's impact is compared with the law solved densely from Pinocchio's crba and the frame
  Jacobians of tests/constraint_reference.py, its derivatives with that solution's central differences.  Likewise
  its computeConstraintDynamicsDerivatives on the loop is 1.3 relative away from central differences of its own
  constraintDynamics (which agree with ours to 1e-11): the loop's forward derivatives are compared with those
  differences (fourth order, h = 1e-4).
* impulse_dynamics_derivatives: dqd+/dq against ``ddq_dq``; Pinocchio's ``ddq_dv`` holds d(qd+ - qd-)/dqd-
  (measured: it equals -(1 + r) M^-1 J^T G^-1 J, without the identity), so dqd+/dqd- - E against it; the impulse's
  derivatives against d(M(q) (qd+ - qd-)): computeRNEADerivatives at v = 0, a = qd+ - qd-, gravity off, plus
  M ddq_dq, and M ddq_dv.  Tolerance 1e-8.
* constrained_forward_dynamics_derivatives: the six blocks of computeConstraintDynamicsDerivatives for qdd,
  and for J^T lambda = M qdd + nle - tau: computeRNEADerivatives at (q, v, qdd) plus M d qdd.  Tolerance 1e-8.
  A weld's drift in Pinocchio is the spatial acceleration (no omega x v term), ours the classical one: they agree
  where J v = 0 and so do their derivatives (the difference, omega_k x v_P, is a product of two terms that vanish
  there), so welds are compared at such velocities; point contacts at any.
Measured (worst over 2-3 states each): impulse_dynamics 3e-15 to 6e-14; derivatives against Pinocchio 1.5e-14
(Panda) to 6.7e-12 (solo12 welded); on the loop 4e-10 against the central differences (their own error).
"""
from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import aggsym
import constraint_reference as cr
from aggsym.codegen.compile import CLibrary, compile_shared
from aggsym.codegen.generate import generate, write
from aggsym.contract import sample_configurations, select_routines
from aggsym.errors import ModelWarning
from aggsym.model.readers.side_files import load_constraints
from aggsym.twin import NumericTwin
from helpers import DATA, relative_error, robot_path
from pinocchio_reference import pin, pinocchio_q, pinocchio_tree
from test_free_flyer import pinocchio_configuration

pytestmark = pytest.mark.pinocchio

IMPULSE_TOLERANCE = 1e-9
DERIVATIVE_TOLERANCE = 1e-8
LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
ROUTINES = ["constrained_forward_dynamics", "impulse_dynamics", "constrained_forward_dynamics_derivatives",
            "impulse_dynamics_derivatives", "constraint_jacobian", "inertia"]
MAX_CONDITION = 1e6  # states where cond(G) is larger are drawn again: two double-precision solves differ by about
# cond(G) * 1e-16 there (solo12 with two welded feet at a random configuration: cond(G) up to 1e9, and ours and
# Pinocchio's dqd+/dq then differ by 1.4e-7 while both differ from central differences of impulseDynamics by 1e-7)
SOLO_FEET = ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"]


def stencil(n, f):
    """Columns of the fourth-order central difference of f along steps 1e-4 e_j (f takes the step vector)."""
    cols = []
    for j in range(n):
        e = np.zeros(n)
        e[j] = 1e-4
        cols.append((8 * (f(e) - f(-e)) - (f(2 * e) - f(-2 * e))) / 12e-4)
    return np.array(cols).T


def side(tmp_path, lines) -> Path:
    path = tmp_path / "constraints.yaml"
    path.write_text("constraints:\n" + "".join(f"  - {line}\n" for line in lines))
    return path


def quiet(fn, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        return fn(*args, **kwargs)


class Contacts:
    """Pinocchio's RigidConstraintModels for a list of (frame, point in the frame, medium frame or None, 3 | 6) at
    the configuration Q (c1 on body k at P, c2 on the medium where P is at Q: no residual; LOCAL_WORLD_ALIGNED)."""

    def __init__(self, pm, Q, specs, prox=None):
        self.pm = pm
        data = pm.createData()
        pin.framesForwardKinematics(pm, data, Q)
        self.models = pin.StdVec_RigidConstraintModel()
        for frame, point, medium, size in specs:
            fr = pm.frames[pm.getFrameId(frame)]
            placement = fr.placement * pin.SE3(np.eye(3), np.asarray(point, dtype=float))
            oMc = data.oMi[fr.parentJoint] * placement
            kind = pin.ContactType.CONTACT_3D if size == 3 else pin.ContactType.CONTACT_6D
            if medium is None:
                cm = pin.RigidConstraintModel(kind, pm, fr.parentJoint, placement, 0, oMc, LWA)
            else:
                j2 = pm.frames[pm.getFrameId(medium)].parentJoint
                cm = pin.RigidConstraintModel(kind, pm, fr.parentJoint, placement, j2, data.oMi[j2].actInv(oMc), LWA)
            self.models.append(cm)
        self.prox = pin.ProximalSettings(1e-14, 0.0, 1) if prox is None else prox

    def _data(self):
        datas = pin.StdVec_RigidConstraintData([m.createData() for m in self.models])
        data = self.pm.createData()
        pin.initConstraintDynamics(self.pm, data, self.models, datas)
        return data, datas

    def mass(self, Q):
        M = pin.crba(self.pm, self.pm.createData(), Q)
        return np.triu(M) + np.triu(M, 1).T

    def impulse(self, Q, v, r) -> dict:
        pm = self.pm
        data, datas = self._data()
        vp = pin.impulseDynamics(pm, data, Q, v, self.models, datas, r, self.prox).copy()
        Lam = data.impulse_c.copy()
        pin.computeImpulseDynamicsDerivatives(pm, data, self.models, datas, r, self.prox)
        dq, dv = data.ddq_dq.copy(), data.ddq_dv.copy()
        M = self.mass(Q)
        still = pin.Model(pm)
        still.gravity = pin.Motion.Zero()
        kept = still.createData()  # (kept alive: Pinocchio returns references into its Data)
        rq = pin.computeRNEADerivatives(still, kept, Q, np.zeros(pm.nv), vp - v)[0].copy()
        return {"qd_plus": vp, "impulse": M @ (vp - v), "Lambda": Lam, "dqd_plus_dq": dq,
                "dqd_plus_dqd_minus": dv + np.eye(pm.nv), "dimpulse_dq": rq + M @ dq, "dimpulse_dqd_minus": M @ dv}

    def dense_impulse(self, Q, v, r, constraints) -> dict:
        """The impact law solved densely from Pinocchio's crba and the frame-Jacobian rows of
        tests/constraint_reference.py (``constraints``), its derivatives by fourth-order central differences on
        the manifold (h = 1e-4): the reference where Pinocchio's impulseDynamics does not hold (a loop)."""
        pm, n = self.pm, self.pm.nv

        def law(QQ, vv):
            M, J = self.mass(QQ), cr.jacobian(pm, QQ, constraints)
            Lam = np.linalg.solve(J @ np.linalg.solve(M, J.T), -(1 + r) * (J @ vv))
            return v_plus_and_impulse(M, J, vv, Lam)

        def v_plus_and_impulse(M, J, vv, Lam):
            return np.concatenate([vv + np.linalg.solve(M, J.T @ Lam), J.T @ Lam])

        value = law(Q, v)
        dq = stencil(n, lambda e: law(pin.integrate(pm, Q, e), v))
        dv = stencil(n, lambda e: law(Q, v + e))
        return {"qd_plus": value[:n], "impulse": value[n:], "dqd_plus_dq": dq[:n], "dqd_plus_dqd_minus": dv[:n],
                "dimpulse_dq": dq[n:], "dimpulse_dqd_minus": dv[n:]}

    def differenced_forward(self, Q, v, tau, specs) -> dict:
        """constraintDynamics (right on the loop) and its fourth-order central differences (h = 1e-4; the
        constraint models rebuilt at every configuration), where computeConstraintDynamicsDerivatives is not
        right (the loop: 1.3 relative from those differences, which agree with ours to 1e-11)."""
        pm, n = self.pm, self.pm.nv

        def solve(QQ, vv, tt):
            out = Contacts(pm, QQ, specs, self.prox).forward(QQ, vv, tt)
            return np.concatenate([out["qdd"], self.mass(QQ) @ out["qdd"] + pin.nonLinearEffects(
                pm, pm.createData(), QQ, vv) - tt])

        out = self.forward(Q, v, tau)
        parts = {"q": stencil(n, lambda e: solve(pin.integrate(pm, Q, e), v, tau)),
                 "qd": stencil(n, lambda e: solve(Q, v + e, tau)), "tau": stencil(n, lambda e: solve(Q, v, tau + e))}
        out.update({f"dqdd_d{k}": d[:n] for k, d in parts.items()})
        out.update({f"dJtlambda_d{k}": d[n:] for k, d in parts.items()})
        return out

    def forward(self, Q, v, tau) -> dict:
        pm = self.pm
        data, datas = self._data()
        a = pin.constraintDynamics(pm, data, Q, v, tau, self.models, datas, self.prox).copy()
        lam = data.lambda_c.copy()
        blocks = [x.copy() for x in pin.computeConstraintDynamicsDerivatives(pm, data, self.models, datas,
                                                                              self.prox)]
        M = self.mass(Q)
        kept = pm.createData()
        rq, rv, _ = [x.copy() for x in pin.computeRNEADerivatives(pm, kept, Q, v, a)]
        return {"qdd": a, "lambda": lam, "dqdd_dq": blocks[0], "dqdd_dqd": blocks[1], "dqdd_dtau": blocks[2],
                "dJtlambda_dq": rq + M @ blocks[0], "dJtlambda_dqd": rv + M @ blocks[1],
                "dJtlambda_dtau": M @ blocks[2] - np.eye(pm.nv)}


def ours(twin, q, v_impact, v, tau, r) -> tuple:
    qd_plus, impulse, Lam = twin.impulse_dynamics(q, v_impact, r)
    I = twin.impulse_dynamics_derivatives(q, v_impact, r)
    imp = dict(zip(["qd_plus", "impulse", "Lambda", "dqd_plus_dq", "dqd_plus_dqd_minus", "dimpulse_dq",
                    "dimpulse_dqd_minus"], (qd_plus, impulse, Lam) + tuple(I)))
    qdd, lam = twin.constrained_forward_dynamics(q, v, tau)
    D = twin.constrained_forward_dynamics_derivatives(q, v, tau)
    fwd = dict(zip(["qdd", "lambda", "dqdd_dq", "dqdd_dqd", "dqdd_dtau", "dJtlambda_dq", "dJtlambda_dqd",
                    "dJtlambda_dtau"], (qdd, lam) + tuple(D)))
    return imp, fwd


class Compiled:
    """The generated C library with the twin's calls (the routines it holds; the others from the twin)."""

    def __init__(self, lib, twin):
        self.lib, self.twin = lib, twin

    def __getattr__(self, role):
        if role in self.lib.manifest["functions"]:
            return lambda *args: self.lib.call(role, *args)
        return getattr(self.twin, role)


def check(model, pm, to_pin, specs, rng, states, consistent, dense=None, compiled=None):
    """Compare at ``states`` random states; ``consistent``: the forward dynamics at a velocity with J v = 0;
    ``dense``: the reference's constraints for the impact law solved densely instead of impulseDynamics;
    ``compiled``: a folder, where the model's C is generated (every column map looped), compiled and compared
    instead of the twin."""
    model = select_routines(model, ROUTINES)
    twin = NumericTwin(model)
    if compiled is not None:
        write(generate(model, targets="c,numpy,manifest", looped_above=0), compiled)
        manifest = json.loads((compiled / f"{model.name}.json").read_text())
        twin = Compiled(CLibrary(compile_shared(compiled / f"{model.name}.c", compiled / f"lib{model.name}.so",
                                                extra=("-O1",)), manifest), twin)
    worst = {}
    done = 0
    while done < states:
        q = sample_configurations(model, rng) if model.nq != model.nv else rng.uniform(-np.pi, np.pi, model.nq)
        Q = to_pin(pm, q)
        v, tau, r = rng.normal(size=model.nv), rng.normal(size=model.nv), rng.uniform()
        J = twin.constraint_jacobian(q)
        if np.linalg.cond(J @ np.linalg.solve(twin.inertia(q), J.T)) > MAX_CONDITION:
            continue
        done += 1
        w = v - np.linalg.pinv(J) @ (J @ v) if consistent else v
        contacts = Contacts(pm, Q, specs)
        got_imp, got_fwd = ours(twin, q, v, w, tau, r)
        impact = contacts.impulse(Q, v, r) if dense is None else contacts.dense_impulse(Q, v, r, dense)
        forward = contacts.forward(Q, w, tau) if dense is None else contacts.differenced_forward(Q, w, tau, specs)
        for got, want, tol in ((got_imp, impact, IMPULSE_TOLERANCE), (got_fwd, forward, DERIVATIVE_TOLERANCE)):
            for key, value in want.items():
                tolerance = tol if key.startswith("d") else IMPULSE_TOLERANCE
                error = relative_error(got[key], value, floor=1.0 if key.startswith("d") else 1e-300)
                worst[key] = max(worst.get(key, 0.0), error)
                assert error < tolerance, f"{model.name}: {key}: {error:.3g}"
    return worst


def quadruped_on_four_point_feet(tmp_path, rng, compiled=None):
    """solo12 on a quaternion free-flyer standing on its four point feet, against Pinocchio (``check``)."""
    path = robot_path("solo12")
    model = quiet(load_constraints, side(tmp_path, [f"{{name: c{i}, body: {f}, block: point}}"
                                                    for i, f in enumerate(SOLO_FEET)]),
                  quiet(aggsym.load, path, floating_base="quaternion"))
    pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    check(model, pm, pinocchio_configuration, [(f, [0, 0, 0], None, 3) for f in SOLO_FEET], rng, 2,
          consistent=False, compiled=compiled)
    return model


def test_a_quadruped_on_four_point_feet(tmp_path, rng):
    quadruped_on_four_point_feet(tmp_path, rng)


@pytest.mark.compiler
def test_the_generated_c_of_a_quadruped_on_four_point_feet_looped(tmp_path, rng):
    """The C with the solves of both derivative routines looped (aggsym/codegen/targets/c_columns.py; by default
    only a routine as large as Talos's is), compiled, against Pinocchio."""
    model = quadruped_on_four_point_feet(tmp_path, rng, compiled=tmp_path)
    text = (tmp_path / f"{model.name}.c").read_text()
    for role in ("constrained_forward_dynamics_derivatives", "impulse_dynamics_derivatives"):
        assert f"{model.name}_{role}_columns(aggsym_c, aggsym_v" in text


def test_a_quadruped_with_two_welded_feet(tmp_path, rng):
    path = robot_path("solo12")
    feet = ["FL_FOOT", "HR_FOOT"]
    model = quiet(load_constraints, side(tmp_path, [f"{{name: c{i}, body: {f}, block: weld}}"
                                                    for i, f in enumerate(feet)]),
                  quiet(aggsym.load, path, floating_base="quaternion"))
    pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    check(model, pm, pinocchio_configuration, [(f, [0, 0, 0], None, 6) for f in feet], rng, 2, consistent=True)


@pytest.mark.compiler
def test_a_quadruped_on_a_weld_a_foot_and_an_offset_point_looped(tmp_path, rng):
    """A mixed contact set: one foot welded (6D), one a point, one a point 1.5 cm off its frame (3D each: 12
    rows), at consistent velocities; the generated C with both derivative routines looped."""
    path = robot_path("solo12")
    offset = [0.0131, -0.0042, 0.00587]
    lines = ["{name: c0, body: FL_FOOT, block: weld}", "{name: c1, body: HR_FOOT, block: point}",
             f"{{name: c2, body: FR_FOOT, point: {offset}, block: point}}"]
    model = quiet(load_constraints, side(tmp_path, lines), quiet(aggsym.load, path, floating_base="quaternion"))
    pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    specs = [("FL_FOOT", [0, 0, 0], None, 6), ("HR_FOOT", [0, 0, 0], None, 3), ("FR_FOOT", offset, None, 3)]
    check(model, pm, pinocchio_configuration, specs, rng, 2, consistent=True, compiled=tmp_path)


@pytest.mark.slow
def test_a_humanoid_on_two_welded_soles(tmp_path, rng):
    path = robot_path("talos")
    soles = ["left_sole_link", "right_sole_link"]
    model = quiet(load_constraints, side(tmp_path, [f"{{name: c{i}, body: {f}, block: weld}}"
                                                    for i, f in enumerate(soles)]),
                  quiet(aggsym.load, path, floating_base="quaternion"))
    pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    check(model, pm, pinocchio_configuration, [(f, [0, 0, 0], None, 6) for f in soles], rng, 1, consistent=True)


def test_an_arm_welded_at_its_hand(tmp_path, rng):
    path = robot_path("panda")
    model = quiet(load_constraints, side(tmp_path, ["{name: weld, body: panda_hand, block: weld}"]),
                  quiet(aggsym.load, path))
    pm = pin.buildModelFromUrdf(str(path))
    check(model, pm, pinocchio_q, [("panda_hand", [0, 0, 0], None, 6)], rng, 2, consistent=True)


def test_a_closed_loop(tmp_path, rng):
    model = aggsym.load(DATA / "rail_loop.yaml")  # a spatial chain whose tip is pinned to a cart on a rail
    pm, _ = pinocchio_tree(model)
    assert (model.nq, model.constraint_rows) == (4, 3)
    reference = [cr.Constraint("lower", [0.2, 0.05, -0.1], [0, 1, 2], medium="cart")]
    check(model, pm, lambda pm, q: np.asarray(q, dtype=float), [("lower", [0.2, 0.05, -0.1], "cart", 3)], rng, 3,
          consistent=False, dense=reference)


def test_the_damped_solve_equals_pinocchio_proximal_iterations(tmp_path, rng):
    """Panda welded at the hand plus a point of the hand: J (9 rows) has rank 6 everywhere.  With the same mu
    and N, our damped solve and Pinocchio's proximal iterations (accuracy 0, so exactly N of them) give the same
    qdd and lambda; ours are finite."""
    mu, N = 1e-3, 3
    path = robot_path("panda")
    text = ["{name: weld, body: panda_hand, block: weld}",
            "{name: tip, body: panda_hand, point: [0.0, 0.05, 0.1], block: point}"]
    file = side(tmp_path, text)
    file.write_text(file.read_text() + f"proximal: {{mu: {mu}, iterations: {N}}}\n")
    model = select_routines(quiet(load_constraints, file, quiet(aggsym.load, path)), ROUTINES)
    twin = NumericTwin(model)
    pm = pin.buildModelFromUrdf(str(path))
    for _ in range(2):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        Q = pinocchio_q(pm, q)
        J = twin.constraint_jacobian(q)
        assert np.linalg.matrix_rank(J) == 6
        v = rng.normal(size=model.nv)
        v = v - np.linalg.pinv(J) @ (J @ v)
        tau = rng.normal(size=model.nv)
        prox = pin.ProximalSettings(0.0, mu, N)
        contacts = Contacts(pm, Q, [("panda_hand", [0, 0, 0], None, 6), ("panda_hand", [0.0, 0.05, 0.1], None, 3)],
                            prox)
        want = contacts.forward(Q, v, tau)
        assert prox.iter == N
        qdd, lam = twin.constrained_forward_dynamics(q, v, tau)
        assert relative_error(qdd, want["qdd"]) < IMPULSE_TOLERANCE
        assert relative_error(lam, want["lambda"]) < IMPULSE_TOLERANCE
        D = twin.constrained_forward_dynamics_derivatives(q, v, tau)
        assert all(np.isfinite(x).all() for x in D)
        assert relative_error(D[1], want["dqdd_dqd"], floor=1.0) < DERIVATIVE_TOLERANCE
        assert relative_error(D[2], want["dqdd_dtau"], floor=1.0) < DERIVATIVE_TOLERANCE
