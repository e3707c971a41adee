"""The command line: ``aggsym generate | latex | check | ops MODEL``.

Exit codes: 0 success, 1 generated code disagrees with the numeric twin, 2 bad input (with a message naming
the file, the place in it and the problem; never a traceback).
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
import time
import warnings
from pathlib import Path

from .errors import AggsymError

FLOATING_BASE_KINDS = ("euler", "quaternion")  # --floating-base KIND; bare --floating-base is euler


def _formats() -> str:
    """The readers and their suffixes, for the help (model.readers: one registry)."""
    from .model.readers.registry import READERS

    return ", ".join(f"{r.name}: {' '.join(r.suffixes + r.sniffed)}" for r in READERS)


def _only(option: str, then: str) -> str:
    """The help's opening for an option that only some readers accept ("URDF only" and ``then``), from the
    readers' declarations."""
    from .model.readers.registry import listing, takers

    return f"{listing(takers(option))} only{then}"

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
        p.add_argument("--floating-base", choices=FLOATING_BASE_KINDS, default=None,
                       help=_only("--floating-base", ": ")
                            + "a free root. euler (the default when no kind is given): the 6-coordinate "
                            "pair o1 o2 o3 theta4 theta5 theta6; quaternion: Pinocchio's free-flyer, q = (x, y, z, "
                            "qx, qy, qz, qw, joints) (nq = n + 7), velocities (v, w of the base in its own axes, "
                            "joint rates) (nv = n + 6)"),
        p.add_argument("--mimic", choices=["independent", "couple"], default="independent",
                       help=_only("--mimic", ": ")
                            + "<mimic> joints keep their own coordinate (default) or follow their master")
        p.add_argument("--snap-angles", metavar="TOL", type=_snap_tolerance, default=0.0,
                       help=_only("--snap-angles", ", ")
                            + "an approximation on request (off by default): take the rpy angles of the "
                            "file's origins within TOL rad of a multiple of pi/2 as that multiple (1.5708 -> pi/2); "
                            "every angle it moves is listed in the manifest's 'snapped_angles'")
        p.add_argument("--xacro-arg", metavar="NAME:=VALUE", action="append", type=_xacro_arg, default=[],
                       help=_only("--xacro-arg", ": ") + "the value of the file's <xacro:arg name=NAME> (repeat for "
                            "several)")
        p.add_argument("--package-path", metavar="PKG=DIR", action="append", type=_package_path, default=[],
                       help=_only("--package-path", ": ") + "$(find PKG) is DIR, and files there may be included "
                            "(repeat for several; else the folders of ROS_PACKAGE_PATH)")
        p.add_argument("--frictionloss", choices=["list", "coulomb"], default=None,
                       help=_only("--frictionloss", ": ")
                            + "MuJoCo's frictionloss (a constraint in MuJoCo) is listed in the manifest and left out "
                            "of the equations (list, the default), or taken as Coulomb friction f sign(qd) on the "
                            "left side of forward and inverse dynamics and in passive_forces (coulomb: runtime "
                            "parameters friction_<coordinate>, tendon_friction_<tendon>; not conservative)")
        p.add_argument("--armature", metavar="VALUE", type=_armature, default=0.0,
                       help="add a rotor inertia VALUE (kg m^2, or kg for a prismatic joint) on every coordinate, as "
                            "Pinocchio's armature: A(q) + VALUE E (makes A regular where a joint moves no mass)")
        p.add_argument("--constraints", metavar="FILE",
                       help=_only("--constraints", ": ")
                            + "a YAML side file with the robot's 'constraints:' (contacts with the world, "
                            "closed loops; bodies named by URDF link) and 'stabilization:'")
        p.add_argument("--support", action="store_true",
                       help=_only("--support", ", ")
                            + "with --floating-base: the free root is the support of the support equation "
                            "(3.1); its 6 coordinates are q, the joints gamma (support_* routines)")
        p.add_argument("--inertial-parameters", metavar="all|LINK,...",
                       help=_only("--inertial-parameters", ": ")
                            + "the named links' inertial data (or every link's: all) become entries of p, "
                            "ten per link (m, m c, inertia about the link origin in link axes; defaults from the file)")
        p.add_argument("--payload", metavar="LINK[,LINK...]",
                       help=_only("--payload", ": ")
                            + "a payload fixed to LINK, its ten inertial parameters in p (zero by default; several "
                              "links: a payload on each), and a helper NAME_set_payload_<LINK> that writes them from "
                              "mass, centre of mass and inertia about it")
        p.add_argument("--gravity-parameter", action="store_true",
                       help=_only("--gravity-parameter", ": ")
                            + "the gravity vector becomes the last three entries of p (gravity_x, gravity_y, "
                            "gravity_z, m/s^2 in the root frame; default the file's (0, 0, -9.81)), for a wall- or "
                            "ceiling-mounted robot without generating again")
        p.add_argument("--passive", choices=["exclude", "include"], default=None,
                       help=_only("--passive", ": ")
                            + "the joints' <dynamics damping friction> in forward and inverse dynamics: exclude "
                            "(default; as Pinocchio: they are in p and in joint_friction, the header says so) or "
                            "include (A qdd + b + g + D qd + F sign(qd) = tau; the manifest's conservative is false)")
        p.add_argument("--frames", metavar="A,B,...",
                       help="the frames of the frame routines, in this order: URDF link names, or a YAML model's "
                            "bodies and 'frames:' (default: the links or bodies without a child, then 'frames:')")
        p.add_argument("--routines", metavar="A,B,...",
                       help="emit only these routines (names as --list-routines shows them, without the model's "
                            "prefix, or with it as it prints them; 'default': those emitted when none are named; "
                            "'all': every routine, with those "
                            "on request: derivatives, regressor, friction_regressor)")
        p.add_argument("--name", metavar="NAME",
                       help="the name of the generated code (C prefix, module and file names); default: the model "
                            "file's name without its suffix (a YAML model's 'name:' where it gives one)")
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
                        "manifest (NAME.json), latex (NAME.tex), jax (NAME_jax.py), torch (NAME_torch.py), ext "
                        "(NAME_ext.c, NAME_ext.py: one state per call through the compiled C; with c and numpy); "
                        "default: c, numpy, manifest, latex")
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
                        "and torch where they import; ext when named)")
    command("ops", "operation counts per routine beside the book's tables and Featherstone's counts")
    return parser


