"""``make bench``: the whole benchmark, then benchmarks/REPORT.md, benchmarks/*.json, the plots and the targets table.

    python -m benchmarks.run        # from the repository root (make bench does this in .venv)
    python -m benchmarks.run --report-only   # REPORT.md again from the JSONs of the last runs, nothing measured

Settings (environment variables; defaults in brackets):

    AGGSYM_BENCH_CHAINS            chain lengths n for sections 1 and 2                 [4,8,12,16,24,32]
    AGGSYM_BENCH_KANE_TIMEOUT      seconds allowed to one KanesMethod + cse run          [600]
    AGGSYM_BENCH_KANE_MAX_N        largest chain given to KanesMethod                    [32]
                                   (n goes up through AGGSYM_BENCH_CHAINS until one run exceeds the timeout)
    AGGSYM_BENCH_GEN_TIMEOUT       seconds allowed to one aggsym generate               [300]
    AGGSYM_BENCH_GEN_REPEATS       runs per model; the one of median wall time is kept   [3]
    AGGSYM_BENCH_RUNTIME_SECONDS   timing budget per routine pair and robot             [0.5]
    AGGSYM_BENCH_STATES            precomputed random states per robot                  [1000]
    AGGSYM_BENCH_CALLS             calls per timed batch (cycling through the states)  [100]
    AGGSYM_BENCH_RUNTIME_ROBOTS    robots of section 3 (a subset, for a quick run)       [all: ur5,panda,hyq,
                                   talos, their _ff variants, solo12_euler,chain24,chain48,
                                   xarm7]
    AGGSYM_BENCH_PEER_ROBOTS       robots also timed against the CasADi peer and -O3    [ur5,panda,solo12_euler,
                                                                                         talos,chain24,chain48]
    AGGSYM_BENCH_CPU               the CPU the harness is pinned to                      [the last allowed]
    AGGSYM_BENCH_SECTIONS          sections to run: generation,runtime,kane,inputs,     [all]
                                   opsn,scaling,trig,split,batch,python,
                                   constrained_derivatives,casadi
                                   (a section left out is read back from its JSON of an earlier run)
    AGGSYM_BENCH_BATCH_PYTHON      the interpreter of the batch section's own venv      [.venv-batch/bin/python]
                                   (the AGGSYM_BENCH_BATCH_* settings: benchmarks/batch/orchestrator.py)

Sections: 1. generation time and peak memory of every models/*.yaml, the four example-robot-data robots and
the chains, with KanesMethod on the chains (generation.json, kane.json); 2. operation counts from the
manifests (opcounts.json); 3. runtime of the generated C against Pinocchio C++ (runtime.json; the four robots generated again, untimed, with
the routines on request: derivatives, regressor; with solo12
standing on its four feet, constrained forward dynamics against constraintDynamics,
:mod:`benchmarks.runtime.constrained`);
4. parsing a 2000-link YAML and URDF chain (inputs.json, :mod:`benchmarks.generation.inputs`); opsn: the
operations per coordinate of inverse_dynamics and forward_dynamics from the manifests of four arms (opsn.json);
constrained_derivatives: the derivatives of constrained dynamics and of impacts (solo12 on four point feet, Talos
on two welded soles, Panda welded at the hand) against Pinocchio C++ (constrained_derivatives.json,
:mod:`benchmarks.runtime.constrained_derivatives`).

Section 3 also times, for the robots of AGGSYM_BENCH_PEER_ROBOTS (solo12 with the 6-coordinate Euler root, the
24- and 48-link chains of :mod:`benchmarks.harness.chain` written as URDF, generated for this section alone), the
generated C compiled -O3 and a CasADi peer (:mod:`benchmarks.runtime.casadi_peer`) compiled -O2 and -O3, in the same
batches as the generated code and Pinocchio; the harness runs pinned to one CPU, and the host's CPU model and
load average are recorded beside Pinocchio's absolute times.
"""
from __future__ import annotations

import importlib
import os
import sys
import time
from pathlib import Path

