"""Model readers (YAML, URDF), validation, the immutable Model and its tree indexing."""
from __future__ import annotations

from pathlib import Path

from ..collector import collector_paused
from ..errors import ModelError
from .tree import Tree
from .types import COORDINATE_CODES, WORLD, Body, Coordinate, Coupling, Inertial, Model, Pair, Parameter
from .urdf_reader import load_urdf
from .yaml_reader import load_yaml


def load(path, **options) -> Model:
    """Read a model from a ``.yaml``/``.yml`` or ``.urdf`` file; options go to the reader (``load_urdf``)."""
    with collector_paused():
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
