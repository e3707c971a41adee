"""The tests' small URDF robots, written from their numbers by name instead of as pasted text.

Two layers, one layout:

* :func:`link`, :func:`joint`, :func:`robot` and :func:`arm` write elements in a fixed layout (a link on one line,
  a joint on five: the opening tag, ``<parent>``, ``<child>``, the inner elements, ``</joint>``), the text the
  error-location tests edit and count lines in (tests/test_urdf_validation.py, tests/test_urdf_safety.py): what
  they write must not change, or those tests' lines move.
* :func:`segment` (a joint and the link it carries), :func:`root` (the root link) and :func:`chain` write a robot
  from its numbers, in that layout: a serial chain by default, a tree where a segment names its ``parent``.
  :func:`inertial`, :func:`origin` and :func:`limit` are the pieces; :func:`rubbing` is a robot of two modules.

Numbers are written as given: a string as it stands (``"0.1 0 0"``), an integer as an integer, any other number
by ``repr(float(x))``, so the file holds the test's own doubles digit for digit.  Names and other text go in
verbatim (a test that wants hostile names escapes them for XML itself).

Robots whose point is their literal text stay as text: in their test, or as files in tests/data (read through
``helpers.data_text``).
"""
from __future__ import annotations

import numbers
from dataclasses import dataclass

XML = '<?xml version="1.0"?>\n'
INERTIA = '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>'
INERTIAL = f'<inertial><mass value="1"/>{INERTIA}</inertial>'  # the unit link of the error-location tests
AXIS = '<axis xyz="0 0 1"/>'


# --------------------------------------------------------------------------------------------------------------
# elements in the fixed layout


def link(name, inertial=INERTIAL) -> str:
    """``<link>`` on one line (``inertial=""``: a massless link)."""
    return f'  <link name="{name}">{inertial}</link>\n'


