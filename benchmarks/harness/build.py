"""Compiling and running the C and C++ timing harnesses of this folder: the flags (C99 -O2 for the generated code,
C++17 -O2 against Pinocchio from the ``pin`` wheel: its headers, compile definitions and libraries under its
``cmeel.prefix``, Eigen from ``cmeel-eigen``, the URDF headers from ``cmeel-urdfdom-headers``), objects rebuilt only
when their command or sources change (a stamp beside each), and a harness run pinned to one CPU.  Shared by section
3 (:mod:`benchmarks.runtime.pinocchio_cpp`) and the constrained derivatives
(:mod:`benchmarks.runtime.constrained_derivatives`).
"""
from __future__ import annotations

import hashlib
import os
import re
import shlex
import subprocess
import time
from pathlib import Path

from .paths import HARNESS

C_STD = ["-std=c99", "-O2", "-fPIC", "-Wall", "-Wextra", "-Wpedantic"]
CXX_STD = ["-std=c++17", "-O2", "-DNDEBUG", "-fPIC"]
# pinocchio targets whose INTERFACE_COMPILE_DEFINITIONS we compile with (the ones we link)
TARGETS = ("pinocchio_headers", "pinocchio_default", "pinocchio_parsers")


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


def run_command(cmd, log, cwd=None) -> tuple:
    """Run ``cmd`` (logged first); (seconds, the completed process); a failure raises with its stderr."""
    log(" ".join(shlex.quote(str(c)) for c in cmd))
    t0 = time.perf_counter()
    proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, cwd=cwd)
    if proc.returncode != 0:
        raise RuntimeError(f"command failed ({proc.returncode}): {' '.join(map(str, cmd))}\n{proc.stderr[-4000:]}")
    return time.perf_counter() - t0, proc


def build_key(cmd, text: str = "") -> str:
    """What an object is built from: its compiler command and the text of its sources."""
    return hashlib.sha256((" ".join(map(str, cmd)) + text).encode()).hexdigest()


def is_built(path: Path, key: str) -> bool:
    """True when ``path`` exists and was built with the same key (compiler command and sources)."""
    stamp = path.with_suffix(path.suffix + ".key")
    return path.exists() and stamp.exists() and stamp.read_text() == key


def mark_built(path: Path, key: str):
    path.with_suffix(path.suffix + ".key").write_text(key)


def compile_once(cmd, obj: Path, text: str, log) -> float | None:
    """Run the compiler command ``cmd`` that writes ``obj`` from sources whose text is ``text``, unless ``obj`` was
    built by the same command from the same text; the seconds it took, or None when the object was reused."""
    key = build_key(cmd, text)
    if is_built(obj, key):
        return None
    seconds, _ = run_command(cmd, log)
    mark_built(obj, key)
    return seconds


def compile_c(src: Path, obj: Path, log) -> float | None:
    """``$CC C_STD -c SRC -o OBJ`` (cc by default) unless OBJ is up to date (:func:`compile_once`)."""
    cmd = [os.environ.get("CC", "cc"), *C_STD, "-c", str(src), "-o", str(obj)]
    return compile_once(cmd, obj, Path(src).read_text(), log)


def bench_cpu() -> int | None:
    """The CPU the harness is pinned to: AGGSYM_BENCH_CPU, else the last one this process may run on (the first
    is where a shared machine's interrupts and other jobs tend to land); None where affinity is not supported."""
    if not hasattr(os, "sched_getaffinity"):
        return None
    allowed = sorted(os.sched_getaffinity(0))
    want = os.environ.get("AGGSYM_BENCH_CPU")
    if want not in (None, ""):
        if int(want) not in allowed:
            raise ValueError(f"AGGSYM_BENCH_CPU={want}: this process may run on CPUs {allowed} only")
        return int(want)
    return allowed[-1]


def run_pinned(cmd, cpu: int | None, log, what: str = "harness") -> subprocess.CompletedProcess:
    """Run a harness (logged first), pinned to ``cpu`` (os.sched_setaffinity in the child) when given; its stderr
    (the harness' progress) is logged line by line; a failure raises, naming ``what``."""
    log(("" if cpu is None else f"taskset -c {cpu} ") + " ".join(shlex.quote(str(c)) for c in cmd))
    pin = (lambda: os.sched_setaffinity(0, {cpu})) if cpu is not None else None
    proc = subprocess.run([str(c) for c in cmd], text=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          preexec_fn=pin)
    for line in proc.stderr.splitlines():
        log("  " + line)
    if proc.returncode != 0:
        raise RuntimeError(f"{what} failed ({proc.returncode}):\n{proc.stderr[-4000:]}")
    return proc
