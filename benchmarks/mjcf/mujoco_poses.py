"""The poses of an MJCF model against MuJoCo's kinematics: every body's and site's frame, every body's centre of mass
and inertia, in the model as read and in the internal frames the generated routines are built from.

At random qpos (hinges and slides uniform in [-pi, pi], balls and free joints random unit quaternions:
:func:`benchmarks.mjcf.mujoco_reference.states`), MuJoCo's ``mj_kinematics`` gives ``xpos``/``xmat`` (bodies),
``site_xpos``/``site_xmat`` and ``xipos``/``ximat`` with ``body_inertia``; aggsym gives

* ``frame``: the routine ``frame_poses`` of the model as read, over every MuJoCo body and site (each a frame of the
  body it was merged into: ``Model.link_table``), against ``xpos``/``xmat`` and ``site_xpos``/``site_xmat``;
* ``com``, ``inertia``: per aggsym body, its mass, centre of mass and inertia about it in world axes (its Mises
  matrix (2.3) moved by its world pose (1.13)) against those of the MuJoCo bodies merged into it (their masses at
  ``xipos``, their inertias ``ximat diag(body_inertia) ximat^T`` moved to the common centre);
* ``internal``: per internal model (both of :func:`benchmarks.mjcf.mujoco_reference.routine_models`), the world pose
  of each body's internal frame against the pose of the model as read composed with where
  :func:`aggsym.model.transforms.reframe.internal_frames` puts it.

A pose error anywhere (a reader's placement, an anchor, a joint's ``ref``, an internal frame's offset) fails here
before it reaches A.  :func:`with_refs` gives a file's model with a ``ref`` on each hinge and slide, compiled by
MuJoCo from its ``MjSpec``: the corpora have almost none.  Errors: positions relative to the model's size (the
largest distance of a body, site or centre of mass from the world origin, at least 1), rotations absolute,
inertias relative to the largest.
"""
from __future__ import annotations

import numpy as np

from .mujoco_reference import compiled, states


def with_refs(path, rng, scale: float = 1.0):
    """(MjModel, its aggsym model): the MJCF file at ``path`` with every hinge's and slide's ``ref`` a random
    number in [-scale, scale] (radians or the file's length unit; a hinge's in the compiler's angle unit) written
    with 5 digits, compiled by MuJoCo from its ``MjSpec`` (qpos0 = ref; the bodies stay where the file puts them)."""
    import mujoco

    from aggsym.model.readers.mjcf_reader import read_compiled

    spec = mujoco.MjSpec.from_file(str(path))
    for joint in spec.joints:
        if joint.type in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
            value = round(float(rng.uniform(-scale, scale)), 5)
            if joint.type == mujoco.mjtJoint.mjJNT_HINGE and spec.compiler.degree:
                value = round(float(np.degrees(value)), 3)
            joint.ref = value
    m = spec.compile()
    return m, read_compiled(m, path)


def _names(m, kind, count, prefix, offset=0):
    """The reader's names of MuJoCo's elements of one kind (aggsym.model.readers.mjcf_reader._name)."""
    from aggsym.model.readers.mjcf_reader import _name
    import mujoco

    return [_name(m, mujoco, kind, i, prefix) for i in range(offset, count)]


def _rel(a, b, scale) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b)))) / scale if np.size(a) else 0.0


