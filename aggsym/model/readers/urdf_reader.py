"""The URDF reader: links and joints onto the book's bodies and pairs (1.24)-(1.27), with precise errors.

Every mistake is reported as :class:`ModelError` with the file, the element (``<joint name="elbow">``, or
``<joint name="elbow"> <axis>`` for a part of it), the line, and what is wrong.  The file is parsed with the
standard library's expat, which gives the line of every element (:mod:`aggsym.model.readers.xml_source`, which also
accepts with a warning what urdfdom reads and whose meaning is clear: an XML declaration after white space, an
element the reader takes once given again identically; a repeat that differs is an error).

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
* A ``planar`` joint (URDF: motion in the plane normal to its ``<axis>``, default (1, 0, 0)) is one pair of three
  coordinates: R_a brings e_i onto the axis as above, then the translations along the two other axes of the joint
  frame (in the order x, y, z) and the rotation about e_i: for the axis z, o1 o2 theta6 (coordinates
  ``<joint>_x, <joint>_y, <joint>_rz``), Pinocchio's planar joint with q = (x, y, angle) instead of its
  (x, y, cos, sin), and the velocities the rates of these three (the translation rates in the parent-side axes,
  where Pinocchio's are in the child's).  Pinocchio's URDF importer ignores a planar joint's axis (its plane is
  always x-y); here the axis is the normal, as the URDF specification says.
* A ``floating`` joint (anywhere in the tree; its axis is unused) is the book's Euler pair o1 o2 o3 theta4 theta5
  theta6 at the joint's origin, as ``floating_base=True`` makes for the root: translations along x, y, z, then
  rotations about x, y, z in that order (R = Rx Ry Rz; Pinocchio's composite PX PY PZ RX RY RZ), coordinates
  ``<joint>_x, _y, _z, _rx, _ry, _rz``.  ``<dynamics>``, ``<limit>`` and ``<mimic>`` of a planar or floating joint
  are not read (a mimic on one is an error).
* A ``spherical`` joint (a simulator extension: a ball joint; its axis is unused) is the ball pair at the joint's
  origin (Pinocchio's JointModelSpherical): q holds its unit quaternion ``<joint>_qx, _qy, _qz, _qw`` (the child
  link's rotation in the joint's origin frame) and qd its angular velocity ``<joint>_wx, _wy, _wz`` in the child
  link's axes (docs/ball-joints.md).  Its ``<dynamics>``, ``<limit>`` and ``<mimic>`` are not read (a mimic on one
  is an error), and ``mimic="couple"`` in a model with one is refused.
* A ``fixed`` joint merges its child link into the parent's body: masses add, the centre of mass is the
  mass-weighted mean, and the inertia tensors (rotated into the body axes) are moved to the common centre of
  mass by the parallel-axis theorem; the fixed transform is composed into the origins of the child's joints
  (long chains of fixed joints fold their rotations into one roll-pitch-yaw, so merging stays linear).
* ``<inertial>``: mass, ``<origin>`` (the centre of mass and the axes of the inertia tensor, in the link frame)
  and the full tensor ixx..izz about the centre of mass, rotated into the body axes.  A link without
  ``<inertial>`` is massless.  A mass of 0 keeps its rotational inertia (Pinocchio does the same); a link with
  mass 0 and zero inertia is massless.
* The root link (the one link that is no joint's child) is attached to the world by a pair without
  coordinates (fixed base), or with ``floating_base=True`` (or ``"euler"``) by the free pair o1, o2, o3, theta4,
  theta5, theta6 (coordinates ``base_x, base_y, base_z, base_rx, base_ry, base_rz``; Pinocchio's composite
  PX, PY, PZ, RX, RY, RZ), or with ``floating_base="quaternion"`` by Pinocchio's free-flyer: q starts with
  ``base_x, base_y, base_z, base_qx, base_qy, base_qz, base_qw`` (origin, unit quaternion) and the velocities with
  ``base_vx, base_vy, base_vz, base_wx, base_wy, base_wz`` (the root's own (v, w), body axes).
* Bodies and coordinates are ordered as Pinocchio orders its joints for the same file: depth first from the
  root, the joints leaving a link in the byte order of their names (urdfdom keeps them in a ``std::map``),
  fixed joints walked through in place.  So q maps one-to-one onto Pinocchio's fixed-base model.
* ``<mimic>``: by default the joint keeps an independent coordinate, the relation is only recorded in
  ``model.meta["mimic"]`` and a :class:`ModelWarning` says so; with ``mimic="couple"`` the joint's coordinate
  becomes ``multiplier * master + offset`` (``Model.couplings``): it leaves q, and the generated routines take
  and return the remaining coordinates (:mod:`aggsym.coupling`), as Pinocchio's ``mimic=True`` models do.  A
  ``<mimic>`` that cannot be used (its joint or its master is fixed, its master does not exist, it names its own
  joint) is ignored with a warning, unless ``mimic="couple"`` needs it (then it is an error).
* ``<dynamics damping= friction=>`` and ``<limit lower= upper= velocity= effort=>`` of a movable joint are kept on
  its coordinate (``Coordinate.dynamics``, ``Coordinate.limits``; ``Model.joint_dynamics``, ``Model.limits``),
  None where absent.  Damping and friction must not be negative; a limit with lower > upper or a negative
  velocity or effort is kept with a warning.
* Coordinate names are the joint names made identifiers (``Coordinate.joint`` keeps the URDF name); body names
  are the link names made identifiers (anything but ASCII letters, digits and ``_`` becomes ``_``; a leading
  digit or ``_`` gets a prefix, a reserved word a trailing ``_``); two names that would become the same
  identifier are an error naming both.  The model name is the robot's.  Gravity is (0, 0, -9.81) in the root
  frame.  No parameters: every number is folded.  Visuals, collisions, meshes, transmissions and gazebo tags are
  skipped unread.
* ``model.links`` (:class:`~aggsym.model.types.Links`, kind ``"link"``): each URDF link, merged links included,
  as a :class:`~aggsym.model.types.LinkFrame`: its body and placement there (x_body = R x_link + t, for
  constraints on links and for the frame routines) and its own mass, centre of mass and inertia about it in its
  body's axes (for :mod:`aggsym.model.transforms.inertials`); its ``leaves`` are the links without a child link (the frames
  emitted by default).
* ``model.meta``: ``mimic`` (above), ``links`` (each URDF link's body, merged links included), ``floating_base``, and ``warnings``: what was accepted but looks wrong, also issued as :class:`ModelWarning`;
  ``snapped_angles`` (only when ``snap_angles`` moved an angle of the file: the tolerance and each angle moved,
  where, its value and the multiple of pi/2 taken; the manifest repeats it).

Physical validity (where the dynamics sees it)
----------------------------------------------
Each moving body is judged after its welded links are merged, on the motions its joints allow
(:func:`~aggsym.model.readers.validate.kinetic_energy_problem`): a body whose kinetic energy can be negative for a
velocity its joints give it (its inertia about the centre of mass not positive semi-definite, by more than 1e-6
of its largest principal moment, in a direction it can turn about) is an error naming the body and its links.
A link whose own inertia is not physical (not positive semi-definite, or principal moments violating the
triangle inequality) is used as given with a warning naming it and its body: when the merged body is physical
(tiago's ``base_antenna_left_link`` merges into its base), when the body is welded to the world (never judged:
the dynamics never sees it), or when the body's kinetic energy stays non-negative for every motion its joints
allow (romeo_small's shoulder violates the triangle inequality; romeo_laas_small's hips are not positive
semi-definite but only turn about the hip's centre, where they are).  Pinocchio loads all of these.

Hostile files
-------------
No entity is ever expanded: a document type declaration that declares entities (internal, external or
parameter) or names an external DTD is refused, and nothing outside the file is read.  The file is at most
:data:`MAX_BYTES`, with at most :data:`MAX_LINKS` links, :data:`MAX_JOINTS` joints and :data:`MAX_ELEMENTS` XML
elements; elements the reader does not use are skipped without being stored.  Ordering the tree and merging fixed
links are O(n log n).
"""
from __future__ import annotations

