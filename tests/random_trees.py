"""Random URDF trees for testing the URDF reader against Pinocchio.

``random_urdf(seed)`` writes the text of a branching tree whose file exercises every feature the reader maps:
revolute, continuous, prismatic and fixed joints (chains of fixed joints included); joint axes along +-x, +-y,
+-z (sometimes scaled, e.g. ``0 0 -2``) and arbitrary directions (sometimes not of unit length); joint origins
with arbitrary and with right-angle roll-pitch-yaw; inertial frames with offsets and rotations, so the tensors
in the link frames have products of inertia (built physical: R diag(principal moments) R^T with the moments
satisfying the triangle inequality); massless links; a link of mass 0 with rotational inertia; joint names in
no particular order (so Pinocchio's sibling order, by name, differs from the file's); elements shuffled; in
every third file (URDF 1.1) some joint origins given as quaternions ``quat_xyzw``.
Numbers are written with ``repr`` so both readers see the same doubles.
"""
from __future__ import annotations

import math

import numpy as np

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed")
JOINT_WEIGHTS = (0.35, 0.15, 0.2, 0.3)
EXACT_AXES = ((1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1))
RIGHT_ANGLES = (0.0, math.pi / 2, -math.pi / 2, math.pi)
SYLLABLES = ("ka", "Zu", "mi", "_o", "re", "Ta", "x-", "po", "LI", "ne")


def _f(x: float) -> str:
    return repr(float(x))


def _vec(v) -> str:
    return " ".join(_f(x) for x in v)


def _rpy_matrix(r, p, y) -> np.ndarray:
    cr, sr, cp, sp_, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    Ry = np.array([[cp, 0, sp_], [0, 1, 0], [-sp_, 0, cp]])
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def _rpy(rng) -> tuple:
    kind = rng.random()
    if kind < 0.25:
        return (0.0, 0.0, 0.0)
    if kind < 0.5:
        return tuple(float(rng.choice(RIGHT_ANGLES)) for _ in range(3))
    return tuple(float(x) for x in rng.uniform(-math.pi, math.pi, 3))


def _axis(rng) -> tuple:
    if rng.random() < 0.5:
        scale = float(rng.choice((1.0, 1.0, 2.0, 0.5)))
        return tuple(scale * a for a in EXACT_AXES[rng.integers(6)])
    v = rng.normal(size=3)
    v /= np.linalg.norm(v)
    if rng.random() < 0.3:
        v *= rng.uniform(0.2, 3.0)  # not of unit length: the readers normalize
    return tuple(float(x) for x in v)


def _inertial(rng, zero_mass=False) -> str:
    a, b = rng.uniform(0.01, 0.1, 2)
    c = rng.uniform(abs(a - b) + 1e-3, a + b - 1e-3)  # triangle inequality
    R = _rpy_matrix(*rng.uniform(-math.pi, math.pi, 3))
    J = R @ np.diag([a, b, c]) @ R.T
    mass = 0.0 if zero_mass else rng.uniform(0.2, 3.0)
    xyz = rng.normal(scale=0.1, size=3)
    rpy = _rpy(rng)
    return (f'    <inertial>\n      <origin xyz="{_vec(xyz)}" rpy="{_vec(rpy)}"/>\n'
            f'      <mass value="{_f(mass)}"/>\n'
            f'      <inertia ixx="{_f(J[0, 0])}" ixy="{_f(J[0, 1])}" ixz="{_f(J[0, 2])}" iyy="{_f(J[1, 1])}" '
            f'iyz="{_f(J[1, 2])}" izz="{_f(J[2, 2])}"/>\n    </inertial>\n')


def _quaternion(rpy) -> tuple:
    """(x, y, z, w) of Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = (a / 2 for a in rpy)
    cr, sr, cp, sp_, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return (sr * cp * cy - cr * sp_ * sy, cr * sp_ * cy + sr * cp * sy, cr * cp * sy - sr * sp_ * cy,
            cr * cp * cy + sr * sp_ * sy)


def _name(rng, used: set) -> str:
    while True:
        name = "".join(rng.choice(SYLLABLES) for _ in range(rng.integers(1, 4)))
        if name not in used:
            used.add(name)
            return name


def random_urdf(seed: int, links: int | None = None) -> str:
    """The URDF text of a random branching tree (``links`` links, default 6 to 13)."""
    rng = np.random.default_rng(seed)
    n = int(links if links is not None else rng.integers(6, 14))
    quaternions = seed % 3 == 2
    link_names, joint_names = set(), set()
    names = [_name(rng, link_names) for _ in range(n)]
    elements = []
    zero_mass = int(rng.integers(1, n)) if rng.random() < 0.3 else -1
    for k, name in enumerate(names):
        body = ""
        if k == 0 or k == zero_mass or rng.random() < 0.85:
            body = _inertial(rng, zero_mass=(k == zero_mass))
        elements.append(f'  <link name="{name}">\n{body}  </link>\n')
    for k in range(1, n):
        parent = names[int(rng.integers(max(0, k - 3), k)) if rng.random() < 0.6 else int(rng.integers(0, k))]
        jtype = "revolute" if k == 1 else str(rng.choice(JOINT_TYPES, p=JOINT_WEIGHTS))
        xyz = rng.normal(scale=0.3, size=3)
        rpy = _rpy(rng)
        rotation = f'quat_xyzw="{_vec(_quaternion(rpy))}"' if quaternions and rng.random() < 0.5 else \
            f'rpy="{_vec(rpy)}"'
        text = (f'  <joint name="{_name(rng, joint_names)}" type="{jtype}">\n'
                f'    <parent link="{parent}"/>\n    <child link="{names[k]}"/>\n'
                f'    <origin xyz="{_vec(xyz)}" {rotation}/>\n')
        if jtype != "fixed":
            axis = _axis(rng)
            if axis != (1.0, 0.0, 0.0) or rng.random() < 0.5:  # else the default axis
                text += f'    <axis xyz="{_vec(axis)}"/>\n'
        if jtype in ("revolute", "prismatic"):
            text += '    <limit lower="-3" upper="3" effort="10" velocity="10"/>\n'
        elements.append(text + "  </joint>\n")
    order = rng.permutation(len(elements))
    version = ' version="1.1"' if quaternions else ""
    return (f'<?xml version="1.0"?>\n<robot name="random_tree_{seed}"{version}>\n'
            + "".join(elements[i] for i in order) + "</robot>\n")
