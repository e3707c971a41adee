"""The MJCF reader: MuJoCo's own compiler reads the XML, this reader maps the compiled ``MjModel`` onto the book's
bodies and pairs (1.24)-(1.27) through :class:`~aggsym.model.readers.builder.TreeBuilder`.

Nothing of MJCF's meaning is re-implemented: defaults and classes, ``<include>``, ``compiler angle/eulerseq``,
``fromto``, inertias from geoms, ``settotalmass`` and ``boundmass`` are what MuJoCo compiled.  The file is first
screened (:mod:`aggsym.model.readers.mjcf_source`: size, entities, includes outside the model's folder); a file MuJoCo's
compiler refuses is a :class:`~aggsym.errors.ModelError` carrying the compiler's message.

The mapping
-----------
* Bodies in MuJoCo's order (depth first).  A body's frame in its parent at qpos0 is ``body_pos`` then
  ``body_quat``; its mass ``body_mass`` at ``body_ipos`` with the inertia R(``body_iquat``) diag(``body_inertia``)
  R^T about it.  A body without joints is welded to its parent (merged into its parent's body, as a URDF fixed
  joint); the bodies welded to the world are merged into one massless fixed root, ``worldbody``, present when some
  child of the world is not a free body.
* ``hinge`` and ``slide`` joints: one pair each (theta about / o along the joint's axis, :func:`~.builder.align`),
  placed at the joint's anchor ``jnt_pos`` (MuJoCo turns the body about the axis through the anchor), with the
  pair's offset -``qpos0``: **q is MuJoCo's qpos** entry for entry.  Several joints in one body are applied in
  order, as MuJoCo does: each but the last moves a massless intermediate body named ``<body>_<joint>``.
* ``free`` joint (only on a child of the world, MuJoCo's rule): the root of a tree of its own, aggsym's quaternion
  free-flyer, its coordinates named after the joint: positions ``J_x J_y J_z J_qx J_qy J_qz J_qw``, velocities
  ``J_vx J_vy J_vz J_wx J_wy J_wz``.  Several free bodies are several trees of one model.  Conversion from MuJoCo
  (qpos, qvel of the joint: x, y, z, qw, qx, qy, qz and v_world, w_body; R the body's rotation):
  q = (x, y, z, qx, qy, qz, qw); v = R^T v_world, w = w_body; generalized forces f_lin = R^T f_world (torques
  as they are); accelerations dv/dt = R^T a_world - w x v (a_world = d v_world / dt = MuJoCo's qacc).
* ``ball`` joint: the ball pair (:attr:`~aggsym.model.types.Pair.positions`, Pinocchio's spherical joint) at the
  joint's anchor, its coordinates named after the joint: positions ``J_qx J_qy J_qz J_qw`` (MuJoCo's qpos holds
  ``qw qx qy qz``: the same unit quaternion reordered), velocities ``J_wx J_wy J_wz``, MuJoCo's qvel entry for
  entry (the angular velocity in the body's axes), and so are its forces and accelerations.  It must be the last
  joint of its body (MuJoCo then turns the body's frame by it last, and its velocity is in the body's axes); a
  stiffness on it (a spring on the quaternion) is refused.  Its ``range`` (a cone) is listed with the limits.
* What MuJoCo adds (runtime parameters, defaults from the compiled model; only where the model's value is not
  zero, so that zeros fold):  ``armature_<coordinate>`` (``dof_armature``, on A's diagonal:
  ``Model.dof_armature``), ``damping_<coordinate>`` (``dof_damping``, the viscous force D qd on the left:
  ``Model.damping``), ``stiffness_<coordinate>`` and ``springref_<coordinate>`` (``jnt_stiffness`` and
  ``qpos_spring``: an elastic pair, C (q - q0) of (2.27)), and always ``gravity_x gravity_y gravity_z``
  (``opt.gravity``, 0 when ``<flag gravity="disable">``).  ``<flag spring/damper="disable">`` leave those out.
  ``meta["mjcf"]["qpos0"]`` (the manifest's ``mjcf.qpos0``): the file's configuration, MuJoCo's qpos0 (each
  hinge's and slide's ``ref``, the free bodies' poses) as aggsym's q, the pose to start a simulation from.
  Fixed tendons with a ``stiffness`` or ``damping`` (``Model.tendons``, :mod:`aggsym.mechanics.joint_space`):
  ``tendon_stiffness_<tendon>``, ``tendon_springlength_<tendon>`` (``tendon_lengthspring``; a dead band lower <
  upper: ``tendon_springlower_<tendon>``, ``tendon_springupper_<tendon>``), ``tendon_damping_<tendon>``: the force
  ``f = -k s - d L'`` along the tendon (s the stretch beyond the rest length or dead band), ``-c f`` on the left;
  ``tendon_armature_<tendon>`` (``tendon_armature``): an inertia a along a fixed tendon, a c c^T in A
  (:mod:`aggsym.mechanics.tendon_armature`).
  Forward and inverse dynamics then include the passive forces as MuJoCo's ``qacc`` and ``qfrc_passive`` do:
  A qdd + b + g + C (q - q0) + D qd + t = tau (``passive_forces`` gives -(C (q - q0) + D qd + t), MuJoCo's sign).
  Gravity compensation (``gravcomp`` s on a body, ``Model.gravcomp``, :mod:`aggsym.mechanics.gravcomp`): the runtime
  parameter ``gravcomp_<body>`` (default s) lifts that fraction of the body's weight at its centre of mass, among
  the passive forces as in MuJoCo's ``qfrc_passive`` (g(q) keeps the whole weight, as ``qfrc_bias`` does); the
  potential energy holds the lift's.  ``actuatorgravcomp`` (the lift routed through the actuators) is refused.
* ``frictionloss`` (a constraint in MuJoCo, not a smooth force): listed per joint and tendon in the manifest; with
  ``frictionloss="coulomb"`` (``--frictionloss coulomb``, on request) taken as Coulomb friction: ``F sign(qd)`` on
  the left (``friction_<coordinate>``, ``Model.coulomb``) and ``-F sign(L')`` along a fixed tendon
  (``tendon_friction_<tendon>``), in forward and inverse dynamics and ``passive_forces``; the model is then not
  conservative.  Refused then on a free joint (MuJoCo's friction acts on the world-axes velocity there).
* Not in the equations, listed in ``model.meta["mjcf"]`` (and the manifest): ``frictionloss`` (unless asked for as
  above), joint and tendon limits (also on the coordinates' limits), contacts, actuators (with their joint and
  gear), tendons that change nothing but constraints or actuation, inactive equalities.  Fluid forces
  (``density``, ``viscosity``, ``wind``) are passive forces: MuJoCo's inertia-box model (``Model.fluid``) and its
  ellipsoid model on the geoms with ``fluidshape="ellipsoid"`` (``Model.fluid_ellipsoids``).  Active equalities
  (:mod:`aggsym.model.readers.mjcf_equalities`): ``connect`` and ``weld`` become constraints
  (``model.constraints``), ``joint`` and fixed-tendon equalities couplings (``model.couplings``) or joint-space constraint rows, each listed in ``meta["mjcf"]["equalities"]``; the others
  are refused there by name.  Spatial tendons through sites and pulleys with a stiffness or damping
  (``Model.spatial_tendons``, :mod:`aggsym.mechanics.spatial_tendons`): the same parameters as a fixed tendon's.
  Refused with an error naming them, since they would change the equations: spatial tendons wrapping around geoms
  with a stiffness or damping, spatial tendons with armature, polynomial or yielding tendon springs, flexes,
  gravity compensation routed through the actuators, actuators with damping or armature, polynomial damping or
  stiffness.
* ``model.links`` (kind ``"link"``): every MuJoCo body (``world`` included when ``worldbody`` is there) and every
  site (a site sharing a body's name is listed as ``site:<name>``) as a frame on the body it belongs to, for
  ``--frames``, ``--payload``, ``--inertial-parameters`` and ``--constraints``; the leaves are the moving bodies
  without a child body.  Unnamed bodies, joints and sites are named ``body<id>``, ``joint<id>``, ``site<id>``
  (with ``_`` appended while an element of that kind has the name).
"""
from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path

