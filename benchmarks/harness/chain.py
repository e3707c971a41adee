"""The benchmark's 3-D n-link chains: a spatial serial arm of n revolute joints, as an aggsym YAML model.

Body k (k = 1..n) hangs from body k-1 (body 0 is the world) by a one-coordinate rotation pair:

- joint axis: z, y, x, z, y, x, ... (``theta6``, ``theta5``, ``theta4`` in the book's codes), so consecutive
  axes are perpendicular and the arm moves in 3-D (no planar sub-chains, no parallel neighbours);
- offset: the constant translation from body k-1's frame to joint k, in body k-1's axes: a link of length
  0.20..0.40 m along its local z axis with lateral offsets of 0.01..0.06 m along x and y (all three components
  non-zero, so no offset coordinate folds away; joint 1 sits at the world origin);
- mass 0.5..3 kg, centre of mass with three non-zero components, and a full inertia tensor about the centre of
  mass (all six entries non-zero): R diag(I1, I2, I3) R^T with principal moments satisfying the triangle
  inequality strictly and a fixed tilt R, rounded to 6 decimals;
- gravity (0, 0, -9.81) in the world frame.

The numbers of body k come from a random generator seeded with k alone, so the chain of n links is the first
n links of the chain of n + 1: models of different n differ only in length.  Every number is a plain float in
the YAML, so both tools see the same constants (aggsym folds them into the generated code; KanesMethod gets
them as SymPy Floats).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

AXES = ("theta6", "theta5", "theta4")  # about z, y, x


def _rotation(rng) -> np.ndarray:
    """A fixed tilt: rotations about x, y, z by angles of 0.2..0.6 rad."""
    a, b, c = rng.uniform(0.2, 0.6, 3)
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    return rz @ ry @ rx


def link(k: int) -> dict:
    """The numbers of link k (1-based): axis code, offset, mass, centre of mass, inertia about the centre."""
    rng = np.random.default_rng(1000 + k)
    length = rng.uniform(0.20, 0.40)
    lateral = rng.uniform(0.01, 0.06, 2) * rng.choice([-1, 1], 2)
    offset = [0.0, 0.0, 0.0] if k == 1 else [round(float(lateral[0]), 4), round(float(lateral[1]), 4),
                                             round(float(length), 4)]
    mass = round(float(rng.uniform(0.5, 3.0)), 4)
    com = [round(float(x), 4) for x in (rng.uniform(0.01, 0.04, 3) * rng.choice([-1, 1], 3))]
    com[2] = abs(com[2]) + 0.08  # the centre of mass lies along the link
    principal = rng.uniform(0.004, 0.012, 3) * mass  # within a factor 3: the triangle inequality holds
    principal = np.sort(principal)
    principal[2] = min(principal[2], 0.95 * (principal[0] + principal[1]))
    R = _rotation(rng)
    J = R @ np.diag(principal) @ R.T
    inertia = {"xx": J[0, 0], "yy": J[1, 1], "zz": J[2, 2], "xy": J[0, 1], "xz": J[0, 2], "yz": J[1, 2]}
    return {"axis": AXES[(k - 1) % 3], "offset": offset, "mass": mass, "com": com,
            "inertia": {key: round(float(v), 6) for key, v in inertia.items()}}


def _list(xs) -> str:
    return "[" + ", ".join(repr(float(x)) for x in xs) + "]"


def chain_yaml(n: int) -> str:
    """The YAML text of the n-link chain ``chain{n}``."""
    if n < 1:
        raise ValueError("a chain has at least one link")
    lines = [f"# {n}-link spatial serial arm for the benchmark (benchmarks/harness/chain.py): joint axes z, y, x, ...,",
             "# offsets with three non-zero components, full inertia tensors.  Generated; do not edit.",
             f"name: chain{n}",
             f"description: {n}-link spatial serial arm (benchmarks/harness/chain.py)",
             "gravity: [0, 0, -9.81]",
             "bodies:"]
    for k in range(1, n + 1):
        lines += body_lines(k, "world" if k == 1 else f"link{k - 1}")
    return "\n".join(lines) + "\n"


def body_lines(k: int, parent: str) -> list:
    """The YAML lines of link k (its numbers from :func:`link`) hung from ``parent``."""
    d = link(k)
    inertia = ", ".join(f"{key}: {value!r}" for key, value in d["inertia"].items())
    return [f"  - name: link{k}",
            f"    parent: {parent}",
            f"    pair: {{name: joint{k}, translation: {_list(d['offset'])}, functional: {{{d['axis']}: q{k}}}}}",
            f"    mass: {d['mass']!r}",
            f"    com: {_list(d['com'])}",
            f"    inertia: {{{inertia}}}"]


def write_text(folder, name: str, text: str) -> Path:
    """Write ``text`` to ``folder/name`` (the folder created; the file left alone when it already holds it)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    return path


