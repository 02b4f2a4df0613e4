"""A1: the tool paths of an ESPRIT document's operations as one ToolPath (:mod:`core.model`).

The paper's extractor (Tapie et al., sec. 3.1) "explores the tool path object selected in the
workspace of ESPRIT" and reads its segments, arcs and feeds. Here every ``PartOperation``
read becomes one operation of the tool path; each ``ToolPath.ItemCopy(i)`` is one move (points
mark the path's ends and make none). ESPRIT has no program lines: ``ToolPath.line`` holds the
1-based item index inside the operation, which is what error messages and zones name.

The object model is per item by nature, so reading costs a few calls per item; the numbers
land in flat lists and all geometry (arc end points, planes, sweeps) is computed with numpy.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from adapters.esprit_com import object_model as om
from adapters.esprit_com.object_model import ComObject
from core.model import geometry as g
from core.model.errors import InputError, Notice
from core.model.tolerances import TOL
from core.model.toolpath import (
    POINTS_DROPPED,
    MoveKind,
    ToolPath,
    drop_zero_length,
    empty_columns,
)

SCOPES = ("auto", "selected", "all")
PER_MIN = 60.0


@dataclass(frozen=True, eq=False)
class EspritSource:
    """An ESPRIT document and which of its operations to read.

    Attributes
    ----------
    host : ComObject
        ESPRIT ``Application`` or ``Document`` (COM through pythonnet, the .NET emulation or
        the Python twin).
    scope : {"auto", "selected", "all"}
        "selected": the operations in ``Document.Group``; "all": every operation that is not
        suppressed; "auto": the selected ones if any operation is selected, else all.
    """

    host: ComObject
    scope: str = "auto"

    def __post_init__(self) -> None:
        if self.scope not in SCOPES:
            raise ValueError(f"scope must be one of {SCOPES}, got {self.scope!r}")


def optional(obj: ComObject, name: str, default: object = None) -> ComObject:
    """``obj.name``, or ``default`` where the object model has no such member."""
    try:
        return getattr(obj, name)
    except AttributeError:
        return default


def document_of(source: object) -> ComObject | None:
    """The ESPRIT ``Document`` behind ``source``, or None if it is not an ESPRIT object.

    Paths are refused before any attribute is touched, so a file never wakes pythonnet.
    """
    if source is None or isinstance(source, str | bytes | os.PathLike):
        return None
    if isinstance(source, EspritSource):
        return document_of(source.host)
    if optional(source, "PartOperations") is not None:
        return source
    doc = optional(source, "Document")
    if doc is not None and optional(doc, "PartOperations") is not None:
        return doc
    return None


def document_label(doc: ComObject) -> str:
    """``ESPRIT document NAME``: the ``source`` of the tool path and of its errors."""
    return f"ESPRIT document {optional(doc, 'Name') or 'untitled'}"


def _collection(coll: ComObject) -> Iterator[ComObject]:
    """Items 1..Count of an ESPRIT collection."""
    for i in range(1, int(coll.Count) + 1):
        yield coll[i]


def operations(doc: ComObject, scope: str, notes: list[Notice], label: str) -> list[ComObject]:
    """The ``PartOperation`` objects ``scope`` asks for, in document (or selection) order."""
    selected = []
    group = optional(doc, "Group")
    if scope != "all" and group is not None:
        for obj in _collection(group):
            if int(optional(obj, "GraphicObjectType", -1)) == om.GRAPHIC_OPERATION:
                selected.append(obj)
    if scope == "selected" or (scope == "auto" and selected):
        if not selected:
            raise InputError(
                "no operation is selected (select one, or read them all)", source=label
            )
        return selected
    ops = []
    for obj in _collection(doc.PartOperations):
        if optional(obj, "Suppress", False):
            notes.append(Notice(label, None, f"suppressed operation '{obj.Name}' left out"))
            continue
        ops.append(obj)
    if not ops:
        raise InputError("the document has no operation to read", source=label)
    return ops


def _units(doc: ComObject, notes: list[Notice], label: str) -> tuple[str, float]:
    code = optional(doc, om.SYSTEM_UNIT)
    if code is not None and int(code) in om.UNITS:
        return om.UNITS[int(code)]
    what = "no SystemUnit" if code is None else f"SystemUnit {int(code)}, not in the table"
    notes.append(Notice(label, None, f"document has {what}: mm assumed"))
    return "mm", 1.0


class _Operation:
    """The raw numbers of one operation's motion items, in document units."""

    def __init__(self, op: ComObject, label: str) -> None:
        self.name = str(optional(op, "Name") or "unnamed")
        self.label = label
        self.op = op
        self.tech = optional(op, "Technology")
        self.feeds: dict[int, float | None] = {}
        # Per motion item: its 1-based index, its class (1 segment, 2 arc), its feed
        # (per minute, document units; NaN for rapids) and 12 numbers: x0 y0 z0 x1 y1 z1
        # for segments, cx cy cz r ux uy uz vx vy vz a0 a1 for arcs.
        self.index: list[int] = []
        self.shape: list[int] = []
        self.feed: list[float] = []
        self.rows: list[tuple[float, ...]] = []

    def error(self, message: str, item: int | None = None) -> InputError:
        return InputError(f"operation '{self.name}': {message}", source=self.label, line=item)

    def feed_of(self, aux: int, item: int) -> float:
        """Feed per minute (document units) of an item with ``aux``; NaN for rapids."""
        if aux in self.feeds:
            f = self.feeds[aux]
            return np.nan if f is None else f
        if aux not in om.AUX_CODES:
            known = ", ".join(str(k) for k in om.AUX_CODES)
            raise self.error(
                f"item {item} has AuxCode {aux}, none of the codes ncperf knows ({known}; "
                "adapters/esprit_com/object_model.py AUX_CODES)",
                item,
            )
        attrs = om.AUX_CODES[aux]
        if attrs is None:
            self.feeds[aux] = None
            return np.nan
        for name in attrs:
            value = optional(self.tech, name) if self.tech is not None else None
            if value is not None and float(value) > 0:
                self.feeds[aux] = float(value)
                return float(value)
        raise self.error(
            f"item {item} (AuxCode {aux}) is a feed move, but the operation's technology has "
            f"no positive {' or '.join(attrs)}",
            item,
        )

    def read(self) -> int:
        """Read every item; returns the item count."""
        path = optional(self.op, "ToolPath")
        count = int(path.Count) if path is not None else 0
        if count == 0:
            raise self.error("has no tool path (compute it in ESPRIT, or leave it out)")
        for i in range(1, count + 1):
            item = path.ItemCopy(i)
            kind = int(item.Type)
            if kind in om.POINT_ITEMS:
                continue
            if kind not in om.SEGMENT_ITEMS and kind not in om.ARC_ITEMS:
                known = ", ".join(f"{n} = {v}" for n, v in om.ITEM_TYPES.items())
                raise self.error(
                    f"item {i} has type {kind}, none of the espToolPathItemType values ncperf "
                    f"knows ({known}; adapters/esprit_com/object_model.py ITEM_TYPES)",
                    i,
                )
            feed = self.feed_of(int(item.AuxCode), i)
            data = item.data
            row: tuple[float, ...]
            if kind in om.SEGMENT_ITEMS:
                s, e = data.StartPoint, data.EndPoint
                row = (s.X, s.Y, s.Z, e.X, e.Y, e.Z) + (0.0,) * 6
                shape = 1
            else:
                if np.isnan(feed):
                    raise self.error(
                        f"item {i} is an arc marked rapid (AuxCode {om.AUX_RAPID}); ncperf "
                        "models rapids as straight moves",
                        i,
                    )
                c, u, v = data.CenterPoint, data.U, data.V
                row = (c.X, c.Y, c.Z, data.Radius, u.X, u.Y, u.Z, v.X, v.Y, v.Z)
                row += (data.StartAngle, data.EndAngle)
                shape = 2
            self.index.append(i)
            self.shape.append(shape)
            self.feed.append(feed)
            self.rows.append(row)
        return count


