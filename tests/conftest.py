import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
MODELS = sorted((ROOT / "models").glob("*.yaml"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from helpers import ROBOTS  # noqa: E402  (the tests folder is on the path from here on)


def pytest_collection_modifyitems(items):
    """A test on :func:`robot_code` compiles C (the fixture does, once per session and robot): it carries the
    ``compiler`` marker whether or not it was the one that built the fixture."""
    for item in items:
        if "robot_code" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.compiler)


@pytest.fixture
def rng():
    return np.random.default_rng(20261121)


def model_path(name: str) -> Path:
    return ROOT / "models" / f"{name}.yaml"


@pytest.fixture(scope="session", params=sorted(ROBOTS))
def robot_code(request, tmp_path_factory):
    """(name, model, C library, NumPy module, Pinocchio model) of an example-robot-data robot's generated code,
    compiled -O2 with the -Werror flags, as users compile it.  Session-wide: built once for every test module that
    compares it."""
    import warnings

    import aggsym
    from aggsym.errors import ModelWarning
    from helpers import generated_code, robot_path
    from pinocchio_reference import pinocchio_model

    name = request.param
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)  # hyq's and anymal's dummy inertias
        model = aggsym.load(robot_path(name))
    lib, module, _ = generated_code(model, tmp_path_factory.mktemp(name), opt="-O2")
    return name, model, lib, module, pinocchio_model(robot_path(name))
