"""Models of one coordinate (nv = 1): every routine of every array target (NumPy, JAX, PyTorch, ext) returns the
shape the manifest declares, (..., n) for a vector of n = 1 entries and (..., 1, 1) for a matrix, with any leading
batch dimensions (none, (4,), (2, 3)); only the contract's scalars (kinetic and potential energy, declared (1,))
are one number per state.  Before, a vector of one entry came out as a number per state, as the energies do.

Two models: a pendulum from URDF (one revolute joint about a random axis, a link whose inertia has off-diagonal
terms), and one hinge from MJCF (with damping, armature and a spring).  Values: every routine against the numeric
twin state by state, and the dynamics against Pinocchio (URDF) and MuJoCo (MJCF), through every target; the
derivatives through JAX's and PyTorch's custom rules 1 x 1.  And the same rule in the bundled models whose vectors
have one entry for another reason (one constraint row, one slip velocity, one transvection)."""
from __future__ import annotations

import json

import numpy as np
import pytest

import aggsym
from aggsym.codegen.compile import import_module
from aggsym.codegen.generate import generate, write
from aggsym.contract import ROUTINES, SCALAR_INPUTS, input_length, select_routines, shapes, signature
from aggsym.twin import NumericTwin
from helpers import relative_error

TARGETS = ("numpy", "jax", "torch", "ext")
BATCHES = ((), (4,), (2, 3))
MODULE_FILES = {"numpy": "{}.py", "jax": "{}_jax.py", "torch": "{}_torch.py", "ext": "{}_ext.py"}


def _unit(rng, n=3):
    v = rng.normal(size=n)
    return v / np.linalg.norm(v)


def _numbers(xs) -> str:
    return " ".join(repr(float(x)) for x in xs)


def pendulum_urdf(rng) -> str:
    """One revolute joint about a random unit axis, at a tilted origin; the link's centre of mass and inertia
    rotated, with off-diagonal terms (a physical tensor: R diag(m1, m2, m3) R^T)."""
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    inertia = R @ np.diag([0.05, 0.06, 0.04]) @ R.T
    i = {"ixx": inertia[0, 0], "iyy": inertia[1, 1], "izz": inertia[2, 2], "ixy": inertia[0, 1],
         "ixz": inertia[0, 2], "iyz": inertia[1, 2]}
    assert min(abs(i["ixy"]), abs(i["ixz"]), abs(i["iyz"])) > 1e-4
    return f"""<robot name="pendulum">
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="0.1 -0.05 0.3" rpy="0.2 -0.1 0.4"/><mass value="1.7"/>
    <inertia {" ".join(f'{k}="{float(v)!r}"' for k, v in i.items())}/></inertial></link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
    <origin xyz="0.1 0.2 0.3" rpy="0.3 0.2 0.1"/><axis xyz="{_numbers(_unit(rng))}"/>
    <limit lower="-3" upper="3" effort="10" velocity="10"/><dynamics damping="0.3" friction="0.1"/></joint>
</robot>
"""


def hinge_mjcf(rng) -> str:
    """One hinge about a random axis, anchored off the body's origin, with damping, armature and a spring; the
    body's inertia full (off-diagonal terms), gravity tilted."""
    return f"""<mujoco model="hinge">
  <compiler angle="radian"/>
  <option gravity="0.3 -0.2 -9.81"/>
  <worldbody>
    <body name="arm" pos="0.1 0.2 0.5" euler="0.2 0.3 0.5">
      <joint name="swing" type="hinge" axis="{_numbers(_unit(rng))}" pos="0.02 -0.01 0.05" damping="0.3"
             armature="0.02" stiffness="1.5" springref="0.2"/>
      <inertial pos="0.1 -0.05 0.3" mass="1.7" fullinertia="0.05 0.06 0.04 0.004 -0.003 0.002"/>
      <site name="tip" pos="0.2 0 0.4" euler="0 0.5 0"/>
    </body>
  </worldbody>
</mujoco>
"""


SOURCES = {"urdf": ("pendulum.urdf", pendulum_urdf), "mjcf": ("hinge.xml", hinge_mjcf)}


_BUILT = {}


