"""The batched benchmark's part of the report (:mod:`benchmarks.batch.orchestrator`'s batch.json): the agreement with
Pinocchio, the timing tables, the log-log plot and the issue's targets.  Pure: it reads the dict alone (no
framework, no timing), so tests/test_bench_batch.py renders it from fake data.
"""
from __future__ import annotations

import math
from pathlib import Path

from ..harness.plots import dress, pyplot, save
from ..harness.tables import markdown_table, text_table
from .peers import PROJECT_ENTRIES

ROUTINE_TITLES = {"fd": "forward dynamics", "A": "A(q)", "id": "inverse dynamics",
                  "jac": "Jacobian of forward dynamics w.r.t. (q, v)"}
HUMANOID = "talos"
JIT_TARGET_SECONDS = {"panda": 2.0, "talos": 15.0}
# the agreement targets: values against the NumPy module, the Jacobian against Pinocchio's derivatives
VALUE_AGREEMENT, JACOBIAN_AGREEMENT = 1e-12, 1e-8


def _table(header, rows, left=1) -> str:
    return markdown_table(header, rows, "l" * left + "r" * (len(header) - left))


def _text(header, rows) -> str:
    return text_table(header, rows)


def _us(x) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "—"
    return f"{x:.3g}" if x < 100 else f"{x:.0f}"


def _sizes(data) -> list:
    return [str(b) for b in data.get("config", {}).get("sizes", [])]


def _rows(data, robot=None, routine=None) -> list:
    return [r for r in data.get("rows", []) if (robot is None or r["robot"] == robot)
            and (routine is None or r["routine"] == routine)]


def _timed(data, entry, robot, routine):
    """The row of an entry that ran, agreed and has times; else None."""
    for r in _rows(data, robot, routine):
        if r["entry"] == entry and r.get("sizes"):
            return r
    return None


def _status(r) -> str:
    if "error" in r:
        return "failed: " + r["error"].strip().splitlines()[-1][:160] if r["error"].strip() else "failed"
    a = r["agreement"]
    if not a["ok"]:
        return f"REFUSED: differs from Pinocchio by {a.get('max_relative')} ({a.get('error', a.get('where'))})"
    return f"{a['max_relative']:.1e}"


def project_versions(data) -> str:
    """The sentence naming the framework of the entries run by the project's own venv (none: empty)."""
    seen = sorted({(r["label"], r["framework_version"]) for r in data.get("rows", [])
                   if r.get("entry") in PROJECT_ENTRIES and r.get("framework_version")})
    return "".join(f"  {label}: the project's venv, jax {version}." for label, version in seen)


def _label(r) -> str:
    return r["label"] + (" (an earlier run)" if r.get("earlier_run") else "")


def agreement_rows(data) -> list:
    """robot, entry, then per routine the largest relative difference from Pinocchio (or why there is none)."""
    routines = data.get("config", {}).get("routines", [])
    out = {}
    for r in data.get("rows", []):
        out.setdefault((r["robot"], _label(r)), {})[r["routine"]] = _status(r)
    return [[robot, label] + [got.get(routine, "—") for routine in routines] for (robot, label), got in out.items()]


def _agreement_header(data) -> list:
    return ["robot", "entry"] + [ROUTINE_TITLES.get(r, r) for r in data.get("config", {}).get("routines", [])]


def agreement_text(data) -> str:
    return ("Agreement with Pinocchio (largest difference / largest reference entry) on the first "
            f"{data.get('config', {}).get('check')} states of every batch:\n"
            + _text(_agreement_header(data), agreement_rows(data)))


def timing_rows(data, robot, routine) -> list:
    """entry, then per B 'min / median' µs per state, the first call at the largest B (s), peak memory (MiB)."""
    out = []
    sizes = _sizes(data)
    for r in _rows(data, robot, routine):
        if not r.get("sizes"):
            out.append([_label(r)] + ["—"] * len(sizes) + ["—", "—"])
            continue
        cells = [f"{_us(r['sizes'][b]['min_us'])} / {_us(r['sizes'][b]['median_us'])}" if b in r["sizes"] else "—"
                 for b in sizes]
        first = r["sizes"][max(r["sizes"], key=int)]["first_call_seconds"]
        out.append([_label(r)] + cells + [f"{first:.2f}" if first is not None else "—",
                                           f"{r.get('maxrss_mib', float('nan')):.0f}"])
    return out


