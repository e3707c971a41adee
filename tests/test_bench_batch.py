"""The batched benchmark's pure parts (benchmarks/batch/: orchestrator.py, report.py, peers.py, engines.py),
without its venv and without timing: the agreement check that withholds a disagreeing entry's times, the
tables, plot and targets rendered from fake results, the merge with an earlier run, the URDF the peers read,
the SDF with fixed joints merged, and the tangent-space retraction against Pinocchio's integrate."""
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks.batch import engines as batch_engines, orchestrator as batch, peers as batch_peers  # noqa: E402
from benchmarks.batch import report as batch_report  # noqa: E402

SIZES = [1, 64, 4096]


def test_agreement_accepts_equal_outputs_and_refuses_a_disagreeing_peer():
    rng = np.random.default_rng(1)
    ref = rng.normal(size=(16, 7)) * 10
    same = {"B1": ref[:1] * (1 + 1e-15), "B64": ref.copy()}
    good = batch.agreement(same, ref, 1e-8)
    assert good["ok"] and good["max_relative"] <= 1e-14
    off = ref.copy()
    off[3, 2] += 1e-6 * np.abs(ref).max()  # one entry of one state, 1e-6 of the largest reference entry
    bad = batch.agreement({"B1": ref[:1], "B64": off}, ref, 1e-8)
    assert not bad["ok"] and bad["where"] == "B64" and bad["max_relative"] == pytest.approx(1e-6, rel=1e-6)
    assert not batch.agreement({"B64": ref[:, :6]}, ref, 1e-8)["ok"]  # wrong shape
    nan = ref.copy()
    nan[0, 0] = np.nan
    assert not batch.agreement({"B64": nan}, ref, 1e-8)["ok"]


def _row(entry, robot, routine, us, ok=True, first=1.0):
    label = batch_peers.ENTRIES[entry][0]
    row = {"entry": entry, "label": label, "robot": robot, "routine": routine, "maxrss_mib": 300.0,
           "agreement": {"ok": ok, "max_relative": 1e-15 if ok else 0.3, "where": "B64"}}
    if ok:  # per state, falling with B
        row["sizes"] = {str(b): {"min_us": us / (1 + k), "median_us": 1.2 * us / (1 + k),
                                 "first_call_seconds": first} for k, b in enumerate(SIZES)}
    if entry in ("aggsym_jax", "aggsym_torch") and routine != "jac":
        row["against_numpy"] = 2e-16
    return row


def fake_results():
    speed = {"aggsym_jax": 1.0, "aggsym_torch": 2.0, "numpy": 8.0, "adam_jax": 20.0, "adam_torch": 50.0,
             "jaxsim": 15.0, "mjx": 12.0, "pinocchio": 3.0}
    rows = []
    for robot in ("panda", "talos"):
        for routine in batch_peers.ROUTINES:
            for entry, us in speed.items():
                rows.append(_row(entry, robot, routine, us * (5 if robot == "talos" else 1),
                                 ok=not (entry == "jaxsim" and robot == "talos")))  # one refused peer
    rows.append({"entry": "mjx", "label": "MuJoCo MJX", "robot": "talos", "routine": "jac",
                 "error": "Traceback ...\nRuntimeError: no memory"})
    return {"host": "a test CPU", "environment": {"date": "today"},
            "config": {"sizes": SIZES, "routines": list(batch_peers.ROUTINES), "repeats": 5, "sample_seconds": 0.2,
                       "rounds": 1, "check": 16, "tolerance": 1e-8},
            "robots": {"panda": {"nq": 7, "nv": 7, "floating": False}, "talos": {"nq": 39, "nv": 38, "floating": True}},
            "entries": {k: {"label": v[0], "framework": v[1], "jacobian": v[3]} for k, v in batch_peers.ENTRIES.items()},
            "rows": rows}


