"""B Panda arms simulated for one second with jax.lax.scan (semi-implicit Euler), timed: compile, then run.

    python examples/jax_simulate.py [--batch 4096] [--steps 1000] [--robot panda] [--folder DIR]

Every arm starts at its own random state with zero torque (the arms fall under gravity); a step is
qd += dt * forward_dynamics(q, qd, 0), q += dt * qd, dt = 1 s / steps, all arms at once.  float64 (jax's x64 mode).
Prints the compile time and the run time (µs per arm and step); ``--check`` also steps the NumPy module the same way
and prints the largest difference (the test runs it small)."""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)  # (the example's choice; the generated module never sets it)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from robots import module  # noqa: E402


def simulate(fd, q, qd, steps: int, dt: float):
    """(q, qd) after ``steps`` semi-implicit Euler steps of ``fd`` with zero torque, by jax.lax.scan."""
    tau = jnp.zeros_like(qd)

    def step(state, _):
        q, qd = state
        qd = qd + dt * fd(q, qd, tau)
        return (q + dt * qd, qd), None
    return jax.lax.scan(step, (q, qd), None, length=steps)[0]


def simulate_numpy(fd, q, qd, steps: int, dt: float):
    tau = np.zeros_like(qd)
    for _ in range(steps):
        qd = qd + dt * fd(q, qd, tau)
        q = q + dt * qd
    return q, qd


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=4096)
    parser.add_argument("--steps", type=int, default=1000, help="steps in one second (default 1000: dt = 1 ms)")
    parser.add_argument("--robot", default="panda")
    parser.add_argument("--folder", default=str(Path(__file__).resolve().parent / "generated"))
    parser.add_argument("--check", action="store_true", help="also step the NumPy module and compare")
    args = parser.parse_args(argv)
    npm, jm = module(args.robot, Path(args.folder) / args.robot, "forward_dynamics")
    rng = np.random.default_rng(0)
    q0 = rng.uniform(-1.0, 1.0, (args.batch, jm.NQ)) * 0.5
    qd0 = rng.normal(size=(args.batch, jm.NV)) * 0.1
    dt = 1.0 / args.steps
    run = jax.jit(lambda q, qd: simulate(jm.forward_dynamics, q, qd, args.steps, dt))
    t0 = time.perf_counter()
    compiled = run.lower(jnp.asarray(q0), jnp.asarray(qd0)).compile()
    t1 = time.perf_counter()
    q, qd = jax.block_until_ready(compiled(jnp.asarray(q0), jnp.asarray(qd0)))
    t2 = time.perf_counter()
    print(f"{args.robot}: {args.batch} arms, {args.steps} steps of {dt * 1e3:g} ms: compile {t1 - t0:.2f} s, "
          f"run {t2 - t1:.3f} s ({(t2 - t1) / (args.batch * args.steps) * 1e6:.3f} µs per arm and step) "
          f"on {jax.devices()[0].platform}")
    out = {"q": np.asarray(q), "qd": np.asarray(qd), "compile": t1 - t0, "run": t2 - t1}
    if args.check:
        qn, qdn = simulate_numpy(npm.forward_dynamics, q0, qd0, args.steps, dt)
        out["difference"] = max(float(np.max(np.abs(out["q"] - qn))), float(np.max(np.abs(out["qd"] - qdn))))
        print(f"largest difference from the NumPy module stepped the same way: {out['difference']:.2e}")
    return out


if __name__ == "__main__":
    main()
