"""Sim-to-real gap diagnosis: where the prediction misses a measured trace, which unmodelled
effect explains it, and how far the gap shrinks once that effect is modelled.

1. Every trace is aligned with the program (:mod:`core.diagnosis.align`); its feed is resampled on the
   arc length of the feed moves every ``STEP`` mm.
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

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from core.diagnosis.align import Alignment
from core.view.annotations import Annotations
from core.engine.effects import Effect, Param, Setup
from core.facade import Ncperf
from core.model.machine import Machine
from core.engine.predict import Prediction, predict
from core.model.toolpath import ToolPath

#: Comparison step along the path (mm); coarser for long programs (MAX_POINTS).
STEP = 0.1
MAX_POINTS = 200_000
#: A stretch belongs to the gap map where |measured - predicted| exceeds this share of F.
GAP_SHARE = 0.05
#: Time weights use the measured feed, but never below this share of F (stops would weigh
#: without bound).
TIME_FLOOR = 0.02
#: Gap-map stretches closer than this (mm) are one zone.
MERGE_MM = 1.0
#: The best effect must remove this share of the held-out gap; later ones ADD_SHARE of
#: what is left.
BEST_SHARE = 0.20
ADD_SHARE = 0.10
STOP_SHARE = 0.10
#: ... and remove at least this share of the programmed feed (RMS over the held-out data):
#: a gap already within 0.75 % of F is explained, whatever share of it an effect could fit.
MIN_FEED_SHARE = 0.0075
MAX_CHOSEN = 4
#: Effects whose held-out gaps differ by less than this share of what the best removes are
#: equally good; the one with the fewest parameters is ranked first.
TIE_SHARE = 0.05
#: Samples further apart than this many sample periods leave a hole: not compared.
GAP_PERIODS = 20
#: Stretches of one run used for calibration / held-out data (alternating).
CHUNKS = 16
#: Grid points per parameter when fitting (then a local refinement).
GRID_1D = 11
GRID_2D = 6
GRID_ND = 4
REFINE = 8
PER_MIN = 60.0
#: Gap classes of the display: (measured - predicted) / F.
GAP_EDGES = (-0.20, -0.10, 0.10, 0.20)
GAP_LABELS = (
    "measured 20 % slower or more",
    "10-20 % slower",
    "within 10 %",
    "10-20 % faster",
    "measured 20 % faster or more",
)
GAP_COLOURS = ("#b2182b", "#f4a582", "#1a9850", "#92c5de", "#2166ac")


@dataclass(frozen=True, eq=False)
class Data:
    """Measured feed of one trace on the arc-length grid of the feed moves."""

    s: NDArray[np.float64]
    v: NDArray[np.float64]
    feed: NDArray[np.float64]  # programmed F there (mm/s)
    move: NDArray[np.int64]
    calibration: NDArray[np.bool_]  # grid points used for fitting
    label: str
    weight: NDArray[np.float64]  # time spent at each grid point (s)
    case: int = 0  # which program (tool path) the trace ran


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
            move_class=cls,
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


def resample(tp: ToolPath, al: Alignment, label: str, step: float = STEP, case: int = 0) -> Data:
    """The aligned measured feed every ``step`` mm of the feed moves the trace covers."""
    start_s = np.concatenate([[0.0], np.cumsum(tp.length)[:-1]])
    lo, hi = float(al.s.min()), float(al.s.max())
    step = max(step, (hi - lo) / MAX_POINTS)
    grid = np.arange(lo + 0.5 * step, hi, step)
    move = np.clip(np.searchsorted(start_s, grid, side="right") - 1, 0, tp.n - 1)
    keep = tp.is_feed[move]
    grid, move = grid[keep], move[keep]
    # Average the samples at one arc length (stops), then interpolate along the path.
    s_u, first, inv = np.unique(al.s, return_index=True, return_inverse=True)
    v_u = np.bincount(inv, weights=al.v) / np.bincount(inv)
    # Not across a hole in the recording: grid points whose neighbouring samples are more
    # than GAP_PERIODS sample periods apart in time are left out (event-based recordings,
    # whose values hold until the next event, have none).
    if al.t.size > 2 and s_u.size > 1 and al.method != "line and feed":
        period = float(np.median(np.diff(al.t)))
        last = np.append(first[1:] - 1, al.t.size - 1)  # s is non-decreasing in time
        k = np.clip(np.searchsorted(s_u, grid), 1, s_u.size - 1)
        hole = al.t[first[k]] - al.t[last[k - 1]] > GAP_PERIODS * period
        grid, move = grid[~hole], move[~hole]
    v = np.interp(grid, s_u, v_u)
    feed = tp.feed[move]
    weight = step / np.maximum(v, TIME_FLOOR * feed)
    return Data(
        s=grid,
        v=v,
        feed=feed,
        move=move,
        calibration=np.ones(grid.size, dtype=bool),
        label=label,
        weight=weight,
        case=case,
    )


def split(data: list[Data]) -> tuple[list[Data], str]:
    """Calibration / held-out split (see the module docstring).

    Several runs of one program: alternate runs. Otherwise (one run, or one run of each of
    several programs): alternate stretches of every run, the parity changing from run to run
    so that what happens once per program (its end) is fitted on some programs and measured
    on others.
    """
    programs = {d.case for d in data}
    if len(data) >= 2 and len(programs) == 1:
        out = [
            dataclasses.replace(d, calibration=np.full(d.s.size, k % 2 == 0))
            for k, d in enumerate(data)
        ]
        cal = ", ".join(d.label for k, d in enumerate(data) if k % 2 == 0)
        held = ", ".join(d.label for k, d in enumerate(data) if k % 2 == 1)
        return out, f"other runs: fitted on {cal}, measured on {held}"
    out = []
    for k, d in enumerate(data):
        edges = np.quantile(d.s, np.linspace(0, 1, CHUNKS + 1))
        chunk = np.clip(np.searchsorted(edges, d.s, side="right") - 1, 0, CHUNKS - 1)
        out.append(dataclasses.replace(d, calibration=chunk % 2 == k % 2))
    runs = "one run" if len(data) == 1 else f"each of {len(data)} runs"
    return out, (
        f"alternate stretches of {runs} ({CHUNKS} stretches of equal length, "
        "every other one fitted and the others measured)"
    )


def gap(preds: list[Prediction], data: list[Data], which: str) -> float:
    """RMS over time of measured - predicted feed (mm/min) on the calibration, held-out or
    all data."""
    sq, n = 0.0, 0.0
    for d in data:
        sel = (
            d.calibration
            if which == "calibration"
            else ~d.calibration
            if which == "held_out"
            else np.ones(d.s.size, dtype=bool)
        )
        if not sel.any():
            continue
        r = d.v[sel] - preds[d.case].speed_at(d.s[sel])
        w = d.weight[sel]
        sq += float(np.sum(w * r * r))
        n += float(w.sum())
    return math.sqrt(sq / n) * PER_MIN if n > 0 else 0.0


def feed_level(data: list[Data]) -> float:
    """RMS over time of the programmed feed on the held-out data (mm/min)."""
    sq, n = 0.0, 0.0
    for d in data:
        sel = ~d.calibration
        sq += float(np.sum(d.weight[sel] * d.feed[sel] ** 2))
        n += float(d.weight[sel].sum())
    return math.sqrt(sq / n) * PER_MIN if n > 0 else 0.0


def _grid(p: Param, count: int) -> NDArray[np.float64]:
    if p.log and p.low > 0:
        g = np.geomspace(p.low, p.high, count)
    else:
        g = np.linspace(p.low, p.high, count)
    if p.integer:
        g = np.unique(np.round(g))
    return g


def predict_all(nc: Ncperf, tps: list[ToolPath], setup: Setup) -> list[Prediction]:
    """The prediction of ``setup`` for every program."""
    return [predict(nc, tp, setup) for tp in tps]


def fit(
    nc: Ncperf, tps: list[ToolPath], base: Setup, eff: Effect, data: list[Data]
) -> tuple[dict[str, float], list[Prediction]]:
    """Parameters of ``eff`` (on top of ``base``) minimising the calibration gap."""
    m = base.machine
    defaults = eff.start(m)
    cache: dict[tuple, tuple[float, list[Prediction]]] = {}

    def score(values: dict[str, float]) -> float:
        key = tuple(round(values[p.name], 12) for p in eff.params)
        if key not in cache:
            preds = predict_all(nc, tps, eff.apply(base, values))
            cache[key] = (gap(preds, data, "calibration"), preds)
        return cache[key][0]

    if not eff.params:
        score({})
        return {}, cache[()][1]
    params = eff.params
    if len(params) == 1:
        p = params[0]
        candidates = [{p.name: float(x)} for x in _grid(p, GRID_1D)]
    else:
        per = GRID_2D if len(params) == 2 else GRID_ND
        grids = [_grid(p, per) for p in params]
        mesh = np.meshgrid(*grids, indexing="ij")
        candidates = [
            dict(zip([p.name for p in params], map(float, vals), strict=True))
            for vals in zip(*(g.ravel() for g in mesh), strict=True)
        ]
    # Defaults first: among equal scores the effect changes nothing.
    candidates.insert(0, dict(defaults))
    best = min(candidates, key=score)
    if len(params) > 1:
        # The coarse mesh can straddle a limit that only acts below a threshold (an axis
        # speed under the programmed feed): scan each parameter on the fine 1-D grid, the
        # others held at the best so far.
        for p in params:
            line = [best | {p.name: float(x)} for x in _grid(p, GRID_1D)]
            best = min([best, *line], key=score)
    # Local refinement, one parameter at a time: a bracket around the best value that halves
    # (in log space for log parameters) every round.
    brackets = {}
    for p in params:
        grid = _grid(p, GRID_1D)
        k = int(np.argmin(np.abs(grid - best[p.name])))
        brackets[p.name] = (float(grid[max(k - 1, 0)]), float(grid[min(k + 1, grid.size - 1)]))
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
    for p in params:
        trial = dict(best)
        trial[p.name] = defaults[p.name]
        if score(trial) <= score(best) * (1 + 1e-9):
            best = trial
    key = tuple(round(best[p.name], 12) for p in eff.params)
    return best, cache[key][1]


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


def gap_zones(preds: list[Prediction], data: list[Data], count: int = 10) -> tuple[GapZone, ...]:
    """Where |measured - predicted| exceeds GAP_SHARE of F, worst (most seconds) first."""
    zones = []
    for d in data:
        pred = preds[d.case]
        tp = pred.toolpath
        vp = pred.speed_at(d.s)
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
                    (1.0 / np.maximum(d.v[sel], 1e-3) - 1.0 / np.maximum(vp[sel], 1e-3)) * step
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


def diagnose(
    nc: Ncperf,
    tp: ToolPath,
    alignments: list[Alignment],
    labels: list[str],
    base: Setup,
    baseline: str,
    effects: dict[str, Effect],
) -> Diagnosis:
    """The diagnosis of one program against its aligned traces (see the module docstring)."""
    return diagnose_cases(nc, [(tp, alignments, labels)], base, baseline, effects)


def diagnose_cases(
    nc: Ncperf,
    cases: list[tuple[ToolPath, list[Alignment], list[str]]],
    base: Setup,
    baseline: str,
    effects: dict[str, Effect],
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
    before = predict_all(nc, tps, base)
    g_before_all = gap(before, data, "all")
    g_before = gap(before, data, "held_out")
    results = []
    fitted: dict[str, tuple[dict[str, float], list[Prediction]]] = {}
    for name, eff in effects.items():
        params, preds = fit(nc, tps, base, eff, data)
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
                params, preds = fit(nc, tps, current, effects[r.name], data)
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


# ----------------------------------------------------------------------------- reports
def _fmt_params(params: dict[str, float], eff: Effect) -> str:
    units = {p.name: p.unit for p in eff.params}
    return (
        ", ".join(
            f"{k}={v:.4g}{(' ' + units[k]) if units.get(k) else ''}" for k, v in params.items()
        )
        or "-"
    )


def toml_snippet(
    d: Diagnosis, machine: Machine | None = None, effects: Mapping[str, Effect] | None = None
) -> str:
    """The machine-file tables that make the chosen effects part of the model (for a scale
    the machine already folds in, the product of the two)."""
    out = []
    for name in d.chosen:
        values = dict(d.chosen_params[name])
        eff = effects.get(name) if effects is not None else None
        if machine is not None and eff is not None and eff.relative:
            before = eff.folded(machine)
            values = {
                k: v * before.get(k, 1.0) if k in eff.relative else v for k, v in values.items()
            }
        out.append(f"[effects.{name}]")
        out.extend(f"{k} = {v:.6g}" for k, v in values.items())
    return "\n".join(out)


def report(
    d: Diagnosis,
    *,
    program: str,
    machine: str,
    labels: list[str],
    effects: dict[str, Effect],
    machine_file: Machine | None = None,
) -> str:
    """The terminal report of ``ncperf diagnose`` (``machine_file``: the machine whose file
    the suggested tables go into)."""
    lines = [f"ncperf diagnose: {program} on {machine} (baseline: {d.baseline})"]
    for lab, al in zip(labels, d.alignments, strict=True):
        lines.append(
            f"  trace            {lab}: {al.t.size:,} samples over {al.t[-1]:.2f} s; {al.message}"
        )
        for note in al.notes:
            lines.append(f"                   {note}")
    lines.append(f"  held-out data    {d.held_out}")
    lines.append(
        f"  gap before       {d.gap_rms_before:.1f} mm/min RMS over time "
        "(measured - predicted feed on the feed moves)"
    )
    lines += _zone_table("  where it lies", d.zones)
    lines.append(
        "  effects          fitted on the calibration data; gap on the held-out data (mm/min):"
    )
    params = [_fmt_params(r.params, effects[r.name]) for r in d.effects]
    width = max([len("parameters"), *map(len, params)])
    lines.append(
        f"    {'#':>2s}  {'effect':28s} {'parameters':{width}s} {'before':>8s} "
        f"{'after':>8s} {'removed':>8s}"
    )
    for k, (r, ps) in enumerate(zip(d.effects, params, strict=True), start=1):
        lines.append(
            f"    {k:2d}  {r.name:28s} {ps:{width}s} "
            f"{r.held_out_gap_before:8.1f} {r.held_out_gap_after:8.1f} "
            f"{r.removed * 100:7.0f}%"
        )
    if d.best_effect is None:
        lines.append(
            f"  best effect      none: no effect removes {BEST_SHARE:.0%} of the held-out"
            f" gap and {MIN_FEED_SHARE:.0%} of F (what is left is noise, or an effect not in"
            " this list)"
        )
    else:
        lines.append(f"  best effect      {d.best_effect}")
        lines.append(
            f"  chosen           {' + '.join(d.chosen)} (each removing at least "
            f"{ADD_SHARE:.0%} of what was left on held-out data, until less than "
            f"{STOP_SHARE:.0%} of the gap was left)"
        )
    lines.append(f"  gap after        {d.gap_rms_after:.1f} mm/min")
    if d.chosen:
        lines += _zone_table("  where it remains", d.zones_after[:5])
        lines.append("  to model it      add to the machine file (or replace there):")
        lines += [
            "                   " + t for t in toml_snippet(d, machine_file, effects).splitlines()
        ]
    return "\n".join(lines)


def _zone_table(title: str, zones: tuple[GapZone, ...]) -> list[str]:
    if not zones:
        return [f"{title:18s} nowhere beyond {GAP_SHARE:.0%} of F"]
    out = [
        f"{title}:",
        f"    {'lines':13s} {'arc length [mm]':>19s} {'feature':20s} "
        f"{'RMS gap':>14s} {'time':>10s}",
    ]
    for z in zones:
        lines = f"{z.line_start}" if z.line_start == z.line_end else f"{z.line_start}-{z.line_end}"
        out.append(
            f"    {lines:13s} {z.s_start:9.1f}-{z.s_end:<9.1f} {z.feature:20s} "
            f"{z.gap_rms:8.0f} mm/min {z.time_s:+8.3f} s"
        )
    return out


def to_json(
    d: Diagnosis, machine: Machine | None = None, effects: Mapping[str, Effect] | None = None
) -> dict:
    """The JSON report (gaps in mm/min, times in s: > 0 the machine is slower)."""

    def zone(z: GapZone) -> dict:
        return {
            "line_start": z.line_start,
            "line_end": z.line_end,
            "s_start_mm": round(z.s_start, 3),
            "s_end_mm": round(z.s_end, 3),
            "feature": z.feature,
            "gap_rms": round(z.gap_rms, 3),
            "time_s": round(z.time_s, 4),
        }

    return {
        "baseline": d.baseline,
        "held_out": d.held_out,
        "alignment": [
            {
                "method": a.method,
                "ok": a.ok,
                "message": a.message,
                "offset_mm": [round(float(x), 4) for x in a.offset],
                "coverage": round(a.coverage, 4),
            }
            for a in d.alignments
        ],
        "gap_rms_before": round(d.gap_rms_before, 3),
        "zones": [zone(z) for z in d.zones],
        "effects": [
            {
                "name": r.name,
                "params": {k: round(v, 6) for k, v in r.params.items()},
                "held_out_gap_before": round(r.held_out_gap_before, 3),
                "held_out_gap_after": round(r.held_out_gap_after, 3),
                "removed": round(r.removed, 4),
            }
            for r in d.effects
        ],
        "best_effect": d.best_effect,
        "chosen": list(d.chosen),
        "chosen_params": {
            k: {p: round(v, 6) for p, v in ps.items()} for k, ps in d.chosen_params.items()
        },
        "gap_rms_after": round(d.gap_rms_after, 3),
        "zones_after": [zone(z) for z in d.zones_after],
        "machine_file_tables": toml_snippet(d, machine, effects),
    }
