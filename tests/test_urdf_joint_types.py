"""URDF ``planar`` and ``floating`` joints against Pinocchio (``spherical``, the ball joint: tests/test_ball_joint.py).

The reference is a Pinocchio model built here by hand from the numbers of the URDF written below, not from our
reader: each planar joint is Pinocchio's composite of its two translations and its rotation in the joint frame
turned so that its axis is e_i (for the axis z: PX PY RZ, Pinocchio's JointModelPlanar with q = (x, y, angle)), each
floating joint the composite PX PY PZ RX RY RZ (the book's Euler pair, as ``--floating-base euler``).  A, b + g,
inverse and forward dynamics at random states agree to 1e-10 relative.  A planar joint about z is also checked
against Pinocchio's own import of the file (its JointModelPlanar, velocities in the child's axes).
"""
from __future__ import annotations

import numpy as np
import pytest

import aggsym
from helpers import relative_error
from pinocchio_reference import pin
from robot_builder import chain, segment

pytestmark = pytest.mark.pinocchio

TOL = 1e-10

# (name, mass, com, inertia ixx ixy ixz iyy iyz izz); the tensors are full and the centres off the origins
LINKS = {
    "base": (2.0, (0.01, -0.02, 0.05), (0.03, 0.001, -0.002, 0.025, 0.0015, 0.02)),
    "arm": (1.3, (0.02, 0.01, 0.15), (0.012, -0.0005, 0.0007, 0.011, 0.0009, 0.004)),
    "slider": (0.7, (-0.03, 0.02, 0.01), (0.004, 0.0002, -0.0003, 0.005, 0.0001, 0.003)),
    "tip": (0.4, (0.05, 0.0, -0.01), (0.001, 0.0001, 0.0002, 0.0015, -0.0001, 0.0012)),
}
# (name, type, parent, child, xyz, rpy, axis)
JOINTS = [
    ("free", "floating", "world", "base", (0.1, -0.2, 0.3), (0.2, -0.1, 0.4), None),
    ("shoulder", "revolute", "base", "arm", (0.0, 0.05, 0.1), (0.0, 0.3, 0.0), (0.0, 1.0, 0.0)),
    ("table", "planar", "arm", "slider", (0.0, 0.0, 0.3), (0.1, 0.2, -0.3), None),  # axis given per test
    ("wrist", "continuous", "slider", "tip", (0.08, 0.0, 0.02), (0.0, 0.0, 0.5), (1.0, 0.0, 0.0)),
]


def urdf(planar_axis) -> str:
    links = ['<link name="world"/>']
    for name, (m, c, (ixx, ixy, ixz, iyy, iyz, izz)) in LINKS.items():
        links.append(f'<link name="{name}"><inertial><origin xyz="{c[0]} {c[1]} {c[2]}"/><mass value="{m}"/>'
                     f'<inertia ixx="{ixx}" ixy="{ixy}" ixz="{ixz}" iyy="{iyy}" iyz="{iyz}" izz="{izz}"/>'
                     f'</inertial></link>')
    joints = []
    for name, jtype, parent, child, xyz, rpy, axis in JOINTS:
        axis = planar_axis if jtype == "planar" else axis
        ax = f'<axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>' if axis is not None else ""
        joints.append(f'<joint name="{name}" type="{jtype}"><parent link="{parent}"/><child link="{child}"/>'
                      f'<origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/>{ax}</joint>')
    return '<robot name="joint_types">\n' + "\n".join(links + joints) + "\n</robot>\n"


def rpy_matrix(r, p, y):
    return pin.rpy.rpyToMatrix(r, p, y)


def composite(*kinds):
    joint = pin.JointModelComposite()
    for kind in kinds:
        joint.addJoint(kind())
    return joint


# the joint frame's turn R_a (R_a e_i = axis) and the composite of a planar joint, per axis written in the tests
PLANAR = {
    (0.0, 0.0, 1.0): (np.eye(3), (pin.JointModelPX, pin.JointModelPY, pin.JointModelRZ)),
    (-1.0, 0.0, 0.0): (np.diag([-1.0, -1.0, 1.0]), (pin.JointModelPY, pin.JointModelPZ, pin.JointModelRX)),
}
SINGLE = {(0.0, 1.0, 0.0): pin.JointModelRY, (1.0, 0.0, 0.0): pin.JointModelRX}


