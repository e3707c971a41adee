"""``aggsym generate``: every routine of the contract as C, NumPy and LaTeX, plus the JSON manifest.

The recursions run once on the symbolic backend into one shared straight-line program (kinematics shared by
all routines); each routine's outputs are then cut out of it (:func:`~aggsym.codegen.printing.straight_line`),
printed through the SymPy printer subclasses, and laid out by the Jinja templates in ``templates/`` (layout
only).  Files are written only after everything has been generated, through a temporary folder, so a failure
leaves the output folder as it was.
"""
from __future__ import annotations

import json
import os
import shutil
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import jinja2

from .. import __version__
from ..backend import Symbolic, bind
from ..kinematics import TreeKinematics
from ..model.tree import Tree
from ..routines import ROUTINES, Routine
from .printing import CPrinter, Converter, NumPyPrinter, count_ops, straight_line
from .program import Node

INPUT_KINDS = ("q", "qd", "qdd", "tau")


@dataclass
class EmittedRoutine:
    routine: Routine
    symbol: str  # C function name
    c_body: list  # C statements
    py_body: list  # Python statements
    ops: dict
    temps: int


@dataclass
class Generated:
    model: object
    routines: list
    files: dict = field(default_factory=dict)  # file name -> text
    timings: list = field(default_factory=list)  # (stage, seconds)


def templates() -> jinja2.Environment:
    """The Jinja environment over the package's templates (shipped inside the wheel as aggsym/templates)."""
    from importlib.resources import files

    root = files("aggsym.templates")
    return jinja2.Environment(
        loader=jinja2.FunctionLoader(lambda name: (root / name).read_text(encoding="utf-8")),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
        autoescape=False,
    )


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


def symbolic_routines(model, tree=None, roles=None):
    """Run every routine on the symbolic backend: (program, {role: list of flat output lists})."""
    backend = Symbolic()
    prog = backend.program
    tree = tree or Tree(model)
    bound = bind(model, backend, tree=tree)
    vectors = {k: prog.vector(k, model.nq) for k in INPUT_KINDS}
    kin = TreeKinematics(bound, vectors["q"])
    outputs = {}
    for role, routine in ROUTINES.items():
        if roles is not None and role not in roles or not routine.exists_for(model):
            continue
        x = {k: vectors[k] for k in routine.inputs if k != "p"}
        outputs[role] = [list(o) for o in routine.build(bound, kin, x)]
    return prog, outputs


def _input_symbols(sl, c: bool):
    names = {}
    for kind, index in sl.inputs:
        node = sl.program.inputs[(kind, index)]
        names[node.id] = f"{kind}[{index}]" if c else f"{kind}_{index}"
    return names


def emit_routine(model, prog, routine: Routine, outputs, prefix: str) -> EmittedRoutine:
    """C and Python statements of one routine, and the operation count of the C."""
    sl = straight_line(prog, outputs)
    allowed = set(routine.inputs)
    for kind, _ in sl.inputs:
        if kind not in allowed:
            raise RuntimeError(f"routine {routine.role} depends on input {kind!r} outside its signature")
    cp, pp = CPrinter(), NumPyPrinter()
    temp_names = {i: f"x{k}" for k, i in enumerate(sl.temps)}
    c_names = {**_input_symbols(sl, True), **temp_names}
    py_names = {**_input_symbols(sl, False), **temp_names}
    c_conv, py_conv = Converter(prog, c_names), Converter(prog, py_names)
    c_body, py_body = [], []
    for kind in routine.inputs:
        used = [i for k, i in sl.inputs if k == kind]
        if not used:
            c_body.append(f"(void){kind};")
        for i in used:
            py_body.append(f"{kind}_{i} = {kind}[..., {i}]")
    trig = _trig_pairs(prog, sl.temps)
    done = set()
    shapes = [out.shape(model) for out in routine.outputs]
    for step in sl.steps:
        if step[0] == "out":
            _, o, k = step
            x = outputs[o][k]
            name = routine.outputs[o].name
            rhs_c = cp._print(c_conv(x, top=not (isinstance(x, Node) and x.id in c_names)))
            rhs_py = pp._print(py_conv(x, top=not (isinstance(x, Node) and x.id in py_names)))
            c_body.append(f"{name}[{k}] = {rhs_c};")
            idx = ", ".join(str(j) for j in _unravel(k, shapes[o]))
            py_body.append(f"{name}[..., {idx}] = {rhs_py}")
            continue
        i = step[1]
        node = prog.nodes[i]
        py_body.append(f"{py_names[i]} = {pp._print(py_conv(node))}")
        if i not in trig:
            c_body.append(f"const double {c_names[i]} = {cp._print(c_conv(node))};")
            continue
        sin_id, cos_id, arg = trig[i]
        if (sin_id, cos_id) in done:
            continue
        done.add((sin_id, cos_id))
        s_name = c_names[sin_id] if sin_id is not None else c_names[cos_id] + "_sin"
        c_name = c_names[cos_id] if cos_id is not None else c_names[sin_id] + "_cos"
        c_body.append(f"double {s_name}, {c_name};")
        c_body.append(f"aggsym_sincos({cp._print(c_conv(arg, top=False))}, &{s_name}, &{c_name});")
    ops = count_ops("\n".join(c_body))
    return EmittedRoutine(routine, f"{prefix}_{routine.role}", c_body, py_body, ops, len(sl.temps))


