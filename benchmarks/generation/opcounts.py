"""Section 2: operation counts of the emitted C per routine, beside the book's tables and Featherstone's counts.

Our counts are the manifest's (``ops`` of ``NAME.json``: ``*``, ``/``, binary ``+``/``-`` of the emitted C, plus
function calls).  The references (``aggsym.codegen.ops``) count multiplications and additions only and assume
sin/cos given, so the comparison is mul + add + div against ref mul + ref add; calls are shown apart.
"""
from __future__ import annotations

from aggsym.codegen.ops import (BOOK_A_38, BOOK_TABLE_23, BOOK_TRANSVECTIVE, FEATHERSTONE_RNEA, REFERENCES,
                                 Reference, arithmetic)

# The book's (3.12)-(3.17) count is the *extra* cost of the delta form over the factors (3.8), not the cost of a
# whole routine: the routine transvective_factors is compared with their sum, the increment alone is shown.
BOOK_38_AND_DELTA = Reference("book (3.8) + (3.12)-(3.17), factors by the delta form",
                              lambda n: BOOK_A_38.mul(n) + BOOK_TRANSVECTIVE.mul(n),
                              lambda n: BOOK_A_38.add(n) + BOOK_TRANSVECTIVE.add(n))
ADDED = {"transvective_factors": (BOOK_38_AND_DELTA,)}
# Shown for information, not targets: Pinocchio's nonLinearEffects is RNEA with q'' = 0; the delta form's
# increment alone (see above).
INFORMATIONAL = {"nonlinear_effects": (FEATHERSTONE_RNEA,), "transvective_factors": (BOOK_TRANSVECTIVE,)}


def rows(ops: dict, n: int) -> list:
    """One row per (routine, reference): ours, the reference at n, their ratio; plus inertia+bias vs Table 2.3."""
    out = []
    for role, o in ops.items():
        info = INFORMATIONAL.get(role, ())
        refs = [(r, r not in info) for r in REFERENCES.get(role, ()) + ADDED.get(role, ())]
        refs += [(r, False) for r in info if r not in REFERENCES.get(role, ())]
        if not refs:
            out.append({"routine": role, **o, "ours": arithmetic(o), "reference": None})
            continue
        for ref, target in refs:
            m, a = ref.at(n)
            out.append({"routine": role, **o, "ours": arithmetic(o), "reference": ref.label, "ref_mul": m,
                        "ref_add": a, "ref_total": m + a, "ratio": arithmetic(o) / (m + a), "target": target})
    if "inertia" in ops and "bias" in ops:
        ours = arithmetic(ops["inertia"]) + arithmetic(ops["bias"])
        m, a = BOOK_TABLE_23.at(n)
        out.append({"routine": "inertia+bias", "mul": ops["inertia"]["mul"] + ops["bias"]["mul"],
                    "add": ops["inertia"]["add"] + ops["bias"]["add"],
                    "div": ops["inertia"]["div"] + ops["bias"]["div"],
                    "call": ops["inertia"]["call"] + ops["bias"]["call"], "ours": ours,
                    "reference": BOOK_TABLE_23.label, "ref_mul": m, "ref_add": a, "ref_total": m + a,
                    "ratio": ours / (m + a), "target": True})
    return out


def section(generation_runs: list) -> dict:
    """Op-count rows for every generated model (name -> {nq, rows})."""
    out = {}
    for run in generation_runs:
        if run.get("ok"):
            out[run["label"]] = {"name": run["name"], "nq": run["nq"], "ops": run["ops"],
                                 "rows": rows(run["ops"], run["nq"])}
    return out
