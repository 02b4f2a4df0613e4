"""Sim-to-real gap diagnosis: where the prediction misses a measured trace, which unmodelled
effect explains it, and how far the gap shrinks once that effect is modelled.

1. Every trace is aligned with the program (:mod:`core.diagnosis.align`); its feed is
   resampled on the arc length of the feed moves every ``STEP`` mm
   (:mod:`core.diagnosis.resample`).
2. The gap is the measured minus the predicted feed there (mm/min in reports), its RMS taken
   over time: every grid point weighs the time the machine spends there (step / measured
   feed, floored at 2 % of F), so that slow stretches -- where the time goes -- count as
   long as they last, not as long as they are. The gap map
   lists the stretches where it exceeds GAP_SHARE of the programmed feed: program lines, arc
   lengths, what is there, RMS gap, seconds lost or gained.
3. Every effect (:mod:`core.engine.effects`) has its parameters fitted on calibration data -- the
   even-numbered traces when there are several (other runs or programs), else alternate
   stretches of one run -- and its gap measured on the held-out data it was not fitted on.
4. An effect is named from the evidence of the held-out stretches (:func:`decide`; the
   constants are in :mod:`core.diagnosis.rules`): it must reduce the squared gap on them
   significantly (a sign-flip test over pieces of the held-out stretches, p <= SIG_P), by more than
   the noise floor (the machine file's, from ``ncperf calibrate``, else estimated from the
   trace, and never under MIN_FEED_SHARE of F) and by at least BEST_SHARE of the gap (or,
   where it removes most of the gap -- MOST_SHARE -- significantly, by MOST_FLOOR of the
   floor: no patch for what the model leaves out does that; or most of it on every one of
   too few pieces for the test, by FEW_FLOOR of the floor; or nearly all of it --
   NEAR_ALL_SHARE -- by NEAR_ALL_FLOOR of the floor, however few the pieces); an effect
   whose fit left every parameter at the machine file's value (a block time of 1.00 ms
   where the file says 1.02) is not named, whatever it removes; nor is one whose fit
   leaves the rapids more than twice as far off as the model without an effect, and the
   floor more (RAPIDS_CONTRADICT: it explains the feed moves with a machine the rapids show
   is not there). Among
   the effects that clear it, those not significantly worse than the best, or leaving a gap
   within TIE_SHARE of its gap, are equally good: the rapids (which only the effects that
   act on them are fitted on, on their calibration half) drop those they show wrong (a
   rapid gap over twice the least and the floor); then one the machine file does not set,
   one whose fit did not run to a bound, the one with the fewest parameters the data moved
   and the first in EFFECT_PRIORITY (then the least held-out gap) are named, in that order.
   Where nothing clears the test on the feed moves, the effects that also act on the rapids
   (an axis's speed or acceleration, a path speed cap) are fitted on alternate rapids and
   one is named by the same test on the other rapids, with the rapids' own floor, unless
   the feed moves contradict it (:func:`_on_rapids`).
   Where the machine's traces sample once per controller cycle (``[diagnosis]
   trace_cycle`` in its file: LinuxCNC's sampler runs on the servo thread) and these
   sample at another period, the controller ran with that cycle: block_cycle_time at the
   block time it gives is named first, read rather than fitted, unless the feed moves
   contradict it (:func:`_on_clock`); the other effects are then added on top as below.
   "None" is an answer: the model already explains the trace, or what is left is noise or
   an effect not in the list. Effects are then added greedily while each
   clears the same test on what is left (ADD_SHARE of it), until less than STOP_SHARE of the
   gap before is left.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from core.diagnosis.align import Alignment
from core.diagnosis.fit import bounded, predict_all
from core.diagnosis.gaps import GapZone, gap_zones
from core.diagnosis.objective import FEED, Objective
from core.diagnosis.parallel import fit_and_weigh, fit_each
from core.diagnosis.resample import (
    Data,
    feed_level,
    gap,
    held_out_chunks,
    held_out_speeds,
    rapid_data,
    rapid_gap,
    resample,
    split,
    trace_noise,
)
from core.diagnosis.rules import (
    ADD_SHARE,
    BEST_SHARE,
    CLEAR_FLOOR,
    CLEAR_P,
    CLEAR_SHARE,
    CLOCK_JITTER,
    CLOCK_REGULAR,
    CLOCK_SHARE,
    EFFECT_PRIORITY,
    FEW_FLOOR,
    FEW_P,
    GAP_COLOURS,
    GAP_EDGES,
    GAP_LABELS,
    MAX_CHOSEN,
    MIN_FEED_SHARE,
    MOST_FLOOR,
    MOST_SHARE,
    NEAR_ALL_FLOOR,
    NEAR_ALL_SHARE,
    NOISE_K,
    PER_MIN,
    RAPIDS_CONTRADICT,
    SIG_P,
    SIGN_FLIPS,
    STOP_SHARE,
    STRONG_K,
    TIE_P,
    TIE_SHARE,
)
from core.engine.effects import MOVED_SHARE, Effect, Setup
from core.engine.indicators import IndicatorSource
from core.engine.predict import Prediction
from core.model.jit import allow
from core.model.machine import Machine
from core.model.tolerances import TOL
from core.model.toolpath import ToolPath
from core.view.annotations import Annotations
from core.view.targets import file_target

#: Progress lines of the forward selection (:func:`add_effects`, formats of
#: :func:`core.diagnosis.parallel.fit_each`): as each fit starts, as the fits of a round
#: start on worker processes, as each of those ends.
COMBINE_STEP = "combining effects: fitting {name} on top of the chosen ones"
COMBINE_START = (
    "combining effects: fitting {n} effects on top of the chosen ones, on {workers} processes"
)
COMBINE_DONE = "combining effects: fitted {name} on top of the chosen ones ({k} of {n})"


@dataclass(frozen=True)
class EffectResult:
    name: str
    params: dict[str, float]
    held_out_gap_before: float  # mm/min
    held_out_gap_after: float
    calibration_gap_after: float
    #: parameters the fit moved from where it started (the effect's size on this data)
    moved: int = 0
    #: p value of the squared-gap reduction over the held-out pieces (sign-flip test)
    p: float = 1.0
    #: squared gap per held-out piece ((mm/min)^2 s), for comparing effects pairwise
    chunk_sq: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0), repr=False)
    #: RMS gap on all the rapids (mm/min; NaN: the traces cover none): the effects that act
    #: on the rapids are fitted on their calibration half, the others on none of them
    rapid_gap: float = math.nan

    @property
    def removed(self) -> float:
        b = self.held_out_gap_before
        return (b - self.held_out_gap_after) / b if b > 0 else 0.0


@dataclass(frozen=True, eq=False)
class Diagnosis:
    baseline: str
    held_out: str
    gap_rms_before: float
    zones: tuple[GapZone, ...]
    effects: tuple[EffectResult, ...]
    best_effect: str | None
    chosen: tuple[str, ...]
    chosen_params: dict[str, dict[str, float]]
    gap_rms_after: float
    zones_after: tuple[GapZone, ...]
    alignments: tuple[Alignment, ...]
    data: tuple[Data, ...] = field(repr=False)
    befores: tuple[Prediction, ...] = field(repr=False)
    afters: tuple[Prediction, ...] = field(repr=False)
    #: the floor an effect had to clear (mm/min) and where it came from
    floor: float = 0.0
    floor_source: str = ""
    #: why the best effect was (or was not) named, in one sentence
    reason: str = ""
    #: where the feed moves showed no effect: the effects that act on the rapids too,
    #: fitted on alternate rapids, their gaps those of the other rapids (mm/min), ranked;
    #: the floor there, and whether the named effect was found there
    rapid_effects: tuple[EffectResult, ...] = ()
    rapid_floor: float = math.nan
    on_rapids: bool = False
    #: the period the traces are sampled at (s; NaN: irregular, or the traces disagree)
    sample_cycle: float = math.nan
    #: where the machine's traces sample its cycle and these ran with another
    #: (:func:`_on_clock`): block_cycle_time at the block time that cycle gives, its evidence
    #: on the held-out feed moves (not fitted), and whether it was named from the clock
    clock: EffectResult | None = None
    on_clock: bool = False

    @property
    def clock_agrees(self) -> bool:
        """Whether the traces' sample clock says the cycle the machine file says
        (:func:`clock_agrees`): block_cycle_time is then not named from a fit."""
        return clock_agrees(self.before.setup.machine, self.sample_cycle)

    @property
    def before(self) -> Prediction:
        """The baseline prediction of the (first) program."""
        return self.befores[0]

    @property
    def after(self) -> Prediction:
        """The prediction with the chosen effects, of the (first) program."""
        return self.afters[0]

    def move_gap(self, case: int = 0) -> NDArray[np.float64]:
        """(n,) mean (measured - predicted) / F of each move over the data; NaN where none."""
        tp = self.befores[case].toolpath
        num = np.zeros(tp.n)
        cnt = np.zeros(tp.n)
        for d in self.data:
            if d.case != case:
                continue
            r = (d.v - self.befores[case].speed_at(d.s, commanded=d.commanded)) / d.feed
            np.add.at(num, d.move, r)
            np.add.at(cnt, d.move, 1.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(cnt > 0, num / cnt, np.nan)

    def annotations(self) -> Annotations:
        """The path classed by gap, for the displays (no discontinuity markers)."""
        tp = self.before.toolpath
        g = self.move_gap()
        cls = np.searchsorted(np.asarray(GAP_EDGES), np.nan_to_num(g), side="right")
        cls = np.where(np.isnan(g) | ~tp.is_feed, -1, cls).astype(np.int8)
        z = np.zeros(0, dtype=np.int64)
        return Annotations(
            title=tp.source,
            machine=self.before.setup.machine.name,
            move_class=cls.astype(np.int8),
            junction=z,
            junction_class=z.astype(np.int8),
            junction_feed=z.astype(float),
            junction_reduction=z.astype(float),
            junction_cause=z,
            junction_limit=z,
            length_class=np.full(tp.n, -1, dtype=np.int8),
            zones=(),
            indicator_names=(),
            indicator_counts=(),
            labels=(),
            class_labels=GAP_LABELS,
            class_colours=GAP_COLOURS,
        )


def diagnose(
    indicators_of: IndicatorSource,
    tp: ToolPath,
    alignments: Sequence[Alignment],
    labels: Sequence[str],
    base: Setup,
    baseline: str,
    effects: Mapping[str, Effect],
) -> Diagnosis:
    """The diagnosis of one program against its aligned traces (see the module docstring)."""
    return diagnose_cases(indicators_of, [(tp, alignments, labels)], base, baseline, effects)


def diagnose_cases(
    indicators_of: IndicatorSource,
    cases: Sequence[tuple[ToolPath, Sequence[Alignment], Sequence[str]]],
    base: Setup,
    baseline: str,
    effects: Mapping[str, Effect],
    progress: Callable[[str], None] | None = None,
    *,
    jobs: int = 1,
) -> Diagnosis:
    """The diagnosis of several programs, each with its aligned traces, on one machine:
    effects are fitted on some traces and measured on the others (see the module docstring).
    ``progress``, if given, is told what is being done (one short line per step); ``jobs``:
    the worker processes the independent fits may run on (:mod:`core.diagnosis.parallel`;
    the diagnosis is the same whatever their number)."""
    allow()  # the compiled kernels where numba is installed (core.model.jit)
    tps = [tp for tp, _, _ in cases]
    data = [
        resample(tp, al, lab, case=k)
        for k, (tp, als, labs) in enumerate(cases)
        for al, lab in zip(als, labs, strict=True)
    ]
    data, held_out = split(data)
    before = predict_all(indicators_of, tps, base)
    g_before_all = gap(before, data, "all")
    g_before = gap(before, data, "held_out")
    # the effects that act on the rapids are fitted on the calibration rapids too: an axis
    # limit fitted on the feed moves alone may slow the rapids where the trace shows none
    rdata, _ = rapid_data(data)
    weigh = _weigher(effects, base, before, g_before, data, lambda preds: rapid_gap(preds, data))
    fitted, results = _fitted_and_weighed(
        fit_and_weigh(
            indicators_of, tps, base, effects, data, weigh, jobs=jobs, progress=progress,
            rapids=rdata,
        )
    )  # fmt: skip
    floor, floor_source = noise_floor(base, data)
    # effects whose values the machine file sets (absolute, not a further factor on top)
    folded = frozenset(
        name
        for name, _, _ in base.machine.effects
        if name in effects and not effects[name].relative
    )
    # effects whose fit ran to a bound of a parameter: stretched to cover for something else
    stretched = frozenset(
        r.name for r in results if bounded(effects[r.name], r.params, base.machine)
    )
    idle = _idle(indicators_of, tps, base, effects, results, before, data, floor)
    cycle = sample_cycle([al.t for _, als, _ in cases for al in als])
    # where the clock says the cycle is the machine file's, so is the block time: a fit of
    # another one patches something else and is not named (it stays in the table, last)
    read = frozenset({"block_cycle_time"}) if clock_agrees(base.machine, cycle) else frozenset()
    ranked, best, reason = decide(
        [r for r in results if r.name not in read],
        floor,
        folded,
        stretched,
        idle,
        rapid_before=rapid_gap(before, data),
    )
    results = ranked + [r for r in results if r.name in read]
    clock, clock_preds, clock_why = _on_clock(
        indicators_of, tps, base, effects, cycle, before, g_before, data, floor
    )

    chosen: list[str] = []
    chosen_params: dict[str, dict[str, float]] = {}
    current_preds = before
    rapid_results: list[EffectResult] = []
    floor_r = math.nan
    on_rapids = False
    on_clock = clock is not None and clock_preds is not None
    # the first effect named, where the others are fitted on top of it: its parameters, its
    # predictions and the others in the order they are tried
    first: tuple[dict[str, float], list[Prediction], dict[str, Effect]] | None = None
    if clock is not None and clock_preds is not None:
        # a cycle read off the trace's clock comes first
        best = clock.name
        reason = f"{clock_why}; on the feed moves alone, {reason.removeprefix('none: ')}"
        first = (clock.params, clock_preds, {n: e for n, e in effects.items() if n != best})
    elif best is None:
        rapid_results, floor_r, named, why = _on_rapids(
            indicators_of, tps, base, effects, data, rdata, before, floor, folded, progress, jobs
        )
        if named is not None:
            best, on_rapids = named[0], True
            reason = f"{why}; on the feed moves alone, {reason.removeprefix('none: ')}"
            chosen.append(best)
            chosen_params[best] = named[1]
            current_preds = named[2]
    else:
        others = {r.name: effects[r.name] for r in results if r.name not in read | {best}}
        first = (fitted[best][0], fitted[best][1], others)
    if clock_why and not on_clock:  # what the clock said, and why it was not named
        reason = f"{reason}; {clock_why}"
    if first is not None and best is not None:
        params, preds, others = first
        chosen.append(best)
        chosen_params[best] = params
        added, _, current_preds = add_effects(
            indicators_of,
            tps,
            effects[best].apply(base, params),
            preds,
            others,
            data,
            floor,
            share=ADD_SHARE,
            most=MAX_CHOSEN - 1,
            stop=STOP_SHARE * g_before,
            progress=progress,
            jobs=jobs,
            rapids=rdata,
        )
        for name, p, _, _ in added:
            chosen.append(name)
            chosen_params[name] = p
    return Diagnosis(
        baseline=baseline,
        held_out=held_out,
        gap_rms_before=g_before_all,
        zones=gap_zones(before, data),
        effects=tuple(results),
        best_effect=best,
        chosen=tuple(chosen),
        chosen_params=chosen_params,
        gap_rms_after=gap(current_preds, data, "all"),
        zones_after=gap_zones(current_preds, data),
        alignments=tuple(al for _, als, _ in cases for al in als),
        data=tuple(data),
        befores=tuple(before),
        afters=tuple(current_preds),
        floor=floor,
        floor_source=floor_source,
        reason=reason,
        rapid_effects=tuple(rapid_results),
        rapid_floor=floor_r,
        on_rapids=on_rapids,
        sample_cycle=cycle,
        clock=clock,
        on_clock=on_clock,
    )


def sample_cycle(times: Sequence[NDArray[np.float64]]) -> float:
    """The period (s) every trace of ``times`` samples at, where each samples regularly
    (CLOCK_REGULAR of its steps within CLOCK_JITTER of their median) and they agree within
    CLOCK_SHARE; else NaN. Two steps at least."""
    periods = []
    for t in times:
        dt = np.diff(np.asarray(t, dtype=np.float64))
        if dt.size < 2:
            return math.nan
        med = float(np.median(dt))
        if med <= 0 or np.mean(np.abs(dt - med) <= CLOCK_JITTER) < CLOCK_REGULAR:
            return math.nan
        periods.append(med)
    if not periods or max(periods) > min(periods) * (1.0 + CLOCK_SHARE):
        return math.nan
    return float(np.mean(periods))


def clock_agrees(machine: Machine, cycle: float) -> bool:
    """Whether traces sampled every ``cycle`` s ran with the cycle ``machine``'s file says
    its traces sample (``Machine.trace_cycle``, within CLOCK_SHARE): then its block time is
    the file's. False where either is unknown."""
    t = machine.trace_cycle
    return math.isfinite(cycle) and math.isfinite(t) and abs(cycle / t - 1.0) <= CLOCK_SHARE


