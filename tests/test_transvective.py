"""Chapter 3: the transvective factors of A(q), A(q)^-1 = T^T diag(1/.) T (3.19), and the Cauchy form (3.20).

Rung 1 (identities) on every model, symbolically on the double pendulum and the planar three-link arm; rung 2
(the book's examples after (3.17) and (3.20)); the Delta form (3.7) against the delta form (3.15); Pinocchio's
``aba`` and ``computeMinverse`` on models built directly through its API (no URDF involved).
"""
import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import aggsym
from aggsym.core.backend import Numeric, Symbolic
from aggsym.mechanics.bound import bind
from aggsym.mechanics.kinematics import TreeKinematics
from aggsym.model.tree import Tree
from aggsym.contract import ROUTINES
from aggsym.mechanics import sweeps
from aggsym.mechanics.transvective import (
    apply_T, apply_T_transpose, apply_T_transpose_tree, apply_T_tree, articulated_factors, cauchy_solve,
    cauchy_solve_tree, coordinates_above, corrected_factors, forward_dynamics,
    transvected_forces, transvection_pairs,
)
from aggsym.contract import transvective_layout as layout
from aggsym.symbolic import factored_form
from conftest import MODELS, model_path
from helpers import routine_program, routine_sympy
from pinocchio_reference import pin, pinocchio_tree
from robot_builder import chain, root, segment
from test_variants import chain_of_elementary_frames

pytestmark = pytest.mark.pinocchio

DATA = Path(__file__).resolve().parent / "data"
ALL = MODELS + [DATA / "five_body.yaml", DATA / "branching_tree.yaml"]
TRIALS = 4
ROLES = ("forward_dynamics", "inertia_inverse", "transvective_factors")


@pytest.fixture(params=ALL, ids=lambda p: p.stem)
def model(request):
    return aggsym.load(request.param)


def states(model, rng, n=TRIALS):
    for _ in range(n):
        yield rng.uniform(-np.pi, np.pi, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq)


def T_from_layout(model, targs):
    """T rebuilt the way a controller would, from the manifest's layout and the targs output (3.9)."""
    T = np.eye(model.nq)
    for (t, k), a in zip(layout(model)["targs"], targs):
        factor = np.eye(model.nq)
        factor[t, k] = -a
        T = T @ factor
    return T


def rel(x, ref):
    return np.abs(np.asarray(x) - np.asarray(ref)).max() / max(1.0, np.abs(ref).max())


def tol(A):
    """1e-10, widened for ill-conditioned A(q): two backward-stable solutions differ by about cond(A) * 1e-16 (the
    test bench's wrists pass near gimbal lock, cond up to 1e8 on random states; there numpy's own residual
    |inv(A) A - E| reaches 1e-9)."""
    return 1e-10 * max(1.0, np.linalg.cond(A) * 1e-5)


# --------------------------------------------------------------------------------------------------------------
# numerically, every model


def test_factors_diagonalize_inertia(model, rng):
    """T A T^T = diag (3.11) and A = T^-1 diag T^-T (3.18), T rebuilt from the manifest layout."""
    twin = aggsym.NumericTwin(model)
    json.dumps(layout(model))
    for q, _, _ in states(model, rng):
        A = twin.inertia(q)
        targs, diag = twin.transvective_factors(q)
        T = T_from_layout(model, targs)
        D = T @ A @ T.T
        assert np.abs(D - np.diag(np.diag(D))).max() <= 1e-10 * np.abs(A).max()
        assert rel(np.diag(D), diag) <= 1e-10
        Ti = np.linalg.inv(T)
        assert rel(Ti @ np.diag(diag) @ Ti.T, A) <= 1e-10
        assert (diag > 0).all()


def test_inertia_inverse(model, rng):
    """inertia_inverse (3.19) times A is the identity, equals numpy's inverse, and is exactly symmetric."""
    twin = aggsym.NumericTwin(model)
    for q, _, _ in states(model, rng):
        A = twin.inertia(q)
        Ainv = twin.inertia_inverse(q)
        assert np.abs(Ainv @ A - np.eye(model.nq)).max() <= tol(A)
        assert rel(Ainv, np.linalg.inv(A)) <= tol(A)
        assert np.array_equal(Ainv, Ainv.T)
        targs, diag = twin.transvective_factors(q)
        T = T_from_layout(model, targs)
        assert rel(T.T @ np.diag(1 / diag) @ T, Ainv) <= 1e-10