def _trig_pairs(prog, temps) -> dict:
    """For every sin or cos temp: (sin id or None, cos id or None, argument), so that C computes both at once."""
    from .program import COS, SIN, _key

    by_arg = {}
    for i in temps:
        entry = prog.ops[i]
        if entry[0] in (SIN, COS):
            pair = by_arg.setdefault(_key(entry[1]), [None, None, entry[1]])
            pair[0 if entry[0] == SIN else 1] = i
    return {i: tuple(pair) for pair in by_arg.values() for i in pair[:2] if i is not None}


def _unravel(k, shape):
    out = []
    for n in reversed(shape):
        out.append(k % n)
        k //= n
    return tuple(reversed(out))


def manifest(model, emitted, conservative: bool = True) -> dict:
    """The JSON manifest of the generated-code contract."""
    tree = Tree(model)
    layouts = {}
    for e in emitted:
        if e.routine.layout is not None:
            layouts[e.routine.role] = e.routine.layout(model)
    return {
        "name": model.name,
        "nq": model.nq,
        "coordinates": [{"name": c.name, "joint": c.joint, "kind": c.kind} for c in model.coordinates],
        "parameters": [{"name": p.name, "value": p.value} for p in model.parameters],
        "functions": {e.routine.role: e.symbol for e in emitted},
        "signatures": {e.routine.role: {"inputs": list(e.routine.inputs),
                                        "outputs": [{"name": o.name, "shape": list(o.shape(model))}
                                                    for o in e.routine.outputs]} for e in emitted},
        "layouts": layouts,
        "conservative": conservative,
        "ops": {e.routine.role: e.ops for e in emitted},
        "bodies": len(tree),
        "generator": f"aggsym {__version__}",
    }


def generate(model, progress=None, latex: bool = True) -> Generated:
    """Generate all files of a model in memory."""
    from .latex import latex_document

    stages = _Stages(progress)
    tree = Tree(model)
    prog, outputs = symbolic_routines(model, tree)
    stages.done("recursions")
    emitted = [emit_routine(model, prog, ROUTINES[role], outs, model.name) for role, outs in outputs.items()]
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
        "coordinates": model.coordinates,
        "sincos": any("aggsym_sincos(" in line for r in emitted for line in r.c_body),
    }
    gen = Generated(model, emitted)
    gen.files[f"{model.name}.h"] = env.get_template("model.h.j2").render(ctx)
    gen.files[f"{model.name}.c"] = env.get_template("model.c.j2").render(ctx)
    gen.files[f"{model.name}.py"] = env.get_template("model.py.j2").render(ctx)
    gen.files[f"{model.name}.json"] = json.dumps(manifest(model, emitted), indent=2) + "\n"
    stages.done("templates")
    if latex:
        gen.files[f"{model.name}.tex"] = latex_document(model, env, prog, outputs)
        stages.done("latex")
    gen.timings = stages.timings
    return gen


def write(gen: Generated, outdir) -> list:
    """Write the files into ``outdir`` through a temporary folder; returns the paths written."""
    outdir = Path(outdir)
    outdir.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{outdir.name}.", dir=outdir.parent))
    try:
        for name, text in gen.files.items():
            (tmp / name).write_text(text, encoding="utf-8")
        outdir.mkdir(exist_ok=True)
        paths = []
        for name in gen.files:
            os.replace(tmp / name, outdir / name)
            paths.append(outdir / name)
        return paths
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
