"""The URDF reader: links and joints onto the book's bodies and pairs (1.24)-(1.27), with precise errors.

Every mistake is reported as :class:`ModelError` with the file, the element (``<joint name="elbow">``, or
``<joint name="elbow"> <axis>`` for a part of it), the line, and what is wrong.  The file is parsed with the
standard library's expat, which gives the line of every element.

The mapping
-----------
* One movable joint (``revolute``, ``continuous``, ``prismatic``) is one pair (1.24)-(1.27).  Its constructive
  configuration is the joint's ``<origin>`` (translation ``xyz``, then the rotation ``rpy``, URDF's
  R = Rz(yaw) Ry(pitch) Rx(roll), i.e. the elementary rotations ``[(3, yaw), (2, pitch), (1, roll)]``), followed
  by a constant rotation R_a that brings e1, e2 or e3 onto the joint's ``<axis>`` (normalized, as Pinocchio
  does; default (1, 0, 0)).  For axes along +-x, +-y, +-z R_a is exact (identity, or a rotation by ``pi``);
  a general axis a gets R_a = c3(phi) c2(theta) with R_a e3 = a.  The functional configuration is the one
  coordinate: theta4/theta5/theta6 (rotation about e1/e2/e3) for revolute and continuous joints, o1/o2/o3
  for prismatic ones, so q is the joint's angle or displacement about or along its URDF axis.
* The body frame F of a movable joint's child link is the link frame turned by R_a (same origin):
  ``Body.link_rotation = R_a^T`` (x_F = R_a^T x_link).  The link's inertial data are expressed in F, and R_a^T
  is folded into the constructive configuration of every joint leaving the link (its origin is given in the
  link frame).
* A ``fixed`` joint merges its child link into the parent's body: masses add, the centre of mass is the
  mass-weighted mean, and the inertia tensors (rotated into the body axes) are moved to the common centre of
  mass by the parallel-axis theorem; the fixed transform is composed into the origins of the child's joints.
* ``<inertial>``: mass, ``<origin>`` (the centre of mass and the axes of the inertia tensor, in the link frame)
  and the full tensor ixx..izz about the centre of mass, rotated into the body axes.  A link without
  ``<inertial>`` is massless.  A mass of 0 keeps its rotational inertia (Pinocchio does the same); a link with
  mass 0 and zero inertia is massless.
* The root link (the one link that is no joint's child) is attached to the world by a pair without
  coordinates (fixed base), or with ``floating_base=True`` by the free pair o1, o2, o3, theta4, theta5, theta6
  (coordinates ``base_x, base_y, base_z, base_rx, base_ry, base_rz``; Pinocchio's composite
  PX, PY, PZ, RX, RY, RZ).
* Bodies and coordinates are ordered as Pinocchio orders its joints for the same file: depth first from the
  root, the joints leaving a link in the byte order of their names (urdfdom keeps them in a ``std::map``),
  fixed joints walked through in place.  So q maps one-to-one onto Pinocchio's fixed-base model.
* ``<mimic>``: by default the joint keeps an independent coordinate and the relation is only recorded in
  ``model.meta["mimic"]``; with ``mimic="couple"`` the joint's coordinate becomes
  ``multiplier * master + offset`` (``Model.couplings``): it leaves q, and the generated routines take and
  return the remaining coordinates (:mod:`aggsym.coupling`), as Pinocchio's ``mimic=True`` models do.
* Coordinate names are the joint names made identifiers (``Coordinate.joint`` keeps the URDF name); body names
  are the link names made identifiers; the model name is the robot's.  Gravity is (0, 0, -9.81) in the root
  frame.  No parameters: every number is folded.  Visuals, collisions, meshes, transmissions, gazebo tags and
  joint limits are ignored.
* ``model.meta``: ``mimic`` (above), ``links`` (each URDF link's body, merged links included),
  ``floating_base``, and ``warnings``: what was accepted but looks wrong, also issued as :class:`ModelWarning`
  (an inertia tensor that is positive semi-definite but violates the triangle inequality, as dummy links in
  real files do; a ``<mimic>`` on a fixed joint).
"""
from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

