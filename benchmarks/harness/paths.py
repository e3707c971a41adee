"""Where the benchmark reads and writes: its results (REPORT.md, ``NAME.json``, the plots) in ``benchmarks/``, what
it builds and generates under ``benchmarks/build/`` (git-ignored), the C and C++ harness sources in this folder."""
from __future__ import annotations

import json
from pathlib import Path

HARNESS = Path(__file__).resolve().parent  # bench.h, pinocchio_bench.cpp, ...: the harnesses' sources
BENCHMARKS = HARNESS.parent  # the results: REPORT.md, the sections' JSON and plots
ROOT = BENCHMARKS.parent  # the repository (models/, aggsym/)
BUILD = BENCHMARKS / "build"


def result_path(name: str) -> Path:
    """``benchmarks/NAME.json``: a section's results, read back by the report."""
    return BENCHMARKS / f"{name}.json"


def write_json(path, data, indent: int = 1) -> Path:
    """``data`` as JSON (anything else as its str) with a final newline."""
    path = Path(path)
    path.write_text(json.dumps(data, indent=indent, default=str) + "\n")
    return path


def read_json(path) -> dict:
    """A JSON file of an earlier run, or {} when there is none."""
    path = Path(path)
    return json.loads(path.read_text()) if path.exists() else {}
