"""The MJCF reader against MuJoCo on two whole corpora: every model of dm_control's suite and of gymnasium's MuJoCo
environments (the XML their wheels ship) that has a joint; and on this project's probes (``benchmarks/mjcf/probes``:
a gravity-compensated arm and free body, ...).

For each: load it with aggsym (``aggsym.load``, MuJoCo's compiler underneath), and compare A, d = b + g - passive
and qacc of the model as read and of its internal models (the frames the generated routines are built in) with
MuJoCo's ``mj_fullM``, ``qfrc_bias - qfrc_passive`` and ``mj_forward`` at random states and forces
(:func:`benchmarks.mjcf.mujoco_reference.compare`: contacts, limits, equalities, frictionloss and actuators disabled,
fluid forces zero, the model's own armature, damping, springs, tendon springs and dampers and gravity kept).  A
model with equalities that are constraints (joint-space rows, connect, weld) is also compared as a hard constrained
system: constrained_forward_dynamics against the dense KKT solve from MuJoCo's M and equality rows
(:func:`benchmarks.mjcf.mujoco_reference.compare_constrained`, within ``KKT_TOLERANCE``; MuJoCo's own equalities are
soft).  Its poses (every body's and site's frame, every body's centre of mass and inertia, the internal frames) are
compared with MuJoCo's kinematics (:func:`benchmarks.mjcf.mujoco_poses.compare_poses`, within ``POSE_TOLERANCE``).  A
model that does not load is listed with aggsym's message (what is not supported yet).  Writes
``benchmarks/mjcf_corpus.json`` and prints the Markdown table of ``docs/mjcf.md``.

    python -m benchmarks.mjcf.corpus [--samples N]
"""
from __future__ import annotations

import argparse
import warnings
from pathlib import Path

from ..harness.paths import result_path, write_json

TOLERANCE = 1e-9
POSE_TOLERANCE = 1e-12  # benchmarks.mjcf.mujoco_poses: positions relative to the model's size, rotations absolute
KKT_TOLERANCE = 1e-8
OUT = result_path("mjcf_corpus")


PROBES = Path(__file__).parent / "probes"  # aggsym's own MJCF files, one feature each (gravity compensation, ...)


def corpora() -> dict:
    """{corpus name: sorted XML files}: dm_control's suite and gymnasium's MuJoCo assets, from the installed wheels,
    dm_control's fruit fly (its wings in the fluid), and this project's probes (:data:`PROBES`)."""
    import dm_control
    import gymnasium

    suite = Path(dm_control.__file__).parent / "suite"
    gym = Path(gymnasium.__file__).parent / "envs" / "mujoco" / "assets"
    fly = Path(dm_control.__file__).parent / "locomotion" / "walkers" / "assets" / "fruitfly_v2" / "fruitfly.xml"
    return {"dm_control suite": sorted(suite.glob("*.xml")), "gymnasium mujoco": sorted(gym.glob("*.xml")),
            "dm_control walkers": [fly], "aggsym probes": sorted(PROBES.glob("*.xml"))}


def has_joint(path) -> bool:
    import mujoco

    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda text: None)
    try:
        return mujoco.MjModel.from_xml_path(str(path)).njnt > 0
    finally:
        mujoco.set_mju_user_warning(previous)


def reason(message: str) -> str:
    """The short reason of a refusal, from the reader's message."""
    for key, short in (("ball joint", "ball joint (not yet)"), ("spatial tendon", "spatial tendon (not representable)"),
                       ("tendon with armature", "tendon armature (not yet)"), ("flex", "flex"),
                       ("gravity compensation", "gravcomp")):
        if key in message:
            return short
    return message


def kind_of(became: str) -> str:
    """What an equality became, in short: a coupling, a joint-space row, a point or weld constraint, or nothing."""
    if became.startswith("coupling"):
        return "coupling"
    if "joint-space row" in became:
        return "joint-space row"
    if became.startswith("constraint"):
        return became.split("(", 1)[1].split(":", 1)[0] + " constraint"
    return "left out"


