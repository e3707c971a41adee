"""The engine: folding and value numbering of straight-line programs, the motion group, M F and (M F)'."""
from pathlib import Path

import numpy as np
import sympy as sp

from aggsym.core.backend import Numeric, Symbolic
from aggsym.core.program import Node, Program
from aggsym.core.program import to_sympy
from aggsym.mechanics.group import Chain, Motion, phi_force, phi_motion, rotation
from aggsym.mechanics.kinematics import pair_functional, pair_velocity_product
from aggsym.mechanics.linalg import mm


def test_folding_of_zeros_ones_and_constants():
    prog = Program()
    x, y = prog.input("q", 0), prog.input("q", 1)
    assert 0 * x == 0 and x * 0 == 0
    assert (1 * x) is x and (x + 0) is x and (x - 0) is x
    assert (x - x) == 0
    assert 2 * (3 * x) == 6 * x
    assert (-x) * (-y) == x * y
    assert -(-x) is x
    assert x + (-y) == x - y
    assert -(x - y) == y - x


def test_value_numbering_shares_equal_operations():
    prog = Program()
    x, y = prog.input("q", 0), prog.input("q", 1)
    assert x * y == y * x
    assert prog.sin(x) is prog.sin(x) or prog.sin(x) == prog.sin(x)
    n = len(prog.ops)
    _ = prog.cos(x) * y, prog.cos(x) * y
    assert len(prog.ops) == n + 2  # cos(x) once, the product once


def test_a_term_and_its_opposite_cancel():
    prog = Program()
    x, y = prog.input("q", 0), prog.input("q", 1)
    assert (x - y) - x == -y and (x + y) - y == x and (x - y) + y == x and x + (y - x) == y
    assert x - (x + y) == -y and x - (x - y) == y


def test_program_evaluates_like_floats():
    prog = Program()
    x, y = prog.input("q", 0), prog.input("q", 1)
    out = [prog.sin(x) * y - 3 * x / (y + 2), -(x - y) * prog.cos(y)]
    vals = prog.evaluate(out, {("q", 0): 0.3, ("q", 1): -1.2}, np)
    assert np.allclose(vals, [np.sin(0.3) * -1.2 - 0.9 / 0.8, -(1.5) * np.cos(-1.2)])


def random_rotation(rng):
    a = rng.uniform(-3, 3, 3)
    return mm(mm(rotation(1, np.cos(a[0]), np.sin(a[0])), rotation(2, np.cos(a[1]), np.sin(a[1]))),
              rotation(3, np.cos(a[2]), np.sin(a[2])))


def six(L: Motion):
    """The 6x6 matrix of L = T(o) C(c) (1.13)-(1.14)."""
    c, o = np.array(L.c, dtype=float), np.array(L.o, dtype=float)
    oh = np.array([[0, -o[2], o[1]], [o[2], 0, -o[0]], [-o[1], o[0], 0]])
    return np.block([[np.eye(3), np.zeros((3, 3))], [oh, np.eye(3)]]) @ np.block(
        [[c, np.zeros((3, 3))], [np.zeros((3, 3)), c]])


def test_motion_group(rng):
    L1 = Motion(random_rotation(rng), tuple(rng.normal(size=3)))
    L2 = Motion(random_rotation(rng), tuple(rng.normal(size=3)))
    F = tuple(rng.normal(size=6))
    assert np.allclose(six(L1.compose(L2)), six(L1) @ six(L2))  # (1.15)
    assert np.allclose(L1.wrench(F), six(L1) @ F)
    assert np.allclose(L1.twist(F), six(L1).T @ F)  # quasi-velocities move with L^T (1.28)
    # power is invariant: (L^T V) . F = V . (L F)
    V = tuple(rng.normal(size=6))
    assert np.isclose(np.dot(L1.twist(V), F), np.dot(V, L1.wrench(F)))


def test_a_chain_turns_like_its_product(rng):
    factors = [rotation(1, np.cos(a), np.sin(a)) if i % 2 else rotation(3, np.cos(a), np.sin(a))
               for i, a in enumerate(rng.uniform(-3, 3, 3))]
    c = mm(mm(factors[0], factors[1]), factors[2])
    L = Motion(c, tuple(rng.normal(size=3)))
    C = Chain(c, L.o, factors)
    F = tuple(rng.normal(size=6))
    for method in ("wrench", "twist", "motion"):
        assert np.allclose(getattr(C, method)(F), getattr(L, method)(F))
    assert np.allclose(C.rotate_free(F[:3]), L.rotate_free(F[:3]))
    assert np.allclose(C.unrotate_free(F[:3]), L.unrotate_free(F[:3]))


