"""The block-time objective: the time between observed program-line changes, measured against
predicted.

A recording that samples the feed coarsely (MTConnect polls every 0.1-0.2 s) shows the
motion only as averages; the feed gap (:mod:`core.diagnosis.resample`) cannot see a machine
through it. It still says, at every poll, which program line is running. Between two
observed changes, line ``a`` first seen at ``t_a`` and line ``b`` first seen at ``t_b``, the
machine ran lines ``a .. b - 1``: measured ``t_b - t_a``, predicted the profile's motion
time plus rests of the moves of those lines (the time between the starts of lines ``a``
and ``b``). Each end is late by a share of a poll, the same share on average, so the
difference is unbiased and its noise (about a poll / sqrt(6)) does not depend on the
machine; summed over many changes it shows a few per cent of block time.

Only feed blocks are compared (:func:`feed_lines`): an interval counts when every line in
it carries feed moves (G1/G2/G3) and nothing else. Left out are the lines of rapids -- where
CAM output puts the tool changes, spindle and coolant starts (M3, M8, each a wait of
seconds), the returns home (G28/G53, to a position the program does not state) -- and the
lines without motion, whose time ncperf does not predict: stops (M0/M1), tool calls (M6),
spindle stops, program end (M30), dwells, and comments or modal settings (harmless, but the
tool path cannot tell them from the others). A feed line that also carries an M-code of
that kind (``G1 X10 M8``) is not detected: the tool path does not keep M-codes.

The errors are compared over windows, not interval by interval: consecutive intervals (the
next starting at the line the last one ended on) summed until they last WINDOW_PERIODS
sampling periods. Which lines a poll happens to see depends on how long they last, so the
delay of each observed change is correlated with the model: fitted interval by interval,
on reversing strokes of a refvm trace sampled every 0.2 s, the acceleration scale came out
0.36 for a true 0.32; over windows the delays inside cancel (the sum telescopes), only the
two ends remain, and the fit finds 0.32. The gap is the RMS over windows of measured -
predicted time (ms); the held-out data are other runs (or programs), or alternate stretches
of one run, as for the feed gap.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from core.diagnosis.align import Alignment
from core.diagnosis.rules import (
    BLOCK_FLOOR_SHARE,
    CHUNKS,
    COARSE_SAMPLING,
    PIECES,
    WINDOW_PERIODS,
)
from core.engine.predict import Prediction
from core.model.toolpath import ToolPath

#: Block-time gaps are reported in ms; computed in s.
PER_MS = 1000.0


@dataclass(frozen=True, eq=False)
class BlockData:
    """Intervals between observed line changes of one trace, over feed blocks only.

    Attributes
    ----------
    first, last : (k,) int64
        The interval runs program lines ``first .. last - 1`` (``last``: the line observed
        next).
    t : (k,) float, s
        When ``first`` was observed (from the trace's start).
    measured : (k,) float, s
        Time until ``last`` was observed.
    calibration : (k,) bool
        Intervals used for fitting (the others are held out).
    label : str
    case : int
        Which program (tool path) the trace ran.
    period : float, s
        The trace's sampling period (median): how late an observed change can be.
    window : (k,) int64
        The window (0, 1, ...) each interval is summed into (see the module docstring).
    chunk : (k,) int64 or None
        The piece of the run each interval's window is in (CHUNKS stretches of PIECES pieces
        of equal time), the samples of the decision rule's significance test.
    """

    first: NDArray[np.int64]
    last: NDArray[np.int64]
    t: NDArray[np.float64]
    measured: NDArray[np.float64]
    calibration: NDArray[np.bool_]
    label: str
    case: int = 0
    period: float = 0.0
    window: NDArray[np.int64] = dataclasses.field(default_factory=lambda: np.zeros(0, np.int64))
    chunk: NDArray[np.int64] | None = None


def has_lines(al: Alignment) -> bool:
    """Whether the trace itself carried program lines (not lines placed by the alignment)."""
    return al.method in ("line and feed", "line and position")


def sample_period(al: Alignment) -> float:
    """Median time between the trace's samples (s); inf for fewer than two."""
    return float(np.median(np.diff(al.t))) if al.t.size > 1 else math.inf


def is_coarse(alignments: Sequence[Alignment]) -> bool:
    """Whether the block-time objective is the one to calibrate on: every trace carries
    program lines and samples coarser than COARSE_SAMPLING (median period)."""
    return bool(alignments) and all(
        has_lines(al) and sample_period(al) > COARSE_SAMPLING for al in alignments
    )


