import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
MODELS = sorted((ROOT / "models").glob("*.yaml"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from pinocchio_reference import ROBOTS  # noqa: E402  (the tests folder is on the path from here on)


@pytest.fixture
def rng():
    return np.random.default_rng(20261121)


def model_path(name: str) -> Path:
    return ROOT / "models" / f"{name}.yaml"


@pytest.fixture(scope="session", params=sorted(ROBOTS))
def robot_code(request, tmp_path_factory):
    """(name, model, C library, NumPy module, Pinocchio model) of an example-robot-data robot's generated code,
    compiled -O0 (the -Werror flags stay; -O2 is exercised by test_codegen and `aggsym check`), which keeps
    talos' compile to seconds.  Session-wide: built once for every test module that compares it."""
    import json
    import warnings

    import aggsym
    from aggsym.codegen.compile import CLibrary, compile_shared, import_module
    from aggsym.codegen.generate import generate, write
    from aggsym.errors import ModelWarning
    from pinocchio_reference import pinocchio_model, robot_path

    name = request.param
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)  # hyq's and anymal's dummy inertias
        model = aggsym.load(robot_path(name))
    out = tmp_path_factory.mktemp(name)
    write(generate(model, latex=False), out)
    manifest = json.loads((out / f"{model.name}.json").read_text())
    lib = CLibrary(compile_shared(out / f"{model.name}.c", out / "lib.so", extra=("-O0",)), manifest)
    return name, model, lib, import_module(out / f"{model.name}.py"), pinocchio_model(robot_path(name))
