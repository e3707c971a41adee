"""The routines of the equations of motion (2.17), (2.27) and of the transvective factors (3.7)-(3.20): A, b, C,
g, d, tau, c, the energies, the momentum, the joint wrenches and friction, the forward dynamics, A^-1, the factors,
the elastic partition (Prop. 2.14); with the layouts the manifest gives their outputs."""
from __future__ import annotations

from ..mechanics import elastic, joint_space, passive, sweeps, transvective
from ..mechanics.bias import coriolis_matrix, gravity_vector
from ..mechanics.energy import kinetic_energy, momentum, potential_energy
from ..mechanics.inertia import inertia_matrix
from ..mechanics.spatial_tendons import spatial_tendon_energy
from ..model.tree import Tree
from .registry import Output, Routine, flat, minus, register
from .shapes import (
    joint_wrench_shape, momentum_shape, nq_square, nq_vector, partition_block_shape, scalar, transvection_count,
)


def momentum_layout(model) -> dict:
    return {"rows": ["px", "py", "pz", "Lx", "Ly", "Lz"],
            "convention": "linear momentum, then angular momentum about the world origin, world axes (with added "
                          "masses the medium's impulse included; the armature carries none)"}


JOINT_WRENCH_CONVENTION = (
    "row r: the wrench (fx, fy, fz, mx, my, mz) that the parent exerts on the child body and its subtree through "
    "the joint (reaction + control + friction + the spring of an elastic pair, Z = R + U + N (+ C) of (2.9), "
    "(2.42), Prop. 2.13), moment about the child frame "
    "origin, both in the child frame's axes (for URDF models the child link frame); the joint's generalized "
    "forces tau are the projections of this wrench on its axes")


def joint_wrench_layout(model) -> dict:
    """The manifest entry of joint_wrenches: one row per coordinate-bearing joint, its names and frame."""
    rows = []
    for k in sweeps.pair_bodies(model):
        body = model.bodies[k]
        rows.append({
            "joint": body.pair.name,
            "body": body.name,
            "coordinates": [c.name for c in body.pair.coordinates],
            "frame": "link" if body.link_rotation is not None else "body",
        })
    return {"W": {"shape": [len(rows), 6], "order": "row-major",
                  "columns": ["fx", "fy", "fz", "mx", "my", "mz"],
                  "convention": JOINT_WRENCH_CONVENTION, "rows": rows}}


def transvective_layout(model) -> dict:
    """The manifest's description of the outputs of ``transvective_factors``: enough to rebuild T and A^-1."""
    names = [c.name for c in model.coordinates]
    pairs = transvective.transvection_pairs(Tree.of(model))
    return {
        "indexing": "0-based coordinate indices in q order",
        "targs": [[t, k] for t, k in pairs],
        "targs_names": [[names[t], names[k]] for t, k in pairs],
        "diag": names,
        "T": "T = prod_i (E - targs[i] E_{t_i k_i}) in the listed order, E_tk the unit matrix at row t, column k "
             "(the transvections t_tk^-1(<t,k>) of (3.9)); t is above k on k's path to the root",
        "identities": ["T A(q) T^T = diag(diag) (3.11)", "A(q)^-1 = T^T diag(1/diag) T (3.19)",
                       "qdd = T^T diag(1/diag) T (tau - b - g) (3.20)"],
    }


def partition_layout(model) -> dict:
    """The manifest entry of elastic_partition: the permutation and the meaning of every block."""
    slow, fast = elastic.fast_slow(model)
    names = [c.name for c in model.coordinates]
    book = {"pp": "++", "mp": "-+", "pm": "+-", "mm": "--"}
    blocks = {}
    for name, m, rows, cols in elastic.BLOCKS:
        blocks[name] = {"book": f"{m}{book[name[2:]]}", "rows": rows, "columns": cols,
                        "shape": list(partition_block_shape(name)(model)), "order": "row-major"}
    return {
        "slow": [names[i] for i in slow],
        "fast": [names[i] for i in fast],
        "permutation": slow + fast,
        "convention": (
            "Prop. 2.14: (P q)[r] = q[permutation[r]], the slow (non-elastic, +) coordinates first, then the fast "
            "(elastic, -) ones.  X_pp, X_mp, X_pm, X_mm are the book's X++, X-+, X+-, X-- (upper index first: "
            "the motion that contributes, lower: the equation it contributes to): rows are the equations of "
            "'rows', columns the motions of 'columns'.  A: inertia, B: the matrix with b = B qd, "
            "B = S Phi(V) A S^T + S A S'^T (2.17), C: stiffness.  Slow rows: "
            "A_pp qdd+ + B_pp qd+ + A_mp qdd- + B_mp qd- + g+ = tau+; fast rows: "
            "A_mm qdd- + B_mm qd- + A_pm qdd+ + B_pm qd+ + C_mm (q- - q0-) + g- = tau-"),
        "blocks": blocks,
    }


