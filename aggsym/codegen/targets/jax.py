"""The JAX target: NAME_jax.py, the NumPy module's routines as pure JAX functions (``--targets jax``).

Each routine is printed from its straight line (:func:`~.numpy.array_steps`, spelled by :data:`JAX`: ``jnp.sin``
...) into a private function over arrays of any leading batch shape: inputs unpacked, each temporary one
assignment, each output entry named where it is computed, and every output assembled once at the end by
stacking its entries (a zero entry is a broadcast constant): no in-place write, no Python branch on a value, so
that ``jit``, ``vmap``, ``grad``, ``jacfwd``, ``jacrev`` and ``hessian`` go through every routine.  The public
function converts its inputs (the dtype follows them: float32 stays float32, float64 where the user enabled
x64), fills in ``p`` and calls the private one.  A long routine's statements are cut into segments, each a function
called through ``jax.lax.cond`` (:mod:`.jax_segments`: XLA's CPU compiler would otherwise fuse the whole straight
line into kernels that evaluate shared values again at every use); in every routine the sines and cosines of the
inputs go first into a segment of their own, so that each is evaluated once.  An output is assembled by chains of
selects (``_stack``), in a cut routine by one ``jnp.stack`` of its entries, which the segments have written to
memory already (``_stacked``); a short routine whose outputs have many entries (A(q)) goes into one segment and is
assembled so too.

Analytic derivatives (:data:`CUSTOM`): when the module also holds a routine's derivative routine, the public
function goes through a :func:`jax.custom_jvp` whose rule applies the generated derivative matrices to the
tangents (forward dynamics: d qdd/d q, d qdd/d qd and A^-1 for tau; inverse dynamics: d tau/d q, d tau/d qd and A
for qdd), so that ``jax.jacfwd`` and ``jax.jacrev`` cost what the derivative routine costs.  A direction the
routines do not cover (p, the time t, and the entries of a quaternion pair in q, where the derivative routines are
in Pinocchio's tangent space rather than along the entries of q) is differentiated by tracing the plain function;
of a quaternion pair's entries, only those the routine reads (a free-flyer's origin is never read by the dynamics).

With the kernels target (:mod:`.kernels`: ``--targets c,jax``) the module also calls, on the CPU in float32 and
float64, each routine's batch kernel as an XLA foreign-function call (``_kernel``, ``_kernel_function``): its JVP
through the derivative routines' kernels where :data:`CUSTOM` has them (and the quaternion columns' kernel), the
traced straight line for every other direction and every second derivative; elsewhere the traced module as above.

A routine with a returned status (a system that can be singular) cannot raise on a value under ``jit``: its
outputs are NaN in the states where the NumPy module raises LinAlgError.  Checked (``aggsym check``, column
JAX) by importing the module, in float64 with ``--scalar double`` (held to ``--tol`` like the NumPy module) and
in float32 with ``--scalar float`` (held to the float C's bounds, the manifest's ``float_tolerance``).
"""
from __future__ import annotations

from ...contract import ROUTINES, SCALAR_INPUTS, input_length, signature
from ...core.functions import FUNCTIONS
from ...model.tree import Tree
from ..compile import import_module
from ..printing import Spelling, _number
from .base import Runner, Target
from .kernel_table import kernels_context, traced_modules
from .jax_segments import cut, limits, segmented
from .numpy import array_steps, quaternion_entries_read, scalar_output, step_statement

# the JAX spelling: jax.numpy's element-wise functions (the same names as NumPy's), double literals as the C's (a
# Python float is weakly typed in JAX: it takes the dtype of the array it meets, so float32 stays float32)
JAX = Spelling({name: f"jnp.{f.numpy_name}" for name, f in FUNCTIONS.items()}, _number)

# routine -> (its derivative routine, {input: (routine giving d out / d input, index of that output)}): the
# directions the custom JVP applies generated matrices to; the others are traced
CUSTOM = {
    "forward_dynamics": ("forward_dynamics_derivatives",
                         {"q": ("forward_dynamics_derivatives", 0), "qd": ("forward_dynamics_derivatives", 1),
                          "tau": ("inertia_inverse", 0)}),
    "inverse_dynamics": ("inverse_dynamics_derivatives",
                         {"q": ("inverse_dynamics_derivatives", 0), "qd": ("inverse_dynamics_derivatives", 1),
                          "qdd": ("inertia", 0)}),
}


