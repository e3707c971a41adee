"""The PyTorch target: NAME_torch.py, the NumPy module's routines as functions of tensors (``--targets torch``).

Each routine is printed from its straight line by :func:`~.numpy.array_steps` with the spelling :data:`TORCH`
(``torch.sin``, ...): inputs unpacked, each named temporary one assignment, and the output entries collected and
stacked once at the end (no in-place write on a tensor that autograd tracks), so that autograd, ``torch.func``
(``vmap``, ``jacrev``) and ``torch.compile`` go through every routine; a temporary no output reads is deleted after
its last read (:func:`freed`).  The functions take any leading batch
dimensions (broadcast like the NumPy module's, ``p`` included), compute in the inputs' floating dtype on the
inputs' device (the default ``p`` is made there), and import only torch.

Where the module also has the derivative routines (``--routines default,inverse_dynamics_derivatives,
forward_dynamics_derivatives``), ``inverse_dynamics`` and ``forward_dynamics`` carry them as a
``torch.autograd.Function`` (:func:`analytic_routines`): their gradients along q, qd and qdd|tau are the generated
derivative matrices (with A or A^-1), those along p (and t) go through plain autograd of the traced routine.  With
quaternion pairs (a free-flyer, ball joints) the derivative routines are in Pinocchio's tangent space, not along
the entries of q: there the coordinates' columns are the routine's, and those of the quaternion pairs' entries that
the routine reads are generated too, by forward mode on its straight line (:func:`quaternion_columns`: four for a
free-flyer's dynamics, whose origin is never read).  The Function keeps the matrices that its first backward pass
makes for the later passes through the same graph (a Jacobian row by row).

With the kernels target (:mod:`.kernels`: ``--targets c,torch``) each routine's private function calls, on CPU
tensors of float32 or float64, its batch kernel as an operator of the module's ``torch.library.Library`` (fake
implementation, vmap rule) inside an ``autograd.Function`` whose derivatives are a vjp and a jvp of the traced
straight line (skipped where no derivative can be asked), its large outputs in a pool of reused blocks; the analytic
Functions above then run on the derivative routines' kernels (and the quaternion columns' kernel).

A routine with a status (a singular system: constrained forward dynamics, the support problems) cannot raise
under ``vmap`` or ``torch.compile``: its outputs hold NaN at the states of the batch where the status is nonzero
(the NumPy module raises LinAlgError there).  Checked by ``aggsym check`` against the numeric twin when torch is
installed: in float64, or in float32 under ``--scalar float`` against the float C's bounds (the manifest's
``float_tolerance``).
"""
from __future__ import annotations

import textwrap

from ...contract import SCALAR_INPUTS, input_length, routines_for
from ...core.functions import FUNCTIONS
from ...core.program import Node
from ...model.tree import Tree
from ..compile import import_module
from ..printing import Spelling, _number
from .base import Runner, Target
from .kernel_table import kernels_context, traced_modules
from .numpy import (_unravel, array_steps, names_read, quaternion_columns_lines, quaternion_entries_read, scalar_output,
                    statement_parts,
                    step_statement)

# torch's name of each function of aggsym/core/functions.py (element-wise, so that inputs carry batch dimensions)
TORCH_NAMES = {"sin": "sin", "cos": "cos", "sqrt": "sqrt", "tan": "tan", "exp": "exp", "log": "log", "abs": "abs",
               "asin": "asin", "acos": "acos", "atan": "atan", "atan2": "atan2", "sign": "sign"}
_missing = set(FUNCTIONS) - set(TORCH_NAMES)
if _missing:  # a function added to the table must be spelled here too
    raise ImportError(f"the PyTorch target has no spelling for {sorted(_missing)}")
# double literals as the C's (a Python float keeps a float32 tensor float32: torch's scalar promotion)
TORCH = Spelling({name: f"torch.{TORCH_NAMES[name]}" for name in FUNCTIONS}, _number)

# role -> (derivative routine, routine of the matrix along the third input, and how it acts): the routines whose
# gradients the generated derivatives carry; d tau / d qdd = A, d qdd / d tau = A^-1 (both symmetric)
ANALYTIC = {
    "inverse_dynamics": ("inverse_dynamics_derivatives", "inertia"),
    "forward_dynamics": ("forward_dynamics_derivatives", "inertia_inverse"),
}