def built(kind, tmp_path_factory):
    """(kind, source path, model with every routine, folder with its C, NumPy, JAX, PyTorch and ext files,
    manifest), generated once per session."""
    if kind == "mjcf":
        pytest.importorskip("mujoco")
    if kind not in _BUILT:
        file, text = SOURCES[kind]
        folder = tmp_path_factory.mktemp(f"one_{kind}")
        path = folder / file
        path.write_text(text(np.random.default_rng(20261201)))
        model = select_routines(aggsym.load(path), ["all"])
        assert model.nq == model.nv == 1
        write(generate(model, targets="c,numpy,manifest,jax,torch,ext"), folder)
        _BUILT[kind] = (kind, path, model, folder, json.loads((folder / f"{model.name}.json").read_text()))
    return _BUILT[kind]


@pytest.fixture(params=sorted(SOURCES))
def one(request, tmp_path_factory):
    """Each of the two models (:func:`built`)."""
    return built(request.param, tmp_path_factory)


@pytest.fixture
def pendulum(tmp_path_factory):
    return built("urdf", tmp_path_factory)


@pytest.fixture
def hinge(tmp_path_factory):
    return built("mjcf", tmp_path_factory)


_IMPORTED = {}


def module_of(one, target):
    """The target's generated module (jax, torch: skipped where they do not import; ext compiles its C)."""
    _, _, model, folder, _ = one
    if target in ("jax", "torch"):
        pytest.importorskip(target)
    key = (str(folder), target)
    if key not in _IMPORTED:
        _IMPORTED[key] = import_module(folder / MODULE_FILES[target].format(model.name))
    return _IMPORTED[key]


class Caller:
    """A generated module's routine called on NumPy float64 arrays, its outputs as a tuple of NumPy arrays (JAX
    in float64 within the call; PyTorch on float64 tensors)."""

    def __init__(self, module, target):
        self.module, self.target = module, target

    def __call__(self, role, *args):
        f = getattr(self.module, role)
        if self.target == "jax":
            from jax_support import float64

            with float64():
                out = f(*args)
        elif self.target == "torch":
            import torch

            out = f(*(torch.as_tensor(np.asarray(a, dtype=float)) for a in args))
        else:
            out = f(*args)
        out = out if isinstance(out, tuple) else (out,)
        if self.target == "torch":
            out = tuple(o.detach().numpy() for o in out)
        return tuple(np.asarray(o) for o in out)

    def call(self, role, *args):
        """One output as an array (for benchmarks.mjcf.mujoco_reference.compare's evaluators)."""
        out = self(role, *args)
        return out[0] if len(out) == 1 else out


def arguments(model, role, rng, batch):
    """Random arguments of a routine (without p), with leading batch dimensions: q within +-1.5, the rest normal;
    the numbers (t, dt, r) in [0, 1]."""
    out = []
    for name in signature(ROUTINES[role], model):
        if name == "p":
            continue
        if name in SCALAR_INPUTS:
            out.append(rng.uniform(0.0, 1.0, batch))
        elif name == "q":
            out.append(rng.uniform(-1.5, 1.5, batch + (input_length(model, name, ROUTINES[role]),)))
        else:
            out.append(rng.normal(size=batch + (input_length(model, name, ROUTINES[role]),)))
    return out


def expected_shapes(model, role, manifest) -> list:
    """Per output the shape of one state: the manifest's, but () for the contract's scalars (declared (1,))."""
    declared = [tuple(o["shape"]) for o in manifest["signatures"][role]["outputs"]]
    scalar = [o.shape is shapes.scalar for o in ROUTINES[role].written]
    assert len(declared) == len(scalar)
    return [() if s else d for d, s in zip(declared, scalar)]


def test_the_routines_cover_the_vectors_and_matrices_of_one_coordinate(one):
    """The models have routines with outputs of every kind the issue names: vectors of n = 1 (b, g, qdd, tau,
    passive forces, ...), 1 x 1 matrices, frame blocks, derivatives."""
    kind, _, _, _, manifest = one
    roles = set(manifest["signatures"])
    assert {"bias", "gravity", "forward_dynamics", "inverse_dynamics", "nonlinear_effects", "inertia",
            "inertia_inverse", "forward_dynamics_derivatives", "inverse_dynamics_derivatives", "frame_poses",
            "frame_jacobians", "com_jacobian", "transvective_factors"} <= roles
    assert ("passive_forces" if kind == "mjcf" else "joint_friction") in roles
    ones = {role for role, sig in manifest["signatures"].items() for o in sig["outputs"] if o["shape"] == [1]
            and role not in ("kinetic_energy", "potential_energy")}
    assert {"bias", "gravity", "nonlinear_effects", "inverse_dynamics", "forward_dynamics",
            "transvective_factors"} <= ones, ones
    assert {"elastic", "passive_forces"} <= ones if kind == "mjcf" else "joint_friction" in ones