def _on_clock(
    indicators_of: IndicatorSource,
    tps: Sequence[ToolPath],
    base: Setup,
    effects: Mapping[str, Effect],
    cycle: float,
    before: Sequence[Prediction],
    g_before: float,
    data: Sequence[Data],
    floor: float,
) -> tuple[EffectResult | None, list[Prediction] | None, str]:
    """The controller cycle read off the traces' sample clock. A machine whose traces sample
    once per cycle (``Machine.trace_cycle``: LinuxCNC's sampler on the servo thread) and a
    trace sampled every ``cycle`` s that differs from it by more than CLOCK_SHARE: the
    controller ran with that cycle, and its blocks last at least the machine's block time
    scaled by the ratio (LinuxCNC: 1.02 servo periods, tp.c TP_MIN_SEGMENT_CYCLES). That
    is a measurement, not a fit: block_cycle_time at that block time is named before the
    evidence of the feed moves is weighed -- which is why: a servo period of 1.5-4.5 ms
    moves LinuxCNC's feed time by under 0.5 % on engravings, domes and free-form chord
    paths (the blind benchmark's drawn18/19: 10 of 24 servo periods named nothing or a
    filter) -- unless the feed moves contradict it (its held-out gap worse by more than the
    floor). Returns the effect's evidence on the held-out feed moves (None where the clock
    says nothing), its predictions where it is named (else None), and a sentence."""
    m = base.machine
    eff = effects.get("block_cycle_time")
    if (
        eff is None
        or not (math.isfinite(cycle) and math.isfinite(m.trace_cycle))
        or clock_agrees(m, cycle)
    ):
        return None, None, ""
    ratio = cycle / m.trace_cycle
    t_file = eff.start(m)["t_block"]
    params = {"t_block": t_file * ratio}
    preds = predict_all(indicators_of, tps, eff.apply(base, params))
    (r,) = _evidence(
        {eff.name: eff},
        base,
        {eff.name: (params, preds)},
        before,
        g_before,
        data,
        lambda p: rapid_gap(p, data),
    )
    said = (
        f"the traces sample every {cycle * 1e3:.4g} ms, this machine's traces once per cycle "
        f"of {m.trace_cycle * 1e3:.4g} ms: blocks of at least {params['t_block'] * 1e3:.4g} ms "
        f"({t_file * 1e3:.4g} ms x {ratio:.3g})"
    )
    gaps = f"held-out gap {g_before:.1f} -> {r.held_out_gap_after:.1f} mm/min"
    if r.held_out_gap_after - g_before > floor:
        return r, None, f"{said}, but that makes the {gaps} (floor {floor:.1f}): not named"
    return r, preds, f"{eff.name} from the sample clock: {said}; {gaps}"


