"""Indicator results (what A2 plugins return) and their combination.

A plugin returns :class:`Indicator` objects: columnar records at junctions
(the point between feed moves ``j`` and ``j + 1``) or on elements (move ``i``
itself), each with the feed the indicator allows there and the limit that
binds. :func:`combine` keeps, per junction and per element, the lowest feed
over all plugins, capped by the programmed feed.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from core.model.machine import Machine
from core.model.toolpath import ToolPath

#: Limit label when no indicator is below the programmed feed.
PROGRAMMED = "programmed feed"

#: Upper edges of the feed-reduction classes (paper, Figure 11: green 0-10 %
#: ... red above 90 %).
REDUCTION_EDGES = (0.10, 0.30, 0.50, 0.70, 0.90)
REDUCTION_LABELS = ("0-10 %", "10-30 %", "30-50 %", "50-70 %", "70-90 %", "> 90 %")


def reduction_class(reduction: ArrayLike) -> NDArray[np.int8]:
    """Class 0..5 of reductions in [0, 1] (0: 0-10 %, 5: above 90 %)."""
    r = np.asarray(reduction, dtype=np.float64)
    return np.searchsorted(np.asarray(REDUCTION_EDGES), r, side="right").astype(np.int8)


def min_block_length(feed: ArrayLike, interpolation_time: float) -> NDArray[np.float64]:
    """Eq. (16): L = Vp * t_int, the shortest block the controller runs at feed Vp (mm)."""
    return np.asarray(feed, dtype=np.float64) * interpolation_time


@dataclass(frozen=True, eq=False)
class Indicator:
    """One indicator's results, as columns over its records.

    Attributes
    ----------
    name : str
        Indicator name ("tangential", "curvature", "ncu_capacity", ...).
    at : {"junction", "element"}
        Junction ``j`` is the point between moves ``j`` and ``j + 1``;
        element ``i`` is move ``i``.
    index : (m,) int
        Junction or element indices, each at most once.
    feed : (m,) float, mm/s
        Feed the indicator allows there (may exceed the programmed feed).
    limit : (m,) int
        Index into ``labels`` of the limit that binds.
    labels : tuple of str
        Limit names, e.g. ("jerk X", "acceleration Y", "block time").
    values : mapping of str to (m,) arrays
        Extra columns for reports (e.g. the inserted radius, mm). One the core reads:
        ``hold_mm``, the distance on each side of a junction over which the speed stays at
        the indicator's feed (model 1: the inserted arc's tangent length; model 2: the
        distance run during the transition time), and optionally ``travel_mm``, the length
        the tool actually runs over each side of it (model 1: half the inserted arc,
        R beta / 2, shorter than the programmed R tan(beta / 2); default ``hold_mm``);
        and optionally :data:`BLEND_SPEED` at junctions the planner runs as an overlap (NaN
        elsewhere).
    """

    name: str
    at: Literal["junction", "element"]
    index: NDArray[np.int64]
    feed: NDArray[np.float64]
    limit: NDArray[np.int64]
    labels: tuple[str, ...]
    values: Mapping[str, NDArray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.at not in ("junction", "element"):
            raise ValueError(f"at must be 'junction' or 'element', got {self.at!r}")
        idx = np.ascontiguousarray(self.index, dtype=np.int64)
        if idx.ndim != 1:
            raise ValueError(f"index must have shape (m,), got {idx.shape}")
        m = idx.shape[0]
        feed = np.ascontiguousarray(self.feed, dtype=np.float64)
        limit = np.ascontiguousarray(self.limit, dtype=np.int64)
        for name, a in (("feed", feed), ("limit", limit)):
            if a.shape != (m,):
                raise ValueError(f"{name} must have shape ({m},), got {a.shape}")
        if m and (limit.min() < 0 or limit.max() >= len(self.labels)):
            raise ValueError(f"limit codes must index labels (0..{len(self.labels) - 1})")
        if m > 1:
            d = np.diff(idx)
            if (d <= 0).any() and (np.diff(np.sort(idx)) == 0).any():
                raise ValueError(f"indicator {self.name!r} has repeated {self.at} indices")
        for k, v in self.values.items():
            if np.shape(v) != (m,):
                raise ValueError(f"values[{k!r}] must have shape ({m},), got {np.shape(v)}")
        object.__setattr__(self, "index", idx)
        object.__setattr__(self, "feed", feed)
        object.__setattr__(self, "limit", limit)
        object.__setattr__(self, "labels", tuple(self.labels))


#: Junction value (mm/s) where the planner overlaps the two segments (LinuxCNC's parabolic
#: blend, tp.c ``tpDoParabolicBlending``): the segment before brakes to rest at the
#: junction, and once it is down to this speed the segment after starts from rest, the two
#: motions added. Where the indicator that gives it binds, the evaluation keeps it
#: (:attr:`Evaluation.junction_blend`); the feed profile is unchanged (its junction speed
#: is the one that costs the overlap's time), the speed a trace shows there is not
#: (:func:`core.engine.predict.overlap_column`).
BLEND_SPEED = "blend_speed_mm_s"

#: What produces the A2 results of a tool path on a machine: every registered plugin's
#: indicators (:meth:`core.facade.Ncperf.indicators`). The engine takes it as an argument
#: rather than the facade, so that it does not depend on the plugin manager.
IndicatorSource = Callable[[ToolPath, Machine], list[Indicator]]

#: Dtype of the indicator and limit codes of an evaluation: indices into its short tables of
#: names and labels (two bytes a move, not eight: a million moves, 24 MB).
CODE = np.int16


@dataclass(frozen=True, eq=False)
class Evaluation:
    """The combined prediction of all indicators on one tool path.

    Junction arrays have one row per junction that some indicator reported;
    element arrays have one row per move (NaN / -1 for rapids).

    Attributes
    ----------
    junction : (m,) int
        Junction indices j (between moves j and j + 1), ascending.
    junction_programmed : (m,) float, mm/s
        The smaller of the two blocks' programmed feeds.
    junction_feed : (m,) float, mm/s
        Predicted feed: the lowest indicator feed, at most the programmed one.
    junction_indicator, junction_limit : (m,) int
        Indices into ``indicator_names`` and ``labels`` of what binds.
    junction_hold : (m,) float, mm
        The binding indicator's ``hold_mm`` (0 where it gives none, or where the programmed
        feed binds).
    junction_travel : (m,) float, mm
        Its ``travel_mm`` (the length run over each side of the hold).
    element_feed : (n,) float, mm/s
        Predicted feed on each block (programmed unless an element indicator caps it).
    element_indicator, element_limit : (n,) int
        What caps each block; -1 where nothing does.
    min_length : (n,) float, mm
        Eq. (16) L = F t_int for feed moves, NaN for rapids.
    blend_rest : (n,) float, mm, or None
        What is left of each move that the planner runs as part of the arc at its end
        (LinuxCNC merges a short rest into the next blend arc); None: nothing is.
    acceleration_share : (n,) float, or None
        The share of its tangential acceleration each move keeps, from the junctions at its
        two ends (``acceleration_share`` of a junction indicator; LinuxCNC halves both
        segments' acceleration at a parabolic blend and takes the kink ratio off at a
        tangent kink), times an element indicator's ``acceleration_share`` (LinuxCNC's share
        on each arc); None: every move keeps all of it.
    junction_arc_feed : (m,) float, mm/s, or None
        ``corner_blending = "linuxcnc"``: the lowest indicator feed at each junction before
        the programmed feeds cap it -- the limit of the arc LinuxCNC inserts there, which it
        runs up to whatever the feeds on either side (the arc's requested speed is the
        higher of the two: blendmath.c ``blendParamKinematics``); None elsewhere.
    junction_blend : (m,) float, mm/s, or None
        The binding indicator's :data:`BLEND_SPEED` at junctions the planner runs as an
        overlap of the two segments, NaN at the others; None where none is.
    """

    toolpath: ToolPath
    machine: Machine
    indicator_names: tuple[str, ...]
    labels: tuple[str, ...]
    junction: NDArray[np.int64]
    junction_programmed: NDArray[np.float64]
    junction_feed: NDArray[np.float64]
    junction_indicator: NDArray[np.int16]
    junction_limit: NDArray[np.int16]
    element_feed: NDArray[np.float64]
    element_indicator: NDArray[np.int16]
    element_limit: NDArray[np.int16]
    min_length: NDArray[np.float64]
    junction_hold: NDArray[np.float64]
    junction_travel: NDArray[np.float64]
    blend_rest: NDArray[np.float64] | None = None
    acceleration_share: NDArray[np.float64] | None = None
    junction_arc_feed: NDArray[np.float64] | None = None
    junction_blend: NDArray[np.float64] | None = None

    @cached_property
    def junction_reduction(self) -> NDArray[np.float64]:
        """(m,) 1 - predicted / programmed at each reported junction."""
        return np.clip(1.0 - self.junction_feed / self.junction_programmed, 0.0, 1.0)

    @property
    def element_reduction(self) -> NDArray[np.float64]:
        """(n,) 1 - predicted / programmed on each block (NaN for rapids). (Made when asked
        for, not kept: read twice, by the zones and the classes; 5M moves, 40 MB.)"""
        return np.clip(1.0 - self.element_feed / self.toolpath.feed, 0.0, 1.0)

    @cached_property
    def move_feed(self) -> NDArray[np.float64]:
        """(n,) lowest predicted feed on a move or at its two ends (mm/s, NaN for rapids)."""
        f = self.element_feed.copy()
        jf = self.junction_feed
        np.fmin.at(f, self.junction, jf)
        np.fmin.at(f, self.junction + 1, jf)
        return f

    @cached_property
    def paper_time(self) -> float:
        """Feed-move time of the paper's point model, s.

        Each block runs at its own predicted feed (model 3 caps short blocks);
        discontinuities are points and cost no time, since the paper predicts
        the feed there but not the braking towards it (the profile adds that).
        """
        tp = self.toolpath
        f = tp.is_feed
        return float(np.sum(tp.length[f] / self.element_feed[f]))


#: The indicator name and limit labels of the block time on the segments a planner makes at
#: corners: the arcs it inserts, and (LinuxCNC) what is left of the blocks between them.
BLEND_INDICATOR = "ncu_capacity"
BLEND_LABEL = "block time (blend arc)"
REST_LABEL = "block time (rest between blend arcs)"
#: LinuxCNC 2.9's planner (``corner_blending = "linuxcnc"``; tp_types.h, blendmath.h and the
#: ini defaults), in one place for the plugins and the profile: a segment lasts at least
#: TP_MIN_SEGMENT_CYCLES servo periods (a servo period is the block time over it); a line
#: whose rest between arcs would last under ARC_BLEND_GAP_CYCLES servo periods (at the next
#: arc's speed) is run as part of that arc (blendmath.c blendCheckConsume); the
#: tangent-kink threshold ARC_BLEND_KINK_RATIO; the share of the plane's acceleration along
#: a blend arc, BLEND_ACC_RATIO_TANGENTIAL.
LCNC_MIN_SEGMENT_CYCLES = 1.02
LCNC_GAP_CYCLES = 4
LCNC_KINK_RATIO = 0.1
LCNC_TANGENTIAL_RATIO = 0.5
LCNC_GAP_BLOCKS = LCNC_GAP_CYCLES / LCNC_MIN_SEGMENT_CYCLES


def _blend_block_time(
    tp: ToolPath, machine: Machine, indicators: Sequence[Indicator]
) -> list[Indicator]:
    """Model 3 on the segments a planner executes when it inserts arcs at corners (LinuxCNC;
    the paper's model 3 caps programmed blocks only):

    - an inserted arc of length 2 travel (the junction's ``travel_mm`` on each side) lasts at
      least the block time: the corner speed is at most 2 travel / t_int;
    - with ``corner_blending = "linuxcnc"``, a block trimmed by the arcs at its ends (their
      ``hold_mm``, the tangent lengths) keeps a rest r = length - the holds, a segment of its
      own: its speed is at most r / t_int; but a line whose rest would last under
      LCNC_GAP_BLOCKS block times at the following arc's speed is run as part of that arc,
      whose length is then 2 travel + r.
    """
    out = []
    t_int = machine.interpolation_time
    rests = machine.corner_blending == "linuxcnc"
    for ind in indicators:
        if ind.at != "junction" or "travel_mm" not in ind.values or ind.name == BLEND_INDICATOR:
            continue
        travel = np.asarray(ind.values["travel_mm"], dtype=np.float64)
        hold = np.asarray(ind.values.get("hold_mm", travel), dtype=np.float64)
        ok = travel > 0
        if not ok.any():
            continue
        if ok.all():  # every corner has an arc: share the arrays, no copies
            index = ind.index
        else:
            index, hold, travel = ind.index[ok], hold[ok], travel[ok]
        arc = 2.0 * travel
        if rests:
            corner = np.asarray(ind.feed, dtype=np.float64)[ok]
            trimmed = np.zeros(tp.n)
            np.add.at(trimmed, index, hold)
            np.add.at(trimmed, index + 1, hold)
            rest = np.maximum(tp.length - trimmed, 0.0)
            v_arc = np.fmin(corner, np.fmax(tp.feed[index], tp.feed[index + 1]))
            merged = (
                tp.is_feed[index]
                & ~tp.is_arc[index]
                & (rest[index] < LCNC_GAP_BLOCKS * t_int * v_arc)
            )
            merged_mm = np.where(merged, rest[index], 0.0)
            arc = arc + merged_mm
            own = trimmed > 0
            own[index[merged]] = False
            # (a programmed arc is never run as part of a blend; only lines keep rests here)
            own &= tp.is_feed & ~tp.is_arc & (rest < tp.feed * t_int)
            i = np.flatnonzero(own)
            if i.size:
                out.append(
                    Indicator(
                        name=BLEND_INDICATOR,
                        at="element",
                        index=i,
                        feed=rest[i] / t_int,
                        limit=np.zeros(i.size, dtype=np.int64),
                        labels=(REST_LABEL,),
                        values={"rest_mm": rest[i]},
                    )
                )
        out.append(
            Indicator(
                name=BLEND_INDICATOR,
                at="junction",
                index=index,
                feed=arc / t_int,
                limit=np.zeros(index.size, dtype=np.int64),
                labels=(BLEND_LABEL,),
                values={"hold_mm": hold, "travel_mm": travel}
                | ({"merged_mm": merged_mm} if rests else {}),
            )
        )
    return out


def _zeros(values: NDArray) -> bool:
    """Whether ``values`` is one +0.0 broadcast over its places (a column with no value)."""
    return values.strides == (0,) and bool(values.size) and values.flat[0].tobytes() == _ZERO


_ZERO = np.float64(0.0).tobytes()


def junction_shares(out: NDArray, index: NDArray, share: NDArray) -> NDArray:
    """The share of its acceleration each move keeps from the junctions ``index`` at its two
    ends (``share`` each): the least, written into ``out`` (n,); returned."""
    np.minimum.at(out, index, share)
    np.minimum.at(out, index + 1, share)
    return out


def combine(toolpath: ToolPath, machine: Machine, indicators: Sequence[Indicator]) -> Evaluation:
    """Keep, per junction and per element, the lowest feed any indicator allows."""
    tp = toolpath
    names: list[str] = []
    label_id: dict[str, int] = {PROGRAMMED: 0}
    parts: dict[str, list[tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray]]] = {
        "junction": [],
        "element": [],
    }
    if machine.block_time_on_blends:
        indicators = [*indicators, *_blend_block_time(tp, machine, indicators)]
    for ind in indicators:
        if ind.at == "element" and "acceleration_share" in ind.values:
            continue  # a share of the moves' acceleration, not a limit (below)
        if ind.name not in names:
            names.append(ind.name)
        nid = names.index(ind.name)
        codes = np.array(
            [label_id.setdefault(lab, len(label_id)) for lab in ind.labels], dtype=CODE
        )
        limit = codes[ind.limit] if ind.index.size else np.zeros(0, dtype=CODE)
        bound = tp.n - 1 if ind.at == "junction" else tp.n
        if ind.index.size and (ind.index.min() < 0 or ind.index.max() >= bound):
            raise ValueError(f"indicator {ind.name!r}: {ind.at} index out of range 0..{bound - 1}")
        # Columns of one value are broadcasts (no memory per record): 1M junctions, 24 MB
        # less per indicator.
        none = np.broadcast_to(0.0, ind.index.shape)
        hold = np.asarray(ind.values.get("hold_mm", none), dtype=np.float64)
        travel = np.asarray(ind.values.get("travel_mm", hold), dtype=np.float64)
        nids = np.broadcast_to(CODE(nid), ind.index.shape)
        parts[ind.at].append((ind.index, ind.feed, nids, limit, hold, travel))

    def lowest(kind: str) -> tuple[NDArray, NDArray, NDArray, NDArray, tuple[NDArray, ...]]:
        # Dense passes over the junctions (or elements), no sort: the first indicator to
        # report a place claims it (so a record with no limit, feed inf, still names its
        # indicator), then any lower feed takes it over; ties keep the earlier indicator.
        # The holds only at junctions (the elements' are not used). A record that claims
        # all its places writes its columns as they are (no gathered copies), and a column
        # of zeros (no hold) goes where the holds are zero still.
        junction = kind == "junction"
        size = max(tp.n - 1, 0) if junction else tp.n
        feed = np.full(size, np.inf)
        ind = np.full(size, -1, dtype=CODE)
        lim = np.zeros(size, dtype=CODE)
        hold: tuple[NDArray, ...] = (np.zeros(size), np.zeros(size)) if junction else ()
        for idx, f, i, lab, h, t in parts[kind]:
            new = ind[idx] < 0
            if new.all():
                sel = idx
                feed[sel], ind[sel], lim[sel] = f, i, lab
                cols = (h, t) if junction else ()
            else:
                sel = idx[new]
                feed[sel], ind[sel], lim[sel] = f[new], i[new], lab[new]
                cols = (h[new], t[new]) if junction else ()
            for col, values in zip(hold, cols, strict=True):
                if not _zeros(values):
                    col[sel] = values
        for idx, f, i, lab, h, t in parts[kind]:
            better = f < feed[idx]
            sel = idx[better]
            feed[sel], ind[sel], lim[sel] = f[better], i[better], lab[better]
            if junction:
                hold[0][sel], hold[1][sel] = h[better], t[better]
        where = np.flatnonzero(ind >= 0)
        return where, feed[where], ind[where], lim[where], tuple(col[where] for col in hold)

    j, jfeed, jind, jlim, jhold = lowest("junction")
    jprog = np.fmin(tp.feed[j], tp.feed[j + 1])
    not_below = ~(jfeed < jprog)
    jlim = np.where(not_below, 0, jlim)
    keep_all = machine.corner_blending == "linuxcnc"
    arc_feed = jfeed.copy() if keep_all else None
    jfeed = np.fmin(jfeed, jprog)

    blend_rest = None
    for ind in indicators:
        if ind.name == BLEND_INDICATOR and "merged_mm" in ind.values:
            blend_rest = np.zeros(tp.n) if blend_rest is None else blend_rest
            blend_rest[ind.index] = np.maximum(blend_rest[ind.index], ind.values["merged_mm"])
    acc_share = None
    for ind in indicators:
        if ind.at == "junction" and "acceleration_share" in ind.values:
            share = np.asarray(ind.values["acceleration_share"], dtype=np.float64)
            lower = share < 1.0
            if lower.any():
                acc_share = np.ones(tp.n) if acc_share is None else acc_share
                junction_shares(acc_share, ind.index[lower], share[lower])
    for ind in indicators:
        # a planner's own share of a move's tangential acceleration (LinuxCNC's on its arcs),
        # on top of what its junctions take
        if ind.at == "element" and "acceleration_share" in ind.values:
            acc_share = np.ones(tp.n) if acc_share is None else acc_share
            acc_share[ind.index] *= np.asarray(ind.values["acceleration_share"], dtype=np.float64)
    junction_blend = None
    for ind in indicators:
        if ind.at == "junction" and BLEND_SPEED in ind.values:
            v_b = np.asarray(ind.values[BLEND_SPEED], dtype=np.float64)
            have = np.flatnonzero(np.isfinite(v_b))
            if have.size == 0:
                continue
            # where this indicator binds (names the junction, below the programmed feeds)
            at = np.searchsorted(j, ind.index[have])
            binds = (jind[at] == names.index(ind.name)) & (jlim[at] != 0)
            if binds.any():
                if junction_blend is None:
                    junction_blend = np.full(j.size, np.nan)
                junction_blend[at[binds]] = v_b[have[binds]]
    efeed = tp.feed.copy()
    eind = np.full(tp.n, -1, dtype=CODE)
    elim = np.full(tp.n, -1, dtype=CODE)
    e, ef, ei, el, _ = lowest("element")
    below = ef < efeed[e]
    efeed[e[below]] = ef[below]
    eind[e[below]] = ei[below]
    elim[e[below]] = el[below]
    return Evaluation(
        toolpath=tp,
        machine=machine,
        indicator_names=tuple(names),
        labels=tuple(label_id),
        junction=j,
        junction_programmed=jprog,
        junction_feed=jfeed,
        junction_indicator=jind,
        junction_limit=jlim,
        element_feed=efeed,
        element_indicator=eind,
        element_limit=elim,
        min_length=np.where(
            tp.is_feed, min_block_length(tp.feed, machine.interpolation_time), np.nan
        ),
        # A corner that does not bind is crossed at the programmed feed: nothing held there;
        # but LinuxCNC's arcs change the acceleration along them wherever they are inserted.
        junction_hold=jhold[0] if keep_all else np.where(not_below, 0.0, jhold[0]),
        junction_travel=jhold[1] if keep_all else np.where(not_below, 0.0, jhold[1]),
        blend_rest=blend_rest,
        acceleration_share=acc_share,
        junction_arc_feed=arc_feed,
        junction_blend=junction_blend,
    )
