"""The solves of the derivatives of the dynamics (constrained, impulse and free forward dynamics) as one body
applied to columns (aggsym/core/columns.py) and its C: the body printed once and called in a loop
(aggsym/codegen/targets/c_columns.py).

The C against Pinocchio is in tests/test_impacts_pinocchio.py (a quadruped on four point feet, compiled); here:
the body at each column's values is the unrolled solve there, entry by entry, on floats; the C's operation count
is its straight line's plus the body's times the columns; its text compiles warning-free in every layout and
scalar, is the same on every generation, and the loop stores every entry."""
from __future__ import annotations

import dataclasses
import json
import math
import re

import numpy as np
import pytest
import sympy as sp

import aggsym
from aggsym.codegen.compile import CLibrary, compile_shared
from aggsym.codegen.generate import generate, symbolic_routines, write
from aggsym.codegen.printing import count_ops
from aggsym.contract import ROUTINES as CONTRACT, input_length, select_routines
from aggsym.core.columns import CAPTURES, VALUES, body_program
from aggsym.twin import NumericTwin
from conftest import model_path
from helpers import relative_error

ROUTINES = ["constrained_forward_dynamics_derivatives", "impulse_dynamics_derivatives", "forward_dynamics_derivatives"]
BLOCKS = {"constrained_forward_dynamics_derivatives": 3, "impulse_dynamics_derivatives": 2,
          "forward_dynamics_derivatives": 2}  # the column blocks of n columns each
MODELS = ["four_bar", "walking_machine_on_ground", "delta_robot", "four_bar+damped"]
# every routine with a column map looped (by default, those above 50,000 operations)
LOOPED = {"targets": "c,numpy,manifest", "looped_above": 0}


def with_routines(name):
    """The model with both derivative routines; ``NAME+damped``: with the damped (proximal) solve, 3 iterations."""
    name, _, damped = name.partition("+")
    model = aggsym.load(model_path(name))
    if damped:
        model = dataclasses.replace(model, proximal=(sp.Float(1e-3), 3))
    return select_routines(model, ROUTINES)


def random_inputs(model, rng) -> dict:
    """(kind, index) -> a float: every input a routine of the model may read (p at its defaults)."""
    values = {}
    for kind in ("q", "qd", "tau", "qd_minus", "t"):
        for i in range(input_length(model, kind)):
            values[(kind, i)] = float(rng.uniform(-1.5, 1.5))
    values[("r", 0)] = float(rng.uniform())
    values.update({("p", i): float(x.value) for i, x in enumerate(model.parameters)})
    return values


@pytest.mark.parametrize("name", MODELS)
def test_the_body_at_each_column_is_the_unrolled_solve(name, rng):
    """Every entry the loop writes, evaluated through the body program at its column's values (the captures and
    values evaluated in the routine's program), equals the routine's own unrolled entry: to rounding, as both
    are the same arithmetic on the same operands (the unrolled one folded on its zeros)."""
    model = with_routines(name)
    prog, outputs = symbolic_routines(model)
    assert set(prog.columns) == set(ROUTINES)
    for role, cmap in prog.columns.items():
        body = body_program(prog, cmap)
        assert body.captures and all(hasattr(c, "id") for c in body.captures)
        columns = [list(column) for run in cmap.runs for column in run.values]
        assert len(columns) == cmap.columns == BLOCKS[role] * model.nv
        for _ in range(2):
            values = random_inputs(model, rng)
            unrolled = [prog.evaluate(out, values) for out in outputs[role]]
            captured = prog.evaluate(body.captures, values)
            for column in columns:
                flat = [x for group in column for x in group]
                assert len(flat) == cmap.width
            got = {}
            for col, column in enumerate(columns):
                v = prog.evaluate([x for group in column for x in group], values)
                inputs = {(CAPTURES, k): c for k, c in enumerate(captured)}
                inputs.update({(VALUES, i): x for i, x in enumerate(v)})
                got[col] = body.program.evaluate(body.outputs, inputs)
            offsets = {(o, k): c for o, k, c in cmap.offsets}
            written = set()
            for o, k, col, j in cmap.placements():
                want, have = unrolled[o][k], got[col][j] + offsets.get((o, k), 0)
                assert math.isfinite(have)
                assert abs(have - want) <= 1e-12 * max(1.0, abs(want)), (role, o, k)
                written.add((o, k))
            matrices = [o for o, out in enumerate(outputs[role]) if len(out) == model.nv ** 2]  # (not the status)
            assert written == {(o, k) for o in matrices for k in range(model.nv ** 2)}


def c_text(model, **options) -> dict:
    return generate(model, **LOOPED, **options).files


