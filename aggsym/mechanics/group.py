"""The motion group L(R,6) of binary vectors, (1.9)-(1.23).

A motion ``L^{st}_{lk} = T(o) C(c)`` (1.13)-(1.14) maps the coordinates of a binary vector (a wrench
F = (f, mu), or a twist written force-like) given in frame lk to frame st:

* ``c`` is the 3x3 rotation whose columns are the axes of lk in st (1.12),
* ``o`` is the origin of lk in st, in st's basis (notation 1.3), ``T(o) = [[E, 0], [hat(o), E]]``.

Quasi-velocities V = (v, w) (Def. 1.9, translation first) go the other way with the transpose,
``V_lk = L^T V_st`` (1.28).  Six-vectors are 6-tuples, translation (or force) part first.
"""
from __future__ import annotations

from .linalg import EYE3, ZERO3, add, cross, mm, mtv, mv

__all__ = ["Motion", "Chain", "rotation", "phi_motion", "phi_force"]


def rotation(axis: int, cos, sin):
    """The elementary rotation c_axis(phi) about e_axis (axis 1, 2 or 3), given cos(phi) and sin(phi).

    ``c_i(phi) = E + hat(e_i) sin(phi) + hat(e_i)^2 (1 - cos(phi))`` (Prop. 1.17); it maps coordinates in the
    rotated basis to the fixed one.
    """
    if axis == 1:
        return ((1, 0, 0), (0, cos, -sin), (0, sin, cos))
    if axis == 2:
        return ((cos, 0, sin), (0, 1, 0), (-sin, 0, cos))
    if axis == 3:
        return ((cos, -sin, 0), (sin, cos, 0), (0, 0, 1))
    raise ValueError(f"axis must be 1, 2 or 3, not {axis!r}")


class Motion:
    """L = T(o) C(c) in L(R,6) (1.13)-(1.15): child (moving) frame to parent frame."""

    __slots__ = ("c", "o")

    def __init__(self, c=EYE3, o=ZERO3):
        self.c = c
        self.o = o

    def compose(self, other: "Motion") -> "Motion":
        """L1 L2 = T(o1 + c1 o2) C(c1 c2) (proof of Prop. 1.8)."""
        return Motion(mm(self.c, other.c), add(self.o, mv(self.c, other.o)))

    def wrench(self, F):
        """L F: a wrench (f, mu) about the child origin in child axes, to the parent (1.13)."""
        f = mv(self.c, F[:3])
        mu = add(cross(self.o, f), mv(self.c, F[3:]))
        return f + mu

    def twist(self, V):
        """L^T V: a quasi-velocity (v, w) of the parent origin in parent axes, to the child (1.28)."""
        w = V[3:]
        v = add(V[:3], cross(w, self.o))
        return mtv(self.c, v) + mtv(self.c, w)

    def motion(self, V):
        """L V: a quasi-velocity (v, w) of the child origin in child axes, as the parent origin's in parent axes
        (``w' = c w``, ``v' = c v + o x w'``); the inverse of :meth:`twist`, and it pairs with :meth:`wrench`:
        ``motion(V) . wrench(F) = V . F``.  With a body's world pose, the motion of the world origin in world axes."""
        w = mv(self.c, V[3:])
        return add(mv(self.c, V[:3]), cross(self.o, w)) + w

    def rotate_free(self, x):
        """c x for a free vector (no translation part)."""
        return mv(self.c, x)

    def unrotate_free(self, x):
        """c^T x."""
        return mtv(self.c, x)


class Chain(Motion):
    """A motion whose rotation is kept as the product of its factors, ``c = c_1 c_2 ... c_r`` (1.17): vectors are
    turned by one factor after the other.  An elementary rotation turns a vector in one plane (4 products, 2 sums);
    when a constant one is not a right angle (xarm7's 1.5708 about x) the product c_1(alpha) c_3(q) is a full
    rotation with 7 non-zero entries, whose entries cost 4 products once and every vector 8 products and 5 sums,
    against 8 and 4 one factor at a time.  Same values; ``c`` itself stays for :meth:`compose`."""

    __slots__ = ("factors",)

    def __init__(self, c, o, factors):
        super().__init__(c, o)
        self.factors = tuple(factors)

    def rotate_free(self, x):
        for f in reversed(self.factors):
            x = mv(f, x)
        return x

    def unrotate_free(self, x):
        for f in self.factors:
            x = mtv(f, x)
        return x

    def wrench(self, F):
        f = self.rotate_free(F[:3])
        return f + add(cross(self.o, f), self.rotate_free(F[3:]))

    def twist(self, V):
        w = V[3:]
        return self.unrotate_free(add(V[:3], cross(w, self.o))) + self.unrotate_free(w)

    def motion(self, V):
        w = self.rotate_free(V[3:])
        return add(self.rotate_free(V[:3]), cross(self.o, w)) + w



def phi_motion(V, U):
    """Phi(V)-action on a quasi-velocity U in (v, w) order: (w x u + v x eta, w x eta).

    This is the matrix of quasi-velocities (1.22), transposed into the quasi-velocity ordering, as it appears in
    the forward sweep (2.40): ``Phi^{rel,T} L^T V = phi_motion(L^T V, V_rel)``.
    """
    v, w = V[:3], V[3:]
    u, eta = U[:3], U[3:]
    return add(cross(w, u), cross(v, eta)) + cross(w, eta)


def phi_force(V, F):
    """Phi(V) F for a wrench or kinetic binary vector F = (f, mu) (1.22): (w x f, v x f + w x mu).

    In (2.10) this gives the gyroscopic term ``Phi Theta V`` of a body with quasi-velocity V.
    """
    v, w = V[:3], V[3:]
    f, mu = F[:3], F[3:]
    return cross(w, f) + add(cross(v, f), cross(w, mu))