def _on_rapids(
    indicators_of: IndicatorSource,
    tps: Sequence[ToolPath],
    base: Setup,
    effects: Mapping[str, Effect],
    data: Sequence[Data],
    rdata: Sequence[Data],
    before: Sequence[Prediction],
    floor: float,
    folded: frozenset[str],
    progress: Callable[[str], None] | None,
    jobs: int,
) -> tuple[list[EffectResult], float, tuple[str, dict[str, float], list[Prediction]] | None, str]:
    """Where the feed moves show no effect, the rapids may: an axis's acceleration or speed
    that the cutting feeds hardly meet, a path speed cap above them. The effects that act on
    the rapids too (``Effect.rapids``) are fitted on alternate rapids of every run and
    measured on the others (:func:`core.diagnosis.resample.rapid_data`), and one is named
    by the same rule as on the feed moves (:func:`decide`, with the rapids' own floor:
    MIN_FEED_SHARE of the fastest measured rapid at least), provided it leaves the feed
    moves' held-out gap within the feed floor of where it was -- a fit on the rapids that
    the feed moves contradict names nothing. Development data (LinuxCNC, seeds 990000+):
    a Z acceleration of 790 mm/s^2 on thread milling shows 26 ms on the feed moves and
    159 ms on the Z rapids; fitted there, accel_z 0.39 (true 0.395) leaves 12 of 967 mm/min.
    Returns the results ranked, the rapids' floor, (name, parameters, predictions) of the
    named effect or None, and the reason."""
    on = {name: eff for name, eff in effects.items() if eff.rapids}
    if not on or not rdata or not any((~d.calibration).any() for d in rdata):
        return [], math.nan, None, ""
    if progress is not None:
        progress("the feed moves show no effect: fitting the axes' limits on the rapids")
    g_feed = gap(before, data, "held_out")
    # (``rapid_gap`` here: the feed moves' held-out gap, which these fits did not see)
    weigh = _weigher(
        on, base, before, gap(before, rdata, "held_out"), rdata,
        lambda preds: gap(preds, data, "held_out"),
    )  # fmt: skip
    fitted, results = _fitted_and_weighed(
        fit_and_weigh(indicators_of, tps, base, on, rdata, weigh, jobs=jobs, progress=progress)
    )
    floor_r, _ = noise_floor(base, rdata)
    contradicted = frozenset(r.name for r in results if r.rapid_gap - g_feed > floor)
    idle = _idle(indicators_of, tps, base, on, results, before, rdata, floor_r)
    stretched = frozenset(r.name for r in results if bounded(on[r.name], r.params, base.machine))
    ranked, best, why = decide(
        [r for r in results if r.name not in contradicted],
        floor_r,
        folded,
        stretched,
        idle,
        near_all=False,
    )
    ranked += [r for r in results if r.name in contradicted]
    if best is None:
        return ranked, floor_r, None, ""
    r = ranked[0]
    why = (
        f"{best} on the rapids: removes {r.removed:.0%} of the held-out rapids' gap "
        f"({r.held_out_gap_before:.0f} -> {r.held_out_gap_after:.0f} mm/min, p = {r.p:.2g}, "
        f"floor {floor_r:.0f} mm/min) and leaves the feed moves' held-out gap at "
        f"{r.rapid_gap:.1f} mm/min (before {g_feed:.1f})"
    )
    return ranked, floor_r, (best, fitted[best][0], fitted[best][1]), why


