"""The numeric twin: every routine run on floats, the reference the generated C and NumPy are checked against.

``NumericTwin(model).inertia(q, p)`` etc. have the argument order of the generated NumPy module.  For a model with
prescribed motions the time t comes after the other inputs (``inertia(q, t)``); the twin also accepts it omitted
(then the keyword ``t``, default 0).
"""
from __future__ import annotations

import numpy as np

from .contract import ROUTINES, input_length, routine_of, run, signature
from .core.backend import Numeric
from .mechanics.bound import bind
from .model.tree import Tree


class NumericTwin:
    """Float evaluation of every routine of :data:`aggsym.contract.ROUTINES`."""

    def __init__(self, model):
        self.model = model
        self.tree = Tree.of(model)
        self.backend = Numeric()
        self._bound = {}

    def bound(self, p=None, t=None):
        key = (None if p is None else tuple(float(x) for x in np.ravel(p)), None if t is None else float(t))
        if key not in self._bound:
            if len(self._bound) > 64:  # a time-dependent model is bound at every t it is called at
                self._bound.clear()
            self._bound[key] = bind(self.model, self.backend, p=None if p is None else list(key[0]), tree=self.tree,
                                    t=key[1])
        return self._bound[key]

    def call(self, role: str, *args, p=None, t=None):
        """Evaluate routine ``role`` with its inputs (q, qd, ..., and t for a time-dependent model) in order.

        Returns a NumPy array of the output's shape, or a tuple of arrays for a routine with several outputs."""
        routine = routine_of(self.model, role)
        if self.model.couplings and routine.coupled is None:
            raise ValueError(f"{role} is not a routine of {self.model.name}: its coordinates are coupled "
                             "(--mimic couple), and the routine has no coupled form")
        names = [n for n in signature(routine, self.model) if n != "p"]
        if "t" in names and len(args) == len(names) - 1:
            args = args + (0.0 if t is None else t,)
        if len(args) != len(names):
            raise TypeError(f"{role} takes {', '.join(names)}, got {len(args)} arguments")
        inputs = {}
        for name, value in zip(names, args):
            arr = np.asarray(value, dtype=float).reshape(-1)
            if name == "t":
                if arr.size != 1:
                    raise ValueError(f"{role}: t is one number, got {arr.size}")
                t = float(arr[0])
                continue
            length = input_length(self.model, name, routine)
            if arr.size != length:
                raise ValueError(f"{role}: {name} has {arr.size} entries, expected {length}")
            inputs[name] = [float(x) for x in arr]
        outs = run(routine, self.bound(p, t if self.model.time_dependent else None), inputs)
        arrays = tuple(np.array([float(x) for x in flat]).reshape(o.shape(self.model))
                       for o, flat in zip(routine.outputs, outs) if not o.returned)
        if routine.status is not None and float(outs[-1][0]) != 0.0:
            raise np.linalg.LinAlgError(f"{role}: {routine.status.failure}, at this state")
        return arrays[0] if len(arrays) == 1 else arrays

    def __getattr__(self, role):
        if role in ROUTINES:
            return lambda *args, p=None, t=None: self.call(role, *args, p=p, t=t)
        raise AttributeError(role)
