"""Colour annotations (what A3 displays draw) and critical zones.

Built from an :class:`~core.indicators.Evaluation`: the paper's two views
(sec. 3.3) -- blocks classed by predicted feed reduction with the
discontinuity points marked by class (Figure 11), and blocks classed by
length against L = F t_int (Figure 10) -- plus the worst zones, findable by
program line.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from core.indicators import REDUCTION_LABELS, Evaluation, reduction_class

#: Colours of the reduction classes, green (0-10 %) to red (> 90 %), as in Figure 11.
REDUCTION_COLOURS = ("#1a9850", "#91cf60", "#d9ef8b", "#fdae61", "#f46d43", "#d73027")

#: Block length against L = F t_int (Figure 10).
LENGTH_LABELS = ("shorter than L (feed capped)", "L to 2 L", "2 L and longer")
LENGTH_COLOURS = ("#d73027", "#fdae61", "#1a9850")
RAPID_COLOUR = "#9e9e9e"

#: A move belongs to a critical zone when its feed, or the feed at one of its
#: ends, is predicted at least this much below the programmed feed.
ZONE_THRESHOLD = 0.10


VIEWS = ("xy", "xz", "yz", "iso")


@dataclass(frozen=True)
class FileTarget:
    """A file to draw into, with the projection to use.

    Attributes
    ----------
    path : str
        Output file; its extension picks the display (``.svg`` ...).
    view : {"xy", "xz", "yz", "iso"}
        Top view (xy, default), front (xz), side (yz) or isometric.
    """

    path: str
    view: str = "xy"

    def __post_init__(self) -> None:
        if self.view not in VIEWS:
            raise ValueError(f"view must be one of {VIEWS}, got {self.view!r}")


@dataclass(frozen=True)
class Zone:
    """A run of consecutive feed moves predicted to slow down.

    Attributes
    ----------
    rank : int
        1 = worst.
    first, last : int
        Move indices (inclusive).
    line_first, line_last : int
        Lowest and highest source line in the run.
    length : float, mm
    discontinuities : int
        Junctions inside or at the ends of the run that an indicator reported.
    worst_reduction : float
        Largest reduction in the run (0..1).
    min_feed : float, mm/s
        Lowest predicted feed in the run.
    programmed_feed : float, mm/s
        Programmed feed where the minimum is.
    cause : str
        Indicator and limit of the minimum, e.g. "tangential: jerk X".
    score : float, mm
        Sum of length x reduction over the run's moves: path "lost" to slow-down.
    point : (3,) float, mm
        Where the minimum is (for labels).
    """

    rank: int
    first: int
    last: int
    line_first: int
    line_last: int
    length: float
    discontinuities: int
    worst_reduction: float
    min_feed: float
    programmed_feed: float
    cause: str
    score: float
    point: tuple[float, float, float]

    @property
    def lines(self) -> str:
        a, b = self.line_first, self.line_last
        return f"{a}" if a == b else f"{a}-{b}"


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
        Reduction class 0..5 of each block's own predicted feed; -1 for rapids.
    junction : (m,) int
        Junctions an indicator reported (the point is the end of move j).
    junction_class : (m,) int8
        Their reduction class.
    junction_feed : (m,) float, mm/s
        Their predicted feed.
    junction_cause, junction_limit : (m,) int
        Indices into ``indicator_names`` and ``labels`` of what binds.
    length_class : (n,) int8
        0: shorter than L, 1: L..2L, 2: 2L and longer; -1 for rapids.
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
    """

    title: str
    machine: str
    move_class: NDArray[np.int8]
    junction: NDArray[np.int64]
    junction_class: NDArray[np.int8]
    junction_feed: NDArray[np.float64]
    junction_cause: NDArray[np.int64]
    junction_limit: NDArray[np.int64]
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


def move_reduction(ev: Evaluation) -> NDArray[np.float64]:
    """(n,) reduction of the lowest predicted feed on each move or at its ends (NaN: rapids)."""
    return np.clip(1.0 - ev.move_feed / ev.toolpath.feed, 0.0, 1.0)


