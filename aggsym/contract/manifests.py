"""The manifest (NAME.json, :func:`manifest`): coordinates, parameters, the routines' signatures, layouts and
operation counts, and the entries of constraints, time, elastic pairs and frames; and the bounds ``aggsym check``
holds the float C to (:data:`FLOAT_TOLERANCE`).  The C functions' names are given (``functions``): they belong to
the C target (:mod:`aggsym.codegen.names`), and the contract does not import the code generator."""
from __future__ import annotations

from .. import __version__
from ..mechanics import elastic
from ..model.transforms.joint_dynamics import passive_entry
from .registry import ROUTINES, input_length, signature
from .regularity import mass_matrix_entry
from .singular_states import status_entry


def frames_entry(model) -> list:
    """The manifest's list of the emitted frames, in output order: name, body, origin and axes in the body."""
    return [{"name": f.name, "body": f.body, "point": [str(x) for x in f.point],
             "axes": None if f.axes is None else [[str(x) for x in row] for row in f.axes],
             "rotation": [[axis, str(angle)] for axis, angle in f.rotation]} for f in model.frames]


# --scalar float: per routine the bound of the float C's error against the double twin, relative to the largest
# value the routine returns (for FLOAT_PER_CONDITION also divided by cond(A) at the state), the inputs rounded to
# float: at least 8x the worst seen over the bundled models and the suite's robots (docs/generated-code.md, "Single precision"); the
# issue's 1e-4 on A, the inverse dynamics and the frame poses.  Models with prescribed motions get FLOAT_TIME times
# as much: their spin angles w t are computed in float, so the error grows with t (check draws 0 <= t <= 10).
FLOAT_TOLERANCE = {
    "inertia": 1e-4, "inverse_dynamics": 1e-4, "frame_poses": 1e-4,
    "bias": 5e-5, "coriolis": 2e-4, "gravity": 1e-5, "nonlinear_effects": 5e-5, "kinetic_energy": 1e-5,
    "potential_energy": 1e-3, "momentum": 1e-5, "joint_wrenches": 1e-5, "elastic": 1e-5, "elastic_partition": 1e-5,
    "frame_jacobians": 1e-5, "frame_accelerations": 1e-5, "center_of_mass": 1e-5, "com_jacobian": 1e-5,
    "centroidal_map": 5e-5, "regressor": 1e-5, "base_regressor": 1e-5, "friction_regressor": 1e-5,
    "friction_base_regressor": 1e-5, "inverse_dynamics_derivatives": 2e-4,
    "constraint_residual": 1e-4, "constraint_jacobian": 1e-5, "constraint_bias": 5e-5, "slip_velocities": 1e-5,
    "delassus": 1e-6, "constrained_forward_dynamics": 5e-5, "support_coefficients": 1e-5, "support_direct": 2e-5,
    "support_inverse": 1e-5,
    "forward_dynamics": 1e-6, "inertia_inverse": 1e-6, "transvective_factors": 1e-6,
    "forward_dynamics_derivatives": 1e-6,
}
FLOAT_PER_CONDITION = ("forward_dynamics", "inertia_inverse", "transvective_factors", "forward_dynamics_derivatives",
                       "delassus")
FLOAT_TOLERANCE_DEFAULT = 1e-4  # the others: joint_friction (worst seen 7e-8), integrate (1.8e-7 on solo12)
FLOAT_TIME = 100


def float_tolerance(model, routines) -> dict:
    """The manifest's ``float_tolerance`` (role -> bound) and the notes that say how to read it."""
    factor = FLOAT_TIME if model.time_dependent else 1
    out = {"float_tolerance": {r.role: FLOAT_TOLERANCE.get(r.role, FLOAT_TOLERANCE_DEFAULT) * factor
                               for r in routines},
           "float_tolerance_per_condition": [r.role for r in routines if r.role in FLOAT_PER_CONDITION]}
    if model.time_dependent:
        out["float_time"] = (f"prescribed motions: the spin angles are computed in float, so the error grows with "
                             f"t; the bounds ({FLOAT_TIME}x those of a model without them) hold for 0 <= t <= 10")
    return out


