"""Run-time model edits without generating again (issue 35, items 2 and 3).

* ``--gravity-parameter``: the gravity vector as the last three entries of p; a wall-mounted Panda (gravity along
  the base's x) and a random gravity agree with Pinocchio given the same gravity, through the compiled C and the
  NumPy module; the defaults are the model without the option.
* ``set_payload_<link>`` (C in the header, NumPy, JAX, PyTorch): mass, centre of mass and inertia about it
  (URDF's order and sign convention, ixy = -integral x y dm) written into p; the result agrees with Pinocchio's
  model of the URDF with the payload appended as a fixed link with that ``<inertial>``, for masses over four
  decades and a full inertia tensor.
* Links welded to the world are refused (exit 2, a message saying why); ``all`` leaves them out with a warning.
* ``--passive include``: URDF damping and Coulomb friction in inverse and forward dynamics, against Pinocchio's
  rnea and aba with the same D qd + F sign(qd) (Pinocchio's own ``damping`` and ``friction`` read from the file),
  and against a hand-written pendulum; ``--passive exclude`` (the default) says so in the header and manifest.
* The header: <stddef.h>, the passive notes next to the routines, a routine left out with its reason and the flag
  that brings it back; it compiles warning-free with -std=c99 -Wall -Wextra -Wpedantic.
"""
from __future__ import annotations

import ctypes
import json
import subprocess

import numpy as np
import pytest

import aggsym
from aggsym import cli
from aggsym.codegen.compile import CLibrary, compile_shared, compiler, import_module
from aggsym.codegen.generate import generate, write
from aggsym.errors import AggsymError
from aggsym.model.transforms.gravity import with_gravity_parameters
from aggsym.model.transforms.inertials import with_inertial_parameters
from aggsym.model.transforms.joint_dynamics import with_passive_included
from aggsym.twin import NumericTwin
from helpers import relative_error, robot_path, written
from pinocchio_reference import pin, pinocchio_q
from robot_builder import chain, segment

TOLERANCE = 1e-9
WALL = np.array([9.81, 0.0, 0.0])  # an arm mounted on a wall: gravity along the base's x axis


def urdf_inertia_order(J) -> np.ndarray:
    """(ixx, ixy, ixz, iyy, iyz, izz) of a symmetric tensor: the helpers' input order (URDF's)."""
    return np.array([J[0, 0], J[0, 1], J[0, 2], J[1, 1], J[1, 2], J[2, 2]])


def with_payload_link(text: str, link: str, mass, com, J) -> str:
    """The URDF with a link 'payload' fixed to ``link`` at its frame, carrying the given <inertial> (inertia about
    the centre of mass, URDF's entries: the tensor's)."""
    c = [float(x) for x in com]
    J = [[float(x) for x in row] for row in J]
    inertial = (f'<inertial><origin xyz="{c[0]!r} {c[1]!r} {c[2]!r}" rpy="0 0 0"/><mass value="{float(mass)!r}"/>'
                f'<inertia ixx="{J[0][0]!r}" ixy="{J[0][1]!r}" ixz="{J[0][2]!r}" iyy="{J[1][1]!r}" '
                f'iyz="{J[1][2]!r}" izz="{J[2][2]!r}"/></inertial>')
    extra = (f'<link name="payload">{inertial}</link><joint name="payload_fix" type="fixed"><parent link="{link}"/>'
             f'<child link="payload"/><origin xyz="0 0 0" rpy="0 0 0"/></joint>')
    end = text.rindex("</robot>")
    return text[:end] + extra + text[end:]


def pinocchio_reference(pm, q, v, a, tau) -> dict:
    """Pinocchio's A, g, rnea and aba at one state (a fresh Data each)."""
    Q = pinocchio_q(pm, q)
    M = pin.crba(pm, pm.createData(), Q)
    return {"inertia": (np.triu(M) + np.triu(M, 1).T, (q,)),
            "gravity": (pin.computeGeneralizedGravity(pm, pm.createData(), Q).copy(), (q,)),
            "inverse_dynamics": (pin.rnea(pm, pm.createData(), Q, v, a).copy(), (q, v, a)),
            "forward_dynamics": (pin.aba(pm, pm.createData(), Q, v, tau).copy(), (q, v, tau))}


