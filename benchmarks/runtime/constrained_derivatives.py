"""The derivatives of constrained dynamics and of impacts (issue 34): the generated C against Pinocchio C++.

    python -m benchmarks.runtime.constrained_derivatives [OUT.json]    # section constrained_derivatives of run.py

Robots (example-robot-data): solo12 on a quaternion free-flyer standing on its four point feet, Talos (the reduced
32-joint model) on a quaternion free-flyer with both soles welded, Panda (fixed base) welded at the hand.  Each is
generated (not timed) with ``--constraints`` and ``--routines`` constrained_forward_dynamics,
constrained_forward_dynamics_derivatives, impulse_dynamics, impulse_dynamics_derivatives into
``benchmarks/build/constrained_derivatives/LABEL``; the C is compiled ``-O2`` as in section 3
(:mod:`benchmarks.runtime.pinocchio_cpp`, :mod:`benchmarks.harness.build`: the same flags, the same wheel's Pinocchio,
its batch timers from ``harness/bench.h`` and the timing loop of ``harness/pinocchio_common.hpp``) with
``harness/constrained_derivatives_bench.cpp``, which first checks every derivative block against Pinocchio on the first
states (relative error, each matrix on its own scale; at most :data:`TOLERANCE`), then times four pairs in interleaved
batches, pinned to one CPU:

* the derivatives alone: ``constrained_forward_dynamics_derivatives`` against ``computeConstraintDynamicsDerivatives``
  (each call after an untimed ``constraintDynamics`` at the same state, as Pinocchio requires; the derivatives'
  call alone is timed), ``impulse_dynamics_derivatives`` against ``computeImpulseDynamicsDerivatives`` (after an
  untimed ``impulseDynamics``);
* value and derivatives: ``constrained_forward_dynamics`` then its derivatives against ``constraintDynamics`` then
  ``computeConstraintDynamicsDerivatives``; ``impulse_dynamics`` then its derivatives against ``impulseDynamics``
  then ``computeImpulseDynamicsDerivatives``.  This is the like-for-like pair (Pinocchio's derivatives need its
  value first, and both sides then hold value and derivatives) and the one the target is judged on.

Pinocchio's contacts in LOCAL_WORLD_ALIGNED and in LOCAL, the faster counting; default ``ProximalSettings`` (an
exact solve).  The forward dynamics at velocities with J qd = 0 (a weld's drift differs from aggsym's elsewhere),
the impacts at any velocity, restitution :data:`RESTITUTION`; states whose Delassus matrix has a condition number
above 1e6 are drawn again.  The host's CPU and load average are recorded; the ratio is generated / Pinocchio
(time per call), and the issue's target is a ratio of at most 1/3 on the quadruped and the humanoid.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

from ..harness.build import C_STD, bench_cpu, cmeel_prefix, compile_c, compile_once, cxx_flags, link_flags, \
    run_command, run_pinned
from ..harness.cli import section_main
from ..harness.environment import cpu_line, load_average
from ..harness.generate import generated_manifest
from ..harness.paths import BUILD as BENCH_BUILD, HARNESS, result_path
from ..harness.robots import FILES, robots_directory
from ..harness.tables import markdown_table
from .pinocchio_cpp import bench_models_source, model_arrays

BUILD = BENCH_BUILD / "constrained_derivatives"
ROUTINES = ("constrained_forward_dynamics,constrained_forward_dynamics_derivatives,impulse_dynamics,"
            "impulse_dynamics_derivatives")
# label -> (example-robot-data file, root ("free": --floating-base quaternion, "fixed"), contacts (frame, rows))
MODELS = {
    "solo12": (FILES["solo12"], "free", (("FL_FOOT", 3), ("FR_FOOT", 3), ("HL_FOOT", 3), ("HR_FOOT", 3))),
    "talos": (FILES["talos"], "free", (("left_sole_link", 6), ("right_sole_link", 6))),
    "panda": (FILES["panda"], "fixed", (("panda_hand", 6),)),
}
TARGET_ROBOTS = ("solo12", "talos")  # the quadruped and humanoid
RATIO_TARGET = 1 / 3  # generated / Pinocchio: "at least 3x faster"
TOLERANCE = 1e-8
RESTITUTION = 0.3
SECONDS = 0.5  # timing budget per pair and robot
STATES = 200
CALLS = 10  # calls per batch: a batch of Talos' derivatives is about a millisecond
PAIRS = ("constrained_forward_dynamics+derivatives", "constrained_forward_dynamics_derivatives",
         "impulse_dynamics+derivatives", "impulse_dynamics_derivatives")
LABELS = {"constrained_forward_dynamics+derivatives": "q̈, λ and their derivatives ↔ constraintDynamics + "
                                                      "computeConstraintDynamicsDerivatives",
          "constrained_forward_dynamics_derivatives": "their derivatives alone ↔ "
                                                      "computeConstraintDynamicsDerivatives alone",
          "impulse_dynamics+derivatives": "q̇⁺, JᵀΛ and their derivatives ↔ impulseDynamics + "
                                          "computeImpulseDynamicsDerivatives",
          "impulse_dynamics_derivatives": "their derivatives alone ↔ computeImpulseDynamicsDerivatives alone"}


def name_of(label: str) -> str:
    """The generated code's name (C prefix) of a robot with its contacts."""
    return f"{label}_contacts"


