"""A two-link arm swung up from hanging to upright by direct multiple shooting in casadi.Opti with IPOPT.

    python examples/casadi_swing_up.py [--intervals 60] [--horizon 2.5] [--torque 6] [--folder DIR]

The arm is models/planar_2link.yaml (Tokad's planar two-link arm, gravity along -y; theta1 = -pi/2 hangs down).
The example generates its CasADi module itself (``aggsym.load`` and ``aggsym.generate`` with ``--targets casadi``
and the derivative routines, into a temporary folder unless --folder), so that IPOPT's constraint Jacobians along
q and qd are aggsym's forward_dynamics_derivatives (the Function's custom Jacobian) and along tau A^-1.

Direct multiple shooting: the state x = (q, qd) at N + 1 nodes, the torque u piecewise constant on N intervals,
one RK4 step of forward_dynamics per interval as an equality constraint; |u_i| <= the torque bound (below the
8.4 N m that holds the arm out horizontally, so it must swing), minimise the integral of |u|^2.  Prints IPOPT's
iterations, its return status (Solve_Succeeded) and the times; writes casadi_swing_up.png into the current folder
(with matplotlib installed).
"""
from __future__ import annotations

import argparse
import importlib.util
import math
import tempfile
import time
from pathlib import Path

import casadi as ca

import aggsym
from aggsym.codegen.generate import write

MODEL = Path(__file__).resolve().parent.parent / "models" / "planar_2link.yaml"
ROUTINES = ["default", "inverse_dynamics_derivatives", "forward_dynamics_derivatives"]


def casadi_module(folder: Path):
    """The arm's generated CasADi module (planar_2link_casadi.py written into ``folder`` and imported)."""
    model = aggsym.load(MODEL, routines=ROUTINES)
    write(aggsym.generate(model, targets="casadi,manifest"), folder)
    path = folder / f"{model.name}_casadi.py"
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def rk4(fd, p, x, u, dt):
    """One RK4 step of x' = (qd, forward_dynamics(q, qd, u, p)) (x = (q, qd))."""
    n = x.shape[0] // 2

    def f(x):
        return ca.vertcat(x[n:], fd(x[:n], x[n:], u, p))
    k1 = f(x)
    k2 = f(x + dt / 2 * k1)
    k3 = f(x + dt / 2 * k2)
    k4 = f(x + dt * k3)
    return x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def swing_up(module, intervals: int, horizon: float, torque: float):
    """(the solution's times, states, torques, IPOPT's stats) of the swing-up."""
    fd, p, n = module.forward_dynamics, module.PARAMETERS, module.NQ
    dt = horizon / intervals
    opti = ca.Opti()
    X = opti.variable(2 * n, intervals + 1)
    U = opti.variable(n, intervals)
    start = ca.DM([-math.pi / 2, 0.0] + [0.0] * n)
    goal = ca.DM([math.pi / 2, 0.0] + [0.0] * n)
    opti.subject_to(X[:, 0] == start)
    opti.subject_to(X[:, -1] == goal)
    for k in range(intervals):
        opti.subject_to(X[:, k + 1] == rk4(fd, p, X[:, k], U[:, k], dt))
    opti.subject_to(opti.bounded(-torque, ca.vec(U), torque))
    opti.minimize(dt * ca.sumsqr(U))
    for k in range(intervals + 1):  # the initial guess: the angles interpolated, at rest
        opti.set_initial(X[:, k], start + (goal - start) * k / intervals)
    opti.solver("ipopt", {"print_time": True}, {"max_iter": 500, "print_level": 5})
    solution = opti.solve()
    times = [k * dt for k in range(intervals + 1)]
    return times, solution.value(X), solution.value(U), opti.stats()


def plot(times, X, U, path: Path) -> bool:
    """The trajectory's angles, rates and torques drawn into ``path``; False where matplotlib is not installed."""
    try:
        import matplotlib
    except ImportError:
        return False

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = U.shape[0]
    fig, axes = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    for i in range(n):
        axes[0].plot(times, X[i], label=f"q{i + 1}")
        axes[1].plot(times, X[n + i], label=f"qd{i + 1}")
        axes[2].step(times[:-1], U[i], where="post", label=f"tau{i + 1}")
    for ax, label in zip(axes, ("angle (rad)", "rate (rad/s)", "torque (N m)")):
        ax.set_ylabel(label)
        ax.legend(loc="upper right")
        ax.grid(True, alpha=0.3)
    axes[2].set_xlabel("time (s)")
    fig.suptitle("planar_2link swung up: direct multiple shooting, RK4, IPOPT")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    return True


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--intervals", type=int, default=60)
    parser.add_argument("--horizon", type=float, default=2.5, help="seconds")
    parser.add_argument("--torque", type=float, default=6.0, help="the bound on each joint's torque, N m")
    parser.add_argument("--folder", type=Path, help="where to write the generated module (default: a temporary one)")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.folder or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        module = casadi_module(folder)
        generated = time.perf_counter() - start
        times, X, U, stats = swing_up(module, args.intervals, args.horizon, args.torque)
    solved = time.perf_counter() - start - generated
    print(f"generated the CasADi module in {generated:.2f} s; built and solved the NLP in {solved:.2f} s "
          f"(IPOPT: {stats['iter_count']} iterations, {stats['t_wall_total']:.2f} s wall)")
    print(f"return status: {stats['return_status']}")
    print(f"largest torque {abs(U).max():.3f} N m of {args.torque} N m; final state {X[:, -1].round(6).tolist()}")
    path = Path.cwd() / "casadi_swing_up.png"
    if plot(times, X, U, path):
        print(f"wrote {path}")
    else:
        print("no plot: matplotlib is not installed (pip install matplotlib)")
    return 0 if stats["success"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
