"""Fitting an effect's parameters to the calibration data: a grid, then a local refinement.

An effect (:mod:`core.engine.effects`) is applied on top of a base setup; its parameters are
those that minimise the gap on the calibration data: the RMS gap over time of the feed
(:func:`core.diagnosis.resample.gap`), or another :class:`core.diagnosis.objective.Objective`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from core.diagnosis.objective import FEED, Objective
from core.diagnosis.rules import AT_BOUND, GRID_1D, GRID_2D, GRID_ND, REFINE
from core.engine.effects import Effect, Param, Setup
from core.engine.indicators import Indicator, IndicatorSource
from core.engine.predict import Prediction, predict, retimed, same_plan
from core.engine.profile import RoundsMemo
from core.model.machine import Machine
from core.model.tolerances import TOL
from core.model.toolpath import ToolPath

#: Plans (evaluations and profiles) a fit keeps for candidates that only change the
#: time-domain filters (servo lag, setpoint filter).
PLANS = 2


def points_1d(p: Param) -> int:
    """Points of ``p``'s 1-D search grid: its own, or GRID_1D."""
    return GRID_1D if p.points is None else p.points


def grid_points(group: Sequence[Param]) -> int:
    """Points per parameter of the search's grid over ``group``: a parameter's own 1-D grid
    alone, GRID_2D for two, GRID_ND for more."""
    if len(group) == 1:
        return points_1d(group[0])
    return GRID_2D if len(group) == 2 else GRID_ND


#: The most parameters an effect with stages searches its first stage over on a grid.
MESHED = 3


def _mesh(group: Sequence[Param], start: dict[str, float]) -> list[dict[str, float]]:
    """``start`` with every point of the grid over ``group`` (:func:`grid_points` a
    parameter), the first parameter varying slowest."""
    grids = [grid(p, grid_points(group)) for p in group]
    mesh = np.meshgrid(*grids, indexing="ij")
    names = [p.name for p in group]
    return [
        start | dict(zip(names, map(float, vals), strict=True))
        for vals in zip(*(g.ravel() for g in mesh), strict=True)
    ]


def grid(p: Param, count: int) -> NDArray[np.float64]:
    if p.log and p.low > 0:
        g = np.geomspace(p.low, p.high, count)
    else:
        g = np.linspace(p.low, p.high, count)
    if p.integer:
        g = np.unique(np.round(g))
    return g


def predict_all(
    indicators_of: IndicatorSource,
    tps: Sequence[ToolPath],
    setup: Setup,
    plans: list[tuple[Setup, list[Prediction]]] | None = None,
    *,
    keep: bool = True,
    memos: Sequence[RoundsMemo] | None = None,
) -> list[Prediction]:
    """The prediction of ``setup`` for every program. ``plans``: predictions made before
    (most recent last, kept to PLANS); one of a setup that plans alike (differs in the
    time-domain filters only) gives its evaluations and profiles, and this one is added;
    else one evaluated alike gives its profile (:func:`core.engine.predict.predict`).
    ``keep`` False: the plans only give profiles (the predictions are made again, and not
    added). ``memos``: each program's last jerk rounds (:class:`RoundsMemo`), which a
    profile with the same rounds' inputs takes."""
    if plans is not None and keep:
        for k in range(len(plans) - 1, -1, -1):
            setup_k, preds_k = plans[k]
            if same_plan(setup_k, setup):
                return [retimed(p, setup) for p in preds_k]
    earlier = plans or []
    preds = [
        predict(
            indicators_of,
            tp,
            setup,
            [p[i] for _, p in earlier],
            None if memos is None else memos[i],
        )
        for i, tp in enumerate(tps)
    ]
    if plans is not None and keep:
        plans.append((setup, preds))
        del plans[:-PLANS]
    return preds