@pytest.mark.compiler
@pytest.mark.parametrize("target", TARGETS)
def test_every_output_has_the_manifests_shape_and_the_twins_values(one, target, rng):
    """Every routine, batched and not: each output of shape batch + the manifest's shape (the energies: batch),
    and per state equal to the numeric twin's to 1e-12."""
    _, _, model, _, manifest = one
    call = Caller(module_of(one, target), target)
    twin = NumericTwin(model)
    wrong = []
    for role in manifest["signatures"]:
        want_shapes = expected_shapes(model, role, manifest)
        for batch in BATCHES:
            args = arguments(model, role, rng, batch)
            got = call(role, *args)
            shapes_got = [o.shape for o in got]
            if shapes_got != [batch + s for s in want_shapes]:
                wrong.append(f"{role} {batch}: {shapes_got}, not {[batch + s for s in want_shapes]}")
                continue
            for index in np.ndindex(*batch):
                want = twin.call(role, *[a[index] for a in args])
                want = want if isinstance(want, tuple) else (want,)
                for g, w, s in zip(got, want, want_shapes):
                    if np.size(w):
                        assert relative_error(g[index], np.reshape(w, s), floor=1.0) < 1e-12, (role, batch, index)
    assert not wrong, "\n".join(wrong)


@pytest.mark.compiler
@pytest.mark.parametrize("target", TARGETS)
def test_one_state_gives_arrays_not_numbers(one, target):
    """For one state (1-D inputs) b, g, qdd and tau are arrays of shape (1,), A is (1, 1): indexing them as the
    contract says works (b[0], A[0, 0]); the energies are numbers."""
    _, _, model, _, _ = one
    call = Caller(module_of(one, target), target)
    q, qd, u = np.array([0.4]), np.array([-0.7]), np.array([0.9])
    for role, args in (("bias", (q, qd)), ("gravity", (q,)), ("forward_dynamics", (q, qd, u)),
                       ("inverse_dynamics", (q, qd, u)), ("nonlinear_effects", (q, qd))):
        out, = call(role, *args)
        assert out.shape == (1,) and np.isfinite(out[0]), role
    A, = call("inertia", q)
    assert A.shape == (1, 1) and A[0, 0] > 0
    qdd, = call("forward_dynamics", q, qd, u)
    d, = call("nonlinear_effects", q, qd)
    assert np.allclose(A @ qdd + d, u, rtol=1e-12, atol=1e-12)
    T, = call("kinetic_energy", q, qd)
    assert T.shape == () and np.isclose(float(T), 0.5 * qd @ A @ qd, rtol=1e-12)


