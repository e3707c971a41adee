"""MuJoCo's active equalities on the book's constraints (chapter 4) and couplings: what
:mod:`aggsym.model.readers.mjcf_reader` makes of ``eq_*`` and the fixed tendons (``tendon_*``, ``wrap_*``) of the compiled
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
* ``joint`` (joint1, joint2, polycoef y0 a1..a4) and ``tendon`` (tendon1, tendon2) on fixed tendons (every wrap
  of type joint: ``L = sum coef_j q_j``, qpos itself): MuJoCo's residual ``(L1 - L1_0) - P(L2 - L2_0)``, P the
  polynomial y0 + a1 x + ... + a4 x^4 (q_0: ``qpos0``, L_0: ``tendon_length0``; without joint2/tendon2 P = y0).
  Where every joint and tendon equality of the model ties one coordinate to another linearly (a2 = a3 = a4 = 0,
  exactly two coordinates in ``L1 - a1 L2``), none is tied twice or chained, and the model has neither connect
  nor weld constraints nor a free joint, they are :class:`~aggsym.model.types.Coupling` s (the later joint in
  MuJoCo's order follows the earlier one: ``q_f = k q_m + offset``; the coupled coordinate leaves q).  Otherwise
  every one of them is a joint-space constraint row (kind ``joint``, :class:`~aggsym.model.types.JointRow`: the
  residual above exactly, its Jacobian and rate term from :mod:`aggsym.mechanics.joint_space`), beside the
  connect and weld constraints, in the constrained dynamics of chapter 4; a row in which no coordinate appears
  constrains nothing (a warning, listed as left out).
* ``tendon`` on a spatial tendon (tendon1 and/or tendon2 ``<spatial>`` through sites and pulleys, no wrapping
  geom): always a joint-space row with the same residual, L the tendon's length (sum over its branches of the
  distances between consecutive sites over the branch's divisor, the path the MJCF reader's ``spatial_path`` reads for
  the passive forces; L_0 MuJoCo's ``tendon_length0``), ``JointRow.first_sites`` / ``second_sites`` its branches;
  J = dL1/dq - P'(x) dL2/dq and gamma = L1'' - P''(x) L2'^2 - P'(x) L2'' at qdd = 0
  (:class:`~aggsym.mechanics.spatial_tendons.SpatialLength`).  Never a coupling.

Refused with an error naming the equality: an equality on a spatial tendon wrapping around a geom, on a flex, on a
free or ball joint.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import sympy as sp

from .link_numbers import exact
from ..types import JOINT_ROW, WORLD, CONSTRAINT_KINDS, Constraint, Coupling, JointRow

CONNECT, WELD, JOINT, TENDON, FLEX = 0, 1, 2, 3, 4  # mjtEq
WRAP_JOINT, WRAP_PULLEY, WRAP_SITE = 1, 2, 3  # mjtWrap
SCALAR_JOINTS = (2, 3)  # slide, hinge


@dataclasses.dataclass(frozen=True)
class Spatial:
    """A spatial tendon's length in an equality: its name and branches (``SpatialTendon.branches``)."""

    name: str
    branches: tuple


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
        self.notes: dict = {}  # equality id -> what it became

    def note(self, e: int, entry: dict):
        self.notes[e] = entry

    @property
    def listing(self) -> list:
        """The manifest's entries in the file's order of the equalities."""
        return [self.notes[e] for e in sorted(self.notes)]

    def name(self, e: int) -> str:
        return self.reader.equality_name(e)

    def where(self, e: int, kind: str) -> str:
        return f'<equality> <{kind} name="{self.name(e)}">'

    def apply(self):
        """(constraints, couplings, listing): the active equalities as the model's constraints and couplings, and
        the manifest's list of what each equality became.  Joint and tendon equalities are couplings where every
        one of them can be (see :meth:`couplings_possible`), joint-space constraint rows otherwise."""
        m = self.m
        constraints, items = [], []
        for e in range(m.neq):
            kind = {CONNECT: "connect", WELD: "weld", JOINT: "joint", TENDON: "tendon", FLEX: "flex"}.get(
                int(m.eq_type[e]), str(int(m.eq_type[e])))
            if not m.eq_active0[e]:
                self.note(e, {"equality": self.name(e), "type": kind, "became": "nothing (inactive)"})
                continue
            where = self.where(e, kind)
            if kind in ("connect", "weld"):
                constraint = self.body_constraint(e, kind, where)
                if constraint is not None:
                    constraints.append(constraint)
            elif kind in ("joint", "tendon"):
                items.append((e, kind, where, self.forms(e, kind, where)))
            else:
                self.reader.fail(where, f"an active {kind} equality is not supported (connect, weld, joint and "
                                        f"tendon equalities are)")
        couplings = []
        if items and self.couplings_possible(items, constraints):
            couplings = [self.coupling(e, kind, f) for e, kind, _, f in items]
        else:
            for e, kind, where, f in items:
                row = self.joint_row(e, kind, where, f)
                if row is not None:
                    constraints.append(row)
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
            self.note(e, {"equality": self.name(e), "type": kind, "became": f"nothing ({why})"})
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
        self.note(e, {"equality": self.name(e), "type": kind, "became": became})
        return constraint

    # joint and tendon ---------------------------------------------------------------------------------------
    def scalar_joint(self, j: int, where: str) -> str:
        if int(self.m.jnt_type[j]) not in SCALAR_JOINTS:
            self.reader.fail(where, f"joint {self.reader.joint_name(j)!r} is a free or ball joint; a joint or "
                                    f"tendon equality on it is not supported")
        return self.reader.joint_name(j)

    def tendon_row(self, t: int, where: str):
        """{MuJoCo joint id: coefficient}: the fixed tendon t's length L = sum coef q (MuJoCo's qpos); a spatial
        tendon through sites and pulleys: its :class:`Spatial` path."""
        m = self.m
        name = self.reader.tendon_name(t)
        wraps = range(int(m.tendon_adr[t]), int(m.tendon_adr[t]) + int(m.tendon_num[t]))
        if any(int(m.wrap_type[w]) != WRAP_JOINT for w in wraps):
            if any(int(m.wrap_type[w]) not in (WRAP_SITE, WRAP_PULLEY) for w in wraps):
                self.reader.fail(where, f"tendon {name!r} is a spatial tendon wrapping around a geom; an equality on "
                                        f"it is not supported (fixed tendons and spatial ones through sites and "
                                        f"pulleys are)")
            return Spatial(name, self.reader.spatial_paths(t))
        row: dict = {}
        for w in wraps:
            j = int(m.wrap_objid[w])
            self.scalar_joint(j, where)
            row[j] = row.get(j, 0.0) + float(m.wrap_prm[w])
        return row

    def forms(self, e: int, kind: str, where: str) -> dict:
        """MuJoCo's residual of a joint or tendon equality as linear forms: ``first``, ``second`` ({joint id:
        coefficient}; second None without joint2/tendon2), ``ref1``, ``ref2`` and ``poly`` (y0 a1 a2 a3 a4):
        phi = (L1 - ref1) - P(L2 - ref2)."""
        m = self.m
        data = np.array(m.eq_data[e], dtype=float)
        o1, o2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])

        def form(o):
            if kind == "tendon":
                return self.tendon_row(o, where)
            self.scalar_joint(o, where)
            return {o: 1.0}

        def ref(o):
            return float(m.tendon_length0[o]) if kind == "tendon" else float(m.qpos0[m.jnt_qposadr[o]])

        return {"first": form(o1), "second": form(o2) if o2 >= 0 else None, "ref1": ref(o1),
                "ref2": ref(o2) if o2 >= 0 else 0.0, "poly": tuple(float(x) for x in data[:5])}

    @staticmethod
    def combined(f: dict) -> tuple:
        """(row {joint id: coefficient}, constant): the linear case's ``sum r q + constant`` (a2 = a3 = a4 = 0)."""
        y0, a1 = f["poly"][:2]
        row = dict(f["first"])
        constant = -f["ref1"] - y0
        if f["second"] is not None:
            for j, c in f["second"].items():
                row[j] = row.get(j, 0.0) - a1 * c
            constant += a1 * f["ref2"]
        return {j: c for j, c in row.items() if c != 0}, constant

    def as_coupling(self, f: dict):
        """The equality as a coupling (follower, master, multiplier, offset), or None when it is not one coordinate
        following another (a nonlinear polynomial, or a row on one coordinate or more than two)."""
        if isinstance(f["first"], Spatial) or isinstance(f["second"], Spatial):
            return None
        if f["second"] is not None and any(f["poly"][2:]):
            return None
        row, constant = self.combined(f)
        joints = sorted(row)
        if len(joints) != 2:
            return None
        master, follower = joints  # r_m q_m + r_f q_f + constant = 0
        multiplier = float(-row[master] / row[follower]) + 0.0
        offset = float(-constant / row[follower]) + 0.0  # (+ 0.0: no negative zero)
        return (self.coordinate_of[self.reader.joint_name(follower)],
                self.coordinate_of[self.reader.joint_name(master)], multiplier, offset)

    def couplings_possible(self, items, constraints) -> bool:
        """Whether every joint and tendon equality can be a coupling: each ties one coordinate to another, none is
        coupled twice or chained, and the model has no connect or weld constraint and no free or ball joint."""
        if constraints or any(b.pair.quaternion for b in self.model.bodies):
            return False
        ties = [self.as_coupling(f) for _, _, _, f in items]
        if any(t is None for t in ties):
            return False
        followers = [t[0] for t in ties]
        return len(set(followers)) == len(followers) and not set(followers) & {t[1] for t in ties}

    def coupling(self, e: int, kind: str, f: dict) -> Coupling:
        follower, master, multiplier, offset = self.as_coupling(f)
        coupling = Coupling(follower, master, multiplier, offset)
        self.note(e, {"equality": self.name(e), "type": kind,
                             "became": f"coupling {coupling.coordinate} = {multiplier!r} * {coupling.master} + "
                                       f"{offset!r}"})
        return coupling

    def joint_row(self, e: int, kind: str, where: str, f: dict):
        """The equality as a joint-space constraint row (kind ``joint``), or None (with a warning) when no
        coordinate appears in it."""
        def terms(form):
            if isinstance(form, Spatial):
                return ()
            return tuple((self.coordinate_of[self.reader.joint_name(j)], exact(c)) for j, c in sorted(form.items())
                         if c != 0)

        first = terms(f["first"])
        second = terms(f["second"]) if f["second"] is not None else ()
        sites = tuple(g.branches if isinstance(g, Spatial) else () for g in (f["first"], f["second"]))
        spatial = isinstance(f["first"], Spatial) or isinstance(f["second"], Spatial)
        poly = f["poly"] if second or sites[1] else (f["poly"][0], 0.0, 0.0, 0.0, 0.0)
        if not spatial and (not second or not any(poly[2:])):  # linear: the combined row decides
            row, _ = self.combined(f)
            if not row:
                why = "no coordinate appears in its row (its coefficients cancel): it constrains no motion"
                self.reader.warn(where, f"the {kind} equality: {why}; left out")
                self.note(e, {"equality": self.name(e), "type": kind, "became": f"nothing ({why})"})
                return None
        row = JointRow(first=first, second=second, reference=(exact(f["ref1"]), exact(f["ref2"])),
                       polynomial=tuple(exact(a) for a in poly), first_sites=sites[0], second_sites=sites[1])
        constraint = Constraint(name=self.reader.ids_constraint(self.name(e)), body="", point=(), rows=(JOINT_ROW,),
                                kind="joint", source=str(self.reader.file), path=where, joint_row=row)

        def shown_of(form, named):
            if isinstance(form, Spatial):
                return f"length of spatial tendon {form.name!r}"
            return " + ".join(f"{float(c)!r} {name}" for name, c in named)

        shown = shown_of(f["first"], first)
        became = f"constraint {constraint.name!r} (joint-space row: ({shown}) - {f['ref1']!r}"
        if second or sites[1]:
            shown2 = shown_of(f["second"], second)
            became += f" - P(({shown2}) - {f['ref2']!r}), P with polycoef {' '.join(repr(a) for a in poly)})"
        else:
            became += f" - {poly[0]!r} = 0)"
        self.note(e, {"equality": self.name(e), "type": kind, "became": became})
        return constraint


def with_equalities(reader, model):
    """The model with its active equalities as constraints and couplings, and ``meta["mjcf"]["equalities"]``."""
    constraints, couplings, listing = Equalities(reader, model).apply()
    meta = dict(model.meta)
    meta["mjcf"] = dict(meta["mjcf"], equalities=listing)
    return dataclasses.replace(model, constraints=constraints, couplings=couplings, meta=meta)


__all__ = ["with_equalities", "Equalities"]
