"""MuJoCo itself as the reference of the MJCF reader: A, the velocity and gravity terms with the passive forces,
and the forward dynamics of aggsym's numeric twin against ``mj_fullM``, ``qfrc_bias - qfrc_passive`` and
``qacc`` of ``mj_forward``, at random states and forces.

MuJoCo runs with its constraints (contacts, joint limits, equalities, frictionloss) and its actuators disabled and
fluid forces set to zero (none of them is in the equations of motion); the model's own armature, damping, springs
and gravity (and their disable flags) are kept.  A free joint's velocity is converted as the reader's convention
says (``aggsym.model.readers.mjcf_reader.CONVENTION``): with J = I except R (the body's rotation) on each free joint's
linear velocity, qvel = J v, MuJoCo's qacc = J qdd + c (c = R (w x v) on the free linear rows), so
A = J^T M J, d = J^T (M c + qfrc_bias - qfrc_passive), tau = J^T qfrc_applied.  A ball joint's quaternion is
reordered (MuJoCo's w x y z to aggsym's x y z w); its velocity, force and acceleration are MuJoCo's.
"""
from __future__ import annotations

import numpy as np

from aggsym.contract import ROUTINES
from aggsym.mechanics.passive import has_passive
from aggsym.model.readers.mjcf_reader import BALL, FREE


def _quat(rng):
    v = rng.normal(size=4)
    return v / np.linalg.norm(v)


def states(m, rng):
    """A random MuJoCo (qpos, qvel, force): hinge and slide positions uniform in [-pi, pi], free joints a random
    position and unit quaternion, ball joints a random unit quaternion; velocities and forces normal."""
    qpos = rng.uniform(-np.pi, np.pi, m.nq)
    for j in range(m.njnt):
        if m.jnt_type[j] == FREE:
            a = m.jnt_qposadr[j]
            qpos[a + 3:a + 7] = _quat(rng)
        elif m.jnt_type[j] == BALL:
            a = m.jnt_qposadr[j]
            qpos[a:a + 4] = _quat(rng)
    return qpos, rng.normal(size=m.nv), rng.normal(size=m.nv) * 3


def to_aggsym(m, qpos, qvel, force):
    """(q, qd, tau, J, c-builder) in aggsym's convention from MuJoCo's."""
    import mujoco

    q, qd, tau = [], qvel.copy(), force.copy()
    J = np.eye(m.nv)
    free = []
    for j in range(m.njnt):
        a, d = m.jnt_qposadr[j], m.jnt_dofadr[j]
        if m.jnt_type[j] == FREE:
            w, x, y, z = qpos[a + 3:a + 7]
            R = np.zeros(9)
            mujoco.mju_quat2Mat(R, qpos[a + 3:a + 7])
            R = R.reshape(3, 3)
            J[d:d + 3, d:d + 3] = R
            qd[d:d + 3] = R.T @ qvel[d:d + 3]
            tau[d:d + 3] = R.T @ force[d:d + 3]
            q.extend([*qpos[a:a + 3], x, y, z, w])
            free.append((d, R))
        elif m.jnt_type[j] == BALL:
            w, x, y, z = qpos[a:a + 4]
            q.extend([x, y, z, w])
        else:
            q.append(qpos[a])
    c = np.zeros(m.nv)
    for d, R in free:
        c[d:d + 3] = R @ np.cross(qd[d + 3:d + 6], qd[d:d + 3])
    return np.array(q), qd, tau, J, c


