"""The example-robot-data robots the benchmark's sections share, and where the installed package keeps them.

Here rather than in :mod:`benchmarks.run` so that a section (:mod:`benchmarks.compile_split`,
:mod:`benchmarks.slicing_runtime`) reads them without importing the runner that imports it back.
"""
from __future__ import annotations

from pathlib import Path

# example-robot-data files (as in tests/helpers.py's ROBOTS; talos is the reduced 32-DOF model)
ROBOT_FILES = {
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "hyq": "hyq_description/robots/hyq_no_sensors.urdf",
    "talos": "talos_data/robots/talos_reduced.urdf",
}
# the routines the peers have: EXTRA_RUNTIME_ROBOTS of benchmarks/run.py are generated with these alone, and the
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