import numpy as np
import sympy as sp

from ...errors import ModelError, ModelWarning
from .builder import TreeBuilder, ball_names, floating_root, identifier, link_table, quaternion_rotations
from .link_numbers import add, rotation_matrix, turn
from ..transforms.frames import default_frames
from .link_numbers import exact
from .mjcf_equalities import WRAP_JOINT, with_equalities
from .mjcf_source import screen
from ..types import (WORLD, Coordinate, FluidBox, FluidEllipsoid, JointLimits, Links, Model, Parameter, SpatialTendon,
                     Tendon)

FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3  # mjtJoint
KINDS = {HINGE: "theta", SLIDE: "o"}
JOINT_TYPES = {FREE: "free", BALL: "ball", SLIDE: "slide", HINGE: "hinge"}
DISABLE_FRICTIONLOSS, DISABLE_SPRING, DISABLE_DAMPER, DISABLE_GRAVITY = 4, 32, 64, 128  # mjtDisableBit
FRICTIONLOSS_OPTIONS = ("list", "coulomb")
WORLD_BODY = "worldbody"
WRAP_PULLEY, WRAP_SPHERE, WRAP_CYLINDER = 2, 4, 5  # mjtWrap (WRAP_JOINT: 1, WRAP_SITE: 3)
GEOM_SPHERE, GEOM_CAPSULE, GEOM_CYLINDER = 2, 3, 5  # mjtGeom
EQUALITY_TYPES = {0: "connect", 1: "weld", 2: "joint", 3: "tendon", 4: "flex"}
CONVENTION = (
    "q is MuJoCo's qpos and qd its qvel entry for entry, except for a free joint J: q holds J_x J_y J_z "
    "J_qx J_qy J_qz J_qw (MuJoCo: x y z qw qx qy qz) and qd the body's own velocity J_vx J_vy J_vz (body axes: "
    "v = R^T v_world, R the body's rotation) and J_wx J_wy J_wz (body axes, as MuJoCo's); a generalized force "
    "on its linear part is R^T f_world, and its acceleration R^T a_world - w x v (a_world: MuJoCo's qacc); and a ball "
    "joint J: q holds J_qx J_qy J_qz J_qw (MuJoCo: qw qx qy qz), qd its J_wx J_wy J_wz as MuJoCo's qvel (body axes)")


def _frame_in(place, pos, quat) -> tuple:
    """(axes, origin) of a frame given in a MuJoCo body (its ``pos``, ``quat``: an inertial frame, a geom's) in the
    axes of the aggsym body ``place`` puts that MuJoCo body in: the axes' columns, the origin."""
    w, x, y, z = (float(v) for v in quat)
    turned = rotation_matrix(place.rotation + (quaternion_rotations(x, y, z, w)
                                               if (w, x, y, z) != (1.0, 0.0, 0.0, 0.0) else []))
    origin = add(place.t, turn(place.R, tuple(exact(float(v)) for v in pos)))
    return tuple(map(tuple, turned)), tuple(origin)


def _name(m, mujoco, kind, i: int, prefix: str) -> str:
    """The element's name, or ``<prefix><id>`` when it has none (``_`` appended while a named element of its kind
    has that name: names of one kind stay distinct)."""
    name = mujoco.mj_id2name(m, kind, i)
    if name:
        return name
    name = f"{prefix}{i}"
    while mujoco.mj_name2id(m, kind, name) >= 0:
        name += "_"
    return name


class _Ids:
    """Identifiers for the generated code, made unique deterministically (``identifier``); the file's names stay
    on the coordinates (``Coordinate.joint``) and links."""

    def __init__(self):
        self.used: set = set()

    def own(self, name: str) -> str:
        return identifier(name, self.used, "q")


