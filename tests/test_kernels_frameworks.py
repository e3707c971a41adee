"""The JAX and PyTorch modules on the batch kernels (issue 51): the same values as the NumPy module, every
transformation (jit, vmap, grad, jacfwd, jacrev, hessian, shard_map; autograd, torch.func, torch.compile), the
derivatives against central differences, a closed form and Pinocchio; the traced modules with AGGSYM_KERNELS=0; the
build's cache and its errors; --no-kernels and the manifest."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

import aggsym
from aggsym.cli import main
from aggsym.codegen.compile import import_module
from aggsym.codegen.generate import generate, write
from aggsym.contract import select_routines
from aggsym.errors import ModelWarning
from helpers import central_differences, robot_path
from jax_support import float64, jax, jnp
from random_trees import random_urdf

ROUTINES = ["inertia", "inertia_inverse", "inverse_dynamics", "forward_dynamics", "inverse_dynamics_derivatives",
            "forward_dynamics_derivatives", "kinetic_energy", "momentum"]


@pytest.fixture(scope="module")
def tree(tmp_path_factory):
    """NumPy, JAX and PyTorch modules (on the kernels) of a random tree on a quaternion free-flyer."""
    import torch

    folder = tmp_path_factory.mktemp("kernels_modules")
    (folder / "tree.urdf").write_text(random_urdf(5, links=6))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = select_routines(aggsym.load(folder / "tree.urdf", floating_base="quaternion",
                                            inertial_parameters="all"), ROUTINES)
    write(generate(model, targets="c,numpy,jax,torch,manifest"), folder)
    npm = import_module(folder / "tree.py")
    jm = import_module(folder / "tree_jax.py")
    tm = import_module(folder / "tree_torch.py")
    assert jm._KERNELS is not None and tm._KERNELS is not None
    return folder, npm, jm, tm, torch


def _state(rng, nq, nv, batch=()):
    q = rng.uniform(-np.pi, np.pi, batch + (nq,)).round(5)
    quat = rng.normal(size=batch + (4,))
    q[..., 3:7] = quat / np.linalg.norm(quat, axis=-1, keepdims=True)
    return q, rng.normal(size=batch + (nv,)), rng.normal(size=batch + (nv,))


def _relative(a, b):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.max(np.abs(a - b)) / max(1.0, float(np.max(np.abs(b)))))


def test_jax_on_the_kernels_equals_the_numpy_module(tree, rng):
    """float64 and float32, a batch of shape (4, 3) with p unbatched, one state, under jit: the NumPy module's
    values (1e-13; float32 1e-4); the jitted function calls the kernel (an ffi_call in its jaxpr)."""
    folder, npm, jm, tm, torch = tree
    q, qd, tau = _state(rng, jm.NQ, jm.NV, (4, 3))
    with float64():
        for role, args in (("forward_dynamics", (q, qd, tau)), ("inverse_dynamics", (q, qd, tau)),
                           ("inertia", (q,)), ("kinetic_energy", (q, qd)), ("momentum", (q, qd))):
            want = getattr(npm, role)(*args)
            got = jax.jit(getattr(jm, role))(*args)
            assert got.dtype == jnp.float64 and got.shape == np.shape(want)
            assert _relative(got, want) < 1e-13, role
            assert _relative(getattr(jm, role)(*(a[1, 2] for a in args)), want[1, 2]) < 1e-13
            assert "ffi_call" in str(jax.make_jaxpr(getattr(jm, role))(*args))
    got = jm.forward_dynamics(*(jnp.asarray(a, jnp.float32) for a in (q, qd, tau)))
    assert got.dtype == jnp.float32
    assert _relative(got, npm.forward_dynamics(q, qd, tau)) < 1e-3


def test_jax_derivatives_on_the_kernels(tree, rng):
    """vmap is one kernel call; jacfwd and jacrev of forward dynamics along q (the quaternion's entries
    included), qd and tau equal each other and central differences of the NumPy module; grad along p (traced)
    equals central differences; the hessian of the kinetic energy along qd is A(q) (second derivatives: traced)."""
    folder, npm, jm, tm, torch = tree
    q, qd, tau = _state(rng, jm.NQ, jm.NV, (5,))
    with float64():
        batched = jax.jit(jax.vmap(jm.forward_dynamics))(q, qd, tau)
        assert _relative(batched, jm.forward_dynamics(q, qd, tau)) == 0.0
        for k, x in enumerate((q[0], qd[0], tau[0])):
            args = [q[0], qd[0], tau[0]]
            fwd = jax.jit(jax.jacfwd(jm.forward_dynamics, k))(*args)
            rev = jax.jit(jax.jacrev(jm.forward_dynamics, k))(*args)
            cd = central_differences(lambda v, k=k: npm.forward_dynamics(*[v if j == k else a
                                                                          for j, a in enumerate(args)]), x)
            assert _relative(fwd, rev) < 1e-12
            assert _relative(fwd, cd) < 1e-6, k
        p = np.asarray(jm.PARAMETERS)
        g = jax.grad(lambda p: jnp.sum(jm.forward_dynamics(q[0], qd[0], tau[0], p) ** 2))(p)
        i = int(np.argmax(np.abs(g)))
        e = np.zeros_like(p)
        e[i] = 1e-6 * max(1.0, abs(p[i]))
        f = lambda p: np.sum(npm.forward_dynamics(q[0], qd[0], tau[0], p) ** 2)  # noqa: E731
        assert abs(g[i] - (f(p + e) - f(p - e)) / (2 * e[i])) < 1e-5 * max(1.0, abs(g[i]))
        h = jax.hessian(jm.kinetic_energy, 1)(q[0], qd[0])
        assert _relative(h, npm.inertia(q[0])) < 1e-12


def test_jax_traced_without_the_kernels_and_shard_map(tree, rng, tmp_path):
    """AGGSYM_KERNELS=0: the module traces its straight lines (no ffi_call), the same values; with two host
    devices, shard_map over the batch runs the kernel on each device's half, the values of one call."""
    folder, npm, jm, tm, torch = tree
    q, qd, tau = _state(rng, jm.NQ, jm.NV, (8,))
    np.save(tmp_path / "q.npy", q)
    np.save(tmp_path / "qd.npy", qd)
    np.save(tmp_path / "tau.npy", tau)
    np.save(tmp_path / "want.npy", npm.forward_dynamics(q, qd, tau))
    common = f"""
        import sys, numpy as np, jax, jax.numpy as jnp
        jax.config.update("jax_enable_x64", True)
        sys.path.insert(0, {str(folder)!r})
        import tree_jax as m
        q, qd, tau, want = (np.load({str(tmp_path)!r} + f"/{{x}}.npy") for x in ("q", "qd", "tau", "want"))
    """
    traced = common + """
        assert m._KERNELS is None
        assert "ffi_call" not in str(jax.make_jaxpr(m.forward_dynamics)(q, qd, tau))
        assert np.max(np.abs(m.forward_dynamics(q, qd, tau) - want)) < 1e-12 * max(1.0, np.abs(want).max())
    """
    sharded = common + """
        from jax.sharding import Mesh, PartitionSpec as P
        assert len(jax.devices()) == 2 and m._KERNELS is not None
        mesh = Mesh(np.array(jax.devices()), ("b",))
        shard_map = getattr(jax, "shard_map", None)
        if shard_map is None:
            from jax.experimental.shard_map import shard_map
        f = jax.jit(shard_map(m.forward_dynamics, mesh=mesh, in_specs=(P("b"), P("b"), P("b")), out_specs=P("b")))
        got = f(q, qd, tau)
        assert len(got.sharding.device_set) == 2
        assert np.max(np.abs(got - want)) < 1e-12 * max(1.0, np.abs(want).max())
    """
    for script, env in ((traced, {"AGGSYM_KERNELS": "0"}),
                        (sharded, {"XLA_FLAGS": "--xla_force_host_platform_device_count=2"})):
        run = subprocess.run([sys.executable, "-c", textwrap.dedent(script)], env={**os.environ, **env},
                             capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, run.stderr[-3000:]


def test_torch_on_the_kernels(tree, rng):
    """float64 and float32 values (a broadcast batch); torch.func.jacrev and jacfwd of forward dynamics under vmap
    equal central differences; autograd along p equals central differences; torch.compile gives the same values."""
    folder, npm, jm, tm, torch = tree
    q, qd, tau = _state(rng, tm.NQ, tm.NV, (3, 2))
    T = lambda x: torch.tensor(x, dtype=torch.float64)  # noqa: E731
    for role, args in (("forward_dynamics", (q, qd, tau)), ("inertia", (q,)), ("kinetic_energy", (q, qd))):
        want = getattr(npm, role)(*args)
        got = getattr(tm, role)(*map(T, args))
        assert got.dtype == torch.float64 and _relative(got, want) < 1e-13, role
        single = getattr(tm, role)(*(T(a).float() for a in args))
        assert single.dtype == torch.float32 and _relative(single, want) < 1e-3
    x = [T(a[0, 0]) for a in (q, qd, tau)]
    for jac in (torch.func.jacrev, torch.func.jacfwd):
        got = torch.func.vmap(jac(tm.forward_dynamics, argnums=(0, 1, 2)))(*[T(a[:, 0]) for a in (q, qd, tau)])
        for k in range(3):
            args = [a[0, 0] for a in (q, qd, tau)]
            cd = central_differences(lambda v, k=k: npm.forward_dynamics(*[v if j == k else a
                                                                          for j, a in enumerate(args)]), args[k])
            assert _relative(got[k][0].numpy(), cd) < 1e-6
    p = T(np.asarray(npm.PARAMETERS)).requires_grad_()
    (tm.forward_dynamics(*x, p) ** 2).sum().backward()
    i = int(torch.argmax(p.grad.abs()))
    P = np.asarray(npm.PARAMETERS)
    e = np.zeros_like(P)
    e[i] = 1e-6 * max(1.0, abs(P[i]))
    f = lambda p: np.sum(npm.forward_dynamics(q[0, 0], qd[0, 0], tau[0, 0], p) ** 2)  # noqa: E731
    assert abs(float(p.grad[i]) - (f(P + e) - f(P - e)) / (2 * e[i])) < 1e-5 * max(1.0, abs(float(p.grad[i])))
    compiled = torch.compile(tm.forward_dynamics)
    assert _relative(compiled(*map(T, (q, qd, tau))), npm.forward_dynamics(q, qd, tau)) < 1e-13


def test_torch_kernel_outputs_reuse_no_block_still_held(tree, rng):
    """Large outputs come from the module's pool of blocks: a block is handed out again only once nothing holds it
    (the tensor, a view of it, autograd's saved tensors), so earlier results never change; a call with no derivative
    asked skips the autograd.Function, one under torch.func.jvp (no batch) still takes its derivatives."""
    folder, npm, jm, tm, torch = tree
    n = 1 + tm._POOLED // (8 * tm.NV * tm.NV)  # states whose A(q) is a pooled block
    T = lambda x: torch.tensor(x, dtype=torch.float64)  # noqa: E731
    qs = [_state(rng, tm.NQ, tm.NV, (n,))[0] for _ in range(4)]
    first = tm.inertia(T(qs[0]))
    view = tm.inertia(T(qs[1]))[5:, 1:3]  # the tensor dropped, a view of it kept
    q2 = T(qs[2]).requires_grad_()
    w = tm.inertia(q2)
    loss = (w * w).sum()  # autograd keeps w
    del w
    held = {first.data_ptr(), view.untyped_storage().data_ptr()}
    again = tm.inertia(T(qs[3]))
    assert again.data_ptr() not in held
    assert _relative(first, npm.inertia(qs[0])) < 1e-13
    assert _relative(view, npm.inertia(qs[1])[5:, 1:3]) < 1e-13
    loss.backward()
    grad = q2.grad.clone()
    q2.grad = None
    w = tm.inertia(q2)
    (w * w).sum().backward()
    assert torch.equal(q2.grad, grad)
    before = again.data_ptr()
    del again
    assert tm.inertia(T(qs[3])).data_ptr() == before  # the freed block serves the next call of its size
    q, qd, tau = _state(rng, tm.NQ, tm.NV)
    e = np.zeros(tm.NV)
    e[-1] = 1.0
    tangent = torch.func.jvp(lambda v: tm.forward_dynamics(T(q), v, T(tau)), (T(qd),), (T(e),))[1]
    cd = central_differences(lambda v: npm.forward_dynamics(q, v, tau), qd)
    assert _relative(tangent.numpy(), cd[:, -1]) < 1e-6


def test_torch_forward_mode_levels_on_the_kernels(tree, rng):
    """torch.autograd.forward_ad (a dual level, no torch.func transform): the derivatives along qd (the analytic
    Function), along p (the traced routine, by two reverse passes: torch.func.jvp cannot open a second level) and
    of a routine without derivative routines (its kernel's jvp) equal central differences."""
    import torch.autograd.forward_ad as fwAD

    folder, npm, jm, tm, torch = tree
    T = lambda x: torch.tensor(x, dtype=torch.float64)  # noqa: E731
    q, qd, tau = _state(rng, tm.NQ, tm.NV)
    P = np.asarray(npm.PARAMETERS)
    dqd, dp = rng.normal(size=tm.NV), rng.normal(size=P.size) * np.maximum(np.abs(P), 1e-3)
    h = 1e-6

    def along(f, x, dx):
        return (np.asarray(f(x + h * dx)) - np.asarray(f(x - h * dx))) / (2 * h)

    with fwAD.dual_level():
        out = tm.forward_dynamics(T(q), fwAD.make_dual(T(qd), T(dqd)), T(tau))
        by_qd = fwAD.unpack_dual(out).tangent
        out = tm.forward_dynamics(T(q), T(qd), T(tau), fwAD.make_dual(T(P), T(dp)))
        by_p = fwAD.unpack_dual(out).tangent
        energy = fwAD.unpack_dual(tm.kinetic_energy(T(q), fwAD.make_dual(T(qd), T(dqd)))).tangent
    assert _relative(by_qd.numpy(), along(lambda v: npm.forward_dynamics(q, v, tau), qd, dqd)) < 1e-6
    assert _relative(by_p.numpy(), along(lambda v: npm.forward_dynamics(q, qd, tau, v), P, dp)) < 1e-6
    assert _relative(energy.numpy(), along(lambda v: npm.kinetic_energy(q, v), qd, dqd)) < 1e-6


@pytest.mark.pinocchio
@pytest.mark.slow
def test_kernel_jacobians_of_a_robot_equal_pinocchio(tmp_path, rng):
    """Panda (fixed base) with --targets c,jax,torch: jacfwd and jacrev of forward dynamics (JAX) and
    torch.func.jacrev equal Pinocchio's computeABADerivatives to 1e-9."""
    from pinocchio_reference import pin, pinocchio_model, pinocchio_q

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = select_routines(aggsym.load(robot_path("panda")), ROUTINES[:6])
    write(generate(model, targets="c,numpy,jax,torch,manifest"), tmp_path)
    jm = import_module(tmp_path / f"{model.name}_jax.py")
    tm = import_module(tmp_path / f"{model.name}_torch.py")
    import torch

    pm = pinocchio_model(robot_path("panda"))
    n = jm.NV
    q, v, tau = rng.uniform(-1.5, 1.5, n).round(5), rng.normal(size=n), rng.normal(size=n)
    data = pm.createData()
    aba = [x.copy() for x in pin.computeABADerivatives(pm, data, pinocchio_q(pm, q), v, tau)[:3]]
    aba[2] = np.triu(aba[2]) + np.triu(aba[2], 1).T
    with float64():
        for jac in (jax.jacfwd, jax.jacrev):
            for ours, theirs in zip(jax.jit(jac(jm.forward_dynamics, (0, 1, 2)))(q, v, tau), aba):
                assert _relative(ours, theirs) < 1e-9
    T = lambda x: torch.tensor(x, dtype=torch.float64)  # noqa: E731
    for ours, theirs in zip(torch.func.jacrev(tm.forward_dynamics, argnums=(0, 1, 2))(T(q), T(v), T(tau)), aba):
        assert _relative(ours.numpy(), theirs) < 1e-9


def test_cache_errors_no_kernels_and_the_manifest(tmp_path):
    """A second process loads the cached library without compiling; a missing C compiler is an ImportError naming
    CC and the ways to the traced modules; --no-kernels writes no kernel files; the manifest lists the kernels, the
    modules that use them and the flags."""
    from conftest import model_path

    out = tmp_path / "gen"
    assert main(["generate", str(model_path("double_pendulum")), "-o", str(out), "-q", "--targets",
                 "c,numpy,jax,manifest"]) == 0
    manifest = json.loads((out / "double_pendulum.json").read_text())
    assert manifest["kernels"]["used_by"] == ["double_pendulum_jax.py"]
    assert "-march=native" in manifest["kernels"]["flags"] and "forward_dynamics" in manifest["kernels"]["routines"]
    script = f"import sys; sys.path.insert(0, {str(out)!r}); import double_pendulum_jax as m; assert m._KERNELS"
    first = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert first.returncode == 0 and "compiling" in first.stderr, first.stderr
    second = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert second.returncode == 0 and "compiling" not in second.stderr, second.stderr
    env = {**os.environ, "CC": str(tmp_path / "no-such-cc"), "AGGSYM_KERNEL_CACHE": str(tmp_path / "cache")}
    broken = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=600)
    assert broken.returncode != 0
    assert "ImportError" in broken.stderr or "KernelError" in broken.stderr
    for words in ("C compiler", "CC", "AGGSYM_KERNELS=0", "--no-kernels"):
        assert words in broken.stderr
    plain = tmp_path / "plain"
    assert main(["generate", str(model_path("double_pendulum")), "-o", str(plain), "-q", "--targets",
                 "c,numpy,jax,manifest", "--no-kernels"]) == 0
    assert not list(plain.glob("*kernels*"))
    assert "kernels" not in json.loads((plain / "double_pendulum.json").read_text())