def wrapped_library(model, folder, helper: str):
    """The generated C compiled with a wrapper that calls the header's static inline ``helper`` (not in the
    library by itself): (CLibrary, the wrapper as a ctypes function, manifest)."""
    write(generate(model, targets="c,numpy,manifest"), folder)
    wrapper = folder / "wrapper.c"
    wrapper.write_text(f'#include "{model.name}.c"\n'
                       f"void wrapped_{helper}(double *p, double m, const double *c, const double *I)\n"
                       f"{{\n    {model.name}_{helper}(p, m, c, I);\n}}\n")
    manifest = json.loads((folder / f"{model.name}.json").read_text())
    lib = CLibrary(compile_shared(wrapper, folder / "libwrapped.so", extra=("-O1",)), manifest)
    fn = getattr(lib.lib, f"wrapped_{helper}")
    fn.restype = None
    D = ctypes.POINTER(ctypes.c_double)
    fn.argtypes = [D, ctypes.c_double, D, D]

    def call(p, m, c, I):
        out = np.array(p, dtype=float)
        c, I = np.ascontiguousarray(c, dtype=float), np.ascontiguousarray(I, dtype=float)
        fn(out.ctypes.data_as(D), float(m), c.ctypes.data_as(D), I.ctypes.data_as(D))
        return out
    return lib, call, manifest


# ---------------------------------------------------------------------------------------------------------------
# gravity and payload at run time, against Pinocchio (the must-show)


