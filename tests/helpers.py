"""The tests' one helper module: robots and Pinocchio as their reference, building and compiling generated code,
routines as programs or SymPy, random states, integration, and checks of error messages.

Pinocchio as the reference for URDF models: the example-robot-data files, configurations, comparisons.

The package ``example-robot-data`` (>= 4.4) ships the robot files only; its Python loaders moved to
``example-robot-data-loaders``.  The files are found the way the package installs them: through the
distribution's own file list (``importlib.metadata``), which holds ``share/example-robot-data/robots/...``
under whatever prefix the wheel uses.
"""
from __future__ import annotations

import json
from functools import lru_cache
from importlib import metadata
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import aggsym
from aggsym.codegen.compile import CLibrary, compile_shared, import_module
from aggsym.codegen.generate import generate, write
from aggsym.contract import ROUTINES
from aggsym.core.backend import Symbolic
from aggsym.core.program import to_sympy
from aggsym.symbolic import coordinate_symbols
from aggsym.errors import ModelError
from aggsym.mechanics.bias import bias_vector, gravity_vector
from aggsym.mechanics.bound import bind
from aggsym.mechanics.elastic import elastic_forces
from aggsym.mechanics.inertia import inertia_matrix
from aggsym.mechanics.kinematics import TreeKinematics
from aggsym.mechanics.linalg import dot
from reference import NumericModel

# The files example-robot-data's loaders open for these robots (robots_loader.py: path, urdf_subpath, urdf_filename).
ROBOTS = {
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "double_pendulum": "double_pendulum_description/urdf/double_pendulum.urdf",
    "hyq": "hyq_description/robots/hyq_no_sensors.urdf",
    "solo12": "solo_description/robots/solo12.urdf",
    "anymal": "anymal_b_simple_description/robots/anymal.urdf",
    "talos": "talos_data/robots/talos_reduced.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
}
TOLERANCE = 1e-9


@lru_cache(maxsize=None)
def robots_directory() -> Path:
    """``share/example-robot-data/robots`` of the installed example-robot-data distribution."""
    dist = metadata.distribution("example-robot-data")
    for f in dist.files or ():
        if f.as_posix().endswith("share/example-robot-data/package.xml"):
            return Path(dist.locate_file(f)).parent / "robots"
    raise FileNotFoundError("example-robot-data is installed but lists no share/example-robot-data/package.xml")


def robot_path(name: str) -> Path:
    """The URDF file of one of :data:`ROBOTS`."""
    path = robots_directory() / ROBOTS[name]
    if not path.is_file():
        raise FileNotFoundError(path)
    return path


def free_root() -> "pin.JointModelComposite":
    """The root joint matching ``floating_base=True``: PX, PY, PZ, RX, RY, RZ in this order."""
    root = pin.JointModelComposite()
    for joint in (pin.JointModelPX(), pin.JointModelPY(), pin.JointModelPZ(), pin.JointModelRX(), pin.JointModelRY(),
                  pin.JointModelRZ()):
        root.addJoint(joint)
    return root


def pinocchio_model(path, floating_base: bool = False):
    """Pinocchio's model of a URDF file, fixed base or with :func:`free_root`."""
    if floating_base:
        return pin.buildModelFromUrdf(str(path), free_root())
    return pin.buildModelFromUrdf(str(path))


def pinocchio_q(pm, q) -> np.ndarray:
    """Pinocchio's configuration vector for our joint values q (continuous joints are (cos, sin))."""
    out = np.zeros(pm.nq)
    for j in range(1, pm.njoints):
        joint = pm.joints[j]
        v = q[joint.idx_v: joint.idx_v + joint.nv]
        if joint.nq == joint.nv:
            out[joint.idx_q: joint.idx_q + joint.nq] = v
        elif joint.nq == 2 and joint.nv == 1:  # unbounded revolute
            out[joint.idx_q: joint.idx_q + 2] = (np.cos(v[0]), np.sin(v[0]))
        else:
            raise ValueError(f"no conversion for Pinocchio joint {joint.shortname()}")
    return out


def joint_names(pm) -> list:
    """Pinocchio's joint names in q order, one per coordinate (the free root's six under its name)."""
    names = []
    for j in range(1, pm.njoints):
        names += [pm.names[j]] * pm.joints[j].nv
    return names