def torch_body(model, prog, lines, routine, inputs) -> dict:
    """One routine as PyTorch (:func:`_printed`); for a routine whose gradients the derivative routines carry (when
    they are emitted too), on a model with quaternion pairs, also ``columns``: its derivative along the entries of
    those pairs that it reads (:func:`quaternion_columns`), or None."""
    body = _printed(model, prog, lines, inputs, [out.shape(model) for out in routine.outputs],
                    [f"{routine.role}: output {out.name}" for out in routine.outputs])
    if routine.role in ANALYTIC and model.nq != model.nv \
            and set(ANALYTIC[routine.role]) <= {r.role for r in routines_for(model)}:
        body["columns"] = quaternion_columns(model, prog, lines, routine, inputs, body["reads"])
    return body


def quaternion_columns(model, prog, lines, routine, inputs, reads) -> dict | None:
    """The derivative of the routine's first output along the entries of q's quaternion pairs that its straight line
    reads (the derivative routines are in the tangent space and do not give them), as a straight line of its own:
    forward mode on the routine's straight line (:func:`~aggsym.core.dual.along_inputs`), printed like a routine
    (:func:`_printed`) with one output of shape (n, len(entries)), and ``entries``.  None when it reads none."""
    entries = quaternion_entries_read(model, reads)
    if not entries:
        return None
    columns, rows = quaternion_columns_lines(prog, lines.outputs[0], entries)
    shape = (rows, len(entries))
    body = _printed(model, prog, columns, inputs, [shape],
                    [f"{routine.role}: its columns along q's quaternion entries"])
    return {**body, "entries": entries, "shape": shape}


def _printed(model, prog, lines, inputs, shapes, labels) -> dict:
    """A straight line as PyTorch: ``statements`` (inputs unpacked, temporaries), ``outputs``, per output (of
    ``shapes``) its entries' texts in row-major order (``zero`` for a zero, ``zero + c`` for another constant, so
    that every entry is a tensor of the batch shape when stacked), and ``reads``, per input the set of its entries
    that the straight line reads.  ``labels``: the outputs' names in errors."""
    entries = [[None] * _size(shape) for shape in shapes]
    statements, reads, temporaries = [], {}, set()
    for step in array_steps(model, prog, lines, None, inputs, TORCH):
        if step[0] == "input":
            reads.setdefault(step[2], set()).add(step[3])
        elif step[0] == "temp":
            temporaries.add(step[1])
        statement = step_statement(step)
        if statement is not None:
            statements.append(statement)
        else:
            _, o, k, rhs = step
            x = lines.outputs[o][k]
            if rhs is None or (not isinstance(x, Node) and float(x) == 0.0):
                entries[o][k] = "zero"
            elif not isinstance(x, Node):  # a constant
                entries[o][k] = f"zero + {rhs}"
            else:
                entries[o][k] = rhs
    for o, shape in enumerate(shapes):
        for k, e in enumerate(entries[o]):
            if e is None:
                raise RuntimeError(f"{labels[o]} entry {_unravel(k, shape)} was never written")
    return {"statements": freed(statements, entries, temporaries), "outputs": entries, "reads": reads,
            "zero": any(e == "zero" or e.startswith("zero + ") for out in entries for e in out)}


def freed(statements: list, entries: list, temporaries: set) -> list:
    """The statements with each of the ``temporaries`` that no output entry reads deleted (``del``) right after the
    last statement that reads it: its tensor returns to PyTorch's allocator and is reused, still in the caches, by
    the next result.  Otherwise every temporary of a routine lives until its outputs are stacked: Panda's A(q) holds
    about 300 of them, 10 MB at B = 4096, far beyond the caches, so that its time per state grew from B = 1024 to
    4096 (by hand, an AMD EPYC host: 2.3 then 2.8 µs per state, median; with the temporaries freed 2.1 then 1.2).
    Autograd keeps what it saves whatever the name: only the name goes."""
    kept = {name for out in entries for e in out for name in names_read(e)}
    last = {}
    for k, statement in enumerate(statements):
        target, used = statement_parts(statement)
        for name in used:
            last[name] = k
        last.setdefault(target, k)  # (a temporary no statement reads: freed where it is made)
    after = {}
    for name, k in last.items():
        if name in temporaries and name not in kept:
            after.setdefault(k, []).append(name)
    out = []
    for k, statement in enumerate(statements):
        out.append(statement)
        if k in after:
            out.append("del " + ", ".join(after[k]))
    return out


