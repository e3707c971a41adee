"""Errors that reach the user: each names the file, the place in it and what is wrong."""
from __future__ import annotations


class AggsymError(Exception):
    """Base of the errors the CLI reports without a traceback."""

    exit_code = 2


class ModelError(AggsymError):
    """A model file that cannot be used.

    ``where`` is the place in the file: a YAML path such as ``bodies[2].pair.functional`` or a URDF element
    such as ``<joint name="elbow">``; ``line`` is the 1-based line when the parser knows it.
    """

    def __init__(self, file, where: str, message: str, line: int | None = None):
        self.file = str(file) if file is not None else "<model>"
        self.where = where
        self.message = message
        self.line = line
        super().__init__(str(self))

    def __str__(self) -> str:
        loc = self.file if self.line is None else f"{self.file}:{self.line}"
        at = f" at {self.where}" if self.where else ""
        return f"{loc}:{at}: {self.message}" if at else f"{loc}: {self.message}"


class ModelWarning(UserWarning):
    """A model file that can be used but looks wrong (e.g. a URDF inertia violating the triangle inequality)."""
