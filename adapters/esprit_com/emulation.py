"""The headless ESPRIT: fill an emulated document from any ToolPath, read back what was drawn.

Two implementations of one object model: the .NET assembly built from
``csharp/EspritEmulation.cs`` (loaded through pythonnet, so the adapter's calls cross into .NET
for real) and its Python twin (:mod:`~adapters.esprit_com.twin`). A :class:`Backend` hides the
only differences: how arrays cross into .NET, and whether the adapter sees the objects
directly or through COM-style late binding (:class:`~adapters.esprit_com.clr_host.LateBound`,
which is how a live ESPRIT is reached).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from adapters.esprit_com import object_model as om
from adapters.esprit_com.clr_host import LateBound, load_emulation
from adapters.esprit_com.object_model import ComObject
from core.cli.output import atomic_writer
from core.model import geometry as g
from core.model.errors import InputError
from core.model.tolerances import TOL
from core.model.toolpath import MoveKind, ToolPath

#: Backend names: the Python twin, the .NET emulation as pythonnet shows it, and the .NET
#: emulation reached by name through reflection (the code path of a live ESPRIT over COM).
BACKENDS = ("python-twin", "dotnet", "dotnet-latebound")
PER_MIN = 60.0
IT = om.ITEM_TYPES


@dataclass(frozen=True)
class Backend:
    """One implementation of the emulated object model.

    Attributes
    ----------
    name : str
        One of :data:`BACKENDS`.
    ns : module
        Provides ``Application`` and ``Emulation`` (the twin module or the .NET namespace).
    """

    name: str
    ns: ModuleType

    @property
    def dotnet(self) -> bool:
        return self.name != "python-twin"

    def host(self, app: ComObject) -> ComObject:
        """The Application as the adapter sees it."""
        return LateBound(app) if self.name == "dotnet-latebound" else app

    def ints(self, a: NDArray) -> object:
        a = np.ascontiguousarray(a, dtype=np.int32)
        if not self.dotnet:
            return a
        import System
        from System.Runtime.InteropServices import Marshal

        out = System.Array[System.Int32](a.size)
        if a.size:
            Marshal.Copy(System.IntPtr(a.ctypes.data), out, 0, a.size)
        return out

    def doubles(self, a: NDArray) -> object:
        a = np.ascontiguousarray(a, dtype=np.float64).reshape(-1)
        if not self.dotnet:
            return a
        import System
        from System.Runtime.InteropServices import Marshal

        out = System.Array[System.Double](a.size)
        if a.size:
            Marshal.Copy(System.IntPtr(a.ctypes.data), out, 0, a.size)
        return out

    def to_numpy(self, values: ComObject, width: int) -> NDArray[np.float64]:
        if not self.dotnet:
            return np.asarray(values, dtype=np.float64).reshape(-1, width)
        from System import IntPtr
        from System.Runtime.InteropServices import Marshal

        out = np.empty(len(values), dtype=np.float64)
        if out.size:
            Marshal.Copy(values, 0, IntPtr(out.ctypes.data), out.size)
        return out.reshape(-1, width)


def backend(name: str) -> Backend:
    """The backend called ``name``; the .NET ones raise
    :class:`~adapters.esprit_com.clr_host.DotnetUnavailable` saying what is missing."""
    if name == "python-twin":
        from adapters.esprit_com import twin

        return Backend(name, twin)
    if name in ("dotnet", "dotnet-latebound"):
        return Backend(name, load_emulation())
    raise ValueError(f"backend must be one of {BACKENDS}, got {name!r}")


# ----------------------------------------------------------------------------- filling
def _chunks(feed: NDArray[np.float64], rapid: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """Split moves into runs using at most two distinct feeds (ESPRIT's technology holds an
    XY and a Z feed; the items only say which of the two applies)."""
    out: list[tuple[int, int]] = []
    start = 0
    seen: set[float] = set()
    for i, (f, r) in enumerate(zip(feed.tolist(), rapid.tolist(), strict=True)):
        if r or f in seen:
            continue
        if len(seen) == 2:
            out.append((start, i))
            start, seen = i, set()
        seen.add(f)
    out.append((start, feed.size))
    return out


def _arc_frames(tp: ToolPath, idx: NDArray[np.int64]) -> NDArray[np.float64]:
    """(k, 12) IComArc numbers of arcs ``idx``: centre, radius, U, V, start and end angle.

    U is the coordinate axis least aligned with the plane's normal, projected into the plane,
    so angles do not all start at 0 and both angle conventions get exercised.
    """
    ccw = tp.kind[idx] == MoveKind.ARC_CCW
    n = tp.normal[idx] * np.where(ccw, 1.0, -1.0)[:, None]
    axis = np.eye(3)[np.abs(n).argmin(axis=1)]
    u = g.unit(axis - g.dot(axis, n)[:, None] * n)
    v = np.cross(n, u)
    r0 = tp.start[idx] - tp.center[idx]
    a0 = np.mod(np.arctan2(g.dot(r0, v), g.dot(r0, u)), om.FULL_TURN)
    a1 = a0 + tp.sweep[idx]
    return np.column_stack(
        [tp.center[idx], tp.radius[idx], u, v, a0 / om.ANGLE_TO_RAD, a1 / om.ANGLE_TO_RAD]
    )


def fill_document(tp: ToolPath, be: Backend, name: str | None = None) -> ComObject:
    """An emulated ESPRIT Application whose document holds ``tp`` as operations.

    One PartOperation per operation of ``tp`` -- split where it uses more than two feeds --
    whose technology has the most used feed as ``XYFeedratePM`` and the other as
    ``ZFeedratePM`` (mm/min); each move is one item: rapids and lines ``tpiSEG2`` (constant Z)
    or ``tpiSEG3``, arcs ``tpiARC2`` (in an XY plane) or ``tpiARC3``; ``tpiSTART_POINT`` and
    ``tpiEND_POINT`` items around them; AuxCodes as :data:`~.object_model.AUX_CODES`.

    Raises
    ------
    InputError
        For a helical arc (ESPRIT's tool path arcs are planar), naming its line.
    """
    helix = tp.is_arc & (
        np.abs(np.nan_to_num(tp.pitch) * np.nan_to_num(tp.sweep)) > TOL.zero_length
    )
    if helix.any():
        i = int(np.flatnonzero(helix)[0])
        raise InputError(
            "helical arc: ESPRIT tool path arcs are planar, the emulation cannot hold it",
            source=tp.source,
            line=int(tp.line[i]),
        )
    app = be.ns.Application(name or os.path.basename(tp.source))
    doc = app.Document
    emu = be.ns.Emulation
    rapid = ~tp.is_feed
    for k, op_name in enumerate(tp.op_names):
        lo, hi = int(tp.op_offsets[k]), int(tp.op_offsets[k + 1])
        parts = _chunks(tp.feed[lo:hi], rapid[lo:hi])
        for p, (a, b) in enumerate(parts):
            idx = np.arange(lo + a, lo + b)
            feed_moves = idx[tp.is_feed[idx]]
            feeds, inverse = np.unique(tp.feed[feed_moves], return_inverse=True)
            used = np.bincount(inverse, weights=tp.length[feed_moves], minlength=feeds.size)
            order = np.argsort(-used, kind="stable")
            xy = feeds[order[0]] if feeds.size else 0.0
            z = feeds[order[1]] if feeds.size > 1 else 0.0
            label = op_name if len(parts) == 1 else f"{op_name} ({p + 1}/{len(parts)})"
            op = emu.AddOperation(doc, label, xy * PER_MIN, z * PER_MIN, True)
            m = idx.size
            types = np.empty(m + 2, dtype=np.int32)
            aux = np.full(m + 2, om.AUX_CUT, dtype=np.int32)
            data = np.zeros((m + 2, 12))
            types[0], types[-1] = IT["tpiSTART_POINT"], IT["tpiEND_POINT"]
            data[0, :3], data[-1, :3] = tp.start[idx[0]], tp.end[idx[-1]]
            body = slice(1, m + 1)
            arc = tp.is_arc[idx]
            flat = tp.start[idx, 2] == tp.end[idx, 2]
            planar = np.abs(np.nan_to_num(tp.normal[idx, 2])) == 1.0
            types[body] = np.where(
                arc,
                np.where(planar, IT["tpiARC2"], IT["tpiARC3"]),
                np.where(flat, IT["tpiSEG2"], IT["tpiSEG3"]),
            )
            aux[body] = np.where(
                rapid[idx], om.AUX_RAPID, np.where(tp.feed[idx] == xy, om.AUX_CUT, om.AUX_PLUNGE)
            )
            rows = data[body]
            rows[~arc, 0:3] = tp.start[idx[~arc]]
            rows[~arc, 3:6] = tp.end[idx[~arc]]
            if arc.any():
                rows[arc] = _arc_frames(tp, idx[arc])
            data[body] = rows
            emu.AddItems(op, be.ints(types), be.ints(aux), be.doubles(data), om.AUX_RAPID)
    return app


def raw_document(app: ComObject) -> ComObject:
    """The emulated Document behind an Application, unwrapped from late binding."""
    return app.Document if not isinstance(app, LateBound) else app._target.Document


# ----------------------------------------------------------------------------- reading back
@dataclass(frozen=True, eq=False)
class Recording:
    """What an emulated document holds after drawing.

    Attributes
    ----------
    layers : tuple of str
        Layer names, in document order.
    segments : (s, 8) float
        x0 y0 z0 x1 y1 z1 (mm), COLORREF colour, layer index.
    arcs : (a, 14) float
        centre (mm), radius (mm), U, V, start and end angle, colour, layer index.
    points : (p, 5) float
        x y z (mm), colour, layer index.
    undo_steps, cancelled, refreshes : int
        Undo transactions kept and cancelled; calls of ``Refresh()``.
    transaction_open : bool
    """

    layers: tuple[str, ...]
    segments: NDArray[np.float64]
    arcs: NDArray[np.float64]
    points: NDArray[np.float64]
    undo_steps: int
    cancelled: int
    refreshes: int
    transaction_open: bool

    def on_layer(self, name: str) -> Recording:
        """Only what is drawn on layer ``name``."""
        k = self.layers.index(name) if name in self.layers else -1
        return Recording(
            self.layers,
            self.segments[self.segments[:, 7] == k],
            self.arcs[self.arcs[:, 13] == k],
            self.points[self.points[:, 4] == k],
            self.undo_steps,
            self.cancelled,
            self.refreshes,
            self.transaction_open,
        )


def recording(app: ComObject, be: Backend) -> Recording:
    """Read back what is drawn in the emulated document of ``app``."""
    doc = raw_document(app)
    emu = be.ns.Emulation
    return Recording(
        layers=tuple(str(x) for x in emu.LayerNames(doc)),
        segments=be.to_numpy(emu.SegmentRecords(doc), 8),
        arcs=be.to_numpy(emu.ArcRecords(doc), 14),
        points=be.to_numpy(emu.PointRecords(doc), 5),
        undo_steps=int(emu.UndoSteps(doc)),
        cancelled=int(emu.Cancelled(doc)),
        refreshes=int(emu.Refreshes(doc)),
        transaction_open=bool(emu.TransactionOpen(doc)),
    )


# ----------------------------------------------------------------------------- SVG
#: Chords per full turn when an arc is drawn; 64 keeps the sagitta under 0.12 % of the radius.
SVG_ARC_CHORDS = 64
SVG_WIDTH = 900.0
SVG_PAD = 20.0


def hex_colour(colorref: float) -> str:
    """``#rrggbb`` of a COLORREF (0x00BBGGRR)."""
    c = int(colorref)
    return f"#{c & 0xFF:02x}{(c >> 8) & 0xFF:02x}{(c >> 16) & 0xFF:02x}"


def write_recording_svg(rec: Recording, path: str, *, title: str = "") -> str:
    """Draw a recording as ESPRIT's top view (XY) would show it: what is drawn, as drawn.

    Segments and arcs (sampled with :data:`SVG_ARC_CHORDS` chords a turn) become one path per
    colour, points small discs; nothing is re-derived from the tool path.

    Returns the path written.
    """
    seg = rec.segments
    arcs = rec.arcs
    m = np.maximum(
        2,
        np.ceil(
            np.abs(arcs[:, 11] - arcs[:, 10]) * om.ANGLE_TO_RAD / om.FULL_TURN * SVG_ARC_CHORDS
        ),
    ).astype(np.int64)
    frac = (
        np.concatenate([np.linspace(0.0, 1.0, int(k) + 1) for k in m]) if arcs.size else np.zeros(0)
    )
    offs = np.concatenate([[0], np.cumsum(m + 1)])
    owner = np.repeat(np.arange(arcs.shape[0]), m + 1)
    ang = (arcs[owner, 10] + frac * (arcs[owner, 11] - arcs[owner, 10])) * om.ANGLE_TO_RAD
    pts = arcs[owner, 0:3] + arcs[owner, 3:4] * (
        np.cos(ang)[:, None] * arcs[owner, 4:7] + np.sin(ang)[:, None] * arcs[owner, 7:10]
    )
    allxy = np.concatenate([seg[:, 0:2], seg[:, 3:5], pts[:, 0:2], rec.points[:, 0:2]])
    if allxy.size == 0:
        allxy = np.zeros((1, 2))
    lo, hi = allxy.min(axis=0), allxy.max(axis=0)
    ext = float(max(hi[0] - lo[0], hi[1] - lo[1], TOL.zero_length))
    scale = (SVG_WIDTH - 2 * SVG_PAD) / ext
    height = (hi[1] - lo[1]) * scale + 2 * SVG_PAD

    def px(xy: NDArray) -> NDArray:
        return np.column_stack(
            [SVG_PAD + (xy[:, 0] - lo[0]) * scale, height - SVG_PAD - (xy[:, 1] - lo[1]) * scale]
        )

    colours = sorted(
        set(seg[:, 6].tolist()) | set(arcs[:, 12].tolist()) | set(rec.points[:, 3].tolist())
    )
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{SVG_WIDTH:.0f}" height="{height:.0f}" '
        f'viewBox="0 0 {SVG_WIDTH:.0f} {height:.0f}">',
        f"<title>{_escape(title)}</title>",
        '<rect width="100%" height="100%" fill="#202020"/>',
    ]
    for c in colours:
        d: list[str] = []
        s = seg[seg[:, 6] == c]
        a0, a1 = px(s[:, 0:2]), px(s[:, 3:5])
        d.extend(
            f"M{x0:.2f} {y0:.2f}L{x1:.2f} {y1:.2f}"
            for (x0, y0), (x1, y1) in zip(a0.tolist(), a1.tolist(), strict=True)
        )
        for k in np.flatnonzero(arcs[:, 12] == c).tolist():
            p = px(pts[offs[k] : offs[k + 1], 0:2]).tolist()
            d.append("M" + "L".join(f"{x:.2f} {y:.2f}" for x, y in p))
        if d:
            out.append(
                f'<path fill="none" stroke="{hex_colour(c)}" stroke-width="1.5" d="{"".join(d)}"/>'
            )
        q = px(rec.points[rec.points[:, 3] == c][:, 0:2]).tolist()
        out.extend(
            f'<circle cx="{x:.2f}" cy="{y:.2f}" r="2.5" fill="{hex_colour(c)}"/>' for x, y in q
        )
    out.append("</svg>\n")
    with atomic_writer(path) as fh:
        fh.write("\n".join(out))
    return path


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
