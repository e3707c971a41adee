"""The generated-code contract, in one place: every routine's name, inputs, outputs and their layouts, the C and
NumPy signatures, the header's size and index macros, and the manifest.

A :class:`Routine` takes named input vectors (``q``, ``qd``, ``qdd``, ``tau``; ``p`` is bound with the model) and
returns its outputs flattened row-major.  Its ``build`` is written once over a backend (:mod:`aggsym.mechanics`):
on floats it is the numeric twin (:mod:`aggsym.twin`), on the symbolic backend the straight-line program that
:mod:`aggsym.codegen` prints as C and NumPy.  Adding an output is adding one entry to :data:`ROUTINES` (its
algorithm lives in the mechanics; a layout for the manifest, if it needs one, lives here).

The equations are ``A(q) q'' + b(q, q') + g(q) + c(q) = tau`` (2.17), (2.27):

* ``c(q) = C (q - q0)``, the elastic generalized force of the Hooke-elastic pairs (routine ``elastic``, models
  with stiffness only); it is in ``inverse_dynamics``, ``nonlinear_effects`` (d = b + g + c) and hence
  ``forward_dynamics``, and its energy is in ``potential_energy``; ``bias`` and ``gravity`` never hold it.
* A model with prescribed motions (rotors with a prescribed spin, (2.13)) is time dependent: every routine then
  takes the time ``t`` (one number) after its other inputs and before ``p`` (:func:`signature`).  Its
  ``bias`` holds every term of the spins' rates and accelerations (the book's A'V and T of (2.13) less the
  rotors' weight, which is in ``gravity``), so that ``b = B q'`` no longer holds, and A(q, t) turns with the
  rotors.
* Coordinates tied to others (URDF ``<mimic>`` with ``mimic="couple"``) are handled by
  :mod:`aggsym.mechanics.coupling`; each routine says how its outputs reduce (``Routine.coupled``).
"""
from __future__ import annotations

import functools
import keyword
from dataclasses import dataclass
from typing import Callable

from . import __version__
from .mechanics import constraints, derivatives, elastic, frames, manifold, regressor, support, sweeps, transvective
from .mechanics.bias import coriolis_matrix, gravity_vector
from .mechanics.coupling import Coupler
from .mechanics.energy import kinetic_energy, momentum, potential_energy
from .mechanics.inertia import inertia_matrix
from .mechanics.kinematics import TreeKinematics
from .model.tree import Tree

INPUT_KINDS = ("q", "qd", "qdd", "tau", "gamma", "gammad", "gammadd", "T", "t", "v", "dt")  # t: the time of models
# with prescribed motions; gamma, gammad, gammadd (the mechanism's coordinates) and T (a wrench) of the support
# routines; v (a velocity, nv) and dt (a time step) of integrate


@dataclass(frozen=True)
class Output:
    """One output array of a routine: its C argument name and shape (as a function of the model)."""

    name: str
    shape: Callable  # model -> tuple
    returned: bool = False  # the C function returns it as an int (nonzero: failed) instead of writing it; the NumPy
    # function raises numpy.linalg.LinAlgError naming the states of the batch where it is nonzero
    failure: str = ""  # for a returned status: what a nonzero value means

    @property
    def py(self) -> str:
        """Its variable name in the NumPy module (a Python keyword such as ``lambda`` gets a trailing _)."""
        return self.name + "_" if keyword.iskeyword(self.name) else self.name


@dataclass(frozen=True)
class Routine:
    role: str  # the contract's name, e.g. "inertia" -> NAME_inertia
    inputs: tuple  # input vectors in argument order, "p" included where the C signature has it
    outputs: tuple  # Output, in argument order after the inputs
    build: Callable  # (bound, kinematics, inputs) -> tuple of flat lists, one per output
    doc: str  # one line: what it computes, with the book's equation
    layout: Callable | None = None  # model -> JSON-able description of the outputs' layout (manifest)
    applies: Callable | None = None  # model -> bool; None means every model has this routine
    regular: bool = False  # defined only where A(q) is regular (left out, with the reason, where it is not)
    # with coupled coordinates: "force" (outputs reduce by J^T), "matrix" (J^T X J), "rows" (each row of an
    # m x n Jacobian times J), "columns" (J^T Y for an n x m matrix Y), "tree" (the tree's own outputs),
    # "forward" / "inverse" (q'' and A^-1 under the coupling), None (not emitted)
    coupled: str | None = "force"
    input_lengths: Callable | None = None  # model -> {input: length} where it is not q's (the support routines)
    on_request: bool = False  # emitted only when named (--routines): large outputs that few users need
    frame_free: bool = False  # its outputs depend on the coordinates alone, not on the body frames nor on how the
    # inertia is shared between bodies: generated from the internal model (aggsym.model.reframe).  Not the Coriolis
    # matrix: of the many C with C qd = b and A' - 2C skew, the one built from the bodies' B (2.17) depends on them
    slice_size: int | None = None  # the C's slices (aggsym.codegen.slicing) where smaller than the default's run faster
    scalar_stores: bool = False  # a symmetric matrix: its C compiled without GCC's basic-block vectorizer
    # (AGGSYM_SCALAR_STORES, templates/attributes.c.j2), which packs the neighbouring stores into shuffled vectors

    @property
    def written(self) -> tuple:
        """The outputs written through pointer arguments (all but a returned status)."""
        return tuple(o for o in self.outputs if not o.returned)

    @property
    def status(self):
        """The returned status output, or None."""
        return next((o for o in self.outputs if o.returned), None)

    def exists_for(self, model) -> bool:
        if model.couplings and self.coupled is None:
            return False
        return self.applies is None or bool(self.applies(model))


ROUTINES: dict[str, Routine] = {}


def register(routine: Routine) -> Routine:
    """Add a routine to the contract (the order of registration is the order of emission)."""
    ROUTINES[routine.role] = routine
    return routine


# --------------------------------------------------------------------------------------------------------------
# signatures


def signature(routine: Routine, model) -> tuple:
    """The routine's inputs for this model: ``t`` (the time, one number) is added before ``p`` when the model has
    prescribed motions (``model.time_dependent``)."""
    if not model.time_dependent:
        return routine.inputs
    ins = [i for i in routine.inputs if i != "p"]
    return tuple(ins + ["t"] + (["p"] if "p" in routine.inputs else []))


def input_length(model, name: str, routine: Routine | None = None) -> int:
    if routine is not None and routine.input_lengths is not None and name in routine.input_lengths(model):
        return routine.input_lengths(model)[name]
    if name in ("gamma", "gammad", "gammadd"):
        return model.mechanism_coordinates
    if name == "q":
        return model.nq
    return len(model.parameters) if name == "p" else 1 if name in ("t", "dt") else 6 if name == "T" else model.nv


def c_symbol(model, routine: Routine) -> str:
    return f"{model.name}_{routine.role}"


def c_prototype(model, routine: Routine, scalar: str = "double") -> str:
    """``void NAME_role(const double *q, ..., double *out)``: inputs in the order q, qd, qdd|tau, t, p, then the
    outputs (``float`` in place of ``double`` for ``scalar="float"``)."""
    args = [f"const {scalar} *{i}" for i in signature(routine, model)] + \
        [f"{scalar} *{o.name}" for o in routine.written]
    return f"{'int' if routine.status else 'void'} {c_symbol(model, routine)}({', '.join(args)})"


def python_parameters(model, routine: Routine) -> str:
    """The NumPy function's parameter list: the same inputs, ``p=None`` (the defaults) last."""
    return ", ".join(f"{i}=None" if i == "p" else i for i in signature(routine, model))


def size_macro(model, routine: Routine, output: Output) -> str:
    """``NAME_ROLE_SIZE`` for a routine's only output, ``NAME_ROLE_OUTPUT_SIZE`` for one of several."""
    parts = [model.name, routine.role] + ([output.name] if len(routine.written) > 1 else [])
    return "_".join(parts).upper() + "_SIZE"


def parameter_macro(model, parameter) -> str:
    """``NAME_P_<param>``: the index of a parameter in p, the parameter's name spelled as in the model (so that
    ``m`` and ``M`` stay two macros)."""
    return f"{model.name.upper()}_P_{parameter.name}"


