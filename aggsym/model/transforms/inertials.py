"""Runtime inertial parameters of a URDF robot: a link's inertial data, or a payload's, as entries of p.

``aggsym generate robot.urdf --inertial-parameters all|LINK,LINK,...`` makes the named links' inertial data runtime
parameters, and ``--payload LINK`` adds a payload fixed to LINK (massless by default), so that a controller can
change a tool or a load without generating again.  Each gets ten parameters in the regressor's form
(:mod:`aggsym.mechanics.regressor`): ``m``, the first moment ``mcx mcy mcz`` (m times the centre of mass) and the
inertia ``Ixx Ixy Iyy Ixz Iyz Izz`` about the link frame's origin, in link axes, named ``<param>_<link>`` (the link
made an identifier) and ``payload_<param>`` (``--payload A,B``: a payload on each, ``payload_<param>_<link>``); the
links' defaults are their URDF values, the payloads' zero.  They are appended to p in the order named, the payloads
last.

The body a link was merged into keeps its other links as numbers: its Mises matrix (2.3) at the body origin is the
merged one less the link's own part plus the parametrized part, moved from the link frame (R, t: x_body = R x_link
+ t) by ``h = R h_L + m t``, ``Theta_O = R I_L R^T + m(|t|^2 E - t t^T) + 2 (t . R h_L) E - t (R h_L)^T - (R h_L) t^T``
(polynomial in the parameters: a mass set to zero at run time divides nothing).

Each such block of ten is recorded on the model (``Model.inertial_blocks``), and the generated code gets a helper
per block (``NAME_set_payload_<link>``, ``NAME_set_inertial_<link>``: :mod:`aggsym.codegen.inertial_helpers`) that
writes the ten entries from a mass, a centre of mass and an inertia about it.

A link welded to the world (its body reached from the world through joints without coordinates: a fixed base's
root and the links fixed to it) moves with nothing, so its inertial data never enter the equations of motion:
naming it is an error (parameters that would change nothing), and ``all`` leaves such links out with a warning
that lists them.
"""
from __future__ import annotations

import dataclasses
import re
import warnings

import numpy as np
import sympy as sp

from ...errors import AggsymError, ModelWarning
from ...suggest import did_you_mean
from ..types import WORLD, Inertial, InertialBlock, Model, Parameter

NAMES = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
_ENTRIES = ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2))


def _identifier(name: str) -> str:
    s = re.sub(r"[^A-Za-z0-9_]", "_", name)
    return s if s and s[0].isalpha() else f"link_{s}"


def _origin_form(mass, com, J) -> tuple:
    """(m, h, Theta_O) of a part given by its mass, centre of mass and inertia about it (body axes)."""
    c = sp.Matrix(com)
    theta = sp.Matrix(J) + mass * (c.dot(c) * sp.eye(3) - c * c.T)
    return mass, sp.Matrix(mass * c), theta


class _Symbols:
    """The products :func:`moved_mises` and :func:`mises_in_frame` need, on SymPy column matrices."""

    eye = staticmethod(lambda: sp.eye(3))
    dot = staticmethod(lambda a, b: a.dot(b))
    outer = staticmethod(lambda a, b: a * b.T)


class _Numbers:
    """The same on NumPy vectors (double precision: the internal frames of numeric inertias, model.reframe)."""

    eye = staticmethod(lambda: np.eye(3))
    dot = staticmethod(np.dot)
    outer = staticmethod(np.outer)


def _algebra(h):
    return _Numbers if isinstance(h, np.ndarray) else _Symbols


def moved_mises(m, h, theta, C, p) -> tuple:
    """L Theta L^T (2.7) for L = T(p) C(C): a Mises matrix (m, h, Theta_O) given about a frame's origin in its axes
    (a link frame, a child's frame), about the origin of the frame in which the first has axes C and origin p (the
    body's, the parent's).  SymPy column matrices, or NumPy arrays throughout."""
    la = _algebra(h)
    hr = C @ h
    shift = C @ theta @ C.T + (2 * la.dot(p, hr) + m * la.dot(p, p)) * la.eye() - la.outer(hr, p) - la.outer(p, hr) \
        - m * la.outer(p, p)
    return m, hr + m * p, shift


