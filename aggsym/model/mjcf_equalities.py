"""MuJoCo's active equalities on the book's constraints (chapter 4) and couplings: what
:mod:`aggsym.model.mjcf_reader` makes of ``eq_*`` and the fixed tendons (``tendon_*``, ``wrap_*``) of the compiled
model.

MuJoCo's conventions (checked against its ``efc_pos``: the residual rows it stabilizes):

* ``connect`` (body1, body2): the point ``eq_data[0:3]`` of body1 (body1's frame) coincides with the point
  ``eq_data[3:6]`` of body2 (the compiler puts it where body1's anchor is at qpos0).  It becomes a
  :class:`~aggsym.model.types.Constraint` of kind ``point`` (rows o1 o2 o3): body1's point against a reference
  frame on body2 at its point, with body2's axes (the multiplier is the force body2 exerts on body1, in body2's
  axes).
* ``weld`` (body1, body2): the frame at ``eq_data[3:6]`` of body1 with the axes R1 R(``eq_data[6:10]``) (relpose)
  coincides with the frame at ``eq_data[0:3]`` (anchor) of body2 with body2's axes; MuJoCo scales the rotational
  residual by ``torquescale`` (``eq_data[10]``), which leaves the hard constraint unchanged (its multiplier's
  moment is in the unscaled rows here).  It becomes a constraint of kind ``weld`` (six rows: the relative motion of
  body1's frame against body2's, along body2's axes), with ``orientation`` the relative orientation at which the
  rotational residual is zero.  With ``torquescale`` 0 MuJoCo's rotational rows vanish: a ``point`` constraint.
  A body welded to the world is the world (the medium); when body1 is, the two sides swap.  Two ends on one
  rigid body (both welded to the world, or one welded to the other) constrain no motion: a warning, and the
  manifest lists the equality as left out.
* Between sites (``site1``, ``site2``): site1's frame coincides with site2's (``connect``: their origins), as
  MuJoCo's residual (site positions, and neg(q_site2) q_site1) says; the reference axes are site2's.
* ``joint`` (joint1, joint2, polycoef y0 a1..a4): ``q1 - q1_0 = y0 + a1 (q2 - q2_0) + a2 (q2 - q2_0)^2 + ...``
  (q_0: ``qpos0``).  Linear (a2 = a3 = a4 = 0, a1 != 0): a :class:`~aggsym.model.types.Coupling`
  ``q1 = a1 q2 + (q1_0 + y0 - a1 q2_0)``.
* ``tendon`` on fixed tendons (every wrap of type joint: ``L = sum coef_j q_j``, qpos itself), polycoef as above on
  ``L - tendon_length0``: linear in the joints, ``sum r_j q_j + c = 0``; with exactly two joints it is a coupling
  (the later joint in MuJoCo's order follows the earlier one).

Refused with an error naming the equality: a nonlinear polynomial, a joint or tendon equality that fixes one
coordinate or ties more than two (aggsym's constraints are motions of body points, its couplings one coordinate
following another: a general joint-space row has no place yet), an equality on a spatial tendon, on a flex, on a free or ball joint, couplings that chain or collide (a coordinate coupled
twice, or coupled and master), constraints beside couplings in one model (not supported together yet), and
couplings in a model with a free joint (not yet).
"""
from __future__ import annotations

import dataclasses

import numpy as np
import sympy as sp

from .types import WORLD, Constraint, Coupling, CONSTRAINT_KINDS

CONNECT, WELD, JOINT, TENDON, FLEX = 0, 1, 2, 3, 4  # mjtEq
WRAP_JOINT = 1  # mjtWrap
SCALAR_JOINTS = (2, 3)  # slide, hinge


def _quat_matrix(w, x, y, z) -> np.ndarray:
    """The rotation matrix of a unit quaternion (w, x, y, z) (columns: the rotated frame's axes)."""
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _numbers(v) -> tuple:
    return tuple(sp.Float(float(x), 17) for x in v)


def _matrix(R) -> tuple:
    return tuple(tuple(sp.Float(float(x), 17) for x in row) for row in R)


