"""The JAX module sharded (issue 32, item 2): a batch split across two CPU devices (forced host devices, in a
subprocess: the device count is fixed when jax starts) with jax.sharding gives the unsharded result, and the
result stays split across both devices; also with the routines cut into segments (conditionals in the program)."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

import aggsym
from aggsym.codegen.targets import jax_segments
from conftest import ROOT, model_path
from jax_support import modules

SCRIPT = textwrap.dedent("""
    import sys
    import jax
    jax.config.update("jax_enable_x64", True)
    import numpy as np
    from jax.sharding import Mesh, NamedSharding, PartitionSpec
    sys.path.insert(0, sys.argv[1])
    import planar_2link_jax as m
    import planar_2link as ref
    assert len(jax.devices()) == 2, jax.devices()
    assert hasattr(m, "_forward_dynamics__2") == (sys.argv[2] == "cut")
    rng = np.random.default_rng(0)
    q, qd, tau = (rng.normal(size=(64, 2)) for _ in range(3))
    mesh = Mesh(np.array(jax.devices()), ("batch",))
    split = NamedSharding(mesh, PartitionSpec("batch"))
    args = [jax.device_put(x, split) for x in (q, qd, tau)]
    out = jax.jit(m.forward_dynamics)(*args)
    assert len(out.sharding.device_set) == 2, out.sharding
    assert {s.data.shape for s in out.addressable_shards} == {(32, 2)}
    whole = m.forward_dynamics(q, qd, tau)
    assert np.max(np.abs(np.asarray(out) - np.asarray(whole))) <= 1e-12 * np.max(np.abs(np.asarray(whole)))
    assert np.max(np.abs(np.asarray(out) - ref.forward_dynamics(q, qd, tau))) <= 1e-12 * np.max(np.abs(whole))
    A = jax.jit(m.inertia)(args[0])
    assert len(A.sharding.device_set) == 2 and np.allclose(np.asarray(A), ref.inertia(q), rtol=1e-12, atol=0)
    print("sharded ok")
""")


@pytest.mark.parametrize("form", ["whole", "cut"])
def test_a_batch_split_across_two_devices_gives_the_unsharded_result(tmp_path, form, monkeypatch):
    if form == "cut":
        monkeypatch.setattr(jax_segments, "SEGMENT", 5)
        monkeypatch.setattr(jax_segments, "SEGMENTED", 10)
    modules(aggsym.load(model_path("planar_2link")), tmp_path)
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=2", "JAX_PLATFORMS": "cpu"}
    proc = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path), form], capture_output=True, text=True,
                          env=env, cwd=ROOT, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "sharded ok"
