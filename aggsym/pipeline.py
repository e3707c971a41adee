"""From a model file to the model that code is generated from: one ordered list of steps, one table of options.

``aggsym generate robot.urdf --floating-base quaternion --armature 0.01 --routines ...`` and
``aggsym.load("robot.urdf", floating_base="quaternion", armature=0.01, routines=[...])`` run the same steps, in
the order of :data:`OPTIONS`:

1. the file's reader, chosen once (:func:`~aggsym.model.readers.registry.reader_for`; a shared suffix such as
   ``.xml`` sniffed once), refusing the options it does not accept, and the options checked against each other;
2. the reader's own options (floating base, mimic joints, snapping, xacro arguments and packages, MuJoCo's
   frictionloss) go to its ``load``;
3. the generated code's name: ``name``, else the file's own name (a YAML model's ``name:``);
4. the transforms, each one module of :mod:`aggsym.model.transforms` or a side file: constraints, support,
   inertial parameters and payloads, gravity as a parameter, passive forces included, the frames, the armature;
5. the routine selection last (:func:`aggsym.contract.select_routines`), so that it judges the model every other
   option made (A regular with the armature, say).

:data:`OPTIONS` is also what the command line's model options are built from (``aggsym.cli``) and what says which
readers take an option: a reader takes the options its ``load`` names (:attr:`Reader.options`) and those the table
gives it.  :func:`prepare` returns the model with its reader and where its name came from (for the messages about
a name too long for the file system).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .collector import collector_paused
from .errors import AggsymError

FLOATING_BASE_KINDS = ("euler", "quaternion")  # floating_base: a kind, or True for euler
TREE_READERS = ("URDF", "xacro")  # the readers of a tree of links and joints with URDF's options
LINK_READERS = ("URDF", "xacro", "MJCF")  # the readers whose bodies are named links (side files, inertials)


@dataclass(frozen=True)
class Option:
    """One model option: ``name`` its keyword of :func:`load`, ``flag`` its command-line spelling, ``help`` what it
    does, ``default`` its value when not given, ``readers`` the readers that take it (None: every model; READ: the
    readers whose ``load`` names it), ``cli`` argparse's keywords (choices, metavar, type, action) and ``from_cli``
    the value :func:`load` takes from argparse's."""

    name: str
    flag: str
    help: str
    default: object = None
    readers: object = None
    cli: dict = dataclasses.field(default_factory=dict)
    from_cli: Callable = None  # (None: the value as argparse gives it)

    def __post_init__(self):
        if self.from_cli is None:
            object.__setattr__(self, "from_cli", _as_given)

    def given(self, value) -> bool:
        """Whether ``value`` asks for something (not the default, None, False or an empty list)."""
        return value is not None and value is not False and value != self.default and value not in ([], {}, ())


READ = "read"  # Option.readers: the readers whose load takes the option


def _as_given(value):
    return value


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"{text!r} is not a number") from None


def armature_value(value) -> float:
    """A rotor inertia on every coordinate: a finite number >= 0 (ValueError with the reason otherwise)."""
    value = _number(value) if isinstance(value, str) else float(value)
    if not (0.0 <= value < math.inf):
        raise ValueError(f"{value!r}: the armature is a finite number >= 0")
    return value


def snap_tolerance(value) -> float:
    """The tolerance of ``snap_angles``: an angle in radians in (0, pi/4)."""
    value = _number(value) if isinstance(value, str) else float(value)
    if not (0.0 < value < math.pi / 4):
        raise ValueError(f"{value!r}: the tolerance is an angle in radians, above 0 and below pi/4 (e.g. 1e-4)")
    return value


def xacro_arg(text: str) -> tuple:
    """``NAME:=VALUE`` as (NAME, VALUE)."""
    name, sep, value = text.partition(":=")
    if not sep or not name.strip():
        raise ValueError(f"{text!r}: expected NAME:=VALUE")
    return name.strip(), value


def package_path(text: str) -> tuple:
    """``PKG=DIR`` as (PKG, DIR)."""
    name, sep, folder = text.partition("=")
    if not sep or not name.strip() or not folder:
        raise ValueError(f"{text!r}: expected PKG=DIR")
    return name.strip(), folder


