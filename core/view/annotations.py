"""Colour annotations: what the A3 displays draw.

Built from an :class:`~core.engine.indicators.Evaluation`: the paper's two views
(sec. 3.3) -- blocks classed by predicted feed reduction with the
discontinuity points marked by class (Figure 11), and blocks classed by
length against L = F t_int (Figure 10) -- plus the worst zones
(:mod:`core.view.zones`), findable by program line.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from core.engine.indicators import REDUCTION_LABELS, Evaluation, reduction_class
from core.engine.profile import Profile, build_profile
from core.model.arrays import nan_to_num
from core.model.heap import release_free_heap
from core.model.pieces import piecewise
from core.model.toolpath import ToolPath
from core.view.zones import Zone, find_zones

#: Colours of the reduction classes, green (0-10 %) to red (> 90 %), as in Figure 11.
REDUCTION_COLOURS = ("#1a9850", "#91cf60", "#d9ef8b", "#fdae61", "#f46d43", "#d73027")

#: Block length against L = F t_int (Figure 10).
LENGTH_LABELS = ("shorter than L (feed capped)", "L to 2 L", "2 L and longer")
LENGTH_COLOURS = ("#d73027", "#fdae61", "#1a9850")
RAPID_COLOUR = "#9e9e9e"


@dataclass(frozen=True, eq=False)
class Annotations:
    """What a display draws.

    Attributes
    ----------
    title : str
        Program (source) name.
    machine : str
        Machine name.
    move_class : (n,) int8
        Reduction class 0..5 of each block's own predicted feed (5 is the worst); -1 for
        rapids.
    junction : (m,) int
        Junctions an indicator reported (the point is the end of move j).
    junction_class : (m,) int8
        Their reduction class.
    junction_feed : (m,) float, mm/s
        Their predicted feed.
    junction_reduction : (m,) float
        1 - predicted / programmed feed (the smaller of the two blocks' F), 0..1.
    junction_cause, junction_limit : (m,) int
        Indices into ``indicator_names`` and ``labels`` of what binds.
    length_class : (n,) int8
        0: shorter than L (the worst), 1: L..2L, 2: 2L and longer; -1 for rapids.
    zones : tuple of Zone
        The worst zones, worst first.
    indicator_names : tuple of str
        Indicators that reported something (plugins), for the legend.
    indicator_counts : tuple of int
        How many junctions or blocks each indicator holds below the programmed feed.
    labels : tuple of str
        Limit names.
    class_labels, class_colours : tuple of str
        The six reduction classes.
    length_labels, length_colours : tuple of str
        The three length classes.
    rapid_colour : str
    speed_share : (n,) float32 or None
        Mean predicted speed of each move over its programmed feed, from the feed profile
        (length / predicted time / F, 0..1): where the time goes. NaN for rapids; None when
        no profile was given (a diagnosis colours by its gap instead).
    speed_class : (n,) int8 or None
        Reduction class 0..5 of ``1 - speed_share`` (the classes of ``move_class``); -1 for
        rapids. The displays colour by it by default.
    """

    title: str
    machine: str
    move_class: NDArray[np.int8]
    junction: NDArray[np.int64]
    junction_class: NDArray[np.int8]
    junction_feed: NDArray[np.float64]
    junction_reduction: NDArray[np.float64]
    junction_cause: NDArray[np.integer]
    junction_limit: NDArray[np.integer]
    length_class: NDArray[np.int8]
    zones: tuple[Zone, ...]
    indicator_names: tuple[str, ...]
    indicator_counts: tuple[int, ...]
    labels: tuple[str, ...]
    class_labels: tuple[str, ...] = REDUCTION_LABELS
    class_colours: tuple[str, ...] = REDUCTION_COLOURS
    length_labels: tuple[str, ...] = LENGTH_LABELS
    length_colours: tuple[str, ...] = LENGTH_COLOURS
    rapid_colour: str = RAPID_COLOUR
    speed_share: NDArray[np.float32] | None = None
    speed_class: NDArray[np.int8] | None = None


def check_drawable(tp: ToolPath) -> None:
    """Raise ValueError, naming the move and its line, if an end point of ``tp`` is not
    finite (the readers' range checks keep this from happening; a path built in code can
    still hold one, and no display can place it)."""
    if np.isfinite(tp.start).all() and np.isfinite(tp.end).all():
        return  # (over all the numbers at once: 1M moves, 3 ms, not 40 row by row)
    bad = ~(np.isfinite(tp.start).all(axis=1) & np.isfinite(tp.end).all(axis=1))
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(
            f"{tp.source}:{tp.line[i]}: move {i} has a non-finite end point; it cannot be drawn"
        )


def length_class(ev: Evaluation) -> NDArray[np.int8]:
    """(n,) Figure-10 class of each block: 0 below L, 1 from L to 2 L, 2 above; -1 rapids."""
    tp = ev.toolpath
    edges = np.array([1.0, 2.0])

    def cls(b: slice) -> NDArray[np.int8]:
        ratio = tp.length[b] / ev.min_length[b]
        c = np.searchsorted(edges, nan_to_num(ratio, nan=np.inf), side="right")
        return np.where(tp.is_feed[b], c.astype(np.int8), -1).astype(np.int8)

    return piecewise(tp.n, np.int8, cls)  # (in pieces: no (n,) temporaries)


def speed_share(
    profile: Profile, k: NDArray[np.int64] | slice = slice(None)
) -> NDArray[np.float64]:
    """Mean predicted speed of moves ``k`` (all by default) over their programmed feed
    (length / time / F); NaN for rapids. A move the profile runs at F has share 1."""
    tp = profile.toolpath

    def f(m: NDArray[np.int64] | slice) -> NDArray[np.float64]:
        with np.errstate(invalid="ignore", divide="ignore"):
            share = tp.length[m] / (profile.time[m] * tp.feed[m])
        return np.where(tp.is_feed[m], np.minimum(share, 1.0), np.nan)

    if isinstance(k, slice) and k == slice(None):  # all moves: in pieces, no temporaries
        return piecewise(tp.n, np.float64, f)
    return f(k)


def speed_class(share: NDArray[np.floating], is_feed: NDArray[np.bool_]) -> NDArray[np.int8]:
    """Reduction class 0..5 of ``1 - share`` (a :func:`speed_share`), -1 for rapids."""

    def f(b: slice) -> NDArray[np.int8]:
        cls = reduction_class(1.0 - nan_to_num(share[b], nan=1.0))
        return np.where(is_feed[b], cls, -1).astype(np.int8)

    return piecewise(share.shape[0], np.int8, f)  # (in pieces: no (n,) temporaries)


def build_annotations(
    ev: Evaluation, profile: Profile | None = None, *, zones: int = 10
) -> Annotations:
    """Classes, markers and zones of an evaluation (its profile is built if not given)."""
    tp = ev.toolpath
    if profile is None:
        profile = build_profile(ev)
    worst = find_zones(ev, profile, zones)  # first: its peak is the stage's (1M moves)
    release_free_heap()  # its holes (5M arcs: 100 MB; see core.model.heap)
    er, feed = ev.element_reduction, tp.is_feed
    mc = piecewise(  # (in pieces: no (n,) temporaries)
        tp.n,
        np.int8,
        lambda b: np.where(feed[b], reduction_class(nan_to_num(er[b])), -1),
    )
    share = speed_share(profile)
    counts = []
    for k in range(len(ev.indicator_names)):
        nj = int(np.count_nonzero((ev.junction_indicator == k) & (ev.junction_limit != 0)))
        ne = int(np.count_nonzero(ev.element_indicator == k))
        counts.append(nj + ne)
    return Annotations(
        title=tp.source,
        machine=ev.machine.name,
        move_class=mc,
        junction=ev.junction,
        junction_class=reduction_class(ev.junction_reduction),
        junction_feed=ev.junction_feed,
        junction_reduction=ev.junction_reduction,
        junction_cause=ev.junction_indicator,
        junction_limit=ev.junction_limit,
        length_class=length_class(ev),
        zones=worst,
        indicator_names=ev.indicator_names,
        indicator_counts=tuple(counts),
        labels=ev.labels,
        speed_share=share.astype(np.float32),
        speed_class=speed_class(share, tp.is_feed),
    )
