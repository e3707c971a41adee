"""Hooke elasticity (1.4, 2.3): A q'' + b + g + C q = tau (2.27), and the slow/fast partition of Prop. 2.14.

The book's example after (2.28), the double pendulum with sliding hanger on an elastic stand, with its printing
errors repaired:

* the signs: the book writes C = [f1]^T C(0,1) [f1] = -[[c22, c25, 0], [c52, c55, 0], [0, 0, 0]] and the rows
  "... - c22 delta12 - c25 delta15 = Q1": its c_ij are the coefficients of the elastic wrench *on* the body
  (M^T C^{lk} = C(i, k-1) f q of Notation 2.8), i.e. minus the stiffness K of the model file; with K positive
  the left side holds + K q, a restoring force;
* the second row is printed with "- c22 delta12 - c25 delta15", the first row's spring; it is row 2 of C q,
  "- c52 delta12 - c55 delta15";
* with one elementary motion per frame ((1.24)-(1.26)) the book prints Cq = col(c22 delta12, c52 delta12, 0),
  which should be col(-c22 delta12, -c55 delta15, 0): C is diagonal there, the cross term c25 is lost (the
  book's remark after (2.27)) - a test below builds that model and finds C = diag(k22, k55, 0);
* alpha is printed without the factor sin(theta36) of its first term, as in (2.24).

B(q, q') is the book's S Phi A S^T + S A S'^T (2.17), (2.31): for the double pendulum it is (2.25)'s matrix.
"""
import json

import numpy as np
import pytest
import sympy as sp

import aggsym
from aggsym.core.backend import Numeric, Symbolic
from aggsym.mechanics.bound import bind
from aggsym.mechanics.bias import coriolis_matrix
from aggsym.codegen.generate import generate
from aggsym.mechanics.elastic import BLOCKS, fast_slow
from aggsym.core.program import to_sympy
from aggsym.symbolic import coordinate_symbols
from aggsym.errors import ModelError
from aggsym.mechanics.kinematics import TreeKinematics
from conftest import MODELS, model_path
from helpers import assert_model_error, routine_sympy
from test_book_closed_forms import assert_equal, sym

ELASTIC = "double_pendulum_elastic_stand"


def book_coefficients(theta):
    m2, m3, r21, r31, p31, I255, I344, I355, I366 = sym("m2", "m3", "r21", "r31", "p21", "I255", "I344", "I355",
                                                       "I366")
    c, s = sp.cos(theta), sp.sin(theta)
    alpha = (I344 - I355) * s * c - m3 * (p31 + r31 * c) * r31 * s
    beta = -m3 * r31 * s
    gamma = I255 + m2 * r21**2 + m3 * (p31 + r31 * c) ** 2 + I344 * s**2 + I355 * c**2
    return alpha, beta, gamma, m2, m3, r31, I366


def test_elastic_double_pendulum_is_the_book_example():
    """A q'' + b + C q of the model equals the three equations after (2.28), with the book's c_ij = -k_ij."""
    model = aggsym.load(model_path(ELASTIC))
    eq = aggsym.equations(model)
    d12, d15, th = eq.q
    v12, v15, vth = eq.qd
    a12, a15, ath = eq.qdd
    alpha, beta, gamma, m2, m3, r31, I366 = book_coefficients(th)
    k22, k25, k55 = sym("k22", "k25", "k55")
    c22, c25, c52, c55 = -k22, -k25, -k25, -k55  # the book's elastic-wrench coefficients
    book = sp.Matrix([
        (m2 + m3) * a12 + m3 * r31 * sp.cos(th) * ath + beta * vth**2 - c22 * d12 - c25 * d15,
        gamma * a15 + 2 * alpha * v15 * vth - c52 * d12 - c55 * d15,
        m3 * r31 * sp.cos(th) * a12 + (I366 + m3 * r31**2) * ath - alpha * v15**2,
    ])
    assert_equal(eq.A * eq.qdd + eq.b + eq.c, book)
    C = sp.Matrix([[k22, k25, 0], [k25, k55, 0], [0, 0, 0]])
    assert eq.c == C * eq.q
    # and the generated routines: elastic is C q, inverse_dynamics is A q'' + b + g + C q
    (c,) = routine_sympy(model, "elastic")
    assert sp.Matrix(c) == C * eq.q


