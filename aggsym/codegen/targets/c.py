"""The C target: NAME.h and NAME.c (``--split``: NAME_ROUTINE.c per routine, NAME_helpers.h, a Makefile).

How a routine's straight-line program is printed as C (:func:`print_c`): inputs read first, each named
temporary a ``const`` assignment, sin and cos of one angle in one ``aggsym_sincos`` call (two angles in one
``aggsym_sincos2``), runs of zero entries by ``AGGSYM_ZEROS``, a large routine as slices (:mod:`..slicing`).
The emission (:mod:`aggsym.codegen.emit`) prints the C of every routine whatever the targets: this printer counts
the operations as it prints them (the manifest's ``ops``, ``aggsym ops``) and gives the texts that the other infix
targets print alike (:attr:`~.base.RoutineLines.shared`).  Checked by compiling it and calling it against the
numeric twin.
"""
from __future__ import annotations

import os
import re
import shlex
from collections import deque
from dataclasses import dataclass, field
from itertools import islice

from ...contract import Routine, signature
from ...core.functions import FUNCTIONS
from ...core.program import COS, SIN, Node, straight_line
from ...errors import AggsymError
from .. import compile as build
from ..names import c_symbol
from ..printing import Infix, Spelling, _number
from ..slicing import Sliced, Statement, slice_routine, work
from .base import RoutineLines, Runner, Target, file_pattern
from .c_columns import columns_c


# the C spelling of the functions: <math.h>'s names (fabs for abs), sign the emitted aggsym_sign: (x > 0) - (x < 0),
# and NaN for NaN as NumPy's sign (a returned status then stays nonzero when a solve meets a NaN)
C_FUNCTIONS = {name: name for name in FUNCTIONS} | {"abs": "fabs", "sign": "aggsym_sign"}


def c_spelling(scalar: str = "double") -> Spelling:
    """The C target's spelling table: round-trip literals of the C type ``scalar``; for ``float`` the suffix f on
    literals and <math.h>'s float functions (sinf, fabsf, ...), so that nothing is promoted to double."""
    functions = C_FUNCTIONS if scalar == "double" else \
        {name: c + ("f" if name != "sign" else "") for name, c in C_FUNCTIONS.items()}
    return Spelling(functions, lambda value: _number(value, scalar))


@dataclass
class CBody:
    """A routine's C (``EmittedRoutine.bodies["c"]``): its statements ``lines``, ``sliced`` the same as several
    functions (:mod:`..slicing`) for a routine above the threshold, ``functions`` the C lines of static functions
    before it (:mod:`.c_columns`)."""

    lines: list
    sliced: Sliced | None = None
    functions: list = field(default_factory=list)

    @property
    def zeros(self) -> bool:
        """Whether it writes a chunk of zero entries with AGGSYM_ZEROS (templates/c/attributes.c.j2)."""
        return any(line.startswith("AGGSYM_ZEROS(") for line in self.lines)


@dataclass
class PrintedC:
    """What :func:`print_c` gives: the ``body``, the operations it counted while printing (``ops``: mul, add, div,
    call), the number of named temporaries (``temps``), its size as :func:`..slicing.work` measures it (``work``)
    and the straight line as the other targets print it (``lines``)."""

    body: CBody
    ops: dict
    temps: int
    work: int
    lines: RoutineLines


def _input_symbols(sl):
    return {sl.program.inputs[(kind, index)].id: f"{kind}_{index}" for kind, index in sl.inputs}


def print_c(model, prog, routine: Routine, outputs, sl, scalar: str = "double", slicing=None, columns=None,
            looped_above: int = 0) -> PrintedC:
    """The C of one routine from its straight line ``sl`` (its arrays, temporaries and literals of the C type
    ``scalar``, double or float).  ``slicing``: (threshold, size), the C of a routine of more work than the
    threshold also as slices of about that size (:mod:`..slicing`); None: never.  ``columns``: the routine's
    :class:`~aggsym.core.columns.ColumnMap`, whose body the C prints once and applies in a loop (:mod:`.c_columns`)
    when the routine's unrolled C has more than ``looped_above`` operations; the other targets print the outputs
    as they are (``lines`` is always the unrolled straight line's)."""
    printed = _print_c(model, prog, routine, outputs, scalar, slicing, sl)
    if columns is not None and sum(printed.ops[k] for k in ("mul", "add", "div")) > looped_above:
        mapped = _print_mapped(model, prog, routine, outputs, scalar, slicing, columns)
        return PrintedC(mapped.body, mapped.ops, mapped.temps, mapped.work, printed.lines)
    return printed


