"""The LaTeX document of a model's equations of motion, to be read and printed.

Small models (at most :data:`CLOSED_FORM_MAX_NQ` coordinates, :data:`CLOSED_FORM_MAX_NODES` program nodes and
:data:`CLOSED_FORM_MAX_TERMS` expanded terms (:func:`expanded_terms`) in A, b and g) get closed forms: every entry
of A, b and g simplified by SymPy, the inverse dynamics as the scalar equations ``sum_j A_ij q''_j + b_i + g_i =
tau_i`` (for the double pendulum these are (2.26)) and the forward dynamics in the transvective Cauchy form
(3.20).  Larger models get the intermediate-variable form: the straight-line programs of A, b, g and of the
transvective factors, one named intermediate per line as the C code computes them, then the inverse dynamics
tau_i = sum_j A_ij q''_j + b_i + g_i and the forward dynamics q'' = T^T diag(1/(beta,beta)) T (tau - b - g)
written out coordinate by coordinate (3.9), (3.10), (3.20).

The notation (q_1..q_n for names that are not the book's, short parameter symbols, their tables) is
:mod:`.latex_symbols`; the breaking of long lines to the page is :mod:`.latex_layout`, of pieces printed by
:mod:`.latex_terms`.  A is symmetric; only its upper triangle is shown, and the document says so.
"""
from __future__ import annotations

import sympy as sp

from ..core.program import expanded_terms, straight_line, to_sympy
from ..mechanics.transvective import transvection_pairs
from ..model.tree import Tree
from ..model.types import TIME
from ..symbolic import Equations, coordinate_symbols
from .latex_layout import SAFETY, TEXT_WIDTH, Piece, align_rows, matrix, paren
from .latex_symbols import Notation
from .latex_terms import TreePieces, sympy_latex, sympy_terms
from .printing import Converter

CLOSED_FORM_MAX_NQ = 4
CLOSED_FORM_MAX_NODES = 300  # and at most this many program nodes in A, b, g (SymPy's simplification of the
# flywheel on a spherical pair, 3 coordinates but ~570 nodes, does not finish in minutes)
CLOSED_FORM_MAX_TERMS = 1000  # and at most this many terms in the expansion of any entry (see expanded_terms)
ROOM = TEXT_WIDTH * SAFETY - 60.0  # pt a closed-form term may take before it is opened (a guess at the left column)


def _rows(rows) -> list:
    """align* rows (lhs, pieces, tail) broken to the page."""
    return align_rows(rows)


def closed_form(model, notation):
    """Closed forms: the nonzero entries of A (upper triangle), b, g (and c), the inverse dynamics by the sweeps
    (2.39)-(2.42) per coordinate; as sections (title, align* rows)."""
    eq = Equations(model, simplify=True)
    names = notation.names
    n = model.nv

    def entries(label, values):
        return _rows([(label(i), sympy_terms(x, names, ROOM), None) for i, x in values if x != 0])

    sections = [("Inertia matrix $A(q)$", entries(lambda ij: f"A_{{{ij[0] + 1}{ij[1] + 1}}}",
                                                  [((i, j), eq.A[i, j]) for i in range(n) for j in range(i, n)])),
                ("Velocity terms $b(q,\\dot q)$", entries(lambda i: f"b_{{{i + 1}}}", enumerate(eq.b))),
                ("Gravity $g(q)$", entries(lambda i: f"g_{{{i + 1}}}", enumerate(eq.g)))]
    if any(x != 0 for x in eq.c):
        sections.append(("Elastic forces $c(q) = C\\,(q - q_0)$ (2.27)", entries(lambda i: f"c_{{{i + 1}}}",
                                                                                     enumerate(eq.c))))
    rows = []
    for i in range(n):  # u*_i by the sweeps, its q'' coefficients and the rest d_i (2.45)
        u = sp.expand(eq.u_star[i])
        pieces = []
        for j in range(n):
            a = eq.closed_form(u.coeff(eq.qdd[j]))
            if a == 0:
                continue
            qdd = names[eq.qdd[j]]
            inner = sympy_terms(a, names, ROOM)
            if a.is_Add:
                left, right = paren(1)
                first = inner[0].text[2:] if inner[0].text.startswith("+ ") else inner[0].text
                inner[0] = Piece(f"+ {left}{first}", True)
                inner[-1] = Piece(f"{inner[-1].text}{right} {qdd}", inner[-1].brk)
            elif len(inner) == 1 and inner[0].text[2:] == "1":
                inner[0] = Piece(f"{inner[0].text[:2]}{qdd}", True)
            else:
                inner[-1] = Piece(f"{inner[-1].text} {qdd}", inner[-1].brk)
            pieces.extend(inner)
        rest = eq.closed_form(u.subs({x: 0 for x in eq.qdd}))
        pieces += sympy_terms(rest, names, ROOM) if rest != 0 else []
        rows.append((None, pieces, f"= u^*_{{{i + 1}}}"))
    sections.append(("Inverse dynamics: $u^* = \\tau$ by the sweeps (2.39)-(2.42) (for the double pendulum: (2.26))",
                     _rows(rows)))
    return sections


