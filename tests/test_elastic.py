"""Hooke elasticity (1.4, 2.3): A q'' + b + g + C q = tau (2.27).

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
"""
import json

import numpy as np
import pytest
import sympy as sp

import aggsym
from aggsym.backend import Symbolic, bind
from aggsym.codegen.generate import generate
from aggsym.equations import coordinate_symbols, to_sympy
from aggsym.errors import ModelError
from aggsym.kinematics import TreeKinematics
from aggsym.routines import ROUTINES
from conftest import model_path
from test_book_closed_forms import assert_equal, sym

ELASTIC = "double_pendulum_elastic_stand"


def routine_sympy(model, role):
    """The outputs of a routine as SymPy expressions in the symbols of aggsym.equations."""
    routine = ROUTINES[role]
    back = Symbolic()
    prog = back.program
    bound = bind(model, back)
    ins = {n: prog.vector(n, model.nq) for n in routine.inputs if n != "p"}
    outs = routine.build(bound, TreeKinematics(bound, ins["q"]), ins)
    q, qd, _ = coordinate_symbols(model)
    symbols = {("p", i): s for i, s in enumerate(model.parameter_symbols)}
    symbols.update({("q", i): s for i, s in enumerate(q)})
    symbols.update({("qd", i): s for i, s in enumerate(qd)})
    return [to_sympy(prog, out, symbols) for out in outs]


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


def test_manifest_of_an_elastic_model():
    model = aggsym.load(model_path(ELASTIC))
    m = json.loads(generate(model, latex=False).files[f"{ELASTIC}.json"])
    assert m["conservative"] is True
    assert m["functions"]["elastic"] == f"{ELASTIC}_elastic"
    assert m["signatures"]["elastic"] == {"inputs": ["q", "p"], "outputs": [{"name": "c", "shape": [3]}]}
    assert m["elastic"]["pairs"] == [{"joint": "stand", "coordinates": ["delta12", "delta15"],
                                      "stiffness": [["k22", "k25"], ["k25", "k55"]], "rest": ["0", "0"]}]
    rigid = json.loads(generate(aggsym.load(model_path("double_pendulum")), latex=False).files[
        "double_pendulum.json"])
    assert "elastic" not in rigid["functions"]


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
    with pytest.raises(ModelError) as info:
        aggsym.load(path)
    err = info.value
    assert err.where == where, str(err)
    assert err.line is not None and str(err).startswith(f"{path}:{err.line}:")
    for w in words:
        assert w in str(err), str(err)