def test_report_tables_plot_and_targets_from_fake_results(tmp_path):
    data = fake_results()
    text = batch_report.markdown(data)
    assert "REFUSED: differs from Pinocchio by 0.3" in text
    assert "failed: RuntimeError: no memory" in text
    assert "| aggsym JAX | 1 / 1.2 | 0.5 / 0.6 | 0.333 / 0.4 | 1.00 | 300 |" in text
    # the refused peer has no times in its table
    talos_fd = batch_report.timing_rows(data, "talos", "fd")
    assert ["jaxsim", "—", "—", "—", "—", "—"] in talos_fd
    assert batch_report.plot(data, tmp_path / "batch.png")
    assert (tmp_path / "batch.png").read_bytes()[:4] == b"\x89PNG"
    rows = {what: (measured, ok) for what, measured, ok in batch_report.targets(data)}
    assert rows["panda forward dynamics, B = 4096: aggsym JAX ≥ 10× faster than adam JAX"] == \
        ("20.00× (0.333 vs 6.67 µs)", True)
    assert rows["panda forward dynamics, B = 4096: aggsym JAX ≥ 10× faster than MuJoCo MJX"][1] is True
    assert rows["panda A(q), B = 4096: aggsym JAX faster per state than the Pinocchio loop"][1] is True
    assert rows["talos forward dynamics, B = 4096: aggsym JAX ≥ 10× faster than jaxsim"][1] is None  # refused
    assert rows["panda JIT of forward dynamics ≤ 2 s (first call at B = 4096)"] == ("1.00 s", True)
    assert rows["panda forward dynamics: PyTorch time per state falls as B grows"][1] is True
    assert rows["panda forward dynamics, B = 4096: aggsym PyTorch ≥ 10× faster than adam PyTorch"][1] is True
    assert rows["panda Jacobian, B = 4096: aggsym JAX ≥ 10× faster than adam JAX jacrev"][1] is True
    assert rows["panda Jacobian: aggsym JAX equals Pinocchio's derivatives to 1e-08"][1] is True
    # a slower aggsym misses its targets
    for r in data["rows"]:
        if r["entry"] == "aggsym_jax" and r.get("sizes"):
            for s in r["sizes"].values():
                s["min_us"] *= 10
    rows = {what: ok for what, _, ok in batch_report.targets(data)}
    assert rows["panda forward dynamics, B = 4096: aggsym JAX ≥ 10× faster than adam JAX"] is False
    assert rows["panda forward dynamics, B = 4096: aggsym JAX faster per state than the Pinocchio loop"] is False
    summary = batch_report.targets_text(data)
    assert summary.startswith("Targets of issue 32 (batched benchmark): ") and "NO" in summary
    assert "REFUSED" in batch_report.agreement_text(data)


def test_a_section_that_did_not_run_says_why():
    assert "did not complete: no venv" in batch_report.markdown({"error": "no venv"})
    assert "- kept from two runs\n" in batch_report.markdown(dict(fake_results(), notes=["kept from two runs"]))
    assert not batch_report.plot({"error": "no venv"}, Path("unused.png"))


def test_a_run_on_one_robot_keeps_the_other_robots_rows():
    earlier = fake_results()
    now = fake_results()
    now["robots"].pop("talos")
    now["rows"] = [r for r in now["rows"] if r["robot"] == "panda"]
    now["config"]["sizes"] = [1, 8]
    merged = batch.keep_earlier(now, earlier)
    assert merged["kept_from_earlier_run"] == ["talos"]
    assert merged["config"]["sizes"] == [1, 8, 64, 4096]
    assert all(r.get("earlier_run") for r in merged["rows"] if r["robot"] == "talos")
    assert "aggsym JAX (an earlier run)" in batch_report.markdown(merged)
    assert "another host" not in batch_report.markdown(merged)


def test_rows_kept_from_a_run_on_another_host_say_so():
    """A kept row carries its run's host; the report names the other host, so that a ratio between the runs is
    not taken for one machine's."""
    earlier = dict(fake_results(), host="Host A")
    now = dict(fake_results(), host="Host B")
    now["rows"] = [r for r in now["rows"] if r["robot"] == "panda"]
    merged = batch.keep_earlier(now, earlier)
    assert {r["host"] for r in merged["rows"] if r.get("earlier_run")} == {"Host A"}
    text = batch_report.markdown(merged)
    assert "measured on another host (Host A)" in text
    again = batch.keep_earlier(dict(fake_results(), host="Host C", rows=[]), merged)  # (a kept row keeps its host)
    assert {r["host"] for r in again["rows"]} == {"Host A", "Host B"}


@pytest.mark.parametrize("key", ["entry", "routine"])
def test_a_run_of_some_entries_or_routines_keeps_the_others_rows_of_the_same_robot(key):
    earlier = fake_results()
    now = fake_results()
    ran = now["rows"][0][key]
    now["rows"] = [r for r in now["rows"] if r[key] == ran]
    merged = batch.keep_earlier(now, earlier)
    assert len(merged["rows"]) == len(earlier["rows"])
    assert {r[key] for r in merged["rows"]} == {r[key] for r in earlier["rows"]}
    assert all(r.get("earlier_run") is None for r in merged["rows"] if r[key] == ran)
    assert all(r.get("earlier_run") for r in merged["rows"] if r[key] != ran)


