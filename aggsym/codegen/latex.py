"""The LaTeX document of a model's equations of motion.

Small models (at most :data:`CLOSED_FORM_MAX_NQ` coordinates, :data:`CLOSED_FORM_MAX_NODES` program nodes and
:data:`CLOSED_FORM_MAX_TERMS` expanded terms (:func:`expanded_terms`) in
A, b and g) get closed forms: every entry of A, b and g
simplified by SymPy, written as the scalar equations ``sum_j A_ij q''_j + b_i + g_i = tau_i`` (for the double
pendulum these are (2.26)).  Larger models get the intermediate-variable form: the straight-line programs of
A, b and g, one named intermediate per line, as the C code computes them.
"""
from __future__ import annotations

import sympy as sp
from sympy.printing.latex import LatexPrinter

from ..core.program import expanded_terms, straight_line, to_sympy
from ..model.types import TIME
from ..symbolic import Equations, coordinate_symbols
from .printing import _TREE, Converter, LinComb, Num, Prod, Ref

CLOSED_FORM_MAX_NQ = 4
CLOSED_FORM_MAX_NODES = 300  # and at most this many program nodes in A, b, g (SymPy's simplification of the
# flywheel on a spherical pair, 3 coordinates but ~570 nodes, does not finish in minutes)
CLOSED_FORM_MAX_TERMS = 1000  # and at most this many terms in the expansion of any entry (see expanded_terms)


def _dotted(name_latex: str, accent: str) -> str:
    base, sep, sub = name_latex.partition("_")
    return f"\\{accent}{{{base}}}{sep}{sub}"


def symbol_names(model) -> dict:
    """LaTeX for the coordinate symbols and their derivatives: theta36 -> \\theta_{36}, \\dot{\\theta}_{36}."""
    _, qd, qdd = coordinate_symbols(model)
    free = {c.name for b in model.bodies if b.pair.quaternion for c in b.pair.coordinates}
    names = {}
    for c, d, dd in zip(model.coordinates, qd, qdd):
        base = sp.latex(sp.Symbol(c.name, real=True))
        if c.name in free:  # a free-flyer's or ball's velocity is no coordinate's rate: v, its rate v-dot
            names[d], names[dd] = base, _dotted(base, "dot")
        else:
            names[d], names[dd] = _dotted(base, "dot"), _dotted(base, "ddot")
    return names


def _latex(expr, names):
    return sp.latex(expr, symbol_names=names, long_frac_ratio=2, mul_symbol=None)


def _terms(expr, names) -> list:
    """LaTeX of the top-level terms of a sum, each with its sign: ['+ a', '- b c', ...]."""
    terms = sp.Add.make_args(expr) if expr.is_Add else (expr,)
    out = []
    for t in terms:
        negative = t.could_extract_minus_sign()
        text = _latex(-t if negative else t, names)
        out.append(("- " if negative else "+ ") + text)
    return out


def broken(lhs: str, terms: list, rhs: str | None = None, width: int = 150) -> str:
    """An align* row ``lhs &= t1 + t2 ...`` broken into several lines of at most ``width`` LaTeX characters;
    with ``rhs`` the row is ``&t1 + ... = rhs`` instead."""
    lines, current = [], ""
    for t in terms or ["+ 0"]:
        if current and len(current) + len(t) > width:
            lines.append(current)
            current = ""
        current += (" " if current else "") + t
    lines.append(current)
    first = lines[0][2:] if lines[0].startswith("+ ") else lines[0]
    rows = [first] + lines[1:]
    if rhs is None:
        head = f"{lhs} &= {rows[0]}"
        tail = [f"&\\quad {r}" for r in rows[1:]]
    else:
        head = f"&{rows[0]}"
        tail = [f"&\\quad {r}" for r in rows[1:]]
        if tail:
            tail[-1] += f" = {rhs}"
        else:
            head += f" = {rhs}"
    return " \\\\\n".join([head] + tail)