import numpy as np
import sympy as sp

from ..errors import ModelError, ModelWarning
from .expressions import check_identifier
from .types import _snap as snap
from .types import WORLD, Body, Coordinate, Coupling, Inertial, Model, Pair, elementary_rotation
from .validate import inertia_problem

GRAVITY = (sp.Integer(0), sp.Integer(0), sp.Float(-9.81))
MOVABLE = {"revolute": "theta", "continuous": "theta", "prismatic": "o"}
CODES = {"theta": ("theta4", "theta5", "theta6"), "o": ("o1", "o2", "o3")}
UNSUPPORTED = {
    "planar": "planar joints are not supported (revolute, continuous, prismatic and fixed are)",
    "floating": ("floating joints inside the tree are not supported (revolute, continuous, prismatic and fixed "
                 "are); for a free root use floating_base=True"),
}
FLOATING = (("base_x", "o1"), ("base_y", "o2"), ("base_z", "o3"), ("base_rx", "theta4"), ("base_ry", "theta5"),
            ("base_rz", "theta6"))
MIMIC_OPTIONS = ("independent", "couple")
ROOT_PAIR = "root_joint"
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
_AXIS_TOL = 1e-12


@dataclass
class _Element:
    """An XML element with the line it starts on."""

    tag: str
    attrib: dict
    line: int
    parent: "_Element | None" = None
    children: list = field(default_factory=list)

    def all(self, tag: str) -> list:
        return [c for c in self.children if c.tag == tag]


def _parse(file: Path, data: bytes) -> _Element:
    """Parse XML with expat, recording each element's line; raises ModelError for malformed XML."""
    parser = expat.ParserCreate()
    stack: list[_Element] = []
    top: list[_Element] = []

    def start(tag, attrib):
        el = _Element(tag, attrib, parser.CurrentLineNumber, stack[-1] if stack else None)
        (stack[-1].children if stack else top).append(el)
        stack.append(el)

    def end(tag):
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise ModelError(file, "", f"not XML: {expat.errors.messages[exc.code]}", exc.lineno) from None
    return top[0]


def _where(el: _Element) -> str:
    """The element as a reader finds it: ``<joint name="elbow">``, or ``<joint name="elbow"> <axis>``."""
    parts = []
    while el is not None:
        name = el.attrib.get("name")
        top_level = el.parent is None or el.parent.tag == "robot"
        if el.tag in ("robot", "link", "joint") and (name is not None or top_level):
            parts.append(f'<{el.tag} name="{name}">' if name is not None else f"<{el.tag}>")
            break
        parts.append(f"<{el.tag}>")
        el = el.parent
    return " ".join(reversed(parts))


def _exact(value: float) -> sp.Expr:
    """A float from the file as a SymPy number, integers exact (so structural zeros fold)."""
    return sp.Integer(int(value)) if float(value).is_integer() else sp.Float(value)


def _matrix(rotation) -> sp.Matrix:
    """The product of elementary rotations [(axis, angle), ...] (Prop. 1.17)."""
    c = sp.eye(3)
    for axis, angle in rotation:
        c = c * elementary_rotation(axis, angle)
    return c.applyfunc(snap)


def _inverse(rotation) -> list:
    return [(axis, -angle) for axis, angle in reversed(rotation)]


def _tidy(rotation) -> list:
    """Merge neighbouring rotations about one axis and drop rotations by multiples of 2 pi."""
    out: list = []
    for axis, angle in rotation:
        if out and out[-1][0] == axis:
            angle = out.pop()[1] + angle
        if not (angle.is_zero or (angle / (2 * sp.pi)).is_integer):
            out.append((axis, angle))
    return out


ANGLE_SNAP = 1e-9  # rad


