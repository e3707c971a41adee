"""Spatial tendons through sites (MuJoCo's ``<spatial>`` without wrapping geoms): their length, its rate and the
passive force of their springs and dampers, straight-line code like the rest.

A tendon's length is a sum over its branches of the distances between consecutive sites, each branch divided by its
pulley's divisor (:class:`~aggsym.model.types.SpatialTendon`):

    L(q) = sum_b (1 / d_b) sum_i |p_{i+1} - p_i|,      L' = sum_b (1 / d_b) sum_i u_i . (p'_{i+1} - p'_i),

p_i = R_k r_i + o_k the world position of site i (on body k at r_i in its axes; a world site is constant),
p'_i = R_k (v_k + w_k x r_i) from the body's quasi-velocity (2.39), u_i the unit vector from p_i to p_{i+1}.  The
force along the tendon, f = -(k s + d L' + F sign(L')) (s the stretch beyond the rest length or dead band, as for a
fixed tendon: :func:`~.joint_space.tendon_forces`), acts on the coordinates as J^T f, J = dL/dq: a force f u_i / d_b
pulling site i towards site i + 1 and its opposite at site i + 1, which is how it is computed here: point forces
turned into each body's axes, their moments about its origin, carried to the root (Prop. 2.19) and projected on the
pairs' axes (2.46), as gravity's weights are (:func:`~.bias.gravity_vector`).  The spring's energy 1/2 k s^2 joins
the potential energy.
"""
from __future__ import annotations

from ..core.program import is_zero
from ..model.types import WORLD
from .joint_space import _stretch, spring_energy
from .kinematics import ZERO6, TreeKinematics, generalized, point_motion, point_rows, world_poses
from .linalg import add, cross, dot, mtv, mul, mv, scale, sub


def _branches(bound, kin, branches, poses):
    """Per branch (1/divisor, [(body index or None, r, world position p)])."""
    index = {name: k for k, name in enumerate(bound.tree.names)}
    out = []
    for divisor, sites in branches:
        placed = []
        for body, point in sites:
            r = tuple(bound.scalar(x) for x in point)
            if body == WORLD:
                placed.append((None, r, r))
            else:
                k = index[body]
                placed.append((k, r, add(mv(poses[k].c, r), poses[k].o)))
        out.append((1 if divisor == 1 else 1 / bound.scalar(divisor), placed))
    return out


def _segments(bound, kin, branches, poses):
    """Per straight piece between consecutive sites: (1/divisor, site a, site b, |b - a|, the unit vector u)."""
    out = []
    for inverse, placed in _branches(bound, kin, branches, poses):
        for a, b in zip(placed, placed[1:]):
            d = sub(b[2], a[2])
            length = bound.backend.call("sqrt", dot(d, d))
            out.append((inverse, a, b, length, scale(1 / length, d)))
    return out


def _site_velocity(poses, V, site):
    """p' = R_k (v_k + w_k x r) of a site on body k (0 for a world site)."""
    k, r, _ = site
    if k is None:
        return (0, 0, 0)
    v, w = V[k][:3], V[k][3:]
    return mv(poses[k].c, add(v, cross(w, r)))


def tendon_length(bound, kin, tendon, poses=None):
    """L(q) (the module's text)."""
    poses = world_poses(kin) if poses is None else poses
    acc = 0
    for inverse, _, _, length, _ in _segments(bound, kin, tendon.branches, poses):
        acc = acc + mul(inverse, length)
    return acc


def _tension(bound, tendon, L, rate):
    """k s + d L' + F sign(L'): minus the force along the tendon (0 when it has none)."""
    k, d, fr = bound.scalar(tendon.stiffness), bound.scalar(tendon.damping), bound.scalar(tendon.friction)
    left = 0
    if not is_zero(k):
        left = mul(k, _stretch(bound, tendon, L))
    if not is_zero(d):
        left = left + mul(d, rate())
    if not is_zero(fr):
        left = left + mul(fr, bound.backend.call("sign", rate()))
    return left


def spatial_tendon_forces(bound, q, qd) -> list:
    """-J^T f summed over the spatial tendons: their passive forces on the left side (n scalars)."""
    n = bound.tree.nv
    if not bound.model.spatial_tendons:
        return [0] * n
    kin = TreeKinematics(bound, q)  # (on the symbolic backend the same nodes as the routine's own kinematics)
    poses = world_poses(kin)
    V = None
    Y = [ZERO6] * len(bound.tree)
    for tendon in bound.model.spatial_tendons:
        segments = _segments(bound, kin, tendon.branches, poses)
        L = 0
        for inverse, _, _, length, _ in segments:
            L = L + mul(inverse, length)

        def rate():
            nonlocal V
            V = kin.velocities(qd) if V is None else V
            acc = 0
            for inverse, a, b, _, u in segments:
                acc = acc + mul(inverse, dot(u, sub(_site_velocity(poses, V, b), _site_velocity(poses, V, a))))
            return acc

        tension = _tension(bound, tendon, L, rate)
        if is_zero(tension):
            continue
        for inverse, a, b, _, u in segments:
            pull = scale(mul(inverse, tension), u)  # the left side's: -(force at a) = +(force at b)
            for site, sign in ((a, -1), (b, 1)):
                k, r, _ = site
                if k is None:
                    continue
                f = mtv(poses[k].c, pull if sign > 0 else tuple(-x for x in pull))
                Y[k] = add(Y[k], f + cross(r, f))
    return generalized(kin, kin.backward(Y))


