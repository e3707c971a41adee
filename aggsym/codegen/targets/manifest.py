"""The manifest target: NAME.json (:func:`aggsym.contract.manifest`): coordinates, parameters, functions (their C
names, :func:`aggsym.codegen.names.c_symbol`), the operation counts of the emitted C (computed whatever the
targets), the files of a ``--split`` layout.  Nothing to run; ``aggsym check`` reads it, and a later generation
reads its file list for the stale files."""
from __future__ import annotations

import json

from ...contract import manifest
from ..inertial_helpers import manifest_entry
from ..names import c_symbol
from .base import Target, file_pattern
from .c import split_layout
from .kernels import kernels_manifest


class ManifestTarget(Target):
    name = "manifest"
    default = True

    def file_names(self, job):
        return [f"{job.model.name}.json"]

    def owns(self, name, file):
        return bool(file_pattern(name, ("json",)).fullmatch(file))

    def render(self, job):
        emitted = job.emitted
        layout = split_layout(job.model.name, emitted, job.names) if job.split and job.chosen("c") else None
        data = manifest(job.model, [e.routine for e in emitted], {e.routine.role: e.ops for e in emitted},
                        job.omitted, job.scalar, layout=layout,
                        functions={e.routine.role: c_symbol(job.model, e.routine) for e in emitted})
        if job.model.inertial_blocks:  # the helpers that write a link's ten inertial parameters (C and Python)
            data["inertial_helpers"] = manifest_entry(job.model)
        if job.chosen("kernels"):  # the batch kernels behind the JAX and PyTorch modules
            data["kernels"] = kernels_manifest(job)
        return {f"{job.model.name}.json": json.dumps(data, indent=2) + "\n"}
