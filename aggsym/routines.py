"""The routines of the generated-code contract, each written once over a backend.

A routine takes named input vectors (``q``, ``qd``, ``qdd``, ``tau``; ``p`` is bound with the model) and returns
its output flattened row-major.  The same function gives the numeric twin (floats) and, on the symbolic
backend, the straight-line program that :mod:`aggsym.codegen` emits as C and NumPy.  Adding an output is
adding one entry to :data:`ROUTINES`.

The equations are ``A(q) q'' + b(q, q') + g(q) + c(q) = tau`` (2.17), (2.27):

* ``c(q) = C (q - q0)``, the elastic generalized force of the Hooke-elastic pairs (routine ``elastic``, models
  with stiffness only); it is in ``inverse_dynamics``, ``nonlinear_effects`` (d = b + g + c) and hence
  ``forward_dynamics``, and its energy is in ``potential_energy``; ``bias`` and ``gravity`` never hold it.
* A model with prescribed motions (rotors with a prescribed spin, (2.13)) is time dependent: every routine then
  takes the time ``t`` (one number) after its other inputs and before ``p`` (:func:`signature`).  Its
  ``bias`` holds every term of the spins' rates and accelerations (the book's A'V and T of (2.13) less the
  rotors' weight, which is in ``gravity``), so that ``b = B q'`` no longer holds, and A(q, t) turns with the
  rotors.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from . import elastic
from .bias import bias_vector, coriolis_matrix, gravity_vector
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
    # with coupled coordinates (aggsym.coupling): "force" (outputs reduce by J^T), "matrix" (J^T X J), "tree"
    # (the tree's own outputs), "forward" / "inverse" (q'' and A^-1 under the coupling), None (not emitted)
    coupled: str | None = "force"

    def exists_for(self, model) -> bool:
        if model.couplings and self.coupled is None:
            return False
        return self.applies is None or bool(self.applies(model))


def signature(routine: Routine, model) -> tuple:
    """The routine's inputs for this model: ``t`` (the time, one number) is added before ``p`` when the model has
    prescribed motions (``model.time_dependent``)."""
    if not model.time_dependent:
        return routine.inputs
    ins = [i for i in routine.inputs if i != "p"]
    return tuple(ins + ["t"] + (["p"] if "p" in routine.inputs else []))


def nq_vector(model):
    return (model.nq,)


def nq_square(model):
    return (model.nq, model.nq)


def scalar(model):
    return (1,)


def _flat(rows):
    return [x for row in rows for x in row]


def inverse_dynamics_by_equations(bound, kin, qd, qdd):
    """A(q) qdd + b(q, qd) + g(q) + C (q - q0) from the assembled equations (2.17), (2.27), (2.29): a cross-check of
    the sweep."""
    A = inertia_matrix(bound, kin)
    b = bias_vector(bound, kin, qd)
    g = gravity_vector(bound, kin)
    c = elastic.elastic_forces(bound, kin.q)
    return [dot(A[i], qdd) + b[i] + g[i] + c[i] for i in range(len(b))]


def _plus(a, b):
    """a + b entry by entry (b's structural zeros fold)."""
    return [x + y for x, y in zip(a, b)]


def _minus(a, b):
    """a - b for two vectors of scalars (b may be all structural zeros)."""
    return [x - y for x, y in zip(a, b)]


ROUTINES: dict[str, Routine] = {}


def register(routine: Routine) -> Routine:
    """Add a routine to the contract's list (order of registration is the order of emission)."""
    ROUTINES[routine.role] = routine
    return routine


def _zeros(kin):
    return [0] * kin.tree.nq


register(Routine("inertia", ("q", "p"), (Output("A", nq_square, symmetric=True),),
                 lambda bound, kin, x: (_flat(inertia_matrix(bound, kin)),),
                 "A(q), the inertia matrix, n*n row-major, by composite bodies (2.32)-(2.34)",
                 coupled="matrix"))
register(Routine("bias", ("q", "qd", "p"), (Output("b", nq_vector),),
                 lambda bound, kin, x: (sweeps.d_vector(bound, kin, x["qd"], gravity=False),),
                 "b(q, qd), the velocity terms: d(q, qd) of the sweeps (2.44)-(2.46) without gravity, = b by (2.52) "
                 "(with prescribed spins: every term of their rates and accelerations too)"))

register(Routine("coriolis", ("q", "qd", "p"), (Output("C", nq_square),),
                 lambda bound, kin, x: (_flat(coriolis_matrix(bound, kin, x["qd"], skew=True)),),
                 "C(q, qd), n*n row-major: the Coriolis matrix with C qd = b and A' - 2C skew "
                 "(S (Phi(V) A + A phi(V)) S^T + S A S'^T, from the book's B of (2.17), (2.36)), for passivity-based "
                 "control", applies=lambda model: not model.time_dependent, coupled="matrix"))


def _gravity(bound, kin, x):
    """g = -S G: the sweeps at rest, or, when prescribed spins keep rotors turning at rest, the backward recurrence
    of -S G itself (:func:`aggsym.bias.gravity_vector`), which leaves their motion out."""
    if bound.model.time_dependent:
        return (gravity_vector(bound, kin),)
    return (sweeps.inverse_dynamics(bound, kin, _zeros(kin), _zeros(kin)),)


register(Routine("gravity", ("q", "p"), (Output("g", nq_vector),), _gravity,
                 "g(q) = -S G, the generalized gravity force on the left side (the sweeps at rest)"))
register(Routine("nonlinear_effects", ("q", "qd", "p"), (Output("d", nq_vector),),
                 lambda bound, kin, x: (_plus(sweeps.d_vector(bound, kin, x["qd"]),
                                              elastic.elastic_forces(bound, kin.q)),),
                 "d(q, qd) = b(q, qd) + g(q) + c(q): the sweeps with qdd = 0 (2.44)-(2.46), (2.52), plus the elastic "
                 "force C (q - q0) of (2.27)"))
register(Routine("inverse_dynamics", ("q", "qd", "qdd", "p"), (Output("tau", nq_vector),),
                 lambda bound, kin, x: (_plus(sweeps.inverse_dynamics(bound, kin, x["qd"], x["qdd"]),
                                              elastic.elastic_forces(bound, kin.q)),),
                 "tau = u* by the forward and backward sweeps (2.39)-(2.42) plus C (q - q0) (2.27); equals "
                 "A(q) qdd + b(q, qd) + g(q) + c(q)"))
register(Routine("elastic", ("q", "p"), (Output("c", nq_vector),),
                 lambda bound, kin, x: (elastic.elastic_forces(bound, kin.q),),
                 "c(q) = C (q - q0), the generalized force of the Hooke-elastic pairs on the left side of (2.27)",
                 applies=elastic.is_elastic))
register(Routine("kinetic_energy", ("q", "qd", "p"), (Output("T", scalar),),
                 lambda bound, kin, x: ([kinetic_energy(bound, kin, x["qd"])],),
                 "T = 1/2 sum V^T A_lk V over the bodies (Def. 2.4; with added masses the medium's 1/2 V^T Lambda V, "
                 "Prop. 2.8); = 1/2 qd^T A(q) qd without prescribed spins", coupled="tree"))
register(Routine("potential_energy", ("q", "p"), (Output("U", scalar),),
                 lambda bound, kin, x: ([potential_energy(bound, kin) + elastic.elastic_energy(bound, kin.q)],),
                 "U(q), the potential energy of gravity plus 1/2 (q - q0)^T C (q - q0) of the elastic pairs",
                 coupled="tree"))
register(Routine("joint_wrenches", ("q", "qd", "qdd", "p"),
                 (Output("W", lambda model: (len(sweeps.pair_bodies(model)), 6)),),
                 lambda bound, kin, x: ([v for row in sweeps.joint_wrench_rows(
                     bound, sweeps.transmitted_wrenches(bound, kin, x["qd"], x["qdd"])) for v in row],),
                 "W: per joint, the wrench (f, mu) from parent to child in the child frame (2.42)",
                 layout=sweeps.joint_wrench_layout, coupled="tree"))
register(Routine("forward_dynamics", ("q", "qd", "tau", "p"), (Output("qdd", nq_vector),),
                 lambda bound, kin, x: (transvective.forward_dynamics(
                     bound, kin, _minus(x["tau"], elastic.elastic_forces(bound, kin.q)), x["qd"]),),
                 "qdd = T^T diag(1/(beta,beta)) T (tau - b - g - c), the transvective Cauchy form (3.20), "
                 "evaluated in O(n)", coupled="forward"))
register(Routine("inertia_inverse", ("q", "p"), (Output("Ainv", nq_square, symmetric=True),),
                 lambda bound, kin, x: (_flat(transvective.inertia_inverse(bound, kin)),),
                 "A(q)^-1 = T^T diag(1/(beta,beta)) T, n*n row-major (3.19)", coupled="inverse"))
register(Routine("transvective_factors", ("q", "p"),
                 (Output("targs", transvective.number_of_transvections), Output("diag", nq_vector)),
                 lambda bound, kin, x: transvective.factor_outputs(bound, kin),
                 "the arguments <t,k> of the transvections of T (3.8), (3.9) and the pivots (beta,beta)^k "
                 "of T A(q) T^T = diag (3.11)", layout=transvective.layout, coupled=None))


register(Routine("elastic_partition", ("q", "qd", "p"),
                 tuple(Output(name, elastic.block_shape(name)) for name, _, _, _ in elastic.BLOCKS),
                 lambda bound, kin, x: elastic.partition(bound, kin, x["qd"]),
                 "the slow/fast partition of Prop. 2.14: blocks of A(q), B(q, qd) (b = B qd) and C, slow (+) "
                 "and fast (-, elastic) coordinates, see the manifest's layout",
                 layout=elastic.partition_layout,
                 applies=lambda model: elastic.is_elastic(model) and not model.time_dependent, coupled=None))


def run(routine: Routine, bound, inputs: dict, kin=None) -> tuple:
    """Evaluate a routine on a bound model; ``inputs`` maps vector names (without p) to lists of scalars of q's
    length (``kin``: the kinematics of ``inputs["q"]`` when already built).  Models with coupled coordinates go
    through :mod:`aggsym.coupling`.

    Returns one flat list of scalars per output."""
    if bound.model.couplings:
        from .coupling import coupled_outputs

        return coupled_outputs(routine, bound, inputs)
    kin = kin or TreeKinematics(bound, inputs["q"])
    return routine.build(bound, kin, inputs)


def input_length(model, name: str) -> int:
    return len(model.parameters) if name == "p" else 1 if name == "t" else model.nq
