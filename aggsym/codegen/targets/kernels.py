"""The kernels target: the routines as batch kernels in C behind the JAX and PyTorch modules.

Chosen with the JAX or PyTorch target and the C target (``--targets c,jax``, ``c,torch``; not with
``--no-kernels``: :func:`aggsym.codegen.targets.with_kernels`), it writes

- ``NAME_kernels.c``: every routine's straight line as a kernel over a batch of states, W states at a time in the
  lanes of the host's vector registers (:mod:`.kernels_c`), the batch split across threads; one source compiled in
  double and in single precision (``templates/kernels/kernels.c.j2``);
- ``NAME_kernels_jax.cc``: the XLA foreign-function handler that calls them (``jax.ffi``; C++ on XLA's own
  header ``xla/ffi/api/ffi.h``, shipped in jaxlib);
- ``NAME_kernels.py``: the builder and loader (the standard library only): it compiles the two where it runs, with
  the host's flags (:data:`FLAGS`: ``-march=native`` as any JIT), once, into a folder beside it keyed by the
  content of the sources, the compilers' versions and the flags, and loads them through ctypes.

The one-state C (NAME.c) keeps its portable flags.  For forward and inverse dynamics with quaternion pairs and their
derivative routines, a kernel of the columns along the quaternions' entries that the routine reads
(``ROLE_quaternion_columns``, forward mode on its straight line as :func:`.torch.quaternion_columns`) completes the
derivative routines' tangent-space columns, so that a Jacobian along q needs no tracing.
"""
from __future__ import annotations

from dataclasses import replace

import jinja2

from ...contract import ROUTINES, SCALAR_INPUTS, input_length, routines_for
from ...errors import AggsymError
from ..printing import _number
from ..compile import import_module
from .base import Runner, Target, environment
from .c import _trig_pairs
from .jax import CUSTOM
from .kernel_table import NAME as _TARGET_NAME, kernel_table
from .kernels_c import lane_kernel
from .numpy import quaternion_columns_lines, quaternion_entries_read

# the compilers' flags where the kernels run (NAME_kernels.py; in its cache key and the manifest): the host's vector
# instructions, no contraction of a*b+c into one rounding (the one-state C's bits), no errno (sqrt in vectors)
FLAGS = ("-std=gnu11", "-O2", "-march=native", "-ffp-contract=off", "-fno-math-errno", "-fno-trapping-math",
         "-fPIC", "-pthread")
FLOAT_FLAGS = ("-DAGGSYM_F32", "-fsingle-precision-constant")
CXX_FLAGS = ("-std=c++17", "-O2", "-fPIC")


def columns_role(role: str) -> str:
    return f"{role}_quaternion_columns"


def _reads(sl) -> dict:
    reads = {}
    for kind, i in sl.inputs:
        reads.setdefault(kind, set()).add(i)
    return reads


def _entry(model, routine, role, inputs, kernel, written, shapes, symbol) -> dict:
    """A kernel (named ``role``, of ``routine``'s inputs) as the C template's tables see it (written: the indices of
    the outputs written)."""
    reads, reads_at = [], [0]
    for pairs in kernel.inputs:
        for entry, row in pairs:
            reads += [entry, row]
        reads_at.append(len(reads))
    writes, writes_at, constants = [], [], []
    for o in written:
        writes_at.append(len(writes))
        for x in kernel.outputs[o]:
            if isinstance(x, int) and not isinstance(x, bool):
                writes.append(x)
            else:  # a constant entry: a row after the straight line's, filled once per call
                writes.append(kernel.rows + len(constants))
                constants.append(_number(float(x), "double"))
    sizes = [len(kernel.outputs[o]) for o in written]
    return {"role": role, "symbol": symbol, "functions": kernel.functions, "rows": kernel.rows,
            "status": -1 if kernel.status is None else kernel.status,
            "in_length": [input_length(model, i, routine) for i in inputs],
            "reads": reads or [0], "reads_at": reads_at, "out_size": sizes or [0], "writes": writes or [0],
            "writes_at": writes_at or [0], "n_constants": len(constants), "constants": constants or ["0.0"],
            "inputs": list(inputs),
            "shapes": [tuple(shapes[o]) for o in written]}


def kernels_manifest(job) -> dict:
    """The manifest's ``kernels``: which modules call them, every kernel, how they are built and with what flags."""
    name = job.model.name
    return {
        "files": [f"{name}_kernels.c", f"{name}_kernels_jax.cc", f"{name}_kernels.py"],
        "used_by": [f"{name}_{t}.py" for t in ("jax", "torch") if job.chosen(t)],
        "routines": [k["role"] for k in kernel_table(job.emitted)],
        "flags": list(FLAGS), "float_flags": list(FLOAT_FLAGS), "binding_flags": list(CXX_FLAGS),
        "lanes": "AGGSYM_W states per kernel step: one vector register of the host (64 bytes with AVX-512, 32 with "
                 "AVX, else 16) of double or float",
        "build": f"at the first import of the modules that use them, by {name}_kernels.py with CC and CXX, cached in "
                 f"{name}_kernels_build/ (keyed by the sources, the compilers' versions and the flags); "
                 "AGGSYM_KERNELS=0: the traced modules",
        "paths": "CPU, float32 and float64: the kernels; other devices and dtypes: the traced straight line",
    }


