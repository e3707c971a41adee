"""The XML under the URDF reader: expat with the line of every element, hostile files refused, and the quirks of
files the common parser (urdfdom, on TinyXML) reads accepted with a warning where their meaning is unambiguous.

* Only the elements of :data:`_USED` are stored; the others (visual, collision, gazebo, ...) are only counted,
  against :data:`MAX_ELEMENTS`; at most :data:`MAX_LINKS` links and :data:`MAX_JOINTS` joints.
* No entity is ever expanded: a document type declaration that declares entities or names an external DTD is
  refused, and nothing outside the file is read.
* An XML declaration preceded by white space (a blank first line: XML forbids it, urdfdom reads it) is read as if
  it were at the start, with a :class:`ModelWarning`; line numbers stay those of the file.
* An element the reader takes once (``<origin>``, ``<axis>``, ``<limit>``, ``<inertial>`` and its ``<mass>``, ...)
  given again identically (the same numbers after parsing: ``0 0 1`` and ``0 0 1.0``, defaults filled in; the
  same names) is dropped here and noted on the first (:attr:`_Element.repeated_on`), so the reader warns; a repeat
  that differs is kept, and the reader refuses it (which one was meant is not known).  At most the first and one
  differing repeat are stored per tag and parent, so repeats cost no memory.
"""
from __future__ import annotations

import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from ...errors import ModelError, ModelWarning

MAX_LINKS = 10_000
MAX_JOINTS = 10_000
MAX_ELEMENTS = 1_000_000  # every XML element, read or skipped

