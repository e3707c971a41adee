"""Issue 32, item 6: the batched benchmark.  ``python -m benchmarks.batch`` (in the peers' venv, ``.venv-batch``:
``make .venv-batch/.ready``; ``make bench`` runs it through :mod:`benchmarks.run`'s section ``batch``).

Panda (7 DOF: the fingers welded) and Talos on Pinocchio's free-flyer (``--floating-base quaternion``), batches
of B states on the CPU in float64: forward dynamics, A(q), inverse dynamics and the Jacobian of forward
dynamics with respect to (q, v) in Pinocchio's tangent space; the entries of :data:`benchmarks.batch.peers.ENTRIES`
(the generated JAX, PyTorch and NumPy modules, adam-robotics' JAX and PyTorch backends, jaxsim, MuJoCo MJX, a
loop over Pinocchio).  Each (entry, robot, routine) runs in its own process (:mod:`benchmarks.batch.worker`),
whose peak resident memory is the entry's; the first call of each batch shape is its compile time.  Before any
time is printed, every entry's outputs on the first states of every batch are compared with Pinocchio's
(:func:`agreement`): an entry that disagrees by more than the tolerance has its times withheld.

Settings (environment variables; defaults in brackets):

    AGGSYM_BENCH_BATCH_SIZES      batch sizes B                                    [1,64,1024,4096]
    AGGSYM_BENCH_BATCH_ROBOTS     robots (panda, talos)                            [panda,talos]
    AGGSYM_BENCH_BATCH_ROUTINES   routines (fd, A, id, jac)                        [fd,A,id,jac]
    AGGSYM_BENCH_BATCH_ENTRIES    entries (benchmarks/batch/peers.py ENTRIES)      [all]
    AGGSYM_BENCH_BATCH_REPEATS    interleaved samples per batch size               [5]
    AGGSYM_BENCH_BATCH_SAMPLE     seconds one sample should last                   [0.2]
    AGGSYM_BENCH_BATCH_ROUNDS     rounds over all the processes (each a sample set) [1]
    AGGSYM_BENCH_BATCH_CHECK      states of each batch compared with Pinocchio      [16]
    AGGSYM_BENCH_BATCH_TOLERANCE  largest relative difference accepted             [1e-8]
    AGGSYM_BENCH_BATCH_TIMEOUT    seconds allowed to one worker process            [3600]
    AGGSYM_BENCH_BATCH_REUSE      1: keep the generated modules of an earlier run   [0]
    AGGSYM_BENCH_BATCH_PROJECT_PYTHON  the interpreter of the entry aggsym_jax_project [.venv/bin/python]

Writes benchmarks/batch.json and benchmarks/batch.png; :mod:`benchmarks.batch.report` renders the section of
REPORT.md and the targets of the issue.
"""
from __future__ import annotations

import json
import os
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from ..harness.cli import logger, names
from ..harness.environment import cpu_line, environment, load_average, versions
from ..harness.generate import aggsym_generate
from ..harness.measure import child_env, run_measured
from ..harness.paths import BUILD as BENCH_BUILD, ROOT, read_json, result_path, write_json
from ..harness.robots import FILES, robots_directory
from . import report as batch_report
from .peers import ALL_CORES, C_LOOP, ENTRIES, PROJECT_ENTRIES, ROUTINES

BUILD = BENCH_BUILD / "batch"
# label -> (example-robot-data file, free-flyer, joints welded by name)
ROBOTS = {
    "panda": (FILES["panda"], False, ("panda_finger_joint1", "panda_finger_joint2")),
    "talos": (FILES["talos"], True, ()),
}
# (inertia_inverse: the PyTorch module wires its autograd.Function only with both the derivative routine and the
# matrix along tau, as the default routines give them)
GENERATED = "inertia,inertia_inverse,inverse_dynamics,forward_dynamics,forward_dynamics_derivatives"
PLAIN = "inertia,inverse_dynamics,forward_dynamics"
KERNELS = "c,numpy,jax,torch,manifest"  # (with c: the batch kernels behind the JAX and PyTorch modules)


# the frameworks and peers whose versions in this venv batch.json records
PEER_PACKAGES = ("jax", "jaxlib", "torch", "adam-robotics", "jaxsim", "mujoco", "mujoco-mjx", "pin", "numpy")


