"""Tree indexing of a model: parents before children, the sets (lk)+ and (lk)- of Def. 1.7.

Bodies are numbered 0..N-1 in the model's order (parents first); ``parent[k] == -1`` means the inertial frame
E_10.  Coordinates are numbered in the same order, pair by pair, each pair's in the order of its mobility axes
f_1..f_6 (1.40).  ``nv`` counts them (the length of qd, qdd, tau on the tree); the entries of q are the same
except for a free-flyer pair, which has seven positions for its six coordinates, and a ball pair, which has four
(a unit quaternion) for its three (``positions``, ``nq``).
"""
from __future__ import annotations

from functools import cached_property

from .types import Model


class Tree:
    """The flat, parent-before-child form of a model's graph (:meth:`of`: a model's own, built once)."""

    @classmethod
    def of(cls, model: Model) -> "Tree":
        """The tree of ``model``, built on first use and kept on the model (which is immutable), so that the
        readers of one generation share one."""
        tree = model.__dict__.get("_tree")
        if tree is None or tree.model is not model:
            tree = cls(model)
            object.__setattr__(model, "_tree", tree)
        return tree

    def __init__(self, model: Model):
        self.model = model
        self.names = [b.name for b in model.bodies]
        index = {name: k for k, name in enumerate(self.names)}
        self.parent = [index.get(b.parent, -1) for b in model.bodies]
        for k, p in enumerate(self.parent):
            if p >= k:
                raise ValueError(f"body {self.names[k]!r} is listed before its parent")
        self.children = [[] for _ in self.names]
        for k, p in enumerate(self.parent):
            if p >= 0:
                self.children[p].append(k)
        self.coords = []  # per body: list of coordinate indices of its pair
        self.positions = []  # per body: the indices of its pair's entries of q
        i = j = 0
        for k, b in enumerate(model.bodies):
            n = len(b.pair.coordinates)
            m = len(b.pair.positions) if b.pair.quaternion else n
            if b.pair.free_flyer and self.parent[k] >= 0:
                raise ValueError(f"body {self.names[k]!r}: a free-flyer pair joins a root of the tree to the world")
            self.coords.append(list(range(i, i + n)))
            self.positions.append(list(range(j, j + m)))
            i += n
            j += m
        self.nv = i
        self.nq = j
        self.body_of = [k for k, cs in enumerate(self.coords) for _ in cs]  # coordinate -> body

    def __len__(self) -> int:
        return len(self.names)

    def ancestors(self, k: int) -> list[int]:
        """The chain (lk)- of counter accessibility from the root to k, k included."""
        chain = []
        while k >= 0:
            chain.append(k)
            k = self.parent[k]
        return chain[::-1]

    @cached_property
    def neutral(self) -> list:
        """q = 0, with a free-flyer's or a ball's quaternion the identity (qw = 1, its last entry): the
        configuration of zero coordinates."""
        q = [0] * self.nq
        for b, idx in zip(self.model.bodies, self.positions):
            if b.pair.quaternion:
                q[idx[-1]] = 1
        return q

    @cached_property
    def position_split(self) -> tuple:
        """(Q, V, T): the entries Q of q that are coordinates themselves (Q[i] is coordinate V[i]), and the entries T
        of the quaternion pairs (a free-flyer's origin and quaternion, a ball's quaternion), which are not."""
        Q, V, T = [], [], []
        for b, positions, coords in zip(self.model.bodies, self.positions, self.coords):
            if b.pair.quaternion:
                T += positions
            else:
                Q += positions
                V += coords
        return tuple(Q), tuple(V), tuple(T)

    @cached_property
    def subtrees(self) -> list[list[int]]:
        """(lk)+ for every body: k and all its descendants, in body order."""
        sub = [[k] for k in range(len(self))]
        for k in range(len(self) - 1, -1, -1):
            p = self.parent[k]
            if p >= 0:
                sub[p].extend(sub[k])
        return [sorted(s) for s in sub]

    @cached_property
    def moving(self) -> list[bool]:
        """Per body: whether it moves (a coordinate or a prescribed spin on its path from the root); the others are
        welded to the world."""
        out: list[bool] = []
        for k, (p, b) in enumerate(zip(self.parent, self.model.bodies)):
            out.append(bool(self.coords[k]) or bool(b.pair.prescribed) or (p >= 0 and out[p]))
        return out

    @cached_property
    def depth(self) -> list[int]:
        """Number of bodies on the path from the root to k, k included."""
        d = []
        for k, p in enumerate(self.parent):
            d.append(1 if p < 0 else d[p] + 1)
        return d
