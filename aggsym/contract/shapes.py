"""The shapes of the routines' outputs (and the input lengths that differ from q's), as functions of the model:
each :class:`~.registry.Output` holds one.  Layouts (what the entries mean, for the manifest) live with the routines
that return them."""
from __future__ import annotations

from ..mechanics import elastic, regressor, sweeps, transvective
from ..model.tree import Tree


def nq_vector(model):
    """n: a vector of generalized forces or accelerations (Pinocchio's nv; = the length of q but with a
    free-flyer)."""
    return (model.nv,)


def nq_square(model):
    return (model.nv, model.nv)


def positions_vector(model):
    """The length of q."""
    return (model.nq,)


def scalar(model):
    return (1,)


def momentum_shape(model):
    return (6,)


def joint_wrench_shape(model):
    return (len(sweeps.pair_bodies(model)), 6)


def transvection_count(model):
    """Shape of the targs output: one scalar per transvection."""
    return (len(transvective.transvection_pairs(Tree.of(model))),)


def partition_block_shape(name):
    """model -> shape of one output block of :func:`aggsym.mechanics.elastic.partition`."""
    _, _, rows, cols = next(b for b in elastic.BLOCKS if b[0] == name)

    def shape(model):
        slow, fast = elastic.fast_slow(model)
        groups = {"slow": len(slow), "fast": len(fast)}
        return (groups[rows], groups[cols])

    return shape


def constraint_rows_vector(model):
    return (model.constraint_rows,)


def constraint_jacobian_shape(model):
    return (model.constraint_rows, model.nv)


def constraint_square(model):
    return (model.constraint_rows, model.constraint_rows)


def slip_vector(model):
    return (model.slip_rows,)


def support_lengths(model) -> dict:
    return {"q": 6, "qd": 6, "qdd": 6}


def support_block(columns):
    def shape(model):
        return (6, model.mechanism_coordinates if columns == "k" else 6)
    return shape


def six(model):
    return (6,)


def mechanism_vector(model):
    return (model.mechanism_coordinates,)


def frame_count(model) -> int:
    return len(model.frames)


def regressor_shape(model):
    return (model.nv, 10 * len(regressor.blocks(model)))


def friction_regressor_shape(model):
    """The regressor with drives: 10 per moving body, then viscous and Coulomb friction per joint, then armature."""
    joints, rotors = regressor.drives(model)
    return (model.nv, 10 * len(regressor.blocks(model)) + 2 * len(joints) + len(rotors))
