"""Which routines a model emits: those left out and why (:func:`omitted_routines`: the regressor where tau = Y pi
does not hold, the routines that need a regular A(q) where it is singular) and the ``--routines`` choice
(:func:`select_routines`)."""
from __future__ import annotations

from .analyses import regressor_problem
from .regularity import regularity


def _zero(x) -> bool:
    return getattr(x, "is_zero", False) is True or x == 0
from .registry import ROUTINES, routines_for


def omitted_routines(model) -> dict:
    """{role: reason} of the routines left out: the regressor where tau = Y pi does not hold
    (:func:`regressor_problem`), and, when A(q) is singular at every configuration at the default parameters
    (:func:`~.regularity.regularity`: a coordinate that moves no mass, e.g. a massless finger joint), forward
    dynamics, A^-1 and the factors, undefined there (A, b, g, inverse dynamics and the joint wrenches stay defined
    and are emitted)."""
    out = {}
    wanted = [r.role for r in routines_for(model)]  # (a list: the order of emission, the same in every run)
    problem = regressor_problem(model)
    if problem:
        out.update({role: f"tau = Y pi does not hold: {problem}" for role in ("regressor", "base_regressor", "friction_regressor", "friction_base_regressor")
                    if role in wanted})
    if not any(ROUTINES[role].regular for role in wanted):
        return out
    armed = [t.name for t in model.tendons if not _zero(t.armature)]
    if armed:  # (aggsym.mechanics.tendon_armature: forward dynamics and A^-1 hold it, not the tree's factors)
        out.update({role: f"the armature of tendon(s) {', '.join(repr(n) for n in armed)} couples coordinates "
                          f"outside the tree's factorization; forward_dynamics and inertia_inverse hold it "
                          f"(Sherman-Morrison), the routines built on the factors do not yet"
                    for role in wanted if ROUTINES[role].regular and role not in ("forward_dynamics",
                                                                                   "inertia_inverse")})
    regular = regularity(model)
    if not regular.singular:
        return out
    zero = regular.zero
    names = ", ".join(f"{model.coordinates[i].name} (joint {model.coordinates[i].joint!r})" for i in zero)
    reason = (f"A(q) is singular at the default parameters: {'coordinate(s) ' + names + ' move(s) no mass' if zero else 'its smallest eigenvalue is zero at every configuration'}; "
              f"--armature VALUE adds a rotor inertia on every coordinate")
    return {**out, **{role: reason for role in wanted if ROUTINES[role].regular}}


def unprefixed(model, name: str) -> str:
    """A routine's name as the contract spells it: ``NAME_role`` (the C symbol, as ``--list-routines`` prints it,
    NAME the model's name) becomes ``role``; any other name is returned as it is."""
    prefix = f"{model.name}_"
    if name not in ROUTINES and name.startswith(prefix) and name[len(prefix):] in ROUTINES:
        return name[len(prefix):]
    return name


def select_routines(model, names):
    """The model emitting the named routines (``--routines``: names of the contract, with or without the model's
    prefix ``NAME_`` of the C symbols, ``default`` for the routines emitted when none are named, ``all`` for every
    routine that applies); an unknown name (with the closest names offered), or one that does not apply to the
    model, is an error that lists the choices."""
    import dataclasses

    from ..errors import AggsymError
    from ..suggest import did_you_mean

    names = [unprefixed(model, name) for name in names]
    chosen = []
    for name in names:
        if name == "all":
            picked = [r.role for r in ROUTINES.values() if r.exists_for(model)]
        elif name == "default":
            picked = [r.role for r in ROUTINES.values() if r.exists_for(model) and not r.on_request]
        elif name not in ROUTINES:
            shown = name if len(name) <= 80 else name[:80] + "..."
            bare = name.removeprefix(f"{model.name}_")  # (a misspelled name may carry the prefix)
            applying = [role for role, r in ROUTINES.items() if r.exists_for(model)]
            hint = did_you_mean(bare, [*applying, "default", "all"]) or did_you_mean(bare, ROUTINES)
            raise AggsymError(f"{model.source}: --routines: no routine named {shown!r}{hint} (the routines are "
                              f"{', '.join(ROUTINES)}; or 'default', 'all')")
        elif not ROUTINES[name].exists_for(model):
            raise AggsymError(f"{model.source}: --routines: {name!r} does not apply to this model (the ones that do: "
                              f"{', '.join(r.role for r in ROUTINES.values() if r.exists_for(model))})")
        else:
            picked = [name]
        chosen.extend(role for role in picked if role not in chosen)
    if not chosen:
        raise AggsymError(f"{model.source}: --routines: no routine named")
    selected = dataclasses.replace(model, routines=tuple(chosen))
    named = [name for name in names if name in ROUTINES]  # named one by one, not through 'all' or 'default'
    if named:
        omitted = omitted_routines(selected)
        for name in named:
            if name in omitted:
                raise AggsymError(f"{model.source}: --routines: {name!r} is left out for this model: {omitted[name]}")
    return selected
