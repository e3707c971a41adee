"""The program-to-text pipeline after its speed-up: operation counts taken while printing equal the counts read back
from the C text, the text counter reads C as C's grammar does, and ``generate`` leaves Python's garbage collector
as it found it."""
from __future__ import annotations

import gc

import pytest

import aggsym
from aggsym.errors import AggsymError
from aggsym.codegen.generate import generate
from aggsym.codegen.printing import count_ops
from aggsym.core.program import Program, straight_line

from conftest import model_path


@pytest.mark.parametrize("name,scalar", [("double_pendulum", "double"), ("manipulator6", "double"),
                                         ("walking_machine_on_ground", "double"), ("manipulator6", "float"),
                                         ("gyroscope_spinning_rotor", "double")])
def test_ops_counted_while_printing_equal_the_c_texts(name, scalar):
    """The manifest's ops come from the printer's counts; the tokenizing counter over each routine's C statements
    (a separate reading of the text) must give the same numbers, routine by routine."""
    gen = generate(aggsym.load(model_path(name)), targets="c,numpy,manifest", scalar=scalar)
    assert gen.routines
    for r in gen.routines:
        assert r.ops == count_ops("\n".join(r.bodies["c"].lines)), r.routine.role


@pytest.mark.parametrize("code,expected", [
    ("const double x0 = 1e-05 - y;", (0, 1, 0, 0)),  # the exponent's sign is part of the literal
    ("z = x1e5-2.5E+3*y;", (1, 1, 0, 0)),  # digits in a name are not a literal
    ("A[1]-B[2] + (a)-(b);", (0, 3, 0, 0)),  # after ] and ) a sign is binary
    ("a = -b + -c*-d;", (1, 1, 0, 0)),  # after = + * a sign is unary
    ("if (!p) p = p_defaults;\nreturn s[0] != 0.0;\n(void)q;", (0, 0, 0, 0)),  # keywords and casts are no calls
    ("y = f (a, b)/g(c) + sizeof(x);", (0, 1, 1, 2)),
    ("/* a*b + c/d */ x = 1.5f + .5;", (0, 1, 0, 0)),
    ("aggsym_sincos(q_0, &s, &c);", (0, 0, 0, 1)),
    ("aggsym_sincos2(q_0, q_1, &s, &c, &t, &d);", (0, 0, 0, 2)),  # two angles: two calls, as the manifest counts
])
def test_count_ops_reads_c(code, expected):
    got = count_ops(code)
    assert (got["mul"], got["add"], got["div"], got["call"]) == expected


def test_generate_leaves_the_collector_as_it_was():
    """The collector is paused while generating (the program's nodes are freed by reference counting) and
    restored after, whether it was on or off, and after a failure too."""
    model = aggsym.load(model_path("double_pendulum"))
    assert gc.isenabled()
    generate(model, targets="c,numpy,manifest")
    assert gc.isenabled()
    gc.disable()
    try:
        generate(model, targets="c,numpy,manifest")
        assert not gc.isenabled()
    finally:
        gc.enable()
    with pytest.raises(AggsymError):
        generate(model, targets="c,numpy,manifest", scalar="half")
    assert gc.isenabled()


def test_hash_consing_and_product_numbering_survive_the_fast_paths():
    """Operations on two nodes, on a node and a constant, and products equal up to order and constant factors are
    one node each; the folds give the same values as plain arithmetic."""
    prog = Program()
    x, y, z = prog.vector("q", 3)
    assert (x + y).id == (y + x).id
    assert (x - y).id != (y - x).id
    assert (2 * x).id == (x * 2).id
    assert ((2 * x) * y).id == (x * (2 * y)).id == (y * (x * 2)).id
    assert ((x * y) * z).id == (z * (y * x)).id
    assert (x * y) - (y * x) == 0
    exprs = [x + y, x - y, -x * y, (x * -2.5) / y, -(x - y), x + -y, -x - y, 3 - x, (2 * x) * (3 * y)]
    values = {("q", 0): 0.7, ("q", 1): -1.3, ("q", 2): 2.0}
    X, Y = 0.7, -1.3
    want = [X + Y, X - Y, -X * Y, (X * -2.5) / Y, -(X - Y), X - Y, -X - Y, 3 - X, 6 * X * Y]
    got = prog.evaluate(exprs, values)
    assert got == pytest.approx(want, rel=1e-15)
    sl = straight_line(prog, [exprs])
    assert sl.inputs == [("q", 0), ("q", 1)]


def test_scratch_programs_are_freed_while_the_collector_is_paused():
    """The counts that choose a routine's form build throwaway programs; generating pauses the cyclic
    collector, so a scratch program must be freed by reference counting alone (Program.release breaks the
    node <-> program cycle), or a 96-link chain held three dead programs (1 GB instead of 450 MB)."""
    from aggsym.collector import collector_paused
    from aggsym.core.backend import Symbolic
    from aggsym.mechanics import bias
    from aggsym.mechanics.bound import bind, scratch_operations
    from aggsym.mechanics.kinematics import TreeKinematics

    model = aggsym.load(model_path("manipulator6"))
    back = Symbolic()
    bound = bind(model, back)
    kin = TreeKinematics(bound, back.program.vector("q", model.nq))

    def programs():
        # (type(), not isinstance(): another test may leave a dead weakref.proxy among the objects, and
        # isinstance() would look through it and raise ReferenceError)
        return sum(1 for o in gc.get_objects() if type(o) is Program)

    with collector_paused():
        before = programs()
        count = scratch_operations(bound, kin, lambda b, k, u: bias.coriolis_by_recursion(b, k, u, True))
        assert count > 0 and programs() == before