def closed_form(model):
    """Closed forms: the nonzero entries of A (upper triangle), b and g, and the scalar equations (2.26)."""
    eq = Equations(model, simplify=True)
    names = symbol_names(model)
    n = model.nv
    sections = []
    rows = [broken(f"A_{{{i + 1}{j + 1}}}", _terms(eq.A[i, j], names))
            for i in range(n) for j in range(i, n) if eq.A[i, j] != 0]
    sections.append(("Inertia matrix $A(q)$ (upper triangle; the other entries are zero)", rows))
    rows = [broken(f"b_{{{i + 1}}}", _terms(eq.b[i], names)) for i in range(n) if eq.b[i] != 0]
    sections.append(("Velocity terms $b(q,\\dot q)$", rows))
    rows = [broken(f"g_{{{i + 1}}}", _terms(eq.g[i], names)) for i in range(n) if eq.g[i] != 0]
    sections.append(("Gravity $g(q)$", rows))
    if any(x != 0 for x in eq.c):
        rows = [broken(f"c_{{{i + 1}}}", _terms(eq.c[i], names)) for i in range(n) if eq.c[i] != 0]
        sections.append(("Elastic forces $c(q) = C\\,(q - q_0)$ (2.27)", rows))
    rows = []
    for i in range(n):  # u*_i by the sweeps, its q'' coefficients and the rest d_i (2.45)
        u = sp.expand(eq.u_star[i])
        terms = []
        for j in range(n):
            a = eq.closed_form(u.coeff(eq.qdd[j]))
            if a == 0:
                continue
            if a.is_Add:
                terms.append(f"+ \\left({_latex(a, names)}\\right) {names[eq.qdd[j]]}")
            else:
                (sign, text), = [(t[0], t[2:]) for t in _terms(a, names)]
                terms.append(f"{sign} {text} {names[eq.qdd[j]]}" if text != "1" else f"{sign} {names[eq.qdd[j]]}")
        rest = eq.closed_form(u.subs({x: 0 for x in eq.qdd}))
        terms += _terms(rest, names) if rest != 0 else []
        rows.append(broken("", terms, rhs=f"u^*_{{{i + 1}}}"))
    sections.append(("The preplanned control $u^* = \\tau$ by the forward and backward sweeps (2.39)-(2.42), "
                     "one equation per coordinate (for the double pendulum: (2.26))", rows))
    return sections


def cauchy_form(model):
    """The transvective Cauchy form (3.20) in the book's matrix-product form: the arguments <t,k>, the pivots
    (beta,beta)_k, and q'' = T^T diag(1/(beta,beta)) T F with T the product of the transvections (3.9)."""
    eq = Equations(model)
    names = symbol_names(model)
    n = model.nv
    factors, diag = eq.transvective_factors(simplify=False)

    def readable(x):
        num, den = sp.fraction(sp.together(x))
        return eq.closed_form(num) / eq.closed_form(den) if den != 1 else eq.closed_form(num)

    rows, args = [], []
    for f in factors:
        (t, k), = [(i, j) for i in range(n) for j in range(n) if i != j and f[i, j] != 0]
        value = readable(-f[t, k])
        if value == 0:
            continue
        args.append((t, k))
        rows.append(broken(f"\\langle {t + 1},{k + 1}\\rangle", _terms(value, names)))
    for k in range(n):
        rows.append(broken(f"(\\beta,\\beta)_{{{k + 1}}}", _terms(readable(diag[k, k]), names)))

    def matrix(entries):
        body = " \\\\ ".join(" & ".join(entries(i, j) for j in range(n)) for i in range(n))
        return f"\\begin{{pmatrix}} {body} \\end{{pmatrix}}"

    def factor(t, k, transpose=False):
        def entry(i, j):
            if i == j:
                return "1"
            if (i, j) == ((k, t) if transpose else (t, k)):
                return f"-\\langle {t + 1},{k + 1}\\rangle"
            return "0"
        return matrix(entry)

    inv_diag = matrix(lambda i, j: f"\\frac{{1}}{{(\\beta,\\beta)_{{{i + 1}}}}}" if i == j else "0")
    T = " ".join(factor(t, k) for t, k in args) or "E"
    Tt = " ".join(factor(t, k, True) for t, k in reversed(args)) or "E"
    product = f"\\ddot q = {Tt} \\, {inv_diag} \\, {T} \\, F, \\qquad F = \\tau - b(q,\\dot q) - g(q)"
    return rows, product


