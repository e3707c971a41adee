"""The transforms wing of :mod:`aggsym.model`: a :class:`~aggsym.model.types.Model` to another.

Each module is one change of a model that keeps it a model: the internal frames of the recursions
(``reframe``), runtime inertial parameters and payloads (``inertials``), gravity as a parameter (``gravity``),
the joints' damping and friction in the equations (``joint_dynamics``), the frames of the frame routines
(``frames``).  A transform uses the model's types alone (and :mod:`aggsym.core`); it never imports a reader.
The order in which ``aggsym generate``'s options apply them is :mod:`aggsym.model.prepare`'s.
"""
