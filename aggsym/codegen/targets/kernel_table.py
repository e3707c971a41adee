"""The batch kernels of a generation as the JAX and PyTorch targets see them (the kernels target, :mod:`.kernels`,
prints them): their order and indices, and per routine which kernel computes it.  A module of its own so that the
JAX and PyTorch targets read it without importing the kernels target, which reads theirs."""
from __future__ import annotations

import contextlib
import os

NAME = "kernels"  # the kernels target's name: its bodies are EmittedRoutine.bodies[NAME]


def kernel_table(emitted) -> list:
    """Every kernel of a generation in order (the routines', each followed by its quaternion columns' kernel), with
    its ``index`` (the C's routine number)."""
    kernels = []
    for e in emitted:
        for entry in e.bodies[NAME]:
            entry["index"] = len(kernels)
            kernels.append(entry)
    return kernels


def kernels_context(job) -> dict | None:
    """For the JAX and PyTorch templates: {role: {index, shapes (of the written outputs), columns: the quaternion
    columns' kernel {index, shape, entries} or None}}; None without the kernels target."""
    if not job.chosen(NAME):
        return None
    table = kernel_table(job.emitted)
    out = {}
    for k in table:
        if "of" in k:
            out[k["of"]]["columns"] = {"index": k["index"], "shape": k["shapes"][0], "entries": tuple(k["quaternions"])}
        else:
            out[k["role"]] = {"index": k["index"], "shapes": k["shapes"], "columns": None}
    return out


@contextlib.contextmanager
def traced_modules():
    """A context in which a generated JAX or PyTorch module imported takes its traced path (AGGSYM_KERNELS=0)."""
    before = os.environ.get("AGGSYM_KERNELS")
    os.environ["AGGSYM_KERNELS"] = "0"
    try:
        yield
    finally:
        if before is None:
            del os.environ["AGGSYM_KERNELS"]
        else:
            os.environ["AGGSYM_KERNELS"] = before


__all__ = ["NAME", "kernel_table", "kernels_context", "traced_modules"]
