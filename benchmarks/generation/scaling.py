"""Scaling of ``aggsym generate`` with the number of bodies: 3-D chains of n = 6 ... 192 and a 200-body tree.

Every model is generated twice, each time by a fresh ``python -m aggsym generate MODEL -o DIR -q`` process
(:func:`benchmarks.generation.measured.generate_measured`: wall time from the interpreter's start, the child's own CPU
time and peak resident set by ``os.wait4``):

- the default routine set (what a user gets without ``--routines``);
- the routines whose output has O(n) entries and an O(n) algorithm: gravity, bias, inverse_dynamics and
  forward_dynamics (``--routines``), whose generation time should grow linearly.

Per model the table gives wall and CPU time, peak memory, lines of C and the arithmetic operations (mul + add +
div of the manifest's ``ops``) per routine.  Exponents are least-squares slopes of log(y) on log(n) over the chains
with n >= :data:`FIT_FROM` (below that the interpreter's start and the imports, about a second, dominate):

- ``time_all``: wall time of the default set (target <= 1.6);
- ``time_linear``: wall time of the O(n) set (target <= 1.2);
- ``ops:<routine>``: the operations of each routine of the default set (target <= 1.2 for the O(n) routines).

The chains are :mod:`benchmarks.harness.chain`'s (link k's numbers depend on k alone); the tree (:func:`tree_yaml`) uses
the same links, hung in branches of :data:`BRANCH` bodies from bodies chosen by a seeded generator.  Timings taken
on a loaded machine say so: the load average before and after the run is recorded beside them.
"""
from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from ..harness.chain import body_lines, write_chain, write_text
from ..harness.environment import load_average
from ..harness.paths import result_path, write_json
from ..harness.plots import dress, pyplot, save
from .measured import generate_measured

CHAINS = (6, 12, 24, 48, 96, 192)
TREE_BODIES = 200
BRANCH = 8  # bodies per branch of the tree
FIT_FROM = 24  # smallest chain in the exponent fits
LINEAR = ("gravity", "bias", "inverse_dynamics", "forward_dynamics")  # O(n) outputs by O(n) algorithms
TARGETS = {"chain96_seconds": 10.0, "chain96_mib": 500.0, "tree200_seconds": 30.0, "exponent_linear": 1.2,
           "exponent_all": 1.6}
TIMEOUT = 240.0  # seconds per generate process


def tree_yaml(n: int = TREE_BODIES, seed: int = 7) -> str:
    """A branching tree of n bodies (``tree{n}``): branches of :data:`BRANCH` links in a row, each branch hung from
    a body of the earlier branches (seeded choice; the first from the world).  Link k's numbers (axis, offset,
    mass, centre of mass, inertia) are :func:`benchmarks.harness.chain.link` (k)'s."""
    rng = np.random.default_rng(seed)
    lines = [f"# {n}-body branching tree for the scaling benchmark (benchmarks/generation/scaling.py): branches of "
             f"{BRANCH} links.  Generated; do not edit.",
             f"name: tree{n}",
             f"description: {n}-body branching tree (benchmarks/generation/scaling.py)",
             "gravity: [0, 0, -9.81]",
             "bodies:"]
    for k in range(1, n + 1):
        if k == 1:
            parent = "world"
        elif (k - 1) % BRANCH == 0:
            parent = f"link{int(rng.integers(1, k))}"
        else:
            parent = f"link{k - 1}"
        lines += body_lines(k, parent)
    return "\n".join(lines) + "\n"


def write_tree(n: int, folder) -> Path:
    return write_text(folder, f"tree{n}.yaml", tree_yaml(n))


def _arith(ops: dict) -> int:
    return ops["mul"] + ops["add"] + ops["div"]


def _measure(label, path, outdir, routines=None, timeout=TIMEOUT) -> dict:
    run = generate_measured(label, path, outdir, timeout=timeout, routines=routines, options=["-q"])
    row = {"ok": run["ok"], "timed_out": run["timed_out"], "wall_seconds": round(run["wall_seconds"], 3),
           "cpu_seconds": round(run["cpu_seconds"], 3), "peak_mib": round(run["maxrss_kib"] / 1024, 1)}
    if run["ok"]:
        c_files = list(Path(outdir).glob("*.c"))
        row["c_lines"] = sum(p.read_text().count("\n") for p in c_files)
        row["ops"] = {role: _arith(o) for role, o in run["ops"].items()}
    else:
        row["error"] = run.get("stderr", "")[-500:]
    return row