def cauchy_form(model, notation):
    """The transvective Cauchy form (3.20) in the book's matrix-product form: the arguments <t,k>, the pivots
    (beta,beta)_k, and q'' = T^T diag(1/(beta,beta)) T F with T the product of the transvections (3.9)."""
    eq = Equations(model)
    names = notation.names
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
        rows.append((f"\\langle {t + 1},{k + 1}\\rangle", sympy_terms(value, names, ROOM), None))
    for k in range(n):
        rows.append((f"(\\beta,\\beta)_{{{k + 1}}}", sympy_terms(readable(diag[k, k]), names, ROOM), None))

    def factor(t, k, transpose=False):
        def entry(i, j):
            if i == j:
                return "1"
            if (i, j) == ((k, t) if transpose else (t, k)):
                return f"-\\langle {t + 1},{k + 1}\\rangle"
            return "0"
        return matrix([[entry(i, j) for j in range(n)] for i in range(n)])

    inv_diag = matrix([[f"\\frac{{1}}{{(\\beta,\\beta)_{{{i + 1}}}}}" if i == j else "0" for j in range(n)]
                       for i in range(n)])
    product = ([factor(t, k, True) for t, k in reversed(args)] or [Piece("E")]) + [inv_diag] + (
        [factor(t, k) for t, k in args] or [Piece("E", True)]) + [Piece("F", True)]
    return _rows(rows), _rows([("\\ddot q", product, None)]) + _rows(
        [("F", [Piece("\\tau - b(q,\\dot q) - g(q)")], None)])


LATEX_ROLES = ("inertia", "bias", "gravity")  # the routines whose programs the document sizes the closed forms by
PRINTED_ROLES = LATEX_ROLES + ("transvective_factors",)  # the programs the intermediate form prints
_TITLES = {"inertia": "Inertia matrix $A(q)$", "bias": "Velocity terms $b(q,\\dot q)$",
           "gravity": "Gravity $g(q)$",
           "transvective_factors": "Transvective factors: the arguments $\\langle t,k\\rangle$ and pivots "
                                   "$(\\beta,\\beta)_k$ of $T A(q) T^T = \\mathrm{diag}\\,(\\beta,\\beta)_k$ "
                                   "(3.7)-(3.11)"}


def _output_labels(model, role):
    """The LaTeX name of every entry of a routine's flat outputs (None: not shown: A's lower triangle)."""
    n = model.nv
    if role == "inertia":
        return [[f"A_{{{i + 1},{j + 1}}}" if j >= i else None for i in range(n) for j in range(n)]]
    if role == "transvective_factors":
        pairs = transvection_pairs(Tree.of(model))
        return [[f"\\langle {t + 1},{k + 1}\\rangle" for t, k in pairs],
                [f"(\\beta,\\beta)_{{{k + 1}}}" for k in range(n)]]
    return [[f"{ {'bias': 'b', 'gravity': 'g'}[role]}_{{{i + 1}}}" for i in range(n)]]


