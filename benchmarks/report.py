"""REPORT.md, the plots, and the targets table of ``make bench`` from the collected results.

``results`` is a dict: ``environment``, ``config``, ``generation`` ({runs}), ``kane`` ({runs, timed_out_at}),
``opcounts`` (label -> {name, nq, rows}), ``runtime`` (the harness JSON plus compile times).  Every section
is optional; a missing one is reported as not run.
"""
from __future__ import annotations

import math
from pathlib import Path

from . import report_derivatives, report_plots
from .harness import tables

ROBOTS = ("ur5", "panda", "hyq", "talos")
RUNTIME_TARGET_ROLES = ("inertia", "nonlinear_effects", "inverse_dynamics", "forward_dynamics",
                        "inverse_dynamics_derivatives", "forward_dynamics_derivatives", "frame_jacobians", "regressor")
RUNTIME_LABELS = {"inertia": "A(q) ↔ crba", "nonlinear_effects": "b+g ↔ nonLinearEffects",
                  "inverse_dynamics": "inverse dynamics ↔ rnea", "forward_dynamics": "forward dynamics ↔ aba",
                  "inertia_inverse": "A⁻¹ ↔ computeMinverse",
                  "inverse_dynamics_derivatives": "∂τ/∂q, ∂τ/∂q̇ ↔ computeRNEADerivatives",
                  "forward_dynamics_derivatives": "∂q̈/∂q, ∂q̈/∂q̇ ↔ computeABADerivatives",
                  "frame_jacobians": "frame Jacobians ↔ computeJointJacobians + getFrameJacobian",
                  "regressor": "regressor Y ↔ computeJointTorqueRegressor"}
FREE_FLYER_SUFFIX = "_ff"  # the robots generated with --floating-base quaternion (benchmarks/run.py)
FREE_FLYER_TARGET_ROLES = ("inertia", "inverse_dynamics", "forward_dynamics")
# Pinocchio 4.1 figures quoted in the design brief (its "Performance"; the brief is not part of this repository,
# the figures are copied here), ns per call: crba / nonLinearEffects / aba
DESIGN_PINOCCHIO_NS = {"ur5": {"inertia": 300, "nonlinear_effects": 660, "forward_dynamics": 1360},
                       "panda": {"inertia": 480, "nonlinear_effects": 970, "forward_dynamics": 2050},
                       "talos": {"inertia": 1800, "nonlinear_effects": 3600, "forward_dynamics": 7500}}
GEN_TARGETS = (("panda", 5.0, None), ("chain12", 10.0, None), ("talos", 60.0, 2 * 2 ** 20),  # label, s, KiB
               ("talos", 1.5, None))  # (issue 18's: all routines of the 32-DOF Talos in 1.5 s, Python's start included)
RUNTIME_RATIO_TARGET = 0.5
CONSTRAINED_RATIO_TARGET = 1.0  # solo12 on four point feet, constrained_forward_dynamics vs constraintDynamics
OPS_TARGET_MODEL = "manipulator6"
# the second peer (benchmarks/runtime/casadi_peer.py) and the generated code at -O3 (harness/bench.h, bench_peer)
PEER_ROBOTS = ("ur5", "panda", "solo12_euler", "talos", "chain24", "chain48")
PEER_TARGET_ROLES = ("inertia", "nonlinear_effects", "inverse_dynamics", "forward_dynamics")
PEER_ROLES = ("inertia", "nonlinear_effects", "inverse_dynamics", "forward_dynamics", "inertia_inverse")
GEN_O3, CASADI_O2, CASADI_O3 = "aggsym -O3", "CasADi -O2", "CasADi -O3"
PINOCCHIO_HOST_ROLES = ("inertia", "nonlinear_effects", "inverse_dynamics", "forward_dynamics", "inertia_inverse")


# ---------------------------------------------------------------------------------------------- helpers
def _fmt(x, digits=2):
    if x is None:
        return "—"
    if isinstance(x, float):
        if math.isnan(x):
            return "—"
        return f"{x:.{digits}f}"
    return str(x)


def _mib(kib):
    return None if kib is None else kib / 1024


def _cell(c) -> str:
    return c if isinstance(c, str) else _fmt(c)


def table(header, rows, align=None) -> str:
    """A Markdown table; ``align`` is a string of 'l'/'r' per column (default: first left, rest right)."""
    return tables.markdown_table(header, rows, align or "l" + "r" * (len(header) - 1), cell=_cell)


def text_table(header, rows) -> str:
    """A plain-text table for stdout."""
    return tables.text_table(header, rows, cell=_cell)


def _gen_runs(results) -> dict:
    return {r["label"]: r for r in results.get("generation", {}).get("runs", [])}


def _runtime_ops(results, robot) -> dict:
    """The operation counts of the routines timed for ``robot`` (the manifest of the code the runtime section
    built; older runs have none)."""
    for r in results.get("runtime", {}).get("robots", []):
        if r["name"] == robot:
            return r.get("ops") or {}
    return {}


def _runtime_pairs(results) -> dict:
    """(robot, role) -> pair dict."""
    out = {}
    for robot in results.get("runtime", {}).get("robots", []):
        for pair in robot["pairs"]:
            out[(robot["name"], pair["role"])] = pair
    return out


