"""The CasADi target: NAME_casadi.py, every routine as a ``casadi.Function`` over SX (``--targets casadi``).

Each routine is printed from its straight line by :func:`~.numpy.array_steps` with the spelling :data:`CASADI`
(``ca.sin``, ``ca.fabs``, ...): the inputs split into their entries once (``ca.vertsplit``), each named
temporary one assignment of SX scalars, the outputs assembled once from their entries (row-major, as every
target's) into CasADi's 2-D shapes (:func:`casadi_shape`): a vector of n entries is an (n, 1) column, a matrix
(n, m) stays (n, m), a scalar (the energies) is (1, 1), an array of more dimensions has its leading ones merged.
A routine with a status (a singular system) has it as one more output, ``status`` (1, 1), nonzero where the
system is singular (a Function cannot raise).  The module imports casadi
only, and builds each Function on first use (the module's ``__getattr__``; :func:`functions` builds them all),
so that importing it costs only Python's compilation of its text (Talos reduced, 32 joints: import 0.35 s, every
Function with the derivative routines 1.6 s, on this project's shared 2-core machine).

SX, not MX: the same straight line over MX scalars (Talos' forward dynamics; measured by hand with the generated
module's ``ca.SX`` replaced by ``ca.MX``) took 0.14 s to build against SX's 0.09 s, had 7,678 instructions
against 6,643, and one evaluation in CasADi's virtual machine took 203 µs against 90 µs; an MX Function calling
SX pieces would only add call nodes to a program whose CSE has already run across the whole routine.  So every
routine is SX, and an MX graph of a user's (``casadi.Opti``) holds each as one call node.

Where the module also has the derivative routines (``--routines default,inverse_dynamics_derivatives,
forward_dynamics_derivatives``), ``inverse_dynamics`` and ``forward_dynamics`` carry them as CasADi's
``custom_jacobian`` (with ``jac_penalty`` 0): a Function ``jac_ROLE`` of the routine's inputs and its nominal
output (``out_OUTPUT``) giving ``jac_OUTPUT_INPUT`` for every input, the generated matrices along q, qd and
qdd|tau (d tau / d qdd = A, d qdd / d tau = A^-1), CasADi's AD of the SX graph along the others (t, p).  So
``casadi.jacobian`` of an MX expression that calls the Function (``casadi.Opti``, ``nlpsol``) takes the
generated derivatives; calling a Function on SX symbols inlines its graph, whose Jacobian is CasADi's AD.  With
quaternion pairs (a free-flyer, ball joints) the derivative routines are in Pinocchio's tangent space (nv
columns) while the Function's q has nq entries: there the Jacobian along q takes the tangent columns for the
scalar joints' entries and CasADi's AD of the graph along the quaternion pairs' entries alone (the free-flyer's
seven: forward AD in seven directions, not nq) (:func:`_q_columns`).  Where A(q) may be singular on a set of
configurations (:mod:`aggsym.contract.singular_states`) the routines have a status output too, whose Jacobian
(a piecewise constant) is zero.
"""
from __future__ import annotations

import re
from collections import Counter

from ...contract import SCALAR_INPUTS, input_length
from ...core.functions import FUNCTIONS
from ...core.program import DIV, Node
from ..compile import import_module
from ..printing import Spelling, _number
from .base import Runner, Target
from .numpy import _unravel, array_steps, scalar_output
from .torch import analytic_routines

# CasADi's name of each function of aggsym/core/functions.py (casadi.sin, ... on SX and MX alike)
CASADI_NAMES = {"sin": "sin", "cos": "cos", "sqrt": "sqrt", "tan": "tan", "exp": "exp", "log": "log",
                "abs": "fabs", "asin": "asin", "acos": "acos", "atan": "atan", "atan2": "atan2", "sign": "sign"}
_missing = set(FUNCTIONS) - set(CASADI_NAMES)
if _missing:  # a function added to the table must be spelled here too
    raise ImportError(f"the CasADi target has no spelling for {sorted(_missing)}")
CASADI = Spelling({name: f"ca.{CASADI_NAMES[name]}" for name in FUNCTIONS}, _number)


