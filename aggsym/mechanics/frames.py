"""Frames for control: their poses, Jacobians and classical accelerations; the centre of mass, its Jacobian and the
centroidal momentum map.

A frame is fixed on body k: its origin r and its axes R_f (columns, in k's axes) (:class:`aggsym.model.Frame`).
With body k's world pose L_k = (R_k, o_k) (1.13), composed from the root (Prop. 1.8):

* pose: the origin ``o_k + R_k r`` and the rotation ``R_k R_f`` (frame axes to world axes);
* Jacobian: the velocity of the origin and the angular velocity, world axes, per unit rate of each coordinate:
  the columns of the parastrophic matrix S (1.42) moved to the point (:func:`~.kinematics.point_rows`), i.e.
  Pinocchio's LOCAL_WORLD_ALIGNED frame Jacobian;
* classical acceleration: ``R_k (a + alpha x r + w x (v + w x r))`` and ``R_k alpha`` from body k's quasi-velocity
  (v, w) (2.39) and quasi-acceleration (a, alpha) of the forward sweep (2.40) run without gravity; at qdd = 0 it is
  J' qd.

Mass properties are those of the bodies that move (a body welded to the world, with no coordinate on its path,
is left out, as Pinocchio's centerOfMass leaves out the universe's inertia), each body's own Theta_lk (2.3)
(no added mass, no armature): mass m_k, first moment h_k = m_k r_ck (k's axes), Theta about k's origin.  In world
quantities about the world origin, ``c_k = m_k o_k + R_k h_k`` and, summed over the subtree of body s (the bodies a
coordinate of s moves), M_s and C_s.  A unit rate of a coordinate of s with world column (v_i, w_i) moves the
subtree rigidly: the velocity of the point at the world origin is ``u = v_i - w_i x o_s``, so its linear momentum is
``p_i = M_s u + w_i x C_s`` (the column of the centre of mass Jacobian times the total mass M) and its angular
momentum about the world origin ``C_s x u + I_s w_i`` (I_s the subtree's rotational inertia about the world
origin, world axes).  The centroidal map (Pinocchio's computeCentroidalMap: h_G = A_G qd, linear momentum then
angular momentum about the centre of mass G, world axes) takes ``L_G = L_O - G x p``.
"""
from __future__ import annotations

from dataclasses import dataclass

from .bound import constant_axes
from .kinematics import ZERO6, moving_bodies, point_motion, point_rows, world_poses
from .linalg import add, cross, dot, mm, mmt, mul, mv, scale, sub


@dataclass
class BoundFrame:
    k: int  # the body
    r: tuple  # the origin, k's axes
    R: tuple | None  # 3x3: the frame's axes in k's axes (None: k's axes)


def bind_frames(bound) -> list:
    index = {name: k for k, name in enumerate(bound.tree.names)}
    return [BoundFrame(index[f.body], tuple(bound.scalar(x) for x in f.point), constant_axes(bound, f.axes, f.rotation))
            for f in bound.model.frames]


def frame_poses(bound, kin) -> list:
    """Per frame 12 numbers: the origin in the world, then the rotation (frame axes to world axes) row-major."""
    poses = world_poses(kin)
    out = []
    for f in bind_frames(bound):
        pose = poses[f.k]
        out.extend(add(pose.o, mv(pose.c, f.r)))
        R = pose.c if f.R is None else mm(pose.c, f.R)
        out.extend(x for row in R for x in row)
    return out


def frame_jacobians(bound, kin) -> list:
    """Per frame a 6 x n block of rows: (v, w) of the frame origin per unit rate of each coordinate, world axes."""
    poses = world_poses(kin)
    rows = []
    for f in bind_frames(bound):
        pose = poses[f.k]
        rows.extend(point_rows(kin, poses, f.k, add(pose.o, mv(pose.c, f.r))))
    return rows


def frame_accelerations(bound, kin, qd, qdd) -> list:
    """Per frame the classical acceleration of its origin and its angular acceleration, world axes."""
    poses = world_poses(kin)
    V = kin.velocities(qd)
    A = kin.accelerations(qd, qdd, V, ZERO6)
    out = []
    for f in bind_frames(bound):
        _, a, _, alpha = point_motion(poses[f.k].c, V[f.k], A[f.k], f.r)
        out.extend(a)
        out.extend(alpha)
    return out


