"""Operation counts of the derivative routines against the dynamics they differentiate (issue 52).

    python -m benchmarks.generation.derivative_counts [OUT.json]

For each robot (example-robot-data's files; ``+ff``: with Pinocchio's free-flyer, ``--floating-base quaternion``),
in the internal frames the routines are built in (:func:`aggsym.codegen.generate.internal_model`), the arithmetic
operations (mul + add + div; negations and inputs free) of inverse_dynamics and forward_dynamics, of dtau/d(q, qd)
in each of its two forms (the dual-number sweep, :mod:`aggsym.mechanics.derivatives`, and the composites of the
tree, :mod:`aggsym.mechanics.spatial_derivatives`), the form the program takes, and of
forward_dynamics_derivatives as emitted; the ratios are routine / its dynamics.  Counted on fresh straight-line
programs (:func:`aggsym.mechanics.bound.program_operations`), nothing compiled or timed.
"""
from __future__ import annotations

import warnings

ROBOTS = ("ur5", "panda", "xarm7", "so100", "hyq", "talos", "solo12+ff", "talos+ff")


def _model(label):
    import aggsym
    from aggsym.codegen.generate import internal_model
    from aggsym.errors import ModelWarning

    from ..harness.robots import FILES, robots_directory

    name, _, base = label.partition("+")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        model = aggsym.load(robots_directory() / FILES[name], floating_base="quaternion" if base else None)
    return internal_model(model)


def _count(model, build) -> int:
    """Operations of ``build(bound, kin, vectors)``'s flat outputs on a fresh program."""
    from aggsym.core.backend import Symbolic
    from aggsym.mechanics.bound import bind, program_operations
    from aggsym.mechanics.kinematics import TreeKinematics

    backend = Symbolic()
    program = backend.program

    def rows():
        bound = bind(model, backend)
        kin = TreeKinematics(bound, program.vector("q", model.nq))
        x = {k: program.vector(k, model.nv) for k in ("qd", "qdd", "tau")}
        yield [v for out in build(bound, kin, x) for v in out]

    return program_operations(program, rows)


def robot_row(label) -> dict:
    from aggsym.contract.registry import ROUTINES, run
    from aggsym.mechanics import derivatives

    model = _model(label)

    def routine(role):
        def build(bound, kin, x):
            return run(ROUTINES[role], bound, {**x, "q": kin.q}, kin)
        return _count(model, build)

    def form(way):
        def build(bound, kin, x):
            return [[v for row in m for v in row] for m in derivatives.inverse_dynamics_derivatives(
                bound, kin, x["qd"], x["qdd"], by_direction=False, form=way)]
        return _count(model, build)

    row = {"robot": label, "nv": model.nv, "inverse_dynamics": routine("inverse_dynamics"),
           "forward_dynamics": routine("forward_dynamics"), "dual": form("dual"), "spatial": form("spatial"),
           "inverse_dynamics_derivatives": routine("inverse_dynamics_derivatives"),
           "forward_dynamics_derivatives": routine("forward_dynamics_derivatives")}
    row["form"] = "spatial" if row["inverse_dynamics_derivatives"] == row["spatial"] else "dual"
    return row


def run(robots=ROBOTS, progress=None) -> dict:
    rows = []
    for label in robots:
        rows.append(robot_row(label))
        if progress:
            progress(f"{label}: {rows[-1]}")
    return {"robots": rows}


def markdown(results) -> str:
    lines = ["| robot | nv | ID | dID dual | dID spatial | taken | dID / ID | FD | dFD | dFD / FD |",
             "| --- | ---: | ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: |"]
    for r in results["robots"]:
        lines.append(f"| {r['robot']} | {r['nv']} | {r['inverse_dynamics']} | {r['dual']} | {r['spatial']} | "
                     f"{r['form']} | {r['inverse_dynamics_derivatives'] / r['inverse_dynamics']:.1f} | "
                     f"{r['forward_dynamics']} | {r['forward_dynamics_derivatives']} | "
                     f"{r['forward_dynamics_derivatives'] / r['forward_dynamics']:.1f} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    from ..harness.cli import section_main

    section_main(run, markdown)
