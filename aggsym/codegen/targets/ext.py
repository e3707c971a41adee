"""The extension target: the generated C callable from Python with NumPy arrays, one state per call
(``--targets c,numpy,ext``).

Why: the NumPy module (:mod:`.numpy`) is written for batches; for one state its per-call time is that of some
thousand NumPy operations on scalars (tens of microseconds for a 7-DOF arm), while a controller written in
Python calls the dynamics once per state.  This target writes

- ``NAME_ext.c``: a CPython extension module ``NAME_ext_c`` that includes ``NAME.c`` and, per routine, a function
  taking the routine's inputs and its outputs as buffers (contiguous float64 vectors of the contract's lengths;
  the time t as a number); it fills the outputs and returns True, or returns False without writing anything when
  an input is anything else (a batch, a list, another dtype or length) or the routine reports a singular system;
- ``NAME_ext.py``: the NumPy module's functions, names and argument order: each allocates its outputs, calls the
  extension, and where it returned False calls the NumPy module ``NAME.py`` beside it, which computes batches,
  converts lists, raises the ValueError of a wrong length and the LinAlgError of a singular system.  The
  extension is compiled the first time the module is imported (``CC``, default ``cc``; Python's own headers), into
  the module's folder, and again whenever ``NAME_ext.c``, ``NAME.c`` or ``NAME.h`` is newer than it.

It needs the C and NumPy targets in the same folder (non-split, double).  Checked (``aggsym check``, column
ext) by importing the module, one state per call, against the numeric twin.
"""
from __future__ import annotations

import math

from ...contract import SCALAR_INPUTS, input_length
from ...errors import AggsymError
from ..compile import compiler, import_module
from .base import Runner, Target, file_pattern
from .numpy import scalar_output

SCALARS = SCALAR_INPUTS  # inputs passed to the C as a pointer to one double, to Python as a number


class ExtensionTarget(Target):
    """NAME_ext.c and NAME_ext.py: the C of one state at a time behind the NumPy module's functions."""

    name = "ext"
    column = "ext"
    checked_by_default = False  # (a second compile of NAME.c: ``aggsym check --targets c,numpy,ext`` asks for it)
    folder = "ext"
    templates = ("model_ext.c.j2", "model_ext.py.j2")

    def file_names(self, job):
        return [f"{job.model.name}_ext.c", f"{job.model.name}_ext.py"]

    def owns(self, name, file):
        return bool(file_pattern(f"{name}_ext", ("c", "py")).fullmatch(file))

    def render(self, job):
        missing = [t for t in ("c", "numpy") if not job.chosen(t)]
        if missing:
            raise AggsymError(f"--targets ext calls the C and falls back on the NumPy module: add "
                              f"{' and '.join(missing)} to --targets (e.g. --targets c,numpy,ext)")
        if job.split or job.scalar != "double":
            raise AggsymError("--targets ext includes NAME.c in double: it cannot go with "
                              + ("--split" if job.split else "--scalar float"))
        model = job.model
        routines = []
        for e in job.emitted:
            r = e.routine
            inputs = [{"name": i, "scalar": i in SCALARS,
                       "length": None if i in SCALARS else input_length(model, i, r)} for i in e.inputs]
            outputs = [{"name": o.name, "py": o.py, "shape": o.shape(model), "size": math.prod(o.shape(model)),
                        "scalar": scalar_output(o)} for o in r.written]
            routines.append({"role": r.role, "doc": r.doc, "symbol": e.symbol, "status": r.status is not None,
                             "inputs": inputs, "outputs": outputs, "parameters": e.py_parameters,
                             "args": ", ".join("PARAMETERS if p is None else p" if i == "p" else i for i in e.inputs)})
        ctx = {**job.ctx, "ext_routines": routines}
        name = model.name
        return {f"{name}_ext.c": self.template("model_ext.c.j2").render(ctx),
                f"{name}_ext.py": self.template("model_ext.py.j2").render(ctx)}

    def main_file(self, name):
        return f"{name}_ext.py"

    def unavailable(self):
        import sysconfig
        from pathlib import Path

        try:
            compiler()
        except AggsymError as exc:
            return str(exc)
        include = sysconfig.get_paths().get("include")
        if not include or not (Path(include) / "Python.h").exists():
            return f"Python's headers (Python.h) are not installed (looked in {include})"
        return None

    def runner(self, model, folder, manifest, opt):
        module = import_module(folder / f"{model.name}_ext.py")
        return Runner(lambda role, *args: getattr(module, role)(*args))
