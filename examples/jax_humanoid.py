"""A humanoid's forward dynamics and its Jacobian on 1024 states at once, on the batch kernels, timed.

    python examples/jax_humanoid.py [--batch 1024] [--robot talos] [--folder DIR] [--threads N]

Talos (example-robot-data's reduced model, 32 joints) on a quaternion free-flyer (nq = 39, nv = 38) is generated with
its forward dynamics derivatives (``aggsym generate --targets c,numpy,jax --floating-base quaternion``): the JAX
module calls the batch kernels (NAME_kernels.c, compiled once on the first import: about two minutes for Talos,
then cached).  Prints the build, each first call (the jit) and the µs per state of forward dynamics, of its
Jacobian along (q, qd) by jax.jacfwd and by jax.jacrev, and the largest difference from the NumPy module and from
its central differences on the first state (relative to the largest entry)."""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)  # (the example's choice; the generated module never sets it)
import numpy as np  # noqa: E402

from robots import module  # noqa: E402

ROUTINES = "inertia,inertia_inverse,forward_dynamics,forward_dynamics_derivatives"


def timed(f, *args, repeats: int = 5):
    """(first call's seconds, best of ``repeats`` later calls' seconds, the result)."""
    t0 = time.perf_counter()
    out = jax.block_until_ready(f(*args))
    first = time.perf_counter() - t0
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(f(*args))
        best = min(best, time.perf_counter() - t0)
    return first, best, out


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=1024)
    parser.add_argument("--robot", default="talos")
    parser.add_argument("--folder", default=str(Path(__file__).resolve().parent / "generated"))
    parser.add_argument("--threads", type=int, default=None, help="the kernels' threads (default: every core)")
    args = parser.parse_args(argv)
    if args.threads:
        os.environ["AGGSYM_THREADS"] = str(args.threads)
    t0 = time.perf_counter()
    npm, jm = module(args.robot, Path(args.folder) / f"{args.robot}_ff", ROUTINES, "--floating-base", "quaternion")
    print(f"{args.robot}: nq = {jm.NQ}, nv = {jm.NV}; generated (or found) and built in "
          f"{time.perf_counter() - t0:.1f} s"
          f" ({'on the batch kernels' if jm._KERNELS is not None else 'traced: AGGSYM_KERNELS=0'})")
    rng = np.random.default_rng(0)
    n = args.batch
    quat = rng.normal(size=(n, 4))
    q = np.hstack([rng.uniform(-1, 1, (n, 3)), quat / np.linalg.norm(quat, axis=1, keepdims=True),
                   rng.uniform(-1.0, 1.0, (n, jm.NQ - 7))])
    qd, tau = rng.normal(size=(n, jm.NV)), rng.normal(size=(n, jm.NV)) * 10
    fd = jax.jit(jm.forward_dynamics)
    jac = {name: jax.jit(jax.vmap(how(jm.forward_dynamics, argnums=(0, 1))))
           for name, how in (("jacfwd", jax.jacfwd), ("jacrev", jax.jacrev))}
    out = {}
    first, best, qdd = timed(fd, q, qd, tau)
    out["forward_dynamics"] = (first, best / n * 1e6)
    print(f"forward dynamics: first call {first:.2f} s, {best / n * 1e6:.3f} µs per state")
    want = npm.forward_dynamics(q, qd, tau)
    difference = float(np.max(np.abs(np.asarray(qdd) - want)) / max(1.0, float(np.max(np.abs(want)))))
    for name, f in jac.items():
        first, best, (dq, dv) = timed(f, q, qd, tau)
        out[name] = (first, best / n * 1e6)
        print(f"Jacobian of forward dynamics by {name}: first call {first:.2f} s, {best / n * 1e6:.2f} µs per state")
    h, k = 1e-6, jm.NQ - 1  # (a joint's column by central differences of the NumPy module, on the first state)
    e = np.zeros(jm.NQ)
    e[k] = h
    cd = (npm.forward_dynamics(q[0] + e, qd[0], tau[0]) - npm.forward_dynamics(q[0] - e, qd[0], tau[0])) / (2 * h)
    out["difference"] = difference
    scale = max(1.0, float(np.max(np.abs(cd))))
    out["central_differences"] = float(np.max(np.abs(np.asarray(dq)[0][:, k] - cd)) / scale)
    print(f"largest difference from the NumPy module {difference:.1e}, a column of the Jacobian from central "
          f"differences {out['central_differences']:.1e} (relative to the largest entry)")
    return out


if __name__ == "__main__":
    main()