def feed_lines(tp: ToolPath) -> NDArray[np.bool_]:
    """(max line + 2,) whether each program line carries feed moves and nothing else (see
    the module docstring): lines without moves and lines with a rapid are False."""
    size = int(tp.line.max(initial=0)) + 2
    feed = np.zeros(size, dtype=bool)
    feed[tp.line[tp.is_feed]] = True
    rapid = np.zeros(size, dtype=bool)
    rapid[tp.line[~tp.is_feed]] = True
    return feed & ~rapid


def block_data(tp: ToolPath, al: Alignment, label: str, case: int = 0) -> BlockData:
    """The feed-block intervals between the observed line changes of an aligned trace."""
    line = np.asarray(al.line, dtype=np.int64)
    change = np.flatnonzero(np.diff(line) != 0) + 1
    t, seen = al.t[change], line[change]
    a, b = seen[:-1], seen[1:]
    ok_line = feed_lines(tp)
    # Lines outside the program count as not feed: bad[L] = non-feed lines before L.
    bad = np.concatenate([[0], np.cumsum(~ok_line)])
    inside = (a > 0) & (b > a) & (b < ok_line.size)
    ac, bc = np.where(inside, a, 0), np.where(inside, b, 0)
    keep = inside & (bad[bc] == bad[ac])
    first, last = a[keep], b[keep]
    ta = t[:-1][keep]
    measured = (t[1:] - t[:-1])[keep]
    period = sample_period(al) if al.t.size > 1 else 0.0
    window = windows(first, last, measured, WINDOW_PERIODS * period)
    # Each window's piece is that of its first interval (a window is fitted or held out whole).
    start = np.flatnonzero(np.diff(window, prepend=-1) != 0)
    chunk = pieces(ta)[start][window] if first.size else np.zeros(0, dtype=np.int64)
    return BlockData(
        first=first,
        last=last,
        t=ta,
        measured=measured,
        calibration=np.ones(first.size, dtype=bool),
        label=label,
        case=case,
        period=period,
        window=window,
        chunk=chunk,
    )


def windows(
    first: NDArray[np.int64], last: NDArray[np.int64], measured: NDArray[np.float64], span: float
) -> NDArray[np.int64]:
    """(k,) window of every interval: within a run of consecutive intervals (each starting
    at the line the previous one ended on), the intervals that start within the same
    ``span`` seconds of the run's start; numbered 0, 1, ... in order."""
    k = first.size
    if k == 0:
        return np.zeros(0, dtype=np.int64)
    new_run = np.ones(k, dtype=bool)
    new_run[1:] = first[1:] != last[:-1]
    run = np.cumsum(new_run) - 1
    before = np.cumsum(measured) - measured  # time from the trace's first interval
    local = before - before[np.flatnonzero(new_run)][run]
    slot = np.floor(local / span).astype(np.int64) if span > 0 else np.arange(k)
    edge = new_run.copy()
    edge[1:] |= slot[1:] != slot[:-1]
    return np.cumsum(edge) - 1


def pieces(t: NDArray[np.float64]) -> NDArray[np.int64]:
    """The piece (0..CHUNKS x PIECES - 1, equal time between the first and last interval)
    of every interval starting at ``t`` (s)."""
    k = CHUNKS * PIECES
    if t.size == 0:
        return np.zeros(0, dtype=np.int64)
    lo, hi = float(t[0]), float(t[-1])
    span = hi - lo if hi > lo else 1.0
    return np.clip(((t - lo) / span * k).astype(np.int64), 0, k - 1)