def _arcs(raw: NDArray[np.float64], items: NDArray[np.int64], op: _Operation) -> dict[str, NDArray]:
    """Start, end, centre, canonical normal, sweep and kind of (k,) IComArc rows (k, 12).

    The point at angle a is centre + r (cos a U + sin a V); the arc turns from StartAngle to
    EndAngle counter-clockwise about U x V. ncperf's tool paths keep the plane's normal
    pointing along the positive axis it is closest to (G17 +Z, G18 +Y, G19 +X) and say
    clockwise instead, so an arc written from G-code comes back exactly as it was read.
    """
    centre, radius = raw[:, 0:3], raw[:, 3]
    bad = np.flatnonzero(~(radius > TOL.min_arc_radius))
    if bad.size:
        k = bad[0]
        raise op.error(f"item {items[k]} is an arc with zero radius ({radius[k]:g})", items[k])
    u_len = g.norm(raw[:, 4:7])
    u = raw[:, 4:7] / np.where(u_len > 0, u_len, 1.0)[:, None]
    # Gram-Schmidt: V is taken in the plane of U and V, perpendicular to U.
    v = raw[:, 7:10] - np.einsum("ij,ij->i", raw[:, 7:10], u)[:, None] * u
    v_len = g.norm(v)
    bad = np.flatnonzero(~((u_len > 0.5) & (v_len > 0.5)))
    if bad.size:
        k = bad[0]
        raise op.error(
            f"item {items[k]} is an arc whose U and V do not span a plane "
            f"(U {raw[k, 4:7].tolist()}, V {raw[k, 7:10].tolist()})",
            items[k],
        )
    v /= v_len[:, None]
    a0 = raw[:, 10] * om.ANGLE_TO_RAD
    a1 = raw[:, 11] * om.ANGLE_TO_RAD
    sweep = a1 - a0
    sweep = np.where(sweep <= 0.0, sweep + om.FULL_TURN, sweep)
    r = radius[:, None]
    start = centre + r * (np.cos(a0)[:, None] * u + np.sin(a0)[:, None] * v)
    end = centre + r * (np.cos(a1)[:, None] * u + np.sin(a1)[:, None] * v)
    normal = np.cross(u, v)
    dominant = np.abs(normal).argmax(axis=1)
    flip = normal[np.arange(normal.shape[0]), dominant] < 0.0
    normal[flip] *= -1.0
    kind = np.where(flip, MoveKind.ARC_CW, MoveKind.ARC_CCW).astype(np.int8)
    return {
        "start": start,
        "end": end,
        "center": centre,
        "normal": normal,
        "sweep": sweep,
        "kind": kind,
        "length": radius * sweep,
    }