def _earlier_hosts(data) -> str:
    """What the report says of the rows kept from earlier runs on other hosts (their ratios to this run's rows
    compare two machines)."""
    hosts = sorted({r["host"] for r in data.get("rows", []) if r.get("earlier_run") and r.get("host")
                    and r["host"] != data.get("host")})
    if not hosts:
        return ""
    return ("  The rows marked *an earlier run* were measured on another host (" + "; ".join(hosts) + "): a ratio "
            "or target between one of them and a row of this run compares two machines.")


def _header(data) -> list:
    return ["entry"] + [f"B = {b}" for b in _sizes(data)] + ["first call at its largest B, s", "peak MiB"]


def timing_text(data) -> str:
    parts = [f"Host: {data.get('host', 'unknown')}.  µs per state, min / median over interleaved samples."]
    for robot in data.get("robots", {}):
        for routine in data.get("config", {}).get("routines", []):
            parts += [f"\n{robot}: {ROUTINE_TITLES.get(routine, routine)}",
                      _text(_header(data), timing_rows(data, robot, routine))]
    return "\n".join(parts)


# ------------------------------------------------------------------------------------------------- targets
def _largest(data, robot, entries=None) -> str:
    """The largest batch size measured on the robot (a run may have measured a robot on fewer sizes); with
    ``entries``, the largest that each of them measured (on some routine) where they share one (the PyTorch
    entries of a robot may run on more sizes than its JAX ones)."""
    rows = [r for r in _rows(data, robot) if r.get("sizes")]
    if entries is not None:
        shared = None
        for entry in entries:
            mine = {int(b) for r in rows if r["entry"] == entry for b in r["sizes"]}
            if mine:
                shared = mine if shared is None else shared & mine
        if shared:
            return str(max(shared))
    got = {int(b) for r in rows for b in r["sizes"]}
    return str(max(got)) if got else (_sizes(data)[-1] if _sizes(data) else "?")


def _at(data, entry, robot, routine, b=None, key="min_us"):
    r = _timed(data, entry, robot, routine)
    if r is None:
        return None
    b = b or _largest(data, robot)
    return r["sizes"].get(b, {}).get(key)


def _jacobian_rows(data, robot, entry, big, required=False) -> list:
    """The Jacobian's two targets for an aggsym JAX entry (none where it was not measured, unless ``required``)."""
    ours = _at(data, entry, robot, "jac", big)
    if ours is None and not required:
        return []
    label = data["entries"][entry]["label"] if entry in data.get("entries", {}) else "aggsym JAX"
    return [_ratio_row(f"{robot} Jacobian, B = {big}: {label} ≥ 10× faster than adam JAX jacrev", ours,
                       _at(data, "adam_jax", robot, "jac", big), 10),
            _ratio_row(f"{robot} Jacobian, B = {big}: {label} no slower than Pinocchio's computeABADerivatives", ours,
                       _at(data, "pinocchio", robot, "jac", big), 1, strict=False)]