def fit_exponent(ns, ys):
    """Least-squares slope of log y on log n (None with fewer than two positive points)."""
    pts = [(math.log(n), math.log(y)) for n, y in zip(ns, ys) if y and y > 0]
    if len(pts) < 2:
        return None
    x, y = np.array(pts).T
    return round(float(np.polyfit(x, y, 1)[0]), 3)


def exponents(results: dict) -> dict:
    chains = [m for m in results["models"] if m["kind"] == "chain" and m["n"] >= FIT_FROM]
    out = {}
    for key, part in (("time_all", "all"), ("time_linear", "linear")):
        pts = [(m["n"], m[part]["wall_seconds"]) for m in chains if m[part]["ok"]]
        out[key] = fit_exponent(*zip(*pts)) if len(pts) >= 2 else None
        cpu = [(m["n"], m[part]["cpu_seconds"]) for m in chains if m[part]["ok"]]
        out[key.replace("time", "cpu")] = fit_exponent(*zip(*cpu)) if len(cpu) >= 2 else None
    pts = [(m["n"], m["all"]["peak_mib"]) for m in chains if m["all"]["ok"]]
    out["peak_mib_all"] = fit_exponent(*zip(*pts)) if len(pts) >= 2 else None
    roles = sorted({r for m in chains if m["all"]["ok"] for r in m["all"]["ops"]})
    for role in roles:
        pts = [(m["n"], m["all"]["ops"].get(role)) for m in chains if m["all"]["ok"]]
        out[f"ops:{role}"] = fit_exponent(*zip(*pts)) if len(pts) >= 2 else None
    return out


def verdicts(results: dict) -> dict:
    """Each target: (value, limit, met)."""
    by = {m["label"]: m for m in results["models"]}
    ex = results["exponents"]
    out = {}

    def put(name, value, limit):
        out[name] = {"value": value, "limit": limit, "met": None if value is None else bool(value <= limit)}

    chain96 = by.get("chain96")
    if chain96 and chain96["all"]["ok"]:
        put("chain96 wall seconds (default set)", chain96["all"]["wall_seconds"], TARGETS["chain96_seconds"])
        put("chain96 peak MiB (default set)", chain96["all"]["peak_mib"], TARGETS["chain96_mib"])
    tree = by.get(f"tree{TREE_BODIES}")
    if tree and tree["all"]["ok"]:
        put(f"tree{TREE_BODIES} wall seconds (default set)", tree["all"]["wall_seconds"], TARGETS["tree200_seconds"])
    put("exponent: wall time of the default set", ex.get("time_all"), TARGETS["exponent_all"])
    put("exponent: wall time of the O(n) routines", ex.get("time_linear"), TARGETS["exponent_linear"])
    for role in LINEAR:
        put(f"exponent: ops of {role}", ex.get(f"ops:{role}"), TARGETS["exponent_linear"])
    return out


def run(out_dir, chains=CHAINS, tree: int | None = TREE_BODIES, progress=print, timeout: float = TIMEOUT) -> dict:
    """Generate every model (default set, then the O(n) set) in fresh processes under ``out_dir``; write
    ``benchmarks/scaling.json`` and ``benchmarks/scaling.png``; return the results."""
    out_dir = Path(out_dir)
    models = [("chain", n, write_chain(n, out_dir / "models")) for n in chains]
    if tree:
        models.append(("tree", tree, write_tree(tree, out_dir / "models")))
    results = {"timeout": timeout, "load_before": load_average(), "cpus": os.cpu_count(), "fit_from": FIT_FROM,
               "linear_routines": list(LINEAR), "models": []}
    t0 = time.perf_counter()
    for kind, n, path in models:
        label = path.stem
        row = {"label": label, "kind": kind, "n": n}
        row["all"] = _measure(label, path, out_dir / "out" / label, timeout=timeout)
        row["linear"] = _measure(label, path, out_dir / "out" / f"{label}_linear", routines=",".join(LINEAR),
                                 timeout=timeout)
        results["models"].append(row)
        if progress:
            a, lin = row["all"], row["linear"]
            progress(f"scaling: {label}: default set {a['wall_seconds']:.1f} s, {a['peak_mib']:.0f} MiB"
                     f"{'' if a['ok'] else ' (FAILED' + (', timed out' if a['timed_out'] else '') + ')'}; "
                     f"O(n) set {lin['wall_seconds']:.1f} s")
    results["seconds"] = round(time.perf_counter() - t0, 1)
    results["load_after"] = load_average()
    results["exponents"] = exponents(results)
    results["targets"] = verdicts(results)
    write_json(result_path("scaling"), results, indent=2)
    plot(results, result_path("scaling").with_suffix(".png"))
    return results


