"""Build and load generated code: compile C into a shared library (or a ``--split`` folder by its Makefile) and call
it on NumPy arrays (:class:`CLibrary`), import a generated Python module.  The targets' runners
(:meth:`~aggsym.codegen.targets.base.Target.runner`) are made of these; :mod:`.check` compares them with the numeric
twin (``aggsym check``)."""
from __future__ import annotations

import ctypes
import importlib.util
import json
import os
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

from ..errors import AggsymError

CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-O2", "-fPIC", "-shared"]
FLOAT_CFLAGS = ["-Wdouble-promotion", "-Wfloat-conversion"]  # the float build: nothing silently done in double
CTYPES = {"double": (ctypes.c_double, np.float64), "float": (ctypes.c_float, np.float32)}


def compiler() -> str:
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if not cc:
        raise AggsymError("no C compiler found (set CC or install cc)")
    return cc


def compile_shared(c_file: Path, out: Path, extra=(), scalar: str = "double") -> Path:
    """cc -std=c99 -Wall -Wextra -Wpedantic -Werror -O2 -shared (with ``scalar="float"`` also -Wdouble-promotion
    -Wfloat-conversion), then ``extra`` (e.g. the --opt level), then the environment's CFLAGS (which win:
    ``CFLAGS=-ffast-math aggsym check ...``); CC names the compiler.  Raises with the compiler's message on
    failure."""
    flags = CFLAGS + (FLOAT_CFLAGS if scalar == "float" else [])
    cmd = [*shlex.split(compiler()), *flags, *extra, *shlex.split(os.environ.get("CFLAGS", "")), "-o", str(out), str(c_file),
           "-lm"]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as exc:
        raise AggsymError(f"cannot run the C compiler {cmd[0]!r} (CC): {exc.strerror or exc}") from None
    if proc.returncode != 0 or proc.stderr.strip():
        raise AggsymError(f"compiling {c_file.name} failed:\n{proc.stderr.strip()}")
    return out


def build_split(folder: Path, cflags: str = "-O2 -std=c99 -fPIC", jobs: int = 2) -> Path:
    """``make -jJOBS CC=... CFLAGS=...`` in an ``aggsym generate --split`` folder (CC as :func:`compiler`):
    the path of its static library (the manifest's ``split.library``).  Raises with make's message on failure."""
    folder = Path(folder)
    manifests = [json.loads(f.read_text(encoding="utf-8")) for f in sorted(folder.glob("*.json"))]
    manifests = [m for m in manifests if isinstance(m, dict) and "split" in m]
    if len(manifests) != 1:
        raise AggsymError(f"{folder}: not the output of aggsym generate --split (one NAME.json with 'split')")
    manifest = manifests[0]
    make = shutil.which("make")
    if not make:
        raise AggsymError("no make found (install make)")
    cmd = [make, f"-j{jobs}", f"CC={compiler()}", f"CFLAGS={cflags}"]
    proc = subprocess.run(cmd, cwd=folder, capture_output=True, text=True)
    if proc.returncode != 0:
        raise AggsymError(f"make in {folder} failed:\n{proc.stderr.strip()}")
    return folder / manifest["split"]["library"]


def shared_from_archive(archive: Path, out: Path) -> Path:
    """A shared library holding every object of a static one (its objects compiled with -fPIC), for ctypes."""
    cmd = [*shlex.split(compiler()), "-shared", "-o", str(out), "-Wl,--whole-archive", str(archive),
           "-Wl,--no-whole-archive", "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise AggsymError(f"linking {archive.name} failed:\n{proc.stderr.strip()}")
    return out


class CLibrary:
    """The generated C functions of a model, callable on NumPy arrays (converted to the manifest's ``scalar``,
    double or float; the outputs are arrays of that type)."""

    def __init__(self, lib_path: Path, manifest: dict):
        self.lib = ctypes.CDLL(str(lib_path))
        self.manifest = manifest
        self.nq = manifest["nq"]
        self.ctype, self.dtype = CTYPES[manifest.get("scalar", "double")]

    def call(self, role: str, *args, p=None):
        sig = self.manifest["signatures"][role]
        fn = getattr(self.lib, self.manifest["functions"][role])
        fn.restype = None
        keep = []
        cargs = []
        names = [n for n in sig["inputs"] if n != "p"]
        if len(args) != len(names):
            raise TypeError(f"{role} takes {names}")
        values = dict(zip(names, args))
        for name in sig["inputs"]:
            if name == "p":
                pv = [x["value"] for x in self.manifest["parameters"]] if p is None else p
                if len(pv) == 0:
                    cargs.append(None)
                    continue
                arr = np.ascontiguousarray(pv, dtype=self.dtype)
            else:
                arr = np.ascontiguousarray(values[name], dtype=self.dtype)
                size = sig.get("input_sizes", {}).get(name)
                if size is not None and arr.size != size:
                    raise ValueError(f"{role}: {name} has {arr.size} entries, expected {size}")
            keep.append(arr)
            cargs.append(arr.ctypes.data_as(ctypes.POINTER(self.ctype)))
        # NaN-filled: an entry the C leaves unwritten shows (every output entry is written, zeros too)
        outs = [np.full(o["shape"], np.nan, dtype=self.dtype) for o in sig["outputs"]]
        for o in outs:
            cargs.append(o.ctypes.data_as(ctypes.POINTER(self.ctype)))
        if sig.get("returns", "void") != "void":
            fn.restype = ctypes.c_int
            if fn(*cargs):
                raise np.linalg.LinAlgError(f"{role}: the C function returned nonzero: {sig['returns']}")
        else:
            fn(*cargs)
        return outs[0] if len(outs) == 1 else tuple(outs)


def import_module(py_file: Path):
    name = f"_aggsym_generated_{py_file.stem}_{abs(hash(str(py_file)))}"
    spec = importlib.util.spec_from_file_location(name, py_file)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module