class couplings:
    """A model's couplings on MuJoCo's arrays (hinge and slide joints, no free joint: q = qpos, qd = qvel):
    ``keep`` the dofs that stay in q, ``Jc`` (nv x len(keep)) with qvel = Jc qd, ``C`` the rows e_d - k e_m
    (C qvel = 0)."""

    def __init__(self, m, model):
        import mujoco

        if m.nq != m.nv:
            raise ValueError("couplings beside free or ball joints are not compared here")
        joint = {c.name: c.joint for c in model.pair_coordinates}
        dof = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j): int(m.jnt_dofadr[j]) for j in range(m.njnt)}
        self.ties = [(dof[joint[c.coordinate]], dof[joint[c.master]], c.multiplier, c.offset) for c in model.couplings]
        coupled = {d for d, _, _, _ in self.ties}
        self.keep = np.array([i for i in range(m.nv) if i not in coupled])
        self.Jc = np.zeros((m.nv, len(self.keep)))
        self.Jc[self.keep, np.arange(len(self.keep))] = 1.0
        self.C = np.zeros((len(self.ties), m.nv))
        for r, (d, master, k, _) in enumerate(self.ties):
            self.Jc[d] = k * self.Jc[master]  # (a master is never coupled itself: the reader refuses chains)
            self.C[r, d], self.C[r, master] = 1.0, -k

    def state(self, qpos, qvel, force):
        qpos, force = qpos.copy(), force.copy()
        for d, master, k, offset in self.ties:
            qpos[d] = k * qpos[master] + offset
            force[d] = 0.0
        return qpos, self.Jc @ qvel[self.keep], force

    def kkt(self, A, rhs):
        """q's part of qdd from [A C^T; C 0] [qdd; -lambda] = [rhs; 0]."""
        k = len(self.C)
        x = np.linalg.solve(np.block([[A, self.C.T], [self.C, np.zeros((k, k))]]), np.concatenate([rhs, np.zeros(k)]))
        return x[self.keep]


def compiled(source):
    """MuJoCo's model of ``source``: an MJCF file's path (compiled, its warnings silenced: the reader has issued
    them; no log file in the working folder), or an ``MjModel`` (a copy: :func:`mujoco_model` changes it)."""
    import copy

    import mujoco

    if isinstance(source, mujoco.MjModel):
        return copy.deepcopy(source)
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda text: None)
    try:
        return mujoco.MjModel.from_xml_path(str(source))
    finally:
        mujoco.set_mju_user_warning(previous)


def routine_models(model) -> list:
    """The model as read and the internal models the generated routines of the coordinates alone may be built from
    (:func:`aggsym.codegen.generate.internal_model` chooses one of the two of :func:`aggsym.model.transforms.reframe.reframe`
    by operation count), each compared with MuJoCo: a frame chosen wrongly there reaches A without reaching the
    model as read."""
    from aggsym.model.transforms.reframe import reframe

    out = [model]
    for fewest in (False, True):
        inner = reframe(model, fewest=fewest)
        if inner is not model:
            out.append(inner)
    return out


class Module:
    """A generated NumPy (or JAX, PyTorch) module as an evaluator of :func:`compare`: ``call(role, *inputs)``."""

    def __init__(self, module):
        self.module = module

    def call(self, role: str, *args):
        return np.asarray(getattr(self.module, role)(*args), dtype=float)


def mujoco_model(path, fluid: bool = False):
    """The compiled model with constraints and actuation disabled and no fluid unless ``fluid`` (the comparison's
    MuJoCo: the fluid kept where aggsym's model holds it); ``path`` an MJCF file or an ``MjModel`` (:func:`compiled`)."""
    import mujoco

    m = compiled(path)
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT) | int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
    if not fluid:
        m.opt.density = 0.0
        m.opt.viscosity = 0.0
    return m


def reference_terms(m, data, qpos, qvel, force) -> tuple:
    """MuJoCo's forward at (qpos, qvel, qfrc_applied = force, no control), and its terms in aggsym's coordinates:
    (M, (q, qd, tau, J, c) of :func:`to_aggsym`, A = J^T M J, d = J^T (M c + qfrc_bias - qfrc_passive))."""
    import mujoco

    data.qpos[:], data.qvel[:], data.qfrc_applied[:] = qpos, qvel, force
    data.ctrl[:] = 0
    mujoco.mj_forward(m, data)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, data, M)
    converted = to_aggsym(m, qpos, qvel, force)
    J, c = converted[3], converted[4]
    return M, converted, J.T @ M @ J, J.T @ (M @ c + data.qfrc_bias - data.qfrc_passive)


