"""Rung 3: a peer.  sympy.physics.mechanics (KanesMethod), built here from the model's data, against aggsym on a
3-D tree of five bodies with a branch, on random states."""
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from sympy.physics import mechanics as me

import aggsym

DATA = Path(__file__).parent / "data"
UNIT = {1: "x", 2: "y", 3: "z"}


def kane(model):
    """Mass matrix and forcing of KanesMethod for a model (any tree of pairs), as functions of (q, u)."""
    values = dict(zip(model.parameter_symbols, model.parameter_values))
    num = lambda x: sp.nsimplify(sp.sympify(x).subs(values), rational=False)
    n = model.nq
    q = me.dynamicsymbols(f"q0:{n}")
    u = me.dynamicsymbols(f"u0:{n}")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    frames, points, bodies, loads = {"world": N}, {"world": O}, [], []
    g = sum((num(gi) * getattr(N, UNIT[i + 1]) for i, gi in enumerate(model.gravity)), me.Vector(0))
    i = 0
    for b in model.bodies:
        F, P = frames[b.parent], points[b.parent]
        trans = [num(x) for x in b.pair.translation]
        P = P.locatenew(f"{b.name}_p", sum((t * getattr(F, UNIT[j + 1]) for j, t in enumerate(trans)), me.Vector(0)))
        for step, (axis, angle) in enumerate(b.pair.rotation):
            G = me.ReferenceFrame(f"{b.name}_c{step}")
            G.orient_axis(F, getattr(F, UNIT[axis]), num(angle))
            F = G
        for c in b.pair.coordinates:  # translations first (codes are ordered)
            if c.axis < 3:
                P = P.locatenew(f"{b.name}_{c.code}", q[i] * getattr(F, UNIT[c.axis + 1]))
            else:
                G = me.ReferenceFrame(f"{b.name}_{c.code}")
                G.orient_axis(F, getattr(F, UNIT[c.axis - 2]), q[i])
                F = G
            i += 1
        frames[b.name], points[b.name] = F, P
        if b.inertial is None:
            continue
        m = num(b.inertial.mass)
        com = P.locatenew(f"{b.name}_com", sum((num(x) * getattr(F, UNIT[j + 1])
                                                for j, x in enumerate(b.inertial.com)), me.Vector(0)))
        com.set_vel(N, com.pos_from(O).dt(N).subs({sp.Derivative(qi, me.dynamicsymbols._t): ui for qi, ui in zip(q, u)}))
        J = [[num(x) for x in row] for row in b.inertial.inertia]
        I = me.inertia(F, J[0][0], J[1][1], J[2][2], J[0][1], J[1][2], J[0][2])
        bodies.append(me.RigidBody(b.name, com, F, m, (I, com)))
        loads.append((com, m * g))
    KM = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=[qi.diff() - ui for qi, ui in zip(q, u)])
    KM.kanes_equations(bodies, loads)
    M = sp.lambdify([q, u], KM.mass_matrix, "numpy")
    f = sp.lambdify([q, u], KM.forcing, "numpy")
    return M, f


@pytest.mark.parametrize("name", ["branching_tree"])
def test_agrees_with_kanes_method(name, rng):
    model = aggsym.load(DATA / f"{name}.yaml")
    assert len(model.bodies) >= 4 and any(
        sum(1 for b in model.bodies if b.parent == p.name) > 1 for p in model.bodies)
    M, forcing = kane(model)
    twin = aggsym.NumericTwin(model)
    for _ in range(5):
        q, u = rng.uniform(-np.pi, np.pi, model.nq), rng.normal(size=model.nq)
        A = twin.inertia(q)
        assert np.allclose(A, np.array(M(q, u), dtype=float), rtol=1e-12, atol=1e-13)
        rhs = -(twin.bias(q, u) + twin.gravity(q))
        assert np.allclose(rhs, np.array(forcing(q, u), dtype=float).ravel(), rtol=1e-11, atol=1e-12)
