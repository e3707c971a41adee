"""The model readers, one registry: which reader takes a file, and which options it accepts.

A reader is one module with a ``load(path, **options) -> Model`` and one :class:`Reader` entry in :data:`READERS`
(or :func:`register`): its name, the suffixes it claims and the keyword options of its ``load``.  Which of the
options applied after reading a reader's models take is said by the table of options, :data:`aggsym.pipeline.OPTIONS`.
A suffix that several formats share (``.xml``: URDF, MJCF) is listed in ``sniffed``: the reader takes such a file
only when its ``sniff`` accepts the file's first :data:`SNIFF_BYTES` bytes.  :func:`reader_for` chooses;
:func:`aggsym.model.load` and the pipeline (:mod:`aggsym.pipeline`) consult it.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ...errors import ModelError

SNIFF_BYTES = 4096  # what sniff sees of a file whose suffix is shared


@dataclass(frozen=True)
class Reader:
    """One model format."""

    name: str  # as messages name it: "URDF", "YAML"
    suffixes: tuple  # lower-case suffixes with the dot that this reader claims by the suffix alone
    load: Callable  # load(path, **options) -> Model
    options: tuple = ()  # the keyword options of load (floating_base, ...)
    sniffed: tuple = ()  # suffixes shared with other formats: taken only when sniff(head) says so
    sniff: Callable | None = None  # sniff(first bytes of the file) -> bool
    note: str = ""  # said after an option the reader does not accept (what to do instead)


def _load_yaml(path, **options):
    from .yaml_reader import load_yaml

    return load_yaml(path, **options)


def _load_urdf(path, **options):
    from .urdf_reader import load_urdf

    return load_urdf(path, **options)


def _load_xacro(path, **options):
    from .xacro_reader import load_xacro

    return load_xacro(path, **options)


def _load_mjcf(path, **options):
    from .mjcf_reader import load_mjcf

    return load_mjcf(path, **options)


def _is_urdf(head: bytes) -> bool:
    return b"<robot" in head


def _is_mjcf(head: bytes) -> bool:
    return b"<mujoco" in head


READERS: list = [
    Reader("YAML", (".yaml", ".yml"), _load_yaml,
           note="a YAML model lists its constraints and support itself, and writes its masses and inertias as "
                "expressions in its parameters"),
    Reader("URDF", (".urdf",), _load_urdf, options=("floating_base", "mimic", "snap_angles", "root"),
           sniffed=(".xml",), sniff=_is_urdf),
    Reader("xacro", (".xacro",), _load_xacro,
           options=("floating_base", "mimic", "snap_angles", "xacro_args", "package_paths", "root"),
           note="a xacro file is expanded by the xacro package, then read as URDF with the URDF options"),
    Reader("MJCF", (".mjcf",), _load_mjcf, options=("frictionloss", "root"), sniffed=(".xml",), sniff=_is_mjcf,
           note="an MJCF model's joints come from its file (a free joint is the quaternion free-flyer), as do its "
                "angles"),
]


def register(reader: Reader) -> Reader:
    """Add a reader (a new format); a suffix it claims outright must not be claimed already."""
    taken = {s for r in READERS for s in r.suffixes}
    clash = sorted(taken & set(reader.suffixes))
    if clash:
        raise ValueError(f"reader {reader.name!r}: the suffixes {clash} are taken (list shared suffixes in sniffed)")
    READERS.append(reader)
    return reader


def known_suffixes() -> list:
    """Every suffix some reader claims, in registry order (claimed outright first, then shared ones)."""
    out = [s for r in READERS for s in r.suffixes]
    return out + [s for r in READERS for s in r.sniffed if s not in out]


def reader_for(path) -> Reader:
    """The reader of the file, by its suffix, and for a shared suffix by its content; a :class:`ModelError` when
    none takes it."""
    path = Path(path)
    suffix = path.suffix.lower()
    for r in READERS:
        if suffix in r.suffixes:
            return r
    candidates = [r for r in READERS if suffix in r.sniffed]
    if candidates:
        try:
            with open(path, "rb") as f:
                head = f.read(SNIFF_BYTES)
        except OSError as exc:
            raise ModelError(path, "", f"cannot read the file: {exc.strerror}") from None
        for r in candidates:
            if r.sniff is not None and r.sniff(head):
                return r
        raise ModelError(path, "", f"a {suffix} file that no reader recognizes (tried "
                                   f"{', '.join(r.name for r in candidates)})")
    expected = [s for r in READERS for s in r.suffixes]
    listed = ", ".join(expected[:-1]) + " or " + expected[-1] if len(expected) > 1 else expected[0]
    raise ModelError(path, "", f"unknown model type {suffix!r}: expected {listed}")


def listing(names) -> str:
    """"a", "a and b", "a, b and c"."""
    names = list(names)
    return " and ".join(names) if len(names) <= 2 else ", ".join(names[:-1]) + " and " + names[-1]


__all__ = ["Reader", "READERS", "register", "reader_for", "known_suffixes", "listing"]
