"""Section 3, constrained forward dynamics: solo12 (floating base) standing on its four point feet.

``aggsym generate solo12.urdf --floating-base --constraints feet.yaml`` (four ``block: point`` contacts of the
feet with the world) gives ``constrained_forward_dynamics(q, qd, tau, p, qdd, lambda)``; the harness times it
against Pinocchio's ``constraintDynamics`` (``initConstraintDynamics`` once; one ``RigidConstraintModel``
CONTACT_3D per foot frame, default ``ProximalSettings``: mu = 0, one exact solve).  Pinocchio's floating base is
the composite root joint PX, PY, PZ, RX, RY, RZ that mirrors ``--floating-base`` coordinate for coordinate, so q
maps one-to-one.  Pinocchio's contact drift equals J' qd only where the feet do not move, so the states are
consistent: qd projected onto the null space of the feet's Jacobian.  :func:`pinocchio_check` compares the
generated NumPy module with the ``pin`` bindings on a few such states before anything is timed.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..harness.generate import generated_manifest, load_module
from ..harness.robots import FILES

LABEL = "solo12"
NAME = "solo12_feet"  # the generated code's name (C prefix), apart from the robots'
URDF = FILES[LABEL]
FEET = ("FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT")
TOLERANCE = 1e-8


def constraints_yaml() -> str:
    """The side file of ``--constraints``: each foot a point contact with the world."""
    lines = ["constraints:"]
    lines += [f"  - {{name: {foot[:2].lower()}, body: {foot}, block: point}}" for foot in FEET]
    return "\n".join(lines) + "\n"


def generate(urdf, outdir, timeout: float | None = None) -> dict:
    """``aggsym generate URDF --floating-base --constraints feet.yaml --name solo12_feet -o OUTDIR -q`` in a fresh
    process (not timed: section 1 measures generation); returns the manifest."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    feet = outdir.parent / f"{NAME}_constraints.yaml"
    feet.write_text(constraints_yaml())
    return generated_manifest(urdf, outdir, NAME, "--floating-base", "--constraints", feet, "--name", NAME, "-q",
                              timeout=timeout)


def pinocchio_model(urdf):
    """Pinocchio's model with the free root of ``--floating-base``: PX, PY, PZ, RX, RY, RZ in this order."""
    import pinocchio as pin

    root = pin.JointModelComposite()
    for joint in (pin.JointModelPX(), pin.JointModelPY(), pin.JointModelPZ(), pin.JointModelRX(), pin.JointModelRY(),
                  pin.JointModelRZ()):
        root.addJoint(joint)
    return pin.buildModelFromUrdf(str(urdf), root)


def pinocchio_check(outdir, urdf, states: int = 5, seed: int = 12) -> dict:
    """q'' (and lambda) of the generated NumPy module against ``pin.constraintDynamics`` (LOCAL_WORLD_ALIGNED) on
    ``states`` random consistent states (q uniform in [-pi, pi], tau standard normal, qd standard normal projected
    so that the feet are at rest).  Returns the largest relative errors and whether q'' is within TOLERANCE."""
    import pinocchio as pin

    manifest = json.loads((Path(outdir) / f"{NAME}.json").read_text())
    module = load_module(Path(outdir) / f"{NAME}.py", NAME)
    pm = pinocchio_model(urdf)
    n = manifest["nq"]
    names = [pm.names[j] for j in range(1, pm.njoints) for _ in range(pm.joints[j].nv)]
    if pm.nq != n or pm.nv != n or names != [c["joint"] for c in manifest["coordinates"]]:
        raise ValueError(f"{NAME}: Pinocchio's joints {names} (nq {pm.nq}) are not the generated coordinates")
    frames = [pm.getFrameId(foot) for foot in FEET]
    contacts = pin.StdVec_RigidConstraintModel()
    for f in frames:
        contacts.append(pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, pm, pm.frames[f].parentJoint,
                                                 pm.frames[f].placement, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED))
    datas = pin.StdVec_RigidConstraintData()
    for c in contacts:
        datas.append(c.createData())
    data = pm.createData()
    pin.initConstraintDynamics(pm, data, contacts, datas)
    rng = np.random.default_rng(seed)
    err_qdd = err_lambda = 0.0
    for _ in range(states):
        q = rng.uniform(-np.pi, np.pi, n)  # every joint has nq = nv here (composite root, revolute legs)
        qd, tau = rng.standard_normal(n), rng.standard_normal(n)
        kin = pm.createData()
        pin.computeJointJacobians(pm, kin, q)
        pin.updateFramePlacements(pm, kin)
        J = np.vstack([pin.getFrameJacobian(pm, kin, f, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:3] for f in frames])
        qd = qd - np.linalg.pinv(J) @ (J @ qd)
        qdd, lam = module.constrained_forward_dynamics(q, qd, tau)
        theirs = pin.constraintDynamics(pm, data, q, qd, tau, contacts, datas, pin.ProximalSettings()).copy()
        err_qdd = max(err_qdd, float(np.abs(qdd - theirs).max() / np.abs(theirs).max()))
        lam_c = np.array(data.lambda_c)
        err_lambda = max(err_lambda, float(np.abs(lam - lam_c).max() / np.abs(lam_c).max()))
    return {"states": states, "qdd_relative_error": err_qdd, "lambda_relative_error": err_lambda,
            "tolerance": TOLERANCE, "ok": err_qdd <= TOLERANCE}


def prepare(urdf, outdir, timeout: float | None = None, log=print) -> dict:
    """Generate the constrained solo12 into ``outdir`` and check it against the ``pin`` bindings (not timed).
    Returns {"outdir", "urdf", "frames", "ops" (the routine's op count from the manifest), "check"}."""
    manifest = generate(urdf, outdir, timeout=timeout)
    check = pinocchio_check(outdir, urdf)
    log(f"{LABEL} on {len(FEET)} point feet: NumPy module vs pin.constraintDynamics on {check['states']} consistent "
        f"states: qdd rel. error {check['qdd_relative_error']:.1e}, lambda {check['lambda_relative_error']:.1e}")
    return {"outdir": Path(outdir), "urdf": Path(urdf), "frames": list(FEET),
            "ops": manifest["ops"]["constrained_forward_dynamics"], "check": check}