import math
import re
import dataclasses
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import sympy as sp

from ...errors import ModelError, ModelWarning
from .builder import Names, TreeBuilder, ball_names, floating_root
from .builder import identifier as _identifier
from .builder import quaternion_rotations as _quaternion_rotations, right_angle as _right_angle
from .builder import rpy as _rpy
from .model_root import ModelRoot
from ..transforms.frames import default_frames
from ..types import Coordinate, Coupling, JointDynamics, JointLimits, Model, Parameter
from .sympy_numbers import double
from .validate import kinetic_energy_problem, motion_space, principal_problem
from .xml_source import NUMBER as _NUMBER, _Element, _parse, _where, read_capped

GRAVITY = (sp.Integer(0), sp.Integer(0), sp.Float(-9.81))
MOVABLE = {"revolute": "theta", "continuous": "theta", "prismatic": "o"}
SEVERAL = {"planar": "planar", "floating": "floating"}  # joints of several coordinates (builder.motions)
SUFFIX = {"o1": "x", "o2": "y", "o3": "z", "theta4": "rx", "theta5": "ry", "theta6": "rz"}  # their coordinates
BALL = "spherical"  # the ball joint (a simulator extension of URDF)
FLOATING_BASES = (False, True, "euler", "quaternion")
MIMIC_OPTIONS = ("independent", "couple")
ROOT_PAIR = "root_joint"
_AXIS_TOL = 1e-12

