"""The measured feed on the path, the calibration / held-out split, and the gap.

1. Every trace is aligned with the program (:mod:`core.diagnosis.align`); its feed is
   resampled on the arc length of the feed moves every ``STEP`` mm.
2. The gap is the measured minus the predicted feed there (mm/min in reports), its RMS taken
   over time: every grid point weighs the time the machine spends there (step / measured
   feed, floored at ``TIME_FLOOR`` of F), so that slow stretches -- where the time goes --
   count as long as they last, not as long as they are.
3. Calibration data (for fitting) and held-out data (for measuring) are other runs, or
   alternate stretches of each run (:func:`split`).

The thresholds are in :mod:`core.diagnosis.rules`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from core.diagnosis.align import Alignment
from core.diagnosis.rules import (
    CHUNKS,
    COARSE_SAMPLING,
    GAP_PERIODS,
    JUMP_K,
    MAX_POINTS,
    MIN_RAPID_POINTS,
    PER_MIN,
    PIECES,
    REVERSAL,
    STEP,
    TIME_FLOOR,
)
from core.engine.predict import Prediction
from core.model.jit import compiled
from core.model.toolpath import ToolPath


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
    #: the piece of the run each grid point is in (CHUNKS stretches of PIECES pieces; the
    #: held-out pieces are the samples of the decision rule's significance test)
    chunk: NDArray[np.int64] | None = None
    #: the noise of the measured feed (mm/s RMS) from its samples in time (NaN: samples too
    #: coarse or irregular for that; :func:`trace_noise` then falls back on the path grid)
    noise: float = math.nan
    #: recent predicted speeds on the selections of this grid (:func:`_speeds`)
    memo: dict = field(default_factory=dict, repr=False)
    #: the measured speed on the rapids the trace covers, on the same kind of grid (arc
    #: length, speed in mm/s, time weight in s): :func:`rapid_gap`, :func:`rapid_data`
    rapid_s: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0), repr=False)
    rapid_v: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0), repr=False)
    rapid_weight: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0), repr=False)
    rapid_move: NDArray[np.int64] = field(
        default_factory=lambda: np.zeros(0, dtype=np.int64), repr=False
    )
    #: the measured feed is the trace's commanded-feed column (``Alignment.commanded``):
    #: predictions are read as it is (``Prediction.speed_at(..., commanded=True)``)
    commanded: bool = False


def resample(tp: ToolPath, al: Alignment, label: str, step: float = STEP, case: int = 0) -> Data:
    """The aligned measured feed every ``step`` mm of the feed moves the trace covers."""
    lo, hi = float(al.s.min()), float(al.s.max())
    step = max(step, (hi - lo) / MAX_POINTS)
    grid = np.arange(lo + 0.5 * step, hi, step)
    move = tp.move_at(grid)
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
        dt = al.t[first[k]] - al.t[last[k - 1]]
        hole = dt > GAP_PERIODS * period
        # Nor across a turn back that the samples jumped: where the path turns back on
        # itself by more than REVERSAL (the bottom of a drilled hole: the feed down and the
        # rapid up lie on one line), a tool off the path near the turn (a lagging servo, a
        # setpoint filter) is as near to one side as to the other, and its projection jumps
        # the turn anywhere within that reach; where consecutive places across a turn are
        # further apart than JUMP_K times what the measured speed covers in the time between
        # them (and than a grid step), the grid between them would show an interpolation
        # whose extent is chance, not a measurement. (A cut corner's jump is left in: the
        # side a projection takes there is the nearer one, for the trace as for a model.)
        turns = tp.end_s[:-1][tp.turn_angle > REVERSAL]
        if turns.size:
            ds = s_u[k] - s_u[k - 1]
            carried = 0.5 * (v_u[k] + v_u[k - 1]) * dt
            across = np.searchsorted(turns, s_u[k]) > np.searchsorted(
                turns, s_u[k - 1], side="right"
            )
            hole |= across & (ds > JUMP_K * carried) & (ds > step)
        grid, move = grid[~hole], move[~hole]
    v = np.interp(grid, s_u, v_u)
    keep = tp.is_feed[move]
    rapid_s, rapid_v, rapid_move = grid[~keep], v[~keep], move[~keep]
    # time weights floored at TIME_FLOOR of the fastest measured rapid (no rapid: none kept)
    slowest = TIME_FLOOR * float(rapid_v.max(initial=0.0))
    if not slowest > 0:
        rapid_s, rapid_v, rapid_move = rapid_s[:0], rapid_v[:0], rapid_move[:0]
    rapid_weight = step / np.maximum(rapid_v, slowest)
    grid, move, v = grid[keep], move[keep], v[keep]
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
        noise=sample_noise(tp, al),
        rapid_s=rapid_s,
        rapid_v=rapid_v,
        rapid_weight=rapid_weight,
        rapid_move=rapid_move,
        commanded=al.commanded,
    )


def _robust_d2_rms(d2: NDArray[np.float64]) -> float:
    """The RMS of white noise whose second differences are ``d2``, robustly: 1.4826 x the
    median absolute second difference / sqrt(6) (a second difference of white noise of RMS
    sigma has RMS sqrt(6) sigma; ramps, whose second difference is zero, and the few places
    where a ramp begins or ends, add nothing to the median)."""
    return float(1.4826 * np.median(np.abs(d2)) / math.sqrt(6.0))


def sample_noise(tp: ToolPath, al: Alignment) -> float:
    """The noise of the measured feed (mm/s RMS) from consecutive samples in time on feed
    moves, or NaN where the samples are coarser than COARSE_SAMPLING, event-based ("line and
    feed": values hold between events) or too few.

    In time, a controller's motion is ramps of constant acceleration, whose second difference
    vanishes except where one starts or ends -- a few samples of every corner or stop at
    millisecond sampling. On the path grid the same motion is not: approaching a stop v
    follows sqrt(2 a s), whose second difference grows without bound, so a program of stops
    every half millimetre (exact stop on chords) looked like noise of 1000 mm/min there."""
    if al.method == "line and feed" or al.t.size < 3:
        return math.nan
    dt = np.diff(al.t)
    period = float(np.median(dt))
    if not period > 0 or period > COARSE_SAMPLING:
        return math.nan
    feed = tp.is_feed[tp.move_at(al.s)]
    # triples of samples on feed moves, evenly spaced in time (no hole between them)
    even = np.abs(dt - period) <= 0.5 * period
    ok = feed[2:] & feed[1:-1] & feed[:-2] & even[1:] & even[:-1]
    v = al.v
    d2 = (v[2:] - 2.0 * v[1:-1] + v[:-2])[ok]
    d2 = d2[np.isfinite(d2)]
    if d2.size < 3:
        return math.nan
    return _robust_d2_rms(d2)


def split(data: Sequence[Data]) -> tuple[list[Data], str]:
    """Calibration / held-out split (see the module docstring).

    Several runs of one program: alternate runs. Otherwise (one run, or one run of each of
    several programs): alternate stretches of every run, the parity changing from run to run
    so that what happens once per program (its end) is fitted on some programs and measured
    on others.
    """
    programs = {d.case for d in data}
    if len(data) >= 2 and len(programs) == 1:
        out = [
            dataclasses.replace(d, calibration=np.full(d.s.size, k % 2 == 0), chunk=pieces(d))
            for k, d in enumerate(data)
        ]
        cal = ", ".join(d.label for k, d in enumerate(data) if k % 2 == 0)
        held = ", ".join(d.label for k, d in enumerate(data) if k % 2 == 1)
        return out, f"other runs: fitted on {cal}, measured on {held}"
    out = []
    for k, d in enumerate(data):
        chunk = pieces(d)
        out.append(dataclasses.replace(d, calibration=(chunk // PIECES) % 2 == k % 2, chunk=chunk))
    runs = "one run" if len(data) == 1 else f"each of {len(data)} runs"
    return out, (
        f"alternate stretches of {runs} ({CHUNKS} stretches of equal length, "
        "every other one fitted and the others measured)"
    )


def pieces(d: Data) -> NDArray[np.int64]:
    """The piece (0..CHUNKS x PIECES - 1, equal arc length; stretch = piece // PIECES) of
    every grid point of a run."""
    k = CHUNKS * PIECES
    edges = np.quantile(d.s, np.linspace(0, 1, k + 1))
    return np.clip(np.searchsorted(edges, d.s, side="right") - 1, 0, k - 1)


def held_out_speeds(preds: Sequence[Prediction], data: Sequence[Data]) -> list[NDArray]:
    """Each run's predicted speed at its held-out grid points: for :func:`held_out_chunks`
    and :func:`gap` of the same predictions (the evidence of an effect needs both), made
    once."""
    return [preds[d.case].speed_at(d.s[~d.calibration], commanded=d.commanded) for d in data]


def held_out_chunks(
    preds: Sequence[Prediction], data: Sequence[Data], speeds: Sequence[NDArray] | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per held-out piece (run by run): the time-weighted sum of the squared gap
    ((mm/min)^2 s) and the time (s) -- the samples the decision rule's test uses.
    ``speeds``: the predictions' :func:`held_out_speeds`, if made already."""
    sq: list[float] = []
    n: list[float] = []
    for i, d in enumerate(data):
        sel = ~d.calibration
        if not sel.any():
            continue
        chunk = d.chunk if d.chunk is not None else np.zeros(d.s.size, dtype=np.int64)
        v = preds[d.case].speed_at(d.s[sel], commanded=d.commanded) if speeds is None else speeds[i]
        r = (d.v[sel] - v) * PER_MIN
        w = d.weight[sel]
        c = chunk[sel]
        u = np.unique(c)
        sq.extend(np.bincount(c, weights=w * r * r, minlength=CHUNKS * PIECES)[u].tolist())
        n.extend(np.bincount(c, weights=w, minlength=CHUNKS * PIECES)[u].tolist())
    return np.asarray(sq), np.asarray(n)


#: Profiles whose speeds on a selection of a grid :func:`_speeds` keeps.
RECENT = 3


def _move_values(pred: Prediction) -> NDArray[np.int64] | None:
    """(fields, n) the bits of every per-move value the profile's speed at a place depends on
    (:meth:`core.engine.profile.Profile.speed_at`), or None where the prediction is not a
    profile's speed (point model, time-domain filters)."""
    prof = pred.profile
    su = pred.setup
    if prof is None or not (su.servo_tau <= 0 and su.filter_window <= 0):
        return None
    tp = prof.toolpath
    cols = [
        tp.start_s,
        tp.length,
        prof.v_entry,
        prof.v_peak,
        prof.v_exit,
        prof.a_up,
        prof.a_down,
        prof.hold_start,
        prof.hold_end,
        *(prof.ramps or ()),
    ]
    if prof.arc_ramps is not None:  # holds whose speed changes along them (and their ratios)
        ar = prof.arc_ramps
        cols += [prof.hold_start_ratio, prof.hold_end_ratio, ar.start, ar.end, ar.a_start, ar.a_end]
    return np.stack([np.asarray(c, dtype=np.float64).view(np.int64) for c in cols])


def _speeds(
    pred: Prediction, d: Data, which: str, sel: NDArray[np.bool_], s: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The predicted speed at the grid points ``sel`` of ``d`` (``s``: their arc lengths,
    d.s[sel]): where a recent profile on the same selection had every per-move value of a
    move bit for bit (a fit's candidates often change a few moves), its speeds there, the
    others computed -- the same values as ``pred.speed_at`` everywhere (the speed at a
    place depends on its move's values alone)."""
    bits = _move_values(pred) if which == "calibration" else None
    if bits is None:
        return pred.speed_at(s, commanded=d.commanded)
    entry = d.memo.get(which)
    # (copies of a Data share its memo: kept for this grid and selection only)
    if entry is None or entry[0] is not sel or entry[1] is not d.s:
        entry = d.memo[which] = (sel, d.s, [])
    recent: list[tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]] = entry[2]
    best = None
    for old_bits, k, v in recent:
        if old_bits.shape != bits.shape or not np.array_equal(old_bits[0], bits[0]):
            continue  # other moves (their starts decide which move a place is on)
        changed = _changed_moves(old_bits, bits)[k]
        if best is None or np.count_nonzero(changed) < np.count_nonzero(best[0]):
            best = (changed, k, v)
    if best is None:
        k = pred.toolpath.move_at(s)
        v = pred.speed_at(s)
    else:
        changed, k, v = best
        v = v.copy()
        if changed.any():
            v[changed] = pred.speed_at(s[changed])
    recent.append((bits, k, v))
    del recent[:-RECENT]
    return v


def _changed_moves(old: NDArray[np.int64], new: NDArray[np.int64]) -> NDArray[np.bool_]:
    """The moves (columns of two (values, moves) arrays of bits) where any value differs."""
    kernels = compiled()
    if kernels is not None:  # one pass, no (values, moves) temporary
        return kernels.changed_moves(old, new)
    return (old != new).any(axis=0)


def _selected(d: Data, which: str, sel: NDArray[np.bool_]) -> tuple[NDArray, NDArray, NDArray]:
    """The arc lengths, measured speeds and time weights of ``d`` at its grid points
    ``sel``: for the calibration data (``which``) gathered once per grid and selection (a
    fit asks for them at every candidate), else gathered."""
    if which != "calibration":
        return d.s[sel], d.v[sel], d.weight[sel]
    key = "calibration rows"
    entry = d.memo.get(key)
    # (copies of a Data share its memo: kept for this grid, its speeds and weights only)
    made_of = (sel, d.s, d.v, d.weight)
    if entry is None or any(a is not b for a, b in zip(entry[:4], made_of, strict=True)):
        entry = d.memo[key] = (*made_of, d.s[sel], d.v[sel], d.weight[sel])
    return entry[4], entry[5], entry[6]


def gap(
    preds: Sequence[Prediction],
    data: Sequence[Data],
    which: str,
    speeds: Sequence[NDArray] | None = None,
) -> float:
    """RMS over time of measured - predicted feed (mm/min) on the calibration, held-out or
    all data. ``speeds``: for the held-out data, the predictions' :func:`held_out_speeds`,
    if made already."""
    sq, n = 0.0, 0.0
    for i, d in enumerate(data):
        sel = (
            d.calibration
            if which == "calibration"
            else ~d.calibration
            if which == "held_out"
            else np.ones(d.s.size, dtype=bool)
        )
        if not sel.any():
            continue
        s_sel, v_sel, w = _selected(d, which, sel)
        if which == "held_out" and speeds is not None:
            r = v_sel - speeds[i]
        else:
            r = v_sel - _speeds(preds[d.case], d, which, sel, s_sel)
        sq += float(np.sum(w * r * r))
        n += float(w.sum())
    return math.sqrt(sq / n) * PER_MIN if n > 0 else 0.0


def rapid_gap(preds: Sequence[Prediction], data: Sequence[Data]) -> float:
    """RMS over time of measured - predicted speed (mm/min) on the rapids of every trace
    (NaN where the traces cover none). Only the effects that act on the rapids are fitted
    on them (on their calibration half, :func:`rapid_data`): where effects explain the feed
    moves equally, the rapids are evidence most of them have not seen."""
    sq, n = 0.0, 0.0
    for d in data:
        if d.rapid_s.size == 0:
            continue
        r = d.rapid_v - preds[d.case].speed_at(d.rapid_s, commanded=d.commanded)
        sq += float(np.sum(d.rapid_weight * r * r))
        n += float(d.rapid_weight.sum())
    return math.sqrt(sq / n) * PER_MIN if n > 0 else math.nan


def rapid_data(data: Sequence[Data]) -> tuple[list[Data], str]:
    """The rapids of every run as data of their own -- speed and time weight on the same
    kind of grid, the fastest measured rapid of the run standing for F -- split into
    calibration and held-out data as the feed moves are (:func:`split`). Runs with fewer
    than MIN_RAPID_POINTS grid points on rapids are left out."""
    views = [
        dataclasses.replace(
            d,
            s=d.rapid_s,
            v=d.rapid_v,
            feed=np.full(d.rapid_s.size, float(d.rapid_v.max())),
            move=d.rapid_move,
            weight=d.rapid_weight,
            calibration=np.ones(d.rapid_s.size, dtype=bool),
            chunk=None,
            memo={},
            rapid_s=d.rapid_s[:0],
            rapid_v=d.rapid_v[:0],
            rapid_weight=d.rapid_weight[:0],
            rapid_move=d.rapid_move[:0],
        )
        for d in data
        if d.rapid_s.size >= MIN_RAPID_POINTS
    ]
    if not views:
        return [], "no rapids"
    return split(views)


def feed_level(data: Sequence[Data]) -> float:
    """RMS over time of the programmed feed on the held-out data (mm/min)."""
    sq, n = 0.0, 0.0
    for d in data:
        sel = ~d.calibration
        sq += float(np.sum(d.weight[sel] * d.feed[sel] ** 2))
        n += float(d.weight[sel].sum())
    return math.sqrt(sq / n) * PER_MIN if n > 0 else 0.0


def trace_noise(data: Sequence[Data]) -> float:
    """The noise of the measured feed itself (mm/min RMS): the noise floor of a machine whose
    file gives none. From the samples in time (:func:`sample_noise`; the median over the
    traces) where every trace has it, else from the second differences along the path grid
    of the held-out points (coarse or event-based recordings)."""
    if data and all(math.isfinite(d.noise) for d in data):
        return float(np.median([d.noise for d in data])) * PER_MIN
    d2 = [np.diff(d.v[~d.calibration], 2) for d in data if (~d.calibration).sum() > 2]
    if not d2:
        return 0.0
    return _robust_d2_rms(np.concatenate(d2)) * PER_MIN
