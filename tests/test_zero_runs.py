"""Zero entries of an output in chunks (aggsym/codegen/targets/c.py, _zero_chunks): every run of consecutive zero
entries of one output is cut into chunks of 16 bytes (2 doubles, 4 floats), each written by AGGSYM_ZEROS (one
vector store under GCC and Clang, entry by entry elsewhere), the rest entry by entry.  Every entry is written:
HyQ's A (four legs on a fixed trunk: blocks of zeros) and A^-1 against Pinocchio from NaN-filled outputs, one
function each and sliced, in double and float, and with the fallback for compilers without GCC's vector extension
(the text's #if turned off)."""
from __future__ import annotations

import json
import re
import warnings

import numpy as np
import pytest

import aggsym
from aggsym.codegen.compile import CLibrary, compile_shared
from aggsym.codegen.generate import generate, write
from aggsym.codegen.targets.c import _zero_chunks
from aggsym.codegen.printing import count_ops
from aggsym.contract import select_routines
from aggsym.core.program import Node
from aggsym.errors import ModelWarning
from helpers import relative_error, robot_path
from pinocchio_reference import crba, pinocchio_model, pinocchio_q

pytestmark = pytest.mark.pinocchio

ZEROS = re.compile(r"^AGGSYM_ZEROS\((\w+) \+ (\d+)\);$")


def test_runs_are_cut_into_chunks_of_the_width():
    node = Node.__new__(Node)  # (an output entry that is not a constant)
    outputs = [[0, 0, 1.5, 0, node, 0, 0, 0, 0, 0, 0.0, 2.0, 0], [0, 0, 0]]
    steps = [("out", 0, k) for k in range(len(outputs[0]))] + [("out", 1, k) for k in range(3)]
    chunks = _zero_chunks(steps, outputs, 2)
    # 0-1; 3 alone; 5-10 (six zeros: three chunks); 12 alone; output 1: 0-1, its entry 2 alone
    assert {s for s, first in chunks.items() if first} == {0, 5, 7, 9, 13}
    assert set(chunks) == {0, 1, 5, 6, 7, 8, 9, 10, 13, 14}
    four = _zero_chunks(steps, outputs, 4)
    assert {s for s, first in four.items() if first} == {5} and set(four) == {5, 6, 7, 8}


def test_a_chunk_of_zeros_counts_no_operation():
    assert count_ops("AGGSYM_ZEROS(A + 3);\nA[0] = x1*x2 + 1;") == {"mul": 1, "add": 1, "div": 0, "call": 0}


def _hyq(folder, slicing, scalar):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = select_routines(aggsym.load(robot_path("hyq")), ["inertia", "inertia_inverse"])
    gen = generate(model, targets="c,numpy,manifest", slicing=slicing, scalar=scalar)
    write(gen, folder)
    manifest = json.loads((folder / f"{model.name}.json").read_text())
    lib = compile_shared(folder / f"{model.name}.c", folder / "lib.so", extra=("-O2",), scalar=scalar)
    return model, gen, CLibrary(lib, manifest)


@pytest.mark.compiler
@pytest.mark.parametrize("scalar, width, tolerance", [("double", 2, 1e-9), ("float", 4, 1e-4)])
def test_zero_blocks_are_written_and_right(scalar, width, tolerance, tmp_path, rng):
    """HyQ's A and A^-1, one function each and sliced, against Pinocchio from outputs filled with NaN by CLibrary:
    every entry written, the zero blocks exactly 0; the chunks are whole and apart."""
    pm = pinocchio_model(robot_path("hyq"))
    model, one, one_lib = _hyq(tmp_path / "one", None, scalar)
    _, sliced, sliced_lib = _hyq(tmp_path / "sliced", (150, 60), scalar)
    assert all(r.bodies["c"].sliced for r in sliced.routines) and not any(r.bodies["c"].sliced for r in one.routines)
    n = model.nq
    for r in one.routines:
        starts = [int(m.group(2)) for m in map(ZEROS.match, r.bodies["c"].lines) if m]
        assert len(starts) >= 8, r.routine.role
        assert all(b - a >= width for a, b in zip(starts, starts[1:])), r.routine.role
    text = one.files[f"{model.name}.c"]
    vector = f"#if defined(__GNUC__)\ntypedef {scalar} aggsym_zeros_t __attribute__((vector_size(16)"
    fallback = ", ".join(f"(p)[{j}] = 0.0{'f' if scalar == 'float' else ''}" for j in range(width))
    assert text.count(vector) == 1 and f"#define AGGSYM_ZEROS(p) ({fallback})" in text
    plain = tmp_path / "fallback" / f"{model.name}.c"
    plain.parent.mkdir()
    plain.write_text(text.replace(vector, vector.replace("defined(__GNUC__)", "0")))
    (plain.parent / f"{model.name}.h").write_text(one.files[f"{model.name}.h"])
    manifest = json.loads((tmp_path / "one" / f"{model.name}.json").read_text())
    fallback_lib = CLibrary(compile_shared(plain, plain.parent / "lib.so", extra=("-O2",), scalar=scalar), manifest)
    for _ in range(3):
        q = rng.uniform(-np.pi, np.pi, n)
        M = crba(pm, pinocchio_q(pm, q))
        for lib in (one_lib, sliced_lib, fallback_lib):
            A, Ainv = lib.call("inertia", q), lib.call("inertia_inverse", q)
            assert np.all(np.isfinite(A)) and np.all(np.isfinite(Ainv))
            assert relative_error(A, M) <= tolerance and relative_error(Ainv, np.linalg.inv(M)) <= tolerance
            assert np.array_equal(A == 0, np.abs(M) < 1e-15 * np.abs(M).max())
