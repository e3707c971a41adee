"""The entries of the batched benchmark (:mod:`benchmarks.batch.orchestrator`): each one's four routines over a batch
of states, in Pinocchio's conventions, in the framework it runs in.

Every entry takes and returns what Pinocchio's free-flyer takes and returns: q = (position, quaternion x y z w,
joints) with nq = n + 7 (a fixed base: the joints alone), v = (base velocity and angular velocity in the base's
own axes, joint rates), tau and the acceleration over the same nv entries; the joints in Pinocchio's order.
The routines (:data:`ROUTINES`):

    fd   forward dynamics (q, v, tau) -> a                      (B, nv)
    A    the inertia matrix (q,) -> A(q)                        (B, nv, nv)
    id   inverse dynamics (q, v, a) -> tau                      (B, nv)
    jac  the Jacobian of forward dynamics (q, v, tau) -> [da/dq, da/dv]     (B, nv, 2 nv)

da/dq is taken in Pinocchio's tangent space, as ``computeABADerivatives`` gives it: the derivative at delta = 0
of a(q (+) delta, v, tau), where (+) moves the base as M exp(delta).  Every peer differentiated by a framework
(jacfwd, jacrev, autograd) is differentiated through :func:`retract`, a map that agrees with Pinocchio's
``integrate`` to first order at delta = 0 (the base's position moved by R delta_v, its quaternion multiplied by
(delta_w / 2, 1) and normalized, the joints added): its derivative there is the exponential's, so the Jacobian is
exactly the tangent-space one.  A peer whose own state differs from Pinocchio's (MuJoCo's free joint: the base's
linear velocity in world axes, its acceleration the derivative of that; quaternions w x y z; its own joint
order) is converted inside the timed function, both ways (:class:`_MjxConvention`); the converted function is
what is differentiated.

An entry is built by :func:`build` in the worker process (:mod:`benchmarks.batch.worker`), which imports the
framework; nothing here imports a framework at module level, so the orchestrator and the unit tests import
:data:`ENTRIES` without the peers' environment.
"""
from __future__ import annotations

import importlib.util
import sys
from dataclasses import dataclass, field
from pathlib import Path