def _load(args):
    from .model import load
    from .model.readers.registry import check_cli_options

    path = Path(args.model)
    options = {"floating_base": args.floating_base} if args.floating_base else {}
    if args.mimic != "independent":
        options["mimic"] = args.mimic
    if args.snap_angles:
        options["snap_angles"] = args.snap_angles
    if args.xacro_arg:
        options["xacro_args"] = dict(args.xacro_arg)
    if args.package_path:
        options["package_paths"] = dict(args.package_path)
    if args.frictionloss:
        options["frictionloss"] = args.frictionloss
    given = [flag for flag, value in (("--floating-base", args.floating_base), ("--mimic", "mimic" in options),
                                      ("--xacro-arg", args.xacro_arg), ("--package-path", args.package_path),
                                      ("--snap-angles", args.snap_angles), ("--constraints", args.constraints),
                                      ("--support", args.support),
                                      ("--inertial-parameters", args.inertial_parameters is not None),
                                      ("--payload", args.payload is not None),
                                      ("--frictionloss", args.frictionloss),
                                      ("--gravity-parameter", args.gravity_parameter),
                                      ("--passive", args.passive is not None)) if value]
    reader = check_cli_options(path, given)  # the reader's name and the option it does not accept
    if args.support and not args.floating_base:
        raise AggsymError(f"{path}: --support needs --floating-base (the support is the free root)")
    if args.support and args.floating_base == "quaternion":
        raise AggsymError(f"{path}: --support takes the Euler base (--floating-base euler): the support equation "
                          f"(3.1) is written in the support's six coordinates, which a quaternion base does not have")
    if args.mimic == "couple" and args.floating_base == "quaternion":
        raise AggsymError(f"{path}: --mimic couple with --floating-base quaternion is not supported; use "
                          f"--floating-base euler, or independent mimic joints")
    model = load(path, **options)
    name = _output_name(args, path, reader)
    if name is not None:
        model = dataclasses.replace(model, name=name)
    if args.constraints:
        from .model.readers.yaml_reader import load_constraints

        model = load_constraints(args.constraints, model)
    if args.support:
        from .model.readers.validate import support_problem

        root = model.bodies[0].name
        problem = support_problem(model, root)
        if problem:
            raise AggsymError(f"{path}: --support: {problem}")
        model = dataclasses.replace(model, support=root)
    if args.inertial_parameters is not None or args.payload is not None:
        from .model.transforms.inertials import with_inertial_parameters

        links = [x.strip() for x in (args.inertial_parameters or "").split(",") if x.strip()]
        payloads = None if args.payload is None else [x.strip() for x in args.payload.split(",") if x.strip()]
        if payloads == []:
            raise AggsymError(f"{path}: --payload: no link named (e.g. --payload tool0)")
        model = with_inertial_parameters(model, links, payloads)
    if args.gravity_parameter:  # (after the inertial parameters: p keeps their indices, gravity comes last)
        from .model.transforms.gravity import with_gravity_parameters

        model = with_gravity_parameters(model)
    if args.passive == "include":
        from .model.transforms.joint_dynamics import with_passive_included

        model = with_passive_included(model)
    if args.frames is not None:
        from .model.transforms.frames import select_frames

        model = select_frames(model, [name.strip() for name in args.frames.split(",") if name.strip()])
    if args.routines is not None:
        from .contract import select_routines

        model = select_routines(model, [name.strip() for name in args.routines.split(",") if name.strip()])
    if args.armature:
        model = dataclasses.replace(model, armature=args.armature)
    return model


