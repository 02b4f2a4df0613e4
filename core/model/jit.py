"""Whether the compiled kernels (:mod:`core.model.compiled`, numba) stand in for numpy.

numba comes with ncperf where it ships wheels (CPython 3.11-3.13 on 64-bit x86 and ARM;
``pip install "ncperf[fast]"`` elsewhere, if it installs there). The kernels run the
diagnosis's hottest loops (the profile's rounds and passes, the speed inside jerk-limited
ramps, the projection of points onto the path, the search of each program line's samples,
the trace CSV's numbers, LinuxCNC's look-ahead walks, the servo lag and the speed of
filtered positions, the corner model's limits, the moves a fit's candidate changed)
element by element with the same floating-point operations in the same order as numpy's
array-wide code: the same bits (``tests/test_jit.py``). They are used where all three hold:

* the diagnosis asked for them (:func:`allow`: :func:`core.diagnosis.align.align`,
  :func:`core.diagnosis.diagnose.diagnose_cases`, :func:`core.diagnosis.calibrate.calibrate`
  and the commands that read traces for them do): importing numba and loading its cached
  kernels costs about 0.4 s, which the diagnosis's minutes of fits repay and a single
  ``ncperf analyze`` would not -- or a loop is long enough that its Python would cost more
  (:func:`compiled_for`: LinuxCNC's look-ahead walks over 150k segments and more);
* numba is installed;
* the environment variable ``NCPERF_NO_JIT`` is not set to a non-empty value other
  than ``0``.

Elsewhere numpy's code runs, as before. numba compiles the kernels on their first use after
an install or a change (several seconds, once) and keeps them in its cache beside
``compiled.py`` (or, where that folder is not writable, in the user's cache folder).
"""

from __future__ import annotations

import os
from functools import cache
from types import ModuleType

#: Set (to anything but "" or "0") to keep numpy's code where numba is installed.
NO_JIT_ENV = "NCPERF_NO_JIT"

_allowed = [False]  # (a list: set by allow() without a global statement)


def allow() -> None:
    """Let the kernels stand in for numpy from now on in this process (and in the worker
    processes it forks): the diagnosis calls this."""
    _allowed[0] = True


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
    """The compiled kernels' module, or None: not :func:`allow`-ed, numba absent, or
    ``NCPERF_NO_JIT`` set (read at every call, so a test may switch)."""
    if not _allowed[0] or disabled():
        return None
    return _load()


#: Python steps above which a loop that has a kernel takes the kernels even where the
#: diagnosis did not ask for them: LinuxCNC's lazy look-ahead walks
#: (core.engine.lookahead) take about 4.5 us a segment in Python (99k segments of a chord
#: raster: 0.45 s), numba's start-up with the cached kernel about as long (0.46-0.64 s for
#: the same queue, measured while another job ran): the kernels pay from about 150k on.
WORTH_LOADING = 150_000


def compiled_for(steps: int) -> ModuleType | None:
    """:func:`compiled`, and also the kernels (numba installed, ``NCPERF_NO_JIT`` not set)
    for a loop of at least :data:`WORTH_LOADING` steps, whose Python would cost more than
    loading them. The kernels give the same bits, so only the time depends on which runs."""
    kernels = compiled()
    if kernels is not None or disabled() or steps < WORTH_LOADING:
        return kernels
    return _load()