# ---------------------------------------------------------------------------------------------- targets
def targets(results) -> list:
    """Rows (target, measured, met) where met is True, False or None (not measured)."""
    rows = []
    runs = _gen_runs(results)
    for label, limit, mem in GEN_TARGETS:
        r = runs.get(label)
        what = f"full generation {label} ≤ {limit:g} s" + (f", peak memory ≤ {mem / 2 ** 20:g} GiB" if mem else "")
        if not r or not r.get("ok"):
            rows.append((what, "not measured" if not r else "generation failed", None))
            continue
        met = r["wall_seconds"] <= limit and (mem is None or r["maxrss_kib"] <= mem)
        measured = f"{r['wall_seconds']:.2f} s wall ({r['cpu_seconds']:.2f} s CPU)"
        if mem:
            measured += f", {r['maxrss_kib'] / 2 ** 20:.2f} GiB"
        rows.append((what, measured, met))
    pairs = _runtime_pairs(results)

    def ratio_row(what, role, suffix=""):
        got = [(robot, pairs.get((robot + suffix, role))) for robot in ROBOTS]
        if any(p is None for _, p in got):
            return (what, "not measured", None)
        measured = ", ".join(f"{robot} {p['ratio']:.2f}" for robot, p in got)
        return (what, measured, all(p["ratio"] <= RUNTIME_RATIO_TARGET for _, p in got))

    for role in RUNTIME_TARGET_ROLES:
        rows.append(ratio_row(f"runtime {RUNTIME_LABELS[role]}: generated/Pinocchio ≤ {RUNTIME_RATIO_TARGET:g} on "
                              f"all four robots", role))
    for role in FREE_FLYER_TARGET_ROLES:
        rows.append(ratio_row(f"runtime free-flyer (--floating-base quaternion) {RUNTIME_LABELS[role]} of "
                              f"Pinocchio's JointModelFreeFlyer model: generated/Pinocchio ≤ "
                              f"{RUNTIME_RATIO_TARGET:g} on all four robots", role, FREE_FLYER_SUFFIX))
    rt = results.get("runtime", {})
    if "constrained" in rt or "constrained_error" in rt:
        what = (f"runtime constrained dynamics, solo12 on 4 point feet ↔ constraintDynamics: generated/Pinocchio "
                f"< {CONSTRAINED_RATIO_TARGET:g}")
        got = [(r, p) for r in rt.get("constrained", []) for p in r["pairs"]]
        if not got:
            rows.append((what, "not measured", None))
        for r, p in got:
            measured = f"{r['name']} {p['ratio']:.2f} ({p['generated_ns']:.0f} ns vs {p['pinocchio_ns']:.0f} ns)"
            rows.append((what, measured, p["ratio"] < CONSTRAINED_RATIO_TARGET))
    rows += peer_targets(results)
    if results.get("constrained_derivatives"):
        from .runtime.constrained_derivatives import targets as contact_targets

        rows += contact_targets(results["constrained_derivatives"])
    rows += report_derivatives.targets(results)
    rows += opsn_targets(results)
    inputs = results.get("inputs", {})
    for row in inputs.get("rows", []):
        target = row.get("target_seconds", inputs.get("target_seconds"))
        if target is not None:
            if "links" in row:  # the 3-D chain of benchmarks/harness/chain.py (issue 30: the parse alone)
                what = (f"parse a {row['links']}-link {row['file']} (3-D, full inertias; aggsym.load in process) "
                        f"≤ {target:g} s")
            else:
                what = f"read and order a {row['bodies']}-body {row['file']} ≤ {target:g} s"
            cpu = f"; CPU {row['cpu_seconds']:.3f} s" if "cpu_seconds" in row else ""
            rows.append((what, f"{row['seconds']:.3f} s (median of 3{cpu})", row["seconds"] <= target))
    ops = results.get("opcounts", {}).get(OPS_TARGET_MODEL)
    if not ops:
        rows.append((f"op counts at n = 6 ({OPS_TARGET_MODEL}) below the book's and Featherstone's", "not measured",
                     None))
    else:
        by_routine = {}
        for row in ops["rows"]:
            if row.get("reference") and row.get("target"):
                by_routine.setdefault(row["routine"], []).append(row)
        for routine, rs in by_routine.items():
            what = f"op count {routine} at n = {ops['nq']} ({OPS_TARGET_MODEL}) below " + \
                   ", ".join(_short(r["reference"]) for r in rs)
            measured = f"{rs[0]['ours']} vs " + ", ".join(str(r["ref_total"]) for r in rs)
            rows.append((what, measured, all(r["ours"] < r["ref_total"] for r in rs)))
    return rows


def peer_ratio(pair: dict, level: str = "O2"):
    """generated / CasADi at the same optimisation level (None when the pair has no CasADi peer)."""
    peers = pair.get("peers") or {}
    casadi = peers.get(CASADI_O2 if level == "O2" else CASADI_O3)
    ours = pair["generated_ns"] if level == "O2" else (peers.get(GEN_O3) or {}).get("ns")
    if not casadi or ours is None:
        return None
    return ours / casadi["ns"]


def peer_targets(results) -> list:
    """Rows (target, measured, met) of the issue's runtime target against the CasADi peer (-O2 both sides, the
    flags of the generated code's rows), on the robots of PEER_ROBOTS that ran."""
    rows = []
    pairs = _runtime_pairs(results)
    robots = [r for r in PEER_ROBOTS if any((pairs.get((r, role)) or {}).get("peers") for role in PEER_TARGET_ROLES)]
    for role in PEER_TARGET_ROLES:
        what = (f"runtime against the CasADi peer, `{role}`: generated/CasADi (both -O2) ≤ "
                f"{RUNTIME_RATIO_TARGET:g} on " + (", ".join(robots) or "the peer robots"))
        got = [(robot, peer_ratio(pairs[(robot, role)])) for robot in robots if (robot, role) in pairs]
        if not got or any(x is None for _, x in got):
            rows.append((what, "not measured", None))
            continue
        rows.append((what, ", ".join(f"{robot} {x:.2f}" for robot, x in got),
                     all(x <= RUNTIME_RATIO_TARGET for _, x in got)))
    return rows


def opsn_targets(results) -> list:
    """Rows (target, measured, met) of item 7: ops per coordinate of inverse and forward dynamics."""
    opsn = results.get("opsn") or {}
    rows = []
    for role, limit in (opsn.get("targets") or {}).items():
        got = [r for r in opsn.get("rows", []) if role in r]
        what = f"op count {role} ≤ {limit} n (mul+add+div) on " + ", ".join(r["robot"] for r in opsn["rows"])
        if not got or len(got) < len(opsn["rows"]):
            rows.append((what, "not measured" if not got else "a generation failed", None))
            continue
        rows.append((what, ", ".join(f"{r['robot']} {r[role]['per_n']:.1f} n" for r in got),
                     all(r[role]["per_n"] <= limit for r in got)))
    return rows


def _short(label: str) -> str:
    return label.replace("book ", "").replace(" total", "").replace("Featherstone ", "")


