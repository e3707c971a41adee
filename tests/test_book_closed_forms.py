"""The seeds' closed forms: the double pendulum (2.23)-(2.26) and Tokad's Tables 1 and 2, symbolically."""
import pytest
import sympy as sp

import aggsym
from conftest import model_path


def sym(*names):
    return sp.symbols(names, real=True)


def assert_equal(actual, expected):
    diff = sp.simplify(sp.expand(sp.Matrix(actual) - sp.Matrix(expected)))
    assert diff == sp.zeros(*diff.shape), diff


def book_double_pendulum(q1, q2, q3, v1, v2, v3, p31):
    """A (2.23) and b (2.25) of the book.  alpha of (2.24) is printed without a factor sin(theta36) in its first
    term; the book's own rows a^{2-5}_3 = (0, 0, -m3(p31 + r31 c), I344 s, (I355 + m3 r31^2) c + m3 p31 r31, 0)
    and s'^{2-5}_3 = (0, c, -s, 0) theta36' give alpha = (I344 - I355) s c - m3 (p31 + r31 c) r31 s, which is also
    1/2 dA22/dtheta36 as it must be."""
    m2, m3, r21, r31, I255, I344, I355, I366 = sym("m2", "m3", "r21", "r31", "I255", "I344", "I355", "I366")
    c, s = sp.cos(q3), sp.sin(q3)
    A = sp.Matrix([
        [m2 + m3, 0, m3 * r31 * c],
        [0, I255 + m2 * r21**2 + m3 * (p31 + r31 * c) ** 2 + I344 * s**2 + I355 * c**2, 0],
        [m3 * r31 * c, 0, I366 + m3 * r31**2],
    ])
    alpha = (I344 - I355) * s * c - m3 * (p31 + r31 * c) * r31 * s
    beta = -m3 * r31 * s
    b = sp.Matrix([beta * v3**2, 2 * alpha * v2 * v3, -alpha * v2**2])
    return A, b


@pytest.mark.parametrize("variant", ["double_pendulum", "double_pendulum_variant2"])
def test_double_pendulum_matches_book(variant):
    eq = aggsym.equations(aggsym.load(model_path(variant)))
    q1, q2, q3 = eq.q
    v1, v2, v3 = eq.qd
    p31 = sym("p31" if variant == "double_pendulum" else "p21")[0]
    A, b = book_double_pendulum(q1, q2, q3, v1, v2, v3, p31)
    assert_equal(eq.A, A)
    assert_equal(eq.b, b)


def test_double_pendulum_closed_form_on_request():
    """simplify=True gives (2.23) entry by entry, with m2 + m3 (not m2 + m3 sin^2 + m3 cos^2) in the corner."""
    eq = aggsym.equations(aggsym.load(model_path("double_pendulum")), simplify=True)
    m2, m3 = sym("m2", "m3")
    assert eq.A[0, 0] == m2 + m3
    assert eq.A[0, 1] == 0 and eq.A[1, 2] == 0


