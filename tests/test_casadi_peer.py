"""The benchmark's CasADi peer (benchmarks/runtime/casadi_peer.py) against Pinocchio: its SX functions and its C.

The peer is a timing reference, so it must compute what Pinocchio computes: A (crba), b+g (nonLinearEffects),
inverse dynamics (rnea), forward dynamics (aba) and A^-1 (computeMinverse), on a fixed-base arm, on solo12 with
the composite Euler root, and on the benchmark's chain written as URDF.
"""
import ctypes
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.harness import chain  # noqa: E402
from benchmarks.harness.robots import robots_directory  # noqa: E402
from benchmarks.runtime import casadi_peer  # noqa: E402
from pinocchio_reference import pin  # noqa: E402

pytestmark = pytest.mark.pinocchio

TOL = 1e-9


def _reference(model, q, v, a, tau):
    """Pinocchio's five results (q: one angle per coordinate; no continuous joints in these models)."""
    data = model.createData()
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    Minv = pin.computeMinverse(model, data, q)
    Minv = np.triu(Minv) + np.triu(Minv, 1).T
    return {"inertia": M, "nonlinear_effects": pin.nonLinearEffects(model, data, q, v).copy(),
            "inverse_dynamics": pin.rnea(model, data, q, v, a).copy(),
            "forward_dynamics": pin.aba(model, data, q, v, tau).copy(), "inertia_inverse": Minv}


def _relative(ours, theirs):
    return float(np.max(np.abs(np.asarray(ours) - theirs)) / np.max(np.abs(theirs)))


def _models(tmp_path):
    root = robots_directory()
    return {"ur5": (root / "ur_description/urdf/ur5_robot.urdf", None),
            "solo12_euler": (root / "solo_description/robots/solo12.urdf", "euler"),
            "chain5": (chain.write_chain_urdf(5, tmp_path), None)}


@pytest.mark.parametrize("label", ["ur5", "solo12_euler", "chain5"])
def test_peer_functions_match_pinocchio(tmp_path, label):
    urdf, root = _models(tmp_path)[label]
    model = casadi_peer.pinocchio_model(urdf, root)
    joints = casadi_peer.tree_from_pinocchio(model)
    assert len(joints) == model.nv == model.nq
    funcs = casadi_peer.functions(label, joints, np.array(model.gravity.linear))
    rng = np.random.default_rng(7)
    for _ in range(3):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        v, a, tau = rng.normal(size=(3, model.nv))
        ref = _reference(model, q, v, a, tau)
        ours = {"inertia": funcs["inertia"](q), "nonlinear_effects": funcs["nonlinear_effects"](q, v),
                "inverse_dynamics": funcs["inverse_dynamics"](q, v, a),
                "forward_dynamics": funcs["forward_dynamics"](q, v, tau),
                "inertia_inverse": funcs["inertia_inverse"](q)}
        for role, theirs in ref.items():
            got = np.array(ours[role]).reshape(theirs.shape)
            assert _relative(got, theirs) < TOL, (label, role)


def test_euler_root_is_six_one_axis_joints_with_massless_links():
    model = casadi_peer.pinocchio_model(robots_directory() / "solo_description/robots/solo12.urdf", "euler")
    joints = casadi_peer.tree_from_pinocchio(model)
    assert [(j.kind, tuple(j.axis)) for j in joints[:6]] == [
        ("P", (1, 0, 0)), ("P", (0, 1, 0)), ("P", (0, 0, 1)), ("R", (1, 0, 0)), ("R", (0, 1, 0)), ("R", (0, 0, 1))]
    assert [j.mass for j in joints[:5]] == [0.0] * 5 and joints[5].mass == pytest.approx(model.inertias[1].mass)
    assert [j.parent for j in joints[:6]] == [-1, 0, 1, 2, 3, 4]


def test_joints_beyond_one_axis_are_refused():
    model = pin.buildModelFromUrdf(str(robots_directory() / "solo_description/robots/solo12.urdf"),
                                   pin.JointModelFreeFlyer())
    with pytest.raises(ValueError, match="one-axis joints only"):
        casadi_peer.tree_from_pinocchio(model)


def test_peer_c_wrappers_match_pinocchio(tmp_path):
    """The C that the benchmark compiles: CasADi's code and the wrappers with the generated code's signatures."""
    urdf = robots_directory() / "ur_description/urdf/ur5_robot.urdf"
    info = casadi_peer.write_peer("ur5", urdf, tmp_path)
    lib = tmp_path / "libpeer.so"
    subprocess.run(["cc", "-std=c99", "-O2", "-fPIC", "-shared", "-o", str(lib), str(info["path"]), "-lm"],
                   check=True, capture_output=True)
    so = ctypes.CDLL(str(lib))
    model = casadi_peer.pinocchio_model(urdf)
    n = model.nv
    rng = np.random.default_rng(3)
    q = rng.uniform(-np.pi, np.pi, n)
    v, a, tau = rng.normal(size=(3, n))
    ref = _reference(model, q, v, a, tau)
    ptr = lambda x: x.ctypes.data_as(ctypes.POINTER(ctypes.c_double))  # noqa: E731
    args = {"inertia": (q,), "nonlinear_effects": (q, v), "inverse_dynamics": (q, v, a),
            "forward_dynamics": (q, v, tau), "inertia_inverse": (q,)}
    for role, xs in args.items():
        out = np.zeros(ref[role].size)
        getattr(so, f"ur5_{role}")(*[ptr(np.ascontiguousarray(x)) for x in xs], None, ptr(out))
        assert _relative(out.reshape(ref[role].shape), ref[role]) < TOL, role


def test_chain_urdf_carries_the_chain_numbers(tmp_path):
    model = pin.buildModelFromUrdf(str(chain.write_chain_urdf(4, tmp_path)))
    assert model.nq == 4 and [j.shortname() for j in model.joints[1:]] == [
        "JointModelRZ", "JointModelRY", "JointModelRX", "JointModelRZ"]
    for k in range(1, 5):
        d = chain.link(k)
        assert model.inertias[k].mass == pytest.approx(d["mass"])
        assert np.allclose(model.inertias[k].lever, d["com"])
        assert np.allclose(model.jointPlacements[k].translation, d["offset"])
