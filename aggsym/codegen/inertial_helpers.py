"""The generated helpers that write a link's ten inertial parameters into p: ``NAME_set_payload_<link>`` (C) and
``set_payload_<link>`` (the NumPy, JAX and PyTorch modules), ``set_inertial_<link>`` for a link's own data
(``--inertial-parameters``), one per :class:`~aggsym.model.types.InertialBlock` of the model.

The user gives what a URDF ``<inertial>`` gives, in the link frame: the mass m, the centre of mass c (link axes,
from the link frame's origin) and the inertia tensor about the centre of mass in link axes,
I = (ixx, ixy, ixz, iyy, iyz, izz) in URDF's attribute order, whose off-diagonal entries are the tensor's (ixy =
-integral of x y dm, as URDF and Pinocchio read them).  p holds the regressor's form about the link frame's
origin (:mod:`aggsym.model.transforms.inertials`): m, m c, and the parallel-axis theorem I_O = I + m (|c|^2 E - c c^T), in
the order Ixx, Ixy, Iyy, Ixz, Iyz, Izz.  The helper does that arithmetic; the expressions are written here once and
spelled by each target (C arrays ``c[0]``, batched Python ``c[..., 0]``).
"""
from __future__ import annotations

from types import SimpleNamespace

from .names import parameter_macro

# the inertia the user gives: URDF's <inertia> attributes, in their order
INPUT_ORDER = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")

CONVENTION = ("m: mass (kg); c: centre of mass (m) in the link frame; I: inertia tensor (kg m^2) about the centre "
              "of mass in link axes, (ixx, ixy, ixz, iyy, iyz, izz) in URDF's <inertia> order, its entries the "
              "tensor's (ixy = -integral of x*y dm, as URDF and Pinocchio); the helper writes m, m c and the "
              "inertia about the link frame's origin (parallel-axis theorem) into p")


def _expressions(m: str, c, I) -> list:
    """The ten parameters (m, mcx, mcy, mcz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz) as text, from the spelled inputs: ``m``,
    ``c(i)`` the centre of mass's entry i, ``I(k)`` the k-th input inertia entry (INPUT_ORDER)."""
    xx, xy, xz, yy, yz, zz = (I(k) for k in range(6))
    x, y, z = c(0), c(1), c(2)
    return [m, f"{m} * {x}", f"{m} * {y}", f"{m} * {z}",
            f"{xx} + {m} * ({y} * {y} + {z} * {z})",
            f"{xy} - {m} * {x} * {y}",
            f"{yy} + {m} * ({x} * {x} + {z} * {z})",
            f"{xz} - {m} * {x} * {z}",
            f"{yz} - {m} * {y} * {z}",
            f"{zz} + {m} * ({x} * {x} + {y} * {y})"]


def inertial_helpers(model) -> list:
    """Per inertial block: its ``kind``, ``link``, ``helper`` (the Python name), ``c_name`` (``NAME_<helper>``) and
    ``entries``: (parameter name, index in p, index macro, C expression, Python expression) in p's order."""
    index = {p.name: i for i, p in enumerate(model.parameters)}
    by_name = {p.name: p for p in model.parameters}
    out = []
    for block in model.inertial_blocks:
        c_text = _expressions("m", lambda i: f"c[{i}]", lambda k: f"I[{k}]")
        py_text = _expressions("m", lambda i: f"c[..., {i}]", lambda k: f"I[..., {k}]")
        entries = [SimpleNamespace(name=n, index=index[n], macro=parameter_macro(model, by_name[n]), c=ce, py=pe)
                   for n, ce, pe in zip(block.parameters, c_text, py_text)]
        out.append(SimpleNamespace(kind=block.kind, link=block.link, helper=block.helper,
                                   c_name=f"{model.name}_{block.helper}", entries=entries,
                                   indices=[e.index for e in entries]))
    return out


def manifest_entry(model) -> list:
    """The manifest's ``inertial_helpers``: per block, the link, what it is, the C and Python helpers, the ten
    parameters it writes, and the convention of its inputs."""
    return [{"link": b.link, "kind": b.kind, "c": f"{model.name}_{b.helper}", "python": b.helper,
             "parameters": list(b.parameters), "inputs": {"m": 1, "c": 3, "I": list(INPUT_ORDER)},
             "convention": CONVENTION} for b in model.inertial_blocks]


__all__ = ["CONVENTION", "INPUT_ORDER", "inertial_helpers", "manifest_entry"]
