"""The registry of routines: what a routine is (:class:`Routine`, its :class:`Output` arrays), the registry
:data:`ROUTINES` in the order of registration (the order of emission and of the manifest), a routine's inputs for a
model (:func:`signature`, :func:`input_length`), the routines a model emits (:func:`routines_for`), and running a
routine on a bound model (:func:`run`, through :class:`~aggsym.mechanics.coupling.Coupler` for coupled
coordinates).  The routines themselves are registered by the ``routines_*`` modules of this package."""
from __future__ import annotations

import keyword
from dataclasses import dataclass
from typing import Callable

from ..mechanics.coupling import Coupler
from ..mechanics.kinematics import TreeKinematics


INPUT_KINDS = ("q", "qd", "qdd", "tau", "gamma", "gammad", "gammadd", "T", "t", "v", "dt", "qd_minus", "r")  # t: the
# time of models with prescribed motions; gamma, gammad, gammadd (the mechanism's coordinates) and T (a wrench) of
# the support routines; v (a velocity, nv) and dt (a time step) of integrate; qd_minus (the velocity before an
# impact, nv) and r (the restitution coefficient, one number) of the impulse dynamics
SCALAR_INPUTS = ("t", "dt", "r")  # the inputs that are one number


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
    # inertia is shared between bodies: generated from the internal model (aggsym.model.transforms.reframe).  Not the Coriolis
    # matrix: of the many C with C qd = b and A' - 2C skew, the one built from the bodies' B (2.17) depends on them
    slice_size: int | None = None  # the C's slices (aggsym.codegen.slicing) where smaller than the default's run faster
    scalar_stores: bool = False  # a symmetric matrix: its C compiled without GCC's basic-block vectorizer
    # (AGGSYM_SCALAR_STORES, templates/c/attributes.c.j2), which packs the neighbouring stores into shuffled vectors

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
# (model, role) -> the routine as that model emits it: ROUTINES[role] here; aggsym.contract.singular_states puts its
# routine_of in (the package imports it), so that this module imports nothing of the judgement of A(q)
EMITTED_AS = [lambda model, role: ROUTINES[role]]


def register(routine: Routine) -> Routine:
    """Add a routine to the contract (the order of registration is the order of emission)."""
    ROUTINES[routine.role] = routine
    return routine


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
    return len(model.parameters) if name == "p" else 1 if name in SCALAR_INPUTS else 6 if name == "T" else model.nv


def routines_for(model, roles=None, omitted=()) -> list:
    """The routines emitted for a model, in emission order: those named (``roles``, else the model's own selection
    ``model.routines``, else every routine of the contract that applies and is not on request), less the
    ``omitted`` ones (:func:`omitted_routines`), each as the model emits it (:data:`EMITTED_AS`: with a status
    where A(q) may be singular on a set of configurations, :func:`~.singular_states.routine_of`)."""
    if roles is None:
        roles = model.routines
    return [EMITTED_AS[0](model, role) for role, r in ROUTINES.items()
            if (role in roles if roles is not None else not r.on_request) and r.exists_for(model)
            and role not in omitted]


def flat(rows):
    """Rows (or columns) as one flat list, row-major: how a build returns a matrix."""
    return [x for row in rows for x in row]


def minus(a, b):
    """a - b entry by entry."""
    return [x - y for x, y in zip(a, b)]


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
        return (flat(coupler.inertia_inverse(bound, kin)),)
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
        return tuple(flat(coupler.reduce_matrix([list(o[i * n:(i + 1) * n]) for i in range(n)])) for o in outs)
    return outs
