"""A routine's straight line as a batch kernel: the statements evaluated on W states at once, one lane each.

The lane technique of :mod:`.c_columns`, applied to states instead of columns.  A block of W states lives in one
workspace ``w`` of rows, each a vector of W values (``aggsym_v *restrict w``, GCC's and Clang's vector extension:
arithmetic acts lane by lane in the host's vector instructions, no intrinsics): a row per input entry the routine
reads (gathered from the caller's arrays), a row per value that crosses from one block of statements to another
(slots, reused once dead), a row per computed output entry (scattered to the caller's arrays after the block).  The
statements go, in the straight line's order, into blocks of at most :data:`CHUNK`::

    {
        const aggsym_v x12 = w[3]*w[7] + w[0];   /* used only in this block: a register */
        w[41] = x12*x12 - w[5];                  /* used later: a row */
    }

sqrt, fabs and sign on the vectors (``aggsym_vsqrt``, ...), a statement calling any other function (tan, exp, log,
asin, acos, atan, atan2) lane by lane in a loop of its own, and the sines and cosines of one angle by
``aggsym_sincos_lanes`` (the one-state C's ``aggsym_sincos`` on all lanes at once: the same bits).  The same
operations on the same operands in every lane, in the one-state C's order: per state, the one-state C's results to
the bit where the compiler contracts nothing (``-ffp-contract=off``).  A first version wrote each block as a loop
over the lanes for the compiler to vectorise: the same bits, 2.5 times the compile time and slower.  A long routine
is cut into functions of about :data:`PART` statements (the compiler's time grows faster than a function's length),
called in order.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from ...core.program import Node
from ..printing import Infix
from .c import c_spelling

CHUNK = 48  # statements per block
PART = 1500  # statements per function of a long routine
# the functions of the vectors (templates/kernels/kernels.c.j2: sqrt and fabs instructions, sign comparisons) for
# the C's; a statement calling any other is evaluated lane by lane, in a loop of its own
VECTOR_FUNCTIONS = {"sqrt": "aggsym_vsqrt", "fabs": "aggsym_vabs", "aggsym_sign": "aggsym_vsign"}
_SCALAR_CALL = re.compile(r"\b(?!(?:sqrt|fabs|aggsym_sign)\()[A-Za-z_][A-Za-z0-9_]*\(")
_VECTOR_CALL = re.compile(r"\b(sqrt|fabs|aggsym_sign)\(")
_NAME = re.compile(r"\b[A-Za-z_][A-Za-z0-9_]*\b")
# a numeric literal: an integer one is written as a floating one in vector statements (GCC converts a scalar
# operand to the vector's element type only where that loses nothing: 16777217 would not fit a float)
_LITERAL = re.compile(r"(?<![\w.])\d+(\.\d*)?([eE][+-]?\d+)?(?![\w.])")


def _vector_text(text: str) -> str:
    """A statement's C on the vectors: the vector functions' names, integer literals as floating ones."""
    text = _VECTOR_CALL.sub(lambda m: VECTOR_FUNCTIONS[m.group(1)] + "(", text)
    return _LITERAL.sub(lambda m: m.group(0) if m.group(1) or m.group(2) else m.group(0) + ".0", text)


@dataclass
class LaneKernel:
    """One routine as a block function over the workspace: ``functions`` its C lines (the part functions, then
    the block function ``SYMBOL_block``), ``rows`` the workspace's rows, ``inputs`` per input of the routine's
    signature [(entry, row)] of the entries it reads, ``outputs`` per output [row, or the constant (a float)] per
    entry, ``status`` the row of a returned status (None: no status)."""

    functions: list
    rows: int
    inputs: list
    outputs: list
    status: int | None


def lane_kernel(prog, lines, signature, status_index, symbol: str) -> LaneKernel:
    """The :class:`LaneKernel` of a routine's straight line ``lines`` (:class:`~.base.RoutineLines`; its inputs
    named ``KIND_INDEX``, its temps ``xK``); ``signature`` the routine's inputs in order, ``status_index`` the
    index of its returned status among its outputs (or None)."""
    sl, names, outputs = lines.sl, lines.names, lines.outputs
    printer = Infix(prog, names, c_spelling("double"))
    stmts = []  # (kind, defined names, right-hand side with the straight line's names, names read)

    def printed(x, top=True):
        text = printer(x, top)
        refs = list(printer.refs)
        printer.refs.clear()
        return text, refs
    out_names, constants, pairs = {}, {}, set()
    for step in sl.steps:
        if step[0] == "out":
            _, o, k = step
            x = outputs[o][k]
            if not isinstance(x, Node):
                constants[(o, k)] = float(x)
                continue
            out_names[(o, k)] = f"aggsym_o{o}_{k}"
            text, refs = printed(x, top=x.id not in names)
            stmts.append(("call" if _SCALAR_CALL.search(text) else "plain", (out_names[(o, k)],), text, refs))
            continue
        i = step[1]
        if i in lines.trig:  # sin and cos of one angle together, as the one-state C
            sin_id, cos_id, arg = lines.trig[i]
            if (sin_id, cos_id) in pairs:
                continue
            pairs.add((sin_id, cos_id))
            text, refs = printed(arg, top=False)
            if isinstance(arg, Node) and text in names.values():  # a named value (an input, a temp): its row
                angle = text
            else:
                angle = f"aggsym_a{i}"
                stmts.append(("plain", (angle,), text, refs))
            stmts.append(("sincos", (names[sin_id] if sin_id is not None else f"aggsym_s{i}",
                                     names[cos_id] if cos_id is not None else f"aggsym_c{i}"), "", [angle]))
            continue
        text, refs = printed(prog.nodes[i])
        stmts.append(("call" if _SCALAR_CALL.search(text) else "plain", (names[i],), text, refs))
    # the blocks: runs of at most CHUNK plain statements, runs of calls (a lane loop), each sincos
    loops = []  # [kind, [statement indices]]
    for s, st in enumerate(stmts):
        kind = st[0]
        if loops and kind == loops[-1][0] and (kind == "call" or (kind == "plain" and len(loops[-1][1]) < CHUNK)):
            loops[-1][1].append(s)
        else:
            loops.append((kind, [s]))
    loop_of = {s: j for j, (_, members) in enumerate(loops) for s in members}
    defined_in = {name: loop_of[s] for s, st in enumerate(stmts) for name in st[1]}
    last_use, rowed = {}, set()
    for s, st in enumerate(stmts):
        if st[0] != "plain":
            rowed.update(st[1])
        for name in st[3]:
            last_use[name] = loop_of[s]
            if name in defined_in and defined_in[name] != loop_of[s]:
                rowed.add(name)
    # the rows: the input entries read, the outputs' computed entries, then the slots (reused once dead)
    rows, input_rows = {}, []
    for kind in signature:
        input_rows.append([])
        for k, i in sl.inputs:
            if k == kind:
                rows[f"{kind}_{i}"] = len(rows)
                input_rows[-1].append((i, rows[f"{kind}_{i}"]))
    for name in out_names.values():
        rows[name] = len(rows)
    base, free, used = len(rows), [], 0
    ends = {}
    for name, j in last_use.items():
        if name in rowed:
            ends.setdefault(j, []).append(name)
    for name, j in defined_in.items():  # (a sin or cos that nothing reads: its row free after its loop)
        if name in rowed and name not in last_use:
            ends.setdefault(j, []).append(name)
    for j, (_, members) in enumerate(loops):
        for s in members:
            for name in stmts[s][1]:
                if name in rowed and name not in rows:
                    if free:
                        rows[name] = free.pop()
                    else:
                        rows[name] = base + used
                        used += 1
        for name in ends.get(j, ()):
            if rows.get(name, -1) >= base:
                free.append(rows[name])

    def sub(text, lane=""):
        return _NAME.sub(lambda m: f"w[{rows[m.group(0)]}]{lane}" if m.group(0) in rows else m.group(0), text)
    parts, part, count = [], [], 0
    for kind, members in loops:
        if kind == "sincos":
            (s,) = members
            sin_name, cos_name = stmts[s][1]
            part.append(f"aggsym_sincos_lanes(w[{rows[stmts[s][3][0]]}], &w[{rows[sin_name]}], &w[{rows[cos_name]}]);")
        elif kind == "call":  # lane by lane
            part.append("for (l = 0; l < AGGSYM_W; ++l) {")
            for s in members:
                _, (target,), text, _ = stmts[s]
                part.append(f"    w[{rows[target]}][l] = {sub(text, '[l]')};")
            part.append("}")
        else:  # on the vectors
            part.append("{")
            for s in members:
                _, (target,), text, _ = stmts[s]
                text = sub(_vector_text(text))
                part.append(f"    w[{rows[target]}] = {text};" if target in rows
                            else f"    const aggsym_v {target} = {text};")
            part.append("}")
        count += len(members)
        if count >= PART:
            parts.append(part)
            part, count = [], 0
    if part or not parts:
        parts.append(part)
    functions = []
    for n, body in enumerate(parts):
        functions += [f"static void {symbol}_part{n}(aggsym_v *restrict w)", "{", "    int l;", "    (void)l;"]
        functions += [f"    {line}" for line in body] + ["}", ""]
    functions += [f"static void {symbol}_block(aggsym_v *restrict w)", "{"]
    functions += [f"    {symbol}_part{n}(w);" for n in range(len(parts))] + ["}", ""]
    table = [[rows[out_names[(o, k)]] if (o, k) in out_names else constants[(o, k)] for k in range(len(flat))]
             for o, flat in enumerate(outputs)]
    status = None
    if status_index is not None and isinstance(table[status_index][0], int):
        status = table[status_index][0]
    return LaneKernel(functions, max(base + used, 1), input_rows, table, status)


__all__ = ["LaneKernel", "lane_kernel", "CHUNK", "PART"]