def split(data: Sequence[BlockData]) -> tuple[list[BlockData], str]:
    """Calibration / held-out split, as :func:`core.diagnosis.resample.split`: several runs
    of one program, alternate runs; else alternate stretches of every run."""
    programs = {d.case for d in data}
    if len(data) >= 2 and len(programs) == 1:
        out = [
            dataclasses.replace(d, calibration=np.full(d.first.size, k % 2 == 0))
            for k, d in enumerate(data)
        ]
        cal = ", ".join(d.label for k, d in enumerate(data) if k % 2 == 0)
        held = ", ".join(d.label for k, d in enumerate(data) if k % 2 == 1)
        return out, f"other runs: fitted on {cal}, measured on {held}"
    out = []
    for k, d in enumerate(data):
        chunk = d.chunk if d.chunk is not None else pieces(d.t)
        out.append(dataclasses.replace(d, calibration=(chunk // PIECES) % 2 == k % 2))
    runs = "one run" if len(data) == 1 else f"each of {len(data)} runs"
    return out, (
        f"alternate stretches of {runs} ({CHUNKS} stretches of equal time, every other one "
        "fitted and the others measured)"
    )


def line_starts(pred: Prediction) -> NDArray[np.float64]:
    """(max line + 3,) predicted time (s) from the program's first move to the start of each
    line: the motion time and rests of every move of the lines before it."""
    tp = pred.toolpath
    if pred.profile is not None:
        per_move = pred.profile.time + pred.profile.rest
    else:  # the paper's point model: each block at its own speed
        per_move = tp.length / pred.block_speed + tp.dwell
    per_line = np.bincount(tp.line, weights=per_move, minlength=int(tp.line.max(initial=0)) + 2)
    return np.concatenate([[0.0], np.cumsum(per_line)])


def expected(pred: Prediction, d: BlockData) -> NDArray[np.float64]:
    """(k,) predicted time (s) between the observed changes of every interval.

    A change is seen at the first sample after it, late by a share of the sampling period
    p; but a line that lasts d < p is seen only when a sample falls inside it, and then
    within d of its start. With samples at a random phase the delay of an observed line is
    uniform on [0, min(d, p)): its mean min(d, p) / 2. The interval from line a to line b
    is therefore expected to last start_b - start_a + (min(d_b, p) - min(d_a, p)) / 2: without
    this, the errors of short lines depend on the model (a share of their predicted
    duration), and the fit is drawn away from the truth (an acceleration scale 0.36 for a
    true 0.32 on reversing strokes sampled every 0.2 s).
    """
    start = line_starts(pred)
    own = np.diff(start)  # each line's own predicted time
    p = d.period
    late_a = np.minimum(own[d.first], p)
    late_b = np.minimum(own[d.last], p)
    return start[d.last] - start[d.first] + 0.5 * (late_b - late_a)


def errors(pred: Prediction, d: BlockData) -> NDArray[np.float64]:
    """(k,) measured - expected time of every interval (s), see :func:`expected`."""
    return d.measured - expected(pred, d)


def _select(d: BlockData, which: str) -> NDArray[np.bool_]:
    if which == "calibration":
        return d.calibration
    if which == "held_out":
        return ~d.calibration
    return np.ones(d.first.size, dtype=bool)


def window_errors(
    pred: Prediction, d: BlockData, sel: NDArray[np.bool_]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Measured - predicted time (s) of the windows of the selected intervals, and the
    windows' ids."""
    e = errors(pred, d)[sel]
    w = d.window[sel]
    ids = np.unique(w)
    sums = np.bincount(w, weights=e, minlength=int(d.window.max(initial=0)) + 1)
    return sums[ids].astype(np.float64), ids


def gap(preds: Sequence[Prediction], data: Sequence[BlockData], which: str) -> float:
    """RMS over windows of measured - predicted time (ms) on the calibration, held-out or
    all data."""
    sq, n = 0.0, 0
    for d in data:
        sel = _select(d, which)
        if not sel.any():
            continue
        e, _ = window_errors(preds[d.case], d, sel)
        sq += float(np.sum(e * e))
        n += e.size
    return math.sqrt(sq / n) * PER_MS if n else 0.0


def held_out_chunks(
    preds: Sequence[Prediction], data: Sequence[BlockData]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per held-out piece (run by run): the sum of the windows' squared errors (ms^2) and
    their number -- the samples of the decision rule's test."""
    sq: list[float] = []
    n: list[float] = []
    k = CHUNKS * PIECES
    for d in data:
        sel = ~d.calibration
        if not sel.any():
            continue
        chunk = d.chunk if d.chunk is not None else np.zeros(d.first.size, dtype=np.int64)
        e, ids = window_errors(preds[d.case], d, sel)
        e = e * PER_MS
        # the piece of each window: that of its intervals (one per window)
        c = np.zeros(int(d.window.max(initial=0)) + 1, dtype=np.int64)
        c[d.window[sel]] = chunk[sel]
        c = c[ids]
        u = np.unique(c)
        sq.extend(np.bincount(c, weights=e * e, minlength=k)[u].tolist())
        n.extend(np.bincount(c, minlength=k)[u].astype(float).tolist())
    return np.asarray(sq), np.asarray(n)


def floor(data: Sequence[BlockData]) -> float:
    """The least RMS reduction (ms) an effect must bring: BLOCK_FLOOR_SHARE of the RMS
    measured window time on the held-out data."""
    parts: list[NDArray[np.float64]] = [np.zeros(0)]
    for d in data:
        held = ~d.calibration
        if held.any():
            parts.append(np.bincount(d.window[held], weights=d.measured[held]).astype(np.float64))
    m = np.concatenate(parts)
    m = m[m > 0]
    return BLOCK_FLOOR_SHARE * float(np.sqrt(np.mean(m * m))) * PER_MS if m.size else 0.0
