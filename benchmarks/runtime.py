"""Section 3: runtime of the generated C against Pinocchio C++ from the ``pin`` wheel, ns per call.

The generated C of every robot is compiled ``-O2`` (no ``-march=native``: the wheel's libraries are built
without it) into one shared library, next to ``bench_models.c``, which holds a direct-call batch timer per
routine (``harness/bench.h``).  ``harness/pinocchio_bench.cpp`` is compiled against the wheel's headers
(Eigen from ``cmeel-eigen``, URDF headers from ``cmeel-urdfdom-headers``) with the compile definitions the
wheel's CMake config lists, linked to ``pinocchio_default``, ``pinocchio_parsers`` and ``urdfdom_model``.
One run of that program checks, for each robot, that both sides compute the same thing on the first states,
then times the pairs in interleaved batches (median of per-batch means).  A model generated with constraints
(:mod:`benchmarks.constrained`) joins the same library and is timed the same way against ``constraintDynamics``.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
import shlex
import subprocess
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
HARNESS = HERE / "harness"
C_STD = ["-std=c99", "-O2", "-fPIC", "-Wall", "-Wextra", "-Wpedantic"]
CXX_STD = ["-std=c++17", "-O2", "-DNDEBUG", "-fPIC"]
# pinocchio targets whose INTERFACE_COMPILE_DEFINITIONS we compile with (the ones we link)
TARGETS = ("pinocchio_headers", "pinocchio_default", "pinocchio_parsers")

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


def cmeel_prefix() -> Path:
    """The ``cmeel.prefix`` folder of the installed ``pin`` wheel (headers, libraries, CMake configs)."""
    import pinocchio

    for parent in Path(pinocchio.__file__).resolve().parents:
        if parent.name == "cmeel.prefix":
            return parent
    raise FileNotFoundError(f"no cmeel.prefix above {pinocchio.__file__}")


def _target_definitions(cmake_text: str, target: str) -> list:
    out = []
    for m in re.finditer(r"set_target_properties\(" + re.escape(target) + r" PROPERTIES(.*?)\n\)", cmake_text, re.S):
        d = re.search(r'INTERFACE_COMPILE_DEFINITIONS "([^"]*)"', m.group(1))
        out += d.group(1).split(";") if d else []
    return out


def compile_definitions(prefix: Path) -> list:
    """-D flags of the pinocchio targets we link, read from the wheel's ``lib/cmake/pinocchio`` config
    (generator expressions naming coal's definitions are resolved from coal's config; others dropped)."""
    cmake = prefix / "lib" / "cmake"
    text = "\n".join(p.read_text() for p in sorted((cmake / "pinocchio").glob("*.cmake")))
    coal_text = "\n".join(p.read_text() for p in sorted((cmake / "coal").glob("*.cmake"))) \
        if (cmake / "coal").is_dir() else ""
    out = []
    for target in TARGETS:
        for d in _target_definitions(text, f"pinocchio::{target}"):
            d = d.replace("\\$", "$")
            g = re.fullmatch(r"\$<TARGET_PROPERTY:([\w:]+),INTERFACE_COMPILE_DEFINITIONS>", d)
            if g:
                sub = _target_definitions(coal_text, g.group(1)) if g.group(1).startswith("coal::") else []
                out += [x for x in sub if x and "$<" not in x]
            elif d and "$<" not in d:
                out.append(d)
    seen = []
    for d in out:
        if d not in seen:
            seen.append(d)
    return ["-D" + d for d in seen]


def cxx_flags(prefix: Path) -> list:
    inc = prefix / "include"
    return [*CXX_STD, *compile_definitions(prefix), f"-I{inc}", f"-I{inc / 'eigen3'}", f"-I{inc / 'urdfdom_headers'}",
            f"-I{inc / 'urdfdom'}", f"-I{HARNESS}"]


def link_flags(prefix: Path) -> list:
    lib = prefix / "lib"
    return [f"-L{lib}", f"-Wl,-rpath,{lib}", "-lpinocchio_default", "-lpinocchio_parsers", "-lurdfdom_model"]


def _run(cmd, log, cwd=None):
    log(" ".join(shlex.quote(str(c)) for c in cmd))
    t0 = time.perf_counter()
    proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, cwd=cwd)
    if proc.returncode != 0:
        raise RuntimeError(f"command failed ({proc.returncode}): {' '.join(map(str, cmd))}\n{proc.stderr[-4000:]}")
    return time.perf_counter() - t0, proc


def _stamp(path: Path, key: str) -> bool:
    """True when ``path`` exists and was built with the same key (compiler command and sources)."""
    stamp = path.with_suffix(path.suffix + ".key")
    return path.exists() and stamp.exists() and stamp.read_text() == key


def _write_stamp(path: Path, key: str):
    path.with_suffix(path.suffix + ".key").write_text(key)


def compiler_versions() -> dict:
    out = {}
    for name, exe in (("cc", os.environ.get("CC", "cc")), ("c++", os.environ.get("CXX", "g++"))):
        try:
            out[name] = subprocess.run([exe, "--version"], capture_output=True, text=True).stdout.splitlines()[0]
        except (OSError, IndexError):
            out[name] = "unknown"
    return out


def build_pinocchio_object(build: Path, log=print) -> tuple:
    """Compile harness/pinocchio_bench.cpp once (about 1.5 min); reused while flags and sources are unchanged.
    Returns (object path, seconds spent compiling or 0.0 when reused)."""
    prefix = cmeel_prefix()
    cxx = os.environ.get("CXX", "g++")
    src = HARNESS / "pinocchio_bench.cpp"
    obj = build / "pinocchio_bench.o"
    cmd = [cxx, *cxx_flags(prefix), "-c", str(src), "-o", str(obj)]
    key = hashlib.sha256((" ".join(cmd) + src.read_text() + (HARNESS / "bench.h").read_text()).encode()).hexdigest()
    if _stamp(obj, key):
        return obj, 0.0
    seconds, _ = _run(cmd, log)
    _write_stamp(obj, key)
    return obj, seconds


def c_string(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _model_arrays(m: dict) -> tuple:
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
    arrays, p = _model_arrays(m)
    has = [role for role in EXTRA_ROLES if role in m["functions"]]
    lines = arrays + [f"BENCH_MODEL_TIMERS({name})"] + [f"BENCH_{role.upper()}({name})" for role in has]
    frames = m.get("layouts", {}).get("frame_jacobians", {}).get("frames", []) if "frame_jacobians" in has else []
    if frames:
        lines.append(f"static const char *const {name}_frames[] = {{{', '.join(c_string(f) for f in frames)}}};")
    cols = m["layouts"]["regressor"]["Y"]["shape"][1] if "regressor" in has else 0
    free_flyer = any(c["kind"] == "quaternion" for c in m["coordinates"])
    fields = [c_string(name), str(m["nq"]), str(m.get("nv", m["nq"])), str(int(free_flyer)),
              str(len(m["parameters"])), p, f"{name}_joints"]
    fields += [f"{name}_{role}" for role in DEFAULT_ROLES] + [f"{name}_t_{role}" for role in DEFAULT_ROLES]
    fields += [str(len(frames)), f"{name}_frames" if frames else "NULL", str(cols)]
    fields += [f"{name}_{role}" if role in has else "NULL" for role in EXTRA_ROLES]
    fields += [f"{name}_t_{role}" if role in has else "NULL" for role in EXTRA_ROLES]
    lines.append(f"static const bench_model {name}_bench = {{{', '.join(fields)}}};")
    return lines


def bench_models_source(manifests: list, constrained: list = ()) -> str:
    """bench_models.c: the batch timers and records of the generated models (harness/bench.h); ``constrained``:
    the manifests of models timed for their constrained forward dynamics alone."""
    lines = ["/* Generated by benchmarks/runtime.py: direct-call batch timers of the generated code. */",
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
        arrays, p = _model_arrays(m)
        lines += arrays
        lines.append(f"BENCH_CONSTRAINED_MODEL({name}, {m['nq']}, {m['constraints']['m']}, {len(m['parameters'])}, "
                     f"{p}, {name}_joints)")
    lines.append("const bench_model *const bench_models[] = {"
                 + "".join(f"&{m['name']}_bench, " for m in manifests) + "NULL};")
    lines.append("const bench_constrained_model *const bench_constrained_models[] = {"
                 + "".join(f"&{m['name']}_constrained_bench, " for m in constrained) + "NULL};")
    return "\n".join(lines) + "\n"


def _build_generated(build: Path, generated: dict, log=print, constrained: dict | None = None) -> tuple:
    """The generated C of every model as one shared library (cc -O2 -fPIC, each model its own translation unit)
    and bench_models.o (the direct-call timers).  ``constrained``: name -> folder of the models timed for their
    constrained forward dynamics alone.  Returns the compile times."""
    build.mkdir(parents=True, exist_ok=True)
    cc = os.environ.get("CC", "cc")
    constrained = constrained or {}
    manifests = [json.loads((Path(d) / f"{name}.json").read_text()) for name, d in generated.items()]
    constrained_manifests = [json.loads((Path(d) / f"{name}.json").read_text()) for name, d in constrained.items()]
    times = {}
    objects = []
    for name, d in {**generated, **constrained}.items():
        obj = build / f"{name}.o"
        cmd = [cc, *C_STD, "-c", str(Path(d) / f"{name}.c"), "-o", str(obj)]
        key = hashlib.sha256((" ".join(cmd) + (Path(d) / f"{name}.c").read_text()).encode()).hexdigest()
        if not _stamp(obj, key):
            times[f"cc -O2 {name}.c"], _ = _run(cmd, log)
            _write_stamp(obj, key)
        objects.append(obj)
    _run([cc, "-shared", "-o", build / "libaggsym_bench_models.so", *objects, "-lm"], log)
    src = build / "bench_models.c"
    src.write_text(bench_models_source(manifests, constrained_manifests))
    includes = [f"-I{HARNESS}", *sorted({f"-I{Path(d)}" for d in [*generated.values(), *constrained.values()]})]
    _run([cc, *C_STD, *includes, "-c", src, "-o", build / "bench_models.o"], log)
    return times


def build_harness(build: Path, generated: dict, log=print, constrained: dict | None = None) -> dict:
    """Compile the generated C (one shared library) and link the Pinocchio harness.  ``generated``: name ->
    folder with NAME.c, NAME.h, NAME.json; ``constrained`` the same for models with constraints (their
    constrained forward dynamics only).  Returns the executable and the compile times."""
    times = _build_generated(build, generated, log, constrained)
    obj, seconds = build_pinocchio_object(build, log)
    if seconds:
        times["c++ -O2 pinocchio_bench.cpp"] = seconds
    exe = build / "pinocchio_bench"
    _run([os.environ.get("CXX", "g++"), "-o", exe, obj, build / "bench_models.o", f"-L{build}",
          f"-Wl,-rpath,{build}", "-laggsym_bench_models", *link_flags(cmeel_prefix()), "-lm"], log)
    return {"executable": exe, "compile_seconds": times}


def build_generated_only(build: Path, generated: dict, log=print) -> Path:
    """The generated side alone (harness/generated_only.c): no Pinocchio, builds in seconds."""
    _build_generated(build, generated, log)
    cc = os.environ.get("CC", "cc")
    exe = build / "generated_only"
    _run([cc, *C_STD, f"-I{HARNESS}", "-o", exe, HARNESS / "generated_only.c", build / "bench_models.o",
          f"-L{build}", f"-Wl,-rpath,{build}", "-laggsym_bench_models", "-lm"], log)
    return exe


def run_harness(exe: Path, robots: dict, out_json: Path, seconds: float = 0.5, states: int = 1000,
                calls: int = 100, log=print, constrained: dict | None = None) -> dict:
    """Run the harness on ``robots`` (name -> URDF path) and the ``constrained`` models (name -> (URDF path,
    contact frames), floating base); returns its JSON."""
    cmd = [exe, str(seconds), str(states), str(calls), out_json]
    for name, path in robots.items():
        cmd += [name, path]
    for name, (path, frames) in (constrained or {}).items():
        cmd += ["--constrained", name, path, ",".join(frames)]
    log(" ".join(shlex.quote(str(c)) for c in cmd))
    proc = subprocess.run([str(c) for c in cmd], text=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    for line in proc.stderr.splitlines():
        log("  " + line)
    if proc.returncode != 0:
        raise RuntimeError(f"harness failed ({proc.returncode}):\n{proc.stderr[-4000:]}")
    return json.loads(Path(out_json).read_text())


def run_generated_only(exe: Path, out_json: Path, seconds: float = 0.05, states: int = 100, calls: int = 100) -> dict:
    """Run harness/generated_only.c; returns its JSON."""
    subprocess.run([str(exe), str(seconds), str(states), str(calls), str(out_json)], check=True)
    return json.loads(Path(out_json).read_text())