def test_one_motion_per_frame_loses_the_cross_stiffness(tmp_path):
    """The same stand indexed by frames (1.24)-(1.26): a massless hanger frame with o2, the arm with theta5, each
    elastic with its own 1x1 stiffness.  C is diagonal (the book's remark after (2.27)), and the equations equal
    the variant-2 model's with k25 = 0."""
    text = model_path(ELASTIC).read_text()
    variant1 = text.replace(
        "  - name: arm1\n    parent: world\n    pair:\n      name: stand\n"
        "      functional: {o2: delta12, theta5: delta15}\n      stiffness: [[k22, k25], [k25, k55]]\n",
        "  - name: hanger\n    parent: world\n    pair: {name: slide, functional: {o2: delta12}, stiffness: [k22]}\n"
        "  - name: arm1\n    parent: hanger\n"
        "    pair: {name: swing, functional: {theta5: delta15}, stiffness: [k55]}\n")
    assert variant1 != text
    (tmp_path / "v1.yaml").write_text(variant1)
    e1 = aggsym.equations(aggsym.load(tmp_path / "v1.yaml"))
    e2 = aggsym.equations(aggsym.load(model_path(ELASTIC)))
    k22, k25, k55 = sym("k22", "k25", "k55")
    assert e1.c == sp.Matrix([k22 * e1.q[0], k55 * e1.q[1], 0])
    assert_equal(e1.lhs().subs(k25, 0), e2.lhs().subs(k25, 0))
    assert e2.lhs() != e2.lhs().subs(k25, 0)


def test_coriolis_matrix_of_the_double_pendulum_is_the_book_2_25():
    """B = S Phi Theta S^T + S Theta S'^T is printed after (2.24): [[0, 0, beta th'], [0, 2 alpha th', 0],
    [beta th', -alpha th25', -beta o12']] (alpha with the sin factor, see test_book_closed_forms)."""
    model = aggsym.load(model_path("double_pendulum"))
    back = Symbolic()
    prog = back.program
    bound = bind(model, back)
    qv, qdv = prog.vector("q", 3), prog.vector("qd", 3)
    B = coriolis_matrix(bound, TreeKinematics(bound, qv), qdv)
    q, qd, _ = coordinate_symbols(model)
    symbols = {("p", i): s for i, s in enumerate(model.parameter_symbols)}
    symbols.update({("q", i): s for i, s in enumerate(q)})
    symbols.update({("qd", i): s for i, s in enumerate(qd)})
    Bs = sp.Matrix(3, 3, to_sympy(prog, [x for row in B for x in row], symbols))
    m3, r31, p31, I344, I355 = sym("m3", "r31", "p31", "I344", "I355")
    c, s = sp.cos(q[2]), sp.sin(q[2])
    alpha = (I344 - I355) * s * c - m3 * (p31 + r31 * c) * r31 * s
    beta = -m3 * r31 * s
    book = sp.Matrix([[0, 0, beta * qd[2]], [0, 2 * alpha * qd[2], 0], [beta * qd[2], -alpha * qd[1], -beta * qd[0]]])
    assert_equal(Bs, book)


@pytest.mark.parametrize("path", [p for p in MODELS if not aggsym.load(p).time_dependent], ids=lambda p: p.stem)
def test_bias_is_B_times_qd(path, rng):
    """b = B(q, q') q' (2.17) for every model without prescribed spins, B built column by column."""
    model = aggsym.load(path)
    twin = aggsym.NumericTwin(model)
    bound = bind(model, Numeric())
    for _ in range(2):
        q, qd = rng.uniform(-np.pi, np.pi, model.nq), rng.normal(size=model.nq)
        B = np.array(coriolis_matrix(bound, TreeKinematics(bound, list(q)), list(qd)), dtype=float)
        b = twin.bias(q, qd)
        assert np.abs(B @ qd - b).max() <= 1e-11 * max(1.0, np.abs(b).max())
        # B is linear in q'
        B2 = np.array(coriolis_matrix(bound, TreeKinematics(bound, list(q)), list(2 * qd)), dtype=float)
        assert np.allclose(B2, 2 * B, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(B).max()))


