"""Section 3: runtime of the generated C against Pinocchio C++ from the ``pin`` wheel, ns per call.

The generated C of every robot is compiled ``-O2`` (no ``-march=native``: the wheel's libraries are built
without it) into one shared library, next to ``bench_models.c``, which holds a direct-call batch timer per
routine (``harness/bench.h``).  ``harness/pinocchio_bench.cpp`` is compiled against the wheel's headers
(Eigen from ``cmeel-eigen``, URDF headers from ``cmeel-urdfdom-headers``) with the compile definitions the
wheel's CMake config lists, linked to ``pinocchio_default``, ``pinocchio_parsers`` and ``urdfdom_model``.
One run of that program checks, for each robot, that both sides compute the same thing on the first states,
then times the pairs in interleaved batches (median of per-batch means).  A model generated with constraints
(:mod:`benchmarks.runtime.constrained`) joins the same library and is timed the same way against ``constraintDynamics``.
The PEERS of a robot (its five routines compiled -O3, and the CasADi peer of :mod:`benchmarks.runtime.casadi_peer`
compiled -O2 and -O3, each object's symbols renamed with objcopy) join the library too and are timed in the
same batches; the harness runs pinned to one CPU (:func:`benchmarks.harness.build.bench_cpu`).  The flags, the
builds and the pinned run are :mod:`benchmarks.harness.build`'s.
"""
from __future__ import annotations

import json
import os
import shlex
import subprocess
import time
from pathlib import Path

from ..harness.build import (C_STD, build_key, cmeel_prefix, compile_c, compile_once, cxx_flags, is_built, link_flags,
                             mark_built, run_command, run_pinned)
from ..harness.build import compile_definitions  # noqa: F401  (the flags' test reads them through this module)
from ..harness.environment import load_average
from ..harness.paths import HARNESS

# The peers of a generated model, timed beside it (harness/bench.h, bench_peer): (tag, label, source, level).  Each
# peer object is the source compiled with C_STD at that level, its defined global symbols prefixed with TAG_
# (objcopy), so the same functions at -O2 and -O3, and the CasADi peer's wrappers that carry the generated
# names, live in one library.  source "generated": NAME.c; "casadi": NAME_casadi.c (:mod:`.casadi_peer`).
PEERS = (("aggsym_O3", "aggsym -O3", "generated", "-O3"),
         ("casadi_O2", "CasADi -O2", "casadi", "-O2"),
         ("casadi_O3", "CasADi -O3", "casadi", "-O3"))
_PEER_SIGNATURES = {
    "inertia": "const double *q, const double *p, double *out",
    "nonlinear_effects": "const double *q, const double *qd, const double *p, double *out",
    "inverse_dynamics": "const double *q, const double *qd, const double *qdd, const double *p, double *out",
    "forward_dynamics": "const double *q, const double *qd, const double *tau, const double *p, double *out",
    "inertia_inverse": "const double *q, const double *p, double *out",
}

PAIRS = [
    # (our role, Pinocchio function, label)
    ("inertia", "crba", "A(q) / crba"),
    ("nonlinear_effects", "nonLinearEffects", "b+g / nonLinearEffects"),
    ("inverse_dynamics", "rnea", "inverse dynamics / rnea"),
    ("forward_dynamics", "aba", "forward dynamics / aba"),
    ("inertia_inverse", "computeMinverse", "A^-1 / computeMinverse"),
    # beyond the five, timed where the generated model has them: the derivatives and the regressor are emitted on
    # request (aggsym generate --routines default,...), frame_jacobians is in the default set
    ("inverse_dynamics_derivatives", "computeRNEADerivatives", "dtau/dq, dtau/dqd / computeRNEADerivatives"),
    ("forward_dynamics_derivatives", "computeABADerivatives", "dqdd/dq, dqdd/dqd / computeABADerivatives"),
    ("frame_jacobians", "computeJointJacobians + getFrameJacobian", "frame Jacobians / getFrameJacobian"),
    ("regressor", "computeJointTorqueRegressor", "regressor Y / computeJointTorqueRegressor"),
]
DEFAULT_ROLES = ("inertia", "nonlinear_effects", "inverse_dynamics", "forward_dynamics", "inertia_inverse")
EXTRA_ROLES = ("inverse_dynamics_derivatives", "forward_dynamics_derivatives", "frame_jacobians", "regressor")
# what the runtime section asks ``aggsym generate`` for (section 1 times the default set alone, which has
# frame_jacobians but not the derivatives nor the regressor)
ROUTINES = ",".join(("default",) + EXTRA_ROLES)