ROUTINES = ("fd", "A", "id", "jac")
# name -> (label, framework, routines, how the Jacobian is taken)
ENTRIES = {
    "aggsym_jax": ("aggsym JAX", "jax", ROUTINES,
                   "jax.jacfwd through forward_dynamics, which carries the generated derivative routine as its "
                   "custom derivative"),
    "aggsym_jax_plain": ("aggsym JAX plain jacfwd", "jax", ("jac",),
                         "jax.jacfwd traced through the straight line (the module generated without the derivative "
                         "routine)"),
    "aggsym_jax_routine": ("aggsym JAX derivative routine", "jax", ("jac",),
                           "forward_dynamics_derivatives called directly (jit)"),
    "aggsym_jax_project": ("aggsym JAX, the project's jax", "jax", ROUTINES,
                           "as aggsym JAX (the custom JVP), in the project's venv"),
    "aggsym_jax_rev": ("aggsym JAX jacrev", "jax", ("jac",),
                       "jax.jacrev through forward_dynamics: JAX transposes the custom JVP, whose derivative matrices "
                       "are made once and applied to the nv cotangents (jacfwd pushes 2 nv tangents)"),
    "aggsym_jax_project_rev": ("aggsym JAX jacrev, the project's jax", "jax", ("jac",),
                               "as aggsym JAX jacrev, in the project's venv"),
    "aggsym_torch": ("aggsym PyTorch", "torch", ROUTINES,
                     "torch.autograd.grad through forward_dynamics (its analytic autograd.Function: the first pass "
                     "makes the derivative matrices, the others reuse them), one reverse pass per output over the "
                     "whole batch"),
    "aggsym_jax_kernels": ("aggsym JAX kernels", "jax", ROUTINES,
                           "the module generated with --targets c,jax: every routine its batch kernel (an XLA "
                           "foreign-function call, one thread); jax.jacfwd through forward_dynamics, whose custom "
                           "JVP calls the derivative routines' kernels"),
    "aggsym_jax_kernels_rev": ("aggsym JAX kernels jacrev", "jax", ("jac",),
                               "as aggsym JAX kernels, by jax.jacrev (the custom JVP transposed)"),
    "aggsym_jax_kernels_all": ("aggsym JAX kernels, all cores", "jax", ROUTINES,
                               "as aggsym JAX kernels, the batch split across every core (AGGSYM_THREADS)"),
    "aggsym_torch_kernels": ("aggsym PyTorch kernels", "torch", ROUTINES,
                             "the module generated with --targets c,torch: every routine its batch kernel (a "
                             "torch.library operator, one thread); torch.autograd.grad through forward_dynamics "
                             "(its autograd.Function on the derivative routines' kernels), one reverse pass per "
                             "output"),
    "aggsym_torch_kernels_func": ("aggsym PyTorch kernels, torch.func", "torch", ("jac",),
                                  "as aggsym PyTorch kernels, the Jacobian by torch.func.vmap(torch.func.jacrev(...)) "
                                  "over the states: one backward call for all the cotangents"),
    "c_loop": ("one-state C loop", "numpy", ROUTINES,
               "the generated one-state C (NAME.c, -O2, portable flags) called state by state in a C loop (ctypes "
               "calls the loop once per batch); the Jacobian by NAME_forward_dynamics_derivatives"),
    "pinocchio_parallel": ("Pinocchio abaInParallel, one thread", "numpy", ("fd",),
                           "abaInParallel(1, ModelPool, ...): Pinocchio's own batched forward dynamics"),
    "pinocchio_parallel_all": ("Pinocchio abaInParallel, all cores", "numpy", ("fd",),
                               "abaInParallel(cores, ModelPool, ...)"),
    "numpy": ("aggsym NumPy", "numpy", ROUTINES, "forward_dynamics_derivatives of the generated NumPy module"),
    "adam_jax": ("adam JAX", "jax", ROUTINES, "jax.jacrev through adam's aba (as the issue measured it)"),
    "adam_torch": ("adam PyTorch", "torch", ROUTINES,
                   "torch.autograd.grad through adam's aba, one reverse pass per output over the whole batch"),
    "jaxsim": ("jaxsim", "jax", ROUTINES, "jax.jacfwd through forward_dynamics_aba"),
    "mjx": ("MuJoCo MJX", "jax", ROUTINES, "jax.jacfwd through mjx.forward (MuJoCo's state converted inside)"),
    "pinocchio": ("Pinocchio loop", "numpy", ROUTINES, "computeABADerivatives, state by state"),
}
# entries run by the project's own interpreter (.venv: the jax that `pip install aggsym[jax]` brings, newer than the
# peers' venv, whose adam-robotics pins jax <= 0.6): the generated module as a user of aggsym meets it
PROJECT_ENTRIES = ("aggsym_jax_project", "aggsym_jax_project_rev", "aggsym_jax_kernels", "aggsym_jax_kernels_rev",
                   "aggsym_jax_kernels_all")
# the entries whose kernels (or Pinocchio's pool) use every core; the others run on one thread
ALL_CORES = ("aggsym_jax_kernels_all", "pinocchio_parallel_all")
GRAVITY = 9.81  # Pinocchio's, given to the peers that have their own default (adam: 9.80665)


@dataclass
class Built:
    """One entry's routines for one robot: ``routines[name](*inputs)`` on framework arrays made by ``put``;
    ``fetch`` turns an output into a NumPy array (after ``ready``, which waits for asynchronous frameworks)."""
    routines: dict
    put: object
    fetch: object
    ready: object = field(default=lambda out: out)
    compiles: bool = False  # whether the first call of each new batch shape compiles (jit)


def load_module(path: Path, name: str):
    """A generated module loaded from its file (not from sys.path: every robot's folder has its own)."""
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


# ------------------------------------------------------------------------------------ Lie-group helpers (any xp)
def quat_matrix(xp, quat):
    """R from a unit quaternion (x, y, z, w) on the last axis; shape (..., 3, 3)."""
    x, y, z, w = (quat[..., k] for k in range(4))
    rows = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    return xp.stack([xp.stack(r, -1) for r in rows], -2)


def _cross(xp, a, b):
    return xp.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1], a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], -1)


def _matvec(xp, R, x):
    return (R * x[..., None, :]).sum(-1)


def _tmatvec(xp, R, x):
    return (R * x[..., :, None]).sum(-2)


def retract(xp, q, delta, floating: bool):
    """q (+) delta to first order at delta = 0 (see the module's docstring); a fixed base: q + delta."""
    if not floating:
        return q + delta
    p, quat, joints = q[..., :3], q[..., 3:7], q[..., 7:]
    R = quat_matrix(xp, quat)
    p2 = p + _matvec(xp, R, delta[..., :3])
    h = delta[..., 3:6] / 2
    vec, w = quat[..., :3], quat[..., 3]
    # (vec, w) * (h, 1)
    vec2 = w[..., None] * h + vec + _cross(xp, vec, h)
    w2 = w - (vec * h).sum(-1)
    quat2 = xp.concatenate([vec2, w2[..., None]], -1)
    quat2 = quat2 / xp.sqrt((quat2 * quat2).sum(-1))[..., None]
    return xp.concatenate([p2, quat2, joints + delta[..., 6:]], -1)