def compare_poses(path, model=None, samples: int = 3, seed: int = 0) -> dict:
    """The largest errors {frame, rotation, com, inertia, internal} over ``samples`` random qpos (module docstring).
    ``path``: the MJCF file, or an ``MjModel`` with ``model`` its aggsym model."""
    import mujoco

    from aggsym.core.backend import Numeric
    from aggsym.mechanics.bound import bind
    from aggsym.mechanics.kinematics import TreeKinematics, world_poses
    from aggsym.model import load
    from aggsym.model.transforms.frames import catalog, select_frames
    from aggsym.model.transforms.reframe import internal_frames
    from aggsym.twin import NumericTwin

    from .mujoco_reference import couplings, to_aggsym

    model = load(path) if model is None else model
    m = compiled(path)
    data = mujoco.MjData(m)
    bodies = _names(m, mujoco.mjtObj.mjOBJ_BODY, m.nbody, "body", offset=1)
    offered = catalog(model)
    sites = []
    for s, name in enumerate(_names(m, mujoco.mjtObj.mjOBJ_SITE, m.nsite, "site")):
        link = f"site:{name}" if name in bodies else name
        if link in offered:  # (a site on a body welded to the world of a model without a worldbody is no frame)
            sites.append((s, link))
    framed = select_frames(model, bodies + [link for _, link in sites])
    twin = NumericTwin(framed)
    numeric = Numeric()
    bound = bind(model, numeric)
    names = bound.tree.names
    body_of = [names.index(offered[name].body) for name in bodies]  # MuJoCo body i + 1 -> aggsym body
    internal = []  # (bound internal model, its frames) of both internal models the routines may be built from
    for fewest in (False, True):
        inner, placements = internal_frames(model, fewest=fewest)
        if placements is not None:
            internal.append((bind(inner, numeric), placements))
    coupled = couplings(m, model) if model.couplings else None
    rng = np.random.default_rng(seed)
    worst = {"frame": 0.0, "rotation": 0.0, "com": 0.0, "inertia": 0.0, "internal": 0.0}
    for _ in range(samples):
        qpos, qvel, force = states(m, rng)
        if coupled is not None:  # a configuration where the couplings hold; q without the coupled coordinates
            qpos = coupled.state(qpos, qvel, force)[0]
        data.qpos[:] = qpos
        mujoco.mj_kinematics(m, data)
        full = to_aggsym(m, qpos, np.zeros(m.nv), np.zeros(m.nv))[0]  # (the tree's: coupled coordinates too)
        q = full if coupled is None else full[coupled.keep]
        X = np.asarray(twin.call("frame_poses", q)).reshape(-1, 12)
        ref_o = np.vstack([data.xpos[1:], data.site_xpos[[s for s, _ in sites]].reshape(-1, 3)])
        ref_R = np.vstack([data.xmat[1:], data.site_xmat[[s for s, _ in sites]].reshape(-1, 9)])
        size = max(1.0, float(np.max(np.abs(ref_o), initial=0.0)), float(np.max(np.abs(data.xipos), initial=0.0)))
        worst["frame"] = max(worst["frame"], _rel(X[:, :3], ref_o, size))
        worst["rotation"] = max(worst["rotation"], _rel(X[:, 3:], ref_R, 1.0))
        kin = TreeKinematics(bound, list(full))
        poses = world_poses(kin)
        for k, body in enumerate(model.bodies):
            merged = [i + 1 for i, b in enumerate(body_of) if b == k]
            mass_ref = float(sum(m.body_mass[i] for i in merged))
            com_ref = (sum(m.body_mass[i] * data.xipos[i] for i in merged) / mass_ref if mass_ref else None)
            I_ref = np.zeros((3, 3))
            for i in merged:
                R = data.ximat[i].reshape(3, 3)
                I_ref += R @ np.diag(m.body_inertia[i]) @ R.T
                if com_ref is not None:
                    r = data.xipos[i] - com_ref
                    I_ref += m.body_mass[i] * (r @ r * np.eye(3) - np.outer(r, r))
            mine = _world_inertial(bound.bodies[k].rigid, poses[k])
            if mine is None:
                worst["inertia"] = max(worst["inertia"], _rel(0.0, I_ref, 1.0))
                continue
            mass, com, I = mine
            scale = max(float(np.max(np.abs(I_ref))), float(np.max(np.abs(I))), 1e-300)
            worst["inertia"] = max(worst["inertia"], abs(mass - mass_ref) / max(mass_ref, 1e-300),
                                   _rel(I, I_ref, scale))
            if com_ref is not None:
                worst["com"] = max(worst["com"], _rel(com, com_ref, size))
        for inner_bound, placements in internal:
            inner = world_poses(TreeKinematics(inner_bound, list(full)))
            for k, (R_int, o_int) in enumerate(placements):
                R, o = np.array(poses[k].c, dtype=float), np.array(poses[k].o, dtype=float)
                Ri, oi = np.array(inner[k].c, dtype=float), np.array(inner[k].o, dtype=float)
                worst["internal"] = max(worst["internal"], _rel(Ri, R @ np.array(R_int), 1.0),
                                        _rel(oi, o + R @ np.array(o_int), size))
    return worst


def _world_inertial(rigid, pose):
    """(mass, centre of mass, inertia about it) in world axes of a body's Mises matrix (m, h, theta_O) (2.3) at its
    world pose; None for a body without one."""
    if rigid is None:
        return None
    mass = float(rigid.m)
    h = np.array(rigid.h, dtype=float)
    theta = np.array(rigid.theta, dtype=float)
    R, o = np.array(pose.c, dtype=float), np.array(pose.o, dtype=float)
    c = h / mass if mass else np.zeros(3)
    I_c = theta - mass * (c @ c * np.eye(3) - np.outer(c, c))
    return mass, o + R @ c, R @ I_c @ R.T