class _Reader:
    def __init__(self, file: Path, m, mujoco, frictionloss: str = "list"):
        self.file, self.m, self.mj = file, m, mujoco
        self.frictionloss = frictionloss
        self.coulomb = frictionloss == "coulomb" and not m.opt.disableflags & DISABLE_FRICTIONLOSS
        self.warnings: list[str] = []
        self.constraint_ids: set = set()

    def fail(self, where: str, message: str):
        raise ModelError(self.file, where, message)

    def warn(self, where: str, message: str):
        text = str(ModelError(self.file, where, message))
        self.warnings.append(text)
        warnings.warn(text, ModelWarning, stacklevel=3)

    # names -----------------------------------------------------------------------------------------------
    def body_name(self, i):
        return _name(self.m, self.mj, self.mj.mjtObj.mjOBJ_BODY, i, "body")

    def joint_name(self, j):
        return _name(self.m, self.mj, self.mj.mjtObj.mjOBJ_JOINT, j, "joint")

    def geom_name(self, g):
        return _name(self.m, self.mj, self.mj.mjtObj.mjOBJ_GEOM, g, "geom")

    def tendon_name(self, t):
        return _name(self.m, self.mj, self.mj.mjtObj.mjOBJ_TENDON, t, "tendon")

    def equality_name(self, e):
        return _name(self.m, self.mj, self.mj.mjtObj.mjOBJ_EQUALITY, e, "equality")

    def ids_constraint(self, name: str) -> str:
        """A constraint's identifier (distinct from the others')."""
        return identifier(name, self.constraint_ids, "equality")

    # what the equations cannot hold ------------------------------------------------------------------------
    def refuse_unsupported(self):
        m, mj = self.m, self.mj
        for j in range(m.njnt):
            b = int(m.jnt_bodyid[j])
            where = f'<joint name="{self.joint_name(j)}"> (body {self.body_name(b)!r})'
            if m.jnt_type[j] == BALL:
                if j != int(m.body_jntadr[b]) + int(m.body_jntnum[b]) - 1:
                    self.fail(where, "a ball joint followed by other joints in one body is not supported (MuJoCo "
                                     "gives its velocity in the axes the later joints turn); make it the body's "
                                     "last joint")
                if m.jnt_stiffness[j] != 0 and not m.opt.disableflags & DISABLE_SPRING:
                    self.fail(where, f"stiffness={m.jnt_stiffness[j]:g} on a ball joint (a spring on the "
                                     f"quaternion) is not supported")
            if m.jnt_type[j] == FREE:
                if m.body_parentid[b] != 0:
                    self.fail(where, "a free joint below the top level; a free joint must be on a child of the "
                                     "world")
                if m.body_jntnum[b] != 1:
                    self.fail(where, "a free joint beside other joints in one body; give the body the free joint "
                                     "alone")
                if m.jnt_stiffness[j] != 0 and not m.opt.disableflags & DISABLE_SPRING:
                    self.fail(where, f"stiffness={m.jnt_stiffness[j]:g} on a free joint (a spring on the pose) is "
                                     f"not supported")
            if np.any(m.jnt_stiffnesspoly[j]):
                self.fail(where, "a polynomial stiffness (stiffnesspoly) is not supported (stiffness is)")
            if hasattr(m, "jnt_springyield") and np.any(m.jnt_springyield[j]):
                self.fail(where, "a spring with a yield (springyield) is not supported")
        for i in range(m.nv):
            if np.any(m.dof_dampingpoly[i]):
                self.fail(f'<joint name="{self.joint_name(int(m.dof_jntid[i]))}">',
                          "a polynomial damping (dampingpoly) is not supported (damping is)")
        for e in range(m.neq):
            name = _name(m, mj, mj.mjtObj.mjOBJ_EQUALITY, e, "equality")
            kind = EQUALITY_TYPES.get(int(m.eq_type[e]), str(int(m.eq_type[e])))
            if m.eq_active0[e]:
                continue  # (aggsym.model.readers.mjcf_equalities: a constraint, a coupling or an error naming it)
            self.warn(f'<equality> <{kind} name="{name}">', f"an inactive {kind} equality is not in the equations "
                                                            f"of motion (listed in the manifest)")
        springs = not m.opt.disableflags & DISABLE_SPRING
        dampers = not m.opt.disableflags & DISABLE_DAMPER
        for t in range(m.ntendon):
            where = f'<tendon name="{self.tendon_name(t)}">'
            wraps = [int(m.wrap_type[w]) for w in range(int(m.tendon_adr[t]), int(m.tendon_adr[t] + m.tendon_num[t]))]
            if hasattr(m, "tendon_armature") and m.tendon_armature[t] and any(w != WRAP_JOINT for w in wraps):
                self.fail(where, "a spatial tendon with armature (its Jacobian depends on q: A and the bias would "
                                 "change with it) is not supported yet; a fixed tendon's armature is")
            for field, what in (("tendon_stiffnesspoly", "a polynomial stiffness (stiffnesspoly)"),
                                ("tendon_dampingpoly", "a polynomial damping (dampingpoly)"),
                                ("tendon_springyield", "a spring with a yield (springyield)")):
                if hasattr(m, field) and np.any(getattr(m, field)[t]):
                    self.fail(where, f"{what} on a tendon is not supported (stiffness and damping are)")
            acts = ((springs and m.tendon_stiffness[t] != 0) or (dampers and m.tendon_damping[t] != 0) or
                    (self.coulomb and m.tendon_frictionloss[t] != 0))
            if acts and any(w in (WRAP_SPHERE, WRAP_CYLINDER) for w in wraps):
                self.fail(where, "a spatial tendon wrapping around a geom (sphere or cylinder) with a stiffness or "
                                 "damping" + (" or (--frictionloss coulomb) a frictionloss" if self.coulomb else "")
                                 + " is not supported: its length switches between the straight and the wrapped "
                                   "path (each wrap's branches would have to be generated); tendons through sites "
                                   "and pulleys, and fixed tendons, are")
        if m.nflex:
            self.fail("<deformable>", f"{m.nflex} flex object(s); flexes are not supported")
        heavy = [self.body_name(i) for i in range(m.nbody) if m.body_gravcomp[i] != 0]
        routed = [self.joint_name(j) for j in range(m.njnt) if hasattr(m, "jnt_actgravcomp") and m.jnt_actgravcomp[j]]
        if heavy and routed:
            self.fail(f'<joint name="{routed[0]}">', "actuatorgravcomp (gravity compensation routed through the "
                                                    "actuators, qfrc_actuator) is not supported; the passive "
                                                    "gravity compensation of gravcomp alone is")
        for a in range(m.nu):
            name = _name(m, mj, mj.mjtObj.mjOBJ_ACTUATOR, a, "actuator")
            for field, what in (("actuator_damping", "damping"), ("actuator_armature", "armature")):
                if hasattr(m, field) and np.any(getattr(m, field)[a]):
                    self.fail(f"actuator {name!r}", f"an actuator with {what} (it changes the equations of motion) "
                                                    f"is not supported")

    def ellipsoid_bodies(self) -> list:
        """The bodies MuJoCo gives the ellipsoid fluid model (some geom of theirs has fluidshape="ellipsoid")."""
        m = self.m
        return [i for i in range(1, m.nbody) if any(m.geom_fluid[int(m.body_geomadr[i]) + j][0] > 0
                                                    for j in range(int(m.body_geomnum[i])))]

    def fluid(self, tree, names, welded, params) -> tuple:
        """(the bodies of MuJoCo's inertia-box fluid model as :class:`~aggsym.model.types.FluidBox` es, the geoms of
        its ellipsoid model as :class:`~aggsym.model.types.FluidEllipsoid` s, the medium (density, viscosity,
        wind)): every moving body of mass >= 1e-15 (MuJoCo's mjMINVAL) whose geoms do not use the ellipsoid model,
        its box as MuJoCo computes it; on the other moving bodies of that mass, every geom with
        ``fluidshape="ellipsoid"`` (MuJoCo's ``mj_fluid``: such a body has no box, its other geoms no drag); the
        runtime parameters ``fluid_density``, ``fluid_viscosity``, ``wind_x wind_y wind_z`` where they are not
        zero."""
        m = self.m
        if not (m.opt.density > 0 or m.opt.viscosity > 0):
            return (), (), ()
        medium = []
        for name, value in (("fluid_density", float(m.opt.density)), ("fluid_viscosity", float(m.opt.viscosity))):
            if value > 0:
                params.append(Parameter(name, value))
                medium.append(params[-1].symbol)
            else:
                medium.append(sp.Integer(0))
        wind = []
        for axis, value in zip("xyz", (float(x) for x in m.opt.wind)):
            if value:
                params.append(Parameter(f"wind_{axis}", value))
                wind.append(params[-1].symbol)
            else:
                wind.append(sp.Integer(0))
        skip = set(self.ellipsoid_bodies())
        boxes, ellipsoids = [], []
        for i in range(1, m.nbody):
            mass = float(m.body_mass[i])
            if mass < 1e-15 or welded[i] or names[i] not in tree.place:
                continue
            place = tree.place[names[i]]
            if i in skip:
                for g in range(int(m.body_geomadr[i]), int(m.body_geomadr[i] + m.body_geomnum[i])):
                    if m.geom_fluid[g][0] != 0:
                        ellipsoids.append(self.fluid_ellipsoid(g, tree, place))
                continue
            inertia = [float(x) for x in m.body_inertia[i]]
            box = tuple(math.sqrt(max(1e-15, inertia[j] + inertia[k] - inertia[a]) / mass * 6.0)
                        for a, j, k in ((0, 1, 2), (1, 0, 2), (2, 0, 1)))
            turned, com = _frame_in(place, m.body_ipos[i], m.body_iquat[i])
            boxes.append(FluidBox(tree.rows[place.body]["name"], com, turned, box))
        return tuple(boxes), tuple(ellipsoids), (medium[0], medium[1], tuple(wind))

    def fluid_ellipsoid(self, g: int, tree, place) -> FluidEllipsoid:
        """The geom ``g`` of the ellipsoid model, its pose in the aggsym body's axes, its semi-axes as MuJoCo's
        ``mju_geomSemiAxes`` takes them from its type and size, its coefficients from ``geom_fluid``."""
        m = self.m
        size, kind = [float(x) for x in m.geom_size[g]], int(m.geom_type[g])
        if kind == GEOM_SPHERE:
            semiaxes = (size[0], size[0], size[0])
        elif kind == GEOM_CAPSULE:
            semiaxes = (size[0], size[0], size[1] + size[0])
        elif kind == GEOM_CYLINDER:
            semiaxes = (size[0], size[0], size[1])
        else:
            semiaxes = (size[0], size[1], size[2])
        c = [float(x) for x in m.geom_fluid[g]]
        turned, centre = _frame_in(place, m.geom_pos[g], m.geom_quat[g])
        return FluidEllipsoid(tree.rows[place.body]["name"], self.geom_name(g), centre, turned, semiaxes,
                              blunt=c[1], slender=c[2], angular=c[3], kutta=c[4], magnus=c[5],
                              virtual_mass=tuple(c[6:9]), virtual_inertia=tuple(c[9:12]), interaction=c[0])

    # the tree ------------------------------------------------------------------------------------------------
    def read(self) -> Model:
        m = self.m
        self.refuse_unsupported()
        flags = int(m.opt.disableflags)
        springs, dampers = not flags & DISABLE_SPRING, not flags & DISABLE_DAMPER
        ids, bodies_ids = _Ids(), _Ids()
        tree = TreeBuilder()
        names = [self.body_name(i) for i in range(m.nbody)]
        welded = [True] + [False] * (m.nbody - 1)  # welded to the world
        for i in range(1, m.nbody):
            welded[i] = welded[m.body_parentid[i]] and m.body_jntnum[i] == 0
        needs_world = any(m.body_parentid[i] == 0 and not (m.body_jntnum[i] == 1 and m.jnt_type[m.body_jntadr[i]] ==
                                                           FREE) for i in range(1, m.nbody))
        world_link = names[0]
        params: list = []
        gravity = np.zeros(3) if flags & DISABLE_GRAVITY else np.array(m.opt.gravity, dtype=float)
        dof_of: list = []  # MuJoCo's dof of each coordinate, in tree order
        armature, damping, coulomb = [], [], []
        pending_stiffness: dict = {}  # row index -> (stiffness symbol, rest symbol)
        free_joints = []
        coordinate_of: dict = {}  # MuJoCo joint id -> its coordinate (hinge and slide)
        added_mass: dict = {}  # row index of a free body -> its armature symbol

        def rate_parameters(coordinate: str, dof: int):
            a = float(m.dof_armature[dof])
            d = float(m.dof_damping[dof]) if dampers else 0.0
            if a:
                params.append(Parameter(f"armature_{coordinate}", a))
                armature.append(params[-1].symbol)
            else:
                armature.append(sp.Integer(0))
            if d:
                params.append(Parameter(f"damping_{coordinate}", d))
                damping.append(params[-1].symbol)
            else:
                damping.append(sp.Integer(0))
            f = float(m.dof_frictionloss[dof]) if self.coulomb else 0.0
            if f:
                params.append(Parameter(f"friction_{coordinate}", f))
                coulomb.append(params[-1].symbol)
            else:
                coulomb.append(sp.Integer(0))
            dof_of.append(dof)

        if needs_world:
            tree.root(world_link, bodies_ids.own(WORLD_BODY), floating_root(False, ids, "world"))
        for i in range(1, m.nbody):
            link, parent = names[i], names[m.body_parentid[i]]
            xyz = tuple(float(x) for x in m.body_pos[i])
            w, x, y, z = (float(v) for v in m.body_quat[i])
            rotation = quaternion_rotations(x, y, z, w) if (w, x, y, z) != (1.0, 0.0, 0.0, 0.0) else []
            n, first = int(m.body_jntnum[i]), int(m.body_jntadr[i])
            if n == 0:
                tree.fixed(parent, link, xyz, rotation)
            elif m.jnt_type[first] == FREE:
                jname = self.joint_name(first)
                prefix = identifier(jname, set(), "q")
                tree.root(link, bodies_ids.own(link), floating_root("quaternion", ids, jname, prefix=prefix))
                # (the free body's frame is its pose in the world: body_pos and body_quat are qpos0's)
                free_joints.append(jname)
                dof = int(m.jnt_dofadr[first])
                a = float(m.dof_armature[dof])
                d = float(m.dof_damping[dof]) if dampers else 0.0
                if a:  # MuJoCo's a on the free joint's six dofs: the kinetic energy 1/2 a (|v|^2 + |w|^2) of an
                    # added mass a E6 at the body's origin (Prop. 2.8), which gravity does not pull: its momentum
                    # a v_world changes as a R (dv + w x v), the term MuJoCo's M qacc holds
                    params.append(Parameter(f"armature_{prefix}", a))
                    added_mass[len(tree.rows) - 1] = params[-1].symbol
                if d:
                    params.append(Parameter(f"damping_{prefix}", d))
                if self.coulomb and np.any(m.dof_frictionloss[dof:dof + 6]):
                    self.fail(f'<joint name="{jname}">', "frictionloss on a free joint with --frictionloss coulomb: "
                                                         "MuJoCo's friction acts on the world-axes velocity there; not "
                                                         "supported (leave out --frictionloss coulomb to list it)")
                for k in range(6):
                    armature.append(sp.Integer(0))
                    coulomb.append(sp.Integer(0))
                    damping.append(params[-1].symbol if d else sp.Integer(0))
                    dof_of.append(dof + k)
            else:
                for k in range(n):
                    j = first + k
                    if m.jnt_type[j] == BALL:
                        self.ball(tree, ids, bodies_ids, parent, link, j, k, xyz, rotation, rate_parameters)
                        continue
                    if m.jnt_type[j] not in KINDS:
                        self.fail(f'<joint name="{self.joint_name(j)}">', f"a {JOINT_TYPES.get(int(m.jnt_type[j]))} "
                                                                         f"joint here is not supported")
                    jname = self.joint_name(j)
                    coordinate = ids.own(jname)
                    coordinate_of[j] = coordinate
                    last = k == n - 1
                    child = link if last else ("mjcf-joint", j)
                    body_id = bodies_ids.own(link if last else f"{link}_{jname}")
                    limits = JointLimits(float(m.jnt_range[j][0]), float(m.jnt_range[j][1])) if m.jnt_limited[j] \
                        else JointLimits()
                    q0 = float(m.qpos0[m.jnt_qposadr[j]])
                    anchor = tuple(float(v) for v in m.jnt_pos[j])
                    tree.joint(parent if k == 0 else ("mjcf-joint", j - 1), child, body_id, jname,
                               lambda code, c=coordinate, jn=jname, lim=limits: Coordinate(c, code, jn, limits=lim),
                               xyz if k == 0 else (0.0, 0.0, 0.0), rotation if k == 0 else [],
                               tuple(float(v) for v in m.jnt_axis[j]), KINDS[int(m.jnt_type[j])],
                               anchor=anchor if any(anchor) else None, offset=(exact(-q0),) if q0 else ())
                    rate_parameters(coordinate, int(m.jnt_dofadr[j]))
                    stiffness = float(m.jnt_stiffness[j]) if springs else 0.0
                    if stiffness:
                        params.append(Parameter(f"stiffness_{coordinate}", stiffness))
                        params.append(Parameter(f"springref_{coordinate}", float(m.qpos_spring[m.jnt_qposadr[j]])))
                        pending_stiffness[len(tree.rows) - 1] = (params[-2].symbol, params[-1].symbol)
            if m.body_mass[i] or np.any(m.body_inertia[i]):
                w, x, y, z = (float(v) for v in m.body_iquat[i])
                irot = quaternion_rotations(x, y, z, w) if (w, x, y, z) != (1.0, 0.0, 0.0, 0.0) else []
                J = tuple(tuple(float(m.body_inertia[i][r]) if r == c else 0.0 for c in range(3)) for r in range(3))
                tree.inertial(link, float(m.body_mass[i]), tuple(float(v) for v in m.body_ipos[i]), J, irot)
        if dof_of != list(range(m.nv)):
            self.fail("", "internal: the coordinates are not in MuJoCo's dof order")  # (the walk above keeps it)
        for k, (stiffness, rest) in pending_stiffness.items():
            pair = tree.rows[k]["pair"]
            tree.rows[k]["pair"] = dataclasses.replace(pair, stiffness=((stiffness,),), rest=(rest,))
        body_links = set(names) if needs_world else set(names[1:])
        sites = self.sites(tree, names, welded, needs_world, body_links)
        tendons, spatial = self.tendons(params, coordinate_of, springs, dampers, tree, body_links)
        self.tendon_forces = tendons + spatial
        self.spatial_paths = lambda t: self.spatial_path(t, tree, body_links)  # (for equalities on spatial tendons)
        gravcomp = self.gravcomp(tree, names, welded, params)
        fluid, ellipsoids, medium = self.fluid(tree, names, welded, params)
        for axis, value in zip("xyz", gravity):
            params.append(Parameter(f"gravity_{axis}", float(value)))
        seen: dict = {}
        for parameter in params:
            if parameter.name in seen:
                self.fail("", f"two joints give the runtime parameter the name {parameter.name!r} (their names "
                              f"become one identifier); rename one of them")
            seen[parameter.name] = parameter
        g = tuple(sp.Symbol(f"gravity_{axis}", real=True) for axis in "xyz")
        bodies = list(tree.bodies(lambda link: f'<body name="{link}">' if isinstance(link, str) else ""))
        zero = sp.Integer(0)
        for k, a in added_mass.items():
            bodies[k] = dataclasses.replace(bodies[k], added_mass=tuple(tuple(a if r == c else zero for c in range(6))
                                                                        for r in range(6)))
        bodies = tuple(bodies)
        children = {int(m.body_parentid[i]) for i in range(1, m.nbody)}
        leaves = [names[i] for i in range(1, m.nbody) if not welded[i] and i not in children]
        place = {link: p for link, p in tree.place.items() if isinstance(link, str)}
        table = link_table(place, [row["name"] for row in tree.rows], tree.parts, leaves)
        model_name = self.model_name() or self.file.stem
        model = Model(name=identifier(model_name, set(), "robot"), bodies=bodies, gravity=g,
                      parameters=tuple(params), source=str(self.file), description=f"MJCF model {model_name!r}",
                      links=Links(table.kind, table.frames, table.leaves),
                      dof_armature=tuple(armature) if any(a != 0 for a in armature) else (),
                      damping=tuple(damping) if any(d != 0 for d in damping) or pending_stiffness else (),
                      tendons=tendons, spatial_tendons=spatial, coulomb=tuple(coulomb) if any(f != 0 for f in coulomb) else (),
                      gravcomp=gravcomp, fluid=fluid, fluid_ellipsoids=ellipsoids, fluid_medium=medium,
                      meta={"floating_base": "quaternion" if free_joints else False,
                            "warnings": list(self.warnings),
                            "mjcf": self.summary(free_joints, sites, springs, dampers, flags)})
        model = dataclasses.replace(model, frames=default_frames(model))
        home = dict(zip((name for name, _, _ in model.positions), self.home_pose()))
        model = with_equalities(self, model)
        armed = [t.name for t in model.tendons if t.armature != 0]
        if armed and model.couplings:
            self.fail(f'<tendon name="{armed[0]}">', "a tendon's armature with coupled coordinates (a joint or "
                                                      "tendon equality that becomes a coupling) is not supported")
        meta = dict(model.meta)
        meta["mjcf"] = dict(meta["mjcf"], qpos0=[home[name] for name, _, _ in model.positions])
        model = dataclasses.replace(model, meta=meta)
        if model.nv == 0:
            self.fail("", "the model has no joint; there are no equations of motion")
        return model

    def gravcomp(self, tree, names, welded, params) -> tuple:
        """The compensated weights of the bodies (``Model.gravcomp``, :mod:`aggsym.mechanics.gravcomp`): for each
        moving MuJoCo body with a ``gravcomp`` s and a mass, the runtime parameter ``gravcomp_<body>`` (default s)
        times its mass and its mass's first moment in the axes of the body it is merged into, summed per body."""
        m = self.m
        lifted: dict = {}
        for i in range(1, m.nbody):
            s = float(m.body_gravcomp[i])
            if not s or welded[i] or names[i] not in tree.parts:
                continue
            params.append(Parameter(f"gravcomp_{identifier(names[i], set(), 'body')}", s))
            mass, c, _ = tree.parts[names[i]]
            body = tree.rows[tree.place[names[i]].body]["name"]
            ms, h = lifted.get(body, (sp.Integer(0), (sp.Integer(0),) * 3))
            symbol = params[-1].symbol
            lifted[body] = (ms + symbol * mass, tuple(x + symbol * mass * y for x, y in zip(h, c)))
        return tuple((body, ms, h) for body, (ms, h) in lifted.items())

    def home_pose(self) -> list:
        """MuJoCo's ``qpos0`` (the file's configuration: a hinge's or slide's ``ref``, a free body's pose as the
        file places it) as aggsym's q, before couplings: a free joint's x y z qx qy qz qw, a ball's qx qy qz qw."""
        m, out = self.m, []
        for j in range(m.njnt):
            a = int(m.jnt_qposadr[j])
            values = [float(v) for v in m.qpos0[a:a + {FREE: 7, BALL: 4}.get(int(m.jnt_type[j]), 1)]]
            if m.jnt_type[j] == FREE:
                values = values[:3] + values[4:] + values[3:4]
            elif m.jnt_type[j] == BALL:
                values = values[1:] + values[:1]
            out.extend(values)
        return out

    def ball(self, tree, ids, bodies_ids, parent, link, j, k, xyz, rotation, rate_parameters):
        """Ball joint ``j``, the ``k``-th and last joint of the body ``link``: a ball pair at its anchor, named
        after it (``J_wx J_wy J_wz``, positions ``J_qx J_qy J_qz J_qw``), its three dofs' armature and damping."""
        m = self.m
        jname = self.joint_name(j)
        if tuple(float(v) for v in m.qpos0[m.jnt_qposadr[j]:m.jnt_qposadr[j] + 4]) != (1.0, 0.0, 0.0, 0.0):
            self.fail(f'<joint name="{jname}">', "a ball joint whose qpos0 is not the identity quaternion")
        prefix = identifier(jname, set(), "q")
        velocities, positions = ball_names(prefix)
        velocities = [ids.own(n) for n in velocities]
        positions = tuple(ids.own(n) for n in positions)
        anchor = tuple(float(v) for v in m.jnt_pos[j])
        tree.joint(parent if k == 0 else ("mjcf-joint", j - 1), link, bodies_ids.own(link), jname,
                   lambda code, v=velocities: Coordinate(v[("theta4", "theta5", "theta6").index(code)], code, jname),
                   xyz if k == 0 else (0.0, 0.0, 0.0), rotation if k == 0 else [], None, "ball",
                   anchor=anchor if any(anchor) else None, positions=positions)
        for i, coordinate in enumerate(velocities):
            rate_parameters(coordinate, int(m.jnt_dofadr[j]) + i)

    def tendons(self, params: list, coordinate_of: dict, springs: bool, dampers: bool, tree, body_links) -> tuple:
        """(fixed, spatial): the fixed tendons with a spring, a damper (or, with ``frictionloss="coulomb"``, a
        frictionloss) as :class:`~aggsym.model.types.Tendon` s, the spatial ones through sites and pulleys as
        :class:`~aggsym.model.types.SpatialTendon` s (:meth:`spatial_path`), their runtime parameters appended to
        ``params``:
        ``tendon_stiffness_<tendon>`` and ``tendon_springlength_<tendon>`` (a dead band:
        ``tendon_springlower_<tendon>``, ``tendon_springupper_<tendon>``), ``tendon_damping_<tendon>``,
        ``tendon_friction_<tendon>``."""
        m = self.m
        out, spatial_out, used = [], [], set()
        for t in range(m.ntendon):
            k = float(m.tendon_stiffness[t]) if springs else 0.0
            d = float(m.tendon_damping[t]) if dampers else 0.0
            f = float(m.tendon_frictionloss[t]) if self.coulomb else 0.0
            a = float(m.tendon_armature[t]) if hasattr(m, "tendon_armature") else 0.0
            if not (k or d or f or a):
                continue
            name = self.tendon_name(t)
            tag = identifier(name, used, "tendon")
            terms = []
            wraps = range(int(m.tendon_adr[t]), int(m.tendon_adr[t] + m.tendon_num[t]))
            spatial = any(int(m.wrap_type[w]) != WRAP_JOINT for w in wraps)
            for w in wraps if not spatial else ():
                j = int(m.wrap_objid[w])
                if j not in coordinate_of:
                    self.fail(f'<tendon name="{name}">',
                              f"the tendon wraps joint {self.joint_name(j)!r}, which is not a hinge or slide joint")
                terms.append((coordinate_of[j], exact(float(m.wrap_prm[w]))))
            values: dict = {"stiffness": 0, "lower": 0, "upper": 0, "damping": 0}
            if k:
                params.append(Parameter(f"tendon_stiffness_{tag}", k))
                values["stiffness"] = params[-1].symbol
                lower, upper = (float(x) for x in m.tendon_lengthspring[t])
                if lower == upper:
                    params.append(Parameter(f"tendon_springlength_{tag}", lower))
                    values["lower"] = values["upper"] = params[-1].symbol
                else:
                    params.append(Parameter(f"tendon_springlower_{tag}", lower))
                    params.append(Parameter(f"tendon_springupper_{tag}", upper))
                    values["lower"], values["upper"] = params[-2].symbol, params[-1].symbol
            if d:
                params.append(Parameter(f"tendon_damping_{tag}", d))
                values["damping"] = params[-1].symbol
            if f:
                params.append(Parameter(f"tendon_friction_{tag}", f))
                values["friction"] = params[-1].symbol
            if a:  # (aggsym.mechanics.tendon_armature: a c c^T in A)
                params.append(Parameter(f"tendon_armature_{tag}", a))
                values["armature"] = params[-1].symbol
            if spatial:
                spatial_out.append(SpatialTendon(name, self.spatial_path(t, tree, body_links), **values))
            else:
                out.append(Tendon(name, tuple(terms), **values))
        return tuple(out), tuple(spatial_out)

    def spatial_path(self, t, tree, body_links) -> tuple:
        """Tendon ``t``'s branches (:class:`~aggsym.model.types.SpatialTendon`): its sites, each as (body, point in the
        body's axes) where the tree places it (a site on a body welded to the world, outside the tree: WORLD and
        its world position, MuJoCo's), a ``<pulley>`` starting a new branch with its divisor."""
        m, mj = self.m, self.mj
        branches, divisor, sites = [], 1, []
        world = None
        for w in range(int(m.tendon_adr[t]), int(m.tendon_adr[t] + m.tendon_num[t])):
            if int(m.wrap_type[w]) == WRAP_PULLEY:
                branches.append((divisor, tuple(sites)))
                divisor, sites = exact(float(m.wrap_prm[w])), []
                continue
            s = int(m.wrap_objid[w])
            name = _name(m, mj, mj.mjtObj.mjOBJ_SITE, s, "site")
            link = f"site:{name}" if name in body_links else name
            if link in tree.place:
                place = tree.place[link]
                sites.append((tree.rows[place.body]["name"], tuple(place.t)))
            else:  # (a body welded to the world, the world not in the tree: the site does not move)
                if world is None:
                    world = mj.MjData(m)
                    mj.mj_kinematics(m, world)
                sites.append((WORLD, tuple(exact(float(x)) for x in world.site_xpos[s])))
        branches.append((divisor, tuple(sites)))
        return tuple((d, path) for d, path in branches if len(path) >= 2)

    def model_name(self) -> str:
        raw = bytes(self.m.names)
        return raw[:raw.index(b"\0")].decode("utf-8", "replace") if b"\0" in raw else ""

    def sites(self, tree, names, welded, needs_world, body_links) -> list:
        """Every site as a link of the body it is on (its name, or ``site:<name>`` beside a body of that name)."""
        m, mj = self.m, self.mj
        out = []
        for s in range(m.nsite):
            b = int(m.site_bodyid[s])
            if welded[b] and not needs_world:
                continue
            name = _name(m, mj, mj.mjtObj.mjOBJ_SITE, s, "site")
            link = f"site:{name}" if name in body_links else name
            w, x, y, z = (float(v) for v in m.site_quat[s])
            rotation = quaternion_rotations(x, y, z, w) if (w, x, y, z) != (1.0, 0.0, 0.0, 0.0) else []
            tree.fixed(names[b], link, tuple(float(v) for v in m.site_pos[s]), rotation)
            out.append(link)
        return out

    def summary(self, free_joints, sites, springs, dampers, flags) -> dict:
        """``model.meta["mjcf"]``: the conventions, and what MuJoCo has that the equations leave out."""
        m, mj = self.m, self.mj
        joints = []
        for j in range(m.njnt):
            dof = int(m.jnt_dofadr[j])
            entry = {"joint": self.joint_name(j), "type": JOINT_TYPES[int(m.jnt_type[j])],
                     "body": self.body_name(int(m.jnt_bodyid[j]))}
            if m.dof_frictionloss[dof]:
                entry["frictionloss"] = float(m.dof_frictionloss[dof])
            if m.jnt_limited[j]:
                entry["range"] = [float(m.jnt_range[j][0]), float(m.jnt_range[j][1])]
            joints.append(entry)
        actuators = []
        for a in range(m.nu):
            target = int(m.actuator_trnid[a][0])
            kind = int(m.actuator_trntype[a])
            on = (self.joint_name(target) if kind in (0, 1) else
                  _name(m, mj, mj.mjtObj.mjOBJ_TENDON, target, "tendon") if kind == 3 else str(target))
            actuators.append({"name": _name(m, mj, mj.mjtObj.mjOBJ_ACTUATOR, a, "actuator"),
                              "transmission": {0: "joint", 1: "joint", 2: "slider-crank", 3: "tendon",
                                               4: "site", 5: "body"}.get(kind, str(kind)),
                              "target": on, "gear": [float(v) for v in m.actuator_gear[a]]})
        tendons = []
        in_model = {t.name for t in self.tendon_forces}
        for t in range(m.ntendon):
            fixed = all(int(m.wrap_type[w]) == WRAP_JOINT for w in range(int(m.tendon_adr[t]),
                                                                        int(m.tendon_adr[t] + m.tendon_num[t])))
            entry = {"tendon": self.tendon_name(t), "type": "fixed" if fixed else "spatial",
                     "in_the_equations": self.tendon_name(t) in in_model}
            for field, key in (("tendon_stiffness", "stiffness"), ("tendon_damping", "damping"),
                               ("tendon_frictionloss", "frictionloss")):
                if getattr(m, field)[t]:
                    entry[key] = float(getattr(m, field)[t])
            if m.tendon_stiffness[t]:
                entry["springlength"] = [float(x) for x in m.tendon_lengthspring[t]]
            if m.tendon_limited[t]:
                entry["range"] = [float(x) for x in m.tendon_range[t]]
            tendons.append(entry)
        inactive = [_name(m, mj, mj.mjtObj.mjOBJ_EQUALITY, e, "equality") for e in range(m.neq) if not m.eq_active0[e]]
        return {
            "source": "MuJoCo's compiled model (mujoco " + mj.__version__ + ")",
            "convention": CONVENTION,
            "free_joints": list(free_joints),
            "in_the_equations": (
                "A(q) qdd + b + g + C (q - q0) + D qd + t(q, qd) = tau: armature on A's diagonal "
                "(armature_<coordinate>), viscous damping D (damping_<coordinate>), springs C (stiffness_<coordinate>, "
                "rest springref_<coordinate>), the fixed tendons' springs and dampers t = -c f, f = -k s - d L' "
                "along the tendon (L = sum c q, s the stretch beyond springlength or its dead band; "
                "tendon_stiffness_<tendon>, tendon_springlength_<tendon> or tendon_springlower_/tendon_springupper_"
                "<tendon>, tendon_damping_<tendon>), gravity (gravity_x, gravity_y, gravity_z); forward and inverse "
                "dynamics include the passive forces as MuJoCo's qacc and qfrc_passive do; passive_forces gives "
                "-(C (q - q0) + D qd + t) (MuJoCo's qfrc_passive sign)" + (
                    "; frictionloss as Coulomb friction (--frictionloss coulomb): + F sign(qd) on the left "
                    "(friction_<coordinate>) and -F sign(L') along a tendon (tendon_friction_<tendon>), in "
                    "forward and inverse dynamics and passive_forces; zero at qd = 0 (MuJoCo's frictionloss is a "
                    "constraint that can hold the joint still: not the same)" if self.coulomb else "") + (
                    "; gravity compensation (gravcomp_<body>, default the file's gravcomp) lifts that fraction of "
                    "each listed body's weight at its centre of mass: among the passive forces (in passive_forces and "
                    "on the left of forward and inverse dynamics, as in MuJoCo's qfrc_passive), not in g(q) (as "
                    "qfrc_bias); the potential energy holds the lift's" if np.any(m.body_gravcomp) else "")),
            "frictionloss": "coulomb" if self.coulomb else "list",
            "springs": springs, "dampers": dampers, "gravity_disabled": bool(flags & DISABLE_GRAVITY),
            "not_in_the_equations": (
                ("" if self.coulomb else "frictionloss (a constraint in MuJoCo; --frictionloss coulomb takes it "
                                         "as Coulomb friction), ")
                + "joint and tendon limits, contacts, inactive equalities "
                "(active ones are constraints or couplings: equalities), actuators (their forces are tau's to "
                "give: actuators lists each with its "
                "transmission target and gear)"),
            "joints": joints, "actuators": actuators, "tendons": tendons, "inactive_equalities": inactive,
            "sites": list(sites),
            **({"fluid": {"model": "inertia box (MuJoCo's mj_inertiaBoxFluidModel) on each body, ellipsoid "
                                   "(mj_ellipsoidFluidModel) on each geom of ellipsoid_geoms",
                          "density": float(m.opt.density), "viscosity": float(m.opt.viscosity),
                          "wind": [float(x) for x in m.opt.wind],
                          "ellipsoid_geoms": [self.geom_name(g) for i in self.ellipsoid_bodies()
                                              for g in range(int(m.body_geomadr[i]),
                                                             int(m.body_geomadr[i] + m.body_geomnum[i]))
                                              if m.geom_fluid[g][0] != 0]}}
               if m.opt.density or m.opt.viscosity else {}),
            **({"gravcomp": [{"body": self.body_name(i), "gravcomp": float(m.body_gravcomp[i])}
                             for i in range(1, m.nbody) if m.body_gravcomp[i]]} if np.any(m.body_gravcomp) else {}),
        }


