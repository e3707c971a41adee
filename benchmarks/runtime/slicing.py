"""Runtime of the sliced routines (aggsym/codegen/slicing.py) against the same routines as one function each.

``python -m benchmarks.runtime.slicing [OUT.json]``: Talos (the five benchmark routines, C, b and g) and the
chains of 24 and 48 links of :mod:`benchmarks.harness.chain` (the five), each generated twice as one NAME.c, with
``slicing=None`` and with the default slicing, the sliced one compiled twice, as generated (GCC on x86 compiles the
slices for size, and A and A^-1 without its basic-block vectorizer: templates/c/attributes.c.j2) and with
``-DAGGSYM_AS_COMPILED`` (every function at -O2), all ``cc -O2 -std=c99`` beside a small timer generated here
(64 random states, fixed seed, the same for both; ``p`` NULL, the defaults), then run in turn ROUNDS times, pinned to
one CPU when ``taskset`` exists.  Each run reports per routine the best of REPS batches of ITERS calls (ns per call);
the table gives the median over the rounds of each variant and the change.  Routines under the threshold are the
same text in both variants: their change is the noise (and the code layout's effect).
"""
from __future__ import annotations

import json
import shutil
import statistics
import subprocess
import tempfile
import warnings
from pathlib import Path

from aggsym import load
from aggsym.codegen.compile import compiler
from aggsym.codegen.generate import generate, write
from aggsym.codegen.slicing import SLICE_SIZE, SLICE_THRESHOLD
from aggsym.contract import select_routines

from ..harness.chain import write_chain
from ..harness.cli import section_main
from ..harness.environment import load_average
from ..harness.robots import FIVE, ROBOT_FILES, robots_directory

ROBOTS = {"talos": FIVE + ",coriolis,bias,gravity", "chain24": FIVE, "chain48": FIVE}
# label, slicing, extra flags: the unsliced file, the sliced file with every function at -O2, the sliced file as
# generated
VARIANTS = (("one function", None, ()), ("sliced -O2", (SLICE_THRESHOLD, SLICE_SIZE), ("-DAGGSYM_AS_COMPILED",)),
            ("sliced", (SLICE_THRESHOLD, SLICE_SIZE), ()))
STATES = 64


def timer_source(manifest: dict, roles) -> str:
    """C of a program timing ``roles`` of the generated code: ``prog REPS ITERS`` prints ``role ns`` per line."""
    signatures = manifest["signatures"]
    width = max(max(s["input_sizes"].values(), default=1) for s in signatures.values())
    out_size = max(sum(_size(o["shape"]) for o in signatures[r]["outputs"]) for r in roles)
    lines = ["#include <stdio.h>", "#include <stdlib.h>", "#include <time.h>", f'#include "{manifest["name"]}.h"',
             "static double now(void)",
             "{ struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec * 1e9 + t.tv_nsec; }",
             f"static double in[4][{STATES}][{width}], out[{out_size}];", "static volatile double sink;",
             "int main(int argc, char **argv)", "{",
             "    int reps = argc > 1 ? atoi(argv[1]) : 9, iters = argc > 2 ? atoi(argv[2]) : 1000;",
             "    srand(1);",
             f"    for (int k = 0; k < 4; k++) for (int s = 0; s < {STATES}; s++) for (int i = 0; i < {width}; i++)",
             "        in[k][s][i] = 2.0 * rand() / RAND_MAX - 1.0;"]
    for role in roles:
        sig = signatures[role]
        args = [f"in[{k}][s]" if name != "p" else "NULL" for k, name in enumerate(sig["inputs"])]
        offset = 0
        for o in sig["outputs"]:
            args.append(f"out + {offset}")
            offset += _size(o["shape"])
        call = f"{manifest['functions'][role]}({', '.join(args)})"
        lines += ["    {", "        double best = 1e300;", "        for (int r = 0; r < reps; r++) {",
                  "            double t0 = now();",
                  f"            for (int it = 0; it < iters; it++) {{ int s = it % {STATES}; {call}; sink += out[0]; }}",
                  "            double ns = (now() - t0) / iters;", "            if (ns < best) best = ns;", "        }",
                  f'        printf("{role} %.1f\\n", best);', "    }"]
    return "\n".join(lines + ["    return 0;", "}", ""])


