"""The xacro reader: a ``.xacro`` file expanded by the ``xacro`` package (PyPI, no ROS needed), then read by the
URDF reader with all its options.

* ``xacro_args`` ({name: value}, the command line's ``--xacro-arg NAME:=VALUE``) are the file's ``<xacro:arg>``
  values; ``package_paths`` ({package: folder}, ``--package-path PKG=DIR``) resolve ``$(find pkg)``, then the
  folders of the ``ROS_PACKAGE_PATH`` environment variable (a folder that is the package, holds it as a
  subfolder, or holds ``share/<pkg>``; ament's and rospkg's indexes are not consulted).
* Errors (a missing argument, an unknown macro, a bad ``$(find)``, malformed XML, an expression refused below)
  are :class:`ModelError` naming the xacro file being read when it happened (an included one where the error is
  there), the line where xacro knows it (XML syntax errors), and the macros being expanded.  An error of the
  expanded URDF names the xacro file and the line of the expanded document.

What a file may do (the xacro package's own rules, narrowed here)
-----------------------------------------------------------------
xacro evaluates ``${...}`` with Python's ``eval`` over a table of its own: no builtins, names starting with ``__``
refused, and exposed the functions list dict map len str float int bool min max round sorted range, a ``python``
namespace (abs all any complex divmod enumerate filter frozenset hash isinstance issubclass ord repr reversed set
slice sum tuple type vars zip), ``math`` and an ``xacro`` namespace (``load_yaml`` reading any file,
``abs_filename``, messages).  ``$(eval ...)`` is another ``eval`` (math, ``find``, ``env``, ``optenv``, ``arg``,
text containing ``__`` refused).  That is not a sandbox: ``python.vars(python.type)`` reaches ``__subclasses__``
through a string key, and ``'{0.__globals__}'.format(f)`` walks attributes inside a string; both let a file run
code or read what it should not.  So here:

* every expression (``${...}`` and ``$(eval ...)``) is parsed first and refused when it names a name or an
  attribute starting with ``_``, or an attribute of :data:`DENIED` (string formatting, frame and code objects,
  ``mro``); ``python.type`` and ``python.vars`` are removed from the table (:data:`REMOVED`);
* every file read (the model, ``<xacro:include>``, ``xacro.load_yaml``) must lie inside the model root (the
  model's folder, or ``--model-root``: :mod:`.model_root`) or a package folder (``--package-path``, ``ROS_PACKAGE_PATH``), after following links; it is at most
  :data:`MAX_BYTES`, and a document type declaring entities or naming an external DTD is refused, as the URDF
  reader does;
* ``$(env VAR)``, ``$(optenv VAR default)`` and ``$(cwd)`` stay allowed (they read the environment, no file).

The package keeps module-level state and offers no hooks for the file reader, ``find`` or the evaluator, so
:func:`_hooks` replaces ``xacro.parse``, ``xacro.safe_eval`` and the ``find``/``eval`` of
``xacro.substitution_args`` for the duration of one expansion (under a lock) and restores them after, also on
error.  Expansion is not bounded in time or memory beyond the file sizes: a macro that calls itself stops at
Python's recursion limit (an error); one that doubles its output at each level can still take long.
"""
from __future__ import annotations

import ast
import contextlib
import io
import os
import threading
import warnings
from pathlib import Path
from xml.parsers import expat

from ...errors import ModelError, ModelWarning
from .model_root import ModelRoot

MAX_BYTES = 16 * 2 ** 20  # the largest xacro file (or included file) read
REMOVED = frozenset({"type", "vars"})  # taken out of the package's ``python`` namespace
DENIED = frozenset({"format", "format_map", "mro", "gi_frame", "gi_code", "gi_yieldfrom", "cr_frame",
                    "cr_code", "cr_await", "ag_frame", "ag_code", "f_globals", "f_locals", "f_builtins", "f_back",
                    "f_code", "tb_frame", "tb_next", "co_consts"})  # attributes an expression may not name
_LOCK = threading.Lock()


class _Refused(Exception):
    """An expression or a file refused here (reported as the model's error)."""