def manifest(model, routines, ops: dict, omitted=None, scalar: str = "double", layout: dict | None = None, *,
             functions: dict) -> dict:
    """The JSON manifest of the generated code: ``routines`` those emitted, ``ops[role]`` their operation counts,
    ``omitted`` the routines left out and why, ``scalar`` the C type (with ``float``, ``float_tolerance``: per
    routine the error bound against the double twin that ``aggsym check`` holds the C to).  ``layout``: with
    ``aggsym generate --split``, the ``split`` entry (every file written, each routine's .c, the helpers' header,
    the Makefile and its library); without it the manifest has no ``split`` key, the C being NAME.c.  ``functions``:
    role -> the C function's name (:func:`aggsym.codegen.names.c_symbol`, given by the caller: naming the C is the
    C target's, above the contract)."""
    out = {
        "name": model.name,
        "scalar": scalar,
        "nq": model.nq,
        "nv": model.nv,
        "coordinates": [{"name": name, "joint": joint, "kind": kind} for name, joint, kind in model.positions],
        "velocities": [{"name": c.name, "joint": c.joint, "kind": c.kind} for c in model.coordinates],
        "parameters": [{"name": p.name, "value": p.value} for p in model.parameters],
        "functions": dict(functions),
        "descriptions": {r.role: r.doc for r in routines},
        "signatures": {r.role: {"inputs": list(signature(r, model)),
                                "outputs": [{"name": o.name, "shape": list(o.shape(model))} for o in r.written],
                                "input_sizes": {i: input_length(model, i, r) for i in signature(r, model)},
                                "returns": f"int: 0, or nonzero when {r.status.failure}" if r.status else "void"}
                       for r in routines},
        "layouts": {r.role: r.layout(model) for r in routines if r.layout is not None},
        "couplings": [{"coordinate": c.coordinate, "master": c.master, "multiplier": c.multiplier,
                       "offset": c.offset} for c in model.couplings],
        "conservative": model.conservative,
        "ops": {r.role: ops[r.role] for r in routines},
        "omitted": dict(omitted or {}),
        "not_emitted": [r.role for r in ROUTINES.values() if r.exists_for(model) and r not in routines
                       and r.role not in (omitted or {})],
        "limits": [dict(limits) for limits in model.limits],
        "armature": model.armature,
        "bodies": len(model.bodies),
        "generator": f"aggsym {__version__}",
    }
    if scalar == "float":
        out.update(float_tolerance(model, routines))
    if model.time_dependent:
        out["time"] = time_entry(model, scalar)
    if elastic.is_elastic(model):
        out["elastic"] = elastic_entry(model)
    if model.constraints:
        out["constraints"] = constraints_entry(model)
    if any(r.role.startswith("frame_") for r in routines):
        out["frames"] = frames_entry(model)
    mass_matrix = mass_matrix_entry(model)
    if mass_matrix is not None:  # A(q) not proved regular everywhere: degenerate bodies, where it is singular
        out["mass_matrix"] = {**mass_matrix, **status_entry(routines)}
    passive = passive_entry(model)
    if passive is not None:  # the joints' damping and friction: in forward and inverse dynamics or not
        out["passive"] = passive
    if model.meta.get("mjcf"):  # an MJCF model: its conventions and what MuJoCo has beside the equations
        out["mjcf"] = model.meta["mjcf"]
    if model.meta.get("snapped_angles"):  # an approximation the user asked for (--snap-angles), recorded
        out["snapped_angles"] = model.meta["snapped_angles"]
    if layout is not None:
        out["split"] = layout
    return out


