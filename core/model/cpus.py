"""The CPUs this process may run on: without numpy, so that what needs to know it before
numpy is imported (the heap filled ahead on the second core, :mod:`core.model.heap`) can."""

from __future__ import annotations

import os
from functools import cache


def usable_cpus() -> int:
    """The CPUs this process may run on (its affinity where the platform tells it, else all
    the machine's), at least 1."""
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:  # no sched_getaffinity (macOS, Windows)
        return max(os.cpu_count() or 1, 1)


@cache
def two_cores() -> bool:
    """Whether this process may run on two cores or more."""
    return usable_cpus() >= 2