def config() -> dict:
    env = os.environ
    return {
        "sizes": [int(x) for x in env.get("AGGSYM_BENCH_BATCH_SIZES", "1,64,1024,4096").split(",") if x.strip()],
        "robots": names(env.get("AGGSYM_BENCH_BATCH_ROBOTS", "panda,talos")),
        "routines": names(env.get("AGGSYM_BENCH_BATCH_ROUTINES", ",".join(ROUTINES))),
        "entries": names(env.get("AGGSYM_BENCH_BATCH_ENTRIES", ",".join(ENTRIES))),
        "repeats": int(env.get("AGGSYM_BENCH_BATCH_REPEATS", "5")),
        "sample_seconds": float(env.get("AGGSYM_BENCH_BATCH_SAMPLE", "0.2")),
        "rounds": int(env.get("AGGSYM_BENCH_BATCH_ROUNDS", "1")),
        "check": int(env.get("AGGSYM_BENCH_BATCH_CHECK", "16")),
        "tolerance": float(env.get("AGGSYM_BENCH_BATCH_TOLERANCE", "1e-8")),
        "timeout": float(env.get("AGGSYM_BENCH_BATCH_TIMEOUT", "3600")),
        "reuse": env.get("AGGSYM_BENCH_BATCH_REUSE", "0") == "1",
    }


log = logger("batch")


# ------------------------------------------------------------------------------------------------ preparation
def strip_urdf(source: Path, out: Path, weld=()) -> Path:
    """The URDF's links, joints and inertials alone (no meshes, transmissions, mimics: every peer reads the same
    rigid-body tree; an inertial without <origin> gets URDF's default written out); the joints named in ``weld``
    become fixed."""
    root = ET.parse(source).getroot()
    for child in list(root):
        if child.tag not in ("link", "joint"):
            root.remove(child)
    for link in root.findall("link"):
        for el in list(link):
            if el.tag != "inertial":
                link.remove(el)
            elif el.find("origin") is None:  # URDF's default written out: adam's reader needs it
                ET.SubElement(el, "origin", xyz="0 0 0", rpy="0 0 0")
    for joint in root.findall("joint"):
        for el in joint.findall("mimic"):
            joint.remove(el)
        if joint.get("name") in weld:
            joint.set("type", "fixed")
            for el in joint.findall("limit") + joint.findall("axis") + joint.findall("dynamics"):
                joint.remove(el)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(ET.tostring(root, encoding="unicode"))
    return out


def generate(urdf: Path, outdir: Path, name: str, floating: bool, targets: str, routines: str) -> dict:
    run = aggsym_generate(urdf, outdir, "--name", name, "-q", "--targets", targets, "--routines", routines,
                          *(["--floating-base", "quaternion"] if floating else []), cwd=ROOT, timeout=1800)
    return {"cmd": " ".join(run.cmd[1:]), "ok": run.ok, "seconds": run.wall_seconds,
            "stderr": run.stderr[-2000:] if not run.ok else ""}


def prepare_robot(label: str, cfg) -> dict:
    """The stripped URDF, Pinocchio's dimensions and joint order, the generated modules (the JAX and PyTorch
    targets: when generation fails, the error is kept and those entries report it)."""
    import pinocchio as pin

    rel, floating, weld = ROBOTS[label]
    work = BUILD / label
    urdf = strip_urdf(robots_directory() / rel, work / f"{label}.urdf", weld)
    model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer()) if floating else \
        pin.buildModelFromUrdf(str(urdf))
    joints = [n for n in list(model.names)[1:] if not (floating and n == "root_joint")]
    module = f"{label}_batch"
    robot = {"label": label, "urdf": str(urdf), "floating": floating, "nq": model.nq, "nv": model.nv,
             "joints": joints, "module": module, "work": str(work), "gen": str(work / "gen"),
             "gen_plain": str(work / "gen_plain"), "gen_kernels": str(work / "gen_kernels"), "generation": {}}
    have = (work / "gen" / f"{module}.py").exists()
    if not (cfg["reuse"] and (work / "gen_kernels" / f"{module}_kernels.py").exists()):
        log(f"aggsym generate {label} --targets {KERNELS} --routines {GENERATED}")
        robot["generation"]["kernels"] = generate(urdf, work / "gen_kernels", module, floating, KERNELS, GENERATED)
        if robot["generation"]["kernels"]["ok"]:
            robot["generation"]["kernels_build"] = build_kernels(robot)
            robot["generation"]["c_loop"] = build_c_loop(robot)
    if not (cfg["reuse"] and have):
        for key, folder, targets, routines in (("full", "gen", "numpy,jax,torch,manifest", GENERATED),
                                               ("plain", "gen_plain", "jax", PLAIN)):
            log(f"aggsym generate {label} --targets {targets} --routines {routines}")
            r = generate(urdf, work / folder, module, floating, targets, routines)
            if not r["ok"] and key == "full":
                log(f"  failed:\n{r['stderr']}\n  again with the NumPy module alone")
                r = dict(generate(urdf, work / folder, module, floating, "numpy,manifest", GENERATED),
                         error=r["stderr"])
            robot["generation"][key] = r
    return robot