def _output_name(args, path: Path, reader) -> str | None:
    """The name of the generated code (C prefix, module and file names): ``--name``, else the model file's own
    name without its suffix (``laikago_toes.urdf`` writes ``laikago_toes.h``, whatever its ``<robot name>``),
    made an identifier; None for a YAML model, whose ``name:`` is the file's name unless it says otherwise.
    ``args.name_origin`` records where it came from, for the messages about a name too long."""
    from .codegen.escape import check_c_identifier, check_module_name

    if args.name is not None:
        problem = check_c_identifier(args.name) or check_module_name(args.name)
        if problem:
            raise AggsymError(f"--name: {problem}")
        args.name_origin = "the option --name"
        return args.name
    args.name_origin = None  # (the model's own name: codegen.generate.name_origin says where it is written)
    if reader.name == "YAML":
        return None
    from .model.readers.builder import mangle

    from .model.readers.registry import known_suffixes

    stem = path.name
    while Path(stem).suffix.lower() in known_suffixes() and Path(stem).stem:  # (robot.urdf.xacro: robot)
        stem = Path(stem).stem
    name = mangle(stem, "model")
    problem = check_c_identifier(name) or check_module_name(name)
    if problem:
        raise AggsymError(f"{path}: the generated code is named after the file, and {problem}; give it a name "
                          f"with --name NAME")
    args.name_origin = f"{path} (the file's name; --name NAME gives another)"
    return name


