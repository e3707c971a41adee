"""The body's dynamic aggregate: Mises matrices (2.3), their motion (2.7), and general symmetric 6x6 blocks.

Two representations of a symmetric 6x6 matrix acting on quasi-velocities V = (v, w):

* :class:`Rigid` is the Mises matrix of a rigid body or of a composite of rigid bodies (2.3), (2.32):
  ``[[m E, -hat(h)], [hat(h), theta]]`` with h = m r_c and theta the inertia tensor about the origin.  Moving
  it keeps this form, so ``m E`` never turns into ``m c c^T``.
* :class:`General` is any symmetric 6x6 matrix ``[[X11, X12], [X12^T, X22]]``: added masses (2.8) and the
  articulated blocks of chapter 3 (3.7) are of this kind.

Both implement ``apply(V)`` (the kinetic binary vector ``Theta V`` (2.5)), ``moved(L)`` (``L Theta L^T`` (2.7))
and addition.
"""
from __future__ import annotations

from .codegen.program import is_zero
from .group import phi_force
from .linalg import (
    add, congruence3, cross, dot, hat, madd, mm, mmt, msub, mscale, mtv, mv, outer, scale, transpose,
)


class Rigid:
    """Mises matrix (2.3) [[m E, -hat(h)], [hat(h), theta]] at a frame origin."""

    __slots__ = ("m", "h", "theta")

    def __init__(self, m, h, theta):
        self.m = m
        self.h = h
        self.theta = theta

    def apply(self, V):
        """Theta V = (m v + w x h, h x v + theta w) (2.5)."""
        v, w = V[:3], V[3:]
        return add(scale(self.m, v), cross(w, self.h)) + add(cross(self.h, v), mv(self.theta, w))

    def dynamic_wrench(self, A, V):
        """Theta A + Phi(V) Theta V: the left side of (2.10) for quasi-acceleration A and quasi-velocity V.

        With the classical acceleration a = A_v + w x v of the origin, and v x (m v) = 0 and the Jacobi
        identity v x (w x h) + w x (h x v) = h x (w x v):
        ``(m a + A_w x h + w x (w x h),  h x a + theta A_w + w x (theta w))``.
        """
        v, w = V[:3], V[3:]
        a = add(A[:3], cross(w, v))
        aw = A[3:]
        f = add(add(scale(self.m, a), cross(aw, self.h)), cross(w, cross(w, self.h)))
        mu = add(add(cross(self.h, a), mv(self.theta, aw)), cross(w, mv(self.theta, w)))
        return f + mu

    def rotated(self, axis, c, s, s2, sc) -> "Rigid":
        """C Theta C^T (2.7) for the elementary rotation C = diag(c_axis, c_axis) (Prop. 1.17), with cos c, sin s,
        s2 = sin^2 and sc = sin cos of its angle.

        The first moment and the entries joining the axis to its plane turn as 2-vectors; in the plane (i, j)
        the symmetric block [[A, B], [B, D]] becomes [[A - d, B - e], [B - e, D + d]] with
        d = (A - D) s2 + 2B sc and e = 2B s2 - (A - D) sc (a rotation by the double angle): 4 products where
        the full congruence takes 12."""
        a = axis - 1
        i, j = (a + 1) % 3, (a + 2) % 3
        h = list(self.h)
        h[i], h[j] = _mul(c, self.h[i]) - _mul(s, self.h[j]), _mul(s, self.h[i]) + _mul(c, self.h[j])
        th = [list(r) for r in self.theta]
        x, y = self.theta[a][i], self.theta[a][j]
        th[a][i] = th[i][a] = _mul(c, x) - _mul(s, y)
        th[a][j] = th[j][a] = _mul(s, x) + _mul(c, y)
        A, B, D = self.theta[i][i], self.theta[i][j], self.theta[j][j]
        amd, b2 = A - D, B + B
        d = _mul(amd, s2) + _mul(b2, sc)
        e = _mul(b2, s2) - _mul(amd, sc)
        th[i][i], th[j][j] = A - d, D + d
        th[i][j] = th[j][i] = B - e
        return Rigid(self.m, tuple(h), tuple(tuple(r) for r in th))

    def moved(self, L) -> "Rigid":
        """L Theta L^T (2.7) for L = T(o) C(c): the same body seen from the parent frame."""
        c, o, m = L.c, L.o, self.m
        hr = mv(c, self.h)
        th = congruence3(c, self.theta)
        if all(is_zero(x) for x in o):
            return Rigid(m, hr, th)
        h = add(hr, scale(m, o))
        ho = dot(hr, o)
        oo = dot(o, o)
        diag = 2 * ho + _mul(m, oo)
        out = [[0] * 3 for _ in range(3)]
        for i in range(3):
            for j in range(i, 3):
                x = th[i][j] - _mul(hr[i], o[j]) - _mul(o[i], hr[j]) - _mul(m, _mul(o[i], o[j]))
                if i == j:
                    x = x + diag
                out[i][j] = out[j][i] = x
        return Rigid(m, h, tuple(tuple(r) for r in out))

    def __add__(self, other):
        if other is None:
            return self
        if isinstance(other, Rigid):
            return Rigid(self.m + other.m, add(self.h, other.h), madd(self.theta, other.theta))
        return self.general() + other

    __radd__ = __add__

    def general(self) -> "General":
        m = self.m
        return General(((m, 0, 0), (0, m, 0), (0, 0, m)), mscale(-1, hat(self.h)), self.theta)

    def matrix(self):
        return self.general().matrix()