def test_phi_is_derivative_of_motion(rng):
    """dL/dt = L Phi (1.22): L(t) = T(o + t v) C(exp(t w^)) to first order."""
    c = random_rotation(rng)
    o, v, w = rng.normal(size=(3, 3))
    h = 1e-6
    wh = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    def L(t):
        from scipy.linalg import expm
        return six(Motion(tuple(map(tuple, np.array(c) @ expm(t * wh))), tuple(o + t * np.array(c) @ v)))
    Ldot = (L(h) - L(-h)) / (2 * h)
    V = tuple(v) + tuple(w)
    U = tuple(rng.normal(size=6))
    F = tuple(rng.normal(size=6))
    # L^T' U = -Phi^T... checked through the actions used by the sweeps:
    assert np.allclose(Ldot.T @ U, phi_motion(six(Motion(c, tuple(o))).T @ U, V), atol=1e-6)
    assert np.allclose(np.linalg.solve(L(0), Ldot) @ F, phi_force(V, F), atol=1e-6)


def test_mf_and_its_derivative_against_sympy():
    """M F (1.30)-(1.31) is the Jacobian of the pair's twist, and (M F)' q' (2.19) its time derivative."""
    codes = ("o1", "o3", "theta4", "theta5", "theta6")
    t = sp.Symbol("t")
    qs = [sp.Function(f"q{i}")(t) for i in range(5)]
    back = Symbolic()
    prog = back.program
    qn = prog.vector("q", 5)
    motion, psi, rots = pair_functional(codes, qn, back)
    qdn = prog.vector("qd", 5)
    zeta = pair_velocity_product(codes, qdn, rots)
    syms = {("q", i): qs[i] for i in range(5)}
    syms.update({("qd", i): qs[i].diff(t) for i in range(5)})
    Psi = sp.Matrix(6, 5, lambda r, c: to_sympy(prog, [psi[c][r]], syms)[0])
    c = sp.Matrix(3, 3, lambda i, j: to_sympy(prog, [motion.c[i][j]], syms)[0])
    o = sp.Matrix([to_sympy(prog, [x], syms)[0] for x in motion.o])
    # twist of the child in its own frame: v = c^T o', w from c^T c'
    qdot = sp.Matrix([x.diff(t) for x in qs])
    v = c.T * o.diff(t)
    W = c.T * c.diff(t)
    w = sp.Matrix([W[2, 1], W[0, 2], W[1, 0]])
    twist = sp.Matrix.vstack(v, w)
    assert sp.simplify(Psi * qdot - twist) == sp.zeros(6, 1)
    zeta_s = sp.Matrix([to_sympy(prog, [x], syms)[0] for x in zeta])
    expected = (Psi * qdot).diff(t) - Psi * qdot.diff(t)
    vals = {qs[i]: 0.3 * i - 0.5 for i in range(5)}
    vals.update({qs[i].diff(t): 0.7 - 0.2 * i for i in range(5)})
    num = (zeta_s - expected).subs({d: vals[d] for d in vals if isinstance(d, sp.Derivative)}).subs(vals)
    assert max(abs(float(x)) for x in num) < 1e-12


def test_numeric_backend_runs_on_batches():
    q = np.array([0.1, 0.2, 0.3])
    motion, psi, _ = pair_functional(("theta4", "theta5", "theta6"), [q, q, q], Numeric())
    assert np.shape(motion.c[0][0]) == (3,)


def test_nodes_have_no_truth_value():
    prog = Program()
    x = prog.input("q", 0)
    assert isinstance(x, Node)
    try:
        bool(x)
    except TypeError:
        pass
    else:
        raise AssertionError("a symbolic value must not have a truth value")


def test_deep_programs_print_and_evaluate_without_deep_recursion():
    """A 200,000-term sum (a chain of additions, each used once) is named every INLINE_DEPTH levels, so printing it
    recurses no deeper than that; evaluation is iterative.  The interpreter's recursion limit is never raised."""
    import sys

    from aggsym.codegen.printing import Infix
    from aggsym.codegen.targets.c import c_spelling
    from aggsym.core.program import INLINE_DEPTH, Program, straight_line

    limit = sys.getrecursionlimit()
    prog = Program()
    xs = prog.vector("p", 200_000)
    acc = 0
    for x in xs:
        acc = acc + x * x
    sl = straight_line(prog, [[acc]])
    assert 200_000 // INLINE_DEPTH - 2 <= len(sl.temps) <= 200_000 // (INLINE_DEPTH // 2)
    names = {prog.inputs[key].id: f"p_{key[1]}" for key in sl.inputs}
    names.update({i: f"x{k}" for k, i in enumerate(sl.temps)})
    printer = Infix(prog, names, c_spelling())
    lines = [printer(prog.nodes[i]) for i in sl.temps]
    assert lines[-1].count("+") <= INLINE_DEPTH
    values = {("p", i): 1.0 + (i % 7) for i in range(200_000)}
    (total,) = prog.evaluate([acc], values)
    assert total == sum((1.0 + (i % 7)) ** 2 for i in range(200_000))
    assert sys.getrecursionlimit() == limit


