"""The names in the generated code, which the contract (below the code generator) does not spell: the C function
of a routine (``NAME_role``, :func:`c_symbol`, also the manifest's ``functions`` and ``aggsym list``), its
prototype, the header's size and index macros, and the NumPy function's parameter list (:func:`python_parameters`,
which the C target's emitted routine carries for the NumPy target)."""
from __future__ import annotations

from ..contract import Output, Routine, signature


def c_symbol(model, routine: Routine) -> str:
    return f"{model.name}_{routine.role}"


def c_prototype(model, routine: Routine, scalar: str = "double") -> str:
    """``void NAME_role(const double *q, ..., double *out)``: inputs in the order q, qd, qdd|tau, t, p, then the
    outputs (``float`` in place of ``double`` for ``scalar="float"``)."""
    args = [f"const {scalar} *{i}" for i in signature(routine, model)] + \
        [f"{scalar} *{o.name}" for o in routine.written]
    return f"{'int' if routine.status else 'void'} {c_symbol(model, routine)}({', '.join(args)})"


def python_parameters(model, routine: Routine) -> str:
    """The NumPy function's parameter list: the same inputs, ``p=None`` (the defaults) last."""
    return ", ".join(f"{i}=None" if i == "p" else i for i in signature(routine, model))


def size_macro(model, routine: Routine, output: Output) -> str:
    """``NAME_ROLE_SIZE`` for a routine's only output, ``NAME_ROLE_OUTPUT_SIZE`` for one of several."""
    parts = [model.name, routine.role] + ([output.name] if len(routine.written) > 1 else [])
    return "_".join(parts).upper() + "_SIZE"


def parameter_macro(model, parameter) -> str:
    """``NAME_P_<param>``: the index of a parameter in p, the parameter's name spelled as in the model (so that
    ``m`` and ``M`` stay two macros)."""
    return f"{model.name.upper()}_P_{parameter.name}"


def header_macros(model, routines, scalar: str = "double") -> list:
    """(macro, value, comment) of the header: NQ, NP, one index per parameter, one size per output array."""
    out = [(f"{model.name}_NQ".upper(), model.nq, "the length of q" if model.nq != model.nv else
            "coordinates: the length of q, qd, qdd, tau"),
           (f"{model.name}_NV".upper(), model.nv, "velocities: the length of qd, qdd, tau" +
            (" (q has NQ entries: quaternions)" if model.nq != model.nv else " (= NQ)")),
           (f"{model.name}_NP".upper(), len(model.parameters), "parameters: the length of p")]
    for i, p in enumerate(model.parameters):
        out.append((parameter_macro(model, p), i, "index in p"))
    for r in routines:
        for o in r.written:
            shape = o.shape(model)
            size = 1
            for n in shape:
                size *= n
            out.append((size_macro(model, r, o), size,
                        f"{r.role}: {o.name}, " + " x ".join(str(n) for n in shape) + f" {scalar}s"))
    return out
