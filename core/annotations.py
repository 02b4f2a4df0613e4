"""Colour annotations (what A3 displays draw) and critical zones.

Built from an :class:`~core.indicators.Evaluation`: the paper's two views
(sec. 3.3) -- blocks classed by predicted feed reduction with the
discontinuity points marked by class (Figure 11), and blocks classed by
length against L = F t_int (Figure 10) -- plus the worst zones, findable by
program line.
"""

from __future__ import annotations

import os
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

#: A junction or block is a slow point of a zone when its predicted feed is at least
#: this much below the programmed feed (the paper's green class ends at 10 %).
ZONE_THRESHOLD = 0.10


VIEWS = ("xy", "xz", "yz", "iso")


@dataclass(frozen=True)
class FileTarget:
    """A file to draw into, with the projection to use.

    Attributes
    ----------
    path : str or os.PathLike
        Output file; its extension picks the display (``.svg`` ...). Kept as ``str``.
    view : {"xy", "xz", "yz", "iso"}
        Top view (xy, default), front (xz), side (yz) or isometric.
    """

    path: str | os.PathLike[str]
    view: str = "xy"

    def __post_init__(self) -> None:
        object.__setattr__(self, "path", os.fspath(self.path))
        if self.view not in VIEWS:
            raise ValueError(f"view must be one of {VIEWS}, got {self.view!r}")


@dataclass(frozen=True)
class Zone:
    """A cluster of slow points: junctions and capped blocks close enough together that the
    machine cannot regain the programmed feed between them.

    Attributes
    ----------
    rank : int
        1 = worst (most time lost).
    first, last : int
        First and last move index involved.
    line_first, line_last : int
        Lowest and highest source line involved.
    length : float, mm
        Path length from the first slow point to the last (0 for a single corner).
    discontinuities : int
        Junctions in the zone predicted >= ZONE_THRESHOLD below F.
    capped_blocks : int
        Blocks in the zone whose own feed is capped (model 3 and element plugins).
    worst_reduction : float
        Largest reduction in the zone (0..1).
    min_feed : float, mm/s
        Lowest predicted feed in the zone.
    programmed_feed : float, mm/s
        Programmed feed where the minimum is.
    cause : str
        Indicator and limit of the minimum, e.g. "tangential: jerk X".
    time_lost : float, s
        Rough cost: each slow point braked into and left at the machine's lowest axis
        acceleration A, (F - v)^2 / (A F), plus the slower traverse of capped blocks.
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
    capped_blocks: int
    worst_reduction: float
    min_feed: float
    programmed_feed: float
    cause: str
    time_lost: float
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
    """

    title: str
    machine: str
    move_class: NDArray[np.int8]
    junction: NDArray[np.int64]
    junction_class: NDArray[np.int8]
    junction_feed: NDArray[np.float64]
    junction_reduction: NDArray[np.float64]
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