def targets(data) -> list:
    """(target, measured, met: True/False/None) for the issue's Targets at the largest B measured on each robot by
    the aggsym entry of the row (minimum times)."""
    rows = []
    for robot in data.get("robots", {}):
        # the generated module in the peers' jax, and (when measured) in the project's own
        jax_entries = [e for e in ("aggsym_jax", "aggsym_jax_project")
                       if e == "aggsym_jax" or _timed(data, e, robot, "fd") is not None]
        limit = JIT_TARGET_SECONDS.get(robot, JIT_TARGET_SECONDS[HUMANOID])
        for entry in jax_entries:
            big = _largest(data, robot, [entry])
            label = data["entries"][entry]["label"] if entry in data.get("entries", {}) else "aggsym JAX"
            for routine in ("fd", "A"):
                ours = _at(data, entry, robot, routine, big)
                for peer, factor in (("adam_jax", 10), ("jaxsim", 10), ("mjx", 10), ("pinocchio", 1)):
                    theirs = _at(data, peer, robot, routine, big)
                    what = (f"{robot} {ROUTINE_TITLES[routine]}, B = {big}: {label} ≥ {factor}× faster than "
                            f"{data['entries'][peer]['label']}" if factor > 1 else
                            f"{robot} {ROUTINE_TITLES[routine]}, B = {big}: {label} faster per state than the "
                            f"Pinocchio loop")
                    rows.append(_ratio_row(what, ours, theirs, factor))
            rows += _jacobian_rows(data, robot, entry, big, required=entry == "aggsym_jax")
            jit = _at(data, entry, robot, "fd", big, key="first_call_seconds")
            which = "" if entry == "aggsym_jax" else f", {label}"
            rows.append((f"{robot} JIT of forward dynamics ≤ {limit:g} s{which} (first call at B = {big})",
                         "—" if jit is None else f"{jit:.2f} s", None if jit is None else jit <= limit))
        for entry in ("aggsym_jax_rev", "aggsym_jax_project_rev"):  # (the Jacobian alone, where measured)
            rows += _jacobian_rows(data, robot, entry, _largest(data, robot, [entry]))
        big = _largest(data, robot, ["aggsym_torch", "adam_torch"])
        for routine in data.get("config", {}).get("routines", []):
            r = _timed(data, "aggsym_torch", robot, routine)
            if r is None:
                rows.append((f"{robot} {ROUTINE_TITLES[routine]}: PyTorch time per state falls as B grows",
                             "—", None))
            else:
                sizes = [b for b in _sizes(data) if b in r["sizes"]]
                med = [r["sizes"][b]["median_us"] for b in sizes]
                # (one batch size shows no trend: not measured rather than met)
                falls = all(b < a for a, b in zip(med, med[1:])) if len(med) > 1 else None
                rows.append((f"{robot} {ROUTINE_TITLES[routine]}: PyTorch time per state falls as B grows",
                             " → ".join(_us(x) for x in med) + " µs" + ("" if len(med) > 1 else
                                                                      f" (B = {sizes[0]} only)"), falls))
            rows.append(_ratio_row(f"{robot} {ROUTINE_TITLES[routine]}, B = {big}: aggsym PyTorch ≥ 10× faster "
                                   "than adam PyTorch", _at(data, "aggsym_torch", robot, routine, big),
                                   _at(data, "adam_torch", robot, routine, big), 10))
        for entry in ("aggsym_jax", "aggsym_torch"):
            for routine in ("fd", "A", "id"):
                r = next((x for x in _rows(data, robot, routine) if x["entry"] == entry), None)
                d = None if r is None else r.get("against_numpy")
                rows.append((f"{robot} {ROUTINE_TITLES[routine]}: {data['entries'][entry]['label']} equals the "
                             f"NumPy module to {VALUE_AGREEMENT:g}", "—" if d is None else f"{d:.1e}",
                             None if d is None else d <= VALUE_AGREEMENT))
            r = next((x for x in _rows(data, robot, "jac") if x["entry"] == entry and "agreement" in x), None)
            d = None if r is None else r["agreement"]["max_relative"]
            rows.append((f"{robot} Jacobian: {data['entries'][entry]['label']} equals Pinocchio's derivatives to "
                         f"{JACOBIAN_AGREEMENT:g}", "—" if d is None else f"{d:.1e}",
                         None if d is None else d <= JACOBIAN_AGREEMENT))
    return rows


KERNEL_FIRST_CALL_SECONDS, KERNEL_BUILD_SECONDS, KERNEL_PEAK_MIB = 1.0, 120.0, 1024.0
KERNEL_AGREEMENT = 1e-13


def _label_of(data, entry) -> str:
    return data.get("entries", {}).get(entry, {}).get("label", entry)


def _vs(data, robot, routine, big, ours, theirs, factor, what=None):
    """ours ≥ factor× faster per state than theirs (the entries' minimum times at B = big)."""
    what = what or (f"{robot} {ROUTINE_TITLES[routine]}, B = {big}: {_label_of(data, ours)} ≥ {factor:g}× faster "
                    f"per state than {_label_of(data, theirs)}")
    return _ratio_row(what, _at(data, ours, robot, routine, big), _at(data, theirs, robot, routine, big), factor)