def constraints_yaml(contacts) -> str:
    """The side file of ``--constraints``: each frame a point contact (3 rows) or a weld (6) with the world."""
    lines = ["constraints:"]
    lines += [f"  - {{name: c{i}, body: {frame}, block: {'point' if rows == 3 else 'weld'}}}"
              for i, (frame, rows) in enumerate(contacts)]
    return "\n".join(lines) + "\n"


def generate(label: str, urdf: Path, outdir: Path, timeout: float | None = 600) -> dict:
    """``aggsym generate URDF [--floating-base quaternion] --constraints C.yaml --routines ROUTINES`` in a fresh
    process (not timed); returns the manifest."""
    _, root, contacts = MODELS[label]
    outdir.mkdir(parents=True, exist_ok=True)
    side = outdir.parent / f"{label}_constraints.yaml"
    side.write_text(constraints_yaml(contacts))
    return generated_manifest(urdf, outdir, name_of(label), *(["--floating-base", "quaternion"] if root == "free"
                                                              else []),
                              "--constraints", side, "--routines", ROUTINES, "--name", name_of(label), "-q",
                              timeout=timeout)


def timers_source(manifests: dict) -> str:
    """bench_contacts.c: section 3's clocks and (empty) model lists, then each model's header and its
    BENCH_CONTACT_MODEL record (harness/contact_bench.h); ``manifests``: label -> the generated model's manifest
    (a quaternion coordinate: Pinocchio's free-flyer)."""
    lines = [bench_models_source([]).rstrip("\n"), '#include "contact_bench.h"']
    for label, m in manifests.items():
        name = m["name"]
        arrays, p = model_arrays(m)
        lines += [f'#include "{name}.h"', *arrays]
        free = 1 if any(c["kind"] == "quaternion" for c in m["coordinates"]) else 0
        lines.append(f"BENCH_CONTACT_MODEL({name}, {m['nq']}, {m.get('nv', m['nq'])}, {m['constraints']['m']}, "
                     f"{free}, {len(m['parameters'])}, {p}, {RESTITUTION!r}, {name}_joints)")
    lines.append("const bench_contact_model *const bench_contact_models[] = {"
                 + "".join(f"&{m['name']}_contact_bench, " for m in manifests.values()) + "NULL};")
    return "\n".join(lines) + "\n"


def build(folders: dict, manifests: dict, log=print) -> dict:
    """Compile each generated NAME.c (-O2, section 3's flags) into one shared library, the timers, and the harness
    (reused while its command and sources are unchanged).  Returns {"executable", "compile_seconds"}."""
    BUILD.mkdir(parents=True, exist_ok=True)
    cc, cxx = os.environ.get("CC", "cc"), os.environ.get("CXX", "g++")
    times, objects = {}, []
    for label, folder in folders.items():
        name = manifests[label]["name"]
        obj = BUILD / f"{name}.o"
        seconds = compile_c(Path(folder) / f"{name}.c", obj, log)
        if seconds is not None:
            times[f"cc -O2 {name}.c"] = seconds
        objects.append(obj)
    library = BUILD / "libaggsym_contacts.so"
    run_command([cc, "-shared", "-o", library, *objects, "-lm"], log)
    timers = BUILD / "bench_contacts.c"
    timers.write_text(timers_source(manifests))
    includes = [f"-I{HARNESS}", *sorted({f"-I{Path(d)}" for d in folders.values()})]
    run_command([cc, *C_STD, *includes, "-c", timers, "-o", BUILD / "bench_contacts.o"], log)
    prefix = cmeel_prefix()
    src = HARNESS / "constrained_derivatives_bench.cpp"
    obj = BUILD / "constrained_derivatives_bench.o"
    cmd = [cxx, *cxx_flags(prefix), "-c", str(src), "-o", str(obj)]
    text = "".join((HARNESS / f).read_text() for f in ("bench.h", "contact_bench.h", "pinocchio_common.hpp"))
    seconds = compile_once(cmd, obj, src.read_text() + text, log)
    if seconds is not None:
        times["c++ -O2 constrained_derivatives_bench.cpp"] = seconds
    exe = BUILD / "constrained_derivatives_bench"
    run_command([cxx, "-o", exe, obj, BUILD / "bench_contacts.o", f"-L{BUILD}", f"-Wl,-rpath,{BUILD}",
                 "-laggsym_contacts", *link_flags(prefix), "-lm"], log)
    return {"executable": exe, "compile_seconds": times}


