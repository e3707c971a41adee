"""The NumPy target: NAME.py, the routines as NumPy functions over any leading batch dimensions.

A routine is printed from its straight line in program order: inputs unpacked, each named temporary one
assignment, each output entry stored; a right-hand side without a function call is the C's text when the C is
double (:attr:`~.base.RoutineLines.shared`: the two printers differ only in function names and float literals),
otherwise printed by :class:`~aggsym.codegen.printing.Infix` with the spelling table :data:`NUMPY`.  Checked by
importing the module and calling it against the numeric twin.
"""
from __future__ import annotations

import ast
from dataclasses import dataclass

from ...contract import SCALAR_INPUTS, input_length, scalar
from ...core.functions import FUNCTIONS
from ...core.dual import along_inputs
from ...core.program import Node, straight_line
from ...model.tree import Tree
from ..printing import Infix, Spelling, _number
from ..compile import import_module
from .base import RoutineLines, Runner, Target, file_pattern


# the NumPy spelling: each function's NumPy form (element-wise, so that inputs may carry a leading batch
# dimension), double literals as the C's
NUMPY = Spelling({name: f"np.{f.numpy_name}" for name, f in FUNCTIONS.items()}, _number)


def _unravel(k, shape):
    out = []
    for n in reversed(shape):
        out.append(k % n)
        k //= n
    return tuple(reversed(out))


def array_steps(model, prog, lines, routine, inputs, spelling):
    """One routine's straight line for a target over arrays with leading batch dimensions (NumPy, JAX,
    PyTorch, ...), in program order: ``("input", name, kind, index)`` an input entry unpacked,
    ``("temp", name, text)`` a named temporary, ``("out", output, entry index, text)`` an output entry (text
    None: written as a chunk of zeros).  ``spelling``: the target's :class:`~aggsym.codegen.printing.Spelling`;
    a right-hand side without a function call is the C's text when the C is double (the same in every infix
    target whose literals agree)."""
    sl, names, outputs, zeros, shared = lines.sl, lines.names, lines.outputs, lines.zeros, lines.shared
    printer = Infix(prog, names, spelling)  # (its operation counts are the C's concern; discarded here)

    def printed(x, top=True):
        text = printer(x, top)
        printer.refs.clear()
        return text

    def text(x, key, top=True):
        done = shared.get(key)
        return done if done is not None else printed(x, top)
    for kind in inputs:
        for k, i in sl.inputs:
            if k == kind:
                yield ("input", f"{kind}_{i}", kind, i)
    for s, step in enumerate(sl.steps):
        if step[0] == "out":
            _, o, k = step
            x = outputs[o][k]
            yield ("out", o, k, None if s in zeros
                   else text(x, (o, k), top=not (isinstance(x, Node) and x.id in names)))
            continue
        i = step[1]
        if i in lines.trig:  # (the C computes sin and cos together; an array target each where it stands)
            yield ("temp", names[i], printed(prog.nodes[i]))
            continue
        yield ("temp", names[i], text(prog.nodes[i], i))


def scalar_output(output) -> bool:
    """Whether an output is one number per state in the array targets (shape (...,), not (..., 1)): the contract's
    scalars (:func:`~aggsym.contract.shapes.scalar`: the energies), not a vector that has one entry for this model
    (b, g, qdd of one coordinate, one constraint row, ...), which keeps its declared shape (..., 1)."""
    return output.shape is scalar


def quaternion_columns_lines(prog, output, entries) -> tuple:
    """(lines, rows): the derivative of a routine's flat first output ``output`` along q's ``entries`` (those of its
    quaternion pairs that it reads) as a straight line of its own, forward mode on the routine's
    (:func:`~aggsym.core.dual.along_inputs`): one output of ``rows`` x len(entries), row-major, its inputs named
    ``KIND_INDEX`` and its temps ``xK`` (no sin and cos pairs: :attr:`RoutineLines.trig` empty)."""
    columns = along_inputs(prog, output, [("q", i) for i in entries])
    flat = [x for row in columns for x in row]
    sl = straight_line(prog, [flat])
    names = {prog.inputs[key].id: f"{key[0]}_{key[1]}" for key in sl.inputs}
    names.update({i: f"x{k}" for k, i in enumerate(sl.temps)})
    return RoutineLines(sl, names, [flat], {}, {}, {}, False), len(columns)


