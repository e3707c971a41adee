"""The "did you mean ...?" of errors: the names closest to a misspelled one (a routine, a YAML key, a link, a frame), for the
error that lists the choices.

Python's :mod:`difflib` ranks the choices by similarity; at most three are offered, the closest first, and none
when nothing is close (an error then lists the choices alone).
"""
from __future__ import annotations

import difflib

MAX_SUGGESTIONS = 3
CUTOFF = 0.6  # difflib's similarity ratio below which a choice is not offered
MARGIN = 0.1  # a choice is offered only within this much of the closest one's ratio (one clear answer alone)


def close_names(name: str, choices) -> list:
    """The choices closest to ``name``, closest first (at most :data:`MAX_SUGGESTIONS`, each within
    :data:`MARGIN` of the closest); [] when none is close.  A choice differing from ``name`` in letter case alone
    comes first."""
    name = str(name)
    choices = list(dict.fromkeys(str(c) for c in choices))
    folded = [c for c in choices if c.lower() == name.lower() and c != name]
    ranked = []
    for c in choices:
        matcher = difflib.SequenceMatcher(None, name, c)
        if matcher.real_quick_ratio() >= CUTOFF and matcher.quick_ratio() >= CUTOFF and matcher.ratio() >= CUTOFF:
            ranked.append((-matcher.ratio(), c))
    ranked.sort()
    close = [c for r, c in ranked if -r >= -ranked[0][0] - MARGIN] if ranked else []
    return (folded + [c for c in close if c not in folded])[:MAX_SUGGESTIONS]


def did_you_mean(name: str, choices) -> str:
    """``"; did you mean 'x'?"`` (or ``'x' or 'y'``) for the end of an error message, or "" when no choice is
    close to ``name``."""
    close = close_names(name, choices)
    if not close:
        return ""
    return "; did you mean " + " or ".join(repr(c) for c in close) + "?"


__all__ = ["close_names", "did_you_mean"]
