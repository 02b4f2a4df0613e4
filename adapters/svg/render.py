"""Render colour annotations as one standalone SVG (Tapie et al., sec. 3.3, Figures 10 and 11).

Two panels side by side, same view and scale:

* left, Figure 11: feed moves coloured by predicted feed reduction (models
  1-3), discontinuity markers coloured by their own reduction, the worst
  zones numbered;
* right, Figure 10: feed moves coloured by block length against
  L = F t_int (model 3, eq. 16).

Everything is built with array operations, so a million moves take a fraction
of a second, and the output is bounded by the drawing's pixel resolution
rather than by the number of moves:

* coordinates are quantised to 0.1 px and written as integers under
  ``scale(0.1)``;
* consecutive moves of one class form one ``<polyline>``; inside it, points in
  the same 1 px cell as the point before are dropped (the cell grows where
  passes are closer than a pixel, until :data:`MAX_POINTS` fits);
* along the path, moves shorter than a few pixels are pooled and shown in
  the worst class among them (the pooling length grows until the number of
  polylines fits :data:`MAX_RUNS`), so a class that alternates every move
  neither vanishes nor costs one element per move;
* discontinuity markers keep one per class and cell (the slowest), the cell
  growing until :data:`MAX_MARKERS` fits.

Every polyline and marker has a ``<title>`` naming its program lines.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from core.cli.output import atomic_writer
from core.model import geometry as g
from core.model.arrays import unique
from core.model.pieces import pieces
from core.model.text import printable
from core.model.tolerances import TOL
from core.model.toolpath import MoveKind, ToolPath
from core.view.annotations import Annotations, check_drawable
from core.view.targets import COLOURINGS, VIEWS
from core.view.zones import Zone

if TYPE_CHECKING:
    from core.diagnosis.diagnose import Diagnosis

# ---------------------------------------------------------------- layout, px
#: Width of each panel's plot area; the height follows the drawing's aspect.
PLOT_W = 900.0
#: Largest and smallest plot height (a flat drawing still gets room for labels).
PLOT_H_MAX = 900.0
PLOT_H_MIN = 240.0
#: Empty border between the drawing's bounding box and the plot frame.
PAD = 24.0
MARGIN = 20.0
GAP = 40.0
TOP = 72.0
ROW = 18.0
#: Largest scale (px/mm): a path of a few microns is not blown up to the panel.
MAX_SCALE = 1.0e4

# ---------------------------------------------------------------- resolution
#: Quantisation units per px: coordinates are written as integers of 0.1 px,
#: finer than any screen, and a tenth of the size of six-decimal floats.
Q = 10
#: Arcs are sampled so that the chord deviates from the arc by at most this (px).
CHORD_PX = 0.5
ARC_MIN_SEGMENTS = 2
ARC_MAX_SEGMENTS = 64
#: Upper bound on arc sample points: beyond it arcs get fewer segments, since
#: that many points cannot all be told apart at 900 px anyway.
ARC_POINT_BUDGET = 4_000_000
#: A point in the same cell (px) as the previous point of its polyline is
#: dropped: the stroke (1.5 px) hides the difference. Where more than
#: MAX_POINTS points would remain (passes closer than a pixel, drawn as a
#: solid area anyway), the cell doubles up to DEDUPE_MAX_PX: this bounds the
#: file (about 10 bytes a point, twice) whatever the path length.
DEDUPE_PX = 1
DEDUPE_MAX_PX = 8
MAX_POINTS = 300_000
#: Along the path, moves shorter than the pooling length (px) whose ends fall
#: in the same stretch of that length are shown in their worst class; the
#: length doubles up to POOL_MAX_PX until at most MAX_RUNS polylines per panel
#: remain (each costs ~60 bytes of tags and title).
POOL_PX = 2
POOL_MAX_PX = 64
MAX_RUNS = 20_000
#: Discontinuity markers: one per (class, cell), the cell doubling from
#: MARKER_CELL_PX (the marker's radius, so kept markers barely overlap) until
#: at most MAX_MARKERS remain.
MARKER_CELL_PX = 2
MARKER_MAX_CELL_PX = 64
MARKER_R_PX = 2.5
MAX_MARKERS = 10_000

STROKE_PX = 1.5
RAPID_STROKE_PX = 0.8

_C30 = float(np.cos(np.pi / 6.0))

#: (2, 3) projection of (x, y, z) onto drawing axes (u right, v up), per view.
#: The isometric one keeps lengths along x, y and z (|(cos30, sin30)| = 1), so
#: one scale bar holds for all three axes.
PROJECTIONS: dict[str, NDArray[np.float64]] = {
    "xy": np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
    "xz": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
    "yz": np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
    "iso": np.array([[_C30, -_C30, 0.0], [0.5, 0.5, 1.0]]),
}
VIEW_NAMES = {"xy": "top (XY)", "xz": "front (XZ)", "yz": "side (YZ)", "iso": "isometric"}

#: Titles of the left panel by what it colours blocks by (:data:`COLOURINGS`): the feed
#: profile's mean speed over each block against F (``speed``, the default: where the time
#: goes, ramps and all), or each block's own predicted cruise feed (``paper``: the paper's
#: Figure 11, which ignores the ramps).
LEFT_TITLES = {
    "speed": "Predicted speed over each block, below F (feed profile: where the time goes)",
    "paper": "Predicted cruise feed reduction of each block (models 1-3, paper Fig. 11)",
}
LEGEND_TITLES = {
    "speed": "Mean predicted speed of blocks below F (profile), discontinuities (models 1-3)",
    "paper": "Predicted feed reduction of blocks and discontinuities",
}
CLASS_PREFIX = {"speed": "speed below F by", "paper": "reduction"}
RIGHT_TITLE = "Block length vs L = F t_int (model 3)"


def escape(text: str, entities: dict[str, str] | None = None) -> str:
    """Text for an SVG element or attribute: control characters and bytes that are not UTF-8
    shown as escapes (they would make the file ill-formed XML or unwritable), then XML-escaped:
    ``&``, ``<``, ``>`` and the ``entities`` given (as ``xml.sax.saxutils.escape`` does; not
    imported from there, which pulls in urllib and http: 30 ms of every run's start-up)."""
    out = printable(text).replace("&", "&amp;").replace(">", "&gt;").replace("<", "&lt;")
    for key, value in (entities or {}).items():
        out = out.replace(key, value)
    return out


def project(points: ArrayLike, view: str) -> NDArray[np.float64]:
    """Drawing coordinates of 3-D points.

    Parameters
    ----------
    points : (m, 3) float, mm
    view : {"xy", "xz", "yz", "iso"}

    Returns
    -------
    (m, 2) float, mm
        u to the right, v up.
    """
    if view not in PROJECTIONS:
        raise ValueError(f"view must be one of {VIEWS}, got {view!r}")
    p = g.as_points(points, "points")
    return p @ PROJECTIONS[view].T


@dataclass(frozen=True)
class Frame:
    """Placement of the drawing in a plot area: uniform scale, y flipped.

    Attributes
    ----------
    u_min, v_max : float, mm
        Left and top of the drawing's bounding box.
    scale : float, px/mm
    x0, y0 : float, px
        Where (u_min, v_max) lands in the plot area.
    height : float, px
        Plot area height (the width is PLOT_W).
    """

    u_min: float
    v_max: float
    scale: float
    x0: float
    y0: float
    height: float

    def to_px(self, uv: NDArray[np.float64]) -> NDArray[np.float64]:
        """(m, 2) px in the plot area (x right, y down) of (m, 2) drawing coordinates in mm."""
        out = np.empty_like(uv)
        out[:, 0] = self.x0 + (uv[:, 0] - self.u_min) * self.scale
        out[:, 1] = self.y0 + (self.v_max - uv[:, 1]) * self.scale
        return out


def fit_frame(
    lo: NDArray[np.float64], hi: NDArray[np.float64], scale: float | None = None
) -> Frame:
    """Fit the bounding box ``lo``..``hi`` (mm) into the plot area with a uniform scale.

    A zero extent along one axis (a vertical line seen from above) leaves the
    other axis to set the scale; a single point is drawn at 1 px/mm, centred.
    ``scale`` (px/mm), when given, is used instead (it must fit: comparisons pass
    the smallest scale of their panels so that all share it).
    """
    ext = np.maximum(hi - lo, 0.0)
    if scale is None:
        room_w = PLOT_W - 2.0 * PAD
        room_h = PLOT_H_MAX - 2.0 * PAD
        cand = [
            room_w / ext[0] if ext[0] > 0 else np.inf,
            room_h / ext[1] if ext[1] > 0 else np.inf,
        ]
        scale = min(cand)
        scale = 1.0 if not np.isfinite(scale) else min(scale, MAX_SCALE)
    height = float(np.clip(ext[1] * scale + 2.0 * PAD, PLOT_H_MIN, PLOT_H_MAX))
    x0 = (PLOT_W - ext[0] * scale) / 2.0
    y0 = (height - ext[1] * scale) / 2.0
    return Frame(float(lo[0]), float(hi[1]), float(scale), float(x0), float(y0), height)


def arc_segments(radius_px: ArrayLike, sweep: ArrayLike) -> NDArray[np.int64]:
    """Segments per arc so the chord error stays below CHORD_PX.

    A chord over angle a deviates from a circle of radius r by the sagitta
    r (1 - cos(a / 2)), so a <= 2 arccos(1 - CHORD_PX / r).

    Parameters
    ----------
    radius_px : (m,) float, px
        Radius as drawn (an upper bound for tilted arcs).
    sweep : (m,) float, rad

    Returns
    -------
    (m,) int
        Between ARC_MIN_SEGMENTS and ARC_MAX_SEGMENTS; the minimum where the
        radius or sweep is not finite.
    """
    r = np.asarray(radius_px, dtype=np.float64)
    sweep = np.asarray(sweep, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        cos_half = np.clip(1.0 - CHORD_PX / r, -1.0, 1.0)
        step = 2.0 * np.arccos(cos_half)
        n = np.ceil(sweep / step)
    n = np.where(np.isfinite(n), n, ARC_MIN_SEGMENTS)
    return np.clip(n, ARC_MIN_SEGMENTS, ARC_MAX_SEGMENTS).astype(np.int64)


@dataclass(frozen=True, eq=False)
class Strokes:
    """The drawn points of every move, one after the other, in both panels' coordinates.

    Attributes
    ----------
    frame : Frame
    q : (p, 2) int64, 0.1 px
        Quantised plot coordinates: move i's points are ``q[first[i]:last[i] + 1]``
        (start, arc samples, end).
    first, last : (n,) int64
        Index of each move's start and end point in ``q``.
    breaks : (n,) bool
        True where move i cannot continue the polyline of move i - 1 (its start
        is not where i - 1 ends, or one is a rapid and the other is not).
    drawn : (n,) float, px
        Length of each move as drawn.
    new_cell : (p,) bool
        The point is in another ``dedupe_px`` cell than the point before.
    dedupe_px : int
        Cell size used for ``new_cell`` (px).
    """

    frame: Frame
    q: NDArray[np.int64]
    first: NDArray[np.int64]
    last: NDArray[np.int64]
    breaks: NDArray[np.bool_]
    drawn: NDArray[np.float64]
    new_cell: NDArray[np.bool_]
    dedupe_px: int


def _cell_key(q: NDArray[np.int64], cell: int) -> NDArray[np.int64]:
    """One int64 per (x, y) cell of ``cell`` quantisation units."""
    # The plot is at most ~2e4 units high, far below 2**31: no collisions.
    # (Each column copied out first: the divisions on contiguous arrays, twice as fast.)
    key = np.empty(q.shape[0], dtype=np.int64)
    np.copyto(key, q[:, 0])
    np.floor_divide(key, cell, out=key)
    key <<= 31
    low = np.empty(q.shape[0], dtype=np.int64)
    np.copyto(low, q[:, 1])
    np.floor_divide(low, cell, out=low)
    key += low
    return key


def _sample_arcs_into(
    pts: NDArray[np.float64],
    tp: ToolPath,
    arcs: NDArray[np.int64],
    counts: NDArray[np.int64],
    first: NDArray[np.int64],
    proj: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Projected samples of ``arcs`` (:func:`core.model.geometry.sample_arcs`, ``counts``
    segments each) into their interior rows of ``pts`` (arc i's points start at row
    ``first[i]``), in pieces of whole arcs of about SAMPLE_PIECE points; returns the box
    (min, max) of all the samples, ends included."""
    per = counts + 1
    ends = np.cumsum(per)
    lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
    a = 0
    while a < per.size:
        done = ends[a - 1] if a else 0
        b = max(int(np.searchsorted(ends, done + g.SAMPLE_PIECE, side="right")), a + 1)
        k = arcs[a:b]
        samples = (
            g.sample_arcs(
                tp.start[k],
                tp.center[k],
                tp.normal[k],
                tp.kind[k] == MoveKind.ARC_CCW,
                tp.sweep[k],
                tp.pitch[k],
                counts[a:b],
            )
            @ proj.T
        )
        lo = np.minimum(lo, samples.min(axis=0))
        hi = np.maximum(hi, samples.max(axis=0))
        p = per[a:b]
        local = np.arange(samples.shape[0]) - np.repeat(np.cumsum(p) - p, p)
        inner = (local > 0) & (local < np.repeat(counts[a:b], p))
        pts[np.repeat(first[a:b], p)[inner] + local[inner]] = samples[inner]
        a = b
    return lo, hi


def _column_extreme(uv: NDArray[np.float64], reduce: Any) -> NDArray[np.float64]:
    """``reduce(uv, axis=0)`` of (n, 2) finite coordinates, a column at a time (several
    times faster). The extremes are the same numbers; only a tie between 0.0 and -0.0 may
    come out with the other sign, which no pixel sees (the frame subtracts them, then adds
    a positive offset)."""
    return np.array([reduce(uv[:, 0]), reduce(uv[:, 1])])


def _as_rows(uv: NDArray[np.float64]) -> NDArray[np.complex128]:
    """(n,) complex128 view of (n, 2) float64 (contiguous: one row per element)."""
    return np.ascontiguousarray(uv).view(np.complex128).reshape(-1)


def strokes(tp: ToolPath, view: str, scale: float | None = None) -> Strokes:
    """Project, fit (at ``scale`` px/mm if given), sample the arcs and quantise every move."""
    proj = PROJECTIONS[view]
    n = tp.n
    uv_s = tp.start @ proj.T
    uv_e = tp.end @ proj.T
    if n:
        lo = np.minimum(_column_extreme(uv_s, np.min), _column_extreme(uv_e, np.min))
        hi = np.maximum(_column_extreme(uv_s, np.max), _column_extreme(uv_e, np.max))
    else:
        lo = hi = np.zeros(2)

    arcs = np.flatnonzero(tp.is_arc)
    arc_ok = (
        np.isfinite(tp.radius[arcs])
        & np.isfinite(tp.sweep[arcs])
        & np.isfinite(tp.pitch[arcs])
        & (tp.sweep[arcs] > 0)
    )
    arcs = arcs[arc_ok]
    counts = np.zeros(0, dtype=np.int64)
    if arcs.size:
        # Segment counts from the end points' box: the final box holds the arcs'
        # bulges too, so its scale is at most this one and the chord error in
        # px only gets smaller.
        scale0 = fit_frame(lo, hi).scale
        gain = np.linalg.norm(proj, 2)  # the projection's largest stretch (iso: 1.22)
        counts = arc_segments(tp.radius[arcs] * scale0 * gain, tp.sweep[arcs])
        total = int(counts.sum()) + arcs.size
        if total > ARC_POINT_BUDGET:
            counts = np.maximum(counts * ARC_POINT_BUDGET // total, ARC_MIN_SEGMENTS)

    m = np.full(n, 2, dtype=np.int64)
    m[arcs] = counts + 1
    last = np.cumsum(m) - 1
    first = last - m + 1
    del m
    pts = np.empty((int(last[-1]) + 1 if n else 0, 2))
    # (each row's two float64 as one complex128: the same bytes, moved a row at a time
    # several times faster than (n, 2) rows)
    rows = pts.view(np.complex128).reshape(-1)
    rows[first] = _as_rows(uv_s)
    rows[last] = _as_rows(uv_e)
    del rows
    del uv_s, uv_e
    if arcs.size:
        # The arcs' samples straight into their rows, in pieces of whole arcs (the same
        # numbers as all at once): interior samples only, the ends come from the program,
        # exactly; the box holds every sample, ends included.
        slo, shi = _sample_arcs_into(pts, tp, arcs, counts, first[arcs], proj)
        lo = np.minimum(lo, slo)
        hi = np.maximum(hi, shi)
        tp.release_arc_shapes()  # sampled: what follows is the drawing's peak
    frame = fit_frame(lo, hi, scale)
    # Plot px, then 0.1 px as int64, in place and in pieces: the same numbers as
    # frame.to_px, * Q, rint and astype over all points at once, with no (p, 2) copies.
    # (Column by column through a small buffer: frame.to_px's operations in its order.)
    q = pts.view(np.int64)
    size = min(pts.shape[0], PX_PIECE)
    col = np.empty(size)
    for b in pieces(pts.shape[0], PX_PIECE):
        c = col[: b.stop - b.start]
        for k in range(2):
            if k == 0:  # x0 + (u - u_min) * scale
                np.subtract(pts[b, 0], frame.u_min, out=c)
                c *= frame.scale
                np.add(frame.x0, c, out=c)
            else:  # y0 + (v_max - v) * scale
                np.subtract(frame.v_max, pts[b, 1], out=c)
                c *= frame.scale
                np.add(frame.y0, c, out=c)
            c *= Q
            np.rint(c, out=c)
            q[b, k] = c  # (float to int64: astype's conversion)
    del pts

    breaks = np.ones(n, dtype=bool)
    if n > 1:
        feed = tp.is_feed
        qx, qy = q[:, 0], q[:, 1]  # (column by column: the same comparisons, faster)
        breaks[1:] = (feed[1:] != feed[:-1]) | (qx[first[1:]] != qx[last[:-1]])
        breaks[1:] |= qy[first[1:]] != qy[last[:-1]]
        del qx, qy
    # Drawn length of each move: its segments between first and last point.
    seg = _hypot_ints(np.diff(q[:, 0]), np.diff(q[:, 1])) / Q if q.shape[0] > 1 else np.zeros(0)
    along = np.concatenate([[0.0], np.cumsum(seg)])
    del seg
    drawn = along[last] - along[first]
    del along
    cell = DEDUPE_PX
    new_cell = np.ones(q.shape[0], dtype=bool)
    while True:
        _new_cells(q, cell * Q, new_cell)
        if np.count_nonzero(new_cell) <= MAX_POINTS or cell >= DEDUPE_MAX_PX:
            break
        cell *= 2
    return Strokes(frame, q, first, last, breaks, drawn, new_cell, cell)


#: Integer steps below this (in either coordinate) take their length from a table.
HYPOT_TABLE = 256


def _hypot_ints(dx: NDArray[np.int64], dy: NDArray[np.int64]) -> NDArray[np.float64]:
    """np.hypot(dx, dy) of integer steps: the short ones (most, on a dense path) read from a
    table of np.hypot's own values of |dx|, |dy| (hypot is even in each argument), the
    others computed (the same numbers, several times faster than hypot throughout)."""
    if not dx.size:
        return np.zeros(0)
    side = np.arange(HYPOT_TABLE)
    table = np.hypot(side[:, None], side[None, :]).reshape(-1)
    ax, ay = np.abs(dx), np.abs(dy)
    longer = np.flatnonzero((ax >= HYPOT_TABLE) | (ay >= HYPOT_TABLE))
    if longer.size:  # (their keys clipped into the table; their lengths computed below)
        np.minimum(ax, HYPOT_TABLE - 1, out=ax)
        np.minimum(ay, HYPOT_TABLE - 1, out=ay)
    ax *= HYPOT_TABLE
    ax += ay
    out = np.take(table, ax)
    if longer.size:
        out[longer] = np.hypot(dx[longer], dy[longer])
    return out


def _new_cells(q: NDArray[np.int64], cell: int, out: NDArray[np.bool_]) -> None:
    """``out[i]`` for i >= 1: point i is in another cell (:func:`_cell_key`) than point
    i - 1. (In pieces: the same comparisons without the keys of every point at once; 5M
    arcs, 160 MB.)"""
    for b in pieces(q.shape[0] - 1):
        key = _cell_key(q[b.start : b.stop + 1], cell)
        np.not_equal(key[1:], key[:-1], out=out[b.start + 1 : b.stop + 1])


#: Points per piece of :func:`strokes`' conversion to quantised px (in the cache).
PX_PIECE = 1 << 14


# ---------------------------------------------------------------- text output
#: Values written per piece by :func:`render_ints`.
INT_PIECE = 262_144


def render_ints(values: ArrayLike, suffix: ArrayLike, table: Sequence[bytes]) -> bytes:
    """Write integers in decimal, each followed by a piece of text, without a Python loop.

    Parameters
    ----------
    values : (t,) int
    suffix : (t,) int
        Index into ``table`` of the text written after each value.
    table : sequence of bytes

    Returns
    -------
    bytes
        ``b"".join(str(v).encode() + table[s] for v, s in zip(values, suffix))``,
        about ten times faster for millions of values.
    """
    v = np.asarray(values, dtype=np.int64)
    sfx = np.asarray(suffix, dtype=np.intp)
    if v.shape != sfx.shape or v.ndim != 1:
        raise ValueError(f"values and suffix must have one shape (t,), got {v.shape}, {sfx.shape}")
    if v.size == 0:
        return b""
    if v.size > INT_PIECE:
        # Each value is written on its own: in pieces, the (t, digits) temporaries stay small
        # and the bytes are the same.
        return b"".join(
            render_ints(v[a : a + INT_PIECE], sfx[a : a + INT_PIECE], table)
            for a in range(0, v.size, INT_PIECE)
        )
    neg = v < 0
    av = np.abs(v)
    width = len(str(int(av.max())))
    powers = 10 ** np.arange(width - 1, -1, -1, dtype=np.int64)
    ndig = np.searchsorted(powers[::-1][1:], av, side="right") + 1
    tlen = np.array([len(t) for t in table], dtype=np.int64)
    slen = tlen[sfx]
    size = neg + ndig + slen
    end = np.cumsum(size)
    start = end - size
    total = int(end[-1])
    # Digits: the one of 10**j of every value at once, j from the highest down, each value's
    # right-aligned in ``width`` places that end where its own digits end. A shorter value's
    # leading zeros land on the bytes before it (``width`` spare bytes before the first),
    # all of which a later write covers: its sign and the suffix before it are written after
    # the digits, and the digits of the value before it, of a lower j, after these.
    # (Each digit is the quotient by its power of what the higher ones leave, taken off as
    # it is written; in int32 where the values fit, faster than int64 and the same digits.)
    buf = np.empty(width + total, dtype=np.uint8)
    pos = start + neg
    pos += ndig  # (in buf: the place of 10**(width - 1))
    left = av.astype(np.int32) if width < 10 else av.copy()
    d = np.empty_like(left)
    digit = np.empty(left.size, dtype=np.uint8)
    for p in powers.tolist():
        np.floor_divide(left, p, out=d)
        np.add(d, ord("0"), out=digit, casting="unsafe")
        buf[pos] = digit
        d *= p
        left -= d
        pos += 1
    del pos, left, d, digit
    out = buf[width:]
    out[start[neg]] = ord("-")

    # Suffixes: gather their bytes from one blob (those of one byte, most, at once).
    blob = np.frombuffer(b"".join(table), dtype=np.uint8)
    toff = np.cumsum(tlen) - tlen
    after = start + neg
    after += ndig
    one = slen == 1
    out[after[one]] = blob[toff[sfx[one]]]
    nz = slen > 1
    reps = slen[nz]
    s_total = int(reps.sum())
    if s_total:
        local = np.arange(s_total) - np.repeat(np.cumsum(reps) - reps, reps)
        dest = np.repeat(after[nz], reps) + local
        out[dest] = blob[np.repeat(toff[sfx[nz]], reps) + local]
    return out.tobytes()


# ---------------------------------------------------------------- runs
@dataclass(frozen=True, eq=False)
class Runs:
    """The polylines of one panel: maximal stretches of moves drawn in one class.

    Attributes
    ----------
    start, stop : (r,) int64
        First and last move of each run.
    severity : (r,) int64
        Severity shown (-1: rapids; higher is worse).
    mixed : (r,) bool
        The run holds moves of a milder class, pooled into the worst one.
    pool_px : int
        Pooling length used (px).
    """

    start: NDArray[np.int64]
    stop: NDArray[np.int64]
    severity: NDArray[np.int64]
    mixed: NDArray[np.bool_]
    pool_px: int


def runs(st: Strokes, severity: ArrayLike) -> Runs:
    """Split the moves into polylines of one shown class.

    A run breaks where the path is discontinuous on screen, at rapid/feed
    changes and where the shown class changes. Along each polyline, moves
    shorter than the pooling length (px) whose ends fall in the same stretch of
    that length are shown in the worst class among them: below a few pixels
    the colours could not be told apart, and the worst one is what the viewer
    is for. A move longer than the pooling length keeps its own class. The
    pooling length doubles until at most MAX_RUNS runs remain.

    Parameters
    ----------
    st : Strokes
    severity : (n,) int
        Per move; -1 for rapids, higher is worse.
    """
    sev = np.asarray(severity, dtype=np.int64)
    n = st.first.size
    if sev.shape != (n,):
        raise ValueError(f"severity must have shape ({n},), got {sev.shape}")
    if n == 0:
        z = np.zeros(0, dtype=np.int64)
        return Runs(z, z, z, np.zeros(0, dtype=bool), POOL_PX)
    # Stretches along the path, not cells on the screen: cells would cut
    # short runs at arbitrary grid lines and leave isolated milder moves.
    end_at = np.cumsum(st.drawn)
    pool = POOL_PX
    while True:
        stretch = np.floor(end_at / pool)
        long = st.drawn >= pool
        group = st.breaks.copy()
        group[1:] |= (stretch[1:] != stretch[:-1]) | long[1:] | long[:-1]
        gs = np.flatnonzero(group)
        shown = np.repeat(np.maximum.reduceat(sev, gs), np.diff(np.append(gs, n)))
        brk = st.breaks.copy()
        brk[1:] |= shown[1:] != shown[:-1]
        start = np.flatnonzero(brk)
        if start.size <= MAX_RUNS or pool >= POOL_MAX_PX:
            break
        pool *= 2
    stop = np.append(start[1:], n) - 1
    mixed = np.minimum.reduceat(sev, start) < shown[start]
    return Runs(start, stop, shown[start], mixed, pool)


_OPEN_POLYLINE = b'<polyline points="'


@dataclass(frozen=True, eq=False)
class Layout:
    """One panel's runs and the points each keeps.

    Attributes
    ----------
    runs : Runs
    kept : (k,) int64
        Indices into ``Strokes.q`` of the points written, run after run.
    kept_run : (k,) int64
        Their run.
    kept_count : (r,) int64
        Points written per run (at least 2: a run's first and last point).
    line_lo, line_hi : (r,) int64
        Lowest and highest program line of each run.
    """

    runs: Runs
    kept: NDArray[np.int64]
    kept_run: NDArray[np.int64]
    kept_count: NDArray[np.int64]
    line_lo: NDArray[np.int64]
    line_hi: NDArray[np.int64]


def layout(st: Strokes, tp: ToolPath, severity: ArrayLike) -> Layout:
    """Runs of one panel; inside each, the points in a new cell and both ends."""
    rn = runs(st, severity)
    if rn.start.size == 0:
        z = np.zeros(0, dtype=np.int64)
        return Layout(rn, z, z, z, z, z)
    # Runs are consecutive slices of the point stream.
    p0 = st.first[rn.start]
    p1 = st.last[rn.stop]
    keep = st.new_cell.copy()
    keep[p0] = True
    keep[p1] = True
    kept = np.flatnonzero(keep)
    kept_run = np.searchsorted(p0, kept, side="right") - 1
    return Layout(
        rn,
        kept,
        kept_run,
        np.bincount(kept_run, minlength=rn.start.size),
        np.minimum.reduceat(tp.line, rn.start),
        np.maximum.reduceat(tp.line, rn.start),
    )


def polylines(st: Strokes, lay: Layout, severity: int, label: str) -> bytes:
    """``<polyline>`` elements, each with a title, of the runs shown at one severity.

    Parameters
    ----------
    st : Strokes
    lay : Layout
    severity : int
    label : str
        Class name for the titles: "lines 120-245: {label}".

    Returns
    -------
    bytes
        Empty when no run has that severity.
    """
    sel = lay.runs.severity == severity
    rc = np.flatnonzero(sel)
    if rc.size == 0:
        return b""
    pts = lay.kept[sel[lay.kept_run]]
    cnt = lay.kept_count[rc]
    lo, hi, mixed = lay.line_lo[rc], lay.line_hi[rc], lay.runs.mixed[rc]
    single = lo == hi
    # Tokens per run: x, y per point, then the first line and (for a range) the last.
    ntok = 2 * cnt + 2 - single
    tstart = np.cumsum(ntok) - ntok
    vals = np.empty(int(ntok.sum()), dtype=np.int64)
    sfx = np.empty(vals.size, dtype=np.intp)
    owner = np.repeat(np.arange(rc.size), cnt)
    local = np.arange(pts.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    xpos = tstart[owner] + 2 * local
    vals[xpos] = st.q[pts, 0]
    vals[xpos + 1] = st.q[pts, 1]
    sfx[xpos] = 0
    sfx[xpos + 1] = 1
    sfx[tstart + 2 * cnt - 1] = np.where(single, 2, 3)
    close = np.where(mixed, 6, 5)
    apos = tstart + 2 * cnt
    vals[apos] = lo
    sfx[apos] = np.where(single, close, 4)
    bpos = apos[~single] + 1
    vals[bpos] = hi[~single]
    sfx[bpos] = close[~single]
    text = escape(label)
    # Every run ends by opening the next one; the last opening is cut off.
    table = [
        b",",
        b" ",
        b'"><title>line ',
        b'"><title>lines ',
        b"-",
        f": {text}</title></polyline>\n".encode() + _OPEN_POLYLINE,
        f": {text} (worst; shorter runs of milder classes merged)</title></polyline>\n".encode()
        + _OPEN_POLYLINE,
    ]
    return _OPEN_POLYLINE + render_ints(vals, sfx, table)[: -len(_OPEN_POLYLINE)]


def panel(
    st: Strokes, tp: ToolPath, severity: ArrayLike, styles: dict[int, tuple[str, str]]
) -> tuple[list[bytes], Runs]:
    """The polyline groups of one panel, mildest first so the worst are drawn on top.

    Parameters
    ----------
    st : Strokes
    tp : ToolPath
    severity : (n,) int
        Per move, -1 for rapids, higher is worse.
    styles : dict of int to (str, str)
        Per severity: the group's SVG attributes and the class name for titles.
    """
    lay = layout(st, tp, severity)
    out = []
    for sev in sorted(styles):
        body = polylines(st, lay, sev, styles[sev][1])
        if body:
            out.append(f"<g {styles[sev][0]}>\n".encode() + body + b"</g>\n")
    return out, lay.runs


# ---------------------------------------------------------------- markers
def markers(st: Strokes, tp: ToolPath, ann: Annotations) -> tuple[list[bytes], int, int]:
    """Discontinuity markers of reduction class >= 1, one per class and cell.

    The slowest junction of each (class, cell) is kept and its tooltip names it.

    Returns
    -------
    groups : list of bytes
        One ``<g fill=...>`` of circles per class, mildest first.
    cell_px : int
        Cell size used.
    kept : int
        Markers drawn.
    """
    jc_all = np.asarray(ann.junction_class, dtype=np.int64)
    sel = np.flatnonzero(jc_all >= 1)
    if sel.size == 0:
        return [], MARKER_CELL_PX, 0
    j = np.asarray(ann.junction, dtype=np.int64)[sel]
    jc = jc_all[sel]
    feed = np.asarray(ann.junction_feed, dtype=np.float64)[sel]
    pos = st.q[st.last[j]]
    ncls = int(jc.max()) + 1

    def cell_class(cell: int) -> NDArray[np.int64]:
        # Dense (column, row, class) index: the plot spans at most ~900 x 900 px.
        c = pos // (cell * Q)
        # (c0 * rows + c1) * ncls + jc, in place: one (m,) array, not four
        key = c[:, 0] * (int(c[:, 1].max()) + 1)
        key += c[:, 1]
        del c
        key *= ncls
        key += jc
        return key

    # Pick the cell by counting occupied bins (no sort), then sort once.
    cell = MARKER_CELL_PX
    key = cell_class(cell)
    while np.count_nonzero(np.bincount(key)) > MAX_MARKERS and cell < MARKER_MAX_CELL_PX:
        cell *= 2
        key = cell_class(cell)
    order = np.lexsort((feed, key))  # slowest first within each (cell, class)
    ks = key[order]
    first = np.ones(ks.size, dtype=bool)
    first[1:] = ks[1:] != ks[:-1]
    kept = np.sort(order[first])
    j, jc, feed, pos = j[kept], jc[kept], feed[kept], pos[kept]
    cause = np.asarray(ann.junction_cause, dtype=np.int64)[sel][kept]
    limit = np.asarray(ann.junction_limit, dtype=np.int64)[sel][kept]
    red = np.nan_to_num(np.asarray(ann.junction_reduction, dtype=np.float64)[sel][kept])
    pct = -np.rint(100.0 * red).astype(np.int64)
    mm_min = np.rint(np.nan_to_num(feed) * 60.0).astype(np.int64)

    nl = max(len(ann.labels), 1)
    combo, inverse = np.unique(cause * nl + limit, return_inverse=True)
    names = []
    for c in combo.tolist():
        ci, li = divmod(c, nl)
        ind = ann.indicator_names[ci] if 0 <= ci < len(ann.indicator_names) else "?"
        lab = ann.labels[li] if 0 <= li < len(ann.labels) else "?"
        names.append(f" % ({escape(ind)}: {escape(lab)}), ".encode())
    r = int(round(MARKER_R_PX * Q))
    opener = b'<circle cx="'
    base = [
        b'" cy="',
        f'" r="{r}"><title>line '.encode(),
        b"/",
        b": ",
        b" mm/min</title></circle>\n" + opener,
    ]
    out = []
    for c in unique(jc).tolist():
        m = np.flatnonzero(jc == c)
        k = m.size
        vals = np.empty((k, 6), dtype=np.int64)
        vals[:, 0] = pos[m, 0]
        vals[:, 1] = pos[m, 1]
        vals[:, 2] = tp.line[j[m]]
        vals[:, 3] = tp.line[j[m] + 1]
        vals[:, 4] = pct[m]
        vals[:, 5] = mm_min[m]
        sfx = np.empty((k, 6), dtype=np.intp)
        sfx[:, :4] = (0, 1, 2, 3)
        sfx[:, 4] = len(base) + inverse.reshape(-1)[m]
        sfx[:, 5] = 4
        body = render_ints(vals.ravel(), sfx.ravel(), base + names)
        colour = _colour(ann.class_colours, c)
        out.append(f'<g fill="{colour}">\n'.encode() + opener + body[: -len(opener)] + b"</g>\n")
    return out, cell, int(kept.size)


# ---------------------------------------------------------------- document
def _colour(colours: Sequence[str], i: int) -> str:
    """Colour ``i``, escaped for an attribute (a bad index gives black, not an exception)."""
    c = colours[i] if 0 <= i < len(colours) else "#000000"
    return escape(str(c), {'"': "&quot;"})


def nice_length(most: float) -> float:
    """Largest 1, 2 or 5 times a power of ten not above ``most`` (mm), for the scale bar."""
    if not np.isfinite(most) or most <= 0:
        return 1.0
    p = 10.0 ** np.floor(np.log10(most))
    for f in (5.0, 2.0, 1.0):
        if f * p <= most * (1 + TOL.rel_equal):
            return float(f * p)
    return float(p)


def _f(x: float) -> str:
    return f"{x:.1f}"


def zone_title(z: Zone) -> str:
    """Tooltip and legend text of a critical zone (feeds in mm/min)."""
    pct = round(100.0 * z.worst_reduction)
    called = f" (run by {z.origin})" if z.origin else ""
    return (
        f"zone {z.rank}: lines {z.lines}{called}, worst -{pct} %, "
        f"min feed {z.min_feed * 60.0:.0f} mm/min ({z.cause})"
    )


def _scale_bar(fr: Frame) -> str:
    """A bar of a round length (at most 150 px) under the plot frame."""
    length = nice_length(150.0 / fr.scale)
    w = length * fr.scale
    x, y = 0.0, fr.height + 14.0
    return (
        f'<path d="M{_f(x)} {_f(y - 4)}V{_f(y)}H{_f(x + w)}V{_f(y - 4)}" fill="none" '
        f'stroke="#000000" stroke-width="1.5"/>'
        f'<text x="{_f(x + w + 6)}" y="{_f(y + 4)}">{length:g} mm</text>\n'
    )


#: Zones whose rings would lie this close (px) share one ring, labelled with all their ranks
#: (Z-level step-downs at one XY point).
ZONE_MERGE_PX = 6.0
ZONE_RING_PX = 7.0
#: Size of a zone label's characters (13 px bold sans-serif), for placing labels apart.
LABEL_CHAR_PX = 8.0
LABEL_H_PX = 13.0


def _overlaps(a: tuple[float, float, float, float], b: tuple[float, float, float, float]) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def zone_labels(
    px: NDArray[np.float64], ranks: Sequence[int], width: float, height: float
) -> list[tuple[float, float, list[int], str, tuple[float, float, float, float]]]:
    """Rings and labels of the zones at ``px`` (their points on the plot, rank order), placed
    so that no two labels overlap each other or another ring.

    Zones closer than ZONE_MERGE_PX share a ring whose label lists their ranks ("1, 4, 7").
    Each label takes the first of a set of places around its ring, near to far (beside,
    above, below, then at 2 and 3 times the distance with a leader line), that stays in the
    plot and clear of the labels placed before it and of every ring.

    Returns
    -------
    list of (x, y, member indices, text, label box (x0, y0, x1, y1))
        One per ring; the text's baseline starts at (x0, y1 - 2).
    """
    rings: list[list] = []
    for k, (x, y) in enumerate(px.tolist()):
        for r in rings:
            if math.hypot(x - r[0], y - r[1]) <= ZONE_MERGE_PX:
                r[2].append(k)
                break
        else:
            rings.append([x, y, [k]])
    ring_boxes = [
        (x - ZONE_RING_PX, y - ZONE_RING_PX, x + ZONE_RING_PX, y + ZONE_RING_PX)
        for x, y, _ in rings
    ]
    placed: list[tuple[float, float, float, float]] = []
    out = []
    for i, (x, y, members) in enumerate(rings):
        text = ", ".join(str(ranks[k]) for k in members)
        w, h = LABEL_CHAR_PX * len(text), LABEL_H_PX
        candidates = []
        for reach in range(4):
            d = ZONE_RING_PX + 2.0 + reach * (h + 4.0)
            for dx, dy in (
                (d, -d - h / 2),
                (d, d - h / 2),
                (-d - w, -d - h / 2),
                (-d - w, d - h / 2),
                (-w / 2, -d - h),
                (-w / 2, d),
            ):
                candidates.append((x + dx, y + dy, x + dx + w, y + dy + h))
        clear = [
            box
            for box in candidates
            if not any(_overlaps(box, b) for b in placed)
            and not any(_overlaps(box, rb) for j, rb in enumerate(ring_boxes) if j != i)
        ]
        inside = [b for b in clear if b[0] >= 0 and b[1] >= 0 and b[2] <= width and b[3] <= height]
        # the nearest clear place in the plot; else the nearest clear one; else the farthest
        best = (inside or clear or candidates[-6:])[0]
        placed.append(best)
        out.append((x, y, members, text, best))
    return out


def _zones(zones: Sequence[Zone], fr: Frame, view: str) -> str:
    """Numbered rings at the worst zones, with their tooltips; labels never overlap."""
    if not zones:
        return ""
    pts = np.array([z.point for z in zones], dtype=np.float64)
    px = fr.to_px(project(pts, view))
    out = ['<g font-size="13" font-weight="bold">\n']
    for x, y, members, text, box in zone_labels(px, [z.rank for z in zones], PLOT_W, fr.height):
        tip = "\n".join(zone_title(zones[k]) for k in members)
        lx, ly = box[0], box[3] - 2.0
        cx, cy = 0.5 * (box[0] + box[2]), 0.5 * (box[1] + box[3])
        leader = ""
        if math.hypot(cx - x, cy - y) > 2.5 * ZONE_RING_PX + LABEL_CHAR_PX * len(text) / 2:
            # far from its ring: a thin line says whose label it is
            leader = (
                f'<path d="M{_f(x)} {_f(y)}L{_f(cx)} {_f(cy)}" stroke="#000000" '
                f'stroke-width="0.5"/>'
            )
        out.append(
            f"<g><title>{escape(tip)}</title>{leader}"
            f'<circle cx="{_f(x)}" cy="{_f(y)}" r="{ZONE_RING_PX:g}" fill="none" '
            f'stroke="#000000" stroke-width="1.5"/>'
            f'<text x="{_f(lx)}" y="{_f(ly)}" stroke="#ffffff" stroke-width="3" '
            f'paint-order="stroke">{text}</text></g>\n'
        )
    out.append("</g>\n")
    return "".join(out)


def _swatch(x: float, y: float, colour: str, label: str, rapid: bool = False) -> str:
    style = ' stroke-dasharray="4 3" stroke-width="1.5"' if rapid else ' stroke-width="4"'
    return (
        f'<line x1="{x:.0f}" y1="{y - 4:.0f}" x2="{x + 28:.0f}" y2="{y - 4:.0f}" '
        f'stroke="{colour}"{style}/>'
        f'<text x="{x + 36:.0f}" y="{y:.0f}">{escape(label)}</text>\n'
    )


def _legend(
    ann: Annotations,
    x_left: float,
    x_right: float,
    y: float,
    info_y: float,
    notes: str,
    colour: str = "speed",
) -> str:
    """Classes of both panels, the rapid style, the indicators that ran and the zones."""
    rapid = _colour((ann.rapid_colour,), 0)
    out = [
        '<g class="legend">\n',
        f'<text x="{x_left:.0f}" y="{y:.0f}" font-weight="bold">'
        f"{LEGEND_TITLES[_colouring(ann, colour)]}</text>\n",
    ]
    yy = y + ROW
    for c, lab in enumerate(ann.class_labels):
        out.append(_swatch(x_left, yy, _colour(ann.class_colours, c), lab))
        yy += ROW
    out.append(
        f'<circle cx="{x_left + 14:.0f}" cy="{yy - 4:.0f}" r="{MARKER_R_PX + 1:g}" '
        f'fill="{_colour(ann.class_colours, len(ann.class_colours) - 1)}" stroke="#000000" '
        f'stroke-width="0.5"/>'
        f'<text x="{x_left + 36:.0f}" y="{yy:.0f}">discontinuity, coloured by its own '
        f"reduction; drawn only for a reduction of 10 % or more</text>\n"
    )
    yy += ROW
    out.append(_swatch(x_left, yy, rapid, "rapid (G0)", rapid=True))

    out.append(
        f'<text x="{x_right:.0f}" y="{y:.0f}" font-weight="bold">'
        f"Block length l against L = F t_int (eq. 16)</text>\n"
    )
    yy = y + ROW
    for c, lab in enumerate(ann.length_labels):
        out.append(_swatch(x_right, yy, _colour(ann.length_colours, c), lab))
        yy += ROW
    out.append(_swatch(x_right, yy, rapid, "rapid (G0)", rapid=True))

    counts = ", ".join(
        f"{name} {count}"
        for name, count in zip(ann.indicator_names, ann.indicator_counts, strict=False)
    )
    out.append(
        f'<text x="{x_left:.0f}" y="{info_y:.0f}">Indicators (points or blocks '
        f"held below the programmed feed): {escape(counts or 'none')}</text>\n"
    )
    out.append(
        f'<text x="{x_left:.0f}" y="{info_y + ROW:.0f}" fill="#555555">{escape(notes)}</text>\n'
    )
    if ann.zones:
        out.append(
            f'<text x="{x_left:.0f}" y="{info_y + 2 * ROW:.0f}" font-weight="bold">'
            f"Worst zones (numbered on the left panel)</text>\n"
        )
    for k, z in enumerate(ann.zones):
        out.append(
            f'<text x="{x_left + 12:.0f}" y="{info_y + ROW * (k + 3):.0f}">'
            f"{escape(zone_title(z))}</text>\n"
        )
    out.append("</g>\n")
    return "".join(out)


def _check(tp: ToolPath, ann: Annotations) -> None:
    """Raise ValueError, naming the array and its shape, if ``ann`` does not fit ``tp``."""
    n = tp.n
    for name in ("move_class", "length_class"):
        shape = np.shape(getattr(ann, name))
        if shape != (n,):
            raise ValueError(
                f"annotations.{name} must have shape ({n},) like the tool path, got {shape}"
            )
    m = np.shape(ann.junction)
    for name in (
        "junction_class",
        "junction_feed",
        "junction_reduction",
        "junction_cause",
        "junction_limit",
    ):
        if np.shape(getattr(ann, name)) != m:
            raise ValueError(
                f"annotations.{name} must have shape {m} like annotations.junction, "
                f"got {np.shape(getattr(ann, name))}"
            )
    check_drawable(tp)
    j = np.asarray(ann.junction)
    if j.size and (j.min() < 0 or j.max() >= n - 1):
        raise ValueError(f"annotations.junction must lie in 0..{n - 2}, got {j.min()}..{j.max()}")


#: Attributes of a plot group: coordinates are integers of 1/Q px, stroke widths too.
PLOT_ATTRS = (
    f'transform="scale({1 / Q:g})" fill="none" stroke-width="{round(STROKE_PX * Q)}"'
    f' stroke-linecap="round" stroke-linejoin="round"'
)


def _document_head(width: float, height: float, title: str, head: str) -> bytes:
    """The SVG's opening: size, title, white background and the heading line."""
    return (
        f'<?xml version="1.0" encoding="UTF-8"?>\n'
        f'<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{width:.0f}" '
        f'height="{height:.0f}" viewBox="0 0 {width:.0f} {height:.0f}" '
        f'font-family="sans-serif" font-size="12">\n'
        f"<title>{title}</title>\n"
        f'<rect width="{width:.0f}" height="{height:.0f}" fill="#ffffff"/>\n'
        f'<text x="{MARGIN:.0f}" y="28" font-size="16" font-weight="bold">{head}</text>\n'
    ).encode()


def _rapid_style(ann: Annotations, label: str = "rapid") -> tuple[str, str]:
    """Stroke attributes and legend label of rapids: dashed, in the annotations' colour."""
    rapid = _colour((ann.rapid_colour,), 0)
    return (
        f'stroke="{rapid}" stroke-width="{round(RAPID_STROKE_PX * Q)}" '
        f'stroke-dasharray="{4 * Q} {3 * Q}"',
        label,
    )


def _colouring(ann: Annotations, colour: str) -> str:
    """The colouring drawn: ``colour``, or ``paper`` when the annotations have no profile."""
    if colour not in COLOURINGS:
        raise ValueError(f"colour must be one of {COLOURINGS}, got {colour!r}")
    return colour if ann.speed_class is not None else "paper"


def _reduction_severity(
    tp: ToolPath, ann: Annotations, colour: str = "speed"
) -> tuple[NDArray[np.int64], dict[int, tuple[str, str]]]:
    """Severity of each move by its class (-1 for rapids), and the styles: the class of
    the profile's mean speed (``speed``) or of the block's own cruise feed (``paper``)."""
    how = _colouring(ann, colour)
    nclass = len(ann.class_labels)
    mc = np.asarray(ann.speed_class if how == "speed" else ann.move_class, dtype=np.int64)
    sev = np.where(tp.is_feed, np.clip(mc, 0, nclass - 1), -1)
    styles = {-1: _rapid_style(ann)}
    for c in range(nclass):
        styles[c] = (
            f'stroke="{_colour(ann.class_colours, c)}"',
            f"{CLASS_PREFIX[how]} {ann.class_labels[c]}",
        )
    return sev, styles


def shown_name(source: str) -> str:
    """The program's file name for titles (not the folders of its path)."""
    return os.path.basename(source.rstrip("/\\")) or source


def render_svg(tp: ToolPath, ann: Annotations, view: str = "xy", colour: str = "speed") -> bytes:
    """The whole SVG document (UTF-8) for a tool path and its annotations.

    Parameters
    ----------
    tp : ToolPath
    ann : Annotations
        Built from an evaluation of ``tp``.
    view : {"xy", "xz", "yz", "iso"}
    colour : {"speed", "paper"}
        What the left panel colours blocks by (see :data:`COLOURINGS`).

    Returns
    -------
    bytes
    """
    if view not in PROJECTIONS:
        raise ValueError(f"view must be one of {VIEWS}, got {view!r}")
    _check(tp, ann)
    st = strokes(tp, view)
    fr = st.frame
    # Left (Figure 11): the severity is the reduction class.
    nclass = len(ann.class_labels)
    sev_left, left_styles = _reduction_severity(tp, ann, colour)
    rapid_style = left_styles[-1]
    left, rn_left = panel(st, tp, sev_left, left_styles)
    marks, mark_cell, mark_count = markers(st, tp, ann)

    # Right (Figure 10): class 0 (shorter than L) is the worst.
    lc = np.asarray(ann.length_class, dtype=np.int64)
    nlen = len(ann.length_labels)
    sev_right = np.where(tp.is_feed, nlen - 1 - np.clip(lc, 0, nlen - 1), -1)
    right_styles = {-1: rapid_style}
    for c in range(nlen):
        right_styles[nlen - 1 - c] = (
            f'stroke="{_colour(ann.length_colours, c)}"',
            f"block {ann.length_labels[c]}",
        )
    right, rn_right = panel(st, tp, sev_right, right_styles)

    pool = max(rn_left.pool_px, rn_right.pool_px)
    notes = (
        f"{tp.n} moves. Runs shorter than {pool} px show their worst class; "
        f"points within {st.dedupe_px} px merged; "
        f"{mark_count} discontinuity markers, at most one per class and {mark_cell} px cell "
        f"(the slowest). Hover over any line or marker for its program lines."
    )

    width = 2 * MARGIN + 2 * PLOT_W + GAP
    x_left, x_right = MARGIN, MARGIN + PLOT_W + GAP
    ph = fr.height
    legend_y = TOP + ph + 48.0
    info_y = legend_y + ROW * (max(nclass + 2, nlen + 1) + 1) + 10.0
    height = info_y + ROW * (3 + len(ann.zones)) + MARGIN

    head = escape(f"{shown_name(ann.title)} on {ann.machine}: {VIEW_NAMES[view]} view")
    s: list[bytes] = []
    w = s.append
    w(_document_head(width, height, f"ncperf: {head}", head))
    for x, title, groups, is_left in (
        (x_left, LEFT_TITLES[_colouring(ann, colour)], left, True),
        (x_right, RIGHT_TITLE, right, False),
    ):
        w(
            (
                f'<g transform="translate({x:.0f},{TOP:.0f})">\n'
                f'<text x="0" y="-10" font-size="14" font-weight="bold">{escape(title)}</text>\n'
                f'<rect width="{PLOT_W:.0f}" height="{ph:.1f}" fill="none" stroke="#cccccc"/>\n'
                f"<g {PLOT_ATTRS}>\n"
            ).encode()
        )
        s.extend(groups)
        if is_left and marks:
            w(f'<g stroke="#000000" stroke-width="{round(0.5 * Q)}">\n'.encode())
            s.extend(marks)
            w(b"</g>\n")
        w(b"</g>\n")
        if is_left:
            w(_zones(ann.zones, fr, view).encode())
        w(_scale_bar(fr).encode())
        w(b"</g>\n")
    w(_legend(ann, x_left, x_right, legend_y, info_y, notes, colour).encode())
    w(b"</svg>\n")
    return b"".join(s)


def render_comparison(
    panels: Sequence[tuple[str, ToolPath, Annotations]], view: str = "xy", colour: str = "speed"
) -> bytes:
    """Several programs side by side, at one scale and in one colour scale (the reduction
    classes), each with its discontinuity markers and worst zones.

    Parameters
    ----------
    panels : sequence of (label, ToolPath, Annotations)
        In the order to draw them, left to right.
    view : {"xy", "xz", "yz", "iso"}
    """
    if view not in PROJECTIONS:
        raise ValueError(f"view must be one of {VIEWS}, got {view!r}")
    if not panels:
        raise ValueError("nothing to compare")
    for _, tp, ann in panels:
        _check(tp, ann)
    # One scale for all: the smallest that fits each program in its own panel.
    scale = min(strokes(tp, view).frame.scale for _, tp, _ in panels)
    drawn = [(label, tp, ann, strokes(tp, view, scale)) for label, tp, ann in panels]
    first_ann = panels[0][2]
    nclass = len(first_ann.class_labels)
    rapid = _colour((first_ann.rapid_colour,), 0)
    plot_h = max(st.frame.height for *_, st in drawn)
    width = 2 * MARGIN + len(drawn) * PLOT_W + (len(drawn) - 1) * GAP
    legend_y = TOP + plot_h + 48.0
    height = legend_y + ROW * (nclass + 3) + MARGIN
    head = escape(f"ncperf compare on {first_ann.machine}: {VIEW_NAMES[view]} view, one scale")
    s: list[bytes] = [_document_head(width, height, head, head)]
    for k, (label, tp, ann, st) in enumerate(drawn):
        x = MARGIN + k * (PLOT_W + GAP)
        sev, styles = _reduction_severity(tp, ann, colour)
        groups, _ = panel(st, tp, sev, styles)
        marks, _, _ = markers(st, tp, ann)
        s.append(
            (
                f'<g transform="translate({x:.0f},{TOP:.0f})">\n'
                f'<text x="0" y="-10" font-size="14" font-weight="bold">{escape(label)}</text>\n'
                f'<rect width="{PLOT_W:.0f}" height="{st.frame.height:.1f}" fill="none" '
                f'stroke="#cccccc"/>\n<g {PLOT_ATTRS}>\n'
            ).encode()
        )
        s.extend(groups)
        if marks:
            s.append(f'<g stroke="#000000" stroke-width="{round(0.5 * Q)}">\n'.encode())
            s.extend(marks)
            s.append(b"</g>\n")
        s.append(b"</g>\n")
        s.append(_zones(ann.zones, st.frame, view).encode())
        s.append(_scale_bar(st.frame).encode())
        s.append(b"</g>\n")
    out = [
        '<g class="legend">\n',
        f'<text x="{MARGIN:.0f}" y="{legend_y:.0f}" font-weight="bold">'
        f"{LEGEND_TITLES[_colouring(first_ann, colour)]} (all panels)</text>\n",
    ]
    yy = legend_y + ROW
    for c, lab in enumerate(first_ann.class_labels):
        out.append(_swatch(MARGIN, yy, _colour(first_ann.class_colours, c), lab))
        yy += ROW
    out.append(_swatch(MARGIN, yy, rapid, "rapid (G0)", rapid=True))
    out.append("</g>\n")
    s.append("".join(out).encode())
    s.append(b"</svg>\n")
    return b"".join(s)


def _feed_plot(
    x0: float,
    y0: float,
    w: float,
    h: float,
    title: str,
    series: Sequence[tuple[NDArray, NDArray, str, str]],
) -> str:
    """A small chart of feed (mm/min) over arc length (mm): (s, v, colour, dash) series."""
    s_all = np.concatenate([s for s, *_ in series])
    v_all = np.concatenate([v for _, v, *_ in series])
    s_lo, s_hi = float(s_all.min()), float(s_all.max())
    v_hi = float(max(v_all.max(), TOL.nil_speed)) * 1.08
    if s_hi <= s_lo:
        s_hi = s_lo + 1.0
    out = [
        f'<g transform="translate({x0:.0f},{y0:.0f})">\n',
        f'<text x="0" y="-6" font-weight="bold">{escape(title)}</text>\n',
        f'<rect width="{w:.0f}" height="{h:.0f}" fill="none" stroke="#cccccc"/>\n',
    ]
    for s, v, colour, dash in series:
        xs = (s - s_lo) / (s_hi - s_lo) * w
        ys = h - v / v_hi * h
        pts = " ".join(f"{a:.1f},{b:.1f}" for a, b in zip(xs.tolist(), ys.tolist(), strict=True))
        dash_attr = f' stroke-dasharray="{dash}"' if dash else ""
        out.append(
            f'<polyline points="{pts}" fill="none" stroke="{colour}" '
            f'stroke-width="1.5"{dash_attr}/>\n'
        )
    out.append(
        f'<text x="0" y="{h + 14:.0f}">{s_lo:.1f} mm</text>'
        f'<text x="{w:.0f}" y="{h + 14:.0f}" text-anchor="end">{s_hi:.1f} mm</text>'
        f'<text x="-4" y="8" text-anchor="end">{v_hi:.0f}</text>'
        f'<text x="-4" y="{h:.0f}" text-anchor="end">0</text>\n</g>\n'
    )
    return "".join(out)


def render_diagnosis(
    tp: ToolPath, ann: Annotations, diagnosis: Diagnosis, view: str = "xy"
) -> bytes:
    """The path coloured by gap (measured against predicted feed), the gap zones numbered,
    and measured against predicted feed over arc length for the worst zones (``ann``: the
    diagnosis's annotations).
    """
    d = diagnosis
    if view not in PROJECTIONS:
        raise ValueError(f"view must be one of {VIEWS}, got {view!r}")
    _check(tp, ann)
    st = strokes(tp, view)
    rapid = _colour((ann.rapid_colour,), 0)
    styles = {-1: _rapid_style(ann, "rapid or not measured")}
    for c, lab in enumerate(ann.class_labels):
        styles[c] = (f'stroke="{_colour(ann.class_colours, c)}"', lab)
    # Draw the widest gaps on top: order the severities by distance from "within".
    mid = len(ann.class_labels) // 2
    sev = np.asarray(ann.move_class, dtype=np.int64)
    rank = np.where(sev < 0, -1, np.abs(sev - mid))
    ranked_styles = {-1: styles[-1]}
    groups = []
    for r in sorted(set(rank.tolist())):
        sel_styles = {k: v for k, v in styles.items() if k >= 0 and abs(k - mid) == r}
        for c, style in sel_styles.items():
            mask = np.where(sev == c, 0, -1)
            g, _ = panel(st, tp, mask, {0: style})
            groups += g
    g_rapid, _ = panel(st, tp, np.where(sev < 0, -1, -2), ranked_styles)
    fr = st.frame
    zones = list(d.zones[:10])
    n_plots = min(4, len(zones))
    plot_w, plot_h = 420.0, 150.0
    width = 2 * MARGIN + PLOT_W + GAP + 2 * plot_w + 80
    legend_y = TOP + fr.height + 48.0
    height = (
        max(
            legend_y + ROW * (len(ann.class_labels) + 8),
            TOP + (plot_h + 50) * ((n_plots + 1) // 2) + 40,
        )
        + MARGIN
    )
    head = escape(
        f"{shown_name(tp.source)}: measured against predicted feed ({d.baseline} baseline), "
        f"{VIEW_NAMES[view]} view"
    )
    s: list[bytes] = [_document_head(width, height, f"ncperf diagnose: {head}", head)]
    s.append(
        (
            f'<g transform="translate({MARGIN:.0f},{TOP:.0f})">\n'
            f'<text x="0" y="-10" font-size="14" font-weight="bold">Gap along the path '
            f"(before the chosen effects)</text>\n"
            f'<rect width="{PLOT_W:.0f}" height="{fr.height:.1f}" fill="none" '
            f'stroke="#cccccc"/>\n<g {PLOT_ATTRS}>\n'
        ).encode()
    )
    s += g_rapid + groups
    s.append(b"</g>\n")
    # Numbered gap zones.
    out = ['<g font-size="13" font-weight="bold">\n']
    for k, z in enumerate(zones, start=1):
        mv = int(tp.move_at(0.5 * (z.s_start + z.s_end)))
        ((x, y),) = fr.to_px(project(0.5 * (tp.start[mv : mv + 1] + tp.end[mv : mv + 1]), view))
        lines = f"{z.line_start}" if z.line_start == z.line_end else f"{z.line_start}-{z.line_end}"
        tip = (
            f"gap zone {k}: lines {lines}, {z.feature}, RMS gap {z.gap_rms:.0f} mm/min, "
            f"{z.time_s:+.3f} s"
        )
        out.append(
            f"<g><title>{escape(tip)}</title>"
            f'<circle cx="{_f(x)}" cy="{_f(y)}" r="7" fill="none" stroke="#000000" '
            f'stroke-width="1.5"/><text x="{_f(x + 8)}" y="{_f(y - 8)}" stroke="#ffffff" '
            f'stroke-width="3" paint-order="stroke">{k}</text></g>\n'
        )
    out.append("</g>\n")
    s.append("".join(out).encode())
    s.append(_scale_bar(fr).encode())
    s.append(b"</g>\n")
    # Feed plots of the worst zones.
    px0 = MARGIN + PLOT_W + GAP + 30
    for k, z in enumerate(zones[:n_plots]):
        pad = max(2.0, 0.5 * (z.s_end - z.s_start))
        series = []
        for dd in d.data:
            sel = (dd.s >= z.s_start - pad) & (dd.s <= z.s_end + pad)
            if sel.sum() >= 2:
                # (read as the trace's feed is: its commanded column or its positions' speed)
                before = d.before.speed_at(dd.s[sel], commanded=dd.commanded)
                series.append((dd.s[sel], before * 60, "#888888", "5 3"))
                if d.chosen:
                    after = d.after.speed_at(dd.s[sel], commanded=dd.commanded)
                    series.append((dd.s[sel], after * 60, "#2166ac", ""))
                series.append((dd.s[sel], dd.v[sel] * 60, "#000000", ""))  # on top
                break
        if not series:
            continue
        lines = f"{z.line_start}" if z.line_start == z.line_end else f"{z.line_start}-{z.line_end}"
        x = px0 + (k % 2) * (plot_w + 30)
        y = TOP + (k // 2) * (plot_h + 50)
        s.append(
            _feed_plot(
                x, y, plot_w, plot_h, f"zone {k + 1}: lines {lines} ({z.feature})", series
            ).encode()
        )
    # Legend and verdict.
    out = ['<g class="legend">\n']
    yy = legend_y
    for c, lab in enumerate(ann.class_labels):
        out.append(_swatch(MARGIN, yy, _colour(ann.class_colours, c), lab))
        yy += ROW
    out.append(_swatch(MARGIN, yy, rapid, "rapid, or not in the trace", rapid=True))
    yy += ROW * 1.5
    from core.diagnosis.rules import BEST_SHARE  # the diagnosis's drawing only

    verdict = (
        f"best effect: {d.best_effect}; chosen: {' + '.join(d.chosen)}; gap "
        f"{d.gap_rms_before:.0f} -> {d.gap_rms_after:.0f} mm/min (RMS over time)"
        if d.best_effect
        else f"no effect removes {BEST_SHARE * 100:.0f} % of the held-out gap "
        f"({d.gap_rms_before:.0f} mm/min): "
        "the model already explains this trace"
    )
    out.append(f'<text x="{MARGIN:.0f}" y="{yy:.0f}" font-weight="bold">{escape(verdict)}</text>\n')
    yy += ROW
    out.append(
        f'<text x="{MARGIN:.0f}" y="{yy:.0f}">plots: measured (black), predicted '
        f"before (grey, dashed) and with the chosen effects (blue), feed in mm/min over "
        f"arc length</text>\n</g>\n"
    )
    s.append("".join(out).encode())
    s.append(b"</svg>\n")
    return b"".join(s)


def write_svg(
    tp: ToolPath,
    ann: Annotations,
    path: str | os.PathLike[str],
    view: str = "xy",
    colour: str = "speed",
) -> str:
    """Render, then write atomically: the file is complete or absent, never partial.

    Returns
    -------
    str
        The path written.
    """
    data = render_svg(tp, ann, view, colour)
    with atomic_writer(path, binary=True) as fh:
        fh.write(data)
    return os.fspath(path)