def jax_jacobian(fd_single, floating: bool, nv: int, mode: str = "fwd"):
    """The batched tangent-space Jacobian [da/dq, da/dv] of a single-state forward dynamics, jit(vmap(jac*))."""
    import jax
    import jax.numpy as jnp

    def one(q, v, tau):
        def f(delta, vel):
            return fd_single(retract(jnp, q, delta, floating), vel, tau)

        jac = jax.jacfwd if mode == "fwd" else jax.jacrev
        jq, jv = jac(f, argnums=(0, 1))(jnp.zeros(nv, dtype=q.dtype), v)
        return jnp.concatenate([jq, jv], -1)

    return jax.jit(jax.vmap(one))


def torch_jacobian(fd_batched, floating: bool, nv: int):
    """The batched tangent-space Jacobian by reverse passes through a batched forward dynamics: the states are
    independent, so the gradient of the batch's sum of output i is row i of every state's Jacobian."""
    import torch

    def jac(q, v, tau):
        delta = torch.zeros(q.shape[:-1] + (nv,), dtype=q.dtype, requires_grad=True)
        vel = v.detach().clone().requires_grad_(True)
        a = fd_batched(retract(torch, q, delta, floating), vel, tau)
        rows = []
        for i in range(nv):
            gq, gv = torch.autograd.grad(a[..., i].sum(), (delta, vel), retain_graph=i + 1 < nv)
            rows.append(torch.cat([gq, gv], -1))
        return torch.stack(rows, -2)

    return jac


def torch_func_jacobian(fd, floating: bool, nv: int):
    """The batched tangent-space Jacobian [da/dq, da/dv] by torch.func: vmap over the states of jacrev of one
    state's forward dynamics (the cotangents of all outputs in one backward call)."""
    import torch

    def one(q, v, tau):
        def f(delta, vel):
            return fd(retract(torch, q, delta, floating), vel, tau)

        jq, jv = torch.func.jacrev(f, argnums=(0, 1))(torch.zeros(nv, dtype=q.dtype), v)
        return torch.cat([jq, jv], -1)

    return torch.func.vmap(one)


# ------------------------------------------------------------------------------------------------ the entries
def _jax_built(routines):
    import jax
    import numpy as np

    return Built(routines, put=lambda x: jax.device_put(x), fetch=lambda out: np.asarray(out),
                 ready=lambda out: jax.block_until_ready(out), compiles=True)


def _torch_built(routines):
    import torch

    return Built(routines, put=lambda x: torch.from_numpy(x), fetch=lambda out: out.detach().numpy())


def build_numpy(robot):
    import numpy as np

    mod = load_module(Path(robot["gen"]) / f"{robot['module']}.py", robot["module"])
    return Built({"fd": mod.forward_dynamics, "A": mod.inertia, "id": mod.inverse_dynamics,
                  "jac": lambda q, v, tau: np.concatenate(mod.forward_dynamics_derivatives(q, v, tau), -1)},
                 put=lambda x: x, fetch=lambda out: out)


def build_pinocchio(robot):
    import numpy as np
    import pinocchio as pin

    model = pinocchio_model(robot)
    data = model.createData()
    nv = model.nv

    def loop(fn, width):
        def run(*args):
            out = np.empty((args[0].shape[0],) + width)
            for k in range(args[0].shape[0]):
                out[k] = fn(*(a[k] for a in args))
            return out
        return run

    lower = np.tril_indices(nv, -1)

    def A(q):
        M = pin.crba(model, data, q)  # the upper triangle is Pinocchio's; the lower is copied from it
        M[lower] = M.T[lower]
        return M

    def jac(q, v, tau):
        pin.computeABADerivatives(model, data, q, v, tau)
        return np.hstack([data.ddq_dq, data.ddq_dv])

    return Built({"fd": loop(lambda q, v, t: pin.aba(model, data, q, v, t), (nv,)), "A": loop(A, (nv, nv)),
                  "id": loop(lambda q, v, a: pin.rnea(model, data, q, v, a), (nv,)),
                  "jac": loop(jac, (nv, 2 * nv))}, put=lambda x: x, fetch=lambda out: out)