def clears(
    g_before: float, g_after: float, p: float, floor: float, share: float, *, near_all: bool = True
) -> bool:
    """The test an effect must pass to be named or added (mm/min RMS held-out gaps before and
    after it, and the p value of the reduction): it removes at least ``share`` of the gap,
    at least the floor, and significantly -- p <= SIG_P, or STRONG_K times the floor where
    it shows in too few places for the test; or CLEAR_SHARE of the gap at p <= CLEAR_P and
    CLEAR_FLOOR of the floor; or MOST_SHARE of the gap at p <= SIG_P and MOST_FLOOR of the
    floor, or at p <= FEW_P (the least the test gives on five pieces) and FEW_FLOOR of it;
    or NEAR_ALL_SHARE of the gap and NEAR_ALL_FLOOR of the floor, at any p (``near_all``:
    this last clause is tried)."""
    gain = g_before - g_after
    if not (g_before > 0 and gain / g_before >= share):
        return False
    if gain >= floor and (p <= SIG_P or gain >= STRONG_K * floor):
        return True
    # a large share of the gap, removed far beyond chance: half the floor will do
    if gain / g_before >= CLEAR_SHARE and p <= CLEAR_P and gain >= CLEAR_FLOOR * floor:
        return True
    # most of the gap, significantly: no patch for what the model leaves out does that
    if gain / g_before >= MOST_SHARE and p <= SIG_P and gain >= MOST_FLOOR * floor:
        return True
    # most of the gap where too few pieces show it for SIG_P (2^-n on n pieces): half the floor
    if gain / g_before >= MOST_SHARE and p <= FEW_P and gain >= FEW_FLOOR * floor:
        return True
    # nearly all of it, predicted where it lies from other stretches, however few the pieces
    return near_all and gain / g_before >= NEAR_ALL_SHARE and gain >= NEAR_ALL_FLOOR * floor


