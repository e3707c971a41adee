"""The CasADi target (issue 54) against the CasADi SX Featherstone peer, both through CasADi's code generator.

``python -m benchmarks.runtime.casadi_target [ROBOT ...] [--json OUT.json]`` (default: ur5 panda talos): generates
each robot's NAME_casadi.py with the derivative routines (``--targets casadi``), and prints per robot

- the Functions' sizes: ``n_instructions`` and ``n_nodes`` of aggsym's forward dynamics and of the peer's ABA
  (:mod:`.casadi_peer`), and of their Jacobians along (q, qd, tau): aggsym's by CasADi's AD of the SX graph, aggsym's
  by the attached derivative routines (the Function's custom Jacobian, inlined over SX), the peer's by CasADi's AD;
- the seconds to build aggsym's Functions (the module's ``functions()``, derivative routines included);
- the runtime of CasADi's generated C of each (``casadi.CodeGenerator``, compiled ``cc -O2``), ns per call: the best
  of 7 passes over 64 random states, in one process per function, timed by a small C driver.

Timings on a shared machine are noisy: the load average is printed beside them.  In ``make bench`` as the section
``casadi`` (:func:`run`, casadi_target.json, :func:`markdown` in REPORT.md), with the target of issue 54: forward
dynamics and its Jacobian from aggsym's Functions at most :data:`TARGET` of the peer's runtime.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from aggsym.codegen.compile import compiler, import_module

from ..harness.robots import robot_paths
from . import casadi_peer

ROBOTS = ("ur5", "panda", "talos")
TARGET = 0.5  # issue 54: aggsym's forward dynamics and its Jacobian through CasADi's C, as a fraction of the peer's
DRIVER = r"""
#include <stdio.h>
#include <time.h>
int %(fn)s(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem);
#define NS 64
static double states[NS][%(nin)d];
static casadi_real out[%(nout)d];
static casadi_int iw[%(iw)d + 1];
static casadi_real w[%(w)d + 1];
int main(void) {
    unsigned s = 12345u;
    for (int k = 0; k < NS; ++k) for (int i = 0; i < %(nin)d; ++i) {
        s = s * 1103515245u + 12345u; states[k][i] = ((double)(s >> 8) / 16777216.0 - 0.5) * 2.0;
    }
    int sizes[] = {%(sizes)s};
    const casadi_real *arg[%(narg)d + 1];
    casadi_real *res[%(nres)d + 1];
    double best = 1e300, sink = 0.0;
    long reps = %(reps)ld;
    for (int pass = 0; pass < 7; ++pass) {
        struct timespec a, b;
        clock_gettime(CLOCK_MONOTONIC, &a);
        for (long r = 0; r < reps; ++r) for (int k = 0; k < NS; ++k) {
            int off = 0;
            for (int i = 0; i < %(nargs)d; ++i) { arg[i] = states[k] + off; off += sizes[i]; }
            res[0] = out;
            for (int i = 1; i < %(nres)d; ++i) res[i] = 0;
            %(fn)s(arg, res, iw, w, 0);
            sink += out[0];
        }
        clock_gettime(CLOCK_MONOTONIC, &b);
        double ns = ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / (reps * NS);
        if (ns < best) best = ns;
    }
    printf("%%.1f %%g\n", best, sink);
    return 0;
}
"""


def _ca():
    import casadi
    return casadi


def aggsym_functions(urdf, folder: Path) -> tuple:
    """(module, seconds to generate, seconds for functions()) of a robot's NAME_casadi.py with the derivatives."""
    import aggsym
    from aggsym.codegen.generate import write

    from aggsym.errors import ModelWarning

    t0 = time.perf_counter()
    with warnings.catch_warnings():  # (the robots' mimic joints: independent coordinates, as the peer's)
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(urdf, routines=["default", "inverse_dynamics_derivatives",
                                            "forward_dynamics_derivatives"])
    write(aggsym.generate(model, targets="casadi,manifest"), folder)
    t1 = time.perf_counter()
    module = import_module(folder / f"{model.name}_casadi.py")
    module.functions()
    return module, t1 - t0, time.perf_counter() - t1