MAX_BYTES = 64 * 2 ** 20  # the largest URDF read (example-robot-data's largest is under 1 MiB)



@dataclass
class _Inertial:
    """One link's inertial data as floats in its link frame."""

    mass: float
    com: tuple
    rotation: list  # the inertial frame's axes, elementary rotations
    inertia: tuple  # 3x3 about the centre of mass, inertial-frame axes
    el: _Element  # the <inertia> element
    problem: str | None  # why the tensor is not physical, or None


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
    dynamics: JointDynamics = JointDynamics()
    limits: JointLimits = JointLimits()


class _Reader:
    def __init__(self, file: Path, root: _Element, floating_base: bool, mimic: str, snap_angles: float = 0.0,
                 notes=()):
        self.file = file
        self.snap_angles = snap_angles
        self.snapped: list[dict] = []  # the angles that snap_angles moved (the manifest's "snapped_angles")
        self.root = root
        self.floating_base = floating_base
        self.mimic = mimic
        self.version = (1, 0)
        self.warnings: list[str] = list(notes)  # (the parser's, already issued)

    def fail(self, el: _Element, message: str):
        raise ModelError(self.file, _where(el), message, el.line)

    def warn(self, el: _Element, message: str, line: int | None = None):
        text = str(ModelError(self.file, _where(el), message, el.line if line is None else line))
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
        if len(found) > 1:  # (xml_source keeps a repeat only when it differs from the first)
            self.fail(found[1], f"a second <{tag}> that differs from the first (line {found[0].line}): which one is "
                                f"meant is not clear; give one")
        if not found:
            if required:
                self.fail(el, f"missing <{tag}> element")
            return None
        first = found[0]
        if first.repeated_on is not None:
            again = f" ({first.repeats} repeats in all)" if first.repeats > 1 else ""
            self.warn(first, f"a second <{tag}> identical to the first (line {first.line}){again} is ignored; give "
                             f"one", line=first.repeated_on)
        return first

    def numbers(self, el, name, n, default=None) -> tuple:
        """The attribute as n finite floats separated by white space."""
        text = el.attrib.get(name)
        if text is None:
            if default is None:
                self.fail(el, f"missing attribute {name!r}")
            return default
        parts = text.split()
        shown = text if len(text) <= 80 else text[:77] + "..."
        hint = " (an unexpanded xacro file? run xacro first)" if "$" in text else ""
        if len(parts) != n:
            what = "a number" if n == 1 else f"{n} numbers separated by spaces"
            self.fail(el, f'{name}="{shown}" must be {what}{hint}')
        values = []
        for part in parts:
            if not _NUMBER.match(part):
                self.fail(el, f'{name}="{shown}": {part[:40]!r} is not a number{hint}')
            value = float(part)
            if not math.isfinite(value):
                self.fail(el, f'{name}="{shown}": {part[:40]!r} is not finite (beyond the largest double, about '
                              f"1.8e308); give a finite number")
            values.append(0.0 if value == 0 else value)
        return tuple(values)

    def number(self, el, name) -> float | None:
        """An optional attribute holding one finite number; None when absent."""
        if el is None or name not in el.attrib:
            return None
        return self.numbers(el, name, 1)[0]

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
            return xyz, _quaternion_rotations(x / norm, y / norm, z / norm, w / norm)
        rpy = self.numbers(o, "rpy", 3, (0.0, 0.0, 0.0))
        if self.snap_angles:
            for name, value in zip(("roll", "pitch", "yaw"), rpy):
                k = _right_angle(value, self.snap_angles)
                if k is not None and _right_angle(value, 0.0) is None:
                    self.snapped.append({"where": f"{_where(o)}, line {o.line}", "angle": name, "value": value,
                                         "taken_as": f"{k}*pi/2"})
        return xyz, _rpy(rpy, self.snap_angles) if any(rpy) else []  # (no rotation: most origins; _rpy's SymPy
        # work is per angle)

    # the document ---------------------------------------------------------------------------------------
    def read(self) -> Model:
        robot = self.root
        if robot.tag != "robot":
            self.fail(robot, f"not a URDF file: the top element is <{robot.tag}>, expected <robot>")
        version = robot.attrib.get("version", "1.0")
        if not re.fullmatch(r"\d{1,9}\.\d{1,9}", version.strip()):
            self.fail(robot, f'version="{version[:40]}" is not a version number like 1.0')
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
        """A link's ``<inertial>``; a tensor that is not physical is kept, and judged on the link's body."""
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
        if max(abs(x) for row in J for x in row) > 1e150:
            self.fail(inertia_el, "the inertia's entries are too large to compute with (above 1e150)")
        return _Inertial(mass, xyz, rotation, J, inertia_el, principal_problem(J))

    def joints(self, robot, links, link_el) -> dict:
        joints: dict[str, _Joint] = {}
        for el in robot.all("joint"):
            name = self.attribute(el, "name")
            if name in joints:
                self.fail(el, f"duplicate joint name {name!r} (also on line {joints[name].el.line})")
            jtype = self.attribute(el, "type")
            if jtype not in MOVABLE and jtype not in SEVERAL and jtype not in (BALL, "fixed"):
                self.fail(el, f"unknown joint type {jtype[:40]!r} (expected revolute, continuous, prismatic, "
                              f"planar, floating, spherical or fixed)")
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
            dynamics, limits = JointDynamics(), JointLimits()
            if jtype in MOVABLE or jtype == "planar":  # (a floating joint has no axis)
                axis_el = self.single(el, "axis")
                axis = (1.0, 0.0, 0.0)
                if axis_el is not None:
                    raw = self.numbers(axis_el, "xyz", 3, axis)
                    norm = math.sqrt(sum(x * x for x in raw))
                    if norm <= _AXIS_TOL:
                        self.fail(axis_el, f'the axis xyz="{axis_el.attrib.get("xyz")}" has zero length; a joint '
                                           f"axis must be a non-zero vector")
                    axis = tuple(0.0 if x == 0 else x / norm for x in raw)
            if jtype in MOVABLE:  # (<dynamics> and <limit> of one coordinate)
                dynamics, limits = self.dynamics(el), self.limits(el)
            mimic = None
            mimic_el = self.single(el, "mimic")
            if mimic_el is not None:
                mimic = {"joint": name, "master": self.attribute(mimic_el, "joint"),
                         "multiplier": self.numbers(mimic_el, "multiplier", 1, (1.0,))[0],
                         "offset": self.numbers(mimic_el, "offset", 1, (0.0,))[0], "el": mimic_el}
            joints[name] = _Joint(el, name, jtype, ends["parent"], ends["child"], xyz, rotation, axis, mimic,
                                  dynamics, limits)
        self.mimics(joints)
        return joints

    def dynamics(self, joint) -> JointDynamics:
        """``<dynamics damping= friction=>`` of a movable joint: non-negative numbers, None where absent."""
        el = self.single(joint, "dynamics")
        values = {}
        for name in ("damping", "friction"):
            values[name] = self.number(el, name)
            if values[name] is not None and values[name] < 0:
                self.fail(el, f'{name}="{el.attrib[name]}" is negative: a {name} coefficient takes energy out of '
                              f"the joint, so it must be 0 or positive")
        return JointDynamics(**values)

    def limits(self, joint) -> JointLimits:
        """``<limit lower= upper= velocity= effort=>`` of a movable joint, None where absent; kept as given, with a
        warning when they contradict themselves."""
        el = self.single(joint, "limit")
        values = {name: self.number(el, name) for name in ("lower", "upper", "velocity", "effort")}
        if values["lower"] is not None and values["upper"] is not None and values["lower"] > values["upper"]:
            self.warn(el, f"lower={values['lower']:g} is above upper={values['upper']:g}; kept as given")
        for name in ("velocity", "effort"):
            if values[name] is not None and values[name] < 0:
                self.warn(el, f"{name}={values[name]:g} is negative (a largest {name} is a magnitude); kept as given")
        return JointLimits(**values)

    def mimics(self, joints):
        """Check the ``<mimic>`` tags: warn about those that are ignored (the joint stays independent), fail where
        ``mimic="couple"`` needs one that cannot be used."""
        couple = self.mimic == "couple"
        for joint in joints.values():
            if joint.mimic is None:
                continue
            el, wanted = joint.mimic["el"], joint.mimic["master"]
            master = joints.get(wanted)
            for which in (joint, master):
                if which is not None and (which.type in SEVERAL or which.type == BALL):
                    self.fail(el, f"a <mimic> ties one coordinate to one other; joint {which.name!r} is {which.type} "
                                  f"(several coordinates)")
            problem = None
            if joint.type not in MOVABLE:
                # e.g. talos_reduced.urdf: gripper joints made fixed, their <mimic> tags left (Pinocchio ignores them)
                self.warn(el, f"ignored: joint {joint.name!r} is fixed, so there is nothing to couple")
            elif master is None:
                problem = f"mimics joint {wanted!r}, which is not defined"
            elif master.name == joint.name:
                problem = "a joint cannot mimic itself"
            elif master.type not in MOVABLE:
                self.warn(el, f"ignored: joint {master.name!r} is fixed, so there is nothing to couple")
            else:
                continue
            if problem is not None:
                if couple:
                    self.fail(el, f"{problem}; mimic='couple' (--mimic couple) cannot tie joint {joint.name!r}")
                self.warn(el, f"ignored: {problem} (joint {joint.name!r} keeps its own coordinate; with "
                              f"mimic='couple' this is an error)")
            joint.mimic = None
        if couple:
            for joint in joints.values():
                if joint.mimic is not None and joints[joint.mimic["master"]].mimic is not None:
                    self.fail(joint.mimic["el"], f"mimics joint {joint.mimic['master']!r}, which mimics another "
                                                 f"joint itself; couple to the primary joint")
        else:
            for joint in joints.values():
                if joint.mimic is not None:
                    m = joint.mimic
                    self.warn(m["el"], f"joint {joint.name!r} mimics {m['master']!r} (multiplier {m['multiplier']:g}, "
                                       f"offset {m['offset']:g}) but keeps an independent coordinate; load with "
                                       f"mimic='couple' (--mimic couple) to tie it to {m['master']!r}")

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
            chain, seen = [start], {start: 0}
            while True:
                nxt = parent_joint[chain[-1]].parent
                if nxt in seen:
                    chain = chain[seen[nxt]:] + [nxt]
                    break
                seen[nxt] = len(chain)
                chain.append(nxt)
            loop = [parent_joint[name] for name in chain[:-1]]
            self.fail(loop[0].el, "loop in the kinematic tree: " + " -> ".join(f"{n!r}" for n in reversed(chain))
                      + f" (parent -> child through joints {', '.join(repr(j.name) for j in reversed(loop))}); "
                      "a URDF must be a tree")
        return root, children

    # the model ------------------------------------------------------------------------------------------
    def build(self, robot_name, root, links, link_el, joints, children) -> Model:
        bodies_names = Names(self.fail, "link", "link")
        coordinate_names = Names(self.fail, "joint", "q")
        tree = TreeBuilder()

        def add_inertial(link):
            data = links[link]
            if data is not None:
                tree.inertial(link, data.mass, data.com, data.inertia, data.rotation)

        root_pair_name = _identifier(ROOT_PAIR, set(joints), "joint")
        tree.root(root, bodies_names.claim(root, link_el[root]),
                  floating_root(self.floating_base, coordinate_names, root_pair_name))
        add_inertial(root)
        stack = list(reversed(children[root]))  # depth first, siblings in order (Pinocchio's order)
        while stack:
            joint = stack.pop()
            if joint.type == "fixed":
                tree.fixed(joint.parent, joint.child, joint.xyz, joint.rotation)
            elif joint.type == BALL:
                velocities, positions = ball_names(joint.name)
                velocities = [coordinate_names.claim(n, joint.el) for n in velocities]
                positions = tuple(coordinate_names.claim(n, joint.el) for n in positions)
                tree.joint(joint.parent, joint.child, bodies_names.claim(joint.child, link_el[joint.child]),
                           joint.name, lambda code, j=joint, v=velocities: Coordinate(v[("theta4", "theta5",
                                                                                         "theta6").index(code)],
                                                                                       code, j.name),
                           joint.xyz, joint.rotation, None, "ball", positions=positions)
            elif joint.type in SEVERAL:
                names = {}  # (claimed in code order: the builder makes them in that order)

                def several(code, j=joint, names=names):
                    names[code] = coordinate_names.claim(f"{j.name}_{SUFFIX[code]}", j.el)
                    return Coordinate(names[code], code, j.name)

                tree.joint(joint.parent, joint.child, bodies_names.claim(joint.child, link_el[joint.child]),
                           joint.name, several, joint.xyz, joint.rotation, joint.axis, SEVERAL[joint.type])
            else:
                name = coordinate_names.claim(joint.name, joint.el)
                tree.joint(joint.parent, joint.child, bodies_names.claim(joint.child, link_el[joint.child]),
                           joint.name, lambda code, j=joint, n=name: Coordinate(n, code, j.name, j.dynamics, j.limits),
                           joint.xyz, joint.rotation, joint.axis, MOVABLE[joint.type])
            add_inertial(joint.child)
            stack.extend(reversed(children[joint.child]))
        bodies = tree.bodies(lambda link: _where(link_el[link]))
        rows, place = tree.rows, tree.place
        self.judge(bodies, rows, place, links, link_el)
        name = _identifier(robot_name, set(), "robot")
        coordinate_of = {c.joint: c.name for row in rows for c in row["pair"].coordinates}
        couplings = tuple(Coupling(coordinate_of[j.name], coordinate_of[j.mimic["master"]],
                                   float(j.mimic["multiplier"]), float(j.mimic["offset"]))
                          for j in joints.values() if j.mimic is not None) if self.mimic == "couple" else ()
        links = tree.links(link for link in place if not children[link])
        if couplings and any(joint.type == BALL for joint in joints.values()):
            self.fail(self.root, "mimic='couple' (--mimic couple) in a robot with a spherical joint is not "
                                 "supported; keep the mimic joints independent")
        model = Model(couplings=couplings, name=name, bodies=bodies, gravity=GRAVITY, links=links,
                      parameters=friction_parameters(c for row in rows for c in row["pair"].coordinates),
                      source=str(self.file), description=f"URDF robot {robot_name!r}",
                      meta={"mimic": [{k: j.mimic[k] for k in ("joint", "master", "multiplier", "offset")}
                                      for j in joints.values() if j.mimic is not None],
                            "links": {link: rows[p.body]["name"] for link, p in place.items()},
                            "floating_base": self.floating_base, "warnings": list(self.warnings),
                            **({"snapped_angles": {"tolerance": self.snap_angles, "angles": list(self.snapped)}}
                               if self.snapped else {})})
        model = dataclasses.replace(model, frames=default_frames(model))
        if model.nq == 0:
            self.fail(self.root, "the robot has no movable joint (revolute, continuous, prismatic, planar or "
                                 "floating); there are "
                                 "no equations of motion (load with floating_base=True for a free body)")
        return model

    def judge(self, bodies, rows, place, links, link_el):
        """Physical validity where the dynamics sees it: each body's merged inertia on the velocities its joints
        allow (an error when its kinetic energy can be negative); a warning for each link whose own inertia is not
        physical, saying why it is used as given."""
        members: list[list[str]] = [[] for _ in bodies]
        for link, where in place.items():
            members[where.body].append(link)
        spaces: dict[int, np.ndarray] = {}

        def space(k):
            """The body's motion space (validate.motion_space), computed down from the nearest known ancestor."""
            path, j = [], k
            while j >= 0 and j not in spaces:
                path.append(j)
                j = parent_index[j]
            for i in reversed(path):
                pair = bodies[i].pair
                spaces[i] = motion_space(spaces.get(parent_index[i]), pair.translation, pair.rotation, pair.codes)
            return spaces[k]

        position = {b.name: i for i, b in enumerate(bodies)}
        parent_index = [position.get(b.parent, -1) for b in bodies]
        verdict: list[str] = []
        for k, body in enumerate(bodies):
            shown = members[k][:6]
            links_text = ", ".join(repr(link) for link in shown) + (
                f" and {len(members[k]) - len(shown)} more" if len(members[k]) > len(shown) else "")
            of = f"body {body.name!r} (links {links_text})" if len(members[k]) > 1 else f"body {body.name!r}"
            if body.inertial is None:
                verdict.append(f"its {of} is massless")
                continue
            mass = double(body.inertial.mass)
            com = [double(x) for x in body.inertial.com]
            J = np.array([[double(x) for x in row] for row in body.inertial.inertia])
            if not (math.isfinite(mass) and all(math.isfinite(x) for x in com) and np.all(np.isfinite(J))):
                self.fail(link_el[rows[k]["link"]], f"the merged mass, centre of mass or inertia of {of} overflows "
                                                    f"a double (mass {mass:g}); the numbers are too large")
            problem = principal_problem(J)
            if problem is None:
                verdict.append(f"its {of} is physical")
                continue
            W = space(k)
            if W.shape[1] == 0:
                verdict.append(f"its {of} is welded to the world, where the dynamics never sees it")
                continue
            energy = kinetic_energy_problem(mass, com, J, W)
            bad = [link for link in members[k] if links[link] is not None and links[link].problem]
            if energy is not None:
                which = "; ".join(f"link {link!r}: {links[link].problem} (line {links[link].el.line})"
                                  for link in bad)
                self.fail(link_el[rows[k]["link"]],
                          f"non-physical inertia of {of}: {problem}; {energy}"
                          + (f". Not physical: {which}" if which else "")
                          + ". Fix the <inertia> (Pinocchio loads it as given, and its equations then let this "
                            "body's kinetic energy go negative)")
            verdict.append(f"its {of} keeps a non-negative kinetic energy for every motion its joints allow")
            if not bad:
                self.warn(link_el[rows[k]["link"]], f"non-physical inertia of {of} accepted: {problem}; its kinetic "
                                                    f"energy stays non-negative for every motion its joints allow")
        owner = {link: where.body for link, where in place.items()}
        for link in sorted((name for name, data in links.items() if data is not None and data.problem),
                           key=lambda name: links[name].el.line):
            data = links[link]
            self.warn(data.el, f"non-physical inertia accepted (as Pinocchio does): {data.problem}; the link is used "
                               f"as given, since {verdict[owner[link]]}")