def kernel_targets(data) -> list:
    """(target, measured, met) for issue 51's targets: the kernel-backed modules at B = 4096 (or the largest B
    measured) against Pinocchio's batched calls, the traced modules, MJX, adam and the one-state C loop; their
    first calls, build, memory and agreement."""
    rows = []
    traced = lambda robot, e: e if _timed(data, e, robot, "fd") else e.replace("_project", "")  # noqa: E731
    for robot in data.get("robots", {}):
        big = "4096" if "4096" in _sizes(data) else _largest(data, robot)
        if robot == HUMANOID:
            rows.append(_vs(data, robot, "fd", big, "aggsym_jax_kernels", "pinocchio_parallel", 10))
            rows.append(_vs(data, robot, "fd", big, "aggsym_jax_kernels", traced(robot, "aggsym_jax_project"), 10))
            rows.append(_vs(data, robot, "fd", big, "aggsym_jax_kernels", "mjx", 50))
            rows.append(_vs(data, robot, "jac", big, "aggsym_jax_kernels", "pinocchio", 3))
            rows.append(_vs(data, robot, "jac", big, "aggsym_jax_kernels_rev", traced(robot, "aggsym_jax_project_rev"),
                            20))
            rows.append(_vs(data, robot, "fd", big, "aggsym_jax_kernels_all", "pinocchio_parallel_all", 10))
        else:
            for routine in ("fd", "A"):
                ours, loop = _at(data, "aggsym_jax_kernels", robot, routine, big), _at(data, "c_loop", robot,
                                                                                        routine, big)
                rows.append((f"{robot} {ROUTINE_TITLES[routine]}, B = {big}: aggsym JAX kernels ≤ 0.4× the one-state "
                             f"C loop per state", "—" if ours is None or loop is None else
                             f"{ours / loop:.2f}× ({_us(ours)} vs {_us(loop)} µs)",
                             None if ours is None or loop is None else ours <= 0.4 * loop))
                rows.append(_vs(data, robot, routine, big, "aggsym_jax_kernels", traced(robot, "aggsym_jax_project"),
                                4))
        for routine in data.get("config", {}).get("routines", []):
            for torch_entry in ("aggsym_torch_kernels",) + (("aggsym_torch_kernels_func",) if routine == "jac" else ()):
                jx, th = (_at(data, e, robot, routine, big) for e in ("aggsym_jax_kernels", torch_entry))
                rows.append((f"{robot} {ROUTINE_TITLES[routine]}, B = {big}: {_label_of(data, torch_entry)} within "
                             f"1.5× of JAX kernels",
                             "—" if jx is None or th is None else f"{th / jx:.2f}× ({_us(th)} vs {_us(jx)} µs)",
                             None if jx is None or th is None else th <= 1.5 * jx))
            rows.append(_vs(data, robot, routine, big, "aggsym_torch_kernels", "adam_torch", 30))
            for entry in ("aggsym_jax_kernels", "aggsym_jax_kernels_rev", "aggsym_torch_kernels",
                          "aggsym_torch_kernels_func"):
                r = _timed(data, entry, robot, routine)
                if r is None:
                    continue
                first = max(s["first_call_seconds"] or 0.0 for s in r["sizes"].values())
                rows.append((f"{robot} {ROUTINE_TITLES[routine]}: {_label_of(data, entry)} first call ≤ "
                             f"{KERNEL_FIRST_CALL_SECONDS:g} s (every B)", f"{first:.2f} s",
                             first <= KERNEL_FIRST_CALL_SECONDS))
                mib = r.get("maxrss_mib")
                rows.append((f"{robot} {ROUTINE_TITLES[routine]}: {_label_of(data, entry)} peak memory ≤ 1 GiB",
                             "—" if mib is None else f"{mib:.0f} MiB",
                             None if mib is None else mib <= KERNEL_PEAK_MIB))
                d = r.get("against_numpy")
                if d is not None:
                    rows.append((f"{robot} {ROUTINE_TITLES[routine]}: {_label_of(data, entry)} equals the NumPy "
                                 f"module to {KERNEL_AGREEMENT:g}", f"{d:.1e}", d <= KERNEL_AGREEMENT))
        build = data.get("robots", {}).get(robot, {}).get("generation", {}).get("kernels_build")
        rows.append((f"{robot}: the kernels' build (double, float, the XLA binding) ≤ {KERNEL_BUILD_SECONDS:g} s",
                     "—" if not build else f"{build['seconds']:.0f} s, peak {build['maxrss_mib']:.0f} MiB"
                     + ("" if build["ok"] else " (FAILED)"),
                     None if not build else build["ok"] and build["seconds"] <= KERNEL_BUILD_SECONDS))
    return rows


def _ratio_row(what, ours, theirs, factor, strict=True):
    if ours is None or theirs is None:
        return (what, "not measured" if ours is None else "peer not measured", None)
    ratio = theirs / ours
    return (what, f"{ratio:.2f}× ({_us(ours)} vs {_us(theirs)} µs)", ratio >= factor if strict else ratio >= factor)


def targets_text(data) -> str:
    rows = targets(data)
    met = sum(1 for r in rows if r[2] is True)
    kernels = kernel_targets(data)
    met_k = sum(1 for r in kernels if r[2] is True)
    return (f"Targets of issue 32 (batched benchmark): {met} of {len(rows)} met\n"
            + _text(("target", "measured", "met"),
                    [(w, m, {True: "yes", False: "NO", None: "not measured"}[ok]) for w, m, ok in rows])
            + f"\n\nTargets of issue 51 (the batch kernels): {met_k} of {len(kernels)} met\n"
            + _text(("target", "measured", "met"),
                    [(w, m, {True: "yes", False: "NO", None: "not measured"}[ok]) for w, m, ok in kernels]))