def _with_defaults(module, f, name: str, analytic: bool):
    """(q, qd, tau) -> qdd and (q, qd, tau) -> d qdd / d (q, qd, tau) of aggsym's forward dynamics with p at its
    defaults, over SX: the Jacobian by CasADi's AD of the inlined graph or, ``analytic``, the Function's attached
    Jacobian (``f.jacobian()``, the derivative routines and A^-1: what an MX call's Jacobian evaluates) inlined."""
    ca = _ca()
    n = module.NQ
    q, qd, tau = (ca.SX.sym(s, n) for s in ("q", "qd", "tau"))
    qdd = f(q, qd, tau, module.PARAMETERS)
    fd = ca.Function(f"{name}_fd", [q, qd, tau], [qdd])
    if analytic:
        d_q, d_qd, d_tau = f.jacobian()(q, qd, tau, module.PARAMETERS, qdd)[:3]
        jacobian = ca.horzcat(d_q, d_qd, d_tau)
    else:
        jacobian = ca.jacobian(qdd, ca.vertcat(q, qd, tau))
    return fd, ca.Function(f"{name}_jac", [q, qd, tau], [ca.densify(jacobian)])


def _peer(urdf, name: str) -> tuple:
    """(fd, jac) of the CasADi peer's ABA: CasADi's AD of its SX graph."""
    ca = _ca()
    pm = casadi_peer.pinocchio_model(urdf)
    joints = casadi_peer.tree_from_pinocchio(pm)
    fd = casadi_peer.functions(name, joints, np.array(pm.gravity.linear))["forward_dynamics"]
    q, qd, tau = (ca.SX.sym(s, len(joints)) for s in ("q", "qd", "tau"))
    qdd = fd(q, qd, tau)
    jac = ca.Function(f"{name}_jac", [q, qd, tau], [ca.cse(ca.densify(ca.jacobian(qdd, ca.vertcat(q, qd, tau))))])
    return ca.Function(f"{name}_fd", [q, qd, tau], [qdd]), jac


def time_c(f, folder: Path, reps: int) -> float:
    """ns per call of CasADi's C of ``f`` (-O2), by the driver."""
    ca = _ca()
    name = f.name()
    cg = ca.CodeGenerator(f"{name}.c", {"with_header": False, "casadi_real": "double"})
    cg.add(f)
    sizes = [f.nnz_in(k) for k in range(f.n_in())]
    driver = DRIVER % {"fn": name, "nin": sum(sizes), "nout": max(1, f.nnz_out(0)), "iw": f.sz_iw(), "w": f.sz_w(),
                       "sizes": ", ".join(map(str, sizes)), "narg": f.sz_arg(), "nres": f.sz_res(),
                       "nargs": f.n_in(), "reps": reps}
    source = folder / f"{name}.c"
    source.write_text(cg.dump() + driver)
    exe = folder / name
    subprocess.run([compiler(), "-O2", "-o", str(exe), str(source), "-lm"], check=True)
    return float(subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout.split()[0])