def fit(
    indicators_of: IndicatorSource,
    tps: Sequence[ToolPath],
    base: Setup,
    eff: Effect,
    data: Sequence[Any],
    objective: Objective = FEED,
) -> tuple[dict[str, float], list[Prediction]]:
    """Parameters of ``eff`` (on top of ``base``) minimising the calibration gap of
    ``objective`` (``data``: what it measures, :class:`core.diagnosis.resample.Data` for the
    feed gap)."""
    m = base.machine
    defaults = eff.start(m)
    indicators_of = _remembered(indicators_of)
    # the gap and setup of every candidate scored (not its predictions: hundreds of
    # profiles; only those of the lowest gap so far, which is most often the fitted one,
    # are kept -- the others' are made again, the same, at the end)
    cache: dict[tuple, tuple[float, Setup]] = {}
    plans: list[tuple[Setup, list[Prediction]]] = []
    memos = [RoundsMemo() for _ in tps]
    lowest: list[tuple[tuple, float, list[Prediction]]] = []

    def score(values: dict[str, float]) -> float:
        key = _key(eff, values)
        if key not in cache:
            setup = eff.apply(base, values)
            preds = predict_all(indicators_of, tps, setup, plans, memos=memos)
            g = objective.gap(preds, data, "calibration")
            cache[key] = (g, setup)
            if not lowest or g < lowest[0][1]:
                lowest[:] = [(key, g, preds)]
        return cache[key][0]

    def result(best: dict[str, float]) -> tuple[dict[str, float], list[Prediction]]:
        """The fitted values and their predictions: those kept, or made again from the kept
        setup (the same values: a prediction is a function of its setup)."""
        key = _key(eff, best)
        if lowest and lowest[0][0] == key:
            return best, lowest[0][2]
        return best, predict_all(indicators_of, tps, cache[key][1], plans, keep=False, memos=memos)

    if not eff.params:
        score({})
        return result({})
    params = eff.params
    if eff.stages:
        # each end of the coarse search refined, the better one kept (ties: the first)
        ends = [_refined(eff, s, defaults, score) for s in _staged(eff, defaults, score)]
        return result(min(ends, key=score))
    candidates = _mesh(params, {})
    # Defaults first: among equal scores the effect changes nothing.
    candidates.insert(0, dict(defaults))
    best = min(candidates, key=score)
    if len(params) > 1:
        # The coarse mesh can straddle a limit that only acts below a threshold (an axis
        # speed under the programmed feed): scan each parameter on the fine 1-D grid, the
        # others held at the best so far.
        for p in params:
            line = [best | {p.name: float(x)} for x in grid(p, points_1d(p))]
            best = min([best, *line], key=score)
    return result(_refined(eff, best, defaults, score))


def scores_planned(eff: Effect) -> int:
    """About how many candidates :func:`fit` scores for ``eff`` (at most: the search's
    grids, lines and refinement rounds as they are laid out, before its cache finds
    repeats): what a fit costs, for running the longest first (:mod:`.parallel`)."""
    params = eff.params
    if not params:
        return 1
    lines = sum(points_1d(p) for p in params)
    refine = 2 * REFINE * len(params) + len(params)  # two trials a round, then the defaults
    if eff.stages:
        first = [p for p in params if p.name in eff.stages[0]]
        meshed = grid_points(first) ** len(first) if len(first) <= MESHED else 0
        later = lines - sum(points_1d(p) for p in first)
        # the first stage's grid and its lines twice; the later stages' lines twice from
        # each of the two ends; each end refined
        return 1 + meshed + 2 * (lines - later) + 2 * 2 * later + 2 * refine
    if len(params) == 1:
        return 1 + lines + refine
    return 1 + grid_points(params) ** len(params) + lines + refine


def _remembered(indicators_of: IndicatorSource) -> IndicatorSource:
    """``indicators_of`` that gives the indicators of the last tool path and machine again
    (the same objects: a look-ahead, path compression or acceleration share evaluates the
    same path on the same machine for every candidate), in a list of its own."""
    last: list[tuple[ToolPath, Machine, list[Indicator]]] = []

    def source(tp: ToolPath, machine: Machine) -> list[Indicator]:
        if last and last[0][0] is tp and last[0][1] is machine:
            return list(last[0][2])
        out = indicators_of(tp, machine)
        last[:] = [(tp, machine, list(out))]
        return out

    return source