URDF = """<robot name="r">
 <link name="base"><inertial><mass value="2"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
  <visual><geometry><mesh filename="package://x/base.stl"/></geometry></visual></link>
 <link name="arm"><inertial><origin xyz="0.1 0 0" rpy="0 0 0"/><mass value="1"/>
  <inertia ixx="0.1" iyy="0.2" izz="0.3" ixy="0" ixz="0" iyz="0"/></inertial>
  <collision><geometry><box size="1 1 1"/></geometry></collision></link>
 <link name="tool"><inertial><origin xyz="0 0 0.2" rpy="0 0 0"/><mass value="0.5"/>
  <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <link name="finger"><inertial><mass value="0.1"/>
  <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
 <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
  <origin xyz="0 0 0.5"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
 <joint name="weld" type="fixed"><parent link="arm"/><child link="tool"/><origin xyz="0.3 0 0" rpy="0 0 1.5707963267948966"/></joint>
 <joint name="f1" type="prismatic"><parent link="tool"/><child link="finger"/><axis xyz="1 0 0"/>
  <limit lower="0" upper="0.04" effort="1" velocity="1"/><mimic joint="j1"/></joint>
 <transmission name="t"/>
</robot>"""


def test_the_urdf_every_peer_reads(tmp_path):
    src = tmp_path / "r.urdf"
    src.write_text(URDF)
    out = ET.parse(batch.strip_urdf(src, tmp_path / "s.urdf", weld=("f1",))).getroot()
    assert [c.tag for c in out] == ["link"] * 4 + ["joint"] * 3
    assert not out.findall(".//visual") and not out.findall(".//collision") and not out.findall(".//mimic")
    assert [j.get("type") for j in out.findall("joint")] == ["revolute", "fixed", "fixed"]
    assert all(i.find("origin") is not None for i in out.findall(".//inertial"))


def test_sdf_merges_fixed_joints_into_their_parents(tmp_path):
    src = tmp_path / "r.urdf"
    src.write_text(URDF)
    urdf = batch.strip_urdf(src, tmp_path / "s.urdf", weld=("f1",))
    sdf = ET.parse(batch_engines.write_sdf(urdf, tmp_path / "r.sdf", fixed_base=True)).getroot()
    links = {lk.get("name"): lk for lk in sdf.iter("link")}
    assert list(links) == ["base", "arm"]  # the root first; tool and finger welded to arm
    arm = links["arm"].find("inertial")
    assert float(arm.find("mass").text) == pytest.approx(1.6)
    # arm's centre at x = 0.1, tool's at (0.3, 0, 0.2), the finger at the tool's origin (0.3, 0, 0)
    com = np.array([float(x) for x in arm.find("pose").text.split()[:3]])
    assert com == pytest.approx((1 * np.array([0.1, 0, 0]) + 0.5 * np.array([0.3, 0, 0.2])
                                 + 0.1 * np.array([0.3, 0, 0])) / 1.6)
    assert [float(x) for x in links["arm"].find("pose").text.split()[:3]] == pytest.approx([0, 0, 0.5])
    joints = {j.get("name"): (j.get("type"), j.find("parent").text, j.find("child").text) for j in sdf.iter("joint")}
    assert joints == {"j1": ("revolute", "base", "arm"), "world_to_base": ("fixed", "world", "base")}


@pytest.mark.pinocchio
def test_retraction_is_pinocchios_integrate_to_first_order(tmp_path):
    """The map every framework-differentiated peer is differentiated through agrees with Pinocchio's integrate up
    to O(eps^2), so its derivative at delta = 0 is the tangent-space one of computeABADerivatives."""
    import pinocchio as pin

    src = tmp_path / "r.urdf"
    src.write_text(URDF)
    model = pin.buildModelFromUrdf(str(batch.strip_urdf(src, tmp_path / "s.urdf")), pin.JointModelFreeFlyer())
    rng = np.random.default_rng(3)
    q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    direction = rng.normal(size=model.nv)
    errors = []
    for eps in (1e-3, 1e-4):
        ours = batch_peers.retract(np, q, eps * direction, floating=True)
        theirs = pin.integrate(model, q, eps * direction)
        errors.append(np.abs(ours - theirs).max())
    assert errors[0] < 1e-5 and errors[1] < errors[0] / 50  # second order: a tenth of eps, a hundredth of the error
    assert np.allclose(batch_peers.retract(np, q, np.zeros(model.nv), True), q, atol=0, rtol=1e-15)


def test_one_batch_size_shows_no_trend():
    """A robot timed at one batch size only: 'time per state falls as B grows' is not measured, not met."""
    data = fake_results()
    for r in data["rows"]:
        if r["robot"] == "talos" and r.get("sizes"):
            r["sizes"] = {"64": r["sizes"]["64"]}
    rows = {what: (measured, ok) for what, measured, ok in batch_report.targets(data)}
    measured, ok = rows["talos forward dynamics: PyTorch time per state falls as B grows"]
    assert ok is None and measured.endswith("(B = 64 only)")
    assert rows["panda forward dynamics: PyTorch time per state falls as B grows"][1] is True


