"""The benchmark's second peer: Featherstone's algorithms written with CasADi SX, emitted as C by CasADi.

Pinocchio's own times vary 2-4x between hosts of one kind while the generated code's vary much less, so the
runtime section also times a peer that is, like the generated code, straight-line C compiled with the same
compiler and flags: the same five routines built symbolically from the same URDF data and printed by CasADi's
``CodeGenerator``.

The tree is read from Pinocchio's model of the URDF (``pin.buildModelFromUrdf``: parents, joint placements,
joint axes, body inertias with the fixed links already merged), so the peer computes exactly what Pinocchio
computes.  The algorithms are Featherstone's (Rigid Body Dynamics Algorithms, 2008) in body coordinates, as
Pinocchio writes them (``Convention::LOCAL``):

- RNEA (inverse dynamics, Table 5.1; b + g is RNEA with q̈ = 0),
- CRBA (A(q), Table 6.2) with composite inertias,
- ABA (forward dynamics, Table 7.1),
- A⁻¹ by ABA columns: the q-dependent part of ABA (transforms, articulated inertias, U = IA S, D = Sᵀ U) once,
  then for each unit τ the two light sweeps with q̇ = 0 and no gravity (O(n²) in all, as Carpentier's).

Every joint of these robots has a one-column motion subspace S (a revolute or prismatic joint about an axis;
the 6-coordinate Euler root is six such joints joined by massless links, Pinocchio's composite PX PY PZ RX RY
RZ), so S is never a matrix: Sᵀ f is one component (or a dot product with an unaligned axis) and S q̇ a
vector with one non-zero entry.  Spatial quantities are kept as pairs of 3-vectors, spatial inertias as (m,
h = m c, Ī about the frame origin) and articulated inertias as symmetric 3×3 blocks (M, H, J), transformed
block-wise; the model's numbers are constants, and CasADi's SX folds x·0, x·1, x + 0 as the graph is built.
``casadi.cse`` runs on the outputs of each function before the C is written.

The C is one file per robot: CasADi's code for the five functions, then thin wrappers with the generated code's
signatures (``NAME_inertia(q, p, out)`` ...; p is ignored: the peer's constants are folded in) so the same
batch timers of ``harness/bench.h`` call both.  Coordinates are angles (continuous joints too), as aggsym's.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROLES = ("inertia", "nonlinear_effects", "inverse_dynamics", "forward_dynamics", "inertia_inverse")
# Pinocchio's one-axis joints: short name -> (kind, axis); unaligned ones read their axis from the joint
_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}
EULER_ROOT = ("PX", "PY", "PZ", "RX", "RY", "RZ")  # aggsym's --floating-base euler: o1 o2 o3 theta4 theta5 theta6


@dataclass
class Joint:
    """One coordinate: a revolute ("R") or prismatic ("P") joint about ``axis`` (unit, joint frame), placed at
    (R0, p0) in its parent's frame (parent -1: the world), carrying a body of mass m, first moment h = m c and
    rotational inertia Ibar about the joint frame's origin (all in joint axes)."""
    name: str
    parent: int
    R0: np.ndarray
    p0: np.ndarray
    kind: str
    axis: np.ndarray
    mass: float
    h: np.ndarray
    Ibar: np.ndarray


def _one_axis(joint_model) -> tuple:
    """(kind, axis) of a Pinocchio one-axis joint model; ValueError for any other joint."""
    short = joint_model.shortname().removeprefix("JointModel")
    if short in ("RevoluteUnaligned", "RevoluteUnboundedUnaligned", "PrismaticUnaligned"):
        axis = np.array(joint_model.extract().axis, dtype=float)
        return ("P" if short.startswith("Prismatic") else "R"), axis / np.linalg.norm(axis)
    for prefix, kind in (("RUB", "R"), ("R", "R"), ("P", "P")):
        if short.startswith(prefix) and short[len(prefix):] in _AXES:
            return kind, np.array(_AXES[short[len(prefix):]])
    raise ValueError(f"joint model {joint_model.shortname()}: the CasADi peer handles one-axis joints only")