class General:
    """A symmetric 6x6 matrix [[X11, X12], [X12^T, X22]] acting on (v, w)."""

    __slots__ = ("x11", "x12", "x22")

    def __init__(self, x11, x12, x22):
        self.x11 = x11
        self.x12 = x12
        self.x22 = x22

    def apply(self, V):
        v, w = V[:3], V[3:]
        return add(mv(self.x11, v), mv(self.x12, w)) + add(mtv(self.x12, v), mv(self.x22, w))

    def dynamic_wrench(self, A, V):
        """Theta A + Phi(V) Theta V (2.10), (2.13)."""
        return add(self.apply(A), phi_force(V, self.apply(V)))

    def moved(self, L) -> "General":
        """L X L^T (2.7) for any symmetric X: rotate the blocks, then translate by T(o)."""
        c, o = L.c, L.o
        y11 = congruence3(c, self.x11)
        y12 = mmt(mm(c, self.x12), c)
        y22 = congruence3(c, self.x22)
        if all(is_zero(x) for x in o):
            return General(y11, y12, y22)
        oh = hat(o)
        z12 = msub(y12, mm(y11, oh))
        w = mm(oh, y12)
        oyo = mm(mm(oh, y11), oh)
        z22 = [[0] * 3 for _ in range(3)]
        for i in range(3):
            for j in range(i, 3):
                z22[i][j] = z22[j][i] = y22[i][j] + w[i][j] + w[j][i] - oyo[i][j]
        return General(y11, z12, tuple(tuple(r) for r in z22))

    def __add__(self, other):
        if other is None:
            return self
        if isinstance(other, Rigid):
            other = other.general()
        return General(madd(self.x11, other.x11), madd(self.x12, other.x12), madd(self.x22, other.x22))

    __radd__ = __add__

    def minus_outer(self, u, s) -> "General":
        """X - s u u^T for a 6-vector u and a scalar s (the articulated correction of (3.7))."""
        su = scale(s, u)
        full = outer(u, su)
        x11 = tuple(tuple(self.x11[i][j] - full[i][j] for j in range(3)) for i in range(3))
        x12 = tuple(tuple(self.x12[i][j] - full[i][j + 3] for j in range(3)) for i in range(3))
        x22 = tuple(tuple(self.x22[i][j] - full[i + 3][j + 3] for j in range(3)) for i in range(3))
        return General(x11, x12, x22)

    def general(self) -> "General":
        return self

    def matrix(self):
        """The 6x6 as a list of rows."""
        top = [list(self.x11[i]) + list(self.x12[i]) for i in range(3)]
        x21 = transpose(self.x12)
        bottom = [list(x21[i]) + list(self.x22[i]) for i in range(3)]
        return top + bottom


def _mul(a, b):
    return 0 if is_zero(a) or is_zero(b) else a * b

