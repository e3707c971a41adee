"""The routines of the generated-code contract, each written once over a backend.

A routine takes named input vectors (``q``, ``qd``, ``qdd``, ``tau``; ``p`` is bound with the model) and returns
its output flattened row-major.  The same function gives the numeric twin (floats) and, on the symbolic
backend, the straight-line program that :mod:`aggsym.codegen` emits as C and NumPy.  Adding an output is
adding one entry to :data:`ROUTINES`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from .bias import bias_vector, gravity_vector
from .energy import kinetic_energy, potential_energy
from .inertia import inertia_matrix
from .kinematics import TreeKinematics
from .linalg import dot


@dataclass(frozen=True)
class Output:
    """One output array of a routine: its C argument name and shape (as a function of the model)."""

    name: str
    shape: Callable  # model -> tuple
    symmetric: bool = False  # an n x n output known to be symmetric


@dataclass(frozen=True)
class Routine:
    role: str  # the contract's name, e.g. "inertia" -> NAME_inertia
    inputs: tuple  # input vectors in argument order, "p" included where the C signature has it
    outputs: tuple  # Output, in argument order after the inputs
    build: Callable  # (bound, kinematics, inputs) -> tuple of flat lists, one per output
    doc: str
    layout: Callable | None = None  # model -> JSON-able description of the outputs' layout (manifest)
    applies: Callable | None = None  # model -> bool; None means every model has this routine

    def exists_for(self, model) -> bool:
        return self.applies is None or bool(self.applies(model))


def nq_vector(model):
    return (model.nq,)


def nq_square(model):
    return (model.nq, model.nq)


def scalar(model):
    return (1,)


def _flat(rows):
    return [x for row in rows for x in row]


def _inverse_dynamics(bound, kin, x):
    A = inertia_matrix(bound, kin)
    b = bias_vector(bound, kin, x["qd"])
    g = gravity_vector(bound, kin)
    return ([dot(A[i], x["qdd"]) + b[i] + g[i] for i in range(len(b))],)


ROUTINES: dict[str, Routine] = {}


def register(routine: Routine) -> Routine:
    """Add a routine to the contract's list (order of registration is the order of emission)."""
    ROUTINES[routine.role] = routine
    return routine


register(Routine("inertia", ("q", "p"), (Output("A", nq_square, symmetric=True),),
                 lambda bound, kin, x: (_flat(inertia_matrix(bound, kin)),),
                 "A(q), the inertia matrix, n*n row-major (2.32)-(2.34)"))
register(Routine("bias", ("q", "qd", "p"), (Output("b", nq_vector),),
                 lambda bound, kin, x: (bias_vector(bound, kin, x["qd"]),),
                 "b(q, qd), the velocity terms (2.36)-(2.37), Prop. 2.19"))
register(Routine("gravity", ("q", "p"), (Output("g", nq_vector),),
                 lambda bound, kin, x: (gravity_vector(bound, kin),),
                 "g(q) = -S G, the generalized gravity force on the left side"))
register(Routine("inverse_dynamics", ("q", "qd", "qdd", "p"), (Output("tau", nq_vector),), _inverse_dynamics,
                 "tau = A(q) qdd + b(q, qd) + g(q)"))
register(Routine("kinetic_energy", ("q", "qd", "p"), (Output("T", scalar),),
                 lambda bound, kin, x: ([kinetic_energy(bound, kin, x["qd"])],),
                 "T = 1/2 qd^T A(q) qd (Def. 2.4)"))
register(Routine("potential_energy", ("q", "p"), (Output("U", scalar),),
                 lambda bound, kin, x: ([potential_energy(bound, kin)],),
                 "U(q), the potential energy of gravity"))


def run(routine: Routine, bound, inputs: dict) -> tuple:
    """Evaluate a routine on a bound model; ``inputs`` maps vector names (without p) to lists of scalars.

    Returns one flat list of scalars per output."""
    kin = TreeKinematics(bound, inputs["q"])
    return routine.build(bound, kin, inputs)


def input_length(model, name: str) -> int:
    return len(model.parameters) if name == "p" else model.nq


from . import transvective  # noqa: E402,F401  (registers forward_dynamics, inertia_inverse, transvective_factors)