def relative_error(ours, theirs, floor: float = 1e-300) -> float:
    """max |ours - theirs| relative to the largest entry of theirs, or to ``floor`` when that is larger (for
    references that can vanish, e.g. dM/dt of a chain whose inertia does not change: floor = max|M| max|qd|)."""
    theirs = np.asarray(theirs)
    return float(np.abs(np.asarray(ours) - theirs).max() / max(np.abs(theirs).max(), floor))


def has_composite_joint(pm) -> bool:
    return any(pm.joints[j].shortname() == "JointModelComposite" for j in range(1, pm.njoints))


def crba(pm, Q) -> np.ndarray:
    """Pinocchio's M(Q), both triangles (crba fills the upper one)."""
    M = pin.crba(pm, pm.createData(), Q)
    return np.triu(M) + np.triu(M, 1).T


def inertia_rate(pm, Q, v) -> tuple:
    """dM/dt along v and the relative tolerance to compare with it.

    From Pinocchio's computeCoriolisMatrix Cp: dM/dt = Cp + Cp^T (its Cp has dM/dt - 2 Cp skew).  Pinocchio 4.1's
    computeCoriolisMatrix is wrong on composite joints (the floating root of :func:`free_root`: its Cp + Cp^T
    differs from the rate of its own crba by a few per cent), so there dM/dt is the central difference of crba
    along v (relative error about 1e-10, compared to 1e-7).  A Coriolis matrix is not unique, but C qd = b and
    C + C^T = dM/dt pin down the class with the skew property (A' - 2C skew is C + C^T = A', A' symmetric)."""
    if has_composite_joint(pm):
        h = 1e-6
        return (crba(pm, pin.integrate(pm, Q, h * v)) - crba(pm, pin.integrate(pm, Q, -h * v))) / (2 * h), 1e-7
    Cp = pin.computeCoriolisMatrix(pm, pm.createData(), Q, v)
    return Cp + Cp.T, TOLERANCE


def compare(model, pm, rng, states: int = 3, tolerance: float = TOLERANCE) -> float:
    """Assert A, b + g, g and inverse dynamics equal Pinocchio's on random states, and that the Coriolis matrix C has
    C qd = b and C + C^T = dM/dt (:func:`inertia_rate`); returns the largest error."""
    assert model.nq == pm.nv
    twin = aggsym.NumericTwin(model)
    data = pm.createData()
    worst = 0.0
    for _ in range(states):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        qd, qdd = rng.normal(size=model.nq), rng.normal(size=model.nq)
        Q = pinocchio_q(pm, q)
        M = pin.crba(pm, data, Q)
        M = np.triu(M) + np.triu(M, 1).T  # crba fills the upper triangle
        errors = {
            "A vs crba": relative_error(twin.inertia(q), M),
            "b + g vs nonLinearEffects": relative_error(twin.bias(q, qd) + twin.gravity(q),
                                                        pin.nonLinearEffects(pm, data, Q, qd)),
            "g vs computeGeneralizedGravity": relative_error(twin.gravity(q),
                                                             pin.computeGeneralizedGravity(pm, data, Q)),
            "inverse_dynamics vs rnea": relative_error(twin.inverse_dynamics(q, qd, qdd),
                                                       pin.rnea(pm, data, Q, qd, qdd)),
        }
        if not model.time_dependent:
            C = twin.coriolis(q, qd)
            errors["C qd vs nonLinearEffects - g"] = relative_error(
                C @ qd, pin.nonLinearEffects(pm, data, Q, qd) - pin.computeGeneralizedGravity(pm, data, Q),
                floor=np.abs(M).max() * np.abs(qd).max() ** 2)
            Mdot, rate_tolerance = inertia_rate(pm, Q, qd)
            error = relative_error(C + C.T, Mdot, floor=np.abs(M).max() * np.abs(qd).max())
            assert error <= rate_tolerance, f"{model.name}: C + C^T vs dM/dt: relative error {error:.3g} at q={q.tolist()}"
        for what, error in errors.items():
            assert error <= tolerance, f"{model.name}: {what}: relative error {error:.3g} at q={q.tolist()}"
        worst = max(worst, *errors.values())
    return worst


# --------------------------------------------------------------------------------------------------------------
# generated code


