"""The generated Python's per-call time for one state, beside Pinocchio's Python call (issue 35, item 4).

``python -m benchmarks.runtime.python_call [OUT.json]`` (section ``python`` of ``benchmarks/run.py``): for each robot of
:data:`ROBOTS`, ``aggsym generate URDF --targets c,numpy,manifest,ext --routines FIVE --name LABEL`` into
``benchmarks/build/python_call/LABEL`` (not timed; the ext module's C extension is compiled at its first import,
not timed either), then, on the same :data:`STATES` random states, each of the five routines called one state per
call from Python: the NumPy module ``LABEL.py`` (its array code on 1-D inputs), the ext module ``LABEL_ext.py``
(the compiled C behind the same functions) and Pinocchio's bindings (``crba``, ``nonLinearEffects``, ``rnea``,
``aba``, ``computeMinverse``, one ``Data`` made beforehand, as a Python controller would).  The three are first
checked to agree on the first states (upper triangles of A and A^-1: Pinocchio's Python ``crba`` and
``computeMinverse`` fill that alone).  A pass is a loop of calls through the states, about :data:`PASS_SECONDS`
long (at least 10 calls), for each of the three in turn (interleaved, so that a busy moment of a shared machine
falls on all three alike); each figure is the best of :data:`PASSES` passes, the mean time per call of that pass
in microseconds of the process's CPU time (``time.process_time``: other processes' turns on a shared machine do not
count; the loop's own cost, a few tens of ns, is in every figure alike).  Short passes and the best of many: some
pass of each runs with its caches undisturbed.  The load average is recorded beside them.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ..harness.cli import section_main
from ..harness.environment import cpu_line, load_average
from ..harness.generate import aggsym_generate, load_module
from ..harness.paths import BUILD as BENCH_BUILD, result_path
from ..harness.robots import FILES, FIVE, robots_directory

BUILD = BENCH_BUILD / "python_call"
# label -> example-robot-data file; xarm7: a 7-DOF arm, as the issue's
ROBOTS = {label: FILES[label] for label in ("xarm7", "ur5", "panda")}
ROUTINES = FIVE.split(",")
STATES = 200
PASSES = 41
PASS_SECONDS = 0.005
TOLERANCE = 1e-9


def _pinocchio(urdf: Path):
    """{role: f(q, qd, x)} of Pinocchio's Python calls, and its nq."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    calls = {"inertia": lambda q, qd, x: pin.crba(model, data, q),
             "nonlinear_effects": lambda q, qd, x: pin.nonLinearEffects(model, data, q, qd),
             "inverse_dynamics": lambda q, qd, x: pin.rnea(model, data, q, qd, x),
             "forward_dynamics": lambda q, qd, x: pin.aba(model, data, q, qd, x),
             "inertia_inverse": lambda q, qd, x: pin.computeMinverse(model, data, q)}
    return calls, model.nq


def _ours(module) -> dict:
    return {"inertia": lambda q, qd, x: module.inertia(q),
            "nonlinear_effects": lambda q, qd, x: module.nonlinear_effects(q, qd),
            "inverse_dynamics": lambda q, qd, x: module.inverse_dynamics(q, qd, x),
            "forward_dynamics": lambda q, qd, x: module.forward_dynamics(q, qd, x),
            "inertia_inverse": lambda q, qd, x: module.inertia_inverse(q)}


def per_call_us(functions: dict, states) -> dict:
    """{side: the best over PASSES of the mean microseconds per call of its function}, the sides timed in turn
    within each pass; a pass calls the function about PASS_SECONDS long (at least 10 calls), cycling through the
    states from where the last pass stopped, so that every state is used."""
    count, at = {}, dict.fromkeys(functions, 0)
    for side, f in functions.items():
        t0 = time.process_time()
        for q, qd, x in states[:10]:
            f(q, qd, x)
        count[side] = max(10, int(PASS_SECONDS / max((time.process_time() - t0) / 10, 1e-9)))
    best = dict.fromkeys(functions, float("inf"))
    for _ in range(PASSES):
        for side, f in functions.items():
            chosen = [states[(at[side] + k) % len(states)] for k in range(count[side])]
            at[side] = (at[side] + count[side]) % len(states)
            t0 = time.process_time()
            for q, qd, x in chosen:
                f(q, qd, x)
            best[side] = min(best[side], (time.process_time() - t0) / count[side])
    return {side: t * 1e6 for side, t in best.items()}


