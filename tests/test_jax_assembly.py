"""How the JAX module assembles an output from its entries (issue 32): blocks of selects, then one concatenate
(``_stack``); in a routine cut into segments, one ``jnp.stack`` (``_stacked``).

XLA's CPU compiler fuses ``jnp.stack`` of straight-line entries with everything they are computed from into one
kernel that evaluates shared values again for every entry: with jax 0.10 the Panda's forward dynamics took 483 µs
per state that way, 2 µs with the blocks (``python -m benchmarks.batch``, entry aggsym_jax_project).  In a cut
routine every entry is a result of a segment, already in memory, and one stack only copies them (Talos's A(q) at
B = 4096: 5.9 µs per state, 13 with the blocks).  Speed is measured there; here: both assemblies are exact (every
bit of every entry lands in its place, -0.0, inf and NaN included, in float32 and float64, for any batch shape),
the traces of the routines kept whole hold no stack of their entries, and the cut ones use the stack.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import aggsym
from aggsym.codegen.targets import jax_segments
from aggsym.contract import select_routines
from conftest import model_path
from jax_support import arguments, float64, jax, jnp, modules, routines


@pytest.fixture(scope="module")
def module(tmp_path_factory):
    """planar_2link's JAX module with every routine (derivatives, regressors, frames)."""
    model = select_routines(aggsym.load(model_path("planar_2link")), ["all"])
    return modules(model, tmp_path_factory.mktemp("assembly"))[1]


@pytest.fixture(scope="module")
def cut_module(tmp_path_factory):
    """planar_2link's JAX module with every routine of more than 30 statements cut into segments of 6."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(jax_segments, "SEGMENT", 6)
        mp.setattr(jax_segments, "SEGMENTED", 30)
        model = select_routines(aggsym.load(model_path("planar_2link")), ["all"])
        return modules(model, tmp_path_factory.mktemp("assembly_cut"))[1]


def entries_of(rng, batch, dtype, count):
    """``count`` entries of the batch shape: random values, then -0.0, inf, -inf, NaN in some entries, and every
    fifth entry the literal 0.0 the generated code writes for a zero."""
    out = []
    for k in range(count):
        if k % 5 == 4:
            out.append(0.0)
            continue
        x = rng.normal(size=batch).astype(dtype)
        if k % 7 == 1:
            x = np.full(batch, (-0.0, np.inf, -np.inf, np.nan)[k % 4], dtype)
        out.append(jnp.asarray(x))
    return out


@pytest.mark.parametrize("batch", [(), (3,), (2, 4)])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("shape", [(1,), (7,), (7, 10), (2, 3, 11)])
@pytest.mark.parametrize("assemble", ["_stack", "_stacked"])
def test_every_entry_lands_exactly_in_its_place(cut_module, rng, batch, dtype, shape, assemble):
    count = math.prod(shape)
    with float64():
        entries = entries_of(rng, batch, dtype, count)
        got = np.asarray(getattr(cut_module, assemble)(tuple(entries), batch, dtype, shape))
    want = np.stack([np.broadcast_to(np.asarray(e, dtype), batch) for e in entries], axis=-1).reshape(batch + shape)
    assert got.dtype == dtype and got.shape == batch + shape
    assert np.array_equal(got.view(np.uint32 if dtype == np.float32 else np.uint64),
                          want.view(np.uint32 if dtype == np.float32 else np.uint64))  # bit for bit: -0.0, NaN


def _equations(jaxpr):
    """Every equation of a jaxpr, those of its sub-jaxprs (pjit, custom derivatives) included."""
    for eqn in jaxpr.eqns:
        yield eqn
        for value in eqn.params.values():
            for sub in (value if isinstance(value, (list, tuple)) else (value,)):
                inner = getattr(sub, "jaxpr", None)
                if inner is not None:
                    yield from _equations(getattr(inner, "jaxpr", inner))


def _concatenates(jaxpr):
    """The numbers of operands of every concatenate (and stack: a primitive of its own in newer jax) in a jaxpr,
    sub-jaxprs included."""
    return [len(eqn.invars) for eqn in _equations(jaxpr) if eqn.primitive.name in ("concatenate", "stack")]


def test_an_output_is_blocks_of_selects_joined_once(module, rng):
    entries = tuple(jnp.asarray(rng.normal(size=(5,))) for _ in range(70))
    jaxpr = jax.make_jaxpr(lambda *e: module._stack(e, (5,), jnp.float32, (7, 10)))(*entries).jaxpr
    blocks = -(-70 // module._BLOCK)
    assert _concatenates(jaxpr) == [blocks]
    assert sum(eqn.primitive.name == "select_n" for eqn in _equations(jaxpr)) == 70


def test_no_routine_stacks_its_entries(module, rng):
    """Every routine of the module (planar_2link with all its routines), traced on a batch: the concatenates join
    no more operands than the outputs have blocks (one block: none; a jnp.stack of an output's entries would join
    one operand per entry)."""
    with float64():
        for name in routines(module):
            args = arguments(module, name, rng, (4,))
            closed = jax.make_jaxpr(getattr(module, name))(*args)
            blocks = [-(-math.prod(v.aval.shape[1:]) // module._BLOCK) for v in closed.jaxpr.outvars]
            joined = sum(_concatenates(closed.jaxpr))
            assert joined <= sum(b for b in blocks if b > 1), (name, joined, blocks)


def test_the_cut_routines_stack_their_entries_once(module, cut_module):
    """The routines cut into segments assemble their outputs with _stacked, the others with _stack; the module
    whose routines are all whole has no _stacked."""
    text = open(cut_module.__file__).read()
    cut = {f.split("__")[0][1:] for f in vars(cut_module) if "__" in f and f.startswith("_")
           and not f.startswith("__") and not f.endswith("__calls")}
    assert cut and cut < set(routines(cut_module))
    for name in routines(cut_module):
        body = text.split(f"\ndef _{name}(", 1)[1].split("\n\n\n", 1)[0]
        assert ("_stacked((" in body) == (name in cut), name
        assert ("_stack((" in body) == (name not in cut), name
    assert not hasattr(module, "_stacked")