def diagnose(results) -> list:
    """For each missed target, where the time or the operations go (one line each)."""
    notes = []
    runs = _gen_runs(results)
    for label, limit, mem in GEN_TARGETS:
        r = runs.get(label)
        if not r or not r.get("ok"):
            continue
        if r["wall_seconds"] > limit or (mem and r["maxrss_kib"] > mem):
            s = r.get("stages", {})
            inside = r.get("internal_seconds") or sum(s.values())
            parts = ", ".join(f"{k} {v:.2f} s" for k, v in sorted(s.items(), key=lambda kv: -kv[1]))
            notes.append(f"generation of {label}: {r['wall_seconds']:.2f} s wall ({r['cpu_seconds']:.2f} s CPU) = "
                         f"{r['wall_seconds'] - inside:.2f} s interpreter start, imports and reading the model + "
                         f"{inside:.2f} s inside `generate` ({parts}); peak {r['maxrss_kib'] / 1024:.0f} MiB")
    for r in results.get("generation", {}).get("runs", []):
        if not r.get("ok"):
            s = r.get("stages", {})
            stage = next((k for k in ("recursions", "printing", "templates", "latex") if k not in s), "?")
            done = ", ".join(f"{k} {v:.2f} s" for k, v in s.items())
            what = f"killed after {r['wall_seconds']:.0f} s" if r.get("timed_out") else f"failed ({r.get('returncode')})"
            notes.append(f"generation of {r['label']} (not a target): {what} in the {stage} stage"
                         + (f" (finished before it: {done})" if done else "")
                         + (" — models with at most 4 coordinates get closed forms in the LaTeX "
                            "(aggsym/codegen/latex.py, CLOSED_FORM_MAX_NQ), simplified symbolically"
                            if stage == "latex" and r.get("n") is not None and r["n"] <= 4 else ""))
    pairs = _runtime_pairs(results)
    for role in RUNTIME_TARGET_ROLES:
        for robot in ROBOTS:
            p = pairs.get((robot, role))
            if p is None or p["ratio"] <= RUNTIME_RATIO_TARGET:
                continue
            o = _runtime_ops(results, robot).get(role) or runs.get(robot, {}).get("ops", {}).get(role)
            ops = f"; the routine's C has {o['mul']} mul + {o['add']} add + {o['div']} div, {o['call']} calls" \
                if o else ""
            notes.append(f"runtime {robot} {role}: {p['generated_ns']:.0f} ns against {p['pinocchio']} "
                         f"{p['pinocchio_ns']:.0f} ns (ratio {p['ratio']:.2f}, target {RUNTIME_RATIO_TARGET:g}){ops}")
    for r in results.get("runtime", {}).get("constrained", []):
        for p in r["pairs"]:
            if p["ratio"] >= CONSTRAINED_RATIO_TARGET:
                o = r.get("ops") or {}
                notes.append(f"runtime {r['name']} {p['role']}: {p['generated_ns']:.0f} ns against {p['pinocchio']} "
                             f"{p['pinocchio_ns']:.0f} ns (ratio {p['ratio']:.2f}); the routine's C has "
                             f"{o.get('mul')} mul + {o.get('add')} add + {o.get('div')} div, {o.get('call')} calls")
    ops = results.get("opcounts", {}).get(OPS_TARGET_MODEL)
    for row in (ops or {}).get("rows", []):
        if row.get("reference") and row.get("target") and row["ours"] >= row["ref_total"]:
            notes.append(f"op count {row['routine']} ({OPS_TARGET_MODEL}): {row['ours']} (mul {row['mul']}, add "
                         f"{row['add']}, div {row['div']}) against {row['reference']} {row['ref_total']}")
    return notes


def host_lines(results) -> list:
    """The host of the runtime section and Pinocchio's absolute times there, so that hosts can be compared."""
    rt = results.get("runtime", {})
    if not rt.get("robots"):
        return []
    out = [f"host: {rt.get('cpu') or results.get('environment', {}).get('cpu', '?')}; load average before / after "
           f"the harness {rt.get('load_average_before', '?')} / {rt.get('load_average_after', '?')}; harness pinned "
           f"to CPU {rt.get('pinned_cpu', '—')}"]
    for robot in rt["robots"]:
        got = {p["role"]: p for p in robot["pairs"]}
        cells = [f"{p['pinocchio'].split(' ')[0]} {p['pinocchio_ns']:.0f}" for role in PINOCCHIO_HOST_ROLES
                 for p in [got.get(role)] if p]
        if cells:
            out.append(f"Pinocchio ns on {robot['name']}" + (" (an earlier run)" if robot.get("earlier_run") else "")
                       + ": " + ", ".join(cells))
    return out


def summary_text(results) -> str:
    rows = targets(results)
    met = sum(1 for r in rows if r[2] is True)
    body = text_table(("target", "measured", "met"),
                      [(w, m, {True: "yes", False: "NO", None: "not measured"}[ok]) for w, m, ok in rows])
    host = "\n".join(host_lines(results))
    return (host + "\n\n" if host else "") + f"aggsym benchmark targets: {met} of {len(rows)} met\n{body}"


# ---------------------------------------------------------------------------------------------- the report
def _environment(results) -> str:
    env = results.get("environment", {})
    cfg = results.get("config", {})
    v = env.get("versions", {})
    comp = env.get("compilers", {})
    lines = ["## Machine and software", "",
             table(("", ""), [
                 ("date", env.get("date", "—")),
                 ("CPU", env.get("cpu", "—")),
                 ("logical CPUs", str(env.get("logical_cpus", "—"))),
                 ("memory", f"{env['memory_gib']:.1f} GiB" if env.get("memory_gib") else "—"),
                 ("OS", env.get("os", "—")),
                 ("load average (1, 5, 15 min) at start / end",
                  f"{env.get('load_average_start', '—')} / {env.get('load_average_end', '—')}"),
                 ("C compiler", comp.get("cc", "—")),
                 ("C++ compiler", comp.get("c++", "—")),
                 ("Python", env.get("python", "—")),
                 ("aggsym", f"{v.get('aggsym')} (commit {env.get('commit')})"),
                 *[(name, str(v.get(name))) for name in ("sympy", "numpy", "pin", "example-robot-data",
                                                          "cmeel-eigen", "cmeel-urdfdom-headers", "matplotlib")],
             ], "ll"), "",
             "Settings (environment variables of `make bench`, see `benchmarks/run.py`): " +
             ", ".join(f"`{k}={v}`" for k, v in cfg.items()) + ".", ""]
    load = env.get("load_average_start") or []
    if load and env.get("logical_cpus") and max(load) > 0.5 * env["logical_cpus"]:
        lines += [f"**The machine was shared while this ran** (load average {load} at the start on "
                  f"{env['logical_cpus']} CPUs): wall times of section 1 are inflated by other processes; CPU times "
                  "are given beside them.  The runtime ratios of section 3 interleave the two sides batch by batch, "
                  "so both see the same conditions.", ""]
    return "\n".join(lines)