def test_check_has_a_column_per_kernel_module_and_precision(capsys):
    """aggsym check --targets c,numpy,jax,torch: the traced modules' columns and the kernels' (JAX and PyTorch, float64
    and float32), and the derivative rows against central differences."""
    from conftest import model_path

    assert main(["check", str(model_path("double_pendulum")), "--targets", "c,numpy,jax,torch", "--trials", "2"]) == 0
    out = capsys.readouterr().out
    for heading in ("JAX k64", "JAX k32", "torch k64", "torch k32", "d forward_dynamics", "d inverse_dynamics"):
        assert heading in out
    assert "ok: every routine within its bound" in out


def test_the_readmes_batched_snippet_runs(tmp_path):
    """The README's JAX snippet (on the kernels), against arm3 generated as its comment says."""
    import re

    from conftest import ROOT

    snippet = next(s for s in re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
                   if "arm3_jax" in s)
    command = re.search(r"# aggsym generate (.*)\n", snippet).group(1).split()
    folder = tmp_path / "build" / "arm3"
    assert main(["generate", str(ROOT / "models" / "arm3.urdf"), "--targets", "c,numpy,jax", "-o", str(folder),
                 "-q"]) == 0
    assert command == ["models/arm3.urdf", "--targets", "c,numpy,jax", "-o", "build/arm3"]
    run = subprocess.run([sys.executable, "-c", snippet + "\nprint(qdd.shape, A.shape, dqdd_dq.shape)"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "(4096, 3) (4096, 3, 3) (4096, 3, 3)" in run.stdout


@pytest.mark.parametrize("option", [{"split": True}, {"scalar": "float"}])
def test_the_kernels_go_with_any_layout_and_scalar_of_the_c(option):
    """--split and --scalar float change the one-state C, not the kernels: the same three files, the same text."""
    from conftest import model_path

    model = aggsym.load(model_path("double_pendulum"))
    plain = generate(model, targets="c,numpy,jax,manifest").files
    other = generate(model, targets="c,numpy,jax,manifest", **option).files
    for name in ("double_pendulum_kernels.c", "double_pendulum_kernels_jax.cc", "double_pendulum_kernels.py"):
        assert other[name] == plain[name]
