"""Fitting an arm's inertial parameters to noisy torques with jax.grad.

    python examples/jax_fit_inertia.py [--samples 2000] [--robot ur5] [--noise 0.05] [--folder DIR]

The arm is generated with ``--inertial-parameters all`` (ten parameters per link in p: m, m c, the inertia about
the link origin) and inverse dynamics alone.  Torques are measured at random states (q, qd, qdd) with the file's
parameters plus Gaussian noise; the fit starts from parameters scaled by random factors in [0.5, 1.5] and
minimizes the mean squared torque error.  tau is linear in p, so the loss is quadratic: Newton's step, with the
gradient from jax.grad and its Jacobian (jax.jacfwd of the gradient), solved in the least-squares sense (some
parameter combinations do not act on tau: they stay where they started), converges in one step; a second shows it.
Prints the RMS torque error before and after, against the noise, and the error on fresh states."""
from __future__ import annotations

import argparse
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)  # (the example's choice; the generated module never sets it)
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from robots import module  # noqa: E402


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=2000)
    parser.add_argument("--robot", default="ur5")
    parser.add_argument("--noise", type=float, default=0.05, help="torque noise, N m (default 0.05)")
    parser.add_argument("--folder", default=str(Path(__file__).resolve().parent / "generated"))
    args = parser.parse_args(argv)
    npm, jm = module(args.robot, Path(args.folder) / f"{args.robot}_inertial", "inverse_dynamics",
                     "--inertial-parameters", "all")
    rng = np.random.default_rng(1)
    n = jm.NV

    def states(count):
        return rng.uniform(-np.pi, np.pi, (count, n)), rng.normal(size=(count, n)), rng.normal(size=(count, n))
    q, qd, qdd = states(args.samples)
    p_true = np.asarray(jm.PARAMETERS)
    tau = npm.inverse_dynamics(q, qd, qdd) + args.noise * rng.normal(size=(args.samples, n))
    p0 = p_true * rng.uniform(0.5, 1.5, p_true.shape)

    def loss(p):
        return jnp.mean((jm.inverse_dynamics(q, qd, qdd, p) - tau) ** 2)
    gradient = jax.jit(jax.grad(loss))
    hessian = jax.jit(jax.jacfwd(jax.grad(loss)))
    rms = [float(jnp.sqrt(loss(p0) * 1.0))]
    p = jnp.asarray(p0)
    for _ in range(2):
        p = p - jnp.linalg.lstsq(hessian(p), gradient(p), rcond=1e-10)[0]
        rms.append(float(jnp.sqrt(loss(p))))
    q2, qd2, qdd2 = states(200)
    fresh = float(np.sqrt(np.mean((npm.inverse_dynamics(q2, qd2, qdd2, np.asarray(p))
                                   - npm.inverse_dynamics(q2, qd2, qdd2)) ** 2)))
    print(f"{args.robot}: {p_true.size} inertial parameters, {args.samples} noisy torques (noise {args.noise:g} N m)")
    print(f"RMS torque error: start {rms[0]:.3g}, after one Newton step {rms[1]:.4g}, after two {rms[2]:.4g} N m")
    print(f"on 200 fresh states, the fitted parameters' torques differ from the true ones by {fresh:.3g} N m (RMS)")
    return {"rms": rms, "fresh": fresh, "noise": args.noise, "p": np.asarray(p), "p_true": p_true}


if __name__ == "__main__":
    main()