def header_macros(model, routines, scalar: str = "double") -> list:
    """(macro, value, comment) of the header: NQ, NP, one index per parameter, one size per output array."""
    out = [(f"{model.name}_NQ".upper(), model.nq, "the length of q" if model.nq != model.nv else
            "coordinates: the length of q, qd, qdd, tau"),
           (f"{model.name}_NV".upper(), model.nv, "velocities: the length of qd, qdd, tau" +
            (" (q has NQ entries: a free-flyer's quaternion)" if model.nq != model.nv else " (= NQ)")),
           (f"{model.name}_NP".upper(), len(model.parameters), "parameters: the length of p")]
    for i, p in enumerate(model.parameters):
        out.append((parameter_macro(model, p), i, "index in p"))
    for r in routines:
        for o in r.written:
            shape = o.shape(model)
            size = 1
            for n in shape:
                size *= n
            out.append((size_macro(model, r, o), size,
                        f"{r.role}: {o.name}, " + " x ".join(str(n) for n in shape) + f" {scalar}s"))
    return out


# --------------------------------------------------------------------------------------------------------------
# output shapes and layouts


def nq_vector(model):
    """n: a vector of generalized forces or accelerations (Pinocchio's nv; = the length of q but with a
    free-flyer)."""
    return (model.nv,)


def nq_square(model):
    return (model.nv, model.nv)


def positions_vector(model):
    """The length of q."""
    return (model.nq,)


def scalar(model):
    return (1,)


def momentum_shape(model):
    return (6,)


def momentum_layout(model) -> dict:
    return {"rows": ["px", "py", "pz", "Lx", "Ly", "Lz"],
            "convention": "linear momentum, then angular momentum about the world origin, world axes (with added "
                          "masses the medium's impulse included; the armature carries none)"}


def joint_wrench_shape(model):
    return (len(sweeps.pair_bodies(model)), 6)


JOINT_WRENCH_CONVENTION = (
    "row r: the wrench (fx, fy, fz, mx, my, mz) that the parent exerts on the child body and its subtree through "
    "the joint (reaction + control + friction + the spring of an elastic pair, Z = R + U + N (+ C) of (2.9), "
    "(2.42), Prop. 2.13), moment about the child frame "
    "origin, both in the child frame's axes (for URDF models the child link frame); the joint's generalized "
    "forces tau are the projections of this wrench on its axes")


def joint_wrench_layout(model) -> dict:
    """The manifest entry of joint_wrenches: one row per coordinate-bearing joint, its names and frame."""
    rows = []
    for k in sweeps.pair_bodies(model):
        body = model.bodies[k]
        rows.append({
            "joint": body.pair.name,
            "body": body.name,
            "coordinates": [c.name for c in body.pair.coordinates],
            "frame": "link" if body.link_rotation is not None else "body",
        })
    return {"W": {"shape": [len(rows), 6], "order": "row-major",
                  "columns": ["fx", "fy", "fz", "mx", "my", "mz"],
                  "convention": JOINT_WRENCH_CONVENTION, "rows": rows}}


def transvection_count(model):
    """Shape of the targs output: one scalar per transvection."""
    return (len(transvective.transvection_pairs(Tree(model))),)


def transvective_layout(model) -> dict:
    """The manifest's description of the outputs of ``transvective_factors``: enough to rebuild T and A^-1."""
    names = [c.name for c in model.coordinates]
    pairs = transvective.transvection_pairs(Tree(model))
    return {
        "indexing": "0-based coordinate indices in q order",
        "targs": [[t, k] for t, k in pairs],
        "targs_names": [[names[t], names[k]] for t, k in pairs],
        "diag": names,
        "T": "T = prod_i (E - targs[i] E_{t_i k_i}) in the listed order, E_tk the unit matrix at row t, column k "
             "(the transvections t_tk^-1(<t,k>) of (3.9)); t is above k on k's path to the root",
        "identities": ["T A(q) T^T = diag(diag) (3.11)", "A(q)^-1 = T^T diag(1/diag) T (3.19)",
                       "qdd = T^T diag(1/diag) T (tau - b - g) (3.20)"],
    }


def partition_block_shape(name):
    """model -> shape of one output block of :func:`aggsym.mechanics.elastic.partition`."""
    _, _, rows, cols = next(b for b in elastic.BLOCKS if b[0] == name)

    def shape(model):
        slow, fast = elastic.fast_slow(model)
        groups = {"slow": len(slow), "fast": len(fast)}
        return (groups[rows], groups[cols])

    return shape


def partition_layout(model) -> dict:
    """The manifest entry of elastic_partition: the permutation and the meaning of every block."""
    slow, fast = elastic.fast_slow(model)
    names = [c.name for c in model.coordinates]
    book = {"pp": "++", "mp": "-+", "pm": "+-", "mm": "--"}
    blocks = {}
    for name, m, rows, cols in elastic.BLOCKS:
        blocks[name] = {"book": f"{m}{book[name[2:]]}", "rows": rows, "columns": cols,
                        "shape": list(partition_block_shape(name)(model)), "order": "row-major"}
    return {
        "slow": [names[i] for i in slow],
        "fast": [names[i] for i in fast],
        "permutation": slow + fast,
        "convention": (
            "Prop. 2.14: (P q)[r] = q[permutation[r]], the slow (non-elastic, +) coordinates first, then the fast "
            "(elastic, -) ones.  X_pp, X_mp, X_pm, X_mm are the book's X++, X-+, X+-, X-- (upper index first: "
            "the motion that contributes, lower: the equation it contributes to): rows are the equations of "
            "'rows', columns the motions of 'columns'.  A: inertia, B: the matrix with b = B qd, "
            "B = S Phi(V) A S^T + S A S'^T (2.17), C: stiffness.  Slow rows: "
            "A_pp qdd+ + B_pp qd+ + A_mp qdd- + B_mp qd- + g+ = tau+; fast rows: "
            "A_mm qdd- + B_mm qd- + A_pm qdd+ + B_pm qd+ + C_mm (q- - q0-) + g- = tau-"),
        "blocks": blocks,
    }


# --------------------------------------------------------------------------------------------------------------
# the routines


def _flat(rows):
    return [x for row in rows for x in row]


def _plus(a, b):
    """a + b entry by entry (b's structural zeros fold)."""
    return [x + y for x, y in zip(a, b)]


def _minus(a, b):
    return [x - y for x, y in zip(a, b)]


def _zeros(kin):
    return [0] * kin.tree.nv


def _gravity(bound, kin, x):
    """g = -S G: the sweeps at rest, or, when prescribed spins keep rotors turning at rest, the backward recurrence
    of -S G itself (:func:`aggsym.mechanics.bias.gravity_vector`), which leaves their motion out."""
    if bound.model.has_prescribed_spins:
        return (gravity_vector(bound, kin),)
    return (sweeps.inverse_dynamics(bound, kin, _zeros(kin), _zeros(kin)),)


def _joint_friction(bound, kin, x):
    """tau_f,i = -d_i qd_i - f_i sign(qd_i) for the joints with URDF <dynamics> (0 elsewhere), d_i and f_i the
    runtime parameters damping_<coordinate> and friction_<coordinate>."""
    index = {p.name: i for i, p in enumerate(bound.model.parameters)}
    out = []
    for c, rate in zip(bound.model.coordinates, x["qd"]):
        if not c.dynamics.given:
            out.append(0)
            continue
        d, f = bound.params[index[f"damping_{c.name}"]], bound.params[index[f"friction_{c.name}"]]
        out.append(-(d * rate) - f * bound.backend.call("sign", rate))
    return (out,)


def _joint_wrenches(bound, kin, x):
    Z = sweeps.transmitted_wrenches(bound, kin, x["qd"], x["qdd"])
    return (_flat(sweeps.joint_wrench_rows(bound, Z)),)


register(Routine("inertia", ("q", "p"), (Output("A", nq_square),),
                 lambda bound, kin, x: (_flat(inertia_matrix(bound, kin)),),
                 "A(q), the inertia matrix, n*n row-major, by composite bodies (2.32)-(2.34)",
                 coupled="matrix", frame_free=True, scalar_stores=True))
register(Routine("bias", ("q", "qd", "p"), (Output("b", nq_vector),),
                 lambda bound, kin, x: (sweeps.d_vector(bound, kin, x["qd"], gravity=False),),
                 "b(q, qd), the velocity terms: d(q, qd) of the sweeps (2.44)-(2.46) without gravity, = b by (2.52) "
                 "(with prescribed spins: every term of their rates and accelerations too)", frame_free=True))
