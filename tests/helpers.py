"""The tests' helpers that need no Pinocchio: the example-robot-data files, comparisons, building and compiling
generated code, routines as programs or SymPy, random states, integration, and checks of error messages.

Pinocchio as the reference (its models of URDF files and of our models, configurations, comparisons) is in
``pinocchio_reference.py``, so that this module, and every test that needs no Pinocchio, imports where Pinocchio is
not installed.

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


def relative_error(ours, theirs, floor: float = 1e-300) -> float:
    """max |ours - theirs| relative to the largest entry of theirs, or to ``floor`` when that is larger (for
    references that can vanish, e.g. dM/dt of a chain whose inertia does not change: floor = max|M| max|qd|)."""
    theirs = np.asarray(theirs)
    return float(np.abs(np.asarray(ours) - theirs).max() / max(np.abs(theirs).max(), floor))


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


def central_differences(f, x, h=1e-6):
    """d f / d x (f: a vector to an array) by central differences, the direction last."""
    x = np.asarray(x, dtype=float)
    return np.stack([(np.asarray(f(x + h * e)) - np.asarray(f(x - h * e))) / (2 * h) for e in np.eye(x.size)],
                    axis=-1)


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


# a ball pair's quaternion in the middle of q (hinge, ball, hinge: nq = 6, nv = 5), masses over six decades
BALL_BETWEEN_HINGES = """
name: ball_between_hinges
gravity: [0.0, 0.0, -9.81]
bodies:
  - name: hub
    parent: world
    pair: {name: turn, translation: [0.03125, -0.01, 0.45], rotation: [[1, 0.21837]], functional: {theta6: q_turn}}
    mass: 350.0
    com: [0.012, 0.004, 0.11]
    inertia: {xx: 4.1, yy: 3.7, zz: 2.2, xz: 0.03}
  - name: link
    parent: hub
    pair: {name: socket, type: ball, translation: [0.0, 0.17, 0.3], rotation: [[2, -1.05713], [3, 0.33871]]}
    mass: 0.85
    com: [-0.02, 0.07, -0.31]
    inertia: {xx: 0.011, yy: 0.013, zz: 0.0045, xy: 0.0004}
  - name: tip
    parent: link
    pair: {name: wrist, translation: [0.01, 0, -0.62], rotation: [[3, 2.46109]], functional: {theta5: q_wrist}}
    mass: 0.00035
    com: [0.004, 0.001, -0.01]
    inertia: {xx: 0.000000021, yy: 0.000000034, zz: 0.000000018}
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
