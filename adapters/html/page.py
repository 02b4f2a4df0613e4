"""Build the self-contained HTML viewer: one file, scripts and styles inline, the tool path and
its predictions as compressed typed arrays (zlib, base64) that ``viewer.js`` draws with WebGL.

What is embedded, per program (a *panel*; ``compare`` has several):

* the path as a polyline of points: each move adds ``npts`` points (1 for a line, the
  samples of an arc, its end included), preceded by its own start where it does not begin
  at the previous move's end (``npts`` has bit 7 set then). Points are integers of
  ``quantum`` mm from ``centre`` (0.1 um, or coarser for paths over 100 m across), stored
  per axis as differences from the previous point: small integers that zlib packs tightly
  (a 1M-move raster takes about 3 bytes a point). Arcs are drawn as chords whose sagitta
  is at most :data:`CHORD_REL` of the path's extent (2 to :data:`ARC_MAX_SEGMENTS` per arc);
* per move: kind (rapid, line, arc), program line, programmed feed (mm/min), the profile's
  mean speed over F (``speed_share``, 1/65535), the three class arrays the colour modes use,
  length (mm), the profile's entry, peak and exit speeds (of the largest speed, 1/65535)
  and where along the move the ramps end and start (1/255 of its length) for the speed
  plot, and what caps the block (an index into ``names``);
* per reported junction: the move it ends, its class, predicted feed and binding limit;
* the program text (zlib), unless it is over :data:`TEXT_LIMIT` (the page says so).

Every array is little-endian, its bytes split into planes (all first bytes, then all second
bytes...) before compression, which lets zlib find the slowly varying high bytes. The small
metadata (names, zones, labels, the table) is JSON in a ``<script type="application/json">``
block, with ``<``, ``>``, ``&`` and U+2028/2029 escaped so no input text can close the block;
the page puts every text it shows in place with ``textContent``.
"""

from __future__ import annotations

import base64
import json
import math
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from importlib import resources
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from core.diagnosis.rules import GAP_COLOURS, GAP_LABELS
from core.engine.indicators import REDUCTION_LABELS
from core.model import geometry as g
from core.model.pieces import pieces, piecewise
from core.model.text import printable, printable_tree
from core.model.toolpath import MoveKind, ToolPath
from core.view.annotations import (
    LENGTH_COLOURS,
    LENGTH_LABELS,
    REDUCTION_COLOURS,
    Annotations,
    check_drawable,
    speed_class,
    speed_share,
)

if TYPE_CHECKING:
    from core.diagnosis.diagnose import Diagnosis
    from core.engine.indicators import Evaluation
    from core.engine.profile import Profile

#: Finest coordinate step embedded (mm): 0.1 um, below any controller's resolution.
QUANTUM = 1e-4
#: Largest integer coordinate (the quantum grows for paths wider than 2^30 quanta).
MAX_UNITS = 2**30
#: Arc chords deviate from the arc by at most this share of the path's largest extent
#: (0.2 px on a 1000 px view of the whole path).
CHORD_REL = 2e-4
ARC_MIN_SEGMENTS = 2
ARC_MAX_SEGMENTS = 64
#: Most arc sample points in all: beyond it arcs get fewer segments (bounds the file).
ARC_POINT_BUDGET = 2_000_000
#: Program text beyond this many bytes is not embedded (the page says so).
TEXT_LIMIT = 50 * 2**20
#: Measured samples embedded for the plot of a diagnosis, at most (per trace).
MAX_MEASURED = 500_000
PER_MIN = 60.0
U16 = 65535
#: Bit of ``npts`` that says the move's own start point comes first.
BREAK = 0x80
_KIND_RAPID, _KIND_LINE, _KIND_ARC = 0, 1, 2


def _read_asset(name: str) -> str:
    return resources.files("adapters.html").joinpath(name).read_text(encoding="utf-8")


def json_for_script(value: object) -> str:
    """JSON safe inside ``<script type="application/json">``: no ``<``, ``>``, ``&`` or line
    separators that could end the block or confuse a parser; NaN becomes null."""
    text = json.dumps(value, ensure_ascii=False, allow_nan=False, separators=(",", ":"))
    return (
        text.replace("&", "\\u0026")
        .replace("<", "\\u003c")
        .replace(">", "\\u003e")
        .replace("\u2028", "\\u2028")
        .replace("\u2029", "\\u2029")
    )