def write_chain(n: int, folder) -> Path:
    """Write ``chain{n}.yaml`` into ``folder`` (created) and return its path."""
    return write_text(folder, f"chain{n}.yaml", chain_yaml(n))


def chain_model(n: int, folder):
    """The aggsym Model of the n-link chain (written to ``folder`` and read back by the YAML reader)."""
    import aggsym

    return aggsym.load(write_chain(n, folder))


_URDF_AXES = {"theta6": "0 0 1", "theta5": "0 1 0", "theta4": "1 0 0"}


def chain_urdf(n: int) -> str:
    """The n-link chain as a URDF (``chain{n}``), for the runtime section's three-way comparison (aggsym, Pinocchio
    and the CasADi peer all read this one file): link k's joint ``joint{k}`` is a revolute joint about the link's
    axis code (z, y, x, ...) at ``offset``, its inertial block the same mass, centre of mass and inertia tensor
    about the centre of mass (the tensor's entries as URDF's ixx ... izz) as :func:`link` gives the YAML."""
    if n < 1:
        raise ValueError("a chain has at least one link")
    lines = urdf_head(n)
    for k in range(1, n + 1):
        link_lines, joint_lines = urdf_lines(k)
        lines += link_lines + joint_lines
    return "\n".join(lines + ["</robot>"]) + "\n"


def urdf_head(n: int) -> list:
    """The first lines of the URDF of the n-link chain, up to its root link ``world``."""
    return ['<?xml version="1.0"?>', f'<!-- {n}-link spatial serial arm (benchmarks/harness/chain.py). Generated. -->',
            f'<robot name="chain{n}">', '  <link name="world"/>']


def urdf_lines(k: int) -> tuple:
    """(the ``<link>`` lines, the ``<joint>`` lines) of link k (its numbers from :func:`link`) in the URDF."""
    d = link(k)
    i = d["inertia"]
    link_lines = [f'  <link name="link{k}">',
                  '    <inertial>',
                  f'      <origin xyz="{" ".join(repr(float(x)) for x in d["com"])}" rpy="0 0 0"/>',
                  f'      <mass value="{d["mass"]!r}"/>',
                  f'      <inertia ixx="{i["xx"]!r}" ixy="{i["xy"]!r}" ixz="{i["xz"]!r}" iyy="{i["yy"]!r}" '
                  f'iyz="{i["yz"]!r}" izz="{i["zz"]!r}"/>',
                  '    </inertial>',
                  '  </link>']
    joint_lines = [f'  <joint name="joint{k}" type="revolute">',
                   f'    <parent link="{"world" if k == 1 else f"link{k - 1}"}"/>',
                   f'    <child link="link{k}"/>',
                   f'    <origin xyz="{" ".join(repr(float(x)) for x in d["offset"])}" rpy="0 0 0"/>',
                   f'    <axis xyz="{_URDF_AXES[d["axis"]]}"/>',
                   '    <limit lower="-3.1416" upper="3.1416" effort="100" velocity="10"/>',
                   '  </joint>']
    return link_lines, joint_lines


def write_chain_urdf(n: int, folder) -> Path:
    """Write ``chain{n}.urdf`` into ``folder`` (created) and return its path."""
    return write_text(folder, f"chain{n}.urdf", chain_urdf(n))