def test_partition_of_prop_2_14(rng):
    """The blocks of elastic_partition rebuild P A P^T, P B P^T and P C P^T with the manifest's permutation, and
    the two block equations of Prop. 2.14 hold with tau = inverse_dynamics."""
    model = aggsym.load(model_path(ELASTIC))
    twin = aggsym.NumericTwin(model)
    layout = json.loads(generate(model, targets="c,numpy,manifest").files[f"{ELASTIC}.json"])["layouts"]["elastic_partition"]
    assert layout["slow"] == ["theta26"] and layout["fast"] == ["delta12", "delta15"]
    perm = layout["permutation"]
    assert perm == [2, 0, 1]
    ns = len(layout["slow"])
    bound = bind(model, Numeric())
    for _ in range(3):
        q, qd, qdd = rng.normal(size=(3, 3))
        out = dict(zip([b[0] for b in BLOCKS], twin.elastic_partition(q, qd)))
        for name, blk in out.items():
            assert list(blk.shape) == layout["blocks"][name]["shape"]
        PA = np.block([[out["A_pp"], out["A_mp"]], [out["A_pm"], out["A_mm"]]])
        PB = np.block([[out["B_pp"], out["B_mp"]], [out["B_pm"], out["B_mm"]]])
        A = twin.inertia(q)
        B = np.array(coriolis_matrix(bound, TreeKinematics(bound, list(q)), list(qd)), dtype=float)
        assert np.allclose(PA, A[np.ix_(perm, perm)], rtol=1e-14, atol=1e-15)
        assert np.allclose(PB, B[np.ix_(perm, perm)], rtol=1e-13, atol=1e-14)
        assert np.allclose(PB @ qd[perm], twin.bias(q, qd)[perm], rtol=1e-12, atol=1e-13)
        values = dict(zip(model.parameter_symbols, model.parameter_values))
        k = [values[sp.Symbol(n, real=True)] for n in ("k22", "k25", "k55")]
        assert np.array_equal(out["C_mm"], [[k[0], k[1]], [k[1], k[2]]])
        tau = twin.inverse_dynamics(q, qd, qdd)[perm]
        g = twin.gravity(q)[perm]
        qm = q[perm][ns:]
        vp, vm = qd[perm][:ns], qd[perm][ns:]
        ap, am = qdd[perm][:ns], qdd[perm][ns:]
        slow = out["A_pp"] @ ap + out["B_pp"] @ vp + out["A_mp"] @ am + out["B_mp"] @ vm + g[:ns]
        fast = out["A_mm"] @ am + out["B_mm"] @ vm + out["A_pm"] @ ap + out["B_pm"] @ vp + out["C_mm"] @ qm + g[ns:]
        assert np.allclose(slow, tau[:ns], rtol=1e-12, atol=1e-12)
        assert np.allclose(fast, tau[ns:], rtol=1e-12, atol=1e-12)


def test_partition_blocks_are_the_book_example():
    """Symbolically: A-+ = (m3 r31 c, 0) (row theta26, columns delta12, delta15), A++ = I366 + m3 r31^2,
    B-+ = (beta th', -alpha delta15'), B+- = (beta th', 0)^T, B-- = [[0, 0], [0, 2 alpha th']], B++ = -beta
    delta12', C-- = K: the elastic stand has no inertial coupling of delta15 with theta26."""
    model = aggsym.load(model_path(ELASTIC))
    out = dict(zip([b[0] for b in BLOCKS], routine_sympy(model, "elastic_partition")))
    q, qd, _ = coordinate_symbols(model)
    alpha, beta, gamma, m2, m3, r31, I366 = book_coefficients(q[2])
    k22, k25, k55 = sym("k22", "k25", "k55")
    c = sp.cos(q[2])
    expected = {
        "A_pp": [I366 + m3 * r31**2], "A_mp": [m3 * r31 * c, 0], "A_pm": [m3 * r31 * c, 0],
        "A_mm": [m2 + m3, 0, 0, gamma],
        "B_pp": [-beta * qd[0]], "B_mp": [beta * qd[2], -alpha * qd[1]], "B_pm": [beta * qd[2], 0],
        "B_mm": [0, 0, 0, 2 * alpha * qd[2]], "C_mm": [k22, k25, k25, k55],
    }
    for name, value in expected.items():
        assert_equal(out[name], value)