class MassDistribution:
    """The moving bodies' mass, first moment and rotational inertia, world axes about the world origin, per body
    and summed over subtrees (see the module's text)."""

    def __init__(self, bound, kin, inertia: bool = False):
        tree = kin.tree
        self.poses = world_poses(kin)
        moves = moving_bodies(bound)
        self.mass, self.first, self.inertia = [], [], []
        for k, body in enumerate(bound.bodies):
            th = body.rigid if moves[k] else None
            if th is None:
                self.mass.append(0)
                self.first.append((0, 0, 0))
                self.inertia.append(None)
                continue
            R, o = self.poses[k].c, self.poses[k].o
            h = mv(R, th.h)
            self.mass.append(th.m)
            self.first.append(add(scale(th.m, o), h))
            if inertia:  # R Theta R^T about o, moved to the world origin: + m(|o|^2 E - o o^T) + 2(o.h)E - o h^T - h o^T
                J = mmt(mm(R, th.theta), R)
                oh = dot(o, h)
                oo = dot(o, o)
                J = tuple(tuple(J[i][j] + mul(th.m, (oo if i == j else 0) - mul(o[i], o[j])) + (2 * oh if i == j else 0)
                                - mul(o[i], h[j]) - mul(h[i], o[j]) for j in range(3)) for i in range(3))
                self.inertia.append(J)
            else:
                self.inertia.append(None)
        # subtree sums, leaves first
        self.M, self.C, self.I = list(self.mass), list(self.first), list(self.inertia)
        for k in range(len(tree) - 1, -1, -1):
            p = tree.parent[k]
            if p >= 0:
                self.M[p] = self.M[p] + self.M[k]
                self.C[p] = add(self.C[p], self.C[k])
                if self.I[k] is not None:
                    self.I[p] = self.I[k] if self.I[p] is None else tuple(
                        add(a, b) for a, b in zip(self.I[p], self.I[k]))
        roots = [k for k, p in enumerate(tree.parent) if p < 0]
        self.total = sum((self.M[k] for k in roots[1:]), self.M[roots[0]])
        first = self.C[roots[0]]
        for k in roots[1:]:
            first = add(first, self.C[k])
        self.total_first = first

    def centre(self) -> tuple:
        return scale(1 / self.total, self.total_first)

    def columns(self, kin):
        """Per coordinate i: (its body s, the world column (v_i, w_i), the velocity u of the point at the world
        origin)."""
        for s in range(len(kin.tree)):
            R, o = self.poses[s].c, self.poses[s].o
            for i, psi in zip(kin.tree.coords[s], kin.psi[s]):
                w = mv(R, psi[3:])
                v = mv(R, psi[:3])
                yield i, s, w, sub(v, cross(w, o))

    def linear_momentum(self, s, w, u) -> tuple:
        """p_i = M_s u + w x C_s: the subtree's linear momentum for the unit rate."""
        return add(scale(self.M[s], u), cross(w, self.C[s]))


def center_of_mass(bound, kin) -> list:
    """G = sum c_k / M over the moving bodies, world axes."""
    return list(MassDistribution(bound, kin).centre())


def com_jacobian(bound, kin) -> list:
    """dG/dq: 3 x n rows, column i = p_i / M."""
    mass = MassDistribution(bound, kin)
    n = kin.tree.nq
    rows = [[0] * n for _ in range(3)]
    inv = 1 / mass.total
    for i, s, w, u in mass.columns(kin):
        p = mass.linear_momentum(s, w, u)
        for a in range(3):
            rows[a][i] = mul(inv, p[a])
    return rows


def centroidal_map(bound, kin) -> list:
    """A_G: 6 x n rows, h_G = A_G qd (linear momentum, angular momentum about G, world axes)."""
    mass = MassDistribution(bound, kin, inertia=True)
    G = mass.centre()
    n = kin.tree.nq
    rows = [[0] * n for _ in range(6)]
    for i, s, w, u in mass.columns(kin):
        p = mass.linear_momentum(s, w, u)
        L = add(cross(mass.C[s], u), mv(mass.I[s], w)) if mass.I[s] is not None else cross(mass.C[s], u)
        L = sub(L, cross(G, p))
        for a in range(3):
            rows[a][i] = p[a]
            rows[3 + a][i] = L[a]
    return rows


__all__ = ["frame_poses", "frame_jacobians", "frame_accelerations", "center_of_mass", "com_jacobian",
           "centroidal_map", "bind_frames", "MassDistribution"]