def joint(name, parent, child, jtype="revolute", inner=AXIS) -> str:
    """``<joint>`` on five lines, ``inner`` (origin, axis, limit, ...) on the fourth."""
    return (f'  <joint name="{name}" type="{jtype}">\n'
            f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n    {inner}\n  </joint>\n')


def robot(*parts, name="r", head=XML) -> str:
    """``<robot>`` around the parts: the declaration (``head``) on line 1, ``<robot name>`` on line 2."""
    return f'{head}<robot name="{name}">\n' + "".join(parts) + "</robot>\n"


def arm(*extra, inner=AXIS, head=XML, name="r") -> str:
    """base -> upper (shoulder) -> lower (elbow), unit links, both joints' inner elements ``inner``, plus extra
    elements."""
    return robot(link("base"), link("upper"), link("lower"), joint("shoulder", "base", "upper", inner=inner),
                 joint("elbow", "upper", "lower", inner=inner), *extra, head=head, name=name)


# --------------------------------------------------------------------------------------------------------------
# robots from their numbers


def number(x) -> str:
    """A number as the file writes it: a string as it stands, an integer as an integer, else repr(float)."""
    if isinstance(x, str):
        return x
    if isinstance(x, numbers.Integral):
        return str(int(x))
    return repr(float(x))


def vector(v) -> str:
    """Numbers separated by spaces (a string as it stands)."""
    return v if isinstance(v, str) else " ".join(number(x) for x in v)


def origin(xyz=None, rpy=None) -> str:
    """``<origin>`` with the attributes given ('' with none)."""
    attributes = "".join(f' {k}="{vector(v)}"' for k, v in (("xyz", xyz), ("rpy", rpy)) if v is not None)
    return f"<origin{attributes}/>" if attributes else ""


def inertial(mass, com=None, inertia=(0, 0, 0), rpy=None) -> str:
    """``<inertial>``: the centre of mass ``com`` (and the inertial frame's ``rpy``), ``inertia`` = (ixx, iyy, izz)
    or (ixx, iyy, izz, ixy, ixz, iyz) about it (a string of those numbers, or a sequence)."""
    values = inertia.split() if isinstance(inertia, str) else list(inertia)
    values = values + [0] * (6 - len(values)) if len(values) == 3 else values
    if len(values) != 6:
        raise ValueError(f"inertia: 3 or 6 numbers, got {inertia!r}")
    tensor = " ".join(f'{k}="{number(v)}"' for k, v in zip(("ixx", "iyy", "izz", "ixy", "ixz", "iyz"), values))
    return f'<inertial>{origin(com, rpy)}<mass value="{number(mass)}"/><inertia {tensor}/></inertial>'


def limit(spec) -> str:
    """``<limit>`` of (lower, upper, effort, velocity), or of a dict of attributes in its order ('' for None)."""
    if spec is None:
        return ""
    if not isinstance(spec, dict):
        spec = dict(zip(("lower", "upper", "effort", "velocity"), spec))
    return "<limit" + "".join(f' {k}="{number(v)}"' for k, v in spec.items()) + "/>"


@dataclass(frozen=True)
class Segment:
    """A link and the joint that carries it (``joint`` None: the root link); see :func:`segment`."""
    link: str
    joint: str | None = None
    jtype: str = "revolute"
    parent: str | None = None
    xyz: object = None
    rpy: object = None
    axis: object = None
    limit: object = None
    damping: object = None
    friction: object = None
    mimic: object = None
    mass: object = None
    com: object = None
    inertia: object = (0, 0, 0)
    com_rpy: object = None

    def link_text(self) -> str:
        return link(self.link, "" if self.mass is None else inertial(self.mass, self.com, self.inertia, self.com_rpy))

    def joint_text(self, parent) -> str:
        inner = origin(self.xyz, self.rpy)
        if self.axis is not None:
            inner += f'<axis xyz="{vector(self.axis)}"/>'
        inner += limit(self.limit)
        dynamics = "".join(f' {k}="{number(v)}"' for k, v in (("damping", self.damping), ("friction", self.friction))
                           if v is not None)
        if dynamics:
            inner += f"<dynamics{dynamics}/>"
        if self.mimic is not None:
            master, *rest = (self.mimic,) if isinstance(self.mimic, str) else self.mimic
            factors = "".join(f' {k}="{number(v)}"' for k, v in zip(("multiplier", "offset"), rest))
            inner += f'<mimic joint="{master}"{factors}/>'
        return joint(self.joint, self.parent or parent, self.link, self.jtype, inner)


def segment(joint_name, link_name, jtype="revolute", **attributes) -> Segment:
    """The joint ``joint_name`` of type ``jtype`` and its child link ``link_name``.  Keywords: ``parent`` (the
    previous segment's link unless given), the joint's ``xyz``, ``rpy``, ``axis``, ``limit`` (see :func:`limit`),
    ``damping``, ``friction``, ``mimic`` (the master's name, or (master, multiplier[, offset])); the link's
    ``mass`` (none: massless), ``com``, ``inertia`` and ``com_rpy`` (see :func:`inertial`)."""
    return Segment(link_name, joint_name, jtype, **attributes)


def root(link_name, **attributes) -> Segment:
    """The root link of a :func:`chain` that carries mass (``mass``, ``com``, ``inertia``, ``com_rpy``)."""
    return Segment(link_name, **attributes)


def chain(name, *segments, base="base", head=XML) -> str:
    """A robot of segments, each carried by the one before unless it names its ``parent``; the root is the first
    segment when it is a :func:`root`, else a massless link ``base``.  The links come first, then the joints, in
    the segments' order."""
    if segments[0].joint is not None:
        segments = (root(base),) + segments
    links, joints = [], []
    for before, s in zip((None,) + segments, segments):
        links.append(s.link_text())
        if s.joint is not None:
            joints.append(s.joint_text(before.link))
    return robot(*links, *joints, name=name, head=head)


# --------------------------------------------------------------------------------------------------------------
# robots that several modules use


def rubbing(a_com="0.1 0 0", a_inertia=(0.01, 0.02, 0.03), b_com="0.1 0 0", b_inertia=(0.01, 0.02, 0.03),
            j3_damping=None, j2_xyz="0.2 0 0", j2_rpy=None) -> str:
    """A revolute, a continuous and a prismatic joint in a chain, with URDF <dynamics> (damping 0.7 and friction
    0.2 on j1, friction 1.5 and damping ``j3_damping`` on j3) and <limit> on j1 and j3; the first two links'
    centres of mass and inertias, and j2's origin, as given (tests/test_joint_friction.py,
    tests/test_regressor_friction.py)."""
    return chain("rubbing",
                 segment("j1", "a", axis="0 0 1", damping=0.7, friction=0.2, limit=(-2, 2.5, 30, 4),
                         mass=1, com=a_com, inertia=a_inertia),
                 segment("j2", "b", "continuous", xyz=j2_xyz, rpy=j2_rpy, axis="0 1 0", mass=0.5, com=b_com,
                         inertia=b_inertia),
                 segment("j3", "c", "prismatic", xyz="0.2 0 0", axis="0 0 -1", damping=j3_damping, friction=1.5,
                         limit=(0, 0.3, 100, 0.5), mass=0.3, com="0 0 0.1", inertia=(0.01, 0.01, 0.01)))
