"""``aggsym generate`` in a fresh process, as every section runs it (the interpreter of the benchmark, the
repository on its PYTHONPATH), and the generated Python modules loaded from their files."""
from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

from .measure import Run, child_env, python, run_measured


def aggsym_generate(model, outdir, *options, timeout: float | None = None, cwd=None) -> Run:
    """``python -m aggsym generate MODEL -o OUTDIR OPTIONS...`` in a fresh process, measured
    (:func:`benchmarks.harness.measure.run_measured`)."""
    return run_measured([python(), "-m", "aggsym", "generate", str(model), "-o", str(outdir), *map(str, options)],
                        timeout=timeout, env=child_env(), cwd=cwd)


def generated_manifest(model, outdir, name: str, *options, timeout: float | None = None) -> dict:
    """:func:`aggsym_generate` for its code alone (not timed): the manifest ``OUTDIR/NAME.json``; a failure raises
    with the command's stderr."""
    run = aggsym_generate(model, outdir, *options, timeout=timeout)
    if not run.ok:
        raise RuntimeError(f"aggsym generate {model} {' '.join(map(str, options))} failed "
                           f"({'timed out' if run.timed_out else run.returncode}):\n{run.stderr[-2000:]}")
    return json.loads((Path(outdir) / f"{name}.json").read_text())


def load_module(path: Path, name: str):
    """A generated module loaded from its file under ``name`` (not from sys.path: every robot's folder has its
    own)."""
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module
