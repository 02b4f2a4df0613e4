"""Fitting several effects at once, on worker processes (``ncperf diagnose --jobs N``).

The fits of one step of a diagnosis -- every effect on top of the same setup, on the same
data -- are independent and deterministic: :func:`fit_each` runs them on forked processes
(:func:`core.model.workers.forked_map`), the longest first (:func:`cost`: the diagnose
benchmark's axis_dynamics, 9 parameters, takes 7.2 s of its 17.4 s of fits; started last, a
long fit would keep one worker busy while the other waits), and returns them in the
effects' order, the same to the bit as one after the other.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

from core.diagnosis.fit import fit, scores_planned
from core.diagnosis.objective import FEED, Objective
from core.engine.effects import Effect, Setup
from core.engine.indicators import IndicatorSource
from core.engine.predict import TIME_DOMAIN, Prediction, same_plan
from core.model.toolpath import ToolPath
from core.model.workers import forked_map, workers_for

#: What one fit gives: the parameters and the predictions of every program with them.
Fitted = tuple[dict[str, float], list[Prediction]]
#: What :func:`fit_and_weigh`'s ``weigh`` makes of a fit.
W = TypeVar("W")

#: Progress lines of :func:`fit_each` (``name``: the effect, ``k`` of ``n``): as a fit starts
#: (one after the other); as the fits start on ``workers`` processes, and as each is done
#: there (in the order they end).
STEP = "fitting {name} ({k} of {n} effects)"
START = "fitting {n} effects on {workers} processes"
DONE = "fitted {name} ({k} of {n} effects)"

#: What a candidate of an effect that acts in time only (a servo lag, a setpoint filter:
#: its candidates share one plan) costs against one that plans anew: it filters the whole
#: motion and projects it back onto the path. Measured on the diagnose benchmark
#: (2026-11-28): 60-76 ms a candidate against 11-24 ms (median 17).
FILTERED_COST = 4.0


def cost(eff: Effect, base: Setup) -> float:
    """What fitting ``eff`` on top of ``base`` costs, roughly (in candidates that plan
    anew): its candidates (:func:`core.diagnosis.fit.scores_planned`), each weighted
    FILTERED_COST where the effect changes the motion in time only. For the order in which
    the fits start; their results do not depend on it."""
    n = float(scores_planned(eff))
    if eff.params:
        far = eff.apply(base, {p.name: p.high for p in eff.params})
        timed = any(getattr(far, f) != getattr(base, f) for f in TIME_DOMAIN)
        if timed and same_plan(base, far):
            n *= FILTERED_COST
    return n


def fit_each(
    indicators_of: IndicatorSource,
    tps: Sequence[ToolPath],
    base: Setup,
    effects: Mapping[str, Effect],
    data: Sequence[Any],
    objective: Objective = FEED,
    **options: Any,
) -> dict[str, Fitted]:
    """Every effect of ``effects`` fitted on top of ``base``
    (:func:`core.diagnosis.fit.fit`), on worker processes where it can (see the module
    docstring): {name: (params, predictions)}, in the order of ``effects``, the same to the
    bit whatever the number of workers. ``options``: :func:`fit_and_weigh`'s (``jobs``,
    ``progress`` and its lines, ``rapids``)."""
    both = fit_and_weigh(indicators_of, tps, base, effects, data, None, objective, **options)
    return {name: fitted for name, (fitted, _) in both.items()}


def fit_and_weigh(
    indicators_of: IndicatorSource,
    tps: Sequence[ToolPath],
    base: Setup,
    effects: Mapping[str, Effect],
    data: Sequence[Any],
    weigh: Callable[[str, Fitted], W] | None,
    objective: Objective = FEED,
    *,
    jobs: int = 1,
    progress: Callable[[str], None] | None = None,
    step: str = STEP,
    start: str = START,
    done: str = DONE,
    rapids: Sequence[Any] = (),
) -> dict[str, tuple[Fitted, W | None]]:
    """Every effect of ``effects`` fitted on top of ``base`` (:func:`core.diagnosis.fit.fit`),
    on ``jobs`` worker processes where it can, and each fit then weighed where it was made:
    {name: ((params, predictions), weigh(name, (params, predictions)))} (None without
    ``weigh``), in the order of ``effects``, the same to the bit whatever ``jobs`` -- the
    evidence of every fit (its held-out gaps, its test) made on the workers beside the fits
    rather than one after the other once they are all back. ``weigh`` must give what it
    would give in this process (a function of the fit and of what the workers inherit).
    ``rapids``: more data the effects that act on the rapids (``Effect.rapids``) are fitted
    on besides ``data`` -- the rapids of the runs
    (:func:`core.diagnosis.resample.rapid_data`), where an axis's or the path's limits show
    as on the feed moves. ``progress``, if given, is told ``step`` as each fit starts (one
    after the other), or ``start`` once and ``done`` as each fit ends (on workers),
    formatted with the effect's ``name``, ``k`` and ``n`` and the ``workers``."""
    say = progress or (lambda _: None)
    names = list(effects)
    with_rapids = [*data, *rapids]

    def data_of(name: str) -> Sequence[Any]:
        return with_rapids if rapids and effects[name].rapids else data

    def one(k: int) -> tuple[Fitted, W | None]:
        name = names[k]
        fitted = fit(indicators_of, tps, base, effects[name], data_of(name), objective)
        return fitted, None if weigh is None else weigh(name, fitted)

    n = len(names)
    workers = workers_for(jobs, n)
    if workers == 1:
        out = {}
        for k, name in enumerate(names, start=1):
            say(step.format(name=name, k=k, n=n))
            out[name] = one(k - 1)
        return out

    def sent(k: int) -> tuple[Fitted, W | None]:
        (params, preds), weighed = one(k)
        # (what the plans share stays: 50 MB a fit of a servo lag, not read by the parent)
        return (params, [p.unshared() for p in preds]), weighed

    say(start.format(n=n, workers=workers))
    costs = [cost(effects[name], base) for name in names]
    fitted = forked_map(
        sent,
        n,
        workers,
        # the longest fits first, so that none starts last (ties: those fitted on the rapids
        # too, which have more data, then the effects' order)
        order=sorted(range(n), key=lambda k: (-costs[k], not effects[names[k]].rapids)),
        # the predictions refer to the tool paths: the parent's own, not copies
        shared=tps,
        done=lambda k, i: say(done.format(name=names[k], k=i, n=n)),
    )
    return dict(zip(names, fitted, strict=True))