def build_kernels(robot: dict) -> dict:
    """The batch kernels of the kernels' generation built once (the first import of its JAX module, in the project's
    venv: the C in double and float and the XLA binding), timed from an empty cache (an earlier run's is removed:
    the same sources would load it in seconds); the workers load them from the cache."""
    import shutil
    import time

    folder, module = robot["gen_kernels"], robot["module"]
    shutil.rmtree(Path(folder) / f"{module}_kernels_build", ignore_errors=True)
    script = f"import sys; sys.path.insert(0, {folder!r}); import {module}_jax, {module}_torch"
    log(f"building the batch kernels of {robot['label']} ...")
    t0 = time.perf_counter()
    run = run_measured([interpreter("aggsym_jax_kernels"), "-c", script], env=child_env(), cwd=ROOT, timeout=3600)
    seconds = time.perf_counter() - t0
    log(f"  {'built' if run.ok else 'FAILED'} in {seconds:.1f} s, peak {run.maxrss_kib / 1024:.0f} MiB")
    return {"ok": run.ok, "seconds": seconds, "maxrss_mib": run.maxrss_kib / 1024,
            "stderr": run.stderr[-2000:] if not run.ok else ""}


def build_c_loop(robot: dict) -> dict:
    """The one-state C of the kernels' generation and a plain loop over it (:data:`peers.C_LOOP`) as a shared library
    (``cc -O2``, portable flags: the C a controller links)."""
    import subprocess
    import time

    folder, module = Path(robot["gen_kernels"]), robot["module"]
    (folder / "loop.c").write_text(C_LOOP.format(module=module, nq=robot["nq"], nv=robot["nv"]))
    cmd = [os.environ.get("CC", "cc"), "-O2", "-fPIC", "-shared", "-I", str(folder), str(folder / f"{module}.c"),
           str(folder / "loop.c"), "-o", str(folder / f"lib{module}_loop.so"), "-lm"]
    t0 = time.perf_counter()
    run = subprocess.run(cmd, capture_output=True, text=True)
    return {"ok": run.returncode == 0, "seconds": time.perf_counter() - t0, "cmd": " ".join(cmd),
            "stderr": run.stderr[-2000:]}


def states(robot: dict, n: int, seed: int = 32):
    """n random states in Pinocchio's conventions: q (unit quaternions for the free-flyer), v, tau (zero on a
    free-flyer's six base entries), a."""
    import numpy as np

    rng = np.random.default_rng(seed)
    nj = len(robot["joints"])
    q = rng.uniform(-1.5, 1.5, (n, nj))
    if robot["floating"]:
        quat = rng.normal(size=(n, 4))
        quat /= np.linalg.norm(quat, axis=1, keepdims=True)
        q = np.hstack([rng.uniform(-1, 1, (n, 3)), quat, q])
    nv = robot["nv"]
    tau = rng.uniform(-20, 20, (n, nv))
    if robot["floating"]:
        tau[:, :6] = 0  # the humanoid's base is not actuated (and adam's, jaxsim's ABA take joint torques alone)
    return {"q": q, "v": rng.uniform(-2, 2, (n, nv)), "tau": tau, "a": rng.uniform(-5, 5, (n, nv))}


def reference(robot: dict, data: dict, routine: str, k: int):
    """Pinocchio's outputs on the first k states (the agreement check's reference)."""
    from .peers import build_pinocchio
    from .worker import ARGS

    built = build_pinocchio(robot)
    return built.routines[routine](*(data[name][:k] for name in ARGS[routine]))


def agreement(outputs: dict, ref, tolerance: float) -> dict:
    """The largest difference of an entry's outputs (``B{b}`` -> array on the first states) from the reference,
    relative to the reference's largest entry, over every batch size; ``ok`` when it is within ``tolerance``.
    An entry that is not ``ok`` has its times withheld."""
    import numpy as np

    worst, where = 0.0, None
    scale = float(np.max(np.abs(ref))) or 1.0
    for key, out in outputs.items():
        out = np.asarray(out)
        r = ref[: out.shape[0]]
        if out.shape != r.shape:
            return {"ok": False, "max_relative": None, "where": key,
                    "error": f"shape {out.shape} where Pinocchio's is {r.shape}"}
        diff = float(np.max(np.abs(out - r))) / scale if out.size else 0.0
        if not np.isfinite(diff):
            return {"ok": False, "max_relative": None, "where": key, "error": "non-finite outputs"}
        if diff >= worst:
            worst, where = diff, key
    return {"ok": worst <= tolerance, "max_relative": worst, "where": where}


