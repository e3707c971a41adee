"""``aggsym check``: every generated target that has something to run (the C compiled, the Python modules
imported: each target's :meth:`~aggsym.codegen.targets.base.Target.runner`) against the numeric twin on random
states."""
from __future__ import annotations

import json
import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..contract import ROUTINES, input_length, sample_configurations, signature
from ..twin import NumericTwin
from .compile import CTYPES
from .targets import TARGETS


@dataclass
class CheckResult:
    """One routine's worst errors against the numeric twin, per target checked (its name: ``c``, ``numpy``,
    ...), and the targets' own bounds where they have one (float C: the manifest's float_tolerance)."""

    role: str
    errors: dict  # column key (a target's name, or one of its runners') -> worst relative error; NaN: not checked
    tolerances: dict = field(default_factory=dict)  # column key -> its bound; absent: the --tol
    columns: dict = field(default_factory=dict)  # column key -> its heading, in order

    @property
    def c_error(self) -> float:
        return self.errors["c"]

    @property
    def py_error(self) -> float:
        return self.errors["numpy"]

    @property
    def c_tolerance(self) -> float | None:
        return self.tolerances.get("c")


def random_inputs(model, role, rng):
    routine = ROUTINES[role]
    args = []
    for name in signature(routine, model):
        if name == "p":
            continue
        size = input_length(model, name, routine)
        if name == "q" and size == model.nq:
            args.append(sample_configurations(model, rng))
        elif name in ("q", "gamma"):
            args.append(rng.uniform(-np.pi, np.pi, size))
        elif name == "t":
            args.append(float(rng.uniform(0, 10)))
        elif name == "r":  # a restitution coefficient
            args.append(float(rng.uniform(0, 1)))
        else:
            args.append(rng.normal(size=size))
    return args


def relative_error(a, b, scale=None) -> float:
    """max |a - b| / max |b| (or / scale when given, e.g. the largest output of a routine with several)."""
    a, b = np.atleast_1d(np.asarray(a, dtype=float)), np.atleast_1d(np.asarray(b, dtype=float))
    if not a.size:
        return 0.0
    scale = float(np.max(np.abs(b))) if scale is None else scale
    return float(np.max(np.abs(a - b)) / (scale if scale > 0 else 1.0))


def _support_matrices(twin, role, args):
    """A and I of the support equation at the state of a support routine's arguments."""
    x = dict(zip([n for n in signature(ROUTINES[role], twin.model) if n != "p"], args))
    A, _, I, _, _, _ = twin.call("support_coefficients", x["q"], x["qd"], x["gamma"], x["gammad"])
    return A, I


CONDITIONING = {  # role -> (twin, role, args) -> the condition number that the routine's solve multiplies rounding by
    "constrained_forward_dynamics": lambda twin, role, args: float(np.linalg.cond(twin.call("delassus", args[0]))),
    "impulse_dynamics": lambda twin, role, args: float(np.linalg.cond(twin.call("delassus", args[0]))),
    "constrained_forward_dynamics_derivatives":
        lambda twin, role, args: float(np.linalg.cond(twin.call("delassus", args[0]))),
    "impulse_dynamics_derivatives": lambda twin, role, args: float(np.linalg.cond(twin.call("delassus", args[0]))),
    "support_direct": lambda twin, role, args: float(np.linalg.cond(_support_matrices(twin, role, args)[0])),
    "support_inverse": lambda twin, role, args: float(np.linalg.cond(_support_matrices(twin, role, args)[1])) ** 2,
}


def _inertia_condition(twin, role, args) -> float:
    """The condition number of A(q) at the state of a routine's arguments (q first)."""
    return float(np.linalg.cond(np.asarray(twin.call("inertia", args[0]), dtype=float)))


def _fails(call) -> bool:
    """True when ``call()`` raises numpy.linalg.LinAlgError (a returned nonzero status)."""
    try:
        call()
    except np.linalg.LinAlgError:
        return True
    return False


def checked_targets(model, files: dict, targets=None) -> tuple:
    """(targets to check, {name: why not}): those of ``targets`` (names; None: every registered one) whose files
    are among ``files`` and that have something to run, less those that cannot run here (no compiler)."""
    chosen, skipped = [], {}
    for name, target in TARGETS.items():
        main = target.main_file(model.name)
        if (targets is not None and name not in targets) or main is None or main not in files:
            continue
        why = target.unavailable()
        if why:
            skipped[name] = why
        else:
            chosen.append(target)
    return chosen, skipped


