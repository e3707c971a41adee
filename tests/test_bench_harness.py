"""The benchmark's code paths (benchmarks/), quickly: the chain generator, the per-process measurement, the C
timing harness on a tiny model, KanesMethod on a short chain, the Pinocchio build flags, the report writer.
No timing is asserted: timings are the benchmark's business (make bench)."""
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks import report  # noqa: E402
from benchmarks.generation import kane  # noqa: E402
from benchmarks.generation.measured import generate_measured  # noqa: E402
from benchmarks.harness import chain  # noqa: E402
from benchmarks.harness.measure import run_measured  # noqa: E402
from benchmarks.runtime import pinocchio_cpp as runtime  # noqa: E402

import aggsym  # noqa: E402
from aggsym.codegen.check import check_generated  # noqa: E402
from aggsym.codegen.generate import generate, write  # noqa: E402
from aggsym.contract import select_routines  # noqa: E402
from robot_builder import chain as robot_chain, root, segment  # noqa: E402


def test_chain_models_are_valid_and_prefixes_of_each_other(tmp_path):
    m3, m4 = chain.chain_model(3, tmp_path), chain.chain_model(4, tmp_path)
    assert (m3.nq, m4.nq) == (3, 4)
    assert [c.code for c in m4.coordinates] == ["theta6", "theta5", "theta4", "theta6"]
    assert chain.chain_yaml(4).split("bodies:")[1].startswith(chain.chain_yaml(3).split("bodies:")[1])
    for body in m4.bodies[1:]:
        assert all(float(x) != 0 for x in body.pair.translation)
    for body in m4.bodies:
        J = np.array(body.inertial.inertia, dtype=float)
        assert np.all(J != 0) and np.allclose(J, J.T)
        moments = np.linalg.eigvalsh(J)
        assert moments.min() > 0 and 2 * moments.max() < moments.sum()  # triangle inequality
    twin = aggsym.NumericTwin(m4)
    assert np.linalg.eigvalsh(twin.inertia(np.array([0.3, -1.0, 2.0, 0.5]))).min() > 0


def test_input_chains_are_the_benchmark_arm_listed_from_the_tip(tmp_path):
    """The inputs section's chains (benchmarks/generation/inputs.py): the 3-D arm of benchmarks/harness/chain.py, its
    bodies (YAML) and joints (URDF) listed from the tip, load as the same model as the arm listed from the root; the
    section's rows carry the targets (no timing asserted)."""
    import dataclasses

    from benchmarks.generation import inputs

    def bodies(model):  # (where: the body's place in its file, which differs)
        return [dataclasses.replace(b, where="") for b in model.bodies]

    forward = aggsym.load(chain.write_chain(7, tmp_path))
    reversed_yaml = aggsym.load(inputs.yaml_chain(7, tmp_path / "reversed.yaml"))
    assert bodies(reversed_yaml) == bodies(forward) and reversed_yaml.gravity == forward.gravity
    forward_urdf = aggsym.load(chain.write_chain_urdf(7, tmp_path))
    reversed_urdf = aggsym.load(inputs.urdf_chain(7, tmp_path / "reversed.urdf"))
    assert bodies(reversed_urdf) == bodies(forward_urdf) and len(reversed_urdf.bodies) == 8  # the root link "world"
    rows = inputs.section(tmp_path / "inputs", n=5)["rows"]
    assert [(r["file"], r["links"], r["bodies"], r["target_seconds"]) for r in rows] == \
        [("YAML chain", 5, 5, 1.0), ("URDF chain", 5, 6, 2.0)]
    targets = {what: ok for what, _, ok in report.targets({"inputs": {"rows": rows}})}
    assert "parse a 5-link YAML chain (3-D, full inertias; aggsym.load in process) ≤ 1 s" in targets