def _angle(value: float) -> sp.Expr:
    """An angle from the file; within 1e-9 rad of a multiple of pi/2 (``1.57079632679`` and the like) it is taken
    as that exact multiple, so the zeros and ones of the right-angle rotation fold in the generated code.  The
    change is below 1e-9 rad (results move by about that much relative, far inside the tests' 1e-9 tolerance
    against Pinocchio, which uses the file's float)."""
    k = round(float(value) / (math.pi / 2))
    if abs(float(value) - k * math.pi / 2) < ANGLE_SNAP:
        return sp.Integer(k) * sp.pi / 2
    return _exact(value)


def _rpy(rpy) -> list:
    """URDF roll-pitch-yaw as elementary rotations: R = Rz(y) Ry(p) Rx(r)."""
    r, p, y = rpy
    return _tidy([(3, _angle(y)), (2, _angle(p)), (1, _angle(r))])


def _quaternion_rpy(x, y, z, w) -> tuple:
    """roll, pitch, yaw of a unit quaternion (x, y, z, w), R = Rz(yaw) Ry(pitch) Rx(roll)."""
    R = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if math.hypot(R[0, 0], R[1, 0]) < 1e-12:  # gimbal lock: put everything into roll
        return math.atan2(-R[1, 2], R[1, 1]), pitch, 0.0
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])


def _align(axis) -> tuple:
    """(R_a as elementary rotations, 0-based index i) with R_a e_i = axis, exact for +-x, +-y, +-z."""
    nonzero = [i for i in range(3) if axis[i] != 0.0]
    if len(nonzero) == 1:
        i = nonzero[0]
        if axis[i] > 0:
            return [], i
        return [(3 if i == 0 else 1, sp.pi)], i  # a half turn about an axis orthogonal to e_i
    theta = math.atan2(math.hypot(axis[0], axis[1]), axis[2])
    phi = math.atan2(axis[1], axis[0])
    return _tidy([(3, _exact(phi)), (2, _exact(theta))]), 2


def _identifier(name: str, used: set, prefix: str) -> str:
    """``name`` made a unique identifier (letters, digits, _, not reserved)."""
    s = re.sub(r"[^A-Za-z0-9_]", "_", name)
    if not s or not s[0].isalpha():
        s = f"{prefix}_{s}" if s else prefix
    if check_identifier(s) is not None:
        s += "_"
    base, k = s, 2
    while s in used:
        s, k = f"{base}_{k}", k + 1
    used.add(s)
    return s


@dataclass
class _Inertial:
    """One link's inertial data as floats in its link frame."""

    mass: float
    com: tuple
    rotation: list  # the inertial frame's axes, elementary rotations
    inertia: tuple  # 3x3 about the centre of mass, inertial-frame axes


@dataclass
class _Joint:
    el: _Element
    name: str
    type: str
    parent: str
    child: str
    xyz: tuple
    rotation: list
    axis: tuple | None
    mimic: dict | None


@dataclass
class _Place:
    """Where a link sits in its body: x_body = R x_link + t, R given as elementary rotations."""

    body: int
    rotation: list
    R: sp.Matrix
    t: sp.Matrix