def jax_body(model, prog, lines, routine, inputs) -> dict:
    """One routine as the private function's statements: {"body": lines before the outputs are assembled,
    "entries": per output the texts of its entries in row-major order ("0.0" for a zero), "reads": per input
    the set of its entries the straight line reads}."""
    sizes = []
    for out in routine.outputs:
        size = 1
        for n in out.shape(model):
            size *= n
        sizes.append(size)
    entries = [["0.0"] * size for size in sizes]
    body, reads = [], {}
    for step in array_steps(model, prog, lines, routine, inputs, JAX):
        if step[0] == "input":
            reads.setdefault(step[2], set()).add(step[3])
        statement = step_statement(step)
        if statement is not None:
            body.append(statement)
        elif step[3] is not None:
            _, o, k, rhs = step
            name = f"_o{o}_{k}"
            body.append(f"{name} = {rhs}")
            entries[o][k] = name
    return {"entries": entries, "reads": reads,
            **segmented(routine.role, body, [e for out in entries for e in out])}


def custom_directions(model, role: str, roles, reads: dict) -> dict | None:
    """{input: (role, output index, its arguments' text, split)} of the directions the custom JVP of ``role`` covers
    in a module of the routines ``roles``; None when ``role`` has no derivative routine there (plain tracing).
    ``reads``: the entries of each input that the routine's straight line reads (:func:`jax_body`'s)."""
    spec = CUSTOM.get(role)
    if spec is None or spec[0] not in roles or role not in roles:
        return None
    out = {}
    for name, (source, index) in spec[1].items():
        if source not in roles or name not in signature(ROUTINES[role], model):
            continue
        # with quaternions (a free-flyer, ball pairs) the routines are in the tangent space: along q they give the
        # columns of the entries that are coordinates; of the quaternion pairs' entries, those the routine reads are
        # traced (it is constant along the others, e.g. a free-flyer's origin in the dynamics: tracing them would
        # only add zero columns, 3 of Talos's 7 directions of a JVP through all of forward dynamics)
        split = None
        if name == "q" and model.nq != model.nv:
            Q, V, _ = Tree.of(model).position_split
            split = (Q, V, quaternion_entries_read(model, reads))
        out[name] = (source, index, ", ".join(signature(ROUTINES[source], model)), split)
    return out


def custom_groups(inputs, custom) -> dict:
    """For the template of a custom JVP: ``groups`` [{role, args, uses: [(tangent index, output index, split)]}]
    the derivative routines to call (each once; ``split``: the tree's ``position_split`` for q with quaternions,
    else None), ``traced`` the indices of the inputs differentiated by tracing."""
    if not custom:
        return {"groups": [], "traced": []}
    groups = {}
    for k, name in enumerate(inputs):
        if name in custom:
            role, index, args, split = custom[name]
            groups.setdefault(role, {"role": role, "args": args, "uses": []})["uses"].append((k, index, split))
    return {"groups": list(groups.values()), "traced": [k for k, name in enumerate(inputs) if name not in custom]}


def wrapped(entries, width: int = 100) -> str:
    """An output's entries as the text of a tuple's items (a trailing comma), in lines of about ``width``."""
    lines, line = [], ""
    for e in entries:
        item = e + ", "
        if line and len(line) + len(item) > width:
            lines.append(line.rstrip())
            line = ""
        line += item
    lines.append(line.rstrip())
    return "\n        ".join(lines)


def status_entry(emitted) -> str | None:
    """The text of a routine's returned status (None: it has none)."""
    for k, out in enumerate(emitted.routine.outputs):
        if out.returned:
            return emitted.bodies[JaxTarget.name]["entries"][k][0]
    return None