def mises_in_frame(m, h, theta, R, o) -> tuple:
    """The inverse of :func:`moved_mises`: (m, h, Theta_O) about the origin o of a frame with axes R (x = R x' + o),
    in its axes: h' = R^T (h - m o), Theta' = R^T (Theta_O + (m o.o - 2 o.h) E + h o^T + o h^T - m o o^T) R."""
    la = _algebra(h)
    shift = theta + (m * la.dot(o, o) - 2 * la.dot(o, h)) * la.eye() + la.outer(h, o) + la.outer(o, h) \
        - m * la.outer(o, o)
    return m, R.T @ (h - m * o), R.T @ shift @ R


def _values(model: Model, link: str) -> list:
    """The link's own ten parameters at their URDF values (about its frame's origin, link axes)."""
    frame = model.link_table.by_name[link]
    part = frame.part
    if part is None:
        return [0.0] * 10
    R, t = frame.rotation, frame.translation
    R, t = sp.Matrix(R), sp.Matrix(t)
    m, h_link, I_link = mises_in_frame(*_origin_form(*part), R, t)  # from the body origin back to the link frame
    return [float(m)] + [float(h_link[i]) for i in range(3)] + [float(I_link[i, j]) for i, j in _ENTRIES]


def welded_bodies(model: Model) -> set:
    """The names of the bodies welded to the world: every pair from the world to them has no coordinate and no
    prescribed motion (a fixed base's root, and bodies joined to it without a coordinate)."""
    welded = {WORLD}
    out = set()
    for b in model.bodies:  # (parents before children)
        if b.parent in welded and not b.pair.coordinates and not b.pair.prescribed:
            welded.add(b.name)
            out.add(b.name)
    return out


def _welded_refusal(model: Model, link: str, body: str, option: str) -> AggsymError:
    return AggsymError(
        f"{model.source}: {option}: link {link!r} is welded to the world (body {body!r}: no joint with a "
        f"coordinate between it and the world), so its inertial data never enter the equations of motion and "
        f"parameters for it would change nothing; name a link that moves (one beyond the first movable joint), or "
        f"generate with --floating-base")