@dataclass
class Blobs:
    """The binary arrays of a page, each a base64 text in its own script element."""

    items: list[tuple[str, str]] = field(default_factory=list)
    raw_bytes: int = 0

    def add(self, arr: NDArray, *, delta: bool = False) -> dict[str, Any]:
        """Embed ``arr`` (1-D, or 2-D stored row by row); returns its spec for the JSON.

        ``delta``: integers stored as differences from the previous value of their row
        (int32 wrap-around), undone in the page by a running sum.
        """
        a = np.ascontiguousarray(arr)
        if a.dtype.byteorder == ">":
            a = a.astype(a.dtype.newbyteorder("<"))
        if delta and a.dtype != np.int32:
            raise ValueError(f"delta coding needs int32, got {a.dtype}")
        # The planes (or the bytes) go to zlib piece by piece: one stream flushed once gives
        # the bytes of zlib.compress over the whole, without the whole's copies.
        z = zlib.compressobj(6)
        blob = b"".join(z.compress(part) for part in _stored_pieces(a, delta)) + z.flush()
        self.raw_bytes += a.nbytes
        ident = f"b{len(self.items)}"
        self.items.append((ident, base64.b64encode(blob).decode("ascii")))
        return {
            "id": ident,
            "dtype": a.dtype.str.lstrip("<|="),
            "shape": list(a.shape),
            "delta": delta,
        }

    def html(self) -> str:
        return "".join(
            f'<script type="application/octet-stream" id="{i}">{b}</script>\n'
            for i, b in self.items
        )


def _stored_pieces(a: NDArray, delta: bool) -> Iterator[memoryview]:
    """The bytes :meth:`Blobs.add` compresses, in order, a piece at a time: each byte plane
    over all elements (C order), of the values or, with ``delta``, of their differences along
    the last axis (int32 subtraction wraps as the int64 difference cast back to int32 does)."""
    if a.size == 0:
        return
    size = a.dtype.itemsize
    rows = a.reshape(-1, a.shape[-1]) if delta else a.reshape(1, -1)
    for plane in range(size):
        for row in rows:
            for s in pieces(row.size):
                v = row[s]
                if delta:
                    d = np.empty_like(v)
                    if s.start:
                        np.subtract(v, row[s.start - 1 : s.stop - 1], out=d)
                    else:
                        d[0] = v[0]
                        np.subtract(v[1:], v[:-1], out=d[1:])
                    v = d
                plane_bytes = (
                    v if size == 1 else np.ascontiguousarray(v.view(np.uint8)[plane::size])
                )
                yield plane_bytes.data


