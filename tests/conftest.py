import functools
import importlib
import re
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
MODELS = sorted((ROOT / "models").glob("*.yaml"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from helpers import ROBOTS, written  # noqa: E402  (the tests folder is on the path from here on)


# Optional dependencies: a test module that imports one of these at its top (directly, through helpers of tests/ such
# as pinocchio_reference.py and jax_support.py, or by a top-level pytest.importorskip) is not collected where the
# module does not import, and the run says so at its end.  Nothing is skipped: `make test` installs every
# dependency, and there every module is collected.  Each is imported only when a test module that needs it is about
# to be collected (which would import it anyway), so a run of other modules does not wait for it.
OPTIONAL = {"pinocchio": "Pinocchio (PyPI pin)", "jax": "jax (aggsym[jax])", "torch": "PyTorch (aggsym[torch])",
            "mujoco": "MuJoCo (aggsym[mjcf])", "xacro": "xacro (aggsym[xacro])", "casadi": "CasADi (PyPI casadi)",
            "hypothesis": "Hypothesis (PyPI hypothesis)"}
TOP_IMPORT = re.compile(r"""^(?:(?:from|import)\s+(\w+)|(?:\w+\s*=\s*)?pytest\.importorskip\(\s*["'](\w+))""", re.M)
TESTS = Path(__file__).resolve().parent
_IMPORT_ERRORS = {}  # module -> None (it imports) or the error, once checked
LEFT_OUT = {}  # module -> (its error's text, the test modules not collected for it)


def _import_error(module: str):
    """None when ``module`` imports, else the error (not installed, or installed but broken)."""
    if module not in _IMPORT_ERRORS:
        try:
            importlib.import_module(module)
            _IMPORT_ERRORS[module] = None
        except (ImportError, OSError) as error:  # (OSError: a binary wheel whose shared libraries are missing)
            _IMPORT_ERRORS[module] = error
    return _IMPORT_ERRORS[module]


@functools.lru_cache(maxsize=None)
def _needs() -> dict:
    """{test module (file name): the modules of :data:`OPTIONAL` it needs}: those it imports at its top, directly or
    through other tests/ modules."""
    imports = {f.stem: {a or b for a, b in TOP_IMPORT.findall(f.read_text())} for f in TESTS.glob("*.py")}
    out = {}
    for module in OPTIONAL:
        needing, grew = {module}, True
        while grew:
            grew = False
            for name, names in imports.items():
                if name not in needing and names & needing:
                    needing.add(name)
                    grew = True
        for name in needing:
            if name.startswith("test_"):
                out.setdefault(f"{name}.py", set()).add(module)
    return out


def pytest_ignore_collect(collection_path, config):
    """Leave out a test module of tests/ that needs a module of :data:`OPTIONAL` which does not import here."""
    if collection_path.parent != TESTS:
        return None
    missing = sorted(m for m in _needs().get(collection_path.name, ()) if _import_error(m) is not None)
    for module in missing:
        LEFT_OUT.setdefault(module, (str(_import_error(module)), set()))[1].add(collection_path.name)
    return True if missing else None


def pytest_sessionfinish(session):
    """Under pytest-xdist a worker collects: it hands what it left out to the controller, which reports it."""
    output = getattr(session.config, "workeroutput", None)
    if output is not None:
        output["left_out"] = {m: (error, sorted(files)) for m, (error, files) in LEFT_OUT.items()}


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error):
    for module, (text, files) in getattr(node, "workeroutput", {}).get("left_out", {}).items():
        LEFT_OUT.setdefault(module, (text, set()))[1].update(files)


def pytest_terminal_summary(terminalreporter):
    for module, (error, files) in sorted(LEFT_OUT.items()):
        terminalreporter.write_line(f"needs {OPTIONAL[module]}, which does not import here ({error}): "
                                    f"{len(files)} test modules not collected")


def pytest_collection_modifyitems(items):
    """A test on :func:`robot_code` compiles C (the fixture does, once per session and robot): it carries the
    ``compiler`` marker whether or not it was the one that built the fixture."""
    for item in items:
        if "robot_code" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.compiler)


@pytest.fixture
def rng():
    return np.random.default_rng(20261121)


@pytest.fixture
def write(tmp_path):
    """``write(text, name="robot.urdf")``: the path of a file of tmp_path that holds ``text``."""
    return lambda text, name="robot.urdf": written(tmp_path / name, text)


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