def with_inertial_parameters(model: Model, links=(), payload=None) -> Model:
    """The model with the named links' inertial data (``links``: names, or ``["all"]`` for every link with an
    ``<inertial>`` that moves) and a payload on ``payload`` (a link's name, or a list of them: a payload on each)
    as runtime parameters (see the module's text); an error for a link welded to the world."""
    payloads = [] if payload is None else [payload] if isinstance(payload, str) else list(payload)
    if len(set(payloads)) != len(payloads):
        raise AggsymError(f"{model.source}: --payload names a link twice")
    table = model.link_table
    if not table.from_file:
        raise AggsymError(f"{model.source}: --inertial-parameters and --payload apply to URDF robots (a YAML model "
                          f"writes its masses and inertias as expressions in its parameters)")
    links = list(links)
    welded = welded_bodies(model)
    if links == ["all"]:
        links = [f.name for f in table.frames if f.part is not None and f.body not in welded]
        left = [f.name for f in table.frames if f.part is not None and f.body in welded]
        if left:
            warnings.warn(ModelWarning(
                f"{model.source}: --inertial-parameters all: the links welded to the world are left out (their "
                f"inertial data never enter the equations of motion): {', '.join(repr(n) for n in left)}"))
        if not links:
            raise AggsymError(f"{model.source}: --inertial-parameters all: no link that moves has an <inertial>")
    frames = {f.name: (f.body, f.rotation, f.translation) for f in table.frames}
    for name, option in [(n, "--inertial-parameters") for n in links] + \
            [(n, "--payload") for n in payloads]:
        if name not in frames:
            shown = name if len(name) <= 80 else name[:80] + "..."
            some = ", ".join(repr(n) for n in list(frames)[:8]) + (", ..." if len(frames) > 8 else "")
            raise AggsymError(f"{model.source}: no link named {shown!r}{did_you_mean(name, frames)} (the robot's "
                              f"links: {some})")
        if frames[name][0] in welded:
            raise _welded_refusal(model, name, frames[name][0], option)
        if frames[name][0] in {body for body, _, _ in model.gravcomp}:
            raise AggsymError(f"{model.source}: {option} {name}: its body {frames[name][0]!r} is gravity-compensated "
                              f"(MuJoCo's gravcomp lifts a fraction of the file's mass); its inertial data cannot "
                              f"be runtime parameters")
    if len(set(links)) != len(links):
        raise AggsymError(f"{model.source}: --inertial-parameters names a link twice")
    taken = {p.name for p in model.parameters}
    parameters = list(model.parameters)
    index = {b.name: k for k, b in enumerate(model.bodies)}
    forms = {}  # body index -> its Mises matrix at the origin, being rewritten

    def form(k):
        if k not in forms:
            inertial = model.bodies[k].inertial
            if inertial is None:
                forms[k] = (sp.Integer(0), sp.zeros(3, 1), sp.zeros(3, 3))
            else:
                m, h, theta = inertial.mises()
                forms[k] = (m, sp.Matrix(h), sp.Matrix(theta))
        return forms[k]

    def add(k, part, sign=1):
        m, h, theta = form(k)
        forms[k] = (m + sign * part[0], h + sign * part[1], theta + sign * part[2])

    def symbols(prefix_of, defaults):
        out = []
        for name, value in zip(NAMES, defaults):
            pname = prefix_of(name)
            if pname in taken:
                raise AggsymError(f"{model.source}: the parameter name {pname!r} is taken twice")
            taken.add(pname)
            parameters.append(Parameter(pname, float(value)))
            out.append(parameters[-1].symbol)
        return out

    def parametrized(link, syms):
        body, R, t = frames[link]
        m, h = syms[0], sp.Matrix(syms[1:4])
        I = sp.zeros(3, 3)
        for (i, j), x in zip(_ENTRIES, syms[4:]):
            I[i, j] = I[j, i] = x
        return index[body], moved_mises(m, h, I, sp.Matrix(R), sp.Matrix(t))

    blocks = list(model.inertial_blocks)
    helpers = {b.helper for b in blocks}

    def record(kind, link, names):
        helper = f"set_{kind if kind == 'payload' else 'inertial'}_{_identifier(link)}"
        if helper in helpers:
            raise AggsymError(f"{model.source}: two links give the helper name {helper!r}")
        helpers.add(helper)
        blocks.append(InertialBlock(kind, link, helper, tuple(names)))

    for link in links:
        k, part = parametrized(link, symbols(lambda n, link=link: f"{n}_{_identifier(link)}", _values(model, link)))
        record("link", link, [f"{n}_{_identifier(link)}" for n in NAMES])
        own = table.by_name[link].part
        if own is not None:
            add(k, _origin_form(*own), -1)
        add(k, part)
    for link in payloads:  # (one payload keeps the names it always had: payload_m, ...)
        name = (lambda n: f"payload_{n}") if len(payloads) == 1 else \
            (lambda n, link=link: f"payload_{n}_{_identifier(link)}")
        k, part = parametrized(link, symbols(name, [0.0] * 10))
        record("payload", link, [name(n) for n in NAMES])
        add(k, part)
    defaults = {p.symbol: p.value for p in parameters}
    bodies = list(model.bodies)
    for k, (m, h, theta) in forms.items():
        m = sp.expand(m)
        h = tuple(sp.expand(x) for x in h)
        theta = tuple(tuple(sp.expand(theta[i, j]) for j in range(3)) for i in range(3))
        m0 = float(m.subs(defaults))
        c0 = tuple(float(x.subs(defaults)) / m0 if m0 else 0.0 for x in h)
        J0 = tuple(tuple(float(theta[i][j].subs(defaults)) - m0 * ((sum(x * x for x in c0) if i == j else 0)
                                                                     - c0[i] * c0[j]) for j in range(3))
                   for i in range(3))
        bodies[k] = dataclasses.replace(bodies[k], inertial=Inertial(sp.Float(m0), c0, J0, origin=(m, h, theta)))
    return dataclasses.replace(model, bodies=tuple(bodies), parameters=tuple(parameters),
                               inertial_blocks=tuple(blocks))


__all__ = ["with_inertial_parameters", "welded_bodies", "NAMES"]