def _plus(a, b):
    """a + b entry by entry (b's structural zeros fold)."""
    return [x + y for x, y in zip(a, b)]


def _zeros(kin):
    return [0] * kin.tree.nv


def _gravity(bound, kin, x):
    """g = -S G: the sweeps at rest, or, when prescribed spins keep rotors turning at rest, the backward recurrence
    of -S G itself (:func:`aggsym.mechanics.bias.gravity_vector`), which leaves their motion out."""
    if bound.model.has_prescribed_spins:
        return (gravity_vector(bound, kin),)
    return (sweeps.inverse_dynamics(bound, kin, _zeros(kin), _zeros(kin)),)


def _joint_friction(bound, kin, x):
    """tau_f,i = -d_i qd_i - f_i sign(qd_i) for the joints with URDF <dynamics> (0 elsewhere), d_i and f_i the
    runtime parameters damping_<coordinate> and friction_<coordinate>."""
    index = {p.name: i for i, p in enumerate(bound.model.parameters)}
    out = []
    for c, rate in zip(bound.model.coordinates, x["qd"]):
        if not c.dynamics.given:
            out.append(0)
            continue
        d, f = bound.params[index[f"damping_{c.name}"]], bound.params[index[f"friction_{c.name}"]]
        out.append(-(d * rate) - f * bound.backend.call("sign", rate))
    return (out,)


def _joint_wrenches(bound, kin, x):
    Z = sweeps.transmitted_wrenches(bound, kin, x["qd"], x["qdd"])
    return (flat(sweeps.joint_wrench_rows(bound, Z)),)


register(Routine("inertia", ("q", "p"), (Output("A", nq_square),),
                 lambda bound, kin, x: (flat(inertia_matrix(bound, kin)),),
                 "A(q), the inertia matrix, n*n row-major, by composite bodies (2.32)-(2.34)",
                 coupled="matrix", frame_free=True, scalar_stores=True))
register(Routine("bias", ("q", "qd", "p"), (Output("b", nq_vector),),
                 lambda bound, kin, x: (sweeps.d_vector(bound, kin, x["qd"], gravity=False),),
                 "b(q, qd), the velocity terms: d(q, qd) of the sweeps (2.44)-(2.46) without gravity, = b by (2.52) "
                 "(with prescribed spins: every term of their rates and accelerations too)", frame_free=True))
register(Routine("coriolis", ("q", "qd", "p"), (Output("C", nq_square),),
                 lambda bound, kin, x: (flat(coriolis_matrix(bound, kin, x["qd"], skew=True)),),
                 "C(q, qd), n*n row-major: the Coriolis matrix with C qd = b and A' - 2C skew "
                 "(S (Phi(V) A + A phi(V)) S^T + S A S'^T, from the book's B of (2.17), (2.36)), for passivity-based "
                 "control", applies=lambda model: not model.has_prescribed_spins, coupled="matrix"))
register(Routine("gravity", ("q", "p"), (Output("g", nq_vector),), _gravity,
                 "g(q) = -S G, the generalized gravity force on the left side (the sweeps at rest)", frame_free=True))
register(Routine("nonlinear_effects", ("q", "qd", "p"), (Output("d", nq_vector),),
                 lambda bound, kin, x: (_plus(sweeps.d_vector(bound, kin, x["qd"]),
                                              passive.left_forces(bound, kin.q, x["qd"])),),
                 "d(q, qd) = b(q, qd) + g(q) + c(q): the sweeps with qdd = 0 (2.44)-(2.46), (2.52), plus the elastic "
                 "force C (q - q0) of (2.27)", frame_free=True))
register(Routine("inverse_dynamics", ("q", "qd", "qdd", "p"), (Output("tau", nq_vector),),
                 lambda bound, kin, x: (_plus(sweeps.inverse_dynamics(bound, kin, x["qd"], x["qdd"]),
                                              passive.left_forces(bound, kin.q, x["qd"])),),
                 "tau = u* by the forward and backward sweeps (2.39)-(2.42) plus C (q - q0) (2.27); equals "
                 "A(q) qdd + b(q, qd) + g(q) + c(q)", frame_free=True))
register(Routine("elastic", ("q", "p"), (Output("c", nq_vector),),
                 lambda bound, kin, x: (elastic.elastic_forces(bound, kin.q),),
                 "c(q) = C (q - q0), the generalized force of the Hooke-elastic pairs on the left side of (2.27)",
                 applies=elastic.is_elastic))