def friction_parameters(coordinates) -> tuple:
    """The runtime parameters of the joints that have a ``<dynamics>`` element: ``damping_<coordinate>`` and
    ``friction_<coordinate>`` per joint, in joint (q) order, defaults from the file (0 where one is absent)."""
    out = []
    for c in coordinates:
        if c.dynamics.given:
            out.append(Parameter(f"damping_{c.name}", float(c.dynamics.damping or 0.0)))
            out.append(Parameter(f"friction_{c.name}", float(c.dynamics.friction or 0.0)))
    return tuple(out)


def _check_options(floating_base, mimic, snap_angles):
    """The options of :func:`load_urdf` checked; the floating base's kind (``"euler"`` is True)."""
    if not (isinstance(snap_angles, (int, float)) and 0 <= snap_angles < math.pi / 4):
        raise ValueError(f"snap_angles must be a number of radians from 0 to pi/4 (exclusive), got {snap_angles!r}")
    if mimic not in MIMIC_OPTIONS:
        raise ValueError(f"mimic must be one of {', '.join(MIMIC_OPTIONS)}, got {mimic!r}")
    if not any(floating_base is v or (isinstance(v, str) and floating_base == v) for v in FLOATING_BASES):
        raise TypeError(f"floating_base must be False, True (= 'euler') or 'quaternion', got {floating_base!r}")
    if floating_base == "euler":
        floating_base = True
    if floating_base == "quaternion" and mimic == "couple":
        raise ValueError("mimic='couple' with a quaternion floating base is not supported: use the Euler base "
                         "(floating_base=True) or independent mimic joints")
    return floating_base