@pytest.mark.compiler
def test_chain_generated_c_matches_the_numeric_twin(tmp_path):
    model = chain.chain_model(3, tmp_path)
    gen = generate(model, targets="c,numpy,manifest")
    results = check_generated(model, gen.files, trials=3, seed=1, workdir=tmp_path)
    assert {r.role for r in results} >= {"inertia", "nonlinear_effects", "inverse_dynamics", "forward_dynamics"}
    for r in results:
        assert r.c_error <= 1e-12 and r.py_error <= 1e-12, r


@pytest.mark.compiler
def test_timing_harness_runs_on_a_tiny_model(tmp_path):
    """chain3 generated as the runtime section does (the routines on request too: every pair of runtime.PAIRS is
    timed), chain2 with the default routines alone (the five pairs and the frame Jacobians; the derivatives' and
    the regressor's entries are NULL)."""
    model = select_routines(chain.chain_model(3, tmp_path), runtime.ROUTINES.split(","))
    write(generate(model, targets="c,numpy,manifest"), tmp_path / "chain3")
    write(generate(chain.chain_model(2, tmp_path), targets="c,numpy,manifest"), tmp_path / "chain2")
    free = tmp_path / "free.urdf"  # one revolute joint on Pinocchio's free-flyer: q has 8 entries, qd 7
    free.write_text(robot_chain("free", root("a", mass=2, inertia=(1, 2, 3)),
                                segment("j", "b", xyz="0.1 0 0", axis="0 0 1", limit=(-1, 1, 1, 1), mass=1,
                                        inertia=(1, 1, 1))))
    write(generate(aggsym.load(free, floating_base="quaternion"), targets="c,numpy,manifest"), tmp_path / "free")
    manifest = json.loads((tmp_path / "chain3" / "chain3.json").read_text())
    assert set(runtime.EXTRA_ROLES) <= set(manifest["functions"])
    source = runtime.bench_models_source([manifest])
    assert "BENCH_REGRESSOR(chain3)" in source and "chain3_frames[]" in source
    free_manifest = json.loads((tmp_path / "free" / "free.json").read_text())
    assert '"free", 8, 7, 1,' in runtime.bench_models_source([free_manifest])  # nq, nv, free_flyer
    exe = runtime.build_generated_only(tmp_path / "build", {"chain3": tmp_path / "chain3",
                                                            "chain2": tmp_path / "chain2", "free": tmp_path / "free"},
                                       log=lambda m: None)
    data = runtime.run_generated_only(exe, tmp_path / "out.json", seconds=0.01, states=20)
    robots = {r["name"]: r for r in data["robots"]}
    assert robots["chain3"]["nq"] == 3 and robots["chain2"]["nq"] == 2
    assert (robots["free"]["nq"], robots["free"]["nv"]) == (8, 7)
    assert [p["role"] for p in robots["chain3"]["pairs"]] == [role for role, _, _ in runtime.PAIRS]
    assert [p["role"] for p in robots["chain2"]["pairs"]] == [*runtime.DEFAULT_ROLES, "frame_jacobians"]
    for robot in robots.values():
        for p in robot["pairs"]:
            assert math.isfinite(p["generated_ns"]) and p["generated_ns"] > 0 and p["batches"] >= 15


MEASURE_FROM_A_SMALL_PARENT = """
import json, sys
from benchmarks.harness.measure import run_measured
big = run_measured([sys.executable, "-c", "b = bytearray(300 * 2**20); b[::4096] = b'x' * len(b[::4096])"])
small = run_measured([sys.executable, "-c", "pass"])
print(json.dumps([big.ok, small.ok, big.maxrss_kib, small.maxrss_kib]))
"""


