"""Issue 35, item 4: the generated Python guards its inputs, and one state goes through compiled C.

The NumPy module checks every array argument's last dimension on entry (a ValueError naming the routine, the
argument and the length expected, where a wrong length used to end in a bare IndexError deep inside); the target
``ext`` (``--targets c,numpy,ext``) computes one state per call in the compiled C and hands everything else to the
NumPy module, with the same results.  (Per-call times are the benchmark's, ``benchmarks/runtime/python_call.py``, never
a unit test's.)
"""
from __future__ import annotations

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.codegen.compile import import_module
from aggsym.codegen.generate import generate, write
from aggsym.errors import AggsymError
from conftest import model_path


@pytest.fixture(scope="module")
def pendulum(tmp_path_factory):
    """The double pendulum's C, NumPy module and ext module in one folder: (model, NumPy module, folder)."""
    model = aggsym.load(model_path("double_pendulum"))
    folder = tmp_path_factory.mktemp("pendulum")
    write(generate(model, targets=["c", "numpy", "manifest", "ext"]), folder)
    return model, import_module(folder / f"{model.name}.py"), folder


def test_a_wrong_length_is_a_value_error_naming_the_argument_and_the_length(pendulum):
    _, m, _ = pendulum
    q, qd, tau = np.zeros(3), np.zeros(3), np.zeros(3)
    with pytest.raises(ValueError, match=r"forward_dynamics: q must have 3 entries .*not shape \(2,\)"):
        m.forward_dynamics(q[:2], qd, tau)
    with pytest.raises(ValueError, match=r"forward_dynamics: tau must have 3 entries .*not shape \(4,\)"):
        m.forward_dynamics(q, qd, np.zeros(4))
    with pytest.raises(ValueError, match=r"inverse_dynamics: qdd must have 3 entries .*\(5, 2\)"):
        m.inverse_dynamics(np.zeros((5, 3)), np.zeros((5, 3)), np.zeros((5, 2)))  # a batch of the wrong length
    with pytest.raises(ValueError, match=r"inertia: q must have 3 entries .*not shape \(\)"):
        m.inertia(0.5)  # a number where a vector belongs
    with pytest.raises(ValueError, match=rf"gravity: p must have {len(m.PARAMETERS)} entries"):
        m.gravity(q, m.PARAMETERS[:-1])
    with pytest.raises(ValueError, match=r"q must have 3 entries"):
        m.inertia([])


def test_right_lengths_still_compute_one_state_and_batches_alike(pendulum):
    _, m, _ = pendulum
    rng = np.random.default_rng(3)
    q, qd, tau = rng.standard_normal((3, 4, 3))
    batch = m.forward_dynamics(q, qd, tau)
    for k in range(4):
        assert np.array_equal(m.forward_dynamics(q[k], qd[k], tau[k]), batch[k])
        assert np.array_equal(m.forward_dynamics(list(q[k]), list(qd[k]), list(tau[k])), batch[k])
    p = np.tile(m.PARAMETERS, (4, 1)) * rng.uniform(0.5, 2.0, (4, len(m.PARAMETERS)))
    assert m.gravity(q, p).shape == (4, 3)  # p batched too


@pytest.mark.compiler
def test_the_ext_module_computes_what_the_numpy_module_computes(pendulum):
    model, m, folder = pendulum
    ext = import_module(folder / f"{model.name}_ext.py")
    assert ext.PARAMETERS is m.PARAMETERS or np.array_equal(ext.PARAMETERS, m.PARAMETERS)
    rng = np.random.default_rng(4)
    for _ in range(5):
        q, qd, qdd = rng.standard_normal((3, 3))
        p = m.PARAMETERS * rng.uniform(0.1, 10.0, len(m.PARAMETERS))  # masses and lengths over two decades
        for role, args in (("inertia", (q,)), ("bias", (q, qd)), ("gravity", (q,)), ("inverse_dynamics", (q, qd, qdd)),
                           ("forward_dynamics", (q, qd, qdd)), ("inertia_inverse", (q,)),
                           ("kinetic_energy", (q, qd)), ("potential_energy", (q,)), ("frame_jacobians", (q,))):
            for with_p in ((), (p,)):
                ours, theirs = getattr(ext, role)(*args, *with_p), getattr(m, role)(*args, *with_p)
                assert type(ours) is type(theirs) and np.shape(ours) == np.shape(theirs), role
                np.testing.assert_allclose(ours, theirs, rtol=1e-13, atol=1e-13 * np.max(np.abs(theirs)), err_msg=role)