def looped_library(model, folder, scalar="double"):
    """(C library, manifest) of the model's C with every column map looped, compiled -O1 with -Werror."""
    write(generate(model, scalar=scalar, **LOOPED), folder)
    manifest = json.loads((folder / f"{model.name}.json").read_text())
    return CLibrary(compile_shared(folder / f"{model.name}.c", folder / f"lib{model.name}.so", extra=("-O1",),
                                   scalar=scalar), manifest), manifest


def test_the_operation_count_is_the_straight_line_and_the_body_times_the_columns():
    """The manifest's ops of a routine with a loop: its C's straight line, read back from the text (less the loop's
    call), plus the body's operations, read back from its function, times the columns."""
    model = with_routines("walking_machine_on_ground")
    gen = generate(model, **LOOPED)
    c = gen.files[f"{model.name}.c"]
    manifest = json.loads(gen.files[f"{model.name}.json"])
    for r in gen.routines:
        if r.routine.role not in ROUTINES:
            continue
        body = c.split(f"static void {r.symbol}_column(")[1].split("\n}\n")[0]
        body = body.split("{", 1)[1]
        columns = int(re.search(rf"/\* {r.symbol}: the body applied to each of its (\d+) columns", c).group(1))
        straight = [line for line in r.bodies["c"].lines if not line.startswith(f"{r.symbol}_columns(")]
        want = count_ops("\n".join(straight))
        for key, n in count_ops(body).items():
            want[key] += columns * n
        assert manifest["ops"][r.routine.role] == want == r.ops, r.routine.role


@pytest.mark.compiler
@pytest.mark.parametrize("name,scalar", [("walking_machine_on_ground", "double"), ("delta_robot", "float"),
                                         ("four_bar+damped", "double")])
def test_the_c_equals_the_twin_in_every_scalar(name, scalar, tmp_path, rng):
    """The loop's C (compiled with -Werror, warnings of float conversions too) against the twin, every entry
    written (the library fills its outputs with NaN first); with the damped solve too."""
    model = with_routines(name)
    lib, manifest = looped_library(model, tmp_path, scalar)
    twin = NumericTwin(model)
    tol = 1e-10 if scalar == "double" else manifest["float_tolerance"]["constrained_forward_dynamics_derivatives"]
    for _ in range(3):
        values = random_inputs(model, rng)
        q = np.array([values[("q", i)] for i in range(model.nq)])
        qd = np.array([values[("qd", i)] for i in range(model.nv)])
        tau = np.array([values[("tau", i)] for i in range(model.nv)])
        r = values[("r", 0)]
        for role, args in (("constrained_forward_dynamics_derivatives", (q, qd, tau)),
                           ("impulse_dynamics_derivatives", (q, qd, r)),
                           ("forward_dynamics_derivatives", (q, qd, tau))):
            for got, want in zip(lib.call(role, *args), getattr(twin, role)(*args)):
                assert np.all(np.isfinite(got)), role
                assert relative_error(got, want, floor=1.0) < (tol if scalar == "double" else 10 * tol), role


# bundled models whose features the loop's body must carry (a time input, sliding friction, an elastic stand, a
# rolling constraint, a spinning rotor, a free body): their derivative routines that apply, every one looped
FEATURES = ["cart_on_moving_platform", "flywheel_on_body", "double_pendulum_sliding_friction",
            "double_pendulum_elastic_stand", "rolling_disc", "gyroscope_spinning_rotor", "spacecraft"]


@pytest.mark.compiler
@pytest.mark.parametrize("name", FEATURES)
def test_the_looped_c_of_other_models_equals_the_twin(name, tmp_path, rng):
    """On models with other features than the four above, each derivative routine that applies (only the forward
    dynamics derivatives without constraints), looped and compiled, against the twin at random states: every
    entry written and equal to 1e-10."""
    base = aggsym.load(model_path(name))
    model = select_routines(base, [r for r in ROUTINES if CONTRACT[r].exists_for(base)])
    lib, manifest = looped_library(model, tmp_path)
    twin = NumericTwin(model)
    assert "forward_dynamics_derivatives" in model.routines
    for _ in range(2):
        values = random_inputs(model, rng)
        for role in model.routines:
            names = [n for n in manifest["signatures"][role]["inputs"] if n != "p"]
            args = [np.array([values[(n, i)] for i in range(input_length(model, n))]) for n in names]
            for got, want in zip(lib.call(role, *args), getattr(twin, role)(*args)):
                assert np.all(np.isfinite(got)), role
                assert relative_error(got, want, floor=1.0) < 1e-10, role


def test_the_c_is_deterministic_and_split_alike():
    """Two generations give the same bytes; with --split the routine's file holds the body and the loop."""
    model = with_routines("four_bar")
    assert c_text(model) == c_text(model)
    split = c_text(model, split=True)
    text = split["four_bar_impulse_dynamics_derivatives.c"]
    assert "static void four_bar_impulse_dynamics_derivatives_column(" in text
    assert "four_bar_impulse_dynamics_derivatives_columns(aggsym_c, aggsym_v" in text