def load_urdf(path, floating_base: bool | str = False, mimic: str = "independent", snap_angles: float = 0.0,
              root=None) -> Model:
    """Read and validate a URDF file; raises :class:`ModelError` naming the element and line of a problem.
    ``snap_angles``: an approximation on request (off by default): the angles of joint and inertial origins
    (``rpy``) within this many radians of a multiple of pi/2 are taken as that multiple (recorded in
    ``model.meta["snapped_angles"]`` and the manifest); below it the file's values are kept (to round-off).
    ``root`` (``--model-root``): a folder holding the file; a URDF reads no other file (its meshes, ``package://``
    or ``file://``, are visuals and collisions, never opened), so the root only has to hold it."""
    path = Path(path)
    ModelRoot.of(path, root)
    _check_options(floating_base, mimic, snap_angles)
    data = read_capped(path, path, MAX_BYTES, "a URDF")
    return urdf_from_bytes(path, data, floating_base, mimic, snap_angles)


def urdf_from_bytes(path: Path, data: bytes, floating_base: bool | str = False, mimic: str = "independent",
                    snap_angles: float = 0.0, label: str | None = None) -> Model:
    """A URDF document given as bytes (the xacro reader's expansion), read as :func:`load_urdf` reads a file;
    ``label`` names it in messages and as the model's source (default: ``path``)."""
    floating_base = _check_options(floating_base, mimic, snap_angles)
    if len(data) > MAX_BYTES:
        raise ModelError(label or path, "", f"the document is larger than {MAX_BYTES // 2 ** 20} MiB; a URDF this "
                                            f"large is not read (the limit guards against exhausting memory)")
    shown = Path(label) if label else Path(path)
    notes: list[str] = []
    root = _parse(shown, data, notes)
    return _Reader(shown, root, floating_base, mimic, float(snap_angles), notes).read()
