"""The format-neutral tree builder under the readers: what a reader of a tree of links and joints (URDF; MJCF,
SDF later) needs beside parsing its file.

* Rotations as elementary rotations (axis 1..3, angle) in order of application: :func:`tidy` (merge neighbours about
  one axis, drop multiples of 2 pi), :func:`inverse`, :func:`rpy` (roll-pitch-yaw, R = Rz(yaw) Ry(pitch) Rx(roll),
  angles within round-off of a multiple of pi/2 taken as that multiple: :func:`angle`), :func:`rotations` (a
  rotation matrix of floats, away from the gimbal lock), :func:`quaternion_rotations`, :func:`fold` (a long product
  folded into one roll-pitch-yaw: chains of merged fixed joints, beyond :data:`MAX_ROTATIONS`).
* Axes: :func:`align` gives the constant rotation R_a with R_a e_i = axis (exact for +-x, +-y, +-z), so that a joint
  about or along any axis is the book's elementary motion theta_(4+i) or o_(1+i) after it (1.24)-(1.27).
* Merging fixed joints: a merged link's :class:`Place` in its body (x_body = R x_link + t).
* Names: :func:`mangle`, :func:`identifier` and :class:`Names` make a file's names C identifiers, two names never
  becoming one.
* Floating bases: :func:`floating_root` (the Euler pair :data:`FLOATING`, or the free-flyer :data:`FREE_FLYER` with
  the positions :data:`FREE_FLYER_POSITIONS`), and :func:`link_table`: the model's :class:`~.types.Links`.
* :class:`TreeBuilder`: the tree itself, built a link or a body at a time (a root, a movable joint and the body it
  moves, a fixed joint merged into its parent's body, a link's inertial part, or a body given whole as the YAML
  reader has it); it gives the :class:`~.types.Body` list and the :class:`~.types.Links` of the model.  A reader
  parses its format and calls it; the placement arithmetic, the axis alignment and the merging are here once.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np
import sympy as sp

from .expressions import check_identifier
from .link_numbers import IDENTITY, ORIGIN, add, combine, exact, matvec, product, round_off, rotation_matrix, snapped
from .link_numbers import transpose, turn
from ..types import WORLD, Body, Coordinate, LinkFrame, Links, Pair

FLOATING = (("base_x", "o1"), ("base_y", "o2"), ("base_z", "o3"), ("base_rx", "theta4"), ("base_ry", "theta5"),
            ("base_rz", "theta6"))
FREE_FLYER = (("base_vx", "o1"), ("base_vy", "o2"), ("base_vz", "o3"), ("base_wx", "theta4"), ("base_wy", "theta5"),
              ("base_wz", "theta6"))  # velocities of the quaternion base
FREE_FLYER_POSITIONS = ("base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw")
BALL = (("wx", "theta4"), ("wy", "theta5"), ("wz", "theta6"))  # a ball joint J's velocities J_wx J_wy J_wz
BALL_POSITIONS = ("qx", "qy", "qz", "qw")  # its positions J_qx J_qy J_qz J_qw: a unit quaternion
MAX_ROTATIONS = 9  # elementary rotations a chain of fixed joints may pile up before they are folded into one rpy


def inverse(rotation) -> list:
    return [(axis, -angle) for axis, angle in reversed(rotation)]


def tidy(rotation) -> list:
    """Merge neighbouring rotations about one axis and drop rotations by multiples of 2 pi."""
    out: list = []
    for axis, angle in rotation:
        if out and out[-1][0] == axis:
            angle = out.pop()[1] + angle
        if not (angle.is_zero or (not isinstance(angle, sp.Float) and (angle / (2 * sp.pi)).is_integer)):
            out.append((axis, angle))  # (a float from the file is never a non-zero multiple of 2 pi)
    return out


ANGLE_ROUND_OFF = 1e-15  # rad (times k for k pi/2): an angle of the file this close to a multiple of pi/2 is that
# multiple written to double precision (1.5707963267948966, 1.570796326794897, 3.141592653589793; a few units in the
# last place): it is taken as the exact multiple, the change being round-off.  Nothing farther is moved: 1.57079632679 (5e-12 off) or 1.5708 stay what they are, unless
# the user asks for it (``snap_angles``, recorded in the manifest).


def right_angle(value: float, tolerance: float):
    """k when ``value`` is within ``tolerance`` (at least the round-off) of k pi/2, else None."""
    k = round(float(value) / (math.pi / 2))
    return k if abs(float(value) - k * math.pi / 2) <= max(tolerance, ANGLE_ROUND_OFF * max(1, abs(k))) else None


def angle(value: float, snap: float = 0.0) -> sp.Expr:
    """An angle from the file: the exact multiple of pi/2 within round-off of it (or within ``snap`` when the user
    asked for :func:`load_urdf`'s ``snap_angles``), so that the zeros and ones of the right-angle rotation fold in
    the generated code; otherwise the file's float, as Pinocchio reads it."""
    k = right_angle(value, snap)
    if k is not None:
        return sp.Integer(k) * sp.pi / 2
    return sp.Float(value)  # (an integer angle kept exact would leave sin(7) unevaluated, growing along chains)


def rpy(angles, snap: float = 0.0) -> list:
    """URDF roll-pitch-yaw as elementary rotations: R = Rz(y) Ry(p) Rx(r)."""
    r, p, y = angles
    return tidy([(3, angle(y, snap)), (2, angle(p, snap)), (1, angle(r, snap))])


def matrix_rpy(R) -> tuple:
    """roll, pitch, yaw of a rotation matrix, R = Rz(yaw) Ry(pitch) Rx(roll) (ill-conditioned near pitch = +-pi/2:
    :func:`rotations` avoids that)."""
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])