class _TreePrinter:
    """The dispatch, names and sums of the LaTeX printer of aggsym's expression trees (:mod:`.printing`)."""

    def _print(self, expr, **kwargs):
        """The ``_print_<Class>`` method of an expression tree node, looked up once per printer and class (SymPy's
        own dispatch walks the class's MRO by name on every call); anything else goes to SymPy's dispatch."""
        methods = self.__dict__.get("_tree_methods")
        if methods is None:
            methods = self._tree_methods = {cls: getattr(self, "_print_" + cls.__name__) for cls in _TREE}
        method = methods.get(expr.__class__)
        if method is None or kwargs:
            return super()._print(expr, **kwargs)
        return method(expr)

    def _print_Ref(self, e):
        return str(e.symbol)

    def _print_LinComb(self, e):
        parts = []
        for k, (sign, term) in enumerate(e.terms):
            cls = term.__class__
            text = str(term.symbol) if cls is Ref else self._print(term)
            if cls is LinComb and (sign < 0 or len(term.terms) > 1 and k > 0):
                text = f"({text})"
            if k == 0:
                parts.append(f"-{text}" if sign < 0 else text)
            else:
                parts.append(f" - {text}" if sign < 0 else f" + {text}")
        return "".join(parts)


class IntermediatePrinter(_TreePrinter, LatexPrinter):
    """LaTeX of aggsym's expression trees (a SymPy LaTeX printer subclass); names are LaTeX already."""

    functions = {"sin": "\\sin", "cos": "\\cos", "tan": "\\tan", "exp": "\\exp", "log": "\\log",
                 "asin": "\\arcsin", "acos": "\\arccos", "atan": "\\arctan", "atan2": "\\operatorname{atan2}",
                 "sign": "\\operatorname{sign}"}

    def _print_Num(self, e):
        # SymPy's LaTeX of a number costs tens of microseconds; a large model repeats its constants many times
        key = (e.value.__class__, e.value)
        cache = self.__dict__.setdefault("_numbers", {})
        text = cache.get(key)
        if text is None:
            text = cache[key] = sp.latex(sp.nsimplify(e.value) if not isinstance(e.value, float)
                                         else sp.Float(e.value, 6))
        return text

    def _print_Call(self, e):
        arg = ", ".join(self._print(a) for a in e.args)
        if e.name == "sqrt":
            return f"\\sqrt{{{arg}}}"
        if e.name == "abs":
            return f"\\left|{arg}\\right|"
        return f"{self.functions[e.name]}{{\\left({arg}\\right)}}"

    def _operand(self, e):
        text = self._print(e)
        if isinstance(e, LinComb) or (isinstance(e, Prod) and e.sign < 0):
            return f"\\left({text}\\right)"
        return text

    def _print_Prod(self, e):
        factors = [self._operand(f) for f in e.factors]
        body = " ".join(f if not (k and isinstance(e.factors[k], Num)) else f"\\cdot {f}"
                        for k, f in enumerate(factors))
        return f"-{body}" if e.sign < 0 else body

    def _print_Ratio(self, e):
        return f"\\frac{{{self._print(e.num)}}}{{{self._print(e.den)}}}"


LATEX_ROLES = ("inertia", "bias", "gravity")  # the routines whose programs the document prints (and sizes by)


def intermediate_form(model, prog, outputs, roles=LATEX_ROLES, straight=None):
    """The straight-line programs of A, b, g as LaTeX assignments (x_k = ...); ``straight``: {role: its
    :func:`straight_line`} where already formed (the C's)."""
    q, qd, _ = coordinate_symbols(model)
    names = symbol_names(model)
    blocks = []
    for role in roles:
        if role not in outputs:
            continue
        sl = (straight or {}).get(role) or straight_line(prog, outputs[role])
        sym = {}
        for kind, i in sl.inputs:
            node = prog.inputs[(kind, i)]
            if kind == "q":
                sym[node.id] = sp.latex(q[i])
            elif kind == "qd":
                sym[node.id] = names[qd[i]]
            elif kind == "t":
                sym[node.id] = "t"
            else:
                sym[node.id] = sp.latex(model.parameter_symbols[i])
        for k, i in enumerate(sl.temps):
            sym[i] = f"x_{{{k}}}"
        conv = Converter(prog, sym)
        printer = IntermediatePrinter()
        lines = [f"{sym[i]} &= {printer._print(conv(prog.nodes[i]))}" for i in sl.temps]
        label = {"inertia": "A", "bias": "b", "gravity": "g"}[role]
        flat = outputs[role][0]
        for k, x in enumerate(flat):
            named = getattr(x, "id", None) in sym
            value = printer._print(conv(x, top=not named))
            if role == "inertia":
                i, j = divmod(k, model.nv)
                if j < i:
                    continue
                target = f"{label}_{{{i + 1},{j + 1}}}"
            else:
                target = f"{label}_{{{k + 1}}}"
            if value != "0":
                lines.append(f"{target} &= {value}")
        blocks.append((role, lines))
    return blocks


