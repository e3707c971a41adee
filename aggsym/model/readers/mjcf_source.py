"""The MJCF file before MuJoCo's compiler sees it: hostile and oversized files refused, as for URDF.

MuJoCo's own parser reads the file and everything it includes; this module screens them first, so that what the
compiler is given is bounded and stays inside the model root:

* each file (the model and every file it includes, transitively) is at most :data:`MAX_BYTES`, and all of them
  together at most :data:`MAX_TOTAL_BYTES`; at most :data:`MAX_ELEMENTS` XML elements in all and
  :data:`MAX_INCLUDES` included files;
* it is XML that expat reads (the line of a syntax error is reported), with no entity declared and no external
  DTD named (a plain ``<!DOCTYPE mujoco>`` is fine): nothing is expanded, nothing outside the file is read;
* the top element of the model is ``<mujoco>``;
* every file the model names resolves inside the model root (:mod:`.model_root`: the model's folder, or
  ``--model-root``), symbolic links followed: ``<include file=...>`` and ``<model file=...>`` (MuJoCo's attached
  sub-models; relative to the folder of the model, or of the sub-model, and of the including file: both must be
  inside), and the files MuJoCo's compiler reads for assets (``<mesh>``, ``<skin>``, ``<hfield>``,
  ``<flexcomp>`` and ``<texture>`` with its six cube faces), in the ``<compiler>``'s ``meshdir``, ``texturedir``
  or ``assetdir`` as MuJoCo resolves them (``strippath`` too).  Absolute paths are judged the same way.

:func:`screen` raises :class:`~aggsym.errors.ModelError` naming the file (and the line) of the problem.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from ...errors import ModelError
from .model_root import ModelRoot
from .xml_source import guard, read_capped

MAX_BYTES = 64 * 2 ** 20  # one file (the largest MJCF of dm_control and gymnasium is under 1 MiB)
MAX_TOTAL_BYTES = 256 * 2 ** 20  # the model and everything it includes
MAX_ELEMENTS = 1_000_000  # XML elements in all files together
MAX_INCLUDES = 1_000  # included files
INCLUDING = {"include", "model"}  # elements whose file= is XML that MuJoCo reads as part of the model
CUBE = ("fileright", "fileleft", "fileup", "filedown", "filefront", "fileback")
ASSET_FILES = {"mesh": ("file",), "skin": ("file",), "hfield": ("file",), "flexcomp": ("file",),
               "texture": ("file",) + CUBE}  # the attributes naming files MuJoCo's compiler reads
ASSET_NAMES = {"mesh": "mesh", "skin": "skin", "hfield": "height field", "flexcomp": "flexcomp's mesh",
               "texture": "texture"}


def _read(path: Path, shown, budget: dict) -> bytes:
    data = read_capped(path, shown, MAX_BYTES, "an MJCF file")
    budget["bytes"] += len(data)
    if budget["bytes"] > MAX_TOTAL_BYTES:
        raise ModelError(shown, "", f"the model and its included files exceed {MAX_TOTAL_BYTES // 2 ** 20} MiB "
                                    f"together; a model this large is not read")
    return data


def _scan(shown, data: bytes, budget: dict, top_required: bool) -> tuple:
    """Parse one file with expat (nothing expanded, nothing stored): its includes (file, tag, line), the files its
    assets name (tag, attribute, file, line) and its compiler's folders ({attribute: [values]})."""
    parser = expat.ParserCreate()
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    includes: list = []
    assets: list = []
    compiler: dict = {}
    first = [True]

    def refuse(where, message):
        raise ModelError(shown, where, message, parser.CurrentLineNumber)

    def start(tag, attrib):
        budget["elements"] += 1
        if budget["elements"] > MAX_ELEMENTS:
            refuse(f"<{tag}>", f"more than {MAX_ELEMENTS:,} XML elements; a model this large is not read (the limit "
                               f"guards against files made to exhaust time and memory)")
        if first[0]:
            first[0] = False
            if top_required and tag != "mujoco":
                refuse(f"<{tag}>", f"not an MJCF file: the top element is <{tag}>, expected <mujoco>")
        if tag in INCLUDING and "file" in attrib:
            includes.append((attrib["file"], tag, parser.CurrentLineNumber))
        for attribute in ASSET_FILES.get(tag, ()):
            if attrib.get(attribute):
                assets.append((tag, attribute, attrib[attribute], parser.CurrentLineNumber))
        if tag == "compiler":
            for attribute in ("meshdir", "texturedir", "assetdir", "strippath"):
                if attribute in attrib:
                    compiler.setdefault(attribute, []).append(attrib[attribute])

    guard(parser, refuse, "MJCF")
    parser.StartElementHandler = start
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise ModelError(shown, "", f"not XML: {expat.errors.messages[exc.code]}", exc.lineno) from None
    except LookupError as exc:
        raise ModelError(shown, "<?xml?>", f"not XML that can be read: {exc}", parser.CurrentLineNumber) from None
    return includes, assets, compiler


