"""A routine run on the symbolic backend, for tests that read its straight-line program or its SymPy form."""
from aggsym.backend import Symbolic, bind
from aggsym.equations import coordinate_symbols, to_sympy
from aggsym.kinematics import TreeKinematics
from aggsym.routines import ROUTINES


def routine_program(model, role):
    """(program, outputs): the routine's straight-line program and its outputs (lists of nodes or constants)."""
    routine = ROUTINES[role]
    back = Symbolic()
    prog = back.program
    bound = bind(model, back)
    ins = {n: prog.vector(n, model.nq) for n in routine.inputs if n != "p"}
    return prog, routine.build(bound, TreeKinematics(bound, ins["q"]), ins)


def routine_sympy(model, role):
    """The outputs of a routine as SymPy expressions in the symbols of aggsym.equations."""
    prog, outs = routine_program(model, role)
    q, qd, _ = coordinate_symbols(model)
    symbols = {("p", i): s for i, s in enumerate(model.parameter_symbols)}
    symbols.update({("q", i): s for i, s in enumerate(q)})
    symbols.update({("qd", i): s for i, s in enumerate(qd)})
    return [to_sympy(prog, out, symbols) for out in outs]
