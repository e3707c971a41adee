"""Point-mass links (zero inertia tensors) placed near their joint's axis, angles written with 5 digits, masses over
six decades (issue 53, item 3): every entry of A within 1e-14 of sqrt(A_ii A_jj) of Pinocchio's crba, fixed base and
free-flyer."""
from __future__ import annotations

import numpy as np
import pytest

import aggsym
from aggsym.twin import NumericTwin
from pinocchio_reference import pin, pinocchio_q

AXES = ((1, 0, 0), (0, 1, 0), (0, 0, 1))


def point_mass_chain(seed: int) -> str:
    """A branching tree of 6 links, each a point mass at 0.3-0.8 along its joint's axis and within 0.02 of it."""
    rng = np.random.default_rng(seed)
    links, joints = [], []
    axes = [AXES[int(rng.integers(3))] for _ in range(6)]
    for k in range(6):
        c = np.array(axes[k], float) * rng.uniform(0.3, 0.8) + rng.normal(scale=0.02, size=3)
        m = 10.0 ** rng.uniform(-3, 3)
        links.append(f'<link name="l{k}"><inertial><origin xyz="{" ".join(repr(float(x)) for x in c)}"/>'
                     f'<mass value="{m!r}"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>'
                     f'</inertial></link>')
    for k in range(1, 6):
        parent = int(rng.integers(max(0, k - 2), k))
        o = rng.normal(scale=0.3, size=3)
        rpy = [round(float(x), 5) for x in rng.choice([1.5708, -1.5708, 3.1416, 0.0, rng.uniform(-3, 3)], 3)]
        joints.append(f'<joint name="j{k}" type="revolute"><parent link="l{parent}"/><child link="l{k}"/>'
                      f'<origin xyz="{" ".join(repr(float(x)) for x in o)}" rpy="{" ".join(map(repr, rpy))}"/>'
                      f'<axis xyz="{" ".join(map(str, axes[k]))}"/>'
                      f'<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>')
    return '<?xml version="1.0"?><robot name="point_masses">' + "".join(links + joints) + "</robot>\n"


@pytest.mark.pinocchio
@pytest.mark.parametrize("base", [None, "quaternion"])
def test_point_masses_near_their_axes_keep_their_digits(base, tmp_path):
    worst = 0.0
    for seed in range(12):
        path = tmp_path / f"tree{seed}.urdf"
        path.write_text(point_mass_chain(seed))
        model = aggsym.load(path, floating_base=base)
        twin = NumericTwin(model)
        if base:
            pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
        else:
            pm = pin.buildModelFromUrdf(str(path))
        data = pm.createData()
        rng = np.random.default_rng(seed)
        for _ in range(3):
            q = np.round(rng.uniform(-2, 2, model.nq), 5)
            if base:
                x = rng.normal(size=4)
                q[3:7] = x / np.linalg.norm(x)
                Q = q  # (Pinocchio's free-flyer q: the same seven entries, then the hinges)
            else:
                Q = pinocchio_q(pm, q)
            A = np.array(twin.inertia(q)).reshape(model.nv, model.nv)
            P = pin.crba(pm, data, Q)
            P = np.triu(P) + np.triu(P, 1).T
            scale = np.sqrt(np.outer(np.diag(P), np.diag(P)))
            worst = max(worst, float(np.max(np.abs(A - P) / scale)))
    assert worst < 1e-14


def test_a_constant_turn_near_a_right_angle_keeps_the_small_diagonal_entry():
    """Rigid.rotated with cos^2 given (the constant rotations of move_to_parent): a point mass far along x and near
    it, turned by 1.5708 about z, so that its small theta_xx (about 2e-5 of theta_yy) becomes theta'_yy: kept to a
    few units in the last place (by D + (A - D) c^2), where the double-angle form A - (A - D) s^2 loses digits to
    the large A."""
    from fractions import Fraction

    from aggsym.mechanics.aggregates import Rigid

    m, r = 2.0, (0.61, 0.0013, -0.0021)
    theta = tuple(tuple((m * (sum(x * x for x in r) if i == j else 0) - m * r[i] * r[j]) for j in range(3))
                  for i in range(3))
    th = Rigid(m, tuple(m * x for x in r), theta)
    c, s = np.cos(1.5708), np.sin(1.5708)
    exact = [[Fraction(x) for x in row] for row in theta]
    C, S = Fraction(c), Fraction(s)
    # (R theta R^T)_yy for R about z (axis 3): s^2 theta_xx + 2 s c theta_xy + c^2 theta_yy
    want = float(S * S * exact[0][0] + 2 * S * C * exact[0][1] + C * C * exact[1][1])
    direct = th.rotated(3, c, s, s * s, s * c, c * c).theta[1][1]
    double_angle = th.rotated(3, c, s, s * s, s * c).theta[1][1]
    assert abs(direct - want) <= 4 * np.spacing(want)
    assert abs(double_angle - want) > abs(direct - want)


@pytest.mark.pinocchio
def test_the_status_of_forward_dynamics_follows_the_conditioning(tmp_path):
    """The same point-mass trees on a free-flyer (the base a point mass: A regular at generic configurations, not
    proved regular everywhere, so forward dynamics has a status; with a fixed base every hinge moves its point mass
    and A is proved regular, no status): a singular state is reported only where Pinocchio's M has cond >= 1e11 (so never
    where it is well conditioned), and where none is, forward dynamics agrees with Pinocchio's aba as A's
    conditioning allows (no false report; tests/test_regularity.py holds the reports at a point-mass head's
    singular set).  Half the states have one hinge angle scaled towards 0 (by 1e-3 to 1e-11)."""
    from aggsym.contract import reports_singular_states

    base = "quaternion"
    counted = {"reported": 0, "regular": 0}
    for seed in range(8):
        path = tmp_path / f"tree{seed}.urdf"
        path.write_text(point_mass_chain(seed))
        model = aggsym.load(path, floating_base=base)
        assert reports_singular_states(model) and not reports_singular_states(aggsym.load(path))
        twin = NumericTwin(model)
        pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
        data = pm.createData()
        rng = np.random.default_rng(100 + seed)
        for k in range(8):
            q = np.round(rng.uniform(-2, 2, model.nq), 5)
            x = rng.normal(size=4)
            q[3:7] = x / np.linalg.norm(x)
            if k % 2:
                q[-1 - int(rng.integers(5))] *= 10.0 ** -int(rng.integers(3, 12))
            Q = q  # (Pinocchio's free-flyer q: the same seven entries, then the hinges)
            P = pin.crba(pm, data, Q)
            cond = np.linalg.cond(np.triu(P) + np.triu(P, 1).T)
            qd, tau = rng.normal(size=(2, model.nv))
            try:
                with np.errstate(all="ignore"):
                    qdd = twin.forward_dynamics(q, qd, tau)
            except np.linalg.LinAlgError:
                assert cond >= 1e11, cond
                counted["reported"] += 1
                continue
            want = pin.aba(pm, data, Q, qd, tau)
            assert np.max(np.abs(qdd - want)) <= 1e-13 * cond * np.max(np.abs(want)), cond
            counted["regular"] += 1
    assert counted["regular"] > 20, counted