def reference(planar_axis):
    """Pinocchio's model of :func:`urdf` built by hand: joints in the file's (depth-first) order, each placed at
    its origin in its parent link's frame (the link frame, turned by R_a, is the joint frame)."""
    pm = pin.Model()
    pm.gravity = pin.Motion(np.array([0.0, 0.0, -9.81, 0.0, 0.0, 0.0]))
    link_in_joint = {"world": (0, pin.SE3.Identity())}  # link -> (joint id, placement of the link frame in it)
    for name, jtype, parent, child, xyz, rpy, axis in JOINTS:
        parent_joint, above = link_in_joint[parent]
        origin = above * pin.SE3(rpy_matrix(*rpy), np.array(xyz))
        if jtype == "floating":
            Ra, joint = np.eye(3), composite(pin.JointModelPX, pin.JointModelPY, pin.JointModelPZ,
                                             pin.JointModelRX, pin.JointModelRY, pin.JointModelRZ)
        elif jtype == "planar":
            Ra, kinds = PLANAR[tuple(planar_axis)]
            joint = composite(*kinds)
        else:
            Ra, joint = np.eye(3), SINGLE[axis]()
        turn = pin.SE3(Ra, np.zeros(3))
        jid = pm.addJoint(parent_joint, joint, origin * turn, name)
        link = turn.inverse()
        m, c, (ixx, ixy, ixz, iyy, iyz, izz) = LINKS[child]
        inertia = pin.Inertia(m, np.array(c), np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]))
        pm.appendBodyToJoint(jid, link.act(inertia), pin.SE3.Identity())
        link_in_joint[child] = (jid, link)
    return pm


@pytest.fixture(params=[(0.0, 0.0, 1.0), (-1.0, 0.0, 0.0)], ids=["planar_z", "planar_minus_x"])
def robot(request, tmp_path):
    path = tmp_path / "joint_types.urdf"
    path.write_text(urdf(request.param))
    return aggsym.load(path), reference(request.param)


def test_coordinates(robot):
    model, pm = robot
    names = [c.name for b in model.bodies for c in b.pair.coordinates]
    assert names[:6] == ["free_x", "free_y", "free_z", "free_rx", "free_ry", "free_rz"]
    assert names[7:10] == ["table_x", "table_y", "table_rz"] or names[7:10] == ["table_y", "table_z", "table_rx"]
    assert model.nq == pm.nq == 11


