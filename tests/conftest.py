import importlib
import re
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
MODELS = sorted((ROOT / "models").glob("*.yaml"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from helpers import ROBOTS  # noqa: E402  (the tests folder is on the path from here on)


# Optional references: a test module that imports one of these helpers at its top (directly or through another
# helper) is not collected where the helper's dependency does not import, and the run says so at its end.  Nothing
# is skipped: `make test` installs every dependency, and there every module is collected.
REFERENCES = {"pinocchio_reference": ("pinocchio", "Pinocchio (PyPI pin)"), "jax_support": ("jax", "jax (aggsym[jax])")}
TOP_IMPORT = re.compile(r"^(?:from|import)\s+(\w+)", re.M)


def _import_error(module: str):
    """None when ``module`` imports, else the error (not installed, or installed but broken)."""
    try:
        importlib.import_module(module)
    except ImportError as error:
        return error
    return None


def _modules_needing(helper: str) -> list:
    """The test modules (file names) that import ``helper`` at their top, directly or through other tests/ modules."""
    folder = Path(__file__).resolve().parent
    imports = {f.stem: set(TOP_IMPORT.findall(f.read_text())) for f in folder.glob("*.py")}
    needing, grew = {helper}, True
    while grew:
        grew = False
        for name, names in imports.items():
            if name not in needing and names & needing:
                needing.add(name)
                grew = True
    return sorted(f"{name}.py" for name in needing if name.startswith("test_"))


MISSING = {helper: (label, error) for helper, (module, label) in REFERENCES.items()
           if (error := _import_error(module)) is not None}
collect_ignore = sorted({f for helper in MISSING for f in _modules_needing(helper)})


def pytest_terminal_summary(terminalreporter):
    for helper, (label, error) in MISSING.items():
        terminalreporter.write_line(f"needs {label}, which does not import here ({error}): "
                                    f"{len(_modules_needing(helper))} test modules not collected")


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
