"""The peer for section 1: sympy.physics.mechanics KanesMethod on the same chains, with CSE.

``python -m benchmarks.generation.kane MODEL.yaml OUT.json`` (one run per process, so its peak memory is its own):

1. builds the bodies, frames and gravity loads from the aggsym model (the same numbers, as SymPy Floats),
2. ``KanesMethod.kanes_equations`` gives the mass matrix M(q) and the forcing f(q, u) (M u' = f),
3. ``sympy.cse([M, f])`` names the common subexpressions,

and writes ``{"kane_seconds", "cse_seconds", "seconds", "maxrss_kib"}`` as soon as step 3 is done (the timed
part).  Then, untimed, it counts the operations of the CSE'd result with aggsym's own C operation counter and
checks it against aggsym's numeric twin on a random state (M = A, f = -(b + g)), and adds those to the file.
"""
from __future__ import annotations

import json
import resource
import sys
import time
from pathlib import Path

import numpy as np
import sympy as sp
from sympy.physics import mechanics as me

UNIT = {1: "x", 2: "y", 3: "z"}


def _vector(frame, values):
    return sum((v * getattr(frame, UNIT[j + 1]) for j, v in enumerate(values) if v != 0), me.Vector(0))


def kane_system(model):
    """KanesMethod objects for an aggsym model of revolute/prismatic pairs: (KM, bodies, loads, q, u)."""
    values = dict(zip(model.parameter_symbols, model.parameter_values))

    def num(x):  # parameters at their defaults; integers stay exact (zeros vanish), the rest become Floats
        x = sp.sympify(x).subs(values)
        return x if x.is_Integer else sp.Float(float(x))

    n = model.nq
    q = me.dynamicsymbols(f"q0:{n}")
    u = me.dynamicsymbols(f"u0:{n}")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    frames, points, bodies, loads = {"world": N}, {"world": O}, [], []
    g = _vector(N, [num(x) for x in model.gravity])
    i = 0
    for b in model.bodies:  # the textbook construction: orient_axis, locatenew and v2pt_theory
        F, P = frames[b.parent], points[b.parent]
        J = P.locatenew(f"{b.name}_p", _vector(F, [num(x) for x in b.pair.translation]))
        J.v2pt_theory(P, N, F)
        for step, (axis, angle) in enumerate(b.pair.rotation):
            G = me.ReferenceFrame(f"{b.name}_c{step}")
            G.orient_axis(F, getattr(F, UNIT[axis]), num(angle))
            F = G
        for c in b.pair.coordinates:  # translations first (codes are ordered)
            if c.axis < 3:
                K = J.locatenew(f"{b.name}_{c.code}", q[i] * getattr(F, UNIT[c.axis + 1]))
                K.set_vel(N, J.vel(N) + u[i] * getattr(F, UNIT[c.axis + 1]) + (F.ang_vel_in(N) ^ K.pos_from(J)))
                J = K
            else:
                G = me.ReferenceFrame(f"{b.name}_{c.code}")
                G.orient_axis(F, getattr(F, UNIT[c.axis - 2]), q[i])
                G.set_ang_vel(F, u[i] * getattr(F, UNIT[c.axis - 2]))
                F = G
            i += 1
        frames[b.name], points[b.name] = F, J
        if b.inertial is None:
            continue
        m = num(b.inertial.mass)
        com = J.locatenew(f"{b.name}_com", _vector(F, [num(x) for x in b.inertial.com]))
        com.v2pt_theory(J, N, F)
        Ic = [[num(x) for x in row] for row in b.inertial.inertia]
        I = me.inertia(F, Ic[0][0], Ic[1][1], Ic[2][2], Ic[0][1], Ic[1][2], Ic[0][2])
        bodies.append(me.RigidBody(b.name, com, F, m, (I, com)))
        loads.append((com, m * g))
    KM = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=[qi.diff() - ui for qi, ui in zip(q, u)])
    return KM, bodies, loads, q, u


