"""``aggsym generate``: every routine of the contract as C, NumPy and LaTeX, plus the JSON manifest.

The recursions run once on the symbolic backend into one shared straight-line program (kinematics shared by
all routines); each routine's outputs are then cut out of it (:func:`aggsym.core.program.straight_line`),
printed through the SymPy printer subclasses of :mod:`.printing`, and laid out by the Jinja templates (layout
only; the package data ``aggsym.templates``, the project's top-level ``templates/``).  What a routine is called,
takes and returns comes from :mod:`aggsym.contract`.  Files are written only after everything has been
generated, through a temporary folder, so a failure leaves the output folder as it was.
"""
from __future__ import annotations

import errno
import json
import os
import re
import shutil
import tempfile
import time
import warnings
from collections import deque
from dataclasses import dataclass, field
from itertools import islice
from importlib.resources import files
from types import SimpleNamespace
from pathlib import Path

import jinja2

from .. import __version__
from ..contract import (
    INPUT_KINDS, ROUTINES, Routine, c_prototype, c_symbol, header_macros, input_length, manifest, omitted_routines,
    redundant_constraints,
    python_parameters, routines_for,
    run, signature,
)
from ..core.backend import Symbolic
from ..core.program import COS, SIN, Node, straight_line
from ..mechanics.bound import bind, program_operations
from ..mechanics.kinematics import TreeKinematics
from ..model.reframe import reframe
from ..model.tree import Tree
from ..collector import collector_paused
from ..errors import AggsymError, ModelError, ModelWarning
from .escape import FILTERS, check_c_identifier, check_module_name
from .printing import SCALARS, CPrinter, Converter, CText, LiteralError, NumPyPrinter, _number
from .slicing import SLICE_SIZE, SLICE_THRESHOLD, Sliced, Statement, slice_routine, work


@dataclass
class EmittedRoutine:
    routine: Routine
    inputs: tuple  # the input names in argument order for this model (contract.signature)
    symbol: str  # C function name
    prototype: str  # C prototype, without the semicolon
    py_parameters: str  # the NumPy function's parameter list
    c_body: list  # C statements
    py_body: list  # Python statements
    ops: dict
    temps: int
    work: int = 0  # the C's size as slicing.work measures it (operations + statements)
    sliced: Sliced | None = None  # the C as several functions (slicing.py), for a routine above the threshold

    @property
    def zeros(self) -> bool:
        """Whether its C writes a chunk of zero entries with AGGSYM_ZEROS (templates/attributes.c.j2)."""
        return any(line.startswith("AGGSYM_ZEROS(") for line in self.c_body)


@dataclass
class Generated:
    model: object
    routines: list
    files: dict = field(default_factory=dict)  # file name -> text
    timings: list = field(default_factory=list)  # (stage, seconds)


def templates() -> jinja2.Environment:
    """The Jinja environment over the package data ``aggsym.templates`` (``templates/`` of the project, mapped
    into the package by pyproject.toml, in editable and in wheel installs alike)."""
    root = files("aggsym.templates")
    env = jinja2.Environment(
        loader=jinja2.FunctionLoader(lambda name: (root / name).read_text(encoding="utf-8")),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
        autoescape=False,
    )
    env.filters.update(FILTERS)  # user text reaches a template only through these (aggsym.codegen.escape)
    return env


class _Stages:
    def __init__(self, progress):
        self.progress = progress
        self.timings = []
        self._t = time.perf_counter()

    def done(self, stage):
        now = time.perf_counter()
        self.timings.append((stage, now - self._t))
        if self.progress:
            self.progress(f"{stage}: {now - self._t:.2f} s")
        self._t = now


def _dynamics_operations(model, budget: int | None = None) -> int:
    """The arithmetic operations (negations and inputs free) of the model's inverse and forward dynamics on a fresh
    straight-line program (sharing its kinematics, as the emitted routines do), counted by
    :func:`~aggsym.mechanics.bound.program_operations`: stopping once the count reaches ``budget``, the program
    released after."""
    backend = Symbolic()
    program = backend.program

    def rows():
        bound = bind(model, backend)
        kin = TreeKinematics(bound, program.vector("q", model.nq))
        for role in ("inverse_dynamics", "forward_dynamics"):
            routine = ROUTINES[role]
            x = {k: program.vector(k, input_length(model, k)) for k in signature(routine, model)
                 if k not in ("p", "t")}
            x["q"] = kin.q
            try:
                outputs = [v for o in run(routine, bound, x, kin) for v in o]
            except ZeroDivisionError:  # A(q) singular: the forward dynamics is omitted (contract.omitted_routines)
                continue
            yield outputs

    return program_operations(program, rows, budget)


