"""The routines of frames and of the centre of mass: frame poses, Jacobians and accelerations, the centre of mass,
its Jacobian and the centroidal momentum matrix; with their layouts."""
from __future__ import annotations

from ..mechanics import frames, regressor
from .registry import Output, Routine, flat, register
from .shapes import frame_count


def frame_layout(per_frame: list, convention: str):
    def layout(model) -> dict:
        return {"frames": [f.name for f in model.frames], "per_frame": per_frame, "order": "row-major, frames in "
                "the order of 'frames'", "convention": convention}
    return layout


def _has_frames(model) -> bool:
    return bool(model.frames)


def _has_moving_mass(model) -> bool:
    """The centre of mass needs a moving mass: False when every body that moves is massless (the mass routines are
    then not emitted; a mass that p sets to zero at run time gives NaN)."""
    inertials = [model.bodies[k].inertial for k in regressor.blocks(model) if model.bodies[k].inertial is not None]
    total = sum((i.mass if i.origin is None else i.origin[0] for i in inertials), 0)
    return not (total == 0)


def _has_free_root(model) -> bool:
    """A floating base (the root body's pair has all six coordinates) with a moving mass."""
    return len(model.bodies[0].pair.coordinates) == 6 and _has_moving_mass(model)


COM_CONVENTION = ("the bodies that move (a body welded to the world is left out, as Pinocchio's centerOfMass "
                  "leaves out the universe), their own inertia (no added mass, no armature), world axes")

register(Routine("frame_poses", ("q", "p"), (Output("X", lambda model: (frame_count(model), 12)),),
                 lambda bound, kin, x: (frames.frame_poses(bound, kin),),
                 "per frame: its origin in the world, then the rotation matrix from frame axes to world axes "
                 "(Pinocchio's oMf.rotation), row-major: the world pose L (1.13) composed from the root (Prop. 1.8)",
                 layout=frame_layout(["x", "y", "z", "R00", "R01", "R02", "R10", "R11", "R12", "R20", "R21", "R22"],
                                     "origin in world axes, then R row-major: x_world = R x_frame + origin"),
                 applies=_has_frames, coupled="tree"))
register(Routine("frame_jacobians", ("q", "p"),
                 (Output("J", lambda model: (frame_count(model), 6, model.nv)),),
                 lambda bound, kin, x: (flat(frames.frame_jacobians(bound, kin)),),
                 "per frame a 6 x n block: the velocity of its origin and its angular velocity per unit rate of each "
                 "coordinate, world axes (Pinocchio's LOCAL_WORLD_ALIGNED): the columns of S (1.42) moved to the "
                 "frame's origin",
                 layout=frame_layout(["vx", "vy", "vz", "wx", "wy", "wz"],
                                     "rows of each block: (v, w) of the frame origin, world axes; columns: q"),
                 applies=_has_frames, coupled="rows"))
register(Routine("frame_accelerations", ("q", "qd", "qdd", "p"),
                 (Output("a", lambda model: (frame_count(model), 6)),),
                 lambda bound, kin, x: (frames.frame_accelerations(bound, kin, x["qd"], x["qdd"]),),
                 "per frame the classical acceleration of its origin and its angular acceleration, world axes, from "
                 "the forward sweep (2.40) without gravity; with qdd = 0 it is J' qd",
                 layout=frame_layout(["ax", "ay", "az", "alphax", "alphay", "alphaz"],
                                     "classical (not spatial) acceleration of the origin, then the angular "
                                     "acceleration, world axes (Pinocchio's getFrameClassicalAcceleration, "
                                     "LOCAL_WORLD_ALIGNED)"),
                 applies=_has_frames, coupled="tree"))
register(Routine("center_of_mass", ("q", "p"), (Output("c", lambda model: (3,)),),
                 lambda bound, kin, x: (frames.center_of_mass(bound, kin),),
                 "the centre of mass in the world: sum (m_k o_k + R_k h_k) / M over the moving bodies, h_k the first "
                 "moment of Theta_lk (2.3)",
                 layout=lambda model: {"rows": ["x", "y", "z"], "convention": COM_CONVENTION}, coupled="tree",
                 applies=_has_moving_mass))
register(Routine("com_jacobian", ("q", "p"), (Output("Jc", lambda model: (3, model.nv)),),
                 lambda bound, kin, x: (flat(frames.com_jacobian(bound, kin)),),
                 "the Jacobian of the centre of mass, 3 x n row-major: column i is the linear momentum of the "
                 "subtree that coordinate i moves, per unit rate, over the total mass (S (1.42) applied to the "
                 "subtrees' mass and first moment)",
                 layout=lambda model: {"rows": ["x", "y", "z"], "columns": [c.name for c in model.coordinates],
                                       "order": "row-major", "convention": COM_CONVENTION}, coupled="rows",
                 applies=_has_moving_mass))
register(Routine("centroidal_map", ("q", "p"), (Output("Ag", lambda model: (6, model.nv)),),
                 lambda bound, kin, x: (flat(frames.centroidal_map(bound, kin)),),
                 "the centroidal momentum matrix A_G, 6 x n row-major: h_G = A_G qd, the linear momentum and the "
                 "angular momentum about the centre of mass, world axes (Pinocchio's computeCentroidalMap)",
                 layout=lambda model: {"rows": ["px", "py", "pz", "Lx", "Ly", "Lz"],
                                       "columns": [c.name for c in model.coordinates], "order": "row-major",
                                       "convention": COM_CONVENTION + "; angular momentum about the centre of mass"},
                 applies=_has_free_root, coupled="rows"))
