"""The segments a controller's interpreter sends to its planner, where they are not the
program's blocks: LinuxCNC's "naive CAM detector" (G64 P- Q-).

LinuxCNC 2.9 runs nearly collinear G1 blocks as one straight segment (its task's canonical
layer, src/emc/task/emccanon.cc: ``see_segment``, ``linkable``, ``flush_segments``; read for
the rules, no code carried over). Under G64 with a naive-CAM tolerance q > 0 (G64's Q; P
when Q is absent, rs274ngc ``convert_control_mode``):

* a feed line joins the segment being collected when every point collected so far lies
  within q of the straight line from the segment's start to the new point (distance to the
  segment, its parameter clamped to [0, 1]), the new point is not the start itself, and
  at most 101 points are collected; otherwise the collected points go out as one line,
  from the start to the last point, and the new point starts the next one;
* the segment carries the last block's line number (a trace shows only that line) and the
  feed in force; anything else the interpreter sends (a rapid, an arc it keeps, a change of
  feed, of path mode or of work offset, a dwell, an M, S or T function) sends the collected
  points first;
* an XY-plane arc (G17) under G64 whose chord deviation ``r (1 - cos(included / 2))`` is
  below q is read as two lines through the point halfway round it (``chord_deviation`` and
  ``ARC_FEED``); its height halfway is the mean of its ends'.

Which blocks may join is the adapter's to say (it knows the program's words): this module
takes, per move, the tolerance in force and whether the move may join the move before it.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from core.model.toolpath import MoveKind, PathMode, ToolPath, rebuilt

#: At most this many points are collected into one segment (emccanon.cc ``linkable``:
#: ``chained_points.size() > 100`` refuses a 102nd).
MAX_POINTS = 101

#: Candidate ends tried in the first window (then twice as many each time).
_FIRST_WINDOW = 8


def chord_deviation(radius: NDArray, included: NDArray) -> NDArray:
    """How far an arc of ``included`` angle (rad) strays from its chord: r (1 - cos(a / 2))."""
    return radius * (1.0 - np.cos(included / 2.0))


def included_angle(sweep: NDArray) -> NDArray:
    """The angle LinuxCNC measures an arc by (start to end, in its direction): the sweep
    less its extra full turns, a full circle 2 pi."""
    two_pi = 2.0 * math.pi
    turns = np.maximum(np.ceil(sweep / two_pi) - 1.0, 0.0)
    return sweep - turns * two_pi


def split_flat_arcs(tp: ToolPath, flat: NDArray[np.bool_]) -> tuple[ToolPath, NDArray[np.intp]]:
    """Each arc marked ``flat`` as two lines through the point halfway round it (height the
    mean of its ends'). Returns the path and, per move of it, the move it came from."""
    idx = np.flatnonzero(flat)
    n = tp.n
    if idx.size == 0:
        return tp, np.arange(n)
    reps = np.ones(n, dtype=np.intp)
    reps[idx] = 2
    src = np.repeat(np.arange(n), reps)
    first = np.cumsum(reps) - reps  # row of each move's first piece
    # The point halfway: the start's radius vector turned by half the included angle.
    c, nrm = tp.center[idx], tp.normal[idx]
    s, e = tp.start[idx], tp.end[idx]
    sign = np.where(tp.kind[idx] == MoveKind.ARC_CCW, 1.0, -1.0)
    half = sign * included_angle(tp.sweep[idx]) / 2.0
    u = s - c
    u = u - (u * nrm).sum(axis=1, keepdims=True) * nrm
    w = np.cross(nrm, u)
    mid = c + u * np.cos(half)[:, None] + w * np.sin(half)[:, None]
    # height along the axis: the mean of the ends'
    h = ((s + e) / 2.0 * nrm).sum(axis=1) - (mid * nrm).sum(axis=1)
    mid = mid + h[:, None] * nrm

    start, end = tp.start[src], tp.end[src]  # (gathered: copies of their own)
    end[first[idx]] = mid
    start[first[idx] + 1] = mid
    piece = np.zeros(src.size, dtype=bool)
    piece[first[idx]] = piece[first[idx] + 1] = True
    kind = tp.kind[src]
    kind[piece] = MoveKind.LINE
    center, normal, sweep = tp.center[src], tp.normal[src], tp.sweep[src]
    center[piece] = np.nan
    normal[piece] = np.nan
    sweep[piece] = np.nan
    dwell, mode = tp.dwell[src], tp.path_mode[src]
    # a dwell or a stop after the arc comes after its second half
    dwell[first[idx]] = 0.0
    mode[first[idx]] = PathMode.CONTINUOUS
    out = _take(
        tp,
        src,
        start=start,
        end=end,
        kind=kind,
        center=center,
        normal=normal,
        sweep=sweep,
        dwell=dwell,
        path_mode=mode,
    )
    return out, src


def _take(tp: ToolPath, rows: NDArray[np.intp], **over: NDArray) -> ToolPath:
    """The moves ``rows`` of ``tp`` (each column indexed alike), with columns ``over``."""
    cols = {
        name: over[name] if name in over else getattr(tp, name)[rows]
        for name in (
            "kind",
            "start",
            "end",
            "center",
            "normal",
            "sweep",
            "feed",
            "line",
            "block",
            "tool",
            "path_mode",
            "dwell",
            "tolerance",
        )
    }
    # operation i starts at the first row whose move is at or after its first move
    offs = np.searchsorted(rows, tp.op_offsets[:-1], side="left")
    offs = np.concatenate([offs, [rows.size]]).astype(np.int64)
    return rebuilt(tp, rows, cols, offs, tp.op_names)


def chain_ends(points: NDArray[np.float64], tol: float) -> list[int]:
    """Where LinuxCNC's collector sends its segments along ``points`` (point 0 the start,
    point i the end of the i-th block), all blocks joinable under tolerance ``tol``: the
    indices of the points that end a segment, in order (the last is the last point)."""
    m = points.shape[0] - 1
    ends: list[int] = []
    s = 0
    while s < m:
        e = s + 1  # the first point is collected without a test
        hi = min(m, s + MAX_POINTS)
        width = _FIRST_WINDOW
        while e < hi:
            # candidates in windows twice as wide each time: a segment of L points costs
            # about L^2 distances, not 101^2
            top = min(hi, e + width)
            ok = _joinable(points, s, e + 1, top, tol)
            bad = np.flatnonzero(~ok)
            if bad.size:
                e = e + int(bad[0])
                break
            e = top
            width *= 2
        ends.append(e)
        s = e
    return ends


def _joinable(p: NDArray[np.float64], s: int, x0: int, x1: int, tol: float) -> NDArray:
    """For each candidate new point x in [x0, x1]: whether points s+1..x-1 all lie within
    ``tol`` of the segment from point s to point x (and x is not point s)."""
    b = p[s]
    xs = p[x0 : x1 + 1] - b  # (k, 3) candidate ends, from the start
    pts = p[s + 1 : x1] - b  # (j, 3) collected points, from the start
    mm = np.einsum("ij,ij->i", xs, xs)  # (k,)
    pp = np.einsum("ij,ij->i", pts, pts)[:, None]  # (j, 1)
    px = pts @ xs.T  # (j, k)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip(px / mm, 0.0, 1.0)  # NaN where x is the start: refused below
    # squared distance to the segment: |p|^2 - 2 t p.x + t^2 |x|^2 (at 100 mm from the start
    # its rounding is 1e-12 mm^2, far below any tolerance's square)
    d2 = pp - t * (2.0 * px - t * mm)
    j = np.arange(s + 1, x1)[:, None]
    x = np.arange(x0, x1 + 1)[None, :]
    too_far = (d2 > tol * tol) & (j < x)
    return ~too_far.any(axis=0) & (mm > 0.0)


def merge_lines(
    tp: ToolPath, tol: NDArray[np.float64], join: NDArray[np.bool_]
) -> tuple[ToolPath, int]:
    """The segments LinuxCNC sends for ``tp``: runs of lines that may join (``join[k]``:
    line k may join line k - 1; ``tol[k]``, mm, the tolerance in force) collected as above.
    Returns the path (a segment: the first block's start, the last block's end and every
    other column) and how many blocks were joined into others."""
    n = tp.n
    join = join.copy()
    join[0] = False
    if not join.any():
        return tp, 0
    keep = np.ones(n, dtype=bool)
    seg_start = tp.start.copy()
    run_first = np.flatnonzero(~join)
    run_last = np.concatenate([run_first[1:] - 1, [n - 1]])
    long_runs = np.flatnonzero(run_last > run_first)
    for r in long_runs:
        a, b = int(run_first[r]), int(run_last[r])
        pts = np.concatenate([tp.start[a : a + 1], tp.end[a : b + 1]])
        ends = chain_ends(pts, float(tol[a + 1]))
        prev = 0
        for e in ends:
            # moves a+prev .. a+e-1 form one segment, kept as its last move
            keep[a + prev : a + e - 1] = False
            seg_start[a + e - 1] = pts[prev]
            prev = e
    joined = int(n - keep.sum())
    if joined == 0:
        return tp, 0
    rows = np.flatnonzero(keep)
    out = _take(tp, rows, start=seg_start[rows])
    return out, joined