def _armature(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (0.0 <= value < float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r}: the armature is a finite number >= 0")
    return value


def _xacro_arg(text: str) -> tuple:
    name, sep, value = text.partition(":=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"{text!r}: expected NAME:=VALUE")
    return name.strip(), value


def _package_path(text: str) -> tuple:
    name, sep, folder = text.partition("=")
    if not sep or not name.strip() or not folder:
        raise argparse.ArgumentTypeError(f"{text!r}: expected PKG=DIR")
    return name.strip(), folder


def _snap_tolerance(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (0.0 < value < math.pi / 4):
        raise argparse.ArgumentTypeError(f"{text!r}: the tolerance is an angle in radians, above 0 and below pi/4 "
                                         f"(e.g. 1e-4)")
    return value


def _progress(quiet: bool, name: str):
    if quiet:
        return None
    return lambda msg: print(f"aggsym: {name}: {msg}", file=sys.stderr, flush=True)


def _targets(args):
    """The targets named by --targets (None: the default set), before any work: an unknown one is exit 2."""
    if args.targets is None:
        return None
    from .codegen.targets import select

    return [t.name for t in select(args.targets)]


def cmd_generate(args) -> int:
    t0 = time.perf_counter()
    targets = _targets(args)
    model = _load(args)
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
    origin = args.name_origin  # (None: the model's own name, codegen.generate.name_origin)
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

    model = _load(args)
    gen = generate(model, scalar=args.scalar)
    sys.stdout.write(gen.files[f"{model.name}.tex"])
    return 0


def cmd_check(args) -> int:
    from .codegen.compile import check_generated, checked_targets
    from .codegen.generate import generate
    from .codegen.targets import TARGETS

    targets = _targets(args)
    model = _load(args)
    generated = [n for n in (targets or [n for n, t in TARGETS.items() if t.checked_by_default]) if n != "latex"]
    # (the manifest: always, check reads it)
    gen = generate(model, latex=False, scalar=args.scalar, split=args.split,
                   targets=sorted(set(generated) | {"manifest"}))
    checked, skipped = checked_targets(model, gen.files, targets)
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
    single = args.scalar == "float"
    # the float C and the JAX module in float32: each held to its own bounds (its runner's, the manifest's
    # float_tolerance); the others to --tol
    bounded = {name for r in results for name in r.tolerances} if single else set()
    print(f"{model.name}: {args.trials} random states per routine; worst error against the numeric twin, relative "
          f"to the largest value the routine returns"
          + (f"; {' and '.join(t.column for t in checked if t.name in bounded)} in float, held to "
             f"{'its bound' if len(bounded) == 1 else 'their bounds'}" if bounded else ""))
    print(f"{'routine'.ljust(width)}  " + "  ".join(f"{t.column:>9}" + (f"  {t.column + ' bound':>9}"
                                                                        if t.name in bounded else "")
                                                    for t in checked))
    bad = []
    for r in results:
        cells, ok = [], True
        for t in checked:
            tol = r.tolerances.get(t.name, args.tol) if t.name in bounded else args.tol
            cells.append(f"{r.errors[t.name]:9.2e}" + (f"  {tol:9.0e}" if t.name in bounded else ""))
            ok = ok and r.errors[t.name] <= tol
        flag = "" if ok else "  MISMATCH"
        print(f"{r.role.ljust(width)}  " + "  ".join(cells) + flag)
        if flag:
            bad.append(r.role)
    others = " or ".join(t.column for t in checked if t.name not in bounded)
    if bad:
        print(f"mismatch ({'a float target beyond its bound or ' + others + ' ' if bounded and others else ''}"
              f"> {args.tol:g}) in: {', '.join(bad)}", file=sys.stderr)
        return 1
    floats = ", ".join(t.column for t in checked if t.name in bounded)
    print(f"ok: every routine within {'its float bound (' + floats + ') and ' if bounded else ''}{args.tol:g}"
          + (f" ({others})" if bounded and others else ""))
    return 0


def cmd_ops(args) -> int:
    from .codegen.generate import generate
    from .codegen.ops import ops_table

    model = _load(args)
    gen = generate(model, latex=False, scalar=args.scalar)
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
