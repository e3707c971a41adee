"""The registry of targets: every output of ``aggsym generate`` is one (:class:`~.base.Target`), one module each.

``TARGETS`` maps a name to its target, in the order their files are written; :func:`register` adds one (a new
target is one module, its templates and one line below, or a call from outside), :func:`select` turns
``--targets a,b`` into targets (an unknown name: an AggsymError, exit 2, listing the known ones).
"""
from __future__ import annotations

from ...errors import AggsymError
from .base import Job, RoutineLines, Runner, Target
from .c import CTarget
from .casadi import CasadiTarget
from .ext import ExtensionTarget
from .jax import JaxTarget
from .kernels import KernelsTarget
from .latex import LatexTarget
from .manifest import ManifestTarget
from .numpy import NumPyTarget
from .torch import TorchTarget

TARGETS: dict = {}


def register(target: Target, replace: bool = False) -> Target:
    """Add ``target`` to the registry (after those there); an existing name only with ``replace``."""
    if not target.name or not target.name.isidentifier():
        raise ValueError(f"a target's name must be an identifier, not {target.name!r}")
    if target.name in TARGETS and not replace:
        raise ValueError(f"a target named {target.name!r} is registered already")
    TARGETS[target.name] = target
    return target


def unregister(name: str) -> None:
    """Remove a target (a test's, say) from the registry."""
    TARGETS.pop(name, None)


def with_kernels(targets, kernels: bool = True) -> list:
    """``targets`` with the kernels target added (in registry order) when the C target and the JAX or PyTorch target
    are among them and ``kernels``; otherwise as they are (:mod:`.kernels`: the batch kernels those modules call)."""
    names = {t.name for t in targets}
    if not kernels or KernelsTarget.name in names or "c" not in names or not names & {"jax", "torch"}:
        return list(targets)
    return [t for t in TARGETS.values() if t in targets or t.name == KernelsTarget.name]


def known() -> str:
    return ", ".join(TARGETS)


def default_targets() -> list:
    return [t for t in TARGETS.values() if t.default]


def select(names=None, kernels: bool = True) -> list:
    """The targets named (a comma-separated string or an iterable of names or targets), in registry order; None:
    the default set.  An unknown or missing name is an AggsymError naming the known targets.  With the C target and
    the JAX or PyTorch target, the kernels target too (:func:`with_kernels`), unless ``kernels`` is
    False."""
    if names is None:
        return default_targets()
    if isinstance(names, str):
        names = [n.strip() for n in names.split(",") if n.strip()]
    names = list(names)
    if names and all(isinstance(n, Target) for n in names):  # (chosen already: kept, in registry order)
        return [t for t in TARGETS.values() if t in names] + [t for t in names if t not in TARGETS.values()]
    names = [n.name if isinstance(n, Target) else n for n in names]
    unknown = [n for n in names if n not in TARGETS]
    if unknown:
        raise AggsymError(f"--targets: unknown target{'s' if len(unknown) > 1 else ''} "
                          f"{', '.join(repr(n) for n in unknown)}; the known targets are: {known()}")
    if not names:
        raise AggsymError(f"--targets: no target named; the known targets are: {known()}")
    return with_kernels([t for name, t in TARGETS.items() if name in names], kernels)


for _target in (CTarget(), NumPyTarget(), ManifestTarget(), LatexTarget(), JaxTarget()):  # one line per target
    register(_target)
register(TorchTarget())  # --targets torch (not in the default set)
register(ExtensionTarget())  # --targets c,numpy,ext (not in the default set)
register(CasadiTarget())  # --targets casadi (not in the default set)
register(KernelsTarget())  # with c and jax or torch (with_kernels), unless --no-kernels

__all__ = ["Job", "RoutineLines", "Runner", "Target", "TARGETS", "register", "unregister", "select", "known",
           "default_targets", "with_kernels"]
