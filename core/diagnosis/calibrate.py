"""Calibrating a machine from measured traces (``ncperf calibrate``).

The diagnosis asks which ONE unmodelled effect explains a trace; calibration asks what the
machine IS: the controller's own values (per-axis speed, acceleration and jerk, block time,
path tolerance, path mode, path speed limit, the acceleration shares its planner keeps),
fitted on several programs or runs and checked on others.

1. The traces are resampled as for the diagnosis and cut into two folds: other programs
   (with two or more programs: every other program, whole), else other runs, else
   alternate stretches of the one run (:func:`folds`).
2. Forward selection on fold A: every controller effect is fitted on A's calibration part
   on top of what is already chosen, and the one that removes most of the held-out gap is
   added while it clears the diagnosis's test (:func:`core.diagnosis.diagnose.add_effects`,
   with CAL_ADD_SHARE of what is left) -- so an effect the data cannot see stays out.
3. The chosen effects are refitted, in the same order, with the folds swapped (fold B): two
   values of every parameter, each fitted on data the other was measured on.
4. The value written is their mean (geometric for scales), and its range is what the two
   folds and a scan of the whole data allow (the gap within RANGE_SHARE of its least). A
   documented value inside that range is written instead (the comment says so).
5. The noise floor is the held-out gap the calibrated machine leaves, fold by fold (each
   with its own fit): what a diagnosis with this machine must beat to name an effect.

What "gap" means is the objective's (:mod:`core.diagnosis.objective`): the feed gap (RMS over
time of measured - predicted feed, mm/min) for traces that sample the motion finely, or,
for recordings that sample it coarsely (MTConnect, every 0.1-0.2 s) and carry program
lines, the block-time error (RMS over windows of feed blocks of measured - predicted time
between observed line changes, ms; :mod:`core.diagnosis.blocktime`). ``objective="auto"``
chooses the block-time one when every trace carries lines and samples coarser than
COARSE_SAMPLING (:func:`choose_objective`); the floor of the test is then
BLOCK_FLOOR_SHARE of the measured intervals, and the noise floor (in ms) is reported but is
not the diagnosis's (which is a feed gap).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from core.diagnosis import blocktime
from core.diagnosis.align import Alignment
from core.diagnosis.blocktime import BlockData, block_data, has_lines, is_coarse, sample_period
from core.diagnosis.diagnose import add_effects, noise_floor
from core.diagnosis.fit import fit, predict_all
from core.diagnosis.objective import BLOCK_TIME, FEED, OBJECTIVES, Objective
from core.diagnosis.resample import Data, pieces, resample, split
from core.diagnosis.rules import COARSE_SAMPLING
from core.engine.effects import Effect, Setup
from core.engine.indicators import IndicatorSource
from core.engine.predict import Prediction
from core.model.errors import UsageError
from core.model.jit import allow
from core.model.tolerances import TOL
from core.model.toolpath import ToolPath
from core.model.workers import forked_map, workers_for

#: The effects that are what a controller does (a feed override is the operator's).
CONTROLLER_EFFECTS = (
    "axis_dynamics",
    "block_cycle_time",
    "corner_tolerance",
    "exact_stop",
    "path_feed_limit",
    "normal_acceleration_factor",
    "arc_acceleration",
    "last_block_acceleration",
    "servo_lag",
    "jerk_filter",
)
#: An effect joins while it removes at least this share of what is left (and the floor).
CAL_ADD_SHARE = 0.05
#: Most effects calibrated together.
CAL_MAX = 6
#: A parameter's range: values whose gap on all the data is within this share of the least
#: (or within the noise floor of it); found from a first step (a share of the parameter's
#: span, or of its value for log parameters) doubling outwards, then bisected.
RANGE_SHARE = 0.01
RANGE_FIRST_STEP = 0.005
RANGE_BISECT = 5


@dataclass(frozen=True)
class Calibrated:
    """One effect of the calibrated machine.

    Attributes
    ----------
    name : str
    params : {name: value}
        What is written (the folds' mean, or a documented value inside the range).
    folds : tuple of {name: value}
        The value fitted on each fold.
    ranges : {name: (low, high)}
    documented : {name: str}
        Where a written value is documented (parameters that took the documented value).
    gap_before, gap_after : float
        Held-out gap of fold A (the objective's unit) before and after this effect joined.
    """

    name: str
    params: dict[str, float]
    folds: tuple[dict[str, float], ...]
    ranges: dict[str, tuple[float, float]]
    documented: dict[str, str]
    gap_before: float
    gap_after: float


@dataclass(frozen=True, eq=False)
class Calibration:
    """The result of :func:`calibrate`.

    Attributes
    ----------
    effects : tuple of Calibrated
        In the order they joined.
    setup : Setup
        The start setup with every calibrated effect applied (the written values).
    held_out : str
        How the folds were made.
    gap_before, gap_after : tuple of float
        Held-out gap of each fold (the objective's unit), with the start machine and
        calibrated (each fold with its own fit).
    noise_floor : float
        The RMS of ``gap_after`` over the folds (the objective's unit).
    tried : tuple of str
        The effects tried.
    objective : Objective
        What the gaps are (:data:`core.diagnosis.objective.FEED` or ``BLOCK_TIME``).
    objective_reason : str
        Why that one, in one phrase.
    compared : int
        Samples the gaps are over: grid points (feed) or intervals (block time).
    """

    effects: tuple[Calibrated, ...]
    setup: Setup
    held_out: str
    gap_before: tuple[float, ...]
    gap_after: tuple[float, ...]
    noise_floor: float
    tried: tuple[str, ...]
    objective: Objective = FEED
    objective_reason: str = ""
    compared: int = 0


def _size(d: Data | BlockData) -> int:
    return int(d.first.size if isinstance(d, BlockData) else d.s.size)


def folds(data: Sequence[Any]) -> tuple[list[Any], list[Any], str]:
    """Two folds (calibration / held-out masks swapped between them) of resampled feeds
    (:class:`Data`) or block intervals (:class:`BlockData`); see the module docstring."""
    programs = sorted({d.case for d in data})
    block = bool(data) and isinstance(data[0], BlockData)
    if len(programs) >= 2:
        a = [
            dataclasses.replace(
                d,
                calibration=np.full(_size(d), d.case % 2 == 0),
                chunk=d.chunk if block else pieces(d),
            )
            for d in data
        ]
        how = (
            f"other programs: {len(programs)} programs, every other one fitted and the others "
            "measured, then the other way round"
        )
    else:
        a, how = blocktime.split(data) if block else split(data)
        how += ", then the other way round"
    b = [dataclasses.replace(d, calibration=~d.calibration) for d in a]
    return a, b, how


def choose_objective(name: str, alignments: Sequence[Alignment]) -> tuple[Objective, str]:
    """The objective to calibrate on and why: ``name`` "feed" or "block-time" as asked, or
    "auto": block time when every trace carries program lines and samples coarser than
    COARSE_SAMPLING, else the feed gap."""
    if name not in ("auto", *OBJECTIVES):
        raise UsageError(f"unknown objective '{name}' (auto, {', '.join(OBJECTIVES)})")
    periods = [sample_period(al) for al in alignments]
    fine = [p for p in periods if p <= COARSE_SAMPLING]
    period = f"{(max(fine) if fine else min(periods, default=0.0)) * 1000:.0f} ms"
    if name == "block-time":
        if not all(has_lines(al) for al in alignments):
            raise UsageError(
                "the block-time objective needs traces with program lines (a line column, "
                "MTConnect Block_Number)"
            )
        return BLOCK_TIME, "asked for"
    if name == "feed":
        return FEED, "asked for"
    if is_coarse(alignments):
        return BLOCK_TIME, (
            f"chosen: the traces carry program lines and sample every {period} or more "
            f"(median), coarser than {COARSE_SAMPLING * 1000:g} ms"
        )
    if not all(has_lines(al) for al in alignments):
        return FEED, "chosen: not every trace carries program lines"
    return FEED, (
        f"chosen: the traces sample every {period} or finer (median), "
        f"not coarser than {COARSE_SAMPLING * 1000:g} ms"
    )


def _refit(
    indicators_of: IndicatorSource,
    tps: Sequence[ToolPath],
    base: Setup,
    preds: list[Prediction],
    effects: Mapping[str, Effect],
    names: Sequence[str],
    data: Sequence[Any],
    objective: Objective = FEED,
) -> tuple[list[dict[str, float]], list[Prediction]]:
    """The named effects fitted in order on one fold on top of ``base`` (whose predictions
    are ``preds``); the params and the last predictions."""
    current = base
    out = []
    for name in names:
        params, preds = fit(indicators_of, tps, current, effects[name], data, objective)
        out.append(params)
        current = effects[name].apply(current, params)
    return out, preds


def _mean(eff: Effect, values: Sequence[Mapping[str, float]]) -> dict[str, float]:
    out = {}
    for p in eff.params:
        xs = [float(v[p.name]) for v in values]
        if p.log and min(xs) > 0:
            m = math.exp(sum(math.log(x) for x in xs) / len(xs))
        else:
            m = sum(xs) / len(xs)
        out[p.name] = float(round(m)) if p.integer else m
    return out


def calibrate(
    indicators_of: IndicatorSource,
    cases: Sequence[tuple[ToolPath, Sequence[Alignment], Sequence[str]]],
    base: Setup,
    effects: Mapping[str, Effect],
    objective: str = "auto",
    *,
    jobs: int = 1,
    progress: Callable[[str], None] | None = None,
) -> Calibration:
    """Calibrate the machine of ``base`` on the programs and their aligned traces (see the
    module docstring); ``effects``: those that may be calibrated; ``objective``: "auto",
    "feed" or "block-time" (:func:`choose_objective`); ``jobs``: worker processes for the
    fits of each round of the forward selection and the scans of the parameters' ranges
    (the same calibration whatever their number, :mod:`core.model.workers`); ``progress``,
    if given, is told those fits."""
    allow()  # the compiled kernels where numba is installed (core.model.jit)
    tps = [tp for tp, _, _ in cases]
    obj, reason = choose_objective(objective, [al for _, als, _ in cases for al in als])
    data: list[Any]
    if obj is BLOCK_TIME:
        data = [
            block_data(tp, al, lab, case=k)
            for k, (tp, als, labs) in enumerate(cases)
            for al, lab in zip(als, labs, strict=True)
        ]
        if not data or all(d.first.size == 0 for d in data):
            raise UsageError(
                "no feed-block intervals between observed program-line changes to calibrate on"
            )
    else:
        data = [
            resample(tp, al, lab, case=k)
            for k, (tp, als, labs) in enumerate(cases)
            for al, lab in zip(als, labs, strict=True)
        ]
        if not data or all(d.s.size == 0 for d in data):
            raise UsageError("no measured feed moves to calibrate on")
    fold_a, fold_b, how = folds(data)
    floor = blocktime.floor(fold_a) if obj is BLOCK_TIME else noise_floor(base, fold_a)[0]
    before = predict_all(indicators_of, tps, base)
    chosen, _, preds_a = add_effects(
        indicators_of,
        tps,
        base,
        before,
        effects,
        fold_a,
        floor,
        share=CAL_ADD_SHARE,
        most=CAL_MAX,
        objective=obj,
        progress=progress,
        jobs=jobs,
    )
    names = [c[0] for c in chosen]
    params_b, preds_b = _refit(indicators_of, tps, base, before, effects, names, fold_b, obj)
    gaps_before = (obj.gap(before, fold_a, "held_out"), obj.gap(before, fold_b, "held_out"))
    gaps_after = (obj.gap(preds_a, fold_a, "held_out"), obj.gap(preds_b, fold_b, "held_out"))

    # The written values, their ranges, documented values inside them.
    everything = [dataclasses.replace(d, calibration=np.ones(_size(d), dtype=bool)) for d in data]
    final = base
    out = []
    for k, (name, params_a, g0, g1) in enumerate(chosen):
        eff = effects[name]
        values = _mean(eff, [params_a, params_b[k]])
        ranges: dict[str, tuple[float, float]] = {}
        documented: dict[str, str] = {}
        if eff.params:
            ranges = _ranges(indicators_of, tps, final, eff, values, everything, floor, obj, jobs)
            for p in eff.params:
                lo = min(ranges[p.name][0], params_a[p.name], params_b[k][p.name])
                hi = max(ranges[p.name][1], params_a[p.name], params_b[k][p.name])
                ranges[p.name] = (lo, hi)
            for pname, value, where in eff.documented:
                lo, hi = ranges[pname]
                if lo <= value <= hi:
                    values[pname] = value
                    documented[pname] = where
        final = eff.apply(final, values)
        out.append(
            Calibrated(
                name=name,
                params=values,
                folds=(dict(params_a), dict(params_b[k])),
                ranges=ranges,
                documented=documented,
                gap_before=g0,
                gap_after=g1,
            )
        )
    floor_value = math.sqrt(sum(g * g for g in gaps_after) / len(gaps_after))
    return Calibration(
        effects=tuple(out),
        setup=final,
        held_out=how,
        gap_before=gaps_before,
        gap_after=gaps_after,
        noise_floor=floor_value,
        tried=tuple(effects),
        objective=obj,
        objective_reason=reason,
        compared=sum(_size(d) for d in data),
    )


def _ranges(
    indicators_of: IndicatorSource,
    tps: Sequence[ToolPath],
    base: Setup,
    eff: Effect,
    values: Mapping[str, float],
    data: Sequence[Any],
    floor: float,
    objective: Objective = FEED,
    jobs: int = 1,
) -> dict[str, tuple[float, float]]:
    """Per parameter (the others at ``values``): the values around the written one whose
    gap on all the data is within RANGE_SHARE of its gap, or within the noise floor of it
    (values the data cannot tell apart): steps doubling outwards until one is out, then
    bisection of the edge (RANGE_BISECT rounds). The parameters are scanned on ``jobs``
    worker processes where it can (each scan on its own: the same ranges)."""

    def scan(k: int) -> tuple[float, float]:
        p = eff.params[k]
        v0 = float(values[p.name])

        def gap_at(x: float) -> float:
            preds = predict_all(indicators_of, tps, eff.apply(base, dict(values) | {p.name: x}))
            return objective.gap(preds, data, "calibration")

        g0 = gap_at(v0)
        limit = g0 + max(RANGE_SHARE * g0, floor) + TOL.float_slack
        log = p.log and v0 > 0 and p.low > 0
        edges = []
        for sign in (-1.0, 1.0):
            inside, step, edge = v0, RANGE_FIRST_STEP, None
            while True:
                x = v0 * math.exp(sign * step) if log else v0 + sign * step * (p.high - p.low)
                x = min(max(x, p.low), p.high)
                if gap_at(x) > limit:
                    edge = x
                    break
                inside = x
                if x in (p.low, p.high):
                    break
                step *= 2.0
            if edge is not None:
                for _ in range(RANGE_BISECT):
                    mid = math.sqrt(inside * edge) if log else 0.5 * (inside + edge)
                    if gap_at(mid) > limit:
                        edge = mid
                    else:
                        inside = mid
            edges.append(inside)
        return min(edges), max(edges)

    n = len(eff.params)
    workers = workers_for(jobs, n)
    spans = forked_map(scan, n, workers) if workers > 1 else [scan(k) for k in range(n)]
    return {p.name: span for p, span in zip(eff.params, spans, strict=True)}
