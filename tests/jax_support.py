"""The JAX tests' helpers: generating a model's NumPy and JAX modules side by side, float64 within a test (without
switching jax's global setting for the rest of the suite), random arguments of a routine, central differences.

Where jax does not import, conftest.py does not collect the test modules that import this one (as for
``pinocchio_reference.py`` and Pinocchio)."""
from __future__ import annotations

import contextlib
import inspect

import jax
import jax.numpy as jnp  # noqa: F401  (re-exported for the tests)
import numpy as np

from aggsym.codegen.compile import import_module
from aggsym.codegen.generate import generate, write
from helpers import central_differences  # noqa: F401  (re-exported for the tests)


def x64():
    """A context computing in float64 (jax.enable_x64; jax.experimental.enable_x64 on older releases)."""
    enable = getattr(jax, "enable_x64", None)
    if enable is None:
        from jax.experimental import enable_x64 as enable
    return enable(True)


@contextlib.contextmanager
def float64():
    with x64():
        yield


def modules(model, folder):
    """(NumPy module, JAX module) of ``model`` generated into ``folder``."""
    write(generate(model, targets="numpy,jax,manifest"), folder)
    return (import_module(folder / f"{model.name}.py"), import_module(folder / f"{model.name}_jax.py"))


def routines(module) -> list:
    """The public routines of a generated module, in the order they are defined."""
    return [name for name, f in vars(module).items() if inspect.isfunction(f) and not name.startswith("_")]


def arguments(module, role, rng, batch=()):
    """Random arguments (without p) of a routine of a generated module: q within +-1.5, the rest normal; t, dt, r
    in [0, 1]."""
    out = []
    for name in inspect.signature(getattr(module, role)).parameters:
        if name == "p":
            continue
        if name == "q":
            out.append(rng.uniform(-1.5, 1.5, batch + (module.NQ,)))
        elif name in ("t", "dt", "r"):  # one number each (r: a restitution coefficient)
            out.append(rng.uniform(0.0, 1.0, batch))
        else:
            out.append(rng.normal(size=batch + (module.NV,)))
    return out


def as_tuple(x):
    return x if isinstance(x, tuple) else (x,)


def relative(a, b, floor: float = 1e-300) -> float:
    """max |a - b| / max(|b|, floor) over every output of a routine (floor 1.0 for derivatives that may vanish)."""
    worst = 0.0
    for x, y in zip(as_tuple(a), as_tuple(b)):
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        if y.size:
            worst = max(worst, float(np.max(np.abs(x - y)) / max(float(np.max(np.abs(y))), floor)))
    return worst


def four_bar_dead_centre(npm):
    """The four-bar's constrained_forward_dynamics arguments for two states, the second at its dead centre q = 0
    (tests/test_constraints.py), where the NumPy module ``npm`` raises LinAlgError (checked here)."""
    q = np.stack([np.full(3, 0.3), np.zeros(3)])
    args = (q, np.zeros((2, 3)), np.zeros((2, 3)), np.array([0.1, 0.3, 0.25, 0.3]))
    try:
        npm.constrained_forward_dynamics(*args)
    except np.linalg.LinAlgError:
        return args
    raise AssertionError("the NumPy module did not raise LinAlgError at the dead centre")