def intermediate_form(model, prog, outputs, notation, roles=PRINTED_ROLES, straight=None):
    """The straight-line programs of the ``roles`` as LaTeX: [(role, rows, nonzero)] with the intermediates
    x_1, x_2, ... (each block numbers its own) and one row per nonzero output entry shown; ``nonzero`` {label:
    True} of those entries.  ``straight``: {role: its :func:`straight_line`} where already formed (the C's)."""
    names = notation.names
    q, qd, _ = coordinate_symbols(model)
    letter = notation.letter
    blocks = []
    for role in roles:
        if role not in outputs:
            continue
        sl = (straight or {}).get(role) or straight_line(prog, outputs[role])
        sym = {}
        for kind, i in sl.inputs:
            node = prog.inputs[(kind, i)]
            if kind == "q":
                sym[node.id] = names[q[i]]
            elif kind == "qd":
                sym[node.id] = names[qd[i]]
            elif kind == "t":
                sym[node.id] = "t"
            else:
                sym[node.id] = names[model.parameter_symbols[i]]
        for k, i in enumerate(sl.temps):
            sym[i] = f"{letter}_{{{k + 1}}}"
        conv = Converter(prog, sym)
        printer = TreePieces()
        rows = [(sym[i], printer.print(conv(prog.nodes[i]))[0], None) for i in sl.temps]
        shown = {}
        for flat, labels in zip(outputs[role], _output_labels(model, role)):
            for x, label in zip(flat, labels):
                if label is None:
                    continue
                named = getattr(x, "id", None) in sym
                pieces = printer.print(conv(x, top=not named))[0]
                if len(pieces) == 1 and pieces[0].text == "0":
                    continue
                shown[label] = True
                rows.append((label, pieces, None))
        blocks.append((_TITLES[role], _rows(rows), shown))
    return blocks


def dynamics_rows(model, notation, shown, elastic: bool):
    """The inverse dynamics tau_i = sum_j A_ij q''_j + b_i + g_i (+ c_i with elastic pairs), A_ij = A_ji below
    the diagonal, with the entries ``shown`` nonzero (the others are zero); and F_i = tau_i - b_i - g_i (- c_i)
    of the forward dynamics."""
    n = model.nv
    rows, forces = [], []
    for i in range(n):
        pieces = []
        for j in range(n):
            a, b = min(i, j), max(i, j)
            if shown.get(f"A_{{{a + 1},{b + 1}}}"):
                pieces.append(Piece(f"+ A_{{{a + 1},{b + 1}}} {notation.accelerations[j]}", True))
        rest = [label for label in (f"b_{{{i + 1}}}", f"g_{{{i + 1}}}") if shown.get(label)]
        rest += [f"c_{{{i + 1}}}"] if elastic else []
        pieces += [Piece(f"+ {label}", True) for label in rest]
        rows.append((f"\\tau_{{{i + 1}}}", pieces, None))
        forces.append((f"F_{{{i + 1}}}", [Piece(f"\\tau_{{{i + 1}}}")] + [Piece(f"- {x}", True) for x in rest], None))
    return _rows(rows), _rows(forces)


def cauchy_rows(model, notation, shown_factors):
    """q'' = T^T diag(1/(beta,beta)) T F (3.20) coordinate by coordinate: (T F)_t = F_t - sum_{k below t}
    <t,k> (T F)_k for t descending (3.9), then q''_k = (T F)_k / (beta,beta)_k - sum_{t above k} <t,k> q''_t for
    k ascending (3.10); only the arguments ``shown_factors`` nonzero enter."""
    n = model.nv
    pairs = [(t, k) for t, k in transvection_pairs(Tree.of(model))
             if shown_factors.get(f"\\langle {t + 1},{k + 1}\\rangle")]
    TF = []
    for t in reversed(range(n)):
        pieces = [Piece(f"F_{{{t + 1}}}")]
        pieces += [Piece(f"- \\langle {t + 1},{k + 1}\\rangle (TF)_{{{k + 1}}}", True)
                   for tt, k in sorted(pairs, key=lambda p: -p[1]) if tt == t]
        TF.append((f"(TF)_{{{t + 1}}}", pieces, None))
    acc = []
    for k in range(n):
        pieces = [Piece(f"\\frac{{(TF)_{{{k + 1}}}}}{{(\\beta,\\beta)_{{{k + 1}}}}}")]
        pieces += [Piece(f"- \\langle {t + 1},{k + 1}\\rangle {notation.accelerations[t]}", True)
                   for t, kk in pairs if kk == k]
        acc.append((notation.accelerations[k], pieces, None))
    return _rows(TF), _rows(acc)