def test_each_framework_judged_at_its_own_largest_batch():
    """The humanoid's PyTorch entries timed up to B = 4096, its JAX ones and peers to 64 only: the JAX targets are
    judged at 64 (not 'not measured' at 4096), the PyTorch ones at 4096."""
    data = fake_results()
    for r in data["rows"]:
        if r["robot"] == "talos" and r.get("sizes") and r["entry"] not in ("aggsym_torch", "adam_torch"):
            r["sizes"] = {b: s for b, s in r["sizes"].items() if int(b) <= 64}
    rows = {what: (measured, ok) for what, measured, ok in batch_report.targets(data)}
    assert rows["talos forward dynamics, B = 64: aggsym JAX ≥ 10× faster than adam JAX"][1] is True
    assert rows["talos Jacobian, B = 64: aggsym JAX ≥ 10× faster than adam JAX jacrev"][1] is True
    assert rows["talos JIT of forward dynamics ≤ 15 s (first call at B = 64)"][1] is True
    assert rows["talos forward dynamics, B = 4096: aggsym PyTorch ≥ 10× faster than adam PyTorch"] == \
        ("25.00× (3.33 vs 83.3 µs)", True)
    assert not any(what.startswith("talos") and "B = 4096: aggsym JAX" in what for what in rows)


def test_the_jacrev_entries_are_judged_on_the_jacobian_alone():
    """aggsym JAX's jacrev entries (the Jacobian only) get the Jacobian's two targets where they were measured,
    and no row where they were not."""
    data = fake_results()
    rows = {what for what, _, _ in batch_report.targets(data)}
    assert not any("jacrev, the project's jax" in what or "aggsym JAX jacrev ≥" in what for what in rows)
    data["rows"].append(_row("aggsym_jax_project_rev", "talos", "jac", 2.0))
    rows = {what: ok for what, _, ok in batch_report.targets(data)}
    assert rows["talos Jacobian, B = 4096: aggsym JAX jacrev, the project's jax ≥ 10× faster than adam JAX jacrev"]
    assert rows["talos Jacobian, B = 4096: aggsym JAX jacrev, the project's jax no slower than Pinocchio's "
                "computeABADerivatives"] is True
    assert not any(what.startswith("talos forward dynamics") and "jacrev" in what for what in rows)
    assert "aggsym_jax_project_rev" in batch_peers.PROJECT_ENTRIES


def test_the_kernels_targets_from_fake_results():
    """Issue 51's rows: the kernel entries against Pinocchio's batched calls, the one-state C loop, the traced
    module and adam; met and missed as the times say; the build from the robot's generation."""
    data = fake_results()
    speed = {"aggsym_jax_kernels": 0.1, "aggsym_jax_kernels_rev": 0.1, "aggsym_jax_kernels_all": 0.06,
             "aggsym_torch_kernels": 0.12, "aggsym_torch_kernels_func": 0.2, "c_loop": 0.3,
             "pinocchio_parallel": 3.0, "pinocchio_parallel_all": 1.6}
    for robot in ("panda", "talos"):
        for routine in batch_peers.ROUTINES:
            for entry, us in speed.items():
                if routine in batch_peers.ENTRIES[entry][2]:
                    data["rows"].append(_row(entry, robot, routine, us))
    data["robots"]["talos"]["generation"] = {"kernels_build": {"ok": True, "seconds": 99.0, "maxrss_mib": 545.0}}
    rows = {what: (measured, ok) for what, measured, ok in batch_report.kernel_targets(data)}
    assert rows["talos forward dynamics, B = 4096: aggsym JAX kernels ≥ 10× faster per state than Pinocchio "
                "abaInParallel, one thread"][1] is True
    assert rows["panda forward dynamics, B = 4096: aggsym JAX kernels ≤ 0.4× the one-state C loop per state"][1] is True
    assert rows["talos: the kernels' build (double, float, the XLA binding) ≤ 120 s"] == ("99 s, peak 545 MiB", True)
    assert rows["panda: the kernels' build (double, float, the XLA binding) ≤ 120 s"][1] is None  # not measured
    assert rows["talos Jacobian of forward dynamics w.r.t. (q, v), B = 4096: aggsym PyTorch kernels, torch.func "
                "within 1.5× of JAX kernels"][1] is False
    assert "Targets of issue 51 (the batch kernels)" in batch_report.markdown(data)
    for r in data["rows"]:
        if r["entry"] == "aggsym_jax_kernels":
            for s in r["sizes"].values():
                s["min_us"] *= 100
    rows = {what: ok for what, _, ok in batch_report.kernel_targets(data)}
    assert rows["talos forward dynamics, B = 4096: aggsym JAX kernels ≥ 10× faster per state than Pinocchio "
                "abaInParallel, one thread"] is False
