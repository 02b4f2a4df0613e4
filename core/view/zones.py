"""The zones that lose the most time: stretches the predicted profile keeps below 90 % of the
programmed feed around slow points, ranked by the time they lose against length / F."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from core.engine.indicators import Evaluation
from core.engine.profile import Profile
from core.model.arrays import nan_to_num
from core.model.pieces import PIECE, pieces

#: A junction or block is a slow point of a zone when its predicted feed is at least
#: this much below the programmed feed (the paper's green class ends at 10 %).
ZONE_THRESHOLD = 0.10


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
    origin : str
        The call chain that ran the zone's first block ("" for the main program's own
        blocks; see :attr:`ToolPath.origins`).
    file : str
        The file the lines are in when it is not the main program's ("").
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
    origin: str = ""
    file: str = ""

    @property
    def lines(self) -> str:
        """ "12-15", or "pocket.ngc:3-5" for lines of another file."""
        a, b = self.line_first, self.line_last
        text = f"{a}" if a == b else f"{a}-{b}"
        return f"{self.file}:{text}" if self.file else text


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


#: A run of points: how many pieces of what it is made of (junctions, moves) there are,
#: and the points of piece ``b``: their ids, zones (non-decreasing over the run) and ratios.
_Run = tuple[
    int, Callable[[slice], tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]]
]


def _worst_points(
    zone: NDArray[np.int64], ratio: NDArray[np.float64], n_z: int, split: int | None = None
) -> NDArray:
    """Per zone, the point of lowest ``ratio`` (the first such point on a tie; NaN above
    every number), -1 for a zone without points: the head of each zone in
    ``np.lexsort((ratio, zone))``, without sorting.

    ``zone`` is two non-decreasing runs (the junctions', the blocks'; the second starts at
    ``split``, found where ``zone`` steps down if not given); see :func:`_worst_of_runs`.
    """
    p = zone.size
    if split is None:
        down = np.flatnonzero(zone[1:] < zone[:-1])
        split = int(down[0]) + 1 if down.size else p

    def run(lo: int, hi: int) -> _Run:
        z, r = zone[lo:hi], ratio[lo:hi]
        return hi - lo, lambda b: (np.arange(lo + b.start, lo + b.stop), z[b], r[b])

    return _worst_of_runs((run(0, split), run(split, p)), n_z)[0]


def _worst_of_runs(
    runs: tuple[_Run, ...], n_z: int
) -> tuple[NDArray[np.int64], NDArray[np.int8], list[NDArray[np.int64]]]:
    """The worst point of each zone (:func:`_worst_points`) of the points of ``runs`` one
    after the other, each run's points given piece by piece (no (p,) array of them is
    made: 5M arcs, 10M points, once the annotations' peak): its id (-1: none) and run, and
    each run's count of points per zone.

    A stable sort by zone would merge the runs, each zone's points of the first run before
    those of the second, in their order: so each zone's lowest ratio is the lowest of the
    runs' (reductions over their sorted zones), and its worst point the first point with
    it in the first run, else in the second.
    """
    worst = np.full(n_z, -1, dtype=np.int64)
    which = np.full(n_z, -1, dtype=np.int8)
    low = np.full(n_z, np.nan)
    counts = []
    # a run of one piece keeps its points for the second loop (no larger than a piece,
    # which the loops make anyway): they are not made twice
    kept: dict[int, tuple[NDArray, NDArray, NDArray]] = {}
    for r, (size, get) in enumerate(runs):
        count = np.zeros(n_z, dtype=np.int64)
        for b in pieces(size):
            got = get(b)
            if size <= PIECE:
                kept[r] = got
            _, zb, rb = got
            if zb.size == 0:
                continue
            np.add.at(count, zb, 1)
            first = np.flatnonzero(np.concatenate([[True], zb[1:] != zb[:-1]]))
            z = zb[first]
            low[z] = np.fmin(low[z], np.fmin.reduceat(rb, first))  # NaN only if all are
        counts.append(count)
    for r, (size, get) in enumerate(runs):  # in order, each in pieces in order: the
        for b in pieces(size):  # first point claims
            ids, zb, rb = kept.pop(r) if r in kept else get(b)
            lo = low[zb]
            k = np.flatnonzero((rb == lo) | (np.isnan(lo) & np.isnan(rb)))
            zk = zb[k]
            head = np.ones(k.size, dtype=bool)
            head[1:] = zk[1:] != zk[:-1]
            k, zk = k[head], zk[head]
            free = worst[zk] < 0
            worst[zk[free]] = ids[k[free]]
            which[zk[free]] = r
    return worst, which, counts


def _zones(ev: Evaluation, profile: Profile, count: int | None):
    tp = ev.toolpath
    if tp.n == 0:
        return () if count is not None else 0
    feed = tp.is_feed
    with np.errstate(invalid="ignore"):
        fast = ~feed | (profile.v_peak >= (1.0 - ZONE_THRESHOLD) * tp.feed)
    brk = np.flatnonzero(fast)
    n_z = brk.size + 1
    # The phases of the breaks only (no (n,) arrays): their accelerating start and braking end.
    t_up, t_dn, d_up, d_dn, _ = profile.phases_of(brk)
    th0, th1 = profile.hold_times_of(brk)
    # The holds at a move's ends (inserted arcs) belong with its acceleration and braking.
    d_up = d_up + profile.hold_start[brk]
    d_dn = d_dn + profile.hold_end[brk]
    f_brk, feed_brk = tp.feed[brk], feed[brk]
    with np.errstate(invalid="ignore", divide="ignore"):
        lost_up = np.where(feed_brk, t_up + th0 - d_up / f_brk, 0.0)
        lost_dn = np.where(feed_brk, t_dn + th1 - d_dn / f_brk, 0.0)
    # Zone of each move: zone m lies between break m-1 and break m (the breaks before it).
    zone_of: NDArray[np.int64] = np.cumsum(fast)
    zone_of -= fast
    inner = ~fast
    # Inner moves are feed moves: their Profile.lost_time, without its (n,) array. The sums
    # are float64 whatever the count: a bincount over no moves is int64, and np.add.at
    # below would truncate every lone corner's fractions into it.
    # In pieces, each added in the order of the moves as one bincount would (np.add.at adds
    # one by one, in order: the same sums; 5M moves, 270 MB of temporaries less).
    lost, length = np.zeros(n_z), np.zeros(n_z)
    for piece in pieces(tp.n):
        ii = np.flatnonzero(inner[piece])
        ii += piece.start
        zi, len_i = zone_of[ii], tp.length[ii]
        with np.errstate(invalid="ignore"):
            lost_i = profile.time[ii] - len_i / tp.feed[ii]
        np.add.at(lost, zi, lost_i)
        np.add.at(length, zi, len_i)
    del inner
    # Breaks: their accelerating start ends zone m, their braking end opens zone m + 1.
    m = np.arange(brk.size)
    np.add.at(lost, m, lost_up)
    np.add.at(lost, m + 1, lost_dn)
    np.add.at(length, m, np.where(feed_brk, d_up, 0.0))
    np.add.at(length, m + 1, np.where(feed_brk, d_dn, 0.0))
    # Move range of each zone: from the break before to the break after (where they brake
    # or accelerate), clipped to the program.
    first = np.concatenate([[0], brk])
    last = np.concatenate([brk, [tp.n - 1]])

    # Slow points of the evaluation, each with its zone and feed ratio, piece by piece (no
    # arrays of them: 5M arcs, 10M points, 300 MB off the peak): a junction after a break
    # is in the zone the break opens.
    jr, er = ev.junction_reduction, ev.element_reduction

    def j_points(b: slice) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
        js = np.flatnonzero(jr[b] >= ZONE_THRESHOLD)
        js += b.start
        jm = ev.junction[js]
        return js, zone_of[jm] + fast[jm], ev.junction_feed[js] / ev.junction_programmed[js]

    def e_points(b: slice) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
        es = np.flatnonzero(feed[b] & (nan_to_num(er[b]) >= ZONE_THRESHOLD))
        es += b.start
        return es, zone_of[es] + fast[es], ev.element_feed[es] / tp.feed[es]

    worst, which, (n_j, n_e) = _worst_of_runs(((jr.size, j_points), (tp.n, e_points)), n_z)
    points = n_j + n_e

    candidates = np.flatnonzero(points > 0)
    if count is None:
        return len(candidates)
    top = candidates[np.argsort(-lost[candidates], kind="stable")[:count]]
    zones = []
    for rank, z in enumerate(top, start=1):
        if which[z] == 0:  # a junction's
            q = int(worst[z])
            cause = (
                f"{ev.indicator_names[ev.junction_indicator[q]]}: {ev.labels[ev.junction_limit[q]]}"
            )
            min_feed, prog = float(ev.junction_feed[q]), float(ev.junction_programmed[q])
            point = tp.end[ev.junction[q]]
        else:  # a block's
            i = int(worst[z])
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
                origin="" if tp.origin is None or tp.origin[a] < 0 else tp.origins[tp.origin[a]],
                file="" if tp.origin is None or tp.origin[a] < 0 else tp.origin_files[tp.origin[a]],
            )
        )
    return tuple(zones)