from . import report
from .harness.chain import write_chain
from .harness.cli import logger, names
from .harness.environment import cpu_line, environment, load_average
from .harness.paths import BENCHMARKS, BUILD, ROOT, read_json, result_path, write_json
from .harness.robots import FILES, FIVE, ROBOT_FILES, robot_paths, robots_directory

FREE_FLYER_SUFFIX = report.FREE_FLYER_SUFFIX  # the label of a robot generated with --floating-base quaternion
# the derivative routines (issue 52), timed beside the default set on the free-flyer robots and on xarm7
DERIVATIVES = "inverse_dynamics_derivatives,forward_dynamics_derivatives"
# Section 3's robots beyond ROBOT_FILES: label -> (example-robot-data file or chain length, aggsym options,
# Pinocchio root for the CasADi peer, the routines generated)
EXTRA_RUNTIME_ROBOTS = {
    "solo12_euler": (FILES["solo12"], ("--floating-base", "euler", "--name", "solo12_euler"), "euler", FIVE),
    "chain24": (24, (), None, FIVE),
    "chain48": (48, (), None, FIVE),
    "xarm7": (FILES["xarm7"], (), None, f"{FIVE},{DERIVATIVES}"),
}
PEER_ROBOTS = "ur5,panda,solo12_euler,talos,chain24,chain48"
# item 7 of issue 18: operations per coordinate of these arms' inverse and forward dynamics (section opsn)
OPSN_ROBOTS = {label: FILES[label] for label in ("ur5", "panda", "so100", "xarm7")}


def config() -> dict:
    env = os.environ
    return {
        "AGGSYM_BENCH_CHAINS": env.get("AGGSYM_BENCH_CHAINS", "4,8,12,16,24,32"),
        "AGGSYM_BENCH_KANE_TIMEOUT": float(env.get("AGGSYM_BENCH_KANE_TIMEOUT", "600")),
        "AGGSYM_BENCH_KANE_MAX_N": int(env.get("AGGSYM_BENCH_KANE_MAX_N", "32")),
        "AGGSYM_BENCH_GEN_TIMEOUT": float(env.get("AGGSYM_BENCH_GEN_TIMEOUT", "300")),
        "AGGSYM_BENCH_GEN_REPEATS": int(env.get("AGGSYM_BENCH_GEN_REPEATS", "3")),
        "AGGSYM_BENCH_RUNTIME_SECONDS": float(env.get("AGGSYM_BENCH_RUNTIME_SECONDS", "0.5")),
        "AGGSYM_BENCH_STATES": int(env.get("AGGSYM_BENCH_STATES", "1000")),
        "AGGSYM_BENCH_CALLS": int(env.get("AGGSYM_BENCH_CALLS", "100")),
        "AGGSYM_BENCH_SECTIONS": env.get("AGGSYM_BENCH_SECTIONS",
                                         "generation,runtime,kane,inputs,opsn,scaling,trig,split,batch,python,"
                                         "constrained_derivatives,casadi"),
        "AGGSYM_BENCH_BATCH_PYTHON": env.get("AGGSYM_BENCH_BATCH_PYTHON", str(ROOT / ".venv-batch" / "bin" / "python")),
        "AGGSYM_BENCH_RUNTIME_ROBOTS": env.get("AGGSYM_BENCH_RUNTIME_ROBOTS", ""),
        "AGGSYM_BENCH_PEER_ROBOTS": env.get("AGGSYM_BENCH_PEER_ROBOTS", PEER_ROBOTS),
    }


def chain_lengths(cfg) -> list:
    return sorted({int(x) for x in str(cfg["AGGSYM_BENCH_CHAINS"]).split(",") if x.strip()})


log = logger("bench")


def _save(name: str, data):
    write_json(result_path(name), data)


def _load(name: str):
    return read_json(result_path(name))


def models(cfg) -> list:
    """(label, kind, path, n) of every model of section 1, in order."""
    out = [(p.stem, "seed", p, None) for p in sorted((ROOT / "models").glob("*.yaml"))]
    out += [(name, "robot", path, None) for name, path in robot_paths().items()]
    out += [(f"chain{n}", "chain", write_chain(n, BUILD / "chains"), n) for n in chain_lengths(cfg)]
    return out