def run(log=print, seconds: float = SECONDS, states: int = STATES, calls: int = CALLS, labels=None) -> dict:
    """Generate, build, check and time every robot of MODELS (or ``labels``); returns the section's results."""
    root = robots_directory()
    labels = list(labels or MODELS)
    manifests, folders = {}, {}
    for label in labels:
        folders[label] = BUILD / label
        log(f"generating {label} with its contacts into {folders[label]} (not timed) ...")
        manifests[label] = generate(label, root / MODELS[label][0], folders[label])
    built = build(folders, manifests, log=lambda m: log("  " + m[:200]))
    cmd = [built["executable"], str(seconds), str(states), str(calls), BUILD / "raw.json"]
    for label in labels:
        urdf, kind, contacts = MODELS[label]
        cmd += [manifests[label]["name"], root / urdf, kind, ",".join(f"{f}:{r}" for f, r in contacts)]
    cpu = bench_cpu()
    load = load_average()
    log(f"host: {cpu_line()}; load average {load}; pinned to CPU {cpu}")
    run_pinned(cmd, cpu, log, what="constrained_derivatives_bench")
    data = json.loads((BUILD / "raw.json").read_text())
    by_name = {manifests[label]["name"]: label for label in labels}
    for model in data["models"]:
        label = by_name[model["name"]]
        model["label"] = label
        model["ops"] = {role: manifests[label]["ops"][role] for role in ROUTINES.split(",")}
        model["agrees"] = all(e <= TOLERANCE for e in model["relative_errors"].values())
    data.update({"cpu": cpu_line(), "pinned_cpu": cpu, "load_average_before": load,
                 "load_average_after": load_average(), "compile_seconds": built["compile_seconds"],
                 "tolerance": TOLERANCE, "ratio_target": RATIO_TARGET, "target_robots": list(TARGET_ROBOTS)})
    return data


def _pair(model: dict, role: str) -> dict | None:
    return next((p for p in model["pairs"] if p["role"] == role), None)


def targets(data: dict) -> list:
    """Rows (target, measured, met) for report.targets: value + derivatives against Pinocchio's pair, on the
    quadruped and the humanoid (met only where the derivatives also agree with Pinocchio's)."""
    rows = []
    models = {m["label"]: m for m in data.get("models", [])}
    for role, what in (("constrained_forward_dynamics+derivatives", "constrained forward dynamics derivatives"),
                       ("impulse_dynamics+derivatives", "impulse dynamics derivatives")):
        text = (f"runtime {what} (value + derivatives ↔ Pinocchio's value + derivatives): generated/Pinocchio ≤ "
                f"1/3 on {' and '.join(TARGET_ROBOTS)}")
        got = [(label, models.get(label)) for label in TARGET_ROBOTS]
        if not data.get("models") or any(m is None for _, m in got):
            rows.append((text, "not measured" + (f": {data['error']}" if data.get("error") else ""), None))
            continue
        measured = ", ".join(f"{label} {_pair(m, role)['ratio']:.2f} (derivatives alone "
                             f"{_pair(m, role.replace('+', '_'))['ratio']:.2f})" for label, m in got)
        rows.append((text, measured, all(_pair(m, role)["ratio"] <= RATIO_TARGET and m["agrees"] for _, m in got)))
    return rows