@dataclass
class _Unit:
    """One model as MuJoCo's parser makes it: a file and what it includes (a ``<model file>`` starts another),
    its asset files resolved against its compiler's folders, relative to the folder of its first file."""

    base: str
    assets: list = field(default_factory=list)  # (file shown, tag, attribute, name, line)
    compiler: dict = field(default_factory=dict)

    def folders(self, tag: str) -> list:
        """The folders ``tag``'s files are relative to (as MuJoCo's compiler, checked on 3.x: meshes, skins, height
        fields and flexcomps in meshdir, textures in texturedir, either by assetdir when not set; several values
        in one model: each)."""
        own = "texturedir" if tag == "texture" else "meshdir"
        values = self.compiler.get(own) or self.compiler.get("assetdir") or [""]
        return [os.path.join(self.base, v) for v in dict.fromkeys(values)]

    def strips(self) -> bool:
        return any(v.strip().lower() == "true" for v in self.compiler.get("strippath", ()))


def screen(path, root=None) -> None:
    """Screen an MJCF file and every file it includes or names (see the module's text) before MuJoCo compiles it;
    ``root``: the model root (:mod:`.model_root`; default: the model's folder)."""
    path = Path(path)
    bounds = ModelRoot.of(path, root)
    budget = {"bytes": 0, "elements": 0}
    units = [_Unit(os.path.dirname(bounds.model))]
    pending = [(path, str(path), True, 0)]
    seen: set = set()
    while pending:
        file, shown, top, unit = pending.pop()
        real = os.path.realpath(file)
        if real in seen:
            continue
        seen.add(real)
        if len(seen) > MAX_INCLUDES + 1:
            raise ModelError(shown, "", f"more than {MAX_INCLUDES} included files; a model this large is not read")
        includes, assets, compiler = _scan(shown, _read(file, shown, budget), budget, top)
        for key, values in compiler.items():
            units[unit].compiler.setdefault(key, []).extend(values)
        units[unit].assets.extend((shown, *asset) for asset in assets)
        for name, tag, line in includes:
            where = f'<{tag} file="{name[:80]}">'
            if not name.strip():
                raise ModelError(shown, where, "an empty file name", line)
            base = units[unit].base
            candidates = dict.fromkeys([os.path.join(base, name), os.path.join(os.path.dirname(real), name)])
            what = "the included file" if tag == "include" else "the attached model's file"
            found = [bounds.admit(c, shown, where, what, line) for c in candidates]
            for target in dict.fromkeys(found):
                if os.path.exists(target):  # (a missing file is MuJoCo's compiler's to report)
                    if tag == "model":
                        units.append(_Unit(os.path.dirname(target)))
                    pending.append((Path(target), target, False, unit if tag == "include" else len(units) - 1))
    for unit in units:
        for shown, tag, attribute, name, line in unit.assets:
            where = f'<{tag} {attribute}="{name[:80]}">'
            file = os.path.basename(name.replace("\\", "/")) if unit.strips() else name
            for folder in unit.folders(tag):
                bounds.admit(os.path.join(folder, file), shown, where, f"the {ASSET_NAMES[tag]} file", line)


__all__ = ["screen", "ASSET_FILES", "MAX_BYTES", "MAX_TOTAL_BYTES", "MAX_ELEMENTS", "MAX_INCLUDES"]