def _generation(results) -> str:
    gen = results.get("generation", {})
    runs = gen.get("runs", [])
    lines = ["## 1. Generation time and peak memory", ""]
    if not runs:
        return "\n".join(lines + ["Not run.", ""])
    lines += ["Each row is one full `aggsym generate MODEL -o benchmarks/build/gen/LABEL` (every routine of the "
              "manifest; C, NumPy, LaTeX, JSON) in a fresh `python -m aggsym` process.  *wall* includes the "
              "interpreter's start and the imports (about 1–2 s); *CPU* is user + system time of that process; "
              "*peak* its maximum resident set (`os.wait4`, so per run).  Each model is generated "
              f"{results.get('config', {}).get('AGGSYM_BENCH_GEN_REPEATS', 1)} times and the run of median wall "
              "time is shown (*all wall s*: every run).  The stage columns are what `aggsym "
              "generate` reports itself.  Chains: `benchmarks/harness/chain.py` (3-D serial arm, joint axes z, y, x, "
              "…, offsets with three non-zero components, full inertia tensors).", ""]
    rows = []
    for r in runs:
        s = r.get("stages", {})
        if not r.get("ok"):
            stage = next((k for k in ("recursions", "printing", "templates", "latex") if k not in s), "")
            status = (f"> {r['wall_seconds']:.0f} (timed out in {stage})" if r.get("timed_out")
                      else f"failed (exit {r.get('returncode')})")
            rows.append((r["label"], r.get("kind", ""), str(r.get("n") or "—"), status, f"{r['cpu_seconds']:.0f}",
                         f"{_mib(r['maxrss_kib']):.0f}", _fmt(s.get("recursions")), _fmt(s.get("printing")),
                         _fmt(s.get("templates")), _fmt(s.get("latex")), "—", ""))
            continue
        rows.append((r["label"], r.get("kind", ""), r["nq"], f"{r['wall_seconds']:.2f}", f"{r['cpu_seconds']:.2f}",
                     f"{_mib(r['maxrss_kib']):.0f}", _fmt(s.get("recursions")), _fmt(s.get("printing")),
                     _fmt(s.get("templates")), _fmt(s.get("latex")), f"{r['c_bytes'] / 1024:.0f}",
                     " ".join(f"{w:.1f}" for w in r.get("all_wall_seconds", [r["wall_seconds"]]))))
    lines += [table(("model", "kind", "n", "wall s", "CPU s", "peak MiB", "recursions s", "printing s",
                     "templates s", "latex s", "C KiB", "all wall s"), rows), ""]
    kane = results.get("kane", {})
    kruns = kane.get("runs", [])
    lines += ["### KanesMethod on the same chains", ""]
    if not kruns:
        lines += ["Not run.", ""]
    else:
        by_label = _gen_runs(results)
        lines += ["`python -m benchmarks.generation.kane chainN.yaml` in a fresh process: sympy.physics.mechanics "
                  "`KanesMethod.kanes_equations` (textbook construction: `orient_axis`, `locatenew`, `v2pt_theory`, "
                  "numbers as SymPy Floats) for the mass matrix M and the forcing f, then `sympy.cse([M, f])`.  "
                  f"Timeout {kane.get('timeout', '—')} s per n on the timed part; n goes up until one exceeds it.  "
                  "*ops* counts the CSE'd M and f printed as C with aggsym's own counter (mul + add + div; integer "
                  "powers as products); *check* is the largest relative difference of (M, f) from aggsym's numeric "
                  "twin (A, −(b + g)) on a random state.  Beside it, aggsym's generation of the same chain (all "
                  "routines) and the count of its `inertia` + `nonlinear_effects` (the same two quantities).", ""]
        rows = []

        def wall(r):
            if not r:
                return "—"
            return f"{r['wall_seconds']:.2f}" if r.get("ok") else f"> {r['wall_seconds']:.0f} (killed)"

        for k in kruns:
            ours = by_label.get(f"chain{k['n']}", {})
            ours_ops = None
            if ours.get("ok"):
                ours_ops = sum(ours["ops"][role][x] for role in ("inertia", "nonlinear_effects")
                               for x in ("mul", "add", "div"))
            if k.get("finished"):
                o = k.get("ops")
                rows.append((k["n"], f"{k['kane_seconds']:.1f}", f"{k['cse_seconds']:.1f}", f"{k['seconds']:.1f}",
                             f"{_mib(k['maxrss_kib']):.0f}", str(o["mul"] + o["add"] + o["div"]) if o else "—",
                             f"{k['relative_error_vs_aggsym']:.1e}" if k.get("relative_error_vs_aggsym") is not None
                             else "—", wall(ours), str(ours_ops) if ours_ops else "—"))
            elif k.get("failed"):
                rows.append((k["n"], "failed", "", "error (see kane.json)", "", "", "", wall(ours),
                             str(ours_ops) if ours_ops else "—"))
            elif k.get("skipped"):
                rows.append((k["n"], "not run", "", k["skipped"], "", "", "", wall(ours),
                             str(ours_ops) if ours_ops else "—"))
            else:
                rows.append((k["n"], f"> {k['timeout']:g} s: killed", "", "timed out",
                             f"{_mib(k.get('process_maxrss_kib')):.0f} (at kill)" if k.get("process_maxrss_kib")
                             else "—", "", "", wall(ours), str(ours_ops) if ours_ops else "—"))
        lines += [table(("n", "Kane s", "cse s", "total s", "peak MiB", "ops (M, f)", "check",
                         "aggsym wall s", "aggsym ops (A, b+g)"), rows), ""]
        at = kane.get("timed_out_at")
        lines += [f"KanesMethod exceeded the timeout first at **n = {at}**." if at is not None else
                  "KanesMethod finished every n it was given.", ""]
    lines += ["![generation time](generation.png)", ""]
    return "\n".join(lines)


