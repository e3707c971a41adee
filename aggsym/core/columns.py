"""One straight-line body applied to many columns: the solves of a routine's derivative columns written once.

The derivatives of the constrained dynamics (:mod:`aggsym.mechanics.constraint_derivatives`) solve one system, on
one set of factors, for 2n or 3n right-hand sides; those of the forward dynamics (:mod:`aggsym.mechanics.derivatives`)
apply A^-1 to 2n columns.  Unrolled, every solve is its own copy of the same arithmetic: Talos on its two soles has
114 of them, about 230,000 operations of C whose machine code no longer fits the processor's caches, so that it
runs at a seventh of the speed per operation of the smaller routines.  A
:class:`ColumnMap` records that the routine's outputs are, column by column, one generic body (the solve on
fresh inputs) applied to each column's values, so that a target can print the body once and call it in a loop;
the routine's own outputs stay what they are (the unrolled solves, on which every other target and every
program transform keeps working).

The body is the same arithmetic on the same operands: each output of a column is the body's output at that
column's values.  It differs from the unrolled copy only where the program folded the copy on its known zeros
and ones (``0*x`` not computed, ``x + 0`` kept as ``x``; exact, the same value for finite operands) or reused a
product of the same factors in another order (a rounding of the same product).

:func:`body_program` separates the body from the program it was built in: its nodes are those that depend on the
fresh inputs; the other nodes it reads (the factors, computed once per call by the routine) become its
*captures*, inputs of a program of its own, in which the column's values are inputs too.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial

from .program import INPUT, Node, Program, arithmetic

CAPTURES, VALUES = "c", "v"  # the input kinds of a body program: the captured values, the column's values
# the input kinds of the fresh inputs a routine builds its body on, in its own program (a column's f, h and a term
# added to the result); never inputs of a routine
COLUMN_F, COLUMN_H, COLUMN_T = "column_f", "column_h", "column_t"


@dataclass
class Run:
    """Consecutive columns of one block: ``values[k]``: column k's values, one list per input group of the map
    (nodes or constants of the routine's program); ``targets[g]``: where output group g of column k goes, as
    (output index, first flat index, step per column, stride per entry): entry i of the group at flat index
    ``first + k * step + i * stride`` of that output."""

    values: list
    targets: list


@dataclass
class ColumnMap:
    """A routine's outputs as one body applied to columns.

    ``inputs``: groups of the body's fresh input nodes (for instance f, h and a term added to the result);
    ``outputs``: groups of the body's outputs (nodes or constants) in terms of them and of the factors;
    ``runs``: the columns; ``offsets``: (output index, flat index, constant) added after the body was applied
    (the identity in d qd+ / d qd-)."""

    inputs: list
    outputs: list
    runs: list = field(default_factory=list)
    offsets: list = field(default_factory=list)

    @property
    def width(self) -> int:
        """The values of one column (all its input groups)."""
        return sum(len(g) for g in self.inputs)

    @property
    def columns(self) -> int:
        return sum(len(r.values) for r in self.runs)

    def placements(self):
        """(output index, flat index, column number, body output number) of every entry the body writes."""
        col = 0
        for run in self.runs:
            for k in range(len(run.values)):
                j = 0
                for g, group in enumerate(self.outputs):
                    o, first, step, stride = run.targets[g]
                    for i in range(len(group)):
                        yield o, first + k * step + i * stride, col, j + i
                    j += len(group)
                col += 1


@dataclass
class Body:
    """The body as a program of its own: ``program``, its ``outputs`` (flat, the map's groups in order), the
    routine's nodes it captures (``captures[k]`` is its input ``c[k]``); input ``v[i]`` is entry i of a column's
    values (the map's input groups in order)."""

    program: Program
    outputs: list
    captures: list


def body_program(program: Program, cmap: ColumnMap) -> Body:
    """The map's body moved into a program of its own (see the module's docstring): the routine's program
    interpreted (:meth:`~.program.Program.interpret`) into a new one from the fresh inputs and the captures, the
    nodes outside the body that it reads, in the order of their first use."""
    fresh = [x for g in cmap.inputs for x in g]
    flat = [x for g in cmap.outputs for x in g]
    depends, captures, seen = {x.id for x in fresh}, [], set()

    def captured(x):
        if x.__class__ is Node and x.id not in depends and x.id not in seen:
            seen.add(x.id)
            captures.append(x)
    for i in program.reachable(flat):
        entry = program.ops[i]
        if entry[0] != INPUT and any(a.__class__ is Node and a.id in depends for a in entry[1:]):
            depends.add(i)
            for a in entry[1:]:
                captured(a)
    for x in flat:
        captured(x)
    new = Program()
    given = {x.id: new.input(VALUES, k) for k, x in enumerate(fresh)}
    given.update({x.id: new.input(CAPTURES, k) for k, x in enumerate(captures)})
    outputs = program.interpret(flat, None, lambda code, *x: arithmetic(code, x, lambda name: partial(new.call, name)),
                                given=given)
    return Body(new, outputs, captures)


__all__ = ["ColumnMap", "Run", "Body", "body_program", "CAPTURES", "VALUES", "COLUMN_F", "COLUMN_H",
           "COLUMN_T"]