def test_the_infix_printer_prints_the_program_value_counts_and_names():
    """The infix printer's text of every statement, in NumPy's spelling, evaluates (as Python) to the program's
    value; its operation counts are what count_ops reads from the C spelling's text (double and float), and the
    names it reports used are the names in the text, in order: on the statements of a robot-like model's routines
    and on a program of divisions, calls, negative and fractional constants and several constants in one sum."""
    import re
    from fractions import Fraction

    import numpy as np

    from aggsym.codegen.generate import symbolic_routines
    from aggsym.codegen.printing import Infix, count_ops
    from aggsym.codegen.targets.c import C_FUNCTIONS, c_spelling
    from aggsym.codegen.targets.numpy import NUMPY
    from aggsym.core.program import straight_line
    from aggsym.model import load

    def compare(prog, outputs, scalar):
        sl = straight_line(prog, outputs)
        names = {prog.inputs[key].id: f"{key[0]}_{key[1]}" for key in sl.inputs}
        names.update({i: f"x{k}" for k, i in enumerate(sl.temps)})
        values = {key: 0.3 + 0.17 * k for k, key in enumerate(sorted(sl.inputs))}
        env = {"np": np, **{f"{kind}_{i}": v for (kind, i), v in values.items()}}
        c, py = Infix(prog, names, c_spelling(scalar)), Infix(prog, names, NUMPY)
        rhs = [(prog.nodes[i], True) for i in sl.temps]
        rhs += [(x, not (isinstance(x, Node) and x.id in names)) for out in outputs for x in out]
        texts = []
        for x, top in rhs:
            text = py(x, top)
            texts.append(c(x, top))
            expected = prog.evaluate([x], values, np)[0]
            assert np.isclose(float(eval(text, env)), float(expected), rtol=1e-12, atol=1e-12), text  # noqa: S307
            if isinstance(x, Node) and x.id in names:
                env[names[x.id]] = eval(text, env)  # noqa: S307
            used = [n for n in re.findall(r"[A-Za-z_]\w*", text) if n != "np" and not hasattr(np, n)]
            assert py.refs == used == c.refs
            py.refs.clear()
            c.refs.clear()
        assert c.counts == count_ops(";\n".join(texts)), scalar
        assert all(name in C_FUNCTIONS.values() or name.rstrip("f") in C_FUNCTIONS.values()
                   for name in re.findall(r"([A-Za-z_]\w*)\(", ";".join(texts)))
        return len(rhs)

    prog = Program()
    p = prog.vector("p", 4)
    q = prog.vector("q", 3)
    s, c = prog.sin(q[0]), prog.cos(q[0])
    outs = [
        p[0] * q[1] + 2.5 - p[1] * q[2] + Fraction(1, 3) - 0.75,  # three constants merged into one
        -(p[0] + q[1]) * (q[2] - p[2]) / (p[3] * s + c),
        prog.call("atan2", q[1] * -1.5, q[2] + 1) / (2 * p[0]) - prog.sqrt(p[1] * p[1] + 1e-3),
        -(q[0] * q[1]) - (-(p[0] * s)) * c,
        (q[0] - 1) * (1 - q[0]) * Fraction(2, 7) - prog.call("sign", q[2] - p[3]),
        -(q[1] / (q[2] + 2)),
        prog.call("abs", q[0] * q[1] + 3) * prog.call("abs", q[0] * q[1] + 3),
        q[2] * 1e30 + 0.1 * q[1] - 0.1 * q[1],
        -3 / q[0] + q[1] / -2.5 - prog.call("atan2", -1.5, q[2]) * (Fraction(-1, 2) / q[1]),
    ]
    for scalar in ("double", "float"):
        assert compare(prog, [outs], scalar) > len(outs)
    model = load(_models_dir() / "double_pendulum.yaml")
    prog, outputs = symbolic_routines(model)
    assert sum(compare(prog, outs, "double") for outs in outputs.values()) > 100


