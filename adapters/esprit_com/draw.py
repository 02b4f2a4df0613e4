"""A3: the colour annotations drawn into an ESPRIT document (Tapie et al., sec. 3.3, Fig. 11).

One layer, :data:`~adapters.esprit_com.object_model.LAYER_NAME`, one colour per predicted
feed-reduction class (``Annotations.class_colours`` as COLORREF):

* the feed moves, coloured by the class of their own predicted feed. ESPRIT draws segments
  and arcs, not polylines, so an *element* is the longest run of consecutive moves of one
  class that one segment or one arc reproduces exactly: collinear lines, or arcs on one
  circle turning the same way (at most a full turn) -- a CAM post splitting arcs at
  quadrants, or a straight pass written as many blocks, gives one element. Helices, which
  ESPRIT's planar arcs cannot hold, are drawn as chords. Rapids are not annotated and not
  drawn (ESPRIT shows the tool path itself);
* one point at each discontinuity of class 1 or worse (at least 10 % below F), in its class.

Everything is computed with numpy first (:func:`plan_drawing`); only then is ESPRIT touched,
inside one undo transaction that is kept as one undo step, or cancelled on any error so that
nothing is left half-drawn.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from adapters.esprit_com import object_model as om
from adapters.esprit_com.clr_host import exception_text
from adapters.esprit_com.extract import document_label
from adapters.esprit_com.object_model import ComObject
from core.model import geometry as g
from core.model.errors import NcperfError
from core.model.tolerances import TOL
from core.model.toolpath import MoveKind, ToolPath
from core.view.annotations import Annotations

#: Chords per radian for helices: pi/8 keeps the chord within 2 % of the radius of the helix.
HELIX_CHORDS_PER_RAD = 8.0 / np.pi


class EspritError(NcperfError):
    """ESPRIT refused something the adapter asked it to do; the drawing was cancelled."""


def colorref(colour: str) -> int:
    """``#rrggbb`` as an ESPRIT colour: COLORREF 0x00BBGGRR (object_model.COLOUR_ALPHA on top).

    >>> hex(colorref("#d73027"))
    '0x2730d7'
    """
    text = colour.lstrip("#")
    if len(text) != 6:
        raise ValueError(f"colour must be #rrggbb, got {colour!r}")
    r, gr, b = (int(text[k : k + 2], 16) for k in (0, 2, 4))
    return (om.COLOUR_ALPHA << 24) | (b << 16) | (gr << 8) | r


@dataclass(frozen=True, eq=False)
class DrawPlan:
    """What to draw, computed before ESPRIT is touched; positions in mm.

    Attributes
    ----------
    seg_class : (s,) int8
    seg_start, seg_end : (s, 3) float, mm
    seg_moves : (s, 2) int
        First and last move each segment stands for.
    arc_class : (a,) int8
    arc_center : (a, 3) float, mm
    arc_radius : (a,) float, mm
    arc_u, arc_v : (a, 3) float
        Unit vectors of the arc's plane: it starts at centre + radius U (angle 0) and turns
        towards V.
    arc_sweep : (a,) float, rad
        End angle (the start angle is 0).
    arc_moves : (a, 2) int
    point_class : (p,) int8
    point_xyz : (p, 3) float, mm
    point_moves : (p,) int
        The junction: the point is the end of this move.
    colours : tuple of int
        COLORREF of each reduction class.
    """

    seg_class: NDArray[np.int8]
    seg_start: NDArray[np.float64]
    seg_end: NDArray[np.float64]
    seg_moves: NDArray[np.int64]
    arc_class: NDArray[np.int8]
    arc_center: NDArray[np.float64]
    arc_radius: NDArray[np.float64]
    arc_u: NDArray[np.float64]
    arc_v: NDArray[np.float64]
    arc_sweep: NDArray[np.float64]
    arc_moves: NDArray[np.int64]
    point_class: NDArray[np.int8]
    point_xyz: NDArray[np.float64]
    point_moves: NDArray[np.int64]
    colours: tuple[int, ...]


def _joins(tp: ToolPath, cls: NDArray[np.int64], helix: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """(n - 1,) whether move i + 1 continues the element of move i exactly."""
    same = (cls[1:] >= 0) & (cls[:-1] >= 0) & (cls[1:] == cls[:-1])
    same &= tp.op_index[1:] == tp.op_index[:-1]
    same &= g.norm(tp.start[1:] - tp.end[:-1]) <= TOL.zero_length
    line = tp.kind == MoveKind.LINE
    lines = line[1:] & line[:-1] & (tp.turn_angle <= TOL.collinear_angle)
    arc = tp.is_arc & ~helix
    with np.errstate(invalid="ignore"):
        arcs = (
            arc[1:]
            & arc[:-1]
            & (tp.kind[1:] == tp.kind[:-1])
            & (g.norm(tp.center[1:] - tp.center[:-1]) <= TOL.zero_length)
            & (np.abs(tp.radius[1:] - tp.radius[:-1]) <= TOL.zero_length)
            & (g.angle_between(tp.normal[1:], tp.normal[:-1]) <= TOL.collinear_angle)
        )
    return same & (lines | arcs)


def _split_turns(first: list[int], last: list[int], sweep: NDArray) -> tuple[list, list]:
    """Cut arc runs so that none turns more than a full circle (ESPRIT arcs cannot)."""
    out_first, out_last = [], []
    for a, b in zip(first, last, strict=True):
        start, total = a, 0.0
        for m in range(a, b + 1):
            if total + sweep[m] > om.FULL_TURN * (1.0 + TOL.float_slack) and m > start:
                out_first.append(start)
                out_last.append(m - 1)
                start, total = m, 0.0
            total += sweep[m]
        out_first.append(start)
        out_last.append(b)
    return out_first, out_last


def plan_drawing(tp: ToolPath, ann: Annotations) -> DrawPlan:
    """The segments, arcs and points that show ``ann`` on ``tp`` (see the module docstring).

    Parameters
    ----------
    tp : ToolPath
        The evaluated tool path (n moves).
    ann : Annotations
        Its annotations; ``move_class`` (n,) and the junctions are read.
    """
    n = tp.n
    cls = np.asarray(ann.move_class, dtype=np.int64)
    if cls.shape != (n,):
        raise ValueError(f"annotations.move_class must have shape ({n},), got {cls.shape}")
    cls = np.where(tp.is_feed, cls, -1)
    helix = tp.is_arc & (
        np.abs(np.nan_to_num(tp.pitch) * np.nan_to_num(tp.sweep)) > TOL.zero_length
    )
    drawn = cls >= 0
    join = _joins(tp, cls, helix) if n > 1 else np.zeros(0, dtype=bool)
    first = np.flatnonzero(drawn & ~np.concatenate([[False], join]))
    last = np.flatnonzero(drawn & ~np.concatenate([join, [False]]))
    is_helix = helix[first]
    is_arc = tp.is_arc[first] & ~is_helix
    sweep = np.nan_to_num(tp.sweep)

    # Straight runs.
    sl = ~tp.is_arc[first]
    seg_first, seg_last = first[sl], last[sl]
    # Helices: chords, each its own element.
    hm = first[is_helix]
    chords = np.maximum(2, np.ceil(sweep[hm] * HELIX_CHORDS_PER_RAD)).astype(np.int64)
    owner = np.repeat(hm, chords)
    k = np.concatenate([np.arange(c) for c in chords]) if hm.size else np.zeros(0, np.int64)
    per = np.repeat(chords, chords)

    def on_helix(frac: NDArray) -> NDArray:
        return g.arc_points(
            tp.start[owner],
            tp.center[owner],
            tp.normal[owner],
            tp.kind[owner] == MoveKind.ARC_CCW,
            sweep[owner],
            np.nan_to_num(tp.pitch[owner]),
            frac,
        )

    seg_start = np.concatenate([tp.start[seg_first], on_helix(k / per)])
    seg_end = np.concatenate([tp.end[seg_last], on_helix((k + 1) / per)])
    seg_moves = np.concatenate(
        [np.stack([seg_first, seg_last], axis=1), np.stack([owner, owner], axis=1)]
    ).astype(np.int64)
    seg_class = cls[seg_moves[:, 0]].astype(np.int8)

    # Arc runs, at most a full turn each.
    cum = np.cumsum(sweep)
    af, al = first[is_arc], last[is_arc]
    if np.any(cum[al] - cum[af] + sweep[af] > om.FULL_TURN * (1.0 + TOL.float_slack)):
        a_first, a_last = _split_turns(af.tolist(), al.tolist(), sweep)
        af = np.asarray(a_first, dtype=np.int64)
        al = np.asarray(a_last, dtype=np.int64)
    arc_sweep = cum[al] - cum[af] + sweep[af]
    centre = tp.center[af]
    turn = np.where(tp.kind[af] == MoveKind.ARC_CCW, 1.0, -1.0)[:, None] * tp.normal[af]
    u = g.unit(tp.start[af] - centre)
    v = np.cross(turn, u)

    sel = np.asarray(ann.junction_class) >= 1
    j = np.asarray(ann.junction, dtype=np.int64)[sel]
    return DrawPlan(
        seg_class=seg_class,
        seg_start=seg_start,
        seg_end=seg_end,
        seg_moves=seg_moves,
        arc_class=cls[af].astype(np.int8),
        arc_center=centre,
        arc_radius=tp.radius[af],
        arc_u=u,
        arc_v=v,
        arc_sweep=arc_sweep,
        arc_moves=np.stack([af, al], axis=1),
        point_class=np.asarray(ann.junction_class)[sel].astype(np.int8),
        point_xyz=tp.end[j],
        point_moves=j,
        colours=tuple(colorref(c) for c in ann.class_colours),
    )


@dataclass(frozen=True)
class Drawing:
    """What the ESPRIT display drew (the A3 hook's result)."""

    document: str
    layer: str
    segments: int
    arcs: int
    points: int

    def __str__(self) -> str:
        return (
            f"layer '{self.layer}' of {self.document}: {self.segments:,} segments, "
            f"{self.arcs:,} arcs, {self.points:,} points"
        )


def _find_layer(doc: ComObject, name: str) -> ComObject | None:
    layers = doc.Layers
    for i in range(1, int(layers.Count) + 1):
        layer = layers[i]
        if str(layer.Name) == name:
            return layer
    return None


def _other_layer(doc: ComObject) -> ComObject:
    layers = doc.Layers
    for i in range(1, int(layers.Count) + 1):
        layer = layers[i]
        if str(layer.Name) != om.LAYER_NAME:
            return layer
    raise EspritError(f"the document has no layer but '{om.LAYER_NAME}'")


def _describe(tp: ToolPath, what: str, moves: NDArray) -> str:
    a, b = int(moves[0]), int(moves[-1])
    op = tp.op_names[int(tp.op_index[a])]
    items = tp.describe_lines(a, b)
    return f"the {what} of operation '{op}', item{'s' if a != b else ''} {items}"


def draw_annotations(doc: ComObject, tp: ToolPath, ann: Annotations) -> Drawing:
    """Draw ``ann`` into ESPRIT document ``doc`` as one undoable step.

    Raises
    ------
    EspritError
        ESPRIT refused an element (naming it by operation and item); everything drawn so far
        is cancelled with ``CloseUndoTransaction(False)``.
    """
    plan = plan_drawing(tp, ann)
    label = document_label(doc)
    step = "the layer"
    doc.OpenUndoTransaction()
    try:
        old_colour = doc.ActiveColor
        old_layer = doc.ActiveLayer
        restore_layer = old_layer is not None and str(old_layer.Name) != om.LAYER_NAME
        stale = _find_layer(doc, om.LAYER_NAME)
        if stale is not None:
            if not restore_layer:
                # The layer to replace is the active one, which cannot be removed.
                doc.ActiveLayer = _other_layer(doc)
            doc.Layers.Remove(om.LAYER_NAME)
        layer = doc.Layers.Add(om.LAYER_NAME)
        doc.ActiveLayer = layer
        for c, colour in enumerate(plan.colours):
            doc.ActiveColor = colour
            for k in np.flatnonzero(plan.seg_class == c).tolist():
                step = _describe(tp, "segment", plan.seg_moves[k])
                p0, p1 = plan.seg_start[k].tolist(), plan.seg_end[k].tolist()
                obj = doc.Segments.Add(doc.GetPoint(*p0), doc.GetPoint(*p1))
                _style(obj, colour, layer)
            for k in np.flatnonzero(plan.arc_class == c).tolist():
                step = _describe(tp, "arc", plan.arc_moves[k])
                centre = doc.GetPoint(*plan.arc_center[k].tolist())
                sweep = float(plan.arc_sweep[k]) / om.ANGLE_TO_RAD
                obj = doc.Arcs.Add(centre, float(plan.arc_radius[k]), 0.0, sweep)
                obj.Ux, obj.Uy, obj.Uz = plan.arc_u[k].tolist()
                obj.Vx, obj.Vy, obj.Vz = plan.arc_v[k].tolist()
                _style(obj, colour, layer)
            for k in np.flatnonzero(plan.point_class == c).tolist():
                step = _describe(tp, "discontinuity point", plan.point_moves[k : k + 1])
                obj = doc.Points.Add(*plan.point_xyz[k].tolist())
                _style(obj, colour, layer)
        step = "restoring the active colour and layer"
        doc.ActiveColor = old_colour
        if restore_layer:
            doc.ActiveLayer = old_layer
        doc.Refresh()
    except BaseException as exc:
        _cancel(doc, exc)
        if isinstance(exc, Exception) and not isinstance(exc, NcperfError):
            raise EspritError(
                f"ESPRIT refused {step}: {exception_text(exc)}; the drawing was cancelled",
                source=label,
            ) from exc
        raise
    doc.CloseUndoTransaction(om.UNDO_KEEP)
    return Drawing(
        document=label,
        layer=om.LAYER_NAME,
        segments=int(plan.seg_class.size),
        arcs=int(plan.arc_class.size),
        points=int(plan.point_class.size),
    )


def _style(obj: ComObject, colour: int, layer: ComObject) -> None:
    if not om.USE_ACTIVE_STYLE:
        obj.Color = colour
        obj.Layer = layer


def _cancel(doc: ComObject, exc: BaseException) -> None:
    """Cancel the open undo transaction; a failure to do so is noted on ``exc``."""
    try:
        doc.CloseUndoTransaction(om.UNDO_CANCEL)
        doc.Refresh()
    except Exception as again:
        exc.add_note(f"cancelling the ESPRIT undo transaction failed too: {exception_text(again)}")
