"""``aggsym generate``: every routine of the contract into each chosen target (C, NumPy, LaTeX, the JSON manifest,
...: :mod:`.targets`, one registry).

The recursions run once on the symbolic backend into one shared straight-line program (kinematics shared by
all routines); each routine's outputs are then cut out of it and emitted (:mod:`.emit`: printed as C, which counts
the operations, and by every chosen target), and the targets render their files from the Jinja templates (layout
only; a folder per target, ``templates/TARGET/``, installed as the package ``aggsym.templates``).  What a routine is
called, takes and returns comes from :mod:`aggsym.contract`.  Files are written only after everything has been
generated, through a temporary folder, so a failure leaves the output folder as it was.
"""
from __future__ import annotations

import errno
import json
import os
import shutil
import tempfile
import time
import warnings
from dataclasses import dataclass, field
from types import SimpleNamespace
from pathlib import Path


from .. import __version__
from ..contract import (
    INPUT_KINDS, ROUTINES, input_length, mass_matrix_note, omitted_routines, redundant_constraints, routine_of,
    routines_for, run, signature,
)
from ..contract.singular_states import FAILURE as SINGULAR_FAILURE
from ..core.backend import Symbolic
from ..core.program import straight_line
from ..mechanics.bound import bind, program_operations
from ..mechanics.kinematics import TreeKinematics
from ..model.transforms.joint_dynamics import passive_entry, routine_notes
from ..model.transforms.reframe import reframe
from ..model.tree import Tree
from ..collector import collector_paused
from ..errors import AggsymError, ModelError, ModelWarning
from .escape import check_c_identifier, check_module_name
from .inertial_helpers import inertial_helpers
from .names import header_macros
from .printing import SCALARS, _number
from .slicing import SLICE_SIZE, SLICE_THRESHOLD
from .emit import emit_routine
from .targets import Job, select
from .targets.c import SCALAR_BYTES, ZERO_BYTES
from .targets.c_columns import LOOPED_ABOVE


@dataclass
class Generated:
    model: object
    routines: list
    files: dict = field(default_factory=dict)  # file name -> text
    targets: tuple = ()  # the targets generated (:class:`~.targets.base.Target`), in the registry's order
    timings: list = field(default_factory=list)  # (stage, seconds)


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
    when it is not :func:`~aggsym.model.transforms.reframe.eligible`, else of its two internal models (origins at the feet of
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
    tree = tree or Tree.of(model)
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


def check_constraints(model) -> None:
    """Redundant constraint rows make J A^-1 J^T singular everywhere: an error naming them, with a hint."""
    from ..errors import ModelError

    found = [] if model.regularization != 0 or model.proximal else redundant_constraints(model)
    if found:
        c, codes = found[0]
        raise ModelError(c.source, c.path, f"constraint {c.name!r}: its row(s) {', '.join(codes)} depend on the rows "
                                           f"before them (J is rank-deficient at every configuration tried), so J "
                                           f"A^-1 J^T is singular: block only the independent motions (e.g. "
                                           f"[o1, o2] for a point closing a planar loop), or give the model a "
                                           f"'regularization: epsilon' (J A^-1 J^T + epsilon E) or a damped solve "
                                           f"'proximal: {{mu: MU, iterations: N}}'", c.line)


@collector_paused()
def generate(model, progress=None, scalar: str = "double", split: bool = False,
             slicing=(SLICE_THRESHOLD, SLICE_SIZE), targets=None, looped_above: int = LOOPED_ABOVE) -> Generated:
    """Generate all files of a model in memory; ``scalar`` is the C type (``float``: single-precision C, its
    bounds against the twin in the manifest's ``float_tolerance``; the NumPy module stays double).  ``split``:
    one .c per routine instead of NAME.c, the helpers in NAME_helpers.h and a Makefile
    (:func:`.targets.c.split_files`).
    ``slicing``: (threshold, size): the C of a routine of more work (operations plus statements) than the
    threshold is emitted as static functions of about that size each behind the public one (:mod:`.slicing`: one
    huge function takes GCC minutes); None: every routine as one function.  ``targets``: the targets (names, a
    comma-separated string of them or the targets themselves, :func:`.targets.select`; None: the default set): only
    their files are generated.  ``looped_above``: the C of a routine whose solves are
    one body applied to columns (:mod:`.targets.c_columns`) loops over them when it has more operations than this."""
    chosen = select(targets)
    check_names(model)
    stages = _Stages(progress)
    tree = Tree.of(model)
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
    lines = {}  # the straight lines the targets render from (the LaTeX's A, b and g: latex.intermediate_form)
    wanted = set().union(*(t.lines for t in chosen))
    emitted = []
    for role, outs in outputs.items():
        sl = straight_line(prog, outs)
        if role in wanted:
            lines[role] = sl
        emitted.append(emit_routine(model, prog, routine_of(model, role), outs, chosen, scalar, slicing, sl,
                                    prog.columns.get(role), looped_above))
        del sl
    stages.done("printing")
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
        "sincos": any("aggsym_sincos" in line for r in emitted for line in r.bodies["c"].lines),
        "sincos2": any("aggsym_sincos2(" in line for r in emitted for line in r.bodies["c"].lines),
        "sign": any("aggsym_sign(" in line for r in emitted for line in r.bodies["c"].lines + r.bodies["c"].functions),
        "sliced": any(r.bodies["c"].sliced for r in emitted),
        "scalar_stores": any(r.routine.scalar_stores for r in emitted),
        "zeros": any(r.bodies["c"].zeros for r in emitted),
        "zero_width": ZERO_BYTES // SCALAR_BYTES[scalar],
        "time": model.time_dependent,
        "elastic": any(b.pair.elastic for b in model.bodies),
        "omitted": dict(omitted),  # role -> why it is left out (the header says so where it would be)
        "mass_matrix": mass_matrix_note(model, [e.routine for e in emitted]),  # where A(q) may be singular, or None
        "singular_failure": SINGULAR_FAILURE,
        "passive": passive_entry(model),  # the joints' damping and friction: in forward/inverse dynamics or not
        "passive_notes": routine_notes(model),  # role -> what it holds of them (the header's comment)
        "inertial_helpers": inertial_helpers(model),  # NAME_set_payload_<link>, set_inertial_<link>
    }
    gen = Generated(model, emitted, targets=tuple(chosen))
    job = Job(model, ctx, emitted, prog, outputs, lines, split, scalar, omitted, chosen)
    job.names = [name for t in chosen for name in t.file_names(job)]
    for k, target in enumerate(chosen):
        gen.files.update(target.render(job))
        if k + 1 == len(chosen) or chosen[k + 1].stage != target.stage:
            stages.done(target.stage)
    if list(gen.files) != job.names:
        raise RuntimeError(f"the targets wrote {list(gen.files)}, not the files they name: {job.names}")
    gen.timings = stages.timings
    return gen



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
    is a file in a user's folder, never a list of paths to delete.  Only files of the targets generated now are
    stale (``--targets c`` leaves an earlier NAME.py alone), each target saying which forms are its own."""
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
    return sorted({f for f in previous if isinstance(f, str) and f not in gen.files
                   and any(t.owns(name, f) for t in gen.targets)})


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
