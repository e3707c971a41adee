"""What a target is: one output of ``aggsym generate`` (C, NumPy, LaTeX, the manifest, ...).

A target has a name (``--targets NAME``), the files it writes, how a routine's straight-line program is printed
into it (:meth:`Target.print_routine`, once per routine while its program is at hand), how its files are
rendered from the templates (:meth:`Target.render`), which earlier files are its own (:meth:`Target.owns`, for
the stale files of a re-generation) and how its output is checked (:meth:`Target.runner`, for
``aggsym check``; None: nothing to run).  The registry (:mod:`aggsym.codegen.targets`) holds one of each.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from importlib.resources import files

import jinja2

from ..escape import FILTERS


@dataclass
class Job:
    """What the targets of one generation render from.

    ``model``; ``ctx`` the templates' common context;
    ``emitted`` the routines (:class:`~aggsym.codegen.emit.EmittedRoutine`, in order); ``prog`` and
    ``outputs`` the straight-line program and {role: flat outputs}; ``lines`` {role: straight line} of the roles
    a target asked for (:attr:`Target.lines`); ``split``, ``scalar``, ``omitted`` as given to
    :func:`~aggsym.codegen.generate.generate`; ``targets`` the chosen targets; ``names`` every file this
    generation writes, in order."""

    model: object
    ctx: dict
    emitted: list
    prog: object
    outputs: dict
    lines: dict
    split: bool
    scalar: str
    omitted: dict
    targets: list
    names: list = field(default_factory=list)

    def chosen(self, name: str) -> bool:
        return any(t.name == name for t in self.targets)


class Target:
    """One output.  Subclasses set :attr:`name` and define :meth:`file_names` and :meth:`render`; the rest is
    optional."""

    name: str = ""
    default: bool = False  # part of the default set of ``aggsym generate`` (the built-in four)
    stage: str = "templates"  # the progress line its rendering is timed under
    column: str = ""  # its heading in ``aggsym check``'s table (with a :meth:`runner`)
    checked_by_default: bool = True  # ``aggsym check`` without --targets generates and runs it (where it can)
    folder: str = ""  # its templates' folder in the package data aggsym.templates (templates/FOLDER)
    templates: tuple = ()  # the templates it renders from that folder (documentation; layout only)
    lines: frozenset = frozenset()  # the roles whose straight lines it needs at rendering (Job.lines)

    def template(self, name: str) -> jinja2.Template:
        """Its template ``name`` from its own folder (:attr:`folder`)."""
        env = self.__dict__.get("_env")
        if env is None:
            env = self.__dict__["_env"] = environment(files("aggsym.templates") / self.folder)
        return env.get_template(name)

    def file_names(self, job: Job) -> list:
        """The files it writes for this generation, in order."""
        raise NotImplementedError

    def owns(self, name: str, file: str) -> bool:
        """Whether ``file`` (a name found in an earlier manifest) is of a form this target writes for the model
        ``name``: only such files are ever removed as stale."""
        return False

    def print_routine(self, model, prog, lines, emitted):
        """This target's text of one routine (``lines``: the routine's :class:`RoutineLines`; ``emitted`` the
        :class:`~aggsym.codegen.emit.EmittedRoutine` so far), kept by the emission as ``emitted.bodies[self.name]``
        for :meth:`render`; None: nothing (the target renders from the emitted routines alone)."""

    def render(self, job: Job) -> dict:
        """{file name: text} of its files."""
        raise NotImplementedError

    def main_file(self, name: str) -> str | None:
        """The file whose presence among generated files says this target was generated (for ``check``)."""
        return None

    def unavailable(self) -> str | None:
        """Why its output cannot be run here (e.g. no compiler, a framework that does not import), or None."""
        return None

    def runners(self, model, folder, manifest: dict, opt: str) -> dict:
        """{key: (column heading, :class:`Runner`)} of ``aggsym check``'s columns for this target: its
        :meth:`runner` under its :attr:`column`, or several (the kernels: JAX and PyTorch, float64 and float32)."""
        runner = self.runner(model, folder, manifest, opt)
        return {} if runner is None else {self.name: (self.column, runner)}

    def runner(self, model, folder, manifest: dict, opt: str):
        """A :class:`Runner` calling its generated code written in ``folder``, or None: nothing to run.
        ``opt`` the optimisation level of a compile; built of :mod:`aggsym.codegen.compile` (compiling, calling,
        importing)."""
        return None


@dataclass
class Runner:
    """A target's generated code, callable: ``call(role, *args)`` returns the outputs (one array, or a tuple)
    and raises numpy.linalg.LinAlgError where the routine reports a singular system.  ``bounds``: {role: its
    own error bound} (float C), ``per_condition``: the roles whose error is also relative to cond(A); ``jacobian``:
    where the target differentiates (the kernels' modules), the derivatives it gives of a routine's first output
    (None for a routine it does not differentiate), held to central differences of the numeric twin."""

    call: object
    bounds: dict = field(default_factory=dict)
    per_condition: tuple = ()
    jacobian: object = None  # (role, *args) -> the derivatives of its first output along each array argument, or None


@dataclass
class RoutineLines:
    """One routine's straight line as every target prints it: ``sl`` the straight line, ``names`` node id →
    name, ``outputs`` its flat outputs, ``zeros`` the output steps written as chunks of zeros, ``trig`` the sin
    and cos temps, ``shared`` {node id or (output, entry): text} the C printed that other infix targets may
    print alike (no function call; double C), ``complete`` whether ``shared`` holds every such text."""

    sl: object
    names: dict
    outputs: list
    zeros: dict
    trig: dict
    shared: dict
    complete: bool


def file_pattern(name: str, suffixes) -> re.Pattern:
    """NAME.suffix for the given suffixes (without dots)."""
    return re.compile(rf"{re.escape(name)}\.({'|'.join(re.escape(s) for s in suffixes)})")


def environment(root=None) -> jinja2.Environment:
    """A Jinja environment over the folder ``root`` (default: the package data ``aggsym.templates``,
    ``templates/``), with StrictUndefined and the escaping filters of :mod:`aggsym.codegen.escape` (user
    text reaches a template only through them).  A target's templates are in a folder of their own there
    (:meth:`Target.template`)."""
    root = files("aggsym.templates") if root is None else root
    env = jinja2.Environment(
        loader=jinja2.FunctionLoader(lambda name: (root / name).read_text(encoding="utf-8")),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
        autoescape=False,
    )
    env.filters.update(FILTERS)
    return env
