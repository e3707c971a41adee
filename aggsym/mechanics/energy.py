"""Kinetic and potential energy (Def. 2.4).

``T = 1/2 V^T A V`` summed over bodies with the body quasi-velocities V of (1.41) (A the body's aggregate: with
added masses Theta + Lambda, so T holds the medium's 1/2 V^T Lambda V (Prop. 2.8); a prescribed spin's velocity
is in V), and
``U = sum_k m_k (-g . o_k) + (-g_k) . h_k`` with o_k the body origin in the world frame, g_k gravity in the body's
axes and h_k = m_k r_ck the first moment: the work against gravity of lifting every centre of mass, from the world
origin.  The heights ``-g . o_k`` are carried from the root: ``-g . o_k = -g . o_parent + (-g_parent) . o^{parent}_{k}``.
Bodies welded to the world (no coordinate or prescribed spin on their path from the root) are left out of U: their potential is a
constant, and Pinocchio's computePotentialEnergy leaves them out too.
(The springs' 1/2 (q - q0)^T C (q - q0) is :func:`aggsym.elastic.elastic_energy`.)

The momentum ``h = sum_k L_k (A_lk V_k)``: each body's momentum wrench (linear momentum, angular momentum about
its origin, in its axes: the aggregate times the quasi-velocity, (2.3)) moved to the world origin and axes by its
world pose L_k (1.13), as a wrench; T = 1/2 sum V_k . A_lk V_k is the same product.  With added masses it is the
body's momentum plus the medium's impulse (Prop. 2.8); the armature's reflected inertia carries none (it is not a
body), as in Pinocchio.
"""
from __future__ import annotations

from .bias import gravity_accelerations
from .gravcomp import compensated_potential
from .kinematics import moving_bodies, world_poses
from .linalg import add, dot, mul
from .tendon_armature import kinetic as tendon_kinetic


def kinetic_energy(bound, kin, qd):
    V = kin.velocities(qd)
    acc = 0
    for k, body in enumerate(bound.bodies):
        if body.mises is not None:
            acc = acc + dot(V[k], body.mises.apply(V[k]))
    if bound.rotors:  # each coordinate's own rotor
        for j, rate in enumerate(qd):
            acc = acc + mul(bound.rotor(j), mul(rate, rate))
    else:
        acc = acc + mul(bound.armature, dot(qd, qd))  # the rotors of the armature
    if bound.model.tendons:  # the fixed tendons' armature: a (c . q')^2
        acc = acc + tendon_kinetic(bound, qd)
    return bound.rational(1, 2) * acc


def momentum(bound, kin, qd) -> list:
    """h = (linear momentum, angular momentum about the world origin), world axes."""
    V = kin.velocities(qd)
    poses = world_poses(kin)
    h = [0] * 6
    for k, body in enumerate(bound.bodies):
        if body.mises is not None:
            h = add(h, poses[k].wrench(body.mises.apply(V[k])))
    return list(h)


def potential_energy(bound, kin):
    gam = [g[:3] for g in gravity_accelerations(bound, kin)]  # -g in each body's axes
    minus_g = tuple(-x for x in bound.gravity)
    height = []
    moves = moving_bodies(bound)
    acc = 0
    for k, p in enumerate(kin.tree.parent):
        up = minus_g if p < 0 else gam[p]
        h = dot(up, kin.L[k].o)
        height.append(h if p < 0 else height[p] + h)
        th = bound.bodies[k].rigid
        if th is not None and moves[k]:
            acc = acc + th.m * height[k] + dot(gam[k], th.h)
    if bound.gravcomp:  # (the lifts' potential: MuJoCo's gravcomp, aggsym.mechanics.gravcomp)
        acc = acc - compensated_potential(bound, kin)
    return acc