def _wiring(model, e, derivative, matrix, columns) -> dict:
    """How the autograd.Function of routine ``e`` (inputs q, qd, qdd|tau, [t], p) takes its gradients: along q, qd
    and the third input from the derivative routine and the matrix, along the ``plain`` ones (t, p) by a vjp (jvp)
    of the traced routine; the names and the backward's tuple for the template.

    ``columns``: False without quaternion pairs; with them (a free-flyer, ball joints: the derivative routines are
    in the tangent space) :func:`quaternion_columns`'s (None: the routine reads no quaternion entry).  The derivative
    along q's entries is then assembled by ``_along_entries``: the tangent space's column V[j] at the coordinate's
    entry Q[j] (the tree's ``position_split``), the generated column at each quaternion entry the routine reads,
    zero at the others (a free-flyer's origin in the dynamics), along which it is constant."""
    inputs = list(e.inputs)
    plain = inputs[3:]
    pairs = [(inputs[0], "d_q"), (inputs[1], "d_qd"), (inputs[2], "m")]
    backward = [f"(g @ {d}).squeeze(-2)" for _, d in pairs]
    split = None
    if columns is not False:
        backward[0] = f"None if d_q is None else {backward[0]}"
        Q, V, _ = Tree.of(model).position_split
        entries = columns["entries"] if columns else ()
        where = {**dict(zip(Q, V)), **{i: model.nv + t for t, i in enumerate(entries)}}
        index = [str(where.get(i, model.nv + len(entries))) for i in range(model.nq)]
        split = {"columns": columns, "constant": f"_{e.routine.role.upper()}_ENTRIES",
                 "index": "\n    ".join(textwrap.wrap(", ".join(index) + ",", 100))}
    backward += [f"grad_{i}" for i in plain]
    return {"derivative": derivative.routine.role, "matrix": matrix.routine.role, "class": _class_name(e.routine.role),
            "derivative_inputs": list(derivative.inputs), "matrix_inputs": list(matrix.inputs), "third": inputs[2],
            "analytic": [x for x, _ in pairs[:-1]], "plain": plain, "plain_index": tuple(inputs.index(i) for i in plain),
            "plain_grads": [f"grad_{i}" for i in plain], "plain_dots": [f"{i}_dot" for i in plain],
            "plain_args": [f"{i}_" for i in plain], "plain_call": [f"{i}_" if i in plain else i for i in inputs],
            "analytic_pairs": pairs, "backward": backward, "split": split}


def _class_name(role: str) -> str:
    """The autograd.Function of a routine: ``forward_dynamics`` -> ``_ForwardDynamics``."""
    return "_" + "".join(w.title() for w in role.split("_"))


def _size(shape) -> int:
    n = 1
    for s in shape:
        n *= s
    return n


def analytic_routines(model, emitted) -> dict:
    """{role: (derivative routine, matrix routine)} of the routines whose gradients the module carries by the
    generated derivatives: each of :data:`ANALYTIC` whose two helpers are emitted with the same inputs."""
    roles = {e.routine.role: e for e in emitted}
    out = {}
    for role, (derivative, matrix) in ANALYTIC.items():
        if role in roles and derivative in roles and matrix in roles \
                and roles[derivative].inputs == roles[role].inputs:
            out[role] = (derivative, matrix)
    return out