def check_expression(text: str) -> None:
    """Refuse an expression naming a name or attribute that starts with ``_``, or an attribute in :data:`DENIED`
    (a bare name can only be the file's own or the table's: no builtins)."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError:
        return  # (the package reports its own syntax error)
    for node in ast.walk(tree):
        attribute = isinstance(node, ast.Attribute)
        name = node.attr if attribute else node.id if isinstance(node, ast.Name) else None
        if name is not None and (name.startswith("_") or (attribute and name in DENIED)):
            raise _Refused(f"the expression {text.strip()[:80]!r} uses {name!r}, which is refused here (it could "
                           f"let a file run code or read files; see the xacro section of aggsym's docs/urdf.md)")


def check_file(path: str, roots: list, bounds: ModelRoot | None = None) -> str:
    """``path`` resolved, when it lies inside one of ``roots`` (the model root ``bounds`` first, then the package
    folders); else :class:`_Refused` naming the ``--model-root`` that would admit it."""
    real = Path(path).resolve()
    if not any(real == root or root in real.parents for root in roots):
        shown = ", ".join(str(r) for r in roots)
        link = "" if Path(os.path.abspath(path)) == real else f" (through a symbolic link: {os.path.abspath(path)})"
        hint = f"; or {bounds.hint(str(real))}" if bounds is not None else ""
        named = "the model root" if bounds is not None and bounds.given else "the model's folder"
        raise _Refused(f"the file {path} resolves to {real}{link}, outside {named} and the package folders "
                       f"({shown}); only files there are read (give the package's folder with --package-path "
                       f"PKG=DIR{hint})")
    return str(real)


def _read(path: str) -> bytes:
    with open(path, "rb") as f:
        data = f.read(MAX_BYTES + 1)
    if len(data) > MAX_BYTES:
        raise _Refused(f"{path} is larger than {MAX_BYTES // 2 ** 20} MiB (the limit guards against files made to "
                       f"exhaust memory)")
    parser = expat.ParserCreate()
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)

    def entity(name, *args):
        raise _Refused(f"{path}: an entity declaration (<!ENTITY {name} ...>) is refused; entities are never "
                       f"expanded")

    def doctype(name, system_id, public_id, has_internal_subset):
        if system_id or public_id:
            raise _Refused(f"{path}: a document type naming an external DTD is refused; nothing outside is read")

    parser.EntityDeclHandler = entity
    parser.UnparsedEntityDeclHandler = entity
    parser.StartDoctypeDeclHandler = doctype
    parser.ExternalEntityRefHandler = lambda *args: entity("(external)")
    parser.Parse(data, True)  # (an ExpatError: the package's own parse reports it again, with its line)
    return data


def find_package(name: str, package_paths: dict) -> str:
    """The folder of package ``name``: ``package_paths`` first, then the folders of ``ROS_PACKAGE_PATH``."""
    if name in package_paths:
        return str(Path(package_paths[name]).resolve())
    searched = [p for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    for folder in searched:
        base = Path(folder)
        for candidate in (base, base / name, base / "share" / name):
            if candidate.name == name and candidate.is_dir():
                return str(candidate.resolve())
    given = ", ".join(sorted(package_paths)) or "none"
    raise _Refused(f"$(find {name}): package {name!r} not found (--package-path gives: {given}; ROS_PACKAGE_PATH: "
                   f"{os.pathsep.join(searched) or 'not set'}); give --package-path {name}=DIR")


def roots_of(path: Path, package_paths: dict, bounds: ModelRoot | None = None) -> list:
    """The folders whose files an expansion may read: the model root (``bounds``; default the model's folder),
    the package folders given, those of ``ROS_PACKAGE_PATH``."""
    bounds = bounds or ModelRoot.of(path)
    roots = [Path(bounds.folder)] + [Path(d).resolve() for d in package_paths.values()]
    roots += [Path(p).resolve() for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    return roots


@contextlib.contextmanager
def _hooks(xacro, roots: list, package_paths: dict, bounds: ModelRoot):
    """The package's file reader, evaluator and ``find`` replaced for one expansion (restored after)."""
    from xacro import substitution_args as sa

    saved = (xacro.parse, xacro.safe_eval, sa._eval_find, sa._eval, sa._eval_dict.get("find"))
    parse, safe_eval, _, sa_eval, _ = saved

    def checked_parse(inp, filename=None):
        if inp is None:  # a file: the model or an include
            real = check_file(os.path.join(xacro.root_dir, filename), roots, bounds)
            try:
                data = _read(real)
            except OSError as e:  # (as the package's parse reports it: an optional include may be absent)
                xacro.filestack.pop()
                raise xacro.XacroException(f"{e.strerror}: {filename}", exc=e) from None
            return parse(data.decode("utf-8"), filename)
        return parse(inp, filename)

    def checked_eval(expr, globals, locals=None):
        check_expression(expr)
        return safe_eval(expr, globals, locals)

    def checked_sa_eval(s, context):
        check_expression(s)
        return sa_eval(s, context)

    def find(name):
        return find_package(name, package_paths)

    xacro.parse, xacro.safe_eval, sa._eval_find, sa._eval = checked_parse, checked_eval, find, checked_sa_eval
    sa._eval_dict["find"] = find
    try:
        yield
    finally:
        xacro.parse, xacro.safe_eval, sa._eval_find, sa._eval = saved[:4]
        sa._eval_dict["find"] = saved[4]


def _symbols(xacro, roots: list, bounds: ModelRoot):
    """The package's global table without ``type`` and ``vars``, its ``load_yaml`` reading only inside ``roots``."""
    table = dict(xacro._global_symbols)
    python = xacro.NameSpace()
    python.update({k: v for k, v in table["python"].items() if k not in REMOVED})
    namespace = xacro.NameSpace()
    namespace.update(table["xacro"])
    load = namespace["load_yaml"]

    def load_yaml(filename):
        check_file(xacro.abs_filename_spec(filename), roots, bounds)
        return load(filename)

    namespace["load_yaml"] = load_yaml
    table.update(python=python, xacro=namespace, load_yaml=load_yaml)
    return xacro.Table(table)


def expand(path, xacro_args=None, package_paths=None, root=None) -> str:
    """The URDF text that ``path`` expands to; a :class:`ModelError` naming the file (and line) on failure.
    ``root``: the model root (``--model-root``; default the file's folder), which bounds the files read with the
    package folders."""
    path = Path(path)
    try:
        import xacro
    except ImportError:
        raise ModelError(path, "", "reading xacro needs the xacro package: pip install 'aggsym[xacro]'") from None
    args = {str(k): str(v) for k, v in (xacro_args or {}).items()}
    packages = {str(k): str(v) for k, v in (package_paths or {}).items()}
    for name, folder in packages.items():
        if not Path(folder).is_dir():
            raise ModelError(path, "", f"--package-path {name}={folder}: no such folder")
    bounds = ModelRoot.of(path, root)
    roots = roots_of(path, packages, bounds)
    stderr = io.StringIO()
    with _LOCK, _hooks(xacro, roots, packages, bounds), contextlib.redirect_stderr(stderr):
        xacro.init_stacks(str(path.resolve()))
        xacro.substitution_args_context["arg"] = args
        try:
            doc = xacro.parse(None, str(path.resolve()))
            xacro.eval_all(doc.documentElement, xacro.Table(), _symbols(xacro, roots, bounds))
            text = doc.toprettyxml(indent="  ")
        except Exception as exc:  # the package's errors are of many kinds (its own, NameError, KeyError, ...)
            raise _model_error(xacro, path, exc) from None
        finally:
            xacro.substitution_args_context["arg"] = {}
    messages: list = []  # the package's messages, each with its location lines ("when processing file: ...")
    for line in (x.strip() for x in stderr.getvalue().splitlines()):
        if line and messages and line.startswith(_LOCATION):
            messages[-1] += f" ({line})"
        elif line:
            messages.append(line)
    for message in messages:
        warnings.warn(f"{path}: xacro: {message}", ModelWarning, stacklevel=2)
    return text


_LOCATION = ("when processing file:", "in file:", "included from:", "when instantiating macro:", "instantiated from:")


def _model_error(xacro, path: Path, exc: Exception) -> ModelError:
    files = [f for f in (xacro.filestack or []) if f]
    where = Path(files[-1]) if files else path
    macros = [m.body.getAttribute("name") for m in (xacro.macrostack or [])]
    line = getattr(exc, "lineno", None) if isinstance(exc, expat.ExpatError) else None
    if isinstance(exc, expat.ExpatError):
        message = f"malformed XML: {expat.ErrorString(exc.code)}"
    elif isinstance(exc, RecursionError):
        message = "the expansion recurses without end (a macro calling itself?)"
    else:
        inner = getattr(exc, "exc", None)
        if isinstance(inner, _Refused) or isinstance(exc, _Refused):
            message = str(inner if isinstance(inner, _Refused) else exc)
        elif isinstance(inner, OSError):
            message = f"cannot read {inner.filename}: {inner.strerror}"
        else:
            message = " ".join(str(exc).split()) or exc.__class__.__name__
            if isinstance(exc, KeyError) or (inner is not None and isinstance(inner, KeyError)):
                message = f"undefined: {message}"
    context = f" (in macro {' <- '.join(repr(m) for m in reversed(macros))})" if macros else ""
    shown = path if where == path.resolve() else f"{where} (included from {path})"
    return ModelError(shown, "", f"xacro: {message}{context}", line)


def load_xacro(path, xacro_args=None, package_paths=None, root=None, **urdf_options):
    """Expand ``path`` (:func:`expand`) and read the URDF it gives (:func:`~.urdf_reader.load_urdf`'s options)."""
    from .urdf_reader import urdf_from_bytes

    text = expand(path, xacro_args, package_paths, root)
    return urdf_from_bytes(Path(path), text.encode("utf-8"), label=f"{path} (expanded by xacro)", **urdf_options)


__all__ = ["DENIED", "REMOVED", "MAX_BYTES", "check_expression", "check_file", "expand", "find_package", "load_xacro"]