def quaternion_entries_read(model, reads: dict) -> tuple:
    """The entries of q's quaternion pairs (the tree's ``position_split``: a free-flyer's origin and quaternion, a
    ball's quaternion) that a routine's straight line reads (``reads``: per input the entries it reads, from the
    ``("input", ...)`` steps of :func:`array_steps`), in q's order: where the derivative routines, in the tangent
    space, give no column of their own."""
    return tuple(i for i in Tree.of(model).position_split[2] if i in reads.get("q", ()))


def _names(tree) -> list:
    used = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and node.id not in used:
            used.append(node.id)
    return used


def names_read(expression: str) -> list:
    """The names a generated Python expression reads, in the order of their first appearance."""
    return _names(ast.parse(expression, mode="eval"))


def statement_parts(statement: str) -> tuple:
    """(the name a generated statement ``name = rhs`` assigns, the names its right-hand side reads)."""
    tree = ast.parse(statement, mode="exec").body[0]
    if not (isinstance(tree, ast.Assign) and len(tree.targets) == 1 and isinstance(tree.targets[0], ast.Name)):
        raise ValueError(f"not a generated assignment: {statement!r}")
    return tree.targets[0].id, _names(tree.value)


def step_statement(step) -> str | None:
    """The Python statement of an input or temporary step of :func:`array_steps` (the same in every array
    target); None for an output entry, which each target assembles its own way."""
    if step[0] == "input":
        return f"{step[1]} = {step[2]}[..., {step[3]}]"
    if step[0] == "temp":
        return f"{step[1]} = {step[2]}"
    return None


def numpy_body(model, prog, lines, routine, inputs) -> list:
    """The Python statements of one routine (the function's body, before its returns): outputs filled in
    place."""
    shapes = [out.shape(model) for out in routine.outputs]
    body = []
    for step in array_steps(model, prog, lines, routine, inputs, NUMPY):
        statement = step_statement(step)
        if statement is not None:
            body.append(statement)
        else:
            _, o, k, rhs = step
            target = f"{routine.outputs[o].py}[..., {', '.join(str(j) for j in _unravel(k, shapes[o]))}]"
            body.append(f"{target} = {0 if rhs is None else rhs}")
    return body


@dataclass
class NumPyBody:
    """A routine's NumPy text (``EmittedRoutine.bodies["numpy"]``): its statements ``lines`` and {array input: the
    length of its last dimension} (``lengths``, checked on entry)."""

    lines: list
    lengths: dict


class NumPyTarget(Target):
    """NAME.py: the same functions without the prefix, outputs returned, ``p`` defaulting to PARAMETERS."""

    name = "numpy"
    default = True
    column = "NumPy"
    folder = "numpy"
    templates = ("model.py.j2",)

    def file_names(self, job):
        return [f"{job.model.name}.py"]

    def owns(self, name, file):
        return bool(file_pattern(name, ("py",)).fullmatch(file))

    def print_routine(self, model, prog, lines, emitted):
        # the statements, and the length of each array input's last dimension, checked on entry (a ValueError
        # naming the argument)
        return NumPyBody(numpy_body(model, prog, lines, emitted.routine, emitted.inputs),
                         {i: input_length(model, i, emitted.routine) for i in emitted.inputs
                          if i not in SCALAR_INPUTS})

    def render(self, job):
        ctx = {**job.ctx, "scalar_output": scalar_output}  # (which outputs are returned without their one-entry axis)
        return {f"{job.model.name}.py": self.template("model.py.j2").render(ctx)}

    def main_file(self, name):
        return f"{name}.py"

    def runner(self, model, folder, manifest, opt):
        module = import_module(folder / f"{model.name}.py")
        return Runner(lambda role, *args: getattr(module, role)(*args))