def _opcounts(results) -> str:
    ops = results.get("opcounts", {})
    lines = ["## 2. Operation counts", ""]
    if not ops:
        return "\n".join(lines + ["Not run.", ""])
    lines += ["Counts of the emitted C from each manifest (`ops`): `*`, `/`, binary `+`/`−` (subtractions count as "
              "additions, unary minus not counted) and calls (sin, cos, sqrt).  The references "
              "(`aggsym/codegen/ops.py`) are the book's Tables 2.3 and 3.2 (and 2.2, 3.1), its sweeps (2.41)+(2.43) "
              "and Featherstone's general counts CRBA (10n²+22n−32)m + (6n²+37n−43)a, RNEA (93n−108)m + (81n−100)a, "
              "ABA (224n−259)m + (205n−248)a, evaluated at the model's n.  The book's counts and Featherstone's "
              "exclude the trigonometric calls, so the comparison is *mul+add+div* against *ref mul + ref add*.  "
              "Rows marked *info* are not targets (Pinocchio's nonLinearEffects is RNEA with q̈ = 0).", ""]
    order = [OPS_TARGET_MODEL] + [k for k in ops if k != OPS_TARGET_MODEL]
    full = [k for k in order if k in ops and (k == OPS_TARGET_MODEL or k in ROBOTS)]
    for label in full:
        o = ops[label]
        lines += [f"### {label} (n = {o['nq']})", ""]
        rows = []
        for r in o["rows"]:
            if r.get("reference") is None:
                rows.append((r["routine"], r["mul"], r["add"], r["div"], r["ours"], r["call"], "", "", ""))
            else:
                rows.append((r["routine"], r["mul"], r["add"], r["div"], r["ours"], r["call"],
                             r["reference"] + ("" if r.get("target", True) else " (info)"), r["ref_total"],
                             f"{r['ratio']:.2f}"))
        lines += [table(("routine", "mul", "add", "div", "mul+add+div", "calls", "reference", "ref mul+add",
                         "ours/ref"), rows, "lrrrrrlrr"), ""]
    lines += ["### All models: ours / reference (mul+add+div)", ""]
    cols = [("inertia", "Featherstone CRBA"), ("inertia", "book (2.34) A(q), Table 2.3"),
            ("inertia+bias", "book Table 2.3 total (S, A, b, SH)"), ("inverse_dynamics", "Featherstone RNEA"),
            ("inverse_dynamics", "book sweeps (2.41)+(2.43)"), ("forward_dynamics", "Featherstone ABA"),
            ("forward_dynamics", "book Table 3.2 total (q'' by (3.20))")]
    rows = []
    for label in order:
        o = ops[label]
        idx = {(r["routine"], r.get("reference")): r for r in o["rows"]}
        cells = []
        for role, ref in cols:
            r = idx.get((role, ref))
            cells.append(f"{r['ours']} / {r['ref_total']} = {r['ratio']:.2f}" if r else "—")
        rows.append((label, o["nq"], *cells))
    lines += [table(("model", "n", "A vs CRBA", "A vs book (2.34)", "A+b vs Table 2.3", "ID vs RNEA",
                     "ID vs sweeps", "FD vs ABA", "FD vs Table 3.2"), rows), "",
              "![operation counts](opcounts.png)", ""]
    return "\n".join(lines)