def find_zones(ev: Evaluation, count: int = 10) -> tuple[Zone, ...]:
    """The ``count`` worst runs of consecutive feed moves slowed by >= ZONE_THRESHOLD.

    Runs break at rapids and operation changes. Worst = largest sum of
    length x reduction (the path length the slow-down costs).
    """
    tp = ev.toolpath
    if tp.n == 0:
        return ()
    red = move_reduction(ev)
    flag = tp.is_feed & (np.nan_to_num(red) >= ZONE_THRESHOLD)
    cont = np.zeros(tp.n, dtype=bool)  # move i continues the run of move i-1
    cont[1:] = flag[1:] & flag[:-1] & (tp.op_index[1:] == tp.op_index[:-1])
    starts = np.flatnonzero(flag & ~cont)
    if starts.size == 0:
        return ()
    run_id = np.cumsum(flag & ~cont) - 1
    idx = np.flatnonzero(flag)
    rid = run_id[idx]
    ends = np.zeros(starts.size, dtype=np.int64)
    np.maximum.at(ends, rid, idx)
    score = np.bincount(rid, weights=tp.length[idx] * red[idx], minlength=starts.size)
    order = np.argsort(-score, kind="stable")[:count]

    # Junction lookups: predicted feed and cause at junction j.
    jpos = np.full(tp.n, -1, dtype=np.int64)
    jpos[ev.junction] = np.arange(ev.junction.size)
    zones = []
    for rank, r in enumerate(order, start=1):
        a, b = int(starts[r]), int(ends[r])
        sl = slice(a, b + 1)
        # Candidates for the minimum: the blocks themselves and junctions a-1 .. b.
        j_lo, j_hi = max(a - 1, 0), min(b, tp.n - 2)
        js = jpos[j_lo : j_hi + 1] if tp.n > 1 else np.zeros(0, dtype=np.int64)
        js = js[js >= 0]
        ratio_el = ev.element_feed[sl] / tp.feed[sl]
        k_el = int(np.argmin(ratio_el))
        best_ratio, where = float(ratio_el[k_el]), ("element", a + k_el)
        if js.size:
            ratio_j = ev.junction_feed[js] / ev.junction_programmed[js]
            k_j = int(np.argmin(ratio_j))
            if ratio_j[k_j] < best_ratio:
                best_ratio, where = float(ratio_j[k_j]), ("junction", int(js[k_j]))
        if where[0] == "junction":
            q = where[1]
            cause = (f"{ev.indicator_names[ev.junction_indicator[q]]}: "
                     f"{ev.labels[ev.junction_limit[q]]}")
            min_feed = float(ev.junction_feed[q])
            prog = float(ev.junction_programmed[q])
            point = tp.end[ev.junction[q]]
        else:
            i = where[1]
            ii = ev.element_indicator[i]
            cause = (f"{ev.indicator_names[ii]}: {ev.labels[ev.element_limit[i]]}"
                     if ii >= 0 else "programmed feed")
            min_feed = float(ev.element_feed[i])
            prog = float(tp.feed[i])
            point = 0.5 * (tp.start[i] + tp.end[i])
        zones.append(
            Zone(
                rank=rank,
                first=a,
                last=b,
                line_first=int(tp.line[sl].min()),
                line_last=int(tp.line[sl].max()),
                length=float(tp.length[sl].sum()),
                discontinuities=int(js.size),
                worst_reduction=1.0 - best_ratio,
                min_feed=min_feed,
                programmed_feed=prog,
                cause=cause,
                score=float(score[r]),
                point=(float(point[0]), float(point[1]), float(point[2])),
            )
        )
    return tuple(zones)


def length_class(ev: Evaluation) -> NDArray[np.int8]:
    """(n,) Figure-10 class of each block: 0 below L, 1 from L to 2 L, 2 above; -1 rapids."""
    tp = ev.toolpath
    ratio = tp.length / ev.min_length
    cls = np.searchsorted(np.array([1.0, 2.0]), np.nan_to_num(ratio, nan=np.inf),
                          side="right").astype(np.int8)
    return np.where(tp.is_feed, cls, -1).astype(np.int8)


def build_annotations(ev: Evaluation, *, zones: int = 10) -> Annotations:
    """Classes, markers and zones of an evaluation."""
    tp = ev.toolpath
    mc = np.where(tp.is_feed, reduction_class(np.nan_to_num(ev.element_reduction)), -1)
    counts = []
    for k in range(len(ev.indicator_names)):
        nj = int(np.count_nonzero((ev.junction_indicator == k) & (ev.junction_limit != 0)))
        ne = int(np.count_nonzero(ev.element_indicator == k))
        counts.append(nj + ne)
    return Annotations(
        title=tp.source,
        machine=ev.machine.name,
        move_class=mc.astype(np.int8),
        junction=ev.junction,
        junction_class=reduction_class(ev.junction_reduction),
        junction_feed=ev.junction_feed,
        junction_cause=ev.junction_indicator,
        junction_limit=ev.junction_limit,
        length_class=length_class(ev),
        zones=find_zones(ev, zones),
        indicator_names=ev.indicator_names,
        indicator_counts=tuple(counts),
        labels=ev.labels,
    )
