"""A fixed tendon's armature (aggsym/mechanics/tendon_armature.py, issue 53 item 5): a c c^T in A, so in inverse
dynamics and the kinetic energy, and in forward dynamics and A^-1 by the Sherman-Morrison formula over the tree's
factors.  Against MuJoCo (M, bias, qacc, passive; the twin, the generated C and NumPy) on a probe whose tendons run
along chains; where a tendon spans two branches, MuJoCo's M (sparse as the tree) leaves its terms between them out
and aggsym keeps the documented energy 1/2 a (c . qd)^2, which the test shows term by term.  The routines built on
the tree's factors are left out with the reason; a spatial tendon's armature is refused."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.twin import NumericTwin
from helpers import generated_code

mujoco = pytest.importorskip("mujoco")
pytestmark = pytest.mark.mujoco

from benchmarks.mjcf.mujoco_reference import Module, compare, mujoco_model, reference_terms, states  # noqa: E402

PROBE = Path(__file__).resolve().parent.parent / "benchmarks" / "mjcf" / "probes" / "tendon_armature.xml"


def load(path, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return aggsym.load(path, **options)


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    model = load(PROBE)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (the factors left out: a ModelWarning)
        library, module, manifest = generated_code(model, tmp_path_factory.mktemp("armature"))
    return model, library, module, manifest


def test_the_probe_against_mujoco(probe):
    model, library, module, manifest = probe
    assert [t.name for t in model.tendons] == ["coupled", "heavy"]
    worst = compare(PROBE, model=model, samples=6, seed=3, evaluators=[library, Module(module)])
    assert max(worst.values()) <= 1e-12, worst
    assert {"tendon_armature_coupled", "tendon_armature_heavy"} <= {p["name"] for p in manifest["parameters"]}


def test_the_routines_agree_with_one_another(probe):
    """Inverse dynamics = A qdd + b + g + passive, forward dynamics its inverse, A^-1 the inverse of A, T = 1/2
    qd^T A qd, in the generated NumPy module."""
    model, _, module, manifest = probe
    rng = np.random.default_rng(5)
    for _ in range(3):
        q = rng.uniform(-1, 1, model.nq)
        q[7:11] /= np.linalg.norm(q[7:11])
        qd, qdd = rng.normal(size=(2, model.nv))
        A = module.inertia(q)
        tau = module.inverse_dynamics(q, qd, qdd)
        assert np.allclose(tau, A @ qdd + module.nonlinear_effects(q, qd), rtol=0, atol=1e-12 * np.abs(tau).max())
        assert np.allclose(module.forward_dynamics(q, qd, tau), qdd, rtol=0, atol=1e-10 * np.abs(qdd).max())
        assert np.allclose(module.inertia_inverse(q) @ A, np.eye(model.nv), rtol=0, atol=1e-10)
        assert np.isclose(module.kinetic_energy(q, qd), 0.5 * qd @ A @ qd, rtol=1e-13)
    omitted = manifest["omitted"]
    assert "transvective_factors" in omitted and "armature of tendon(s) 'coupled', 'heavy'" in omitted[
        "transvective_factors"]
    assert "forward_dynamics" in manifest["functions"] and "inertia_inverse" in manifest["functions"]


def test_a_tendon_across_two_branches_keeps_its_whole_energy(tmp_path):
    """MuJoCo's M has no entries between two branches of a tree, so a tendon over j2 (one branch) and j4 (the
    other) loses its a c_2 c_4 there; aggsym's A differs from MuJoCo's by exactly those terms, and nowhere else."""
    text = PROBE.read_text().replace('<joint joint="j3" coef="0.8"/>', '<joint joint="j4" coef="0.8"/>')
    path = tmp_path / "across.xml"
    path.write_text(text)
    model = load(path)
    m = mujoco_model(path)
    data = mujoco.MjData(m)
    rng = np.random.default_rng(2)
    qpos, qvel, force = states(m, rng)
    _, (q, _, _, _, _), A_ref, _ = reference_terms(m, data, qpos, qvel, force)
    A = np.asarray(NumericTwin(model).call("inertia", q))
    names = [c.name for c in model.coordinates]
    a = float(m.tendon_armature[0])
    c = np.zeros(model.nv)
    c[[names.index("j1"), names.index("j2"), names.index("j4")]] = [0.5, -1.25, 0.8]
    expected = np.zeros_like(A)
    for i, j in ((names.index("j2"), names.index("j4")), (names.index("j4"), names.index("j2"))):
        expected[i, j] = a * c[i] * c[j]
    assert np.max(np.abs((A - A_ref) - expected)) <= 1e-13 * np.abs(A).max()


def test_a_spatial_tendons_armature_is_refused(tmp_path, capsys):
    path = tmp_path / "spatial.xml"
    path.write_text('<mujoco><worldbody><site name="a" pos="0 0 1"/><body name="b"><joint name="j"/><geom size=".1"/>'
                    '<site name="s" pos="0.3 0 0"/></body></worldbody><tendon><spatial name="rope" armature="0.5">'
                    '<site site="a"/><site site="s"/></spatial></tendon></mujoco>')
    code = cli.main(["generate", str(path), "-o", str(tmp_path / "out"), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and '<tendon name="rope">' in err and "spatial tendon with armature" in err, err
    assert not (tmp_path / "out").exists()