# right-angle turns P (exact) with P e1 = e_j, as elementary rotations, and their matrices
_TURNS = ((), ((3, sp.pi / 2),), ((2, -sp.pi / 2),))
_TURN_MATRICES = (np.eye(3), np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]), np.array([[0.0, 0, -1], [0, 1, 0], [1, 0, 0]]))


def rotations(R) -> list:
    """A rotation matrix (floats) as elementary rotations, exactly to round-off: roll-pitch-yaw of R P and then
    P^T, where the right-angle turn P (exact) takes e1 to the axis e_j whose entry of R's last row is the smallest,
    so that |sin(pitch)| <= 1/sqrt(3), far from the gimbal lock where roll and yaw lose their digits (P = I unless
    |sin(pitch)| would exceed 0.99)."""
    j = int(np.argmin(np.abs(R[2]))) if abs(R[2, 0]) > 0.99 else 0
    turned = rpy(matrix_rpy(R @ _TURN_MATRICES[j]))
    return tidy(turned + [(axis, -angle) for axis, angle in reversed(_TURNS[j])])


def quaternion_rotations(x, y, z, w) -> list:
    """A unit quaternion (x, y, z, w) as elementary rotations (:func:`rotations`)."""
    return rotations(np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]))


def fold(rotation: list) -> list:
    """A product of elementary rotations folded into one roll-pitch-yaw (3 rotations, in floats; for a long chain of
    fixed joints, whose rotations would otherwise pile up)."""
    R = np.eye(3)
    for axis, angle in rotation:
        c, s = math.cos(float(angle)), math.sin(float(angle))
        E = {1: [[1, 0, 0], [0, c, -s], [0, s, c]], 2: [[c, 0, s], [0, 1, 0], [-s, 0, c]],
             3: [[c, -s, 0], [s, c, 0], [0, 0, 1]]}[axis]
        R = R @ np.array(E)
    return rotations(R)


def align(axis) -> tuple:
    """(R_a as elementary rotations, 0-based index i) with R_a e_i = axis, exact for +-x, +-y, +-z."""
    nonzero = [i for i in range(3) if axis[i] != 0.0]
    if len(nonzero) == 1:
        i = nonzero[0]
        if axis[i] > 0:
            return [], i
        return [(3 if i == 0 else 1, sp.pi)], i  # a half turn about an axis orthogonal to e_i
    theta = math.atan2(math.hypot(axis[0], axis[1]), axis[2])
    phi = math.atan2(axis[1], axis[0])
    return tidy([(3, sp.Float(phi)), (2, sp.Float(theta))]), 2