class Equalities:
    """Builds the constraints and couplings of one compiled model (``reader``: the MJCF reader, for names and
    errors) on the model the tree gave."""

    def __init__(self, reader, model):
        self.reader, self.m, self.mj, self.model = reader, reader.m, reader.mj, model
        self.frames = {f.name: f for f in model.link_table.frames}
        self.coordinate_of = {c.joint: c.name for c in model.pair_coordinates}
        roots = {b.name for b in model.bodies if b.parent == WORLD and not b.pair.coordinates}
        self.world_bodies = roots  # the fixed root (worldbody): the world itself
        self.listing: list = []

    def name(self, e: int) -> str:
        return self.reader.equality_name(e)

    def where(self, e: int, kind: str) -> str:
        return f'<equality> <{kind} name="{self.name(e)}">'

    def apply(self):
        """(constraints, couplings, listing): the active equalities as the model's constraints and couplings, and
        the manifest's list of what each equality became."""
        m = self.m
        constraints, couplings = [], []
        for e in range(m.neq):
            kind = {CONNECT: "connect", WELD: "weld", JOINT: "joint", TENDON: "tendon", FLEX: "flex"}.get(
                int(m.eq_type[e]), str(int(m.eq_type[e])))
            if not m.eq_active0[e]:
                self.listing.append({"equality": self.name(e), "type": kind, "became": "nothing (inactive)"})
                continue
            where = self.where(e, kind)
            if kind in ("connect", "weld"):
                constraint = self.body_constraint(e, kind, where)
                if constraint is not None:
                    constraints.append(constraint)
            elif kind in ("joint", "tendon"):
                couplings.append(self.coupling(e, kind, where))
            else:
                self.reader.fail(where, f"an active {kind} equality is not supported (connect, weld, and joint or "
                                        f"fixed-tendon equalities that tie one coordinate to another are)")
        self.check_couplings(couplings)
        if couplings and any(b.pair.quaternion for b in self.model.bodies):
            self.reader.fail("<equality>", "couplings (joint or tendon equalities) in a model with a free joint or a "
                                           "ball joint are not supported yet")
        if constraints and couplings:
            self.reader.fail("<equality>", "loop or weld constraints (connect, weld) beside couplings (joint or tendon "
                                           "equalities) in one model are not supported together yet")
        return tuple(constraints), tuple(couplings), self.listing

    # connect and weld -------------------------------------------------------------------------------------
    def side(self, b: int):
        """(tree body or WORLD, R, t): MuJoCo body b's frame in the aggsym body it belongs to."""
        if b == 0 and "world" not in self.frames and self.reader.body_name(0) not in self.frames:
            return WORLD, np.eye(3), np.zeros(3)
        frame = self.frames[self.reader.body_name(b)]
        R = np.eye(3) if frame.rotation is None else np.array([[float(x) for x in r] for r in frame.rotation])
        t = np.zeros(3) if frame.translation is None else np.array([float(x) for x in frame.translation])
        body = WORLD if frame.body in self.world_bodies else frame.body
        return body, R, t

    def body_constraint(self, e: int, kind: str, where: str) -> Constraint:
        m = self.m
        data = np.array(m.eq_data[e], dtype=float)
        o1, o2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
        if int(m.eq_objtype[e]) == int(self.mj.mjtObj.mjOBJ_SITE):  # site1's frame on site2's (connect: origins)
            ends = [(int(m.site_bodyid[o]), np.array(m.site_pos[o], dtype=float), _quat_matrix(*m.site_quat[o]))
                    for o in (o1, o2)]
        elif kind == "connect":  # body1's point data[0:3] on body2's point data[3:6]
            ends = [(o1, data[0:3], np.eye(3)), (o2, data[3:6], np.eye(3))]
        else:  # body1's frame (data[3:6], relpose) on body2's frame (anchor data[0:3], body2's axes)
            ends = [(o1, data[3:6], _quat_matrix(*data[6:10])), (o2, data[0:3], np.eye(3))]
        b1, b2 = ends[0][0], ends[1][0]
        rows = CONSTRAINT_KINDS["point"] if kind == "connect" or data[10] == 0 else CONSTRAINT_KINDS["weld"]
        placed = []
        for b, point, axes in ends:
            body, R, t = self.side(b)
            placed.append((body, R @ point + t, R @ axes))  # the end's point and axes in its aggsym body
        if placed[0][0] == placed[1][0]:  # no coordinate moves one end against the other: J = 0, no force
            why = (f"joins two points of one rigid body ({self.reader.body_name(b1)!r} and "
                   f"{self.reader.body_name(b2)!r} move together): it constrains no motion and is left out")
            self.reader.warn(where, f"the {kind} equality {why}")
            self.listing.append({"equality": self.name(e), "type": kind, "became": f"nothing ({why})"})
            return None
        if placed[0][0] == WORLD:
            placed.reverse()
        (body, point, axes1), (medium, at, axes2) = placed
        # reference axes: the medium end's axes; the rotational residual vanishes where the body end's axes are
        # those: body's axes in the reference axes = axes1^T, so C0 = axes1 (see constraints.residual)
        constraint = Constraint(
            name=self.reader.ids_constraint(self.name(e)), body=body, point=_numbers(point), rows=rows,
            medium=medium, at=_numbers(at), medium_axes=_matrix(axes2), kind="point" if len(rows) == 3 else "weld",
            source=str(self.reader.file), path=where, orientation=_matrix(axes1) if len(rows) == 6 else None)
        became = f"constraint {constraint.name!r} ({constraint.kind}: {body} on {medium})"
        if kind == "weld" and len(rows) == 3:
            became += "; torquescale 0: no rotational rows"
        elif kind == "weld" and data[10] != 1:
            became += f"; torquescale {data[10]:g} scales only MuJoCo's soft rows, not the hard constraint"
        self.listing.append({"equality": self.name(e), "type": kind, "became": became})
        return constraint

    # joint and tendon ---------------------------------------------------------------------------------------
    def scalar_joint(self, j: int, where: str) -> str:
        if int(self.m.jnt_type[j]) not in SCALAR_JOINTS:
            self.reader.fail(where, f"joint {self.reader.joint_name(j)!r} is a free or ball joint; a joint or "
                                    f"tendon equality on it is not supported")
        return self.reader.joint_name(j)

    def tendon_row(self, t: int, where: str) -> dict:
        """{MuJoCo joint id: coefficient}: the fixed tendon t's length L = sum coef q (MuJoCo's qpos)."""
        m = self.m
        name = self.reader.tendon_name(t)
        row: dict = {}
        for w in range(int(m.tendon_adr[t]), int(m.tendon_adr[t]) + int(m.tendon_num[t])):
            if int(m.wrap_type[w]) != WRAP_JOINT:
                self.reader.fail(where, f"tendon {name!r} is a spatial tendon (it wraps sites or geoms); an equality "
                                        f"on it is not supported (fixed tendons are)")
            j = int(m.wrap_objid[w])
            self.scalar_joint(j, where)
            row[j] = row.get(j, 0.0) + float(m.wrap_prm[w])
        return row

    def coupling(self, e: int, kind: str, where: str) -> Coupling:
        m = self.m
        data = np.array(m.eq_data[e], dtype=float)
        y0, a1 = data[0], data[1]
        if np.any(data[2:5]):
            self.reader.fail(where, f"a {kind} equality with a nonlinear polynomial (polycoef {' '.join(f'{x:g}' for x in data[:5])}) "
                                    f"is not supported (only its linear case y0 + a1 x becomes a coupling)")
        o1, o2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
        if kind == "joint":  # q1 - q1_0 - y0 - a1 (q2 - q2_0) = 0
            self.scalar_joint(o1, where)
            row = {o1: 1.0}
            constant = -float(m.qpos0[m.jnt_qposadr[o1]]) - y0
            if o2 >= 0:
                self.scalar_joint(o2, where)
                row[o2] = row.get(o2, 0.0) - a1
                constant += a1 * float(m.qpos0[m.jnt_qposadr[o2]])
        else:  # L1 - L1_0 - y0 - a1 (L2 - L2_0) = 0
            row = self.tendon_row(o1, where)
            constant = -float(m.tendon_length0[o1]) - y0
            if o2 >= 0:
                for j, c in self.tendon_row(o2, where).items():
                    row[j] = row.get(j, 0.0) - a1 * c
                constant += a1 * float(m.tendon_length0[o2])
        joints = sorted(j for j, c in row.items() if c != 0)
        names = [self.reader.joint_name(j) for j in joints]
        if len(joints) != 2:
            what = ("fixes the coordinate of joint " + repr(names[0]) if len(joints) == 1 else
                    "ties no coordinate" if not joints else f"ties {len(joints)} coordinates ({', '.join(names)})")
            self.reader.fail(where, f"the {kind} equality {what}: a linear row in joint space, which aggsym's "
                                    f"constraints (motions of body points) and couplings (one coordinate following "
                                    f"another) cannot hold yet")
        master, follower = joints  # r_m q_m + r_f q_f + constant = 0
        multiplier = float(-row[master] / row[follower]) + 0.0
        offset = float(-constant / row[follower]) + 0.0  # (+ 0.0: no negative zero)
        coupling = Coupling(self.coordinate_of[self.reader.joint_name(follower)],
                            self.coordinate_of[self.reader.joint_name(master)], multiplier, offset)
        self.listing.append({"equality": self.name(e), "type": kind,
                             "became": f"coupling {coupling.coordinate} = {multiplier!r} * {coupling.master} + "
                                       f"{offset!r}"})
        return coupling

    def check_couplings(self, couplings):
        seen: dict = {}
        masters = {c.master for c in couplings}
        for c in couplings:
            if c.coordinate in seen:
                self.reader.fail("<equality>", f"coordinate {c.coordinate!r} is tied twice by equalities (to "
                                               f"{seen[c.coordinate]!r} and {c.master!r}); not supported")
            seen[c.coordinate] = c.master
            if c.coordinate in masters:
                self.reader.fail("<equality>", f"coordinate {c.coordinate!r} follows {c.master!r} and is followed by "
                                               f"another: chained couplings are not supported")


def with_equalities(reader, model):
    """The model with its active equalities as constraints and couplings, and ``meta["mjcf"]["equalities"]``."""
    constraints, couplings, listing = Equalities(reader, model).apply()
    meta = dict(model.meta)
    meta["mjcf"] = dict(meta["mjcf"], equalities=listing)
    return dataclasses.replace(model, constraints=constraints, couplings=couplings, meta=meta)


__all__ = ["with_equalities", "Equalities"]