def load_mjcf(path, frictionloss: str = "list", root=None) -> Model:
    """Read an MJCF file through MuJoCo's compiler (the ``mujoco`` package: ``pip install 'aggsym[mjcf]'``); raises
    :class:`ModelError` with the file and the compiler's message, or naming what is not supported.
    ``frictionloss``: ``"list"`` (MuJoCo's frictionloss listed in the manifest, out of the equations) or
    ``"coulomb"`` (taken as Coulomb friction f sign(qd) in the equations, on request).  ``root``: the model root
    (``--model-root``; default the file's folder), inside which every file the model names must resolve."""
    if frictionloss not in FRICTIONLOSS_OPTIONS:
        raise ValueError(f"frictionloss must be one of {', '.join(FRICTIONLOSS_OPTIONS)}, got {frictionloss!r}")
    path = Path(path)
    screen(path, root)
    try:
        import mujoco
    except ImportError:
        raise ModelError(path, "", "reading MJCF needs the mujoco package (pip install 'aggsym[mjcf]')") from None
    said: list = []  # MuJoCo's warnings, taken from its handler (which prints them and appends to a log file in
    # the working directory) and issued as ModelWarning
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(said.append)
    try:
        m = mujoco.MjModel.from_xml_path(str(path))
    except Exception as exc:  # MuJoCo's compiler reports every problem of the file as a ValueError
        text = " ".join(str(exc).split())
        raise ModelError(path, "", f"MuJoCo's compiler refuses the file: {text[:2000]}") from None
    finally:
        mujoco.set_mju_user_warning(previous)
    return read_compiled(m, path, frictionloss, [f"MuJoCo's compiler warns: {' '.join(str(t).split())[:2000]}"
                                                 for t in said])


def read_compiled(m, path, frictionloss: str = "list", warnings_said=()) -> Model:
    """The model of an ``MjModel`` MuJoCo has compiled (from the file ``path``, named in messages and in the
    model's ``source``): what :func:`load_mjcf` does after the compiler, for a model compiled otherwise (an
    ``MjSpec`` edited in memory).  ``warnings_said``: texts issued first as :class:`ModelWarning` s."""
    import mujoco

    if frictionloss not in FRICTIONLOSS_OPTIONS:
        raise ValueError(f"frictionloss must be one of {', '.join(FRICTIONLOSS_OPTIONS)}, got {frictionloss!r}")
    reader = _Reader(Path(path), m, mujoco, frictionloss)
    for text in warnings_said:
        reader.warn("", text)
    return reader.read()


__all__ = ["load_mjcf", "read_compiled", "CONVENTION"]