def tree_from_pinocchio(model) -> list:
    """The peer's joints from a Pinocchio model (fixed base, or the composite root of one-axis joints)."""
    joints, last = [], {0: -1}  # Pinocchio joint index -> our index of its last coordinate
    for j in range(1, model.njoints):
        jm = model.joints[j]
        placement = model.jointPlacements[j]
        Y = model.inertias[j]
        m, c = float(Y.mass), np.array(Y.lever, dtype=float)
        Ibar = np.array(Y.inertia, dtype=float) + m * (float(c @ c) * np.eye(3) - np.outer(c, c))
        if jm.shortname() == "JointModelComposite":
            comp = jm.extract()
            subs = list(comp.joints)
            for k, sub in enumerate(subs):
                jp = comp.jointPlacements[k]
                if not np.allclose(jp.homogeneous, np.eye(4)):
                    raise ValueError(f"joint {model.names[j]}: composite with non-identity inner placements")
            parts = [_one_axis(sub) for sub in subs]
        else:
            parts = [_one_axis(jm)]
        parent = last[int(model.parents[j])]
        for k, (kind, axis) in enumerate(parts):
            first, final = k == 0, k == len(parts) - 1
            R0 = np.array(placement.rotation) if first else np.eye(3)
            p0 = np.array(placement.translation) if first else np.zeros(3)
            joints.append(Joint(f"{model.names[j]}[{k}]" if len(parts) > 1 else model.names[j], parent,
                                R0, p0, kind, axis, m if final else 0.0, m * c if final else np.zeros(3),
                                Ibar if final else np.zeros((3, 3))))
            parent = len(joints) - 1
        last[j] = parent
    return joints


# ------------------------------------------------------------------------------------------- SX algebra
def _ca():
    import casadi

    return casadi


def _const(v):
    """A numeric vector or matrix as an SX with exact zeros and ones kept as constants (folded later)."""
    ca = _ca()
    return ca.SX(ca.DM(np.asarray(v, dtype=float)))