@pytest.mark.pinocchio
@pytest.mark.compiler
@pytest.mark.slow
def test_gravity_and_payload_changed_at_run_time_agree_with_pinocchio(tmp_path, rng):
    """Panda (7-DOF arm and its fingers) generated once with --payload panda_hand --gravity-parameter: gravity
    set to a wall mounting and to a random vector, a payload from 10 g to 100 kg with a full inertia tensor set
    through the generated helper (C and NumPy); each against Pinocchio's model of the URDF with the payload as a
    fixed link and its gravity set alike."""
    path = robot_path("panda")
    with pytest.warns(UserWarning):  # (panda's finger mimic joint)
        base = aggsym.load(path)
    model = with_gravity_parameters(with_inertial_parameters(base, payload="panda_hand"))
    names = [p.name for p in model.parameters]
    assert names[-3:] == ["gravity_x", "gravity_y", "gravity_z"] and names[-13:-3] == [
        f"payload_{n}" for n in ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")]
    assert names[:len(base.parameters)] == [p.name for p in base.parameters]  # the file's p layout kept
    lib, c_helper, manifest = wrapped_library(model, tmp_path, "set_payload_panda_hand")
    module = import_module(tmp_path / f"{model.name}.py")
    assert [h["python"] for h in manifest["inertial_helpers"]] == ["set_payload_panda_hand"]
    J = np.array([[0.012, -0.0021, 0.0013], [-0.0021, 0.018, 0.0007], [0.0013, 0.0007, 0.009]])  # ixy etc. nonzero
    com = np.array([0.02, -0.015, 0.09])
    cases = [(WALL, 0.0), (WALL, 2.5), (rng.normal(size=3) * 5, 0.01), (np.array([0, 0, 9.81]), 100.0)]
    for gravity, mass in cases:
        inertia = J * max(mass, 1e-3)
        pm = pin.buildModelFromXML(with_payload_link(path.read_text(), "panda_hand", mass, com, inertia))
        pm.gravity.linear = gravity
        p = module.set_payload_panda_hand(mass, com, urdf_inertia_order(inertia))
        p[-3:] = gravity
        p_c = c_helper(model.parameter_values, mass, com, urdf_inertia_order(inertia))
        p_c[-3:] = gravity
        assert np.array_equal(p, p_c)
        for _ in range(2):
            q, v, a, tau = rng.uniform(-1.5, 1.5, model.nq), *rng.normal(size=(3, model.nq))
            for role, (want, args) in pinocchio_reference(pm, q, v, a, tau).items():
                assert relative_error(lib.call(role, *args, p=p), want, floor=1.0) < TOLERANCE, (gravity, mass, role)
                assert relative_error(getattr(module, role)(*args, p), want, floor=1.0) < TOLERANCE, (mass, role)


@pytest.mark.pinocchio
def test_the_defaults_are_the_model_without_the_options(rng):
    """--gravity-parameter and a massless payload at their defaults give the plain model's routines."""
    path = robot_path("ur5")
    plain = aggsym.load(path)
    model = with_gravity_parameters(with_inertial_parameters(plain, payload="tool0"))
    a, b = NumericTwin(plain), NumericTwin(model)
    q, v, acc = rng.uniform(-2, 2, plain.nq), *rng.normal(size=(2, plain.nq))
    for role, args in (("inverse_dynamics", (q, v, acc)), ("potential_energy", (q,)), ("gravity", (q,))):
        assert relative_error(getattr(b, role)(*args), getattr(a, role)(*args), floor=1.0) < 1e-14, role
    pm = pin.buildModelFromUrdf(str(path))
    pm.gravity.linear = np.array([0.0, -9.81, 0.0])  # ceiling to wall, through p only
    p = np.array(model.parameter_values)
    p[-3:] = (0.0, -9.81, 0.0)
    want = pin.computeGeneralizedGravity(pm, pm.createData(), pinocchio_q(pm, q))
    assert relative_error(b.gravity(q, p=p), want, floor=1.0) < TOLERANCE


@pytest.mark.pinocchio
@pytest.mark.slow
@pytest.mark.parametrize("target", ["jax", "torch"])
def test_the_batched_modules_helpers_write_what_numpys_writes(target, tmp_path, rng):
    """The JAX and PyTorch helpers give the NumPy helper's p (batched too), and forward dynamics through them
    agrees with Pinocchio's with the payload."""
    pytest.importorskip(target)
    model = with_inertial_parameters(aggsym.load(robot_path("ur5")), payload="tool0")
    from aggsym.contract import select_routines

    model = select_routines(model, ["forward_dynamics"])
    write(generate(model, targets=f"numpy,{target},manifest"), tmp_path)
    numpy_module = import_module(tmp_path / f"{model.name}.py")
    module = import_module(tmp_path / f"{model.name}_{target}.py")
    masses = np.array([0.05, 3.0, 40.0])
    com = rng.normal(size=(3, 3)) * 0.05
    J = np.array([[0.02, 0.003, -0.001], [0.003, 0.03, 0.002], [-0.001, 0.002, 0.025]])
    inertia = np.stack([urdf_inertia_order(J * m) for m in masses])
    want = numpy_module.set_payload_tool0(masses, com, inertia)
    if target == "jax":
        import jax

        jax.config.update("jax_enable_x64", True)
        got = np.asarray(module.set_payload_tool0(masses, com, inertia))
        qdd = np.asarray(module.forward_dynamics(np.zeros(6), np.zeros(6), np.zeros(6), got[1]))
    else:
        import torch

        t = lambda x: torch.as_tensor(x, dtype=torch.float64)  # noqa: E731
        got = module.set_payload_tool0(t(masses), t(com), t(inertia)).numpy()
        qdd = module.forward_dynamics(t(np.zeros(6)), t(np.zeros(6)), t(np.zeros(6)), t(got[1])).numpy()
    assert got.shape == (3, len(model.parameters)) and np.array_equal(got, want)
    pm = pin.buildModelFromXML(with_payload_link(robot_path("ur5").read_text(), "tool0", masses[1], com[1], J * 3.0))
    assert relative_error(qdd, pin.aba(pm, pm.createData(), np.zeros(6), np.zeros(6), np.zeros(6)), floor=1.0) \
        < TOLERANCE


@pytest.mark.pinocchio
def test_a_payload_on_each_of_several_links(tmp_path, rng):
    """--payload tool0,forearm_link: ten parameters each (payload_<param>_<link>), a helper each; both set through
    the helpers agree with Pinocchio's model with both payloads as fixed links."""
    path = robot_path("ur5")
    model = with_inertial_parameters(aggsym.load(path), payload=["tool0", "forearm_link"])
    assert [b.helper for b in model.inertial_blocks] == ["set_payload_tool0", "set_payload_forearm_link"]
    assert [p.name for p in model.parameters][-20:-18] == ["payload_m_tool0", "payload_mcx_tool0"]
    assert [p.name for p in model.parameters][-1] == "payload_Izz_forearm_link"
    from aggsym.contract import select_routines

    write(generate(select_routines(model, ["gravity"]), targets="numpy"), tmp_path)
    module = import_module(tmp_path / f"{model.name}.py")
    J = np.array([[0.02, -0.003, 0.001], [-0.003, 0.03, 0.002], [0.001, 0.002, 0.025]])
    loads = {"tool0": (4.0, np.array([0.01, 0.02, 0.1]), J), "forearm_link": (0.3, np.array([0.2, -0.05, 0.0]), J / 7)}
    p = np.array(model.parameter_values)
    text = path.read_text()
    for link, (mass, com, inertia) in loads.items():
        p = getattr(module, f"set_payload_{link}")(mass, com, urdf_inertia_order(inertia), p)
        text = with_payload_link(text, link, mass, com, inertia).replace('"payload"', f'"payload_{link}"') \
            .replace('"payload_fix"', f'"payload_fix_{link}"')
    pm = pin.buildModelFromXML(text)
    twin = NumericTwin(model)
    for _ in range(2):
        q, v, a, tau = rng.uniform(-1.5, 1.5, model.nq), *rng.normal(size=(3, model.nq))
        for role, (want, args) in pinocchio_reference(pm, q, v, a, tau).items():
            assert relative_error(getattr(twin, role)(*args, p=p), want, floor=1.0) < TOLERANCE, role


@pytest.mark.pinocchio
def test_a_links_own_inertial_data_through_its_helper(tmp_path, rng):
    """--inertial-parameters wrist_3_link: set_inertial_wrist_3_link(m, c, I) gives Pinocchio's model of the URDF
    whose <inertial> of that link says the same (mass 0.5 to 50 kg, a full tensor)."""
    import re

    from aggsym.contract import select_routines

    path = robot_path("ur5")
    model = with_inertial_parameters(aggsym.load(path), ["wrist_3_link"])
    write(generate(select_routines(model, ["gravity"]), targets="numpy"), tmp_path)
    module = import_module(tmp_path / f"{model.name}.py")
    twin = NumericTwin(model)
    text = path.read_text()
    start = text.index('<link name="wrist_3_link"')
    end = text.index("</link>", start)
    for mass in (0.5, 50.0):
        com = rng.normal(size=3) * 0.05
        J = np.array([[0.02, 0.004, -0.001], [0.004, 0.03, 0.002], [-0.001, 0.002, 0.025]]) * mass
        p = module.set_inertial_wrist_3_link(mass, com, urdf_inertia_order(J))
        own = with_payload_link("<robot></robot>", "x", mass, com, J)
        inertial = re.search(r"<inertial>.*</inertial>", own).group(0)
        body = re.sub(r"<inertial>.*?</inertial>", inertial, text[start:end], flags=re.S)
        pm = pin.buildModelFromXML(text[:start] + body + text[end:])
        for _ in range(2):
            q, v, a, tau = rng.uniform(-1.5, 1.5, model.nq), *rng.normal(size=(3, model.nq))
            for role, (want, args) in pinocchio_reference(pm, q, v, a, tau).items():
                assert relative_error(getattr(twin, role)(*args, p=p), want, floor=1.0) < TOLERANCE, (mass, role)


# ---------------------------------------------------------------------------------------------------------------
# refusals


def _run(capsys, *args):
    """The command line in this process: (exit code, what it printed on stderr)."""
    capsys.readouterr()
    code = cli.main([str(a) for a in args])
    return code, capsys.readouterr().err


def test_links_welded_to_the_world_are_refused(tmp_path, capsys):
    """A payload or inertial parameters on a link that never moves: exit 2, the link, why, and what to do."""
    ur5 = robot_path("ur5")
    for option, link in (("--payload", "base_link"), ("--payload", "world"), ("--inertial-parameters", "base_link")):
        code, err = _run(capsys, "generate", ur5, "-o", tmp_path / "out", option, link)
        assert code == 2, err
        assert f"{option}: link {link!r} is welded to the world" in err, err
        assert "never enter the equations of motion" in err and "internal error" not in err
        assert not (tmp_path / "out").exists()
    with pytest.warns(UserWarning, match="left out .*'base_link'"):
        model = with_inertial_parameters(aggsym.load(ur5), ["all"])
    assert not any(n.endswith("_base_link") for n in (p.name for p in model.parameters))
    assert "m_shoulder_link" in [p.name for p in model.parameters]
    floating = with_inertial_parameters(aggsym.load(ur5, floating_base=True), payload="base_link")  # moves now
    assert floating.inertial_blocks[0].helper == "set_payload_base_link"


def test_the_options_are_refused_where_they_mean_nothing(tmp_path, capsys):
    """--gravity-parameter and --passive on a YAML model (it writes gravity and forces itself), gravity made a
    parameter twice, an unknown --passive mode: exit 2 or an error naming the problem."""
    from conftest import model_path

    for option in ("--gravity-parameter", "--passive=include"):
        code, err = _run(capsys, "generate", model_path("double_pendulum"), "-o", tmp_path / "o", option)
        assert code == 2 and "the YAML reader does not accept" in err, err
    model = with_gravity_parameters(aggsym.load(robot_path("ur5")))
    with pytest.raises(AggsymError, match="already has a parameter named 'gravity_x'"):
        with_gravity_parameters(model)
    for payload, message in (("tool0,tool0", "--payload names a link twice"), (",", "--payload: no link named")):
        code, err = _run(capsys, "generate", robot_path("ur5"), "-o", tmp_path / "o", "--payload", payload)
        assert code == 2 and message in err, err
    with pytest.raises(SystemExit) as stop:  # (argparse)
        cli.main(["generate", str(robot_path("ur5")), "-o", str(tmp_path / "o"), "--passive", "sometimes"])
    assert stop.value.code == 2 and "invalid choice: 'sometimes'" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------------------------
# --passive include / exclude

def pendulum(m, l, d, f) -> str:
    """A point mass m at distance l below a y hinge with damping d and Coulomb friction f."""
    return chain("damped", segment("hinge", "arm", "continuous", axis="0 1 0", damping=d, friction=f, mass=m,
                                   com=(0, 0, -l)))


def test_passive_include_is_the_hand_written_damped_pendulum(tmp_path, rng):
    """A point mass m at distance l on a y hinge with damping d and Coulomb friction f:
    m l^2 qdd + m g l sin(q) + d qd + f sign(qd) = tau (inverse and forward dynamics, C and NumPy)."""
    m, l, d, f = 1.7, 0.4, 0.35, 0.8
    path = written(tmp_path / "damped.urdf", pendulum(m, l, d, f))
    code = cli.main(["generate", str(path), "-o", str(tmp_path / "inc"), "--passive", "include", "-q"])
    assert code == 0
    manifest = json.loads((tmp_path / "inc" / "damped.json").read_text())
    assert manifest["conservative"] is False and manifest["passive"]["mode"] == "include"
    assert manifest["passive"]["damping"] == ["damping_hinge"] and manifest["passive"]["friction"] == ["friction_hinge"]
    module = import_module(tmp_path / "inc" / "damped.py")
    lib = CLibrary(compile_shared(tmp_path / "inc" / "damped.c", tmp_path / "libdamped.so", extra=("-O1",)), manifest)
    for q, qd, qdd in [(0.3, 1.2, -0.4), (-1.1, -0.7, 2.0), (2.0, 0.0, 0.5)]:
        tau = m * l * l * qdd + m * 9.81 * l * np.sin(q) + d * qd + f * np.sign(qd)
        for got in (module.inverse_dynamics([q], [qd], [qdd]), lib.call("inverse_dynamics", [q], [qd], [qdd])):
            assert abs(np.ravel(got)[0] - tau) < 1e-12 * max(1.0, abs(tau))
        for got in (module.forward_dynamics([q], [qd], [tau]), lib.call("forward_dynamics", [q], [qd], [tau])):
            assert abs(np.ravel(got)[0] - qdd) < 1e-12 * max(1.0, abs(qdd))
        assert abs(np.ravel(module.passive_forces([q], [qd]))[0] + d * qd + f * np.sign(qd)) < 1e-15
    p = module.PARAMETERS.copy()
    p[[0, 1]] = (3.0, 0.0)  # damping changed at run time, friction off
    tau = np.ravel(module.inverse_dynamics([0.3], [1.2], [0.0], p))[0]
    assert abs(tau - (m * 9.81 * l * np.sin(0.3) + 3.0 * 1.2)) < 1e-12
    code = cli.main(["generate", str(path), "-o", str(tmp_path / "exc"), "-q"])
    excluded = json.loads((tmp_path / "exc" / "damped.json").read_text())
    assert excluded["conservative"] is True and excluded["passive"]["mode"] == "exclude"
    plain = import_module(tmp_path / "exc" / "damped.py")
    assert abs(np.ravel(plain.inverse_dynamics([0.3], [1.2], [0.0]))[0] - m * 9.81 * l * np.sin(0.3)) < 1e-12


@pytest.mark.pinocchio
def test_passive_include_against_pinocchio_with_the_same_damping_and_friction(rng):
    """Panda with --passive include: tau = rnea + D qd + F sign(qd) and qdd = aba(tau - D qd - F sign(qd)), D and F
    Pinocchio's own damping and friction read from the file; then both changed through p at run time."""
    path = robot_path("panda")
    with pytest.warns(UserWarning):
        model = with_passive_included(aggsym.load(path))
    assert not model.conservative
    twin = NumericTwin(model)
    pm = pin.buildModelFromUrdf(str(path))
    names = [p.name for p in model.parameters]
    joints = [c.name for c in model.coordinates]
    D0, F0 = np.array(pm.damping), np.array(pm.friction)
    p0 = np.array(model.parameter_values)
    assert np.array_equal(p0[[names.index(f"damping_{j}") for j in joints]], D0)
    assert np.array_equal(p0[[names.index(f"friction_{j}") for j in joints]], F0)
    D1, F1 = rng.uniform(0, 2, model.nv) * 10.0 ** rng.integers(-2, 2, model.nv), rng.uniform(0, 3, model.nv)
    p1 = p0.copy()
    p1[[names.index(f"damping_{j}") for j in joints]] = D1
    p1[[names.index(f"friction_{j}") for j in joints]] = F1
    for p, D, F in ((p0, D0, F0), (p1, D1, F1)):
        for _ in range(3):
            q, v, a, tau = rng.uniform(-1.5, 1.5, model.nq), *rng.normal(size=(3, model.nq))
            Q = pinocchio_q(pm, q)
            passive = D * v + F * np.sign(v)
            want = pin.rnea(pm, pm.createData(), Q, v, a) + passive
            assert relative_error(twin.inverse_dynamics(q, v, a, p=p), want, floor=1.0) < TOLERANCE
            want = pin.aba(pm, pm.createData(), Q, v, tau - passive)
            assert relative_error(twin.forward_dynamics(q, v, tau, p=p), want, floor=1.0) < TOLERANCE
            assert relative_error(twin.passive_forces(q, v, p=p), -passive, floor=1.0) < 1e-14


# ---------------------------------------------------------------------------------------------------------------
# what the header says


# the singular arm: a mass on j1 and a massless link on j2
MASSLESS = chain("arm2", segment("j1", "a", axis="0 0 1", limit=(-1, 1, 1, 1), damping=0.1, mass=1, com="0 0 0.2",
                                 inertia=(0.01, 0.01, 0.01)),
                 segment("j2", "b", xyz="0 0 0.4", axis="0 1 0", limit=(-1, 1, 1, 1)))


@pytest.mark.compiler
def test_the_header_says_what_each_routine_holds_and_compiles_warning_free(tmp_path, capsys):
    """The singular arm: forward dynamics left out, the header says why and which flag brings it back; the
    passive notes sit next to the routines; a controller using NULL, the helper and the macros compiles with
    -std=c99 -Wall -Wextra -Wpedantic -Werror (C) and as C++."""
    path = written(tmp_path / "arm2.urdf", MASSLESS)
    code = cli.main(["generate", str(path), "-o", str(tmp_path / "g"), "-q", "--payload", "b"])
    assert code == 0
    assert "forward_dynamics, inertia_inverse, transvective_factors left out" in capsys.readouterr().err
    header = (tmp_path / "g" / "arm2.h").read_text()
    assert "#include <stddef.h>" in header
    for role in ("forward_dynamics", "inertia_inverse"):
        line = next(x for x in header.splitlines() if x.startswith(f"/* arm2_{role}: left out"))
        assert "A(q) is singular" in line and "--armature" in line, line
    lines = header.splitlines()
    for role in ("inverse_dynamics", "nonlinear_effects"):
        k = next(i for i, x in enumerate(lines) if x.startswith(f"void arm2_{role}("))
        assert "NOT included" in lines[k - 1] and "--passive include" in lines[k - 1], lines[k - 1]
    assert "static inline void arm2_set_payload_b(double *p, double m, const double c[3], const double I[6])" \
        in header and "ixy = -integral of x*y dm" in header
    controller = tmp_path / "g" / "controller.c"
    controller.write_text(
        '#include "arm2.h"\n'
        "int main(void)\n{\n"
        "    double p[ARM2_NP] = ARM2_P_DEFAULTS;\n"
        "    const double c[3] = {0.0, 0.0, 0.05}, I[6] = {0.001, 0.0, 0.0, 0.001, 0.0, 0.002};\n"
        "    double q[ARM2_NQ] = {0.1, 0.2}, qd[ARM2_NQ] = {0.0, 0.0}, qdd[ARM2_NQ] = {0.0, 0.0};\n"
        "    double tau[ARM2_INVERSE_DYNAMICS_SIZE];\n"
        "    arm2_set_payload_b(p, 0.5, c, I);\n"
        "    arm2_inverse_dynamics(q, qd, qdd, NULL, tau);\n"
        "    arm2_inverse_dynamics(q, qd, qdd, p, tau);\n"
        "    return tau[0] == tau[0] ? 0 : 1;\n}\n")
    flags = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror"]
    run = subprocess.run([compiler(), *flags, "-o", str(tmp_path / "controller"), str(controller),
                          str(tmp_path / "g" / "arm2.c"), "-lm"], capture_output=True, text=True)
    assert run.returncode == 0 and not run.stderr, run.stderr
    assert subprocess.run([str(tmp_path / "controller")]).returncode == 0
    cxx = subprocess.run(["g++", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-x", "c++", "-fsyntax-only",
                          str(controller)], capture_output=True, text=True)
    assert cxx.returncode == 0, cxx.stderr


def test_passive_include_header_and_manifest(tmp_path, capsys):
    """With --passive include the routines' notes say what is included, and the manifest records it; the regressor
    (tau = Y pi, which damping breaks) is refused with the reason."""
    path = written(tmp_path / "arm2.urdf", MASSLESS)
    code = cli.main(["generate", str(path), "-o", str(tmp_path / "g"), "-q", "--passive", "include",
                     "--armature", "0.01", "--gravity-parameter"])
    assert code == 0
    header = (tmp_path / "g" / "arm2.h").read_text()
    lines = header.splitlines()
    for role in ("inverse_dynamics", "forward_dynamics", "nonlinear_effects"):
        k = next(i for i, x in enumerate(lines) if x.startswith(f"void arm2_{role}("))
        assert "included: A(q) qdd + b(q, qd) + g(q) + D qd + F sign(qd) = tau" in lines[k - 1], lines[k - 1]
    assert "left out" not in header  # --armature brings forward dynamics back
    assert "#define ARM2_P_gravity_z 4" in header
    manifest = json.loads((tmp_path / "g" / "arm2.json").read_text())
    assert manifest["passive"]["included_in"] == ["inverse_dynamics", "forward_dynamics", "nonlinear_effects"]
    assert manifest["conservative"] is False and not manifest["omitted"]
    assert [p["name"] for p in manifest["parameters"]][-3:] == ["gravity_x", "gravity_y", "gravity_z"]
    capsys.readouterr()
    code = cli.main(["generate", str(path), "-o", str(tmp_path / "r"), "-q", "--passive", "include",
                     "--armature", "0.01", "--routines", "default,regressor"])
    assert code == 2 and "tau = Y pi does not hold: the joints' damping" in capsys.readouterr().err