@pytest.mark.compiler
@pytest.mark.pinocchio
@pytest.mark.parametrize("target", TARGETS)
def test_the_pendulums_dynamics_equal_pinocchio(pendulum, target, rng):
    """URDF: A, b + g, g, the inverse and forward dynamics and A^-1 of every target equal Pinocchio's crba,
    nonLinearEffects, computeGeneralizedGravity, rnea, aba and computeMinverse (to 1e-9), for one state and a
    batch of four, in the contract's shapes."""
    _, path, _, _, _ = pendulum
    from pinocchio_reference import pin, pinocchio_model, pinocchio_q

    pm = pinocchio_model(path)
    assert pm.nv == 1
    call = Caller(module_of(pendulum, target), target)
    for batch in ((), (4,)):
        q, qd, u = (rng.uniform(-1.5, 1.5, batch + (1,)) for _ in range(3))
        got = {"inertia": call("inertia", q)[0], "nonlinear_effects": call("nonlinear_effects", q, qd)[0],
               "gravity": call("gravity", q)[0], "inverse_dynamics": call("inverse_dynamics", q, qd, u)[0],
               "forward_dynamics": call("forward_dynamics", q, qd, u)[0],
               "inertia_inverse": call("inertia_inverse", q)[0], "bias": call("bias", q, qd)[0]}
        for role, out in got.items():
            assert out.shape == batch + ((1, 1) if role.startswith("inertia") and role != "inverse_dynamics"
                                         else (1,)), (role, out.shape)
        for index in np.ndindex(*batch):
            Q, v, a = pinocchio_q(pm, q[index]), qd[index], u[index]
            data = pm.createData()
            want = {"inertia": pin.crba(pm, data, Q).copy(),
                    "nonlinear_effects": pin.nonLinearEffects(pm, pm.createData(), Q, v).copy(),
                    "gravity": pin.computeGeneralizedGravity(pm, pm.createData(), Q).copy(),
                    "inverse_dynamics": pin.rnea(pm, pm.createData(), Q, v, a).copy(),
                    "forward_dynamics": pin.aba(pm, pm.createData(), Q, v, a).copy(),
                    "inertia_inverse": pin.computeMinverse(pm, pm.createData(), Q).copy()}
            want["bias"] = want["nonlinear_effects"] - want["gravity"]
            for role, theirs in want.items():
                assert relative_error(got[role][index], theirs, floor=1.0) < 1e-9, (role, index)


@pytest.mark.compiler
@pytest.mark.mujoco
@pytest.mark.parametrize("target", TARGETS)
def test_the_hinges_dynamics_equal_mujoco(hinge, target, rng):
    """MJCF: A, d = b + g + c with the damping (the velocity, gravity, spring and damping terms), g, the inverse and
    forward dynamics and the passive forces of every target equal MuJoCo's mj_fullM, qfrc_bias - qfrc_passive,
    qfrc_bias at rest, qfrc_inverse of mj_inverse, qacc of mj_forward and qfrc_passive (constraints and actuators
    disabled; one hinge: qpos, qvel and forces are q, qd and tau), to 1e-9, for one state and a batch of four."""
    _, path, _, _, _ = hinge
    import mujoco

    m = mujoco.MjModel.from_xml_path(str(path))
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT) | int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
    assert m.nq == m.nv == 1
    data = mujoco.MjData(m)
    call = Caller(module_of(hinge, target), target)
    for batch in ((), (4,)):
        q, qd, u, qdd = (rng.uniform(-1.5, 1.5, batch + (1,)) for _ in range(4))
        got = {"inertia": call("inertia", q)[0], "nonlinear_effects": call("nonlinear_effects", q, qd)[0],
               "gravity": call("gravity", q)[0], "inverse_dynamics": call("inverse_dynamics", q, qd, qdd)[0],
               "forward_dynamics": call("forward_dynamics", q, qd, u)[0],
               "passive_forces": call("passive_forces", q, qd)[0]}
        for role, out in got.items():
            assert out.shape == batch + ((1, 1) if role == "inertia" else (1,)), (role, out.shape)
        for index in np.ndindex(*batch):
            data.qpos[:], data.qvel[:], data.qfrc_applied[:] = q[index], qd[index], u[index]
            mujoco.mj_forward(m, data)
            M = np.zeros((1, 1))
            mujoco.mj_fullM(m, data, M)
            want = {"inertia": M, "nonlinear_effects": data.qfrc_bias - data.qfrc_passive,
                    "forward_dynamics": data.qacc.copy(), "passive_forces": data.qfrc_passive.copy()}
            data.qacc[:] = qdd[index]
            mujoco.mj_inverse(m, data)
            want["inverse_dynamics"] = data.qfrc_inverse.copy()
            data.qvel[:] = 0.0
            mujoco.mj_forward(m, data)
            want["gravity"] = data.qfrc_bias.copy()
            for role, theirs in want.items():
                assert relative_error(got[role][index], theirs, floor=1.0) < 1e-9, (role, index)