def constraint_section(model, prog, outputs, small: bool, notation):
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
        names = notation.names
        q, qd, _ = coordinate_symbols(model)
        symbols = {("p", i): s for i, s in enumerate(model.parameter_symbols)}
        symbols.update({("q", i): s for i, s in enumerate(q)})
        symbols.update({("qd", i): s for i, s in enumerate(qd)})
        symbols[("t", 0)] = TIME
        J = to_sympy(prog, outputs["constraint_jacobian"][0], symbols)
        gamma = to_sympy(prog, outputs["constraint_bias"][0], symbols)
        n = model.nv
        lines = []
        for r in range(model.constraint_rows):
            for j in range(n):
                x = sp.trigsimp(J[r * n + j])
                if x != 0:
                    lines.append((f"(D_\\lambda^T)_{{{r + 1}{j + 1}}}", sympy_terms(x, names, ROOM), None))
        for r in range(model.constraint_rows):
            x = sp.expand(gamma[r]) if model.time_dependent else sp.trigsimp(sp.expand(gamma[r]))
            if x != 0:
                lines.append((f"\\gamma_{{{r + 1}}}", sympy_terms(x, names, ROOM), None))
        entries = _rows(lines)
    return {"table": rows, "entries": entries, "m": model.constraint_rows, "moving": model.time_dependent,
            "stabilization": [sympy_latex(x, notation.names) for x in model.stabilization]}


def latex_document(model, template, prog, outputs, straight=None, omitted=None) -> str:
    """The standalone LaTeX document (rendered through ``template``, the LaTeX target's latex/model.tex.j2);
    ``straight``: {role: straight line} of routines already emitted, not formed again; ``omitted``: {role: why}
    of the routines left out (a singular A: no forward dynamics)."""
    # the closed forms are sized by the programs of A, b and g: without all three emitted there is no measure of
    # what SymPy would be asked to simplify (a 4-link chain's derivatives alone once ran it for many minutes)
    sized = all(role in outputs for role in LATEX_ROLES)
    flat = [x for role in LATEX_ROLES if role in outputs for o in outputs[role] for x in o]
    small = (sized and not model.couplings and model.nv <= CLOSED_FORM_MAX_NQ
             and len(prog.reachable(flat)) <= CLOSED_FORM_MAX_NODES
             and expanded_terms(prog, flat) <= CLOSED_FORM_MAX_TERMS)
    notation = Notation(model)
    elastic = any(b.pair.elastic for b in model.bodies)
    ctx = {
        "name": model.name,
        "description": model.description or "",
        "notation": notation,
        "gravity": ", ".join(sympy_latex(g, notation.names) for g in model.gravity),
        "closed": closed_form(model, notation) if small else None,
        "cauchy": cauchy_form(model, notation) if small and "forward_dynamics" in outputs else None,
        "constraints": constraint_section(model, prog, outputs, small, notation),
        "elastic": elastic,
        "friction": model.has_joint_dynamics,
        "forward_omitted": (omitted or {}).get("forward_dynamics"),
        "forward": "forward_dynamics" in outputs,
        "coupled": bool(model.couplings),
        "nv": model.nv,
        "blocks": None, "inverse": None, "forces": None, "transvected": None, "accelerations": None,
    }
    if not small:
        blocks = intermediate_form(model, prog, outputs, notation, straight=straight)
        shown = {k: v for _, _, s in blocks for k, v in s.items()}
        ctx["blocks"] = [(title, rows) for title, rows, _ in blocks]
        if sized:
            ctx["inverse"], ctx["forces"] = dynamics_rows(model, notation, shown, elastic)
        if sized and "transvective_factors" in outputs and "forward_dynamics" in outputs:
            ctx["transvected"], ctx["accelerations"] = cauchy_rows(model, notation, shown)
    return template.render(ctx)