register(Routine("coriolis", ("q", "qd", "p"), (Output("C", nq_square),),
                 lambda bound, kin, x: (_flat(coriolis_matrix(bound, kin, x["qd"], skew=True)),),
                 "C(q, qd), n*n row-major: the Coriolis matrix with C qd = b and A' - 2C skew "
                 "(S (Phi(V) A + A phi(V)) S^T + S A S'^T, from the book's B of (2.17), (2.36)), for passivity-based "
                 "control", applies=lambda model: not model.has_prescribed_spins, coupled="matrix"))
register(Routine("gravity", ("q", "p"), (Output("g", nq_vector),), _gravity,
                 "g(q) = -S G, the generalized gravity force on the left side (the sweeps at rest)", frame_free=True))
register(Routine("nonlinear_effects", ("q", "qd", "p"), (Output("d", nq_vector),),
                 lambda bound, kin, x: (_plus(sweeps.d_vector(bound, kin, x["qd"]),
                                              elastic.elastic_forces(bound, kin.q)),),
                 "d(q, qd) = b(q, qd) + g(q) + c(q): the sweeps with qdd = 0 (2.44)-(2.46), (2.52), plus the elastic "
                 "force C (q - q0) of (2.27)", frame_free=True))
register(Routine("inverse_dynamics", ("q", "qd", "qdd", "p"), (Output("tau", nq_vector),),
                 lambda bound, kin, x: (_plus(sweeps.inverse_dynamics(bound, kin, x["qd"], x["qdd"]),
                                              elastic.elastic_forces(bound, kin.q)),),
                 "tau = u* by the forward and backward sweeps (2.39)-(2.42) plus C (q - q0) (2.27); equals "
                 "A(q) qdd + b(q, qd) + g(q) + c(q)", frame_free=True))
register(Routine("elastic", ("q", "p"), (Output("c", nq_vector),),
                 lambda bound, kin, x: (elastic.elastic_forces(bound, kin.q),),
                 "c(q) = C (q - q0), the generalized force of the Hooke-elastic pairs on the left side of (2.27)",
                 applies=elastic.is_elastic))
register(Routine("kinetic_energy", ("q", "qd", "p"), (Output("T", scalar),),
                 lambda bound, kin, x: ([kinetic_energy(bound, kin, x["qd"])],),
                 "T = 1/2 sum V^T A_lk V over the bodies (Def. 2.4; with added masses the medium's 1/2 V^T Lambda V, "
                 "Prop. 2.8); = 1/2 qd^T A(q) qd without prescribed spins", coupled="tree", frame_free=True))
register(Routine("potential_energy", ("q", "p"), (Output("U", scalar),),
                 lambda bound, kin, x: ([potential_energy(bound, kin) + elastic.elastic_energy(bound, kin.q)],),
                 "U(q), the potential energy of gravity plus 1/2 (q - q0)^T C (q - q0) of the elastic pairs",
                 coupled="tree", frame_free=True))
register(Routine("momentum", ("q", "qd", "p"), (Output("h", momentum_shape),),
                 lambda bound, kin, x: (momentum(bound, kin, x["qd"]),),
                 "h: the total linear momentum and angular momentum about the world origin, world axes: each "
                 "body's A_lk V (2.3) moved to the world by its pose L (1.13)", layout=momentum_layout,
                 coupled="tree"))
register(Routine("joint_wrenches", ("q", "qd", "qdd", "p"), (Output("W", joint_wrench_shape),), _joint_wrenches,
                 "W: per joint, the wrench (f, mu) from parent to child in the child frame (2.42)",
                 layout=joint_wrench_layout, coupled="tree"))
register(Routine("joint_friction", ("qd", "p"), (Output("tau_f", nq_vector),), _joint_friction,
                 "tau_f = -d qd - f sign(qd) per joint with URDF <dynamics> (damping d, Coulomb friction f: the "
                 "parameters damping_<joint>, friction_<joint>), a generalized force on the right: "
                 "A qdd + b + g = tau + tau_f", applies=lambda model: model.has_joint_dynamics, coupled=None))
register(Routine("forward_dynamics", ("q", "qd", "tau", "p"), (Output("qdd", nq_vector),),
                 lambda bound, kin, x: (transvective.forward_dynamics(
                     bound, kin, _minus(x["tau"], elastic.elastic_forces(bound, kin.q)), x["qd"]),),
                 "qdd = T^T diag(1/(beta,beta)) T (tau - b - g - c), the transvective Cauchy form (3.20), "
                 "evaluated in O(n)", coupled="forward", regular=True, frame_free=True))
register(Routine("inertia_inverse", ("q", "p"), (Output("Ainv", nq_square),),
                 lambda bound, kin, x: (_flat(transvective.inertia_inverse(bound, kin)),),
                 "A(q)^-1 = T^T diag(1/(beta,beta)) T, n*n row-major (3.19)", coupled="inverse", regular=True,
                 frame_free=True, scalar_stores=True))
register(Routine("transvective_factors", ("q", "p"),
                 (Output("targs", transvection_count), Output("diag", nq_vector)),
                 lambda bound, kin, x: transvective.factor_outputs(bound, kin),
                 "the arguments <t,k> of the transvections of T (3.8), (3.9) and the pivots (beta,beta)^k "
                 "of T A(q) T^T = diag (3.11)", layout=transvective_layout, coupled=None, regular=True, frame_free=True))
register(Routine("elastic_partition", ("q", "qd", "p"),
                 tuple(Output(name, partition_block_shape(name)) for name, _, _, _ in elastic.BLOCKS),
                 lambda bound, kin, x: elastic.partition(bound, kin, x["qd"]),
                 "the slow/fast partition of Prop. 2.14: blocks of A(q), B(q, qd) (b = B qd) and C, slow (+) "
                 "and fast (-, elastic) coordinates, see the manifest's layout",
                 layout=partition_layout,
                 applies=lambda model: elastic.is_elastic(model) and not model.has_prescribed_spins, coupled=None))


def constraint_rows_vector(model):
    return (model.constraint_rows,)


def constraint_jacobian_shape(model):
    return (model.constraint_rows, model.nv)


def constraint_square(model):
    return (model.constraint_rows, model.constraint_rows)


def constraint_row_labels(model) -> list:
    return [f"{c.name}.{code}" for c in model.constraints for code in c.rows]


def constraint_layout(model) -> dict:
    return {"rows": constraint_row_labels(model), "columns": [c.name for c in model.coordinates],
            "order": "row-major", "convention": "see the manifest's 'constraints'"}


def _has_constraints(model) -> bool:
    return bool(model.constraints)


def slip_vector(model):
    return (model.slip_rows,)


def slip_labels(model) -> list:
    return [f"{c.name}.{code}" for c in model.constraints for code in c.free_translations]


def slip_layout(model) -> dict:
    return {"rows": slip_labels(model), "order": "constraints in order, each one's free translations (o1 o2 o3 "
            "not blocked) in the axes of its reference frame"}


def _has_slip(model) -> bool:
    return model.slip_rows > 0


CONSTRAINT_FAILURE = ("the constraints are singular (J A^-1 J^T has a pivot below 1e-12 of its mean diagonal, or "
                      "is not finite), or Coulomb friction has no consistent solution")


def _constrained_forward_dynamics(bound, kin, x):
    qdd, lam, status = constraints.constrained_forward_dynamics(
        bound, kin, x["qd"], _minus(x["tau"], elastic.elastic_forces(bound, kin.q)))
    return qdd, lam, [status]


register(Routine("constraint_residual", ("q", "p"), (Output("phi", constraint_rows_vector),),
                 lambda bound, kin, x: (constraints.residual(bound, kin),),
                 "phi(q): the constraints' holonomic residual, m rows (ch. 4): the contact point's offset from its "
                 "attachment and the rotation vector of the relative orientation, in the reference axes",
                 layout=constraint_layout, applies=_has_constraints, coupled=None))
register(Routine("constraint_jacobian", ("q", "p"), (Output("J", constraint_jacobian_shape),),
                 lambda bound, kin, x: (_flat(constraints.jacobian(bound, kin)),),
                 "J(q) = D_lambda^T, m*n row-major: the forbidden relative motions per unit rate of each "
                 "coordinate, rows of the parastrophic matrix S moved to the contact points (4.5)-(4.12)",
                 layout=constraint_layout, applies=_has_constraints, coupled=None))