register(Routine("kinetic_energy", ("q", "qd", "p"), (Output("T", scalar),),
                 lambda bound, kin, x: ([kinetic_energy(bound, kin, x["qd"])],),
                 "T = 1/2 sum V^T A_lk V over the bodies (Def. 2.4; with added masses the medium's 1/2 V^T Lambda V, "
                 "Prop. 2.8); = 1/2 qd^T A(q) qd without prescribed spins", coupled="tree", frame_free=True))
register(Routine("potential_energy", ("q", "p"), (Output("U", scalar),),
                 lambda bound, kin, x: ([potential_energy(bound, kin) + elastic.elastic_energy(bound, kin.q)
                                         + joint_space.tendon_energy(bound, kin.q)  # (tendons: 1/2 k s^2)
                                         + spatial_tendon_energy(bound, kin)],),
                 "U(q), the potential energy of gravity plus 1/2 (q - q0)^T C (q - q0) of the elastic pairs",
                 coupled="tree", frame_free=True))
register(Routine("momentum", ("q", "qd", "p"), (Output("h", momentum_shape),),
                 lambda bound, kin, x: (momentum(bound, kin, x["qd"]),),
                 "h: the total linear momentum and angular momentum about the world origin, world axes: each "
                 "body's A_lk V (2.3) moved to the world by its pose L (1.13)", layout=momentum_layout,
                 coupled="tree"))
register(Routine("joint_wrenches", ("q", "qd", "qdd", "p"), (Output("W", joint_wrench_shape),), _joint_wrenches,
                 "W: per joint, the wrench (f, mu) from parent to child in the child frame (2.42)",
                 layout=joint_wrench_layout, coupled="tree"))
register(Routine("joint_friction", ("qd", "p"), (Output("tau_f", nq_vector),), _joint_friction,
                 "tau_f = -d qd - f sign(qd) per joint with URDF <dynamics> (damping d, Coulomb friction f: the "
                 "parameters damping_<joint>, friction_<joint>), a generalized force on the right: "
                 "A qdd + b + g = tau + tau_f", applies=lambda model: model.has_joint_dynamics, coupled=None))
register(Routine("passive_forces", ("q", "qd", "p"), (Output("tau_p", nq_vector),),
                 lambda bound, kin, x: (passive.passive_forces(bound, kin.q, x["qd"]),),
                 "tau_p = -(C (q - q0) + D qd + t + F sign(qd)) + tau_s, the springs (2.27), the viscous joint "
                 "damping, the fixed tendons' springs and dampers (t), the Coulomb joint friction asked for (F) and "
                 "the lifts of gravity compensation (tau_s, MuJoCo's gravcomp) as a "
                 "generalized force on the right side (MuJoCo's qfrc_passive, without F): A qdd + b + g = tau + "
                 "tau_p",
                 applies=lambda model: bool(model.damping or model.tendons or model.coulomb or model.gravcomp
                                            or model.spatial_tendons or model.has_fluid),
                 frame_free=True))
register(Routine("forward_dynamics", ("q", "qd", "tau", "p"), (Output("qdd", nq_vector),),
                 lambda bound, kin, x: (transvective.forward_dynamics(
                     bound, kin, minus(x["tau"], passive.left_forces(bound, kin.q, x["qd"])), x["qd"]),),
                 "qdd = T^T diag(1/(beta,beta)) T (tau - b - g - c), the transvective Cauchy form (3.20), "
                 "evaluated in O(n)", coupled="forward", regular=True, frame_free=True))
register(Routine("inertia_inverse", ("q", "p"), (Output("Ainv", nq_square),),
                 lambda bound, kin, x: (flat(transvective.inertia_inverse(bound, kin)),),
                 "A(q)^-1 = T^T diag(1/(beta,beta)) T, n*n row-major (3.19)", coupled="inverse", regular=True,
                 frame_free=True, scalar_stores=True))
register(Routine("transvective_factors", ("q", "p"),
                 (Output("targs", transvection_count), Output("diag", nq_vector)),
                 lambda bound, kin, x: transvective.factor_outputs(bound, kin),
                 "the arguments <t,k> of the transvections of T (3.8), (3.9) and the pivots (beta,beta)^k "
                 "of T A(q) T^T = diag (3.11)", layout=transvective_layout, coupled=None, regular=True, frame_free=True))
register(Routine("elastic_partition", ("q", "qd", "p"),
                 tuple(Output(name, partition_block_shape(name)) for name, _, _, _ in elastic.BLOCKS),
                 lambda bound, kin, x: elastic.partition(bound, kin, x["qd"]),
                 "the slow/fast partition of Prop. 2.14: blocks of A(q), B(q, qd) (b = B qd) and C, slow (+) "
                 "and fast (-, elastic) coordinates, see the manifest's layout",
                 layout=partition_layout,
                 applies=lambda model: elastic.is_elastic(model) and not model.has_prescribed_spins, coupled=None))