def test_manifest_of_an_elastic_model():
    model = aggsym.load(model_path(ELASTIC))
    m = json.loads(generate(model, targets="c,numpy,manifest").files[f"{ELASTIC}.json"])
    assert m["conservative"] is True
    assert m["functions"]["elastic"] == f"{ELASTIC}_elastic"
    assert m["signatures"]["elastic"] == {"inputs": ["q", "p"], "outputs": [{"name": "c", "shape": [3]}],
                                          "input_sizes": {"q": 3, "p": len(m["parameters"])}, "returns": "void"}
    assert m["elastic"]["pairs"] == [{"joint": "stand", "coordinates": ["delta12", "delta15"],
                                      "stiffness": [["k22", "k25"], ["k25", "k55"]], "rest": ["0", "0"]}]
    assert [o["name"] for o in m["signatures"]["elastic_partition"]["outputs"]] == [b[0] for b in BLOCKS]
    rigid = json.loads(generate(aggsym.load(model_path("double_pendulum")), targets="c,numpy,manifest").files[
        "double_pendulum.json"])
    assert "elastic" not in rigid["functions"] and "elastic_partition" not in rigid["functions"]


def test_rest_position(tmp_path, rng):
    """rest: q0 shifts the spring: c = C (q - q0), U gains 1/2 (q - q0)^T C (q - q0), and q = q0 has no spring."""
    spring = "      stiffness: [[k22, k25], [k25, k55]]\n"
    text = model_path(ELASTIC).read_text().replace(spring, spring + "      rest: [0.01, -0.1]\n")
    path = tmp_path / "rest.yaml"
    path.write_text(text)
    model, ref = aggsym.load(path), aggsym.load(model_path(ELASTIC))
    t, r = aggsym.NumericTwin(model), aggsym.NumericTwin(ref)
    q0 = np.array([0.01, -0.1, 0.0])
    for _ in range(2):
        q = rng.normal(size=3)
        assert np.allclose(t.elastic(q), r.elastic(q - q0), rtol=1e-14, atol=1e-14)
        dU = t.potential_energy(q)[0] - r.potential_energy(q)[0]
        assert dU == pytest.approx(0.5 * (q - q0) @ r.elastic(q - q0) - 0.5 * q @ r.elastic(q), rel=1e-12)
    assert np.abs(t.elastic(q0 + [0, 0, 1.3])).max() == 0


BAD = {
    "stiffness_not_psd": ("stiffness: [[1, 2], [2, 1]]", "bodies[0].pair.stiffness", ["not positive semi-definite"]),
    "stiffness_wrong_size": ("stiffness: [1, 2, 3]", "bodies[0].pair.stiffness", ["expected 2 entries, got 3"]),
    "rest_without_stiffness": ("rest: [0, 0]", "bodies[0].pair.rest", ["needs a stiffness"]),
    "rest_wrong_size": ("stiffness: [1, 1]\n      rest: [0]", "bodies[0].pair.rest", ["expected 2 entries, got 1"]),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_elastic_pair_is_reported_precisely(case, tmp_path):
    entry, where, words = BAD[case]
    path = tmp_path / f"{case}.yaml"
    path.write_text("name: x\nbodies:\n  - name: a\n    pair:\n      functional: {o1: x, o2: y}\n      "
                    + entry + "\n    mass: 1.0\n")
    assert_model_error(path, where, words)


@pytest.mark.compiler
def test_all_coordinates_elastic_generates_empty_slow_blocks(tmp_path):
    """A body on a spring only (no slow coordinate): the slow blocks are empty, and the C still compiles
    warning-free (-Werror) and matches the twin."""
    from aggsym.codegen.check import check_generated

    path = tmp_path / "spring.yaml"
    path.write_text("name: spring\ngravity: [0, 0, -9.81]\nbodies:\n  - name: a\n    pair:\n"
                    "      functional: {o3: z, theta4: r}\n      stiffness: [[100, 1], [1, 5]]\n"
                    "      rest: [-0.1, 0]\n    mass: 2.0\n    com: [0, 0.1, 0]\n"
                    "    inertia: {xx: 0.1, yy: 0.1, zz: 0.1}\n")
    model = aggsym.load(path)
    assert fast_slow(model) == ([], [0, 1])
    gen = generate(model, targets="c,numpy,manifest")
    m = json.loads(gen.files["spring.json"])
    assert m["layouts"]["elastic_partition"]["blocks"]["A_pp"]["shape"] == [0, 0]
    assert "(void)A_pp;" in gen.files["spring.c"]
    for r in check_generated(model, gen.files, trials=3, seed=2, workdir=tmp_path):
        assert r.c_error <= 1e-12 and r.py_error <= 1e-12, r
