"""The immutable Model (``types.py``) and its tree indexing (``tree.py``), in two wings: the readers of model files
(``readers/``: YAML, URDF, xacro, MJCF, one registry) and the transforms of a model (``transforms/``).

:func:`load` here is a file as its reader reads it; ``aggsym.load`` (:mod:`aggsym.pipeline`) also applies the options
of ``aggsym generate`` and names the model after its file, as the command line does."""
from __future__ import annotations

from pathlib import Path

from ..collector import collector_paused
from ..errors import ModelError
from .tree import Tree
from .types import (COORDINATE_CODES, WORLD, Body, Coordinate, Coupling, Inertial, LinkFrame, Links, Model, Pair,
                    Parameter)
from .readers.registry import READERS, Reader, reader_for, register
from .readers.urdf_reader import load_urdf
from .readers.yaml_reader import load_yaml


def load(path, **options) -> Model:
    """Read a model from a file; the reader is chosen by the suffix (``.yaml``/``.yml``, ``.urdf``; a shared
    suffix such as ``.xml`` by the content): :mod:`aggsym.model.readers.registry`.  ``options`` go to the reader
    (``load_urdf``'s ``floating_base``, ``mimic``, ``snap_angles``; for ``.xacro`` also ``xacro_args`` and
    ``package_paths``, :mod:`aggsym.model.readers.xacro_reader`)."""
    with collector_paused():
        return _load(Path(path), options)


def _load(path: Path, options: dict) -> Model:
    reader = reader_for(path)
    if options and not reader.options:
        raise TypeError(f"{reader.name} models take no options, got {sorted(options)}")
    return reader.load(path, **options)


__all__ = ["load", "reader_for", "register", "Reader", "READERS", "Links", "LinkFrame",
           "load_urdf", "load_yaml", "Model", "Body", "Pair", "Coordinate", "Coupling", "Inertial", "Parameter",
           "Tree", "COORDINATE_CODES",
           "WORLD", "ModelError"]
