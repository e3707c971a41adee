"""Input side of the benchmark: reading and ordering large model files (issue 15, point 9).

A 2000-body YAML chain and a 2000-link URDF chain (bodies listed children first, so the ordering has work to do)
are loaded with ``aggsym.load`` in this process, three times each; the median wall time is kept.  Target (issue
15): the YAML chain under one second.  The URDF chain has no target; it is measured beside it for reference (a
URDF's links go through SymPy matrices, about 1 ms per link).
"""
from __future__ import annotations

import statistics
import time
import warnings
from pathlib import Path

BODIES = 2000
TARGET_SECONDS = 1.0


def yaml_chain(n: int, path: Path) -> Path:
    """n bodies in a chain, each a unit mass on a revolute pair, listed from the tip to the root."""
    lines = ["name: chain_yaml", "gravity: [0, 0, -9.81]", "bodies:"]
    for k in range(n - 1, -1, -1):
        parent = "world" if k == 0 else f"b{k - 1}"
        axis = ("theta4", "theta5", "theta6")[k % 3]
        lines += [f"  - name: b{k}", f"    parent: {parent}",
                  f"    pair: {{translation: [0.1, 0, 0], functional: {{{axis}: q{k}}}}}",
                  "    mass: 1.0", "    com: [0.05, 0, 0]", "    inertia: {xx: 0.01, yy: 0.01, zz: 0.01}"]
    path.write_text("\n".join(lines) + "\n")
    return path


def urdf_chain(n: int, path: Path) -> Path:
    """n links in a chain of revolute joints, joints listed from the tip to the root."""
    parts = ['<?xml version="1.0"?>', '<robot name="chain_urdf">', '  <link name="l0"/>']
    for k in range(1, n + 1):
        parts.append(f'  <link name="l{k}"><inertial><origin xyz="0.05 0 0"/><mass value="1"/>'
                     f'<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>')
    for k in range(n, 0, -1):
        axis = ("1 0 0", "0 1 0", "0 0 1")[k % 3]
        parts.append(f'  <joint name="j{k}" type="revolute"><origin xyz="0.1 0 0"/><parent link="l{k - 1}"/>'
                     f'<child link="l{k}"/><axis xyz="{axis}"/>'
                     f'<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>')
    parts.append("</robot>")
    path.write_text("\n".join(parts) + "\n")
    return path


def section(build: Path, n: int = BODIES) -> dict:
    """{"rows": [{file, bodies, seconds (median), all_seconds, target_seconds (None: no target)}]}."""
    import aggsym

    build.mkdir(parents=True, exist_ok=True)
    rows = []
    for label, path, target in (("YAML chain", yaml_chain(n, build / "chain_yaml.yaml"), TARGET_SECONDS),
                                ("URDF chain", urdf_chain(n, build / "chain_urdf.urdf"), None)):
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model = aggsym.load(path)
            times.append(time.perf_counter() - t0)
        rows.append({"file": label, "bodies": len(model.bodies), "seconds": statistics.median(times),
                     "all_seconds": times, "target_seconds": target})
    return {"rows": rows}
