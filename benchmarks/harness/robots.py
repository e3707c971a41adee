"""The example-robot-data robots the benchmark's sections share, and where the installed package keeps them.

Here rather than in :mod:`benchmarks.run` so that a section (:mod:`benchmarks.generation.compile_split`,
:mod:`benchmarks.runtime.slicing`) reads them without importing the runner that imports it back.
"""
from __future__ import annotations

from pathlib import Path

# every example-robot-data file a section reads, relative to robots_directory() (talos is the reduced 32-DOF model)
FILES = {
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "hyq": "hyq_description/robots/hyq_no_sensors.urdf",
    "talos": "talos_data/robots/talos_reduced.urdf",
    "solo12": "solo_description/robots/solo12.urdf",
    "so100": "so_arm_description/urdf/so100.urdf",
    "xarm7": "xarm_description/urdf/xarm7.urdf",
}
# the four robots of sections 1 and 3 (as in tests/helpers.py's ROBOTS)
ROBOT_FILES = {name: FILES[name] for name in ("ur5", "panda", "hyq", "talos")}
# the routines the peers have: EXTRA_RUNTIME_ROBOTS of benchmarks/run.py are generated with these (xarm7 with the
# derivatives too), and the
# -O3 build of a robot of ROBOT_FILES is compiled from a copy generated with these alone (its full file with the
# derivatives and the regressor takes minutes to compile at -O3: talos' is 3.4 MB)
FIVE = "inertia,nonlinear_effects,inverse_dynamics,forward_dynamics,inertia_inverse"


def robots_directory() -> Path:
    """``share/example-robot-data/robots`` of the installed example-robot-data (it has no Python loader)."""
    from importlib import metadata

    dist = metadata.distribution("example-robot-data")
    for f in dist.files or ():
        if f.as_posix().endswith("share/example-robot-data/package.xml"):
            return Path(dist.locate_file(f)).parent / "robots"
    raise FileNotFoundError("example-robot-data lists no share/example-robot-data/package.xml")


def robot_paths() -> dict:
    root = robots_directory()
    return {name: root / rel for name, rel in ROBOT_FILES.items()}
