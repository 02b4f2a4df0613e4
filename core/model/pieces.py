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

import queue
import threading
from collections.abc import Callable, Iterator
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from core.model.cpus import two_cores

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


#: Moves below which work is not split over two threads (handing a task to the worker
#: thread and back costs 0.1-0.3 ms on this project's VM, the marks of 20k moves about
#: 0.5 ms).
SPLIT = 20_000


def side_by_side(first: Callable[[], T], second: Callable[[], U]) -> tuple[T, U]:
    """``first()`` on ncperf's worker thread while this one runs ``second()``; both results
    (an exception of either is raised here, after both ended). For kernels that let go of
    the GIL (ctypes' calls, numba's nogil kernels, numpy's loops over large arrays) and
    write disjoint outputs. Called on the worker thread itself (nested), one after the
    other there."""
    worker = _worker()
    if threading.current_thread() is worker.thread:
        return first(), second()
    box: list = []
    done = threading.Lock()
    done.acquire()
    worker.tasks.put((first, box, done))
    try:
        two = second()
    finally:
        done.acquire()  # (released by the worker once first() ended)
    ok, one = box[0]
    if not ok:
        raise one
    return one, two


class _Worker:
    """One daemon thread that runs the tasks put to it, one after the other: a thread made
    once, not for every call (starting one took about 0.5 ms on this project's VM, as long
    as the passes of 169k moves it was to share)."""

    def __init__(self) -> None:
        self.tasks: queue.SimpleQueue = queue.SimpleQueue()
        self.thread = threading.Thread(target=self._serve, name="ncperf-worker", daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while True:
            fn, box, done = self.tasks.get()
            try:
                box.append((True, fn()))
            except BaseException as exc:  # (raised again in the caller's thread)
                box.append((False, exc))
            finally:
                done.release()


_workers: list[_Worker] = []


def _worker() -> _Worker:
    """The worker thread, started on first use (and again in a forked child, where the
    parent's is not running)."""
    if not _workers or not _workers[0].thread.is_alive():
        _workers[:] = [_Worker()]
    return _workers[0]


def rows_in_pieces(m: int, size: int, fill: Callable[[slice], object]) -> None:
    """``fill`` over consecutive slices of at most ``size`` rows covering ``0..m``, the
    pieces of the two halves on two threads where :func:`halves` splits: ``fill`` is row
    by row and writes its rows of the caller's arrays (bounded temporaries, the same
    values as over all rows at once)."""

    def run(h: slice) -> None:
        for a in range(h.start, h.stop, size):
            fill(slice(a, min(a + size, h.stop)))

    if not halves(m, run):
        run(slice(0, m))


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
