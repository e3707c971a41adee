"""Zero entries of an output in runs (aggsym/codegen/generate.py, _zero_runs): a run of 2..ZERO_RUN consecutive
zero entries of one output is written by one memset in a routine printed as one function, and entry by entry in a
sliced one (GCC's -Os, which compiles the slices, makes a memset a rep stos).  Every entry is written either way:
HyQ's A (four legs on a fixed trunk: blocks of zeros) and its A^-1 against Pinocchio, from NaN-filled outputs."""
from __future__ import annotations

import json
import re
import warnings

import numpy as np

import aggsym
from aggsym.codegen.compile import CLibrary, compile_shared
from aggsym.codegen.generate import ZERO_RUN, _zero_runs, generate, write
from aggsym.codegen.printing import count_ops
from aggsym.contract import select_routines
from aggsym.core.program import Node
from aggsym.errors import ModelWarning
from helpers import crba, pinocchio_model, pinocchio_q, relative_error, robot_path

MEMSET = re.compile(r"memset\((\w+) \+ (\d+), 0, (\d+) \* sizeof \*(\w+)\);")


def test_runs_of_two_to_zero_run_entries_of_one_output():
    node = Node.__new__(Node)  # (an output entry that is not a constant)
    outputs = [[0, 0, 1.5, 0, node, 0, 0, 0] + [0] * (ZERO_RUN + 3), [0, 0]]
    steps = [("out", 0, k) for k in range(len(outputs[0]))] + [("out", 1, 0), ("out", 1, 1)]
    runs = _zero_runs(steps, outputs)
    starts = {s: n for s, n in runs.items() if n}
    # 0..1; 3 alone; 5..7 (node at 4 breaks it) run on into the long tail, cut at ZERO_RUN; output 1 its own run
    assert starts == {0: 2, 5: ZERO_RUN, 5 + ZERO_RUN: 14 - ZERO_RUN, len(outputs[0]): 2}
    covered = sorted(s for s in runs)
    assert 3 not in covered and 2 not in covered and 4 not in covered
    assert all(runs[s] == 0 for s in covered if s not in starts)


def test_a_memset_counts_no_operation():
    assert count_ops("memset(A + 3, 0, 4 * sizeof *A);\nA[0] = x1*x2 + 1;") == {"mul": 1, "add": 1, "div": 0,
                                                                               "call": 0}


def _hyq(folder, slicing):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = select_routines(aggsym.load(robot_path("hyq")), ["inertia", "inertia_inverse"])
    gen = generate(model, latex=False, slicing=slicing)
    write(gen, folder)
    manifest = json.loads((folder / f"{model.name}.json").read_text())
    return model, gen, CLibrary(compile_shared(folder / f"{model.name}.c", folder / "lib.so", extra=("-O2",)),
                                manifest)


def test_zero_blocks_are_written_and_right(tmp_path, rng):
    """HyQ's A and A^-1, one function each (memsets) and sliced (entry by entry), against Pinocchio from outputs
    filled with NaN by CLibrary: every entry written, the zero blocks exactly 0."""
    pm = pinocchio_model(robot_path("hyq"))
    one_model, one, one_lib = _hyq(tmp_path / "one", None)
    _, sliced, sliced_lib = _hyq(tmp_path / "sliced", (150, 60))
    text = one.files[f"{one_model.name}.c"]
    n = one_model.nq
    for r in one.routines:
        runs = [m for m in MEMSET.finditer("\n".join(r.c_body))]
        assert runs, r.routine.role
        for m in runs:
            assert m.group(1) == m.group(4) and 2 <= int(m.group(3)) <= ZERO_RUN
    assert all(r.sliced for r in sliced.routines)
    assert "memset(" not in sliced.files[f"{one_model.name}.c"]
    assert "memset(" in text
    for _ in range(3):
        q = rng.uniform(-np.pi, np.pi, n)
        M = crba(pm, pinocchio_q(pm, q))
        for lib in (one_lib, sliced_lib):
            A, Ainv = lib.call("inertia", q), lib.call("inertia_inverse", q)
            assert np.all(np.isfinite(A)) and np.all(np.isfinite(Ainv))
            assert relative_error(A, M) <= 1e-9 and relative_error(Ainv, np.linalg.inv(M)) <= 1e-9
            assert np.array_equal(A == 0, np.abs(M) < 1e-15 * np.abs(M).max())
