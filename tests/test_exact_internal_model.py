"""The internal model is the model as read, to round-off, on files as calibration and rounding write them (issue 30,
point 1).

The routines of the coordinates alone run on internal frames (:mod:`aggsym.model.transforms.reframe`), chosen from the
file's geometry with tolerances.  A tolerance may choose between exact computations; it must never replace a value
by a nearby one.  Nearly parallel or nearly intersecting axes are where such a choice used to cost digits (the feet
of the common normal of axes 1e-6 rad from parallel lie a million lengths away) or move the robot (axes "parallel"
within 1e-9, angles "right" within 1e-12).  So every joint axis and origin rotation of real robots and of random
trees is tilted by random angles of 1e-9 to 1e-3 rad, or written to 5-7 significant digits as files do, and lengths
and masses are scaled across 1e-4 to 1e2; A, b + g, g, inverse and forward dynamics and A^-1 of both internal models
(the two that :func:`aggsym.codegen.generate.internal_model` chooses between) must equal Pinocchio's on the same
file to 1e-12, relative to the largest entry.  A^-1 (against the 40-digit inverse of Pinocchio's A) to 1e-12 or,
where A is ill-conditioned, to cond(A) times four unit round-offs: how far the inverses of two matrices that agree
to round-off can be (random tree 1, lengths 0.025 and masses 0.0016, has cond(A) = 3.8e5; its A agrees to
9e-16, and the inverses by 1.0e-12 for the model as read, 1.5e-12 for an internal model, on an AMD EPYC host).
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import mpmath
import numpy as np
import pytest

import aggsym
from aggsym.contract import ROUTINES, run
from aggsym.core.backend import Numeric
from aggsym.mechanics.bound import bind
from aggsym.model.transforms.reframe import reframe
from helpers import ROBOTS, relative_error, robots_directory
from pinocchio_reference import pin, pinocchio_model, pinocchio_q
from random_trees import random_urdf

pytestmark = [pytest.mark.pinocchio, pytest.mark.filterwarnings("ignore::aggsym.errors.ModelWarning")]

EXACT = 1e-12
UNIT = np.finfo(float).eps / 2
FILES = {**ROBOTS, "so100": "so_arm_description/urdf/so100.urdf", "xarm7": "xarm_description/urdf/xarm7.urdf",
         "z1": "z1_description/urdf/z1.urdf"}
FILES.pop("talos")  # (32 coordinates: the benchmark covers it; the suite keeps to the smaller trees)
ROLES = ("inertia", "nonlinear_effects", "gravity", "inverse_dynamics", "forward_dynamics", "inertia_inverse")


def _numbers(text: str) -> list:
    return [float(x) for x in text.split()]


def _write(values, digits) -> str:
    return " ".join(repr(float(v)) if digits is None else f"{v:.{digits}g}" for v in values)


def _tilt(rng, v, angle):
    """v turned by ``angle`` about a random axis orthogonal to it (its length kept)."""
    v = np.asarray(v, float)
    d = rng.normal(size=3)
    d -= d.dot(v) * v / v.dot(v)
    d *= np.linalg.norm(v) / np.linalg.norm(d)
    return v * math.cos(angle) + d * math.sin(angle)


def perturbed(text: str, rng, tilt=(1e-9, 1e-3), digits=None, length=1.0, mass=1.0) -> str:
    """The URDF ``text`` with every movable joint's axis tilted and every origin's roll, pitch and yaw moved by
    log-uniform random angles in ``tilt`` (None: not moved), numbers written to ``digits`` significant digits (None:
    every digit), lengths scaled by ``length`` and masses by ``mass`` (inertias by mass * length^2)."""
    root = ET.fromstring(text)

    def angle():
        return float(rng.choice((-1, 1)) * 10 ** rng.uniform(*np.log10(tilt)))

    for joint in root.iter("joint"):
        axis = joint.find("axis")
        if axis is not None and joint.get("type") != "fixed" and tilt is not None:
            axis.set("xyz", _write(_tilt(rng, _numbers(axis.get("xyz")), abs(angle())), digits))
        elif axis is not None and digits is not None:
            axis.set("xyz", _write(_numbers(axis.get("xyz")), digits))
    for origin in root.iter("origin"):
        if "quat_xyzw" in origin.attrib:
            continue
        rpy = _numbers(origin.get("rpy", "0 0 0"))
        if tilt is not None:
            rpy = [a + angle() for a in rpy]
        origin.set("rpy", _write(rpy, digits))
        origin.set("xyz", _write([length * x for x in _numbers(origin.get("xyz", "0 0 0"))], digits))
    for m in root.iter("mass"):
        m.set("value", _write([mass * float(m.get("value"))], digits))
    for inertia in root.iter("inertia"):
        for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
            if key in inertia.attrib:
                inertia.set(key, _write([mass * length ** 2 * float(inertia.get(key))], digits))
    for tag in ("visual", "collision"):  # (meshes Pinocchio would not need either)
        for parent in root.iter("link"):
            for el in parent.findall(tag):
                parent.remove(el)
    return ET.tostring(root, encoding="unicode")


def pinocchio_outputs(path, q, qd, qdd, tau) -> dict:
    """Pinocchio's A, b + g, g, inverse and forward dynamics, and A^-1 as the 40-digit inverse of its A (its own
    computeMinverse loses digits on the worse-conditioned trees: 3e-11 where cond(A) = 4e5, against which aggsym's
    is within 5e-15)."""
    pm = pin.buildModelFromUrdf(str(path))
    data = pm.createData()
    Q = pinocchio_q(pm, q)
    M = pin.crba(pm, data, Q)
    M = np.triu(M) + np.triu(M, 1).T
    mpmath.mp.dps = 40
    try:
        Minv = np.array(mpmath.inverse(mpmath.matrix(M.tolist())).tolist(), float)
    except ZeroDivisionError:  # a coordinate that moves no mass
        Minv = np.full_like(M, np.nan)
    return {"inertia": M, "nonlinear_effects": pin.nonLinearEffects(pm, data, Q, qd),
            "gravity": pin.computeGeneralizedGravity(pm, data, Q), "inverse_dynamics": pin.rnea(pm, data, Q, qd, qdd),
            "forward_dynamics": pin.aba(pm, data, Q, qd, tau), "inertia_inverse": Minv}


def ours(model, role, x) -> np.ndarray:
    routine = ROUTINES[role]
    flat = run(routine, bind(model, Numeric()), {k: x[k] for k in routine.inputs if k != "p"})[0]
    return np.array(flat, float)


def assert_exact(path, rng, states=2):
    """Both internal models of the file at ``path`` against Pinocchio on it, on random states."""
    model = aggsym.load(path)
    inner = [reframe(model, fewest=False), reframe(model, fewest=True)]
    assert all(m is not model for m in inner)  # (the internal model is what is tested)
    n = model.nv
    for _ in range(states):
        q = rng.uniform(-math.pi, math.pi, n)
        qd, qdd, tau = rng.normal(size=(3, n))
        ref = pinocchio_outputs(path, q, qd, qdd, tau)
        x = {"q": list(q), "qd": list(qd), "qdd": list(qdd), "tau": list(tau)}
        tolerance = {"inertia_inverse": max(EXACT, 4 * UNIT * np.linalg.cond(ref["inertia"]))}
        for m in inner:
            for role in ROLES:
                try:
                    got = ours(m, role, x).reshape(np.shape(ref[role]))
                except ZeroDivisionError:  # a coordinate that moves no mass: A(q) singular, in the model as read too
                    assert role in ("forward_dynamics", "inertia_inverse")
                    with pytest.raises(ZeroDivisionError):
                        ours(model, role, x)
                    continue
                assert relative_error(got, ref[role]) <= tolerance.get(role, EXACT), \
                    (path.name, role, relative_error(got, ref[role]))


@pytest.mark.parametrize("robot", sorted(FILES))
def test_robots_with_tilted_axes_and_origins(robot, tmp_path):
    """Every axis and origin rotation tilted by 1e-9 to 1e-3 rad, as kinematic calibration writes them."""
    rng = np.random.default_rng(sum(map(ord, robot)))
    path = tmp_path / f"{robot}.urdf"
    path.write_text(perturbed((robots_directory() / FILES[robot]).read_text(), rng))
    assert_exact(path, rng)


@pytest.mark.parametrize("robot", ["hyq", "panda", "ur5", "xarm7"])
@pytest.mark.parametrize("digits", [5, 6, 7])
def test_robots_written_to_few_digits(robot, digits, tmp_path):
    """Angles, axes and lengths written to 5-7 significant digits (1.5708, 3.14159), tilted or not."""
    rng = np.random.default_rng(digits)
    path = tmp_path / f"{robot}.urdf"
    tilt = None if digits == 5 else (1e-6, 1e-3)
    path.write_text(perturbed((robots_directory() / FILES[robot]).read_text(), rng, tilt=tilt, digits=digits))
    assert_exact(path, rng)


@pytest.mark.parametrize("seed", range(6))
def test_random_trees_tilted_and_scaled(seed, tmp_path):
    """Random branching trees (general axes, prismatic and fixed joints, rotated inertial frames), tilted, and scaled
    to lengths and masses from 1e-4 to 1e2."""
    rng = np.random.default_rng(300 + seed)
    length, mass = (10 ** rng.uniform(-4, 2) for _ in range(2))
    path = tmp_path / "tree.urdf"
    path.write_text(perturbed(random_urdf(seed), rng, length=length, mass=mass))
    assert_exact(path, rng)


@pytest.mark.parametrize("length,mass", [(1e-4, 1e-4), (1e-4, 1e2), (1e2, 1e-4), (1e2, 1e2)])
def test_arms_at_the_ends_of_the_scales(length, mass, tmp_path):
    """UR5 and so100 (nearly parallel axes once tilted) with lengths and masses at 1e-4 and 1e2."""
    rng = np.random.default_rng(7)
    for robot in ("ur5", "so100"):
        path = tmp_path / f"{robot}.urdf"
        path.write_text(perturbed((robots_directory() / FILES[robot]).read_text(), rng, length=length, mass=mass))
        assert_exact(path, rng, states=1)


@pytest.mark.parametrize("base", [True, "quaternion"])
def test_floating_bases_tilted(base, tmp_path):
    """HyQ with a free root (the Euler pair, Pinocchio's free-flyer), every axis and origin tilted: A, b + g, inverse
    and forward dynamics of the internal model against Pinocchio's model with that root."""
    rng = np.random.default_rng(5)
    path = tmp_path / "hyq.urdf"
    path.write_text(perturbed((robots_directory() / FILES["hyq"]).read_text(), rng))
    model = aggsym.load(path, floating_base=base)
    inner = reframe(model)
    assert inner is not model
    if base is True:
        pm = pinocchio_model(path, floating_base=True)
        q = rng.uniform(-1, 1, model.nq)
        Q = pinocchio_q(pm, q)
    else:
        pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
        Q = q = pin.randomConfiguration(pm, -np.ones(pm.nq), np.ones(pm.nq))
    data = pm.createData()
    qd, qdd, tau = rng.normal(size=(3, model.nv))
    M = pin.crba(pm, data, Q)
    ref = {"inertia": np.triu(M) + np.triu(M, 1).T, "nonlinear_effects": pin.nonLinearEffects(pm, data, Q, qd),
           "inverse_dynamics": pin.rnea(pm, data, Q, qd, qdd), "forward_dynamics": pin.aba(pm, data, Q, qd, tau)}
    x = {"q": list(q), "qd": list(qd), "qdd": list(qdd), "tau": list(tau)}
    for role, value in ref.items():
        assert relative_error(ours(inner, role, x).reshape(np.shape(value)), value) <= EXACT, role


def test_the_perturbation_reaches_the_file(tmp_path):
    """The test's own perturbation: every movable axis and origin of the file moved (so the comparisons above are
    of changed geometry), by at most the largest tilt."""
    text = (robots_directory() / FILES["ur5"]).read_text()
    new = perturbed(text, np.random.default_rng(0))
    old_axes = [_numbers(a.get("xyz")) for a in ET.fromstring(text).iter("axis")]
    new_axes = [_numbers(a.get("xyz")) for a in ET.fromstring(new).iter("axis")]
    for a, b in zip(old_axes, new_axes):
        angle = math.acos(min(1.0, np.dot(a, b) / np.linalg.norm(a) / np.linalg.norm(b)))
        assert 0 < angle <= 1.1e-3


def test_angles_are_snapped_only_on_request_and_then_recorded(tmp_path):
    """xarm7 writes its right angles as 1.5708: by default they stay (the manifest has no snapped_angles and the
    dynamics are Pinocchio's on the file to 1e-12); ``--snap-angles 1e-4`` takes them as pi/2, lists every angle it
    moved in the manifest (where, value, multiple taken) and gives Pinocchio's dynamics of the file with those
    angles written as pi/2; a tolerance outside (0, pi/4) is exit 2."""
    import json
    import subprocess
    import sys

    source = robots_directory() / FILES["xarm7"]
    out = {}
    for tag, extra in (("default", []), ("snapped", ["--snap-angles", "1e-4"])):
        folder = tmp_path / tag
        done = subprocess.run([sys.executable, "-m", "aggsym.cli", "generate", str(source), "-o", str(folder), "-q",
                               "--routines", "inertia,inverse_dynamics", *extra], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        out[tag] = json.loads(next(folder.glob("*.json")).read_text())
    assert "snapped_angles" not in out["default"]
    record = out["snapped"]["snapped_angles"]
    assert record["tolerance"] == 1e-4
    assert len(record["angles"]) == 6 and all(abs(abs(a["value"]) - 1.5708) < 1e-12 for a in record["angles"])
    assert {a["taken_as"] for a in record["angles"]} == {"1*pi/2", "-1*pi/2"}
    assert all('<joint name="joint' in a["where"] and "line" in a["where"] for a in record["angles"])
    ops = {tag: sum(m["ops"]["inverse_dynamics"][k] for k in ("mul", "add", "div")) for tag, m in out.items()}
    assert ops["snapped"] < ops["default"]

    rng = np.random.default_rng(3)
    model = aggsym.load(source, snap_angles=1e-4)
    assert model.meta["snapped_angles"] == record
    exact = tmp_path / "xarm7_pi_2.urdf"
    exact.write_text(source.read_text().replace('"1.5708 ', f'"{math.pi / 2!r} ').replace(
        '"-1.5708 ', f'"{-math.pi / 2!r} '))
    n = model.nv
    q = rng.uniform(-math.pi, math.pi, n)
    qd, qdd, tau = rng.normal(size=(3, n))
    ref = pinocchio_outputs(exact, q, qd, qdd, tau)
    x = {"q": list(q), "qd": list(qd), "qdd": list(qdd), "tau": list(tau)}
    for role in ("inertia", "inverse_dynamics", "forward_dynamics"):
        got = ours(reframe(model), role, x).reshape(np.shape(ref[role]))
        assert relative_error(got, ref[role]) <= EXACT, role
    bad = subprocess.run([sys.executable, "-m", "aggsym.cli", "generate", str(source), "-o", str(tmp_path / "bad"),
                          "--snap-angles", "1"], capture_output=True, text=True)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr and "pi/4" in bad.stderr
    assert not (tmp_path / "bad").exists()