def run(samples: int) -> list:
    from aggsym.errors import ModelError
    from aggsym.model import load

    from aggsym.mechanics.passive import has_passive

    from .mujoco_poses import compare_poses
    from .mujoco_reference import compare, compare_constrained

    rows = []
    for corpus, files in corpora().items():
        for path in files:
            row = {"corpus": corpus, "model": path.name}
            if not has_joint(path):
                row["status"] = "no joint (not counted)"
                rows.append(row)
                continue
            with warnings.catch_warnings(record=True) as said:
                warnings.simplefilter("always")
                try:
                    model = load(path)
                except ModelError as exc:
                    row.update(status="refused", reason=reason(exc.message), message=exc.message)
                    rows.append(row)
                    continue
            worst = compare(path, model=model, samples=samples)
            kkt = compare_constrained(path, model=model, samples=samples) if model.constraints else {}
            poses = max(compare_poses(path, model=model, samples=samples).values())
            agrees = (max(worst.values()) <= TOLERANCE and all(v <= KKT_TOLERANCE for v in kkt.values())
                      and poses <= POSE_TOLERANCE)
            row.update(nq=model.nq, nv=model.nv, free=len(model.meta["mjcf"]["free_joints"]),
                       worst={k: float(v) for k, v in worst.items()}, poses=float(poses),
                       constrained={k: float(v) for k, v in kkt.items()},
                       equalities=[kind_of(e["became"]) for e in model.meta["mjcf"].get("equalities", [])],
                       tendons=len(model.tendons), passive=has_passive(model),
                       status="agrees" if agrees else "DIFFERS",
                       notes="fluid forces left out (warned)" if any("fluid" in str(w.message) for w in said)
                       else "")
            rows.append(row)
    return rows


def table(rows) -> str:
    counted = [r for r in rows if not r["status"].startswith("no joint")]
    agree = [r for r in counted if r["status"] == "agrees"]
    refused = [r for r in counted if r["status"] == "refused"]
    differ = [r for r in counted if r["status"] == "DIFFERS"]
    lines = [f"{len(counted)} models with a joint: {len(agree)} load and agree with MuJoCo within "
             f"{TOLERANCE:g} (relative; hard equalities against the dense KKT solve within {KKT_TOLERANCE:g}; "
             f"poses within {POSE_TOLERANCE:g}); "
             f"{len(refused)} do not load (reason below); {len(differ)} load and differ.", "",
             "| corpus | model | nq | nv | A | b + g - passive | passive | qacc | constrained qacc (KKT) | poses | status |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in counted:
        if r["status"] == "refused":
            lines.append(f"| {r['corpus']} | {r['model']} | | | | | | | | | refused: {r['reason']} |")
        else:
            w = r["worst"]
            kkt = f"{r['constrained']['qdd']:.1e}" if r.get("constrained") else ""
            passive = f"{w['passive']:.1e}" if r.get("passive") else "none"
            notes = [r["notes"]] if r["notes"] else []
            made = r.get("equalities", [])
            if made:
                notes.append("equalities: " + ", ".join(f"{made.count(k)} {k}{'s' if made.count(k) > 1 else ''}"
                                                         for k in sorted(set(made))))
            if r.get("tendons"):
                notes.append(f"{r['tendons']} tendon spring(s)/damper(s)")
            note = f" ({'; '.join(notes)})" if notes else ""
            lines.append(f"| {r['corpus']} | {r['model']} | {r['nq']} | {r['nv']} | {w['A']:.1e} | {w['d']:.1e} | "
                         f"{passive} | {w['qdd']:.1e} | {kkt} | {r['poses']:.1e} | {r['status']}{note} |")
    skipped = [r["model"] for r in rows if r["status"].startswith("no joint")]
    if skipped:
        lines += ["", f"Without a joint (not counted): {', '.join(skipped)}."]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=5, help="random states per model (default 5)")
    args = parser.parse_args(argv)
    rows = run(args.samples)
    write_json(OUT, {"tolerance": TOLERANCE, "samples": args.samples, "rows": rows})
    print(table(rows))
    return 0 if all(r["status"] != "DIFFERS" for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
