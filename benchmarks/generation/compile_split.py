"""Compile time of Talos' default routines, one file and ``--split``, each routine as one function and sliced
(issue 18, item 3; target: ``aggsym generate talos.urdf --split`` then ``make -j2`` at -O2 in at most 10 s wall time
on 2 cores, against 33 s measured before slicing).

``python -m benchmarks.generation.compile_split [OUT.json]`` (section ``split`` of ``benchmarks/run.py``): generates
Talos (the reduced 32-joint talos_reduced.urdf of example-robot-data, the default routines of ``aggsym generate``)
twice, every routine as one function (``slicing=None``, the code before aggsym/codegen/slicing.py) and with the default
slicing, each as one NAME.c and with --split, then times back to back, from clean folders, ``cc -O2 -std=c99 -c NAME.c``
and ``make -jJOBS`` (CFLAGS -O2 -std=c99, the Makefile's default), and every file of the split folder alone (their sum
is a serial build): wall-clock seconds, and CPU seconds (user + sys of the compilers, from the children's rusage), which
a loaded machine moves much less.  One measurement each; the load average is recorded before and after.
"""
from __future__ import annotations

import os
import resource
import subprocess
import tempfile
import time
import warnings
from pathlib import Path

from aggsym import load
from aggsym.codegen.compile import compiler
from aggsym.codegen.generate import generate, write
from aggsym.codegen.slicing import SLICE_SIZE, SLICE_THRESHOLD
from aggsym.contract import select_routines

from ..harness.cli import section_main
from ..harness.environment import load_average
from ..harness.robots import ROBOT_FILES, robots_directory

VARIANTS = (("one function per routine", None), ("sliced", (SLICE_THRESHOLD, SLICE_SIZE)))


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _timed(cmd, cwd) -> dict:
    """{"wall", "cpu"} seconds of a command (cpu: user + sys of it and the processes it waited for)."""
    cpu, t0 = _children_cpu(), time.perf_counter()
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed in {cwd}:\n{proc.stderr[-2000:]}")
    return {"wall": wall, "cpu": _children_cpu() - cpu}


def run(robot: str = "talos", jobs: int = 2, opt: str = "-O2", routines=None) -> dict:
    """{"robot", "routines", "opt", "jobs", "cpus", "load_before", "load_after", "builds": [one per VARIANTS:
    {"label", "slicing", "sliced" (roles), "c_bytes", "files", "largest_file_bytes", "single", "split", "per_file"
    (file -> {"wall", "cpu"})}]}; ``routines`` None: the default set."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # talos' <mimic> on fixed joints
        model = load(robots_directory() / ROBOT_FILES[robot])
        if routines:
            model = select_routines(model, routines)
    cc = compiler()
    flags = f"CFLAGS={opt} -std=c99"
    out = {"robot": robot, "opt": opt, "jobs": jobs, "cpus": os.cpu_count(), "load_before": load_average(),
           "builds": []}
    with tempfile.TemporaryDirectory() as tmp:
        folders = []
        for k, (label, slicing) in enumerate(VARIANTS):
            single, split = Path(tmp) / f"single{k}", Path(tmp) / f"split{k}"
            gen = generate(model, targets="c,numpy,manifest", slicing=slicing)
            write(gen, single)
            write(generate(model, targets="c,numpy,manifest", split=True, slicing=slicing), split)
            out["routines"] = [r.routine.role for r in gen.routines]
            sources = sorted(split.glob("*.c"))
            out["builds"].append({
                "label": label, "slicing": list(slicing) if slicing else None,
                "sliced": [r.routine.role for r in gen.routines if r.sliced],
                "c_bytes": (single / f"{model.name}.c").stat().st_size, "files": len(sources),
                "largest_file_bytes": max(p.stat().st_size for p in sources)})
            folders.append((single, split, sources))
        # the variants back to back, build by build, so that a change of the machine's load hits both alike
        for build, (single, _, _) in zip(out["builds"], folders):
            build["single"] = _timed([cc, opt, "-std=c99", "-c", f"{model.name}.c", "-o", f"{model.name}.o"], single)
        for build, (_, split, _) in zip(out["builds"], folders):
            build["split"] = _timed(["make", f"-j{jobs}", f"CC={cc}", flags], split)
        for build, (_, split, sources) in zip(out["builds"], folders):
            build["per_file"] = {p.name: _timed([cc, opt, "-std=c99", "-c", p.name, "-o", "/dev/null"], split)
                                 for p in sources}
    out["load_after"] = load_average()
    return out


def _cell(t: dict) -> str:
    return f"{t['wall']:.1f} ({t['cpu']:.1f})"


def markdown(results: dict) -> str:
    r = results
    if "builds" not in r:  # a result of the earlier format (one variant, wall time only)
        return (f"Compile time of {r['robot']} at {r['opt']}: one file {r['single_seconds']:.1f} s, --split make "
                f"-j{r['jobs']} {r['split_seconds']:.1f} s (wall-clock).\n")
    before, after = r["builds"]
    files = sorted(before["per_file"], key=lambda f: -before["per_file"][f]["cpu"])
    serial = [sum(t["cpu"] for t in b["per_file"].values()) for b in (before, after)]
    lines = [
        f"Compile time of {r['robot']} ({len(r['routines'])} routines, the default set: {', '.join(r['routines'])}) "
        f"at {r['opt']}, seconds of wall-clock time (CPU time, user + sys, in brackets) on {r['cpus']} CPUs (load "
        f"average {r['load_before']} before, {r['load_after']} after; one measurement each, the two variants back to "
        f"back).  *sliced*: routines of more than {after['slicing'][0]} work (operations + statements) emitted as "
        f"static functions of about {after['slicing'][1]} each (aggsym/codegen/slicing.py): "
        f"{', '.join(after['sliced']) or 'none'}.",
        "",
        f"| build | {before['label']} | {after['label']} |",
        "|---|---:|---:|",
        f"| one file, cc -c ({before['c_bytes'] / 1e6:.2f} / {after['c_bytes'] / 1e6:.2f} MB of C) "
        f"| {_cell(before['single'])} | {_cell(after['single'])} |",
        f"| --split, make -j{r['jobs']} ({before['files']} files, largest {before['largest_file_bytes'] / 1e6:.2f} / "
        f"{after['largest_file_bytes'] / 1e6:.2f} MB) | {_cell(before['split'])} | {_cell(after['split'])} |",
        f"| --split, the files one by one (sum of CPU) | {serial[0]:.1f} | {serial[1]:.1f} |",
        "",
        "Each file of --split alone, CPU seconds:",
        "",
        f"| file | {before['label']} | {after['label']} |",
        "|---|---:|---:|",
    ]
    lines += [f"| {f} | {before['per_file'][f]['cpu']:.2f} | {after['per_file'][f]['cpu']:.2f} |" for f in files]
    return "\n".join(lines + [""])


if __name__ == "__main__":
    section_main(run, markdown)
