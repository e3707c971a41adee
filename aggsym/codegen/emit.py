"""The emission of one routine into every chosen target: what no single target owns.

For each routine of a generation (:func:`aggsym.codegen.generate.generate` calls :func:`emit_routine` in the
contract's order), its outputs are cut out of the shared straight-line program
(:func:`aggsym.core.program.straight_line`), printed as C (always, whatever the targets: the C printer counts the
operations as it prints them, the manifest's ``ops``, and gives the texts that the other infix targets print
alike: :func:`~aggsym.codegen.targets.c.print_c`), then by each chosen target's
:meth:`~aggsym.codegen.targets.base.Target.print_routine`.  Every target's text is kept in one place,
``EmittedRoutine.bodies[target name]`` (the C's under ``"c"``), for the target to render its files from.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..contract import Routine, signature
from ..core.program import straight_line
from ..errors import AggsymError
from .names import c_prototype, c_symbol, python_parameters
from .printing import LiteralError
from .targets.c import print_c
from .targets.c_columns import LOOPED_ABOVE


@dataclass
class EmittedRoutine:
    """One routine as the targets printed it: ``routine`` of the contract, its ``inputs`` in argument order for
    this model (:func:`aggsym.contract.signature`), its C ``symbol`` and ``prototype`` (without the semicolon),
    the Python functions' parameter list ``py_parameters``, the operations of its C (``ops``: mul, add, div,
    call), its named temporaries (``temps``), its C's size as :func:`.slicing.work` measures it (``work``) and
    ``bodies``: {target name: what that target printed} (:class:`~.targets.c.CBody` under ``"c"``)."""

    routine: Routine
    inputs: tuple
    symbol: str
    prototype: str
    py_parameters: str
    ops: dict
    temps: int
    work: int = 0
    bodies: dict = field(default_factory=dict)


def emit_routine(model, prog, routine: Routine, outputs, targets=(), scalar: str = "double", slicing=None,
                 sl=None, columns=None, looped_above: int = LOOPED_ABOVE) -> EmittedRoutine:
    """One routine printed as C and by each of ``targets`` (their :meth:`print_routine`; the C target itself
    prints nothing more).  ``scalar``: the C type (double or float); ``slicing``: (threshold, size), a large
    routine's C also as slices (:mod:`.slicing`), None: never; ``sl``: the outputs' straight line when already
    formed; ``columns``: the routine's :class:`~aggsym.core.columns.ColumnMap`, looped over in the C when its
    unrolled C has more than ``looped_above`` operations (:mod:`.targets.c_columns`)."""
    try:
        sl = sl or straight_line(prog, outputs)
        inputs = signature(routine, model)
        printed = print_c(model, prog, routine, outputs, sl, scalar, slicing, columns, looped_above)
        emitted = EmittedRoutine(routine, inputs, c_symbol(model, routine), c_prototype(model, routine, scalar),
                                 python_parameters(model, routine), printed.ops, printed.temps, printed.work,
                                 {"c": printed.body})
        for target in targets:
            body = target.print_routine(model, prog, printed.lines, emitted)
            if body is not None:
                emitted.bodies[target.name] = body
        return emitted
    except LiteralError as exc:
        raise AggsymError(f"{model.source or model.name}: routine {routine.role}: {exc}"
                          + ("; generate with --scalar double, or choose units in which the model's numbers fit"
                             if scalar == "float" else "")) from None