def tokad_table1():
    """Tokad (1993) Table 1, planar three-link arm: c_pq, d_pq and beta_p.

    Read from the extracted table; two printed entries are corrected: d32 is printed -m3 (l2 l3/2) C3 (w1 + w2),
    which breaks the symmetry with d31 and the identity sum_q d_pq w_q = b_p; it is +m3 (l2 l3/2) S3 (w1 + w2).
    """
    m1, m2, m3, l1, l2, l3, g = sym("m1", "m2", "m3", "l1", "l2", "l3", "g")
    t1, t2, t3 = sym("theta1", "theta2", "theta3")
    w1, w2, w3 = sym("theta1_d", "theta2_d", "theta3_d")
    C1, C2, C3 = sp.cos(t1), sp.cos(t2), sp.cos(t3)
    S2, S3 = sp.sin(t2), sp.sin(t3)
    C12, C123, C23, S23 = sp.cos(t1 + t2), sp.cos(t1 + t2 + t3), sp.cos(t2 + t3), sp.sin(t2 + t3)
    h = sp.Rational(1, 2)
    c11 = (m1 * l1**2 / 3 + m2 * (l1**2 + l1 * l2 * C2 + l2**2 / 3)
           + m3 * (l1**2 + l2**2 + l3**2 / 3 + 2 * l1 * l2 * C2 + l2 * l3 * C3 + l1 * l3 * C23))
    c12 = m2 * (l2**2 / 3 + h * l1 * l2 * C2) + m3 * (l2**2 + l3**2 / 3 + l2 * l3 * C3 + l1 * l2 * C2 + h * l1 * l3 * C23)
    c13 = m3 * (l3**2 / 3 + h * l2 * l3 * C3 + h * l1 * l3 * C23)
    c22 = m2 * l2**2 / 3 + m3 * (l2**2 + l3**2 / 3 + l2 * l3 * C3)
    c23 = m3 * (l3**2 / 3 + h * l2 * l3 * C3)
    c33 = m3 * l3**2 / 3
    d11 = -m2 * h * l1 * l2 * S2 * w2 - m3 * (l1 * l2 * S2 * w2 + h * l2 * l3 * S3 * w3 + h * l1 * l3 * S23 * (w2 + w3))
    d12 = (-m2 * h * l1 * l2 * S2 * (w1 + w2) - m3 * h * l2 * l3 * S3 * w3
           - m3 * (l1 * l2 * S2 * (w1 + w2) + h * l1 * l3 * S23 * (w1 + w2 + w3)))
    d13 = -m3 * (h * l2 * l3 * S3 + h * l1 * l3 * S23) * (w1 + w2 + w3)
    d21 = m2 * h * l1 * l2 * S2 * w1 + m3 * (l1 * l2 * S2 + h * l1 * l3 * S23) * w1 - m3 * h * l2 * l3 * S3 * w3
    d22 = -m3 * h * l2 * l3 * S3 * w3
    d23 = -m3 * h * l2 * l3 * S3 * (w1 + w2 + w3)
    d31 = m3 * (h * l1 * l3 * S23 * w1 + h * l2 * l3 * S3 * (w1 + w2))
    d32 = m3 * h * l2 * l3 * S3 * (w1 + w2)
    d33 = 0
    beta1 = g * (m1 * h * l1 * C1 + m2 * (l1 * C1 + h * l2 * C12) + m3 * (l1 * C1 + l2 * C12 + h * l3 * C123))
    beta2 = g * (m2 * h * l2 * C12 + m3 * (l2 * C12 + h * l3 * C123))
    beta3 = g * m3 * h * l3 * C123
    C = sp.Matrix([[c11, c12, c13], [c12, c22, c23], [c13, c23, c33]])
    D = sp.Matrix([[d11, d12, d13], [d21, d22, d23], [d31, d32, d33]])
    return C, D, sp.Matrix([beta1, beta2, beta3]), sp.Matrix([w1, w2, w3]), m3


def test_planar_three_link_matches_tokad_table1():
    eq = aggsym.equations(aggsym.load(model_path("planar_3link")))
    C, D, beta, w, _ = tokad_table1()
    assert_equal(eq.A, C)
    assert_equal(eq.b, D * w)
    assert_equal(eq.g, beta)


def test_planar_two_link_matches_tokad_table2():
    """Table 2 is Table 1 with m3 = 0, restricted to the first two joints."""
    eq = aggsym.equations(aggsym.load(model_path("planar_2link")))
    C, D, beta, w, m3 = tokad_table1()
    sub = {m3: 0}
    C2 = C[:2, :2].subs(sub)
    D2 = D[:2, :2].subs(sub)
    assert_equal(eq.A, C2)
    assert_equal(eq.b, D2 * w[:2, :])
    assert_equal(eq.g, beta[:2, :].subs(sub))