def test_forward_dynamics_inverts_inverse_dynamics(model, rng):
    """forward_dynamics(q, q', inverse_dynamics(q, q', q'')) = q'' (3.20)."""
    twin = aggsym.NumericTwin(model)
    for q, qd, qdd in states(model, rng):
        tau = twin.inverse_dynamics(q, qd, qdd)
        eps = tol(twin.inertia(q))
        assert rel(twin.forward_dynamics(q, qd, tau), qdd) <= eps
        # and it is the Cauchy form with F = tau - b - g - c
        F = tau - twin.bias(q, qd) - twin.gravity(q) - twin.elastic(q)
        assert rel(twin.forward_dynamics(q, qd, tau), twin.inertia_inverse(q) @ F) <= eps


def test_delta_and_Delta_forms_agree(model, rng):
    """The one-step recurrence (3.7) and the multi-step corrections (3.14)-(3.15) give the same arguments <t,k>,
    pivots (beta,beta) and columns beta (Prop. 3.4: (beta,beta)^Delta = (beta,beta)^delta)."""
    bound = bind(model, Numeric())
    for q, _, _ in states(model, rng, 2):
        kin = TreeKinematics(bound, list(q))
        big, small = articulated_factors(bound, kin), corrected_factors(bound, kin)
        assert big.pairs == small.pairs
        scale = max(np.abs(big.diag).max(), 1.0)
        assert np.abs(np.subtract(big.arguments(), small.arguments())).max(initial=0) <= 1e-10 * max(
            1.0, np.abs(big.arguments()).max(initial=0))
        assert np.abs(np.subtract(big.diag, small.diag)).max() <= 1e-10 * scale
        assert np.abs(np.subtract(big.beta, small.beta)).max() <= 1e-10 * max(1.0, np.abs(big.beta).max())


def test_tree_evaluation_is_the_same_product(model, rng):
    """The O(n) evaluation (arguments summed on the tree as 6-vectors) applies the same T, T^T and (3.20) as the
    transvections one by one with the explicit arguments <t,k>, to round-off; so does T F carried by the sweeps."""
    bound = bind(model, Numeric())
    for q, qd, tau in states(model, rng, 3):
        kin = TreeKinematics(bound, list(q))
        fac = articulated_factors(bound, kin)
        lean = articulated_factors(bound, kin, arguments=False)
        assert lean.args == {} and np.array_equal(lean.betabar, fac.betabar)
        F = list(rng.normal(size=model.nq))
        assert rel(apply_T_tree(kin, lean, F), apply_T(fac, F)) <= 1e-13
        assert rel(apply_T_transpose_tree(kin, lean, F), apply_T_transpose(fac, F)) <= 1e-13
        assert rel(cauchy_solve_tree(kin, lean, F), cauchy_solve(fac, F)) <= 1e-13
        F = [t - d for t, d in zip(tau, sweeps.d_vector(bound, kin, list(qd)))]
        assert rel(transvected_forces(bound, kin, lean, list(tau), list(qd)), apply_T(fac, F)) <= 1e-13
        assert rel(forward_dynamics(bound, kin, list(tau), list(qd)), cauchy_solve(fac, F)) <= 1e-13


def test_symbolic_programs_equal_numeric_twin(model, rng):
    """The straight-line programs (with constant folding) evaluate to the numeric twin."""
    twin = aggsym.NumericTwin(model)
    for role in ROLES:
        routine = ROUTINES[role]
        back = Symbolic()
        prog = back.program
        bound = bind(model, back)
        names = [n for n in routine.inputs if n != "p"]
        ins = {n: prog.vector(n, model.nq) for n in names}
        outs = routine.build(bound, TreeKinematics(bound, ins["q"]), ins)
        vals = {n: rng.normal(size=model.nq) for n in names}
        values = {(n, i): float(vals[n][i]) for n in names for i in range(model.nq)}
        values.update({("p", i): v for i, v in enumerate(model.parameter_values)})
        values[("t", 0)] = 0.0  # the time of prescribed spins (the twin's default)
        ref = twin.call(role, *[vals[n] for n in names])
        ref = ref if isinstance(ref, tuple) else (ref,)
        for out, r in zip(outs, ref):
            got = np.array([float(x) for x in prog.evaluate(out, values)])
            assert got.shape == np.ravel(r).shape
            if got.size:
                assert rel(got, np.ravel(r)) <= 1e-12, role


# --------------------------------------------------------------------------------------------------------------
# the number of transvections (branch-induced sparsity)


