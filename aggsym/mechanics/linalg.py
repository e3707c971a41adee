"""Zero-aware 3-vector and 3x3 arithmetic shared by the symbolic and the numeric runs.

Vectors are tuples of three scalars, matrices tuples of three row tuples.  A scalar is a Python number, a
float or NumPy array (numeric twin) or a :class:`~aggsym.core.program.Node` (straight-line program).
Products with an exact structural zero are skipped (:func:`mul`, the one zero-skipping product every
recursion uses), which is where the economy of the book's section 5 rules (P, sec. 5) comes from: an
elementary rotation touches two rows, a translation along one axis one column.
"""
from __future__ import annotations

from ..core.program import _EXACT, is_one, is_zero  # (_EXACT: the Python constants is_zero tests)

ZERO3 = (0, 0, 0)
EYE3 = ((1, 0, 0), (0, 1, 0), (0, 0, 1))


def mul(a, b):
    """a b, or the structural zero when either factor is one."""
    # (is_zero written out: this runs for every product of the recursions)
    if (a.__class__ in _EXACT and a == 0) or (b.__class__ in _EXACT and b == 0):
        return 0
    return a * b


def dot(a, b):
    """Sum of products over two equal-length sequences, skipping structural zeros."""
    acc = 0
    for x, y in zip(a, b):
        if (x.__class__ in _EXACT and x == 0) or (y.__class__ in _EXACT and y == 0):
            continue
        acc = acc + x * y
    return acc


def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def neg(a):
    return tuple(-x for x in a)


def scale(s, a):
    """s a, products with structural zeros skipped."""
    return tuple(mul(s, x) for x in a)


def cross(a, b):
    """a x b."""
    return (
        mul(a[1], b[2]) - mul(a[2], b[1]),
        mul(a[2], b[0]) - mul(a[0], b[2]),
        mul(a[0], b[1]) - mul(a[1], b[0]),
    )


def hat(x):
    """The skew-symmetric matrix of x (1.9): hat(x) y = x cross y."""
    return ((0, -x[2], x[1]), (x[2], 0, -x[0]), (-x[1], x[0], 0))


def mv(m, v):
    """m v."""
    return tuple(dot(row, v) for row in m)


def mtv(m, v):
    """m^T v."""
    return tuple(dot((m[0][j], m[1][j], m[2][j]), v) for j in range(3))


def transpose(m):
    return tuple(tuple(m[i][j] for i in range(3)) for j in range(3))


def mm(a, b):
    """a b."""
    bt = transpose(b)
    return tuple(tuple(dot(row, col) for col in bt) for row in a)


def mmt(a, b):
    """a b^T."""
    return tuple(tuple(dot(row, col) for col in b) for row in a)


def madd(a, b):
    return tuple(add(r, s) for r, s in zip(a, b))


def mscale(s, a):
    return tuple(scale(s, r) for r in a)


def congruence3(c, m):
    """c m c^T for a symmetric m, computing the upper triangle once."""
    cm = mm(c, m)
    out = [[0] * 3 for _ in range(3)]
    for i in range(3):
        for j in range(i, 3):
            out[i][j] = dot(cm[i], c[j])
            out[j][i] = out[i][j]
    return tuple(tuple(r) for r in out)


def is_identity(c) -> bool:
    """c is structurally the 3x3 identity."""
    return all(is_one(c[i][j]) if i == j else is_zero(c[i][j]) for i in range(3) for j in range(3))


def ldl_factor(G) -> tuple:
    """(L, d) with G = L diag(d) L^T for a small symmetric m x m G (lists of rows), L unit lower triangular, no
    pivoting: the factorization both the exact and the damped constraint solves run on."""
    m = len(G)
    L = [[0] * m for _ in range(m)]
    d = [0] * m
    for j in range(m):
        acc = G[j][j]
        for k in range(j):
            acc = acc - mul(mul(L[j][k], L[j][k]), d[k])
        d[j] = acc
        inv = 1 / acc
        for i in range(j + 1, m):
            acc = G[i][j]
            for k in range(j):
                acc = acc - mul(mul(L[i][k], L[j][k]), d[k])
            L[i][j] = mul(acc, inv)
    return L, d
