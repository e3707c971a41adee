"""The identification routines (on request): the regressor Y (tau = Y pi) and the base regressor Yb, the same with
joint friction and armature (tau = Y_f pi_f, issue 34), with the layouts that name their columns (the base
parameters: :func:`~.analyses.base_parameters`)."""
from __future__ import annotations

from ..core.backend import as_expr
from ..mechanics import regressor
from .analyses import BASE_RANK_TOLERANCE, BASE_SEED, base_parameters
from .registry import Output, Routine, flat, register
from .shapes import friction_regressor_shape, regressor_shape

DRIVE_PARAMETERS = ("fv", "fc", "ia")  # viscous friction, Coulomb friction, armature: the names PARAM_COORDINATE


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


def drive_parameter_names(model) -> list:
    """The names of the friction regressor's columns after the standard ones: fv_, fc_ per joint, ia_ per rotor."""
    joints, rotors = regressor.drives(model)
    coords = model.coordinates
    return ([f"fv_{coords[j].name}" for j in joints] + [f"fc_{coords[j].name}" for j in joints]
            + [f"ia_{coords[j].name}" for j in rotors])


def drive_values(model) -> list:
    """Per column after the standard ones (:func:`drive_parameter_names`): (value at the default parameters, the
    expression where it is one).  Viscous: the URDF ``damping_<joint>`` parameter plus MJCF's ``damping``;
    Coulomb: the URDF ``friction_<joint>`` parameter; armature: ``armature`` plus MJCF's own."""
    import sympy as sp

    joints, rotors = regressor.drives(model)
    symbols = {p.name: sym for p, sym in zip(model.parameters, model.parameter_symbols)}
    defaults = dict(zip(model.parameter_symbols, model.parameter_values))

    def own(table, j):
        return as_expr(table[j]) if table else sp.Integer(0)

    def urdf(prefix, j):
        return symbols.get(f"{prefix}_{model.coordinates[j].name}", sp.Integer(0))

    exprs = ([urdf("damping", j) + own(model.damping, j) for j in joints] + [urdf("friction", j) for j in joints]
             + [as_expr(model.armature) + own(model.dof_armature, j) for j in rotors])
    return [(float(as_expr(e).subs(defaults)), str(e) if as_expr(e).free_symbols else None) for e in exprs]


def friction_regressor_layout(model) -> dict:
    base = regressor_layout(model)
    first = base["Y"]["shape"][1]
    drives = []
    for k, (name, (value, expr)) in enumerate(zip(drive_parameter_names(model), drive_values(model))):
        item = {"name": name, "column": first + k, "value": value}
        if expr is not None:
            item["expression"] = expr
        drives.append(item)
    return {**base, "Y": {**base["Y"], "shape": list(friction_regressor_shape(model))},
            "drives": drives,
            "convention": ("tau = Y_f pi_f (inverse_dynamics, less joint_friction where the model has it): the "
                           "regressor's blocks (see 'blocks', as layouts.regressor), then per joint (a coordinate "
                           "of a pair that is not free) its viscous friction fv (column qd_j), then per joint its "
                           "Coulomb friction fc (column sign(qd_j), 0 at qd_j = 0), then the armature ia (column "
                           "qdd_j) per joint and per free coordinate the model gives one; 'drives' names them "
                           "PARAM_COORDINATE with the model's values (URDF damping_<joint> and friction_<joint>, "
                           "MJCF damping and armature, --armature)")}


