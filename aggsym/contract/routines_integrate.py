"""The routine ``integrate``: q (+) v dt on the configuration manifold (a free-flyer's or a ball's quaternion), Pinocchio's
integrate; registered after the support routines and before the derivatives (the order of emission)."""
from __future__ import annotations

from ..mechanics import manifold
from .registry import Output, Routine, register
from .shapes import positions_vector


def _has_quaternion(model) -> bool:
    """A free-flyer root (--floating-base quaternion) or a ball pair: q has more entries than qd (nq > nv)."""
    return any(b.pair.quaternion for b in model.bodies)


register(Routine("integrate", ("q", "v", "dt"), (Output("q_next", positions_vector),),
                 lambda bound, kin, x: (manifold.integrate(bound, x["q"], x["v"], x["dt"][0]),),
                 "q (+) v dt, Pinocchio's integrate: the joints q + v dt, the free-flyer root M exp((v, w) dt) in "
                 "SE(3), a ball pair's rotation R exp(w dt) in SO(3) (quaternions normalized)",
                 layout=lambda model: {"q_next": "the same layout as q (the manifest's 'coordinates'); v has the "
                                                 "layout of the 'velocities'; dt is one number"},
                 applies=_has_quaternion, coupled=None))
