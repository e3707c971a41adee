"""Issue 52's part of benchmarks/REPORT.md: the derivative routines of section 3 against the dynamics they
differentiate (operations from the manifests, Pinocchio's own factor and the runtime ratio, same batches), and the
issue's targets."""
from __future__ import annotations

from .harness import tables

DERIVATIVE_OPS_TARGET = 4.0  # issue 52: dID <= 4 ID and dFD <= 4 FD (mul + add + div)
DERIVATIVE_RUNTIME_TARGET = 0.15  # issue 52: generated / Pinocchio's derivatives


def _arith(ops) -> int | None:
    return None if not ops else ops.get("mul", 0) + ops.get("add", 0) + ops.get("div", 0)


def derivative_rows(results) -> list:
    """Per robot of section 3 timed with both derivative routines: (robot, ID ops, dID ops, dID/ID, Pinocchio's
    rnea -> dRNEA factor, FD ops, dFD ops, dFD/FD, Pinocchio's aba -> dABA factor, dID and dFD runtime ratios to
    Pinocchio's)."""
    pairs = {(robot["name"], p["role"]): p for robot in results.get("runtime", {}).get("robots", [])
             for p in robot["pairs"]}
    rows = []
    for robot in results.get("runtime", {}).get("robots", []):
        name = robot["name"]
        did, dfd = pairs.get((name, "inverse_dynamics_derivatives")), pairs.get((name, "forward_dynamics_derivatives"))
        rnea, aba = pairs.get((name, "inverse_dynamics")), pairs.get((name, "forward_dynamics"))
        if not (did and dfd and rnea and aba):
            continue
        ops = robot.get("ops") or {}
        count = {role: _arith(ops.get(role)) for role in ("inverse_dynamics", "inverse_dynamics_derivatives",
                                                             "forward_dynamics", "forward_dynamics_derivatives")}
        rows.append({"robot": name, "nv": robot.get("nv", robot["nq"]), **count,
                     "pin_rnea_factor": did["pinocchio_ns"] / rnea["pinocchio_ns"],
                     "pin_aba_factor": dfd["pinocchio_ns"] / aba["pinocchio_ns"],
                     "did_ratio": did["ratio"], "dfd_ratio": dfd["ratio"],
                     "did_ns": did["generated_ns"], "dfd_ns": dfd["generated_ns"]})
    return rows


def targets(results) -> list:
    """Issue 52's targets on the robots of section 3 timed with the derivative routines."""
    rows = []
    for r in derivative_rows(results):
        for what, ours, base in (("∂ID ≤ 4× ID", "inverse_dynamics_derivatives", "inverse_dynamics"),
                                 ("∂FD ≤ 4× FD", "forward_dynamics_derivatives", "forward_dynamics")):
            if r[ours] and r[base]:
                factor = r[ours] / r[base]
                rows.append((f"operations {what} ({r['robot']})", f"{factor:.1f}×",
                             factor <= DERIVATIVE_OPS_TARGET))
        for what, key, ns in (("∂τ/∂(q, q̇) ≤ 0.15× computeRNEADerivatives", "did_ratio", "did_ns"),
                              ("∂q̈/∂(q, q̇) ≤ 0.15× computeABADerivatives", "dfd_ratio", "dfd_ns")):
            rows.append((f"runtime {what} ({r['robot']})", f"{r[key]:.3f} ({r[ns]:.0f} ns)",
                         r[key] <= DERIVATIVE_RUNTIME_TARGET))
    return rows


def section(results) -> list:
    rows = derivative_rows(results)
    if not rows:
        return []

    def over(a, b):
        return "—" if not a or not b else f"{a / b:.1f}"

    body = [(r["robot"], str(r["nv"]), str(r["inverse_dynamics"]), str(r["inverse_dynamics_derivatives"]),
             over(r["inverse_dynamics_derivatives"], r["inverse_dynamics"]), f"{r['pin_rnea_factor']:.1f}",
             f"{r['did_ratio']:.3f}", str(r["forward_dynamics"]), str(r["forward_dynamics_derivatives"]),
             over(r["forward_dynamics_derivatives"], r["forward_dynamics"]), f"{r['pin_aba_factor']:.1f}",
             f"{r['dfd_ratio']:.3f}") for r in rows]
    return ["### The derivatives against the dynamics they differentiate", "",
            "Operations (mul + add + div, the manifests of the code timed above) of each derivative routine and of "
            "its dynamics, with the factor between them; beside it Pinocchio's own factor (the time of "
            "computeRNEADerivatives over rnea's, computeABADerivatives over aba's, in these batches) and the "
            "generated routine's time over Pinocchio's.  dτ/d(q, q̇) is built in the form of fewer operations: the "
            "composites of the tree (`aggsym/mechanics/spatial_derivatives.py`) or the sweeps on dual numbers "
            "(`python -m benchmarks.generation.derivative_counts` prints both counts per robot).", "",
            tables.markdown_table(("robot", "nv", "ID ops", "∂ID ops", "∂ID/ID", "Pinocchio ∂rnea/rnea", "∂ID vs Pinocchio",
                   "FD ops", "∂FD ops", "∂FD/FD", "Pinocchio ∂aba/aba", "∂FD vs Pinocchio"), body, "l" + "r" * 11), ""]