def test_book_five_body_example():
    """After (3.17): T = t^-1(11,12) t^-1(11,13) t^-1(12,13) t^-1(11,23) t^-1(12,23) t^-1(11,32), in this order."""
    model = aggsym.load(DATA / "five_body.yaml")
    names = layout(model)["targs_names"]
    assert names == [["q11", "q12"], ["q11", "q13"], ["q12", "q13"], ["q11", "q23"], ["q12", "q23"],
                     ["q11", "q32"]]
    twin = aggsym.NumericTwin(model)
    targs, diag = twin.transvective_factors(np.array([0.3, -0.7, 1.1, 0.2, 2.0]))
    assert targs.shape == (6,) and diag.shape == (5,)
    assert np.all(np.abs(targs) > 1e-6)  # none of the six vanishes here


def independent_count(model):
    """Definition: a transvection t_tk exists for every coordinate t above coordinate k on k's root path, i.e. in
    a pair of an ancestor body, or earlier in k's own pair.  The count is the sum over coordinates of the number
    of coordinates above them."""
    tree = Tree(model)
    count = 0
    for k in range(len(tree)):
        above = sum(len(tree.coords[a]) for a in tree.ancestors(k)[:-1])
        count += sum(above + pos for pos in range(len(tree.coords[k])))
    return count


@pytest.mark.parametrize("name,expected", [("walking_machine", 141), ("test_bench", 393)])
def test_number_of_transvections(name, expected):
    model = aggsym.load(model_path(name))
    tree = Tree(model)
    pairs = transvection_pairs(tree)
    assert len(pairs) == independent_count(model) == expected
    assert len(set(pairs)) == len(pairs)
    if all(len(c) == 1 for c in tree.coords):  # single-coordinate pairs: sum of body depths, the root at 0
        assert len(pairs) == sum(d - 1 for d in tree.depth)
    # no transvection joins two branches: t is always a coordinate of an ancestor pair or of k's own pair
    for t, k in pairs:
        assert tree.body_of[t] in tree.ancestors(tree.body_of[k]) and t < k
    twin = aggsym.NumericTwin(model)
    targs, diag = twin.transvective_factors(np.linspace(-1, 1, model.nq))
    assert targs.shape == (expected,) and diag.shape == (model.nq,)


def test_multi_coordinate_pair_is_a_chain_of_eliminations(rng):
    """A pair with k coordinates is eliminated as k scalar steps: the walking machine's free trunk pair has the 15
    transvections among its own 6 coordinates, and the factors equal those of the same system written as a chain
    of massless one-coordinate frames (variant 1): T and diag of A(q) are unique."""
    model = aggsym.load(model_path("walking_machine"))
    pairs = transvection_pairs(Tree(model))
    assert [p for p in pairs if p[1] < 6] == [(t, k) for k in range(6) for t in range(k)]
    split = chain_of_elementary_frames(model)
    assert transvection_pairs(Tree(split)) == pairs
    t1, t2 = aggsym.NumericTwin(model), aggsym.NumericTwin(split)
    for q, _, _ in states(model, rng, 2):
        a1, d1 = t1.transvective_factors(q)
        a2, d2 = t2.transvective_factors(q)
        assert rel(a1, a2) <= 1e-10 and rel(d1, d2) <= 1e-10


def test_coordinates_above_follow_the_tree():
    tree = Tree(aggsym.load(DATA / "five_body.yaml"))
    assert coordinates_above(tree) == [[], [0], [0, 1], [0, 1], [0]]


# --------------------------------------------------------------------------------------------------------------
# symbolically


def trig_zero(expr, angles) -> bool:
    """expr == 0 identically: its numerator, as a polynomial in c_i = cos(angle_i), s_i = sin(angle_i), reduces to
    zero modulo c_i^2 + s_i^2 - 1 (a normal form of degree <= 1 in every c_i, zero iff the function is)."""
    sub, circles = {}, []
    for a in angles:
        c, s = sp.Symbol(f"c_{a}"), sp.Symbol(f"s_{a}")
        sub[sp.cos(a)], sub[sp.sin(a)] = c, s
        circles.append((c, s))
    num, _ = sp.fraction(sp.together(sp.expand_trig(expr).subs(sub)))
    num = sp.expand(num)
    for c, s in circles:
        num = sp.rem(num, c**2 + s**2 - 1, c)
    return sp.expand(num) == 0


def test_trig_zero_can_fail():
    x, y = sp.symbols("x y", real=True)
    assert trig_zero(sp.sin(x) ** 2 + sp.cos(x) ** 2 - 1 + sp.sin(x + y) - sp.sin(x) * sp.cos(y)
                     - sp.cos(x) * sp.sin(y), [x, y])
    assert not trig_zero(sp.sin(x) ** 2 - sp.cos(x) ** 2, [x])


