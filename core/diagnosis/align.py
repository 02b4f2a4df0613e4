"""Aligning a measured trace with the program: each sample's place on the path (arc length).

* With positions, each sample is projected on the path, near the move of its program line
  when the trace has lines, else within a window ahead of where the previous samples were;
  a rigid offset between program and machine coordinates is fitted first (and reported);
  the arc lengths are then made non-decreasing in time (isotonic regression), which absorbs
  noise and small back-steps.
* With program lines and a feed but no positions (MTConnect recordings), a sample is at the
  start of its block plus the distance the feed covered since the block began, within the
  block.

The measured feed is the trace's own where it has one and it agrees with the positions,
else the speed of the positions (chords over a few samples). Alignment quality -- how far
the samples are from the path, how much of the path the trace covers -- is measured and
stated, so that a trace of another program, or in other units, is reported as such rather
than diagnosed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from core.model import geometry as g
from core.model.errors import InputError
from core.model.jit import allow, compiled
from core.model.pieces import SPLIT, side_by_side, two_cores
from core.model.sampling import PROJECTION_STEP, PathSamples, isotonic
from core.model.tolerances import TOL
from core.model.toolpath import ToolPath
from core.model.trace import Trace
from core.model.workers import forked_map, workers_for

#: Samples per sequential search chunk without line numbers, and how far ahead (mm) beyond
#: what the fastest move could cover a chunk may look.
CHUNK = 256
AHEAD_MARGIN = 5.0
#: Pieces of program lines per worker process the projection is cut into (pieces of about
#: equal sample counts; several per worker, so that one slow piece does not hold the others).
LINE_PIECES = 4
#: A sample farther than this from the path (mm) is "off the path" for the quality figures
#: (at least; 20 x the largest path tolerance when that is larger).
FAR = 0.5
#: Alignment is poor when more than this share of samples is off the path, or when the trace
#: covers less than MIN_COVERAGE of the program's feed length.
MAX_FAR_SHARE = 0.2
MIN_COVERAGE = 0.5
#: Rounding room (mm) of the compiled search's skip (:func:`_jumps`): far above the rounding
#: of distances and arc lengths of coordinates up to 10^5 mm (about 1e-11 mm), far below the
#: path's spacing.
SKIP_SLACK = 1e-6
#: How far behind its program line's move a sample may be (mm): actual positions lag the
#: setpoint whose line the controller reports (v tau: 10 mm at 20 m/min and 30 ms).
LAG_BACK = 10.0
#: Half-width (samples) of the central difference that turns arc length into feed.
DIFF_HALF = 2
#: A trace's own feed column is used when it agrees with its positions: relative RMS
#: difference below CONSISTENT after smoothing both over SMOOTH_S. (The LinuxCNC suite's
#: columns agree to 0.01-0.3 %; a 10 ms servo lag on the positions alone gives 1.5-9.6 %.)
CONSISTENT = 0.012
SMOOTH_S = 0.02
#: A column used that still differs from its positions' speed by more than COMMANDED (the
#: same measure) is not their speed: it is the controller's commanded feed, which a
#: setpoint filter smooths in time while the filtered positions cut inside corners and arcs
#: and run slower there. A trace whose column is the positions' own speed agrees with them
#: to derivative noise, as LinuxCNC's runs of the unchanged machine do: at most 0.14 % on
#: the 1190 of the blind benchmark's sets drawn20-drawn40 (thread milling's helices). The
#: predictions are then read the same way (:meth:`core.engine.predict.Prediction.speed_at`
#: with ``commanded``). On those sets the filters of 10-60 ms whose column is used differ by
#: 0.06-1.2 % (those under 0.2 % fit either reading alike), and LinuxCNC's runs at 2-4 ms
#: servo periods by up to 1.4 % (a coarser clock: read as commanded too).
COMMANDED = 0.002


@dataclass(frozen=True, eq=False)
class Alignment:
    """A trace placed on a program's path.

    Attributes
    ----------
    s : (m,) float, mm
        Arc length of each sample from the program start (rapids included),
        non-decreasing.
    v : (m,) float, mm/s
        Measured path feed at each sample.
    t : (m,) float, s
    line : (m,) int
        Program line of each sample (from the trace, or from where it was placed).
    method : str
        "line and feed", "line and position" or "position".
    offset : (3,) float, mm
        Rigid offset of the trace's coordinates from the program's (trace - program).
    distance : (m,) float, mm
        Distance of each sample from the path (NaN without positions).
    coverage : float
        Share of the program's feed length the trace runs along.
    far_share : float
        Share of samples farther than the "off the path" distance.
    ok : bool
        Whether the alignment is good enough to diagnose.
    message : str
        One line on the quality (and, when poor, what it suggests).
    """

    s: NDArray[np.float64]
    v: NDArray[np.float64]
    t: NDArray[np.float64]
    line: NDArray[np.int64]
    method: str
    offset: NDArray[np.float64]
    distance: NDArray[np.float64]
    coverage: float
    far_share: float
    ok: bool
    message: str
    notes: tuple[str, ...] = field(default_factory=tuple)
    #: The measured feed ``v`` is the trace's commanded-feed column, which differs from its
    #: positions' speed (COMMANDED): predictions are read as that column is.
    commanded: bool = False


#: Most iterations of the rigid offset fit (it stops once a step is under TOL.offset_step;
#: halving steps reach 1e-4 mm from a 1 mm start in about 14).
OFFSET_ITERATIONS = 60
#: An offset is kept only where it brings the trace this much closer to the path (median
#: distance, mm) than none: an offset the path cannot pin down is not reported.
OFFSET_GAIN = 0.01


def _nearest(
    q: NDArray, p: NDArray, s_p: NDArray | None = None, s_exp: NDArray | None = None
) -> tuple[NDArray, NDArray]:
    """Index of the nearest of ``p`` (k, 3) for each of ``q`` (m, 3), and the distance.

    With ``s_p`` (k,) and ``s_exp`` (m,), points equally near are told apart by how close
    their arc length is to the expected one (a penalty of TOL.sequence_tie mm per mm of arc length).
    """
    # the squared differences, axis by axis (the compiled search's arithmetic, point by
    # point: core.model.compiled.project_lines; |q|^2 - 2 q.p + |p|^2 through a matrix
    # product lost digits at coordinates of hundreds of mm and its bits were the BLAS's)
    d2 = np.subtract(q[:, 0, None], p[None, :, 0])
    np.multiply(d2, d2, out=d2)
    for ax in (1, 2):
        d = np.subtract(q[:, ax, None], p[None, :, ax])
        np.multiply(d, d, out=d)
        np.add(d2, d, out=d2)
    if s_p is not None and s_exp is not None:
        key = np.subtract(s_p[None, :], s_exp[:, None])
        np.multiply(key, TOL.sequence_tie, out=key)
        np.square(key, out=key)
        np.add(d2, key, out=key)
        k = np.argmin(key, axis=1)
    else:
        k = np.argmin(d2, axis=1)
    return k, np.sqrt(d2[np.arange(q.shape[0]), k])


def _run_on(q: NDArray, start: float) -> tuple[NDArray, NDArray]:
    """The steps between samples ``q`` (m, 3), and where the samples would be along the path
    if they ran on from arc length ``start`` by their own travel: ties between equally near
    points are broken by it, which tells apart two passes over the same points (a plunge
    down its retract)."""
    step = np.linalg.norm(np.diff(q, axis=0), axis=1)
    return step, start + np.concatenate([[0.0], np.cumsum(step)])


def _project(
    tp: ToolPath, q: NDArray, lines: NDArray | None, path: PathSamples, jobs: int = 1
) -> tuple[NDArray, NDArray]:
    """Arc length and distance of points ``q`` on the path (see the module docstring). With
    lines, each line's samples are projected on their own: in the compiled kernel where
    the kernels are in use (:func:`_project_compiled`; 344k samples of a 1 ms recording in
    0.2 s), else by numpy on ``jobs`` worker processes, LINE_PIECES pieces of lines each,
    where it can (:mod:`core.model.workers`)."""
    pts, s_p, owner = path.points, path.s, path.move
    m = q.shape[0]
    s = np.zeros(m)
    dist = np.full(m, np.inf)
    if lines is not None and np.any(lines > 0):
        line_of_sample = lines
        # The samples of each line (in time order), and the path points of moves a..b as
        # index ranges: the path points are in move order, and (checked) in arc length.
        by_line = np.argsort(line_of_sample, kind="stable")
        u_all, u_first = np.unique(line_of_sample[by_line], return_index=True)
        u_last = np.append(u_first[1:], m)
        ordered = s_p.size < 2 or bool(np.all(s_p[1:] >= s_p[:-1]))
        searched = (
            _project_compiled(q, by_line, u_all, u_first, u_last, tp, path) if ordered else None
        )
        if searched is not None:
            s_l, d_l, done_l = searched
            s[by_line], dist[by_line] = s_l, d_l
            done = np.zeros(m, dtype=bool)
            done[by_line] = done_l
            return _rest(q, np.flatnonzero(~done), s, dist, path)
        moves_of_line: dict[int, tuple[int, int]] = {}
        lp = tp.line
        order = np.argsort(lp, kind="stable")
        uniq, first_idx = np.unique(lp[order], return_index=True)
        last_idx = np.append(first_idx[1:], order.size)
        for u, a, b in zip(uniq.tolist(), first_idx.tolist(), last_idx.tolist(), strict=True):
            mv = order[a:b]
            moves_of_line[u] = (int(mv.min()), int(mv.max()))

        def piece(j0: int, j1: int) -> tuple[NDArray, NDArray, NDArray]:
            """Lines j0..j1-1 (of ``u_all``): the arc length, distance and whether placed
            of their samples, ``by_line[u_first[j0]:u_last[j1 - 1]]``."""
            f_lo = int(u_first[j0])
            size = int(u_last[j1 - 1]) - f_lo
            s_g, dist_g = np.zeros(size), np.full(size, np.inf)
            done_g = np.zeros(size, dtype=bool)
            for u, f0, f1 in zip(
                u_all[j0:j1].tolist(), u_first[j0:j1].tolist(), u_last[j0:j1].tolist(), strict=True
            ):
                if u not in moves_of_line:
                    continue
                sel = by_line[f0:f1]
                a, b = moves_of_line[u]
                # The move of the line, or its neighbours (blends carry a neighbour's line),
                # or up to LAG_BACK mm behind (actual positions lag the setpoint's line)
                # where one of them is nearer: the line's own move wins ties, such as a
                # plunge back down the path of the retract before it.
                if ordered:
                    i_a, i_b1 = np.searchsorted(owner, (a, b + 1))
                    own = np.arange(i_a, i_b1)
                    s_a = s_p[own[0]] if own.size else 0.0
                    i_n0, i_n1 = np.searchsorted(owner, (a - 1, b + 2))
                    i_s = int(np.searchsorted(s_p, s_a - LAG_BACK))  # first s_p >= s_a - LAG_BACK
                    lag = np.arange(i_s, i_b1)
                    near = np.arange(i_n0, i_n1)
                    win = (
                        np.arange(min(i_n0, i_s), max(i_n1, i_b1))
                        if lag.size and near.size and i_s <= i_n1 and i_n0 <= i_b1
                        else np.union1d(near, lag)
                    )
                else:
                    own = np.flatnonzero((owner >= a) & (owner <= b))
                    s_a = s_p[own[0]] if own.size else 0.0
                    win = np.flatnonzero(
                        ((owner >= a - 1) & (owner <= b + 1))
                        | ((s_p >= s_a - LAG_BACK) & (owner <= b))
                    )
                # (on from the line's start: a drilling cycle's feed down and rapid back up
                # its own hole are one line)
                _, s_exp = _run_on(q[sel], s_a)
                for c in range(0, sel.size, 2048):
                    part = sel[c : c + 2048]
                    e = s_exp[c : c + 2048]
                    # where the part's samples are in this piece's arrays
                    at = slice(f0 - f_lo + c, f0 - f_lo + c + part.size)
                    k, dd = _nearest(q[part], pts[own], s_p[own], e)
                    s_g[at] = s_p[own[k]]
                    dist_g[at] = dd
                    if win.size > own.size:
                        k2, d2 = _nearest(q[part], pts[win], s_p[win], e)
                        nearer = d2 < dd - TOL.pass_tie
                        s_g[at][nearer] = s_p[win[k2[nearer]]]
                        dist_g[at][nearer] = d2[nearer]
                done_g[f0 - f_lo : f1 - f_lo] = True
            return s_g, dist_g, done_g

        # pieces of lines with about as many samples each
        workers = workers_for(jobs, u_all.size)
        count = 1 if workers == 1 else workers * LINE_PIECES
        bounds = np.searchsorted(u_first, np.linspace(0, m, count + 1)[1:-1]).tolist()
        edges = [0, *bounds, int(u_all.size)]
        spans = [(j0, j1) for j0, j1 in zip(edges[:-1], edges[1:], strict=True) if j1 > j0]
        if len(spans) == 1:
            placed = [piece(*spans[0])]
        else:
            placed = forked_map(lambda k: piece(*spans[k]), len(spans), workers)
        done = np.zeros(m, dtype=bool)
        for (j0, j1), (s_g, dist_g, done_g) in zip(spans, placed, strict=True):
            idx = by_line[int(u_first[j0]) : int(u_last[j1 - 1])]
            s[idx], dist[idx], done[idx] = s_g, dist_g, done_g
        rest = np.flatnonzero(~done)
    else:
        rest = np.arange(m)
    return _rest(q, rest, s, dist, path)


def _project_compiled(
    q: NDArray,
    by_line: NDArray,
    u_all: NDArray,
    u_first: NDArray,
    u_last: NDArray,
    tp: ToolPath,
    path: PathSamples,
) -> tuple[NDArray, NDArray, NDArray] | None:
    """:func:`_project`'s search of each program line's samples (path points in arc
    length) in the compiled kernel (core.model.jit), the lines' own points and windows
    found for all lines at once: the arc length and distance of the samples ``by_line``
    (in that order) and whether their line is one of the program's. None where the kernels
    are not in use, or where a line has no path point of its own (numpy's search says what
    that is)."""
    kernels = compiled()
    if kernels is None or tp.n == 0 or path.s.size == 0:
        return None
    owner, s_p = path.move, path.s
    # each program line's first and last move
    order = np.argsort(tp.line, kind="stable")
    uniq, first_idx = np.unique(tp.line[order], return_index=True)
    lo_move = np.minimum.reduceat(order, first_idx)
    hi_move = np.maximum.reduceat(order, first_idx)
    at = np.minimum(np.searchsorted(uniq, u_all), uniq.size - 1)
    known = uniq[at] == u_all
    a, b = lo_move[at][known], hi_move[at][known]
    i_a, i_b1 = np.searchsorted(owner, a), np.searchsorted(owner, b + 1)
    if np.any(i_b1 <= i_a):
        return None
    s_a = s_p[i_a]
    # the window: the neighbouring moves' points and up to LAG_BACK mm behind, as one range
    # where they meet, else two in order (np.union1d of the two)
    i_n0, i_n1 = np.searchsorted(owner, a - 1), np.searchsorted(owner, b + 2)
    i_s = np.searchsorted(s_p, s_a - LAG_BACK)
    has_lag, has_near = i_b1 > i_s, i_n1 > i_n0
    lag = np.stack([i_s, i_b1], 1)
    near = np.stack([i_n0, i_n1], 1)
    none = np.zeros_like(lag)
    meet = has_lag & has_near & (i_s <= i_n1) & (i_n0 <= i_b1)
    both = has_lag & has_near & ~meet  # apart: the lower range first
    lag_first = (i_s < i_n0)[:, None]
    first = np.where(has_lag[:, None], lag, np.where(has_near[:, None], near, none))
    first = np.where(both[:, None], np.where(lag_first, lag, near), first)
    merged = np.stack([np.minimum(i_n0, i_s), np.maximum(i_n1, i_b1)], 1)
    first = np.where(meet[:, None], merged, first)
    second = np.where(both[:, None], np.where(lag_first, near, lag), none)
    win = np.ascontiguousarray(np.concatenate([first, second], axis=1), dtype=np.int64)
    lo, hi = u_first[known].astype(np.int64), u_last[known].astype(np.int64)
    qs = q[by_line]
    px, py, pz = path.columns
    cols = tuple(np.ascontiguousarray(qs[:, c]) for c in range(3))
    s_a = np.ascontiguousarray(s_a, dtype=np.float64)
    own = np.stack([i_a, i_b1], 1).astype(np.int64)
    rest = (px, py, pz, np.ascontiguousarray(s_p), (TOL.sequence_tie, TOL.pass_tie), _jumps(path))

    def lines(k: slice) -> tuple[NDArray, NDArray]:
        return kernels.project_lines(*cols, lo[k], hi[k], s_a[k], own[k], win[k], *rest)

    # each line's samples its own: two halves of the samples' lines on two threads (a
    # nogil kernel), each writing its lines' samples (NaN elsewhere)
    h = int(np.searchsorted(hi, qs.shape[0] // 2))
    if qs.shape[0] < 2 * SPLIT or not two_cores() or not 0 < h < lo.size:
        s_l, d_l = lines(slice(None))
    else:
        (s1, d1), (s2, d2) = side_by_side(lambda: lines(slice(0, h)), lambda: lines(slice(h, None)))
        cut = int(lo[h])  # (the first half's lines have the samples before it)
        s_l = np.concatenate([s1[:cut], s2[cut:]])
        d_l = np.concatenate([d1[:cut], d2[cut:]])
    done = np.repeat(known, u_last - u_first)  # the samples of the program's lines
    s_l = np.where(done, s_l, 0.0)
    d_l = np.where(done, d_l, np.inf)
    return s_l, d_l, done


def _jumps(path: PathSamples) -> float:
    """How much farther apart (mm) two path points can be than their arc lengths differ:
    the steps between consecutive points beyond their arc lengths' difference, summed, and
    SKIP_SLACK for rounding. A path that runs on from where it was adds nothing (a chord is
    no longer than its arc); a move that does not start where the one before ended (an arc
    end rounded in the program: 0.1 um) adds its jump. The compiled search skips points
    by it (core.model.compiled._nearest_in)."""
    step = np.linalg.norm(np.diff(path.points, axis=0), axis=1)
    return float(np.sum(np.maximum(step - np.diff(path.s), 0.0))) + SKIP_SLACK


def _rest(q: NDArray, rest: NDArray, s: NDArray, dist: NDArray, path: PathSamples):
    """The samples ``rest`` (without a program line of the path) of :func:`_project`, in
    sequential windows; ``s``, ``dist`` filled in place and returned."""
    pts, s_p = path.points, path.s
    if rest.size:
        # Sequential windows: each chunk searches ahead of where the last one ended.
        s_last = s[rest[0] - 1] if rest[0] > 0 else 0.0
        for c in range(0, rest.size, CHUNK):
            part = rest[c : c + CHUNK]
            step, s_exp = _run_on(q[part], s_last)
            # The chunk cannot run further along the path than its samples travel.
            span = 2.0 * float(step.sum()) + AHEAD_MARGIN
            win = np.flatnonzero((s_p >= s_last - AHEAD_MARGIN) & (s_p <= s_last + span))
            if win.size == 0:
                win = np.arange(s_p.size)
            k, dd = _nearest(q[part], pts[win], s_p[win], s_exp)
            s[part] = s_p[win[k]]
            dist[part] = dd
            s_last = float(np.median(s[part][-8:]))
    return s, dist


def _offset(tp: ToolPath, q: NDArray, lines: NDArray | None, path: PathSamples) -> NDArray:
    """Rigid offset (trace - program) by iterated projection (translation-only ICP)."""
    pts = path.points
    cands = [np.zeros(3), q[0] - tp.start[0], np.median(q, axis=0) - np.median(pts, axis=0)]
    sub = q[:: max(1, q.shape[0] // 2000)]
    sub_lines = None if lines is None else lines[:: max(1, q.shape[0] // 2000)]
    # the projections of the subsample at every offset tried, by its bytes: an offset tried
    # again (the first sample at the program's start: the second candidate is the first;
    # the first iteration starts from a candidate) is not projected again
    done: dict[bytes, tuple[NDArray, NDArray]] = {}

    def projected(off: NDArray) -> tuple[NDArray, NDArray]:
        key = off.tobytes()
        if key not in done:
            done[key] = _project(tp, sub - off, sub_lines, path)
        return done[key]

    meds = []
    for off in cands:
        _, d = projected(off)
        meds.append(float(np.median(d)))
    # No offset unless a candidate fits clearly better: along a direction the path does not
    # constrain (a program along one line) every offset fits alike, and none is the answer.
    k = int(np.argmin(meds))
    off = cands[k] if meds[0] - meds[k] > max(OFFSET_GAIN, 0.5 * meds[0]) else cands[0]
    # Each step removes a share of the remaining error (about half, where corners pull the
    # projections sideways), so the fit runs to convergence, not a fixed count: six halvings
    # left 0.11 mm on a real 840D recording.
    for _ in range(OFFSET_ITERATIONS):
        s, _ = projected(off)
        near = tp.point_at(s)
        step = np.median(sub - off - near, axis=0)
        off = off + step
        if np.linalg.norm(step) < TOL.offset_step:
            break
    _, d_off = projected(off)
    if meds[0] - float(np.median(d_off)) <= OFFSET_GAIN:
        return np.zeros(3)
    return off


def _feed_from_positions(t: NDArray, q: NDArray) -> NDArray:
    """Speed of the positions ``q`` (m, 3): chords over +-DIFF_HALF samples (one-sided at
    the ends). The tool's own speed, also where it leaves the path (a lagging servo cuts a
    corner, and its projection on the path jumps there)."""
    h = DIFF_HALF
    if t.size <= 2 * h:
        return np.linalg.norm(np.gradient(q, t, axis=0), axis=1) if t.size > 1 else np.zeros(t.size)
    v = np.empty(t.size)
    v[h:-h] = g.norm(q[2 * h :] - q[: -2 * h]) / (t[2 * h :] - t[: -2 * h])
    v[:h] = g.norm(q[h : 2 * h] - q[:h]) / (t[h : 2 * h] - t[:h])
    v[-h:] = g.norm(q[-h:] - q[-2 * h : -h]) / (t[-h:] - t[-2 * h : -h])
    return v


def _smooth(x: NDArray, k: int) -> NDArray:
    return np.convolve(x, np.ones(k) / k, mode="same") if k > 1 else x


def _mismatch(t: NDArray, v_col: NDArray, v_pos: NDArray) -> float:
    """Relative RMS difference of a trace's feed column and the feed of its positions, both
    smoothed over SMOOTH_S (which removes the derivative's noise, not a lag)."""
    period = float(np.median(np.diff(t))) if t.size > 1 else SMOOTH_S
    k = max(int(round(SMOOTH_S / period)) | 1, 1)
    a, b = _smooth(v_col, k), _smooth(v_pos, k)
    norm = float(np.sqrt(np.mean(a * a)))
    return float(np.sqrt(np.mean((a - b) ** 2)) / norm) if norm > 0 else 0.0


def align(tp: ToolPath, trace: Trace, *, fit_offset: bool = True, jobs: int = 1) -> Alignment:
    """Place every sample of ``trace`` on the path of ``tp`` (see the module docstring);
    ``jobs``: worker processes for the projection of the samples of each program line (the
    same alignment, sooner)."""
    allow()  # the compiled kernels where numba is installed (core.model.jit)
    start_s, end_s = tp.start_s, tp.end_s
    total_feed = float(tp.length[tp.is_feed].sum()) or float(tp.length.sum())
    tol = np.nan_to_num(tp.tolerance, nan=0.0)
    far = max(FAR, 20.0 * float(tol.max(initial=0.0)))
    notes: list[str] = []
    commanded = False  # (traces without positions: their feed is all there is to read)
    if trace.pos is not None:
        path = tp.sample(PROJECTION_STEP)
        off = _offset(tp, trace.pos, trace.line, path) if fit_offset else np.zeros(3)
        q = trace.pos - off
        s_raw, dist = _project(tp, q, trace.line, path, jobs)
        s = isotonic(s_raw)
        for _ in range(2):
            s_raw, _ = path.project_near(q, s)
            s = isotonic(s_raw)
        dist = g.norm(q - tp.point_at(s))
        method = "line and position" if trace.line is not None else "position"
        v_pos = _feed_from_positions(trace.t, q)
        v = v_pos
        if trace.v is None:
            notes.append(
                f"feed derived from positions (their speed, chords over +-{DIFF_HALF} samples)"
            )
        else:
            mismatch = _mismatch(trace.t, trace.v, v_pos)
            if mismatch <= CONSISTENT:
                v = trace.v
                commanded = mismatch > COMMANDED
                if commanded:
                    notes.append(
                        f"the v column differs from the positions' speed by {mismatch:.2%} "
                        f"RMS after {SMOOTH_S * 1000:g} ms smoothing: read as the commanded "
                        "feed (a setpoint filter smooths it in time; the positions cut "
                        "corners)"
                    )
            else:
                notes.append(
                    f"the v column disagrees with the positions ({mismatch:.1%} RMS after "
                    f"{SMOOTH_S * 1000:g} ms smoothing): the feed is taken from the positions "
                    "(the motion itself)"
                )
        if np.linalg.norm(off) > far:
            notes.append(
                f"trace coordinates offset by ({off[0]:.3f}, {off[1]:.3f}, "
                f"{off[2]:.3f}) mm from the program's"
            )
        line = trace.line if trace.line is not None else tp.line[tp.move_at(s)]
        far_share = float(np.mean(dist > far))
    elif trace.line is not None and trace.v is not None:
        off = np.zeros(3)
        method = "line and feed"
        line = trace.line
        # Each line's first move (lines without moves: the next move's start). Sized by the
        # program, not by the trace: a trace line of 2**31 is just a line the program lacks.
        first_move = np.full(int(tp.line.max()) + 2, -1, dtype=np.int64)
        first_move[tp.line[::-1]] = np.arange(tp.n)[::-1]
        last_move = np.full_like(first_move, -1)
        last_move[tp.line] = np.arange(tp.n)
        nxt = first_move.copy()
        # Lines without a move start where the next line with a move starts.
        idx = np.where(nxt >= 0, np.arange(nxt.size), nxt.size)
        idx = np.minimum.accumulate(idx[::-1])[::-1]
        nxt = np.where(idx < nxt.size, first_move[np.minimum(idx, nxt.size - 1)], tp.n)
        known = (line >= 0) & (line < nxt.size)
        mv0 = np.where(known, nxt[np.clip(line, 0, nxt.size - 1)], tp.n)
        s0 = np.where(mv0 < tp.n, start_s[np.minimum(mv0, tp.n - 1)], end_s[-1])
        mv1 = np.where(known, last_move[np.clip(line, 0, nxt.size - 1)], -1)
        s1 = np.where(mv1 >= 0, end_s[np.maximum(mv1, 0)], s0)
        # Distance run since the block began: integrate the held feed over time.
        change = np.ones(line.size, dtype=bool)
        change[1:] = line[1:] != line[:-1]
        block = np.cumsum(change) - 1
        dt = np.diff(trace.t, prepend=trace.t[0])
        run = np.cumsum(np.concatenate([[0.0], trace.v[:-1]]) * dt)
        run_at_start = run[np.flatnonzero(change)][block]
        s = isotonic(np.minimum(s0 + (run - run_at_start), np.maximum(s1, s0)))
        v = trace.v
        dist = np.full(line.size, np.nan)
        unknown = ~known | (mv0 >= tp.n) & (line > tp.line.max())
        far_share = float(np.mean(unknown))
        if far_share:
            notes.append(f"{far_share:.0%} of samples name lines the program does not have")
    elif trace.v is not None:
        # Only a feed (CSV t,v; SHDR Feed_Rate alone): the distance it covers from the
        # program's start places each sample.
        off = np.zeros(3)
        method = "feed alone"
        dt = np.diff(trace.t, prepend=trace.t[0])
        v = trace.v
        s = np.minimum(np.cumsum(np.concatenate([[0.0], v[:-1]]) * dt), end_s[-1])
        line = tp.line[tp.move_at(s)]
        dist = np.full(s.size, np.nan)
        far_share = 0.0
        notes.append(
            "no positions and no program lines: each sample placed by the distance its feed "
            "covered since the trace began, taken as the program's start"
        )
    else:
        raise InputError(
            "the trace has neither positions nor a feed: nothing to align", source=trace.source
        )

    # Coverage: feed length between the first and last sample's place.
    lo, hi = float(s.min()), float(s.max())
    feed_len = np.clip(np.minimum(end_s, hi) - np.maximum(start_s, lo), 0.0, None)
    coverage = float(feed_len[tp.is_feed].sum() / total_feed) if total_feed else 0.0
    ok = far_share <= MAX_FAR_SHARE and coverage >= MIN_COVERAGE
    if trace.pos is not None:
        msg = (
            f"{method}: median distance to the path {np.median(dist):.3f} mm, "
            f"{far_share:.1%} of samples beyond {far:g} mm, coverage {coverage:.0%}"
        )
    else:
        msg = f"{method}: coverage {coverage:.0%}, {far_share:.1%} of samples on unknown lines"
    if not ok:
        msg = (
            "LOW ALIGNMENT QUALITY: "
            + msg
            + (" -- a trace of another program, other units or another work offset?")
        )
    return Alignment(
        s=s,
        v=np.asarray(v, dtype=np.float64),
        t=trace.t,
        line=np.asarray(line, dtype=np.int64),
        method=method,
        offset=off,
        distance=dist,
        coverage=coverage,
        far_share=far_share,
        ok=ok,
        message=msg,
        notes=tuple(notes),
        commanded=commanded,
    )