def arc_counts(tp: ToolPath, arcs: NDArray[np.int64], extent: float) -> NDArray[np.int64]:
    """Segments per arc so that the sagitta r (1 - cos(a/2)) of each chord stays below
    CHORD_REL * extent; within ARC_MIN_SEGMENTS..ARC_MAX_SEGMENTS and the point budget."""
    if arcs.size == 0:
        return np.zeros(0, dtype=np.int64)
    eps = CHORD_REL * max(extent, QUANTUM)
    r = tp.radius[arcs]
    with np.errstate(divide="ignore", invalid="ignore"):
        step = 2.0 * np.arccos(np.clip(1.0 - eps / r, -1.0, 1.0))
        n = np.ceil(tp.sweep[arcs] / step)
    n = np.where(np.isfinite(n), n, ARC_MIN_SEGMENTS)
    n = np.clip(n, ARC_MIN_SEGMENTS, ARC_MAX_SEGMENTS).astype(np.int64)
    total = int(n.sum())
    if total > ARC_POINT_BUDGET:
        n = np.maximum(n * ARC_POINT_BUDGET // total, ARC_MIN_SEGMENTS)
    return n


@dataclass(frozen=True)
class Geometry:
    """The drawn polyline of a tool path (see the module docstring).

    Attributes
    ----------
    points : (p, 3) float, mm
    npts : (n,) uint8
        Points each move adds, bit 7 set where its own start comes first.
    first, last : (n,) int64
        Index in ``points`` of each move's start and end.
    """

    points: NDArray[np.float64]
    npts: NDArray[np.uint8]
    first: NDArray[np.int64]
    last: NDArray[np.int64]


def geometry(tp: ToolPath, quantum: float, centre: NDArray[np.float64]) -> Geometry:
    """The polyline of ``tp``, arcs tessellated, with breaks where moves do not join (on the
    grid of ``quantum`` mm around ``centre``)."""
    n = tp.n
    lo, hi = _box(tp)
    ext = float((hi - lo).max()) if n else 0.0
    arcs = np.flatnonzero(tp.is_arc)
    ok = (
        np.isfinite(tp.radius[arcs])
        & np.isfinite(tp.sweep[arcs])
        & np.isfinite(tp.pitch[arcs])
        & (tp.sweep[arcs] > 0)
    )
    arcs = arcs[ok]
    counts = arc_counts(tp, arcs, ext)
    add = np.ones(n, dtype=np.int64)
    add[arcs] = counts
    brk = np.ones(n, dtype=bool)
    if n > 1:
        # Move k + 1 starts where move k ends unless their grid points differ.
        brk[1:] = piecewise(
            n - 1,
            np.bool_,
            lambda s: np.any(
                np.rint((tp.start[s.start + 1 : s.stop + 1] - centre) / quantum)
                != np.rint((tp.end[s] - centre) / quantum),
                axis=1,
            ),
        )
    per = add + brk
    last = np.cumsum(per) - 1
    first = last - add
    pts = np.empty((int(per.sum()), 3))
    del per
    pts[first] = tp.start  # where there is no break, the previous end lands here too
    pts[last] = tp.end
    if arcs.size:
        samples = g.sample_arcs(
            tp.start[arcs],
            tp.center[arcs],
            tp.normal[arcs],
            tp.kind[arcs] == MoveKind.ARC_CCW,
            tp.sweep[arcs],
            tp.pitch[arcs],
            counts,
        )
        m = counts + 1
        local = np.arange(samples.shape[0]) - np.repeat(np.cumsum(m) - m, m)
        inner = (local > 0) & (local < np.repeat(counts, m))
        pts[np.repeat(first[arcs], m)[inner] + local[inner]] = samples[inner]
    # Where moves join, the shared point is the previous end (written last, below).
    joined = np.flatnonzero(~brk)
    for s in pieces(joined.size):
        pts[first[joined[s]]] = tp.end[joined[s] - 1]
    npts = add.astype(np.uint8)  # 1..ARC_MAX_SEGMENTS
    npts[brk] |= BREAK
    return Geometry(pts, npts, first, last)


def _box(tp: ToolPath) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(3,) least and greatest coordinates of the moves' ends and starts (mm); zeros for no
    moves."""
    if tp.n == 0:
        return np.zeros(3), np.zeros(3)
    return (
        np.minimum(tp.start.min(axis=0), tp.end.min(axis=0)),
        np.maximum(tp.start.max(axis=0), tp.end.max(axis=0)),
    )


def _names(ev: Evaluation | None, ann: Annotations) -> list[str]:
    """The "indicator: limit" name of every (indicator, label) pair, in index order."""
    if ev is not None:
        ind, lab = ev.indicator_names, ev.labels
    else:
        ind, lab = ann.indicator_names, ann.labels
    return [f"{i}: {b}" for i in ind for b in lab] or ["?"]


def _name_index(ind: NDArray, lim: NDArray, nlab: int) -> NDArray[np.int16]:
    ind, lim = np.asarray(ind), np.asarray(lim)

    def index(s: slice) -> NDArray[np.int16]:
        i = ind[s].astype(np.int64)
        b = lim[s].astype(np.int64)
        return np.where((i >= 0) & (b >= 0), i * max(nlab, 1) + b, -1).astype(np.int16)

    return piecewise(ind.shape[0], np.int16, index)


def _feed_f32(is_feed: NDArray[np.bool_], feed: NDArray) -> NDArray[np.float32]:
    """A feed per move (mm/s) in mm/min as float32, NaN for rapids."""
    return piecewise(
        is_feed.shape[0],
        np.float32,
        lambda s: np.where(is_feed[s], feed[s] * PER_MIN, np.nan).astype(np.float32),
    )


def _u16(x: NDArray, scale: float) -> NDArray[np.uint16]:
    v = np.nan_to_num(np.asarray(x, dtype=np.float64) / scale, nan=0.0)
    return np.rint(np.clip(v, 0.0, 1.0) * U16).astype(np.uint16)


def _u8(x: NDArray) -> NDArray[np.uint8]:
    v = np.nan_to_num(np.asarray(x, dtype=np.float64), nan=0.0)
    return np.rint(np.clip(v, 0.0, 1.0) * 255).astype(np.uint8)


def _speed_arrays(
    blobs: Blobs, tp: ToolPath, ann: Annotations, pr: Profile | None, spec: dict[str, Any]
) -> None:
    """The mean speed over F per move and its class (the "speed" colour mode)."""
    n, is_feed = tp.n, tp.is_feed
    share = ann.speed_share
    if share is None and pr is not None:
        share = piecewise(n, np.float64, lambda s: speed_share(pr, s))
    if share is not None:
        spec["share"] = blobs.add(
            piecewise(n, np.uint16, lambda s: _u16(np.where(is_feed[s], share[s], np.nan), 1.0))
        )
    sclass = ann.speed_class
    if sclass is None and share is not None:
        sclass = piecewise(n, np.int8, lambda s: speed_class(share[s], is_feed[s]))
    if sclass is not None:
        spec["sclass"] = blobs.add(np.asarray(sclass, dtype=np.int8))


def _profile_arrays(blobs: Blobs, tp: ToolPath, pr: Profile, spec: dict[str, Any]) -> None:
    """Entry, peak and exit speeds and the ramps' ends, for the speed plot."""
    speeds = (pr.v_entry, pr.v_peak, pr.v_exit)
    top = [
        float(f.max())
        for v in speeds
        for s in pieces(v.size)
        if (f := v[s][np.isfinite(v[s])]).size
    ]
    vmax = max(top) if top else 0.0
    vmax = vmax if vmax > 0 else 1.0
    spec["vmax"] = vmax * PER_MIN
    n = tp.n
    out16 = np.empty((3, n), dtype=np.uint16)
    for row, v in zip(out16, speeds, strict=True):
        for s in pieces(n):
            row[s] = _u16(v[s], vmax)
    spec["v"] = blobs.add(out16)
    del out16
    # Piece by piece with Profile.phases_of (the arithmetic of Profile.phases, which would
    # keep five (n,) arrays on the profile).
    out8 = np.empty((4, n), dtype=np.uint8)
    for s in pieces(n):
        _, _, d_up, d_dn, _ = pr.phases_of(s)
        length = tp.length[s]
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = np.where(length > 0, 1.0 / length, 0.0)
        up = (pr.hold_start[s] + np.nan_to_num(d_up)) * inv
        dn = 1.0 - (pr.hold_end[s] + np.nan_to_num(d_dn)) * inv
        out8[0, s] = _u8(pr.hold_start[s] * inv)
        out8[1, s] = _u8(up)
        out8[2, s] = _u8(np.maximum(dn, up))
        out8[3, s] = _u8(1.0 - pr.hold_end[s] * inv)
    spec["frac"] = blobs.add(out8)


def _text(program: str | None) -> tuple[str | None, str]:
    """The program text for the hover (None if not embedded) and a note saying why not."""
    if not program:
        return None, "program text not embedded (no program file)"
    try:
        with open(program, "rb") as fh:
            data = fh.read(TEXT_LIMIT + 1)
    except OSError as exc:
        return None, f"program text not embedded ({exc.strerror})"
    if len(data) > TEXT_LIMIT:
        return None, f"program text not embedded (over {TEXT_LIMIT // 2**20} MB)"
    text = data.decode("utf-8", errors="surrogateescape")
    del data  # a long program is held once or twice at a time, not four times
    text = text.replace("\r\n", "\n")
    # Every control, bidi control and undecodable byte as a visible escape (as the terminal
    # and the SVG show them); newlines kept: the page splits the text into lines.
    return printable(text, lines=True), ""


def panel_data(
    blobs: Blobs,
    label: str,
    tp: ToolPath,
    ann: Annotations,
    *,
    evaluation: Evaluation | None = None,
    profile: Profile | None = None,
    program: str | None = None,
    diagnosis: Diagnosis | None = None,
    gap_class: NDArray[np.int8] | None = None,
    centre: NDArray[np.float64] | None = None,
) -> dict[str, Any]:
    """Embed one program's arrays in ``blobs``; returns its JSON description.

    Parameters
    ----------
    blobs : Blobs
    label : str
    tp : ToolPath
    ann : Annotations
        The predicted classes of ``tp`` (speed share, reduction, length, junctions, zones).
    evaluation, profile : optional
        What caps each block (hover) and the feed profile (speed plot).
    program : str, optional
        The main program file, whose lines the hover shows.
    diagnosis : Diagnosis, optional
        Adds the gap per move (``gap_class``, one per move), the gap zones (instead of
        ``ann``'s) and the measured feed.
    centre : (3,) float, mm, optional
        Origin of the embedded coordinates (``compare``: one for all programs).
    """
    n = tp.n
    if np.shape(ann.move_class) != (n,) or np.shape(ann.length_class) != (n,):
        raise ValueError(
            f"annotations must have one class per move ({n}), got {np.shape(ann.move_class)} "
            f"and {np.shape(ann.length_class)}"
        )
    check_drawable(tp)
    lo, hi = _box(tp)
    if centre is None:
        centre = 0.5 * (lo + hi)
    reach = float(np.max(np.abs(np.concatenate([lo - centre, hi - centre])))) if n else 0.0
    quantum = max(QUANTUM, 2.0 * reach / MAX_UNITS * 1.01)
    geo = geometry(tp, quantum, centre)
    # Arc samples bulge beyond the end points: the box is the drawn points'.
    if geo.points.size:
        lo, hi = geo.points.min(axis=0), geo.points.max(axis=0)
    # Stored axis by axis (3, p); the float points go once on the grid.
    q = np.empty((3, geo.points.shape[0]), dtype=np.int32)
    for s in pieces(geo.points.shape[0]):
        q[:, s] = np.rint((geo.points[s] - centre) / quantum).astype(np.int32).T
    npts = geo.npts
    del geo

    ev, pr = evaluation, profile
    names = _names(ev, ann)
    nlab = len(ev.labels) if ev is not None else len(ann.labels)
    is_feed = tp.is_feed
    spec: dict[str, Any] = {
        "label": label,
        "source": tp.source,
        "n": n,
        "centre": centre.tolist(),
        "quantum": quantum,
        "lo": (lo - centre).tolist(),
        "hi": (hi - centre).tolist(),
        "names": names,
        "npts": blobs.add(npts),
        "pts": blobs.add(q, delta=True),
    }
    del npts, q
    kind = np.full(n, _KIND_RAPID, dtype=np.int8)
    kind[is_feed] = _KIND_LINE
    kind[tp.is_arc] = _KIND_ARC
    spec["kind"] = blobs.add(kind)
    del kind
    spec["line"] = blobs.add(tp.line.astype(np.int32), delta=True)
    spec["feed"] = blobs.add(_feed_f32(is_feed, tp.feed))
    spec["length"] = blobs.add(tp.length.astype(np.float32))
    spec["mclass"] = blobs.add(np.asarray(ann.move_class, dtype=np.int8))
    spec["lclass"] = blobs.add(np.asarray(ann.length_class, dtype=np.int8))
    _speed_arrays(blobs, tp, ann, pr, spec)
    if ev is not None:
        spec["elim"] = blobs.add(_name_index(ev.element_indicator, ev.element_limit, nlab))
        spec["efeed"] = blobs.add(_feed_f32(is_feed, ev.element_feed))
    j = np.asarray(ann.junction, dtype=np.int64)
    if j.size:
        spec["junction"] = blobs.add(j.astype(np.int32), delta=True)
        spec["jclass"] = blobs.add(np.asarray(ann.junction_class, dtype=np.int8))
        jfeed = np.asarray(ann.junction_feed)
        spec["jfeed"] = blobs.add(
            piecewise(j.size, np.float32, lambda s: (jfeed[s] * PER_MIN).astype(np.float32))
        )
        spec["jname"] = blobs.add(_name_index(ann.junction_cause, ann.junction_limit, nlab))
    del j
    if pr is not None:
        _profile_arrays(blobs, tp, pr, spec)
    if tp.origin is not None:
        spec["origin"] = blobs.add(tp.origin.astype(np.int16))
        spec["origins"] = list(tp.origins)
        spec["origin_files"] = list(tp.origin_files)
    text, note = _text(program)
    if text is not None:
        raw = text.encode("utf-8")
        del text
        spec["text"] = blobs.add(np.frombuffer(raw, dtype=np.uint8))
        del raw
    spec["text_note"] = note
    spec["zones"] = [
        {
            "rank": z.rank,
            "lines": z.lines,
            "first": z.first,
            "last": z.last,
            "time_lost": z.time_lost,
            "cause": z.cause,
            "worst": round(100.0 * z.worst_reduction),
            "min_feed": z.min_feed * PER_MIN,
            "origin": z.origin,
            "point": (np.asarray(z.point, dtype=np.float64) - centre).tolist(),
            "size": z.length,
        }
        for z in ann.zones
    ]
    if diagnosis is not None:
        if gap_class is None or np.shape(gap_class) != (n,):
            raise ValueError(f"a diagnosis needs one gap class per move ({n})")
        spec["gclass"] = blobs.add(np.asarray(gap_class, dtype=np.int8))
        _diagnosis_arrays(blobs, tp, diagnosis, spec, centre)
    return spec


def _diagnosis_arrays(
    blobs: Blobs, tp: ToolPath, d: Diagnosis, spec: dict[str, Any], centre: NDArray[np.float64]
) -> None:
    """The gap per move, the gap zones and the measured feed over arc length."""
    gap = d.move_gap()
    spec["gap"] = blobs.add(gap.astype(np.float32))
    zones = []
    for k, z in enumerate(d.zones, start=1):
        a, b = (int(m) for m in tp.move_at(np.array([z.s_start, z.s_end])))
        lines = f"{z.line_start}" if z.line_start == z.line_end else f"{z.line_start}-{z.line_end}"
        mid = 0.5 * (z.s_start + z.s_end)
        k1 = tp.move_at(np.array([mid]))
        point = tp.points_along(k1, mid - tp.start_s[k1])[0]
        zones.append(
            {
                "rank": k,
                "lines": lines,
                "first": a,
                "last": b,
                "time_lost": z.time_s,
                "cause": f"{z.feature}, RMS gap {z.gap_rms:.0f} mm/min",
                "program": z.program,
                "point": (point - centre).tolist(),
                "size": z.s_end - z.s_start,
            }
        )
    spec["zones"] = zones
    measured = []
    for dd in d.data:
        if dd.case != 0:
            continue
        step = max(1, math.ceil(dd.s.size / MAX_MEASURED))
        measured.append(
            {
                "label": dd.label,
                "s": blobs.add(dd.s[::step].astype(np.float32)),
                "v": blobs.add((dd.v[::step] * PER_MIN).astype(np.float32)),
            }
        )
    spec["measured"] = measured
    if d.before.profile is None:
        # The paper's point model has no profile: the plot shows each block's own feed.
        spec["block_speed"] = blobs.add((d.before.block_speed * PER_MIN).astype(np.float32))


def page(meta: dict[str, Any], blobs: Blobs) -> bytes:
    """The whole HTML document (UTF-8)."""
    template = _read_asset("template.html")
    title = printable(meta.get("title", "ncperf"))
    title = title.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    # Pieces are put in place in one pass, so text in one cannot be taken for another's mark.
    parts = {
        "@@TITLE@@": title,
        "@@CSS@@": _read_asset("viewer.css"),
        "@@META@@": json_for_script(printable_tree(meta)),
        "@@BLOBS@@": blobs.html(),
        "@@JS@@": _read_asset("viewer.js"),
    }
    out = []
    rest = template
    while True:
        k = rest.find("@@")
        if k < 0:
            out.append(rest)
            break
        end = rest.find("@@", k + 2)
        key = rest[k : end + 2]
        if end < 0 or key not in parts:
            out.append(rest[: k + 2])
            rest = rest[k + 2 :]
            continue
        out.append(rest[:k])
        out.append(parts[key])
        rest = rest[end + 2 :]
    return "".join(out).encode("utf-8")


def _classes(labels: tuple[str, ...], colours: tuple[str, ...]) -> dict[str, list[str]]:
    return {"labels": list(labels), "colours": list(colours)}


def build(tp: ToolPath, ann: Annotations, target: Any, view: str) -> bytes:
    """The page for a display target: an :class:`~core.view.targets.HtmlTarget` (analyze,
    compare, diagnose), a :class:`~core.view.targets.ComparisonTarget`, a
    :class:`~core.diagnosis.diagnose.DiagnosisTarget` or a plain file target (the path and
    its annotations only: no speed plot, no limits, no program text)."""
    from core.view.annotations import build_annotations

    blobs = Blobs()
    panels: list[dict[str, Any]] = []
    table: list[list[str]] = []
    verdict = ""
    kind = "analyze"
    diagnosis = getattr(target, "diagnosis", None)
    items = list(getattr(target, "panels", ()) or ())
    if diagnosis is not None:
        kind = "diagnose"
        pred = diagnosis.before
        program = items[0][2] if items and len(items[0]) > 2 else None
        predicted = build_annotations(pred.evaluation, pred.profile)
        panels.append(
            panel_data(
                blobs,
                items[0][0] if items else tp.source,
                tp,
                predicted,
                evaluation=pred.evaluation,
                profile=pred.profile,
                program=program,
                diagnosis=diagnosis,
                gap_class=np.asarray(ann.move_class, dtype=np.int8),
            )
        )
        verdict = (
            f"best effect: {diagnosis.best_effect}; chosen: {' + '.join(diagnosis.chosen)}; "
            f"gap {diagnosis.gap_rms_before:.0f} -> {diagnosis.gap_rms_after:.0f} mm/min "
            "(RMS over time)"
            if diagnosis.best_effect
            else f"no effect explains the gap ({diagnosis.gap_rms_before:.0f} mm/min RMS): "
            + (diagnosis.reason or "the model already explains this trace")
        )
    elif items:
        # (label, Analysis, program) from an HtmlTarget; (label, ToolPath, Annotations)
        # from a ComparisonTarget.
        resolved = []
        for item in items:
            label, second, third = (tuple(item) + (None, None))[:3]
            if isinstance(second, ToolPath):
                resolved.append((label, second, third, None, None, None))
            else:
                an = second
                resolved.append(
                    (label, an.toolpath, an.annotations, an.evaluation, an.profile, third)
                )
        kind = "compare" if len(resolved) > 1 else "analyze"
        centre = None
        if len(resolved) > 1:
            boxes = [_box(r[1]) for r in resolved if r[1].n]
            if boxes:
                lo = np.min([b[0] for b in boxes], axis=0)
                hi = np.max([b[1] for b in boxes], axis=0)
                centre = 0.5 * (lo + hi)
        for label, rtp, rann, ev, pr, program in resolved:
            panels.append(
                panel_data(
                    blobs,
                    label,
                    rtp,
                    rann,
                    evaluation=ev,
                    profile=pr,
                    program=program,
                    centre=centre,
                )
            )
        table = [list(map(str, row)) for row in getattr(target, "table", ()) or ()]
    else:
        panels.append(panel_data(blobs, tp.source, tp, ann))
    first = panels[0]
    if kind == "compare":
        title = f"ncperf compare on {ann.machine}"
    elif kind == "diagnose":
        title = f"ncperf diagnose: {first['label']} on {ann.machine}"
    else:
        title = f"ncperf: {first['label']} on {ann.machine}"
    modes = []
    if any("sclass" in p for p in panels):
        modes.append(["speed", "predicted speed / F (where the time goes)"])
    modes.append(["junction", "reduction classes at junctions (Fig. 11)"])
    modes.append(["length", "block length against L = F t_int (Fig. 10)"])
    if kind == "diagnose":
        modes.insert(0, ["gap", "measured - predicted feed (gap)"])
    reduction = _classes(REDUCTION_LABELS, REDUCTION_COLOURS)
    if kind != "diagnose":
        reduction = _classes(ann.class_labels, ann.class_colours)
    meta = {
        "kind": kind,
        "title": title,
        "machine": ann.machine,
        "view": view,
        "modes": modes,
        "classes": {
            "speed": reduction,
            "junction": reduction,
            "length": _classes(LENGTH_LABELS, LENGTH_COLOURS),
            "gap": _classes(GAP_LABELS, GAP_COLOURS),
        },
        "rapid_colour": ann.rapid_colour,
        "panels": panels,
        "table": table,
        "verdict": verdict,
        "raw_bytes": blobs.raw_bytes,
        "default_mode": (
            "gap"
            if kind == "diagnose"
            else "junction"
            if getattr(target, "colour", "speed") == "paper"
            else modes[0][0]
        ),
    }
    return page(meta, blobs)