def casadi_body(model, prog, lines, routine, inputs) -> dict:
    """One routine as CasADi statements: ``statements`` (each input split into its entries, the temporaries) and
    ``outputs``, per output its entries' texts in row-major order (``0`` for a structural zero).  A reciprocal
    ``r = 1/d`` that the straight line shares is written ``2/(2*d)`` (:func:`_shared_reciprocals`)."""
    shapes = [out.shape(model) for out in routine.outputs]
    entries = [[None] * _size(shape) for shape in shapes]
    reads, statements, reciprocals = {}, [], {}
    ids = {name: i for i, name in lines.names.items()}
    for step in array_steps(model, prog, lines, routine, inputs, CASADI):
        if step[0] == "input":
            reads.setdefault(step[2], set()).add(step[3])
        elif step[0] == "temp":
            entry = prog.ops[ids[step[1]]]
            if entry[0] == DIV and step[2].startswith("1/") and not isinstance(entry[1], Node) and entry[1] == 1:
                reciprocals[len(statements)] = step[1]
            statements.append(f"{step[1]} = {step[2]}")
        else:
            _, o, k, rhs = step
            x = lines.outputs[o][k]
            entries[o][k] = "0" if rhs is None or (not isinstance(x, Node) and float(x) == 0.0) else rhs
    for o, shape in enumerate(shapes):
        for k, e in enumerate(entries[o]):
            if e is None:
                raise RuntimeError(f"{routine.role}: output {routine.outputs[o].name} entry {_unravel(k, shape)} "
                                   f"was never written")
    _shared_reciprocals(statements, entries, reciprocals)
    split = []
    for kind in inputs:
        if kind in reads and kind not in SCALAR_INPUTS:
            n = input_length(model, kind, routine)
            names = [f"{kind}_{i}" if i in reads[kind] else "_" for i in range(n)]
            split.append(f"{', '.join(names)}{',' if n == 1 else ''} = ca.vertsplit({kind})")
        elif kind in reads:
            split.append(f"{kind}_0 = {kind}")
    return {"statements": split + statements, "outputs": entries}


_NAME = re.compile(r"\bx\d+\b")


def _shared_reciprocals(statements, entries, reciprocals) -> None:
    """Rewrite in place each reciprocal temporary ``r = 1/d`` used more than once as ``r = 2/(2*d)``: CasADi turns
    ``y*r`` into ``y/d`` when r is its reciprocal node (OP_INV), a division at every use where the straight line
    has one (Talos' forward dynamics: 139 against 27); 2/(2*d) is not such a node, and is the same number (2*d is
    exact, so the quotient is 1/d correctly rounded), so the products stay products of the one quotient."""
    if not reciprocals:
        return
    uses = Counter(_NAME.findall("\n".join(statements[k].split(" = ", 1)[1] for k in range(len(statements)))))
    uses.update(_NAME.findall("\n".join(str(e) for out in entries for e in out)))
    for k, name in reciprocals.items():
        if uses[name] > 1:
            denominator = statements[k].split(" = 1/", 1)[1]
            statements[k] = f"{name} = 2/(2*{denominator})"


def _size(shape) -> int:
    n = 1
    for s in shape:
        n *= s
    return n


def casadi_shape(output, model) -> tuple:
    """An output's shape in CasADi (2-D): (n, 1) for a vector of n entries, (1, 1) for a scalar, (n, m) for a
    matrix, (n1 * ... * nk-1, nk) for an array of k > 2 dimensions (the frames' Jacobians (frames, 6, n): their
    6 x n blocks stacked; the same row-major entries)."""
    shape = tuple(output.shape(model))
    if scalar_output(output) or not shape:
        return (1, 1)
    if len(shape) == 1:
        return (shape[0], 1)
    return (_size(shape[:-1]), shape[-1])


def numpy_shape(output, model) -> tuple:
    """The NumPy module's shape of an output for one state: () for a scalar, its declared shape otherwise."""
    return () if scalar_output(output) else tuple(output.shape(model))


def _analytic(model, emitted, e, analytic) -> dict | None:
    """How routine ``e``'s custom Jacobian is made from the derivative routine and the matrix routine (the
    torch target's table of them, :func:`~.torch.analytic_routines`), or None where it has none (along q with
    quaternion pairs: :func:`_q_columns`)."""
    if e.routine.role not in analytic:
        return None
    derivative, matrix = analytic[e.routine.role]
    by_role = {x.routine.role: x for x in emitted}
    inputs = list(e.inputs)
    return {"derivative": derivative, "matrix": matrix, "derivative_inputs": list(by_role[derivative].inputs),
            "matrix_inputs": list(by_role[matrix].inputs), "third": inputs[2], "plain": inputs[3:],
            "columns": _q_columns(model),
            # (A(q) may be singular on a set: the routines' status outputs, after their matrices; a status is
            # piecewise constant, its Jacobian zero)
            "statuses": [by_role[r].routine.status is not None for r in (derivative, matrix)],
            "lengths": [input_length(model, i, e.routine) for i in inputs]}


def _q_columns(model) -> dict | None:
    """With quaternion pairs (a free-flyer, ball joints): how the Jacobian along q's nq entries is made from the
    derivative routine's nv tangent-space columns: ``columns``, per entry of q, the text of its column (the
    tangent column of a scalar joint's entry, ``d_q[:, V]``; for an entry of a quaternion pair, a free-flyer's
    origin included, CasADi's AD of the graph along those entries alone, ``q_ad[:, k]``), and ``entries``, those
    entries; None without quaternion pairs (the tangent space is q's)."""
    if model.nq == model.nv:
        return None
    from ...model.tree import Tree

    positions, velocities, entries = Tree.of(model).position_split
    tangent = dict(zip(positions, velocities))
    ad = {j: k for k, j in enumerate(entries)}
    columns = [f"d_q[:, {tangent[j]}]" if j in tangent else f"q_ad[:, {ad[j]}]" for j in range(model.nq)]
    return {"columns": columns, "entries": list(entries)}