@pytest.mark.parametrize("name", ["double_pendulum", "planar_3link"])
def test_symbolic_identities(name):
    """T A T^T = diag (3.11) and A^-1 A = E (3.19) hold identically for the double pendulum and Tokad's arm."""
    model = aggsym.load(model_path(name))
    eq = aggsym.equations(model)
    angles = [s for s, c in zip(eq.q, model.coordinates) if c.kind == "rotation"]
    factors, D = factored_form(model)
    T = sp.eye(model.nq)
    for f in factors:
        T = T * f
    M = T * eq.A * T.T
    for i in range(model.nq):
        for j in range(model.nq):
            assert trig_zero(M[i, j] - (D[i, i] if i == j else 0), angles), (i, j)
    (flat,) = routine_sympy(model, "inertia_inverse")
    P = sp.Matrix(model.nq, model.nq, flat) * eq.A - sp.eye(model.nq)
    assert all(trig_zero(x, angles) for x in P)


def test_book_cauchy_form_example():
    """The example after (3.20), the double pendulum: only t_13 survives, with argument A_13/(beta,beta)^3, and
    the diagonal is ((beta,beta) of o12, A_22, I366 + m3 r31^2) (A from (2.23))."""
    model = aggsym.load(model_path("double_pendulum"))
    factors, D = factored_form(model, simplify=True)
    m2, m3, r31, I366 = sp.symbols("m2 m3 r31 I366", real=True)
    theta36 = sp.Symbol("theta36", real=True)
    d3 = I366 + m3 * r31**2
    a13 = m3 * r31 * sp.cos(theta36)
    assert len(factors) == 1
    expected = sp.eye(3)
    expected[0, 2] = -a13 / d3
    assert sp.simplify(factors[0] - expected) == sp.zeros(3, 3)
    A = aggsym.equations(model).A
    assert sp.simplify(D[0, 0] - (m2 + m3 - a13**2 / d3)) == 0
    assert sp.simplify(D[1, 1] - A[1, 1]) == 0
    assert sp.simplify(D[2, 2] - d3) == 0
    assert D.is_diagonal()


# --------------------------------------------------------------------------------------------------------------
# Pinocchio, models built through its API


def rigid_tree(path) -> bool:
    """A model Pinocchio can hold: no prescribed spins, no added masses (springs are added to tau)."""
    model = aggsym.load(path)
    return not model.time_dependent and all(b.added_mass is None for b in model.bodies)