class _Reader:
    def __init__(self, file: Path, root: _Element, floating_base: bool, mimic: str):
        self.file = file
        self.root = root
        self.floating_base = floating_base
        self.mimic = mimic
        self.version = (1, 0)
        self.warnings: list[str] = []

    def fail(self, el: _Element, message: str):
        raise ModelError(self.file, _where(el), message, el.line)

    def warn(self, el: _Element, message: str):
        text = str(ModelError(self.file, _where(el), message, el.line))
        self.warnings.append(text)
        warnings.warn(text, ModelWarning, stacklevel=2)

    # attributes and sub-elements ----------------------------------------------------------------------
    def attribute(self, el, name, default=None):
        value = el.attrib.get(name, default)
        if value is None:
            self.fail(el, f"missing attribute {name!r}")
        return value

    def single(self, el, tag, required=False):
        found = el.all(tag)
        if len(found) > 1:
            self.fail(found[1], f"a second <{tag}> (the first is on line {found[0].line}); give one")
        if not found:
            if required:
                self.fail(el, f"missing <{tag}> element")
            return None
        return found[0]

    def numbers(self, el, name, n, default=None) -> tuple:
        """The attribute as n finite floats separated by white space."""
        text = el.attrib.get(name)
        if text is None:
            if default is None:
                self.fail(el, f"missing attribute {name!r}")
            return default
        parts = text.split()
        hint = " (an unexpanded xacro file? run xacro first)" if "$" in text else ""
        if len(parts) != n:
            what = "a number" if n == 1 else f"{n} numbers separated by spaces"
            self.fail(el, f'{name}="{text}" must be {what}{hint}')
        values = []
        for part in parts:
            if not _NUMBER.match(part):
                self.fail(el, f'{name}="{text}": {part!r} is not a number{hint}')
            value = float(part)
            if not math.isfinite(value):
                self.fail(el, f'{name}="{text}": {part!r} is not finite')
            values.append(0.0 if value == 0 else value)
        return tuple(values)

    def origin(self, el) -> tuple:
        """(xyz, rotation) of an optional ``<origin>`` child: translation and elementary rotations."""
        o = self.single(el, "origin")
        if o is None:
            return (0.0, 0.0, 0.0), []
        xyz = self.numbers(o, "xyz", 3, (0.0, 0.0, 0.0))
        if "quat_xyzw" in o.attrib:
            if "rpy" in o.attrib:
                self.fail(o, "both rpy and quat_xyzw are given; use one")
            if self.version < (1, 1):
                self.fail(o, 'quat_xyzw needs <robot version="1.1"> or later (URDF 1.0 ignores it)')
            x, y, z, w = self.numbers(o, "quat_xyzw", 4)
            norm = math.sqrt(x * x + y * y + z * z + w * w)
            if abs(norm - 1) > 1e-6:
                self.fail(o, f"quat_xyzw is not a unit quaternion (norm {norm:g})")
            return xyz, _rpy(_quaternion_rpy(x / norm, y / norm, z / norm, w / norm))
        return xyz, _rpy(self.numbers(o, "rpy", 3, (0.0, 0.0, 0.0)))

    # the document ---------------------------------------------------------------------------------------
    def read(self) -> Model:
        robot = self.root
        if robot.tag != "robot":
            self.fail(robot, f"not a URDF file: the top element is <{robot.tag}>, expected <robot>")
        version = robot.attrib.get("version", "1.0")
        if not re.fullmatch(r"\d+\.\d+", version.strip()):
            self.fail(robot, f'version="{version}" is not a version number like 1.0')
        self.version = tuple(int(x) for x in version.strip().split("."))
        robot_name = self.attribute(robot, "name")
        links, link_el = self.links(robot)
        joints = self.joints(robot, links, link_el)
        root, children = self.tree(robot, link_el, joints)
        return self.build(robot_name, root, links, link_el, joints, children)

    def links(self, robot):
        links: dict[str, _Inertial | None] = {}
        link_el: dict[str, _Element] = {}
        for el in robot.all("link"):
            name = self.attribute(el, "name")
            if name in link_el:
                self.fail(el, f"duplicate link name {name!r} (also on line {link_el[name].line})")
            link_el[name] = el
            links[name] = self.inertial(el)
        if not links:
            self.fail(robot, "the robot has no <link>")
        return links, link_el

    def inertial(self, link) -> _Inertial | None:
        el = self.single(link, "inertial")
        if el is None:
            return None
        xyz, rotation = self.origin(el)
        mass_el = self.single(el, "mass", required=True)
        (mass,) = self.numbers(mass_el, "value", 1)
        if mass < 0:
            self.fail(mass_el, f"negative mass {mass:g}: a mass must be positive (or 0, or omit <inertial> "
                               f"for a massless link)")
        inertia_el = self.single(el, "inertia", required=True)
        e = {k: self.numbers(inertia_el, k, 1)[0] for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        J = ((e["ixx"], e["ixy"], e["ixz"]), (e["ixy"], e["iyy"], e["iyz"]), (e["ixz"], e["iyz"], e["izz"]))
        problem = inertia_problem(J, triangle=False)
        if problem:
            self.fail(inertia_el, f"non-physical inertia: {problem}")
        problem = inertia_problem(J)
        if problem:  # harmless for the equations (A stays positive definite) and common in dummy links
            self.warn(inertia_el, f"non-physical inertia accepted (as Pinocchio does): {problem}")
        return _Inertial(mass, xyz, rotation, J)

    def joints(self, robot, links, link_el) -> dict:
        joints: dict[str, _Joint] = {}
        for el in robot.all("joint"):
            name = self.attribute(el, "name")
            if name in joints:
                self.fail(el, f"duplicate joint name {name!r} (also on line {joints[name].el.line})")
            jtype = self.attribute(el, "type")
            if jtype in UNSUPPORTED:
                self.fail(el, f"joint type {jtype!r}: {UNSUPPORTED[jtype]}")
            if jtype not in MOVABLE and jtype != "fixed":
                self.fail(el, f"unknown joint type {jtype!r} (expected revolute, continuous, prismatic or fixed)")
            ends = {}
            for end in ("parent", "child"):
                e = self.single(el, end, required=True)
                ends[end] = self.attribute(e, "link")
                if ends[end] not in links:
                    self.fail(e, f"{end} link {ends[end]!r} is not defined (no <link name=\"{ends[end]}\">)")
            if ends["parent"] == ends["child"]:
                self.fail(el, f"link {ends['child']!r} is both the parent and the child of the joint")
            xyz, rotation = self.origin(el)
            axis = None
            if jtype in MOVABLE:
                axis_el = self.single(el, "axis")
                axis = (1.0, 0.0, 0.0)
                if axis_el is not None:
                    raw = self.numbers(axis_el, "xyz", 3, axis)
                    norm = math.sqrt(sum(x * x for x in raw))
                    if norm <= _AXIS_TOL:
                        self.fail(axis_el, f'the axis xyz="{axis_el.attrib.get("xyz")}" has zero length; a joint '
                                           f"axis must be a non-zero vector")
                    axis = tuple(0.0 if x == 0 else x / norm for x in raw)
            mimic = None
            mimic_el = self.single(el, "mimic")
            if mimic_el is not None:
                mimic = {"joint": name, "master": self.attribute(mimic_el, "joint"),
                         "multiplier": self.numbers(mimic_el, "multiplier", 1, (1.0,))[0],
                         "offset": self.numbers(mimic_el, "offset", 1, (0.0,))[0], "el": mimic_el}
            joints[name] = _Joint(el, name, jtype, ends["parent"], ends["child"], xyz, rotation, axis, mimic)
        for joint in joints.values():
            if joint.mimic is None:
                continue
            el = joint.mimic["el"]
            master = joints.get(joint.mimic["master"])
            if master is None:
                self.fail(el, f"mimics joint {joint.mimic['master']!r}, which is not defined")
            if master.name == joint.name:
                self.fail(el, "a joint cannot mimic itself")
            if joint.type not in MOVABLE or master.type not in MOVABLE:
                # e.g. talos_reduced.urdf: gripper joints made fixed, their <mimic> tags left (Pinocchio ignores them)
                which = joint if joint.type not in MOVABLE else master
                self.warn(el, f"ignored: joint {which.name!r} is fixed, so there is nothing to couple")
                joint.mimic = None
                continue
        if self.mimic == "couple":
            for joint in joints.values():
                if joint.mimic is not None and joints[joint.mimic["master"]].mimic is not None:
                    self.fail(joint.mimic["el"], f"mimics joint {joint.mimic['master']!r}, which mimics another "
                                                 f"joint itself; couple to the primary joint")
        return joints

    def tree(self, robot, link_el, joints):
        """The root link and each link's joints to its children (byte order of joint names); checks the shape."""
        parent_joint: dict[str, _Joint] = {}
        children: dict[str, list] = {name: [] for name in link_el}
        for joint in joints.values():
            if joint.child in parent_joint:
                first = parent_joint[joint.child]
                self.fail(joint.el, f"link {joint.child!r} has two parents: it is already the child of joint "
                                    f"{first.name!r} (line {first.el.line}); a URDF is a tree")
            parent_joint[joint.child] = joint
            children[joint.parent].append(joint)
        for name in children:
            children[name].sort(key=lambda j: j.name.encode("utf-8"))
        roots = [name for name in link_el if name not in parent_joint]
        if len(roots) > 1:
            a, b = roots[0], roots[1]
            self.fail(link_el[b], f"two root links {a!r} (line {link_el[a].line}) and {b!r}: exactly one link may "
                                  f"be no joint's child; connect the others by joints")
        if not roots:
            self.fail(robot, "no root link: every link is the child of a joint, so the joints form a loop")
        root = roots[0]
        reached = {root}
        stack = [root]
        while stack:
            for joint in children[stack.pop()]:
                reached.add(joint.child)
                stack.append(joint.child)
        if len(reached) < len(link_el):
            start = next(name for name in link_el if name not in reached)
            chain = [start]
            while True:
                nxt = parent_joint[chain[-1]].parent
                if nxt in chain:
                    chain = chain[chain.index(nxt):] + [nxt]
                    break
                chain.append(nxt)
            loop = [parent_joint[name] for name in chain[:-1]]
            self.fail(loop[0].el, "loop in the kinematic tree: " + " -> ".join(f"{n!r}" for n in reversed(chain))
                      + f" (parent -> child through joints {', '.join(repr(j.name) for j in reversed(loop))}); "
                      "a URDF must be a tree")
        return root, children

    # the model ------------------------------------------------------------------------------------------
    def build(self, robot_name, root, links, link_el, joints, children) -> Model:
        body_names: set = set()
        coordinate_names: set = set()
        pair_names = set(joints)
        rows = []  # per body: dict with name, parent, pair, link, rotation, parts (inertial contributions)
        place: dict[str, _Place] = {}

        def add_inertial(link, where: _Place):
            data = links[link]
            if data is None:
                return
            R = where.R * _matrix(data.rotation)
            com = where.t + where.R * sp.Matrix([_exact(x) for x in data.com])
            J = R * sp.Matrix(3, 3, lambda i, j: _exact(data.inertia[i][j])) * R.T
            rows[where.body]["parts"].append((_exact(data.mass), com, J.applyfunc(snap)))

        root_pair_name = _identifier(ROOT_PAIR, pair_names, "joint")
        if self.floating_base:
            coords = tuple(Coordinate(_identifier(n, coordinate_names, "q"), code, root_pair_name)
                           for n, code in FLOATING)
        else:
            coords = ()
        zero = (sp.Integer(0),) * 3
        rows.append({"name": _identifier(root, body_names, "link"), "parent": WORLD, "link": root,
                     "pair": Pair(root_pair_name, zero, (), coords), "link_rotation": None, "parts": []})
        place[root] = _Place(0, [], sp.eye(3), sp.zeros(3, 1))
        add_inertial(root, place[root])
        stack = list(reversed(children[root]))  # depth first, siblings in order (Pinocchio's order)
        while stack:
            joint = stack.pop()
            here = place[joint.parent]
            t = here.t + here.R * sp.Matrix([_exact(x) for x in joint.xyz])
            if joint.type == "fixed":
                rotation = _tidy(here.rotation + joint.rotation)
                place[joint.child] = _Place(here.body, rotation, _matrix(rotation), t)
            else:
                align, i = _align(joint.axis)
                code = CODES[MOVABLE[joint.type]][i]
                name = _identifier(joint.name, coordinate_names, "q")
                pair = Pair(joint.name, tuple(t), tuple(_tidy(here.rotation + joint.rotation + align)),
                            (Coordinate(name, code, joint.name),))
                back = _inverse(align)
                R = _matrix(back)
                link_rotation = tuple(tuple(R[r, c] for c in range(3)) for r in range(3)) if align else None
                rows.append({"name": _identifier(joint.child, body_names, "link"), "parent": rows[here.body]["name"],
                             "link": joint.child, "pair": pair, "link_rotation": link_rotation, "parts": []})
                place[joint.child] = _Place(len(rows) - 1, back, R, sp.zeros(3, 1))
            add_inertial(joint.child, place[joint.child])
            stack.extend(reversed(children[joint.child]))
        bodies = tuple(Body(name=row["name"], parent=row["parent"], pair=row["pair"], inertial=_combine(row["parts"]),
                            where=_where(link_el[row["link"]]), link_rotation=row["link_rotation"])
                       for row in rows)
        name = _identifier(robot_name, set(), "robot")
        coordinate_of = {c.joint: c.name for row in rows for c in row["pair"].coordinates}
        couplings = tuple(Coupling(coordinate_of[j.name], coordinate_of[j.mimic["master"]],
                                   float(j.mimic["multiplier"]), float(j.mimic["offset"]))
                          for j in joints.values() if j.mimic is not None) if self.mimic == "couple" else ()
        model = Model(couplings=couplings, name=name, bodies=bodies, gravity=GRAVITY, parameters=(), source=str(self.file),
                      description=f"URDF robot {robot_name!r}",
                      meta={"mimic": [{k: j.mimic[k] for k in ("joint", "master", "multiplier", "offset")}
                                      for j in joints.values() if j.mimic is not None],
                            "links": {link: rows[p.body]["name"] for link, p in place.items()},
                            "floating_base": self.floating_base, "warnings": list(self.warnings)})
        if model.nq == 0:
            self.fail(self.root, "the robot has no movable joint (revolute, continuous or prismatic); there are "
                                 "no equations of motion (load with floating_base=True for a free body)")
        return model


def _combine(parts) -> Inertial | None:
    """One rigid body from several (mass, centre of mass, inertia about it), all in body axes."""
    if not parts:
        return None
    mass = sum((m for m, _, _ in parts), sp.Integer(0))
    if mass.is_zero:
        com = sp.zeros(3, 1)
    else:
        com = sum((m * c for m, c, _ in parts), sp.zeros(3, 1)) / mass
    J = sp.zeros(3, 3)
    for m, c, Jk in parts:
        d = c - com
        J += Jk + m * (d.dot(d) * sp.eye(3) - d * d.T)
    J = J.applyfunc(lambda x: snap(sp.expand(x)))
    com = com.applyfunc(lambda x: snap(sp.expand(x)))
    if mass.is_zero and all(x.is_zero for x in J):
        return None
    return Inertial(mass, tuple(com), tuple(tuple(J[i, j] for j in range(3)) for i in range(3)))


def load_urdf(path, floating_base: bool = False, mimic: str = "independent") -> Model:
    """Read and validate a URDF file; raises :class:`ModelError` naming the element and line of a problem."""
    path = Path(path)
    if mimic not in MIMIC_OPTIONS:
        raise ValueError(f"mimic must be one of {', '.join(MIMIC_OPTIONS)}, got {mimic!r}")
    if not isinstance(floating_base, bool):
        raise TypeError(f"floating_base must be True or False, got {floating_base!r}")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ModelError(path, "", f"cannot read the file: {exc.strerror}") from None
    return _Reader(path, _parse(path, data), floating_base, mimic).read()
