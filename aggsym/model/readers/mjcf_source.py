"""The MJCF file before MuJoCo's compiler sees it: hostile and oversized files refused, as for URDF.

MuJoCo's own parser reads the file and everything it includes; this module screens them first, so that what the
compiler is given is bounded and stays in the model's folder:

* each file (the model and every file it includes, transitively) is at most :data:`MAX_BYTES`, and all of them
  together at most :data:`MAX_TOTAL_BYTES`; at most :data:`MAX_ELEMENTS` XML elements in all and
  :data:`MAX_INCLUDES` included files;
* it is XML that expat reads (the line of a syntax error is reported), with no entity declared and no external
  DTD named (a plain ``<!DOCTYPE mujoco>`` is fine): nothing is expanded, nothing outside the file is read;
* the top element of the model is ``<mujoco>``;
* every ``<include file=...>`` (and ``<model file=...>``, MuJoCo's attached sub-models) names a relative path that
  stays inside the model's folder, symbolic links resolved: an absolute path or one leading out (``../``) is
  refused.  Mesh, texture and height-field files are MuJoCo's to read (the inertia of a mesh geom comes from its
  mesh) and are not screened here.

:func:`screen` raises :class:`~aggsym.errors.ModelError` naming the file (and the line) of the problem.
"""
from __future__ import annotations

import os
from pathlib import Path
from xml.parsers import expat

from ...errors import ModelError
from .xml_source import guard, read_capped

MAX_BYTES = 64 * 2 ** 20  # one file (the largest MJCF of dm_control and gymnasium is under 1 MiB)
MAX_TOTAL_BYTES = 256 * 2 ** 20  # the model and everything it includes
MAX_ELEMENTS = 1_000_000  # XML elements in all files together
MAX_INCLUDES = 1_000  # included files
INCLUDING = {"include", "model"}  # elements whose file= is XML that MuJoCo reads as part of the model


def _read(path: Path, shown, budget: dict) -> bytes:
    data = read_capped(path, shown, MAX_BYTES, "an MJCF file")
    budget["bytes"] += len(data)
    if budget["bytes"] > MAX_TOTAL_BYTES:
        raise ModelError(shown, "", f"the model and its included files exceed {MAX_TOTAL_BYTES // 2 ** 20} MiB "
                                    f"together; a model this large is not read")
    return data


def _scan(shown, data: bytes, budget: dict, top_required: bool) -> list:
    """Parse one file with expat (nothing expanded, nothing stored): the (file, line) of its includes."""
    parser = expat.ParserCreate()
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    includes: list = []
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

    guard(parser, refuse, "MJCF")
    parser.StartElementHandler = start
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise ModelError(shown, "", f"not XML: {expat.errors.messages[exc.code]}", exc.lineno) from None
    except LookupError as exc:
        raise ModelError(shown, "<?xml?>", f"not XML that can be read: {exc}", parser.CurrentLineNumber) from None
    return includes


def _inside(folder: str, target: str) -> bool:
    return os.path.commonpath([folder, target]) == folder


def screen(path) -> None:
    """Screen an MJCF file and every file it includes (see the module's text) before MuJoCo compiles it."""
    path = Path(path)
    folder = os.path.realpath(path.parent)
    budget = {"bytes": 0, "elements": 0}
    pending = [(path, str(path), True)]
    seen: set = set()
    while pending:
        file, shown, top = pending.pop()
        real = os.path.realpath(file)
        if real in seen:
            continue
        seen.add(real)
        if len(seen) > MAX_INCLUDES + 1:
            raise ModelError(shown, "", f"more than {MAX_INCLUDES} included files; a model this large is not read")
        for name, tag, line in _scan(shown, _read(file, shown, budget), budget, top):
            where = f'<{tag} file="{name[:80]}">'
            if not name or os.path.isabs(name) or name.startswith(("\\", "~")) or ":" in name[:3]:
                raise ModelError(shown, where, "an included file must be given relative to the model's folder "
                                               f"({folder}); an absolute path is refused", line)
            candidates = {os.path.realpath(os.path.join(folder, name)),
                          os.path.realpath(os.path.join(os.path.dirname(real), name))}
            outside = [c for c in candidates if not _inside(folder, c)]
            if outside:
                raise ModelError(shown, where, f"the included file resolves to {outside[0]}, outside the model's "
                                               f"folder {folder}; files outside it are not read", line)
            target = os.path.realpath(os.path.join(folder, name))
            if os.path.exists(target):  # (a missing file is MuJoCo's compiler's to report)
                pending.append((Path(target), target, False))


__all__ = ["screen", "MAX_BYTES", "MAX_TOTAL_BYTES", "MAX_ELEMENTS", "MAX_INCLUDES"]