def _staged(
    eff: Effect, defaults: dict[str, float], score: Callable[[dict[str, float]], float]
) -> list[dict[str, float]]:
    """The coarse search of an effect with stages: the first group on a grid (as a small
    effect is fitted), each later group one parameter at a time on its 1-D grid, twice.

    The later stages run twice: from the first stage's fit and from the defaults; both ends
    are returned (the first stage's first) for refinement. A coordinate search from the
    first stage's fit can be trapped there: a uniform acceleration scale of 0.25 stands for
    one slow Z axis on the calibration data, and no single axis's factor then undoes it for
    X and Y together (drawn8's thread_milling_80522, Z at 480 of 2000 mm/s^2: the uniform
    fit leaves 2.9 mm/min on the calibration data and raises the held-out gap from 45 to
    154; accel_z 0.24 alone leaves 1.7 and 27.8)."""
    by_name = {p.name: p for p in eff.params}

    def lines(best: dict[str, float], stages: tuple[tuple[str, ...], ...]) -> dict[str, float]:
        for stage in stages:
            for _ in range(2):
                for p in (by_name[n] for n in stage):
                    line = [best | {p.name: float(x)} for x in grid(p, points_1d(p))]
                    best = min([best, *line], key=score)
        return best

    first = [by_name[n] for n in eff.stages[0]]
    best = dict(defaults)
    if len(first) <= MESHED:
        best = min([best, *_mesh(first, best)], key=score)
    best = lines(best, eff.stages[:1])
    ends = [lines(best, eff.stages[1:])]
    if best != defaults and len(eff.stages) > 1:
        ends.append(lines(dict(defaults), eff.stages[1:]))
    return ends


def _refined(
    eff: Effect,
    best: dict[str, float],
    defaults: dict[str, float],
    score: Callable[[dict[str, float]], float],
) -> dict[str, float]:
    """Local refinement from ``best``, then parameters the data cannot see back to their
    defaults."""
    params = eff.params
    if eff.stages:
        # many parameters: refine those the coarse search moved (the others' 1-D scans
        # found nothing better than where they start)
        params = tuple(p for p in params if best[p.name] != defaults[p.name])
    # Local refinement, one parameter at a time: a bracket around the best value that halves
    # (in log space for log parameters) every round.
    brackets = {}
    for p in params:
        g = grid(p, points_1d(p))
        k = int(np.argmin(np.abs(g - best[p.name])))
        brackets[p.name] = (float(g[max(k - 1, 0)]), float(g[min(k + 1, g.size - 1)]))
    for _ in range(REFINE):
        for p in params:
            lo, hi = brackets[p.name]
            x = best[p.name]
            geo = p.log and p.low > 0
            mid = (lambda a, b: math.sqrt(a * b)) if geo else (lambda a, b: 0.5 * (a + b))
            y1, y2 = mid(lo, x), mid(x, hi)
            for y in (y1, y2):
                y = float(round(y)) if p.integer else float(y)
                trial = dict(best)
                trial[p.name] = min(max(y, p.low), p.high)
                if score(trial) < score(best):
                    best = trial
            x_new = best[p.name]
            # Shrink the bracket around the (possibly new) best.
            if x_new == x:
                brackets[p.name] = (y1, y2)
            elif x_new < x:
                brackets[p.name] = (lo, x)
            else:
                brackets[p.name] = (x, hi)
    # A parameter the data cannot see (a jerk scale on a machine without a jerk limit) goes
    # back to its default rather than report a value at random.
    for p in eff.params:
        trial = dict(best)
        trial[p.name] = defaults[p.name]
        if score(trial) <= score(best) * (1 + TOL.rel_equal):
            best = trial
    return best


def at_bound(p: Param, value: float, default: float | None = None) -> bool:
    """Whether a fitted value sits at one of the parameter's bounds (within AT_BOUND of its
    range; in log space for log parameters). A bound that is the parameter's ``default``
    (the value that changes nothing, e.g. a lag of 0 s) is where an unused part of the
    effect rests, not a stretched fit."""

    def pos(x: float) -> float:
        if p.log and p.low > 0 and x > 0:
            return (math.log(x) - math.log(p.low)) / (math.log(p.high) - math.log(p.low))
        return (x - p.low) / (p.high - p.low)

    if not (math.isfinite(p.high - p.low) and p.high > p.low):
        return False
    at_low, at_high = pos(value) <= AT_BOUND, pos(value) >= 1.0 - AT_BOUND
    if default is not None:
        at_low &= pos(default) > AT_BOUND
        at_high &= pos(default) < 1.0 - AT_BOUND
    return bool(at_low or at_high)


def bounded(eff: Effect, values: Mapping[str, float], machine: Machine) -> list[Param]:
    """The parameters of ``eff`` whose fitted ``values`` sit at a bound (:func:`at_bound`,
    a bound that is the parameter's default on ``machine`` not counted): the effect was
    stretched to its limit."""
    return [
        p
        for p in eff.params
        if p.name in values and at_bound(p, values[p.name], p.default_for(machine))
    ]


def _key(eff: Effect, values: dict[str, float]) -> tuple[float, ...]:
    """Where a fit keeps what it scored for ``values`` (equal to 12 decimals: one candidate)."""
    return tuple(round(values[p.name], 12) for p in eff.params)
