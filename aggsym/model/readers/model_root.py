"""The model root: the one folder inside which every file a model refers to must lie.

A model file may name other files: MJCF its ``<include>`` s, attached sub-models, meshes, skins, textures and
height fields (which MuJoCo's compiler reads: a mesh geom's inertia comes from its mesh); xacro its
``<xacro:include>`` s and ``xacro.load_yaml`` files.  Each is resolved as the format resolves it, symbolic links
followed, and read only when the resolved path lies inside the model root: the model's own folder by default,
``--model-root DIR`` (``root=`` in ``aggsym.load``) to widen it to a folder above, as a scene library that keeps
``objects/TASK.xml`` beside ``scene/basic_scene.xml`` needs.  xacro's package folders (``--package-path``,
``ROS_PACKAGE_PATH``) are roots too.  A URDF names meshes (``package://``, ``file://``) only for visuals and
collisions, which aggsym never opens: a URDF's inertia is in its ``<inertial>`` elements.

A refusal is a :class:`~aggsym.errors.ModelError` naming the file that refers, the element, the resolved path and
the ``--model-root`` that would admit it (the deepest folder holding both the model and the file).
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from ...errors import ModelError


def _inside(folder: str, target: str) -> bool:
    return os.path.commonpath([folder, target]) == folder


@dataclass(frozen=True)
class ModelRoot:
    """The root ``folder`` (resolved) of the model file ``model`` (its folder resolved, the file itself not followed:
    MuJoCo and xacro resolve relative names from the folder the file is named in); ``given``: by ``--model-root``."""

    folder: str
    model: str
    given: bool = False

    @classmethod
    def of(cls, path, root=None) -> "ModelRoot":
        """The root of the model file ``path``: its folder, or ``root`` (an existing folder holding the file)."""
        model = os.path.join(os.path.realpath(os.path.dirname(os.path.abspath(path))), os.path.basename(path))
        if root is None or root == "":
            return cls(os.path.dirname(model), model)
        folder = os.path.realpath(os.path.expanduser(str(root)))
        if not os.path.isdir(folder):
            raise ModelError(path, "", f"--model-root {root}: no such folder")
        if not _inside(folder, model):
            raise ModelError(path, "", f"--model-root {root}: the model file ({model}) is not inside it; the model "
                                       f"root is a folder that holds the model")
        return cls(folder, model, True)

    def named(self) -> str:
        """How messages name the root."""
        return f"the model root {self.folder} (--model-root)" if self.given else \
            f"the model's folder {self.folder} (the model root)"

    def admits(self, target: str) -> bool:
        return _inside(self.folder, os.path.realpath(target))

    def hint(self, target: str) -> str:
        """The ``--model-root`` that would admit ``target`` (with the model), as a phrase."""
        wider = os.path.commonpath([self.folder, os.path.realpath(target)])
        return f"--model-root {wider} admits it (root= in aggsym.load)"

    def admit(self, target: str, shown, where: str, what: str, line=None) -> str:
        """``target`` resolved, when inside the root; else a :class:`ModelError` at ``shown``/``where`` saying
        ``what`` (\"the included file\", \"the mesh file\") resolves outside."""
        real = os.path.realpath(target)
        if not _inside(self.folder, real):
            link = "" if os.path.abspath(target) == real else f" (through a symbolic link: {os.path.abspath(target)})"
            raise ModelError(shown, where, f"{what} resolves to {real}{link}, outside {self.named()}; files outside "
                                           f"it are not read: {self.hint(real)}", line)
        return real


def model_root(path, root=None) -> ModelRoot:
    """:meth:`ModelRoot.of`."""
    return ModelRoot.of(Path(path), root)


__all__ = ["ModelRoot", "model_root"]
