"""The numeric twin: every routine run on floats, the reference the generated C and NumPy are checked against.

``NumericTwin(model).inertia(q, p)`` etc. have the argument order of the generated NumPy module.
"""
from __future__ import annotations

import numpy as np

from .backend import Numeric, bind
from .model.tree import Tree
from .routines import ROUTINES, run


class NumericTwin:
    """Float evaluation of every routine of :data:`aggsym.routines.ROUTINES`."""

    def __init__(self, model):
        self.model = model
        self.tree = Tree(model)
        self.backend = Numeric()
        self._bound = {}

    def bound(self, p=None):
        key = None if p is None else tuple(float(x) for x in np.ravel(p))
        if key not in self._bound:
            self._bound[key] = bind(self.model, self.backend, p=None if p is None else list(key), tree=self.tree)
        return self._bound[key]

    def call(self, role: str, *args, p=None):
        """Evaluate routine ``role`` with its inputs (q, qd, ...) in order.

        Returns a NumPy array of the output's shape, or a tuple of arrays for a routine with several outputs."""
        routine = ROUTINES[role]
        names = [n for n in routine.inputs if n != "p"]
        if len(args) != len(names):
            raise TypeError(f"{role} takes {', '.join(names)}, got {len(args)} arguments")
        inputs = {}
        for name, value in zip(names, args):
            arr = np.asarray(value, dtype=float).reshape(-1)
            if arr.size != self.model.nq:
                raise ValueError(f"{role}: {name} has {arr.size} entries, the model has {self.model.nq} coordinates")
            inputs[name] = [float(x) for x in arr]
        outs = run(routine, self.bound(p), inputs)
        arrays = tuple(np.array([float(x) for x in flat]).reshape(o.shape(self.model))
                       for o, flat in zip(routine.outputs, outs))
        return arrays[0] if len(arrays) == 1 else arrays

    def __getattr__(self, role):
        if role in ROUTINES:
            return lambda *args, p=None: self.call(role, *args, p=p)
        raise AttributeError(role)
