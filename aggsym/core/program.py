"""Straight-line programs: the symbolic scalar the book's recursions run on, and everything done with them
before printing (naming for CSE, evaluation, conversion to SymPy).

Every recursion of aggsym (kinematics (1.28)-(1.43), composite bodies (2.32)-(2.34), the O(n) bias
(2.36)-(2.37), the sweeps (2.39)-(2.46), the transvective factors (3.7)-(3.20)) is written once against plain
Python arithmetic.  Run on floats (or NumPy arrays) it is the numeric twin; run on :class:`Node` objects of a
:class:`Program` it records a straight-line program: every operation becomes one node ``t = a op b``.

A node is created through :meth:`Program.op`, which

* folds constants (``2*3 -> 6``) and structural zeros and ones (``0*x -> 0``, ``1*x -> x``, ``x+0 -> x``),
  so the structurally zero blocks of L, Phi and M never reach the output;
* moves negations outwards and into subtractions (``(-a)*b -> -(a*b)``, ``a + -b -> a - b``);
* hash-conses (value numbering): the same operation on the same operands is the same node, so common
  subexpressions, and in particular ``sin``/``cos`` of each angle, exist once per program;
* numbers products modulo commutativity and associativity: a product whose factors (and constant coefficient)
  are those of an existing product *is* that node, so ``x (k y)`` and ``y (k x)`` are one value and their
  difference folds to 0.  Only existing nodes are reused; nothing is regrouped.

Constants are plain Python numbers; every constant operand is normalized on the way in (integral floats become
``int``, so ``2.0*x`` and ``2*x`` are one node and the zero and one tests are exact).  Node ids grow in creation
order, which is a topological order.

Everything that walks a program is iterative (no recursion over its depth): :meth:`Program.reachable`,
:meth:`Program.interpret` (the one interpreter: :meth:`Program.evaluate` on floats or arrays, :func:`to_sympy`,
:func:`expanded_terms`) and :func:`straight_line` (which nodes get a name: the CSE of the emitted code).
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from fractions import Fraction

from .functions import COS, FUNCTIONS, SIN, SQRT

__all__ = ["Program", "Node", "arithmetic", "is_zero", "is_one", "is_const", "normalize_const", "fold", "to_sympy",
           "expanded_terms", "straight_line", "StraightLine", "FUNCTIONS", "INLINE_DEPTH"]

# operation codes
INPUT, ADD, SUB, MUL, DIV, NEG = "in", "+", "-", "*", "/", "neg"
_COMMUTATIVE = (ADD, MUL)
# the operation's part of the int key of an operation on two nodes (:meth:`Program._make`)
_CODE_INDEX = {code: k for k, code in enumerate((ADD, SUB, MUL, DIV, NEG) + tuple(FUNCTIONS))}
_CODE_BITS = 5
assert len(_CODE_INDEX) <= 1 << _CODE_BITS
_NUMBERS = (int, float, Fraction)
INLINE_DEPTH = 64  # the deepest expression a named value inlines: what printers may recurse through


def normalize_const(x):
    """An exact ``int`` for integral floats (so 0.0 and 1.0 fold), the float otherwise."""
    cls = x.__class__
    if cls is int:
        return x
    if cls is float:  # (before the isinstance test below, which goes through the numbers ABCs)
        return int(x) if x.is_integer() and abs(x) < 2.0 ** 53 else x
    if isinstance(x, Fraction):
        return int(x) if x.denominator == 1 else x
    x = float(x)
    if x.is_integer() and abs(x) < 2.0 ** 53:
        return int(x)
    return x


def is_const(x) -> bool:
    return not isinstance(x, Node)


def fold(x):
    """A Python number in its canonical form (:func:`normalize_const`); anything else (nodes, NumPy values) as is."""
    return normalize_const(x) if type(x) in _NUMBERS else x


_EXACT = (int, float, Fraction)  # Python constants; NumPy scalars and arrays are runtime values


def is_zero(x) -> bool:
    """True for a constant zero (int, float or Fraction, e.g. 0.00078 - 0.00078 computed on constants), never
    for a symbolic node or a NumPy value.  (On the numeric twin's Python floats it may also skip a runtime exact
    zero, which changes nothing: 0 * x = 0 for finite x.)"""
    return type(x) in _EXACT and x == 0


def is_one(x) -> bool:
    return type(x) in _EXACT and x == 1


class Node:
    """One value of a straight-line program; arithmetic on it records new nodes."""

    __slots__ = ("prog", "id")

    def __init__(self, prog: "Program", ident: int):
        self.prog = prog
        self.id = ident

    # arithmetic (self is a node, so only the other operand needs folding; the rules are :meth:`Program.op`'s)
    def __add__(self, other):
        return self.prog._add(self, other if other.__class__ is Node else fold(other))

    def __radd__(self, other):
        return self.prog._add(other if other.__class__ is Node else fold(other), self)

    def __sub__(self, other):
        return self.prog._sub(self, other if other.__class__ is Node else fold(other))

    def __rsub__(self, other):
        return self.prog._sub(other if other.__class__ is Node else fold(other), self)

    def __mul__(self, other):
        return self.prog._mul(self, other if other.__class__ is Node else fold(other))

    def __rmul__(self, other):
        return self.prog._mul(other if other.__class__ is Node else fold(other), self)

    def __truediv__(self, other):
        return self.prog._div(self, other if other.__class__ is Node else fold(other))

    def __rtruediv__(self, other):
        return self.prog._div(other if other.__class__ is Node else fold(other), self)

    def __neg__(self):
        return self.prog._neg(self)

    def __pos__(self):
        return self

    # identity -------------------------------------------------------------------------------------
    def __hash__(self):
        return self.id

    def __eq__(self, other):  # structural identity; never used for numeric comparison
        return isinstance(other, Node) and other.id == self.id and other.prog is self.prog

    def __bool__(self):
        raise TypeError("a symbolic value has no truth value")

    def __repr__(self):
        return f"<t{self.id} {self.prog.ops[self.id][0]}>"


def _same(x, node) -> bool:
    """x is the node ``node`` (an operand that is a constant is not)."""
    return x.__class__ is Node and x.id == node.id


def _key(x):
    """Hash key and sort key of an operand: constants first, then nodes by id."""
    if isinstance(x, Node):
        return (1, x.id)
    return (0, repr(x))


class Program:
    """A growing straight-line program: ``ops[i] = (opcode, operand, ...)`` defines node ``i``."""

    def __init__(self):
        self.ops: list[tuple] = []
        self.nodes: list[Node] = []
        self._table: dict = {}
        self._products: dict = {}  # product signature -> Node (the factor ids alone when the coefficient is 1)
        self._signatures: dict = {}  # MUL node id -> sorted factor ids
        self._coefficients: dict = {}  # MUL node id -> its constant coefficient, where that is not 1
        self.inputs: dict = {}  # (kind, index) -> Node
        self.columns: dict = {}  # routine role -> ColumnMap: its outputs as one body applied to columns
        # (aggsym.core.columns), recorded by the routine for the targets that print the body once

    def release(self) -> None:
        """Drop every node: a node refers to its program and the program to its nodes, a cycle that only the
        cyclic collector would free, and :func:`~aggsym.collector.collector_paused` keeps it off while
        generating; a scratch program that has served (a count) is released at once instead."""
        self.ops, self.nodes, self.inputs, self.columns = [], [], {}, {}
        self._table, self._products, self._signatures, self._coefficients = {}, {}, {}, {}

    def seal(self) -> None:
        """Drop the tables that share nodes while the program grows (value numbering, the products' signatures),
        keeping every node: once the routines are built, printing them only reads the program, and a node made
        after this is still correct, only not shared with the earlier ones.  On a chain of 96 bodies they held
        about a quarter of the program's memory."""
        self._table, self._products, self._signatures, self._coefficients = {}, {}, {}, {}

    # construction ---------------------------------------------------------------------------------
    def input(self, kind: str, index: int) -> Node:
        """The runtime input ``kind[index]`` (q, qd, qdd, tau, p, ...), created once."""
        key = (kind, index)
        node = self.inputs.get(key)
        if node is None:
            node = self._new((INPUT, kind, index))
            self.inputs[key] = node
        return node

    def vector(self, kind: str, n: int) -> list:
        return [self.input(kind, i) for i in range(n)]

    def call(self, name: str, *args):
        """The function ``name`` of :data:`FUNCTIONS` applied to its arguments (folded on constants)."""
        function = FUNCTIONS[name]
        arity = function.arity
        if len(args) != arity:
            raise TypeError(f"{name} takes {arity} argument(s)")
        args = tuple(fold(a) for a in args)
        if all(is_const(a) for a in args):
            return normalize_const(function.value(*args))
        return self._make(name, *args)

    def sin(self, x):
        return self.call(SIN, x)

    def cos(self, x):
        return self.call(COS, x)

    def sqrt(self, x):
        return self.call(SQRT, x)

    def _new(self, entry: tuple) -> Node:
        node = Node(self, len(self.ops))
        self.ops.append(entry)
        self.nodes.append(node)
        return node

    def _make(self, opcode, *args):
        """The node ``opcode(*args)``, created unless it exists (hash-consing).  The key holds a node operand's id
        and a constant operand's repr (a str: never equal to an id); a commutative operation's operands are put in
        order, constants first, then nodes by id."""
        if len(args) == 2:
            return self._make2(opcode, args[0], args[1])
        key = (opcode,) + tuple(a.id if a.__class__ is Node else repr(a) for a in args)
        node = self._table.get(key)
        if node is None:
            node = self._new((opcode,) + args)
            self._table[key] = node
        return node

    def _make2(self, opcode, a, b):
        """:meth:`_make` of a binary operation (the commonest: every arithmetic operation), written out."""
        if a.__class__ is Node:
            if b.__class__ is Node:  # the key of an operation on two nodes: one int
                ka, kb = a.id, b.id
                if ka > kb and (opcode == ADD or opcode == MUL):
                    a, b, ka, kb = b, a, kb, ka
                key = ((ka << 32 | kb) << _CODE_BITS) | _CODE_INDEX[opcode]
                table = self._table
                node = table.get(key)
                if node is None:
                    ops = self.ops
                    node = table[key] = Node(self, len(ops))
                    ops.append((opcode, a, b))
                    self.nodes.append(node)
                return node
            ka, kb = a.id, repr(b)
            if opcode == ADD or opcode == MUL:
                a, b, ka, kb = b, a, kb, ka
        else:
            ka = repr(a)
            if b.__class__ is Node:
                kb = b.id
            else:
                kb = repr(b)
                if ka > kb and (opcode == ADD or opcode == MUL):
                    a, b, ka, kb = b, a, kb, ka
        key = (opcode, ka, kb)
        node = self._table.get(key)
        if node is None:
            node = self._new((opcode, a, b))
            self._table[key] = node
        return node

    def _neg_arg(self, x):
        """``y`` when ``x`` is the node ``-y``, else None."""
        if x.__class__ is Node:
            entry = self.ops[x.id]
            if entry[0] == NEG:
                return entry[1]
        return None

    def op(self, opcode, a, b=None):
        """Record ``a opcode b`` with folding; the result is a constant or a node."""
        a, b = fold(a), fold(b)
        if opcode == NEG:
            return self._neg(a)
        if opcode in FUNCTIONS:
            return self.call(opcode, a)
        if is_const(a) and is_const(b):
            if opcode == ADD:
                return normalize_const(a + b)
            if opcode == SUB:
                return normalize_const(a - b)
            if opcode == MUL:
                return normalize_const(a * b)
            if opcode == DIV:
                return normalize_const(a / b)
        if opcode == ADD:
            return self._add(a, b)
        if opcode == SUB:
            return self._sub(a, b)
        if opcode == MUL:
            return self._mul(a, b)
        if opcode == DIV:
            return self._div(a, b)
        raise ValueError(f"unknown operation {opcode!r}")

    def _neg(self, a):
        if a.__class__ is not Node:
            return normalize_const(-a)
        entry = self.ops[a.id]
        if entry[0] == NEG:
            return entry[1]
        if entry[0] == SUB:  # -(x - y) = y - x, free
            return self._sub(entry[2], entry[1])
        key = (NEG, a.id)  # (_make's key of a unary operation)
        node = self._table.get(key)
        if node is None:
            node = self._table[key] = self._new((NEG, a))
        return node

    def _add(self, a, b):
        # (the tests of is_zero, _neg_arg and is_const written out: this runs for every addition recorded)
        if a.__class__ is Node and b.__class__ is Node:  # the commonest sum: the rules below that apply to it
            ops = self.ops
            eb = ops[b.id]
            if eb[0] == NEG:
                return self._sub(a, eb[1])
            ea = ops[a.id]
            if ea[0] == NEG:
                return self._sub(b, ea[1])
            if ea[0] == SUB and _same(ea[2], b):  # (x - b) + b = x
                return ea[1]
            if eb[0] == SUB and _same(eb[2], a):  # a + (x - a) = x
                return eb[1]
            return self._make2(ADD, a, b)
        if type(a) in _EXACT and a == 0:
            return b
        if type(b) in _EXACT and b == 0:
            return a
        ops = self.ops
        b_node = b.__class__ is Node
        if b_node and ops[b.id][0] == NEG:
            return self._sub(a, ops[b.id][1])
        a_node = a.__class__ is Node
        if a_node and ops[a.id][0] == NEG:
            return self._sub(b, ops[a.id][1])
        if not b_node and b < 0:
            return self._sub(a, normalize_const(-b))
        if not a_node and a < 0:
            return self._sub(b, normalize_const(-a))
        return self._make2(ADD, a, b)

    def _sub(self, a, b):
        if a.__class__ is Node and b.__class__ is Node:  # the commonest difference: the rules below that apply
            if a.id == b.id:
                return 0
            ops = self.ops
            eb = ops[b.id]
            if eb[0] == NEG:
                return self._add(a, eb[1])
            ea = ops[a.id]
            if ea[0] == NEG:  # -x - b = -(x + b)
                return self._neg(self._add(ea[1], b))
            # a term and its opposite cancel: (x + b) - b = x, (b - y) - b = -y, a - (a + y) = -y, a - (a - y) = y
            if ea[0] == ADD and (_same(ea[1], b) or _same(ea[2], b)):
                return ea[2] if _same(ea[1], b) else ea[1]
            if ea[0] == SUB and _same(ea[1], b):
                return self._neg(ea[2])
            if eb[0] == ADD and (_same(eb[1], a) or _same(eb[2], a)):
                return self._neg(eb[2] if _same(eb[1], a) else eb[1])
            if eb[0] == SUB and _same(eb[1], a):
                return eb[2]
            return self._make2(SUB, a, b)
        if type(b) in _EXACT and b == 0:
            return a
        if type(a) in _EXACT and a == 0:
            return self._neg(b)
        ops = self.ops
        a_node, b_node = a.__class__ is Node, b.__class__ is Node
        if a_node and b_node and a.id == b.id:
            return 0
        if b_node and ops[b.id][0] == NEG:
            return self._add(a, ops[b.id][1])
        if a_node and ops[a.id][0] == NEG:  # -x - b = -(x + b)
            return self._neg(self._add(ops[a.id][1], b))
        if not b_node and b < 0:
            return self._add(a, normalize_const(-b))
        return self._make2(SUB, a, b)

    def _mul(self, a, b):
        if a.__class__ is Node and b.__class__ is Node:  # the commonest product, the rules below written out for it
            ops = self.ops
            ai, bi = a.id, b.id
            ea, eb = ops[ai], ops[bi]
            if ea[0] == NEG:
                if eb[0] == NEG:
                    return self._mul(ea[1], eb[1])
                return self._neg(self._mul(ea[1], b))
            if eb[0] == NEG:
                return self._neg(self._mul(a, eb[1]))
            signatures, coefficients = self._signatures, self._coefficients
            fa, fb = signatures.get(ai), signatures.get(bi)
            if fa is None:  # (a node without a signature has no coefficient either)
                if fb is None:
                    factors = (ai, bi) if ai < bi else (bi, ai)
                    node = self._products.get(factors)
                    if node is None:
                        node = self._make2(MUL, a, b)
                        if node.id not in signatures:
                            signatures[node.id] = factors
                        self._products.setdefault(factors, node)
                    return node
                ca, fa = 1, (ai,)
                cb = coefficients.get(bi, 1)
            else:
                ca = coefficients.get(ai, 1)
                if fb is None:
                    cb, fb = 1, (bi,)
                else:
                    cb = coefficients.get(bi, 1)
            coefficient = normalize_const(ca * cb)
            factors = tuple(sorted(fa + fb))
            return self._product(a, b, coefficient, factors)
        ta, tb = type(a), type(b)
        if (ta in _EXACT and a == 0) or (tb in _EXACT and b == 0):
            return 0
        if ta in _EXACT and a == 1:
            return b
        if tb in _EXACT and b == 1:
            return a
        if ta is int and a == -1:
            return self._neg(b)
        if tb is int and b == -1:
            return self._neg(a)
        ops = self.ops
        a_node, b_node = ta is Node, tb is Node
        ea = ops[a.id] if a_node else None
        eb = ops[b.id] if b_node else None
        na = ea[1] if a_node and ea[0] == NEG else None
        nb = eb[1] if b_node and eb[0] == NEG else None
        if na is not None and nb is not None:
            return self._mul(na, nb)
        if na is not None:
            return self._neg(self._mul(na, b))
        if nb is not None:
            return self._neg(self._mul(a, nb))
        if not a_node and a < 0:
            return self._neg(self._mul(normalize_const(-a), b))
        if not b_node and b < 0:
            return self._neg(self._mul(a, normalize_const(-b)))
        # c1 * (c2 * x) -> (c1*c2) * x
        if not a_node and b_node:
            if eb[0] == MUL and eb[1].__class__ is not Node:
                return self._mul(normalize_const(a * eb[1]), eb[2])
        if not b_node and a_node:
            if ea[0] == MUL and ea[1].__class__ is not Node:
                return self._mul(normalize_const(b * ea[1]), ea[2])
        signatures, coefficients = self._signatures, self._coefficients
        if a_node:
            ca, fa = coefficients.get(a.id, 1), signatures.get(a.id) or (a.id,)
        else:
            ca, fa = a, ()
        if b_node:
            cb, fb = coefficients.get(b.id, 1), signatures.get(b.id) or (b.id,)
        else:
            cb, fb = b, ()
        coefficient = normalize_const(ca * cb)
        factors = fa + fb
        if len(factors) > 1:
            factors = tuple(sorted(factors))
        return self._product(a, b, coefficient, factors)

    def _product(self, a, b, coefficient, factors):
        """The node of a * b, whose signature is its factor ids (sorted) and coefficient: the one made before with
        that signature, else a new MUL node recorded under it."""
        # the key: the factor ids and the coefficient (by repr, so 1/2 and 0.5 stay apart); a tuple of ids alone
        # when the coefficient is the int 1 (never equal to a (str, tuple) pair)
        key = factors if coefficient.__class__ is int and coefficient == 1 else (repr(coefficient), factors)
        node = self._products.get(key)
        if node is None:
            node = self._make2(MUL, a, b)
            signatures, coefficients = self._signatures, self._coefficients
            if node.id not in signatures:
                signatures[node.id] = factors
                if key is not factors:
                    coefficients[node.id] = coefficient
            self._products.setdefault(key, node)
        return node

    def _factors(self, x):
        """(coefficient, factor ids) of a scalar seen as a product."""
        if not isinstance(x, Node):
            return x, ()
        sig = self._signatures.get(x.id)
        return (self._coefficients.get(x.id, 1), sig) if sig is not None else (1, (x.id,))

    def _product_signature(self, a, b):
        ca, fa = self._factors(a)
        cb, fb = self._factors(b)
        return normalize_const(ca * cb), tuple(sorted(fa + fb))

    def _div(self, a, b):
        if is_zero(a):
            return 0
        if is_one(b):
            return a
        if is_zero(b):
            raise ZeroDivisionError("structural division by zero")
        if type(b) is int and b == -1:
            return self._neg(a)
        na, nb = self._neg_arg(a), self._neg_arg(b)
        if na is not None and nb is not None:
            return self._div(na, nb)
        if na is not None:
            return self._neg(self._div(na, b))
        if nb is not None:
            return self._neg(self._div(a, nb))
        return self._make2(DIV, a, b)

    # inspection -----------------------------------------------------------------------------------
    def operands(self, ident: int) -> tuple:
        entry = self.ops[ident]
        return () if entry[0] == INPUT else entry[1:]

    def reachable(self, outputs) -> list[int]:
        """Ids of the nodes the outputs depend on, in topological (creation) order."""
        return sorted(self.reach(outputs, set()))

    def reach(self, outputs, seen: set) -> list[int]:
        """The ids the outputs depend on that ``seen`` does not hold yet (in no order), added to ``seen``: walking
        a program's outputs a few at a time visits each node once (:func:`~aggsym.mechanics.bound.scratch_operations`
        stops as soon as a count passes its budget)."""
        ops = self.ops
        new = []
        stack = [o.id for o in outputs if isinstance(o, Node)]
        while stack:
            i = stack.pop()
            if i in seen:
                continue
            seen.add(i)
            new.append(i)
            entry = ops[i]
            if entry[0] != INPUT:
                for a in entry[1:]:
                    if a.__class__ is Node and a.id not in seen:
                        stack.append(a.id)
        return new

    def interpret(self, outputs, leaf, apply, constant=lambda x: x, given=None):
        """The one interpreter of a program: the values of ``outputs`` with ``leaf(kind, index)`` for the inputs,
        ``apply(opcode, *operand values)`` for every other node and ``constant(x)`` for constant operands, in
        creation (topological) order, iteratively.  ``given``: {node id: value} for nodes taken as they are, what
        they depend on not walked (a body cut out of the program at its captured values, :mod:`.columns`)."""
        val: dict[int, object] = dict(given or {})

        def get(x):
            return val[x.id] if isinstance(x, Node) else constant(x)

        for i in sorted(self.reach(outputs, set(val))):
            entry = self.ops[i]
            if entry[0] == INPUT:
                val[i] = leaf(entry[1], entry[2])
            else:
                val[i] = apply(entry[0], *(get(a) for a in entry[1:]))
        return [get(o) for o in outputs]

    def evaluate(self, outputs, values: dict, lib=math):
        """Evaluate outputs numerically; ``values[(kind, index)]`` gives the inputs (floats or arrays), ``lib`` the
        functions (``math`` or ``numpy``)."""
        if lib is math:
            function = lambda f: FUNCTIONS[f].value  # noqa: E731
        else:
            function = lambda f: FUNCTIONS[f].numpy  # noqa: E731
        return self.interpret(outputs, lambda kind, i: values[(kind, i)],
                              lambda code, *x: arithmetic(code, x, function))


def arithmetic(code, x, function):
    """One operation on values: arithmetic by Python's operators, functions looked up by ``function(name)``."""
    if code == ADD:
        return x[0] + x[1]
    if code == SUB:
        return x[0] - x[1]
    if code == MUL:
        return x[0] * x[1]
    if code == DIV:
        return x[0] / x[1]
    if code == NEG:
        return -x[0]
    return function(code)(*x)


def to_sympy(program, outputs, symbols: dict):
    """SymPy expressions of program outputs; ``symbols[(kind, i)]`` names the inputs."""
    import sympy as sp

    functions = {name: f.sympy for name, f in FUNCTIONS.items()}

    def constant(x):
        if isinstance(x, Fraction):
            return sp.Rational(x.numerator, x.denominator)
        return sp.Integer(x) if type(x) is int else sp.Float(x)

    return program.interpret(outputs, lambda kind, i: symbols[(kind, i)],
                             lambda code, *x: arithmetic(code, x, functions.__getitem__), constant)


def expanded_terms(program, outputs) -> int:
    """An upper bound on the number of terms of the fully expanded outputs: sums add the counts of their operands,
    products (and quotients) multiply them; functions and inputs count one.  Deterministic and linear in the
    program (the double pendulum gives 12, Tokad's three-link arm 76, a general 3-D 4-link arm 4346)."""
    def apply(code, *x):
        if code in (ADD, SUB):
            return x[0] + x[1]
        if code in (MUL, DIV):
            return x[0] * x[1]
        return x[0] if code == NEG else 1

    return max(program.interpret(outputs, lambda kind, i: 1, apply, lambda x: 1), default=0)


@dataclass
class StraightLine:
    """Assignments ``temps`` (node ids in order) and per-output lists of nodes or constants."""

    program: Program
    temps: list
    outputs: list  # list (per output argument) of flat lists of scalars
    inputs: list  # (kind, index) used, sorted
    steps: list  # ("temp", node id) and ("out", output index, entry index), in emission order


def straight_line(program, outputs) -> StraightLine:
    """Which nodes get a name (the CSE of the emitted code): every node used twice or more (common
    subexpressions, already shared by value numbering), every function call (sin/cos of each angle, named
    once), and every node whose inlined expression would be deeper than :data:`INLINE_DEPTH` (so a
    200,000-term sum prints as a chain of named partial sums, and no printer recursion is ever deep); the rest
    is inlined into its single use.  ``outputs`` is a list of flat lists of scalars.

    Steps follow creation order (the recursions' own, which keeps a body's work together), each output stored as
    soon as its value exists so that it does not stay live to the end."""
    flat = [x for out in outputs for x in out]
    ops = program.ops
    # one walk: the reachable ids, and the uses of every node (once per operand of each reachable node, once per
    # output entry)
    uses: dict = {}
    get = uses.get
    stack = []
    for x in flat:
        if x.__class__ is Node:
            j = x.id
            uses[j] = get(j, 0) + 1
            stack.append(j)
    seen = set()
    add = seen.add
    inputs = []
    while stack:
        i = stack.pop()
        if i in seen:
            continue
        add(i)
        entry = ops[i]
        if entry[0] == INPUT:
            inputs.append(entry[1:])
            continue
        for a in entry[1:]:
            if a.__class__ is Node:
                j = a.id
                uses[j] = get(j, 0) + 1
                if j not in seen:
                    stack.append(j)
    ids = sorted(seen)
    named = set()
    depth: dict[int, int] = {}  # depth of the expression a node inlines (0: a name)
    for i in ids:
        entry = ops[i]
        code = entry[0]
        if code == INPUT or code in FUNCTIONS or uses[i] >= 2:
            if code != INPUT:
                named.add(i)
            depth[i] = 0
            continue
        d = 0
        for a in entry[1:]:
            if a.__class__ is Node:
                da = depth[a.id]
                if da > d:
                    d = da
        d += 1
        if d > INLINE_DEPTH:
            named.add(i)
            d = 0
        depth[i] = d
    at: dict = {}
    for o, out in enumerate(outputs):
        for k, x in enumerate(out):
            at.setdefault(x.id if x.__class__ is Node else -1, []).append(("out", o, k))
    steps = list(at.get(-1, []))
    temps = []
    for i in ids:
        if i in named:
            temps.append(i)
            steps.append(("temp", i))
        if i in at:
            steps.extend(at[i])
    return StraightLine(program, temps, outputs, sorted(inputs), steps)