def names(value) -> list:
    """A list of names from a comma-separated text or an iterable of them (blanks dropped)."""
    items = value.split(",") if isinstance(value, str) else list(value)
    return [str(x).strip() for x in items if str(x).strip()]


OPTIONS = (
    Option("floating_base", "--floating-base", readers=READ, cli={"choices": FLOATING_BASE_KINDS},
           help="a free root. euler (the default when no kind is given): the 6-coordinate pair o1 o2 o3 theta4 "
                "theta5 theta6; quaternion: Pinocchio's free-flyer, q = (x, y, z, qx, qy, qz, qw, joints) "
                "(nq = n + 7), velocities (v, w of the base in its own axes, joint rates) (nv = n + 6)"),
    Option("mimic", "--mimic", default="independent", readers=READ, cli={"choices": ["independent", "couple"]},
           help="<mimic> joints keep their own coordinate (default) or follow their master"),
    Option("snap_angles", "--snap-angles", default=0.0, readers=READ, cli={"metavar": "TOL", "type": snap_tolerance},
           help="an approximation on request (off by default): take the rpy angles of the file's origins within TOL "
                "rad of a multiple of pi/2 as that multiple (1.5708 -> pi/2); every angle it moves is listed in the "
                "manifest's 'snapped_angles'"),
    Option("xacro_args", "--xacro-arg", readers=READ, from_cli=dict,
           cli={"metavar": "NAME:=VALUE", "action": "append", "type": xacro_arg, "default": []},
           help="the value of the file's <xacro:arg name=NAME> (repeat for several)"),
    Option("package_paths", "--package-path", readers=READ, from_cli=dict,
           cli={"metavar": "PKG=DIR", "action": "append", "type": package_path, "default": []},
           help="$(find PKG) is DIR, and files there may be included (repeat for several; else the folders of "
                "ROS_PACKAGE_PATH)"),
    Option("root", "--model-root", readers=READ, cli={"metavar": "DIR"},
           help="the folder inside which every file the model names must lie (MJCF includes, attached models, "
                "meshes, textures, height fields; xacro includes and load_yaml): default the model's own folder; a "
                "folder above it for a scene library that shares files between folders (symbolic links followed)"),
    Option("frictionloss", "--frictionloss", readers=READ, cli={"choices": ["list", "coulomb"]},
           help="MuJoCo's frictionloss (a constraint in MuJoCo) is listed in the manifest and left out of the "
                "equations (list, the default), or taken as Coulomb friction f sign(qd) on the left side of forward "
                "and inverse dynamics and in passive_forces (coulomb: runtime parameters friction_<coordinate>, "
                "tendon_friction_<tendon>; not conservative)"),
    Option("name", "--name", cli={"metavar": "NAME"},
           help="the name of the generated code (C prefix, module and file names); default: the model file's name "
                "without its suffix (a YAML model's 'name:' where it gives one)"),
    Option("constraints", "--constraints", readers=LINK_READERS, cli={"metavar": "FILE"},
           help="a YAML side file with the robot's 'constraints:' (contacts with the world, closed loops; bodies "
                "named by URDF link) and 'stabilization:'"),
    Option("support", "--support", default=False, readers=TREE_READERS, cli={"action": "store_true"},
           help="with --floating-base: the free root is the support of the support equation (3.1); its 6 "
                "coordinates are q, the joints gamma (support_* routines)"),
    Option("inertial_parameters", "--inertial-parameters", readers=LINK_READERS, cli={"metavar": "all|LINK,..."},
           help="the named links' inertial data (or every link's: all) become entries of p, ten per link (m, m c, "
                "inertia about the link origin in link axes; defaults from the file)"),
    Option("payload", "--payload", readers=LINK_READERS, cli={"metavar": "LINK[,LINK...]"},
           help="a payload fixed to LINK, its ten inertial parameters in p (zero by default; several links: a "
                "payload on each), and a helper NAME_set_payload_<LINK> that writes them from mass, centre of mass "
                "and inertia about it"),
    Option("gravity_parameter", "--gravity-parameter", default=False, readers=TREE_READERS,
           cli={"action": "store_true"},
           help="the gravity vector becomes the last three entries of p (gravity_x, gravity_y, gravity_z, m/s^2 in "
                "the root frame; default the file's (0, 0, -9.81)), for a wall- or ceiling-mounted robot without "
                "generating again"),
    Option("passive", "--passive", readers=TREE_READERS, cli={"choices": ["exclude", "include"]},
           help="the joints' <dynamics damping friction> in forward and inverse dynamics: exclude (default; as "
                "Pinocchio: they are in p and in joint_friction, the header says so) or include (A qdd + b + g + D "
                "qd + F sign(qd) = tau; the manifest's conservative is false)"),
    Option("frames", "--frames", cli={"metavar": "A,B,..."},
           help="the frames of the frame routines, in this order: URDF link names, or a YAML model's bodies and "
                "'frames:' (default: the links or bodies without a child, then 'frames:')"),
    Option("armature", "--armature", default=0.0, cli={"metavar": "VALUE", "type": armature_value},
           help="add a rotor inertia VALUE (kg m^2, or kg for a prismatic joint) on every coordinate, as "
                "Pinocchio's armature: A(q) + VALUE E (makes A regular where a joint moves no mass)"),
    Option("routines", "--routines", cli={"metavar": "A,B,..."},
           help="emit only these routines (names as --list-routines shows them, without the model's prefix, or "
                "with it as it prints them; 'default': those emitted when none are named; 'all': every routine, "
                "with those on request: derivatives, regressor, friction_regressor)"),
)
BY_NAME = {o.name: o for o in OPTIONS}