register(Routine("constraint_bias", ("q", "qd", "p"), (Output("gamma", constraint_rows_vector),),
                 lambda bound, kin, x: (constraints.bias(bound, kin, x["qd"]),),
                 "gamma(q, qd) = J' qd: the relative accelerations at qdd = 0 (S'^T qd of (2.37) at the contact "
                 "points), so that J qdd + gamma is the constraints' acceleration",
                 layout=constraint_layout, applies=_has_constraints, coupled=None))
register(Routine("slip_velocities", ("q", "qd", "p"), (Output("w", slip_vector),),
                 lambda bound, kin, x: (constraints.slip_velocities(bound, kin, x["qd"]),),
                 "w(q, qd) = D_k+^T V (4.33)-(4.34): each contact point's velocity relative to the medium along "
                 "the free translations of its constraint (the sliding velocities friction acts on)",
                 layout=slip_layout, applies=_has_slip, coupled=None))
register(Routine("delassus", ("q", "p"), (Output("G", constraint_square),),
                 lambda bound, kin, x: (_flat(constraints.delassus(bound, kin)),),
                 "G = J A^-1 J^T, m*m row-major, by the transvective factors: P = T J^T, G = P^T diag(1/(beta,beta)) "
                 "P (3.19)", applies=_has_constraints, coupled=None, regular=True))
register(Routine("constrained_forward_dynamics", ("q", "qd", "tau", "p"),
                 (Output("qdd", nq_vector), Output("lambda", constraint_rows_vector),
                  Output("status", scalar, returned=True, failure=CONSTRAINT_FAILURE)),
                 _constrained_forward_dynamics,
                 "qdd and lambda of A qdd + b + g + c = tau + J^T lambda, J qdd + gamma = -(kd J qd + kp phi) "
                 "(4.25)-(4.28): G lambda = -gamma - stab - P^T D^-1 T F with P = T J^T, then qdd = T^T D^-1 "
                 "(T F + P lambda) (3.20); friction on sliding contacts from the slip velocities (4.5), (4.33); "
                 "returns nonzero when G is singular (or Coulomb friction has no consistent solution)",
                 applies=_has_constraints, coupled=None, regular=True))


# --------------------------------------------------------------------------------------------------------------
# support dynamics (the support paper, (3.1)-(3.4)): q is the support's six coordinates, gamma the mechanism's k

def _has_support(model) -> bool:
    return model.support is not None


def support_lengths(model) -> dict:
    return {"q": 6, "qd": 6, "qdd": 6}


def support_block(columns):
    def shape(model):
        return (6, model.mechanism_coordinates if columns == "k" else 6)
    return shape


def six(model):
    return (6,)


def mechanism_vector(model):
    return (model.mechanism_coordinates,)


SUPPORT_OUTPUTS = (("support_A", "6"), ("support_B", "6"), ("support_I", "k"), ("support_J", "k"),
                   ("support_L", "6"))
SUPPORT_FAILURE = "the support's A = A+ M is singular (its pair's angles at a singularity: cos theta5 = 0)"


def support_layout(model) -> dict:
    support = next(b for b in model.bodies if b.name == model.support)
    return {"support": model.support, "q": [c.name for c in support.pair.coordinates],
            "gamma": [c.name for c in model.coordinates[6:]],
            "equation": "support_A qdd + support_B qd + support_I gammadd + support_J gammad + support_g = "
                        "support_L T (3.1): a wrench balance at the support's origin, its axes",
            "T": "the external wrench on the support: (f, mu) about the world origin, world axes",
            "B_J": "column j of B (of J) is the support-side wrench of column j of the book's B(q, qd) (2.17) "
                   "(B qd = b), before the projection M^T: B multiplies the support's rates, J the mechanism's",
            "order": "row-major"}


def _support_coefficients(bound, kin, x):
    c = support.support_coefficients(bound, x)
    return _flat(c["A"]), _flat(c["B"]), _flat(c["I"]), _flat(c["J"]), _flat(c["L"]), c["g"]


def _support_direct(bound, kin, x):
    qdd, status = support.support_direct(bound, x)
    return qdd, [status]


def _support_inverse(bound, kin, x):
    gammadd, residual, status = support.support_inverse(bound, x)
    return gammadd, residual, [status]


register(Routine("support_coefficients", ("q", "qd", "gamma", "gammad", "p"),
                 tuple(Output(name, support_block(cols)) for name, cols in SUPPORT_OUTPUTS) +
                 (Output("support_g", six),), _support_coefficients,
                 "the coefficients of the support equation A qdd + B qd + I gammadd + J gammad + g = L T (3.1)-(3.3): "
                 "A = A+_11 M, I_beta = L A+_lk M f_beta, B and J the support-side columns of B(q, qd) (2.17), g "
                 "the weights at the support, L the world wrench T moved to the support",
                 layout=support_layout, applies=_has_support, coupled=None, input_lengths=support_lengths))
register(Routine("support_direct", ("q", "qd", "gamma", "gammad", "gammadd", "T", "p"),
                 (Output("qdd", six), Output("status", scalar, returned=True, failure=SUPPORT_FAILURE)),
                 _support_direct,
                 "the direct problem (3.4) 1: the support's qdd from its state, the mechanism's motion gamma(t) and "
                 "the external wrench T", layout=support_layout, applies=_has_support, coupled=None,
                 input_lengths=support_lengths))
register(Routine("support_inverse", ("q", "qd", "qdd", "gamma", "gammad", "T", "p"),
                 (Output("gammadd", mechanism_vector), Output("residual", six),
                  Output("status", scalar, returned=True,
                         failure="I (6 x k) is rank-deficient at the point (I I^T singular when k >= 6, I^T I when "
                                 "k < 6)")),
                 _support_inverse,
                 "the inverse problem (3.4) 2: the mechanism's gammadd that gives the support a wanted qdd: exact "
                 "(minimum norm when k > 6) when rank I = 6, least squares with the 6-residual when k < 6",
                 layout=support_layout, applies=_has_support, coupled=None, input_lengths=support_lengths))


def _has_quaternion(model) -> bool:
    """A free-flyer root (--floating-base quaternion): q has nq = nv + 1 entries."""
    return any(b.pair.quaternion for b in model.bodies)


register(Routine("integrate", ("q", "v", "dt"), (Output("q_next", positions_vector),),
                 lambda bound, kin, x: (manifold.integrate(bound, x["q"], x["v"], x["dt"][0]),),
                 "q (+) v dt, Pinocchio's integrate: the joints q + v dt, the free-flyer root M exp((v, w) dt) in "
                 "SE(3) (its quaternion normalized)",
                 layout=lambda model: {"q_next": "the same layout as q (the manifest's 'coordinates'); v has the "
                                                 "layout of the 'velocities'; dt is one number"},
                 applies=_has_quaternion, coupled=None))


def _inverse_dynamics_derivatives(bound, kin, x):
    dq, dqd = derivatives.inverse_dynamics_derivatives(bound, kin, x["qd"], x["qdd"])
    return _flat(dq), _flat(dqd)


def _forward_dynamics_derivatives(bound, kin, x):
    dq, dqd = derivatives.forward_dynamics_derivatives(
        bound, kin, x["qd"], _minus(x["tau"], elastic.elastic_forces(bound, kin.q)))
    return _flat(dq), _flat(dqd)


register(Routine("inverse_dynamics_derivatives", ("q", "qd", "qdd", "p"),
                 (Output("dtau_dq", nq_square), Output("dtau_dqd", nq_square)), _inverse_dynamics_derivatives,
                 "d tau / d q and d tau / d qd, n*n row-major (entry (i, j): d tau_i / d x_j; d tau / d qdd is A): "
                 "the sweeps (2.39)-(2.46) differentiated in forward mode, reusing their intermediates",
                 coupled="matrix", on_request=True, frame_free=True, slice_size=80))
register(Routine("forward_dynamics_derivatives", ("q", "qd", "tau", "p"),
                 (Output("dqdd_dq", nq_square), Output("dqdd_dqd", nq_square)), _forward_dynamics_derivatives,
                 "d qdd / d q and d qdd / d qd, n*n row-major (d qdd / d tau is A^-1): -A^-1 d tau_ID / d x at the "
                 "forward dynamics' qdd, A^-1 applied column by column by the transvective factors (3.19)-(3.20)",
                 coupled=None, regular=True, on_request=True, frame_free=True, slice_size=80))


