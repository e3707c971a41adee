"""The bias b(q, q') = B(q, q') q' in O(n) (2.36)-(2.37), Prop. 2.19, and the gravity column g(q).

``b = F^T M^T Z`` with ``Z = L Y`` accumulated from the buds to the root (Prop. 2.19),
``Y_lk = Theta_lk X_lk + Phi_lk Theta_lk V_lk`` (2.36), X from (2.37) (see :mod:`aggsym.kinematics`).

Gravity enters the book's right-hand side as ``S H`` with the gravity wrench ``G_lk`` in H (2.9), (2.29); aggsym
moves it to the left: ``g(q) = -S G``.  Since ``G_lk = Theta_lk (g_lk, 0)`` with g_lk the gravity vector in the
body's axes, ``g = F^T M^T L Y_g`` with ``Y_g = Theta (-g_lk, 0)``: the same backward recurrence.
"""
from __future__ import annotations

from .kinematics import ZERO6, generalized, world_frame_vectors
from .linalg import neg


def bias_vector(bound, kin, qd, V=None):
    """b(q, q') (2.36)-(2.37), Prop. 2.19: a list of n scalars."""
    V = kin.velocities(qd) if V is None else V
    X = kin.velocity_products(qd, V)
    Y = []
    for k, body in enumerate(bound.bodies):
        th = body.mises
        Y.append(ZERO6 if th is None else th.dynamic_wrench(X[k], V[k]))
    return generalized(kin, kin.backward(Y))


def gravity_accelerations(bound, kin):
    """(-g_lk, 0) for every body: minus gravity in the body's axes, as a fictitious quasi-acceleration."""
    return [x + (0, 0, 0) for x in world_frame_vectors(kin, neg(bound.gravity))]


def gravity_vector(bound, kin):
    """g(q) = -S G (see the module docstring): a list of n scalars."""
    gam = gravity_accelerations(bound, kin)
    Y = [ZERO6 if b.mises is None else b.mises.apply(gam[k]) for k, b in enumerate(bound.bodies)]
    return generalized(kin, kin.backward(Y))
