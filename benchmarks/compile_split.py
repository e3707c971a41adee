"""Compile time of ``aggsym generate --split`` against one NAME.c (issue 18, item 3; target: Talos' routines of the
contract at -O2 in at most 10 s with ``make -j2``, against 26 s for one file measured before).

``python -m benchmarks.compile_split [OUT.json]`` (not part of ``make bench``'s run.py): generates Talos (the
reduced 32-joint talos_reduced.urdf of example-robot-data) with the routines below, once as one file and once
with --split, then times, in wall-clock seconds, ``cc -O2 -std=c99 -c NAME.c`` and ``make -jJOBS`` (CFLAGS -O2
-std=c99, the Makefile's default) from a clean folder.  One measurement each: a shared machine's load (recorded
before and after) moves them a lot.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

from aggsym import load
from aggsym.codegen.compile import compiler
from aggsym.codegen.generate import generate, write
from aggsym.contract import select_routines

from .environment import load_average
from .run import ROBOT_FILES, robots_directory

# A, b, C, g, d, inverse and forward dynamics, A^-1, joint wrenches, energies, transvective factors
ROUTINES = ["inertia", "bias", "coriolis", "gravity", "nonlinear_effects", "inverse_dynamics", "forward_dynamics",
            "inertia_inverse", "joint_wrenches", "kinetic_energy", "potential_energy", "transvective_factors"]


def _timed(cmd, cwd) -> float:
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed in {cwd}:\n{proc.stderr[-2000:]}")
    return seconds


def run(robot: str = "talos", jobs: int = 2, opt: str = "-O2") -> dict:
    """{"robot", "routines", "opt", "jobs", "cpus", "single_seconds", "split_seconds", "split_serial_seconds",
    "c_bytes", "files", "largest_file_bytes", "load_before", "load_after"}."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # talos' <mimic> on fixed joints
        model = select_routines(load(robots_directory() / ROBOT_FILES[robot]), ROUTINES)
    out = {"robot": robot, "routines": ROUTINES, "opt": opt, "jobs": jobs, "cpus": os.cpu_count(),
           "load_before": load_average()}
    cc = compiler()
    with tempfile.TemporaryDirectory() as tmp:
        single, split = Path(tmp) / "single", Path(tmp) / "split"
        write(generate(model, latex=False), single)
        write(generate(model, latex=False, split=True), split)
        sources = sorted(split.glob("*.c"))
        out["c_bytes"] = (single / f"{model.name}.c").stat().st_size
        out["files"] = len(sources)
        out["largest_file_bytes"] = max(p.stat().st_size for p in sources)
        out["single_seconds"] = _timed([cc, opt, "-std=c99", "-c", f"{model.name}.c", "-o", f"{model.name}.o"],
                                       single)
        flags = f"CFLAGS={opt} -std=c99"
        out["split_seconds"] = _timed(["make", f"-j{jobs}", f"CC={cc}", flags], split)
        subprocess.run(["make", "clean"], cwd=split, check=True, capture_output=True)
        out["split_serial_seconds"] = _timed(["make", "-j1", f"CC={cc}", flags], split)
    out["load_after"] = load_average()
    return out


def markdown(results: dict) -> str:
    r = results
    return "\n".join([
        f"Compile time of {r['robot']} ({len(r['routines'])} routines: {', '.join(r['routines'])}) at {r['opt']}, "
        f"wall-clock seconds on {r['cpus']} CPUs (load average {r['load_before']} before, {r['load_after']} after; "
        f"one measurement each)",
        "",
        "| build | seconds |",
        "|---|---:|",
        f"| one file, cc -c ({r['c_bytes'] / 1e6:.2f} MB of C) | {r['single_seconds']:.1f} |",
        f"| --split, make -j{r['jobs']} ({r['files']} files, largest {r['largest_file_bytes'] / 1e6:.2f} MB) "
        f"| {r['split_seconds']:.1f} |",
        f"| --split, make -j1 | {r['split_serial_seconds']:.1f} |",
        "",
    ])


if __name__ == "__main__":
    res = run()
    print(markdown(res))
    if len(sys.argv) > 1:
        Path(sys.argv[1]).write_text(json.dumps(res, indent=2) + "\n")
