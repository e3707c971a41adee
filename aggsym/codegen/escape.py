"""The one escaping function per target for user text (names, descriptions, file names) that reaches an output.

Model files come from strangers: a URDF joint called ``*/ #define double float /*`` must stay a comment in C,
a description holding ``\"\"\"; import os`` must stay a string in Python, and ``\\input{/etc/passwd}`` must stay
text in LaTeX.  Templates receive user text only through these functions (registered as Jinja filters
``c_comment``, ``py_str``, ``py_doc``, ``latex``, ``latex_breakable``); identifiers are checked, never escaped
(:func:`check_c_identifier`).
"""
from __future__ import annotations

import keyword
import re
import sys

_PRINTABLE = re.compile(r"[^\x20-\x7e]")

C_KEYWORDS = frozenset((
    "auto break case char const continue default do double else enum extern float for goto if inline int long "
    "register restrict return short signed sizeof static struct switch typedef union unsigned void volatile while "
    "_Bool _Complex _Imaginary asm fortran "
    # C++ keywords: the header is included from C++ too
    "alignas alignof and and_eq bitand bitor bool catch class compl concept consteval constexpr constinit "
    "const_cast co_await co_return co_yield decltype delete dynamic_cast explicit export false friend mutable "
    "namespace new noexcept not not_eq nullptr operator or or_eq private protected public reinterpret_cast "
    "requires static_assert static_cast template this thread_local throw true try typeid typename using virtual "
    "wchar_t xor xor_eq char8_t char16_t char32_t").split())
# names of <math.h> and the C library a generated file may meet as macros or functions
C_RESERVED = frozenset("sin cos tan sqrt exp log fabs asin acos atan atan2 sincos pow floor ceil fmod errno "
                       "assert NULL EOF main abs".split())
_C_IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def _visible(text) -> str:
    """Non-printable and non-ASCII characters as <U+XXXX> (so nothing invisible, bidirectional or multi-byte
    reaches a generated file)."""
    return _PRINTABLE.sub(lambda m: f"<U+{ord(m.group()):04X}>", str(text))


def c_comment(text) -> str:
    """Text safe inside a C block comment: no ``*/`` or ``/*`` (written ``* /``, ``/ *``), no trigraph ``??``,
    no backslash (a line splice), no line breaks or control characters."""
    out = _visible(text).replace("\\", "<backslash>")
    while "*/" in out or "/*" in out or "??" in out:
        out = out.replace("*/", "* /").replace("/*", "/ *").replace("??", "? ?")
    return out


def py_str(text) -> str:
    """A Python string literal of the text (its repr, ASCII only)."""
    return ascii(str(text))


def py_doc(text) -> str:
    """Text safe inside a triple-quoted Python docstring: backslashes doubled, quotes escaped, non-ASCII and
    control characters shown as <U+XXXX>."""
    return _visible(text).replace("\\", "\\\\").replace('"', '\\"')


_LATEX = {"\\": r"\textbackslash{}", "{": r"\{", "}": r"\}", "$": r"\$", "&": r"\&", "#": r"\#", "^": r"\^{}",
          "_": r"\_", "%": r"\%", "~": r"\~{}"}


def latex(text) -> str:
    """Text safe in LaTeX's text mode: every special character escaped (so no user text can form a command such
    as \\input, \\include, \\write, \\openin or \\catcode), non-ASCII and control characters shown as codes."""
    return "".join(_LATEX.get(ch, ch) for ch in _visible(text))


def latex_breakable(text) -> str:
    """:func:`latex`, with a line allowed to break after every ``_ - / .`` and within any run of 16 characters
    without one (for names in narrow table columns: ``panda_finger_joint1`` may wrap, nothing runs into the
    margin)."""
    out, run = [], 0
    for ch in _visible(text):
        out.append(_LATEX.get(ch, ch))
        run += 1
        if ch in "_-/." or run >= 16:
            out.append("\\allowbreak{}")
            run = 0
    return "".join(out)


def check_c_identifier(name: str) -> str | None:
    """Why ``name`` cannot be a C identifier of the generated code (a prefix, a function, a macro part), or
    None."""
    if not isinstance(name, str) or not _C_IDENTIFIER.match(name):
        return f"{name!r} is not a C identifier (letters, digits and _, not starting with a digit)"
    if name in C_KEYWORDS or name in C_RESERVED:
        return f"{name!r} is a C/C++ keyword or a C library name"
    if name.startswith("__") or (name.startswith("_") and name[1:2].isupper()):
        return f"{name!r} is reserved in C (a leading double underscore or underscore and capital)"
    return None


PYTHON_MODULE_IMPORTS = frozenset({"np", "numpy"})  # what the generated NumPy module imports


def check_module_name(name: str) -> str | None:
    """Why ``name`` cannot name the generated NumPy module (``import NAME`` must find it and work), or None."""
    if keyword.iskeyword(name) or keyword.issoftkeyword(name):
        return f"{name!r} is a Python keyword"
    if name in sys.stdlib_module_names or name in sys.builtin_module_names:
        return f"{name!r} is a module of Python's standard library (`import {name}` would not find the generated one)"
    if name in PYTHON_MODULE_IMPORTS:
        return f"{name!r} is a module the generated file itself imports"
    return None


FILTERS = {"c_comment": c_comment, "py_str": py_str, "py_doc": py_doc, "latex": latex,
           "latex_breakable": latex_breakable}
