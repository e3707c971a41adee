"""The generated C's aggsym_sincos against libm (issue 18, item 4): ns per sin-and-cos of a double.

``python -m benchmarks.runtime.trig [OUT.json]`` (section ``trig`` of ``benchmarks/run.py``): renders the double
aggsym_sincos of templates/c/helpers.c.j2 into a header, builds benchmarks/harness/trig_bench.c with it (cc -O2,
and -O2 -ffast-math), and times on the same 4096 arguments, uniform in [-pi, pi] (joint angles) and in [-1000, 1000]:
libm's sin and cos called separately, GNU sincos (glibc), aggsym's helper of before (a quadrant switch; libm's
sin and cos under -ffast-math), the generated branch-free aggsym_sincos, aggsym_sincos2 (two angles in the lanes of
one vector) and aggsym_sincos's latency (each argument computed from the last result).  Each figure is the best of 7
passes of 200 x 4096 angles, in CPU time (the harness prints them).
Timings on a shared machine are noisy: :func:`run` records the load average beside them.
"""
from __future__ import annotations

import subprocess
import tempfile
from pathlib import Path

from aggsym.codegen.compile import compiler
from aggsym.codegen.targets import TARGETS

from ..harness.cli import section_main
from ..harness.environment import load_average
from ..harness.paths import HARNESS as HARNESS_SOURCES

HARNESS = HARNESS_SOURCES / "trig_bench.c"
FLAGS = {"-O2": ["-O2"], "-O2 -ffast-math": ["-O2", "-ffast-math"]}
RANGES = {"[-pi, pi]": "3.141592653589793", "[-1000, 1000]": "1000"}
VARIANTS = {"libm": "libm sin + cos", "sincos": "GNU sincos",
            "switch": "aggsym before (quadrant switch; libm under -ffast-math)",
            "aggsym": "aggsym_sincos (branch-free)",
            "aggsym2": "aggsym_sincos2 (two angles a call; per angle)",
            "latency": "aggsym_sincos latency (argument after the last result)"}


def sincos_source() -> str:
    """The double aggsym_sincos and aggsym_sincos2 exactly as the generated C defines them."""
    return TARGETS["c"].template("helpers.c.j2").render(sign=False, sincos=True, sincos2=True, scalar="double",
                                                            zero="0.0")


def run() -> dict:
    """{"load_before", "load_after", "results": {flags: {range: {variant: ns per call}}}}."""
    out = {"load_before": load_average(), "results": {}}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "aggsym_sincos.h").write_text("#include <math.h>\n" + sincos_source())
        for label, flags in FLAGS.items():
            exe = tmp / "trig_bench"
            subprocess.run([compiler(), "-std=c99", "-Wall", "-Wextra", *flags,
                            f'-DAGGSYM_SINCOS_FILE="{tmp / "aggsym_sincos.h"}"', "-o", str(exe), str(HARNESS), "-lm"],
                           check=True)
            per_range = {}
            for name, lo in RANGES.items():
                text = subprocess.run([str(exe), lo], check=True, capture_output=True, text=True).stdout
                per_range[name] = {line.split()[0]: float(line.split()[1]) for line in text.splitlines() if line}
            out["results"][label] = per_range
    out["load_after"] = load_average()
    return out


def markdown(results: dict) -> str:
    """A table per compile flag: the variants' ns per call on each argument range."""
    lines = [f"sin and cos of one double, ns per call (best of 7 passes of 200 x 4096 calls; load average "
             f"{results['load_before']} before, {results['load_after']} after)", ""]
    for label, per_range in results["results"].items():
        ranges = list(per_range)
        lines += [f"`cc {label}`", "", "| variant | " + " | ".join(ranges) + " |",
                  "|---|" + "---:|" * len(ranges)]
        for key, title in VARIANTS.items():
            if all(key in per_range[r] for r in ranges):
                lines.append(f"| {title} | " + " | ".join(f"{per_range[r][key]:.1f}" for r in ranges) + " |")
        lines.append("")
    return "\n".join(lines)


if __name__ == "__main__":
    section_main(run, markdown)