def _gap_loss(d: NDArray, v1: NDArray, v2: NDArray, f: NDArray, acc: float) -> NDArray:
    """Extra time (s) over distance d (mm) from speed v1 to v2 (mm/s), accelerating at most
    at ``acc`` and never above f, compared with running it at f (trapezoid, exact)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        peak = np.minimum(f, np.sqrt(acc * d + 0.5 * (v1**2 + v2**2)))
        feasible = peak >= np.maximum(v1, v2)
        ramps = (2 * peak - v1 - v2) / acc
        cruise = (d - (2 * peak**2 - v1**2 - v2**2) / (2 * acc)) / peak
        t = np.where(feasible, ramps + cruise, 2 * d / (v1 + v2))
        out = t - d / f
    return np.nan_to_num(np.maximum(out, 0.0), posinf=0.0)


def find_zones(ev: Evaluation, count: int = 10) -> tuple[Zone, ...]:
    """The ``count`` zones that cost the most time.

    Slow points are junctions predicted at least ZONE_THRESHOLD below the programmed feed
    and blocks whose own feed is capped that much. Consecutive slow points join one zone
    when the path between them is shorter than F^2 / (2 A) -- the distance the machine
    needs to regain the feed F from a stop at its lowest axis acceleration A -- and no
    rapid or operation change lies between. Zones are ranked by ``Zone.time_lost``.
    """
    tp = ev.toolpath
    if tp.n == 0:
        return ()
    acc = float(np.min(ev.machine.max_acceleration))
    s_end = np.cumsum(tp.length)
    s_start = s_end - tp.length
    # Events: slow junctions (a point at the end of move j) and capped blocks (a span).
    jsel = np.flatnonzero(ev.junction_reduction >= ZONE_THRESHOLD)
    esel = np.flatnonzero(tp.is_feed & (np.nan_to_num(ev.element_reduction) >= ZONE_THRESHOLD))
    jm = ev.junction[jsel]
    n_j = jsel.size
    first_move = np.concatenate([jm, esel])
    last_move = np.concatenate([jm + 1, esel])
    pos_a = np.concatenate([s_end[jm], s_start[esel]])
    pos_b = np.concatenate([s_end[jm], s_end[esel]])
    v = np.concatenate([ev.junction_feed[jsel], ev.element_feed[esel]])
    f = np.concatenate([ev.junction_programmed[jsel], tp.feed[esel]])
    if v.size == 0:
        return ()
    is_j = np.arange(v.size) < n_j
    cause = np.concatenate(
        [
            ev.junction_indicator[jsel] * 10_000 + ev.junction_limit[jsel],
            ev.element_indicator[esel] * 10_000 + ev.element_limit[esel],
        ]
    )

    order = np.lexsort((pos_b, pos_a))
    (first_move, last_move, pos_a, pos_b, v, f, is_j, cause) = (
        x[order] for x in (first_move, last_move, pos_a, pos_b, v, f, is_j, cause)
    )
    # A rapid or operation change between two events breaks the zone.
    barrier = np.cumsum(~tp.is_feed) + tp.op_index * (tp.n + 1)
    gap_limit = f**2 / (2.0 * acc)
    new = np.ones(v.size, dtype=bool)
    new[1:] = (
        pos_a[1:] - np.maximum.accumulate(pos_b)[:-1] > np.minimum(gap_limit[1:], gap_limit[:-1])
    ) | (barrier[first_move[1:]] != barrier[last_move[:-1]])
    zid = np.cumsum(new) - 1
    starts = np.flatnonzero(new)
    n_z = starts.size
    # Time lost: braking from F into the zone's first slow point and accelerating back to F
    # after its last; between slow points the machine never gets back to F; a capped block
    # is crossed at most at its cap, from and to its neighbours' speeds.
    last = np.append(starts[1:], v.size) - 1
    edge = ((f[starts] - v[starts]) ** 2 + (f[last] - v[last]) ** 2) / (2.0 * acc * f[starts])
    loss = np.zeros(v.size)
    inner = np.flatnonzero(~new[1:])  # pairs (k, k + 1) inside one zone
    if inner.size:
        loss[inner] += _gap_loss(
            np.maximum(pos_a[inner + 1] - pos_b[inner], 0.0),
            v[inner],
            v[inner + 1],
            np.minimum(f[inner], f[inner + 1]),
            acc,
        )
    el = np.flatnonzero(~is_j)
    if el.size:
        same_prev = np.zeros(v.size, dtype=bool)
        same_prev[1:] = ~new[1:]
        same_next = np.append(~new[1:], False)
        v_in = np.where(same_prev[el], v[np.maximum(el - 1, 0)], v[el])
        v_out = np.where(same_next[el], v[np.minimum(el + 1, v.size - 1)], v[el])
        d = pos_b[el] - pos_a[el]
        cap = v[el]
        with np.errstate(divide="ignore", invalid="ignore"):
            at_cap = np.nan_to_num(d / cap - d / f[el], posinf=0.0)
        # _gap_loss compares with running at the cap; add the cap's own loss against F.
        loss[el] += _gap_loss(d, np.minimum(v_in, cap), np.minimum(v_out, cap), cap, acc) + at_cap
    z_loss = np.bincount(zid, weights=loss, minlength=n_z) + edge
    top = np.argsort(-z_loss, kind="stable")[:count]
    ratio = v / f
    zones = []
    for rank, z in enumerate(top, start=1):
        sl = slice(starts[z], starts[z + 1] if z + 1 < n_z else v.size)
        k = sl.start + int(np.argmin(ratio[sl]))
        ind, lim = divmod(int(cause[k]), 10_000)
        a_move, b_move = int(first_move[sl].min()), int(last_move[sl].max())
        if is_j[k]:
            point = tp.end[first_move[k]]
        else:
            point = 0.5 * (tp.start[first_move[k]] + tp.end[first_move[k]])
        zones.append(
            Zone(
                rank=rank,
                first=a_move,
                last=b_move,
                line_first=int(tp.line[a_move : b_move + 1].min()),
                line_last=int(tp.line[a_move : b_move + 1].max()),
                length=float(pos_b[sl].max() - pos_a[sl].min()),
                discontinuities=int(is_j[sl].sum()),
                capped_blocks=int((~is_j[sl]).sum()),
                worst_reduction=float(1.0 - ratio[k]),
                min_feed=float(v[k]),
                programmed_feed=float(f[k]),
                cause=f"{ev.indicator_names[ind]}: {ev.labels[lim]}",
                time_lost=float(z_loss[z]),
                point=(float(point[0]), float(point[1]), float(point[2])),
            )
        )
    return tuple(zones)


def length_class(ev: Evaluation) -> NDArray[np.int8]:
    """(n,) Figure-10 class of each block: 0 below L, 1 from L to 2 L, 2 above; -1 rapids."""
    tp = ev.toolpath
    ratio = tp.length / ev.min_length
    cls = np.searchsorted(
        np.array([1.0, 2.0]), np.nan_to_num(ratio, nan=np.inf), side="right"
    ).astype(np.int8)
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
        junction_reduction=ev.junction_reduction,
        junction_cause=ev.junction_indicator,
        junction_limit=ev.junction_limit,
        length_class=length_class(ev),
        zones=find_zones(ev, zones),
        indicator_names=ev.indicator_names,
        indicator_counts=tuple(counts),
        labels=ev.labels,
    )