def build_pinocchio_parallel(robot, threads: int):
    """abaInParallel over a ModelPool: Pinocchio's batched forward dynamics (states as columns)."""
    import numpy as np
    import pinocchio as pin

    model = pinocchio_model(robot)
    pool = pin.ModelPool(model, threads)

    def fd(q, v, tau):
        out = np.empty((model.nv, q.shape[0]), order="F")
        pin.abaInParallel(threads, pool, np.asfortranarray(q.T), np.asfortranarray(v.T), np.asfortranarray(tau.T), out)
        return out.T
    return Built({"fd": fd}, put=lambda x: x, fetch=lambda out: np.ascontiguousarray(out))


def build_c_loop(robot):
    """The one-state C of the kernels' generation in a plain C loop (:func:`c_loop_library`)."""
    import ctypes

    import numpy as np

    folder, module = Path(robot["gen_kernels"]), robot["module"]
    lib = ctypes.CDLL(str(folder / f"lib{module}_loop.so"))
    nv = robot["nv"]

    def loop(symbol, width, arrays):
        fn = getattr(lib, symbol)
        fn.restype = None

        def run(*args):
            args = [np.ascontiguousarray(a, dtype=np.float64) for a in args]
            outs = [np.empty((args[0].shape[0],) + w) for w in width]
            fn(ctypes.c_long(args[0].shape[0]), *[a.ctypes.data_as(ctypes.c_void_p) for a in args],
               *[o.ctypes.data_as(ctypes.c_void_p) for o in outs])
            return outs[0] if len(outs) == 1 else np.concatenate(outs, -1)
        return run
    return Built({"fd": loop("loop_forward_dynamics", [(nv,)], 3), "A": loop("loop_inertia", [(nv, nv)], 1),
                  "id": loop("loop_inverse_dynamics", [(nv,)], 3),
                  "jac": loop("loop_forward_dynamics_derivatives", [(nv, nv), (nv, nv)], 3)},
                 put=lambda x: x, fetch=lambda out: out)


C_LOOP = """#include "{module}.h"
/* the one-state C in a plain loop over n states (contiguous, state-major) */
void loop_forward_dynamics(long n, const double *q, const double *v, const double *tau, double *a)
{{ for (long s = 0; s < n; ++s)
    {module}_forward_dynamics(q + s * {nq}, v + s * {nv}, tau + s * {nv}, 0, a + s * {nv}); }}
void loop_inertia(long n, const double *q, double *A)
{{ for (long s = 0; s < n; ++s) {module}_inertia(q + s * {nq}, 0, A + s * {nv} * {nv}); }}
void loop_inverse_dynamics(long n, const double *q, const double *v, const double *a, double *tau)
{{ for (long s = 0; s < n; ++s)
    {module}_inverse_dynamics(q + s * {nq}, v + s * {nv}, a + s * {nv}, 0, tau + s * {nv}); }}
void loop_forward_dynamics_derivatives(long n, const double *q, const double *v, const double *tau, double *dq,
                                       double *dv)
{{ for (long s = 0; s < n; ++s)
    {module}_forward_dynamics_derivatives(q + s * {nq}, v + s * {nv}, tau + s * {nv}, 0, dq + s * {nv} * {nv},
                                          dv + s * {nv} * {nv}); }}
"""


def pinocchio_model(robot):
    import pinocchio as pin

    if robot["floating"]:
        return pin.buildModelFromUrdf(str(robot["urdf"]), pin.JointModelFreeFlyer())
    return pin.buildModelFromUrdf(str(robot["urdf"]))


def build_aggsym_jax(robot, which):
    import jax

    jax.config.update("jax_enable_x64", True)
    folder = Path(robot["gen_plain"] if which == "plain" else robot["gen_kernels"] if which.startswith("kernels")
                  else robot["gen"])
    mod = load_module(folder / f"{robot['module']}_jax.py", f"{robot['module']}_jax_{which}")
    which = {"kernels": "custom", "kernels_rev": "custom_rev"}.get(which, which)
    nv, floating = robot["nv"], robot["floating"]
    if which == "routine":
        import jax.numpy as jnp

        return _jax_built({"jac": jax.jit(lambda q, v, tau: jnp.concatenate(
            mod.forward_dynamics_derivatives(q, v, tau), -1))})
    routines = {"jac": jax_jacobian(mod.forward_dynamics, floating, nv, "rev" if which == "custom_rev" else "fwd")}
    if which == "custom":
        routines.update({"fd": jax.jit(mod.forward_dynamics), "A": jax.jit(mod.inertia),
                         "id": jax.jit(mod.inverse_dynamics)})
    return _jax_built(routines)