class KernelsTarget(Target):
    """NAME_kernels.c, NAME_kernels_jax.cc and NAME_kernels.py: the batch kernels and their builder."""

    name = _TARGET_NAME
    stage = "kernels"
    column = "kernels"
    checked_by_default = False  # (aggsym check --targets c,jax or c,torch: the modules on them, a column each)
    folder = "kernels"
    templates = ("kernels.c.j2", "kernels_jax.cc.j2", "kernels.py.j2")

    def file_names(self, job):
        name = job.model.name
        return [f"{name}_kernels.c", f"{name}_kernels_jax.cc", f"{name}_kernels.py"]

    def owns(self, name, file):
        return file in (f"{name}_kernels.c", f"{name}_kernels_jax.cc", f"{name}_kernels.py")

    def print_routine(self, model, prog, lines, emitted):
        r = emitted.routine
        status = next((k for k, o in enumerate(r.outputs) if o.returned), None)
        written = [k for k, o in enumerate(r.outputs) if not o.returned]
        shapes = [o.shape(model) for o in r.outputs]
        kernel = lane_kernel(prog, lines, emitted.inputs, status, emitted.symbol)
        entries = [_entry(model, r, r.role, emitted.inputs, kernel, written, shapes, emitted.symbol)]
        spec = CUSTOM.get(r.role)
        roles = {x.role for x in routines_for(model)}
        if spec is not None and model.nq != model.nv and spec[0] in roles:
            qs = quaternion_entries_read(model, _reads(lines.sl))
            if qs:  # the columns along the quaternions' entries read (the derivative routines have none)
                lines_q, rows = quaternion_columns_lines(prog, lines.outputs[0], qs)
                lines_q = replace(lines_q, trig=_trig_pairs(prog, lines_q.sl.temps))  # (sin and cos together)
                symbol = f"{emitted.symbol}_quaternion_columns"
                kq = lane_kernel(prog, lines_q, emitted.inputs, None, symbol)
                entry = _entry(model, r, columns_role(r.role), emitted.inputs, kq, [0], [(rows, len(qs))], symbol)
                entry.update(quaternions=list(qs), quaternions_py=repr(tuple(qs)), of=r.role)
                entries.append(entry)
        return entries

    def render(self, job):
        """The three files, whatever the C's layout (``--split``) and scalar (``--scalar float``): the kernels are
        printed from the straight lines themselves, in double and float alike."""
        model = job.model
        kernels = kernel_table(job.emitted)
        ctx = {**job.ctx, "kernels": kernels, "max_inputs": max(len(k["inputs"]) for k in kernels),
               "sincos": any("aggsym_sincos_lanes(" in line for k in kernels for line in k["functions"]),
               "sign": any("aggsym_sign(" in line or "aggsym_vsign(" in line
                           for k in kernels for line in k["functions"]),
               "flags_py": repr(FLAGS), "float_flags_py": repr(FLOAT_FLAGS), "cxx_flags_py": repr(CXX_FLAGS),
               "scalar_inputs": SCALAR_INPUTS}
        env = kernel_environment()
        name = model.name
        return {f"{name}_kernels.c": env.get_template("kernels.c.j2").render(ctx),
                f"{name}_kernels_jax.cc": env.get_template("kernels_jax.cc.j2").render(ctx),
                f"{name}_kernels.py": env.get_template("kernels.py.j2").render(ctx)}

    def main_file(self, name):
        return f"{name}_kernels.py"

    def unavailable(self):
        from ..compile import compiler

        try:
            compiler()
        except AggsymError as exc:
            return str(exc)
        return None

    def runners(self, model, folder, manifest, opt):
        """The JAX and PyTorch modules beside the kernels, on the kernels: a column each in float64 (with their
        derivatives: jacfwd, torch.func.jacrev) and in float32 (held to the float C's bounds)."""
        from ...contract import float_tolerance
        from .jax import jax_call, jax_jacobian
        from .torch import torch_call, torch_jacobian

        bounds = float_tolerance(model, [ROUTINES[r] for r in manifest["functions"]])
        out = {}
        for framework, heading, call, jacobian in (("jax", "JAX", jax_call, jax_jacobian),
                                                   ("torch", "torch", torch_call, torch_jacobian)):
            path = folder / f"{model.name}_{framework}.py"
            if not path.exists():
                continue
            module = import_module(path)
            if module._KERNELS is None:
                raise AggsymError(f"{path.name}: the kernels are switched off (AGGSYM_KERNELS=0): unset it to "
                                  "check them")
            out[f"kernels_{framework}"] = (f"{heading} k64", Runner(call(module, manifest, False),
                                                                   jacobian=jacobian(module)))
            out[f"kernels_{framework}32"] = (f"{heading} k32", Runner(call(module, manifest, True),
                                                                     bounds["float_tolerance"],
                                                                     tuple(bounds["float_tolerance_per_condition"])))
        return out


def kernel_environment():
    """The templates of templates/kernels/, which also read the C target's (templates/c/: the sin and cos series)."""
    from importlib.resources import files

    root = files("aggsym.templates")

    def load(name):
        for folder in ("kernels", "c"):
            path = root / folder / name
            if path.is_file():
                return path.read_text(encoding="utf-8")
        return None
    env = environment(root)
    env.loader = jinja2.FunctionLoader(load)
    return env


__all__ = ["KernelsTarget", "kernels_manifest", "columns_role", "FLAGS", "FLOAT_FLAGS",
           "CXX_FLAGS"]
