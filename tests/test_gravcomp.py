"""Gravity compensation (MuJoCo's ``gravcomp``, aggsym/mechanics/gravcomp.py, issue 53 item 5): the lift of a fraction
of each compensated body's weight, among the passive forces, equal to MuJoCo's qfrc_passive through the twin, the
generated NumPy and C; on a body with two joints, on bodies merged into their parent with their own fractions, on a
free body; a runtime parameter per body; the potential energy holds the lift's (its gradient is g - passive)."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import aggsym
from aggsym.errors import AggsymError
from aggsym.twin import NumericTwin
from helpers import central_differences, generated_code

mujoco = pytest.importorskip("mujoco")
pytestmark = pytest.mark.mujoco

from benchmarks.mjcf.mujoco_reference import Module, compare, mujoco_model, reference_terms, states  # noqa: E402

PROBES = Path(__file__).resolve().parent.parent / "benchmarks" / "mjcf" / "probes"
ARM, FREE = PROBES / "gravcomp_arm.xml", PROBES / "gravcomp_free.xml"


def load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return aggsym.load(path)


@pytest.fixture(scope="module", params=[ARM, FREE], ids=lambda p: p.stem)
def compensated(request, tmp_path_factory):
    path = request.param
    model = load(path)
    library, module, manifest = generated_code(model, tmp_path_factory.mktemp(path.stem))
    return path, model, library, module, manifest


def test_against_mujoco(compensated):
    path, model, library, module, _ = compensated
    assert model.gravcomp
    worst = compare(path, model=model, samples=5, seed=7, evaluators=[library, Module(module)])
    assert worst["passive"] <= 1e-12 and max(worst.values()) <= 1e-9, worst


def test_the_fractions_are_runtime_parameters(compensated):
    """Each body's fraction in p: changed there, the passive forces follow MuJoCo's with body_gravcomp changed."""
    path, model, _, module, _ = compensated
    names = [p.name for p in model.parameters]
    m = mujoco_model(path)
    rng = np.random.default_rng(3)
    p = np.array(module.PARAMETERS, dtype=float)
    for i in range(1, m.nbody):
        if m.body_gravcomp[i]:
            value = float(rng.uniform(0.0, 2.0))
            m.body_gravcomp[i] = value
            p[names.index(f"gravcomp_{mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, i)}")] = value
    data = mujoco.MjData(m)
    for _ in range(3):
        qpos, qvel, force = states(m, rng)
        M, (q, qd, tau, J, c), A_ref, d_ref = reference_terms(m, data, qpos, qvel, force)
        mine = module.passive_forces(q, qd, p)
        ref = J.T @ data.qfrc_passive
        assert np.max(np.abs(mine - ref)) <= 1e-12 * max(1.0, np.max(np.abs(ref)))
        assert np.max(np.abs(J @ module.forward_dynamics(q, qd, tau, p) + c - data.qacc)) <= \
            1e-9 * max(1.0, np.max(np.abs(data.qacc)))


def test_the_potential_energy_holds_the_lift():
    """grad U = g(q) - passive_forces(q, 0) (the spring's part included), by central differences, and the
    generalized gravity g(q) keeps the whole weight (MuJoCo's qfrc_bias at rest)."""
    model = load(ARM)
    twin = NumericTwin(model)
    m = mujoco_model(ARM)
    data = mujoco.MjData(m)
    rng = np.random.default_rng(11)
    zero = np.zeros(model.nv)
    for _ in range(3):
        q = np.round(rng.uniform(-2, 2, model.nq), 5)
        grad = central_differences(lambda x: np.atleast_1d(twin.call("potential_energy", x)), q)
        expected = np.asarray(twin.call("gravity", q)) - np.asarray(twin.call("passive_forces", q, zero))
        assert np.max(np.abs(grad.ravel() - expected)) <= 1e-7 * max(1.0, np.max(np.abs(expected)))
        data.qpos[:], data.qvel[:] = q, 0  # (a fixed base of hinges and a slide: q is qpos)
        mujoco.mj_forward(m, data)
        assert np.allclose(twin.call("gravity", q), data.qfrc_bias, rtol=0, atol=1e-12 * np.abs(data.qfrc_bias).max())


def test_the_manifest_records_it(compensated):
    path, model, _, _, manifest = compensated
    listed = {e["body"]: e["gravcomp"] for e in manifest["mjcf"]["gravcomp"]}
    m = mujoco_model(path)
    assert listed == {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, i): float(m.body_gravcomp[i])
                      for i in range(1, m.nbody) if m.body_gravcomp[i]}
    assert "gravity compensation" in manifest["mjcf"]["in_the_equations"]
    assert "passive_forces" in manifest["functions"]
    from aggsym.contract.analyses import regressor_problem

    assert "gravity compensation" in regressor_problem(model)


def test_inertial_parameters_of_a_compensated_body_are_refused():
    with pytest.raises(AggsymError, match="gravity-compensated"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            aggsym.load(ARM, inertial_parameters="tip,base")


def test_the_derivatives_carry_the_lift():
    """d qdd / dq and d tau / dq of the compensated arm against central differences of its own dynamics (the lift
    is in both), and the lift's share against differences of passive_forces."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = aggsym.load(ARM, routines=["all"])
    twin = NumericTwin(model)
    rng = np.random.default_rng(2)
    n = model.nv
    for _ in range(2):
        q, qd, x = rng.normal(size=(3, n))
        for role, value in (("forward_dynamics_derivatives", "forward_dynamics"),
                            ("inverse_dynamics_derivatives", "inverse_dynamics")):
            dq = np.asarray(twin.call(role, q, qd, x)[0]).reshape(n, n)
            fd = central_differences(lambda y: np.asarray(twin.call(value, y, qd, x)), q).reshape(n, n)
            assert np.max(np.abs(dq - fd)) <= 1e-7 * np.max(np.abs(fd)), role