def markdown(data: dict) -> str:
    """The section's text and table for REPORT.md."""
    if data.get("error") and not data.get("models"):
        return f"Not run: {data['error']}"
    lines = ["`aggsym generate URDF --constraints C.yaml --routines constrained_forward_dynamics,"
             "constrained_forward_dynamics_derivatives,impulse_dynamics,impulse_dynamics_derivatives` (solo12 and "
             "Talos with `--floating-base quaternion`), compiled -O2 as in section 3, against Pinocchio C++ "
             "(`harness/constrained_derivatives_bench.cpp`, `benchmarks/runtime/constrained_derivatives.py`): solo12 "
             "on its "
             "four point feet (12 rows), Talos on its two welded soles (12 rows), Panda welded at the hand (6 rows).  "
             "Before timing, every derivative block (∂q̈/∂(q, q̇, τ), ∂(Jᵀλ)/∂(q, q̇, τ), ∂q̇⁺/∂(q, q̇⁻), "
             "∂(JᵀΛ)/∂(q, q̇⁻)) is compared with Pinocchio's on the first states (*worst rel. error*, each matrix "
             f"on its own scale; at most {data.get('tolerance', TOLERANCE):g}).  Then each pair is timed in "
             f"interleaved batches of {data.get('calls_per_batch')} calls over {data.get('states')} states (median of "
             "the per-batch means, ns per call, [10 %–90 %]); Pinocchio's contacts in LOCAL_WORLD_ALIGNED and LOCAL, "
             "the faster shown.  *value + derivatives*: our value routine then our derivatives routine against "
             "Pinocchio's value call then its derivatives call (Pinocchio computes the derivatives from the value's "
             "factorization, so this is the like-for-like pair, and the target's); *derivatives alone*: our "
             "derivatives routine against Pinocchio's derivatives call alone, each timed after an untimed value "
             "call at the same state.  The forward dynamics at velocities with J q̇ = 0, the impacts at random "
             f"velocities with restitution r = {RESTITUTION:g}.  *ops*: mul + add + div of the generated routines "
             "(value + derivatives) from the manifest.", "",
             f"Host: {data.get('cpu', '?')}, pinned to CPU {data.get('pinned_cpu')}; load average "
             f"{data.get('load_average_before')} before, {data.get('load_average_after')} after (the ratio is "
             "measured within one batch pair, so a loaded host affects both sides alike, their absolute times "
             "not).", ""]
    rows = []
    for m in data.get("models", []):
        ops = m.get("ops", {})
        for role in PAIRS:
            p = _pair(m, role)
            if p is None:
                continue
            routines = [r for r in ops if (r.startswith("impulse") == role.startswith("impulse"))
                        and (r.endswith("derivatives") or "+" in role)]
            count = sum(ops[r]["mul"] + ops[r]["add"] + ops[r]["div"] for r in routines)
            errors = {k: v for k, v in m["relative_errors"].items()
                      if k.startswith(("dqd_plus", "dimpulse")) == role.startswith("impulse")}
            target = m["label"] in TARGET_ROBOTS and "+" in role
            rows.append((f"{m['label']} (nv = {m['nv']}, m = {m['nc']})", LABELS[role], p["pinocchio"],
                         f"{p['generated_ns']:.0f} [{p['generated_ns_q10']:.0f}–{p['generated_ns_q90']:.0f}]",
                         f"{p['pinocchio_ns']:.0f} [{p['pinocchio_ns_q10']:.0f}–{p['pinocchio_ns_q90']:.0f}]",
                         f"{p['ratio']:.3f}", f"{1 / p['ratio']:.2f}×",
                         ("yes" if p["ratio"] <= RATIO_TARGET else "**no**") if target else "—",
                         f"{max(errors.values()):.1e}", str(count), str(p["batches"])))
    lines += [_table(("robot", "pair", "Pinocchio (faster convention)", "generated ns", "Pinocchio ns", "ratio",
                      "speed-up", "≥ 3× (target)", "worst rel. error", "ops", "batches"), rows), ""]
    comp = data.get("compile_seconds", {})
    if comp:
        lines += ["Compile times in this run: " + ", ".join(f"{k}: {v:.1f} s" for k, v in comp.items()) + ".", ""]
    return "\n".join(lines)


def _table(header, rows) -> str:
    return markdown_table(header, rows, "ll" + "l" + "r" * (len(header) - 3), cell=str)


def main(argv=None) -> int:
    results = section_main(run, markdown, argv, default=result_path("constrained_derivatives"), indent=1,
                           log=lambda m: print(m, flush=True))
    for what, measured, met in targets(results):
        print(f"{what}: {measured} -> {'met' if met else 'NOT met' if met is False else 'not measured'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