def _runtime(results) -> str:
    rt = results.get("runtime", {})
    lines = ["## 3. Runtime", ""]
    if not rt.get("robots"):
        return "\n".join(lines + ["Not run." + (f" {rt['error']}" if rt.get("error") else ""), ""])
    lines += ["ns per call.  The generated C of each robot is compiled `cc -std=c99 -O2 -fPIC` (no `-march=native`, "
              "like the `pin` wheel's libraries) into one shared library; a C batch timer per routine "
              "(`benchmarks/harness/bench.h`) calls it directly.  Pinocchio C++ from the `pin` wheel "
              "(`benchmarks/harness/pinocchio_bench.cpp`, `g++ -std=c++17 -O2 -DNDEBUG` with the wheel's compile "
              "definitions, linked to pinocchio_default, pinocchio_parsers, urdfdom_model) loads the same URDF with "
              "`pinocchio::urdf::buildModel(path, model)` (fixed base) and is called the same way; both sides go "
              "through a shared library.  The harness checks that the generated coordinates are Pinocchio's joints "
              f"in the same order, precomputes {rt.get('states', '—')} random states (q uniform in [−π, π], q̇, q̈, τ "
              "standard normal; continuous joints get (cos, sin) in Pinocchio's q), then per pair alternates one "
              f"batch of the generated routine and one of Pinocchio's on the same states (a batch = "
              f"{rt.get('calls_per_batch', '—')} calls on consecutive states, cycling through all of them; each "
              "output read into a volatile sink), for about "
              f"{rt.get('seconds_per_pair', '—')} s per pair, and reports the **median of the per-batch means** "
              "(q10–q90 of the batch means in brackets).  Batches are short (tens of µs) so that on a shared "
              "machine most of them hold no preemption and the median leaves out those that do; the ratio of the "
              "medians of thread CPU time (`CLOCK_THREAD_CPUTIME_ID`, which excludes preemption) is given beside "
              "as a cross-check.  Before timing, both sides are evaluated on the first "
              "states and compared (*rel. error*: max |ours − theirs| / max |theirs|).", "",
              "Pairing: A(q) ↔ `crba` (Pinocchio fills the **upper triangle only**; the generated code writes the "
              "full n×n matrix), b+g (`nonlinear_effects`) ↔ `nonLinearEffects`, `inverse_dynamics` ↔ `rnea`, "
              "`forward_dynamics` ↔ `aba`, `inertia_inverse` ↔ `computeMinverse` (upper triangle only as well).  "
              "Pinocchio's `crba` and `aba` are timed in both of its conventions (`Convention::LOCAL`, the default, "
              "and `Convention::WORLD`, each checked against the generated code) and the faster is Pinocchio's time "
              "(named in the table).", "",
              "Beyond the five: the runtime section generates the four robots again (untimed, into "
              "`benchmarks/build/runtime/gen/`) with `aggsym generate ROBOT.urdf --routines "
              f"{rt.get('routines', 'default,…')}` (section 1 times the default set alone); the free-flyer variants "
              "(`NAME_ff`, `--floating-base quaternion`) with the default set and the two derivative routines, xarm7 "
              "with the five and the two derivative routines.  "
              "`inverse_dynamics_derivatives` (∂τ/∂q, ∂τ/∂q̇) ↔ `computeRNEADerivatives(model, data, q, v, a)` "
              "(`dtau_dq`, `dtau_dv`: Pinocchio fills both full n×n matrices), `forward_dynamics_derivatives` "
              "(∂q̈/∂q, ∂q̈/∂q̇) ↔ `computeABADerivatives(model, data, q, v, tau)` (`ddq_dq`, `ddq_dv`); each of the "
              "two matrices is compared on its own scale and the larger error shown.  `frame_jacobians` (a 6×n "
              "block per frame: velocity of the frame origin, then angular velocity, world axes) ↔ one "
              "`computeJointJacobians` then `getFrameJacobian(model, data, frame, LOCAL_WORLD_ALIGNED, J)` for each "
              "frame the generated code emits (the manifest's frames: by default the links without a child; "
              "Pinocchio's BODY frames of those links, each J zeroed once, since getFrameJacobian writes only the "
              "columns of the frame's support), timed with and without `updateFramePlacements` (getFrameJacobian "
              "reads `oMi` and the frame's placement, not `oMf`), the faster shown; one call of the generated routine "
              "against the whole sequence.  `regressor` (Y, n × 10 per moving body) ↔ "
              "`computeJointTorqueRegressor(model, data, q, v, a)` (`jointTorqueRegressor`): the layouts agree "
              "(one block per Pinocchio joint, in joint order, (m, m c, I) about the joint frame in Pinocchio's "
              "order, welded links merged), so the full matrices are compared.", ""]
    for robot in rt["robots"]:
        rows = []
        for p in robot["pairs"]:
            rows.append((RUNTIME_LABELS.get(p["role"], p["role"]), p["pinocchio"],
                         f"{p['generated_ns']:.0f} [{p['generated_ns_q10']:.0f}–{p['generated_ns_q90']:.0f}]",
                         f"{p['pinocchio_ns']:.0f} [{p['pinocchio_ns_q10']:.0f}–{p['pinocchio_ns_q90']:.0f}]",
                         f"{p['ratio']:.3f}", _fmt(p.get("cpu_ratio"), 3), f"{p['relative_error']:.1e}",
                         str(p["batches"])))
        lines += [f"### {robot['name']} (n = {robot['nq']}, Pinocchio nq = {robot['pinocchio_nq']})"
                  + (" — from the earlier run" if robot.get("earlier_run") else ""), "",
                  table(("pair", "Pinocchio function", "generated ns", "Pinocchio ns", "ratio", "CPU-time ratio",
                         "rel. error", "batches"),
                        rows), ""]
        if robot.get("frames"):
            lines += [f"Frames of the frame Jacobians ({len(robot['frames'])}): "
                      + ", ".join(f"`{f}`" for f in robot["frames"]) + ".", ""]
    if rt.get("kept_from_earlier_run"):
        lines += ["**This run timed a subset of the robots** (AGGSYM_BENCH_RUNTIME_ROBOTS); the rows of "
                  + ", ".join(rt["kept_from_earlier_run"]) + " are those of the earlier run, kept from runtime.json "
                  "(each ratio is measured within one run, on one robot, so rows of different runs can stand side "
                  "by side; their absolute times cannot be compared).", ""]
    lines += report_derivatives.section(results)
    lines += _peers(results)
    lines += _host(results)
    lines += _constrained(rt)
    comp = rt.get("compile_seconds", {})
    if comp:
        lines += ["Compile times in this run: " + ", ".join(f"{k}: {v:.1f} s" if isinstance(v, (int, float)) else f"{k}: {v} (left out)"
                                                for k, v in comp.items()) + ".", ""]
    pairs = _runtime_pairs(results)
    rows = []
    for robot, figures in DESIGN_PINOCCHIO_NS.items():
        for role, design in figures.items():
            p = pairs.get((robot, role))
            if p:
                rows.append((robot, RUNTIME_LABELS[role], f"{p['pinocchio_ns']:.0f}", str(design),
                             f"{p['pinocchio_ns'] / design:.1f}", f"{p['generated_ns']:.0f}",
                             f"{p['generated_ns'] / design:.2f}"))
    if rows:
        lines += ["### Against the Pinocchio figures quoted in the design brief", "",
                  "The design brief quotes Pinocchio 4.1 times \"measured on this kind of machine\".  The Pinocchio times "
                  "measured here are higher by the factor shown; the last column is what the generated code's ratio "
                  "would be against the design brief's figures instead (a pessimistic reading, if those figures hold for "
                  "some machine of this kind).", "",
                  table(("robot", "pair", "Pinocchio here ns", "design ns", "here / design", "generated ns",
                         "generated / design"), rows), ""]
    lines += ["![runtime ratios](runtime.png)", ""]
    return "\n".join(lines)


