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
   Effects are ranked by how much of the held-out gap they remove (among equally good ones,
   within TIE_SHARE, the one with the fewest parameters first); the best one counts only
   if it removes at least BEST_SHARE of it, and MIN_FEED_SHARE of the programmed feed ("no
   listed effect explains the gap" is an answer: the model already explains the trace, or
   what is left is noise or an effect not in the list). Effects are then added greedily
   while each still removes at least ADD_SHARE of what is left (and MIN_FEED_SHARE of F),
   and what is left is at least STOP_SHARE of the gap before (below that, a further effect
   would be fitted to the noise of the first one's fit).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from core.diagnosis.align import Alignment
from core.diagnosis.fit import fit, predict_all
from core.diagnosis.gaps import GapZone, gap_zones
from core.diagnosis.resample import Data, feed_level, gap, resample, split
from core.diagnosis.rules import (
    ADD_SHARE,
    BEST_SHARE,
    GAP_COLOURS,
    GAP_EDGES,
    GAP_LABELS,
    MAX_CHOSEN,
    MIN_FEED_SHARE,
    STOP_SHARE,
    TIE_SHARE,
)
from core.engine.effects import Effect, Setup
from core.engine.indicators import IndicatorSource
from core.engine.predict import Prediction
from core.model.toolpath import ToolPath
from core.view.annotations import Annotations
from core.view.targets import file_target


@dataclass(frozen=True)
class EffectResult:
    name: str
    params: dict[str, float]
    held_out_gap_before: float  # mm/min
    held_out_gap_after: float
    calibration_gap_after: float

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
            r = (d.v - self.befores[case].speed_at(d.s)) / d.feed
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
) -> Diagnosis:
    """The diagnosis of several programs, each with its aligned traces, on one machine:
    effects are fitted on some traces and measured on the others (see the module docstring)."""
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
    results = []
    fitted: dict[str, tuple[dict[str, float], list[Prediction]]] = {}
    for name, eff in effects.items():
        params, preds = fit(indicators_of, tps, base, eff, data)
        fitted[name] = (params, preds)
        results.append(
            EffectResult(
                name,
                params,
                g_before,
                gap(preds, data, "held_out"),
                gap(preds, data, "calibration"),
            )
        )
    results.sort(key=lambda r: r.held_out_gap_after)
    # Effects that explain the data equally well (within TIE_SHARE of what the best removes):
    # the simplest first -- a single feed rate explains an override and an axis feed limit
    # alike, and the fewer parameters, the fewer ways to fit noise.
    if results:
        lead = results[0]
        margin = TIE_SHARE * max(lead.held_out_gap_before - lead.held_out_gap_after, 0.0)
        tied = [r for r in results if r.held_out_gap_after - lead.held_out_gap_after <= margin]
        simplest = min(tied, key=lambda r: (len(effects[r.name].params), r.held_out_gap_after))
        results.remove(simplest)
        results.insert(0, simplest)
    floor = MIN_FEED_SHARE * feed_level(data)
    best = None
    if results and results[0].removed >= BEST_SHARE:
        if results[0].held_out_gap_before - results[0].held_out_gap_after >= floor:
            best = results[0].name

    chosen: list[str] = []
    chosen_params: dict[str, dict[str, float]] = {}
    current, current_preds = base, before
    if best is not None:
        chosen.append(best)
        chosen_params[best] = fitted[best][0]
        current = effects[best].apply(base, fitted[best][0])
        current_preds = fitted[best][1]
        g_now = gap(current_preds, data, "held_out")
        while len(chosen) < MAX_CHOSEN and g_now >= STOP_SHARE * g_before:
            trials = []
            for r in results:
                if r.name in chosen:
                    continue
                params, preds = fit(indicators_of, tps, current, effects[r.name], data)
                trials.append((gap(preds, data, "held_out"), r.name, params, preds))
            if not trials:
                break
            g_new, name, params, preds = min(trials, key=lambda x: x[0])
            if g_now <= 0 or (g_now - g_new) / g_now < ADD_SHARE or g_now - g_new < floor:
                break
            chosen.append(name)
            chosen_params[name] = params
            current = effects[name].apply(current, params)
            current_preds, g_now = preds, g_new
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
    )


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
