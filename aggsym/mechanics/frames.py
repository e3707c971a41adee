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
from .linalg import add, cross, mm, mul, mv, scale, sub


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
    """The moving bodies' Mises matrices (2.3) moved to the world frame by their poses (2.7), L Theta L^T
    (:meth:`~aggsym.mechanics.aggregates.Rigid.moved`: mass, first moment C and inertia I about the world origin,
    world axes), and their sums over subtrees (see the module's text); None where a subtree has no mass."""

    def __init__(self, bound, kin):
        tree = kin.tree
        self.poses = world_poses(kin)
        moves = moving_bodies(bound)
        self.sub = [b.rigid.moved(self.poses[k]) if moves[k] and b.rigid is not None else None
                    for k, b in enumerate(bound.bodies)]
        for k in range(len(tree) - 1, -1, -1):  # leaves first
            p = tree.parent[k]
            if p >= 0 and self.sub[k] is not None:
                self.sub[p] = self.sub[k] + self.sub[p]
        total = None
        for k, p in enumerate(tree.parent):
            if p < 0 and self.sub[k] is not None:
                total = self.sub[k] + total
        self.total = total

    def centre(self) -> tuple:
        return scale(1 / self.total.m, self.total.h)

    def columns(self, kin):
        """Per coordinate i whose subtree has mass: (i, the subtree's Rigid, the world column's angular part w_i,
        the velocity u of the point at the world origin)."""
        for s in range(len(kin.tree)):
            if self.sub[s] is None:
                continue
            R, o = self.poses[s].c, self.poses[s].o
            for i, psi in zip(kin.tree.coords[s], kin.psi[s]):
                w = mv(R, psi[3:])
                yield i, self.sub[s], w, sub(mv(R, psi[:3]), cross(w, o))


def linear_momentum(X, w, u) -> tuple:
    """p_i = M_s u + w x C_s: the subtree's linear momentum for the unit rate."""
    return add(scale(X.m, u), cross(w, X.h))


def center_of_mass(bound, kin) -> list:
    """G = sum c_k / M over the moving bodies, world axes."""
    return list(MassDistribution(bound, kin).centre())


def com_jacobian(bound, kin) -> list:
    """dG/dq: 3 x n rows, column i = p_i / M."""
    mass = MassDistribution(bound, kin)
    rows = [[0] * kin.tree.nv for _ in range(3)]
    inv = 1 / mass.total.m
    for i, X, w, u in mass.columns(kin):
        for a, x in enumerate(linear_momentum(X, w, u)):
            rows[a][i] = mul(inv, x)
    return rows


def centroidal_map(bound, kin) -> list:
    """A_G: 6 x n rows, h_G = A_G qd (linear momentum, angular momentum about G, world axes)."""
    mass = MassDistribution(bound, kin)
    G = mass.centre()
    rows = [[0] * kin.tree.nv for _ in range(6)]
    for i, X, w, u in mass.columns(kin):
        p = linear_momentum(X, w, u)
        L = sub(add(cross(X.h, u), mv(X.theta, w)), cross(G, p))  # L_O - G x p
        for a in range(3):
            rows[a][i] = p[a]
            rows[3 + a][i] = L[a]
    return rows


__all__ = ["frame_poses", "frame_jacobians", "frame_accelerations", "center_of_mass", "com_jacobian",
           "centroidal_map", "bind_frames", "MassDistribution"]