def add_effects(
    indicators_of: IndicatorSource,
    tps: Sequence[ToolPath],
    current: Setup,
    preds: list[Prediction],
    effects: Mapping[str, Effect],
    data: Sequence[Any],
    floor: float,
    *,
    share: float,
    most: int,
    stop: float = 0.0,
    progress: Callable[[str], None] | None = None,
    objective: Objective = FEED,
    jobs: int = 1,
    rapids: Sequence[Any] = (),
) -> tuple[list[tuple[str, dict[str, float], float, float]], Setup, list[Prediction]]:
    """Forward selection on top of ``current`` (whose predictions are ``preds``): every
    effect not yet added is fitted on the calibration data (on ``jobs`` worker processes,
    :func:`core.diagnosis.parallel.fit_each`), and the one leaving the least held-out gap is
    added while it :func:`clears` the test (``share`` of what is left), at most ``most`` of
    them and while the gap is at least ``stop`` (mm/min). Returns (effect, params, gap
    before, gap after) in the order added, the setup and its predictions. The gaps are
    ``objective``'s (the feed gap, mm/min, unless told); ``rapids``: more calibration data
    for the effects that act on the rapids (:func:`core.diagnosis.parallel.fit_each`)."""
    g_now = objective.gap(preds, data, "held_out")
    sq_now = objective.chunks(preds, data)[0]
    added: list[tuple[str, dict[str, float], float, float]] = []
    while len(added) < most and g_now >= stop:
        left = {name: eff for name, eff in effects.items() if all(a[0] != name for a in added)}
        fitted = fit_each(
            indicators_of,
            tps,
            current,
            left,
            data,
            objective,
            jobs=jobs,
            progress=progress,
            step=COMBINE_STEP,
            start=COMBINE_START,
            done=COMBINE_DONE,
            rapids=rapids,
        )
        trials = [
            (objective.gap(p, data, "held_out"), name, params, p)
            for name, (params, p) in fitted.items()
        ]
        if not trials:
            break
        g_new, name, params, p = min(trials, key=lambda x: x[0])
        sq_new = objective.chunks(p, data)[0]
        # (nearly all of what is left, at any p, names the first effect only: :func:`decide`)
        if not clears(g_now, g_new, sign_flip_p(sq_now, sq_new), floor, share, near_all=False):
            break
        added.append((name, params, g_now, g_new))
        current = effects[name].apply(current, params)
        preds, g_now, sq_now = p, g_new, sq_new
    return added, current, preds


