"""Fitting several effects at once, on worker processes (``ncperf diagnose --jobs N``).

The fits of one step of a diagnosis -- every effect on top of the same setup, on the same
data -- are independent and deterministic: :func:`fit_each` runs them on forked processes
(:func:`core.model.workers.forked_map`), those with the most parameters first (the longest
fits start first: the diagnose benchmark's axis_dynamics, 9 parameters, takes 5.6 s of its
16.6 s of fits), and returns them in the effects' order, the same to the bit as one after
the other.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

from core.diagnosis.fit import fit
from core.diagnosis.objective import FEED, Objective
from core.engine.effects import Effect, Setup
from core.engine.indicators import IndicatorSource
from core.engine.predict import Prediction
from core.model.toolpath import ToolPath
from core.model.workers import forked_map, workers_for

#: What one fit gives: the parameters and the predictions of every program with them.
Fitted = tuple[dict[str, float], list[Prediction]]

#: Progress lines of :func:`fit_each` (``name``: the effect, ``k`` of ``n``): as a fit starts
#: (one after the other); as the fits start on ``workers`` processes, and as each is done
#: there (in the order they end).
STEP = "fitting {name} ({k} of {n} effects)"
START = "fitting {n} effects on {workers} processes"
DONE = "fitted {name} ({k} of {n} effects)"


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
    rapids: Sequence[Any] = (),
) -> dict[str, Fitted]:
    """Every effect of ``effects`` fitted on top of ``base``
    (:func:`core.diagnosis.fit.fit`), on ``jobs`` worker processes where it can (see the
    module docstring): {name: (params, predictions)}, in the order of ``effects``, the same
    to the bit whatever ``jobs``. ``rapids``: more data the effects that act on the rapids
    (``Effect.rapids``) are fitted on besides ``data`` -- the rapids of the runs
    (:func:`core.diagnosis.resample.rapid_data`), where an axis's or the path's limits show
    as on the feed moves. ``progress``, if given, is told ``step`` as each fit
    starts (one after the other), or ``start`` once and ``done`` as each fit ends (on
    workers), formatted with the effect's ``name``, ``k`` and ``n`` and the ``workers``."""
    say = progress or (lambda _: None)
    names = list(effects)
    with_rapids = [*data, *rapids]

    def data_of(name: str) -> Sequence[Any]:
        return with_rapids if rapids and effects[name].rapids else data

    n = len(names)
    workers = workers_for(jobs, n)
    if workers == 1:
        out = {}
        for k, name in enumerate(names, start=1):
            say(step.format(name=name, k=k, n=n))
            out[name] = fit(indicators_of, tps, base, effects[name], data_of(name), objective)
        return out

    def one(k: int) -> Fitted:
        return fit(indicators_of, tps, base, effects[names[k]], data_of(names[k]), objective)

    say(start.format(n=n, workers=workers))
    fitted = forked_map(
        one,
        n,
        workers,
        # the longest fits first (those with the most parameters), so that none starts last
        order=sorted(range(n), key=lambda k: -len(effects[names[k]].params)),
        # the predictions refer to the tool paths: the parent's own, not copies
        shared=tps,
        done=lambda k, i: say(done.format(name=names[k], k=i, n=n)),
    )
    return dict(zip(names, fitted, strict=True))