def measure(robot: str, urdf, folder: Path) -> dict:
    folder.mkdir(parents=True, exist_ok=True)
    module, generate_s, build_s = aggsym_functions(urdf, folder)
    fd = module.functions()["forward_dynamics"]
    ad_fd, ad_jac = _with_defaults(module, module.functions(analytic=False)["forward_dynamics"], f"{robot}_ad", False)
    _, attached_jac = _with_defaults(module, fd, f"{robot}_attached", True)
    peer_fd, peer_jac = _peer(urdf, f"{robot}_peer")
    reps = 200 if module.NQ < 10 else 20
    entries = {"aggsym fd": ad_fd, "aggsym jac (CasADi AD)": ad_jac, "aggsym jac (attached)": attached_jac,
               "peer fd": peer_fd, "peer jac (CasADi AD)": peer_jac}
    out = {"nq": module.NQ, "generate_s": round(generate_s, 2), "functions_s": round(build_s, 2), "entries": {}}
    for label, f in entries.items():
        size = {"n_instructions": int(f.n_instructions()), "n_nodes": int(f.n_nodes())}
        out["entries"][label] = {**size, "ns": time_c(f, folder, reps if "jac" not in label else max(2, reps // 10))}
    return out


def _base(entries: dict, label: str) -> float:
    """The peer's ns of the same function (forward dynamics or its Jacobian)."""
    return entries["peer fd" if "fd" in label else "peer jac (CasADi AD)"]["ns"]


def run(robots=ROBOTS, log=print) -> dict:
    """Every robot measured (:func:`measure`), the load average before and after: the section ``casadi``."""
    paths = robot_paths()
    results = {"load_before": os.getloadavg()[0], "robots": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for robot in robots:
            r = results["robots"][robot] = measure(robot, paths[robot], Path(tmp) / robot)
            log(f"{robot} (nq = {r['nq']}): generated in {r['generate_s']} s, functions() in {r['functions_s']} s")
            for label, e in r["entries"].items():
                log(f"  {label:24s} n_instructions {e['n_instructions']:8d}  n_nodes {e['n_nodes']:8d}  "
                    f"{e['ns']:10.1f} ns  ({e['ns'] / _base(r['entries'], label):.2f} of the peer's)")
            sys.stdout.flush()
    results["load_after"] = os.getloadavg()[0]
    log(f"load average {results['load_before']:.2f} before, {results['load_after']:.2f} after")
    return results


def markdown(results: dict) -> str:
    """The section's table for REPORT.md: per robot and function, the sizes, ns per call and the ratio to the peer,
    with the target of issue 54 (forward dynamics and the faster of aggsym's Jacobians at most TARGET)."""
    if results.get("error") and not results.get("robots"):
        return f"Not run: {results['error']}"
    lines = ["Forward dynamics and its Jacobian along (q, qd, tau) through CasADi's code generator (`cc -O2`, both "
             "sides; ns per call, the best of 7 passes over 64 states): aggsym's `--targets casadi` Functions against "
             "the CasADi SX Featherstone peer (`benchmarks/runtime/casadi_peer.py`).  `python -m "
             f"benchmarks.runtime.casadi_target`; load average {results.get('load_before', 0):.2f} before, "
             f"{results.get('load_after', 0):.2f} after.", "",
             "| robot | function | n_instructions | n_nodes | ns | of the peer's | target |",
             "| --- | --- | ---: | ---: | ---: | ---: | --- |"]
    for robot, r in results.get("robots", {}).items():
        entries = r["entries"]
        fastest_jac = min((e["ns"] for label, e in entries.items() if label.startswith("aggsym jac")), default=None)
        for label, e in entries.items():
            ratio = e["ns"] / _base(entries, label)
            aims = label == "aggsym fd" or (label.startswith("aggsym jac") and e["ns"] == fastest_jac)
            verdict = ("met" if ratio <= TARGET else "missed") + f" (<= {TARGET:g})" if aims else ""
            lines.append(f"| {robot} (nq {r['nq']}) | {label} | {e['n_instructions']} | {e['n_nodes']} | "
                         f"{e['ns']:.1f} | {ratio:.2f} | {verdict} |")
    lines += ["", "Building the Functions: " + ", ".join(
        f"{robot} {r['functions_s']} s (generated in {r['generate_s']} s)" for robot, r in
        results.get("robots", {}).items()) + " (`functions()` with the derivative routines attached)."]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robots", nargs="*", default=list(ROBOTS))
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    results = run(args.robots)
    if args.json:
        args.json.write_text(json.dumps(results, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