def plot(results: dict, path) -> None:
    plt = pyplot()
    chains = [m for m in results["models"] if m["kind"] == "chain"]
    ex = results["exponents"]
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 4.6))
    for part, label, key, marker in (("all", "default set, wall s", "time_all", "o"),
                                     ("linear", "O(n) routines, wall s", "time_linear", "s")):
        pts = [(m["n"], m[part]["wall_seconds"]) for m in chains if m[part]["ok"]]
        if pts:
            ax.loglog(*zip(*pts), marker=marker, label=f"{label} (slope {ex.get(key)})")
    pts = [(m["n"], m["all"]["peak_mib"]) for m in chains if m["all"]["ok"]]
    if pts:
        ax.loglog(*zip(*pts), marker="^", linestyle="--", label=f"default set, peak MiB (slope {ex.get('peak_mib_all')})")
    for m in results["models"]:
        if m["kind"] == "tree" and m["all"]["ok"]:
            ax.loglog([m["n"]], [m["all"]["wall_seconds"]], marker="*", markersize=12, linestyle="",
                      label=f"{m['label']}, default set, wall s")
    dress(ax, "bodies n", title=f"aggsym generate (fits over n >= {results['fit_from']}; load "
                                f"{results['load_before'][0]})")
    roles = [r for r in LINEAR] + [r for r in ("inertia", "coriolis", "inertia_inverse", "transvective_factors")]
    for role in roles:
        pts = [(m["n"], m["all"]["ops"].get(role)) for m in chains if m["all"]["ok"] and m["all"]["ops"].get(role)]
        if pts:
            ax2.loglog(*zip(*pts), marker="o" if role in LINEAR else "x",
                       label=f"{role} (slope {ex.get('ops:' + role)})")
    dress(ax2, "bodies n", "mul + add + div of the C", "operations per routine")
    save(fig, path)


def markdown(results: dict) -> str:
    """The results as Markdown: one row per model, then the exponents and the targets."""
    lines = [f"Generation scaling (`benchmarks/generation/scaling.py`): fresh `python -m aggsym generate MODEL -o DIR "
             f"-q` per row; load average {results['load_before']} before, {results['load_after']} after, on "
             f"{results['cpus']} CPUs; {results['seconds']} s in all.", "",
             "| model | n | default set: wall s | CPU s | peak MiB | lines of C | O(n) set: wall s | CPU s | "
             + " | ".join(f"ops {r}" for r in LINEAR) + " | ops inertia | ops coriolis | ops inertia_inverse |",
             "|---|---:|---:|---:|---:|---:|---:|---:|" + "---:|" * (len(LINEAR) + 3)]
    for m in results["models"]:
        a, lin = m["all"], m["linear"]
        if a["ok"]:
            cells = [f"{a['wall_seconds']:.2f}", f"{a['cpu_seconds']:.2f}", f"{a['peak_mib']:.0f}", str(a["c_lines"])]
            ops = [str(a["ops"].get(r, "")) for r in LINEAR + ("inertia", "coriolis", "inertia_inverse")]
        else:
            cells = ["timed out" if a["timed_out"] else "failed", "", "", ""]
            ops = [""] * (len(LINEAR) + 3)
        lcells = [f"{lin['wall_seconds']:.2f}", f"{lin['cpu_seconds']:.2f}"] if lin["ok"] else ["failed", ""]
        lines.append(f"| {m['label']} | {m['n']} | " + " | ".join(cells + lcells + ops) + " |")
    lines += ["", f"Exponents (log-log least squares over the chains with n >= {results['fit_from']}):", ""]
    lines += [f"- {k}: {v}" for k, v in results["exponents"].items()]
    lines += ["", "| target | value | limit | met |", "|---|---:|---:|---|"]
    for name, t in results["targets"].items():
        met = "n/a" if t["met"] is None else ("yes" if t["met"] else "no")
        lines.append(f"| {name} | {t['value']} | {t['limit']} | {met} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.generation.scaling",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="folder for the models and the generated code (default: a temporary one)")
    parser.add_argument("--chains", default=",".join(map(str, CHAINS)), help="chain lengths, comma-separated")
    parser.add_argument("--tree", type=int, default=TREE_BODIES, help="bodies of the tree (0: none)")
    parser.add_argument("--timeout", type=float, default=TIMEOUT, help="seconds per generate process")
    args = parser.parse_args(argv)
    chains = tuple(int(x) for x in args.chains.split(",") if x)
    if args.out:
        results = run(args.out, chains, args.tree or None, timeout=args.timeout)
    else:
        with tempfile.TemporaryDirectory(prefix="aggsym-scaling-") as tmp:
            results = run(tmp, chains, args.tree or None, timeout=args.timeout)
    print(markdown(results))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