def generated_code(model, folder: Path, opt: str = "-O2", c: bool = True, scalar: str = "double"):
    """Generate a model's files into ``folder``, compile its C (``opt``; -Werror flags, and -Wdouble-promotion
    -Wfloat-conversion for ``scalar="float"``) and import its NumPy module: (C library or None, NumPy module,
    manifest)."""
    write(generate(model, latex=False, scalar=scalar), folder)
    manifest = json.loads((folder / f"{model.name}.json").read_text())
    lib = None
    if c:
        lib = CLibrary(compile_shared(folder / f"{model.name}.c", folder / f"lib{model.name}.so", extra=(opt,),
                                      scalar=scalar), manifest)
    return lib, import_module(folder / f"{model.name}.py"), manifest


# --------------------------------------------------------------------------------------------------------------
# routines as programs and as SymPy


def routine_program(model, role):
    """(program, outputs): the routine's straight-line program and its outputs (lists of nodes or constants)."""
    routine = ROUTINES[role]
    back = Symbolic()
    prog = back.program
    bound = bind(model, back)
    ins = {n: prog.vector(n, model.nq) for n in routine.inputs if n != "p"}
    return prog, routine.build(bound, TreeKinematics(bound, ins["q"]), ins)


def routine_sympy(model, role):
    """The outputs of a routine as SymPy expressions in the symbols of aggsym.equations."""
    prog, outs = routine_program(model, role)
    q, qd, _ = coordinate_symbols(model)
    symbols = {("p", i): s for i, s in enumerate(model.parameter_symbols)}
    symbols.update({("q", i): s for i, s in enumerate(q)})
    symbols.update({("qd", i): s for i, s in enumerate(qd)})
    return [to_sympy(prog, out, symbols) for out in outs]


def inverse_dynamics_by_equations(bound, kin, qd, qdd):
    """A(q) qdd + b(q, qd) + g(q) + C (q - q0) from the assembled equations (2.17), (2.27), (2.29): a cross-check
    of the sweeps."""
    A = inertia_matrix(bound, kin)
    b = bias_vector(bound, kin, qd)
    g = gravity_vector(bound, kin)
    c = elastic_forces(bound, kin.q)
    return [dot(A[i], qdd) + b[i] + g[i] + c[i] for i in range(len(b))]


# --------------------------------------------------------------------------------------------------------------
# states, integration, messages


def states(model, rng, n):
    """n random (q, qd, qdd): angles in [-pi, pi], rates and accelerations standard normal."""
    for _ in range(n):
        yield (rng.uniform(-np.pi, np.pi, model.nq), rng.normal(size=model.nq), rng.normal(size=model.nq))


def rk4_step(f, q, v, dt):
    """One classical RK4 step of q'' = f(q, q'): the new (q, q')."""
    k1q, k1v = v, f(q, v)
    k2q, k2v = v + dt / 2 * k1v, f(q + dt / 2 * k1q, v + dt / 2 * k1v)
    k3q, k3v = v + dt / 2 * k2v, f(q + dt / 2 * k2q, v + dt / 2 * k2v)
    k4q, k4v = v + dt * k3v, f(q + dt * k3q, v + dt * k3v)
    return q + dt / 6 * (k1q + 2 * k2q + 2 * k3q + k4q), v + dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)


def assert_model_error(path, where: str, words) -> ModelError:
    """Loading ``path`` fails with a ModelError at ``where`` whose message names the file and line and holds every
    one of ``words``."""
    with pytest.raises(ModelError) as info:
        aggsym.load(path)
    err = info.value
    assert err.where == where, str(err)
    assert err.line is not None and str(err).startswith(f"{path}:{err.line}:")
    for w in words:
        assert w in str(err), str(err)
    return err