@pytest.mark.parametrize("path", [p for p in ALL if rigid_tree(p)], ids=lambda p: p.stem)
def test_against_pinocchio(path, rng):
    """forward_dynamics = pin.aba and inertia_inverse = pin.computeMinverse (upper triangle, mirrored); the
    springs of elastic pairs are the generalized force -C q given to aba."""
    model = aggsym.load(path)
    twin = aggsym.NumericTwin(model)
    pm, _ = pinocchio_tree(model)
    assert pm.nq == model.nq
    data = pm.createData()
    for q, qd, tau in states(model, rng):
        M = pin.crba(pm, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        assert rel(twin.inertia(q), M) <= 1e-10  # the two models are the same system
        eps = tol(M)
        assert rel(twin.forward_dynamics(q, qd, tau), pin.aba(pm, data, q, qd, tau - twin.elastic(q))) <= eps
        Minv = pin.computeMinverse(pm, data, q)
        Minv = np.triu(Minv) + np.triu(Minv, 1).T
        assert rel(twin.inertia_inverse(q), Minv) <= eps


# --------------------------------------------------------------------------------------------------------------
# operation count (deterministic, not timed)


def program_operations(model, role) -> int:
    """Arithmetic nodes (* / + - and negations) reachable from a routine's outputs in its straight-line program,
    after folding and value numbering (the code generator's CSE comes on top)."""
    from aggsym.core.program import ADD, DIV, MUL, NEG, SUB

    prog, outs = routine_program(model, role)
    ids = prog.reachable([x for out in outs for x in out])
    return sum(prog.ops[i][0] in (MUL, DIV, ADD, SUB, NEG) for i in ids)


def chain_urdf(n: int) -> str:
    """A chain of n revolute joints about e1, e2, e3 in turn, every origin, centre of mass and inertia general."""
    axes = ("1 0 0", "0 1 0", "0 0 1")
    body = dict(mass=1.5, com="0.05 0.02 0.1", inertia=(0.02, 0.03, 0.025, 0.001, 0.002, 0.003))
    return chain("chain", root("l0", **body), *(segment(f"j{k}", f"l{k + 1}", xyz="0.1 0.02 0.3", axis=axes[k % 3],
                                                         limit=(-3, 3, 1, 1), **body) for k in range(n)))


def test_forward_dynamics_is_linear_in_n(tmp_path, monkeypatch):
    """The emitted q'' costs O(n): on chains of 6, 12 and 24 links the operations grow by equal steps per link
    (the transvection-by-transvection order with the explicit arguments grows like n d = n^2 on a chain)."""
    from aggsym.mechanics import transvective

    def counts():
        out = []
        for n in (6, 12, 24):
            path = tmp_path / f"chain{n}.urdf"
            path.write_text(chain_urdf(n))
            out.append(program_operations(aggsym.load(path), "forward_dynamics"))
        return out

    def growth(c):
        return (c[2] - c[1]) / (c[1] - c[0])  # 2 for linear, 3 for quadratic (+ linear) growth

    linear = counts()
    monkeypatch.setattr(transvective, "forward_dynamics", lambda bound, kin, tau, qd: cauchy_solve(
        articulated_factors(bound, kin), [t - d for t, d in zip(tau, sweeps.d_vector(bound, kin, qd))]))
    explicit = counts()
    assert growth(linear) <= 2.05 < 2.6 <= growth(explicit)
    assert linear[2] < explicit[2]


def test_forward_dynamics_operation_count():
    """Issue 5: q'' for the six-link arm in at most a third of Table 3.2's 2,579 operations at n = 6."""
    model = aggsym.load(model_path("manipulator6"))
    assert program_operations(model, "forward_dynamics") <= 2579 // 3


def test_pairs_spanning_body_axes_are_solved_in_those_axes(rng):
    """unit_bases finds the pairs whose columns Psi span body axes: the free pairs of the spacecraft, the walking
    machine and the body in a fluid (translations: an orthogonal block, rotations: a 3x3 one), the spherical pairs of
    the spacecraft's second body and the flywheel's carrier, the rolling disc's translations (its yaw already has a
    unit column); not the delta robot's universal pairs (two rotations span three axes), not a pair whose columns are
    unit already, none with an armature.  Forward dynamics in those axes (the pair eliminated along unit columns, as
    a free-flyer's, and one division by det M per rotation block) equals the elimination in the pair's own
    coordinates and, through the sweeps, inverts inverse dynamics."""
    from aggsym.mechanics.transvective import articulated_factors, forward_dynamics, unit_bases

    expected = {"spacecraft": {0: (0, 1, 2, 3, 4, 5), 1: (3, 4, 5)}, "walking_machine": {0: (0, 1, 2, 3, 4, 5)},
                "added_mass_body_in_fluid": {0: (0, 1, 2, 3, 4, 5)}, "flywheel_on_body": {0: (3, 4, 5)},
                "rolling_disc": {0: (0, 1, 2, 5)}, "delta_robot": {}, "double_pendulum_elastic_stand": {}}
    for name, axes in expected.items():
        model = aggsym.load(model_path(name))
        symbolic = bind(model, Symbolic(), tree=Tree(model))
        kin = TreeKinematics(symbolic, symbolic.backend.program.vector("q", symbolic.tree.nq))
        assert {k: b.axes for k, b in unit_bases(symbolic, kin).items()} == axes, name
        numeric = bind(model, Numeric(), tree=Tree(model))
        twin = aggsym.NumericTwin(model)
        for q, qd, qdd in states(model, rng, 2):
            kin = TreeKinematics(numeric, q)
            tau = twin.inverse_dynamics(q, qd, qdd) - twin.elastic(q)
            in_axes = np.array(forward_dynamics(numeric, kin, list(tau), list(qd)), dtype=float)
            own = forward_dynamics(numeric, kin, list(tau), list(qd), articulated_factors(numeric, kin, arguments=False))
            eps = tol(twin.inertia(q))
            assert rel(in_axes, np.array(own, dtype=float)) <= eps, name
            assert rel(in_axes, qdd) <= eps, name
    model = dataclasses.replace(aggsym.load(model_path("spacecraft")), armature=0.01)
    symbolic = bind(model, Symbolic(), tree=Tree(model))
    assert unit_bases(symbolic, TreeKinematics(symbolic, symbolic.backend.program.vector("q", model.nq))) == {}