def mangle(name: str, prefix: str) -> str:
    """``name`` made an identifier (letters, digits, _, not reserved), deterministically: every other character
    becomes ``_``, a name not starting with a letter gets ``prefix_``, a reserved word a trailing ``_``."""
    s = re.sub(r"[^A-Za-z0-9_]", "_", name)
    if not s or not s[0].isalpha():
        s = f"{prefix}_{s}" if s else prefix
    if check_identifier(s) is not None:
        s += "_"
    return s


def identifier(name: str, used: set, prefix: str) -> str:
    """``name`` made a unique identifier: :func:`mangle`, then ``_2``, ``_3``, ... while taken (for the names the
    reader makes itself)."""
    s = mangle(name, prefix)
    base, k = s, 2
    while s in used:
        s, k = f"{base}_{k}", k + 1
    used.add(s)
    return s


class Names:
    """Identifiers made from a file's names: two distinct names never become one identifier (an error names both,
    through ``fail(where, message)``; ``where`` is the reader's place of a name, with its ``line``)."""

    def __init__(self, fail, kind: str, prefix: str):
        self.fail, self.kind, self.prefix = fail, kind, prefix  # fail(where, message) raises the reader's error
        self.taken: dict[str, tuple] = {}  # identifier -> (original name, element or None for the reader's own)

    def own(self, name: str) -> str:
        """A name the reader makes (the floating base's coordinates): taken as is."""
        self.taken[name] = (name, None)
        return name

    def claim(self, name: str, el) -> str:
        s = mangle(name, self.prefix)
        if s in self.taken:
            first, first_el = self.taken[s]
            if first_el is None:
                self.fail(el, f"{self.kind} name {name!r} becomes the identifier {s!r}, which the floating "
                                     f"base's coordinate {first!r} has; rename the {self.kind}")
            self.fail(el, f"{self.kind} names {first!r} (line {first_el.line}) and {name!r} both become the "
                                 f"identifier {s!r} in the generated code; rename one of them")
        self.taken[s] = (name, el)
        return s


@dataclass
class Place:
    """Where a link sits in its body: x_body = R x_link + t, R given as elementary rotations."""

    body: int
    rotation: list
    R: tuple  # 3x3, rows
    t: tuple


def floating_root(kind, names: Names, pair_name: str, prefix: str = "base") -> Pair:
    """The pair of a tree's root with the world: none (``kind`` False: fixed base), the Euler pair o1 o2 o3 theta4
    theta5 theta6 (True), or the free-flyer (``"quaternion"``: q holds the position and a unit quaternion, the
    velocities the root's own (v, w)); its coordinates named by ``names`` (:data:`FLOATING`, :data:`FREE_FLYER`,
    with ``prefix`` in place of ``base`` when given: several free roots, named after their joints)."""
    positions = ()

    def named(n):
        return n if prefix == "base" else prefix + n[len("base"):]

    if kind == "quaternion":
        coords = tuple(Coordinate(names.own(named(n)), code, pair_name) for n, code in FREE_FLYER)
        positions = tuple(names.own(named(n)) for n in FREE_FLYER_POSITIONS)
    elif kind:
        coords = tuple(Coordinate(names.own(named(n)), code, pair_name) for n, code in FLOATING)
    else:
        coords = ()
    zero = (sp.Integer(0),) * 3
    return Pair(pair_name, zero, (), coords, positions=positions)


def ball_names(joint: str) -> tuple:
    """(velocities, positions): the names a ball joint ``joint`` gives its three coordinates and its four entries of
    q, ``joint_wx joint_wy joint_wz`` and ``joint_qx joint_qy joint_qz joint_qw`` (before they are made
    identifiers)."""
    return tuple(f"{joint}_{n}" for n, _ in BALL), tuple(f"{joint}_{n}" for n in BALL_POSITIONS)


def link_table(place: dict, body_names: list, parts: dict, leaves) -> Links:
    """The model's links (kind ``"link"``) from each link's :class:`Place` (in tree order), the bodies' names (by
    index), each link's own inertial part and the links without a child link."""
    return Links("link", tuple(LinkFrame(link, body_names[p.body], p.R, p.t, parts.get(link))
                               for link, p in place.items()), tuple(leaves))


CODES = {"theta": ("theta4", "theta5", "theta6"), "o": ("o1", "o2", "o3")}  # a joint about / along e1, e2, e3
KINDS = ("theta", "o", "planar", "floating", "ball")  # the motions of :meth:`TreeBuilder.joint`