def test_measured_process_has_its_own_peak_memory_and_a_timeout(tmp_path):
    """Peak memory per run, from a parent as small as benchmarks.run when it measures: a child's ru_maxrss starts
    at its parent's resident set at the fork (Linux carries it through exec), so it is measured here from a fresh
    interpreter and not from this test process, which has grown by the tests before it."""
    out = subprocess.run([sys.executable, "-c", MEASURE_FROM_A_SMALL_PARENT], cwd=ROOT, check=True,
                         capture_output=True, text=True).stdout
    big_ok, small_ok, big, small = json.loads(out)
    assert big_ok and small_ok
    assert big > 300 * 1024 > small
    slow = run_measured([sys.executable, "-c", "import time; time.sleep(30)"], timeout=0.5)
    assert slow.timed_out and not slow.ok and slow.wall_seconds < 10


def test_generate_measured_reads_stages_and_manifest(tmp_path):
    r = generate_measured("planar_2link", ROOT / "models" / "planar_2link.yaml", tmp_path / "out")
    assert r["ok"], r.get("stderr")
    assert set(r["stages"]) == {"recursions", "printing", "templates", "latex"}
    assert r["nq"] == 2 and "inertia" in r["ops"] and r["maxrss_kib"] > 0 and r["cpu_seconds"] > 0
    assert "planar_2link.tex" in r["files"]


def test_kane_peer_agrees_with_aggsym_on_a_short_chain(tmp_path):
    model = chain.chain_model(2, tmp_path)
    replacements, reduced, q, u, timings = kane.kane_cse(model)
    assert timings["seconds"] >= timings["cse_seconds"] >= 0
    assert kane.check_against_twin(model, replacements, reduced, q, u) < 1e-12
    ops = kane.count_cse_ops(replacements, reduced, q, u)
    assert ops["mul"] > 0 and ops["add"] > 0


@pytest.mark.compiler
def test_pinocchio_build_flags_come_from_the_wheel():
    prefix = runtime.cmeel_prefix()
    flags = runtime.compile_definitions(prefix)
    assert "-DPINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION" in flags
    assert "-DPINOCCHIO_WITH_URDFDOM" in flags
    assert not any("$<" in f for f in flags)
    assert "-march=native" not in runtime.cxx_flags(prefix)
    assert "-lpinocchio_default" in runtime.link_flags(prefix)


