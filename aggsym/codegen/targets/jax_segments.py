"""Segments of a long JAX routine: its straight line cut into functions of at most :data:`SEGMENT` statements,
each called through ``jax.lax.cond`` on a predicate XLA cannot fold, with the same function in both branches.

Why: under ``jit`` XLA's CPU compiler fuses the whole straight line of a routine (it is element-wise over the
batch) into one kernel.  Inside a large kernel the values shared by many later statements are evaluated again at
every use (jax 0.10.2: Talos's forward dynamics, about 9,000 operations, took 32,751 µs per state after a 470 s
compile; jax 0.6.0: 161 µs after 104 s), and the compile goes to LLVM on that kernel.  A branch of a conditional
is compiled as a computation of its own, so the kernels end at the segment's borders and the values crossing them
are written to memory once.  ``jax.lax.optimization_barrier`` alone does not do that (XLA's CPU pipeline removes it
before fusion); here it only hides the constant predicate from XLA's constant folding, so that the conditional
(and with it the border) survives.  Both branches being the same function, the result is the straight line's,
exactly, whichever branch runs; ``jit``, ``vmap`` (the predicate is no input, so it is never batched), ``grad``,
``jacfwd`` and ``jacrev`` go through ``cond``.

What it gives is measured in ``docs/batched.md`` (jax 0.10.2: Talos's forward dynamics 5.7 µs per state after a
jit of 30 s; Panda's forward dynamics derivatives 21.4 µs before, 2.9 after).  Called eagerly (no jit) the
segments run directly (``_cut`` in the module): compiling each segment's conditional on its own, once per batch
shape, would cost far more than op-by-op dispatch saves.

A statement that uses no earlier statement (an input's entry unpacked, ``q_3 = q[..., 3]``) stays in the
private function, before the segments; the others are cut, in program order, into runs of :data:`SEGMENT`.  A
segment's parameters are the names it uses that earlier statements define (in order of first use), its results
the names it defines that a later segment or the assembly of the outputs uses (in order of definition).

The functions of the inputs (``jnp.cos(q_3)``, ``jnp.sin(0.785 + q_6)``: a statement that calls one of
:data:`EXPENSIVE` and depends on at most :data:`NEAR` statements besides the unpacked inputs) go first, with
those statements, into a segment of their own, ``_ROLE__calls``, in every routine, cut or whole.  XLA's fusion
otherwise copies each sine and cosine into every kernel that reads it: Panda's forward dynamics (12 sines and
cosines in its straight line) compiled to 140 of them and took 1.6 µs per state (jax 0.10.2, B = 4096), 0.35
with the segment (``docs/batched.md``).  Moving them first changes no value: they read nothing but the inputs
and each other.

A short routine with many output entries (more than :data:`GATHERED`: Panda's A(q), 49) is not cut, but its
statements go into one segment after the calls, whose results are the entries.  Its outputs are then assembled
by one ``jnp.stack`` of values already in memory, as a cut routine's are.  Otherwise, with jax 0.6.0, XLA fuses
the assembly's chains of selects with the statements they read and evaluates shared values again for each block:
Panda's A(q) took 4.8 to 5.1 µs per state at B = 4096, and 0.50 to 0.60 in one segment (jax 0.10.2: 0.37 to 0.52,
and 0.32 to 0.47; same session, by hand).  The forward and inverse dynamics of a robot of up to 32 coordinates
have at most 32 entries and are not affected, so their jit stays as it was (Panda's forward dynamics in one
segment took 3.5 s to compile with jax 0.6.0 instead of 1.6).
"""
from __future__ import annotations

import ast
import dataclasses

from .numpy import statement_parts

SEGMENT = 40  # statements per segment
SEGMENTED = 500  # a routine is cut when it has more statements than this
GATHERED = 32  # a routine kept whole whose outputs have more computed entries than this goes into one segment
# the functions whose statements go into the calls segment (the NumPy names the JAX target prints, jnp.NAME)
EXPENSIVE = frozenset(("sin", "cos", "tan", "sqrt", "exp", "log", "arcsin", "arccos", "arctan", "arctan2"))
NEAR = 4  # a call goes into the calls segment when it depends on at most this many statements (besides inputs)


@dataclasses.dataclass(frozen=True)
class Segment:
    """One segment: ``name`` its function, ``params`` the names it receives, ``results`` those it returns,
    ``lines`` its statements."""
    name: str
    params: tuple
    results: tuple
    lines: tuple


def limits() -> tuple:
    """(:data:`SEGMENT`, :data:`SEGMENTED`, :data:`GATHERED`) as they are now (read when a module is rendered)."""
    return SEGMENT, SEGMENTED, GATHERED


def _calls(statement: str) -> bool:
    """Whether a generated statement calls one of :data:`EXPENSIVE` (``jnp.NAME(...)``) anywhere."""
    return any(isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in EXPENSIVE
               and isinstance(node.func.value, ast.Name) and node.func.value.id == "jnp"
               for node in ast.walk(ast.parse(statement, mode="exec").body[0].value))


