"""Input side of the benchmark: reading a large model file, the parse alone (issue 15, point 9; issue 30).

A 2000-body YAML chain and a 2000-link URDF chain, both the spatial 3-D arm of :mod:`benchmarks.harness.chain` (joint
axes z, y, x, ..., offsets with three non-zero components, full inertia tensors), its bodies (YAML) and joints
(URDF) listed from the tip to the root, so the ordering has work to do.  Each is loaded with ``aggsym.load`` in
this process (after the imports: reading, validation and building the Model), three times; the median wall time
is kept (judged), the median CPU time recorded beside it.  Targets (issue 30): the YAML chain in at most 1 s, the URDF chain in at most 2 s.
"""
from __future__ import annotations

import statistics
import time
import warnings
from pathlib import Path

from ..harness.chain import body_lines, urdf_head, urdf_lines

BODIES = 2000
TARGET_SECONDS = {"YAML chain": 1.0, "URDF chain": 2.0}


def yaml_chain(n: int, path: Path) -> Path:
    """The n-link chain of :mod:`benchmarks.harness.chain` as YAML, bodies listed from the tip to the root."""
    lines = [f"name: chain{n}_reversed", "gravity: [0, 0, -9.81]", "bodies:"]
    for k in range(n, 0, -1):
        lines += body_lines(k, "world" if k == 1 else f"link{k - 1}")
    path.write_text("\n".join(lines) + "\n")
    return path


def urdf_chain(n: int, path: Path) -> Path:
    """The n-link chain of :mod:`benchmarks.harness.chain` as URDF, links from the root, joints from the tip."""
    parts = [urdf_lines(k) for k in range(1, n + 1)]
    lines = urdf_head(n) + [line for link, _ in parts for line in link]
    lines += [line for _, joint in reversed(parts) for line in joint]
    path.write_text("\n".join(lines + ["</robot>"]) + "\n")
    return path


def section(build: Path, n: int = BODIES) -> dict:
    """{"rows": [{file, links (n), bodies (the URDF's root link is one more), seconds (median wall time),
    all_seconds, cpu_seconds (median CPU time of this process), all_cpu_seconds, target_seconds}]}."""
    import aggsym
    import aggsym.model  # noqa: F401  (imported before the clock starts: aggsym imports it on first use)

    build.mkdir(parents=True, exist_ok=True)
    rows = []
    for label, path in (("YAML chain", yaml_chain(n, build / "chain_yaml.yaml")),
                        ("URDF chain", urdf_chain(n, build / "chain_urdf.urdf"))):
        times, cpu = [], []
        for _ in range(3):
            t0, c0 = time.perf_counter(), time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model = aggsym.load(path)
            times.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
        rows.append({"file": label, "links": n, "bodies": len(model.bodies), "seconds": statistics.median(times),
                     "all_seconds": times, "cpu_seconds": statistics.median(cpu), "all_cpu_seconds": cpu,
                     "target_seconds": TARGET_SECONDS[label]})
    return {"rows": rows}
