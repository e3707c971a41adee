"""Rung 4 through rung 5: the generated C and NumPy module of real robots against Pinocchio.

For the robots of example-robot-data (fixed base): A vs crba, d = b + g vs nonLinearEffects, g vs
computeGeneralizedGravity, inverse dynamics vs rnea, the joint wrenches vs data.f after rnea, T and U vs
computeKineticEnergy / computePotentialEnergy, the Coriolis matrix C by C qd = b and C + C^T = dM/dt from
computeCoriolisMatrix; relative error <= 1e-9.  The code comes from conftest's ``robot_code`` (compiled -O0,
shared with test_transvective_pinocchio).
"""
import numpy as np
import pytest

import aggsym
from helpers import TOLERANCE, relative_error
from pinocchio_reference import pin, inertia_rate, pinocchio_model, pinocchio_q
from random_trees import random_urdf

pytestmark = [pytest.mark.pinocchio, pytest.mark.filterwarnings("ignore::aggsym.errors.ModelWarning")]


def both(lib, module, role, *args):
    """The C function and the NumPy function of a role, called on the same inputs."""
    return lib.call(role, *args), getattr(module, role)(*args)


@pytest.mark.compiler
def test_generated_code_equals_pinocchio(robot_code, rng):
    name, model, lib, module, pm = robot_code
    data = pm.createData()
    assert model.nq == pm.nv
    for _ in range(3):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        qd, qdd = rng.normal(size=model.nq), rng.normal(size=model.nq)
        Q = pinocchio_q(pm, q)
        M = pin.crba(pm, data, Q)
        M = np.triu(M) + np.triu(M, 1).T
        tau = pin.rnea(pm, data, Q, qd, qdd)
        f = np.array([np.concatenate([data.f[j].linear, data.f[j].angular]) for j in range(1, pm.njoints)])
        nle = pin.nonLinearEffects(pm, data, Q, qd)
        refs = [
            ("inertia", (q,), M),
            ("nonlinear_effects", (q, qd), nle),
            ("gravity", (q,), pin.computeGeneralizedGravity(pm, data, Q)),
            ("inverse_dynamics", (q, qd, qdd), tau),
            ("joint_wrenches", (q, qd, qdd), f),
            ("kinetic_energy", (q, qd), pin.computeKineticEnergy(pm, data, Q, qd)),
            ("potential_energy", (q,), pin.computePotentialEnergy(pm, data, Q)),
        ]
        for role, args, ref in refs:
            c, py = both(lib, module, role, *args)
            assert relative_error(c, ref) <= TOLERANCE, (name, role, "C", relative_error(c, ref))
            assert relative_error(py, ref) <= TOLERANCE, (name, role, "NumPy", relative_error(py, ref))
        b, _ = both(lib, module, "bias", q, qd)
        assert relative_error(b + lib.call("gravity", q), nle) <= TOLERANCE
        Mdot, _ = inertia_rate(pm, Q, qd)
        for kind, C in zip(("C", "NumPy"), both(lib, module, "coriolis", q, qd)):
            C = np.asarray(C).reshape(model.nq, model.nq)
            assert relative_error(C @ qd, b, floor=np.abs(M).max() * np.abs(qd).max() ** 2) <= TOLERANCE, \
                (name, kind, "C qd = b")
            assert relative_error(C + C.T, Mdot, floor=np.abs(M).max() * np.abs(qd).max()) <= TOLERANCE, \
                (name, kind, "C + C^T = dM/dt")


@pytest.mark.parametrize("seed", range(20))
def test_joint_wrenches_equal_pinocchio_on_random_trees(seed, tmp_path):
    """data.f after rnea: the wrench each joint transmits, in the child link frame, on random branching trees
    with arbitrary axes, rotated joint origins and inertial frames, prismatic, continuous and fixed joints."""
    rng = np.random.default_rng(seed)
    path = tmp_path / "tree.urdf"
    path.write_text(random_urdf(seed))
    model = aggsym.load(path)
    pm = pinocchio_model(path)
    data = pm.createData()
    twin = aggsym.NumericTwin(model)
    for _ in range(2):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        qd, qdd = rng.normal(size=model.nq), rng.normal(size=model.nq)
        pin.rnea(pm, data, pinocchio_q(pm, q), qd, qdd)
        f = np.array([np.concatenate([data.f[j].linear, data.f[j].angular]) for j in range(1, pm.njoints)])
        assert relative_error(twin.joint_wrenches(q, qd, qdd), f) <= TOLERANCE
