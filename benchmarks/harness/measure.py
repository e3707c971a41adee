"""Run one command in a fresh process and measure it: wall time, CPU time and peak memory of that process alone.

``os.wait4`` returns the resource usage of exactly the child waited for (``RUSAGE_CHILDREN`` would accumulate
over all children), so each run's peak resident set (``ru_maxrss``, KiB on Linux) is its own.  A run that
outlives its timeout is killed with its process group and reported as timed out.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field

from .paths import ROOT


@dataclass
class Run:
    cmd: list
    returncode: int | None  # None when timed out
    wall_seconds: float
    cpu_seconds: float  # user + system of the child
    maxrss_kib: int
    timed_out: bool
    stdout: str = ""
    stderr: str = ""
    extra: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return not self.timed_out and self.returncode == 0


def run_measured(cmd, timeout: float | None = None, env=None, cwd=None, poll=None,
                 hard_timeout: float | None = None) -> Run:
    """Run ``cmd``; wait (polling, so ``timeout`` applies) and collect its own rusage.

    ``poll`` (optional) is called every poll interval with the elapsed seconds; if it returns True the timeout no
    longer applies (the caller has seen what it needed, e.g. a result file written by the timed part);
    ``hard_timeout`` applies in any case."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen([str(c) for c in cmd], stdout=out, stderr=err, env=env, cwd=cwd,
                                start_new_session=True)
        timed_out, disarmed = False, False
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid == proc.pid:
                break
            elapsed = time.perf_counter() - t0
            if poll is not None and not disarmed and poll(elapsed):
                disarmed = True
            over = (timeout is not None and elapsed > timeout and not disarmed) or \
                (hard_timeout is not None and elapsed > hard_timeout)
            if over:
                timed_out = True
                os.killpg(proc.pid, signal.SIGKILL)
                pid, status, usage = os.wait4(proc.pid, 0)
                break
            time.sleep(0.02 if elapsed < 2 else 0.25)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        return Run([str(c) for c in cmd], None if timed_out else proc.returncode, wall,
                   usage.ru_utime + usage.ru_stime, int(usage.ru_maxrss), timed_out, out.read(), err.read())


def python() -> str:
    """The interpreter running the benchmark (its venv has aggsym and the extras)."""
    return sys.executable


def child_env() -> dict:
    """The environment for child processes: the repository on PYTHONPATH (``benchmarks`` and ``aggsym``)."""
    env = dict(os.environ)
    root = str(ROOT)
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env
