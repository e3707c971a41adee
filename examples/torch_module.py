"""A policy for the Panda arm trained by backpropagation through its simulated motion: aggsym's PyTorch forward
dynamics inside a ``torch.nn.Module``.

The arm's forward dynamics is generated (``aggsym generate panda.urdf --targets torch --routines
forward_dynamics,forward_dynamics_derivatives,inertia_inverse``) and wrapped as a module whose parameters p are a
buffer (or, with ``learn_parameters``, a ``torch.nn.Parameter``).  A small network adds torques to a PD law; a batch
of arms starting from random states is simulated with semi-implicit Euler, and the network is trained to bring them
to a target configuration and stop there: the gradients through every step go through the generated derivatives
(the autograd.Function of ``forward_dynamics``).

    python examples/torch_module.py                          # 1024 arms, 50 steps of 10 ms, 20 iterations
    python examples/torch_module.py --batch 8 --steps 5 --iterations 2
    python examples/torch_module.py --model models/planar_3link.yaml --device cuda

Needs torch and, for the default model, the package example-robot-data (the Panda URDF).
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import torch

import aggsym
from aggsym.codegen.compile import import_module
from aggsym.codegen.generate import generate, write
from aggsym.contract import select_routines

ROUTINES = ["forward_dynamics", "forward_dynamics_derivatives", "inertia_inverse"]


def panda_urdf() -> Path:
    """The Panda URDF of the installed example-robot-data."""
    from importlib import metadata

    dist = metadata.distribution("example-robot-data")
    for f in dist.files or ():
        if f.as_posix().endswith("panda_description/urdf/panda.urdf"):
            return Path(dist.locate_file(f))
    raise FileNotFoundError("example-robot-data has no panda_description/urdf/panda.urdf")


def generated_module(model_file, folder):
    """The PyTorch module of a model's forward dynamics and its derivatives, generated into ``folder``."""
    model = select_routines(aggsym.load(model_file), ROUTINES)
    write(generate(model, targets="c,torch,manifest"), folder)  # (with c: on the batch kernels)
    return import_module(Path(folder) / f"{model.name}_torch.py")


class ForwardDynamics(torch.nn.Module):
    """qdd = forward_dynamics(q, qd, tau, p) of a generated PyTorch module; p a buffer (it follows ``.to(device,
    dtype)``) or, with ``learn_parameters``, a Parameter (system identification)."""

    def __init__(self, generated, learn_parameters: bool = False):
        super().__init__()
        self.generated = generated
        p = generated.PARAMETERS.clone()
        if learn_parameters:
            self.p = torch.nn.Parameter(p)
        else:
            self.register_buffer("p", p)

    def forward(self, q, qd, tau):
        return self.generated.forward_dynamics(q, qd, tau, self.p)


class Policy(torch.nn.Module):
    """tau = Kp (target - q) - Kd qd + a small network of (target - q, qd)."""

    def __init__(self, n: int, target, hidden: int = 64, kp: float = 2.0, kd: float = 0.2):
        super().__init__()
        self.register_buffer("target", torch.as_tensor(target))
        self.kp, self.kd = kp, kd
        self.net = torch.nn.Sequential(torch.nn.Linear(2 * n, hidden), torch.nn.Tanh(), torch.nn.Linear(hidden, n))
        with torch.no_grad():  # (small torques at first: the gains are low enough for Panda's 15 g fingers at 10 ms)
            self.net[-1].weight.mul_(0.1)
            self.net[-1].bias.zero_()

    def forward(self, q, qd):
        e = self.target - q
        return self.kp * e - self.kd * qd + self.net(torch.cat([e, qd], -1))


class Rollout(torch.nn.Module):
    """The arms simulated for ``steps`` steps of ``dt`` (semi-implicit Euler) under the policy: the cost of the
    motion (distance to the target, final velocity, torque)."""

    def __init__(self, dynamics: ForwardDynamics, policy: Policy, steps: int, dt: float):
        super().__init__()
        self.dynamics, self.policy, self.steps, self.dt = dynamics, policy, steps, dt

    def forward(self, q, qd):
        cost = 0.0
        for _ in range(self.steps):
            tau = self.policy(q, qd)
            qd = qd + self.dt * self.dynamics(q, qd, tau)
            q = q + self.dt * qd
            cost = cost + self.dt * (((q - self.policy.target) ** 2).sum(-1) + 1e-5 * (tau ** 2).sum(-1))
        return (cost + 0.1 * (qd ** 2).sum(-1)).mean()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", help="a model file (default: example-robot-data's Panda URDF)")
    parser.add_argument("--batch", type=int, default=1024, help="arms simulated at once (default 1024)")
    parser.add_argument("--steps", type=int, default=50, help="steps of the rollout (default 50)")
    parser.add_argument("--dt", type=float, default=0.01, help="time step, s (default 0.01)")
    parser.add_argument("--iterations", type=int, default=20, help="training iterations (default 20)")
    parser.add_argument("--device", default="cpu", help="torch device (default cpu)")
    parser.add_argument("--dtype", choices=["float64", "float32"], default="float64")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    torch.manual_seed(args.seed)
    dtype = getattr(torch, args.dtype)
    with tempfile.TemporaryDirectory() as folder:
        t0 = time.perf_counter()
        generated = generated_module(args.model or panda_urdf(), folder)
        print(f"{generated.NAME}: {generated.NV} coordinates, forward dynamics generated in "
              f"{time.perf_counter() - t0:.1f} s")
        n = generated.NV
        dynamics = ForwardDynamics(generated)
        policy = Policy(n, torch.zeros(n))
        rollout = Rollout(dynamics, policy, args.steps, args.dt).to(device=args.device, dtype=dtype)
        optimizer = torch.optim.Adam(policy.parameters(), lr=1e-2)
        q0 = 0.5 * torch.randn(args.batch, n, device=args.device, dtype=dtype)
        qd0 = torch.zeros(args.batch, n, device=args.device, dtype=dtype)
        first = last = None
        t0 = time.perf_counter()
        for it in range(args.iterations):
            optimizer.zero_grad()
            cost = rollout(q0, qd0)
            cost.backward()
            optimizer.step()
            last = float(cost.detach())
            first = last if first is None else first
            if it % max(1, args.iterations // 5) == 0 or it == args.iterations - 1:
                print(f"iteration {it:4d}: cost {last:.5f}")
        seconds = time.perf_counter() - t0
        states = args.batch * args.steps * args.iterations
        print(f"{args.iterations} iterations of {args.batch} arms x {args.steps} steps ({args.device}, {args.dtype}): "
              f"{seconds:.2f} s, {1e6 * seconds / states:.1f} us per state (forward and backward)")
        print(f"cost {first:.5f} -> {last:.5f}")
        if not last == last:  # NaN: the simulation left the arm's reach
            print("the cost is NaN: a smaller --dt", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