def compare(path, model=None, samples: int = 3, seed: int = 0, internal: bool = True, evaluators=()) -> dict:
    """The largest relative differences {A, d, qdd, passive} over ``samples`` random states: max |aggsym - MuJoCo|
    over max |MuJoCo| of each quantity; A, d and qdd of the model as read and (``internal``) of each of its
    internal models (:func:`routine_models`).  ``path``: the MJCF file, or an ``MjModel`` with ``model`` its
    aggsym model (:func:`aggsym.model.readers.mjcf_reader.read_compiled`).  ``evaluators``: more objects whose
    ``call(role, *inputs)`` evaluates the routines (the generated code: :class:`aggsym.codegen.compile.CLibrary`,
    :class:`Module`), compared as the twin is, passive forces included."""
    import mujoco

    from aggsym.model import load
    from aggsym.twin import NumericTwin

    model = load(path) if model is None else model
    twin = NumericTwin(model)
    internal = [NumericTwin(inner) for inner in routine_models(model)[1:]] if internal else []
    m = mujoco_model(path, fluid=model.has_fluid)
    data = mujoco.MjData(m)
    rng = np.random.default_rng(seed)
    worst = {"A": 0.0, "d": 0.0, "qdd": 0.0, "passive": 0.0}
    coupled = couplings(m, model) if model.couplings else None
    for _ in range(samples):
        qpos, qvel, force = states(m, rng)
        if coupled is not None:  # a state where the couplings hold, no force on the coupled coordinates
            qpos, qvel, force = coupled.state(qpos, qvel, force)
        M, (q, qd, tau, J, c), A_ref, d_ref = reference_terms(m, data, qpos, qvel, force)
        if coupled is not None:  # q's coordinates; the reference: the hard coupling solved densely (KKT)
            qacc_ref = coupled.kkt(A_ref, tau - d_ref)
            A_ref, d_ref = coupled.Jc.T @ A_ref @ coupled.Jc, coupled.Jc.T @ d_ref
            q, qd, tau = q[coupled.keep], qd[coupled.keep], tau[coupled.keep]
        else:
            qacc_ref = data.qacc
        for each in [twin] + internal + list(evaluators):
            qacc = each.call("forward_dynamics", q, qd, tau)
            qacc = qacc if coupled is not None else J @ qacc + c
            A = each.call("inertia", q)
            d = each.call("nonlinear_effects", q, qd)
            for key, mine, ref in (("A", A, A_ref), ("d", d, d_ref), ("qdd", qacc, qacc_ref)):
                worst[key] = max(worst[key], float(np.max(np.abs(mine - ref)) / max(np.max(np.abs(ref)), 1e-300)))
        if has_passive(model):
            ref = J.T @ data.qfrc_passive
            if coupled is not None:
                ref = coupled.Jc.T @ ref
            for each in [twin] + list(evaluators):
                mine = (each.call("passive_forces", q, qd) if ROUTINES["passive_forces"].exists_for(model) else
                        -each.call("elastic", q))
                worst["passive"] = max(worst["passive"], float(np.max(np.abs(mine - ref)) /
                                                               max(np.max(np.abs(ref)), 1e-300)))
    return worst


def equality_model(path, fluid: bool = False):
    """The compiled model with only its equalities active (contacts, limits, frictionloss and actuation disabled, no
    fluid unless ``fluid``) and a dense constraint Jacobian: MuJoCo's ``efc_J`` rows of type equality are J."""
    import mujoco

    m = mujoco_model(path, fluid)
    m.opt.disableflags &= ~(int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT) | int(mujoco.mjtDisableBit.mjDSBL_EQUALITY))
    m.opt.disableflags |= (int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_LIMIT) |
                           int(mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS))
    m.opt.jacobian = int(mujoco.mjtJacobian.mjJAC_DENSE)
    return m


