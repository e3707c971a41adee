"""The frames of the frame routines (poses, Jacobians, accelerations: :mod:`aggsym.mechanics.frames`): which
frames a model offers, and which it emits.

A YAML model offers each body (at its origin, in its axes) and each entry of its ``frames:`` list (a point and
constant axes on a body); a URDF robot offers every link, on the body it was merged into, at the link's frame.
By default a model emits the bodies without a child body (end effectors, feet) and then its ``frames:`` (YAML), or
the links without a child link (URDF), in tree order; ``aggsym generate ... --frames a,b,...`` names them instead,
in the order given (:func:`select_frames`).  The manifest lists the emitted frames in output order.
"""
from __future__ import annotations

import dataclasses

import sympy as sp

from ...errors import AggsymError
from ...suggest import did_you_mean
from ..types import Frame, Model

MAX_FRAMES = 10_000  # frames of a YAML model's frames: list, and names given to --frames (as MAX_LINKS)


_IDENTITY = ((sp.S.One, sp.S.Zero, sp.S.Zero), (sp.S.Zero, sp.S.One, sp.S.Zero), (sp.S.Zero, sp.S.Zero, sp.S.One))


def _link_frame(link: str, body: str, R, t) -> Frame:
    axes = None if R is None else tuple(tuple(row) for row in R)
    if axes == _IDENTITY:  # (exactly: a float 1.0 or 0.0 is not the exact identity, as for a Matrix)
        axes = None
    point = (sp.Integer(0),) * 3 if t is None else tuple(t)
    return Frame(name=link, body=body, point=point, axes=axes)


def catalog(model: Model) -> dict:
    """{name: Frame}: every frame the model offers: its links (URDF: the file's links; YAML: its bodies), then a
    YAML model's ``frames:``."""
    out = {f.name: _link_frame(f.name, f.body, f.rotation, f.translation) for f in model.link_table.frames}
    for f in model.link_table.declared:
        out[f.name] = f
    return out


def default_frames(model: Model) -> tuple:
    """The frames emitted when none are named: the childless links (URDF), or the childless bodies and then the
    ``frames:`` list (YAML), in tree order."""
    offered = catalog(model)
    leaves = list(model.link_table.leaves) + [f.name for f in model.link_table.declared]
    return tuple(offered[name] for name in leaves)


def select_frames(model: Model, names) -> Model:
    """The model emitting the named frames, in that order (``--frames``); an unknown or repeated name is an error
    naming the model's file and listing some of the names it offers."""
    names = list(names)
    if len(names) > MAX_FRAMES:
        raise AggsymError(f"--frames: {len(names)} names, at most {MAX_FRAMES}")
    offered = catalog(model)
    out, seen = [], set()
    for name in names:
        if name not in offered:
            some = ", ".join(repr(n) for n in list(offered)[:8]) + (", ..." if len(offered) > 8 else "")
            shown = name if len(name) <= 80 else name[:80] + "..."
            kind = "link" if model.link_table.from_file else "body or frame"
            raise AggsymError(f"{model.source}: --frames: no {kind} named {shown!r}{did_you_mean(name, offered)} "
                              f"(the model has {some})")
        if name in seen:
            raise AggsymError(f"{model.source}: --frames: {name!r} is named twice")
        seen.add(name)
        out.append(offered[name])
    return dataclasses.replace(model, frames=tuple(out))


__all__ = ["catalog", "default_frames", "select_frames", "MAX_FRAMES"]