def _peers(results) -> list:
    """The three-way table: generated (-O2, -O3), the CasADi peer (-O2, -O3) and Pinocchio, same run, same
    batches."""
    rt = results.get("runtime", {})
    robots = [r for r in rt.get("robots", []) if any(p.get("peers") for p in r["pairs"])]
    if not robots:
        return []
    lines = ["### Generated code, the CasADi peer and Pinocchio in the same batches", "",
             "The second peer (`benchmarks/runtime/casadi_peer.py`): Featherstone's CRBA, RNEA (b+g is RNEA with "
             "q̈ = 0), "
             "ABA and A⁻¹ (ABA columns sharing the articulated inertias) written with CasADi SX in body coordinates "
             "from Pinocchio's model of the same URDF (`pin.buildModelFromUrdf`: parents, placements, axes, "
             "inertias), one-column motion subspaces (Sᵀf is one component, S q̇ one entry), constants folded, "
             "`casadi.cse` on each output, then CasADi's `CodeGenerator` C with wrappers of the generated code's "
             "signatures.  Like the generated code it is straight-line C, so its time depends on the host much as "
             "the generated code's does, unlike Pinocchio's (templated C++ from the `pin` wheel).  Both C codes "
             "are compiled with the same `cc` and flags (`-std=c99 -fPIC`, `-O2` and `-O3`), and every one of the "
             "five timers below runs in the same interleaved batches, on the same states, as the generated "
             "code's and Pinocchio's; each peer is checked against Pinocchio on the first states (*err.*: the "
             "largest relative error against Pinocchio of the four builds).  "
             "solo12_euler: `--floating-base euler` (Pinocchio's composite root PX PY PZ RX RY RZ; the peer "
             "expands it into six one-axis joints joined by massless links).  chain24 and chain48: the chains of "
             "`benchmarks/harness/chain.py` written as URDF (`chain_urdf`; the same numbers as the YAML), which all "
             "three read.  *gen/Pin*: generated -O2 over Pinocchio; *gen/CasADi*: generated over CasADi at the same "
             "level.", ""]
    rows = []
    for robot in robots:
        for p in robot["pairs"]:
            peers = p.get("peers") or {}
            if not peers:
                continue
            ns = lambda label: f"{peers[label]['ns']:.0f}" if label in peers else "—"  # noqa: E731
            err = max([p["relative_error"]] + [x["relative_error"] for x in peers.values()])
            r2, r3 = peer_ratio(p, "O2"), peer_ratio(p, "O3")
            rows.append((robot["name"], RUNTIME_LABELS.get(p["role"], p["role"]).split(" ↔")[0],
                         f"{p['pinocchio_ns']:.0f}", f"{p['generated_ns']:.0f}", ns(GEN_O3), ns(CASADI_O2),
                         ns(CASADI_O3), f"{p['ratio']:.3f}", _fmt(r2, 3), _fmt(r3, 3), f"{err:.1e}"))
    lines += [table(("robot", "routine", "Pinocchio ns", "generated -O2 ns", "generated -O3 ns", "CasADi -O2 ns",
                     "CasADi -O3 ns", "gen/Pin", "gen/CasADi -O2", "gen/CasADi -O3", "err."), rows,
                    "ll" + "r" * 9), ""]
    target_rows = [(robot["name"], p) for robot in robots for p in robot["pairs"]
                   if p.get("peers") and p["role"] in PEER_TARGET_ROLES]
    if target_rows:
        vs_pin = [x for x in target_rows if x[1]["ratio"] <= RUNTIME_RATIO_TARGET]
        vs_cas = [x for x in target_rows if (peer_ratio(x[1]) or math.inf) <= RUNTIME_RATIO_TARGET]
        lines += [f"The issue's target (generated ≤ {RUNTIME_RATIO_TARGET:g} × the peer, A, b+g, ID, FD) in this "
                  f"table: against Pinocchio it holds on {len(vs_pin)} of {len(target_rows)} rows, against the "
                  f"CasADi peer (-O2 both) on {len(vs_cas)} of {len(target_rows)}"
                  + (" (" + ", ".join(f"{r} {p['role']}" for r, p in vs_cas) + ")" if vs_cas else "") + ".", ""]
    info = rt.get("casadi") or {}
    if info:
        lines += ["CasADi peer build (SX expressions + cse, then C): " + "; ".join(
            f"{label} {d['build_seconds']:.1f} s + {d['codegen_seconds']:.1f} s, "
            f"{sum(d['instructions'].values())} CasADi instructions" for label, d in info.items()) + ".", ""]
    return lines


def _host(results) -> list:
    lines = host_lines(results)
    if not lines:
        return []
    return ["### Host of this run", "",
            "To compare hosts: the CPU (from /proc/cpuinfo), the load average just before and after the harness, "
            "the CPU it was pinned to (`os.sched_setaffinity`, AGGSYM_BENCH_CPU), and Pinocchio's absolute "
            "times per robot (the faster convention where two are timed).", ""] + [f"- {x}" for x in lines] + [""]


def _opsn(results) -> str:
    opsn = results.get("opsn") or {}
    lines = ["## 2b. Operations per coordinate (issue 18, item 7)", ""]
    if not opsn.get("rows"):
        return "\n".join(lines + ["Not run.", ""])
    t = opsn["targets"]
    lines += ["mul + add + div of `inverse_dynamics` and `forward_dynamics` from each robot's manifest (`aggsym "
              "generate URDF`, default routines, into `benchmarks/build/opsn/`), divided by n; the calls (sin, cos) "
              f"beside.  Targets: ≤ {t['inverse_dynamics']} n (ID), ≤ {t['forward_dynamics']} n (FD).", ""]
    rows = []
    for r in opsn["rows"]:
        if "error" in r:
            rows.append((r["robot"], r["urdf"], "—", "generation failed", "", "", "", "", ""))
            continue
        i, f = r["inverse_dynamics"], r["forward_dynamics"]
        rows.append((r["robot"], f"`{r['urdf']}`", str(r["n"]), str(i["ops"]), f"{i['per_n']:.1f}",
                     "yes" if i["per_n"] <= t["inverse_dynamics"] else "**no**", str(f["ops"]), f"{f['per_n']:.1f}",
                     "yes" if f["per_n"] <= t["forward_dynamics"] else "**no**"))
    lines += [table(("robot", "URDF (example-robot-data)", "n", "ID ops", "ID ops / n", f"≤ {t['inverse_dynamics']} n",
                     "FD ops", "FD ops / n", f"≤ {t['forward_dynamics']} n"), rows, "llrrrrrrr"), ""]
    return "\n".join(lines)