class CasadiTarget(Target):
    """NAME_casadi.py: the NumPy module's routines as casadi.Function over SX (same names, inputs in the same
    order and named alike, outputs in CasADi's 2-D shapes), the generated derivatives attached as Jacobians."""

    name = "casadi"
    column = "CasADi"
    checked_by_default = False  # (``aggsym check --targets casadi``: its column and its derivatives' rows)
    folder = "casadi"
    templates = ("model_casadi.py.j2",)

    def file_names(self, job):
        return [f"{job.model.name}_casadi.py"]

    def owns(self, name, file):
        return file == f"{name}_casadi.py"

    def print_routine(self, model, prog, lines, emitted):
        return casadi_body(model, prog, lines, emitted.routine, emitted.inputs)

    def render(self, job):
        model = job.model
        analytic = analytic_routines(model, job.emitted)
        routines = []
        for e in job.emitted:
            body = e.bodies[self.name]
            status = e.routine.status
            outputs = [{"name": o.py, "shape": casadi_shape(o, model), "numpy": numpy_shape(o, model),
                        "entries": body["outputs"][k]} for k, o in enumerate(e.routine.outputs) if not o.returned]
            if status is not None:
                k = list(e.routine.outputs).index(status)
                outputs.append({"name": "status", "shape": (1, 1), "numpy": (), "entries": body["outputs"][k]})
            routines.append({
                "role": e.routine.role, "doc": e.routine.doc, "inputs": list(e.inputs),
                "lengths": [(i, input_length(model, i, e.routine)) for i in e.inputs],
                "statements": body["statements"], "outputs": outputs, "status": status is not None,
                "failure": status.failure if status is not None else "",
                "analytic": _analytic(model, job.emitted, e, analytic),
            })
        ctx = {**job.ctx, "casadi_routines": routines, "statuses": [r["role"] for r in routines if r["status"]],
               "analytic": [r["role"] for r in routines if r["analytic"]]}
        return {f"{model.name}_casadi.py": self.template("model_casadi.py.j2").render(ctx)}

    def main_file(self, name):
        return f"{name}_casadi.py"

    def unavailable(self):
        try:
            import casadi  # noqa: F401
        except ImportError:
            return "casadi is not installed (pip install aggsym[casadi])"
        return None

    def runner(self, model, folder, manifest, opt):
        """The module's Functions called on numbers (p: its PARAMETERS), outputs in the NumPy module's shapes (a
        nonzero status raised as numpy.linalg.LinAlgError); their Jacobians by ``casadi.jacobian`` through an MX
        call (so the attached derivative routines where there are any)."""
        module = import_module(folder / f"{model.name}_casadi.py")
        return Runner(casadi_call(module), jacobian=casadi_jacobian(module))


def casadi_call(module):
    """A generated CasADi module's Functions as :attr:`Runner.call`: NumPy arrays in (p defaulting to the module's
    PARAMETERS), NumPy arrays out in the NumPy module's shapes (``module.SHAPES``)."""
    import numpy as np

    def call(role, *args):
        f = module.functions()[role]
        values = [np.reshape(np.asarray(a, dtype=float), (-1, 1)) if np.ndim(a) else float(a) for a in args]
        got = f.call(values + [module.PARAMETERS] * (f.n_in() - len(values)))
        shapes = module.SHAPES[role]
        outs = [np.reshape(x.full(), s) for x, s in zip(got, shapes)]
        if role in module.STATUS:
            if float(outs[-1]) != 0.0:
                raise np.linalg.LinAlgError(f"{role}: nonzero status: the system is singular")
            outs = outs[:-1]
        return outs[0] if len(outs) == 1 else tuple(outs)
    return call


def casadi_jacobian(module):
    """:attr:`Runner.jacobian` of a generated CasADi module: ``casadi.jacobian`` of a routine's first output along
    each array argument, through an MX call of its Function (the attached derivative routines where there are
    any), at the module's PARAMETERS."""
    import casadi as ca
    import numpy as np

    def jacobian(role, *args):
        f = module.functions()[role]
        symbols = [ca.MX.sym(f.name_in(k), f.sparsity_in(k)) for k in range(f.n_in())]
        out = f.call(symbols)[0]
        arrays = [k for k, a in enumerate(args) if np.ndim(a)]
        J = ca.Function("J", symbols, [ca.jacobian(out, symbols[k]) for k in arrays])
        values = [np.reshape(np.asarray(a, dtype=float), (-1, 1)) if np.ndim(a) else float(a) for a in args]
        values += [module.PARAMETERS] * (f.n_in() - len(values))
        shape = module.SHAPES[role][0]
        return [np.reshape(j.full(), tuple(shape) + (-1,)) for j in J.call(values)]
    return jacobian