def sign_flip_p(sq_a: NDArray[np.float64], sq_b: NDArray[np.float64]) -> float:
    """One-sided p value that ``b``'s squared gap is smaller than ``a``'s over the held-out
    pieces by chance: the reduction of every piece keeps its size and gets a random sign
    (the null: the fit helps here as often as it hurts there); p is the share of sign
    patterns whose total reduction is at least the one observed. Exact for few pieces,
    else SIGN_FLIPS patterns from a fixed seed."""
    d = np.asarray(sq_a, dtype=np.float64) - np.asarray(sq_b, dtype=np.float64)
    scale = float(np.abs(d).max()) if d.size else 0.0
    d = d[np.abs(d) > TOL.rel_equal * scale] if scale > 0 else d[:0]
    if d.size == 0:
        return 1.0
    observed = float(d.sum())
    a = np.abs(d)
    if d.size <= 12:
        signs = ((np.arange(2**d.size)[:, None] >> np.arange(d.size)) & 1) * 2 - 1
    else:
        rng = np.random.default_rng(0)
        signs = rng.integers(0, 2, size=(SIGN_FLIPS, d.size), dtype=np.int8) * 2 - 1
    totals = signs @ a
    tol = TOL.float_slack * float(a.sum())
    return float(np.mean(totals >= observed - tol))


def _moved(eff: Effect, params: Mapping[str, float], start: Mapping[str, float]) -> int:
    """The size of the explanation: the effect's own count when it has one, else how many
    parameters a fit moved from where it started by more than 1 % of their range (in log
    space for log parameters); an effect without parameters is one switch (1)."""
    if eff.size is not None:
        return eff.size(params)
    if not eff.params:
        return 1
    return sum(p.differs(params.get(p.name, 0.0), start.get(p.name, 0.0)) for p in eff.params)


def _evidence(
    effects: Mapping[str, Effect],
    base: Setup,
    fitted: Mapping[str, tuple[dict[str, float], list[Prediction]]],
    before: Sequence[Prediction],
    g_before: float,
    data: Sequence[Data],
    unseen: Callable[[list[Prediction]], float],
) -> list[EffectResult]:
    """Every fitted effect's evidence on ``data`` (:func:`_weigher`)."""
    weigh = _weigher(effects, base, before, g_before, data, unseen)
    return [weigh(name, f) for name, f in fitted.items()]


def _weigher(
    effects: Mapping[str, Effect],
    base: Setup,
    before: Sequence[Prediction],
    g_before: float,
    data: Sequence[Data],
    unseen: Callable[[list[Prediction]], float],
) -> Callable[[str, tuple[dict[str, float], list[Prediction]]], EffectResult]:
    """What a fitted effect's evidence on ``data`` (whose held-out gap before is
    ``g_before``) is made by: its held-out and calibration gaps, the parameters it moved,
    the p value of its held-out reduction against ``before`` and its squared gap per
    held-out piece, and, as ``rapid_gap``, ``unseen`` of its predictions: its gap on what
    the decision weighs beside -- the rapids on the feed moves, the feed moves on the
    rapids. (A function of the fit alone: the fits' workers weigh their own,
    :func:`core.diagnosis.parallel.fit_and_weigh`.)"""
    sq_before, _ = held_out_chunks(before, data)

    def weigh(name: str, fitted: tuple[dict[str, float], list[Prediction]]) -> EffectResult:
        params, preds = fitted
        speeds = held_out_speeds(preds, data)
        sq_after, _ = held_out_chunks(preds, data, speeds)
        return EffectResult(
            name,
            params,
            g_before,
            gap(preds, data, "held_out", speeds),
            gap(preds, data, "calibration"),
            moved=_moved(effects[name], params, effects[name].start(base.machine)),
            p=sign_flip_p(sq_before, sq_after),
            chunk_sq=sq_after,
            rapid_gap=unseen(preds),
        )

    return weigh


def _fitted_and_weighed(
    both: Mapping[str, tuple[tuple[dict[str, float], list[Prediction]], EffectResult | None]],
) -> tuple[dict[str, tuple[dict[str, float], list[Prediction]]], list[EffectResult]]:
    """:func:`core.diagnosis.parallel.fit_and_weigh`'s fits and their evidence apart."""
    results = [r for _, r in both.values()]
    assert all(r is not None for r in results)
    return {name: f for name, (f, _) in both.items()}, [r for r in results if r is not None]


