"""The two simulators among the batched benchmark's entries, MuJoCo MJX and jaxsim, set to the rigid-body problem
Pinocchio solves and converted to its conventions (:mod:`benchmarks.batch.peers` says which).

MJX: the URDF (meshes stripped by :mod:`benchmarks.batch.orchestrator`) compiled by MuJoCo with ``fusestatic="false"``,
``inertiafromgeom="false"``, ``balanceinertia="false"`` (the URDF's inertials as they are), a free joint added
to the root for a free-flyer, armature, damping, friction and springs zeroed, contacts and every constraint
(limits among them) disabled.  MuJoCo's free joint takes the base's linear velocity in world axes and returns
the derivative of that; its angular velocity is in the base's axes as Pinocchio's; its quaternion is w x y z.

jaxsim reads SDF (its URDF path calls a Gazebo tool that PyPI does not have): :func:`write_sdf` writes the
URDF's links at their poses at q = 0, its joints and inertials; a fixed base is a fixed joint to the world.
jaxsim is used in its body-fixed velocity representation, which is Pinocchio's.
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from .peers import GRAVITY, Built, _cross, _matvec, _tmatvec, jax_jacobian, quat_matrix

MJ_COMPILER = {"fusestatic": "false", "inertiafromgeom": "false", "balanceinertia": "false",
               "discardvisual": "true", "strippath": "true"}


def _permutation(pin_names, names):
    return [names.index(n) for n in pin_names]


# ----------------------------------------------------------------------------------------------------- MJX
def mujoco_model(robot):
    """The MjModel of the robot's stripped URDF, with the settings of the module's docstring."""
    import mujoco

    root = ET.parse(robot["urdf"]).getroot()
    extra = ET.SubElement(root, "mujoco")
    ET.SubElement(extra, "compiler", MJ_COMPILER)
    spec = mujoco.MjSpec.from_string(ET.tostring(root, encoding="unicode"))
    if robot["floating"]:
        spec.worldbody.first_body().add_freejoint()
    m = spec.compile()
    m.dof_armature[:] = 0
    m.dof_damping[:] = 0
    m.dof_frictionloss[:] = 0
    m.jnt_stiffness[:] = 0
    m.opt.gravity[:] = (0, 0, -GRAVITY)
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT) | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    return m


class _MjxConvention:
    """Pinocchio's state to MuJoCo's and back, for one state (jnp)."""

    def __init__(self, m, robot):
        import mujoco

        names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(m.njnt)]
        self.floating = robot["floating"]
        off = 1 if self.floating else 0
        order = _permutation(robot["joints"], names)
        self.qpos = np.array([m.jnt_qposadr[j] for j in order])  # MuJoCo's qpos index of Pinocchio's joint k
        self.dof = np.array([m.jnt_dofadr[j] for j in order])
        self.off = off
        inverse = np.empty(m.nv, dtype=int)  # Pinocchio's index of MuJoCo's dof
        base = 6 if self.floating else 0
        inverse[self.dof] = np.arange(len(order)) + base
        if self.floating:
            inverse[:6] = np.arange(6)
        self.dof_to_pin = inverse  # x_mj = x_pin[dof_to_pin]
        self.pin_to_dof = np.argsort(inverse)  # x_pin = x_mj[pin_to_dof]

    def qpos_of(self, q):
        import jax.numpy as jnp

        if not self.floating:
            return jnp.zeros(len(self.qpos), q.dtype).at[self.qpos].set(q)
        out = jnp.zeros(7 + len(self.qpos), q.dtype)
        out = out.at[:3].set(q[:3]).at[3].set(q[6]).at[4:7].set(q[3:6])
        return out.at[self.qpos].set(q[7:])

    def to_mj(self, q, x, linear_rotate=True):
        """A velocity-like vector (v, or a force for ``linear_rotate``: both rotate the same way, R x)."""
        import jax.numpy as jnp

        if self.floating:
            R = quat_matrix(jnp, q[3:7])
            x = jnp.concatenate([_matvec(jnp, R, x[:3]), x[3:]])
        return x[self.dof_to_pin]

    def acc_to_mj(self, q, v, a):
        import jax.numpy as jnp

        if self.floating:
            R = quat_matrix(jnp, q[3:7])
            a = jnp.concatenate([_matvec(jnp, R, _cross(jnp, v[3:6], v[:3]) + a[:3]), a[3:]])
        return a[self.dof_to_pin]

    def acc_from_mj(self, q, v, qacc):
        import jax.numpy as jnp

        a = qacc[self.pin_to_dof]
        if self.floating:
            R = quat_matrix(jnp, q[3:7])
            a = jnp.concatenate([_tmatvec(jnp, R, a[:3]) - _cross(jnp, v[3:6], v[:3]), a[3:]])
        return a

    def force_from_mj(self, q, f):
        import jax.numpy as jnp

        f = f[self.pin_to_dof]
        if self.floating:
            R = quat_matrix(jnp, q[3:7])
            f = jnp.concatenate([_tmatvec(jnp, R, f[:3]), f[3:]])
        return f

    def matrix_from_mj(self, q, M):
        """S^T M S with v_mj = S v_pin (S: R on the base's linear block, the permutation elsewhere)."""
        import jax.numpy as jnp

        M = M[self.pin_to_dof][:, self.pin_to_dof]
        if self.floating:
            R = quat_matrix(jnp, q[3:7])
            S = jnp.eye(M.shape[0], dtype=M.dtype).at[:3, :3].set(R)
            M = S.T @ M @ S
        return M


def build_mjx(robot):
    import jax
    import jax.numpy as jnp

    jax.config.update("jax_enable_x64", True)
    from mujoco import mjx

    m = mujoco_model(robot)
    c = _MjxConvention(m, robot)
    mx = mjx.put_model(m)
    d0 = mjx.make_data(mx)

    def fd(q, v, tau):
        d = d0.replace(qpos=c.qpos_of(q), qvel=c.to_mj(q, v), qfrc_applied=c.to_mj(q, tau))
        return c.acc_from_mj(q, v, mjx.forward(mx, d).qacc)

    def A(q):
        d = mjx.crb(mx, mjx.com_pos(mx, mjx.kinematics(mx, d0.replace(qpos=c.qpos_of(q)))))
        return c.matrix_from_mj(q, mjx.full_m(mx, d))

    def id_(q, v, a):
        d = d0.replace(qpos=c.qpos_of(q), qvel=c.to_mj(q, v), qacc=c.acc_to_mj(q, v, a))
        return c.force_from_mj(q, mjx.inverse(mx, d).qfrc_inverse)

    vm = lambda f: jax.jit(jax.vmap(f))  # noqa: E731
    return Built({"fd": vm(fd), "A": vm(A), "id": vm(id_), "jac": jax_jacobian(fd, robot["floating"], robot["nv"])},
                 put=jax.device_put, fetch=np.asarray, ready=jax.block_until_ready, compiles=True)


# -------------------------------------------------------------------------------------------------- jaxsim
def _origin(el):
    """(xyz, rpy) of a URDF <origin> (zeros where absent)."""
    o = el.find("origin") if el is not None else None
    xyz = [float(x) for x in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
    rpy = [float(x) for x in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
    return np.array(xyz), np.array(rpy)


def _rpy_matrix(rpy):
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _matrix_rpy(R):
    """Roll-pitch-yaw of R (URDF's fixed-axis x-y-z)."""
    p = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    return (math.atan2(R[2, 1], R[2, 2]), p, math.atan2(R[1, 0], R[0, 0]))


def _pose(t, R):
    return " ".join(repr(float(x)) for x in (*t, *_matrix_rpy(R)))


def _inertial(link):
    """(mass, centre of mass, inertia about it) of a URDF link in its own frame (zeros without <inertial>)."""
    el = link.find("inertial")
    if el is None:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    xyz, rpy = _origin(el)
    src = el.find("inertia")
    g = {k: float(src.get(k, "0")) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    inertia = np.array([[g["ixx"], g["ixy"], g["ixz"]], [g["ixy"], g["iyy"], g["iyz"]], [g["ixz"], g["iyz"], g["izz"]]])
    R = _rpy_matrix(rpy)
    return float(el.find("mass").get("value")), xyz, R @ inertia @ R.T


def write_sdf(urdf: Path, out: Path, fixed_base: bool) -> Path:
    """SDF 1.7 of a URDF tree with its fixed joints merged: every link welded to its parent joins the parent's
    body (mass, centre of mass and inertia summed in the body's frame, as jaxsim and Pinocchio both do); the
    bodies at their poses at q = 0 in the model frame; each moving joint at its child's origin with the URDF's
    axis (joint frame); a fixed base gets a fixed joint to the world."""
    root = ET.parse(urdf).getroot()
    joints = root.findall("joint")
    links = {lk.get("name"): lk for lk in root.findall("link")}
    parent_of = {j.find("child").get("link"): j for j in joints}

    def place(link):
        """(body, t, R): the body a link belongs to and the link's frame in the body's."""
        j = parent_of.get(link)
        if j is None or j.get("type") != "fixed":
            return link, np.zeros(3), np.eye(3)
        body, t, R = place(j.find("parent").get("link"))
        xyz, rpy = _origin(j)
        return body, t + R @ xyz, R @ _rpy_matrix(rpy)

    poses = {}

    def pose(body):
        """The body's frame in the model's at q = 0."""
        if body not in poses:
            j = parent_of.get(body)
            if j is None:
                poses[body] = (np.zeros(3), np.eye(3))
            else:
                pbody, t, R = place(j.find("parent").get("link"))
                tp, Rp = pose(pbody)
                xyz, rpy = _origin(j)
                poses[body] = (tp + Rp @ (t + R @ xyz), Rp @ R @ _rpy_matrix(rpy))
        return poses[body]

    parts = {}
    for name, link in links.items():
        body, t, R = place(name)
        m, c, inertia = _inertial(link)
        parts.setdefault(body, []).append((m, t + R @ c, R @ inertia @ R.T))
    sdf = ET.Element("sdf", version="1.7")
    model = ET.SubElement(sdf, "model", name=root.get("name", "robot"))
    def depth(body):
        j = parent_of.get(body)
        return 0 if j is None else 1 + depth(place(j.find("parent").get("link"))[0])

    for body in sorted(parts, key=depth):  # the root first: rod takes the first link for the base
        items = parts[body]
        el = ET.SubElement(model, "link", name=body)
        ET.SubElement(el, "pose").text = _pose(*pose(body))
        mass = sum(m for m, _, _ in items)
        com = sum(m * c for m, c, _ in items) / mass
        inertia = sum(I + m * (np.dot(c - com, c - com) * np.eye(3) - np.outer(c - com, c - com))
                      for m, c, I in items)
        ie = ET.SubElement(el, "inertial")
        ET.SubElement(ie, "pose").text = _pose(com, np.eye(3))
        ET.SubElement(ie, "mass").text = repr(mass)
        box = ET.SubElement(ie, "inertia")
        for k, (a, b) in {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2),
                          "izz": (2, 2)}.items():
            ET.SubElement(box, k).text = repr(float(inertia[a, b]))
    for j in joints:
        if j.get("type") == "fixed":
            continue
        kind = {"continuous": "revolute"}.get(j.get("type"), j.get("type"))
        el = ET.SubElement(model, "joint", name=j.get("name"), type=kind)
        ET.SubElement(el, "parent").text = place(j.find("parent").get("link"))[0]
        ET.SubElement(el, "child").text = j.find("child").get("link")
        axis = ET.SubElement(el, "axis")
        a = j.find("axis")
        ET.SubElement(axis, "xyz").text = a.get("xyz") if a is not None else "1 0 0"
        limit = ET.SubElement(axis, "limit")
        ET.SubElement(limit, "lower").text = "-1e16"
        ET.SubElement(limit, "upper").text = "1e16"
    if fixed_base:
        roots = [name for name in links if name not in parent_of]
        el = ET.SubElement(model, "joint", name="world_to_base", type="fixed")
        ET.SubElement(el, "parent").text = "world"
        ET.SubElement(el, "child").text = roots[0]
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(ET.tostring(sdf, encoding="unicode"))
    return out


def build_jaxsim(robot):
    import jax
    import jax.numpy as jnp

    jax.config.update("jax_enable_x64", True)
    import jaxsim.api as js
    from jaxsim import VelRepr

    sdf = write_sdf(Path(robot["urdf"]), Path(robot["work"]) / "jaxsim.sdf", fixed_base=not robot["floating"])
    model = js.model.JaxSimModel.build_from_model_description(sdf, considered_joints=robot["joints"],
                                                              gravity=GRAVITY)
    names = list(model.joint_names())
    perm = np.array(_permutation(robot["joints"], names))  # jaxsim's index of Pinocchio's joint k
    back = np.argsort(perm)
    floating = robot["floating"]
    nj = len(names)

    def data(q, v):
        kw = dict(joint_positions=q[7:][back] if floating else q[back],
                  joint_velocities=(v[6:] if floating else v)[back], velocity_representation=VelRepr.Body)
        if floating:
            kw.update(base_position=q[:3], base_quaternion=jnp.concatenate([q[6:7], q[3:6]]),
                      base_linear_velocity=v[:3], base_angular_velocity=v[3:6])
        return js.data.JaxSimModelData.build(model=model, **kw)

    def joints(x):
        return (x[6:] if floating else x)[back]

    def fd(q, v, tau):
        base, s = js.model.forward_dynamics_aba(model, data(q, v), joint_forces=joints(tau))
        return jnp.concatenate([base, s[perm]]) if floating else s[perm]

    def A(q):
        M = js.model.free_floating_mass_matrix(model, data(q, jnp.zeros(nj + (6 if floating else 0), q.dtype)))
        idx = np.concatenate([np.arange(6), 6 + perm]) if floating else 6 + perm
        return M[idx][:, idx]

    def id_(q, v, a):
        kw = {"base_acceleration": a[:6]} if floating else {}
        base, s = js.model.inverse_dynamics(model, data(q, v), joint_accelerations=joints(a), **kw)
        return jnp.concatenate([base, s[perm]]) if floating else s[perm]

    vm = lambda f: jax.jit(jax.vmap(f))  # noqa: E731
    return Built({"fd": vm(fd), "A": vm(A), "id": vm(id_), "jac": jax_jacobian(fd, floating, robot["nv"])},
                 put=jax.device_put, fetch=np.asarray, ready=jax.block_until_ready, compiles=True)