# ---------------------------------------------------------------------------------------------------- plot
def plot(data, path: Path) -> bool:
    """µs per state (minimum) against B, log-log, one line per entry; a panel per robot and routine."""
    robots = list(data.get("robots", {}))
    routines = data.get("config", {}).get("routines", [])
    if not robots or not routines or not any(r.get("sizes") for r in data.get("rows", [])):
        return False
    plt = pyplot()
    fig, axes = plt.subplots(len(robots), len(routines), figsize=(4.2 * len(routines), 3.6 * len(robots)),
                             squeeze=False)
    entries = list(data.get("entries", {}))
    for i, robot in enumerate(robots):
        for j, routine in enumerate(routines):
            ax = axes[i][j]
            for r in _rows(data, robot, routine):
                if not r.get("sizes"):
                    continue
                bs = sorted(int(b) for b in r["sizes"])
                k = entries.index(r["entry"]) if r["entry"] in entries else 0
                ax.plot(bs, [r["sizes"][str(b)]["min_us"] for b in bs], "o-" if "aggsym" in r["entry"] else "s--",
                        color=f"C{k % 10}", label=r["label"], lw=2 if "aggsym" in r["entry"] else 1, ms=4)
            ax.set_xscale("log")
            ax.set_yscale("log")
            dress(ax, "batch size B", "µs per state (min)", f"{robot}: {ROUTINE_TITLES.get(routine, routine)}",
                  legend=6, title_size=9)
    save(fig, path, dpi=100)
    return True


# -------------------------------------------------------------------------------------------------- REPORT.md
def markdown(data) -> str:
    """The section of REPORT.md: host, settings, how each Jacobian is taken, agreement, tables, plot, targets."""
    cfg = data.get("config", {})
    env = data.get("environment", {})
    lines = [f"**The section did not complete: {data['error']}**", ""] if data.get("error") else []
    lines += [f"- {note}" for note in data.get("notes", [])] + ([""] if data.get("notes") else [])
    if not data.get("rows"):
        return "\n".join(lines or ["No results."])
    lines += [f"Host: {data.get('host', 'unknown')}; {env.get('date', '')}; load average "
             f"{env.get('load_average_start')} → {env.get('load_average_end')}.  Settings: B = "
             f"{', '.join(_sizes(data))}, {cfg.get('repeats')} interleaved samples per B of ≥ "
             f"{cfg.get('sample_seconds')} s, {cfg.get('rounds')} round(s); float64 on the CPU; each "
             "(entry, robot, routine) in its own process (`python -m benchmarks.batch`, in `.venv-batch`)."
             + _earlier_hosts(data), "",
             "Versions: " + ", ".join(f"{k} {v}" for k, v in env.get("peer_versions", {}).items()) + "."
             + project_versions(data), "",
             "Robots: " + "; ".join(f"{k} (nq = {v['nq']}, nv = {v['nv']}"
                                     + (", Pinocchio's free-flyer" if v.get("floating") else ", fixed base") + ")"
                                     for k, v in data.get("robots", {}).items()) + ".", "",
             "How each entry's Jacobian is taken (in Pinocchio's tangent space for the free-flyer, through a "
             "first-order retraction, `benchmarks/batch/peers.py`):", ""]
    lines += [f"- {v['label']}: {v['jacobian']}" for v in data.get("entries", {}).values()]
    lines += ["", "Agreement with Pinocchio before any time (an entry beyond the tolerance "
              f"{cfg.get('tolerance')} has no times):", "",
              _table(_agreement_header(data), agreement_rows(data), left=2), "",
              "µs per state, min / median; the first call at the largest B is the compile for a jit entry.", ""]
    for robot in data.get("robots", {}):
        for routine in cfg.get("routines", []):
            lines += [f"**{robot}: {ROUTINE_TITLES.get(routine, routine)}**", "",
                      _table(_header(data), timing_rows(data, robot, routine)), ""]
    lines += ["![µs per state against B](batch.png)", ""]
    rows = targets(data)
    met = sum(1 for r in rows if r[2] is True)
    lines += [f"Targets of issue 32: {met} of {len(rows)} met.", "",
              _table(("target", "measured", "met"), left=2, rows=
                     [(w, m, {True: "yes", False: "**no**", None: "not measured"}[ok]) for w, m, ok in rows]), ""]
    rows = kernel_targets(data)
    met = sum(1 for r in rows if r[2] is True)
    lines += [f"Targets of issue 51 (the batch kernels): {met} of {len(rows)} met.", "",
              _table(("target", "measured", "met"), left=2, rows=
                     [(w, m, {True: "yes", False: "**no**", None: "not measured"}[ok]) for w, m, ok in rows]), ""]
    return "\n".join(lines)