def frame_count(model) -> int:
    return len(model.frames)


def frames_entry(model) -> list:
    """The manifest's list of the emitted frames, in output order: name, body, origin and axes in the body."""
    return [{"name": f.name, "body": f.body, "point": [str(x) for x in f.point],
             "axes": None if f.axes is None else [[str(x) for x in row] for row in f.axes],
             "rotation": [[axis, str(angle)] for axis, angle in f.rotation]} for f in model.frames]


def frame_layout(per_frame: list, convention: str):
    def layout(model) -> dict:
        return {"frames": [f.name for f in model.frames], "per_frame": per_frame, "order": "row-major, frames in "
                "the order of 'frames'", "convention": convention}
    return layout


def _has_frames(model) -> bool:
    return bool(model.frames)


def _has_moving_mass(model) -> bool:
    """The centre of mass needs a moving mass: False when every body that moves is massless (the mass routines are
    then not emitted; a mass that p sets to zero at run time gives NaN)."""
    inertials = [model.bodies[k].inertial for k in regressor.blocks(model) if model.bodies[k].inertial is not None]
    total = sum((i.mass if i.origin is None else i.origin[0] for i in inertials), 0)
    return not (total == 0)


def _has_free_root(model) -> bool:
    """A floating base (the root body's pair has all six coordinates) with a moving mass."""
    return len(model.bodies[0].pair.coordinates) == 6 and _has_moving_mass(model)


COM_CONVENTION = ("the bodies that move (a body welded to the world is left out, as Pinocchio's centerOfMass "
                  "leaves out the universe), their own inertia (no added mass, no armature), world axes")

register(Routine("frame_poses", ("q", "p"), (Output("X", lambda model: (frame_count(model), 12)),),
                 lambda bound, kin, x: (frames.frame_poses(bound, kin),),
                 "per frame: its origin in the world, then the rotation matrix from frame axes to world axes "
                 "(Pinocchio's oMf.rotation), row-major: the world pose L (1.13) composed from the root (Prop. 1.8)",
                 layout=frame_layout(["x", "y", "z", "R00", "R01", "R02", "R10", "R11", "R12", "R20", "R21", "R22"],
                                     "origin in world axes, then R row-major: x_world = R x_frame + origin"),
                 applies=_has_frames, coupled="tree"))
register(Routine("frame_jacobians", ("q", "p"),
                 (Output("J", lambda model: (frame_count(model), 6, model.nv)),),
                 lambda bound, kin, x: (_flat(frames.frame_jacobians(bound, kin)),),
                 "per frame a 6 x n block: the velocity of its origin and its angular velocity per unit rate of each "
                 "coordinate, world axes (Pinocchio's LOCAL_WORLD_ALIGNED): the columns of S (1.42) moved to the "
                 "frame's origin",
                 layout=frame_layout(["vx", "vy", "vz", "wx", "wy", "wz"],
                                     "rows of each block: (v, w) of the frame origin, world axes; columns: q"),
                 applies=_has_frames, coupled="rows"))
register(Routine("frame_accelerations", ("q", "qd", "qdd", "p"),
                 (Output("a", lambda model: (frame_count(model), 6)),),
                 lambda bound, kin, x: (frames.frame_accelerations(bound, kin, x["qd"], x["qdd"]),),
                 "per frame the classical acceleration of its origin and its angular acceleration, world axes, from "
                 "the forward sweep (2.40) without gravity; with qdd = 0 it is J' qd",
                 layout=frame_layout(["ax", "ay", "az", "alphax", "alphay", "alphaz"],
                                     "classical (not spatial) acceleration of the origin, then the angular "
                                     "acceleration, world axes (Pinocchio's getFrameClassicalAcceleration, "
                                     "LOCAL_WORLD_ALIGNED)"),
                 applies=_has_frames, coupled="tree"))
register(Routine("center_of_mass", ("q", "p"), (Output("c", lambda model: (3,)),),
                 lambda bound, kin, x: (frames.center_of_mass(bound, kin),),
                 "the centre of mass in the world: sum (m_k o_k + R_k h_k) / M over the moving bodies, h_k the first "
                 "moment of Theta_lk (2.3)",
                 layout=lambda model: {"rows": ["x", "y", "z"], "convention": COM_CONVENTION}, coupled="tree",
                 applies=_has_moving_mass))
register(Routine("com_jacobian", ("q", "p"), (Output("Jc", lambda model: (3, model.nv)),),
                 lambda bound, kin, x: (_flat(frames.com_jacobian(bound, kin)),),
                 "the Jacobian of the centre of mass, 3 x n row-major: column i is the linear momentum of the "
                 "subtree that coordinate i moves, per unit rate, over the total mass (S (1.42) applied to the "
                 "subtrees' mass and first moment)",
                 layout=lambda model: {"rows": ["x", "y", "z"], "columns": [c.name for c in model.coordinates],
                                       "order": "row-major", "convention": COM_CONVENTION}, coupled="rows",
                 applies=_has_moving_mass))
register(Routine("centroidal_map", ("q", "p"), (Output("Ag", lambda model: (6, model.nv)),),
                 lambda bound, kin, x: (_flat(frames.centroidal_map(bound, kin)),),
                 "the centroidal momentum matrix A_G, 6 x n row-major: h_G = A_G qd, the linear momentum and the "
                 "angular momentum about the centre of mass, world axes (Pinocchio's computeCentroidalMap)",
                 layout=lambda model: {"rows": ["px", "py", "pz", "Lx", "Ly", "Lz"],
                                       "columns": [c.name for c in model.coordinates], "order": "row-major",
                                       "convention": COM_CONVENTION + "; angular momentum about the centre of mass"},
                 applies=_has_free_root, coupled="rows"))


def regressor_shape(model):
    return (model.nv, 10 * len(regressor.blocks(model)))


def regressor_layout(model) -> dict:
    exprs = regressor.standard_parameters(model)
    defaults = dict(zip(model.parameter_symbols, model.parameter_values))
    out = []
    for b, k in enumerate(regressor.blocks(model)):
        body = model.bodies[k]
        block = exprs[10 * b:10 * b + 10]
        item = {"body": body.name, "columns": [10 * b, 10 * b + 10],
                "frame": "link" if body.link_rotation is not None else "body",
                "values": {name: float(v.subs(defaults)) for name, v in zip(regressor.PARAMETERS, block)}}
        if any(v.free_symbols for v in block):
            item["expressions"] = {name: str(v) for name, v in zip(regressor.PARAMETERS, block)}
        out.append(item)
    return {"Y": {"shape": list(regressor_shape(model)), "order": "row-major", "rows": [c.name for c in model.coordinates]},
            "parameters": list(regressor.PARAMETERS),
            "convention": ("tau = Y pi (inverse_dynamics), pi per block (m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, "
                           "Izz): mass, first moment and inertia about the body (URDF: link) frame's origin, in its "
                           "axes (Pinocchio's order and frame); one block per moving body, links welded by fixed "
                           "joints merged into it; 'values': the model's own pi at the default parameters ('expressions': in the "
                           "parameters, where they enter); with an armature a, tau = Y pi + a qdd (the armature is "
                           "not a body: Pinocchio's regressor leaves it out too)"),
            "blocks": out}


def regressor_problem(model) -> str | None:
    """Why tau = Y pi does not hold for a model (the regressor is then omitted), or None."""
    if elastic.is_elastic(model):
        return "the elastic force C (q - q0) of (2.27) is in tau and not linear in the inertial parameters"
    if any(b.added_mass is not None for b in model.bodies):
        return "added masses (Prop. 2.8) act in tau and are not among the inertial parameters"
    return None


BASE_SEED = 0  # the random states of the base-parameter reduction
BASE_RANK_TOLERANCE = "max(rows, columns) * 2.2e-16 * the largest singular value (numpy.linalg.matrix_rank's)"


