"""The identification routines (on request): the regressor Y (tau = Y pi) and the base regressor Yb, with the
layouts that name their columns (the base parameters: :func:`~.analyses.base_parameters`)."""
from __future__ import annotations

from ..mechanics import regressor
from .analyses import BASE_RANK_TOLERANCE, BASE_SEED, base_parameters
from .registry import Output, Routine, flat, register
from .shapes import regressor_shape


def regressor_layout(model) -> dict:
    exprs = regressor.standard_parameters(model)
    defaults = dict(zip(model.parameter_symbols, model.parameter_values))
    out = []
    for b, k in enumerate(regressor.blocks(model)):
        body = model.bodies[k]
        block = exprs[10 * b:10 * b + 10]
        item = {"body": body.name, "columns": [10 * b, 10 * b + 10],
                "frame": "link" if body.link_rotation is not None else "body",
                "values": {name: float(v.subs(defaults)) for name, v in zip(regressor.PARAMETERS, block)}}
        if any(v.free_symbols for v in block):
            item["expressions"] = {name: str(v) for name, v in zip(regressor.PARAMETERS, block)}
        out.append(item)
    return {"Y": {"shape": list(regressor_shape(model)), "order": "row-major", "rows": [c.name for c in model.coordinates]},
            "parameters": list(regressor.PARAMETERS),
            "convention": ("tau = Y pi (inverse_dynamics), pi per block (m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, "
                           "Izz): mass, first moment and inertia about the body (URDF: link) frame's origin, in its "
                           "axes (Pinocchio's order and frame); one block per moving body, links welded by fixed "
                           "joints merged into it; 'values': the model's own pi at the default parameters ('expressions': in the "
                           "parameters, where they enter); with an armature a, tau = Y pi + a qdd (the armature is "
                           "not a body: Pinocchio's regressor leaves it out too)"),
            "blocks": out}


def standard_parameter_names(model) -> list:
    return [f"{name}_{model.bodies[k].name}" for k in regressor.blocks(model) for name in regressor.PARAMETERS]


def base_regressor_layout(model) -> dict:
    independent, dependent, beta, samples = base_parameters(model)
    names = standard_parameter_names(model)
    items = []
    for r, j in enumerate(independent):
        combination = {names[j]: 1.0}
        for d, jd in enumerate(dependent):
            if beta[r, d] != 0.0:
                combination[names[jd]] = float(beta[r, d])
        items.append({"name": names[j], "column": j, "combination": combination})
    return {"Yb": {"shape": [model.nv, len(independent)], "order": "row-major"},
            "base_parameters": items,
            "convention": ("tau = Yb pi_b; pi_b[r] = sum of coefficient * standard parameter over 'combination' (names "
                           "PARAM_BODY of the regressor's blocks: see layouts.regressor); Yb is the regressor's columns "
                           "'column'.  Computed at generation from the regressor at the default parameters: a change of "
                           "the geometry in p may change the combinations"),
            "samples": samples, "seed": BASE_SEED, "rank_tolerance": BASE_RANK_TOLERANCE,
            "unidentifiable": [names[j] for j in dependent]}


register(Routine("regressor", ("q", "qd", "qdd", "p"), (Output("Y", regressor_shape),),
                 lambda bound, kin, x: (flat(regressor.regressor(bound, kin, x["qd"], x["qdd"])),),
                 "the identification regressor Y(q, qd, qdd), n x 10B row-major: tau = Y pi, pi the 10 standard "
                 "inertial parameters of each of the B moving bodies (Pinocchio's order and frames): the dynamic "
                 "wrench (2.10) is linear in pi, carried by the backward sweep (2.41)-(2.42), projected by (2.15)",
                 layout=regressor_layout, coupled="columns", on_request=True))
register(Routine("base_regressor", ("q", "qd", "qdd", "p"),
                 (Output("Yb", lambda model: (model.nv, len(base_parameters(model)[0]))),),
                 lambda bound, kin, x: (_base_columns(bound, kin, x),),
                 "the base regressor Yb, n x r row-major: the regressor's r independent columns, tau = Yb pi_b with "
                 "the base parameters of the manifest (each a combination of standard parameters, found at "
                 "generation from random samples of Y)", layout=base_regressor_layout, coupled=None, on_request=True))


def _base_columns(bound, kin, x):
    """The independent columns of the regressor."""
    Y = regressor.regressor(bound, kin, x["qd"], x["qdd"])
    return [row[j] for row in Y for j in base_parameters(bound.model)[0]]