def _constrained(rt) -> list:
    """The constrained forward dynamics of solo12 on its four feet (benchmarks/runtime/constrained.py), as lines."""
    if "constrained" not in rt and "constrained_error" not in rt:
        return []
    lines = ["### solo12 standing on its four feet: constrained forward dynamics", ""]
    if not rt.get("constrained"):
        return lines + [f"Not run. {rt.get('constrained_error', '')}".rstrip(), ""]
    lines += ["`aggsym generate solo12.urdf --floating-base --constraints feet.yaml` (example-robot-data "
              "`solo_description/robots/solo12.urdf`; the feet FL_FOOT, FR_FOOT, HL_FOOT, HR_FOOT each `block: point` "
              "with the world, 12 constraint rows), routine `constrained_forward_dynamics` (q̈ and λ), against "
              "Pinocchio's `constraintDynamics` on the same URDF with the composite root joint PX, PY, PZ, RX, RY, RZ "
              "(aggsym's `--floating-base`, coordinate for coordinate, so q is the same vector): one "
              "`RigidConstraintModel` CONTACT_3D per foot frame, `initConstraintDynamics` once, default "
              "`ProximalSettings` (μ = 0, one exact solve), in LOCAL_WORLD_ALIGNED (λ in world axes, as aggsym's) "
              "and LOCAL, the faster shown.  Same states and batches as above, except that q̇ is projected onto the "
              "null space of the feet's Jacobian: Pinocchio's drift term equals J̇q̇ only where the feet are at rest, "
              "so only there do both sides solve the same equations.  Before timing, the generated NumPy module is "
              "compared with `pin.constraintDynamics` on a few such states (*pin check*), and the C with "
              "Pinocchio C++ on the first states (*rel. error* of q̈ / of λ).  *ops*: the routine's operation "
              "count from the manifest (mul + add + div, and calls).", ""]
    rows = []
    for r in rt["constrained"]:
        o, check = r.get("ops") or {}, r.get("pinocchio_check") or {}
        for p in r["pairs"]:
            rows.append((f"{r['name']} (n = {r['nq']}, m = {r['nc']})", p["pinocchio"],
                         f"{p['generated_ns']:.0f} [{p['generated_ns_q10']:.0f}–{p['generated_ns_q90']:.0f}]",
                         f"{p['pinocchio_ns']:.0f} [{p['pinocchio_ns_q10']:.0f}–{p['pinocchio_ns_q90']:.0f}]",
                         f"{p['ratio']:.3f}", _fmt(p.get("cpu_ratio"), 3),
                         f"{p['relative_error']:.1e} / {p.get('lambda_relative_error', float('nan')):.1e}",
                         f"{check.get('qdd_relative_error', float('nan')):.1e} ({check.get('states', 0)} states)",
                         f"{o['mul'] + o['add'] + o['div']} ({o['call']} calls)" if o else "—", str(p["batches"])))
    lines += [table(("model", "Pinocchio function", "generated ns", "Pinocchio ns", "ratio", "CPU-time ratio",
                     "rel. error q̈ / λ", "pin check q̈", "ops", "batches"), rows), ""]
    return lines


def _targets(results) -> str:
    rows = targets(results)
    met = sum(1 for r in rows if r[2] is True)
    lines = ["## 4. Targets", "",
             f"{met} of {len(rows)} met.  Generation targets are judged on wall time (CPU time beside it).", "",
             table(("target", "measured", "met"),
                   [(w, m, {True: "yes", False: "**no**", None: "not measured"}[ok]) for w, m, ok in rows], "llr"),
             ""]
    reference = [r for r in results.get("inputs", {}).get("rows", []) if r.get("target_seconds", 0) is None]
    for r in reference:
        lines += [f"Measured without a target: reading and ordering a {r['bodies']}-link {r['file']} took "
                  f"{r['seconds']:.3f} s (median of 3).", ""]
    notes = diagnose(results) + list(results.get("notes") or [])
    if notes:
        lines += ["Where the time goes (missed targets and failed runs):", ""] + [f"- {n}" for n in notes] + [""]
    return "\n".join(lines)


def _extras(results) -> str:
    """Scaling of generation, the sincos helper, --split's compile time and the batched benchmark (each when
    measured)."""
    from .batch import report as batch_report
    from .generation import compile_split, scaling
    from .runtime import casadi_target, constrained_derivatives, python_call, trig

    parts = []
    for key, title, module in (("scaling", "Scaling of generation (benchmarks/generation/scaling.py)", scaling),
                               ("trig", "sin and cos (benchmarks/runtime/trig.py)", trig),
                               ("split", "Compiling with --split (benchmarks/generation/compile_split.py)",
                                compile_split),
                               ("batch", "Batched: JAX, PyTorch and their peers (benchmarks/batch/)", batch_report),
                               ("python_call", "One state from Python: the generated modules beside Pinocchio's Python "
                                               "call (benchmarks/runtime/python_call.py)", python_call),
                               ("constrained_derivatives", "Derivatives of constrained dynamics and of impacts against "
                                                           "Pinocchio (benchmarks/runtime/constrained_derivatives.py)",
                                constrained_derivatives),
                               ("casadi_target", "The CasADi target against the CasADi SX Featherstone peer "
                                                 "(benchmarks/runtime/casadi_target.py)", casadi_target)):
        data = results.get(key)
        if data:
            parts += [f"## {title}", "", module.markdown(data), ""]
    return "\n".join(parts)


def write_report(results, folder) -> Path:
    """Write REPORT.md and the PNG plots into ``folder``; returns the report's path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    report_plots.plot_generation(results, folder / "generation.png")
    report_plots.plot_opcounts(results, folder / "opcounts.png")
    report_plots.plot_runtime(results, folder / "runtime.png", RUNTIME_LABELS, RUNTIME_RATIO_TARGET)
    env = results.get("environment", {})
    parts = [f"# aggsym benchmark ({env.get('date', 'date unknown')})", "",
             "Produced by `make bench` (`benchmarks/run.py`); raw results in `benchmarks/*.json`.  Sections: "
             "1. generation time and peak memory (with KanesMethod), 2. operation counts against the book and "
             "Featherstone, 3. runtime against Pinocchio, 4. the targets and whether each is met.", "",
             _environment(results), _generation(results), _opcounts(results), _opsn(results), _runtime(results),
             _extras(results), _targets(results)]
    path = folder / "REPORT.md"
    path.write_text("\n".join(parts).rstrip() + "\n")
    return path