def base_regressor_layout(model, role: str = "regressor") -> dict:
    independent, dependent, beta, samples, inexact, residual = base_parameters(model, role)
    names = standard_parameter_names(model) + (drive_parameter_names(model) if role == "friction_regressor" else [])
    items = []
    for r, j in enumerate(independent):
        combination = {names[j]: 1.0}
        for d, jd in enumerate(dependent):
            if beta[r, d] != 0.0:
                combination[names[jd]] = float(beta[r, d])
        items.append({"name": names[j], "column": j, "combination": combination})
    return {"Yb": {"shape": [model.nv, len(independent)], "order": "row-major"},
            "base_parameters": items,
            "convention": (f"tau = Yb pi_b; pi_b[r] = sum of coefficient * standard parameter over 'combination' (names "
                           f"PARAM_BODY or PARAM_COORDINATE of the columns of layouts.{role}); Yb is the columns "
                           "'column' of that regressor.  Computed at generation from the regressor at the default "
                           "parameters: a change of the geometry in p may change the combinations.  The coefficients "
                           "are exact rationals of the model's own numbers (rational states), given as the nearest "
                           "doubles; 'inexact' names the dependent parameters whose relation does not hold exactly "
                           "in the model's numbers (e.g. constant rotations by angles that are not right): their "
                           "coefficients are least squares on the samples, 'inexact_residual' the largest relative "
                           "residual there"),
            "samples": samples, "seed": BASE_SEED, "rank_tolerance": BASE_RANK_TOLERANCE,
            "unidentifiable": [names[j] for j in dependent], "inexact": [names[j] for j in inexact],
            "inexact_residual": residual}


register(Routine("regressor", ("q", "qd", "qdd", "p"), (Output("Y", regressor_shape),),
                 lambda bound, kin, x: (flat(regressor.regressor(bound, kin, x["qd"], x["qdd"])),),
                 "the identification regressor Y(q, qd, qdd), n x 10B row-major: tau = Y pi, pi the 10 standard "
                 "inertial parameters of each of the B moving bodies (Pinocchio's order and frames): the dynamic "
                 "wrench (2.10) is linear in pi, carried by the backward sweep (2.41)-(2.42), projected by (2.15)",
                 layout=regressor_layout, coupled="columns", on_request=True))
register(Routine("base_regressor", ("q", "qd", "qdd", "p"),
                 (Output("Yb", lambda model: (model.nv, len(base_parameters(model, "regressor")[0]))),),
                 lambda bound, kin, x: (_base_columns(bound, kin, x),),
                 "the base regressor Yb, n x r row-major: the regressor's r independent columns, tau = Yb pi_b with "
                 "the base parameters of the manifest (each a combination of standard parameters, found at "
                 "generation from random samples of Y)", layout=base_regressor_layout, coupled=None, on_request=True))
register(Routine("friction_regressor", ("q", "qd", "qdd", "p"), (Output("Y", friction_regressor_shape),),
                 lambda bound, kin, x: (flat(regressor.friction_regressor(bound, kin, x["qd"], x["qdd"])),),
                 "the identification regressor with joint friction and drives, n x (10B + 2J + R) row-major: "
                 "tau = Y_f pi_f, pi_f the 10 standard inertial parameters of each of the B moving bodies, then per "
                 "joint the viscous friction (column qd_j), per joint the Coulomb friction (column sign(qd_j)), per "
                 "joint the armature (column qdd_j): tau is inverse dynamics less joint_friction",
                 layout=friction_regressor_layout, coupled=None, on_request=True))
register(Routine("friction_base_regressor", ("q", "qd", "qdd", "p"),
                 (Output("Yb", lambda model: (model.nv, len(base_parameters(model, "friction_regressor")[0]))),),
                 lambda bound, kin, x: (_base_columns(bound, kin, x, "friction_regressor"),),
                 "the base regressor with joint friction and drives, n x r row-major: friction_regressor's r "
                 "independent columns, tau = Yb pi_b with the base parameters of the manifest (e.g. a first joint's "
                 "armature grouped with the link's inertia about its axis)",
                 layout=lambda model: base_regressor_layout(model, "friction_regressor"), coupled=None,
                 on_request=True))

_BUILDS = {"regressor": regressor.regressor, "friction_regressor": regressor.friction_regressor}


def _base_columns(bound, kin, x, role="regressor"):
    """The independent columns of the regressor ``role``."""
    Y = _BUILDS[role](bound, kin, x["qd"], x["qdd"])
    return [row[j] for row in Y for j in base_parameters(bound.model, role)[0]]