def _cross(a, b):
    ca = _ca()
    return ca.vertcat(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _skew(p):
    ca = _ca()
    z = ca.SX(0)
    return ca.vertcat(ca.horzcat(z, -p[2], p[1]), ca.horzcat(p[2], z, -p[0]), ca.horzcat(-p[1], p[0], z))


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _mat(a, b):
    return _ca().mtimes(a, b)


def _sym_congruence(R, S):
    """R S Rᵀ of a symmetric S, computing the upper triangle only."""
    ca = _ca()
    RS = _mat(R, S)
    out = ca.SX(3, 3)
    for i in range(3):
        for k in range(i, 3):
            e = RS[i, 0] * R[k, 0] + RS[i, 1] * R[k, 1] + RS[i, 2] * R[k, 2]
            out[i, k] = e
            out[k, i] = e
    return out


def _sym(M):
    """(M + Mᵀ)/2 taken from the upper triangle: one expression per pair of entries."""
    ca = _ca()
    out = ca.SX(3, 3)
    for i in range(3):
        for k in range(i, 3):
            out[i, k] = M[i, k]
            out[k, i] = M[i, k]
    return out


def _joint_rotation(axis, q):
    """The rotation of angle q about a unit axis (exact zeros for a coordinate axis)."""
    ca = _ca()
    c, s = ca.cos(q), ca.sin(q)
    x, y, z = (float(a) for a in axis)
    t = 1 - c
    rows = [[c + x * x * t, x * y * t - z * s, x * z * t + y * s],
            [y * x * t + z * s, c + y * y * t, y * z * t - x * s],
            [z * x * t - y * s, z * y * t + x * s, c + z * z * t]]
    if (x, y, z) == (1.0, 0.0, 0.0):
        rows = [[1, 0, 0], [0, c, -s], [0, s, c]]
    elif (x, y, z) == (0.0, 1.0, 0.0):
        rows = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    elif (x, y, z) == (0.0, 0.0, 1.0):
        rows = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    return ca.vertcat(*[ca.horzcat(*[ca.SX(e) if isinstance(e, (int, float)) else e for e in r]) for r in rows])


class _Kinematics:
    """The placements (R, p) of each joint frame in its parent's frame: x_parent = R x_child + p."""

    def __init__(self, joints, q):
        self.R, self.p = [], []
        for i, j in enumerate(joints):
            R0, p0 = _const(j.R0), _const(j.p0)
            if j.kind == "R":
                R = _mat(R0, _joint_rotation(j.axis, q[i]))
                p = p0
            else:
                R = R0
                p = p0 + _mat(R0, _const(j.axis)) * q[i]
            self.R.append(R)
            self.p.append(p)

    # motion (lin v, ang w) in the parent's frame -> in the child's: w' = Rᵀ w, v' = Rᵀ (v - p × w)
    def motion_in(self, i, v, w):
        Rt = self.R[i].T
        return _mat(Rt, v - _cross(self.p[i], w)), _mat(Rt, w)

    # force (lin f, moment n about the child's origin) -> parent's frame: f' = R f, n' = R n + p × f'
    def force_out(self, i, f, n):
        fp = _mat(self.R[i], f)
        return fp, _mat(self.R[i], n) + _cross(self.p[i], fp)


def _s_motion(j, qd):
    """S q̇ as (lin, ang)."""
    ca = _ca()
    a = _const(j.axis) * qd
    z = ca.SX.zeros(3, 1)
    return (z, a) if j.kind == "R" else (a, z)


def _s_dot(j, f, n):
    """Sᵀ (f, n): the component of the moment (revolute) or of the force (prismatic) along the axis."""
    return _dot(_const(j.axis), n if j.kind == "R" else f)


def _inertia_times(m, h, Ibar, v, w):
    """A spatial inertia (m, h = m c, Ī about the origin) times a motion (v, w): (f, n)."""
    return m * v - _cross(h, w), _mat(Ibar, w) + _cross(h, v)


def rnea(joints, gravity, q, qd, qdd):
    """τ of Featherstone's RNEA (Table 5.1) in body coordinates; gravity as the base's acceleration −g."""
    ca = _ca()
    kin = _Kinematics(joints, q)
    n = len(joints)
    g = _const(-np.asarray(gravity, dtype=float))
    zero = ca.SX.zeros(3, 1)
    v, w, a, al, f, mom = [None] * n, [None] * n, [None] * n, [None] * n, [None] * n, [None] * n
    for i, j in enumerate(joints):
        pv, pw, pa, pal = (zero, zero, g, zero) if j.parent < 0 else (v[j.parent], w[j.parent], a[j.parent],
                                                                        al[j.parent])
        vi, wi = kin.motion_in(i, pv, pw)
        ai, ali = kin.motion_in(i, pa, pal)
        sv, sw = _s_motion(j, qd[i])
        sav, saw = _s_motion(j, qdd[i])
        v[i], w[i] = vi + sv, wi + sw
        # a = X a_parent + S q̈ + v × S q̇ (the motion cross product: (v, w) × (sv, sw) = (w × sv + v × sw, w × sw))
        a[i] = ai + sav + _cross(w[i], sv) + _cross(v[i], sw)
        al[i] = ali + saw + _cross(w[i], sw)
        fi, ni = _inertia_times(j.mass, _const(j.h), _const(j.Ibar), a[i], al[i])
        hf, hn = _inertia_times(j.mass, _const(j.h), _const(j.Ibar), v[i], w[i])
        f[i] = fi + _cross(w[i], hf)
        mom[i] = ni + _cross(w[i], hn) + _cross(v[i], hf)
    tau = [None] * n
    for i in reversed(range(n)):
        j = joints[i]
        tau[i] = _s_dot(j, f[i], mom[i])
        if j.parent >= 0:
            fp, npar = kin.force_out(i, f[i], mom[i])
            f[j.parent] = f[j.parent] + fp
            mom[j.parent] = mom[j.parent] + npar
    return ca.vertcat(*tau)


def _inertia_to_parent(kin, i, m, h, Ibar):
    """A spatial inertia (m, h, Ī) of frame i expressed in its parent's frame."""
    R, p = kin.R[i], kin.p[i]
    hr = _mat(R, h)
    P = _skew(p)
    Hr = _skew(hr)
    Ib = _sym_congruence(R, Ibar) - _mat(Hr, P) - _mat(P, Hr) - m * _mat(P, P)
    return hr + m * p, _sym(Ib)


def crba(joints, q):
    """A(q) by Featherstone's CRBA (Table 6.2): composite inertias, then F = Ic S carried to the root."""
    ca = _ca()
    kin = _Kinematics(joints, q)
    n = len(joints)
    mass = [j.mass for j in joints]
    h = [_const(j.h) for j in joints]
    Ib = [_const(j.Ibar) for j in joints]
    for i in reversed(range(n)):
        par = joints[i].parent
        if par >= 0:
            hp, Ip = _inertia_to_parent(kin, i, mass[i], h[i], Ib[i])
            mass[par] += mass[i]
            h[par] = h[par] + hp
            Ib[par] = Ib[par] + Ip
    A = [[None] * n for _ in range(n)]
    for i in range(n):
        j = joints[i]
        sv, sw = _s_motion(j, 1.0)
        f, m = _inertia_times(mass[i], h[i], Ib[i], sv, sw)
        A[i][i] = _s_dot(j, f, m)
        k = i
        while joints[k].parent >= 0:
            f, m = kin.force_out(k, f, m)
            k = joints[k].parent
            A[i][k] = A[k][i] = _s_dot(joints[k], f, m)
    zero = ca.SX(0)
    return ca.vertcat(*[ca.horzcat(*[A[r][c] if A[r][c] is not None else zero for c in range(n)]) for r in range(n)])


class _Articulated:
    """A symmetric 6×6 articulated inertia in blocks: f = M v + H w, n = Hᵀ v + J w."""

    def __init__(self, M, H, J):
        self.M, self.H, self.J = M, H, J

    @classmethod
    def rigid(cls, j):
        """A body's spatial inertia: M = m 1, H = −[h]×, J = Ī."""
        return cls(_const(j.mass * np.eye(3)), _const(-_skew_np(j.h)), _const(j.Ibar))

    def times(self, v, w):
        return _mat(self.M, v) + _mat(self.H, w), _mat(self.H.T, v) + _mat(self.J, w)

    def column(self, j):
        """IA S: (lin, ang) parts of the column for the joint's axis."""
        return self.times(*_s_motion(j, 1.0))

    def minus_outer(self, U, D):
        """IA − U Uᵀ / D (U = (Uf, Un))."""
        Uf, Un = U
        Uf_d, Un_d = Uf / D, Un / D
        M = _sym(self.M - _mat(Uf_d, Uf.T))
        H = self.H - _mat(Uf_d, Un.T)
        J = _sym(self.J - _mat(Un_d, Un.T))
        return _Articulated(M, H, J)

    def to_parent(self, kin, i):
        """Xᵀ IA X: the same inertia seen from the parent's frame (rotate, then shift the reference point)."""
        R, p = kin.R[i], kin.p[i]
        M1 = _sym_congruence(R, self.M)
        H1 = _mat(_mat(R, self.H), R.T)
        J1 = _sym_congruence(R, self.J)
        P = _skew(p)
        M1P = _mat(M1, P)
        H2 = H1 - M1P
        J2 = J1 - _mat(H1.T, P) + _mat(P, H1) - _mat(P, M1P)
        return _Articulated(M1, H2, _sym(J2))

    def plus(self, other):
        return _Articulated(self.M + other.M, self.H + other.H, self.J + other.J)


def _skew_np(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


class _ArticulatedBodies:
    """The q-dependent part of ABA (Table 7.1, pass 2 without the bias forces): IA, U = IA S, D = Sᵀ IA S."""

    def __init__(self, joints, q):
        self.joints, self.kin = joints, _Kinematics(joints, q)
        n = len(joints)
        IA = [_Articulated.rigid(j) for j in joints]
        self.U, self.D, self.Ia = [None] * n, [None] * n, [None] * n
        for i in reversed(range(n)):
            j = joints[i]
            U = IA[i].column(j)
            D = _s_dot(j, *U)
            self.U[i], self.D[i] = U, D
            Ia = IA[i].minus_outer(U, D)
            self.Ia[i] = Ia
            if j.parent >= 0:
                IA[j.parent] = IA[j.parent].plus(Ia.to_parent(self.kin, i))

    def solve(self, tau, pA, c, a0):
        """Passes 2 (bias forces) and 3 of ABA: q̈ from τ, the bias forces pA (each (f, n), None for zero), the
        velocity-product accelerations c (each (lin, ang), None for zero) and the base acceleration a0."""
        ca = _ca()
        joints, kin, n = self.joints, self.kin, len(self.joints)
        pA = list(pA)
        u = [None] * n
        for i in reversed(range(n)):
            j = joints[i]
            f, m = pA[i] if pA[i] is not None else (ca.SX.zeros(3, 1), ca.SX.zeros(3, 1))
            u[i] = tau[i] - _s_dot(j, f, m)
            if j.parent >= 0:
                Uf, Un = self.U[i]
                pf = f + Uf * (u[i] / self.D[i])
                pm = m + Un * (u[i] / self.D[i])
                if c[i] is not None:
                    cf, cm = self.Ia[i].times(*c[i])
                    pf, pm = pf + cf, pm + cm
                fp, mp = kin.force_out(i, pf, pm)
                prev = pA[j.parent]
                pA[j.parent] = (fp, mp) if prev is None else (prev[0] + fp, prev[1] + mp)
        qdd, a = [None] * n, [None] * n
        for i, j in enumerate(joints):
            av, aw = a0 if j.parent < 0 else a[j.parent]
            av, aw = kin.motion_in(i, av, aw)
            if c[i] is not None:
                av, aw = av + c[i][0], aw + c[i][1]
            Uf, Un = self.U[i]
            qdd[i] = (u[i] - _dot(Uf, av) - _dot(Un, aw)) / self.D[i]
            sv, sw = _s_motion(j, qdd[i])
            a[i] = (av + sv, aw + sw)
        return ca.vertcat(*qdd)


def aba(joints, gravity, q, qd, tau):
    """q̈ by Featherstone's ABA (Table 7.1) in body coordinates."""
    ca = _ca()
    bodies = _ArticulatedBodies(joints, q)
    kin = bodies.kin
    n = len(joints)
    zero = ca.SX.zeros(3, 1)
    v, w, c, pA = [None] * n, [None] * n, [None] * n, [None] * n
    for i, j in enumerate(joints):
        pv, pw = (zero, zero) if j.parent < 0 else (v[j.parent], w[j.parent])
        vi, wi = kin.motion_in(i, pv, pw)
        sv, sw = _s_motion(j, qd[i])
        v[i], w[i] = vi + sv, wi + sw
        c[i] = (_cross(w[i], sv) + _cross(v[i], sw), _cross(w[i], sw))
        hf, hn = _inertia_times(j.mass, _const(j.h), _const(j.Ibar), v[i], w[i])
        pA[i] = (_cross(w[i], hf), _cross(w[i], hn) + _cross(v[i], hf))
    g = _const(-np.asarray(gravity, dtype=float))
    return bodies.solve([tau[i] for i in range(n)], pA, c, (g, zero))


def inertia_inverse(joints, q):
    """A⁻¹ by ABA columns: q̇ = 0, no gravity, τ = e_k, sharing IA, U, D between the columns."""
    ca = _ca()
    bodies = _ArticulatedBodies(joints, q)
    n = len(joints)
    zero = ca.SX.zeros(3, 1)
    cols = []
    for k in range(n):
        tau = [ca.SX(1.0 if i == k else 0.0) for i in range(n)]
        cols.append(bodies.solve(tau, [None] * n, [None] * n, (zero, zero)))
    return ca.horzcat(*cols)


def functions(name: str, joints, gravity) -> dict:
    """role -> casadi.Function named ``{name}_cas_{role}`` with the generated code's inputs (p left out)."""
    ca = _ca()
    n = len(joints)
    q, qd, x = ca.SX.sym("q", n), ca.SX.sym("qd", n), ca.SX.sym("x", n)
    zeros = [ca.SX(0)] * n
    outputs = {
        "inertia": ([q], crba(joints, q)),
        "nonlinear_effects": ([q, qd], rnea(joints, gravity, q, qd, zeros)),
        "inverse_dynamics": ([q, qd, x], rnea(joints, gravity, q, qd, x)),
        "forward_dynamics": ([q, qd, x], aba(joints, gravity, q, qd, x)),
        "inertia_inverse": ([q], inertia_inverse(joints, q)),
    }
    out = {}
    for role, (inputs, expr) in outputs.items():
        expr = ca.cse(ca.densify(expr))
        out[role] = ca.Function(f"{name}_cas_{role}", inputs, [expr])
    return out


def pinocchio_model(urdf, root: str | None = None):
    """Pinocchio's model of a URDF: fixed base, or with ``root="euler"`` the composite PX PY PZ RX RY RZ root
    (aggsym's ``--floating-base euler``, coordinate for coordinate)."""
    import pinocchio as pin

    if root is None:
        return pin.buildModelFromUrdf(str(urdf))
    if root != "euler":
        raise ValueError(f"root {root!r}: the CasADi peer takes a fixed base or the Euler root")
    comp = pin.JointModelComposite()
    for short in EULER_ROOT:
        comp.addJoint(getattr(pin, f"JointModel{short}")())
    return pin.buildModelFromUrdf(str(urdf), comp)


_WRAPPER_ARGS = {"inertia": ("q", "p"), "nonlinear_effects": ("q", "qd", "p"),
                 "inverse_dynamics": ("q", "qd", "qdd", "p"), "forward_dynamics": ("q", "qd", "tau", "p"),
                 "inertia_inverse": ("q", "p")}


def c_source(name: str, funcs: dict) -> str:
    """One C file: CasADi's code of the functions, then wrappers ``{name}_{role}`` with the generated code's
    signatures (static work arrays: not reentrant, as befits a benchmark)."""
    ca = _ca()
    cg = ca.CodeGenerator(f"{name}_casadi.c", {"with_header": False, "casadi_real": "double"})
    for role in ROLES:
        cg.add(funcs[role])
    lines = [cg.dump(), "", "/* Wrappers with aggsym's signatures (benchmarks/runtime/casadi_peer.py). */"]
    for role in ROLES:
        f = funcs[role]
        args = _WRAPPER_ARGS[role]
        params = ", ".join(f"const double *{a}" for a in args)
        fname = f.name()
        lines += [f"void {name}_{role}({params}, double *out);",
                  f"void {name}_{role}({params}, double *out) {{",
                  f"    static casadi_int iw[{max(1, f.sz_iw())}];",
                  f"    static casadi_real w[{max(1, f.sz_w())}];",
                  f"    const casadi_real *arg[{max(1, f.sz_arg())}];",
                  f"    casadi_real *res[{max(1, f.sz_res())}];",
                  "    (void)p;"]
        lines += [f"    arg[{k}] = {a};" for k, a in enumerate(args[:-1])]
        lines += ["    res[0] = out;", f"    {fname}(arg, res, iw, w, 0);", "}"]
    return "\n".join(lines) + "\n"


def write_peer(name: str, urdf, folder, root: str | None = None) -> dict:
    """Build the peer of a URDF and write ``{name}_casadi.c`` into ``folder``.  Returns its path, the CasADi
    functions' instruction counts and the seconds spent building the expressions and writing the C."""
    import time

    t0 = time.perf_counter()
    model = pinocchio_model(urdf, root)
    joints = tree_from_pinocchio(model)
    funcs = functions(name, joints, np.array(model.gravity.linear))
    t1 = time.perf_counter()
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}_casadi.c"
    text = c_source(name, funcs)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    return {"path": path, "n": len(joints), "instructions": {r: int(f.n_instructions()) for r, f in funcs.items()},
            "build_seconds": round(t1 - t0, 2), "codegen_seconds": round(time.perf_counter() - t1, 2)}
