"""The tests' helpers that need no Pinocchio: the example-robot-data files, comparisons, building and compiling
generated code, routines as programs or SymPy, random states, integration, consistent states of constrained models,
the command line run in this process, checks of error messages, and the files of tests/data (the gripper with
<mimic> joints and the ball between hinges among them).  Small URDF robots written from their numbers are in
``robot_builder.py``.

Pinocchio as the reference (its models of URDF files and of our models, configurations, comparisons) is in
``pinocchio_reference.py``, so that this module, and every test that needs no Pinocchio, imports where Pinocchio is
not installed.

The package ``example-robot-data`` (>= 4.4) ships the robot files only; its Python loaders moved to
``example-robot-data-loaders``.  The files are found the way the package installs them: through the
distribution's own file list (``importlib.metadata``), which holds ``share/example-robot-data/robots/...``
under whatever prefix the wheel uses.
"""
from __future__ import annotations

import io
import json
from contextlib import redirect_stderr, redirect_stdout
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
    write(generate(model, targets="c,numpy,manifest", scalar=scalar), folder)
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
# states, integration, the command line, messages


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


def rk4_step_in_time(f, t, q, v, dt):
    """One classical RK4 step of q'' = f(t, q, q') from time t: the new (q, q') at t + dt."""
    k1q, k1v = v, f(t, q, v)
    k2q, k2v = v + dt / 2 * k1v, f(t + dt / 2, q + dt / 2 * k1q, v + dt / 2 * k1v)
    k3q, k3v = v + dt / 2 * k2v, f(t + dt / 2, q + dt / 2 * k2q, v + dt / 2 * k2v)
    k4q, k4v = v + dt * k3v, f(t + dt, q + dt * k3q, v + dt * k3v)
    return q + dt / 6 * (k1q + 2 * k2q + 2 * k3q + k4q), v + dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)


def consistent_state(system, q, qd, steps: int = 50, tolerance: float = 1e-15):
    """(q, qd) on the constraints of ``system`` (anything with constraint_residual and constraint_jacobian of q: a
    twin, a generated module): Newton on phi(q) = 0 from q (least-squares steps, at most ``steps``, until
    max|phi| < ``tolerance``), then qd projected on the null space of J."""
    for _ in range(steps):
        phi = system.constraint_residual(q)
        if np.abs(phi).max() < tolerance:
            break
        q = q - np.linalg.lstsq(system.constraint_jacobian(q), phi, rcond=None)[0]
    J = system.constraint_jacobian(q)
    return q, qd - np.linalg.lstsq(J, J @ qd, rcond=None)[0]


def run_cli(args):
    """(exit code, stderr) of ``aggsym ARGS`` run in this process, its stdout swallowed."""
    from aggsym import cli

    err = io.StringIO()
    with redirect_stderr(err), redirect_stdout(io.StringIO()):
        code = cli.main(args)
    return code, err.getvalue()


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
# files: the robots of tests/data, a file written


DATA = Path(__file__).resolve().parent / "data"


def data_text(name: str) -> str:
    """The text of ``tests/data/NAME`` (a robot or model file that tests read, edit or copy)."""
    return (DATA / name).read_text()


def written(path: Path, content) -> Path:
    """``path`` once ``content`` (text, or bytes) is written into it."""
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    return path


# --------------------------------------------------------------------------------------------------------------
# robots that several modules use: a gripper with <mimic> joints, a ball pair between hinges


# an arm with a two-finger hand: finger_right mimics finger_left, the fingertip mimics the wrist
GRIPPER = data_text("gripper.urdf")
# a ball pair's quaternion in the middle of q (hinge, ball, hinge: nq = 6, nv = 5), masses over six decades
BALL_BETWEEN_HINGES = data_text("ball_between_hinges.yaml")


def coupled_gripper(folder: Path):
    """(model loaded with mimic="couple", URDF path) of :data:`GRIPPER` written into ``folder``."""
    path = written(folder / "gripper.urdf", GRIPPER)
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