COUNTED_UP_TO = 64  # coordinates: above, the first internal model is taken without counting


def internal_model(model):
    """The model the routines of the coordinates alone (``Routine.frame_free``) are built from: the model as read
    when it is not :func:`~aggsym.model.reframe.eligible`, else of its two internal models (origins at the feet of
    the common normals, or chosen for the fewest translation components) the one whose inverse plus forward
    dynamics take the fewest operations (the first of equals; x axes along the common normals: on the arms of
    the benchmark the URDF's own x axes were never better).  Counting both costs two scratch programs of the
    dynamics: above :data:`COUNTED_UP_TO` coordinates the first is taken (the smaller or equal one on UR5, Panda,
    so100, Talos, Solo12, HyQ, Kinova and a 200-link planar chain; xarm7's second is 5 % smaller), so that a
    1000-link chain does not spend 20 s choosing its frames."""
    first = reframe(model, fewest=False)
    if first is model or model.nv > COUNTED_UP_TO:
        return first
    best, cost = first, _dynamics_operations(first)
    other = reframe(model, fewest=True)
    count = _dynamics_operations(other, budget=cost)
    return other if count < cost else best


def symbolic_routines(model, tree=None, roles=None, omitted=()):
    """Run the model's routines (all, or those named, less the omitted) on the symbolic backend: (program,
    {role: list of flat output lists})."""
    backend = Symbolic()
    prog = backend.program
    tree = tree or Tree(model)
    bound = bind(model, backend, tree=tree)
    vectors = {k: prog.vector(k, input_length(model, k)) for k in INPUT_KINDS}
    kin = None if model.couplings else TreeKinematics(bound, vectors["q"])  # coupled: run() expands q first
    routines = routines_for(model, roles, omitted)
    # the routines of the coordinates alone run in internal frames (chosen only when one of them is emitted)
    internal = internal_model(model) if any(r.frame_free for r in routines) else model
    inner = inner_kin = None
    outputs = {}
    for routine in routines:
        x = {k: vectors[k] for k in signature(routine, model) if k not in ("p", "t")}
        if routine.frame_free and internal is not model:
            if inner is None:
                inner = bind(internal, backend, tree=Tree(internal))
                inner_kin = TreeKinematics(inner, vectors["q"])
            outputs[routine.role] = [list(o) for o in run(routine, inner, x, inner_kin)]
            continue
        outputs[routine.role] = [list(o) for o in run(routine, bound, x, kin)]
    return prog, outputs


def _input_symbols(sl):
    return {sl.program.inputs[(kind, index)].id: f"{kind}_{index}" for kind, index in sl.inputs}


def emit_routine(model, prog, routine: Routine, outputs, scalar: str = "double", slicing=None,
                 sl=None) -> EmittedRoutine:
    """C and Python statements of one routine, and the operation count of the C (its arrays, temporaries and
    literals of the C type ``scalar``, double or float).  ``slicing``: (threshold, size), the C of a routine of
    more work than the threshold also as slices of about that size (:mod:`.slicing`); None: never.  ``sl``: the
    outputs' :func:`~aggsym.core.program.straight_line` when already formed."""
    try:
        return _emit_routine(model, prog, routine, outputs, scalar, slicing, sl)
    except LiteralError as exc:
        raise AggsymError(f"{model.source or model.name}: routine {routine.role}: {exc}"
                          + ("; generate with --scalar double, or choose units in which the model's numbers fit"
                             if scalar == "float" else "")) from None


