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
"""
from __future__ import annotations

import ast
import dataclasses

SEGMENT = 40  # statements per segment
SEGMENTED = 500  # a routine is cut when it has more statements than this


@dataclasses.dataclass(frozen=True)
class Segment:
    """One segment: ``name`` its function, ``params`` the names it receives, ``results`` those it returns,
    ``lines`` its statements."""
    name: str
    params: tuple
    results: tuple
    lines: tuple


def limits() -> tuple:
    """(:data:`SEGMENT`, :data:`SEGMENTED`) as they are now (read when a module is rendered)."""
    return SEGMENT, SEGMENTED


def _parts(statement: str) -> tuple:
    """(the name a generated statement ``name = rhs`` assigns, the names its right-hand side reads)."""
    tree = ast.parse(statement, mode="exec").body[0]
    if not (isinstance(tree, ast.Assign) and len(tree.targets) == 1 and isinstance(tree.targets[0], ast.Name)):
        raise ValueError(f"not a generated assignment: {statement!r}")
    used = []
    for node in ast.walk(tree.value):
        if isinstance(node, ast.Name) and node.id not in used:
            used.append(node.id)
    return tree.targets[0].id, used


def segmented(role: str, body: list, tail: list, size: int | None = None, above: int | None = None) -> dict:
    """``body`` (a routine's statements, in program order) as {"body": the private function's statements,
    "segments": [Segment]}; ``tail`` the texts read after the body (the outputs' entries, the status).  Routines of
    at most ``above`` statements (default :data:`SEGMENTED`) are kept whole: their kernels are small, and cutting
    would cost more compile time than it saves; the others are cut into runs of ``size`` (default
    :data:`SEGMENT`)."""
    size = SEGMENT if size is None else size
    parsed = [_parts(s) for s in body]
    defined = {name for name, _ in parsed}
    if len(body) <= (SEGMENTED if above is None else above):
        return {"body": list(body), "segments": []}
    prelude, runs = [], []
    for statement, (name, used) in zip(body, parsed):
        if not any(u in defined for u in used):
            prelude.append(statement)
            continue
        if not runs or len(runs[-1]) == size:
            runs.append([])
        runs[-1].append((statement, name, used))
    last = {u: k for k, run in enumerate(runs) for _, _, used in run for u in used}
    last.update({node.id: len(runs) for text in tail for node in ast.walk(ast.parse(text, mode="eval"))
                 if isinstance(node, ast.Name)})
    segments, calls = [], []
    for k, run in enumerate(runs):
        here = {name for _, name, _ in run}
        params = tuple(dict.fromkeys(u for _, _, used in run for u in used if u in defined and u not in here))
        results = tuple(name for _, name, _ in run if last.get(name, -1) > k)
        if not results:
            continue  # dead code (the programs are pruned: not seen in practice)
        seg = Segment(f"_{role}__{len(segments) + 1}", params, results, tuple(s for s, _, _ in run))
        segments.append(seg)
        calls.append(f"{', '.join(results)}, = _cut(_kept, {seg.name}, {', '.join(params)})")
    head = ["_kept = jax.lax.optimization_barrier(jnp.asarray(False))  # a predicate XLA cannot fold (see _SEGMENTS)"]
    return {"body": prelude + head + calls, "segments": segments}


__all__ = ["SEGMENT", "SEGMENTED", "Segment", "limits", "segmented"]