def takers(option: Option) -> list | None:
    """The names of the readers that take ``option``, in registry order (None: every model)."""
    from .model.readers.registry import READERS

    if option.readers is None:
        return None
    if option.readers == READ:
        return [r.name for r in READERS if option.name in r.options]
    return [r.name for r in READERS if r.name in option.readers]


def accepts(reader, option: Option) -> bool:
    """Whether ``reader`` takes ``option``."""
    who = takers(option)
    return who is None or reader.name in who


@dataclass(frozen=True)
class Prepared:
    """What :func:`prepare` returns: the ``model`` to generate from, its ``reader`` and ``name_origin``, where the
    generated code's name came from (None: the model's own name, :func:`aggsym.codegen.generate.name_origin`)."""

    model: object
    reader: object
    name_origin: str | None


def load(path, **options):
    """The model of the file ``path`` with the options applied, as ``aggsym generate`` generates from (its
    options by their keywords: ``floating_base="quaternion"``, ``armature=0.01``, ``routines=["inertia"]``,
    ``frames="tool0,base"``, ...; see :data:`OPTIONS`)."""
    return prepare(path, **options).model


@collector_paused()
def prepare(path, **options) -> Prepared:
    """The steps of the module's text on the file ``path``; an unknown option is a TypeError, an option the
    file's reader does not take or that contradicts another an :class:`AggsymError` (exit 2)."""
    from .model.readers.registry import listing, reader_for

    path = Path(path)
    reader = reader_for(path)
    unknown = sorted(set(options) - set(BY_NAME) - set(reader.options))  # (a reader may take options of its own)
    if unknown:
        raise TypeError(f"unknown model option{'s' if len(unknown) > 1 else ''} {', '.join(unknown)}; the options "
                        f"are {', '.join(BY_NAME)}")
    given = {name: value for name, value in options.items() if name not in BY_NAME or BY_NAME[name].given(value)}
    refused = [BY_NAME[name] for name in given if name in BY_NAME and not accepts(reader, BY_NAME[name])]
    if refused:
        able = [r for r in _readers() if all(accepts(r, o) for o in refused)]
        why = [f"{listing(r.name for r in able)} models only"] if able else []
        why += [reader.note] if reader.note else []
        raise AggsymError(f"{path}: the {reader.name} reader does not accept {listing(o.flag for o in refused)}"
                          + (f" ({'; '.join(why)})" if why else ""))
    _check_together(path, given)
    model = reader.load(path, **{k: v for k, v in given.items() if k in reader.options})
    model, origin = _named(model, path, reader, given.get("name"))
    for step in STEPS:
        model = step(model, path, given)
    return Prepared(model, reader, origin)


def _readers():
    from .model.readers.registry import READERS

    return READERS