def kane_cse(model):
    """Timed: (M, f) by KanesMethod, then sympy.cse([M, f]).  Returns (replacements, reduced, q, u, timings)."""
    t0 = time.perf_counter()
    KM, bodies, loads, q, u = kane_system(model)
    KM.kanes_equations(bodies, loads)
    M, f = KM.mass_matrix, KM.forcing
    t1 = time.perf_counter()
    replacements, reduced = sp.cse([M, f])
    t2 = time.perf_counter()
    return replacements, reduced, q, u, {"kane_seconds": t1 - t0, "cse_seconds": t2 - t1, "seconds": t2 - t0}


def _plain(q, u):
    """Plain symbols for q_i(t), u_i(t) (for printing C)."""
    return {**{qi: sp.Symbol(f"q{i}") for i, qi in enumerate(q)}, **{ui: sp.Symbol(f"u{i}") for i, ui in enumerate(u)}}


def count_cse_ops(replacements, reduced, q, u) -> dict:
    """Operations of the CSE'd (M, f) printed as C by SymPy's C99 printer, counted by aggsym's counter
    (integer powers written out as multiplications, as a compiler would)."""
    from sympy.printing.c import C99CodePrinter

    from aggsym.codegen.printing import count_ops

    class Printer(C99CodePrinter):
        def _print_Pow(self, expr):
            base, e = expr.as_base_exp()
            if e.is_Integer and 1 < abs(int(e)) <= 4:
                prod = "*".join([f"({self._print(base)})"] * abs(int(e)))
                return prod if e > 0 else f"1.0/({prod})"
            return super()._print_Pow(expr)

    plain = _plain(q, u)
    printer = Printer()
    lines = [f"{s} = {printer.doprint(e.xreplace(plain))};" for s, e in replacements]
    for mat in reduced:
        lines += [f"o = {printer.doprint(e.xreplace(plain))};" for e in mat]
    return count_ops("\n".join(lines))


def evaluate_cse(replacements, reduced, q, u, qv, uv):
    """The CSE'd (M, f) at one state, evaluated replacement by replacement in floating point."""
    values = {**{qi: sp.Float(x) for qi, x in zip(q, qv)}, **{ui: sp.Float(x) for ui, x in zip(u, uv)}}
    for s, e in replacements:
        values[s] = sp.Float(sp.N(e.xreplace(values)))
    M = np.array(sp.N(reduced[0].xreplace(values)), dtype=float)
    f = np.array(sp.N(reduced[1].xreplace(values)), dtype=float).ravel()
    return M, f


def check_against_twin(model, replacements, reduced, q, u, seed=0) -> float:
    """Largest relative difference of (M, f) from aggsym's numeric twin (A, -(b + g)) on one random state."""
    import aggsym

    rng = np.random.default_rng(seed)
    qv, uv = rng.uniform(-np.pi, np.pi, model.nq), rng.normal(size=model.nq)
    M, f = evaluate_cse(replacements, reduced, q, u, qv, uv)
    twin = aggsym.NumericTwin(model)
    A = twin.inertia(qv)
    rhs = -(twin.bias(qv, uv) + twin.gravity(qv))
    return max(float(np.abs(M - A).max() / np.abs(A).max()), float(np.abs(f - rhs).max() / np.abs(rhs).max()))


def main(argv=None) -> int:
    import aggsym

    args = sys.argv[1:] if argv is None else argv
    model_path, out = Path(args[0]), Path(args[1])
    model = aggsym.load(model_path)
    sys.setrecursionlimit(100000)
    replacements, reduced, q, u, result = kane_cse(model)
    result.update({"model": model.name, "nq": model.nq, "replacements": len(replacements),
                   "maxrss_kib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss})
    out.write_text(json.dumps(result, indent=1))  # the timed part is recorded
    t0 = time.perf_counter()
    result["ops"] = count_cse_ops(replacements, reduced, q, u)
    result["count_seconds"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    result["relative_error_vs_aggsym"] = check_against_twin(model, replacements, reduced, q, u)
    result["check_seconds"] = time.perf_counter() - t0
    out.write_text(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
