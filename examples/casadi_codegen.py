"""CasADi's C code generator on aggsym's dynamics: an RK4 step of a robot and its Jacobian, compiled and timed.

    python examples/casadi_codegen.py [--model models/arm3.urdf] [--dt 0.01] [--folder DIR]

Generates the model's CasADi module (with the derivative routines, so that forward_dynamics' Jacobian is the
generated one), builds the discretised dynamics F(x, u) = one RK4 step of x' = (qd, forward_dynamics(q, qd, u)) and
its Jacobian d F / d (x, u) (what an MPC's linearisation, or acados, asks for), writes them as C with
``casadi.CodeGenerator``, compiles the C (cc -O2 -shared), loads it back with ``casadi.external`` and prints the
time per state of each (mapped over a batch of states, one call from Python): in CasADi's virtual machine and
compiled, and the largest difference between the two.
"""
from __future__ import annotations

import argparse
import importlib.util
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

import aggsym
from aggsym.codegen.generate import write

MODEL = Path(__file__).resolve().parent.parent / "models" / "arm3.urdf"
ROUTINES = ["default", "inverse_dynamics_derivatives", "forward_dynamics_derivatives"]


def casadi_module(model_path: Path, folder: Path):
    """The model's generated CasADi module (NAME_casadi.py written into ``folder`` and imported)."""
    model = aggsym.load(model_path, routines=ROUTINES)
    write(aggsym.generate(model, targets="casadi,manifest"), folder)
    path = folder / f"{model.name}_casadi.py"
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def discretised(module, dt: float):
    """(F, J): F(x, u) one RK4 step of the forward dynamics at the default parameters, J(x, u) = d F / d (x, u);
    over MX, so that J goes through forward_dynamics' attached Jacobian."""
    n = module.NQ
    x, u = ca.MX.sym("x", 2 * n), ca.MX.sym("u", n)
    fd, p = module.forward_dynamics, module.PARAMETERS

    def f(x):
        return ca.vertcat(x[n:], fd(x[:n], x[n:], u, p))
    k1 = f(x)
    k2 = f(x + dt / 2 * k1)
    k3 = f(x + dt / 2 * k2)
    k4 = f(x + dt * k3)
    step = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    F = ca.Function("rk4_step", [x, u], [step], ["x", "u"], ["x_next"])
    J = ca.Function("rk4_step_jacobian", [x, u], [ca.densify(ca.jacobian(step, ca.vertcat(x, u)))], ["x", "u"],
                    ["J"])
    return F, J


def per_state(f, args, batch: int) -> float:
    """Seconds per state of ``f`` mapped over ``batch`` states (``f.map``: one call from Python for them all, so
    that Python's call overhead does not count), the best of 5 calls; ``args`` hold the states as columns."""
    mapped = f.map(batch)
    best = float("inf")
    for _ in range(5):
        t = time.perf_counter()
        mapped(*args)
        best = min(best, (time.perf_counter() - t) / batch)
    return best


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", type=Path, default=MODEL)
    parser.add_argument("--dt", type=float, default=0.01)
    parser.add_argument("--folder", type=Path, help="where to write the module and the C (default: a temporary one)")
    parser.add_argument("--batch", type=int, default=2000, help="states per timed call")
    args = parser.parse_args(argv)
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        print("no C compiler (cc) on PATH")
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.folder or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        module = casadi_module(args.model, folder)
        F, J = discretised(module, args.dt)
        t = time.perf_counter()
        generator = ca.CodeGenerator("rk4_step.c", {"with_header": True})
        generator.add(F)
        generator.add(J)
        c_file = Path(generator.generate(str(folder) + "/"))
        written = time.perf_counter() - t
        library = folder / "rk4_step.so"
        t = time.perf_counter()
        subprocess.run([cc, "-O2", "-fPIC", "-shared", str(c_file), "-o", str(library), "-lm"], check=True)
        compiled = time.perf_counter() - t
        print(f"{module.NAME}: nq = {module.NQ}; wrote {c_file.name} ({c_file.stat().st_size // 1024} kB) in "
              f"{written:.2f} s, compiled it (-O2) in {compiled:.2f} s")
        rng = np.random.default_rng(0)
        x, u = rng.uniform(-1, 1, (2 * module.NQ, args.batch)), rng.uniform(-1, 1, (module.NQ, args.batch))
        for f in (F, J):
            external = ca.external(f.name(), str(library))
            difference = float(np.max(np.abs((f(x[:, 0], u[:, 0]) - external(x[:, 0], u[:, 0])).full())))
            vm = per_state(f, (x, u), args.batch)
            c = per_state(external, (x, u), args.batch)
            print(f"  {f.name():18s} {f.n_instructions():6d} instructions: CasADi's VM {vm * 1e6:8.3f} us, "
                  f"compiled {c * 1e6:8.3f} us per state (largest difference {difference:.1e})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