def _operation_columns(
    op: _Operation, scale: float, units: str, notes: list[Notice]
) -> dict[str, NDArray]:
    """Columns (mm, mm/s) of one operation's moves."""
    n = len(op.rows)
    cols = empty_columns(n)
    items = np.asarray(op.index, dtype=np.int64)
    shape = np.asarray(op.shape, dtype=np.int8)
    feed = np.asarray(op.feed, dtype=np.float64)
    raw = np.asarray(op.rows, dtype=np.float64).reshape(n, 12)
    bad = np.flatnonzero(~np.isfinite(raw).all(axis=1))
    if bad.size:
        k = bad[0]
        raise op.error(f"item {items[k]} has a coordinate that is not a number", items[k])
    seg = shape == 1
    arc = ~seg
    length = np.zeros(n)
    cols["start"][seg] = raw[seg, 0:3]
    cols["end"][seg] = raw[seg, 3:6]
    length[seg] = g.norm(raw[seg, 3:6] - raw[seg, 0:3])
    cols["kind"][seg] = np.where(np.isnan(feed[seg]), MoveKind.RAPID, MoveKind.LINE)
    if arc.any():
        a = _arcs(raw[arc], items[arc], op)
        for key in ("start", "end", "center", "normal", "sweep", "kind"):
            cols[key][arc] = a[key]
        length[arc] = a["length"]
    _cross_check(op, length, np.isnan(feed), units, notes)
    gap = g.norm(cols["start"][1:] - cols["end"][:-1])
    far = np.flatnonzero(gap > TOL.arc_end_abs)
    if far.size:
        k = far[0]
        notes.append(
            Notice(
                op.label,
                int(items[k + 1]),
                f"operation '{op.name}': item {items[k + 1]} starts {gap[k] * scale:.3f} mm "
                f"from where item {items[k]} ended; the gap is not a move",
                count=int(far.size),
            )
        )
    for key in ("start", "end", "center"):
        cols[key] *= scale
    cols["feed"] = feed * scale / PER_MIN
    cols["line"] = items
    return cols