def _print_mapped(model, prog, routine: Routine, outputs, scalar: str, slicing, cmap) -> PrintedC:
    """The C of a routine with a column map: its straight line less the entries the body writes, plus the arrays
    the body reads (:func:`.c_columns.columns_c`)."""
    symbol = c_symbol(model, routine)
    mapped = columns_c(symbol, prog, cmap, [o.name for o in routine.outputs], c_spelling(scalar), scalar)
    hole = float("nan")  # a written entry: neither computed nor counted as a zero (never printed)
    kept = [[hole if (o, k) in mapped.skip else x for k, x in enumerate(out)] for o, out in enumerate(outputs)]
    kept += [values for _, values in mapped.locals]
    printed = _print_c(model, prog, routine, kept, scalar, slicing, straight_line(prog, kept), mapped)
    for key, n in mapped.ops.items():
        printed.ops[key] += n
    printed.body.functions = mapped.functions
    return printed


def _print_c(model, prog, routine: Routine, outputs, scalar: str, slicing, sl, mapped=None) -> PrintedC:
    """:func:`print_c` without the column map.  ``mapped``: the :class:`~.c_columns.ColumnsC` of a routine with a
    column map (``outputs`` then also holds its local arrays' entries, after the routine's outputs)."""
    inputs = signature(routine, model)
    allowed = set(inputs)
    for kind, _ in sl.inputs:
        if kind not in allowed:
            raise RuntimeError(f"routine {routine.role} depends on input {kind!r} outside its signature")
    temp_names = {i: f"x{k}" for k, i in enumerate(sl.temps)}
    names = {**_input_symbols(sl), **temp_names}
    ctext = Infix(prog, names, c_spelling(scalar))  # the C text; the routine's operations counted as printed
    counts, refs = ctext.counts, ctext.refs  # (refs: the names a statement uses; emit clears it)
    shared = {}  # key -> the C text that an infix target prints alike (RoutineLines.shared)

    def c_text(x, key, top=True):
        """The C text of a right-hand side, kept in ``shared`` under ``key`` when it holds no function call and
        the C is double (the C and NumPy printers differ only in function names and in float literals)."""
        calls = ctext.calls
        c = ctext(x, top)
        if scalar == "double" and ctext.calls == calls:
            shared[key] = c
        return c
    stmts = []  # the C body as statements (slicing.Statement): what each defines, uses, reads or writes

    def emit(lines, defines=(), arrays=(), ops=0, entry=""):
        stmts.append(Statement(lines, tuple(defines), tuple(refs), tuple(arrays), ops, entry))
        refs.clear()

    def ops_so_far():
        return sum(counts.values())
    status = routine.status
    if status is not None:
        emit([f"{scalar} {status.name}[1];"], entry="head")
    out_names = [o.name for o in routine.outputs]
    if mapped is not None:
        emit(mapped.head, entry="head")
        out_names += [name for name, _ in mapped.locals]
    for kind in inputs:  # every input is read before any output is written: outputs may alias inputs
        used = [i for k, i in sl.inputs if k == kind]
        if not used:
            emit([f"(void){kind};"], entry="head")
        elif kind == "p":  # p == NULL means the defaults, as in the NumPy module
            defaults = ", ".join(_number(float(x.value), scalar) for x in model.parameters)
            emit([f"static const {scalar} p_defaults[{len(model.parameters)}] = {{{defaults}}};",
                  "if (!p) p = p_defaults;"], arrays=("p",))
        for i in used:
            emit([f"const {scalar} {kind}_{i} = {kind}[{i}];"], defines=(f"{kind}_{i}",), arrays=(kind,))
    for out, flat in zip(routine.outputs, outputs):
        if not flat:
            emit([f"(void){out.name};"], entry="head")
    refs.clear()
    trig = _trig_pairs(prog, sl.temps)
    done = set()
    defined = set(names) - set(temp_names)  # node ids with a C name already defined: the inputs, then temps
    pending = _pending_pairs(sl.steps, trig)
    hoisted = set()  # temps emitted early for a sincos pair
    zeros = _zero_chunks(sl.steps, outputs, ZERO_BYTES // SCALAR_BYTES[scalar])
    for s, step in enumerate(sl.steps):
        before = ops_so_far()
        if step[0] == "out":
            _, o, k = step
            if mapped is not None and (o, k) in mapped.skip:
                continue
            x = outputs[o][k]
            name = out_names[o]
            if s in zeros:  # one of a chunk of zero entries: the first writes them all (AGGSYM_ZEROS)
                if zeros[s]:
                    emit([f"AGGSYM_ZEROS({name} + {k});"], arrays=(name,))
                continue
            rhs_c = c_text(x, (o, k), top=not (isinstance(x, Node) and x.id in names))
            emit([f"{name}[{k}] = {rhs_c};"], arrays=(name,), ops=ops_so_far() - before)
            continue
        i = step[1]
        if i in hoisted:  # its C was emitted before a sincos pair that needed it
            continue
        if i not in trig:
            rhs_c = c_text(prog.nodes[i], i)
            emit([f"const {scalar} {names[i]} = {rhs_c};"], defines=(names[i],), ops=ops_so_far() - before)
            defined.add(i)
            continue
        pair = trig[i]
        if pair[:2] in done:
            continue
        # a second angle whose argument is already computable shares the call (aggsym_sincos2: two in one vector)
        partner, early = _ready_partner(prog, names, trig, pending, done, defined, pair)
        for h in early:  # a temp the partner's angle is made of (q + offset), emitted now; NumPy keeps its place
            rhs_c = c_text(prog.nodes[h], h)
            hoisted.add(h)
            emit([f"const {scalar} {names[h]} = {rhs_c};"], defines=(names[h],), ops=ops_so_far() - before)
            before = ops_so_far()
            defined.add(h)
        c_names, arguments = [], []
        for sin_id, cos_id, arg in (pair,) if partner is None else (pair, partner):
            done.add((sin_id, cos_id))
            defined.update(j for j in (sin_id, cos_id) if j is not None)
            c_names += [names[sin_id] if sin_id is not None else names[cos_id] + "_sin",
                        names[cos_id] if cos_id is not None else names[sin_id] + "_cos"]
            arguments.append(ctext(arg, top=False))
            counts["call"] += 1
        pointers = ", ".join(f"&{n}" for n in c_names)
        emit([f"{scalar} {', '.join(c_names)};",
              f"aggsym_sincos{'' if partner is None else '2'}({', '.join(arguments)}, {pointers});"],
             defines=c_names, ops=ops_so_far() - before)
    if mapped is not None:  # (its operations are mapped.ops, counted by the caller)
        emit(mapped.tail, arrays=out_names, entry="tail")
    if status is not None:
        emit([f"return {status.name}[0] != {_number(0.0, scalar)};"], entry="tail")
    # what count_ops reads from the C, counted while printing (the other statements hold none); the printer
    # prints only what is emitted, the sincos pair's discarded sin/cos were never printed
    ops = dict(counts)
    sliced, size = None, sum(work(st) for st in stmts)
    if slicing is not None and size > slicing[0]:
        arrays = {k: f"const {scalar} *{k}" for k in inputs}
        arrays.update({name: f"{scalar} *{name}" for name in out_names})
        pieces = min(slicing[1], routine.slice_size or slicing[1])
        sliced = slice_routine(c_symbol(model, routine), arrays, stmts, scalar, pieces)
    body = CBody([line for st in stmts for line in st.lines], sliced)
    return PrintedC(body, ops, len(sl.temps), size, RoutineLines(sl, names, outputs, zeros, trig, shared,
                                                                scalar == "double"))


# The bytes AGGSYM_ZEROS writes at once (templates/c/attributes.c.j2): 2 doubles, 4 floats
ZERO_BYTES = 16
SCALAR_BYTES = {"double": 8, "float": 4}


def _zero_chunks(steps, outputs, width: int) -> dict:
    """{index of a step: 1 or 0}: the steps storing a constant 0 that fall in chunks of ``width`` consecutive
    zero entries of one output (each run of zeros cut into chunks from its start; what is left over is stored
    entry by entry), 1 for a chunk's first step, 0 for the others.  (The constant outputs' steps come first, in
    the order of their entries: :func:`aggsym.core.program.straight_line`.)"""
    chunks, run = {}, []

    def close():
        for c in range(0, len(run) - width + 1, width):
            chunks.update((s, int(j == 0)) for j, s in enumerate(run[c:c + width]))
        run.clear()
    for s, step in enumerate(steps):
        x = outputs[step[1]][step[2]] if step[0] == "out" else None
        zero = step[0] == "out" and not isinstance(x, Node) and float(x) == 0.0
        if run and not (zero and steps[run[-1]][1] == step[1] and steps[run[-1]][2] + 1 == step[2]):
            close()
        if zero:
            run.append(s)
    close()
    return chunks


def _trig_pairs(prog, temps) -> dict:
    """For every sin or cos temp: (sin id or None, cos id or None, argument), so that C computes both at once."""
    by_arg = {}
    for i in temps:
        entry = prog.ops[i]
        if entry[0] in (SIN, COS):
            arg = entry[1]
            pair = by_arg.setdefault(("n", arg.id) if isinstance(arg, Node) else ("c", repr(arg)), [None, None, arg])
            pair[0 if entry[0] == SIN else 1] = i
    return {i: tuple(pair) for pair in by_arg.values() for i in pair[:2] if i is not None}


def _pending_pairs(steps, trig) -> deque:
    """The sin-and-cos pairs in the order of their first step (the order aggsym_sincos is called in)."""
    order = {}
    for step in steps:
        if step[0] != "out" and step[1] in trig:
            order.setdefault(trig[step[1]][:2], trig[step[1]])
    return deque(order.values())


PARTNER_LOOKAHEAD = 8  # the pairs not yet emitted that are tried as the partner of a sincos call


def _ready_partner(prog, names, trig, pending, done, defined, pair):
    """(partner, temps): the first pair other than ``pair`` among the next :data:`PARTNER_LOOKAHEAD` not yet emitted
    whose argument is computable now, and the named temps to emit first for it (:func:`_computable`); (None, ())
    if there is none.  ``pending`` (in order) loses its emitted pairs from the front, so that a call costs O(1)."""
    while pending and pending[0][:2] in done:
        pending.popleft()
    for candidate in islice(pending, PARTNER_LOOKAHEAD):
        if candidate[:2] != pair[:2] and candidate[:2] not in done:
            early = _computable(prog, names, trig, candidate[2], defined)
            if early is not None:
                return candidate, early
    return None, ()


def _computable(prog, names, trig, arg, defined):
    """The named temps (in order) to emit before an expression can be, or None if it cannot be yet: it may need
    constants, the ``defined`` nodes (inputs and temps already emitted), the unnamed nodes that the printer
    inlines, and named temps (not sin or cos) whose own operands are all of those (one level: the angle
    ``q + offset`` of a joint whose zero the internal frames moved)."""
    early = []
    stack = [(arg, True)]
    while stack:
        x, may_hoist = stack.pop()
        if not isinstance(x, Node) or x.id in defined or x.id in early:
            continue
        if x.id in names:  # a named node not emitted yet
            if not may_hoist or x.id in trig or not prog.operands(x.id):
                return None
            early.append(x.id)
            stack.extend((a, False) for a in prog.operands(x.id))
            continue
        stack.extend((a, may_hoist) for a in prog.operands(x.id))
    return early[::-1]



HELPERS = ("aggsym_sincos(", "aggsym_sincos2(", "aggsym_sign(")  # the calls of the helpers that helpers.c.j2 defines


def _helpers_used(r) -> bool:
    return any(h in line for line in r.bodies["c"].lines for h in HELPERS)


def split_names(name: str, emitted) -> dict:
    """The files of ``--split``: {"sources": {role: NAME_role.c}, "helpers": NAME_helpers.h or None (no routine
    calls a helper), "makefile", "library"}."""
    return {"sources": {r.routine.role: f"{name}_{r.routine.role}.c" for r in emitted},
            "helpers": f"{name}_helpers.h" if any(_helpers_used(r) for r in emitted) else None,
            "makefile": "Makefile",
            "library": f"lib{name}.a"}


def split_layout(name: str, emitted, files) -> dict:
    """The manifest's ``split`` entry: every file written (``files``), and which holds what."""
    names = split_names(name, emitted)
    return {"files": list(files), "header": f"{name}.h", **names}


def split_files(target, ctx, emitted) -> dict:
    """``--split``: NAME_ROLE.c per routine (including NAME_helpers.h only if it calls a helper), NAME_helpers.h
    with aggsym_sincos and aggsym_sign as static inline (each routine's object inlines them: a separate
    NAME_common.c would make every sin/cos a call across objects), and a Makefile building libNAME.a with
    $(CC) $(CFLAGS) (default -O2 -std=c99), one object per routine, so that make -j builds in parallel and a
    controller links only the routines it calls."""
    name = ctx["name"]
    names = split_names(name, emitted)
    files = {}
    helpers = names["helpers"]
    if helpers:
        files[helpers] = target.template("helpers.h.j2").render(
            {**ctx, "guard": name.upper() + "_HELPERS_H", "sign_storage": "static inline"})
    rules = []
    for r in emitted:
        source = names["sources"][r.routine.role]
        uses = helpers if _helpers_used(r) else None
        files[source] = target.template("routine.c.j2").render({**ctx, "r": r, "helpers": uses})
        rules.append((source, source[:-2] + ".o", [f"{name}.h"] + ([uses] if uses else [])))
    files[names["makefile"]] = target.template("Makefile.j2").render(
        {**ctx, "objects": [o for _, o, _ in rules], "rules": rules})
    return files


class CTarget(Target):
    """NAME.h and NAME.c, or with ``--split`` NAME.h, NAME_helpers.h (when a routine calls a helper),
    NAME_ROUTINE.c per routine and a Makefile; checked by compiling (a split layout by its Makefile) and calling
    the functions through ctypes."""

    name = "c"
    default = True
    column = "C"
    folder = "c"
    templates = ("model.h.j2", "model.c.j2", "function.c.j2", "attributes.c.j2", "helpers.c.j2", "helpers.h.j2",
                 "routine.c.j2", "Makefile.j2")

    def file_names(self, job):
        name = job.model.name
        if not job.split:
            return [f"{name}.h", f"{name}.c"]
        names = split_names(name, job.emitted)
        return ([f"{name}.h"] + ([names["helpers"]] if names["helpers"] else []) + list(names["sources"].values())
                + [names["makefile"]])

    def owns(self, name, file):
        return bool(file_pattern(name, ("h", "c")).fullmatch(file) or file == "Makefile"
                    or re.fullmatch(rf"{re.escape(name)}_[A-Za-z0-9_]+\.[ch]", file))

    def render(self, job):
        files = {f"{job.model.name}.h": self.template("model.h.j2").render(job.ctx)}
        if job.split:
            files.update(split_files(self, job.ctx, job.emitted))
        else:
            files[f"{job.model.name}.c"] = self.template("model.c.j2").render(job.ctx)
        return files

    def main_file(self, name):
        return f"{name}.h"

    def unavailable(self):
        try:
            build.compiler()
        except AggsymError as exc:
            return str(exc)
        return None

    def runner(self, model, folder, manifest, opt):
        scalar = manifest.get("scalar", "double")
        shared = folder / f"lib{model.name}.so"
        if "split" in manifest:  # --split: the Makefile's build of libNAME.a is what runs
            flags = [f for f in build.CFLAGS if f != "-shared"] + (build.FLOAT_CFLAGS if scalar == "float" else [])
            flags += [opt] + shlex.split(os.environ.get("CFLAGS", ""))
            shared = build.shared_from_archive(build.build_split(folder, cflags=shlex.join(flags)), shared)
        else:
            shared = build.compile_shared(folder / f"{model.name}.c", shared, extra=(opt,), scalar=scalar)
        lib = build.CLibrary(shared, manifest)
        return Runner(lib.call, manifest.get("float_tolerance", {}),
                      tuple(manifest.get("float_tolerance_per_condition", ())))