def constraint_section(model, prog, outputs, small: bool):
    """The constraints (chapter 4): a table of them and, for small models, the nonzero entries of
    D_lambda^T = J (4.27) and of gamma = J' qd, simplified."""
    if not model.constraints:
        return None
    rows = []
    for c in model.constraints:
        if c.joint_row is not None:  # a joint-space row: no body or medium; the coordinates it ties
            names = [name for name, _ in c.joint_row.first + c.joint_row.second]
            rows.append((c.name, "(joint space)", "", "row in " + ", ".join(dict.fromkeys(names)), ""))
            continue
        law = "" if c.friction is None else f"{c.friction[0]} {c.friction[1]}"
        rows.append((c.name, c.body, c.medium, " ".join(c.rows), law))
    entries = []
    if small and "constraint_jacobian" in outputs and "constraint_bias" in outputs:
        names = symbol_names(model)
        q, qd, _ = coordinate_symbols(model)
        symbols = {("p", i): s for i, s in enumerate(model.parameter_symbols)}
        symbols.update({("q", i): s for i, s in enumerate(q)})
        symbols.update({("qd", i): s for i, s in enumerate(qd)})
        symbols[("t", 0)] = TIME
        J = to_sympy(prog, outputs["constraint_jacobian"][0], symbols)
        gamma = to_sympy(prog, outputs["constraint_bias"][0], symbols)
        n = model.nv
        for r in range(model.constraint_rows):
            for j in range(n):
                x = sp.trigsimp(J[r * n + j])
                if x != 0:
                    entries.append(broken(f"(D_\\lambda^T)_{{{r + 1}{j + 1}}}", _terms(x, names)))
        for r in range(model.constraint_rows):
            x = sp.expand(gamma[r]) if model.time_dependent else sp.trigsimp(sp.expand(gamma[r]))
            if x != 0:
                entries.append(broken(f"\\gamma_{{{r + 1}}}", _terms(x, names)))
    return {"table": rows, "entries": entries, "m": model.constraint_rows, "moving": model.time_dependent,
            "stabilization": [sp.latex(x) for x in model.stabilization]}


def latex_document(model, template, prog, outputs, straight=None) -> str:
    """The standalone LaTeX document (rendered through ``template``, the LaTeX target's latex/model.tex.j2); ``straight``: {role: straight line}
    of routines already emitted, not formed again."""
    # the closed forms are sized by the programs of A, b and g: without all three emitted there is no measure of
    # what SymPy would be asked to simplify (a 4-link chain's derivatives alone once ran it for many minutes)
    sized = all(role in outputs for role in LATEX_ROLES)
    flat = [x for role in LATEX_ROLES if role in outputs for o in outputs[role] for x in o]
    small = (sized and not model.couplings and model.nv <= CLOSED_FORM_MAX_NQ
             and len(prog.reachable(flat)) <= CLOSED_FORM_MAX_NODES
             and expanded_terms(prog, flat) <= CLOSED_FORM_MAX_TERMS)
    names = symbol_names(model)
    q, qd, qdd = coordinate_symbols(model)
    ctx = {
        "name": model.name,
        "description": model.description or "",
        "coordinates": [(sp.latex(s), joint, kind) for s, (_, joint, kind) in zip(q, model.positions)],
        "parameters": [(sp.latex(p.symbol), repr(p.value)) for p in model.parameters],
        "gravity": ", ".join(sp.latex(g) for g in model.gravity),
        "closed": closed_form(model) if small else None,
        "cauchy": cauchy_form(model) if small and "forward_dynamics" in outputs else None,
        "blocks": None if small else intermediate_form(model, prog, outputs, straight=straight),
        "constraints": constraint_section(model, prog, outputs, small),
        "nq": model.nq,
        "qdd": [names[s] for s in qdd],
    }
    return template.render(ctx)