def motions(kind: str, i: int) -> tuple:
    """The codes of a joint of ``kind`` whose axis is e_(i+1) after :func:`align`: one rotation about it
    (``"theta"``) or translation along it (``"o"``); ``"planar"``: the translations along the two other axes, then
    the rotation about it (the plane normal to the axis, as URDF defines it); ``"floating"``: all six, o1 o2 o3
    theta4 theta5 theta6 (the book's Euler pair, as ``floating_root``), the axis unused; ``"ball"``: the three
    rotations theta4 theta5 theta6 of a ball pair (its coordinates the angular velocity in the child's axes, its
    positions a unit quaternion: :func:`ball_names`), the axis unused."""
    if kind == "ball":
        return CODES["theta"]
    if kind == "planar":
        return tuple(CODES["o"][j] for j in range(3) if j != i) + (CODES["theta"][i],)
    if kind == "floating":
        return CODES["o"] + CODES["theta"]
    return (CODES[kind][i],)


class TreeBuilder:
    """A tree of links (or bodies) built one at a time, parents first; format-neutral (URDF, YAML; MJCF next).

    Links: :meth:`root` starts the tree at a link, :meth:`joint` adds a movable joint and the body its child link
    becomes, :meth:`fixed` merges a link into its parent's body, :meth:`inertial` adds a link's mass to its body.
    Bodies given whole (YAML: each body is its own link): :meth:`body`.  Then :meth:`bodies` and :meth:`links`.
    ``rows`` (per body: name, parent, link, pair, link_rotation, parts) and ``place`` ({link: :class:`Place`}, in
    tree order) stay readable for a reader's own checks (the URDF reader judges the merged inertias on them)."""

    def __init__(self):
        self.rows: list = []
        self.place: dict = {}
        self.parts: dict = {}  # each link's own (mass, com, inertia about it) in its body's axes
        self.given: list = []  # bodies given whole (:meth:`body`)

    def root(self, link: str, name: str, pair: Pair) -> None:
        """A root link, the body ``name`` attached to the world by ``pair`` (:func:`floating_root`); a model of
        several trees (MJCF: several free bodies) calls it once per tree."""
        self.rows.append({"name": name, "parent": WORLD, "link": link, "pair": pair, "link_rotation": None,
                          "parts": []})
        self.place[link] = Place(len(self.rows) - 1, [], IDENTITY, ORIGIN)

    def _origin(self, parent: str, xyz) -> tuple:
        here = self.place[parent]
        return here, add(here.t, matvec(here.R, tuple(exact(x) for x in xyz)))

    def fixed(self, parent: str, child: str, xyz, rotation: list) -> None:
        """A fixed joint: ``child`` merged into the body of ``parent``, at ``xyz`` turned by ``rotation``
        (elementary rotations) in the parent link's frame; long chains fold into one roll-pitch-yaw."""
        here, t = self._origin(parent, xyz)
        turned = tidy(here.rotation + rotation)
        if len(turned) > MAX_ROTATIONS:
            turned = fold(turned)
            R = rotation_matrix(turned)
        else:  # R_here times the joint's own rotation: O(1) whatever the chain's length
            R = snapped(product(here.R, rotation_matrix(rotation))) if rotation else here.R
        self.place[child] = Place(here.body, turned, R, round_off(t))

    def joint(self, parent: str, child: str, body_name: str, joint_name: str, coordinate, xyz, rotation: list,
              axis, kind: str, anchor=None, offset=(), positions=()) -> Pair:
        """A movable joint ``joint_name`` from ``parent`` to ``child``, which becomes the body ``body_name``: its
        origin ``xyz`` and ``rotation`` in the parent link's frame, then the constant rotation R_a bringing e1, e2
        or e3 onto ``axis`` (:func:`align`), so that the joint is the elementary motion of ``kind`` (``"theta"``
        about, ``"o"`` along) (1.24)-(1.27), or the several motions of a ``"planar"`` or ``"floating"`` joint
        (:func:`motions`; a floating joint has no axis: ``axis`` None, no R_a); ``coordinate(code)`` makes each
        :class:`Coordinate`.  The child's body frame is its link frame turned by R_a (``link_rotation``).

        ``anchor`` (MJCF: a joint whose axis does not pass through the child's origin): the point of the axis in
        the child link's frame; the pair then sits at the anchor, and the child link's origin at -R_a^T anchor in
        the body, so that the link turns about (or slides along) the axis through the anchor.  ``offset``: the
        pair's :attr:`~.types.Pair.offset` (MJCF: -qpos0, so that the coordinate is MuJoCo's qpos).  ``positions``:
        a ball joint's (``kind`` ``"ball"``) four entries of q, the names of its unit quaternion qx qy qz qw
        (:attr:`~.types.Pair.positions`)."""
        here, t = self._origin(parent, xyz)
        if anchor is not None:
            turned = here.R if not rotation else snapped(product(here.R, rotation_matrix(rotation)))
            t = round_off(add(t, turn(turned, tuple(exact(x) for x in anchor))))
        if kind not in KINDS:
            raise ValueError(f"joint kind {kind!r}: expected one of {', '.join(KINDS)}")
        if (kind == "ball") != (len(positions) == 4):
            raise ValueError(f"joint {joint_name!r}: a ball joint, and only a ball joint, has the four positions of "
                             f"a unit quaternion (got kind {kind!r} with {len(positions)})")
        rotate, i = align(axis) if kind not in ("floating", "ball") else ([], 0)
        pair = Pair(joint_name, tuple(t), tuple(tidy(here.rotation + rotation + rotate)),
                    tuple(coordinate(code) for code in motions(kind, i)), offset=tuple(offset),
                    positions=tuple(positions))
        back = inverse(rotate)
        R = rotation_matrix(back)
        origin = ORIGIN
        if anchor is not None:
            origin = round_off(tuple(-x for x in turn(R, tuple(exact(x) for x in anchor))))
        self.rows.append({"name": body_name, "parent": self.rows[here.body]["name"], "link": child, "pair": pair,
                          "link_rotation": R if rotate else None, "parts": []})
        self.place[child] = Place(len(self.rows) - 1, back, R, origin)
        return pair

    def inertial(self, link: str, mass, com, inertia, rotation: list) -> None:
        """A link's mass, centre of mass and inertia about it (numbers of the file) in the link frame turned by
        ``rotation`` (its inertial frame), added to its body in the body's axes."""
        where = self.place[link]
        R = rotation_matrix(where.rotation + rotation) if rotation else where.R
        c = add(where.t, turn(where.R, tuple(exact(x) for x in com)))
        J = tuple(tuple(exact(x) for x in row) for row in inertia)
        if rotation or where.rotation:
            J = product(product(R, J), transpose(R))
        self.rows[where.body]["parts"].append((exact(mass), c, round_off(J)))
        self.parts[link] = self.rows[where.body]["parts"][-1]

    def body(self, body: Body) -> None:
        """A body given whole, its own link at its origin in its axes (YAML)."""
        self.given.append(body)

    def bodies(self, where=None) -> tuple:
        """The :class:`Body` list: the given bodies, or one per body of the links with the merged inertial parts
        (``where(link)``: the place in the file of the body's first link, for messages)."""
        if self.given:
            return tuple(self.given)
        return tuple(Body(name=row["name"], parent=row["parent"], pair=row["pair"], inertial=combine(row["parts"]),
                          where=where(row["link"]) if where else "", link_rotation=row["link_rotation"])
                     for row in self.rows)

    def links(self, leaves=None, declared=()) -> Links:
        """The model's :class:`Links`: the links with their places (``leaves``: those without a child link, in
        tree order), or for given bodies each body its own link; ``declared``: the frames the file names beside
        (YAML ``frames:``)."""
        if self.given:
            table = Links.of_bodies(self.given)
        else:
            table = link_table(self.place, [row["name"] for row in self.rows], self.parts, leaves)
        return Links(table.kind, table.frames, table.leaves, tuple(declared))


__all__ = ["BALL", "BALL_POSITIONS", "ball_names", "CODES", "KINDS", "motions", "FLOATING", "FREE_FLYER", "FREE_FLYER_POSITIONS", "MAX_ROTATIONS", "ANGLE_ROUND_OFF", "Names", "Place",
           "align", "angle", "floating_root", "fold", "identifier", "inverse", "link_table", "mangle", "matrix_rpy",
           "quaternion_rotations", "right_angle", "rotations", "rpy", "tidy", "TreeBuilder"]