# --------------------------------------------------------------------------------------------------- running
def interpreter(entry: str) -> str:
    """The Python of an entry's worker: this one (the peers' venv), or for :data:`PROJECT_ENTRIES` the project's own
    (``AGGSYM_BENCH_BATCH_PROJECT_PYTHON``, default ``.venv/bin/python``)."""
    if entry in PROJECT_ENTRIES:
        return os.environ.get("AGGSYM_BENCH_BATCH_PROJECT_PYTHON", str(ROOT / ".venv" / "bin" / "python"))
    return sys.executable


def run_worker(entry: str, robot: dict, routine: str, cfg, round_: int) -> dict:
    import numpy as np

    folder = BUILD / robot["label"] / "runs"
    folder.mkdir(parents=True, exist_ok=True)
    stem = folder / f"{entry}-{routine}-r{round_}"
    job = {"entry": entry, "robot": robot, "routine": routine, "states": str(BUILD / robot["label"] / "states.npz"),
           "sizes": cfg["sizes"], "repeats": cfg["repeats"], "sample_seconds": cfg["sample_seconds"],
           "check": cfg["check"], "outputs": str(stem) + ".npz", "result": str(stem) + ".json"}
    Path(job["result"]).unlink(missing_ok=True)
    Path(str(stem) + ".job.json").write_text(json.dumps(job, indent=1))
    env = child_env()
    env.setdefault("OMP_NUM_THREADS", "1")
    env["AGGSYM_THREADS"] = str(len(os.sched_getaffinity(0))) if entry in ALL_CORES else "1"
    run = run_measured([interpreter(entry), "-m", "benchmarks.batch.worker", str(stem) + ".job.json"], env=env,
                       cwd=ROOT, timeout=cfg["timeout"])
    if not run.ok or not Path(job["result"]).exists():
        text = (run.stderr or run.stdout)[-3000:]
        return {"entry": entry, "robot": robot["label"], "routine": routine,
                "error": ("timed out after %.0f s" % run.wall_seconds) if run.timed_out else text}
    result = json.loads(Path(job["result"]).read_text())
    result["maxrss_mib"] = run.maxrss_kib / 1024
    result["wall_seconds"] = run.wall_seconds
    with np.load(job["outputs"]) as z:
        result["_outputs"] = {k: z[k] for k in z.files}
    return result


def merge_rounds(results: list) -> dict:
    """One entry's result over the rounds: samples pooled, the first round's compile times, the largest memory."""
    out = dict(results[0])
    for r in results[1:]:
        for b, s in r["sizes"].items():
            out["sizes"][b]["seconds_per_call"] = out["sizes"][b]["seconds_per_call"] + s["seconds_per_call"]
        out["maxrss_mib"] = max(out["maxrss_mib"], r["maxrss_mib"])
    return out


def summarize(result: dict) -> dict:
    """Per B: minimum and median microseconds per state over the samples, and the first call's seconds."""
    import statistics

    rows = {}
    for b, s in result["sizes"].items():
        per_state = [t / int(b) * 1e6 for t in s["seconds_per_call"]]
        rows[b] = {"min_us": min(per_state), "median_us": statistics.median(per_state),
                   "first_call_seconds": s["first_call_seconds"], "samples": len(per_state),
                   "calls_per_sample": s["calls_per_sample"]}
    return rows


