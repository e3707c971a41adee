"""The C of a routine whose outputs are one body applied to columns (:mod:`aggsym.core.columns`).

A routine with a :class:`~aggsym.core.columns.ColumnMap` (the derivatives of the constrained dynamics, of an impact
and of the forward dynamics: one solve per column) is printed, when its unrolled C is large, as

* its straight line without the entries the body writes: what the columns need (the factors the body reads,
  ``aggsym_c``, and every column's values, ``aggsym_v``: two local arrays of the public function, written like
  outputs) and the other outputs (the status);
* ``static void SYMBOL_column(c, v, o)``: the body, once, its values read from ``v`` and the factors from ``c``,
  its outputs written to ``o``;
* ``static void SYMBOL_lanes(c, v, o)``: the same body on :data:`LANES` columns at once, a loop over lanes around
  it, which the compiler runs in vector registers;
* ``static void SYMBOL_columns(...)``: a loop per block of columns calling the lanes (then the body for the
  columns left over) and storing each column's outputs in place, called last (before the status is returned);
  then the constants added to some entries (the identity of d qd+ / d qd-).

Talos on its two soles: 114 solves of about 2,400 operations each run from a few kilobytes of code instead of
about 230,000 operations unrolled, whose machine code does not fit the caches.  The operation counts (the
manifest's ``ops``) are those executed: the straight line's, and the body's times the columns.
"""
from __future__ import annotations

from dataclasses import dataclass

from ...core.columns import CAPTURES, VALUES, ColumnMap, body_program
from ...core.program import straight_line
from ..printing import Infix, Spelling

CAPTURED, COLUMN_VALUES = "aggsym_c", "aggsym_v"  # the public function's local arrays

# A routine with a column map is looped when its unrolled C has more operations (mul + add + div) than this, and
# stays unrolled below: the unrolled code does fewer operations (each solve folded on its own zeros) and runs
# faster while it fits the caches.  Measured (GCC 12 -O2, benchmarks/runtime/constrained_derivatives.py, the ratio to
# Pinocchio's value + derivatives, unrolled -> looped).  On a Xeon (2 MB of L2 per core), one column at a time,
# one session: Talos's constrained forward dynamics derivatives, 286,272 operations unrolled, 1.93 -> 0.81; Talos's
# impulse derivatives (121,397) 0.59 -> 0.66; solo12's constrained derivatives (88,364) 0.70 -> 0.64 and impulse
# derivatives (46,695) 0.59 -> 0.63; Panda's (26,256 and 11,977) 0.51 -> 0.57 and 0.52 -> 0.50 (runs repeat within
# about 0.05); the threshold was 150,000.  On an AMD EPYC (512 KB of L2), with the lanes below, three runs looped
# and four unrolled, alternating: solo12's constrained 0.72-1.37 -> 0.61-0.83, its impulse 0.57-0.97 -> 0.60-0.62;
# Talos's impulse 0.58-1.23 -> 0.70-0.85 (Talos's constrained, looped in both, 0.87-1.21: the host's spread); and
# the lanes take a seventh to a fifth off a looped routine (below), which on the Xeon's figures puts solo12's and
# Talos's looped routines level with or ahead of their unrolled ones.  The threshold is 50,000: solo12's constrained
# derivatives and Talos's two are looped; solo12's impulse derivatives (46,695), Panda's, and Talos's forward
# dynamics derivatives (49,121: 0.36 of Pinocchio's unrolled, not measured looped) stay unrolled.  By hand, the
# forward dynamics derivatives: a 32-link chain (331,035 operations) 230-407 us -> 125-247 us; the 48-coordinate
# test_bench (126,780) 32.4 -> 38-41 us (one column at a time, the Xeon).
LOOPED_ABOVE = 50_000
# Columns applied LANES at a time by the body written once more as a loop over lanes (SYMBOL_lanes), the columns'
# values interleaved, so that GCC -O2 runs the lanes in vector registers (SSE2's two doubles without -march: the
# loop over lanes vectorized, checked with -fopt-info-vec); the columns left over, one by one.  The same operations
# on the same operands in each lane: the same bits.  Measured by hand (one AMD EPYC host, GCC 12 -O2, the routines
# interleaved in one process, 1,500 rounds of 16 states, minimum [median], µs per call): Talos's constrained forward
# dynamics derivatives 106 [116] looped one column at a time, 92 [104] four lanes at a time (two: 93 [103]); solo12's
# 26.4 [29.8] -> 21.1 [24.7] (25.5 [36.2] unrolled), its impulse derivatives 15.5 -> 12.4 (12.2 unrolled).
LANES = 4


@dataclass
class ColumnsC:
    """What the C of a mapped routine adds to its straight line: the entries it does not write (``skip``: (output
    index, flat index)), the local arrays (name, length) and the lists of their entries (``locals``, written by
    the straight line like outputs), the statements of the public function's head and tail, the two static
    functions (``functions``: C lines) and the operations beyond the straight line's (``ops``: the body's times the
    columns, and the tail's additions of constants)."""

    skip: set
    locals: list
    head: list
    tail: list
    functions: list
    ops: dict


