"""A large routine as several C functions: contiguous slices of its straight-line statements (issue 18, item 3).

GCC's register allocation (LRA's hard register assignment) grows much faster than linearly with the size of one
straight-line function: Talos' C(q, qd), 17,650 operations in one function, takes 25 s at -O2, four fifths of it
there, while Talos' A(q) with 2,400 operations takes 0.6 s.  A routine whose operations exceed a threshold is
therefore emitted as ``static`` functions that each hold a contiguous slice of its statements, in the order
:func:`aggsym.core.program.straight_line` gives them, and are called one after the other by the public function,
whose name, signature and behaviour stay the contract's.  Nothing is recomputed and nothing is reordered: the
statements are the unsliced ones, so the operations (the manifest's ``ops``) and the rounding are the same.

A value defined in one slice and used in a later one crosses through a workspace, ``double w[K]``, a local array
of the public function passed to the slices as ``double *restrict w`` (it aliases nothing): stored right after
the statement that defines it, loaded into a local of the same name right before the first statement of a later
slice that uses it.  Workspace entries are reused: a value holds its entry from its slice to the last slice that
reads it (intervals of slices, coloured greedily in order of definition), so K is the most values that live
across one boundary, not all of them.  The inputs are read in the first slice, before any output is written (an
output may alias an input); a slice takes only the arrays it reads or writes, so no parameter goes unused.  The
slices are ``noinline`` (GCC and Clang otherwise inline a static function called once back into its caller, which
would undo the slicing; other compilers get plain ``static`` functions).
"""
from __future__ import annotations

from dataclasses import dataclass, field

# A routine is sliced when its work (:func:`work`: operations plus statements) exceeds SLICE_THRESHOLD, into slices
# of about SLICE_SIZE work each.  Chosen by measurement with GCC 12 at -O2 (benchmarks/generation/compile_split.py, docs/generated-code.md):
# slices of 300..1000 compile alike (Talos' C: 2.3..2.8 s against 25 s), and slices of 300..600 run fastest (the
# small functions keep their values in registers: Talos' C, forward dynamics and A^-1 9..18 % faster than one
# function, chain24's and chain48's A, inverse and forward dynamics, A^-1 5..22 %); but a routine of about 4,500
# work (Talos' A, b + g, inverse dynamics) runs 5..10 % slower sliced, so smaller routines stay one function.
# Slices of 200 against 400 (Talos, median of 5 rounds, the same host): derivatives of inverse dynamics 7 %, of
# forward dynamics 4 %, forward dynamics 6 %, C 4 % faster, A^-1 alike; slices of 120 much the same; --split
# make -j2 of Talos' default routines 6.7..6.8 s with either.
# A routine may ask for smaller slices (contract.Routine.slice_size): the derivative routines (one dual sweep per
# direction, aggsym/mechanics/derivatives.py) run fastest in slices of 50..80 (Talos, median of 7 rounds: dtau 6680
# ns with slices of 200, 6291 with 80, 6277 with 50; dqdd 10492 and 9848 with 200 and 80), the other large routines
# not (Talos' A^-1 and forward dynamics are slower with 120).
SLICE_THRESHOLD = 6000
SLICE_SIZE = 200


@dataclass
class Statement:
    """One C statement of a routine's body (or the lines of one sincos pair): the local names it defines and
    uses, the parameter arrays (inputs and outputs) it reads or writes, its operations (mul + add + div + call).
    ``entry``: "head" or "tail" for a statement that stays at the start or the end of the public function when
    the routine is sliced (the declaration of a returned status and the casts that mark unused arguments; the
    return of the status)."""

    lines: list
    defines: tuple = ()
    uses: tuple = ()
    arrays: tuple = ()
    ops: int = 0
    entry: str = ""


@dataclass
class Slice:
    """One static function of a sliced routine: its name, its parameter list (C text), its body lines."""

    name: str
    parameters: str
    body: list = field(default_factory=list)


@dataclass
class Sliced:
    """A routine as slices: the public function's body (``entry``), the slices, the workspace's length."""

    entry: list
    slices: list
    workspace: int


def work(statement: Statement) -> int:
    """What a statement costs the compiler, roughly: its operations plus one for the assignment (a store of a zero
    into an output costs no operation, but thousands of them take GCC's dead-store elimination a second)."""
    return statement.ops + 1


def slice_bounds(statements, size: int) -> list:
    """[(start, stop)] of contiguous runs of the statements, each closed once its :func:`work` reaches ``size``
    (the last may hold less)."""
    bounds, start, ops = [], 0, 0
    for k, s in enumerate(statements):
        ops += work(s)
        if ops >= size:
            bounds.append((start, k + 1))
            start, ops = k + 1, 0
    if start < len(statements):
        bounds.append((start, len(statements)))
    return bounds


def slice_routine(symbol: str, arrays: dict, statements: list, scalar: str = "double",
                  size: int = SLICE_SIZE) -> Sliced:
    """``statements`` as static functions ``SYMBOL_sliceK`` of about ``size`` :func:`work` each.

    ``arrays``: the routine's parameter arrays in argument order, name -> C parameter declaration (``const double
    *q``; a returned status is a local array of the public function, passed like an output).  Returns the
    public function's body (``entry``: the entry statements, the workspace, the calls, and the return last) and
    the slices."""
    body = [s for s in statements if not s.entry]
    bounds = slice_bounds(body, size)
    where = {}  # local name -> the slice that defines it
    last = {}  # local name defined in an earlier slice -> the last slice that uses it
    for k, (a, b) in enumerate(bounds):
        for s in body[a:b]:
            for name in s.uses:
                if where[name] != k:
                    last[name] = k
            for name in s.defines:
                where[name] = k
    slot = {}  # crossing name -> workspace entry
    free, size_w, releases = [], 0, {}
    for k, (a, b) in enumerate(bounds):
        for name in releases.pop(k - 1, ()):  # entries read for the last time in slice k - 1 are free again
            free.append(slot[name])
        free.sort(reverse=True)
        for s in body[a:b]:
            for name in s.defines:
                if name in last:
                    if free:
                        slot[name] = free.pop()
                    else:
                        slot[name], size_w = size_w, size_w + 1
                    releases.setdefault(last[name], []).append(name)
    slices, calls = [], []
    for k, (a, b) in enumerate(bounds):
        lines, loaded, touched, uses_w = [], set(), set(), False
        for s in body[a:b]:
            for name in s.uses:
                if where[name] != k and name not in loaded:
                    lines.append(f"const {scalar} {name} = w[{slot[name]}];")
                    loaded.add(name)
                    uses_w = True
            lines.extend(s.lines)
            touched.update(s.arrays)
            for name in s.defines:
                if name in slot:
                    lines.append(f"w[{slot[name]}] = {name};")
                    uses_w = True
        names = [n for n in arrays if n in touched]
        params = [arrays[n] for n in names] + ([f"{scalar} *restrict w"] if uses_w else [])
        slices.append(Slice(f"{symbol}_slice{k}", ", ".join(params) or "void", lines))
        calls.append(f"{symbol}_slice{k}({', '.join(names + (['w'] if uses_w else []))});")
    head = [line for s in statements if s.entry == "head" for line in s.lines]
    tail = [line for s in statements if s.entry == "tail" for line in s.lines]
    workspace = [f"{scalar} w[{size_w}];"] if size_w else []
    return Sliced(head + workspace + calls + tail, slices, size_w)
