"""Work over the moves in pieces: bounded temporaries on million-move programs.

An elementwise computation gives the same numbers whether it runs over all moves at once or
over consecutive pieces of them; in pieces, its temporaries are a few MB instead of several
copies of every column. And the pieces may run side by side: numpy lets go of the GIL
inside its loops over large arrays (and the C kernels, core.model.native, while they run),
so two halves of the moves on two threads take about half the time on two cores
(:func:`halves`; the corner model's arctan2, hypot, cos and cbrt over 169k corners: 53 ->
28 ms).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterator
from functools import cache
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

T = TypeVar("T")
U = TypeVar("U")

#: Moves per piece (2^18: a float64 temporary of a piece is 2 MB).
PIECE = 1 << 18


def pieces(n: int, size: int = PIECE) -> Iterator[slice]:
    """Consecutive slices of at most ``size`` covering ``0..n``."""
    for i in range(0, n, size):
        yield slice(i, min(i + size, n))


def piecewise(n: int, dtype: type, f: Callable[[slice], NDArray], size: int = PIECE) -> NDArray:
    """``f`` over ``0..n`` piece by piece into one (n,) array of ``dtype``: ``f`` is
    elementwise, so the values are those of ``f`` over all of it at once."""
    out: NDArray = np.empty(n, dtype=dtype)
    for s in pieces(n, size):
        out[s] = f(s)
    return out


#: Moves below which a kernel's work is not split over two threads (starting one costs
#: about 0.1 ms, the marks of 20k moves about 0.5 ms).
SPLIT = 20_000


@cache
def two_cores() -> bool:
    """Whether this process may run on two cores or more."""
    try:
        return len(os.sched_getaffinity(0)) >= 2
    except AttributeError:  # (no sched_getaffinity: macOS, Windows)
        return (os.cpu_count() or 1) >= 2


def side_by_side(first: Callable[[], T], second: Callable[[], U]) -> tuple[T, U]:
    """``first()`` on a new thread while this one runs ``second()``; both results (an
    exception of either is raised here, after both ended). For kernels that let go of the
    GIL (ctypes' calls, numba's nogil kernels) and write disjoint outputs."""
    box: list = []

    def run() -> None:
        try:
            box.append((True, first()))
        except BaseException as exc:  # (raised again in the caller's thread)
            box.append((False, exc))

    thread = threading.Thread(target=run, name="ncperf-kernel", daemon=True)
    thread.start()
    try:
        two = second()
    finally:
        thread.join()
    ok, one = box[0]
    if not ok:
        raise one
    return one, two


def halves(m: int, f: Callable[[slice], object]) -> bool:
    """``f`` over the first and the second half of ``0..m`` on two threads, where ``m`` is
    at least :data:`SPLIT` and two cores are here (True); else nothing (False: the caller
    runs its own loop). ``f`` is elementwise over its slice and writes its results into
    the caller's arrays there (the halves' outputs are disjoint): the values are those of
    ``f`` over all of it at once."""
    if m < SPLIT or not two_cores():
        return False
    h = m // 2
    side_by_side(lambda: f(slice(0, h)), lambda: f(slice(h, m)))
    return True