class SpatialLength:
    """A spatial tendon's length as a length of :mod:`~aggsym.mechanics.joint_space` (a joint-space constraint row
    on it: an MJCF tendon equality), at the configuration of ``kin``: ``value`` L(q), ``rate`` L', ``add_to`` its
    Jacobian row dL/dq over the velocities (``sum (1/d_b) u^T (J_b - J_a)``, J_a a site's rows of
    :func:`~aggsym.mechanics.kinematics.point_rows` in world axes), ``curvature`` d^2 L/dt^2 at qdd = 0: per
    segment, with d = p_b - p_a, u = d/|d|, dv = p'_b - p'_a and da the sites' relative classical acceleration at
    qdd = 0 (:func:`~aggsym.mechanics.kinematics.point_motion` of the quasi-accelerations X = S'^T qd, as a point
    constraint's gamma), ``(1/d_b) (u . da + (|dv|^2 - (u . dv)^2)/|d|)``.  ``q`` and ``qd`` are those ``kin``
    was built at and is asked for (the arguments only keep the interface of a linear form)."""

    def __init__(self, bound, kin, branches, poses=None):
        self.bound, self.kin = bound, kin
        self.poses = world_poses(kin) if poses is None else poses
        self.segments = _segments(bound, kin, branches, self.poses)
        self._motion = None  # (qd, V, X) of the last rate asked

    def value(self, q=None):
        acc = 0
        for inverse, _, _, length, _ in self.segments:
            acc = acc + mul(inverse, length)
        return acc

    def _velocities(self, qd):
        if self._motion is None or self._motion[0] is not qd:
            V = self.kin.velocities(qd)
            self._motion = (qd, V, None)
        return self._motion[1]

    def _products(self, qd):
        V = self._velocities(qd)
        if self._motion[2] is None:
            self._motion = (qd, V, self.kin.velocity_products(qd, V))
        return V, self._motion[2]

    def rate(self, qd):
        V = self._velocities(qd)
        acc = 0
        for inverse, a, b, _, u in self.segments:
            acc = acc + mul(inverse, dot(u, sub(_site_velocity(self.poses, V, b), _site_velocity(self.poses, V, a))))
        return acc

    def add_to(self, row: list, factor=1) -> list:
        """row + factor dL/dq (a new list of n scalars)."""
        out = list(row)
        for inverse, a, b, _, u in self.segments:
            weight = scale(inverse if (type(factor) is int and factor == 1) else mul(factor, inverse), u)
            for (k, _, p), sign in ((b, 1), (a, -1)):
                if k is None:  # (a site on the world)
                    continue
                lin = point_rows(self.kin, self.poses, k, p)[:3]
                for i in range(len(out)):
                    term = 0
                    for w, r in zip(weight, lin):
                        if not is_zero(r[i]):
                            term = term + mul(w, r[i])
                    if is_zero(term):
                        continue
                    if is_zero(out[i]):
                        out[i] = term if sign > 0 else -term
                    else:
                        out[i] = out[i] + term if sign > 0 else out[i] - term
        return out

    def curvature(self, qd):
        V, X = self._products(qd)
        acc = 0
        for inverse, a, b, length, u in self.segments:
            motion = []
            for site in (a, b):
                k, r, _ = site
                motion.append(((0, 0, 0), (0, 0, 0)) if k is None else
                              point_motion(self.poses[k].c, V[k], X[k], r)[:2])
            dv, da = sub(motion[1][0], motion[0][0]), sub(motion[1][1], motion[0][1])
            along = dot(u, dv)
            term = dot(u, da) + (dot(dv, dv) - along * along) / length
            acc = acc + mul(inverse, term)
        return acc


def spatial_tendon_energy(bound, kin):
    """1/2 k s^2 summed over the spatial tendons' springs."""
    if not bound.model.spatial_tendons:
        return 0
    poses = world_poses(kin)
    return spring_energy(bound, bound.model.spatial_tendons, lambda t: tendon_length(bound, kin, t, poses))


__all__ = ["SpatialLength", "spatial_tendon_energy", "spatial_tendon_forces", "tendon_length"]
