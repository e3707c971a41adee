"""The benchmark of ``make bench`` (``python -m benchmarks.run``), above the package: it imports aggsym, aggsym never
imports it.  Bottom to top:

- ``harness/``: what the sections share (the paths, measuring a child process, ``aggsym generate`` in one, the
  host, the robots, the chains, tables and plots, building the C and C++ harnesses, whose sources it holds);
- the sections, by what they measure: ``generation/`` (generating code: time, memory, scale, operation counts,
  compile time, reading large inputs), ``runtime/`` (the generated code's runtime against its peers: Pinocchio C++
  and Python, CasADi, libm), ``batch/`` (batches of states in JAX, PyTorch and NumPy against their peers, in a
  venv of their own), ``mjcf/`` (the MJCF reader against MuJoCo on whole corpora);
- ``report.py`` and ``report_plots.py`` (REPORT.md and its plots), then ``run.py``, which runs every section.

Every result (REPORT.md, the sections' JSON and plots) is written into this folder, everything else into ``build/``.
"""
