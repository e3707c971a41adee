"""The generated-code contract: every routine's name, inputs, outputs and their layouts, and the manifest.

A :class:`Routine` takes named input vectors (``q``, ``qd``, ``qdd``, ``tau``; ``p`` is bound with the model) and
returns its outputs flattened row-major.  Its ``build`` is written once over a backend (:mod:`aggsym.mechanics`):
on floats it is the numeric twin (:mod:`aggsym.twin`), on the symbolic backend the straight-line program that
:mod:`aggsym.codegen` prints as C and NumPy.  Adding an output is adding one entry to :data:`ROUTINES` (its
algorithm lives in the mechanics; a layout for the manifest, if it needs one, lives with its registration).

The equations are ``A(q) q'' + b(q, q') + g(q) + c(q) = tau`` (2.17), (2.27):

* ``c(q) = C (q - q0)``, the elastic generalized force of the Hooke-elastic pairs (routine ``elastic``, models
  with stiffness only); it is in ``inverse_dynamics``, ``nonlinear_effects`` (d = b + g + c) and hence
  ``forward_dynamics``, and its energy is in ``potential_energy``; ``bias`` and ``gravity`` never hold it.
* A model with prescribed motions (rotors with a prescribed spin, (2.13)) is time dependent: every routine then
  takes the time ``t`` (one number) after its other inputs and before ``p`` (:func:`signature`).  Its
  ``bias`` holds every term of the spins' rates and accelerations (the book's A'V and T of (2.13) less the
  rotors' weight, which is in ``gravity``), so that ``b = B q'`` no longer holds, and A(q, t) turns with the
  rotors.
* Coordinates tied to others (URDF ``<mimic>`` with ``mimic="couple"``) are handled by
  :mod:`aggsym.mechanics.coupling`; each routine says how its outputs reduce (``Routine.coupled``).

The package, one concern a module: :mod:`.registry` (Routine, Output, ROUTINES, signatures, running a routine),
:mod:`.shapes` (the outputs' shapes), the registrations by domain (:mod:`.routines_dynamics`,
:mod:`.routines_constraints`, :mod:`.routines_support`, :mod:`.routines_integrate`, :mod:`.routines_impacts`,
:mod:`.routines_derivatives`,
:mod:`.routines_frames`, :mod:`.routines_regressor`: imported below in that order, which is the order of
registration, hence of emission and of the manifest), :mod:`.analyses` (numerical analyses of a model),
:mod:`.exact_relations` (the base parameters' exact coefficients),
:mod:`.selection` (the routines left out, ``--routines``), :mod:`.singular_states` (the status of the routines
that solve with A(q) where it may be singular on a set) and :mod:`.manifests` (the manifest, the float
tolerances).  The C names (``NAME_role``, prototypes, header macros) are the C target's:
:mod:`aggsym.codegen.names`.
"""
from __future__ import annotations

from .registry import (INPUT_KINDS, ROUTINES, SCALAR_INPUTS, Output, Routine, input_length, register, routines_for, run,
                       signature)
from .shapes import (
    constraint_jacobian_shape, constraint_rows_vector, constraint_square, frame_count, joint_wrench_shape,
    mechanism_vector, momentum_shape, nq_square, nq_vector, partition_block_shape, positions_vector, regressor_shape,
    friction_regressor_shape,
    scalar, six, slip_vector, support_block, support_lengths, transvection_count,
)
# the registrations, in the order of emission
from .routines_dynamics import (
    JOINT_WRENCH_CONVENTION, joint_wrench_layout, momentum_layout, partition_layout, transvective_layout,
)
from .routines_constraints import (
    CONSTRAINT_FAILURE, constraint_layout, constraint_row_labels, slip_labels, slip_layout,
)
from .routines_support import SUPPORT_FAILURE, SUPPORT_OUTPUTS, support_layout
from . import routines_integrate  # noqa: F401  (registers integrate)
from . import routines_impacts  # noqa: F401  (registers impulse_dynamics)
from . import routines_derivatives  # noqa: F401  (registers the derivatives of the dynamics)
from .routines_frames import COM_CONVENTION, frame_layout
from .routines_regressor import (
    base_regressor_layout, drive_parameter_names, friction_regressor_layout, regressor_layout, standard_parameter_names,
)
from .analyses import (
    BASE_RANK_TOLERANCE, BASE_SEED, base_parameters, pivoted_columns, redundant_constraints,
    regressor_problem, sample_configurations,
)
from .selection import omitted_routines, select_routines
from .singular_states import mass_matrix_note, reports_singular_states, routine_of
from .manifests import (
    FLOAT_PER_CONDITION, FLOAT_TIME, FLOAT_TOLERANCE, FLOAT_TOLERANCE_DEFAULT, constraints_entry, elastic_entry,
    float_tolerance, frames_entry, manifest, time_entry,
)

__all__ = [
    "INPUT_KINDS", "Output", "Routine", "ROUTINES", "SCALAR_INPUTS", "register", "signature", "input_length", "routines_for", "run",
    "routine_of", "reports_singular_states", "mass_matrix_note",
    "nq_vector", "nq_square", "positions_vector", "scalar", "momentum_shape", "joint_wrench_shape",
    "transvection_count", "partition_block_shape", "constraint_rows_vector", "constraint_jacobian_shape",
    "constraint_square", "slip_vector", "support_lengths", "support_block", "six", "mechanism_vector", "frame_count",
    "regressor_shape", "friction_regressor_shape",
    "momentum_layout", "JOINT_WRENCH_CONVENTION", "joint_wrench_layout", "transvective_layout", "partition_layout",
    "constraint_row_labels", "constraint_layout", "slip_labels", "slip_layout", "CONSTRAINT_FAILURE",
    "SUPPORT_OUTPUTS", "SUPPORT_FAILURE", "support_layout", "frame_layout", "COM_CONVENTION", "regressor_layout",
    "standard_parameter_names", "base_regressor_layout", "friction_regressor_layout", "drive_parameter_names",
    "regressor_problem", "BASE_SEED", "BASE_RANK_TOLERANCE", "base_parameters", "pivoted_columns",
    "sample_configurations", "redundant_constraints",
    "omitted_routines", "select_routines",
    "FLOAT_TOLERANCE", "FLOAT_PER_CONDITION", "FLOAT_TOLERANCE_DEFAULT", "FLOAT_TIME", "float_tolerance", "manifest",
    "constraints_entry", "time_entry", "elastic_entry", "frames_entry",
]