def _agree(role, a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.ndim == 2:  # Pinocchio's Python crba and computeMinverse fill the upper triangle
        a, b = np.triu(a), np.triu(b)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def robot(label: str, urdf: Path, log=print) -> dict:
    folder = BUILD / label
    run = aggsym_generate(urdf, folder, "-q", "--name", label, "--targets", "c,numpy,manifest,ext", "--routines", FIVE)
    if not run.ok:
        return {"robot": label, "error": run.stderr[-1000:]}
    numpy_module = load_module(folder / f"{label}.py", f"{label}_numpy_bench")
    ext_module = load_module(folder / f"{label}_ext.py", f"{label}_ext_bench")  # (compiles its extension here)
    pin_calls, pin_nq = _pinocchio(urdf)
    n = numpy_module.NQ
    if pin_nq != n:
        return {"robot": label, "error": f"Pinocchio's nq {pin_nq} is not aggsym's {n}"}
    rng = np.random.default_rng(0)
    states = [tuple(rng.uniform(-1.0, 1.0, n) for _ in range(3)) for _ in range(STATES)]
    sides = {"numpy": _ours(numpy_module), "ext": _ours(ext_module), "pinocchio": pin_calls}
    rows = []
    for role in ROUTINES:
        worst = {"numpy": 0.0, "ext": 0.0}
        for q, qd, x in states[:20]:
            ref = pin_calls[role](q, qd, x)
            for side in worst:
                worst[side] = max(worst[side], _agree(role, sides[side][role](q, qd, x), ref))
        row = {"routine": role, "relative_error": worst,
               **per_call_us({side: calls[role] for side, calls in sides.items()}, states)}
        rows.append(row)
        log(f"python_call {label} {role}: NumPy module {row['numpy']:.2f} us, ext {row['ext']:.2f} us, "
            f"Pinocchio {row['pinocchio']:.2f} us (errors {worst['numpy']:.1e}, {worst['ext']:.1e})")
    return {"robot": label, "urdf": str(urdf.relative_to(robots_directory())), "n": n, "rows": rows}


def run(log=print) -> dict:
    out = {"cpu": cpu_line(), "load_before": load_average(), "python": sys.version.split()[0], "robots": []}
    root = robots_directory()
    for label, rel in ROBOTS.items():
        out["robots"].append(robot(label, root / rel, log=log))
    out["load_after"] = load_average()
    bad = [(r["robot"], row["routine"]) for r in out["robots"] for row in r.get("rows", [])
           if not max(row["relative_error"].values()) <= TOLERANCE]
    out["agreement"] = f"all within {TOLERANCE:g} relative of Pinocchio" if not bad else f"DISAGREEMENT: {bad}"
    return out


def markdown(results: dict) -> str:
    """Per robot: the five routines' microseconds per call for one state from Python, ours beside Pinocchio's."""
    lines = [f"One state per call from Python ({results.get('python', '')}), microseconds per call: the generated NumPy "
             f"module (`NAME.py`, array code on 1-D inputs), the ext module (`NAME_ext.py`, `--targets c,numpy,ext`: "
             f"the compiled C behind the same functions) and Pinocchio's Python bindings; CPU time, best of {PASSES} "
             f"interleaved passes (each about {PASS_SECONDS * 1e3:g} ms of calls) cycling through {STATES} random states.  Agreement: {results.get('agreement', '')}.  Host: {results.get('cpu', '')}; load "
             f"average {results.get('load_before')} before, {results.get('load_after')} after.", ""]
    for r in results.get("robots", []):
        if "error" in r:
            lines += [f"**{r['robot']}**: not measured: {r['error'].strip()[:300]}", ""]
            continue
        lines += [f"**{r['robot']}** (n = {r['n']}, {r['urdf']})", "",
                  "| routine / Pinocchio | NumPy module (us) | ext module (us) | Pinocchio Python (us) "
                  "| NumPy / Pinocchio | ext / Pinocchio |", "|---|---:|---:|---:|---:|---:|"]
        pin_names = {"inertia": "crba", "nonlinear_effects": "nonLinearEffects", "inverse_dynamics": "rnea",
                     "forward_dynamics": "aba", "inertia_inverse": "computeMinverse"}
        for row in r["rows"]:
            lines.append(f"| {row['routine']} / {pin_names[row['routine']]} | {row['numpy']:.2f} | {row['ext']:.2f} "
                         f"| {row['pinocchio']:.2f} | {row['numpy'] / row['pinocchio']:.1f} "
                         f"| {row['ext'] / row['pinocchio']:.2f} |")
        lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    section_main(run, markdown, argv, default=result_path("python_call"), indent=1, log=lambda m: print(m, flush=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
