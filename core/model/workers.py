"""Independent tasks on forked worker processes (``ncperf diagnose --jobs N``).

The fits of one step of a diagnosis are independent and deterministic (every effect on top
of the same setup, on the same data), and so is the alignment's projection of each program
line's samples: each may run in a process of its own and give the same numbers, to the bit,
as one after the other. :func:`forked_map` runs such tasks on forked processes:

* the task -- a function of the task's number, closing over the work (tool paths, setup,
  effects, data) -- is put in a module variable before the pool is made, so that the
  children inherit it (none of the work is pickled); they are sent task numbers;
* each child sends back its result pickled, with a reference in place of each object it
  shares with the parent (``shared``: the tool paths of a diagnosis, whose predictions then
  come back pointing to the parent's own paths, as those of a fit in the parent do; the
  diagnose benchmark's: 1.4-18 MB each instead of 20-37 MB, 17 MB of which the path's
  cached samples);
* the results are returned by task number, whatever order they were done in.

Callers run their tasks one after the other, in their own process, where
:func:`workers_for` gives 1: one job asked for or one task, a platform without the fork
start method (Windows; the only start method whose children inherit the work rather than
receive it pickled), or a daemonic process (a multiprocessing pool's worker, which may not
have children).
"""

from __future__ import annotations

import io
import multiprocessing
import pickle
import signal
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

from core.model.cpus import usable_cpus

R = TypeVar("R")


@dataclass(frozen=True)
class Task:
    """What forked children inherit (see the module docstring): the function of a task's
    number, and the objects its results may refer to without copying them."""

    fn: Callable[[int], Any]
    shared: tuple[object, ...]


#: How often a wait for the next result looks whether a worker died (s).
POLL_S = 0.5
#: The task of the pool being made or running; None between pools (set and cleared under
#: LOCK, so that two threads never give their children each other's work).
TASK: Task | None = None
LOCK = threading.Lock()


def default_jobs() -> int:
    """The worker processes to use by default: the CPUs this process may run on
    (:func:`core.model.cpus.usable_cpus`)."""
    return usable_cpus()


def can_fork() -> bool:
    """Whether this process may work on forked children: the platform has the fork start
    method and the process is not a daemon (a pool's worker, which may not have children)."""
    return (
        "fork" in multiprocessing.get_all_start_methods()
        and not multiprocessing.current_process().daemon
    )


def workers_for(jobs: int, count: int) -> int:
    """The worker processes ``jobs`` gives ``count`` independent tasks: at most one a task,
    and 1 (none: the tasks run in this process) where this process cannot fork."""
    return max(min(jobs, count), 1) if can_fork() else 1


def forked_map(
    fn: Callable[[int], R],
    count: int,
    workers: int,
    *,
    order: Sequence[int] | None = None,
    shared: Sequence[object] = (),
    done: Callable[[int, int], None] | None = None,
) -> list[R]:
    """``[fn(0), ..., fn(count - 1)]`` computed on ``workers`` forked processes, which
    inherit ``fn`` (and whatever it refers to) rather than receive it: started in ``order``
    (default: 0, 1, ...), returned by number. Their results come back pickled, each of
    ``shared`` they refer to as a reference to this process's own. ``done(k, i)``, if
    given, is called as task ``k`` ends, the ``i``-th to end (1-based)."""
    global TASK
    got: dict[int, R] = {}
    with LOCK:
        TASK = Task(fn, tuple(shared))
        try:
            ctx = multiprocessing.get_context("fork")
            before = set(multiprocessing.active_children())
            with ctx.Pool(workers, initializer=_ignore_interrupts) as pool:
                started = [p for p in multiprocessing.active_children() if p not in before]
                results = pool.imap_unordered(_run, range(count) if order is None else order)
                for i in range(1, count + 1):
                    k, blob = _next(results, started)
                    got[k] = _loads(blob, TASK.shared)
                    if done is not None:
                        done(k, i)
        finally:
            TASK = None
    return [got[k] for k in range(count)]


def _next(results: Any, workers: Sequence[multiprocessing.process.BaseProcess]) -> Any:
    """The next result of a pool's ``imap_unordered``; an error where one of its
    ``workers`` ended meanwhile. (A pool replaces a worker that dies, but the task it was
    running never comes back: without this the wait would never end. A pool's workers end
    only when it is closed, so an exit code while it runs is a death: killed -- SIGKILL is
    what the kernel's out-of-memory killer sends -- or crashed.)"""
    while True:
        try:
            return results.next(timeout=POLL_S)
        except multiprocessing.TimeoutError:
            pass
        for w in workers:
            code = w.exitcode
            if code is None:
                continue
            if code == -signal.SIGKILL:
                raise MemoryError(
                    f"a worker process was killed (SIGKILL, pid {w.pid}): out of memory? "
                    "(fewer --jobs need less)"
                )
            raise RuntimeError(f"a worker process ended with exit code {code} (pid {w.pid})")


def _ignore_interrupts() -> None:
    """A worker leaves Ctrl-C to its parent, which stops the pool (no traceback per worker)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _run(k: int) -> tuple[int, bytes]:
    """In a worker: task ``k`` of the inherited task, its result pickled (:func:`_dumps`)."""
    task = TASK
    assert task is not None, "a worker runs with the task its parent set"
    return k, _dumps(task.fn(k), task.shared)


class _Pickler(pickle.Pickler):
    """Pickles a result with a reference (an index) in place of each of ``shared``."""

    def __init__(self, file: io.BytesIO, shared: Sequence[object]) -> None:
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self._shared = {id(obj): k for k, obj in enumerate(shared)}
        self._objects = shared

    def persistent_id(self, obj: object) -> int | None:
        k = self._shared.get(id(obj))
        return k if k is not None and self._objects[k] is obj else None


class _Unpickler(pickle.Unpickler):
    """Reads what :class:`_Pickler` wrote, each reference back to the object of ``shared``."""

    def __init__(self, file: io.BytesIO, shared: Sequence[object]) -> None:
        super().__init__(file)
        self._objects = shared

    def persistent_load(self, pid: Any) -> object:
        return self._objects[int(pid)]


def _dumps(result: object, shared: Sequence[object]) -> bytes:
    buf = io.BytesIO()
    _Pickler(buf, shared).dump(result)
    return buf.getvalue()


def _loads(blob: bytes, shared: Sequence[object]) -> Any:
    return _Unpickler(io.BytesIO(blob), shared).load()
