"""One process of the batched benchmark: one entry, one robot, one routine, every batch size.

    python -m benchmarks.batch.worker JOB.json

JOB.json (written by :mod:`benchmarks.batch.orchestrator`) names the entry, the robot (files, dimensions, joint order),
the routine, the states file, the batch sizes, the number of interleaved repeats, the seconds a timed sample should
last, how many states are kept for the agreement check, and where to write.  The worker builds the entry
(:mod:`benchmarks.batch.peers`, :mod:`benchmarks.batch.engines`), then for every batch size B: puts the first B states
into the framework, times the first call (the compile, for a jit entry: every new shape compiles), times a second call
to choose how many calls a sample takes, and keeps the outputs of the first states; then it takes REPEATS samples of
every B in turn (B interleaved, so a slow spell of the shared machine spreads over all sizes). It prints no time: the
orchestrator checks the outputs against Pinocchio first.  The result (JSON) has, per B, the first call's seconds, the
calls per sample and every sample's seconds per call; the outputs go to an .npz.
"""
from __future__ import annotations

import json
import resource
import sys
import time
from pathlib import Path

import numpy as np

from . import engines as batch_engines, peers as batch_peers

ARGS = {"fd": ("q", "v", "tau"), "A": ("q",), "id": ("q", "v", "a"), "jac": ("q", "v", "tau")}
ENTRY_FRAMEWORK = {name: spec[1] for name, spec in batch_peers.ENTRIES.items()}


def framework_version(framework: str | None) -> str | None:
    """The version of the framework an entry ran on in this process (the entries of the project's venv and of the
    peers' venv may differ)."""
    if framework not in ("jax", "torch"):
        return None
    module = sys.modules.get(framework)
    return getattr(module, "__version__", None)


def build(entry: str, robot: dict):
    if entry == "numpy":
        return batch_peers.build_numpy(robot)
    if entry == "pinocchio":
        return batch_peers.build_pinocchio(robot)
    if entry.startswith("aggsym_jax"):
        return batch_peers.build_aggsym_jax(robot, {"aggsym_jax": "custom", "aggsym_jax_plain": "plain",
                                                    "aggsym_jax_routine": "routine",
                                                    "aggsym_jax_project": "custom", "aggsym_jax_rev": "custom_rev",
                                                    "aggsym_jax_project_rev": "custom_rev",
                                                    "aggsym_jax_kernels": "kernels",
                                                    "aggsym_jax_kernels_all": "kernels",
                                                    "aggsym_jax_kernels_rev": "kernels_rev"}[entry])
    if entry in ("aggsym_torch", "aggsym_torch_kernels", "aggsym_torch_kernels_func"):
        return batch_peers.build_aggsym_torch(robot, kernels=entry != "aggsym_torch",
                                              functional=entry == "aggsym_torch_kernels_func")
    if entry == "c_loop":
        return batch_peers.build_c_loop(robot)
    if entry.startswith("pinocchio_parallel"):
        import os

        return batch_peers.build_pinocchio_parallel(robot, len(os.sched_getaffinity(0)) if entry.endswith("_all")
                                                    else 1)
    if entry == "adam_jax":
        return batch_peers.build_adam_jax(robot)
    if entry == "adam_torch":
        return batch_peers.build_adam_torch(robot)
    if entry == "mjx":
        return batch_engines.build_mjx(robot)
    if entry == "jaxsim":
        return batch_engines.build_jaxsim(robot)
    raise KeyError(f"unknown entry {entry!r}; known: {sorted(batch_peers.ENTRIES)}")


def rss_mib() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def run(job: dict) -> dict:
    t0 = time.perf_counter()
    built = build(job["entry"], job["robot"])
    fn = built.routines[job["routine"]]
    build_seconds = time.perf_counter() - t0
    states = np.load(job["states"])
    sizes = [int(b) for b in job["sizes"]]
    keep = int(job["check"])
    inputs, first, calls, outputs = {}, {}, {}, {}

    def call(b):
        out = fn(*inputs[b])
        built.ready(out)
        return out

    for b in sizes:
        inputs[b] = tuple(built.put(np.ascontiguousarray(states[name][:b])) for name in ARGS[job["routine"]])
        t = time.perf_counter()
        out = call(b)
        first[b] = time.perf_counter() - t
        outputs[f"B{b}"] = built.fetch(out)[:keep]
        t = time.perf_counter()
        call(b)
        once = time.perf_counter() - t
        calls[b] = max(1, int(job["sample_seconds"] / max(once, 1e-9)))
    samples = {b: [] for b in sizes}
    for _ in range(int(job["repeats"])):
        for b in sizes:
            t = time.perf_counter()
            for _ in range(calls[b]):
                call(b)
            samples[b].append((time.perf_counter() - t) / calls[b])
    np.savez(job["outputs"], **outputs)
    return {"entry": job["entry"], "robot": job["robot"]["label"], "routine": job["routine"],
            "framework_version": framework_version(ENTRY_FRAMEWORK.get(job["entry"])),
            "compiles": built.compiles, "build_seconds": build_seconds,
            "sizes": {str(b): {"first_call_seconds": first[b], "calls_per_sample": calls[b],
                               "seconds_per_call": samples[b]} for b in sizes},
            "rss_end_mib": rss_mib(), "maxrss_self_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    job = json.loads(Path(argv[0]).read_text())
    result = run(job)
    Path(job["result"]).write_text(json.dumps(result, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
