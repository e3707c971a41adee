"""benchmarks.generation.derivative_counts: the routine's count is the smaller form's, and the table says which."""
from __future__ import annotations

from benchmarks.generation import derivative_counts


def test_the_emitted_derivatives_take_the_smaller_form():
    results = derivative_counts.run(robots=("ur5", "so100"))
    for row in results["robots"]:
        assert row["inverse_dynamics_derivatives"] == min(row["dual"], row["spatial"])
        assert row["forward_dynamics_derivatives"] > row["forward_dynamics"] > 0
    assert [r["form"] for r in results["robots"]] == ["dual", "spatial"]
    table = derivative_counts.markdown(results)
    assert "| ur5 | 6 |" in table and "| so100 |" in table


def test_the_report_sets_each_derivative_routine_against_its_dynamics():
    from benchmarks import report_derivatives

    def pair(role, ours, theirs):
        return {"role": role, "generated_ns": ours, "pinocchio_ns": theirs, "ratio": ours / theirs}

    ops = {"inverse_dynamics": {"mul": 50, "add": 50, "div": 0},
           "inverse_dynamics_derivatives": {"mul": 150, "add": 150, "div": 0},
           "forward_dynamics": {"mul": 100, "add": 90, "div": 10},
           "forward_dynamics_derivatives": {"mul": 500, "add": 400, "div": 100}}
    robot = {"name": "arm", "nq": 6, "ops": ops,
             "pairs": [pair("inverse_dynamics", 50, 500), pair("inverse_dynamics_derivatives", 100, 2000),
                       pair("forward_dynamics", 90, 1000), pair("forward_dynamics_derivatives", 400, 2500)]}
    results = {"runtime": {"robots": [robot, {"name": "no_derivatives", "nq": 3, "pairs": robot["pairs"][:1]}]}}
    rows = {what: (measured, met) for what, measured, met in report_derivatives.targets(results)}
    assert rows["operations ∂ID ≤ 4× ID (arm)"] == ("3.0×", True)
    assert rows["operations ∂FD ≤ 4× FD (arm)"] == ("5.0×", False)
    assert rows["runtime ∂τ/∂(q, q̇) ≤ 0.15× computeRNEADerivatives (arm)"] == ("0.050 (100 ns)", True)
    assert rows["runtime ∂q̈/∂(q, q̇) ≤ 0.15× computeABADerivatives (arm)"] == ("0.160 (400 ns)", False)
    assert len(rows) == 4  # the robot without derivative routines has no row
    text = "\n".join(report_derivatives.section(results))
    assert "| arm | 6 | 100 | 300 | 3.0 | 4.0 | 0.050 | 200 | 1000 | 5.0 | 2.5 | 0.160 |" in text
