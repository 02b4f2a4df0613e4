"""Fitting several effects at once, on worker processes (``ncperf diagnose --jobs N``).

The fits of one step of a diagnosis are independent -- every effect on top of the same setup,
on the same data -- and deterministic: each may run in a process of its own and give the
same parameters and predictions, to the bit, as one after the other. :func:`fit_each` runs
them on ``jobs`` forked processes:

* the work (the tool paths, the setup, the effects, the data, the objective) is put in a
  module variable before the pool is made, so that the children inherit it (none of it is
  pickled); they are sent effect names, those with the most parameters first (the longest
  fits start first: the diagnose benchmark's axis_dynamics, 9 parameters, takes 5.6 s of
  16.6);
* each child sends back the fitted parameters and predictions, pickled without the tool
  paths they share with the parent: a reference stands for each, so the predictions come
  back pointing to the parent's own tool paths, as those of a fit in the parent do (the
  benchmark's: 1.4-18 MB each instead of 20-37 MB, 17 of them the path's cached samples);
* the results are returned in the effects' order, whatever order they were done in.

The fits run one after the other, in this process, where one job is asked for or one effect
is left, where the platform cannot fork (Windows; the fork start method is the only one
whose children inherit the work rather than receive it pickled), or inside a daemonic
process (a multiprocessing pool's worker, which may not have children).
"""

from __future__ import annotations

import io
import multiprocessing
import os
import pickle
import signal
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from core.diagnosis.fit import fit
from core.diagnosis.objective import FEED, Objective
from core.engine.effects import Effect, Setup
from core.engine.indicators import IndicatorSource
from core.engine.predict import Prediction
from core.model.toolpath import ToolPath

#: What one fit gives: the parameters and the predictions of every program with them.
Fitted = tuple[dict[str, float], list[Prediction]]

#: Progress lines of :func:`fit_each` (``name``: the effect, ``k`` of ``n``): as a fit starts
#: (one after the other); as the fits start on ``workers`` processes, and as each is done
#: there (in the order they end).
STEP = "fitting {name} ({k} of {n} effects)"
START = "fitting {n} effects on {workers} processes"
DONE = "fitted {name} ({k} of {n} effects)"


@dataclass(frozen=True)
class Work:
    """The fits' common inputs, which forked children inherit (see the module docstring)."""

    indicators_of: IndicatorSource
    tps: tuple[ToolPath, ...]
    base: Setup
    effects: Mapping[str, Effect]
    data: Sequence[Any]
    objective: Objective


#: The work of the pool being made or running; None between pools (set and cleared under
#: LOCK, so that two threads never give their children each other's work).
WORK: Work | None = None
LOCK = threading.Lock()


def default_jobs() -> int:
    """The worker processes to use by default: the CPUs this process may run on (its
    affinity where the platform tells it, else all the machine's), at least 1."""
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:  # no sched_getaffinity (macOS, Windows)
        return max(os.cpu_count() or 1, 1)


def can_fork() -> bool:
    """Whether this process may fit on forked children: the platform has the fork start
    method and the process is not a daemon (a pool's worker, which may not have children)."""
    return (
        "fork" in multiprocessing.get_all_start_methods()
        and not multiprocessing.current_process().daemon
    )


def fit_each(
    indicators_of: IndicatorSource,
    tps: Sequence[ToolPath],
    base: Setup,
    effects: Mapping[str, Effect],
    data: Sequence[Any],
    objective: Objective = FEED,
    *,
    jobs: int = 1,
    progress: Callable[[str], None] | None = None,
    step: str = STEP,
    start: str = START,
    done: str = DONE,
) -> dict[str, Fitted]:
    """Every effect of ``effects`` fitted on top of ``base``
    (:func:`core.diagnosis.fit.fit`), on ``jobs`` worker processes where it can (see the
    module docstring): {name: (params, predictions)}, in the order of ``effects``, the same
    to the bit whatever ``jobs``. ``progress``, if given, is told ``step`` as each fit
    starts (one after the other), or ``start`` once and ``done`` as each fit ends (on
    workers), formatted with the effect's ``name``, ``k`` and ``n`` and the ``workers``."""
    n = len(effects)
    workers = min(jobs, n)
    if workers <= 1 or not can_fork():
        out = {}
        for k, (name, eff) in enumerate(effects.items(), start=1):
            if progress is not None:
                progress(step.format(name=name, k=k, n=n))
            out[name] = fit(indicators_of, tps, base, eff, data, objective)
        return out
    global WORK
    # the longest fits first (those with the most parameters), so that none starts last
    order = sorted(effects, key=lambda name: -len(effects[name].params))
    got: dict[str, Fitted] = {}
    if progress is not None:
        progress(start.format(n=n, workers=workers))
    with LOCK:
        WORK = Work(indicators_of, tuple(tps), base, effects, data, objective)
        try:
            ctx = multiprocessing.get_context("fork")
            with ctx.Pool(workers, initializer=_ignore_interrupts) as pool:
                for k, (name, blob) in enumerate(pool.imap_unordered(_fit_one, order), start=1):
                    got[name] = _loads(blob, WORK.tps)
                    if progress is not None:
                        progress(done.format(name=name, k=k, n=n))
        finally:
            WORK = None
    return {name: got[name] for name in effects}


def _ignore_interrupts() -> None:
    """A worker leaves Ctrl-C to its parent, which stops the pool (no traceback per worker)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _fit_one(name: str) -> tuple[str, bytes]:
    """In a worker: the fit of effect ``name`` of the inherited work, pickled (
    :func:`_dumps`)."""
    w = WORK
    assert w is not None, "a fitting worker runs with the work its parent set"
    fitted = fit(w.indicators_of, w.tps, w.base, w.effects[name], w.data, w.objective)
    return name, _dumps(fitted, w.tps)


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


def _dumps(fitted: Fitted, shared: Sequence[object]) -> bytes:
    buf = io.BytesIO()
    _Pickler(buf, shared).dump(fitted)
    return buf.getvalue()


def _loads(blob: bytes, shared: Sequence[object]) -> Fitted:
    out: Fitted = _Unpickler(io.BytesIO(blob), shared).load()
    return out
