"""The plots of REPORT.md's first three sections (generation time and memory against KanesMethod, operation counts
against the references, the runtime ratios against Pinocchio), drawn from the results dict of
:mod:`benchmarks.report` (moved out of it: one idea each)."""
from __future__ import annotations

import math
from pathlib import Path

from .harness.plots import dress, pyplot, save


def plot_generation(results, path: Path) -> bool:
    plt = pyplot()
    chains = sorted((r for r in results.get("generation", {}).get("runs", []) if r.get("kind") == "chain"
                     and r.get("ok")), key=lambda r: r["n"])
    kane = results.get("kane", {}).get("runs", [])
    if not chains and not kane:
        return False
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    failed = [r for r in results.get("generation", {}).get("runs", []) if r.get("kind") == "chain"
              and not r.get("ok")]
    for r in failed:
        ax.plot([r["n"]], [r["wall_seconds"]], "x", color="C0", markersize=10, mew=2)
        ax.annotate(f"aggsym > {r['wall_seconds']:.0f} s (killed)", (r["n"], r["wall_seconds"]),
                    textcoords="offset points", xytext=(6, 4), color="C0", fontsize=8)
    if chains:
        ax.plot([r["n"] for r in chains], [r["wall_seconds"] for r in chains], "o-", label="aggsym generate (all routines, C + NumPy + LaTeX)")
        ax2.plot([r["n"] for r in chains], [r["maxrss_kib"] / 1024 for r in chains], "o-", label="aggsym generate")
    done = [k for k in kane if k.get("finished")]
    if done:
        ax.plot([k["n"] for k in done], [k["seconds"] for k in done], "s-", color="C3",
                label="KanesMethod (M, forcing) + sympy.cse")
        ax2.plot([k["n"] for k in done], [k["maxrss_kib"] / 1024 for k in done], "s-", color="C3", label="KanesMethod + cse")
    over = [k for k in kane if not k.get("finished") and not k.get("skipped") and not k.get("failed")]
    for k in over:
        ax.plot([k["n"]], [k["timeout"]], "x", color="C3", markersize=10, mew=2)
        ax.annotate(f"> {k['timeout']:g} s (killed)", (k["n"], k["timeout"]), textcoords="offset points",
                    xytext=(6, -12), color="C3", fontsize=8)
    ax.set_yscale("log")
    dress(ax, "links n (3-D chain)", "wall time, s (log)", "Generation time", legend=8)
    dress(ax2, "links n (3-D chain)", "peak resident memory, MiB", "Peak memory of the process", legend=8,
          which="major")
    save(fig, path)
    return True


def plot_runtime(results, path: Path, labels: dict, target: float) -> bool:
    """Bars of time generated / time Pinocchio per robot and routine (``labels``: role -> legend), the target's line."""
    plt = pyplot()
    robots = results.get("runtime", {}).get("robots", [])
    if not robots:
        return False
    roles = []
    for r in robots:
        roles += [p["role"] for p in r["pairs"] if p["role"] not in roles]
    fig, ax = plt.subplots(figsize=(max(10, 1.6 * len(roles) + 2), 4.8))
    width = 0.85 / len(roles)
    for k, role in enumerate(roles):
        xs = [i + (k - (len(roles) - 1) / 2) * width for i in range(len(robots))]
        ys = [next((p["ratio"] for p in r["pairs"] if p["role"] == role), math.nan) for r in robots]
        ax.bar(xs, ys, width, label=labels.get(role, role))
        for x, y in zip(xs, ys):
            if not math.isnan(y):
                ax.text(x, y, f"{y:.2f}", ha="center", va="bottom", fontsize=6)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.axhline(target, color="C3", ls="--", lw=1, label=f"target {target:g}")
    ax.set_xticks(range(len(robots)))
    ax.set_xticklabels([f"{r['name']} (n = {r['nq']})" for r in robots])
    ax.set_ylabel("time generated / time Pinocchio")
    ax.set_title("Runtime ratio, ns per call (median of batch means); below 1 the generated C is faster")
    ax.legend(fontsize=7, ncol=3)
    ax.grid(True, axis="y", alpha=0.3)
    save(fig, path)
    return True


def plot_opcounts(results, path: Path) -> bool:
    from aggsym.codegen.ops import BOOK_TABLE_32, FEATHERSTONE_ABA, FEATHERSTONE_CRBA, FEATHERSTONE_RNEA

    plt = pyplot()
    runs = sorted((r for r in results.get("generation", {}).get("runs", []) if r.get("kind") == "chain" and r.get("ok")),
                  key=lambda r: r["n"])
    if not runs:
        return False
    ns = [r["n"] for r in runs]
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    for k, (role, ref) in enumerate((("inertia", FEATHERSTONE_CRBA), ("inverse_dynamics", FEATHERSTONE_RNEA),
                                     ("forward_dynamics", FEATHERSTONE_ABA))):
        ours = [r["ops"][role]["mul"] + r["ops"][role]["add"] + r["ops"][role]["div"] for r in runs]
        ax.plot(ns, ours, "o-", color=f"C{k}", label=f"aggsym {role}")
        ax.plot(ns, [sum(ref.at(n)) for n in ns], "--", color=f"C{k}", label=ref.label)
    ax.plot(ns, [sum(BOOK_TABLE_32.at(n)) for n in ns], ":", color="C2", label=BOOK_TABLE_32.label)
    ax.set_yscale("log")
    dress(ax, "links n (3-D chain)", "mul + add + div", "Operation counts of the emitted C vs the references")
    save(fig, path)
    return True
