"""What the tests of MuJoCo's two fluid models share (tests/test_fluid.py: the inertia box,
tests/test_fluid_ellipsoid.py: the ellipsoids): a probe's chain without its free glider, the derivatives of forward
dynamics against central differences, and the medium (density, viscosity, wind) set at runtime against MuJoCo."""
from __future__ import annotations

import mujoco
import numpy as np

from aggsym.twin import NumericTwin
from benchmarks.mjcf.mujoco_reference import mujoco_model, states, to_aggsym
from helpers import central_differences


def chain_of(probe) -> str:
    """The probe's MJCF text without its free glider (the body "glider", up to the body "arm"): q is qpos."""
    text = probe.read_text()
    start, end = text.index('    <body name="glider"'), text.index('    <body name="arm"')
    return text[:start] + text[end:]


def derivative_errors(model, seed=1) -> tuple:
    """The twin's d qdd/dq and d qdd/dqd against central differences at a random state: each largest difference
    over the largest entry of the differences."""
    twin = NumericTwin(model)
    n = model.nv
    q, qd, tau = np.random.default_rng(seed).normal(size=(3, n))
    dq, dqd = (np.asarray(a).reshape(n, n) for a in twin.call("forward_dynamics_derivatives", q, qd, tau))
    fq = central_differences(lambda y: np.asarray(twin.call("forward_dynamics", y, qd, tau)), q).reshape(n, n)
    fqd = central_differences(lambda y: np.asarray(twin.call("forward_dynamics", q, y, tau)), qd).reshape(n, n)
    return (float(np.max(np.abs(dq - fq)) / np.max(np.abs(fq))),
            float(np.max(np.abs(dqd - fqd)) / np.max(np.abs(fqd))))


def medium_at_runtime(probe, model, module, seed=9) -> list:
    """The medium changed at runtime (density 1000, viscosity 1.3e-3, wind (-2, 0.5, 1)) in MuJoCo and in p: per
    random state (largest difference of the passive forces from MuJoCo's qfrc_passive, largest entry of MuJoCo's)."""
    names = [p.name for p in model.parameters]
    m = mujoco_model(probe, fluid=True)
    p = np.array(module.PARAMETERS, dtype=float)
    m.opt.density, p[names.index("fluid_density")] = 1000.0, 1000.0
    m.opt.viscosity, p[names.index("fluid_viscosity")] = 1.3e-3, 1.3e-3
    m.opt.wind[:] = [-2.0, 0.5, 1.0]
    for axis, value in zip("xyz", m.opt.wind):
        p[names.index(f"wind_{axis}")] = value
    data = mujoco.MjData(m)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(3):
        qpos, qvel, force = states(m, rng)
        data.qpos[:], data.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, data)
        q, qd, _, J, _ = to_aggsym(m, qpos, qvel, force)
        ref = J.T @ data.qfrc_passive
        out.append((float(np.max(np.abs(module.passive_forces(q, qd, p) - ref))), float(np.max(np.abs(ref)))))
    return out
