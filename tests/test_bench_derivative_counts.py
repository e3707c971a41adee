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
