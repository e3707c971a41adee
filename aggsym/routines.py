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
from . import sweeps, transvective
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


def inverse_dynamics_by_equations(bound, kin, qd, qdd):
    """A(q) qdd + b(q, qd) + g(q) from the assembled equations (2.17), (2.29): a cross-check of the sweep."""
    A = inertia_matrix(bound, kin)
    b = bias_vector(bound, kin, qd)
    g = gravity_vector(bound, kin)
    return [dot(A[i], qdd) + b[i] + g[i] for i in range(len(b))]


ROUTINES: dict[str, Routine] = {}


def register(routine: Routine) -> Routine:
    """Add a routine to the contract's list (order of registration is the order of emission)."""
    ROUTINES[routine.role] = routine
    return routine


def _zeros(kin):
    return [0] * kin.tree.nq


register(Routine("inertia", ("q", "p"), (Output("A", nq_square, symmetric=True),),
                 lambda bound, kin, x: (_flat(inertia_matrix(bound, kin)),),
                 "A(q), the inertia matrix, n*n row-major, by composite bodies (2.32)-(2.34)"))
register(Routine("bias", ("q", "qd", "p"), (Output("b", nq_vector),),
                 lambda bound, kin, x: (sweeps.d_vector(bound, kin, x["qd"], gravity=False),),
                 "b(q, qd), the velocity terms: d(q, qd) of the sweeps (2.44)-(2.46) without gravity, = b by (2.52)"))
register(Routine("gravity", ("q", "p"), (Output("g", nq_vector),),
                 lambda bound, kin, x: (sweeps.inverse_dynamics(bound, kin, _zeros(kin), _zeros(kin)),),
                 "g(q) = -S G, the generalized gravity force on the left side (the sweeps at rest)"))
register(Routine("nonlinear_effects", ("q", "qd", "p"), (Output("d", nq_vector),),
                 lambda bound, kin, x: (sweeps.d_vector(bound, kin, x["qd"]),),
                 "d(q, qd) = b(q, qd) + g(q): the sweeps with qdd = 0 (2.44)-(2.46), (2.52)"))
register(Routine("inverse_dynamics", ("q", "qd", "qdd", "p"), (Output("tau", nq_vector),),
                 lambda bound, kin, x: (sweeps.inverse_dynamics(bound, kin, x["qd"], x["qdd"]),),
                 "tau = u* by the forward and backward sweeps (2.39)-(2.42); equals A(q) qdd + b(q, qd) + g(q)"))
register(Routine("kinetic_energy", ("q", "qd", "p"), (Output("T", scalar),),
                 lambda bound, kin, x: ([kinetic_energy(bound, kin, x["qd"])],),
                 "T = 1/2 qd^T A(q) qd (Def. 2.4)"))
register(Routine("potential_energy", ("q", "p"), (Output("U", scalar),),
                 lambda bound, kin, x: ([potential_energy(bound, kin)],),
                 "U(q), the potential energy of gravity"))
register(Routine("joint_wrenches", ("q", "qd", "qdd", "p"),
                 (Output("W", lambda model: (len(sweeps.pair_bodies(model)), 6)),),
                 lambda bound, kin, x: ([v for row in sweeps.joint_wrench_rows(
                     bound, sweeps.transmitted_wrenches(bound, kin, x["qd"], x["qdd"])) for v in row],),
                 "W: per joint, the wrench (f, mu) from parent to child in the child frame (2.42)",
                 layout=sweeps.joint_wrench_layout))
register(Routine("forward_dynamics", ("q", "qd", "tau", "p"), (Output("qdd", nq_vector),),
                 lambda bound, kin, x: (transvective.forward_dynamics(bound, kin, x["tau"], x["qd"]),),
                 "qdd = T^T diag(1/(beta,beta)) T (tau - b - g), the transvective Cauchy form (3.20), evaluated "
                 "in O(n)"))
register(Routine("inertia_inverse", ("q", "p"), (Output("Ainv", nq_square, symmetric=True),),
                 lambda bound, kin, x: (_flat(transvective.inertia_inverse(bound, kin)),),
                 "A(q)^-1 = T^T diag(1/(beta,beta)) T, n*n row-major (3.19)"))
register(Routine("transvective_factors", ("q", "p"),
                 (Output("targs", transvective.number_of_transvections), Output("diag", nq_vector)),
                 lambda bound, kin, x: transvective.factor_outputs(bound, kin),
                 "the arguments <t,k> of the transvections of T (3.8), (3.9) and the pivots (beta,beta)^k "
                 "of T A(q) T^T = diag (3.11)", layout=transvective.layout))


def run(routine: Routine, bound, inputs: dict) -> tuple:
    """Evaluate a routine on a bound model; ``inputs`` maps vector names (without p) to lists of scalars.

    Returns one flat list of scalars per output."""
    kin = TreeKinematics(bound, inputs["q"])
    return routine.build(bound, kin, inputs)


def input_length(model, name: str) -> int:
    return len(model.parameters) if name == "p" else model.nq
