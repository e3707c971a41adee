"""The body's dynamic aggregate: Mises matrices (2.3), their motion (2.7), and general symmetric 6x6 blocks.

Two representations of a symmetric 6x6 matrix acting on quasi-velocities V = (v, w):

* :class:`Rigid` is the Mises matrix of a rigid body or of a composite of rigid bodies (2.3), (2.32):
  ``[[m E, -hat(h)], [hat(h), theta]]`` with h = m r_c and theta the inertia tensor about the origin.  Moving
  it keeps this form, so ``m E`` never turns into ``m c c^T``.
* :class:`General` is any symmetric 6x6 matrix ``[[X11, X12], [X12^T, X22]]``: added masses (2.8) and the
  articulated blocks of chapter 3 (3.7) are of this kind.

Both implement ``apply(V)`` (the kinetic binary vector ``Theta V`` (2.5)), the congruence ``L Theta L^T`` (2.7)
(``moved(L)``, and its cheap factors: ``rotated`` by an elementary rotation within its plane, ``translated``
by T(o)) and addition.  This is the one place symmetric 6x6 congruences are written.
"""
from __future__ import annotations

from ..core.program import is_zero
from .group import phi_force
from .linalg import add, congruence3, cross, dot, hat, is_identity, madd, mm, mmt, mscale, mtv, mul, mv, scale, \
    transpose


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

    def rotated(self, axis, c, s, s2, sc, c2=None) -> "Rigid":
        """C Theta C^T (2.7) for the elementary rotation C = diag(c_axis, c_axis) (Prop. 1.17), with cos c, sin s,
        s2 = sin^2 and sc = sin cos of its angle.

        The first moment and the entries joining the axis to its plane turn as 2-vectors; in the plane (i, j)
        the symmetric block [[A, B], [B, D]] becomes [[A - d, B - e], [B - e, D + d]] with
        d = (A - D) s2 + 2B sc and e = 2B s2 - (A - D) sc (a rotation by the double angle): 4 products where
        the full congruence takes 12.  With ``c2`` = cos^2 given (a constant rotation) and smaller than s2, the
        diagonal is ``D + d'`` and ``A - d'`` with d' = (A - D) c2 - 2B sc instead, the same products: near a right
        angle A - (A - D) s2 loses the digits of a small D beside a large A (a point mass near the axis it is
        turned onto), where D + (A - D) c2 keeps them."""
        a = axis - 1
        i, j = (a + 1) % 3, (a + 2) % 3
        h = list(self.h)
        h[i], h[j] = mul(c, self.h[i]) - mul(s, self.h[j]), mul(s, self.h[i]) + mul(c, self.h[j])
        th = [list(r) for r in self.theta]
        x, y = self.theta[a][i], self.theta[a][j]
        th[a][i] = th[i][a] = mul(c, x) - mul(s, y)
        th[a][j] = th[j][a] = mul(s, x) + mul(c, y)
        A, B, D = self.theta[i][i], self.theta[i][j], self.theta[j][j]
        amd, b2 = A - D, B + B
        if c2 is None or not c2 < s2:
            d = mul(amd, s2) + mul(b2, sc)
            e = mul(b2, s2) - mul(amd, sc)
            th[i][i], th[j][j] = A - d, D + d
        else:
            d = mul(amd, c2) - mul(b2, sc)
            e = mul(b2, s2) - mul(amd, sc)
            th[i][i], th[j][j] = D + d, A - d
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
        # the parallel-axis terms of theta' = theta + 2 (h.o) E - h o^T - o h^T + m (o.o E - o o^T), the diagonal
        # as sum over k != i of (2 h_k o_k + m o_k^2): no term of size |o|^2 cancels another (a point mass moved
        # along an axis keeps its digits about that axis)
        along = [mul(hr[k], o[k]) for k in range(3)]
        parts = [along[k] + along[k] + mul(m, mul(o[k], o[k])) for k in range(3)]
        out = [[0] * 3 for _ in range(3)]
        for i in range(3):
            for j in range(i, 3):
                if i == j:
                    x = th[i][i] + (parts[(i + 1) % 3] + parts[(i + 2) % 3])
                else:
                    x = th[i][j] - mul(hr[i], o[j]) - mul(o[i], hr[j]) - mul(m, mul(o[i], o[j]))
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
        """L X L^T (2.7) for any symmetric X and L = T(o) C(c): the rotation's congruence block by block, then
        :meth:`translated`."""
        c, o = L.c, L.o
        X = self
        if not is_identity(c):
            X = General(congruence3(c, self.x11), mmt(mm(c, self.x12), c), congruence3(c, self.x22))
        return X if all(is_zero(x) for x in o) else X.translated(o)

    def translated(self, o) -> "General":
        """T(o) X T(o)^T (2.7), T(o) = [[E, 0], [hat(o), E]] (1.13): X11 stays, ``Z12 = X12 - X11 hat(o)`` and,
        reusing it, ``Z22 = X22 + (hat(o) X12)^T + hat(o) Z12`` (= X22 + W + W^T - hat(o) X11 hat(o) with
        W = hat(o) X12), upper triangle only; products with structural zeros of o skipped."""
        oh = hat(o)
        x11, x12, x22 = self.x11, self.x12, self.x22
        z12 = tuple(tuple(x12[i][j] - dot([x11[i][k] for k in range(3)], [oh[k][j] for k in range(3)])
                          for j in range(3)) for i in range(3))
        z22 = [[0] * 3 for _ in range(3)]
        for i in range(3):
            for j in range(i, 3):
                w_ji = dot(oh[j], [x12[k][i] for k in range(3)])
                oz_ij = dot(oh[i], [z12[k][j] for k in range(3)])
                z22[i][j] = z22[j][i] = x22[i][j] + w_ji + oz_ij
        return General(x11, z12, tuple(tuple(r) for r in z22))

    def rotated(self, axis, c, s, s2, sc, c2=None) -> "General":
        """R X R^T for R = diag(c_axis, c_axis), the elementary rotation (Prop. 1.17) of both 3-blocks, with cos c,
        sin s, s2 = sin^2 and sc = sin cos of its angle.

        In the plane (i, j) of the rotation a 2x2 block B = [[a, b], [e, d]] becomes
        ``[[a - delta, b - gamma], [e - gamma, d + delta]]`` with ``delta = (a - d) s2 + (b + e) sc`` and
        ``gamma = (b + e) s2 - (a - d) sc`` (its antisymmetric part is invariant): 4 products where R B R^T takes
        16.  The entries joining the axis itself to the plane turn as 2-vectors.  ``c2`` = cos^2 (a constant
        rotation) below s2: the diagonal entries as ``d + delta'`` and ``a - delta'``, delta' = (a - d) c2 -
        (b + e) sc (see :meth:`Rigid.rotated`)."""
        a = axis - 1
        i, j = (a + 1) % 3, (a + 2) % 3
        planes = ((i, j), (3 + i, 3 + j))
        M = self.matrix()
        out = [list(row) for row in M]
        for f in (a, 3 + a):
            for p, q in planes:
                x, y = M[f][p], M[f][q]
                out[f][p] = out[p][f] = mul(c, x) - mul(s, y)
                out[f][q] = out[q][f] = mul(s, x) + mul(c, y)
        for (p0, p1), (q0, q1) in ((planes[0], planes[0]), (planes[1], planes[1]), (planes[0], planes[1])):
            ba, bb, be, bd = M[p0][q0], M[p0][q1], M[p1][q0], M[p1][q1]
            amd, bpe = ba - bd, bb + be
            if c2 is None or not c2 < s2:
                delta = mul(amd, s2) + mul(bpe, sc)
                gamma = mul(bpe, s2) - mul(amd, sc)
                out[p0][q0] = out[q0][p0] = ba - delta
                out[p1][q1] = out[q1][p1] = bd + delta
            else:
                delta = mul(amd, c2) - mul(bpe, sc)
                gamma = mul(bpe, s2) - mul(amd, sc)
                out[p0][q0] = out[q0][p0] = bd + delta
                out[p1][q1] = out[q1][p1] = ba - delta
            out[p0][q1] = out[q1][p0] = bb - gamma
            out[p1][q0] = out[q0][p1] = be - gamma
        return General.from_rows(out)

    def __add__(self, other):
        if other is None:
            return self
        if isinstance(other, Rigid):
            other = other.general()
        return General(madd(self.x11, other.x11), madd(self.x12, other.x12), madd(self.x22, other.x22))

    __radd__ = __add__

    def general(self) -> "General":
        return self

    def matrix(self):
        """The 6x6 as a list of rows."""
        top = [list(self.x11[i]) + list(self.x12[i]) for i in range(3)]
        x21 = transpose(self.x12)
        bottom = [list(x21[i]) + list(self.x22[i]) for i in range(3)]
        return top + bottom

    @staticmethod
    def from_rows(M) -> "General":
        """The General of a symmetric 6x6 given as 6 rows."""
        return General(tuple(tuple(M[i][j] for j in range(3)) for i in range(3)),
                       tuple(tuple(M[i][j] for j in range(3, 6)) for i in range(3)),
                       tuple(tuple(M[i][j] for j in range(3, 6)) for i in range(3, 6)))

