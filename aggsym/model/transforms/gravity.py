"""Gravity as a runtime parameter: ``aggsym generate robot.urdf --gravity-parameter``.

The model's gravity vector (the URDF reader's (0, 0, -9.81) m/s^2 in the root frame, (1.2)) becomes the three
parameters ``gravity_x, gravity_y, gravity_z``, appended to p with the file's values as defaults, so that a wall- or
ceiling-mounted arm, or a robot on a tilted or accelerating base, needs no second generation: write the gravity
vector, in the root (world) frame, into p.  The vector enters the gravity wrenches G_lk of (2.9) (g = -S G),
inverse and forward dynamics through the base quasi-acceleration (-g, 0) of (2.40), and the potential energy, all
of which are polynomial in it.

An option, not the default: appending three entries to p changes ``NAME_NP`` and the length of p that existing
controllers allocate, so a URDF robot's p stays as it was unless the option is given.  (MJCF models always have
these three parameters, from ``opt.gravity``; a YAML model writes its gravity as expressions in its own parameters.)
"""
from __future__ import annotations

import dataclasses

import sympy as sp

from ...core.backend import as_expr
from ...errors import AggsymError
from ..types import Model, Parameter

NAMES = ("gravity_x", "gravity_y", "gravity_z")


def with_gravity_parameters(model: Model) -> Model:
    """The model with its gravity vector as the last three entries of p (``gravity_x``, ``gravity_y``,
    ``gravity_z``, defaults the model's numbers); an error when the gravity already depends on a parameter or a
    parameter of those names exists."""
    taken = {p.name for p in model.parameters}
    clash = [n for n in NAMES if n in taken]
    if clash:
        raise AggsymError(f"{model.source or model.name}: --gravity-parameter: the model already has a parameter "
                          f"named {clash[0]!r}")
    values = []
    for axis, g in zip("xyz", model.gravity):
        g = as_expr(g)
        if g.free_symbols:
            raise AggsymError(f"{model.source or model.name}: --gravity-parameter: the model's gravity already "
                              f"depends on its parameters ({axis}: {g}); set them in p instead")
        values.append(float(g))
    parameters = tuple(Parameter(n, v) for n, v in zip(NAMES, values))
    return dataclasses.replace(model, gravity=tuple(p.symbol for p in parameters),
                               parameters=tuple(model.parameters) + parameters)


__all__ = ["NAMES", "with_gravity_parameters"]