def _models_dir():
    from pathlib import Path

    return Path(__file__).resolve().parent.parent / "models"


def test_a_sealed_program_keeps_its_nodes_and_generation_is_unchanged(monkeypatch):
    """Program.seal drops the value-numbering tables (a quarter of the program's memory on long chains): the nodes
    stay, a node made afterwards is correct but not shared with an earlier equal one; and generate(), which seals
    the program before printing, writes byte for byte what it writes without sealing (the walking machine: every
    routine, LaTeX included)."""
    from aggsym.codegen.generate import generate
    from aggsym.model import load

    prog = Program()
    x, y = prog.vector("q", 2)
    before = x * y + 2.5
    count = len(prog.ops)
    prog.seal()
    assert len(prog.ops) == count and prog.nodes[before.id] is before
    again = x * y + 2.5
    assert again.id != before.id and prog.evaluate([again], {("q", 0): 3.0, ("q", 1): 4.0}) == [14.5]
    model = load(Path(__file__).resolve().parents[1] / "models" / "walking_machine.yaml")
    sealed = generate(model).files
    monkeypatch.setattr(Program, "seal", lambda self: None)
    assert generate(model).files == sealed


def test_the_function_table_agrees_with_itself():
    """Each function of the one table: its float value, NumPy and SymPy forms agree, the grammar offers all but
    sign, and its derivative rule (dual numbers over floats) matches a central difference."""
    import math

    import numpy as np
    import sympy as sp

    from aggsym.core.backend import Numeric
    from aggsym.core.dual import Dual, DualBackend
    from aggsym.core.functions import FUNCTIONS, GRAMMAR
    from aggsym.model.readers.expressions import parse_value

    assert set(FUNCTIONS) - set(GRAMMAR) == {"sign"}
    dual = DualBackend(Numeric())
    for name, f in FUNCTIONS.items():
        args = (0.4, 0.7)[:f.arity]
        value = f.value(*args)
        assert math.isclose(f.numpy(*args), value, rel_tol=1e-14)
        assert math.isclose(float(f.sympy(*(sp.Float(a) for a in args))), value, rel_tol=1e-14)
        if name in GRAMMAR:
            parsed = parse_value(f"{name}({', '.join(map(str, args))})", {})
            assert math.isclose(float(parsed), value, rel_tol=1e-14)
        if f.derivative is None:
            continue
        for k in range(f.arity):
            seeded = [Dual(a, {0: 1.0}) if j == k else a for j, a in enumerate(args)]
            out = dual.call(name, *seeded)
            got = out.d.get(0, 0.0) if isinstance(out, Dual) else 0.0
            h = 1e-6
            up = [a + (h if j == k else 0) for j, a in enumerate(args)]
            down = [a - (h if j == k else 0) for j, a in enumerate(args)]
            assert math.isclose(got, (f.value(*up) - f.value(*down)) / (2 * h), rel_tol=1e-7, abs_tol=1e-9), name


def test_forward_mode_on_a_straight_line_equals_sympy():
    """along_inputs differentiates a program's outputs along some of its inputs as new nodes of the same program
    (what the PyTorch target emits for the quaternion entries): every function with a derivative rule, quotients,
    an output that does not depend on one input, a constant output; checked against SymPy's derivatives."""
    from aggsym.core.dual import along_inputs

    prog = Program()
    x, y, z = (prog.input("q", i) for i in range(3))
    w = prog.input("p", 0)
    outs = [prog.sin(x) * y / (1 + x * x) + prog.sqrt(y * y + w) - prog.cos(x * y),
            prog.call("atan2", y, x) * prog.call("abs", z) + prog.call("sign", x) * z,
            3 * z - w, 2.5]
    cols = along_inputs(prog, outs, [("q", 0), ("q", 1)])
    assert len(cols) == 4 and all(len(c) == 2 for c in cols)
    assert cols[2] == [0, 0] and cols[3] == [0, 0]  # no dependence: exact zeros, no nodes
    X, Y, Z, W = sp.symbols("x y z w", real=True)
    names = {("q", 0): X, ("q", 1): Y, ("q", 2): Z, ("p", 0): W}
    exprs = to_sympy(prog, outs[:2], names)
    derivs = to_sympy(prog, [d for c in cols[:2] for d in c], names)
    point = {X: 0.37, Y: -1.21, Z: 0.83, W: 2.0}
    want = [float(sp.diff(e, s).subs(point)) for e in exprs for s in (X, Y)]
    got = [float(d.subs(point)) for d in derivs]
    assert np.allclose(got, want, rtol=1e-13, atol=1e-13)
