"""Whether the compiled kernels (:mod:`core.model.compiled`, numba) stand in for numpy.

numba is optional (``pip install ncperf[fast]``): where it is installed and the
environment variable ``NCPERF_NO_JIT`` is not set to a non-empty value other than ``0``,
the diagnosis's hottest loops (the profile's speed inside jerk-limited ramps, the
projection of points onto the path) run compiled, element by element, with the same
floating-point operations in the same order as numpy's array-wide code: the same bits
(``tests/test_jit.py``). Elsewhere numpy alone, as before.

numba is imported on the first call of :func:`compiled` (a few tenths of a second), not
with ncperf: commands that never reach these loops do not pay for it.
"""

from __future__ import annotations

import os
from functools import cache
from types import ModuleType

#: Set (to anything but "" or "0") to keep numpy's code where numba is installed.
NO_JIT_ENV = "NCPERF_NO_JIT"


def disabled() -> bool:
    """Whether ``NCPERF_NO_JIT`` asks for numpy's code."""
    return os.environ.get(NO_JIT_ENV, "") not in ("", "0")


@cache
def _load() -> ModuleType | None:
    try:
        from core.model import compiled as module
    except ImportError:  # numba not installed (or not for this numpy)
        return None
    return module


def compiled() -> ModuleType | None:
    """The compiled kernels' module, or None: numba absent or ``NCPERF_NO_JIT`` set (read
    at every call, so a test may switch)."""
    return None if disabled() else _load()