def _check_together(path: Path, given: dict) -> None:
    base = given.get("floating_base")
    if given.get("support") and not base:
        raise AggsymError(f"{path}: --support needs --floating-base (the support is the free root)")
    if given.get("support") and base == "quaternion":
        raise AggsymError(f"{path}: --support takes the Euler base (--floating-base euler): the support equation "
                          f"(3.1) is written in the support's six coordinates, which a quaternion base does not have")
    if given.get("mimic") == "couple" and base == "quaternion":
        raise AggsymError(f"{path}: --mimic couple with --floating-base quaternion is not supported; use "
                          f"--floating-base euler, or independent mimic joints")


def _named(model, path: Path, reader, name):
    """(model, origin): the model named ``name`` (``--name``), else after its file (``laikago_toes.urdf`` writes
    ``laikago_toes.h``, whatever its ``<robot name>``), made an identifier, with ``_model`` after a name that is a C
    keyword, a C library name or a Python module (``floor.xml`` writes ``floor_model.h``, with a warning); a YAML
    model keeps its ``name:`` (origin None: the file's own name unless it says otherwise)."""
    from .codegen.escape import check_c_identifier, check_module_name

    if name is not None:
        problem = check_c_identifier(name) or check_module_name(name)
        if problem:
            raise AggsymError(f"--name: {problem}")
        return dataclasses.replace(model, name=name), "the option --name"
    if reader.name == "YAML":
        return model, None
    from .model.readers.builder import mangle
    from .model.readers.registry import known_suffixes

    stem = path.name
    while Path(stem).suffix.lower() in known_suffixes() and Path(stem).stem:  # (robot.urdf.xacro: robot)
        stem = Path(stem).stem
    name = mangle(stem, "model")
    problem = check_c_identifier(name) or check_module_name(name)
    if problem:
        suffixed = f"{name}_model"  # (a keyword, a C library function, a Python module: the suffix makes a name)
        if check_c_identifier(suffixed) or check_module_name(suffixed):
            raise AggsymError(f"{path}: the generated code is named after the file, and {problem}; give it a name "
                              f"with --name NAME")
        import warnings

        from .errors import ModelWarning
        warnings.warn(ModelWarning(f"{path}: the generated code is named after the file, and {problem}: it is named "
                                   f"{suffixed!r} instead (--name NAME gives another)"), stacklevel=2)
        name = suffixed
    return dataclasses.replace(model, name=name), f"{path} (the file's name; --name NAME gives another)"


def _constraints(model, path, given):
    if not given.get("constraints"):
        return model
    from .model.readers.side_files import load_constraints

    return load_constraints(given["constraints"], model)


def _support(model, path, given):
    if not given.get("support"):
        return model
    from .model.readers.validate import support_problem

    root = model.bodies[0].name
    problem = support_problem(model, root)
    if problem:
        raise AggsymError(f"{path}: --support: {problem}")
    return dataclasses.replace(model, support=root)


def _inertials(model, path, given):
    links, payload = given.get("inertial_parameters"), given.get("payload")
    if links is None and payload is None:
        return model
    from .model.transforms.inertials import with_inertial_parameters

    payloads = None if payload is None else names(payload)
    if payloads == []:
        raise AggsymError(f"{path}: --payload: no link named (e.g. --payload tool0)")
    return with_inertial_parameters(model, names(links or ""), payloads)


def _gravity(model, path, given):  # (after the inertial parameters: p keeps their indices, gravity comes last)
    if not given.get("gravity_parameter"):
        return model
    from .model.transforms.gravity import with_gravity_parameters

    return with_gravity_parameters(model)


def _passive(model, path, given):
    if given.get("passive") != "include":
        return model
    from .model.transforms.joint_dynamics import with_passive_included

    return with_passive_included(model)


def _frames(model, path, given):
    if given.get("frames") is None:
        return model
    from .model.transforms.frames import select_frames

    return select_frames(model, names(given["frames"]))


def _armature(model, path, given):
    if not given.get("armature"):
        return model
    try:
        value = armature_value(given["armature"])
    except (TypeError, ValueError) as exc:
        raise AggsymError(f"{path}: --armature: {exc}") from None
    return dataclasses.replace(model, armature=value)


def _routines(model, path, given):  # (last: it judges the model every other option made)
    if given.get("routines") is None:
        return model
    from .contract import select_routines

    return select_routines(model, names(given["routines"]))


STEPS = (_constraints, _support, _inertials, _gravity, _passive, _frames, _armature, _routines)
