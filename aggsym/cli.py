"""The command line: ``aggsym generate | latex | check | ops MODEL``.

Exit codes: 0 success, 1 generated code disagrees with the numeric twin, 2 bad input (with a message naming
the file, the place in it and the problem; never a traceback).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from pathlib import Path

from .errors import AggsymError
from .pipeline import FLOATING_BASE_KINDS, OPTIONS


def _formats() -> str:
    """The readers and their suffixes, for the help (model.readers.registry: one registry)."""
    from .model.readers.registry import READERS

    return ", ".join(f"{r.name}: {' '.join(r.suffixes + r.sniffed)}" for r in READERS)


def _help(option) -> str:
    """An option's help, opening with the readers that take it where not every model does ("URDF and xacro only:
    ..."), from the pipeline's table."""
    from .model.readers.registry import listing
    from .pipeline import takers

    who = takers(option)
    return option.help if who is None else f"{listing(who)} only: {option.help}"


def _argparse_type(check):
    """A pipeline check (ValueError with the reason) as argparse's type (an ArgumentTypeError: exit 2, usage)."""
    def convert(text):
        try:
            return check(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
    convert.__name__ = check.__name__
    return convert


EXAMPLES = {
    "generate": "example:\n  aggsym generate models/double_pendulum.yaml             # writes generated/double_pendulum/\n"
                "  aggsym generate robot.urdf --floating-base -o build/robot",
    "latex": "example:\n  aggsym latex models/double_pendulum.yaml > double_pendulum.tex",
    "check": "example:\n  aggsym check models/manipulator6.yaml --trials 50",
    "ops": "example:\n  aggsym ops models/manipulator6.yaml",
}


OPT_LEVELS = ("-O0", "-O1", "-O2", "-O3")  # check --opt


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="aggsym",
        description="Equations of motion of rigid-body trees (Konoplev's aggregative method) as C, NumPy and LaTeX.",
        epilog="example:\n  aggsym generate models/double_pendulum.yaml\n\nexit codes: 0 ok, 1 mismatch, 2 bad input",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    from . import __version__

    parser.add_argument("--version", action="version", version=f"aggsym {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    def command(name, help_text):
        p = sub.add_parser(name, help=help_text, description=help_text, epilog=EXAMPLES[name],
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        p.add_argument("model", metavar="MODEL", help=f"a model file ({_formats()}; the reader is chosen by the "
                                                      f"suffix, and by the content where formats share one)")
        for option in OPTIONS:  # the model options, from the pipeline's table (aggsym.pipeline.OPTIONS)
            keywords = dict(option.cli)
            if "type" in keywords:
                keywords["type"] = _argparse_type(keywords["type"])
            keywords.setdefault("default", option.default)
            p.add_argument(option.flag, dest=option.name, help=_help(option), **keywords)
        p.add_argument("--scalar", choices=["double", "float"], default="double",
                       help="the C type of the generated C (default double; float: single precision for "
                            "microcontrollers, each routine's error bound in the manifest's float_tolerance; the "
                            "NumPy module stays double)")
        return p

    g = command("generate", "write NAME.h, NAME.c, NAME.py, NAME.tex and NAME.json (--split: NAME_ROUTINE.c per "
                            "routine, NAME_helpers.h and a Makefile instead of NAME.c)")
    g.add_argument("-o", "--output", metavar="OUTDIR", help="output folder (default: generated/NAME/)")
    g.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    g.add_argument("--split", action="store_true",
                   help="one C file per routine (NAME_ROUTINE.c), the shared helpers in NAME_helpers.h, and a "
                        "Makefile building libNAME.a (make -j2; CC, CFLAGS default -O2 -std=c99) instead of NAME.c")
    g.add_argument("--targets", metavar="A,B,...",
                   help="write only these targets' files: c (NAME.h, NAME.c or the --split files), numpy (NAME.py), "
                        "manifest (NAME.json), latex (NAME.tex), jax (NAME_jax.py), torch (NAME_torch.py), casadi "
                        "(NAME_casadi.py: casadi.Function over SX), ext "
                        "(NAME_ext.c, NAME_ext.py: one state per call through the compiled C; with c and numpy); "
                        "with c and jax or torch also kernels (NAME_kernels.c, NAME_kernels.py, NAME_kernels_jax.cc: "
                        "the batch kernels the JAX and PyTorch modules call on the CPU); "
                        "default: c, numpy, manifest, latex")
    g.add_argument("--no-kernels", action="store_true",
                   help="with c and jax or torch: no batch kernels (NAME_kernels.c, .py, _jax.cc) behind the JAX and "
                        "PyTorch modules, which then trace their straight lines on every platform")
    g.add_argument("--list-routines", action="store_true",
                   help="print the routines this model gets, one line each (what each computes), and write nothing")
    command("latex", "print the LaTeX document of the equations of motion")
    c = command("check", "compile the C, run it and the NumPy module on random states, compare with the numeric twin")
    c.add_argument("--trials", type=int, default=20, help="random states per routine (default 20)")
    c.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    c.add_argument("--tol", type=float, default=1e-12, help="largest relative error accepted (default 1e-12)")
    c.add_argument("--opt", default="-O2", type=lambda v: v if v.startswith("-") else "-" + v,
                   choices=OPT_LEVELS, metavar="O0|O1|O2|O3",
                   help="optimization level of the compile: O0, O1, O2 or O3 (or -O2; default -O2; large "
                        "models compile much faster at O0)")
    c.add_argument("--split", action="store_true",
                   help="check the --split layout: its Makefile builds libNAME.a (make -j2, the same warnings as "
                        "errors and --opt), and that library is what runs")
    c.add_argument("--targets", metavar="A,B,...",
                   help="check only these targets (default: every target with something to run here: c, numpy, and jax "
                        "and torch where they import; ext and casadi when named)")
    command("ops", "operation counts per routine beside the book's tables and Featherstone's counts")
    return parser


def _load(args):
    """The model the command generates from (:func:`aggsym.pipeline.prepare`, the options from the command line)."""
    from .pipeline import prepare

    options = {o.name: o.from_cli(getattr(args, o.name)) for o in OPTIONS if o.given(getattr(args, o.name))}
    return prepare(args.model, **options)


def _progress(quiet: bool, name: str):
    if quiet:
        return None
    return lambda msg: print(f"aggsym: {name}: {msg}", file=sys.stderr, flush=True)


def _targets(args):
    """The targets named by --targets (None: the default set), chosen once, before any work: an unknown one is
    exit 2."""
    from .codegen.targets import select

    return select(args.targets, kernels=not getattr(args, "no_kernels", False))


def cmd_generate(args) -> int:
    t0 = time.perf_counter()
    targets = _targets(args)
    prepared = _load(args)
    model = prepared.model
    if args.list_routines:
        from .codegen.names import c_symbol
        from .contract import ROUTINES, omitted_routines, routines_for

        omitted = omitted_routines(model)
        routines = routines_for(model, omitted=omitted)
        extra = [r for r in ROUTINES.values() if r.exists_for(model) and r not in routines and r.role not in omitted]
        width = max(len(c_symbol(model, r)) for r in list(routines) + extra)
        for r in routines:
            print(f"{c_symbol(model, r).ljust(width)}  {r.doc}")
        for role, reason in omitted.items():
            print(f"{(model.name + '_' + role).ljust(width)}  (left out: {reason})")
        for r in extra:  # not emitted: on request, or (with --routines) not named
            why = "on request" if r.on_request or model.routines is None else "not selected"
            print(f"{c_symbol(model, r).ljust(width)}  ({why}: --routines {r.role}) {r.doc}")
        return 0
    from .codegen.generate import check_file_names, generate, write

    outdir = Path(args.output) if args.output else Path("generated") / model.name
    origin = prepared.name_origin  # (None: the model's own name, codegen.generate.name_origin)
    check_file_names(outdir, [f"{model.name}.json"], model, origin)  # (before the work: write checks every file)
    gen = generate(model, progress=_progress(args.quiet, model.name), scalar=args.scalar, split=args.split,
                   targets=targets)
    paths = write(gen, outdir, origin)
    if not args.quiet:
        print(f"aggsym: {model.name}: wrote {len(paths)} files to {outdir} in {time.perf_counter() - t0:.2f} s",
              file=sys.stderr)
        for p in paths:
            print(p)
    return 0


def cmd_latex(args) -> int:
    from .codegen.generate import generate

    model = _load(args).model
    gen = generate(model, scalar=args.scalar)
    sys.stdout.write(gen.files[f"{model.name}.tex"])
    return 0


def cmd_check(args) -> int:
    from .codegen.check import check_generated, checked_targets
    from .codegen.generate import generate
    from .codegen.targets import TARGETS

    named = None if args.targets is None else _targets(args)
    targets = named or [t for t in TARGETS.values() if t.checked_by_default]
    # (the manifest: always, check reads it; the LaTeX has nothing to run)
    model = _load(args).model
    gen = generate(model, scalar=args.scalar, split=args.split,
                   targets=[t for t in targets if t.name != "latex"] + [TARGETS["manifest"]])
    checked, skipped = checked_targets(model, gen.files, None if named is None else [t.name for t in named])
    for name, why in skipped.items():
        print(f"aggsym: {model.name}: target {name} not checked: {why}", file=sys.stderr)
    if not checked:
        raise AggsymError(f"{model.name}: nothing to check: "
                          + ("; ".join(f"{n}: {why}" for n, why in skipped.items()) or
                             "none of the targets named has something to run (known: "
                             + ", ".join(n for n, t in TARGETS.items() if t.column) + ")"))
    results = check_generated(model, gen.files, trials=args.trials, seed=args.seed, opt=args.opt,
                              targets=[t.name for t in checked])
    width = max(len(r.role) for r in results)
    columns = results[0].columns  # key -> heading: a column per runner of the targets checked
    # the columns with bounds of their own (the float C, the modules in float32, derivatives against central
    # differences: each its runner's); the others held to --tol
    bounded = {name for r in results for name in r.tolerances}
    print(f"{model.name}: {args.trials} random states per routine; worst error against the numeric twin, relative "
          f"to the largest value the routine returns; d ROUTINE: derivatives against central differences"
          + (f"; {', '.join(columns[k] for k in columns if k in bounded)} held to "
             f"{'its bounds' if len(bounded) == 1 else 'their bounds'}" if bounded else ""))
    print(f"{'routine'.ljust(width)}  " + "  ".join(f"{heading:>9}" + (f"  {heading + ' bound':>9}"
                                                                       if key in bounded else "")
                                                    for key, heading in columns.items()))
    bad = []
    for r in results:
        cells, ok = [], True
        for key in columns:
            tol = r.tolerances.get(key, args.tol)
            error = r.errors[key]
            if error != error:  # (NaN: this column does not check this row)
                cells.append(f"{'—':>9}" + (f"  {'':>9}" if key in bounded else ""))
                continue
            cells.append(f"{error:9.2e}" + (f"  {tol:9.0e}" if key in bounded else ""))
            ok = ok and error <= tol
        flag = "" if ok else "  MISMATCH"
        print(f"{r.role.ljust(width)}  " + "  ".join(cells) + flag)
        if flag:
            bad.append(r.role)
    others = " or ".join(heading for key, heading in columns.items() if key not in bounded)
    if bad:
        print(f"mismatch ({'a column beyond its bound or ' + others + ' ' if bounded and others else ''}"
              f"> {args.tol:g}) in: {', '.join(bad)}", file=sys.stderr)
        return 1
    floats = ", ".join(heading for key, heading in columns.items() if key in bounded)
    bound = "its float bound" if args.scalar == "float" else "its bound"
    print(f"ok: every routine within {bound + ' (' + floats + ') and ' if bounded else ''}{args.tol:g}"
          + (f" ({others})" if bounded and others else ""))
    return 0


def cmd_ops(args) -> int:
    from .codegen.generate import generate
    from .codegen.ops import ops_table

    model = _load(args).model
    gen = generate(model, scalar=args.scalar, targets="manifest")  # (the counts: the C's, printed for any target)
    print(ops_table(model.name, model.nv, {r.routine.role: r.ops for r in gen.routines}))
    return 0


COMMANDS = {"generate": cmd_generate, "latex": cmd_latex, "check": cmd_check, "ops": cmd_ops}


def _show_warning(message, category, filename, lineno, file=None, line=None):
    print(f"aggsym: warning: {message}", file=sys.stderr)


def _bare_floating_base(argv: list) -> list:
    """``--floating-base`` not followed by its kind means ``euler`` (so that ``--floating-base robot.urdf`` does
    not read the model's path as the kind)."""
    out = list(argv)
    for i, a in enumerate(out):
        if a == "--floating-base" and (i + 1 == len(out) or out[i + 1] not in FLOATING_BASE_KINDS):
            out[i] = "--floating-base=euler"
    return out


def _joined_opt(argv: list) -> list:
    """``--opt -O1`` as ``--opt=-O1``: argparse reads a value that starts with a dash as an option and would stop
    with "expected one argument", although the usage line shows these values."""
    out, i = [], 0
    while i < len(argv):
        if argv[i] == "--opt" and i + 1 < len(argv) and argv[i + 1] in OPT_LEVELS:
            out.append(f"--opt={argv[i + 1]}")
            i += 2
            continue
        out.append(argv[i])
        i += 1
    return out


def main(argv=None) -> int:
    warnings.showwarning = _show_warning
    args = _parser().parse_args(_joined_opt(_bare_floating_base(sys.argv[1:] if argv is None else argv)))
    try:
        return COMMANDS[args.command](args)
    except AggsymError as exc:
        print(f"aggsym: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("aggsym: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # an internal error: short message, traceback on request
        if os.environ.get("AGGSYM_DEBUG"):
            raise
        print(f"aggsym: internal error: {exc.__class__.__name__}: {exc}\n"
              f"aggsym: this is a bug in aggsym, not in your model: please report it with the model file and the "
              f"command (AGGSYM_DEBUG=1 shows the traceback)", file=sys.stderr)
        return 3


if __name__ == "__main__":
    sys.exit(main())