# The elements the reader uses, by parent; everything else (visual, collision, gazebo, transmission, ...) is
# skipped without being stored.
_USED = {
    "robot": {"link", "joint"},
    "link": {"inertial"},
    "inertial": {"origin", "mass", "inertia"},
    "joint": {"parent", "child", "origin", "axis", "limit", "dynamics", "mimic"},
}
# The attributes the reader reads from the elements it takes once, with their defaults (None: no default); two
# such elements are the same when these agree.  Names (NAMES) are compared as text, the others as numbers.
_ATTRIBUTES = {
    "origin": {"xyz": "0 0 0", "rpy": "0 0 0", "quat_xyzw": None},
    "axis": {"xyz": "1 0 0"},
    "parent": {"link": None},
    "child": {"link": None},
    "limit": {"lower": None, "upper": None, "velocity": None, "effort": None},
    "dynamics": {"damping": None, "friction": None},
    "mimic": {"joint": None, "multiplier": "1", "offset": "0"},
    "mass": {"value": None},
    "inertia": {k: None for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")},
    "inertial": {},
}
NAMES = {"link", "joint"}
NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
_DECLARATION = re.compile(rb"(\xef\xbb\xbf)?([ \t\r\n]+)(<\?xml[ \t\r\n][^>]*\?>)")


@dataclass
class _Element:
    """An XML element with the line it starts on."""

    tag: str
    attrib: dict
    line: int
    parent: "_Element | None" = None
    children: list = field(default_factory=list)
    repeat: bool = False  # a second element of its tag under its parent, until it is compared with the first
    repeated_on: int | None = None  # the line of the first identical repeat of this element, dropped
    repeats: int = 0  # how many identical repeats were dropped

    def all(self, tag: str) -> list:
        return [c for c in self.children if c.tag == tag]


def _named(tag: str, attrib: dict) -> str:
    name = attrib.get("name")
    return f'<{tag} name="{name}">' if name is not None else f"<{tag}>"


def _where(el: _Element) -> str:
    """The element as a reader finds it: ``<joint name="elbow">``, or ``<joint name="elbow"> <axis>``."""
    parts = []
    while el is not None:
        name = el.attrib.get("name")
        top_level = el.parent is None or el.parent.tag == "robot"
        if el.tag in ("robot", "link", "joint") and (name is not None or top_level):
            parts.append(f'<{el.tag} name="{name}">' if name is not None else f"<{el.tag}>")
            break
        parts.append(f"<{el.tag}>")
        el = el.parent
    return " ".join(reversed(parts))


def _value(name: str, text):
    """An attribute as the reader sees it: a name as text, numbers as floats (``1`` and ``1.0`` alike)."""
    if text is None or name in NAMES:
        return text
    parts = text.split()
    if all(NUMBER.match(p) for p in parts):
        return tuple(float(p) + 0.0 for p in parts)  # (+ 0.0: -0 and 0 alike)
    return text


def _key(el: _Element):
    """What the reader reads from an element: its attributes (defaults filled in) and its children's keys."""
    attributes = _ATTRIBUTES.get(el.tag, {})
    own = tuple(_value(name, el.attrib.get(name, default)) for name, default in attributes.items())
    tags = sorted({c.tag for c in el.children})
    return own, tuple((tag, tuple(_key(c) for c in el.all(tag))) for tag in tags)


def _declaration_first(file: Path, data: bytes) -> tuple:
    """(data, warning text or None): an XML declaration after white space moved to the start, the white space after
    it (so every line keeps its number)."""
    m = _DECLARATION.match(data)
    if not m:
        return data, None
    space = m.group(2)
    line = space.replace(b"\r\n", b"\n").replace(b"\r", b"\n").count(b"\n") + 1
    text = str(ModelError(file, "<?xml?>", "the XML declaration is preceded by white space (XML wants "
                                           "<?xml ...?> at the very start of the file); read as if it were "
                                           "there, as urdfdom does. Remove what comes before <?xml", line))
    return (m.group(1) or b"") + m.group(3) + space + data[m.end():], text


def read_capped(path, shown, limit: int, what: str) -> bytes:
    """The bytes of the file ``path`` (``shown`` in messages), refused above ``limit`` bytes before more is read
    (``what``: "a URDF", "an MJCF file")."""
    try:
        with open(path, "rb") as f:
            data = f.read(limit + 1)
    except OSError as exc:
        raise ModelError(shown, "", f"cannot read the file: {exc.strerror}") from None
    if len(data) > limit:
        raise ModelError(shown, "", f"the file is larger than {limit // 2 ** 20} MiB; {what} this large is not read "
                                    f"(the limit guards against files made to exhaust memory)")
    return data


def guard(parser, refuse, format_name: str) -> None:
    """Refuse, on the expat ``parser``, what would make it expand or read anything beyond the file: entity
    declarations (internal, external, parameter, unparsed), references to external entities and a document type
    naming an external DTD; ``refuse(where, message)`` raises the reader's error (``format_name``: what the
    messages call the file, "URDF", "MJCF")."""

    def entity(name, is_parameter, value, base, system_id, public_id, notation):
        kind = "an external" if system_id or public_id else "a parameter" if is_parameter else "an"
        refuse("<!DOCTYPE>", f"{kind} entity declaration (<!ENTITY {'% ' if is_parameter else ''}{name} ...>) is "
                             f"refused: {format_name} needs no entities, and expanding them can exhaust memory or "
                             f"read other files")

    def external(context, base, system_id, public_id):
        refuse("<!DOCTYPE>", f"a reference to the external entity {system_id!r} is refused; nothing outside the "
                             f"file is read")

    def doctype(name, system_id, public_id, has_internal_subset):
        if system_id or public_id:
            refuse("<!DOCTYPE>", f"a document type naming an external DTD ({system_id or public_id!r}) is refused; "
                                 f"nothing outside the file is read")

    parser.StartDoctypeDeclHandler = doctype
    parser.EntityDeclHandler = entity
    parser.UnparsedEntityDeclHandler = lambda name, base, system_id, public_id, notation: entity(
        name, False, None, base, system_id, public_id, notation)
    parser.ExternalEntityRefHandler = external


def _parse(file: Path, data: bytes, notes: list | None = None) -> _Element:
    """Parse XML with expat, recording each element's line; raises ModelError for malformed XML, for entity
    declarations and for a document over the element limits.  Warnings (a declaration after white space) are
    issued as :class:`ModelWarning` and appended to ``notes``.

    Only the elements of :data:`_USED` are stored, and of each tag under one parent below ``<robot>`` the first
    and at most one repeat that differs from it (all the reader needs to report it); identical repeats are
    dropped and noted on the first; the others are only counted.
    """
    data, warning = _declaration_first(file, data)
    if warning is not None:
        warnings.warn(warning, ModelWarning, stacklevel=3)
        if notes is not None:
            notes.append(warning)
    parser = expat.ParserCreate()
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    stack: list = []  # _Element, or None inside a skipped element
    top: list[_Element] = []
    counts = {"elements": 0, "link": 0, "joint": 0}

    def refuse(where, message):
        raise ModelError(file, where, message, parser.CurrentLineNumber)

    def start(tag, attrib):
        counts["elements"] += 1
        if counts["elements"] > MAX_ELEMENTS:
            refuse(_named(tag, attrib), f"more than {MAX_ELEMENTS:,} XML elements; a URDF this large is not "
                                        f"read (the limit guards against files made to exhaust memory)")
        parent = stack[-1] if stack else None
        if stack and (parent is None or tag not in _USED.get(parent.tag, ())):
            stack.append(None)
            return
        repeat = False
        if parent is not None and parent.tag != "robot":
            same = len(parent.all(tag))
            if same >= 2:  # a differing repeat is kept already: the reader refuses it
                stack.append(None)
                return
            repeat = same == 1
        if parent is not None and parent.tag == "robot":
            counts[tag] += 1
            limit = MAX_LINKS if tag == "link" else MAX_JOINTS
            if counts[tag] > limit:
                refuse(_named(tag, attrib), f"more than {limit:,} <{tag}> elements; larger robots are not read "
                                            f"(the limit guards against files made to exhaust time and memory)")
        el = _Element(tag, attrib, parser.CurrentLineNumber, parent, repeat=repeat)
        (parent.children if parent is not None else top).append(el)
        stack.append(el)

    def end(tag):
        el = stack.pop()
        if el is not None and el.repeat:
            el.repeat = False
            first = el.parent.all(tag)[0]
            if _key(el) == _key(first):  # the same again: dropped, noted on the first
                el.parent.children.remove(el)
                first.repeats += 1
                if first.repeated_on is None:
                    first.repeated_on = el.line

    guard(parser, refuse, "URDF")
    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise ModelError(file, "", f"not XML: {expat.errors.messages[exc.code]}", exc.lineno) from None
    except LookupError as exc:  # <?xml encoding="..."?> that Python does not know
        raise ModelError(file, "<?xml?>", f"not XML that can be read: {exc}", parser.CurrentLineNumber) from None
    return top[0]
