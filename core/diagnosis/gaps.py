"""The gap map: the stretches where the measured feed departs from the prediction by more
than ``GAP_SHARE`` of F, with their program lines, what is there, and the seconds lost."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from core.diagnosis.resample import Data
from core.diagnosis.rules import GAP_SHARE, MERGE_MM, PER_MIN, STEP, ZONES
from core.engine.predict import Prediction
from core.model.tolerances import TOL
from core.model.toolpath import ToolPath


@dataclass(frozen=True)
class GapZone:
    line_start: int
    line_end: int
    s_start: float
    s_end: float
    feature: str
    gap_rms: float  # mm/min
    time_s: float  # measured - predicted time over the zone: > 0 the machine is slower
    program: str = ""


def _features(tp: ToolPath, pred: Prediction, moves: NDArray[np.int64]) -> str:
    """What is there: corner, short blocks, line-arc transition, arc, rapid, long straight."""
    ev = pred.evaluation
    a, b = int(moves.min()), int(moves.max())
    j = ev.junction[(ev.junction >= a - 1) & (ev.junction <= b)]
    names = {ev.indicator_names[i] for i in ev.junction_indicator[np.isin(ev.junction, j)]}
    if "tangential" in names:
        return "corner"
    el = ev.element_indicator[a : b + 1]
    if np.any(el >= 0) and any(ev.indicator_names[i] == "ncu_capacity" for i in el[el >= 0]):
        return "short blocks"
    if np.any(tp.length[a : b + 1] < ev.min_length[a : b + 1]):
        return "short blocks"
    if "curvature" in names:
        return "line-arc transition"
    if tp.is_arc[a : b + 1].any():
        return "arc"
    if (~tp.is_feed[a : b + 1]).any():
        return "rapid"
    return "long straight"


def gap_zones(
    preds: Sequence[Prediction], data: Sequence[Data], count: int = ZONES
) -> tuple[GapZone, ...]:
    """Where |measured - predicted| exceeds GAP_SHARE of F, worst (most seconds) first."""
    zones = []
    for d in data:
        pred = preds[d.case]
        tp = pred.toolpath
        vp = pred.speed_at(d.s, commanded=d.commanded)
        r = d.v - vp
        big = np.abs(r) > GAP_SHARE * d.feed
        if not big.any():
            continue
        idx = np.flatnonzero(big)
        cut = np.flatnonzero(np.diff(d.s[idx]) > MERGE_MM)
        starts = np.concatenate([[0], cut + 1])
        ends = np.concatenate([cut, [idx.size - 1]])
        step = float(np.median(np.diff(d.s))) if d.s.size > 1 else STEP
        for a, b in zip(starts, ends, strict=True):
            sel = slice(idx[a], idx[b] + 1)
            mv = d.move[sel]
            with np.errstate(divide="ignore"):
                dt = np.sum(
                    (
                        1.0 / np.maximum(d.v[sel], TOL.min_speed)
                        - 1.0 / np.maximum(vp[sel], TOL.min_speed)
                    )
                    * step
                )
            zones.append(
                GapZone(
                    line_start=int(tp.line[mv].min()),
                    line_end=int(tp.line[mv].max()),
                    s_start=float(d.s[sel][0]),
                    s_end=float(d.s[sel][-1]),
                    feature=_features(tp, pred, mv),
                    program=tp.source,
                    gap_rms=float(np.sqrt(np.mean(r[sel] ** 2)) * PER_MIN),
                    time_s=float(dt),
                )
            )
    zones.sort(key=lambda z: -abs(z.time_s))
    return tuple(zones[:count])
