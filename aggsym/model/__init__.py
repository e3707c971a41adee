"""Model readers (YAML, URDF), validation, the immutable Model and its tree indexing."""
from __future__ import annotations

import gc
from contextlib import contextmanager
from pathlib import Path

from ..errors import ModelError
from .tree import Tree
from .types import COORDINATE_CODES, WORLD, Body, Coordinate, Coupling, Inertial, Model, Pair, Parameter
from .urdf_reader import load_urdf
from .yaml_reader import load_yaml


@contextmanager
def _collector_paused():
    """Python's cyclic garbage collector off while a file is read, back to its state after.

    Reading allocates some 20 objects per body and frees nearly none until the end, so the collector ran its
    full passes over the growing, cycle-free heap again and again: half the time of a 2000-body chain (0.62 s ->
    0.33 s), more in a process that already holds many objects.  Nothing read forms cycles that need it meanwhile.
    """
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def load(path, **options) -> Model:
    """Read a model from a ``.yaml``/``.yml`` or ``.urdf`` file; options go to the reader (``load_urdf``)."""
    with _collector_paused():
        return _load(Path(path), options)


def _load(path: Path, options: dict) -> Model:
    suffix = path.suffix.lower()
    if suffix in (".yaml", ".yml"):
        if options:
            raise TypeError(f"YAML models take no options, got {sorted(options)}")
        return load_yaml(path)
    if suffix == ".urdf":
        return load_urdf(path, **options)
    raise ModelError(path, "", f"unknown model type {suffix!r}: expected .yaml, .yml or .urdf")


__all__ = ["load", "load_urdf", "load_yaml", "Model", "Body", "Pair", "Coordinate", "Coupling", "Inertial", "Parameter",
           "Tree", "COORDINATE_CODES",
           "WORLD", "ModelError"]
