"""Python's cyclic garbage collector paused around allocation-heavy, cycle-free work (reading a model, generating)."""
from __future__ import annotations

import gc
from contextlib import contextmanager


@contextmanager
def collector_paused():
    """The cyclic collector off for the block, back to its state after (also after an error).

    Reading a model allocates some 20 objects per body and frees nearly none until the end, and generating builds
    millions of long-lived program nodes freed by reference counting: in both the collector ran full passes over a
    growing heap with no cycles in it, again and again (half the time of reading a 2000-body chain, a third of the
    recursions' time of a 96-body chain).  Usable as a decorator."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()