def test_against_pinocchio(robot):
    model, pm = robot
    twin, data, rng = aggsym.NumericTwin(model), pm.createData(), np.random.default_rng(33)
    for _ in range(5):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        qd, qdd, tau = rng.normal(size=(3, model.nq))
        M = pin.crba(pm, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        assert relative_error(twin.inertia(q), M) <= TOL
        assert relative_error(twin.bias(q, qd) + twin.gravity(q), pin.nonLinearEffects(pm, data, q, qd)) <= TOL
        assert relative_error(twin.inverse_dynamics(q, qd, qdd), pin.rnea(pm, data, q, qd, qdd)) <= TOL
        assert relative_error(twin.forward_dynamics(q, qd, tau), pin.aba(pm, data, q, qd, tau)) <= TOL


def test_floating_joint_at_the_root_equals_the_euler_base(tmp_path):
    """A floating joint from a massless world link is ``--floating-base euler`` on the rest of the tree."""
    text = urdf((0.0, 0.0, 1.0))
    path = tmp_path / "joint_types.urdf"
    rootless = text.replace('<link name="world"/>', "").split("\n")
    rootless = "\n".join(line for line in rootless if 'name="free"' not in line)
    based = tmp_path / "based.urdf"
    based.write_text(rootless)
    euler = aggsym.load(based, floating_base="euler")
    rng = np.random.default_rng(5)
    # the Euler base sits at the root link's origin; the floating joint at its own origin: make it the identity
    placed = text.replace('xyz="0.1 -0.2 0.3" rpy="0.2 -0.1 0.4"', 'xyz="0 0 0" rpy="0 0 0"')
    path.write_text(placed)
    inner = aggsym.load(path)
    a, b = aggsym.NumericTwin(inner), aggsym.NumericTwin(euler)
    for _ in range(3):
        q, qd = rng.normal(size=(2, inner.nq))
        assert relative_error(a.inertia(q), b.inertia(q)) <= TOL
        assert relative_error(a.bias(q, qd) + a.gravity(q), b.bias(q, qd) + b.gravity(q)) <= TOL


def test_spherical_is_a_ball_pair(tmp_path):
    """A spherical joint is read as the ball pair (compared with Pinocchio's spherical joint in test_ball_joint.py):
    four positions, three velocities, named after the joint."""
    text = urdf((0.0, 0.0, 1.0)).replace('name="wrist" type="continuous"', 'name="wrist" type="spherical"')
    path = tmp_path / "ball.urdf"
    path.write_text(text)
    model = aggsym.load(path)
    assert model.nq == model.nv + 1 and model.bodies[-1].pair.ball
    assert [n for n, _, _ in model.positions][-4:] == ["wrist_qx", "wrist_qy", "wrist_qz", "wrist_qw"]
    assert [c.name for c in model.coordinates][-3:] == ["wrist_wx", "wrist_wy", "wrist_wz"]


def test_mimic_on_a_planar_joint_is_an_error(tmp_path):
    text = urdf((0.0, 0.0, 1.0)).replace('<axis xyz="1.0 0.0 0.0"/></joint>',
                                         '<axis xyz="1.0 0.0 0.0"/><mimic joint="table"/></joint>')
    path = tmp_path / "mimic.urdf"
    path.write_text(text)
    with pytest.raises(aggsym.ModelError, match="joint 'table' is planar"):
        aggsym.load(path)


def test_generated_numpy_against_pinocchio(robot, tmp_path):
    """The generated NumPy module (not only the numeric twin) on the planar and floating pairs."""
    from aggsym.codegen.compile import import_module
    from aggsym.codegen.generate import generate, write

    model, pm = robot
    write(generate(model, targets=["numpy"]), tmp_path)
    module = import_module(tmp_path / f"{model.name}.py")
    data, rng = pm.createData(), np.random.default_rng(7)
    for _ in range(3):
        q = rng.uniform(-np.pi, np.pi, model.nq)
        qd, tau = rng.normal(size=(2, model.nq))
        M = pin.crba(pm, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        assert relative_error(np.asarray(module.inertia(q)).reshape(M.shape), M) <= TOL
        assert relative_error(np.asarray(module.forward_dynamics(q, qd, tau)), pin.aba(pm, data, q, qd, tau)) <= TOL


# a cart on a planar joint about z (its frame turned) carrying a pole on a hinge about x; full inertia tensors
PLANAR_ARM = chain("planar_arm",
                   segment("table", "cart", "planar", xyz="0.1 0.2 0.3", rpy="0.3 -0.2 0.1", axis="0 0 1", mass=1.5,
                           com="0.05 -0.02 0.01", inertia=(0.02, 0.03, 0.025, 0.001, -0.002, 0.0015)),
                   segment("hinge", "pole", xyz="0.1 0 0.05", rpy="0 0 0.4", axis="1 0 0", limit=(-3, 3, 1, 1),
                           mass=0.6, com="0 0.01 0.3", inertia=(0.01, 0.011, 0.002, 0.0002, 0.0001, -0.0003)),
                   base="ground")


def test_planar_against_pinocchios_own_planar_joint(tmp_path):
    """Pinocchio's URDF importer makes the planar joint JointModelPlanar: q = (x, y, cos, sin), v = (vx, vy, w) in
    the child's axes.  With J = d v / d qd (the rotation R(angle)^T on the translation rates), A = J^T M J and the
    joint forces are J^T rnea(Q, J qd, J qdd + J' qd)."""
    path = tmp_path / "planar_arm.urdf"
    path.write_text(PLANAR_ARM)
    model = aggsym.load(path)
    pm = pin.buildModelFromUrdf(str(path))
    assert pm.joints[1].shortname() == "JointModelPlanar" and model.nq == 4 and pm.nq == 5
    twin, data, rng = aggsym.NumericTwin(model), pm.createData(), np.random.default_rng(11)
    for _ in range(3):
        q, qd, qdd = rng.uniform(-np.pi, np.pi, (3, 4))
        c, s = np.cos(q[2]), np.sin(q[2])
        Q = np.array([q[0], q[1], c, s, q[3]])
        J = np.eye(4)
        J[:2, :2] = [[c, s], [-s, c]]
        Jdot = np.zeros((4, 4))
        Jdot[:2, :2] = qd[2] * np.array([[-s, c], [-c, -s]])
        M = pin.crba(pm, data, Q)
        M = np.triu(M) + np.triu(M, 1).T
        assert relative_error(twin.inertia(q), J.T @ M @ J) <= TOL
        tau = J.T @ pin.rnea(pm, data, Q, J @ qd, J @ qdd + Jdot @ qd)
        assert relative_error(twin.inverse_dynamics(q, qd, qdd), tau) <= TOL