def _cross_check(
    op: _Operation, length: NDArray, rapid: NDArray, units: str, notes: list[Notice]
) -> None:
    """Warn when the feed/rapid split of the items disagrees with ESPRIT's own lengths."""
    want_feed = optional(op.op, om.LENGTH_OF_FEED)
    want_rapid = optional(op.op, om.LENGTH_OF_RAPID)
    if want_feed is None or want_rapid is None:
        return
    got_feed, got_rapid = float(length[~rapid].sum()), float(length[rapid].sum())
    want_feed, want_rapid = float(want_feed), float(want_rapid)
    # Item coordinates are ESPRIT's own doubles: beyond rounding, a difference means some
    # items were classed wrongly; LinuxCNC's end-point tolerance is a generous "rounding".
    slack = TOL.arc_end_abs + TOL.rel_equal * (got_feed + got_rapid)
    if abs(got_feed - want_feed) > slack or abs(got_rapid - want_rapid) > slack:
        notes.append(
            Notice(
                op.label,
                None,
                f"operation '{op.name}': the items give {got_feed:.3f} {units} of feed and "
                f"{got_rapid:.3f} of rapid moves, ESPRIT reports LengthOfFeed {want_feed:.3f} "
                f"and LengthOfRapid {want_rapid:.3f}: the AuxCode table "
                "(adapters/esprit_com/object_model.py) may not hold for this ESPRIT",
            )
        )


def read_esprit(source: object) -> ToolPath:
    """Read the operations of an ESPRIT document.

    Parameters
    ----------
    source : EspritSource, or an ESPRIT Application or Document (scope "auto")

    Returns
    -------
    ToolPath
        One operation per ``PartOperation``; positions mm, feeds mm/s; ``line`` is the
        1-based item index in the operation's tool path.

    Raises
    ------
    InputError
        Naming the document, operation and item: an operation without a tool path, an item
        type or AuxCode not in :mod:`~adapters.esprit_com.object_model`, a zero-radius or
        degenerate arc, a rapid arc, non-numeric coordinates; or nothing to read.
    """
    scope = source.scope if isinstance(source, EspritSource) else "auto"
    doc = document_of(source)
    if doc is None:
        raise TypeError(f"{type(source).__name__} is not an ESPRIT Application or Document")
    label = document_label(doc)
    notes: list[Notice] = []
    units, scale = _units(doc, notes, label)
    parts, names = [], []
    for obj in operations(doc, scope, notes, label):
        op = _Operation(obj, label)
        count = op.read()
        if not op.rows:
            notes.append(Notice(label, None, f"operation '{op.name}': {count} items, no move"))
            continue
        parts.append(_operation_columns(op, scale, units, notes))
        names.append(op.name)
    if not parts:
        raise InputError("the operations read hold no move", source=label)
    cols: dict[str, Any] = {
        key: np.concatenate([p[key] for p in parts]) for key in parts[0] if key != "op_offsets"
    }
    sizes = [p["kind"].shape[0] for p in parts]
    cols["op_offsets"] = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    tp = ToolPath(**cols, op_names=tuple(names), source=label, units=units)
    tp, removed = drop_zero_length(tp)
    if removed.size:
        k = int(removed[0])
        notes.append(Notice(label, int(cols["line"][k]), POINTS_DROPPED, count=int(removed.size)))
    return replace(tp, notices=tuple(notes))