def pinocchio_tree(model):
    """The model as a Pinocchio model, one joint per coordinate (multi-coordinate pairs as chains of joints with
    massless frames between, variant 1 of the book; welded bodies appended to their parent's joint).  The first
    joint of a pair is placed at SE3(R0, p) of the constructive configuration, so its frame after the joint
    motion is our body frame; inertias are given in it.  Returns the model and, per body, the index of the joint
    whose frame is the body frame (the parent's joint for a welded body, with the body's placement in it).
    Each body is also a Pinocchio frame of its name (for frame Jacobians, constraints)."""
    nm = NumericModel(model)
    pm = pin.Model()
    pm.gravity = pin.Motion(np.concatenate([nm.gravity, np.zeros(3)]))
    frame = []  # per body: (joint id, placement of the body frame in that joint's frame)
    kinds = {0: pin.JointModelPX, 1: pin.JointModelPY, 2: pin.JointModelPZ,
             3: pin.JointModelRX, 4: pin.JointModelRY, 5: pin.JointModelRZ}
    for b, body in zip(nm.bodies, model.bodies):
        parent, above = (0, pin.SE3.Identity()) if b["parent"] < 0 else frame[b["parent"]]
        placement = above * pin.SE3(b["R0"], b["p"])
        for j, (_, axis) in enumerate(b["coords"]):
            name = body.pair.name if j == len(b["coords"]) - 1 else f"{body.pair.name}_{j}"
            parent = pm.addJoint(parent, kinds[axis](), placement, name)
            placement = pin.SE3.Identity()
        frame.append((parent, placement))
        inertia = pin.Inertia(b["m"], b["c"], b["I"]) if "m" in b else pin.Inertia.Zero()
        pm.appendBodyToJoint(parent, inertia, placement)
        pm.addFrame(pin.Frame(body.name, parent, placement, pin.FrameType.OP_FRAME))
    assert pm.nq == model.nq
    joint_of = [j for j, _ in frame]
    return pm, joint_of


# --------------------------------------------------------------------------------------------------------------
# a robot with <mimic> joints


# an arm with a two-finger hand: finger_right mimics finger_left, the fingertip mimics the wrist
GRIPPER = """<robot name="gripper">
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="0.2 0 0.01" rpy="0.1 0 0"/><mass value="2"/>
    <inertia ixx="0.01" iyy="0.05" izz="0.05" ixy="0.001" ixz="0" iyz="0"/></inertial></link>
  <link name="palm"><inertial><origin xyz="0.05 0 0"/><mass value="0.6"/>
    <inertia ixx="0.002" iyy="0.003" izz="0.003" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="left"><inertial><origin xyz="0.02 0.01 0"/><mass value="0.1"/>
    <inertia ixx="0.0001" iyy="0.0002" izz="0.0002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="right"><inertial><origin xyz="0.02 -0.01 0"/><mass value="0.1"/>
    <inertia ixx="0.0001" iyy="0.0002" izz="0.0002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip"><inertial><origin xyz="0.01 0 0"/><mass value="0.05"/>
    <inertia ixx="0.00001" iyy="0.00002" izz="0.00002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="wrist" type="revolute"><parent link="arm"/><child link="palm"/><origin xyz="0.4 0 0" rpy="0 0.3 0"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="finger_left" type="prismatic"><parent link="palm"/><child link="left"/><origin xyz="0.1 0.02 0"/>
    <axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/></joint>
  <joint name="finger_right" type="prismatic"><parent link="palm"/><child link="right"/><origin xyz="0.1 -0.02 0"/>
    <axis xyz="0 -1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/>
    <mimic joint="finger_left" multiplier="1" offset="0"/></joint>
  <joint name="tip_joint" type="revolute"><parent link="left"/><child link="tip"/><origin xyz="0.03 0 0"/>
    <axis xyz="0.6 0 0.8"/><limit lower="-1" upper="1" effort="1" velocity="1"/>
    <mimic joint="wrist" multiplier="-0.7" offset="0.2"/></joint>
</robot>
"""


def coupled_gripper(folder: Path):
    """(model loaded with mimic="couple", URDF path) of :data:`GRIPPER` written into ``folder``."""
    path = folder / "gripper.urdf"
    path.write_text(GRIPPER)
    model = aggsym.load(path, mimic="couple")
    assert model.couplings
    return model, path


def reduction(model):
    """J and o of q_tree = J q + o for a coupled model (tree order = Pinocchio's order of the full model)."""
    index = {c.name: i for i, c in enumerate(model.pair_coordinates)}
    free = [index[c.name] for c in model.coordinates]
    J = np.zeros((len(index), len(free)))
    o = np.zeros(len(index))
    for j, t in enumerate(free):
        J[t, j] = 1
    for c in model.couplings:
        J[index[c.coordinate], free.index(index[c.master])] = c.multiplier
        o[index[c.coordinate]] = c.offset
    return J, o