def build_pinocchio_object(build: Path, log=print) -> tuple:
    """Compile harness/pinocchio_bench.cpp once (about 1.5 min); reused while flags and sources are unchanged.
    Returns (object path, seconds spent compiling or 0.0 when reused)."""
    prefix = cmeel_prefix()
    cxx = os.environ.get("CXX", "g++")
    src = HARNESS / "pinocchio_bench.cpp"
    obj = build / "pinocchio_bench.o"
    cmd = [cxx, *cxx_flags(prefix), "-c", str(src), "-o", str(obj)]
    sources = src.read_text() + "".join((HARNESS / f).read_text() for f in ("bench.h", "pinocchio_common.hpp"))
    return obj, compile_once(cmd, obj, sources, log) or 0.0


def c_string(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def model_arrays(m: dict) -> tuple:
    """(C lines of the joint names and default parameters of a manifest's model, the parameters' expression)."""
    name = m["name"]
    joints = ", ".join(c_string(c["joint"]) for c in m.get("velocities", m["coordinates"]))
    lines = [f"static const char *const {name}_joints[] = {{{joints}}};"]
    if not m["parameters"]:
        return lines, "NULL"
    values = ", ".join(repr(float(p["value"])) for p in m["parameters"])
    return lines + [f"static const double {name}_p[] = {{{values}}};"], f"{name}_p"


def _model_record(m: dict) -> list:
    """C lines of one model (fixed base or free-flyer): its arrays, timers and bench_model record (the routines
    beyond the five that its manifest lists get their timers; the others NULL)."""
    name = m["name"]
    arrays, p = model_arrays(m)
    has = [role for role in EXTRA_ROLES if role in m["functions"]]
    lines = arrays + [f"BENCH_MODEL_TIMERS({name})"] + [f"BENCH_{role.upper()}({name})" for role in has]
    frames = m.get("layouts", {}).get("frame_jacobians", {}).get("frames", []) if "frame_jacobians" in has else []
    if frames:
        lines.append(f"static const char *const {name}_frames[] = {{{', '.join(c_string(f) for f in frames)}}};")
    cols = m["layouts"]["regressor"]["Y"]["shape"][1] if "regressor" in has else 0
    fields = [c_string(name), str(m["nq"]), str(m.get("nv", m["nq"])), str(root_kind(m)),
              str(len(m["parameters"])), p, f"{name}_joints"]
    fields += [f"{name}_{role}" for role in DEFAULT_ROLES] + [f"{name}_t_{role}" for role in DEFAULT_ROLES]
    fields += [str(len(frames)), f"{name}_frames" if frames else "NULL", str(cols)]
    fields += [f"{name}_{role}" if role in has else "NULL" for role in EXTRA_ROLES]
    fields += [f"{name}_t_{role}" if role in has else "NULL" for role in EXTRA_ROLES]
    lines.append(f"static const bench_model {name}_bench = {{{', '.join(fields)}}};")
    return lines


def euler_root(m: dict) -> bool:
    """Whether a manifest's model was generated with ``--floating-base euler``: its first six coordinates are one
    joint's x, y, z translations and x, y, z rotations (Pinocchio's composite root PX PY PZ RX RY RZ)."""
    c = m["coordinates"][:6]
    return len(c) == 6 and len({x["joint"] for x in c}) == 1 and \
        [x["kind"] for x in c] == ["translation"] * 3 + ["rotation"] * 3 and \
        len(m["coordinates"]) == m.get("nv", m["nq"])


def root_kind(m: dict) -> int:
    """bench_model's ``free_flyer`` of a manifest's model: 1 a quaternion free-flyer (Pinocchio's JointModelFreeFlyer),
    2 the Euler root of ``--floating-base euler`` (:func:`euler_root`), 0 a fixed base."""
    return 1 if any(c["kind"] == "quaternion" for c in m["coordinates"]) else 2 if euler_root(m) else 0


def _peer_record(tag: str, label: str, m: dict) -> list:
    """C lines of one peer of the model of manifest ``m``: the prototypes of its renamed functions, their timers,
    its bench_model record (the generated model's name, joints and parameters) and its bench_peer."""
    name, peer = m["name"], f"{tag}_{m['name']}"
    lines = [f"void {peer}_{role}({sig});" for role, sig in _PEER_SIGNATURES.items()]
    lines.append(f"BENCH_MODEL_TIMERS({peer})")
    p = f"{name}_p" if m["parameters"] else "NULL"
    fields = [c_string(name), str(m["nq"]), str(m.get("nv", m["nq"])), str(root_kind(m)),
              str(len(m["parameters"])), p, f"{name}_joints"]
    fields += [f"{peer}_{role}" for role in DEFAULT_ROLES] + [f"{peer}_t_{role}" for role in DEFAULT_ROLES]
    fields += ["0", "NULL", "0"] + ["NULL"] * (2 * len(EXTRA_ROLES))
    lines.append(f"static const bench_model {peer}_bench = {{{', '.join(fields)}}};")
    lines.append(f"static const bench_peer {peer}_peer = {{{c_string(label)}, &{peer}_bench}};")
    return lines


def bench_models_source(manifests: list, constrained: list = (), peers: list = ()) -> str:
    """bench_models.c: the batch timers and records of the generated models (harness/bench.h); ``constrained``:
    the manifests of models timed for their constrained forward dynamics alone; ``peers``: (tag, label,
    manifest) of the peers (PEERS) of generated models."""
    lines = ["/* Generated by benchmarks/runtime/pinocchio_cpp.py: direct-call batch timers of the generated code. */",
             "#define _POSIX_C_SOURCE 200809L", "#include <stddef.h>", "#include <time.h>", '#include "bench.h"']
    lines += [f'#include "{m["name"]}.h"' for m in [*manifests, *constrained]]
    lines += ["", "volatile double bench_sink = 0.0;", "",
              "double bench_now_ns(void) {", "    struct timespec t;", "    clock_gettime(CLOCK_MONOTONIC, &t);",
              "    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;", "}", "",
              "double bench_cpu_now_ns(void) {", "    struct timespec t;",
              "    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);",
              "    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;", "}", ""]
    for m in manifests:
        lines += _model_record(m)
    for m in constrained:
        name = m["name"]
        arrays, p = model_arrays(m)
        lines += arrays
        lines.append(f"BENCH_CONSTRAINED_MODEL({name}, {m['nq']}, {m['constraints']['m']}, {len(m['parameters'])}, "
                     f"{p}, {name}_joints)")
    lines.append("const bench_model *const bench_models[] = {"
                 + "".join(f"&{m['name']}_bench, " for m in manifests) + "NULL};")
    for tag, label, m in peers:
        lines += _peer_record(tag, label, m)
    lines.append("const bench_peer *const bench_peers[] = {"
                 + "".join(f"&{tag}_{m['name']}_peer, " for tag, _, m in peers) + "NULL};")
    lines.append("const bench_constrained_model *const bench_constrained_models[] = {"
                 + "".join(f"&{m['name']}_constrained_bench, " for m in constrained) + "NULL};")
    return "\n".join(lines) + "\n"


def peer_compile_timeout() -> float:
    """Seconds one peer object may take to compile (AGGSYM_BENCH_PEER_COMPILE_TIMEOUT, default 420): gcc on one
    straight-line function of 10^5 statements (the CasADi A^-1 of a 48-link chain) can take far longer."""
    return float(os.environ.get("AGGSYM_BENCH_PEER_COMPILE_TIMEOUT", "420"))


def _compile_renamed(src: Path, obj: Path, level: str, tag: str, log=print, timeout: float | None = None):
    """``src`` compiled with C_STD at ``level`` into ``obj``, every defined global symbol renamed TAG_symbol;
    returns the compile seconds (None when the object was up to date), or the string "timed out after T s"
    when the compiler was stopped at ``timeout`` (no object then)."""
    cc = os.environ.get("CC", "cc")
    cmd = [cc, *[level if f == "-O2" else f for f in C_STD], "-c", str(src), "-o", str(obj)]
    key = build_key(cmd, tag + src.read_text())
    if is_built(obj, key):
        return None
    log(" ".join(shlex.quote(str(c)) for c in cmd) + (f"  (timeout {timeout:g} s)" if timeout else ""))
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        obj.unlink(missing_ok=True)
        return f"timed out after {timeout:g} s"
    if proc.returncode != 0:
        raise RuntimeError(f"command failed ({proc.returncode}): {' '.join(cmd)}\n{proc.stderr[-4000:]}")
    seconds = time.perf_counter() - t0
    _, proc = run_command(["nm", "-g", "--defined-only", "-P", obj], lambda m: None)
    symbols = sorted({line.split()[0] for line in proc.stdout.splitlines() if line.strip()})
    mapping = obj.with_suffix(".syms")
    mapping.write_text("".join(f"{s} {tag}_{s}\n" for s in symbols))
    run_command(["objcopy", f"--redefine-syms={mapping}", obj], log)
    mark_built(obj, key)
    return seconds


def _build_generated(build: Path, generated: dict, log=print, constrained: dict | None = None,
                     peers: dict | None = None) -> tuple:
    """The generated C of every model as one shared library (cc -O2 -fPIC, each model its own translation unit)
    and bench_models.o (the direct-call timers).  ``constrained``: name -> folder of the models timed for their
    constrained forward dynamics alone; ``peers``: name -> {"casadi": the folder of NAME_casadi.c, "generated": the
    folder of the NAME.c the -O3 build compiles} for the generated models that get the PEERS.  Returns the
    compile times."""
    build.mkdir(parents=True, exist_ok=True)
    cc = os.environ.get("CC", "cc")
    constrained = constrained or {}
    peers = peers or {}
    manifests = [json.loads((Path(d) / f"{name}.json").read_text()) for name, d in generated.items()]
    constrained_manifests = [json.loads((Path(d) / f"{name}.json").read_text()) for name, d in constrained.items()]
    times = {}
    objects = []
    for name, d in {**generated, **constrained}.items():
        obj = build / f"{name}.o"
        seconds = compile_c(Path(d) / f"{name}.c", obj, log)
        if seconds is not None:
            times[f"cc -O2 {name}.c"] = seconds
        objects.append(obj)
    by_name = {m["name"]: m for m in manifests}
    peer_records = []
    for name, folders in peers.items():
        timed_out = set()  # sources whose -O2 build timed out: their -O3 build (slower still) is not tried
        for tag, label, source, level in PEERS:
            src = Path(folders[source]) / (f"{name}.c" if source == "generated" else f"{name}_casadi.c")
            obj = build / f"{tag}_{name}.o"
            what = f"cc {level} {src.name}" + (" (the five routines)" if source == "generated" else "")
            if source in timed_out:
                times[what] = "not tried (its -O2 build timed out)"
                continue
            seconds = _compile_renamed(src, obj, level, tag, log, peer_compile_timeout())
            if isinstance(seconds, str):  # left out of this run: the report says so
                times[what] = seconds
                timed_out.add(source)
                log(f"{what}: {seconds}; {label} of {name} left out")
                continue
            if seconds is not None:
                times[what] = seconds
            objects.append(obj)
            peer_records.append((tag, label, by_name[name]))
    run_command([cc, "-shared", "-o", build / "libaggsym_bench_models.so", *objects, "-lm"], log)
    src = build / "bench_models.c"
    src.write_text(bench_models_source(manifests, constrained_manifests, peer_records))
    includes = [f"-I{HARNESS}", *sorted({f"-I{Path(d)}" for d in [*generated.values(), *constrained.values()]})]
    run_command([cc, *C_STD, *includes, "-c", src, "-o", build / "bench_models.o"], log)
    return times


def build_harness(build: Path, generated: dict, log=print, constrained: dict | None = None,
                  peers: dict | None = None) -> dict:
    """Compile the generated C (one shared library) and link the Pinocchio harness.  ``generated``: name ->
    folder with NAME.c, NAME.h, NAME.json; ``constrained`` the same for models with constraints (their
    constrained forward dynamics only); ``peers``: name -> {"casadi": folder of NAME_casadi.c, "generated":
    folder of the NAME.c of the -O3 build} (the PEERS of those models).
    Returns the executable and the compile times."""
    times = _build_generated(build, generated, log, constrained, peers)
    obj, seconds = build_pinocchio_object(build, log)
    if seconds:
        times["c++ -O2 pinocchio_bench.cpp"] = seconds
    exe = build / "pinocchio_bench"
    run_command([os.environ.get("CXX", "g++"), "-o", exe, obj, build / "bench_models.o", f"-L{build}",
                 f"-Wl,-rpath,{build}", "-laggsym_bench_models", *link_flags(cmeel_prefix()), "-lm"], log)
    return {"executable": exe, "compile_seconds": times}


def build_generated_only(build: Path, generated: dict, log=print) -> Path:
    """The generated side alone (harness/generated_only.c): no Pinocchio, builds in seconds."""
    _build_generated(build, generated, log)
    cc = os.environ.get("CC", "cc")
    exe = build / "generated_only"
    run_command([cc, *C_STD, f"-I{HARNESS}", "-o", exe, HARNESS / "generated_only.c", build / "bench_models.o",
                 f"-L{build}", f"-Wl,-rpath,{build}", "-laggsym_bench_models", "-lm"], log)
    return exe


def run_harness(exe: Path, robots: dict, out_json: Path, seconds: float = 0.5, states: int = 1000,
                calls: int = 100, log=print, constrained: dict | None = None, cpu: int | None = None) -> dict:
    """Run the harness on ``robots`` (name -> URDF path) and the ``constrained`` models (name -> (URDF path,
    contact frames), floating base), pinned to ``cpu`` (os.sched_setaffinity in the child) when given; returns its
    JSON with ``pinned_cpu`` and ``load_average_before`` added."""
    cmd = [exe, str(seconds), str(states), str(calls), out_json]
    for name, path in robots.items():
        cmd += [name, path]
    for name, (path, frames) in (constrained or {}).items():
        cmd += ["--constrained", name, path, ",".join(frames)]
    load = load_average()
    run_pinned(cmd, cpu, log)
    data = json.loads(Path(out_json).read_text())
    data.update({"pinned_cpu": cpu, "load_average_before": load})
    return data


def run_generated_only(exe: Path, out_json: Path, seconds: float = 0.05, states: int = 100, calls: int = 100) -> dict:
    """Run harness/generated_only.c; returns its JSON."""
    subprocess.run([str(exe), str(seconds), str(states), str(calls), str(out_json)], check=True)
    return json.loads(Path(out_json).read_text())