def constraints_entry(model) -> dict:
    """The manifest's description of the constraints (chapter 4): each one's rows and its slice of lambda."""
    items, start = [], 0
    for c in model.constraints:
        if c.joint_row is not None:
            r = c.joint_row
            items.append({"name": c.name, "kind": "joint", "rows": list(c.rows), "lambda": [start, start + 1],
                          "first": [[name, str(x)] for name, x in r.first],
                          "second": [[name, str(x)] for name, x in r.second],
                          "reference": [str(x) for x in r.reference], "polynomial": [str(x) for x in r.polynomial],
                          "free": []})
            for key, branches in (("first_sites", r.first_sites), ("second_sites", r.second_sites)):
                if branches:  # a spatial tendon's length: its branches (divisor, sites on bodies)
                    items[-1][key] = [[str(div), [[body, [str(x) for x in point]] for body, point in sites]]
                                      for div, sites in branches]
            start += 1
            continue
        items.append({"name": c.name, "body": c.body, "link": c.link or None, "medium": c.medium,
                      "kind": c.kind or None, "rows": list(c.rows), "lambda": [start, start + len(c.rows)],
                      "point": [str(x) for x in c.point], "at": None if c.at is None else [str(x) for x in c.at],
                      "rotation": [[axis, str(angle)] for axis, angle in c.rotation],
                      "free": list(c.free_translations),
                      "friction": None if c.friction is None else {c.friction[0]: str(c.friction[1])},
                      "wheel": None if c.wheel is None else {"radius": str(c.wheel[0]),
                                                             "axle": [str(x) for x in c.wheel[1]]}})
        start += len(c.rows)
    out = {
        "m": model.constraint_rows,
        "equations": ("A(q) qdd + b + g + c = tau + J^T lambda,  J qdd + gamma = -(kd J qd + kp phi) "
                      "(4.25)-(4.28); bilateral (no complementarity: a contact may pull)"),
        "rows": ("row r of J, gamma, phi and lambda: the constraint's forbidden motion along (o1 o2 o3) or about "
                 "(theta4 theta5 theta6) the axes of its reference frame, fixed in the medium at the contact "
                 "point; translational rows: the contact point's velocity relative to the medium, rotational: the "
                 "relative angular velocity; for ground contacts without rotation, Pinocchio's "
                 "LOCAL_WORLD_ALIGNED"),
        "lambda": ("the wrench (f, mu) the medium exerts on the body about the contact point, in the reference "
                   "axes, the entries of the blocked rows; a loop's medium body gets -lambda"),
        "phi": ("translational rows: the contact point's offset from 'at' (default: where it is at q = 0); "
                "rotational rows: the rotation vector of the body's orientation relative to the one it has at "
                "q = 0, both in the reference axes"),
        "stabilization": {"kp": str(model.stabilization[0]), "kd": str(model.stabilization[1])},
        "regularization": str(model.regularization),
        **({"proximal": {"mu": str(model.proximal[0]), "iterations": int(model.proximal[1]),
                         "solve": ("x_0 = 0, (G + mu E) x_{k+1} = b + mu x_k for k < iterations, G = J A^-1 J^T "
                                   "(+ regularization): Pinocchio's proximal iteration with a fixed count; "
                                   "|x_N - G^-1 b| <= (mu / (sigma_min(G) + mu))^N |G^-1 b| when J has full "
                                   "row rank, |x_N| <= N |b| / mu always")}} if model.proximal else {}),
        "rolling": ("a wheel (kind 'rolling'): its rows are the velocity of the disc's material point at the "
                    "contact, centre + radius * (axle x e), e = (axle x normal)/|axle x normal|; only o3 is "
                    "holonomic (phi: the contact point's height over the plane; the o1, o2 entries of phi are 0)"),
        "friction": ("on the free translations of a sliding contact, from its slip velocities w (slip_velocities): "
                     "viscous W = -c w; Coulomb W = -mu |lambda_n| w/|w| (zero where |w| < 1e-9), lambda_n the "
                     "constraint's one blocked translation; W acts on the body at the contact point (the medium "
                     "body gets -W)"),
        "constraints": items,
    }
    if any(c.joint_row is not None for c in model.constraints):
        out["joint_rows"] = ("a joint-space row (kind 'joint', an MJCF joint or fixed-tendon equality): phi = (L1 - "
                             "ref1) - P(L2 - ref2) with L1 = sum of first's c q, L2 = sum of second's c q, P the "
                             "polynomial y0 + a1 x + ... + a4 x^4 ('polynomial'), J = c1 - P'(x) c2, gamma = -P''(x) "
                             "(c2 qd)^2; lambda the generalized force J^T lambda along it")
    if any(c.joint_row is not None and (c.joint_row.first_sites or c.joint_row.second_sites)
           for c in model.constraints):
        out["spatial_joint_rows"] = ("first_sites/second_sites: L1/L2 is a spatial tendon's length (the sum over "
                                     "its branches of the distances between consecutive sites, each branch over its "
                                     "divisor) instead of a linear form; J = dL1/dq - P'(x) dL2/dq, gamma = L1'' - "
                                     "P''(x) L2'^2 - P'(x) L2'' at qdd = 0")
    return out


def time_entry(model, scalar: str = "double") -> dict:
    """The manifest's description of the time input and of the prescribed motions (rotors, (2.13))."""
    rotors = []
    for b in model.bodies:
        for code, expr in b.pair.prescribed:
            rotors.append({"body": b.name, "carrier": b.parent, "joint": b.pair.name, "axis": code,
                           "angle": str(expr)})
    return {
        "input": "t",
        "length": 1,
        "meaning": ("the time: every routine takes it after its other inputs and before p (C: a pointer to one "
                    f"{scalar}; NumPy: a number or an array of the batch shape).  The prescribed angles below and "
                    "their first and second derivatives (taken symbolically) are evaluated at t; the carrier's "
                    "motion does not act on them (Prop. 2.7).  bias holds all their rate and acceleration terms."),
        "prescribed": rotors,
        "constraint_motions": [{"constraint": c.name, "motion": {code: str(expr) for code, expr in c.motion}}
                               for c in model.constraints if c.motion],
    }


def elastic_entry(model) -> dict:
    """The manifest's description of the elastic pairs (2.27)."""
    pairs = []
    for b in model.bodies:
        if b.pair.elastic:
            pairs.append({"joint": b.pair.name, "coordinates": [c.name for c in b.pair.coordinates],
                          "stiffness": [[str(x) for x in row] for row in b.pair.stiffness],
                          "rest": [str(x) for x in b.pair.rest] if b.pair.rest is not None
                          else ["0"] * len(b.pair.coordinates)})
    return {"equation": "A(q) qdd + b(q, qd) + g(q) + C (q - q0) = tau (2.27); c = C (q - q0) is the routine "
                        "'elastic', included in inverse_dynamics, nonlinear_effects and forward_dynamics; "
                        "1/2 (q - q0)^T C (q - q0) is in potential_energy",
            "pairs": pairs}