class JaxTarget(Target):
    """NAME_jax.py: the NumPy module's functions in JAX (same names, argument order, output shapes, p default)."""

    name = "jax"
    column = "JAX"
    folder = "jax"
    templates = ("model_jax.py.j2",)

    def file_names(self, job):
        return [f"{job.model.name}_jax.py"]

    def owns(self, name, file):
        return file == f"{name}_jax.py"

    def print_routine(self, model, prog, lines, emitted):
        return jax_body(model, prog, lines, emitted.routine, emitted.inputs)

    def render(self, job):
        roles = [e.routine.role for e in job.emitted]
        custom = {e.routine.role: custom_directions(job.model, e.routine.role, roles, e.bodies[self.name]["reads"])
                  for e in job.emitted}
        ctx = {**job.ctx, "custom": {role: c for role, c in custom.items() if c}, "scalar_output": scalar_output,
               "kernels": kernels_context(job),
               **dict(zip(("segment_size", "segmented_above", "gathered"), limits())),
               "jax_routines": [{"r": e, "role": e.routine.role, "inputs": list(e.inputs),
                                 "args": ", ".join(e.inputs), "body": e.bodies[self.name]["body"],
                                 "segments": e.bodies[self.name]["segments"],
                                 "cut": cut(e.bodies[self.name]["segments"]),
                                 "entries": [wrapped(x) for x in e.bodies[self.name]["entries"]],
                                 "status_entry": status_entry(e),
                                 "outs": "".join(f"{o.py}, " for o in e.routine.written).rstrip(),
                                 "shapes": [tuple(o.shape(job.model)) for o in e.routine.outputs],
                                 "status": next((k for k, o in enumerate(e.routine.outputs) if o.returned), None),
                                 "written": [k for k, o in enumerate(e.routine.outputs) if not o.returned],
                                 "custom": custom[e.routine.role],
                                 "lengths": {i: input_length(job.model, i, e.routine) for i in e.inputs
                                             if i not in SCALAR_INPUTS},
                                 **custom_groups(list(e.inputs), custom[e.routine.role])} for e in job.emitted]}
        return {f"{job.model.name}_jax.py": self.template("model_jax.py.j2").render(ctx)}

    def main_file(self, name):
        return f"{name}_jax.py"

    def unavailable(self):
        try:
            import jax  # noqa: F401
        except ImportError as exc:
            return f"jax does not import here ({exc}); pip install aggsym[jax]"
        return None

    def runner(self, model, folder, manifest, opt):
        """The module in float64 (``--scalar double``: x64 enabled for the check, held to ``--tol``) or float32
        (``--scalar float``: the inputs rounded to float32 as the check rounds them for the float C, held to the
        same per-routine bounds, the manifest's ``float_tolerance``, relative also to cond(A) for the routines that
        solve with A).  A state where the module's outputs are NaN counts as a singular system (LinAlgError), as
        where the NumPy module raises."""
        single = manifest.get("scalar", "double") == "float"
        with traced_modules():  # (the module as traced: its kernels, if any, are the kernels target's columns)
            module = import_module(folder / f"{model.name}_jax.py")
        call = jax_call(module, manifest, single)
        if single:
            return Runner(call, manifest.get("float_tolerance", {}),
                          tuple(manifest.get("float_tolerance_per_condition", ())))
        return Runner(call)


def jax_call(module, manifest, single: bool):
    """A generated JAX module's routines as :attr:`Runner.call`: float32 (``single``) or float64 arrays in, NumPy
    arrays out; NaN outputs of a routine with a status raised as numpy.linalg.LinAlgError."""
    import jax
    import numpy as np

    dtype = np.float32 if single else np.float64
    statuses = {role for role, sig in manifest["signatures"].items() if sig.get("returns", "void") != "void"}

    def call(role, *args):
        with _precision(jax, not single):
            out = getattr(module, role)(*(np.asarray(a, dtype=dtype) for a in args))
        outs = tuple(np.asarray(o, dtype=float) for o in (out if isinstance(out, tuple) else (out,)))
        if role in statuses and any(np.isnan(o).any() for o in outs):
            raise np.linalg.LinAlgError(f"{role}: the JAX module returned NaN: {manifest['signatures'][role]['returns']}")
        return outs[0] if len(outs) == 1 else outs
    return call


def jax_jacobian(module):
    """:attr:`Runner.jacobian` of a JAX module: jax.jacfwd of a routine's first output along each array argument
    (float64)."""
    import jax
    import numpy as np

    def jacobian(role, *args):
        arrays = [k for k, a in enumerate(args) if np.ndim(a)]
        with _precision(jax, True):
            f = getattr(module, role)

            def first(*xs):
                out = f(*xs)
                return out[0] if isinstance(out, tuple) else out
            jac = jax.jacfwd(first, tuple(arrays))(*(np.asarray(a, dtype=np.float64) for a in args))
        return [np.asarray(j, dtype=float) for j in jac]
    return jacobian


def _precision(jax, x64: bool):
    """A context in which JAX computes in float64 (``x64``) or as configured: ``jax.enable_x64`` (or
    ``jax.experimental.enable_x64`` of older releases), so that the check changes no global setting."""
    import contextlib

    if not x64:
        return contextlib.nullcontext()
    enable = getattr(jax, "enable_x64", None)
    if enable is None:
        from jax.experimental import enable_x64 as enable
    return enable(True)
