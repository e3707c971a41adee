"""Where the examples find their robots (example-robot-data's URDF files) and how they generate a module.

``module(urdf, folder, routines, *options)`` runs ``aggsym generate URDF --targets c,numpy,jax --routines ...`` into
``folder`` (once: an existing module is imported as it is) and returns (NumPy module, JAX module).  With the C
target the JAX module runs on the batch kernels (NAME_kernels.c, compiled on its first import, cached)."""
from __future__ import annotations

import importlib.util
import sys
import warnings
from importlib import metadata
from pathlib import Path

from aggsym.cli import main

ROBOTS = {"panda": "panda_description/urdf/panda.urdf",
          "double_pendulum": "double_pendulum_description/urdf/double_pendulum.urdf",
          "ur5": "ur_description/urdf/ur5_robot.urdf",
          "talos": "talos_data/robots/talos_reduced.urdf"}


def urdf(name: str) -> Path:
    """The URDF file of an example-robot-data robot (pip install example-robot-data)."""
    dist = metadata.distribution("example-robot-data")
    for f in dist.files or ():
        if f.as_posix().endswith("share/example-robot-data/package.xml"):
            return Path(dist.locate_file(f)).parent / "robots" / ROBOTS[name]
    raise FileNotFoundError("example-robot-data lists no share/example-robot-data/package.xml")


def _import(path: Path):
    spec = importlib.util.spec_from_file_location(f"_example_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def module(robot: str, folder: Path, routines: str, *options: str):
    """(NumPy module, JAX module) of ``robot`` with ``routines``, generated into ``folder`` unless already there."""
    folder = Path(folder)
    name = robot
    if not (folder / f"{name}_jax.py").is_file():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            code = main(["generate", str(urdf(robot)), "-q", "--name", name, "--targets", "c,numpy,jax,manifest",
                         "--routines", routines, "-o", str(folder), *options])
        if code != 0:
            raise SystemExit(code)
    return _import(folder / f"{name}.py"), _import(folder / f"{name}_jax.py")