class TorchTarget(Target):
    """NAME_torch.py: the NumPy module's functions over tensors (any leading batch dimensions, the inputs' dtype
    and device), autograd and ``torch.func`` through every routine, the generated derivatives wired in."""

    name = "torch"
    column = "PyTorch"
    folder = "torch"
    templates = ("model_torch.py.j2",)

    def file_names(self, job):
        return [f"{job.model.name}_torch.py"]

    def owns(self, name, file):
        return file == f"{name}_torch.py"

    def print_routine(self, model, prog, lines, emitted):
        return torch_body(model, prog, lines, emitted.routine, emitted.inputs)

    def render(self, job):
        model = job.model
        analytic = analytic_routines(model, job.emitted)
        routines = []
        for e in job.emitted:
            body = e.bodies[self.name]
            arrays = [i for i in e.inputs if i not in ("p", "t", "dt", "r")]
            scalars = [i for i in e.inputs if i in ("t", "dt", "r")]
            wired = analytic.get(e.routine.role)
            if wired:
                by_role = {x.routine.role: x for x in job.emitted}
                columns = body["columns"] if model.nq != model.nv else False
                wired = _wiring(model, e, by_role[wired[0]], by_role[wired[1]], columns)
            routines.append({
                "role": e.routine.role, "doc": e.routine.doc, "inputs": list(e.inputs), "arrays": arrays,
                "scalars": scalars, "has_p": "p" in e.inputs, "py_parameters": e.py_parameters,
                "statements": body["statements"],
                "zero": body["zero"],
                "outputs": [{"py": o.py, "shape": o.shape(model), "entries": body["outputs"][k],
                             "returned": o.returned} for k, o in enumerate(e.routine.outputs)],
                "written": [{"py": o.py, "scalar": scalar_output(o)} for o in e.routine.written],
                "status": e.routine.status.py if e.routine.status else None,
                "failure": e.routine.status.failure if e.routine.status else "",
                "analytic": wired,
                "lengths": [(i, input_length(model, i, e.routine)) for i in e.inputs if i not in SCALAR_INPUTS],
                "kernel_shapes": [tuple(o.shape(model)) for o in e.routine.written],
                "written_index": [k for k, o in enumerate(e.routine.outputs) if not o.returned],
            })
        kernels = kernels_context(job)
        for r in routines:  # the quaternion columns by their kernel (when it is along the same entries)
            k = kernels and kernels[r["role"]]["columns"]
            split = r["analytic"] and r["analytic"]["split"]
            r["kernel_columns"] = None
            if k and split and split["columns"] and tuple(split["columns"]["entries"]) == k["entries"]:
                r["kernel_columns"] = {"role": f"{r['role']}_quaternion_columns", "shape": k["shape"]}
        ctx = {**job.ctx, "torch_routines": routines, "quaternion": model.nq != model.nv, "kernels": kernels,
               "analytic": [r["role"] for r in routines if r["analytic"]],
               "statuses": [r["role"] for r in routines if r["status"]]}
        return {f"{model.name}_torch.py": self.template("model_torch.py.j2").render(ctx)}

    def main_file(self, name):
        return f"{name}_torch.py"

    def unavailable(self):
        try:
            import torch  # noqa: F401
        except ImportError:
            return "torch is not installed (pip install aggsym[torch])"
        return None

    def runner(self, model, folder, manifest, opt):
        """The module called on float64 tensors, or on float32 ones when the manifest's scalar is float (``aggsym
        check --scalar float``), held then to the float C's bounds (the manifest's ``float_tolerance``, those of
        ``float_tolerance_per_condition`` also relative to cond(A)).  NaN outputs of a routine with a status are
        its failure: raised as numpy.linalg.LinAlgError, as the NumPy module does."""
        with traced_modules():  # (the module as traced: its kernels, if any, are the kernels target's columns)
            module = import_module(folder / f"{model.name}_torch.py")
        single = manifest.get("scalar", "double") == "float"
        call = torch_call(module, manifest, single)
        if not single:
            return Runner(call)
        return Runner(call, manifest.get("float_tolerance", {}),
                      tuple(manifest.get("float_tolerance_per_condition", ())))


def torch_call(module, manifest, single: bool):
    """A generated PyTorch module's routines as :attr:`Runner.call`: float32 (``single``) or float64 tensors in,
    NumPy arrays out; NaN outputs of a routine with a status raised as numpy.linalg.LinAlgError."""
    import numpy as np
    import torch

    dtype = torch.float32 if single else torch.float64
    statuses = {role for role, sig in manifest["signatures"].items() if sig.get("returns", "void") != "void"}

    def call(role, *args):
        tensors = [torch.as_tensor(np.asarray(a, dtype=float), dtype=dtype) for a in args]
        with torch.no_grad():
            got = getattr(module, role)(*tensors)
        outs = tuple(x.double().numpy() for x in (got if isinstance(got, tuple) else (got,)))
        if role in statuses and any(np.isnan(x).any() for x in outs):
            raise np.linalg.LinAlgError(f"{role}: NaN outputs: the system is singular")
        return outs[0] if len(outs) == 1 else outs
    return call


def torch_jacobian(module):
    """:attr:`Runner.jacobian` of a PyTorch module: torch.func.jacrev of a routine's first output along each array
    argument (float64)."""
    import numpy as np
    import torch

    def jacobian(role, *args):
        arrays = tuple(k for k, a in enumerate(args) if np.ndim(a))
        f = getattr(module, role)
        tensors = [torch.as_tensor(np.asarray(a, dtype=float), dtype=torch.float64) for a in args]
        jac = torch.func.jacrev(lambda *xs: _first(f(*xs)), argnums=arrays)(*tensors)
        return [j.detach().numpy() for j in jac]
    return jacobian


def _first(out):
    """A routine's first output (the output itself where it has one)."""
    return out[0] if isinstance(out, tuple) else out

