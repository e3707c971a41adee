"""The machine, OS, compilers and library versions a benchmark ran with (for the report's header)."""
from __future__ import annotations

import datetime
import os
import platform
import subprocess
from importlib import metadata
from pathlib import Path

from .paths import ROOT

PACKAGES = ("aggsym", "sympy", "numpy", "pin", "example-robot-data", "cmeel-eigen", "cmeel-urdfdom-headers",
            "cmeel-urdfdom", "matplotlib", "jinja2")


def _read(path) -> str:
    try:
        return Path(path).read_text()
    except OSError:
        return ""


def cpu_model() -> str:
    for line in _read("/proc/cpuinfo").splitlines():
        if line.lower().startswith("model name"):
            return line.split(":", 1)[1].strip()
    return platform.processor() or "unknown"


def cpu_details() -> dict:
    """The first processor's identification in /proc/cpuinfo (vendor, family, model, stepping, MHz, cache) and
    which of the vector extensions that matter to compiled straight-line code it has: hosts that print the same
    model name can still differ here."""
    keys = {"vendor_id": "vendor", "cpu family": "family", "model": "model", "stepping": "stepping",
            "cpu MHz": "mhz", "cache size": "cache", "microcode": "microcode"}
    out = {}
    for line in _read("/proc/cpuinfo").splitlines():
        if not line.strip():
            break
        key, _, value = line.partition(":")
        key = key.strip()
        if key in keys:
            out[keys[key]] = value.strip()
        elif key == "flags":
            flags = set(value.split())
            out["vector"] = [f for f in ("sse4_2", "avx", "avx2", "fma", "avx512f") if f in flags]
    return out


def cpu_line() -> str:
    """One line naming the host's CPU for logs and reports."""
    d = cpu_details()
    extra = ", ".join(x for x in (f"family {d['family']} model {d['model']} stepping {d['stepping']}"
                                  if "family" in d else "", f"{float(d['mhz']):.0f} MHz" if "mhz" in d else "",
                                  d.get("cache", ""), "/".join(d.get("vector", []))) if x)
    return cpu_model() + (f" ({extra})" if extra else "")


def memory_gib() -> float | None:
    for line in _read("/proc/meminfo").splitlines():
        if line.startswith("MemTotal:"):
            return int(line.split()[1]) / 2 ** 20
    return None


def os_name() -> str:
    pretty = ""
    for line in _read("/etc/os-release").splitlines():
        if line.startswith("PRETTY_NAME="):
            pretty = line.split("=", 1)[1].strip().strip('"')
    return f"{pretty or platform.system()} (Linux {platform.release()})"


def load_average() -> list:
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:
        return []


def versions(packages=PACKAGES) -> dict:
    """The installed version of each of ``packages`` (None where one is missing)."""
    out = {}
    for name in packages:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return out


def git_commit() -> str | None:
    try:
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True)
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "aggsym"], cwd=ROOT,
                               capture_output=True, text=True)
    except OSError:
        return None
    if rev.returncode:
        return None
    return rev.stdout.strip() + (" (aggsym/ modified)" if dirty.stdout.strip() else "")


def compiler_versions() -> dict:
    """The first line of `$CC --version` and `$CXX --version` (cc and g++ by default), or "unknown"."""
    out = {}
    for name, exe in (("cc", os.environ.get("CC", "cc")), ("c++", os.environ.get("CXX", "g++"))):
        try:
            out[name] = subprocess.run([exe, "--version"], capture_output=True, text=True).stdout.splitlines()[0]
        except (OSError, IndexError):
            out[name] = "unknown"
    return out


def environment() -> dict:
    return {
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "cpu": cpu_model(),
        "cpu_details": cpu_details(),
        "cpu_line": cpu_line(),
        "logical_cpus": os.cpu_count(),
        "memory_gib": memory_gib(),
        "os": os_name(),
        "python": platform.python_version(),
        "compilers": compiler_versions(),
        "versions": versions(),
        "commit": git_commit(),
        "load_average_start": load_average(),
    }