def _emit_routine(model, prog, routine: Routine, outputs, scalar: str, slicing, sl=None) -> EmittedRoutine:
    sl = sl or straight_line(prog, outputs)
    inputs = signature(routine, model)
    allowed = set(inputs)
    for kind, _ in sl.inputs:
        if kind not in allowed:
            raise RuntimeError(f"routine {routine.role} depends on input {kind!r} outside its signature")
    cp, pp = CPrinter(scalar), NumPyPrinter()
    temp_names = {i: f"x{k}" for k, i in enumerate(sl.temps)}
    names = {**_input_symbols(sl), **temp_names}
    conv = Converter(prog, names)  # the expression trees of the statements printed as NumPy apart from the C
    py_conv = Converter(prog, names)  # (its own list of names used: the C's are conv.refs)
    ctext = CText(prog, names, cp.counts, conv.refs, scalar)  # the C text without a tree

    def both(x, top=True):
        """(C, NumPy) text of a right-hand side; one text for both when it holds no function call and the C is
        double (the printers differ only in function names and in float literals)."""
        calls = ctext.calls
        c = ctext(x, top)
        if scalar == "double" and ctext.calls == calls:
            return c, c
        py = pp._print(py_conv(x, top))
        py_conv.refs.clear()
        return c, py
    py_body = []
    stmts = []  # the C body as statements (slicing.Statement): what each defines, uses, reads or writes

    def emit(lines, defines=(), arrays=(), ops=0, entry=""):
        stmts.append(Statement(lines, tuple(defines), tuple(conv.refs), tuple(arrays), ops, entry))
        conv.refs.clear()

    def ops_so_far():
        return sum(cp.counts.values())
    status = routine.status
    if status is not None:
        emit([f"{scalar} {status.name}[1];"], entry="head")
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
            py_body.append(f"{kind}_{i} = {kind}[..., {i}]")
    for out, flat in zip(routine.outputs, outputs):
        if not flat:
            emit([f"(void){out.name};"], entry="head")
    conv.refs.clear()
    trig = _trig_pairs(prog, sl.temps)
    done = set()
    defined = set(names) - set(temp_names)  # node ids with a C name already defined: the inputs, then temps
    pending = _pending_pairs(sl.steps, trig)
    hoisted = {}  # temps emitted early for a sincos pair: their NumPy right-hand side, appended at their step
    shapes = [out.shape(model) for out in routine.outputs]
    zeros = _zero_chunks(sl.steps, outputs, ZERO_BYTES // SCALAR_BYTES[scalar])
    for s, step in enumerate(sl.steps):
        before = ops_so_far()
        if step[0] == "out":
            _, o, k = step
            x = outputs[o][k]
            name = routine.outputs[o].name
            idx = ", ".join(str(j) for j in _unravel(k, shapes[o]))
            if s in zeros:  # one of a chunk of zero entries: the first writes them all (AGGSYM_ZEROS)
                if zeros[s]:
                    emit([f"AGGSYM_ZEROS({name} + {k});"], arrays=(name,))
                py_body.append(f"{routine.outputs[o].py}[..., {idx}] = 0")
                continue
            rhs_c, rhs_py = both(x, top=not (isinstance(x, Node) and x.id in names))
            emit([f"{name}[{k}] = {rhs_c};"], arrays=(name,), ops=ops_so_far() - before)
            py_body.append(f"{routine.outputs[o].py}[..., {idx}] = {rhs_py}")
            continue
        i = step[1]
        if i in hoisted:  # its C was emitted before a sincos pair that needed it
            py_body.append(f"{names[i]} = {hoisted.pop(i)}")
            continue
        if i not in trig:
            rhs_c, rhs_py = both(prog.nodes[i])
            py_body.append(f"{names[i]} = {rhs_py}")
            emit([f"const {scalar} {names[i]} = {rhs_c};"], defines=(names[i],), ops=ops_so_far() - before)
            defined.add(i)
            continue
        tree = conv(prog.nodes[i])
        py_body.append(f"{names[i]} = {pp._print(tree)}")
        pair = trig[i]
        if pair[:2] in done:
            conv.refs.clear()
            continue
        conv.refs.clear()  # (the sin or cos tree above was built for NumPy; the arguments' names again below)
        # a second angle whose argument is already computable shares the call (aggsym_sincos2: two in one vector)
        partner, early = _ready_partner(prog, names, trig, pending, done, defined, pair)
        for h in early:  # a temp the partner's angle is made of (q + offset), emitted now; NumPy keeps its place
            rhs_c, hoisted[h] = both(prog.nodes[h])
            emit([f"const {scalar} {names[h]} = {rhs_c};"], defines=(names[h],), ops=ops_so_far() - before)
            before = ops_so_far()
            defined.add(h)
        c_names, arguments = [], []
        for sin_id, cos_id, arg in (pair,) if partner is None else (pair, partner):
            done.add((sin_id, cos_id))
            defined.update(j for j in (sin_id, cos_id) if j is not None)
            c_names += [names[sin_id] if sin_id is not None else names[cos_id] + "_sin",
                        names[cos_id] if cos_id is not None else names[sin_id] + "_cos"]
            arguments.append(cp._print(conv(arg, top=False)))
            cp.counts["call"] += 1
        pointers = ", ".join(f"&{n}" for n in c_names)
        emit([f"{scalar} {', '.join(c_names)};",
              f"aggsym_sincos{'' if partner is None else '2'}({', '.join(arguments)}, {pointers});"],
             defines=c_names, ops=ops_so_far() - before)
    if status is not None:
        emit([f"return {status.name}[0] != {_number(0.0, scalar)};"], entry="tail")
    # what count_ops reads from the C, counted while printing (the other statements hold none); the C printer
    # prints only what is emitted, the sincos pair's discarded sin/cos trees were never printed
    ops = dict(cp.counts)
    sliced, size = None, sum(work(st) for st in stmts)
    if slicing is not None and size > slicing[0]:
        arrays = {k: f"const {scalar} *{k}" for k in inputs}
        arrays.update({o.name: f"{scalar} *{o.name}" for o in routine.outputs})
        pieces = min(slicing[1], routine.slice_size or slicing[1])
        sliced = slice_routine(c_symbol(model, routine), arrays, stmts, scalar, pieces)
    c_body = [line for st in stmts for line in st.lines]
    return EmittedRoutine(routine, inputs, c_symbol(model, routine), c_prototype(model, routine, scalar),
                          python_parameters(model, routine), c_body, py_body, ops, len(sl.temps), size, sliced)


# The bytes AGGSYM_ZEROS writes at once (templates/attributes.c.j2): 2 doubles, 4 floats
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


def _unravel(k, shape):
    out = []
    for n in reversed(shape):
        out.append(k % n)
        k //= n
    return tuple(reversed(out))


def check_constraints(model) -> None:
    """Redundant constraint rows make J A^-1 J^T singular everywhere: an error naming them, with a hint."""
    from ..errors import ModelError

    found = [] if model.regularization != 0 else redundant_constraints(model)
    if found:
        c, codes = found[0]
        raise ModelError(c.source, c.path, f"constraint {c.name!r}: its row(s) {', '.join(codes)} depend on the rows "
                                           f"before them (J is rank-deficient at every configuration tried), so J "
                                           f"A^-1 J^T is singular: block only the independent motions (e.g. "
                                           f"[o1, o2] for a point closing a planar loop), or give the model a "
                                           f"'regularization: epsilon' (J A^-1 J^T + epsilon E)", c.line)


@collector_paused()
def generate(model, progress=None, latex: bool = True, scalar: str = "double", split: bool = False,
             slicing=(SLICE_THRESHOLD, SLICE_SIZE)) -> Generated:
    """Generate all files of a model in memory; ``scalar`` is the C type (``float``: single-precision C, its
    bounds against the twin in the manifest's ``float_tolerance``; the NumPy module stays double).  ``split``:
    one .c per routine instead of NAME.c, the helpers in NAME_helpers.h and a Makefile (:func:`split_files`).
    ``slicing``: (threshold, size): the C of a routine of more work (operations plus statements) than the
    threshold is emitted as static functions of about that size each behind the public one (:mod:`.slicing`: one
    huge function takes GCC minutes); None: every routine as one function."""
    from .latex import LATEX_ROLES, latex_document

    check_names(model)
    stages = _Stages(progress)
    tree = Tree(model)
    omitted = omitted_routines(model)
    check_constraints(model)
    singular = {role: why for role, why in omitted.items() if ROUTINES[role].regular}
    if singular:  # (a regressor left out for an elastic model or added masses is only in the manifest)
        warnings.warn(ModelWarning(f"{model.source or model.name}: {next(iter(singular.values()))}: "
                                   f"{', '.join(singular)} left out (see the manifest's 'omitted')"))
    prog, outputs = symbolic_routines(model, tree, omitted=omitted)
    prog.seal()  # (the largest models' peak memory is the program while printing)
    stages.done("recursions")
    if scalar not in SCALARS:
        raise AggsymError(f"--scalar: {scalar!r} is not one of {', '.join(SCALARS)}")
    lines = {}  # the straight lines of A, b and g, which the LaTeX prints too (latex.intermediate_form)
    emitted = []
    for role, outs in outputs.items():
        sl = straight_line(prog, outs)
        if latex and role in LATEX_ROLES:
            lines[role] = sl
        emitted.append(emit_routine(model, prog, ROUTINES[role], outs, scalar, slicing, sl))
        del sl
    stages.done("printing")
    env = templates()
    ctx = {
        "name": model.name,
        "guard": model.name.upper() + "_H",
        "model": model,
        "nq": model.nq,
        "np": len(model.parameters),
        "routines": emitted,
        "source": Path(model.source).name if model.source else model.name,
        "description": model.description,
        "version": __version__,
        "parameters": [(p.name, repr(float(p.value))) for p in model.parameters],
        "p_defaults": [_number(float(p.value), scalar) for p in model.parameters],
        "scalar": scalar,
        "zero": _number(0.0, scalar),
        "macros": header_macros(model, [e.routine for e in emitted], scalar),
        "coordinates": [SimpleNamespace(name=n, joint=j, kind=k) for n, j, k in model.positions],
        "velocities": model.coordinates if model.nq != model.nv else None,
        "nv": model.nv,
        "frames": model.frames if any(e.routine.role.startswith("frame_") for e in emitted) else (),
        "sincos": any("aggsym_sincos" in line for r in emitted for line in r.c_body),
        "sincos2": any("aggsym_sincos2(" in line for r in emitted for line in r.c_body),
        "sign": any("aggsym_sign(" in line for r in emitted for line in r.c_body),
        "sliced": any(r.sliced for r in emitted),
        "scalar_stores": any(r.routine.scalar_stores for r in emitted),
        "zeros": any(r.zeros for r in emitted),
        "zero_width": ZERO_BYTES // SCALAR_BYTES[scalar],
        "time": model.time_dependent,
        "elastic": any(b.pair.elastic for b in model.bodies),
    }
    gen = Generated(model, emitted)
    gen.files[f"{model.name}.h"] = env.get_template("model.h.j2").render(ctx)
    if split:
        gen.files.update(split_files(env, ctx, emitted))
    else:
        gen.files[f"{model.name}.c"] = env.get_template("model.c.j2").render(ctx)
    gen.files[f"{model.name}.py"] = env.get_template("model.py.j2").render(ctx)
    names = list(gen.files) + [f"{model.name}.json"] + ([f"{model.name}.tex"] if latex else [])
    gen.files[f"{model.name}.json"] = json.dumps(
        manifest(model, [e.routine for e in emitted], {e.routine.role: e.ops for e in emitted}, omitted, scalar,
                 layout=split_layout(model.name, emitted, names) if split else None),
        indent=2) + "\n"
    stages.done("templates")
    if latex:
        gen.files[f"{model.name}.tex"] = latex_document(model, env, prog, outputs, lines)
        stages.done("latex")
    gen.timings = stages.timings
    return gen


HELPERS = ("aggsym_sincos(", "aggsym_sincos2(", "aggsym_sign(")  # the calls of the helpers that helpers.c.j2 defines


def _helpers_used(r: EmittedRoutine) -> bool:
    return any(h in line for line in r.c_body for h in HELPERS)


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


def split_files(env, ctx, emitted) -> dict:
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
        files[helpers] = env.get_template("helpers.h.j2").render(
            {**ctx, "guard": name.upper() + "_HELPERS_H", "sign_storage": "static inline"})
    rules = []
    for r in emitted:
        source = names["sources"][r.routine.role]
        uses = helpers if _helpers_used(r) else None
        files[source] = env.get_template("routine.c.j2").render({**ctx, "r": r, "helpers": uses})
        rules.append((source, source[:-2] + ".o", [f"{name}.h"] + ([uses] if uses else [])))
    files[names["makefile"]] = env.get_template("Makefile.j2").render(
        {**ctx, "objects": [o for _, o, _ in rules], "rules": rules})
    return files


def write(gen: Generated, outdir, origin: str | None = None) -> list:
    """Write the files into ``outdir`` through a temporary folder; returns the paths written.

    All or nothing: a new folder appears whole (the temporary one, beside it, is renamed); in an existing folder
    the new files are written into a temporary folder inside it, then each takes its place while the file it
    replaces (and each stale file of an earlier generation, :func:`stale_files`) is kept aside until all are in
    place; a failure puts everything back, so the folder is left as it was.  An output path that cannot be used
    (a file, read-only, a folder where a file goes, a name too long for the file system) is the user's error,
    reported with that path and the fix; ``origin`` says where the model's name came from (default: the model
    file, see :func:`name_origin`), for a name too long."""
    outdir = Path(outdir)
    tmp = None
    created = []  # the folders above outdir this run made, removed again on failure
    try:
        check_file_names(outdir, list(gen.files), gen.model, origin)
        if outdir.exists() and not outdir.is_dir():
            raise AggsymError(f"{outdir}: the output folder is a file; remove it, or write elsewhere with -o OUTDIR")
        if outdir.is_dir() and not os.access(outdir, os.W_OK | os.X_OK):
            raise AggsymError(f"{outdir}: the output folder is not writable")
        if outdir.is_dir():
            for name in gen.files:
                if (outdir / name).is_dir() and not (outdir / name).is_symlink():
                    raise AggsymError(f"{outdir / name}: a folder stands where aggsym writes its file {name}; move "
                                      f"or remove it, or write elsewhere with -o OUTDIR (nothing was written)")
        stale = stale_files(outdir, gen) if outdir.is_dir() else []
        for folder in reversed(outdir.parents):
            if not folder.exists():
                folder.mkdir()
                created.append(folder)
        tmp = Path(tempfile.mkdtemp(prefix=".aggsym-", dir=outdir if outdir.is_dir() else outdir.parent))
        for name, text in gen.files.items():
            (tmp / name).write_text(text, encoding="utf-8")
        if not outdir.exists():
            os.chmod(tmp, 0o777 & ~_umask())
            os.replace(tmp, outdir)
            tmp = None
        else:
            _swap(tmp, outdir, list(gen.files), stale)
        created = []
        return [outdir / name for name in gen.files]
    except OSError as exc:
        if exc.errno == errno.ENAMETOOLONG:
            raise AggsymError(f"{outdir}: cannot write the output folder: a path is too long for the file system; "
                              f"{_shorter(gen.model, origin)}, or a shorter -o OUTDIR (nothing was written)") from None
        raise AggsymError(f"{outdir}: cannot write the output folder: {exc.strerror or exc} (nothing was "
                          f"written)") from None
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
        for folder in reversed(created):
            try:
                folder.rmdir()
            except OSError:
                break


def _swap(tmp: Path, outdir: Path, names: list, stale: list) -> None:
    """Move the files ``names`` from ``tmp`` into ``outdir`` and the ``stale`` ones out of it, all or nothing: what
    they replace is kept in ``tmp`` until every move is done, and put back if one fails."""
    aside = tmp / ".previous"  # (no generated name starts with a dot)
    aside.mkdir()
    kept, placed = [], []
    try:
        for name in names:
            target = outdir / name
            if os.path.lexists(target):
                os.replace(target, aside / name)
                kept.append(name)
            os.replace(tmp / name, target)
            placed.append(name)
        for name in stale:
            target = outdir / name
            if os.path.lexists(target) and not (target.is_dir() and not target.is_symlink()):
                os.replace(target, aside / name)
                kept.append(name)
    except BaseException:  # (an interrupt too: the files put aside must not go with the temporary folder)
        try:
            for name in placed:
                (outdir / name).unlink(missing_ok=True)
            for name in kept:
                os.replace(aside / name, outdir / name)
        except OSError as undo:  # keep the earlier files where they are, and say where
            os.replace(tmp, tmp.with_name(tmp.name + "-previous"))
            raise AggsymError(f"{outdir}: cannot write the output folder, nor restore it ({undo.strerror or undo}); "
                              f"the earlier files are in {tmp.with_name(tmp.name + '-previous') / aside.name}") \
                from None
        raise


def name_origin(model) -> str:
    """Where a model's name comes from, for messages: its file's ``<robot name=...>`` or ``name:``."""
    source = model.source
    if not source:
        return "the model"
    if Path(source).suffix.lower() == ".urdf":
        return f'{source} (its <robot name="...">)'
    if model.name == Path(source).stem:
        return f"{source} (its 'name:', or the file's own name when it has none)"
    return f"{source} (its 'name:')"


def _short(name: str) -> str:
    """A long name shortened for a message, its start and its end kept."""
    return name if len(name) <= 48 else f"{name[:20]}...{name[-24:]}"


def _shorter(model, origin) -> str:
    return (f"the name {_short(model.name)!r} ({len(model.name)} characters) comes from "
            f"{origin or name_origin(model)}: give a shorter one with --name SHORTER")


def check_file_names(outdir: Path, names: list, model, origin: str | None = None) -> None:
    """The files ``names`` and the folders of ``outdir`` still to be made must fit the file system's limit on a
    name (NAME_MAX, usually 255 bytes): an AggsymError naming where the model's name came from and the fix
    otherwise (``origin``: e.g. ``the option --name``; default :func:`name_origin`)."""
    existing = outdir
    missing = []
    while not os.path.exists(existing) and existing != existing.parent:  # (False, not an error, for a long name)
        missing.append(existing.name)
        existing = existing.parent
    try:
        limit = os.pathconf(existing, "PC_NAME_MAX")
    except (OSError, ValueError):
        limit = 255
    for name in sorted(missing + list(names), key=lambda n: -len(os.fsencode(n))):
        size = len(os.fsencode(name))
        if size > limit:
            what = "folder" if name in missing else "file"
            fix = (_shorter(model, origin) if what == "file" or model.name in name else
                   "choose a shorter output folder with -o OUTDIR")
            raise AggsymError(f"{outdir}: cannot write the {what} {_short(name)!r}: its name of {size} bytes is too "
                              f"long for the file system (at most {limit}); {fix} (nothing was written)")
        break  # (the longest fits: all do)


def stale_files(outdir: Path, gen: Generated) -> list:
    """The files that an earlier generation of the same model wrote into ``outdir`` and this one does not (NAME.c
    after a switch to ``--split``, NAME_ROUTINE.c, NAME_helpers.h and the Makefile after a switch back or to
    fewer routines): they would be compiled beside the new ones.  Known from the earlier manifest NAME.json
    (its ``split.files``, or the one-file layout), only when it is an aggsym manifest of this name, and only
    names of the forms this generator writes (NAME.h/.c/.py/.json/.tex, NAME_WORD.c/.h, Makefile): a manifest
    is a file in a user's folder, never a list of paths to delete."""
    name = gen.model.name
    try:
        old = json.loads((outdir / f"{name}.json").read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError):
        return []
    if not isinstance(old, dict) or old.get("name") != name or not str(old.get("generator", "")).startswith("aggsym"):
        return []
    split = old.get("split")
    one_file = [f"{name}.{ext}" for ext in ("h", "c", "py", "json", "tex")]
    previous = split.get("files") if isinstance(split, dict) else one_file
    if not isinstance(previous, list):
        return []
    ours = re.compile(rf"{re.escape(name)}(\.(h|c|py|json|tex)|_[A-Za-z0-9_]+\.[ch])|Makefile")
    return sorted({f for f in previous if isinstance(f, str) and ours.fullmatch(f) and f not in gen.files})


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def check_names(model) -> None:
    """The model's name must make a C prefix and an importable Python module: a ModelError (exit 2) suggesting
    ``--name`` otherwise."""
    problem = check_c_identifier(model.name) or check_module_name(model.name)
    if problem:
        raise ModelError(model.source or model.name, "name",
                         f"the model's name cannot name the generated code: {problem}; give another with "
                         f"--name NAME")