def _fake_results():
    ops6 = {"inertia": {"mul": 100, "add": 90, "div": 0, "call": 10},
            "bias": {"mul": 150, "add": 120, "div": 0, "call": 10},
            "gravity": {"mul": 50, "add": 40, "div": 0, "call": 10},
            "nonlinear_effects": {"mul": 160, "add": 130, "div": 0, "call": 10},
            "inverse_dynamics": {"mul": 200, "add": 150, "div": 0, "call": 10},
            "forward_dynamics": {"mul": 500, "add": 400, "div": 6, "call": 10},
            "transvective_factors": {"mul": 300, "add": 250, "div": 5, "call": 10}}

    def run(label, kind, n, wall, rss=100_000):
        return {"label": label, "kind": kind, "n": n, "nq": n, "name": label, "ok": True, "wall_seconds": wall,
                "cpu_seconds": wall * 0.9, "maxrss_kib": rss, "c_bytes": 2048, "internal_seconds": wall - 1,
                "stages": {"recursions": 0.2, "printing": 0.3, "templates": 0.1, "latex": 0.1}, "ops": ops6,
                "outdir": "x", "timed_out": False}

    from benchmarks.generation.opcounts import section

    gen = {"runs": [run("manipulator6", "seed", 6, 2.0), run("ur5", "robot", 6, 2.0), run("panda", "robot", 7, 6.0),
                    run("hyq", "robot", 12, 3.0), run("talos", "robot", 32, 30.0, rss=3 * 2 ** 20),
                    run("chain4", "chain", 4, 2.0), run("chain12", "chain", 12, 8.0)]}
    pairs = [{"role": role, "pinocchio": pin, "batches": 21, "generated_ns": 100.0, "pinocchio_ns": 300.0,
              "ratio": 1 / 3, "generated_ns_q10": 90.0, "generated_ns_q90": 110.0, "pinocchio_ns_q10": 290.0,
              "pinocchio_ns_q90": 310.0, "cpu_ratio": 0.34, "relative_error": 1e-15} for role, pin, _ in runtime.PAIRS]
    robots = [{"name": r, "nq": 6, "pinocchio_nq": 6, "pairs": [dict(p) for p in pairs]} for r in report.ROBOTS]
    robots[1]["pairs"][3]["ratio"] = 0.8  # panda forward dynamics misses the target
    robots += [{"name": r + report.FREE_FLYER_SUFFIX, "nq": 13, "nv": 12, "free_flyer": True, "pinocchio_nq": 13,
                "pairs": [dict(p) for p in pairs[:5]]} for r in report.ROBOTS]  # the free-flyers meet theirs
    kruns = [{"n": 4, "finished": True, "seconds": 20.0, "kane_seconds": 15.0, "cse_seconds": 5.0,
              "maxrss_kib": 90_000, "ops": {"mul": 1000, "add": 800, "div": 0, "call": 6},
              "relative_error_vs_aggsym": 1e-15, "timeout": 600},
             {"n": 12, "finished": False, "timeout": 600, "process_maxrss_kib": 500_000},
             {"n": 16, "skipped": "n = 12 already exceeded 600 s"}]
    return {"environment": {"date": "2026-01-01 00:00 UTC", "cpu": "Fake CPU", "logical_cpus": 2,
                            "memory_gib": 24.0, "os": "FakeOS", "versions": {"aggsym": "0.1.0"},
                            "compilers": {"cc": "cc 1", "c++": "c++ 1"}, "load_average_start": [0.1, 0.1, 0.1]},
            "config": {"AGGSYM_BENCH_KANE_TIMEOUT": 600},
            "generation": gen, "opcounts": section(gen["runs"]),
            "kane": {"timeout": 600, "runs": kruns, "timed_out_at": 12},
            "runtime": {"states": 1000, "seconds_per_pair": 0.5, "robots": robots}}


def test_report_writer_produces_the_sections_and_the_targets(tmp_path):
    results = _fake_results()
    path = report.write_report(results, tmp_path)
    text = path.read_text()
    for heading in ("## Machine and software", "## 1. Generation time and peak memory",
                    "### KanesMethod on the same chains", "## 2. Operation counts", "### manipulator6 (n = 6)",
                    "## 3. Runtime", "### panda (n = 6", "## 4. Targets"):
        assert heading in text, heading
    assert text.rstrip().splitlines()[-1].startswith("- ")  # ends with the targets' notes
    assert text.index("## 4. Targets") > text.index("## 3. Runtime")
    assert "first at **n = 12**" in text and "upper triangle only" in text and "Fake CPU" in text
    for png in ("generation.png", "runtime.png", "opcounts.png"):
        assert (tmp_path / png).stat().st_size > 1000
    rows = {what: ok for what, _, ok in report.targets(results)}
    assert rows["full generation panda ≤ 5 s"] is False
    assert rows["full generation chain12 ≤ 10 s"] is True
    assert rows["full generation talos ≤ 60 s, peak memory ≤ 2 GiB"] is False  # 3 GiB
    assert [ok for what, ok in rows.items() if "forward dynamics" in what] == [False, True]  # fixed, free-flyer
    assert [ok for what, ok in rows.items() if "A(q) ↔ crba" in what] == [True, True]
    for role in runtime.EXTRA_ROLES:  # the pairs beyond the five have their rows, with the same 0.5 target
        assert [ok for what, ok in rows.items() if report.RUNTIME_LABELS[role] in what] == [True], role
    assert any(what.startswith("op count inertia at n = 6") and ok for what, ok in rows.items())
    summary = report.summary_text(results)
    assert "NO" in summary and "yes" in summary
    assert any("panda forward_dynamics" in n for n in report.diagnose(results))
    json.dumps(results)  # the raw results are JSON
