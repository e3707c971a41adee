"""The side files of a model read from URDF, xacro or MJCF: what those formats cannot say, in the YAML model's
grammar (``aggsym generate robot.urdf --constraints feet.yaml``).
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

from ..types import Model
from .yaml_reader import SIDE_FILE_KEYS, YamlReader, read_text


def load_constraints(path, model: Model) -> Model:
    """A URDF robot's constraints from a side file (``aggsym generate robot.urdf --constraints feet.yaml``):
    ``constraints:`` as in a YAML model, bodies and media named by URDF link (a point in the link's frame), and
    ``stabilization:``.  Returns the model with them after its own (an MJCF model's equalities)."""
    path = Path(path)
    reader = YamlReader(path, read_text(path))
    for p in model.parameters:
        reader.symbols[p.name] = p.symbol
        reader.defaults[p.symbol] = float(p.value)
    top = reader.mapping(reader.doc.root, (), SIDE_FILE_KEYS, required=("constraints",))
    if model.couplings:
        reader.fail(("constraints",), "constraints on a model with coupled (mimic) coordinates are not supported yet")
    frames = {f.name: (f.body, f.rotation, f.translation) for f in model.link_table.frames}
    constraints = reader.constraints(top["constraints"], frames, model.time_dependent)
    own = {c.name for c in model.constraints}  # the model's own (an MJCF model's connect and weld) come first
    for i, c in enumerate(constraints):
        if c.name in own:
            reader.fail(("constraints", i, "name"), f"the model already has a constraint named {c.name!r} (from its "
                                                    f"file); choose another name")
    constraints = tuple(model.constraints) + tuple(constraints)
    stabilization = reader.stabilization(top.get("stabilization"), constraints)
    return dataclasses.replace(model, constraints=constraints, stabilization=stabilization,
                               regularization=reader.regularization(top.get("regularization"), constraints),
                               proximal=reader.proximal(top.get("proximal"), constraints))
