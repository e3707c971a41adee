"""The YAML model reader: every mistake is reported with the file, the YAML path, the line and the reason.

The format is documented in docs/model-format.md.  Summary::

    name: NAME                       # C identifier, prefix of the generated functions (default: file stem)
    description: text                # optional
    gravity: [gx, gy, gz]            # in the world frame; default [0, 0, 0]
    parameters: {NAME: default, ...} # runtime parameters, the entries of p in this order
    bodies:                          # a tree: exactly one body has parent 'world'
      - name: NAME
        parent: world | BODY
        pair:                        # the pair (parent, this body), (1.24)-(1.27); omitted = welded
          name: NAME                 # joint name (default: the body's name)
          translation: [p1, p2, p3]  # constructive translation, parent axes
          rotation: [[axis, angle], ...]   # constructive rotations in order, axis 1|2|3|x|y|z
          functional: {o1|o2|o3|theta4|theta5|theta6: COORDINATE, ...}
          type: ball                 # instead of functional: a ball pair (Pinocchio's spherical joint); q holds
                                     # its unit quaternion NAME_qx NAME_qy NAME_qz NAME_qw, qd its angular
                                     # velocity NAME_wx NAME_wy NAME_wz in the body's axes (docs/ball-joints.md)
          stiffness: [[...]] | [k1, ...]   # Hooke stiffness C over the pair's coordinates (1.32), (2.27):
                                           # C (q - rest) joins the left side, 1/2 (q - rest)^T C (q - rest) U
          rest: [r1, ...]            # the coordinates where the elastic force vanishes (default 0)
        mass: m                      # omit mass (and inertia) for a massless frame
        com: [x, y, z]               # centre of mass, body axes (default 0)
        inertia: {xx:, yy:, zz:, xy:, xz:, yz:} | [[3x3]]   # about the centre of mass, body axes
        mises: [[6x6]]               # alternatively: the Mises matrix (2.3) at the body origin
        added_mass: [[6x6]] | [l1, ..., l6]   # the medium's added masses Lambda about the body origin, (v, w)
                                     # order, symmetric positive semi-definite: Theta -> Theta + Lambda
                                     # (Prop. 2.8); T gains 1/2 V^T Lambda V, gravity still acts on m only
        rotors:                      # rotating bodies carried by this one (2.13), Fig. 1.3
          - name: NAME               # a body name (unique among bodies and rotors)
            joint: NAME              # the spin pair's name (default: the rotor's name)
            translation: [p1, p2, p3]      # constructive configuration on the carrier, as in a pair
            rotation: [[axis, angle], ...]
            spin: {coordinate: NAME}       # the spin about the rotor's e3 is a generalized coordinate, or
            spin: {prescribed: "expr in t"}  # the spin angle is a known function of the time t (and the
                                     # parameters); its rates are derived symbolically, the carrier's motion
                                     # does not act back on it (Prop. 2.7); every routine then takes t
            mass: m                  # mass properties as for a body (mass/com/inertia or mises);
            com: [x, y, z]           # unbalanced (com off the axis) and asymmetric rotors are allowed
            inertia: ...

A rotor becomes a body of the tree, listed right after its carrier: with ``spin: {coordinate: q}`` its pair is
an ordinary one-coordinate pair ``theta6: q``, with ``spin: {prescribed: ...}`` its pair has no coordinate and
turns by the prescribed angle.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import sympy as sp

from ...errors import ModelError
from ...suggest import did_you_mean
from .builder import TreeBuilder, ball_names
from .expressions import ExpressionError, check_identifier, check_supported, evaluate, parse_value
from ..transforms.frames import MAX_FRAMES, default_frames
from ..types import (CONSTRAINT_KINDS, COORDINATE_CODES, TIME, WORLD, Body, Constraint, Coordinate, Frame, Inertial,
                    Model, Parameter, Pair)
from .validate import inertia_problem, mass_problem, order_tree, support_problem
from .yaml_source import _Doc, _path

TOP_KEYS = {"name", "description", "source", "notes", "gravity", "parameters", "bodies", "contacts", "loops",
            "constraints", "stabilization", "support", "regularization", "proximal", "frames"}
FRAME_KEYS = {"name", "body", "point", "rotation", "description", "notes"}
CONSTRAINT_KEYS = {"name", "body", "point", "medium", "at", "rotation", "motion", "block", "friction", "wheel",
                   "description", "notes"}
SIDE_FILE_KEYS = {"constraints", "stabilization", "regularization", "proximal", "description", "notes"}
STABILIZATION_KEYS = {"kp", "kd"}
PROXIMAL_KEYS = {"mu", "iterations"}
MAX_PROXIMAL_ITERATIONS = 100  # each iteration is one more pair of triangular solves per right-hand side
FRICTION_LAWS = ("viscous", "coulomb")
BODY_KEYS = {"name", "parent", "pair", "mass", "com", "inertia", "mises", "rotors", "added_mass", "description",
             "notes"}
PAIR_KEYS = {"name", "translation", "rotation", "functional", "type", "stiffness", "rest", "description"}
PAIR_TYPES = ("ball",)  # the pairs a 'type' names (without it: the functional configuration of 'functional')
ROTOR_KEYS = {"name", "joint", "translation", "rotation", "spin", "mass", "com", "inertia", "mises", "description",
              "notes"}
SPIN_KEYS = {"coordinate", "prescribed"}
INERTIA_KEYS = ("xx", "yy", "zz", "xy", "xz", "yz")
AXES = {1: 1, 2: 2, 3: 3, "x": 1, "y": 2, "z": 3, "1": 1, "2": 2, "3": 3}
CODE_ALIASES = {"θ4": "theta4", "θ5": "theta5", "θ6": "theta6"}
LATER = {
    "contacts": "'contacts' is not a key: contacts with the medium are entries of 'constraints' (medium: world)",
    "loops": "'loops' is not a key: a closed loop is an entry of 'constraints' whose medium is a body of the tree",
}


def _axle_in_body(index: int, R) -> tuple:
    """The wheel's axle (a unit vector) in the body's axes: e_index of the named frame (a URDF link's axes R)."""
    e = tuple(sp.Integer(1) if i == index else sp.Integer(0) for i in range(3))
    return e if R is None else tuple(sum((R[r][c] * e[c] for c in range(3)), sp.Integer(0)) for r in range(3))


MAX_FILE_BYTES = 16 * 2 ** 20  # a model file
MAX_EXPRESSION_TEXT = 1_000_000  # characters of all expression strings of a model together (parsing costs time)
MAX_BODIES = 10_000  # bodies (rotors included) of a model, as for a URDF's links
MAX_PARAMETERS = 10_000


class YamlReader:
    """A YAML file's values read into a model's parts, every mistake a ModelError with the file, the YAML path
    and the line (a model: :meth:`read`; the side files of :mod:`.side_files` read their parts with it)."""

    def __init__(self, file: Path, text: str):
        self.doc = _Doc(file, text)
        self.file = file
        self.symbols: dict[str, sp.Symbol] = {}
        self.defaults: dict[sp.Symbol, float] = {}
        self.text_budget = MAX_EXPRESSION_TEXT

    def fail(self, path, message):
        raise self.doc.error(path, message)

    # generic shapes ------------------------------------------------------------------------------
    def mapping(self, value, path, allowed, required=()):
        if not isinstance(value, dict):
            self.fail(path, f"expected a mapping, got {_kind(value)}")
        for key in value:
            if key not in allowed:
                self.fail(path + (key,), f"unknown key {key!r}{did_you_mean(key, allowed)} (allowed: "
                                         f"{', '.join(sorted(map(str, allowed)))})")
        for key in required:
            if key not in value:
                self.fail(path, f"missing field {key!r}")
        return value

    def sequence(self, value, path, length=None):
        if not isinstance(value, list):
            self.fail(path, f"expected a list, got {_kind(value)}")
        if length is not None and len(value) != length:
            self.fail(path, f"expected {length} entries, got {len(value)}")
        return value

    def expr(self, value, path, symbols=None, hint=""):
        if isinstance(value, str):
            self.text_budget -= len(value)
            if self.text_budget < 0:
                self.fail(path, f"the model's expressions are too long in all (at most {MAX_EXPRESSION_TEXT} "
                                f"characters)")
        try:
            expr = parse_value(value, self.symbols if symbols is None else symbols)
        except ExpressionError as exc:
            self.fail(path, f"{exc}{hint}")
        if not expr.is_Number and not expr.has(TIME):
            self.number(expr, path)  # every constant of the model is finite and real at the parameters' defaults
        return expr

    def number(self, expr, path) -> float:
        """The value of an expression with parameters at their defaults (for validation)."""
        try:
            return evaluate(expr, self.defaults)
        except ValueError as exc:
            self.fail(path, f"{exc}" + (" (with the parameters at their defaults)" if expr.free_symbols else ""))

    def vector(self, value, path, length=3):
        self.sequence(value, path, length)
        return tuple(self.expr(v, path + (i,)) for i, v in enumerate(value))

    def matrix(self, value, path, rows, cols):
        self.sequence(value, path, rows)
        return tuple(self.vector(r, path + (i,), cols) for i, r in enumerate(value))

    def name(self, value, path, what):
        problem = check_identifier(value)
        if problem:
            self.fail(path, f"{what}: {problem}")
        return value

    # the document ----------------------------------------------------------------------------------
    def read(self) -> Model:
        top = self.mapping(self.doc.root, (), TOP_KEYS, required=("bodies",))
        for key, why in LATER.items():
            if top.get(key):
                self.fail((key,), why)
        name = top.get("name", self.file.stem)
        if not isinstance(name, str) or check_identifier(name) is not None:
            self.fail(("name",), f"model name {name!r} must be a C identifier (letters, digits, _)")
        description = top.get("description", "")
        if not isinstance(description, str):
            self.fail(("description",), f"expected text, got {_kind(description)}")
        parameters = self.parameters(top.get("parameters", {}))
        gravity = self.vector(top["gravity"], ("gravity",)) if "gravity" in top else (sp.Integer(0),) * 3
        for i, g in enumerate(gravity):
            self.number(g, ("gravity", i))
        bodies = self.bodies(top["bodies"])
        tree = TreeBuilder()  # each body given whole, its own link at its origin in its axes
        for body in bodies:
            tree.body(body)
        links = tree.links(declared=self.frames(top.get("frames", []), bodies))
        frames = {f.name: (f.body, f.rotation, f.translation) for f in links.frames}
        time_dependent = any(b.pair.prescribed for b in bodies)
        constraints = self.constraints(top.get("constraints", []), frames, time_dependent)
        stabilization = self.stabilization(top.get("stabilization"), constraints)
        model = Model(name=name, bodies=bodies, gravity=gravity, parameters=parameters, source=str(self.file),
                      description=description.strip(), constraints=constraints, stabilization=stabilization,
                      regularization=self.regularization(top.get("regularization"), constraints),
                      proximal=self.proximal(top.get("proximal"), constraints), links=links)
        model = dataclasses.replace(model, frames=default_frames(model))
        if "support" in top:
            support = top["support"]
            if not isinstance(support, str):
                self.fail(("support",), f"expected a body name, got {_kind(support)}")
            problem = support_problem(model, support)
            if problem:
                self.fail(("support",), problem)
            model = dataclasses.replace(model, support=support)
        return model

    # frames (the frame routines) ----------------------------------------------------------------------
    def frames(self, value, bodies) -> tuple:
        """The ``frames:`` list: a name (an identifier, not a body's), the body, a point in its axes (default its
        origin) and constant axes as elementary rotations from the body's (default the body's)."""
        path = ("frames",)
        self.sequence(value, path)
        if len(value) > MAX_FRAMES:
            self.fail(path, f"{len(value)} frames, at most {MAX_FRAMES}")
        bodies_named = {b.name for b in bodies}
        out, names = [], {}
        for i, entry in enumerate(value):
            p = path + (i,)
            self.mapping(entry, p, FRAME_KEYS, required=("name", "body"))
            name = self.name(entry["name"], p + ("name",), "frame name")
            if name in names:
                self.fail(p + ("name",), f"duplicate frame name {name!r} (also frames[{names[name]}])")
            if name in bodies_named:
                self.fail(p + ("name",), f"frame name {name!r} is a body's name (a body is a frame already, at its "
                                         f"origin)")
            names[name] = i
            body, _, _ = self.frame(entry["body"], p + ("body",), {b: (b, None, None) for b in bodies_named}, "body")
            point = self.vector(entry["point"], p + ("point",)) if "point" in entry else (sp.Integer(0),) * 3
            rotation = self.rotation(entry.get("rotation", []), p + ("rotation",))
            out.append(Frame(name=name, body=body, point=point, rotation=rotation, source=str(self.file),
                             path=_path(p), line=self.doc.line(p)))
        return tuple(out)

    # constraints (chapter 4) --------------------------------------------------------------------------
    def constraints(self, value, frames: dict, time_dependent: bool = False) -> tuple:
        """The ``constraints:`` list.  ``frames`` maps the names a constraint may use for its body and medium to
        (body name, R, t): the frame's axes in the body's axes and its origin there (None, None: the body's own
        frame; a URDF link merged into a body has its placement)."""
        path = ("constraints",)
        self.sequence(value, path)
        if value and time_dependent:
            self.fail(path, "constraints on a model with prescribed motions (rotors with a prescribed spin) are not "
                            "supported yet")
        out, names = [], {}
        for i, entry in enumerate(value):
            p = path + (i,)
            self.mapping(entry, p, CONSTRAINT_KEYS, required=("name", "body", "block"))
            name = self.name(entry["name"], p + ("name",), "constraint name")
            if name in names:
                self.fail(p + ("name",), f"duplicate constraint name {name!r} (also constraints[{names[name]}])")
            names[name] = i
            body, R, t = self.frame(entry["body"], p + ("body",), frames, "body")
            if body == WORLD:
                self.fail(p + ("body",), "the constrained body cannot be the world")
            medium_name = entry.get("medium", WORLD)
            medium, Rm, tm = (WORLD, None, None) if medium_name == WORLD else \
                self.frame(medium_name, p + ("medium",), frames, "medium")
            if medium == body:
                self.fail(p + ("medium",), f"the medium {medium_name!r} is the constrained body itself (a loop joins "
                                           f"two different bodies)")
            point = self.vector(entry["point"], p + ("point",)) if "point" in entry else (sp.Integer(0),) * 3
            at = self.vector(entry["at"], p + ("at",)) if "at" in entry else None
            rows = self.block(entry["block"], p + ("block",))
            friction = self.friction(entry["friction"], p + ("friction",), rows) if "friction" in entry else None
            wheel = self.wheel(entry, p, medium, friction)
            motion = self.motion(entry["motion"], p + ("motion",), medium) if "motion" in entry else ()
            out.append(Constraint(
                name=name, body=body, point=_placed(point, R, t), rows=rows, friction=friction,
                wheel=None if wheel is None else (wheel[0], _axle_in_body(wheel[1], R)), motion=motion,
                medium=medium, at=None if at is None else _placed(at, Rm, tm),
                rotation=self.rotation(entry.get("rotation", []), p + ("rotation",)),
                kind=entry["block"] if isinstance(entry["block"], str) else "", source=str(self.file),
                path=_path(p), line=self.doc.line(p),
                link=entry["body"] if R is not None or t is not None else "",
                medium_axes=None if Rm is None else tuple(tuple(r) for r in Rm)))
        return tuple(out)

    def frame(self, value, path, frames, what):
        if not isinstance(value, str):
            self.fail(path, f"expected a {what} name, got {_kind(value)}")
        if value == WORLD and what == "medium":
            return WORLD, None, None
        if value not in frames:
            close = sorted(frames)[:8]
            self.fail(path, f"unknown {what} {value!r}{did_you_mean(value, frames)} (the names are {', '.join(close)}"
                            f"{', ...' if len(frames) > 8 else ''})")
        return frames[value]

    def block(self, value, path) -> tuple:
        if isinstance(value, str):
            if value not in CONSTRAINT_KINDS:
                self.fail(path, f"unknown constraint kind {value!r} (the kinds are {', '.join(CONSTRAINT_KINDS)}, or "
                                f"a list of o1 o2 o3 theta4 theta5 theta6)")
            return CONSTRAINT_KINDS[value]
        self.sequence(value, path)
        codes = set()
        for i, code in enumerate(value):
            code = CODE_ALIASES.get(code, code) if isinstance(code, str) else code
            if code not in COORDINATE_CODES:
                self.fail(path + (i,), f"expected one of {', '.join(COORDINATE_CODES)}, got {_kind(code)}")
            if code in codes:
                self.fail(path + (i,), f"{code} is listed twice")
            codes.add(code)
        if not codes:
            self.fail(path, "a constraint must block at least one relative motion")
        return tuple(c for c in COORDINATE_CODES if c in codes)

    def motion(self, value, path, medium) -> tuple:
        """``motion: {o1: f(t), ..., theta6: f(t)}``: the prescribed functional motion of the world-side frame
        (Prop. 4.5-4.8), ((code, expression), ...) in code order."""
        self.mapping(value, path, set(COORDINATE_CODES) | set(CODE_ALIASES))
        if medium != WORLD:
            self.fail(path, "a prescribed motion of a medium that is a body of the tree is not supported yet "
                            "(medium: world)")
        if not value:
            self.fail(path, "an empty motion: give at least one of o1 o2 o3 theta4 theta5 theta6")
        items = {}
        for key, expr in value.items():
            code = CODE_ALIASES.get(key, key)
            if code in items:
                self.fail(path + (key,), f"{code} is given twice")
            items[code] = self.time_function(expr, path + (key,), "the prescribed motion")
        return tuple((code, items[code]) for code in COORDINATE_CODES if code in items)

    def wheel(self, entry, path, medium, friction):
        """``block: rolling`` with ``wheel: {radius: r, axle: 1|2|3|x|y|z}``: (radius, axle index 0..2), or None."""
        rolling = entry["block"] == "rolling"
        if "wheel" in entry and not rolling:
            self.fail(path + ("wheel",), "a wheel is given but the constraint is not 'block: rolling'")
        if not rolling:
            return None
        if "wheel" not in entry:
            self.fail(path, "a rolling constraint needs 'wheel: {radius: r, axle: 1|2|3}' (the disc about its body "
                            "axis e_axle)")
        value = self.mapping(entry["wheel"], path + ("wheel",), {"radius", "axle"}, required=("radius", "axle"))
        radius = self.expr(value["radius"], path + ("wheel", "radius"))
        if self.number(radius, path + ("wheel", "radius")) <= 0:
            self.fail(path + ("wheel", "radius"), "the wheel's radius must be positive")
        axle = AXES.get(value["axle"]) if not isinstance(value["axle"], bool) else None
        if axle is None:
            self.fail(path + ("wheel", "axle"), f"expected 1, 2, 3 (or x, y, z), got {_kind(value['axle'])}")
        if medium != WORLD:
            self.fail(path + ("medium",), "a wheel rolling on a body of the tree is not supported yet (medium: world)")
        if friction is not None:
            self.fail(path + ("friction",), "a rolling contact does not slide: no friction")
        return radius, axle - 1

    def friction(self, value, path, rows) -> tuple:
        """``{viscous: c}`` (W = -c w) or ``{coulomb: mu}`` (W = -mu |lambda_n| w/|w|) on the free translations."""
        self.mapping(value, path, set(FRICTION_LAWS))
        if len(value) != 1:
            self.fail(path, "give one friction law: {viscous: c} or {coulomb: mu}")
        (law, coefficient), = value.items()
        free = [code for code in COORDINATE_CODES[:3] if code not in rows]
        blocked = [code for code in COORDINATE_CODES[:3] if code in rows]
        if not free:
            self.fail(path, "friction acts on the free translations of a sliding contact, and this constraint "
                            "blocks all three (o1 o2 o3)")
        if law == "coulomb" and len(blocked) != 1:
            self.fail(path + (law,), f"Coulomb friction needs exactly one blocked translation (the normal, e.g. "
                                     f"block: normal), this constraint blocks {', '.join(blocked) or 'none'}")
        expr = self.expr(coefficient, path + (law,))
        if self.number(expr, path + (law,)) < 0:
            self.fail(path + (law,), "a friction coefficient must not be negative")
        return (law, expr)

    def regularization(self, value, constraints):
        """``regularization: epsilon``: G + epsilon E in the constrained forward dynamics (redundant rows allowed)."""
        if value is None:
            return sp.Integer(0)
        if not constraints:
            self.fail(("regularization",), "regularization is given but the model has no constraints")
        eps = self.expr(value, ("regularization",))
        if self.number(eps, ("regularization",)) < 0:
            self.fail(("regularization",), "the regularization must not be negative")
        return eps

    def proximal(self, value, constraints) -> tuple:
        """``proximal: {mu: MU, iterations: N}``: the damped solve of the Delassus system (aggsym.mechanics.damped),
        N fixed proximal iterations on G + mu E (redundant rows allowed); absent: the exact solve."""
        if value is None:
            return ()
        path = ("proximal",)
        self.mapping(value, path, PROXIMAL_KEYS, required=("mu", "iterations"))
        if not constraints:
            self.fail(path, "proximal is given but the model has no constraints")
        mu = self.expr(value["mu"], path + ("mu",))
        if not self.number(mu, path + ("mu",)) > 0:
            self.fail(path + ("mu",), "the proximal mu must be positive")
        n = value["iterations"]
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_PROXIMAL_ITERATIONS:
            self.fail(path + ("iterations",), f"iterations must be a whole number from 1 to {MAX_PROXIMAL_ITERATIONS}")
        return (mu, n)

    def stabilization(self, value, constraints) -> tuple:
        if value is None:
            return (sp.Integer(0), sp.Integer(0))
        path = ("stabilization",)
        self.mapping(value, path, STABILIZATION_KEYS)
        if not constraints:
            self.fail(path, "stabilization is given but the model has no constraints")
        gains = []
        for key in ("kp", "kd"):
            gain = self.expr(value.get(key, 0), path + (key,))
            if self.number(gain, path + (key,)) < 0:
                self.fail(path + (key,), f"the Baumgarte gain {key} must not be negative")
            gains.append(gain)
        return tuple(gains)


    def parameters(self, value):
        path = ("parameters",)
        if not isinstance(value, dict):
            self.fail(path, f"expected a mapping of names to default values, got {_kind(value)}")
        if len(value) > MAX_PARAMETERS:
            self.fail(path, f"{len(value):,} parameters; at most {MAX_PARAMETERS:,} are read")
        out = []
        for key, default in value.items():
            self.name(key, path + (key,), "parameter name")
            if isinstance(default, dict):
                self.mapping(default, path + (key,), {"value", "description", "unit"}, required=("value",))
                default = default["value"]
            if isinstance(default, bool) or not isinstance(default, (int, float)):
                self.fail(path + (key,), f"the default of parameter {key!r} must be a number, got {_kind(default)}")
            try:
                default = float(default)
            except OverflowError:
                default = float("inf")
            if not np.isfinite(default):
                self.fail(path + (key,), f"the default of parameter {key!r} is not finite")
            param = Parameter(key, default)
            self.symbols[key] = param.symbol
            self.defaults[param.symbol] = float(default)
            out.append(param)
        return tuple(out)

    def bodies(self, value):
        path = ("bodies",)
        self.sequence(value, path)
        if not value:
            self.fail(path, "the model has no bodies")
        rotors = sum(len(b["rotors"]) for b in value if isinstance(b, dict) and isinstance(b.get("rotors"), list))
        if len(value) + rotors > MAX_BODIES:
            self.fail(path, f"{len(value) + rotors:,} bodies with the rotors; at most {MAX_BODIES:,} are read")
        raw = []
        names: dict[str, int] = {}
        for i, entry in enumerate(value):
            p = path + (i,)
            self.mapping(entry, p, BODY_KEYS, required=("name",))
            name = self.name(entry["name"], p + ("name",), "body name")
            if name == WORLD:
                self.fail(p + ("name",), f"{WORLD!r} names the inertial frame; choose another body name")
            if name in names:
                self.fail(p + ("name",), f"duplicate body name {name!r} (also bodies[{names[name]}])")
            names[name] = i
            parent = entry.get("parent", WORLD)
            if not isinstance(parent, str):
                self.fail(p + ("parent",), f"expected a body name, got {_kind(parent)}")
            raw.append((name, parent))
        order, problem, where = order_tree([n for n, _ in raw], [q for _, q in raw], WORLD)
        if problem:
            self.fail(path + (where, "parent"), problem)
        joints: dict[str, tuple] = {}
        coordinates: dict[str, tuple] = {}
        self.body_names = {name: path + (i, "name") for name, i in names.items()}
        bodies = []
        for i in order:
            body = self.body(value[i], path + (i,), joints, coordinates)
            bodies.append(body)
            bodies.extend(self.rotors(value[i], path + (i,), joints, coordinates))
        return tuple(bodies)

    def body(self, entry, path, joints, coordinates) -> Body:
        name = entry["name"]
        pair = self.pair(entry.get("pair", {}), path + ("pair",), name, joints, coordinates)
        inertial = self.inertial(entry, path)
        added = self.added_mass(entry["added_mass"], path + ("added_mass",)) if "added_mass" in entry else None
        return Body(name=name, parent=entry.get("parent", WORLD), pair=pair, inertial=inertial, where=_path(path),
                    added_mass=added)

    def added_mass(self, value, path):
        """Lambda of Prop. 2.8: a 6x6 matrix or its diagonal, symmetric and positive semi-definite."""
        if isinstance(value, list) and value and not isinstance(value[0], list):
            diag = self.vector(value, path, 6)
            X = tuple(tuple(diag[i] if i == j else sp.Integer(0) for j in range(6)) for i in range(6))
        else:
            X = self.matrix(value, path, 6, 6)
        num = np.array([[self.number(X[i][j], path + (i, j)) for j in range(6)] for i in range(6)])
        scale = max(1.0, float(np.max(np.abs(num))))
        bad = np.argwhere(np.abs(num - num.T) > 1e-9 * scale)
        if len(bad):
            i, j = bad[0]
            self.fail(path, f"the added mass matrix is not symmetric: [{i}][{j}] = {num[i, j]:g} but "
                            f"[{j}][{i}] = {num[j, i]:g}")
        low = float(np.linalg.eigvalsh(num)[0])
        if low < -1e-9 * scale:
            self.fail(path, f"the added mass matrix is not positive semi-definite (smallest eigenvalue {low:g}): "
                            f"the medium's kinetic energy 1/2 V^T Lambda V must not be negative")
        return X

    def rotors(self, entry, path, joints, coordinates):
        """The rotors of a body (2.13) as bodies of the tree, each right after its carrier."""
        if "rotors" not in entry:
            return []
        carrier = entry["name"]
        out = []
        for j, rotor in enumerate(self.sequence(entry["rotors"], path + ("rotors",))):
            p = path + ("rotors", j)
            self.mapping(rotor, p, ROTOR_KEYS, required=("name", "spin"))
            name = self.name(rotor["name"], p + ("name",), "rotor name")
            if name == WORLD:
                self.fail(p + ("name",), f"{WORLD!r} names the inertial frame; choose another rotor name")
            if name in self.body_names:
                self.fail(p + ("name",), f"duplicate body name {name!r} (also {_path(self.body_names[name])})")
            self.body_names[name] = p + ("name",)
            jname = self.name(rotor.get("joint", name), p + ("joint",), "joint name")
            if jname in joints:
                self.fail(p + ("joint",), f"duplicate joint name {jname!r} (also {_path(joints[jname])})")
            joints[jname] = p
            translation = self.vector(rotor["translation"], p + ("translation",)) if "translation" in rotor \
                else (sp.Integer(0),) * 3
            rotation = self.rotation(rotor.get("rotation", []), p + ("rotation",))
            coords, prescribed = self.spin(rotor["spin"], p + ("spin",), jname, coordinates)
            inertial = self.inertial(rotor, p)
            if inertial is None:
                self.fail(p, "a rotor needs mass properties (mass, com, inertia or mises)")
            pair = Pair(jname, translation, rotation, coords, prescribed=prescribed)
            out.append(Body(name=name, parent=carrier, pair=pair, inertial=inertial, where=_path(p),
                            carrier=carrier))
        return out

    def spin(self, value, path, joint, coordinates):
        """``{coordinate: NAME}`` (the spin is a generalized coordinate) or ``{prescribed: expr in t}``."""
        self.mapping(value, path, SPIN_KEYS)
        if len(value) != 1:
            self.fail(path, "give exactly one of 'coordinate' (the spin is a generalized coordinate) or "
                            "'prescribed' (the spin angle as a function of the time t)")
        if "coordinate" in value:
            where = path + ("coordinate",)
            cname = self.name(value["coordinate"], where, "coordinate name")
            if cname in coordinates:
                self.fail(where, f"duplicate coordinate name {cname!r} (also {_path(coordinates[cname])})")
            if cname in self.symbols:
                self.fail(where, f"coordinate name {cname!r} is also a parameter")
            coordinates[cname] = where
            return (Coordinate(cname, "theta6", joint),), ()
        where = path + ("prescribed",)
        angle = self.time_function(value["prescribed"], where, "the prescribed spin")
        if not angle.has(TIME):
            self.fail(where, f"the prescribed spin {angle} does not depend on the time t (a rotor at a fixed angle "
                             f"is a welded body: give it as a body without pair coordinates)")
        return (), (("theta6", angle),)

    def time_function(self, value, where, what):
        """An expression that may use the time t, whose first two derivatives (derived symbolically) can be
        emitted and are finite at t = 0.37 with the parameters at their defaults."""
        expr = self.expr(value, where, {**self.symbols, "t": TIME}, hint=f" ({what} may use the time t)")
        values = {**self.defaults, TIME: 0.37}
        for k, name in enumerate(("value", "rate", "acceleration")):
            derivative = sp.diff(expr, TIME, k)
            problem = check_supported(derivative)
            if problem:
                self.fail(where, f"{what}'s {name} {derivative} cannot be emitted ({problem})")
            try:
                evaluate(derivative, values)
            except ValueError as exc:
                self.fail(where, f"{what}'s {name} has no finite value at t = 0.37: {exc}")
        return expr

    def rotation(self, value, path):
        rotation = []
        for i, step in enumerate(self.sequence(value, path)):
            p = path + (i,)
            self.sequence(step, p, 2)
            axis = AXES.get(step[0]) if not isinstance(step[0], bool) else None
            if axis is None:
                self.fail(p + (0,), f"rotation axis must be 1, 2, 3 (or x, y, z), got {step[0]!r}")
            rotation.append((axis, self.expr(step[1], p + (1,))))
        return tuple(rotation)

    def pair(self, value, path, body, joints, coordinates) -> Pair:
        self.mapping(value, path, PAIR_KEYS)
        jname = self.name(value.get("name", body), path + ("name",), "joint name")
        if jname in joints:
            self.fail(path + ("name",), f"duplicate joint name {jname!r} (also {_path(joints[jname])})")
        joints[jname] = path
        translation = self.vector(value["translation"], path + ("translation",)) if "translation" in value \
            else (sp.Integer(0),) * 3
        rotation = self.rotation(value.get("rotation", []), path + ("rotation",))
        if "type" in value:
            return self.typed_pair(value, path, jname, translation, rotation, coordinates)
        functional = value.get("functional", {})
        fpath = path + ("functional",)
        if not isinstance(functional, dict):
            self.fail(fpath, f"expected a mapping from o1..o3/theta4..theta6 to coordinate names, got "
                             f"{_kind(functional)}")
        coords = []
        for code, cname in functional.items():
            code = CODE_ALIASES.get(code, code)
            if code not in COORDINATE_CODES:
                self.fail(fpath + (code,), f"{code!r} is not a coordinate of a pair; use one of "
                                           f"{', '.join(COORDINATE_CODES)}")
            self.name(cname, fpath + (code,), "coordinate name")
            if cname in coordinates:
                self.fail(fpath + (code,), f"duplicate coordinate name {cname!r} (also {_path(coordinates[cname])})")
            if cname in self.symbols:
                self.fail(fpath + (code,), f"coordinate name {cname!r} is also a parameter")
            coordinates[cname] = fpath + (code,)
            coords.append(Coordinate(cname, code, jname))
        coords.sort(key=lambda c: COORDINATE_CODES.index(c.code))
        stiffness = rest = None
        if "stiffness" in value:
            stiffness = self.stiffness(value["stiffness"], path + ("stiffness",), len(coords))
        if "rest" in value:
            if stiffness is None:
                self.fail(path + ("rest",), "a rest position needs a stiffness (the pair is not elastic)")
            rest = self.vector(value["rest"], path + ("rest",), len(coords))
        return Pair(jname, translation, rotation, tuple(coords), stiffness, rest)

    def typed_pair(self, value, path, jname, translation, rotation, coordinates) -> Pair:
        """A pair given by ``type``: ``ball``, the ball pair of :attr:`~.types.Pair.positions` (coordinates
        theta4 theta5 theta6, the angular velocity in the body's axes, named ``<name>_wx ..``; positions the unit
        quaternion ``<name>_qx .. <name>_qw``)."""
        tpath = path + ("type",)
        if value["type"] not in PAIR_TYPES:
            self.fail(tpath, f"unknown pair type {value['type']!r} (known: {', '.join(PAIR_TYPES)}; without 'type' "
                             f"the pair is its 'functional' coordinates)")
        for key in ("functional", "stiffness", "rest"):
            if key in value:
                self.fail(path + (key,), f"a ball pair takes no {key!r}: its coordinates are its angular velocity "
                                         f"and its position a unit quaternion, both named after the pair")
        velocities, positions = ball_names(jname)
        for cname in velocities + positions:
            if cname in coordinates:
                self.fail(tpath, f"the ball pair's coordinate {cname!r} is already a coordinate (also "
                                 f"{_path(coordinates[cname])})")
            if cname in self.symbols:
                self.fail(tpath, f"the ball pair's coordinate {cname!r} is also a parameter")
            problem = check_identifier(cname)
            if problem:
                self.fail(path + ("name",), f"the ball pair's coordinate {cname!r}: {problem}")
            coordinates[cname] = tpath
        coords = tuple(Coordinate(n, code, jname) for n, code in zip(velocities, ("theta4", "theta5", "theta6")))
        return Pair(jname, translation, rotation, coords, positions=positions)

    def stiffness(self, value, path, n):
        if n == 0:
            self.fail(path, "a pair without coordinates has no stiffness")
        if isinstance(value, list) and value and not isinstance(value[0], list):
            diag = self.vector(value, path, n)
            K = tuple(tuple(diag[i] if i == j else sp.Integer(0) for j in range(n)) for i in range(n))
        else:
            K = self.matrix(value, path, n, n)
        num = np.array([[self.number(K[i][j], path + (i, j)) for j in range(n)] for i in range(n)])
        if np.max(np.abs(num - num.T)) > 1e-9 * max(1.0, np.max(np.abs(num))):
            self.fail(path, "stiffness matrix is not symmetric")
        if np.linalg.eigvalsh(num)[0] < -1e-9 * max(1.0, np.max(np.abs(num))):
            self.fail(path, "stiffness matrix is not positive semi-definite")
        return K

    def inertial(self, entry, path):
        has = [k for k in ("mass", "com", "inertia", "mises") if k in entry]
        if not has:
            return None
        if "mises" in entry:
            others = [k for k in ("mass", "com", "inertia") if k in entry]
            if others:
                self.fail(path + (others[0],), "give either mises or mass/com/inertia, not both")
            return self.from_mises(entry["mises"], path + ("mises",))
        if "mass" not in entry:
            self.fail(path, f"{has[0]} given without mass (a massless frame has neither)")
        mass = self.expr(entry["mass"], path + ("mass",))
        problem = mass_problem(self.number(mass, path + ("mass",)))
        if problem:
            self.fail(path + ("mass",), problem)
        com = self.vector(entry["com"], path + ("com",)) if "com" in entry else (sp.Integer(0),) * 3
        inertia = self.inertia(entry.get("inertia", {}), path + ("inertia",))
        return Inertial(mass, com, inertia)

    def inertia(self, value, path):
        if isinstance(value, dict):
            self.mapping(value, path, set(INERTIA_KEYS))
            e = {k: self.expr(value[k], path + (k,)) if k in value else sp.Integer(0) for k in INERTIA_KEYS}
            J = ((e["xx"], e["xy"], e["xz"]), (e["xy"], e["yy"], e["yz"]), (e["xz"], e["yz"], e["zz"]))
        else:
            J = self.matrix(value, path, 3, 3)
        self.check_inertia(J, path)
        return J

    def check_inertia(self, J, path):
        num = [[self.number(J[i][j], path) for j in range(3)] for i in range(3)]
        problem = inertia_problem(num)
        if problem:
            self.fail(path, problem)

    def from_mises(self, value, path):
        """Read a Mises matrix (2.3) and check its form [[m E, -hat(h)], [hat(h), theta_O]]."""
        X = self.matrix(value, path, 6, 6)
        num = np.array([[self.number(X[i][j], path + (i, j)) for j in range(6)] for i in range(6)])
        scale = max(1.0, float(np.max(np.abs(num))))
        if np.max(np.abs(num - num.T)) > 1e-9 * scale:
            self.fail(path, "Mises matrix is not symmetric")
        m = X[0][0]
        top = num[:3, :3]
        if np.max(np.abs(top - top[0, 0] * np.eye(3))) > 1e-9 * scale:
            self.fail(path, "the upper-left 3x3 block of a Mises matrix must be m E (2.3)")
        problem = mass_problem(num[0, 0])
        if problem:
            self.fail(path + (0, 0), problem)
        lower = num[3:, :3]
        if np.max(np.abs(lower + lower.T)) > 1e-9 * scale:
            self.fail(path, "the lower-left 3x3 block of a Mises matrix must be skew-symmetric, hat(m r_c) (2.3)")
        h = (X[5][1], X[3][2], X[4][0])  # hat(h) = [[0,-h3,h2],[h3,0,-h1],[-h2,h1,0]]
        com = tuple(sp.simplify(x / m) for x in h)
        r = sp.Matrix(com)
        theta_o = sp.Matrix(3, 3, lambda i, j: X[3 + i][3 + j])
        theta_c = theta_o - m * (r.dot(r) * sp.eye(3) - r * r.T)
        J = tuple(tuple(sp.simplify(theta_c[i, j]) for j in range(3)) for i in range(3))
        self.check_inertia(J, path)
        return Inertial(m, com, J)


def _placed(x, R, t) -> tuple:
    """R x + t: a point given in a URDF link's frame, in its body's axes (R, t None: the body's own frame)."""
    if R is not None:
        x = tuple(sum((R[i][j] * x[j] for j in range(3)), sp.Integer(0)) for i in range(3))
    if t is not None:
        x = tuple(a + b for a, b in zip(x, t))
    return x


def _kind(value) -> str:
    if value is None:
        return "nothing"
    if isinstance(value, bool):
        return f"the boolean {value}"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    text = repr(value)
    text = text if len(text) <= 80 else text[:80] + "..."
    if isinstance(value, str):
        return f"the text {text}"
    return f"{type(value).__name__} {text}"


def read_text(path: Path) -> str:
    """The text of a YAML file (a model or a side file), at most :data:`MAX_FILE_BYTES`; a :class:`ModelError`
    naming the file otherwise."""
    try:
        if path.stat().st_size > MAX_FILE_BYTES:
            raise ModelError(path, "", f"the file is larger than {MAX_FILE_BYTES // 2 ** 20} MiB")
        return path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ModelError(path, "", f"cannot read the file: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise ModelError(path, "", "not a text file (UTF-8)") from None


def load_yaml(path) -> Model:
    """Read and validate a YAML model; raises :class:`ModelError` naming the place of the first problem."""
    path = Path(path)
    return YamlReader(path, read_text(path)).read()