def _idle(
    indicators_of: IndicatorSource,
    tps: Sequence[ToolPath],
    base: Setup,
    effects: Mapping[str, Effect],
    results: Sequence[EffectResult],
    before: Sequence[Prediction],
    data: Sequence[Data],
    floor: float,
) -> frozenset[str]:
    """The effects of ``results`` whose fit moved no parameter and which predict at their
    start what ``base`` does (:func:`_changes_nothing`) -- of those that would clear the
    test: the others are not named anyway and cost no prediction."""
    return frozenset(
        r.name
        for r in results
        if r.moved == 0
        and clears(r.held_out_gap_before, r.held_out_gap_after, r.p, floor, BEST_SHARE)
        and _changes_nothing(indicators_of, tps, base, effects[r.name], before, data)
    )


def _changes_nothing(
    indicators_of: IndicatorSource,
    tps: Sequence[ToolPath],
    base: Setup,
    eff: Effect,
    before: Sequence[Prediction],
    data: Sequence[Data],
) -> bool:
    """Whether ``eff`` at the values its fit starts from predicts what ``base`` does: the
    same gap, bit for bit, on all the data (a block time or tolerance at the machine's own,
    scales of 1; not a switch such as path compression, which acts at its defaults too).
    Such an effect whose fit moved no parameter (by MOVED_SHARE of its range) found only
    how sensitive the model is right at the machine file's values: on unchanged free-form
    chord paths (0.05 mm chords at F2000, LinuxCNC, development seeds) ``block_cycle_time``
    at 1.00 ms against the preset's 1.02 removed 43 % of the held-out gap at p = 0.00025 --
    which junctions LinuxCNC's kink test takes for corners turns on that 2 %."""
    start = predict_all(indicators_of, tps, eff.apply(base, eff.start(base.machine)))
    return gap(start, data, "all") == gap(before, data, "all")


def noise_floor(base: Setup, data: Sequence[Data]) -> tuple[float, str]:
    """The least RMS gap reduction (mm/min) an effect must bring, and its source."""
    least = MIN_FEED_SHARE * feed_level(data)
    m = base.machine
    if math.isfinite(m.noise_floor):
        value, source = m.noise_floor * PER_MIN, "the machine file's noise floor"
    else:
        value = NOISE_K * trace_noise(data)
        source = f"{NOISE_K:g} x the noise of the trace"
    if value < least:
        return least, f"{MIN_FEED_SHARE:.1%} of F"
    return value, source