def columns_c(symbol: str, prog, cmap: ColumnMap, output_names: list, spelling: Spelling, scalar: str) -> ColumnsC:
    """The C of ``cmap`` for the routine ``symbol`` with the outputs ``output_names`` (its C arrays)."""
    body = body_program(prog, cmap)
    sl = straight_line(body.program, [body.outputs])
    kinds = {kind for kind, _ in sl.inputs}
    unused = [f"(void){name};" for name, kind in (("c", CAPTURES), ("v", VALUES)) if kind not in kinds]

    def printed(value, output):
        """The body's statements, a column's value i read as ``value(i)``, its output j written as ``output(j)``;
        and the operations counted."""
        names = {body.program.inputs[(kind, i)].id: f"c[{i}]" if kind == CAPTURES else value(i)
                 for kind, i in sl.inputs}
        names.update({i: f"x{k}" for k, i in enumerate(sl.temps)})
        text = Infix(body.program, names, spelling)
        lines = []
        for step in sl.steps:
            if step[0] == "temp":
                lines.append(f"const {scalar} {names[step[1]]} = {text(body.program.nodes[step[1]])};")
            else:
                x = body.outputs[step[2]]
                lines.append(f"{output(step[2])} = {text(x, getattr(x, 'id', None) not in names)};")
        return lines, dict(text.counts)
    lines, body_ops = printed(lambda i: f"v[{i}]", lambda j: f"o[{j}]")
    lanes, _ = printed(lambda i: f"v[{LANES} * {i} + l]", lambda j: f"o[{LANES} * {j} + l]")
    width, count = cmap.width, cmap.columns
    size = sum(len(g) for g in cmap.outputs)
    used = sorted({o for run in cmap.runs for o, *_ in run.targets})
    params = ", ".join([f"const {scalar} *restrict c", f"const {scalar} *restrict v"]
                       + [f"{scalar} *restrict {output_names[o]}" for o in used])
    loops, start = [], 0
    for run in cmap.runs:
        n = len(run.values)
        stores = [[], []]  # (a column's outputs from o; column k + l's from the lanes' ol)
        j = 0
        for g, group in enumerate(cmap.outputs):
            o, first, step, stride = run.targets[g]
            stores[0].append(f"    for (i = 0; i < {len(group)}; ++i) "
                             f"{output_names[o]}[{first} + {step} * k + {stride} * i] = o[{j} + i];")
            stores[1].append(f"    for (l = 0; l < {LANES}; ++l) for (i = 0; i < {len(group)}; ++i) "
                             f"{output_names[o]}[{first} + {step} * (k + l) + {stride} * i] "
                             f"= ol[{LANES} * ({j} + i) + l];")
            j += len(group)
        loops += ([f"for (k = 0; k + {LANES} <= {n}; k += {LANES}) {{",
                   f"    for (l = 0; l < {LANES}; ++l) for (i = 0; i < {width}; ++i) "
                   f"vl[{LANES} * i + l] = v[{width} * ({start} + k + l) + i];",
                   f"    {symbol}_lanes(c, vl, ol);"] + stores[1] + ["}"]
                  + [f"for (; k < {n}; ++k) {{", f"    {symbol}_column(c, v + {width} * ({start} + k), o);"]
                  + stores[0] + ["}"])
        start += n
    functions = ([f"/* {symbol}: the body applied to each of its {count} columns (aggsym.core.columns): "
                  f"{sum(body_ops.values())} operations each */",
                  f"static void {symbol}_column(const {scalar} *restrict c, const {scalar} *restrict v, "
                  f"{scalar} *restrict o)", "{"]
                 + [f"    {line}" for line in unused + lines] + ["}", "",
                 f"/* {symbol}: the body on {LANES} columns at once, each in a lane of the loop (v and o "
                 f"interleaved: entry i of lane l at {LANES} * i + l), so that the compiler can run the lanes in "
                 f"vector registers */",
                 f"static void {symbol}_lanes(const {scalar} *restrict c, const {scalar} *restrict v, "
                 f"{scalar} *restrict o)", "{", "    int l;"] + [f"    {line}" for line in unused]
                 + [f"    for (l = 0; l < {LANES}; ++l) {{"] + [f"        {line}" for line in lanes]
                 + ["    }", "}", "",
                 f"static void {symbol}_columns({params})", "{",
                 f"    {scalar} o[{size}], ol[{LANES * size}], vl[{LANES * width}];", "    int k, i, l;"]
                 + [f"    {line}" for line in loops] + ["}"])
    captures = body.captures
    values = [x for run in cmap.runs for column in run.values for g in column for x in g]
    head = [f"{scalar} {CAPTURED}[{max(len(captures), 1)}];", f"{scalar} {COLUMN_VALUES}[{max(len(values), 1)}];"]
    call = f"{symbol}_columns({CAPTURED}, {COLUMN_VALUES}, {', '.join(output_names[o] for o in used)});"
    tail = [call] + [f"{output_names[o]}[{k}] = {output_names[o]}[{k}] + {spelling.number(float(constant))};"
                     for o, k, constant in cmap.offsets]
    skip = {(o, k) for o, k, *_ in cmap.placements()}
    ops = {key: body_ops[key] * count for key in body_ops}
    ops["add"] += len(cmap.offsets)
    return ColumnsC(skip, [(CAPTURED, list(captures)), (COLUMN_VALUES, values)], head, tail, functions, ops)


__all__ = ["ColumnsC", "columns_c", "CAPTURED", "COLUMN_VALUES", "LOOPED_ABOVE"]