@pytest.mark.compiler
def test_the_ext_module_hands_batches_lists_other_dtypes_and_wrong_lengths_to_the_numpy_module(pendulum):
    model, m, folder = pendulum
    ext = import_module(folder / f"{model.name}_ext.py")
    rng = np.random.default_rng(5)
    q, qd, tau = rng.standard_normal((3, 6, 3))
    assert np.array_equal(ext.forward_dynamics(q, qd, tau), m.forward_dynamics(q, qd, tau))  # a batch
    np.testing.assert_allclose(ext.forward_dynamics(list(q[0]), list(qd[0]), list(tau[0])),  # lists
                               m.forward_dynamics(q[0], qd[0], tau[0]), rtol=1e-13, atol=1e-13)
    single = ext.forward_dynamics(q[0].astype(np.float32), qd[0], tau[0])  # float32: the NumPy module, in double
    assert single.dtype == np.float64 and single.shape == (3,)
    strided = np.zeros((3, 2))
    strided[:, 0] = q[0]
    np.testing.assert_allclose(ext.inertia(strided[:, 0]), m.inertia(q[0]), rtol=1e-13, atol=1e-13)  # not contiguous
    with pytest.raises(ValueError, match=r"forward_dynamics: qd must have 3 entries"):
        ext.forward_dynamics(q[0], qd[0, :2], tau[0])


def test_the_ext_target_needs_the_c_and_the_numpy_module_beside_it():
    model = aggsym.load(model_path("planar_2link"))
    with pytest.raises(AggsymError, match=r"add c and numpy to --targets"):
        generate(model, targets=["manifest", "ext"])
    with pytest.raises(AggsymError, match=r"--split"):
        generate(model, targets=["c", "numpy", "ext"], split=True)


@pytest.mark.compiler
def test_check_runs_the_ext_target_against_the_twin(capsys):
    assert cli.main(["check", str(model_path("planar_2link")), "--targets", "c,numpy,ext", "--trials", "3"]) == 0
    out = capsys.readouterr().out
    assert "ext" in out and "ok:" in out


def test_the_jax_and_torch_modules_name_a_wrong_length_too(tmp_path):
    import jax
    import torch

    model = aggsym.load(model_path("double_pendulum"))
    write(generate(model, targets=["numpy", "manifest", "jax", "torch"]), tmp_path)
    jm = import_module(tmp_path / f"{model.name}_jax.py")
    tm = import_module(tmp_path / f"{model.name}_torch.py")
    q = np.zeros(3)
    with pytest.raises(ValueError, match=r"inertia: q must have 3 entries .*not shape \(2,\)"):
        jm.inertia(q[:2])
    with pytest.raises(ValueError, match=r"forward_dynamics: tau must have 3 entries .*\(4, 2\)"):
        jax.jit(jm.forward_dynamics)(np.zeros((4, 3)), q, np.zeros((4, 2)))  # (shapes are static under jit)
    with pytest.raises(ValueError, match=r"inertia: q must have 3 entries .*\(2,\)"):
        jax.vmap(jm.inertia)(np.zeros((5, 2)))
    with pytest.raises(ValueError, match=rf"gravity: p must have {len(model.parameters)} entries .*\(3,\)"):
        tm.gravity(torch.zeros(3), torch.zeros(3))
    with pytest.raises(ValueError, match=r"bias: qd must have 3 entries .*\(4,\)"):
        tm.bias(torch.zeros(3), torch.zeros(4))
    assert tuple(jm.inertia(np.zeros((2, 3))).shape) == (2, 3, 3) and tuple(tm.inertia(torch.zeros(3)).shape) == (3, 3)


@pytest.mark.compiler
def test_a_singular_system_raises_in_the_ext_module_as_in_the_numpy_module(tmp_path):
    """The four-bar's constrained forward dynamics with every length zero: J A^-1 J^T is singular, the C returns
    its status, and the ext module's call ends in the NumPy module's LinAlgError; a regular state is computed."""
    from aggsym.contract import select_routines

    model = select_routines(aggsym.load(model_path("four_bar")), ["constrained_forward_dynamics"])
    write(generate(model, targets=["c", "numpy", "manifest", "ext"]), tmp_path)
    m = import_module(tmp_path / f"{model.name}.py")
    ext = import_module(tmp_path / f"{model.name}_ext.py")
    q, zero = np.array([0.3, 0.2, -0.4]), np.zeros(3)
    for got, expected in zip(ext.constrained_forward_dynamics(q, zero, zero), m.constrained_forward_dynamics(q, zero, zero)):
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12 * np.max(np.abs(expected)))
    singular = np.zeros(len(m.PARAMETERS))
    assert not ext._c.constrained_forward_dynamics(q, zero, zero, singular, np.empty(3), np.empty(2))  # the status
    with np.errstate(all="ignore"), pytest.raises(np.linalg.LinAlgError, match="the constraints are singular"):
        ext.constrained_forward_dynamics(q, zero, zero, singular)
