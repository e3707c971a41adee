"""What the sections' command lines share: comma-separated settings, time-stamped log lines, and the ``main`` of a
section run alone (``python -m benchmarks.X [OUT.json]``: its Markdown printed, its results written)."""
from __future__ import annotations

import sys
import time
from pathlib import Path

from .paths import write_json


def names(text: str) -> list:
    """The names of a comma-separated setting, blanks dropped."""
    return [x.strip() for x in str(text).split(",") if x.strip()]


def logger(tag: str):
    """A log function printing ``[TAG HH:MM:SS] message`` at once."""
    def log(msg: str):
        print(f"[{tag} {time.strftime('%H:%M:%S')}] {msg}", flush=True)

    return log


def section_main(run, markdown, argv=None, default: Path | None = None, indent: int = 2, **kwargs) -> dict:
    """Run a section (``run(**kwargs)``), print its Markdown and write its results to OUT.json, the first argument
    (else ``default``, else nowhere); returns the results."""
    argv = sys.argv[1:] if argv is None else argv
    results = run(**kwargs)
    path = Path(argv[0]) if argv else default
    if path is not None:
        write_json(path, results, indent=indent)
    print(markdown(results))
    return results