def section_generation(cfg) -> dict:
    from .generation.measured import generate_measured

    runs = []
    for label, kind, path, n in models(cfg):
        tries = []
        for _ in range(max(1, cfg["AGGSYM_BENCH_GEN_REPEATS"])):
            tries.append(generate_measured(label, path, BUILD / "gen" / label, timeout=cfg["AGGSYM_BENCH_GEN_TIMEOUT"]))
            if not tries[-1]["ok"]:
                break
        # the run of median wall time stands for the model; every run's wall and CPU time are kept
        r = sorted(tries, key=lambda t: t["wall_seconds"])[(len(tries) - 1) // 2] if tries[-1]["ok"] else tries[-1]
        r.update({"kind": kind, "n": n if n is not None else r.get("nq"),
                  "all_wall_seconds": [t["wall_seconds"] for t in tries],
                  "all_cpu_seconds": [t["cpu_seconds"] for t in tries],
                  "all_maxrss_kib": [t["maxrss_kib"] for t in tries]})
        runs.append(r)
        if r["ok"]:
            log(f"generate {label:<26} n={r['nq']:<3} {r['wall_seconds']:7.2f} s wall {r['cpu_seconds']:7.2f} s CPU "
                f"{r['maxrss_kib'] / 1024:7.0f} MiB")
        else:
            log(f"generate {label}: FAILED ({'timed out' if r['timed_out'] else r['returncode']})\n{r.get('stderr', '')}")
    return {"runs": runs}


def section_kane(cfg) -> dict:
    from .generation.measured import kane_measured

    timeout = cfg["AGGSYM_BENCH_KANE_TIMEOUT"]
    runs, timed_out_at, failed_at = [], None, None
    for n in chain_lengths(cfg):
        if n > cfg["AGGSYM_BENCH_KANE_MAX_N"]:
            runs.append({"n": n, "skipped": f"n > AGGSYM_BENCH_KANE_MAX_N = {cfg['AGGSYM_BENCH_KANE_MAX_N']}"})
            continue
        if timed_out_at is not None:
            runs.append({"n": n, "skipped": f"n = {timed_out_at} already exceeded {timeout:g} s"})
            continue
        if failed_at is not None:
            runs.append({"n": n, "skipped": f"the run at n = {failed_at} failed"})
            continue
        log(f"KanesMethod + cse on chain{n} (timeout {timeout:g} s) ...")
        r = kane_measured(write_chain(n, BUILD / "chains"), BUILD / "kane" / f"chain{n}.json", timeout)
        r["n"] = n
        runs.append(r)
        if r["finished"]:
            log(f"kane chain{n}: {r['seconds']:.1f} s (equations {r['kane_seconds']:.1f} s, cse {r['cse_seconds']:.1f} s), "
                f"{r['maxrss_kib'] / 1024:.0f} MiB, ops {r.get('ops')}, check {r.get('relative_error_vs_aggsym')}")
        elif r.get("failed"):
            failed_at = n
            log(f"kane chain{n}: FAILED\n{r.get('stderr', '')}")
        else:
            timed_out_at = n
            log(f"kane chain{n}: exceeded {timeout:g} s")
    return {"timeout": timeout, "runs": runs, "timed_out_at": timed_out_at}


def section_runtime(cfg) -> dict:
    from .generation.measured import generate_measured
    from .harness.build import bench_cpu
    from .harness.chain import write_chain_urdf
    from .runtime import casadi_peer, constrained
    from .runtime.pinocchio_cpp import ROUTINES, build_harness, run_harness

    # The robots' code for this section: its own folders, with the routines on request (section 1 times the
    # default set alone, in build/gen); this generation is not timed.
    root = robots_directory()
    paths = robot_paths()
    wanted = names(cfg["AGGSYM_BENCH_RUNTIME_ROBOTS"])
    take = (lambda label: not wanted or label in wanted)
    runs = {}
    for name in ROBOT_FILES:
        if not take(name):
            continue
        outdir = BUILD / "runtime" / "gen" / name
        log(f"generating {name} into {outdir.relative_to(ROOT)} with --routines {ROUTINES} (not timed) ...")
        runs[name] = generate_measured(name, paths[name], outdir, timeout=cfg["AGGSYM_BENCH_GEN_TIMEOUT"],
                                       routines=ROUTINES)
        if not runs[name]["ok"]:
            return {"error": f"generating {name} with --routines {ROUTINES} failed:\n{runs[name].get('stderr', '')}"}
    # the same robots on Pinocchio's free-flyer (--floating-base quaternion), the default routines, named NAME_ff
    for name in ROBOT_FILES:
        label = f"{name}{FREE_FLYER_SUFFIX}"
        if not take(label):
            continue
        outdir = BUILD / "runtime" / "gen" / label
        log(f"generating {name} with --floating-base quaternion into {outdir.relative_to(ROOT)} (not timed) ...")
        runs[label] = generate_measured(label, paths[name], outdir, timeout=cfg["AGGSYM_BENCH_GEN_TIMEOUT"],
                                        routines=f"default,{DERIVATIVES}",
                                        options=("--floating-base", "quaternion", "--name", label))
        if not runs[label]["ok"]:
            return {"error": f"generating {label} failed:\n{runs[label].get('stderr', '')}"}
    # solo12 on the Euler root and the chains as URDF (the five routines of the CasADi peer's table), xarm7 (the
    # five and the derivatives)
    peer_roots = {name: None for name in ROBOT_FILES}
    for label, (source, options, peer_root, routines) in EXTRA_RUNTIME_ROBOTS.items():
        if not take(label):
            continue
        paths[label] = write_chain_urdf(source, BUILD / "chains") if isinstance(source, int) else root / source
        peer_roots[label] = peer_root
        outdir = BUILD / "runtime" / "gen" / label
        log(f"generating {label} into {outdir.relative_to(ROOT)} with --routines {routines} (not timed) ...")
        runs[label] = generate_measured(label, paths[label], outdir, timeout=cfg["AGGSYM_BENCH_GEN_TIMEOUT"],
                                        routines=routines, options=options)
        if not runs[label]["ok"]:
            return {"error": f"generating {label} failed:\n{runs[label].get('stderr', '')}"}
    labels = list(runs)
    generated = {runs[label]["name"]: Path(runs[label]["outdir"]) for label in labels}
    # the CasADi peer of each robot of AGGSYM_BENCH_PEER_ROBOTS, from Pinocchio's model of the same URDF
    peers, peer_info = {}, {}
    for label in names(cfg["AGGSYM_BENCH_PEER_ROBOTS"]):
        if label not in runs:
            continue
        name = runs[label]["name"]
        folder = BUILD / "runtime" / "casadi"
        log(f"CasADi peer of {label}: building the SX expressions and writing {name}_casadi.c ...")
        info = casadi_peer.write_peer(name, paths[label], folder, root=peer_roots[label])
        log(f"  {info['n']} coordinates, {info['build_seconds']:.1f} s SX + cse, {info['codegen_seconds']:.1f} s "
            f"C; CasADi instructions {info['instructions']}")
        five = Path(runs[label]["outdir"])
        if label in ROBOT_FILES:
            five = BUILD / "runtime" / "gen_five" / label
            log(f"generating {label} with --routines {FIVE} into {five.relative_to(ROOT)} for its -O3 build ...")
            r = generate_measured(label, paths[label], five, timeout=cfg["AGGSYM_BENCH_GEN_TIMEOUT"], routines=FIVE)
            if not r["ok"]:
                return {"error": f"generating {label} with --routines {FIVE} failed:\n{r.get('stderr', '')}"}
        peers[name] = {"casadi": folder, "generated": five}
        peer_info[label] = {k: (str(v) if isinstance(v, Path) else v) for k, v in info.items()}
    # solo12 on its four feet: generated and checked against the pin bindings; a failure here leaves the rest
    feet = {"error": "not among AGGSYM_BENCH_RUNTIME_ROBOTS"}
    if take(constrained.LABEL):
        try:
            feet = constrained.prepare(root / constrained.URDF, BUILD / "runtime" / constrained.NAME,
                                       timeout=cfg["AGGSYM_BENCH_GEN_TIMEOUT"], log=log)
        except Exception as exc:
            feet = {"error": f"{exc.__class__.__name__}: {exc}"}
            log(f"constrained {constrained.LABEL} left out: {feet['error']}")
    with_feet = "error" not in feet
    log("building the runtime harness (the Pinocchio C++ side takes minutes) ...")
    t0 = time.perf_counter()
    built = build_harness(BUILD / "runtime", generated, log=lambda m: log("  " + m[:200]),
                          constrained={constrained.NAME: feet["outdir"]} if with_feet else None, peers=peers)
    log(f"built in {time.perf_counter() - t0:.0f} s")
    robots = {runs[label]["name"]: paths[label.removesuffix(FREE_FLYER_SUFFIX)] for label in labels}
    cpu = bench_cpu()
    log(f"host: {cpu_line()}; load average {load_average()}; the harness pinned to CPU {cpu}")
    data = run_harness(built["executable"], robots, BUILD / "runtime" / "runtime_raw.json",
                       seconds=cfg["AGGSYM_BENCH_RUNTIME_SECONDS"], states=cfg["AGGSYM_BENCH_STATES"],
                       calls=cfg["AGGSYM_BENCH_CALLS"], log=log,
                       constrained={constrained.NAME: (feet["urdf"], feet["frames"])} if with_feet else None,
                       cpu=cpu)
    data["cpu"] = cpu_line()
    data["load_average_after"] = load_average()
    data["casadi"] = peer_info
    data["compile_seconds"] = built["compile_seconds"]
    for entry in data.get("constrained", []):
        entry.update({"model_name": entry["name"], "name": constrained.LABEL, "ops": feet["ops"],
                      "pinocchio_check": feet["check"]})
    if not with_feet:
        data["constrained_error"] = feet["error"]
    # robots are named by their labels (ur5, panda, hyq, talos) in the report
    labels = {runs[label]["name"]: label for label in labels}
    for robot in data["robots"]:
        robot["model_name"] = robot["name"]
        robot["name"] = labels.get(robot["name"], robot["name"])
        # the operation counts of the timed routines, from the manifest of the code timed here
        ops = runs[robot["name"]]["ops"] if robot["name"] in runs else {}
        robot["ops"] = {p["role"]: ops[p["role"]] for p in robot["pairs"] if p["role"] in ops}
    data["routines"] = ROUTINES
    bad = [(r["name"], p["role"], p["relative_error"]) for r in data["robots"] for p in r["pairs"]
           if not p["relative_error"] <= 1e-9]
    bad += [(r["name"], p["role"], label, peer["relative_error"]) for r in data["robots"] for p in r["pairs"]
            for label, peer in p.get("peers", {}).items() if not peer["relative_error"] <= 1e-9]
    tolerance = constrained.TOLERANCE  # qdd of the constrained model, in C (harness) and NumPy (pin bindings)
    bad += [(r["name"], p["role"], p["relative_error"], r["pinocchio_check"]["qdd_relative_error"])
            for r in data.get("constrained", []) for p in r["pairs"]
            if not (p["relative_error"] <= tolerance and r["pinocchio_check"]["ok"])]
    data["agreement"] = ("all pairs (and peers) within 1e-9 relative" + (f", constrained qdd within {tolerance:g}"
                                                              if data.get("constrained") else "")
                         if not bad else f"DISAGREEMENT: {bad}")
    log(f"runtime: {data['agreement']}")
    return data


def section_opsn(cfg) -> dict:
    """Item 7 of issue 18: ops of inverse_dynamics and forward_dynamics per coordinate (mul + add + div of the
    manifest's counts, divided by n) of OPSN_ROBOTS, each generated with the default routines (not timed)."""
    from aggsym.codegen.ops import arithmetic

    from .generation.measured import generate_measured

    root = robots_directory()
    rows = []
    for label, rel in OPSN_ROBOTS.items():
        outdir = BUILD / "opsn" / label
        run = generate_measured(label, root / rel, outdir, timeout=cfg["AGGSYM_BENCH_GEN_TIMEOUT"])
        if not run["ok"]:
            rows.append({"robot": label, "urdf": rel, "error": run.get("stderr", "")[-500:]})
            log(f"opsn {label}: generation FAILED")
            continue
        n = run["nq"]
        row = {"robot": label, "urdf": rel, "name": run["name"], "n": n}
        for role in ("inverse_dynamics", "forward_dynamics"):
            o = run["ops"][role]
            row[role] = {**o, "ops": arithmetic(o), "per_n": arithmetic(o) / n}
        rows.append(row)
        log(f"opsn {label} (n = {n}): inverse_dynamics {row['inverse_dynamics']['per_n']:.1f} n, forward_dynamics "
            f"{row['forward_dynamics']['per_n']:.1f} n")
    return {"rows": rows, "targets": {"inverse_dynamics": 70, "forward_dynamics": 140}}


def _keep_earlier_robots(runtime: dict, earlier: dict) -> dict:
    """A run on a subset of the robots (AGGSYM_BENCH_RUNTIME_ROBOTS) keeps the other robots' rows, and the
    constrained model's, from the earlier runtime.json, each marked ``earlier_run`` (the report says which)."""
    have = {r["name"] for r in runtime["robots"]}
    kept = [dict(r, earlier_run=True) for r in earlier.get("robots", []) if r["name"] not in have]
    runtime["robots"] += kept
    runtime["kept_from_earlier_run"] = [r["name"] for r in kept]
    if not runtime.get("constrained") and earlier.get("constrained"):
        runtime["constrained"] = [dict(r, earlier_run=True) for r in earlier["constrained"]]
        runtime.pop("constrained_error", None)
        runtime["kept_from_earlier_run"] += [r["name"] for r in earlier["constrained"]]
    return runtime


def section_batch(cfg) -> dict:
    """Issue 32's batched benchmark, :mod:`benchmarks.batch`, run in its own venv (its peers pin an older jax than
    the project's): a subprocess whose output is shown as it comes; it writes batch.json and batch.png, read back
    here.  A missing venv or a failed run is reported in the section, not fatal."""
    import subprocess

    from .harness.measure import child_env

    python = Path(cfg["AGGSYM_BENCH_BATCH_PYTHON"])
    if not python.exists():
        return {"error": f"{python} does not exist: make .venv-batch/.ready creates it (make bench does)"}
    log(f"batch section in {python} (python -m benchmarks.batch) ...")
    proc = subprocess.run([str(python), "-m", "benchmarks.batch"], cwd=ROOT, env=child_env())
    if proc.returncode != 0:
        return {**_load("batch"), "error": f"python -m benchmarks.batch exited with {proc.returncode}"}
    return _load("batch")


def section_extras(sections) -> dict:
    """Issue 18's sections: scaling (chains of 6..192 bodies and a 200-body tree, :mod:`benchmarks.generation.scaling`,
    which writes scaling.json and scaling.png itself), trig (the sincos helper against libm,
    :mod:`benchmarks.runtime.trig`) and split (Talos' compile time in one file and with --split,
    :mod:`benchmarks.generation.compile_split`); issue 35's python (the generated Python's per-call time for one state
    beside Pinocchio's Python call, :mod:`benchmarks.runtime.python_call`, python_call.json); issue 34's
    constrained_derivatives (the derivatives of constrained dynamics and of impacts against Pinocchio C++,
    :mod:`benchmarks.runtime.constrained_derivatives`, constrained_derivatives.json); issue 54's casadi (the CasADi
    target's forward dynamics and Jacobians through CasADi's C against the SX Featherstone peer,
    :mod:`benchmarks.runtime.casadi_target`, casadi_target.json)."""
    out = {}
    if "scaling" in sections:
        from .generation import scaling

        out["scaling"] = scaling.run(BUILD / "scaling", progress=log)
    else:
        out["scaling"] = _load("scaling")
    for name, module in (("trig", "runtime.trig"), ("split", "generation.compile_split")):
        if name in sections:
            out[name] = importlib.import_module(f".{module}", __package__).run()
            _save(name, out[name])
        else:
            out[name] = _load(name)
    if "python" in sections:
        from .runtime import python_call

        out["python_call"] = python_call.run(log=log)
        _save("python_call", out["python_call"])
    else:
        out["python_call"] = _load("python_call")
    for section, key, module in (("casadi", "casadi_target", "casadi_target"),
                                 ("constrained_derivatives", "constrained_derivatives", "constrained_derivatives")):
        if section in sections:
            out[key] = _reported(section, lambda m=module: importlib.import_module(f".runtime.{m}", __package__)
                                 .run(log=log))
            _save(key, out[key])
        else:
            out[key] = _load(key)
    return out


def _reported(section: str, run) -> dict:
    """``run()``'s result, or {"error": ...} when it raises (reported in its section, not fatal)."""
    try:
        return run()
    except Exception as exc:  # reported, not fatal
        log(f"{section} section failed: {exc.__class__.__name__}: {exc}")
        return {"error": f"{exc.__class__.__name__}: {exc}"}


SECTION_FILES = ("generation", "kane", "opcounts", "runtime", "inputs", "opsn", "scaling", "trig", "split", "batch",
                 "python_call", "constrained_derivatives", "casadi_target")


def report_only() -> int:
    """``python -m benchmarks.run --report-only``: REPORT.md and the plots written again from the JSONs of the last
    runs, measuring nothing (so a section run on its own, e.g. ``python -m benchmarks.runtime.python_call``, joins the
    report beside the others' figures and their host)."""
    saved = _load("environment")
    results = {"environment": saved.get("environment", {}), "config": saved.get("config", {}),
               **{name: _load(name) for name in SECTION_FILES}}
    path = report.write_report(results, BENCHMARKS)
    log(f"wrote {path.relative_to(ROOT)} from the JSONs of the last runs")
    return 0


def main() -> int:
    if "--report-only" in sys.argv[1:]:
        return report_only()
    t_start = time.perf_counter()
    cfg = config()
    sections = {s.strip() for s in cfg["AGGSYM_BENCH_SECTIONS"].split(",") if s.strip()}
    BUILD.mkdir(parents=True, exist_ok=True)
    env = environment()
    log(f"{env['cpu_line']}, {env['logical_cpus']} CPUs, load {env['load_average_start']}; settings {cfg}")

    generation = section_generation(cfg) if "generation" in sections else _load("generation")
    if "generation" in sections:
        _save("generation", generation)
    from .generation.opcounts import section as opcount_section

    opcounts = opcount_section(generation.get("runs", []))
    _save("opcounts", opcounts)
    if "runtime" in sections:
        try:
            runtime = section_runtime(cfg)
        except Exception as exc:  # reported, not fatal: the other sections still make a report
            runtime = {"error": f"{exc.__class__.__name__}: {exc}"}
            log(f"runtime section failed: {runtime['error']}")
        if cfg["AGGSYM_BENCH_RUNTIME_ROBOTS"] and runtime.get("robots"):
            runtime = _keep_earlier_robots(runtime, _load("runtime"))
        _save("runtime", runtime)
    else:
        runtime = _load("runtime")
    kane = section_kane(cfg) if "kane" in sections else _load("kane")
    if "kane" in sections:
        _save("kane", kane)
    if "inputs" in sections:
        from .generation.inputs import section as inputs_section

        inputs = inputs_section(BUILD / "inputs")
        _save("inputs", inputs)
        for row in inputs["rows"]:
            log(f"load {row['file']} of {row['bodies']} bodies: {row['seconds']:.3f} s (median of 3; target "
                f"{row['target_seconds']:g} s)")
    else:
        inputs = _load("inputs")

    if "opsn" in sections:
        opsn = section_opsn(cfg)
        _save("opsn", opsn)
    else:
        opsn = _load("opsn")
    extras = section_extras(sections)
    extras["batch"] = section_batch(cfg) if "batch" in sections else _load("batch")

    env["load_average_end"] = load_average()
    env["bench_wall_seconds"] = round(time.perf_counter() - t_start, 1)
    results = {"environment": env, "config": cfg, "generation": generation, "kane": kane, "opcounts": opcounts,
               "runtime": runtime, "inputs": inputs, "opsn": opsn, **extras}
    _save("environment", {"environment": env, "config": cfg})
    path = report.write_report(results, BENCHMARKS)
    log(f"wrote {path.relative_to(ROOT)} and the plots in {env['bench_wall_seconds']:.0f} s")
    print()
    print(report.summary_text(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
