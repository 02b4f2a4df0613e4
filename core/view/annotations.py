"""Colour annotations (what A3 displays draw) and critical zones.

Built from an :class:`~core.engine.indicators.Evaluation`: the paper's two views
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

from core.engine.indicators import REDUCTION_LABELS, Evaluation, reduction_class
from core.engine.profile import Profile, build_profile

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


def _file_target(target: object) -> None:
    """Check a drawing target's view and keep its path as ``str`` (the targets are frozen)."""
    object.__setattr__(target, "path", os.fspath(target.path))
    if target.view not in VIEWS:
        raise ValueError(f"view must be one of {VIEWS}, got {target.view!r}")


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
        _file_target(self)


@dataclass(frozen=True, eq=False)
class ComparisonTarget:
    """A file to draw several programs into, side by side (``ncperf compare``).

    Attributes
    ----------
    path : str
        Output file; its extension picks the display.
    panels : tuple of (label, ToolPath, Annotations)
        The programs, in drawing order.
    view : {"xy", "xz", "yz", "iso"}
    """

    path: str
    panels: tuple
    view: str = "xy"

    def __post_init__(self) -> None:
        _file_target(self)


@dataclass(frozen=True, eq=False)
class DiagnosisTarget:
    """A file to draw a diagnosis into: the path coloured by gap, the gap zones, and measured
    against predicted feed over arc length for the worst of them (``ncperf diagnose``).

    Attributes
    ----------
    path : str
    diagnosis : core.diagnosis.diagnose.Diagnosis
    view : {"xy", "xz", "yz", "iso"}
    """

    path: str
    diagnosis: object
    view: str = "xy"

    def __post_init__(self) -> None:
        _file_target(self)