def _hoisted(body: list, parsed: list, prelude: set) -> set:
    """The indices of the statements of the calls segment: each statement calling one of :data:`EXPENSIVE` that
    depends on at most :data:`NEAR` statements other than the ``prelude``, and those statements."""
    near, where, chosen = {}, {}, set()
    for k, (statement, (name, used)) in enumerate(zip(body, parsed)):
        where[name] = k
        if name in prelude:
            continue
        above = set()
        for u in used:
            if u in prelude or u not in where:
                continue
            if near.get(u) is None:
                above = None
                break
            above |= {u} | near[u]
            if len(above) > NEAR:
                above = None
                break
        near[name] = above
        if above is not None and _calls(statement):
            chosen |= {k} | {where[u] for u in above}
    return chosen


def _segment(name: str, lines: list, defined: set, later: set):
    """The segment of ``lines`` ((statement, name, used) triples), with the ``defined`` names its parameters may
    be and the ``later`` names (read after it) its results are; None when nothing after it reads what it
    defines (dead code: the programs are pruned, not seen in practice)."""
    here = {n for _, n, _ in lines}
    params = tuple(dict.fromkeys(u for _, _, used in lines for u in used if u in defined and u not in here))
    results = tuple(n for _, n, _ in lines if n in later)
    if not results:
        return None
    return Segment(name, params, results, tuple(s for s, _, _ in lines))


def cut(segments) -> bool:
    """Whether a routine's ``segments`` cut its straight line (more than the calls segment): every entry of its
    outputs is then a result of a segment, written to memory before the outputs are assembled."""
    return any(not seg.name.endswith("__calls") for seg in segments)


def _call(seg: Segment) -> str:
    return f"{', '.join(seg.results)}, = _cut(_kept, {seg.name}, {', '.join(seg.params)})"


def segmented(role: str, body: list, tail: list, size: int | None = None, above: int | None = None) -> dict:
    """``body`` (a routine's statements, in program order) as {"body": the private function's statements,
    "segments": [Segment]}; ``tail`` the texts read after the body (the outputs' entries, the status).  The calls
    of functions of the inputs go first into their segment ``_ROLE__calls`` (module text).  Routines of at most
    ``above`` statements (default :data:`SEGMENTED`) are otherwise kept whole: their kernels are small, and cutting
    would cost more compile time than it saves; the others are cut into runs of ``size`` (default
    :data:`SEGMENT`).  A routine kept whole whose outputs have more than :data:`GATHERED` computed entries (names
    in ``tail``) goes into one segment, all its statements but the prelude and the calls, so that its entries are
    written to memory once and assembled by one stack (the module docstring)."""
    size = SEGMENT if size is None else size
    parsed = [statement_parts(s) for s in body]
    defined = {name for name, _ in parsed}
    prelude = [k for k, (_, used) in enumerate(parsed) if not any(u in defined for u in used)]
    hoisted = _hoisted(body, parsed, {parsed[k][0] for k in prelude})
    whole = len(body) <= (SEGMENTED if above is None else above)
    gathered = sum(1 for text in tail if text.isidentifier()) > GATHERED
    if whole and not hoisted and not gathered:
        return {"body": list(body), "segments": []}
    first = set(prelude)
    rest = [(body[k], *parsed[k]) for k in range(len(body)) if k not in first and k not in hoisted]
    tail_names = {node.id for text in tail for node in ast.walk(ast.parse(text, mode="eval"))
                  if isinstance(node, ast.Name)}
    calls = _segment(f"_{role}__calls", [(body[k], *parsed[k]) for k in sorted(hoisted)], defined,
                     tail_names | {u for _, _, used in rest for u in used})
    head = ["_kept = jax.lax.optimization_barrier(jnp.asarray(False))  # a predicate XLA cannot fold (see _SEGMENTS)"]
    segments = [calls] if calls else []
    lines = [body[k] for k in prelude] + head + [_call(seg) for seg in segments]
    if whole and not gathered:
        return {"body": lines + [s for s, _, _ in rest], "segments": segments}
    runs = [rest] if whole else [rest[k:k + size] for k in range(0, len(rest), size)]
    last = {u: k for k, run in enumerate(runs) for _, _, used in run for u in used}
    last.update({u: len(runs) for u in tail_names})
    count = 0
    for k, run in enumerate(runs):
        seg = _segment(f"_{role}__{count + 1}", run, defined, {n for n, j in last.items() if j > k})
        if seg is not None:
            count += 1
            segments.append(seg)
            lines.append(_call(seg))
    return {"body": lines, "segments": segments}


__all__ = ["GATHERED", "SEGMENT", "SEGMENTED", "Segment", "cut", "limits", "segmented"]