def section(cfg=None) -> dict:
    import numpy as np

    cfg = cfg or config()
    env = environment()
    env["peer_versions"] = versions(PEER_PACKAGES)
    log(f"host: {cpu_line()}, {env['logical_cpus']} CPUs, load {load_average()}; settings {cfg}")
    unknown = [e for e in cfg["entries"] if e not in ENTRIES]
    if unknown:
        raise SystemExit(f"unknown entries {unknown}; known: {sorted(ENTRIES)}")
    robots = {}
    for label in cfg["robots"]:
        robot = prepare_robot(label, cfg)
        data = states(robot, max(cfg["sizes"]))
        np.savez(BUILD / label / "states.npz", **data)
        robot["reference"] = {r: reference(robot, data, r, cfg["check"]) for r in cfg["routines"]}
        robots[label] = robot
    runs = []
    for round_ in range(cfg["rounds"]):
        for label, robot in robots.items():
            spec = {k: v for k, v in robot.items() if k != "reference"}
            for routine in cfg["routines"]:
                for entry in cfg["entries"]:
                    if routine not in ENTRIES[entry][2]:
                        continue
                    log(f"round {round_ + 1}/{cfg['rounds']}: {label} {routine} {entry} ...")
                    r = run_worker(entry, spec, routine, cfg, round_)
                    if "error" in r:
                        log(f"  {entry} failed: {r['error'][-600:]}")
                    runs.append(r)
    rows = []
    for label, robot in robots.items():
        for routine in cfg["routines"]:
            for entry in cfg["entries"]:
                mine = [r for r in runs if (r["entry"], r["robot"], r["routine"]) == (entry, label, routine)]
                if not mine:
                    continue
                errors = [r["error"] for r in mine if "error" in r]
                row = {"entry": entry, "label": ENTRIES[entry][0], "robot": label, "routine": routine}
                if errors:
                    rows.append(dict(row, error=errors[0]))
                    continue
                merged = merge_rounds(mine)
                check = agreement(merged["_outputs"], robot["reference"][routine], cfg["tolerance"])
                row.update({"agreement": check, "maxrss_mib": merged["maxrss_mib"],
                            "build_seconds": merged["build_seconds"], "compiles": merged["compiles"],
                            "framework_version": merged.get("framework_version")})
                if check["ok"]:
                    row["sizes"] = summarize(merged)
                rows.append(row)
                if entry in ("aggsym_jax", "aggsym_jax_project", "aggsym_torch", "aggsym_jax_kernels",
                             "aggsym_torch_kernels") and routine != "jac":
                    numpy_row = [r for r in runs if (r["entry"], r["robot"], r["routine"]) == ("numpy", label, routine)
                                 and "error" not in r]
                    if numpy_row:
                        same = agreement(merged["_outputs"], numpy_row[0]["_outputs"][f"B{max(cfg['sizes'])}"],
                                         0.0)
                        row["against_numpy"] = same["max_relative"]
    env["load_average_end"] = load_average()
    notes = [f"{label}: `aggsym generate --targets numpy,jax,torch,manifest` failed, so the aggsym JAX and PyTorch "
             f"entries had no module: {robot['generation']['full']['error'].strip().splitlines()[-1]}"
             for label, robot in robots.items() if robot["generation"].get("full", {}).get("error", "").strip()]
    return {"environment": env, "host": cpu_line(), "config": cfg, "notes": notes,
            "robots": {k: {x: v[x] for x in ("nq", "nv", "floating", "joints", "urdf", "generation")}
                       for k, v in robots.items()},
            "entries": {k: {"label": v[0], "framework": v[1], "jacobian": v[3]} for k, v in ENTRIES.items()},
            "rows": rows}


def keep_earlier(data: dict, earlier: dict) -> dict:
    """A run on some robots, entries or routines keeps the earlier batch.json's rows of every (robot, entry,
    routine) it did not run, each marked ``earlier_run`` (the report says so); the batch sizes and routines are the
    union of both runs'."""
    ran = {(r["robot"], r["entry"], r["routine"]) for r in data["rows"]}
    host = earlier.get("host")
    rows = [dict(r, earlier_run=True, host=r.get("host", host)) for r in earlier.get("rows", [])
            if (r["robot"], r["entry"], r["routine"]) not in ran]
    for label, robot in data.get("robots", {}).items():  # (a run that reused the generated modules keeps their builds)
        before = earlier.get("robots", {}).get(label, {}).get("generation", {})
        robot["generation"] = {**before, **robot.get("generation", {})}
    if not rows:
        return data
    kept = sorted({r["robot"] for r in rows})
    data["robots"].update({k: v for k, v in earlier.get("robots", {}).items() if k not in data["robots"]})
    data["rows"] += rows
    data["config"]["sizes"] = sorted(set(data["config"]["sizes"]) | set(earlier.get("config", {}).get("sizes", [])))
    data["config"]["routines"] = [r for r in ROUTINES if r in set(data["config"]["routines"])
                                  | set(earlier.get("config", {}).get("routines", []))]
    data["kept_from_earlier_run"] = kept
    return data


def main() -> int:
    cfg = config()
    BUILD.mkdir(parents=True, exist_ok=True)
    data = section(cfg)
    path = result_path("batch")
    data = keep_earlier(data, read_json(path))
    write_json(path, data)
    batch_report.plot(data, path.with_suffix(".png"))
    # the agreement first: no time is printed for an entry that disagrees with Pinocchio
    print(batch_report.agreement_text(data))
    print()
    print(batch_report.timing_text(data))
    print()
    print(batch_report.targets_text(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