@dataclass(frozen=True)
class Zone:
    """A stretch of the path the predicted profile keeps below 90 % of the programmed feed
    around slow points (see :func:`find_zones`).

    Attributes
    ----------
    rank : int
        1 = worst (most time lost).
    first, last : int
        First and last move index involved (the moves braking into and accelerating out
        of the zone included).
    line_first, line_last : int
        Lowest and highest source line involved.
    length : float, mm
        Path length of the zone: its moves, plus the braking end and accelerating start of
        the moves around it.
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
        Predicted time of the zone's moves minus their length / F (the profile's braking,
        slow crossing and re-acceleration).
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


def zone_count(ev: Evaluation, profile: Profile) -> int:
    """How many zones (see :func:`find_zones`) the program has."""
    return _zones(ev, profile, None)


def find_zones(ev: Evaluation, profile: Profile, count: int = 10) -> tuple[Zone, ...]:
    """The ``count`` zones that cost the most time.

    Moves whose predicted speed reaches (1 - ZONE_THRESHOLD) of the programmed feed, and
    rapids, separate zones: a zone is what lies between two of them -- the braking end of
    the first, every move in between (all kept below 90 % of F), the accelerating start of
    the second. A zone is listed if it holds at least one slow point of the evaluation (a
    junction or a block predicted ZONE_THRESHOLD or more below F); stretches slowed only by
    starting and stopping (program ends, rapids, dwells) are not zones, though their time
    is in the cycle time all the same. Zones are ranked by the time the profile loses on
    them against length / F.
    """
    return _zones(ev, profile, count)


def _zones(ev: Evaluation, profile: Profile, count: int | None):
    tp = ev.toolpath
    if tp.n == 0:
        return () if count is not None else 0
    feed = tp.is_feed
    t_up, t_dn, d_up, d_dn, _ = profile._phases
    th0, th1 = profile._hold_times
    # The holds at a move's ends (inserted arcs) belong with its acceleration and braking.
    d_up = d_up + profile.hold_start
    d_dn = d_dn + profile.hold_end
    with np.errstate(invalid="ignore", divide="ignore"):
        fast = ~feed | (profile.v_peak >= (1.0 - ZONE_THRESHOLD) * tp.feed)
        lost_up = np.where(feed, t_up + th0 - d_up / tp.feed, 0.0)
        lost_dn = np.where(feed, t_dn + th1 - d_dn / tp.feed, 0.0)
    brk = np.flatnonzero(fast)
    n_z = brk.size + 1
    # Zone of each move: zone m lies between break m-1 and break m.
    zone_of = np.searchsorted(brk, np.arange(tp.n), side="left")
    inner = ~fast
    lost = np.bincount(zone_of[inner], weights=profile.lost_time[inner], minlength=n_z)
    length = np.bincount(zone_of[inner], weights=tp.length[inner], minlength=n_z)
    # Breaks: their accelerating start ends zone m, their braking end opens zone m + 1.
    m = np.arange(brk.size)
    np.add.at(lost, m, lost_up[brk])
    np.add.at(lost, m + 1, lost_dn[brk])
    np.add.at(length, m, np.where(feed[brk], d_up[brk], 0.0))
    np.add.at(length, m + 1, np.where(feed[brk], d_dn[brk], 0.0))
    # Move range of each zone: from the break before to the break after (where they brake
    # or accelerate), clipped to the program.
    first = np.concatenate([[0], brk])
    last = np.concatenate([brk, [tp.n - 1]])

    # Slow points of the evaluation, each with its zone.
    jsel = np.flatnonzero(ev.junction_reduction >= ZONE_THRESHOLD)
    jm = ev.junction[jsel]
    j_zone = np.where(fast[jm], zone_of[jm] + 1, zone_of[jm])
    esel = np.flatnonzero(feed & (np.nan_to_num(ev.element_reduction) >= ZONE_THRESHOLD))
    e_zone = zone_of[esel] + fast[esel]
    ratio = np.concatenate(
        [
            ev.junction_feed[jsel] / ev.junction_programmed[jsel],
            ev.element_feed[esel] / tp.feed[esel],
        ]
    )
    pt_zone = np.concatenate([j_zone, e_zone])
    is_j = np.arange(ratio.size) < jsel.size
    points = np.bincount(pt_zone, minlength=n_z)
    n_j = np.bincount(pt_zone[is_j], minlength=n_z)
    # The worst point of each zone: sort by (zone, ratio), take the first of each zone.
    order = np.lexsort((ratio, pt_zone))
    worst = np.full(n_z, -1, dtype=np.int64)
    if order.size:
        head = np.ones(order.size, dtype=bool)
        head[1:] = pt_zone[order[1:]] != pt_zone[order[:-1]]
        worst[pt_zone[order[head]]] = order[head]

    candidates = np.flatnonzero(points > 0)
    if count is None:
        return len(candidates)
    top = candidates[np.argsort(-lost[candidates], kind="stable")[:count]]
    zones = []
    for rank, z in enumerate(top, start=1):
        k = int(worst[z])
        if is_j[k]:
            q = int(jsel[k])
            cause = (
                f"{ev.indicator_names[ev.junction_indicator[q]]}: {ev.labels[ev.junction_limit[q]]}"
            )
            min_feed, prog = float(ev.junction_feed[q]), float(ev.junction_programmed[q])
            point = tp.end[ev.junction[q]]
        else:
            i = int(esel[k - jsel.size])
            cause = (
                f"{ev.indicator_names[ev.element_indicator[i]]}: {ev.labels[ev.element_limit[i]]}"
            )
            min_feed, prog = float(ev.element_feed[i]), float(tp.feed[i])
            point = 0.5 * (tp.start[i] + tp.end[i])
        a, b = int(first[z]), int(last[z])
        zones.append(
            Zone(
                rank=rank,
                first=a,
                last=b,
                line_first=int(tp.line[a : b + 1].min()),
                line_last=int(tp.line[a : b + 1].max()),
                length=float(length[z]),
                discontinuities=int(n_j[z]),
                capped_blocks=int(points[z] - n_j[z]),
                worst_reduction=float(1.0 - min_feed / prog),
                min_feed=min_feed,
                programmed_feed=prog,
                cause=cause,
                time_lost=float(lost[z]),
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


def build_annotations(
    ev: Evaluation, profile: Profile | None = None, *, zones: int = 10
) -> Annotations:
    """Classes, markers and zones of an evaluation (its profile is built if not given)."""
    tp = ev.toolpath
    if profile is None:
        profile = build_profile(ev)
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
        zones=find_zones(ev, profile, zones),
        indicator_names=ev.indicator_names,
        indicator_counts=tuple(counts),
        labels=ev.labels,
    )