@functools.lru_cache(maxsize=8)
def base_parameters(model) -> tuple:
    """The base-parameter reduction at the default parameters: (independent columns of Y, beta, samples) such that
    ``Y[:, dependent] = Y[:, independent] beta`` on every state, so that tau = Y_b pi_b with ``Y_b = Y[:, independent]``
    and ``pi_b = pi[independent] + beta pi[dependent]``.  Found numerically as identification practice does: Y at
    ``samples`` random states (seed :data:`BASE_SEED`: q uniform in [-pi, pi], qd and qdd standard normal) stacked,
    its rank r with the tolerance of :data:`BASE_RANK_TOLERANCE`, and the first r pivots of a QR factorization
    with column pivoting (Householder, largest remaining column first: Gautier's choice), listed in column
    order; beta by least squares, entries below 1e-10 of the largest set to 0, the others rounded to 12 digits."""
    import numpy as np

    from .core.backend import Numeric
    from .mechanics.bound import bind

    n, P = regressor_shape(model)
    samples = max(8, -(-4 * P // max(n, 1)))
    rng = np.random.default_rng(BASE_SEED)
    bound = bind(model, Numeric())
    x = {"q": list(sample_configurations(model, rng, samples)), "qd": list(rng.normal(size=(n, samples))),
         "qdd": list(rng.normal(size=(n, samples)))}
    flat = run(ROUTINES["regressor"], bound, x)[0]
    Y = np.stack([np.broadcast_to(np.asarray(v, dtype=float), (samples,)) for v in flat]).reshape(n, P, samples)
    Y = Y.transpose(2, 0, 1).reshape(samples * n, P)
    sv = np.linalg.svd(Y, compute_uv=False)
    tol = sv[0] * max(Y.shape) * np.finfo(float).eps if sv.size else 0.0
    rank = int((sv > tol).sum())
    independent = sorted(pivoted_columns(Y)[:rank])
    dependent = [j for j in range(P) if j not in set(independent)]
    if rank and dependent:
        beta = np.linalg.lstsq(Y[:, independent], Y[:, dependent], rcond=None)[0]
    else:  # nothing to express, or nothing identifiable (a tree whose moving bodies do no work)
        beta = np.zeros((rank, len(dependent)))
    scale = max(float(np.abs(beta).max()), 1.0) if beta.size else 1.0
    beta[np.abs(beta) < 1e-10 * scale] = 0.0
    beta = np.vectorize(lambda v: float(f"{v:.12g}"))(beta) if beta.size else beta  # least squares' last digits
    return tuple(independent), tuple(dependent), beta, samples


def pivoted_columns(Y) -> list:
    """The column order of a Householder QR factorization of Y with column pivoting (at each step the column of
    largest norm in the remaining rows first): its first r entries are r well-conditioned independent columns."""
    import numpy as np

    R = np.array(Y, dtype=float, copy=True)
    rows, cols = R.shape
    order = list(range(cols))
    for k in range(min(rows, cols)):
        norms = np.einsum("ij,ij->j", R[k:, k:], R[k:, k:])
        j = k + int(np.argmax(norms))
        R[:, [k, j]] = R[:, [j, k]]
        order[k], order[j] = order[j], order[k]
        x = R[k:, k]
        alpha = -np.copysign(np.linalg.norm(x), x[0]) if x[0] != 0 else -np.linalg.norm(x)
        v = x.copy()
        v[0] -= alpha
        vv = v @ v
        if vv > 0:
            R[k:, k:] -= np.outer(v, (2.0 / vv) * (v @ R[k:, k:]))
    return order


def standard_parameter_names(model) -> list:
    return [f"{name}_{model.bodies[k].name}" for k in regressor.blocks(model) for name in regressor.PARAMETERS]


def base_regressor_layout(model) -> dict:
    independent, dependent, beta, samples = base_parameters(model)
    names = standard_parameter_names(model)
    items = []
    for r, j in enumerate(independent):
        combination = {names[j]: 1.0}
        for d, jd in enumerate(dependent):
            if beta[r, d] != 0.0:
                combination[names[jd]] = float(beta[r, d])
        items.append({"name": names[j], "column": j, "combination": combination})
    return {"Yb": {"shape": [model.nv, len(independent)], "order": "row-major"},
            "base_parameters": items,
            "convention": ("tau = Yb pi_b; pi_b[r] = sum of coefficient * standard parameter over 'combination' (names "
                           "PARAM_BODY of the regressor's blocks: see layouts.regressor); Yb is the regressor's columns "
                           "'column'.  Computed at generation from the regressor at the default parameters: a change of "
                           "the geometry in p may change the combinations"),
            "samples": samples, "seed": BASE_SEED, "rank_tolerance": BASE_RANK_TOLERANCE,
            "unidentifiable": [names[j] for j in dependent]}


register(Routine("regressor", ("q", "qd", "qdd", "p"), (Output("Y", regressor_shape),),
                 lambda bound, kin, x: (_flat(regressor.regressor(bound, kin, x["qd"], x["qdd"])),),
                 "the identification regressor Y(q, qd, qdd), n x 10B row-major: tau = Y pi, pi the 10 standard "
                 "inertial parameters of each of the B moving bodies (Pinocchio's order and frames): the dynamic "
                 "wrench (2.10) is linear in pi, carried by the backward sweep (2.41)-(2.42), projected by (2.15)",
                 layout=regressor_layout, coupled="columns", on_request=True))
register(Routine("base_regressor", ("q", "qd", "qdd", "p"),
                 (Output("Yb", lambda model: (model.nv, len(base_parameters(model)[0]))),),
                 lambda bound, kin, x: (_base_columns(bound, kin, x),),
                 "the base regressor Yb, n x r row-major: the regressor's r independent columns, tau = Yb pi_b with "
                 "the base parameters of the manifest (each a combination of standard parameters, found at "
                 "generation from random samples of Y)", layout=base_regressor_layout, coupled=None, on_request=True))


def _base_columns(bound, kin, x):
    """The independent columns of the regressor."""
    Y = regressor.regressor(bound, kin, x["qd"], x["qdd"])
    return [row[j] for row in Y for j in base_parameters(bound.model)[0]]


def routines_for(model, roles=None, omitted=()) -> list:
    """The routines emitted for a model, in emission order: those named (``roles``, else the model's own selection
    ``model.routines``, else every routine of the contract that applies and is not on request), less the
    ``omitted`` ones (:func:`omitted_routines`)."""
    if roles is None:
        roles = model.routines
    return [r for role, r in ROUTINES.items()
            if (role in roles if roles is not None else not r.on_request) and r.exists_for(model)
            and role not in omitted]


def select_routines(model, names):
    """The model emitting the named routines (``--routines``: names of the contract, ``default`` for the routines
    emitted when none are named, ``all`` for every routine that applies); an unknown name, or one that does not
    apply to the model, is an error that lists the choices."""
    import dataclasses

    from .errors import AggsymError

    chosen = []
    for name in names:
        if name == "all":
            picked = [r.role for r in ROUTINES.values() if r.exists_for(model)]
        elif name == "default":
            picked = [r.role for r in ROUTINES.values() if r.exists_for(model) and not r.on_request]
        elif name not in ROUTINES:
            shown = name if len(name) <= 80 else name[:80] + "..."
            raise AggsymError(f"{model.source}: --routines: no routine named {shown!r} (the routines are "
                              f"{', '.join(ROUTINES)}; or 'default', 'all')")
        elif not ROUTINES[name].exists_for(model):
            raise AggsymError(f"{model.source}: --routines: {name!r} does not apply to this model (the ones that do: "
                              f"{', '.join(r.role for r in ROUTINES.values() if r.exists_for(model))})")
        else:
            picked = [name]
        chosen.extend(role for role in picked if role not in chosen)
    if not chosen:
        raise AggsymError(f"{model.source}: --routines: no routine named")
    selected = dataclasses.replace(model, routines=tuple(chosen))
    named = [name for name in names if name in ROUTINES]  # named one by one, not through 'all' or 'default'
    if named:
        omitted = omitted_routines(selected)
        for name in named:
            if name in omitted:
                raise AggsymError(f"{model.source}: --routines: {name!r} is left out for this model: {omitted[name]}")
    return selected


def sample_configurations(model, rng, size=None):
    """Random configurations q (shape (nq,), or (nq, size)): each coordinate uniform in [-pi, pi]; a free-flyer's
    position uniform in [-pi, pi]^3 and its quaternion a random unit quaternion (the samples of the checks, the
    base parameters and the redundancy tests)."""
    import numpy as np

    shape = (model.nq,) if size is None else (model.nq, size)
    q = rng.uniform(-np.pi, np.pi, shape)
    for idx, b in zip(Tree(model).positions, model.bodies):
        if b.pair.quaternion:
            quat = rng.normal(size=(4,) + shape[1:])
            q[idx[3]:idx[3] + 4] = quat / np.linalg.norm(quat, axis=0)
    return q


def massless_coordinates(model, samples: int = 2, tolerance: float = 1e-12) -> tuple:
    """(coordinate indices with A_ii = 0, whether A(q) is singular), at the default parameters and a few fixed
    random configurations: A_ii = psi_i^T A+ psi_i is the kinetic energy of a unit rate of coordinate i alone,
    zero exactly when its joint moves no mass.  Zero and singular are judged relative to the largest entry."""
    import numpy as np

    from .core.backend import Numeric
    from .mechanics.bound import bind

    n = model.nv
    if n == 0:
        return (), False
    bound = bind(model, Numeric())
    rng = np.random.default_rng(0)
    zero, singular = set(range(n)), False
    for _ in range(samples):
        q = [float(x) for x in sample_configurations(model, rng)]
        A = np.array(run(ROUTINES["inertia"], bound, {"q": q})[0], dtype=float).reshape(n, n)
        scale = max(float(np.abs(A).max()), 1e-300)
        zero &= {i for i in range(n) if abs(A[i, i]) <= tolerance * scale}
        singular = singular or float(np.linalg.eigvalsh(A)[0]) <= tolerance * scale
    return tuple(sorted(zero)), singular


def redundant_constraints(model, samples: int = 2, tolerance: float = 1e-9) -> list:
    """The constraints with rows that depend on other rows when J is rank-deficient at q = 0 and at ``samples``
    fixed random configurations, all of them (a structural redundancy, such as a planar four-bar closed by a point
    constraint, and not a singular configuration): [(constraint, [codes])].  Which rows are named is a choice
    (any row of a dependent set could go): those a greedy scan in row order finds dependent at the last sample.
    A model whose J has full rank at any one of the samples has no structural redundancy: []."""
    import numpy as np

    from .core.backend import Numeric
    from .mechanics.bound import bind

    if not model.constraints:
        return []
    bound = bind(model, Numeric())
    rng = np.random.default_rng(0)
    dependent = set()
    for q in [bound.tree.neutral] + [sample_configurations(model, rng) for _ in range(samples)]:
        J = np.array(run(ROUTINES["constraint_jacobian"], bound, {"q": [float(x) for x in q]})[0], dtype=float)
        J = J.reshape(model.constraint_rows, model.nv)
        scale = max(float(np.abs(J).max()), 1e-300)
        dependent, kept = set(), []
        for r in range(J.shape[0]):
            trial = kept + [J[r]]
            if np.linalg.matrix_rank(np.array(trial), tol=tolerance * scale) > len(kept):
                kept.append(J[r])
            else:
                dependent.add(r)
        if not dependent:
            return []
    out, start = [], 0
    for c in model.constraints:
        codes = [code for r, code in enumerate(c.rows, start) if r in dependent]
        if codes:
            out.append((c, codes))
        start += len(c.rows)
    return out


def omitted_routines(model) -> dict:
    """{role: reason} of the routines left out: the regressor where tau = Y pi does not hold
    (:func:`regressor_problem`), and, when A(q) is singular at the default parameters (a coordinate that moves no
    mass, e.g. a massless finger joint), forward dynamics, A^-1 and the factors, undefined there (A, b, g, inverse
    dynamics and the joint wrenches stay defined and are emitted)."""
    out = {}
    wanted = {r.role for r in routines_for(model)}
    problem = regressor_problem(model)
    if problem:
        out.update({role: f"tau = Y pi does not hold: {problem}" for role in ("regressor", "base_regressor")
                    if role in wanted})
    if not any(ROUTINES[role].regular for role in wanted):
        return out
    zero, singular = massless_coordinates(model)
    if not singular:
        return out
    names = ", ".join(f"{model.coordinates[i].name} (joint {model.coordinates[i].joint!r})" for i in zero)
    reason = (f"A(q) is singular at the default parameters: {'coordinate(s) ' + names + ' move(s) no mass' if zero else 'its smallest eigenvalue is zero'}; "
              f"--armature VALUE adds a rotor inertia on every coordinate")
    return {**out, **{role: reason for role in wanted if ROUTINES[role].regular}}


# --------------------------------------------------------------------------------------------------------------
# running a routine


def run(routine: Routine, bound, inputs: dict, kin=None) -> tuple:
    """Evaluate a routine on a bound model; ``inputs`` maps vector names (without p) to lists of scalars of q's
    length (``kin``: the kinematics of ``inputs["q"]`` when already built).  Models with coupled coordinates go
    through :class:`aggsym.mechanics.coupling.Coupler`.

    Returns one flat list of scalars per output."""
    if bound.model.couplings:
        return _coupled_outputs(routine, bound, inputs)
    if kin is None and "q" in inputs and routine.input_lengths is None:
        kin = TreeKinematics(bound, inputs["q"])
    return routine.build(bound, kin, inputs)


def _coupled_outputs(routine, bound, inputs: dict) -> tuple:
    """A routine's outputs for q's inputs of a model with couplings, by ``routine.coupled``."""
    coupler = Coupler(bound.model, bound.tree)
    x = coupler.expand(inputs)
    kin = TreeKinematics(bound, x["q"])
    how = routine.coupled
    if how == "forward":
        return (coupler.forward_dynamics(bound, kin, x),)
    if how == "inverse":
        return (_flat(coupler.inertia_inverse(bound, kin)),)
    outs = routine.build(bound, kin, x)
    if how == "force":
        return tuple(coupler.reduce(list(o)) for o in outs)
    if how == "columns":  # an n_tree x m matrix of generalized forces (the regressor): J^T Y, column by column
        n, out = coupler.n_tree, []
        for o in outs:
            m = len(o) // n
            cols = [coupler.reduce([o[i * m + j] for i in range(n)]) for j in range(m)]
            out.append([cols[j][i] for i in range(len(cols[0]) if cols else 0) for j in range(m)])
        return tuple(out)
    if how == "rows":  # a Jacobian: each row (over the tree's coordinates) times the coupling's J
        n = coupler.n_tree
        return tuple([x for r in range(len(o) // n) for x in coupler.reduce(list(o[r * n:(r + 1) * n]))]
                     for o in outs)
    if how == "matrix":
        n = coupler.n_tree
        return tuple(_flat(coupler.reduce_matrix([list(o[i * n:(i + 1) * n]) for i in range(n)])) for o in outs)
    return outs


# --------------------------------------------------------------------------------------------------------------
# the manifest


# --scalar float: per routine the bound of the float C's error against the double twin, relative to the largest
# value the routine returns (for FLOAT_PER_CONDITION also divided by cond(A) at the state), the inputs rounded to
# float: at least 8x the worst seen over the bundled models and the suite's robots (README, "Single precision"); the
# issue's 1e-4 on A, the inverse dynamics and the frame poses.  Models with prescribed motions get FLOAT_TIME times
# as much: their spin angles w t are computed in float, so the error grows with t (check draws 0 <= t <= 10).
FLOAT_TOLERANCE = {
    "inertia": 1e-4, "inverse_dynamics": 1e-4, "frame_poses": 1e-4,
    "bias": 5e-5, "coriolis": 2e-4, "gravity": 1e-5, "nonlinear_effects": 5e-5, "kinetic_energy": 1e-5,
    "potential_energy": 1e-3, "momentum": 1e-5, "joint_wrenches": 1e-5, "elastic": 1e-5, "elastic_partition": 1e-5,
    "frame_jacobians": 1e-5, "frame_accelerations": 1e-5, "center_of_mass": 1e-5, "com_jacobian": 1e-5,
    "centroidal_map": 5e-5, "regressor": 1e-5, "base_regressor": 1e-5, "inverse_dynamics_derivatives": 2e-4,
    "constraint_residual": 1e-4, "constraint_jacobian": 1e-5, "constraint_bias": 5e-5, "slip_velocities": 1e-5,
    "delassus": 1e-6, "constrained_forward_dynamics": 5e-5, "support_coefficients": 1e-5, "support_direct": 2e-5,
    "support_inverse": 1e-5,
    "forward_dynamics": 1e-6, "inertia_inverse": 1e-6, "transvective_factors": 1e-6,
    "forward_dynamics_derivatives": 1e-6,
}
FLOAT_PER_CONDITION = ("forward_dynamics", "inertia_inverse", "transvective_factors", "forward_dynamics_derivatives",
                       "delassus")
FLOAT_TOLERANCE_DEFAULT = 1e-4  # the others: joint_friction (worst seen 7e-8), integrate (1.8e-7 on solo12)
FLOAT_TIME = 100


def float_tolerance(model, routines) -> dict:
    """The manifest's ``float_tolerance`` (role -> bound) and the notes that say how to read it."""
    factor = FLOAT_TIME if model.time_dependent else 1
    out = {"float_tolerance": {r.role: FLOAT_TOLERANCE.get(r.role, FLOAT_TOLERANCE_DEFAULT) * factor
                               for r in routines},
           "float_tolerance_per_condition": [r.role for r in routines if r.role in FLOAT_PER_CONDITION]}
    if model.time_dependent:
        out["float_time"] = (f"prescribed motions: the spin angles are computed in float, so the error grows with "
                             f"t; the bounds ({FLOAT_TIME}x those of a model without them) hold for 0 <= t <= 10")
    return out


def manifest(model, routines, ops: dict, omitted=None, scalar: str = "double", layout: dict | None = None) -> dict:
    """The JSON manifest of the generated code: ``routines`` those emitted, ``ops[role]`` their operation counts,
    ``omitted`` the routines left out and why, ``scalar`` the C type (with ``float``, ``float_tolerance``: per
    routine the error bound against the double twin that ``aggsym check`` holds the C to).  ``layout``: with
    ``aggsym generate --split``, the ``split`` entry (every file written, each routine's .c, the helpers' header,
    the Makefile and its library); without it the manifest has no ``split`` key, the C being NAME.c."""
    out = {
        "name": model.name,
        "scalar": scalar,
        "nq": model.nq,
        "nv": model.nv,
        "coordinates": [{"name": name, "joint": joint, "kind": kind} for name, joint, kind in model.positions],
        "velocities": [{"name": c.name, "joint": c.joint, "kind": c.kind} for c in model.coordinates],
        "parameters": [{"name": p.name, "value": p.value} for p in model.parameters],
        "functions": {r.role: c_symbol(model, r) for r in routines},
        "descriptions": {r.role: r.doc for r in routines},
        "signatures": {r.role: {"inputs": list(signature(r, model)),
                                "outputs": [{"name": o.name, "shape": list(o.shape(model))} for o in r.written],
                                "input_sizes": {i: input_length(model, i, r) for i in signature(r, model)},
                                "returns": f"int: 0, or nonzero when {r.status.failure}" if r.status else "void"}
                       for r in routines},
        "layouts": {r.role: r.layout(model) for r in routines if r.layout is not None},
        "couplings": [{"coordinate": c.coordinate, "master": c.master, "multiplier": c.multiplier,
                       "offset": c.offset} for c in model.couplings],
        "conservative": model.conservative,
        "ops": {r.role: ops[r.role] for r in routines},
        "omitted": dict(omitted or {}),
        "not_emitted": [r.role for r in ROUTINES.values() if r.exists_for(model) and r not in routines
                       and r.role not in (omitted or {})],
        "limits": [dict(limits) for limits in model.limits],
        "armature": model.armature,
        "bodies": len(model.bodies),
        "generator": f"aggsym {__version__}",
    }
    if scalar == "float":
        out.update(float_tolerance(model, routines))
    if model.time_dependent:
        out["time"] = time_entry(model, scalar)
    if elastic.is_elastic(model):
        out["elastic"] = elastic_entry(model)
    if model.constraints:
        out["constraints"] = constraints_entry(model)
    if any(r.role.startswith("frame_") for r in routines):
        out["frames"] = frames_entry(model)
    if model.meta.get("snapped_angles"):  # an approximation the user asked for (--snap-angles), recorded
        out["snapped_angles"] = model.meta["snapped_angles"]
    if layout is not None:
        out["split"] = layout
    return out


def constraints_entry(model) -> dict:
    """The manifest's description of the constraints (chapter 4): each one's rows and its slice of lambda."""
    items, start = [], 0
    for c in model.constraints:
        items.append({"name": c.name, "body": c.body, "link": c.link or None, "medium": c.medium,
                      "kind": c.kind or None, "rows": list(c.rows), "lambda": [start, start + len(c.rows)],
                      "point": [str(x) for x in c.point], "at": None if c.at is None else [str(x) for x in c.at],
                      "rotation": [[axis, str(angle)] for axis, angle in c.rotation],
                      "free": list(c.free_translations),
                      "friction": None if c.friction is None else {c.friction[0]: str(c.friction[1])},
                      "wheel": None if c.wheel is None else {"radius": str(c.wheel[0]),
                                                             "axle": [str(x) for x in c.wheel[1]]}})
        start += len(c.rows)
    return {
        "m": model.constraint_rows,
        "equations": ("A(q) qdd + b + g + c = tau + J^T lambda,  J qdd + gamma = -(kd J qd + kp phi) "
                      "(4.25)-(4.28); bilateral (no complementarity: a contact may pull)"),
        "rows": ("row r of J, gamma, phi and lambda: the constraint's forbidden motion along (o1 o2 o3) or about "
                 "(theta4 theta5 theta6) the axes of its reference frame, fixed in the medium at the contact "
                 "point; translational rows: the contact point's velocity relative to the medium, rotational: the "
                 "relative angular velocity; for ground contacts without rotation, Pinocchio's "
                 "LOCAL_WORLD_ALIGNED"),
        "lambda": ("the wrench (f, mu) the medium exerts on the body about the contact point, in the reference "
                   "axes, the entries of the blocked rows; a loop's medium body gets -lambda"),
        "phi": ("translational rows: the contact point's offset from 'at' (default: where it is at q = 0); "
                "rotational rows: the rotation vector of the body's orientation relative to the one it has at "
                "q = 0, both in the reference axes"),
        "stabilization": {"kp": str(model.stabilization[0]), "kd": str(model.stabilization[1])},
        "regularization": str(model.regularization),
        "rolling": ("a wheel (kind 'rolling'): its rows are the velocity of the disc's material point at the "
                    "contact, centre + radius * (axle x e), e = (axle x normal)/|axle x normal|; only o3 is "
                    "holonomic (phi: the contact point's height over the plane; the o1, o2 entries of phi are 0)"),
        "friction": ("on the free translations of a sliding contact, from its slip velocities w (slip_velocities): "
                     "viscous W = -c w; Coulomb W = -mu |lambda_n| w/|w| (zero where |w| < 1e-9), lambda_n the "
                     "constraint's one blocked translation; W acts on the body at the contact point (the medium "
                     "body gets -W)"),
        "constraints": items,
    }


def time_entry(model, scalar: str = "double") -> dict:
    """The manifest's description of the time input and of the prescribed motions (rotors, (2.13))."""
    rotors = []
    for b in model.bodies:
        for code, expr in b.pair.prescribed:
            rotors.append({"body": b.name, "carrier": b.parent, "joint": b.pair.name, "axis": code,
                           "angle": str(expr)})
    return {
        "input": "t",
        "length": 1,
        "meaning": ("the time: every routine takes it after its other inputs and before p (C: a pointer to one "
                    f"{scalar}; NumPy: a number or an array of the batch shape).  The prescribed angles below and "
                    "their first and second derivatives (taken symbolically) are evaluated at t; the carrier's "
                    "motion does not act on them (Prop. 2.7).  bias holds all their rate and acceleration terms."),
        "prescribed": rotors,
        "constraint_motions": [{"constraint": c.name, "motion": {code: str(expr) for code, expr in c.motion}}
                               for c in model.constraints if c.motion],
    }


def elastic_entry(model) -> dict:
    """The manifest's description of the elastic pairs (2.27)."""
    pairs = []
    for b in model.bodies:
        if b.pair.elastic:
            pairs.append({"joint": b.pair.name, "coordinates": [c.name for c in b.pair.coordinates],
                          "stiffness": [[str(x) for x in row] for row in b.pair.stiffness],
                          "rest": [str(x) for x in b.pair.rest] if b.pair.rest is not None
                          else ["0"] * len(b.pair.coordinates)})
    return {"equation": "A(q) qdd + b(q, qd) + g(q) + C (q - q0) = tau (2.27); c = C (q - q0) is the routine "
                        "'elastic', included in inverse_dynamics, nonlinear_effects and forward_dynamics; "
                        "1/2 (q - q0)^T C (q - q0) is in potential_energy",
            "pairs": pairs}