def check_generated(model, files: dict, trials: int = 20, seed: int = 0, workdir=None, opt: str = "-O2",
                    targets=None):
    """Run every target generated in ``files`` that has something to run (:func:`checked_targets`; ``targets``:
    only these names) and compare each with the numeric twin on random states: the C compiled (with ``opt``; a
    ``--split`` output by its Makefile, with the same flags), the NumPy module imported, ... (each target's
    :meth:`~aggsym.codegen.targets.base.Target.runner`).

    Errors are relative to the largest value a routine returns, and for the constrained forward dynamics also to
    the condition number of J A^-1 J^T at the state (the solve's rounding grows with it).  Float C (the manifest's
    ``scalar``) gets the states rounded to float, as its caller holds them, and its bound from the manifest's
    ``float_tolerance``; the float errors of the routines that solve with A are also divided by cond(A) at the
    state (the manifest's ``float_tolerance_per_condition``)."""
    manifest = json.loads(files[f"{model.name}.json"])
    dtype = CTYPES[manifest.get("scalar", "double")][1]
    checked, _ = checked_targets(model, files, targets)
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        tmp = Path(tmp)
        for name, text in files.items():
            (tmp / name).write_text(text, encoding="utf-8")
        runners, columns = {}, {}
        for t in checked:
            for key, (heading, runner) in t.runners(model, tmp, manifest, opt).items():
                runners[key], columns[key] = runner, heading
        twin = NumericTwin(model)
        rng = np.random.default_rng(seed)
        results = []
        for role in manifest["functions"]:
            worst = dict.fromkeys(runners, 0.0)
            for _ in range(trials):
                args = _rounded(random_inputs(model, role, rng), dtype)
                try:
                    ref = twin.call(role, *args)
                except np.linalg.LinAlgError:  # a state without a solution: every target must say so too
                    for name, runner in runners.items():
                        said = _fails(lambda: runner.call(role, *args))
                        worst[name] = max(worst[name], 0.0 if said else math.inf)
                    continue
                got = {name: runner.call(role, *args) for name, runner in runners.items()}
                refs = ref if isinstance(ref, tuple) else (ref,)
                scale = max(float(np.max(np.abs(r))) if np.size(r) else 0.0 for r in refs)
                if role in CONDITIONING:  # a solve: its rounding grows with the condition number of its matrix
                    scale *= CONDITIONING[role](twin, role, args)
                for name, runner in runners.items():
                    own = scale * (_inertia_condition(twin, role, args)  # float: solving with A loses cond(A)
                                   if role in runner.per_condition else 1.0)
                    outs = got[name] if isinstance(got[name], tuple) else (got[name],)
                    for r, x in zip(refs, outs):  # relative to the largest value the routine returns
                        worst[name] = max(worst[name], relative_error(x, r, own))
            results.append(CheckResult(role, worst, {name: r.bounds[role] for name, r in runners.items()
                                                     if role in r.bounds}, columns))
            derivatives = _derivatives(model, twin, role, runners, rng, min(trials, DERIVATIVE_TRIALS))
            if derivatives is not None:
                results.append(CheckResult(f"d {role}", *derivatives, columns))
        return results


DERIVATIVE_TRIALS = 3  # states per differentiated routine
DERIVATIVE_TOLERANCE = 1e-6  # central differences' own error (h = 1e-6), relative to the largest derivative


def _derivatives(model, twin, role, runners, rng, trials):
    """(errors, tolerances) of the runners that differentiate ``role`` (their :attr:`~.targets.base.Runner.jacobian`)
    against central differences of the numeric twin along each array argument; None when none does."""
    which = {name: r for name, r in runners.items() if r.jacobian is not None}
    if not which or role not in ("forward_dynamics", "inverse_dynamics"):
        return None
    worst = {name: (0.0 if name in which else math.nan) for name in runners}
    for _ in range(trials):
        args = random_inputs(model, role, rng)
        try:
            cds = [_central(lambda x, k=k: twin.call(role, *[x if j == k else a for j, a in enumerate(args)]),
                            np.asarray(a, dtype=float)) for k, a in enumerate(args)]
        except np.linalg.LinAlgError:
            continue
        scale = max(float(np.max(np.abs(c))) for c in cds) or 1.0
        for name, runner in which.items():
            for got, cd in zip(runner.jacobian(role, *args), cds):
                worst[name] = max(worst[name], relative_error(got, cd, scale))
    return worst, {name: DERIVATIVE_TOLERANCE for name in which}


def _central(f, x, h=1e-6):
    """d f / d x by central differences (the direction last)."""
    first = np.asarray(f(x), dtype=float)
    out = np.empty(first.shape + (x.size,))
    for i in range(x.size):
        e = np.zeros_like(x)
        e.flat[i] = h
        out[..., i] = (np.asarray(f(x + e), dtype=float) - np.asarray(f(x - e), dtype=float)) / (2 * h)
    return out


def _rounded(args, dtype):
    """The arguments as the C's scalar type holds them (unchanged for double), as double again."""
    if dtype == np.float64:
        return args
    return [float(dtype(a)) if np.isscalar(a) else np.asarray(a, dtype=dtype).astype(float) for a in args]