def _size(shape) -> int:
    n = 1
    for d in shape:
        n *= d
    return n


def _model(robot: str, folder: Path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # talos' <mimic> on fixed joints
        path = write_chain(int(robot[5:]), folder) if robot.startswith("chain") else \
            robots_directory() / ROBOT_FILES[robot]
        return select_routines(load(path), ROBOTS[robot].split(","))


def _build(model, slicing, flags, folder: Path) -> Path:
    write(generate(model, targets="c,numpy,manifest", slicing=slicing), folder)
    manifest = json.loads((folder / f"{model.name}.json").read_text())
    (folder / "timer.c").write_text(timer_source(manifest, list(manifest["functions"])))
    cc = compiler()
    for cmd in ([cc, "-O2", "-std=c99", *flags, "-c", f"{model.name}.c", "-o", "model.o"],
                [cc, "-O2", "-std=gnu99", "-I.", "timer.c", "model.o", "-lm", "-o", "timer"]):
        subprocess.run(cmd, cwd=folder, check=True, capture_output=True)
    return folder / "timer"


def run(rounds: int = 5, reps: int = 9, iters: int = 1000, cpu: int = 1) -> dict:
    """{"rounds", "load_before", "load_after", "slicing", "robots": {robot: {role: {label: [ns per round]}}}}."""
    pin = ["taskset", "-c", str(cpu)] if shutil.which("taskset") else []
    out = {"rounds": rounds, "load_before": load_average(), "slicing": [SLICE_THRESHOLD, SLICE_SIZE], "robots": {}}
    with tempfile.TemporaryDirectory() as tmp:
        timers = {}
        for robot in ROBOTS:
            model = _model(robot, Path(tmp) / "models")
            timers[robot] = {label: _build(model, slicing, flags, Path(tmp) / f"{robot}{k}")
                             for k, (label, slicing, flags) in enumerate(VARIANTS)}
        for _ in range(rounds):
            for robot, variants in timers.items():
                for label, exe in variants.items():
                    text = subprocess.run([*pin, str(exe), str(reps), str(iters)], check=True, capture_output=True,
                                          text=True).stdout
                    for line in text.splitlines():
                        role, ns = line.split()
                        out["robots"].setdefault(robot, {}).setdefault(role, {}).setdefault(label, []).append(float(ns))
    out["load_after"] = load_average()
    return out


def markdown(results: dict) -> str:
    labels = [label for label, _, _ in VARIANTS]
    base = labels[0]
    lines = [f"ns per call, median of {results['rounds']} rounds (load average {results['load_before']} before, "
             f"{results['load_after']} after); *sliced*: routines of more than {results['slicing'][0]} work in "
             f"slices of about {results['slicing'][1]}, the others the same text as unsliced, compiled as "
             "generated (GCC on x86: the slices for size, A and A⁻¹ without the basic-block vectorizer); "
             "*sliced -O2*: the same file with -DAGGSYM_AS_COMPILED (every function at -O2); the changes against "
             "one function.", "",
             "| robot | routine | " + " | ".join(labels) + " | " + " | ".join(f"{x} change" for x in labels[1:]) + " |",
             "|---|---|" + "---:|" * (2 * len(labels) - 1)]
    for robot, roles in results["robots"].items():
        for role, times in roles.items():
            t = [statistics.median(times[label]) for label in labels]
            changes = [f"{100 * (x - t[0]) / t[0]:+.1f} %" for x in t[1:]]
            lines.append(f"| {robot} | {role} | " + " | ".join(f"{x:.0f}" for x in t) + " | " + " | ".join(changes)
                         + " |")
    return "\n".join(lines + [""])


if __name__ == "__main__":
    section_main(run, markdown)
