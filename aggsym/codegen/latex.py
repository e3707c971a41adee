"""The LaTeX document of a model's equations of motion.

Small models (at most :data:`CLOSED_FORM_MAX_NQ` coordinates) get closed forms: every entry of A, b and g
simplified by SymPy, written as the scalar equations ``sum_j A_ij q''_j + b_i + g_i = tau_i`` (for the double
pendulum these are (2.26)).  Larger models get the intermediate-variable form: the straight-line programs of
A, b and g, one named intermediate per line, as the C code computes them.
"""
from __future__ import annotations

import re

import sympy as sp

from ..equations import Equations, coordinate_symbols
from .printing import Converter, straight_line

CLOSED_FORM_MAX_NQ = 4


def _dotted(name_latex: str, accent: str) -> str:
    base, sep, sub = name_latex.partition("_")
    return f"\\{accent}{{{base}}}{sep}{sub}"


def symbol_names(model) -> dict:
    """LaTeX for the coordinate symbols and their derivatives: theta36 -> \\theta_{36}, \\dot{\\theta}_{36}."""
    q, qd, qdd = coordinate_symbols(model)
    names = {}
    for s, d, dd in zip(q, qd, qdd):
        base = sp.latex(s)
        names[d] = _dotted(base, "dot")
        names[dd] = _dotted(base, "ddot")
    return names


def _latex(expr, names):
    return sp.latex(expr, symbol_names=names, long_frac_ratio=2, mul_symbol=None)


def closed_form(model):
    """Scalar equations (2.26)-style: one LaTeX line per coordinate."""
    eq = Equations(model, simplify=True)
    names = symbol_names(model)
    tau = [sp.Symbol(f"tau_{{{c.name}}}") for c in model.coordinates]
    lines = []
    for i in range(model.nq):
        terms = []
        for j in range(model.nq):
            if eq.A[i, j] != 0:
                coeff = eq.A[i, j]
                coeff_tex = _latex(coeff, names)
                if coeff.is_Add:
                    coeff_tex = f"\\left({coeff_tex}\\right)"
                terms.append(f"{coeff_tex} {names[eq.qdd[j]]}")
        rest = eq.closed_form(eq.b[i] + eq.g[i])
        if rest != 0:
            terms.append(_latex(rest, names))
        lhs = " + ".join(terms).replace("+ -", "- ") or "0"
        lines.append(f"{lhs} &= {sp.latex(tau[i])}")
    return lines


def intermediate_form(model, prog, outputs, roles=("inertia", "bias", "gravity")):
    """The straight-line programs of A, b, g as LaTeX assignments (x_k = ...)."""
    q, qd, _ = coordinate_symbols(model)
    names = symbol_names(model)
    blocks = []
    for role in roles:
        if role not in outputs:
            continue
        sl = straight_line(prog, outputs[role])
        sym = {}
        for kind, i in sl.inputs:
            node = prog.inputs[(kind, i)]
            sym[node.id] = {"q": q, "qd": qd}.get(kind, [None] * model.nq)[i] if kind in ("q", "qd") \
                else model.parameter_symbols[i]
        for k, i in enumerate(sl.temps):
            sym[i] = sp.Symbol(f"x_{{{k}}}")
        conv = Converter(prog, sym)
        lines = [f"{sp.latex(sym[i])} &= {_latex(conv(prog.nodes[i]), names)}" for i in sl.temps]
        label = {"inertia": "A", "bias": "b", "gravity": "g"}[role]
        flat = outputs[role][0]
        for k, x in enumerate(flat):
            named = getattr(x, "id", None) in sym
            value = _latex(conv(x, top=not named), names)
            if role == "inertia":
                i, j = divmod(k, model.nq)
                if j < i:
                    continue
                target = f"{label}_{{{i + 1},{j + 1}}}"
            else:
                target = f"{label}_{{{k + 1}}}"
            if value != "0":
                lines.append(f"{target} &= {value}")
        blocks.append((role, lines))
    return blocks


def _escape(text: str) -> str:
    return re.sub(r"([_%&#$])", r"\\\1", text)


def latex_document(model, env, prog, outputs) -> str:
    """The standalone LaTeX document (rendered through templates/model.tex.j2)."""
    small = model.nq <= CLOSED_FORM_MAX_NQ
    names = symbol_names(model)
    q, qd, qdd = coordinate_symbols(model)
    ctx = {
        "name": _escape(model.name),
        "description": _escape(model.description or ""),
        "coordinates": [(sp.latex(s), _escape(c.joint), c.kind) for s, c in zip(q, model.coordinates)],
        "parameters": [(sp.latex(p.symbol), repr(p.value)) for p in model.parameters],
        "gravity": ", ".join(sp.latex(g) for g in model.gravity),
        "closed": closed_form(model) if small else None,
        "blocks": None if small else intermediate_form(model, prog, outputs),
        "nq": model.nq,
        "qdd": [names[s] for s in qdd],
    }
    return env.get_template("model.tex.j2").render(ctx)