def build_aggsym_torch(robot, kernels: bool = False, functional: bool = False):
    import torch

    torch.set_num_threads(1)
    folder = Path(robot["gen_kernels" if kernels else "gen"])
    mod = load_module(folder / f"{robot['module']}_torch.py", f"{robot['module']}_torch" + ("_k" if kernels else ""))
    jacobian = torch_func_jacobian if functional else torch_jacobian
    return _torch_built({"fd": mod.forward_dynamics, "A": mod.inertia, "id": mod.inverse_dynamics,
                         "jac": jacobian(mod.forward_dynamics, robot["floating"], robot["nv"])})


def _adam_state(xp, q, floating):
    """adam's (base transform, joints) from Pinocchio's q; a fixed base: the identity."""
    if floating:
        R = quat_matrix(xp, q[..., 3:7])
        top = xp.concatenate([R, q[..., :3, None]], -1)
        bottom = xp.zeros(q.shape[:-1] + (1, 4), dtype=q.dtype) + xp.asarray([0.0, 0.0, 0.0, 1.0], dtype=q.dtype)
        return xp.concatenate([top, bottom], -2), q[..., 7:]
    eye = xp.zeros(q.shape[:-1] + (4, 4), dtype=q.dtype) + xp.eye(4, dtype=q.dtype)
    return eye, q


def _adam_routines(xp, kd, floating, nj, solve):
    """fd, A, id of one adam KinDynComputations in Pinocchio's conventions (body-fixed velocities).  adam's ABA is
    for a floating base only: a fixed base takes M and h and drops the base's six rows and columns (the base held
    still), then solves, as adam's users do."""
    def split(v):
        if floating:
            return v[..., :6], v[..., 6:]
        return xp.zeros(v.shape[:-1] + (6,), dtype=v.dtype), v

    def A(q):
        H, s = _adam_state(xp, q, floating)
        M = kd.mass_matrix(H, s)
        return M if floating else M[..., 6:, 6:]

    def h(q, v):
        H, s = _adam_state(xp, q, floating)
        vb, sd = split(v)
        out = kd.bias_force(H, s, vb, sd)
        out = out.reshape(q.shape[:-1] + (6 + nj,))  # adam drops a batch dimension of 1
        return out if floating else out[..., 6:]

    def fd(q, v, tau):
        if floating:
            H, s = _adam_state(xp, q, floating)
            return kd.aba(H, s, v[..., :6], v[..., 6:], tau[..., 6:]).reshape(q.shape[:-1] + (6 + nj,))
        return solve(A(q), tau - h(q, v))

    def id_(q, v, a):
        return (A(q) @ a[..., None])[..., 0] + h(q, v)

    return fd, A, id_


def build_adam_jax(robot):
    import jax
    import jax.numpy as jnp

    jax.config.update("jax_enable_x64", True)
    from adam.core.constants import Representations
    from adam.jax import KinDynComputations

    kd = KinDynComputations(str(robot["urdf"]), robot["joints"], dtype=jnp.float64,
                            gravity=jnp.array([0, 0, -GRAVITY, 0, 0, 0]))
    kd.set_frame_velocity_representation(Representations.BODY_FIXED_REPRESENTATION)
    solve = lambda M, b: jax.scipy.linalg.cho_solve(jax.scipy.linalg.cho_factor(M), b)  # noqa: E731
    fd, A, id_ = _adam_routines(jnp, kd, robot["floating"], len(robot["joints"]), solve)
    vm = lambda f: jax.jit(jax.vmap(f))  # noqa: E731
    return _jax_built({"fd": vm(fd), "A": vm(A), "id": vm(id_),
                       "jac": jax_jacobian(fd, robot["floating"], robot["nv"], mode="rev")})


def build_adam_torch(robot):
    import torch

    torch.set_num_threads(1)
    from adam.core.constants import Representations
    from adam.pytorch import KinDynComputations

    kd = KinDynComputations(str(robot["urdf"]), robot["joints"], device=torch.device("cpu"), dtype=torch.float64,
                            gravity=torch.tensor([0, 0, -GRAVITY, 0, 0, 0], dtype=torch.float64))
    kd.set_frame_velocity_representation(Representations.BODY_FIXED_REPRESENTATION)

    def solve(M, b):
        return torch.cholesky_solve(b[..., None], torch.linalg.cholesky(M))[..., 0]

    fd, A, id_ = _adam_routines(torch, kd, robot["floating"], len(robot["joints"]), solve)
    return _torch_built({"fd": fd, "A": A, "id": id_, "jac": torch_jacobian(fd, robot["floating"], robot["nv"])})