def equality_jacobian(m, data, qpos):
    """MuJoCo's rows of the active equalities at qpos (efc_J of type equality, nv columns)."""
    import mujoco

    data.qpos[:] = qpos
    data.qvel[:] = 0
    mujoco.mj_forward(m, data)
    J = np.array(data.efc_J[:data.nefc * m.nv]).reshape(data.nefc, m.nv)
    return J[np.array(data.efc_type[:data.nefc]) == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)]


def compare_constrained(path, model=None, samples: int = 3, seed: int = 0, step: float = 1e-5) -> dict:
    """The hard equalities against a dense KKT solve from MuJoCo's own data: the largest relative differences
    {A, J, qdd, lambda} over ``samples`` random states.  A is ``mj_fullM``; J MuJoCo's equality rows (``efc_J``,
    in aggsym's velocity convention); gamma = J' qd by central differences of MuJoCo's J along qd (0 for linear rows);
    the reference solves [A J^T; J 0] [qdd; -lambda] = [tau - d; -gamma] with d = qfrc_bias - qfrc_passive, and is
    compared with aggsym's constrained_forward_dynamics (J and lambda where every constraint is a joint-space row, which
    aggsym writes as MuJoCo does and in its order; qdd always, since it does not depend on how the rows are written:
    a connect's or weld's rows are in other axes than MuJoCo's).  MuJoCo's own qacc is not the reference: its
    equalities are soft."""
    import mujoco

    from aggsym.model import load
    from aggsym.twin import NumericTwin

    model = load(path) if model is None else model
    twin = NumericTwin(model)
    free = mujoco_model(path, fluid=model.has_fluid)
    m = equality_model(path, fluid=model.has_fluid)
    d_free, d_eq = mujoco.MjData(free), mujoco.MjData(m)
    rng = np.random.default_rng(seed)
    worst = {"A": 0.0, "J": 0.0, "qdd": 0.0, "lambda": 0.0}

    def rel(mine, ref):
        return float(np.max(np.abs(mine - ref)) / max(np.max(np.abs(ref)), 1e-300))

    for _ in range(samples):
        qpos, qvel, force = states(free, rng)
        M, (q, qd, tau, Jm, c), A_ref, d_ref = reference_terms(free, d_free, qpos, qvel, force)
        Jq = equality_jacobian(m, d_eq, qpos)
        ahead, behind = qpos.copy(), qpos.copy()
        mujoco.mj_integratePos(m, ahead, qvel, step)
        mujoco.mj_integratePos(m, behind, qvel, -step)
        gamma = (equality_jacobian(m, d_eq, ahead) - equality_jacobian(m, d_eq, behind)) @ qvel / (2 * step)
        J_ref = Jq @ Jm  # (MuJoCo's rows in aggsym's velocities; gamma: the free rows' J c is in it through M c)
        gamma = gamma + Jq @ c
        k = len(J_ref)
        K = np.block([[A_ref, J_ref.T], [J_ref, np.zeros((k, k))]])
        x = np.linalg.solve(K, np.concatenate([tau - d_ref, -gamma]))
        qdd, lam = twin.call("constrained_forward_dynamics", q, qd, tau)  # (raises when G is singular)
        J = np.array(twin.call("constraint_jacobian", q)).reshape(model.constraint_rows, model.nv)
        worst["A"] = max(worst["A"], rel(twin.call("inertia", q), A_ref))
        worst["qdd"] = max(worst["qdd"], rel(qdd, x[:m.nv]))
        if all(con.joint_row is not None for con in model.constraints):  # rows as MuJoCo writes them, in order
            worst["J"] = max(worst["J"], rel(J, J_ref))
            worst["lambda"] = max(worst["lambda"], rel(lam, -x[m.nv:]))
    return worst
