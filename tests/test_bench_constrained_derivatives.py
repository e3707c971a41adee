"""The constrained-derivatives section of the benchmark (benchmarks/runtime/constrained_derivatives.py), quickly: its
timers compile against a generated model with constraints (harness/contact_bench.h), its target is met only where the
ratios and the agreement say so, and its table says which.  No timing is asserted (make bench times)."""
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks.harness.build import C_STD, HARNESS  # noqa: E402
from benchmarks.runtime import constrained_derivatives as cd  # noqa: E402


def fake_results(ratios: dict, agrees: bool = True) -> dict:
    """The harness' JSON for solo12 and Talos with the given value + derivatives ratios (derivatives alone: 1.1 x)."""
    models = []
    for label, ratio in ratios.items():
        pairs = [{"role": role, "pinocchio": "P", "generated_ns": 100.0 * r, "pinocchio_ns": 100.0,
                  "generated_ns_q10": 90.0 * r, "generated_ns_q90": 110.0 * r, "pinocchio_ns_q10": 90.0,
                  "pinocchio_ns_q90": 110.0, "ratio": r, "batches": 51}
                 for role in cd.PAIRS for r in [ratio * (1.1 if "+" not in role else 1.0)]]
        models.append({"label": label, "name": cd.name_of(label), "nv": 18, "nc": 12, "pairs": pairs,
                       "relative_errors": {"dqdd_dq": 1e-13, "dqd_plus_dq": 1e-13 if agrees else 0.2},
                       "agrees": agrees,
                       "ops": {r: {"mul": 1, "add": 1, "div": 0} for r in cd.ROUTINES.split(",")}})
    return {"models": models, "states": 200, "calls_per_batch": 10, "tolerance": cd.TOLERANCE}


def test_the_target_is_met_only_below_a_third_on_both_robots_with_agreement():
    assert [met for _, _, met in cd.targets(fake_results({"solo12": 0.3, "talos": 0.25}))] == [True, True]
    assert [met for _, _, met in cd.targets(fake_results({"solo12": 0.3, "talos": 0.4}))] == [False, False]
    assert [met for _, _, met in cd.targets(fake_results({"solo12": 0.3, "talos": 0.2}, agrees=False))] == \
        [False, False]
    assert [met for _, _, met in cd.targets(fake_results({"solo12": 0.3}))] == [None, None]
    assert [met for _, _, met in cd.targets({"error": "boom"})] == [None, None]


def test_the_table_marks_the_target_rows():
    text = cd.markdown(fake_results({"solo12": 0.5, "talos": 0.2}))
    solo = [line for line in text.splitlines() if line.startswith("| solo12") and "constraintDynamics +" in line]
    talos = [line for line in text.splitlines() if line.startswith("| talos") and "constraintDynamics +" in line]
    assert "**no**" in solo[0] and "| yes |" in talos[0]
    assert "2.00×" in solo[0] and "5.00×" in talos[0]


@pytest.mark.compiler
def test_the_timers_compile_against_a_generated_model_with_constraints(tmp_path):
    import aggsym
    from aggsym.codegen.generate import generate, write
    from aggsym.contract import select_routines

    model = select_routines(aggsym.load(ROOT / "models" / "four_bar.yaml"), cd.ROUTINES.split(","))
    write(generate(model, targets="c,numpy,manifest"), tmp_path)
    import json

    manifest = json.loads((tmp_path / "four_bar.json").read_text())
    source = tmp_path / "bench_contacts.c"
    source.write_text(cd.timers_source({"four_bar": manifest}))
    assert "BENCH_CONTACT_MODEL(four_bar, 3, 3, 2, 0," in source.read_text()
    proc = subprocess.run(["cc", *C_STD, "-Werror", f"-I{HARNESS}", f"-I{tmp_path}", "-c", str(source), "-o",
                           str(tmp_path / "bench_contacts.o")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