@pytest.mark.parametrize("target", ("jax", "torch"))
def test_derivatives_through_the_dynamics_have_the_shapes_of_one_coordinate(one, target, rng):
    """The Jacobians of q'' and tau along q, qd and tau (qdd) through JAX's custom JVP and PyTorch's
    autograd.Function (the generated derivative routines) are 1 x 1, equal to forward_dynamics_derivatives and
    inverse_dynamics_derivatives, A^-1 and A; PyTorch's analytic=False (plain autograd) agrees."""
    module = module_of(one, target)
    numpy = module_of(one, "numpy")
    q, qd, u = (rng.uniform(-1.5, 1.5, (1,)) for _ in range(3))
    want = {"forward_dynamics": (*numpy.forward_dynamics_derivatives(q, qd, u), numpy.inertia_inverse(q)),
            "inverse_dynamics": (*numpy.inverse_dynamics_derivatives(q, qd, u), numpy.inertia(q))}
    for role, matrices in want.items():
        if target == "jax":
            import jax
            from jax_support import float64

            with float64():
                got = [np.asarray(jax.jacfwd(getattr(module, role), argnums=k)(q, qd, u)) for k in range(3)]
                got += [np.asarray(jax.jacrev(getattr(module, role), argnums=k)(q, qd, u)) for k in range(3)]
        else:
            import torch

            x = tuple(torch.tensor(a) for a in (q, qd, u))
            got = [j.numpy() for j in torch.func.jacrev(getattr(module, role), argnums=(0, 1, 2))(*x)]
            plain = torch.func.jacrev(lambda *a: getattr(module, role)(*a, analytic=False), argnums=(0, 1, 2))(*x)
            got += [j.numpy() for j in plain]
        matrices = matrices * 2  # (jacfwd and jacrev; PyTorch: the analytic Function and plain autograd)
        for g, w in zip(got, matrices):
            assert g.shape == (1, 1) and w.shape == (1, 1), (role, g.shape, w.shape)
            assert relative_error(g, w, floor=1.0) < 1e-12, role


# bundled models with outputs of one entry that are not scalars: one constraint row (phi, gamma, lambda), one slip
# velocity (w), one transvection (targs)
ONE_ENTRY = ["double_pendulum_sliding_friction", "four_bar", "planar_2link"]


@pytest.fixture(scope="module", params=ONE_ENTRY)
def one_entry(request, tmp_path_factory):
    """(model, folder, manifest, the roles with an output of shape (1,) that is not a scalar) of a bundled model."""
    from conftest import model_path

    model = aggsym.load(model_path(request.param))
    folder = tmp_path_factory.mktemp(request.param)
    write(generate(model, targets="c,numpy,manifest,jax,torch,ext"), folder)
    manifest = json.loads((folder / f"{model.name}.json").read_text())
    roles = [role for role, sig in manifest["signatures"].items()
             if any(d["shape"] == [1] and o.shape is not shapes.scalar
                    for o, d in zip(ROUTINES[role].written, sig["outputs"]))]
    assert roles
    return request.param, model, folder, manifest, roles


@pytest.mark.compiler
@pytest.mark.parametrize("target", TARGETS)
def test_one_entry_vectors_of_the_bundled_models_keep_their_axis(one_entry, target, rng):
    """A vector of one entry is (..., 1) in every target whatever its length counts (a constraint row, a slip
    velocity, a transvection), as the manifest declares: equal to the twin's state by state."""
    name, model, folder, manifest, roles = one_entry
    call = Caller(module_of((name, None, model, folder, manifest), target), target)
    twin = NumericTwin(model)
    for role in roles:
        want_shapes = expected_shapes(model, role, manifest)
        for batch in ((), (2, 3)):
            for _ in range(20):  # (the NumPy module and ext raise at a singular state of the four-bar: another)
                args = arguments(model, role, rng, batch)
                try:
                    got = call(role, *args)
                    break
                except np.linalg.LinAlgError:
                    continue
            else:
                raise AssertionError(f"{name}: {role} raised LinAlgError at 20 random states of {batch}")
            assert [o.shape for o in got] == [batch + s for s in want_shapes], (role, batch)
            for index in np.ndindex(*batch):
                try:
                    want = twin.call(role, *[a[index] for a in args])
                except np.linalg.LinAlgError:
                    continue
                want = want if isinstance(want, tuple) else (want,)
                for g, w, s in zip(got, want, want_shapes):
                    if np.size(w):
                        assert relative_error(g[index], np.reshape(w, s), floor=1.0) < 1e-10, (role, batch, index)
