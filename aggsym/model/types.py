"""The immutable model: bodies, their kinematic pairs, parameters, gravity (1.2, Def. 1.7, 1.8).

Every numeric field is a SymPy expression: a number (exact where the file was exact, e.g. ``pi/2``) or an
expression in the model's parameters.  Numbers are folded into generated code; parameters are read at run time
from the parameter vector ``p``.

A pair follows the book's configuration (1.24)-(1.27): a constructive part (constant translation ``p`` in the
parent's axes, then constant rotations about the axes ``alpha, beta, gamma`` in the stated order, so that
``c = c_alpha(phi_alpha) c_beta(phi_beta) c_gamma(phi_gamma)``), followed by the functional part: translations
``o1, o2, o3`` along the constructive frame's axes, then the rotation ``c1(theta4) c2(theta5) c3(theta6)``.
Coordinates absent from the pair are zero.

Three body features of chapter 2 live here too:

* a pair may be Hooke-elastic: ``stiffness`` C over its coordinates and a ``rest`` position q0, giving the
  generalized force C (q - q0) on the left of (2.27) and the energy 1/2 (q - q0)^T C (q - q0) (1.32), (2.27);
* a pair may have a *prescribed* functional motion instead of coordinates (``prescribed``: rotations as
  functions of the time t): this is how a rotor with a prescribed spin (2.13) is carried, as a body whose
  relative motion is known and does not depend on the carrier's (Prop. 2.7);
* a body may carry ``added_mass``, the constant symmetric 6x6 matrix Lambda of the inertial medium about its
  origin in (v, w) order; its aggregate is Theta + Lambda (Prop. 2.8), gravity acts on Theta only.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field

import sympy as sp

from ..core.backend import as_expr

COORDINATE_CODES = ("o1", "o2", "o3", "theta4", "theta5", "theta6")
WORLD = "world"
TIME = sp.Symbol("t", real=True)  # the time in prescribed motions (rotor spins)

_SNAP = 1e-14


def code_index(code: str) -> int:
    """0-based position of a coordinate code in the 6-vector of mobility axes (f_1 .. f_6 of (1.29))."""
    return COORDINATE_CODES.index(code)


def _zero(x) -> bool:
    """Whether an expression of the model is exactly zero."""
    return bool(getattr(x, "is_zero", False)) or x == 0


def _snap(x: sp.Expr) -> sp.Expr:
    """Round float entries within 1e-14 of 0 or +-1 to exact values (e.g. cos(1.5707963267948966))."""
    if isinstance(x, sp.Float):
        v = float(x)
        for target in (0, 1, -1):
            if abs(v - target) < _SNAP:
                return sp.Integer(target)
    return x


def elementary_entries(axis: int, angle: sp.Expr) -> tuple:
    """c_axis(angle) of Prop. 1.17 as rows of exact SymPy numbers (cos and sin within 1e-14 of 0, +-1 snapped)."""
    c, s = _snap(sp.cos(angle)), _snap(sp.sin(angle))
    one, zero = sp.Integer(1), sp.Integer(0)
    if axis == 1:
        return (one, zero, zero), (zero, c, -s), (zero, s, c)
    if axis == 2:
        return (c, zero, s), (zero, one, zero), (-s, zero, c)
    return (c, -s, zero), (s, c, zero), (zero, zero, one)


def elementary_rotation(axis: int, angle: sp.Expr) -> sp.Matrix:
    """c_axis(angle) of Prop. 1.17 as an exact SymPy matrix."""
    return sp.Matrix(elementary_entries(axis, angle))


@dataclass(frozen=True)
class Parameter:
    """A runtime parameter: entry of ``p`` with a default value."""

    name: str
    value: float

    @property
    def symbol(self) -> sp.Symbol:
        return sp.Symbol(self.name, real=True)


@dataclass(frozen=True)
class JointDynamics:
    """A URDF joint's ``<dynamics damping= friction=>``: viscous damping d (N m s/rad, or N s/m for a prismatic
    joint) and Coulomb friction f (N m, or N), each None where the file gives none.  They describe the generalized
    force tau_f = -d qd - f sign(qd) along the coordinate: the routine ``joint_friction``, and in forward and inverse
    dynamics under ``--passive include`` (:mod:`aggsym.model.transforms.joint_dynamics`)."""

    damping: float | None = None
    friction: float | None = None

    @property
    def given(self) -> bool:
        return self.damping is not None or self.friction is not None


@dataclass(frozen=True)
class InertialBlock:
    """A link whose ten inertial parameters (``m, mcx, mcy, mcz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz``: mass, first moment
    and inertia tensor about the link frame's origin, link axes) are entries of p: a payload (``kind``
    ``"payload"``) or the link's own inertial data (``"link"``).  ``helper`` is the generated helper's name
    (``set_payload_<link>``, ``set_inertial_<link>``), ``parameters`` the ten parameter names in that order."""

    kind: str
    link: str
    helper: str
    parameters: tuple


@dataclass(frozen=True)
class JointLimits:
    """A URDF joint's ``<limit lower= upper= velocity= effort=>``: position range (rad or m, in the coordinate's own
    sense: q is the joint's angle or displacement about or along its URDF axis), largest speed and largest force
    or torque, each None where the file gives none (and all None without ``<limit>``)."""

    lower: float | None = None
    upper: float | None = None
    velocity: float | None = None
    effort: float | None = None

    def as_dict(self) -> dict:
        """``{lower, upper, velocity, effort}``, None where absent (the manifest's ``limits`` entry)."""
        return {"lower": self.lower, "upper": self.upper, "velocity": self.velocity, "effort": self.effort}


@dataclass(frozen=True)
class Coordinate:
    """One generalized coordinate: a functional motion of a pair (1.26), (1.27).

    ``joint`` is the pair's name as the source file spells it (the URDF joint name, whatever characters it has);
    ``name`` is the identifier made from it.  ``dynamics`` and ``limits`` hold the URDF joint's ``<dynamics>`` and
    ``<limit>`` values (all None for YAML models and for a floating base's coordinates).
    """

    name: str
    code: str  # one of COORDINATE_CODES
    joint: str  # the pair's name
    dynamics: JointDynamics = JointDynamics()
    limits: JointLimits = JointLimits()

    @property
    def axis(self) -> int:
        """0-based index of the mobility axis f (0..2 translations, 3..5 rotations)."""
        return code_index(self.code)

    @property
    def kind(self) -> str:
        return "translation" if self.axis < 3 else "rotation"


QUATERNION_KINDS = ("translation",) * 3 + ("quaternion",) * 4  # the kinds of a free-flyer pair's seven positions
BALL_KINDS = ("quaternion",) * 4  # the kinds of a ball pair's four positions
BALL_CODES = ("theta4", "theta5", "theta6")  # a ball pair's coordinates: its angular velocity in the child's axes


@dataclass(frozen=True)
class Pair:
    """The kinematic pair (parent, body): constructive then functional configuration (1.24)-(1.27)."""

    name: str
    translation: tuple  # 3 expressions, parent axes
    rotation: tuple  # ((axis 1..3, angle expression), ...) in order of application
    coordinates: tuple  # Coordinate, ordered by code
    stiffness: tuple | None = None  # k x k expressions over the pair's coordinates (Hooke, (1.32), (2.27))
    rest: tuple | None = None  # k expressions: the coordinates at which the elastic force vanishes (default 0)
    prescribed: tuple = ()  # ((code, expression in TIME), ...): known rotations of a pair without coordinates
    positions: tuple = ()  # a free-flyer pair (Pinocchio's JointModelFreeFlyer): the names of its seven entries of q,
    # x y z (the origin in the parent's axes) then the unit quaternion qx qy qz qw of its rotation; its six
    # coordinates o1..theta6 are then the body's own quasi-velocity (v, w) in body axes (Def. 1.9), not rates of
    # q.  A ball pair (Pinocchio's JointModelSpherical): the four names qx qy qz qw of its unit quaternion, its
    # three coordinates theta4 theta5 theta6 the angular velocity w of the body relative to its parent, in the
    # body's axes.  Empty for every other pair: its entries of q are its coordinates.
    offset: tuple = ()  # per coordinate, a constant added to it in the functional configuration: the pair moves by
    # c(q + offset) (internal frames of aggsym.model.transforms.reframe); empty: none

    @property
    def quaternion(self) -> bool:
        """True for a pair placed by a unit quaternion, a free-flyer or a ball pair (see ``positions``): its
        coordinates are velocities in the body's axes, not rates of q, and its M F is constant."""
        return bool(self.positions)

    @property
    def ball(self) -> bool:
        """True for a ball pair (four positions: a unit quaternion; coordinates theta4 theta5 theta6)."""
        return len(self.positions) == 4

    @property
    def free_flyer(self) -> bool:
        """True for a free-flyer pair (seven positions: the origin and a unit quaternion; six coordinates)."""
        return len(self.positions) == 7

    @property
    def position_kinds(self) -> tuple:
        """The kinds of the pair's entries of q: a free-flyer's or a ball's positions, else its coordinates'."""
        if self.quaternion:
            return QUATERNION_KINDS if self.free_flyer else BALL_KINDS
        return tuple(c.kind for c in self.coordinates)

    @property
    def codes(self) -> tuple:
        return tuple(c.code for c in self.coordinates)

    @property
    def elastic(self) -> bool:
        return self.stiffness is not None

    def constructive_rotation(self) -> sp.Matrix:
        """c^{mu,k-1}_{lkk} = c_alpha c_beta c_gamma (Prop. 1.17), exact where the angles are (a fresh matrix; the
        product is formed once per pair: every binding of the model reads it)."""
        return sp.Matrix(self._constructive_rotation)

    @functools.cached_property
    def _constructive_rotation(self) -> sp.ImmutableMatrix:
        c = sp.eye(3)
        for axis, angle in self.rotation:
            c = c * elementary_rotation(axis, angle)
        return sp.ImmutableMatrix(c.applyfunc(_snap))


@dataclass(frozen=True)
class Inertial:
    """Mass, centre of mass (body axes) and inertia tensor about the centre of mass (body axes)."""

    mass: sp.Expr
    com: tuple
    inertia: tuple  # 3x3 symmetric, about the centre of mass
    origin: tuple | None = None  # (m, h, theta_O) given at the origin instead (runtime inertial parameters: no
    # division by a mass that p may set to zero); com and inertia then hold their values at the defaults

    def mises(self):
        """(m, h, theta_O): the Mises matrix (2.3) at the body origin, h = m r_c, theta_O = theta_c + m(r.r E - r r^T).
        Expanded by SymPy once per inertial: every binding of the model (the program's, and each scratch program
        that counts a routine's forms) reads it."""
        if self.origin is not None:
            return self.origin
        return self._mises_at_origin

    @functools.cached_property
    def _mises_at_origin(self):
        """theta_O entry by entry in the form without cancellation: ``theta_c,ii + m (r_j^2 + r_k^2)`` on the
        diagonal (not ``m (r.r - r_i^2)``, which loses the digits of a point mass far along an axis and near it:
        a head on its neck axis), ``theta_c,ij - m r_i r_j`` off it; where every number is a number, in exact
        rational arithmetic on their binary values, rounded once (each entry the double nearest the exact one)."""
        m, r, I = self.mass, self.com, self.inertia
        numbers = (m, *r, *(v for row in I for v in row))
        exact = all(isinstance(x, (sp.Number, int, float)) for x in numbers)
        # (rationals given as such, a YAML model's 1/3, stay exact: only a float among them is rounded to)
        exact = exact and any(isinstance(x, (sp.Float, float)) for x in numbers)
        if exact:
            m, r = sp.Rational(m), [sp.Rational(x) for x in r]
            I = [[sp.Rational(v) for v in row] for row in I]

        def entry(i, j):
            if i == j:
                return I[i][i] + m * sum(r[k] ** 2 for k in range(3) if k != i)
            return I[i][j] - m * r[i] * r[j]

        def done(x):
            return (sp.Float(x, precision=53) if x != 0 else sp.S.Zero) if exact else sp.expand(x)

        h = tuple(done(m * x) for x in r)
        return done(m), h, tuple(tuple(done(entry(i, j)) for j in range(3)) for i in range(3))


@dataclass(frozen=True)
class Coupling:
    """A coordinate tied to another: ``coordinate = multiplier * master + offset`` (a URDF ``<mimic>`` joint loaded
    with ``mimic="couple"``).  The coupled coordinate leaves q; the tree still moves it."""

    coordinate: str
    master: str
    multiplier: float
    offset: float = 0.0


@dataclass(frozen=True)
class Body:
    """A rigid body (or a massless frame when ``inertial`` is None) and the pair joining it to its parent."""

    name: str
    parent: str  # WORLD for the root
    pair: Pair
    inertial: Inertial | None = None
    where: str = ""  # the place in the source file, for messages
    link_rotation: tuple | None = None  # 3x3: axes of the source file's link frame in the body frame (URDF)
    added_mass: tuple | None = None  # 6x6 symmetric Lambda about the body origin, (v, w) order (Prop. 2.8)
    carrier: str | None = None  # for a rotor (2.13): the body that carries it (its parent)


JOINT_ROW = "joint"  # the row code of a joint-space constraint (one row: phi, J, gamma, lambda)


@dataclass(frozen=True)
class JointRow:
    """A holonomic constraint in joint space (an MJCF joint or fixed-tendon equality): with the linear forms
    ``L1 = sum c q`` over ``first`` and ``L2`` over ``second`` (pairs (coordinate name, coefficient); the
    coordinates of hinge and slide pairs, q their positions), the residual is

        phi = (L1 - ref1) - (y0 + a1 x + a2 x^2 + a3 x^3 + a4 x^4),   x = L2 - ref2

    (``polynomial`` = (y0, a1, a2, a3, a4); without ``second`` x is 0 and phi = L1 - ref1 - y0).  Its Jacobian row
    is ``c1 - P'(x) c2``, its bias ``gamma = -P''(x) (c2 . qd)^2``; the multiplier is the generalized force
    ``J^T lambda`` it adds along the row.

    Either length may instead be a spatial tendon's (an MJCF tendon equality on a ``<spatial>`` tendon through sites
    and pulleys): ``first_sites`` / ``second_sites`` its branches as :class:`SpatialTendon`'s (then ``first`` /
    ``second`` is empty); its length L(q), Jacobian row dL/dq and rate term (``d^2 L/dt^2`` at qdd = 0) are
    :class:`~aggsym.mechanics.spatial_tendons.SpatialLength`'s, and gamma = L1'' - P''(x) L2'^2 - P'(x) L2''."""

    first: tuple  # ((coordinate name, coefficient expression), ...)
    second: tuple = ()
    reference: tuple = (0, 0)  # (ref1, ref2) expressions
    polynomial: tuple = (0, 0, 0, 0, 0)  # (y0, a1, a2, a3, a4) expressions
    first_sites: tuple = ()  # a spatial tendon's branches ((divisor, ((body, (x, y, z)), ...)), ...), or ()
    second_sites: tuple = ()

    @property
    def linear(self) -> bool:
        """Whether phi is linear in q (a2 = a3 = a4 = 0, no spatial tendon): then J is constant and gamma is 0."""
        if self.first_sites or self.second_sites:
            return False
        return all(as_expr(a) == 0 for a in self.polynomial[2:]) or not self.second


@dataclass(frozen=True)
class Tendon:
    """A fixed tendon with a spring or a damper (MJCF ``<fixed>`` tendon with ``stiffness``/``springlength`` and
    ``damping``): its length ``L = sum c q`` over ``terms`` (pairs (coordinate name, coefficient); hinge and slide
    coordinates, q their positions) and velocity ``L' = sum c qd``; the force along it

        f = -k (L - lower)  below ``lower``,  0 between,  -k (L - upper)  above ``upper``   (lower = upper: a
        linear spring about its rest length),  minus d L',  minus F sign(L') (Coulomb friction, on request)

    acts on the coordinates as ``c f`` (a force on the right side; on the left of the equations of motion
    ``-c f``).  ``armature``: an inertia a along the tendon, a c c^T in A (:mod:`aggsym.mechanics.tendon_armature`).
    ``stiffness``, ``lower``, ``upper``, ``damping``, ``friction`` and ``armature`` are expressions (runtime
    parameters)."""

    name: str
    terms: tuple
    stiffness: object = 0
    lower: object = 0
    upper: object = 0
    damping: object = 0
    friction: object = 0
    armature: object = 0

    @property
    def deadband(self) -> bool:
        """Whether the spring has a dead band (lower < upper): then its force is piecewise linear."""
        return as_expr(self.lower) != as_expr(self.upper)


@dataclass(frozen=True)
class SpatialTendon:
    """A spatial tendon through sites (MJCF ``<spatial>`` without wrapping geoms) with a spring or a damper: its
    length L = sum over its ``branches`` of (the distances between consecutive sites) / the branch's divisor (a
    ``<pulley divisor>`` starts a branch; the first has divisor 1); each branch ``(divisor, sites)``, each site
    ``(body name, (x, y, z))`` a point fixed on a body, in its axes (the body WORLD: a point fixed in the world).
    The force along it is a fixed tendon's (:class:`Tendon`: k, the dead band lower..upper, d, F, its
    ``deadband``), acting on the coordinates as J^T f with J = dL/dq (:mod:`aggsym.mechanics.spatial_tendons`)."""

    name: str
    branches: tuple
    stiffness: object = 0
    lower: object = 0
    upper: object = 0
    damping: object = 0
    friction: object = 0

    deadband = Tendon.deadband


@dataclass(frozen=True)
class FluidBox:
    """One body's part of MuJoCo's inertia-box fluid model (``<option density viscosity wind>``): a MuJoCo body merged
    into ``body``, its centre of mass ``com`` and its inertial frame's axes ``axes`` (3x3, columns in the body's
    axes), the full dimensions ``box`` of its equivalent inertia box (MuJoCo's, from its principal moments and
    mass).  The medium's density, viscosity and wind are ``Model.fluid_medium`` (:mod:`aggsym.mechanics.fluid`)."""

    body: str
    com: tuple
    axes: tuple
    box: tuple


@dataclass(frozen=True)
class FluidEllipsoid:
    """One geom's part of MuJoCo's ellipsoid fluid model (``fluidshape="ellipsoid"``): a geom of a MuJoCo body merged
    into ``body``, its centre ``centre`` and its axes ``axes`` (3x3, columns in the body's axes, as
    :class:`FluidBox`'s), its ``semiaxes`` (MuJoCo's ``mju_geomSemiAxes``), the five coefficients of ``fluidcoef``
    (``blunt``, ``slender`` drag, ``angular`` drag, ``kutta`` and ``magnus`` lift), ``virtual_mass`` and
    ``virtual_inertia`` (per unit density, about the geom's axes: MuJoCo's ``geom_fluid`` precomputes them) and
    ``interaction`` (MuJoCo's ``geom_fluid[0]``, 1 for ``fluidshape="ellipsoid"``: a factor of the whole wrench).
    The medium is ``Model.fluid_medium`` (:mod:`aggsym.mechanics.fluid_ellipsoid`)."""

    body: str
    geom: str
    centre: tuple
    axes: tuple
    semiaxes: tuple
    blunt: float
    slender: float
    angular: float
    kutta: float
    magnus: float
    virtual_mass: tuple
    virtual_inertia: tuple
    interaction: float = 1.0


CONSTRAINT_KINDS = {  # block: kind -> the forbidden relative motions, in the reference frame (ch. 4)
    "point": ("o1", "o2", "o3"),
    "weld": COORDINATE_CODES,
    "hinge3": ("o1", "o2", "o3", "theta4", "theta5"),
    "cylinder3": ("o1", "o2", "theta4", "theta5"),
    "normal": ("o3",),
    "rolling": ("o1", "o2", "o3"),  # the material point of a wheel at its contact: zero velocity (non-holonomic)
}


@dataclass(frozen=True)
class Constraint:
    """A bilateral constraint of a body with the medium (the world, or another body of the tree: a closed loop),
    chapter 4: the relative motions ``rows`` (a subset of o1 o2 o3 theta4 theta5 theta6, in that order) of the
    body's point ``point`` with respect to a reference frame fixed in the medium at ``at``, with axes
    ``rotation`` (constant elementary rotations from the medium's axes), are forbidden.  Its multiplier is the
    wrench (f, mu) the medium exerts on the body about the point, in the reference axes, one entry per row."""

    name: str
    body: str  # the constrained body (a body of the tree)
    point: tuple  # 3 expressions: the contact point in the body's axes
    rows: tuple  # codes, a subset of COORDINATE_CODES in their order
    medium: str = WORLD  # WORLD or a body of the tree
    at: tuple | None = None  # 3 expressions in the medium's axes; None: where the point is at q = 0
    rotation: tuple = ()  # ((axis, angle expression), ...): the reference axes in the medium's axes
    kind: str = ""  # the block kind named in the file (point, weld, ...), or "" for an explicit list
    source: str = ""  # the file it was read from, its YAML path there and line, for messages
    path: str = ""
    line: int | None = None
    link: str = ""  # for a URDF side file: the link named (its point is given in the link frame)
    medium_axes: tuple | None = None  # 3x3: the axes of the medium's URDF link frame in its body's axes (None: same)
    friction: tuple | None = None  # ("viscous", c) or ("coulomb", mu): on the free translations, (4.33)-(4.34)
    wheel: tuple | None = None  # (radius, axle: 3 expressions, unit, body axes) for block: rolling
    motion: tuple = ()  # ((code, expression in TIME), ...): the world-side frame's prescribed functional motion
    orientation: tuple | None = None  # 3x3 (rows): C0 of the rotational residual, the body's axes in the reference
    # axes transposed where the residual vanishes (an MJCF weld's relpose); None: the relative orientation at q = 0
    joint_row: JointRow | None = None  # a joint-space constraint (kind "joint", rows (JOINT_ROW,)): no body, point
    # or medium; see JointRow

    @property
    def free_translations(self) -> tuple:
        """The translations the constraint leaves free (the permitted motions f_k+ of (4.34) among o1 o2 o3):
        the contact point's slip velocities are its relative velocity along these reference axes."""
        if self.joint_row is not None:
            return ()
        return tuple(code for code in COORDINATE_CODES[:3] if code not in self.rows)

    @property
    def normal(self) -> str | None:
        """The one blocked translation (the normal of a sliding contact), or None."""
        if self.joint_row is not None:
            return None
        blocked = [code for code in COORDINATE_CODES[:3] if code in self.rows]
        return blocked[0] if len(blocked) == 1 else None


@dataclass(frozen=True)
class Frame:
    """A frame fixed on a body, for the frame routines (kinematics for control): its origin ``point`` and its axes:
    ``axes`` (3x3, columns: the axes of a URDF link frame in the body's axes; None: the body's axes), then the
    constant elementary rotations ``rotation`` from those (YAML), all constants or expressions in the parameters.  A URDF link is a frame on the body it was merged into; ``source``, ``path``
    and ``line`` place it in its file, for messages."""

    name: str  # the name it is selected and listed by (a YAML frame's identifier, a body's name, a URDF link's)
    body: str
    point: tuple  # 3 expressions, body axes
    axes: tuple | None = None
    rotation: tuple = ()  # ((axis 1..3, angle expression), ...) in order of application
    source: str = ""
    path: str = ""
    line: int | None = None


@dataclass(frozen=True)
class LinkFrame:
    """A link of the file (a URDF ``<link>``; for a YAML model a body) as a frame fixed on the body it belongs to.

    Conventions: a point with coordinates x_link in the link frame has the coordinates x_body = R x_link + t in its
    body's frame, R = ``rotation`` (3x3, rows, exact or float numbers; None: the body's axes, R = E) and
    t = ``translation`` (3 numbers, body axes; None: the body's origin).  ``part`` is the link's own inertial
    contribution ``(mass, com, inertia about com)`` with com and inertia in the body's axes (what a reader adds to
    the body for this link), None when the link has no inertial data of its own (or, YAML, when the body's are
    expressions of the parameters)."""

    name: str  # the link's name in its file (a URDF link name; a YAML body's name)
    body: str  # the body it was merged into
    rotation: tuple | None = None  # R: x_body = R x_link + t
    translation: tuple | None = None  # t
    part: tuple | None = None  # (mass, com, inertia about com), body axes


@dataclass(frozen=True)
class Links:
    """The links a model offers to the options that name links (``--frames``, ``--constraints``,
    ``--inertial-parameters``, ``--payload``) and to reframing.

    ``kind``: ``"link"`` when the file has links of its own that need not be bodies (URDF: fixed joints merge
    links into one body; reframing, inertial parameters and payloads apply), ``"body"`` when each body is its own
    link at its origin, in its axes (YAML, and models built without a reader: :meth:`of_bodies`).  ``frames``:
    one :class:`LinkFrame` per link in tree order (parents first); ``leaves``: the names of the links without a
    child link, in tree order (the frames emitted by default); ``declared``: the frames the file declares beside
    its links (:class:`Frame`: YAML ``frames:``), emitted by default after the leaves."""

    kind: str
    frames: tuple = ()  # LinkFrame, in tree order
    leaves: tuple = ()  # names
    declared: tuple = ()  # Frame

    @functools.cached_property
    def by_name(self) -> dict:
        """{name: LinkFrame}, in tree order."""
        return {f.name: f for f in self.frames}

    @property
    def from_file(self) -> bool:
        """Whether the links are the file's own (URDF), not the bodies."""
        return self.kind == "link"

    @classmethod
    def of_bodies(cls, bodies) -> "Links":
        """Each body its own link, at its origin in its axes; the leaves are the bodies without a child body."""
        parents = {b.parent for b in bodies}
        return cls("body", tuple(LinkFrame(b.name, b.name) for b in bodies),
                   tuple(b.name for b in bodies if b.name not in parents))


@dataclass(frozen=True)
class Model:
    """A tree of bodies, parents listed before children.

    Per coordinate of q (in q order), read from the coordinates: ``joint_dynamics`` (a :class:`JointDynamics`:
    URDF ``<dynamics>`` damping and friction, None where absent; ``has_joint_dynamics`` says whether any is given)
    and ``limits`` (a dict ``{lower, upper, velocity, effort}`` from URDF ``<limit>``, None where absent).
    """

    name: str
    bodies: tuple
    gravity: tuple  # 3 expressions in the root (world) frame
    parameters: tuple = ()
    source: str = ""
    description: str = ""
    meta: dict = field(default_factory=dict, compare=False, hash=False)
    couplings: tuple = ()  # Coupling: coordinates tied to others, not in q
    armature: float = 0.0  # a rotor inertia on every coordinate (Pinocchio's armature): A(q) + armature E
    constraints: tuple = ()  # Constraint: bilateral constraints with the medium and closed loops (chapter 4)
    stabilization: tuple = (0, 0)  # (kp, kd) expressions: Baumgarte terms J qdd + gamma = -(kd J qd + kp phi)
    support: str | None = None  # the support body (the support paper): its 6 coordinates are q, the others gamma
    frames: tuple = ()  # Frame: the frames of the frame routines, in output order (see aggsym.model.transforms.frames)
    routines: tuple | None = None  # the routines to emit (--routines), None: the contract's default set
    regularization: object = 0  # epsilon: constrained forward dynamics solves (J A^-1 J^T + epsilon E) lambda = ...
    proximal: tuple = ()  # (mu expression, iterations): the damped (proximal) solve of the Delassus system
    # (aggsym.mechanics.damped); empty: the exact solve
    links: Links | None = None  # the file's links (see Links); None: each body is its own link (see link_table)
    dof_armature: tuple = ()  # per pair coordinate (tree order): a rotor inertia of its own on A's diagonal, added to
    # ``armature`` (MJCF ``armature``; expressions, usually runtime parameters); empty: none
    damping: tuple = ()  # per pair coordinate (tree order): viscous damping d, the force d qd on the left side of the
    # equations of motion beside the elastic C (q - q0) (MJCF ``damping``, URDF ``<dynamics damping>`` under
    # ``--passive include``; expressions); empty: none
    coulomb: tuple = ()  # per pair coordinate (tree order): Coulomb friction f, the force f sign(qd) on the left side
    # (MJCF ``frictionloss`` under ``--frictionloss coulomb``, URDF ``<dynamics friction>`` under ``--passive include``;
    # expressions); empty: none
    tendons: tuple = ()  # Tendon: fixed tendons with springs or dampers, their forces on the left side
    spatial_tendons: tuple = ()  # SpatialTendon: tendons through sites with springs or dampers (left side)
    fluid: tuple = ()  # FluidBox: the bodies of MuJoCo's inertia-box fluid model (their drag on the left side)
    fluid_ellipsoids: tuple = ()  # FluidEllipsoid: the geoms of MuJoCo's ellipsoid fluid model (left side)
    fluid_medium: tuple = ()  # (density, viscosity, (wind_x, wind_y, wind_z)) expressions, with ``fluid`` or
    # ``fluid_ellipsoids``
    gravcomp: tuple = ()  # (body name, m_s, (h_x, h_y, h_z)): the compensated weight of a body (MuJoCo's gravcomp),
    # a mass and its first moment about the body origin in body axes, lifted against gravity among the passive
    # forces (aggsym.mechanics.gravcomp; expressions); empty: none
    inertial_blocks: tuple = ()  # InertialBlock: links whose ten inertial parameters are entries of p (--payload,
    # --inertial-parameters), each with a generated helper that writes them

    @property
    def link_table(self) -> Links:
        """The model's :class:`Links`: those its reader set, or each body its own link."""
        return self.links if self.links is not None else Links.of_bodies(self.bodies)

    @property
    def constraint_rows(self) -> int:
        """m: the number of rows of all constraints (the length of lambda)."""
        return sum(len(c.rows) for c in self.constraints)

    @property
    def mechanism_coordinates(self) -> int:
        """k: the coordinates gamma of the mechanism carried by the support (nq - 6), 0 without a support."""
        return self.nv - 6 if self.support else 0

    @property
    def slip_rows(self) -> int:
        """The number of slip velocities: the free translations of every constraint."""
        return sum(len(c.free_translations) for c in self.constraints)

    @property
    def has_friction(self) -> bool:
        return any(c.friction is not None for c in self.constraints)

    @functools.cached_property
    def pair_coordinates(self) -> tuple:
        """Every coordinate of every pair, in tree order (the coordinates the recursions move)."""
        return tuple(c for b in self.bodies for c in b.pair.coordinates)

    @functools.cached_property
    def coordinates(self) -> tuple:
        """The coordinates of q: the pairs' coordinates less those coupled to others."""
        coupled = {c.coordinate for c in self.couplings}
        return tuple(c for c in self.pair_coordinates if c.name not in coupled)

    @functools.cached_property
    def nv(self) -> int:
        """The number of coordinates: the length of qd, qdd and tau (Pinocchio's nv)."""
        return len(self.coordinates)

    @functools.cached_property
    def nq(self) -> int:
        """The length of q: nv, plus one for each free-flyer (seven positions for its six velocities) and each ball
        pair (four positions for its three)."""
        return self.nv + sum(1 for b in self.bodies if b.pair.quaternion)

    @functools.cached_property
    def positions(self) -> tuple:
        """The entries of q as (name, joint, kind): a free-flyer pair's seven positions, a ball pair's four, every
        other coordinate itself (in tree order)."""
        coupled = {c.coordinate for c in self.couplings}
        out = []
        for b in self.bodies:
            if b.pair.quaternion:
                out.extend((n, b.pair.name, k) for n, k in zip(b.pair.positions, b.pair.position_kinds))
            else:
                out.extend((c.name, c.joint, c.kind) for c in b.pair.coordinates if c.name not in coupled)
        return tuple(out)

    @property
    def joint_dynamics(self) -> tuple:
        """Per coordinate of q: its joint's :class:`JointDynamics` (damping, friction; None where absent)."""
        return tuple(c.dynamics for c in self.coordinates)

    @property
    def has_joint_dynamics(self) -> bool:
        """True when some coordinate of q has a damping or friction value (a URDF ``<dynamics>``)."""
        return any(d.given for d in self.joint_dynamics)

    @property
    def limits(self) -> tuple:
        """Per coordinate of q: ``{"lower", "upper", "velocity", "effort"}`` from its joint's ``<limit>``, None where
        absent (fresh dicts: the model stays immutable)."""
        return tuple(c.limits.as_dict() for c in self.coordinates)

    @property
    def has_prescribed_spins(self) -> bool:
        """True when some pair of the tree moves as a prescribed function of time (a rotor's spin, (2.13))."""
        return any(b.pair.prescribed for b in self.bodies)

    @property
    def time_dependent(self) -> bool:
        """True when some pair moves as a prescribed function of time (a rotor's spin), or a constraint's
        reference frame does (``motion:``, a moving platform): then every routine takes the time t as an input."""
        return self.has_prescribed_spins or any(c.motion for c in self.constraints)

    @property
    def elastic_coordinates(self) -> tuple:
        """Indices (in q order) of the coordinates of the elastic pairs: the 'fast' motions of Prop. 2.14."""
        out, i = [], 0
        for b in self.bodies:
            n = len(b.pair.coordinates)
            if b.pair.elastic:
                out.extend(range(i, i + n))
            i += n
        return tuple(out)

    @property
    def has_fluid(self) -> bool:
        """Whether a fluid model acts (MuJoCo's inertia box on some body, its ellipsoid model on some geom)."""
        return bool(self.fluid or self.fluid_ellipsoids)

    @property
    def conservative(self) -> bool:
        """True when tau = 0 conserves T + U: no prescribed motion (a prescribed spin injects energy); elastic
        pairs and added masses keep it (U holds 1/2 q^T C q, T the medium's 1/2 V^T Lambda V); friction on a
        sliding contact (chapter 4) dissipates it, and so does viscous joint damping (``damping``).  The armature's
        rotors keep it (T holds their 1/2 a qd^2)."""
        return (not self.time_dependent and not self.has_friction and not self.has_damping and not self.coulomb
                and not self.has_fluid
                and not any(not (_zero(t.damping) and _zero(t.friction)) for t in self.tendons + self.spatial_tendons))

    @property
    def has_damping(self) -> bool:
        """True when some coordinate has a viscous damping or a Coulomb friction in the equations that is not
        exactly zero (``damping``, ``coulomb``)."""
        return any(not (getattr(d, "is_zero", False) or d == 0) for d in self.damping + self.coulomb)

    @functools.cached_property
    def parameter_symbols(self) -> tuple:
        return tuple(p.symbol for p in self.parameters)

    @property
    def parameter_values(self) -> tuple:
        return tuple(float(p.value) for p in self.parameters)

    def body(self, name: str) -> Body:
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(name)