def decide(
    results: Sequence[EffectResult],
    floor: float,
    folded: frozenset[str] = frozenset(),
    stretched: frozenset[str] = frozenset(),
    idle: frozenset[str] = frozenset(),
    *,
    near_all: bool = True,
    rapid_before: float = math.nan,
) -> tuple[list[EffectResult], str | None, str]:
    """Rank the effects and name the best one, or none (see the module docstring).

    ``folded``: effects the machine file already sets (calibrated): among equally good
    effects they come last; ``stretched``: effects whose fit ran to a bound of a parameter
    (a corner tolerance at its least, standing for a stop at every corner): among equally
    good effects they come after the others; ``idle``: effects whose fit left every
    parameter at the machine's own value (:func:`_changes_nothing`): never named, whatever
    they remove -- a setting fitted at the machine file's value is not a setting that
    differs from it. ``near_all``: the clause of nearly all of the gap at any p
    (:func:`clears`) is tried -- on the feed moves, where it was checked on the blind
    benchmark's stored evidence; not on the rapids, whose gaps on an unchanged machine
    include what is not modelled there (LinuxCNC's canned-cycle rapids accelerate at
    0.9 of the axes' limit) and were not stored to check it on. ``rapid_before``: the
    rapids' gap of the model without any effect (NaN: not known); an effect whose fit
    leaves the rapids more than twice as far off, and the floor more, cannot lead
    (:data:`RAPIDS_CONTRADICT`). Returns the effects in rank order (the named or leading one
    first, then by held-out gap), the named effect and the reason in one sentence."""
    ranked = sorted(results, key=lambda r: r.held_out_gap_after)
    if not ranked:
        return ranked, None, "no effects to try"

    ok = [
        r
        for r in ranked
        if r.name not in idle
        and clears(
            r.held_out_gap_before, r.held_out_gap_after, r.p, floor, BEST_SHARE, near_all=near_all
        )
    ]
    # the rapids contradict an effect whose fit wrecks them: it explains the feed moves with a
    # machine the rapids show is not there (RAPIDS_CONTRADICT)
    wrecks = [
        r
        for r in ok
        if math.isfinite(r.rapid_gap)
        and r.rapid_gap - rapid_before > RAPIDS_CONTRADICT * max(floor, rapid_before)
    ]
    ok = [r for r in ok if all(r is not w for w in wrecks)]
    wrecked = (
        f"; {', '.join(r.name for r in wrecks)} fit the feed moves but leave the rapids "
        f"{', '.join(f'{r.rapid_gap:.0f}' for r in wrecks)} mm/min off (without an effect: "
        f"{rapid_before:.0f}): contradicted by them"
        if wrecks
        else ""
    )
    if not ok and wrecks:
        return ranked, None, "none" + wrecked
    if not ok:
        lead = ranked[0]
        if lead.name in idle and clears(
            lead.held_out_gap_before,
            lead.held_out_gap_after,
            lead.p,
            floor,
            BEST_SHARE,
            near_all=near_all,
        ):
            return (
                ranked,
                None,
                (
                    f"none: the best fit, {lead.name}, removes {lead.removed:.0%} of the held-out "
                    "gap with its parameters at the machine file's values (within "
                    f"{MOVED_SHARE:.0%} of their ranges): what the model is sensitive to there, "
                    "not a setting that differs"
                ),
            )
        why = []
        if lead.removed < BEST_SHARE:
            why.append(f"removes {lead.removed:.0%} of the held-out gap (< {BEST_SHARE:.0%})")
        if lead.held_out_gap_before - lead.held_out_gap_after < floor:
            why.append(
                f"removes {lead.held_out_gap_before - lead.held_out_gap_after:.1f} mm/min "
                f"(< the floor {floor:.1f} mm/min)"
            )
        if lead.p > SIG_P and lead.held_out_gap_before - lead.held_out_gap_after < STRONG_K * floor:
            why.append(
                f"is not significant over the held-out pieces (p = {lead.p:.2g} > {SIG_P:g})"
            )
        return ranked, None, f"none: the best fit, {lead.name}, " + " and ".join(why)
    lead = ok[0]
    # equal: remaining gaps within TIE_SHARE of the best's remaining gap (a share of what
    # it removed made a 47 % larger residual "equal" where the gap was large)
    margin = TIE_SHARE * lead.held_out_gap_after
    equal = [
        r
        for r in ok
        if r.held_out_gap_after - lead.held_out_gap_after <= margin
        or (
            r.held_out_gap_after - lead.held_out_gap_after < floor
            and sign_flip_p(r.chunk_sq, lead.chunk_sq) > TIE_P
        )
    ]
    # The rapids, which most fits do not see, decide where they tell effects apart: a path
    # speed limit or an axis's speed slows the rapids too, a feed override does not
    # (LinuxCNC 2.9 scales rapids by its rapid override only). They weigh the equals and
    # those a significance test put behind the best by less than the floor (score6's
    # spiral_pocket_60151: a 40 mm/s path limit left 6.8 mm/min, an axis-speed fit moving
    # five parameters 6.3 -- not equal by the test --, but 22 against 965 mm/min on the
    # rapids).
    near = [r for r in ok if r.held_out_gap_after - lead.held_out_gap_after < floor]
    pool = equal + [r for r in near if r not in equal]
    by_rapids, slower = equal, []
    if len(pool) > 1 and all(math.isfinite(r.rapid_gap) for r in pool):
        least = min(r.rapid_gap for r in pool)
        # (rapids are modelled less closely than feed moves -- 330 mm/min on an unchanged
        # 2.5D part's drilling cycles --: only twice the least, and the floor more, counts)
        margin_r = max(floor, least)
        slower = [r for r in pool if r.rapid_gap - least > margin_r]
        if slower:
            by_rapids = [r for r in pool if r not in slower]
    order = {
        name: k
        for k, entry in enumerate(EFFECT_PRIORITY)
        for name in ((entry,) if isinstance(entry, str) else entry)
    }

    # an effect the machine file already calibrates (``folded``) is the less likely story;
    # an effect that explains anything was at least switched on: one decision even where
    # its fit left every parameter where it started (path compression at its defaults)
    def story(r: EffectResult) -> tuple[bool, bool, int, int]:
        return (
            r.name in folded,
            r.name in stretched,
            max(r.moved, 1),
            order.get(r.name, len(order)),
        )

    best = min(by_rapids, key=lambda r: (*story(r), r.held_out_gap_after))
    ranked.remove(best)
    ranked.insert(0, best)
    reason = (
        f"{best.name}: removes {best.removed:.0%} of the held-out gap (p = {best.p:.2g}, "
        f"floor {floor:.1f} mm/min)"
    )
    if not clears(
        best.held_out_gap_before, best.held_out_gap_after, best.p, floor, BEST_SHARE, near_all=False
    ):
        reason += (
            f"; nearly all of the held-out gap (>= {NEAR_ALL_SHARE:.0%}), predicted where it lies "
            "from the calibration stretches: named whatever the test over so few pieces says"
        )
    reason += wrecked
    same = [r.name for r in by_rapids if r is not best]
    if slower:
        reason += (
            f"; {', '.join(r.name for r in slower)} fit the feed moves within the floor, but "
            f"not the rapids (gap there {', '.join(f'{r.rapid_gap:.0f}' for r in slower)} mm/min "
            f"against {best.rapid_gap:.0f})"
        )
    if same:
        why_best = (
            "is the simpler explanation"
            if any(story(r) != story(best) for r in by_rapids if r is not best)
            else "leaves the least of the held-out gap"
        )
        reason += f"; {', '.join(same)} explain the data as well, {best.name} {why_best}"
    return ranked, best.name, reason


@dataclass(frozen=True, eq=False)
class DiagnosisTarget:
    """A file to draw a diagnosis into: the path coloured by gap, the gap zones, and measured
    against predicted feed over arc length for the worst of them (``ncperf diagnose``).

    Attributes
    ----------
    path : str
    diagnosis : Diagnosis
    view : {"xy", "xz", "yz", "iso"}
    """

    path: str
    diagnosis: Diagnosis
    view: str = "xy"

    def __post_init__(self) -> None:
        file_target(self)
