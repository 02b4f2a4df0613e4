"""The zones that lose the most time: stretches the predicted profile keeps below 90 % of the
programmed feed around slow points, ranked by the time they lose against length / F."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from core.engine.indicators import Evaluation
from core.engine.profile import Profile
from core.model.pieces import piecewise

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


def _worst_points(zone: NDArray[np.int64], ratio: NDArray[np.float64], n_z: int) -> NDArray:
    """Per zone, the point of lowest ``ratio`` (the first such point on a tie; NaN above
    every number), -1 for a zone without points: the head of each zone in
    ``np.lexsort((ratio, zone))``, without sorting the ratios (stellabee1: 47 -> 11 ms).

    ``zone`` is two non-decreasing runs (the junctions', the blocks'), which a stable sort
    merges in one pass; within a zone the points then keep their order. Past the sort's
    order, the (p,) work is done in pieces: this is the annotations' peak.
    """
    worst = np.full(n_z, -1, dtype=np.int64)
    p = zone.size
    if p == 0:
        return worst
    order = np.argsort(zone, kind="stable")
    # where each zone's points start in that order
    change = piecewise(
        p - 1, bool, lambda b: zone[order[b.start + 1 : b.stop + 1]] != zone[order[b]]
    )
    first = np.concatenate([[0], np.flatnonzero(change) + 1])
    del change
    low = np.fmin.reduceat(ratio[order], first)  # NaN only where all of a zone's ratios are

    def lowest(b: slice) -> NDArray[np.bool_]:
        seg = np.searchsorted(first, np.arange(b.start, b.stop), side="right") - 1
        r, lo = ratio[order[b]], low[seg]
        return (r == lo) | (np.isnan(lo) & np.isnan(r))

    k = np.flatnonzero(piecewise(p, bool, lowest))
    seg = np.searchsorted(first, k, side="right") - 1  # the zone (rank) of each
    head = k[np.concatenate([[True], seg[1:] != seg[:-1]])]
    worst[zone[order[head]]] = order[head]
    return worst


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
    ii = np.flatnonzero(inner)
    zi, len_i = zone_of[ii], tp.length[ii]
    with np.errstate(invalid="ignore"):
        lost_i = profile.time[ii] - len_i / tp.feed[ii]
    lost = np.bincount(zi, weights=lost_i, minlength=n_z).astype(np.float64, copy=False)
    length = np.bincount(zi, weights=len_i, minlength=n_z).astype(np.float64, copy=False)
    del ii, zi, len_i, lost_i, inner
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

    # Slow points of the evaluation, each with its zone.
    jsel = np.flatnonzero(ev.junction_reduction >= ZONE_THRESHOLD)
    esel = np.flatnonzero(feed & (np.nan_to_num(ev.element_reduction) >= ZONE_THRESHOLD))
    n_js = jsel.size  # points [0, n_js) are junctions, the rest blocks
    # Zone and feed ratio of each point, written in place (no per-kind copies to join: 5M
    # arcs, 120 MB off the peak): a junction after a break is in the zone the break opens.
    pt_zone = np.empty(n_js + esel.size, dtype=np.int64)
    jm = ev.junction[jsel]
    j_zone = pt_zone[:n_js]
    np.take(zone_of, jm, out=j_zone)
    j_zone += fast[jm]
    del jm
    np.add(zone_of[esel], fast[esel], out=pt_zone[n_js:])
    del zone_of  # the sort below is the peak
    ratio = np.empty(pt_zone.size)
    np.divide(ev.junction_feed[jsel], ev.junction_programmed[jsel], out=ratio[:n_js])
    np.divide(ev.element_feed[esel], tp.feed[esel], out=ratio[n_js:])
    points = np.bincount(pt_zone, minlength=n_z)
    n_j = np.bincount(j_zone, minlength=n_z)
    # (the junctions' indices are found again for the zones listed: the sort is the peak)
    del j_zone, jsel
    worst = _worst_points(pt_zone, ratio, n_z)
    del pt_zone, ratio

    candidates = np.flatnonzero(points > 0)
    if count is None:
        return len(candidates)
    jsel = np.flatnonzero(ev.junction_reduction >= ZONE_THRESHOLD)
    top = candidates[np.argsort(-lost[candidates], kind="stable")[:count]]
    zones = []
    for rank, z in enumerate(top, start=1):
        k = int(worst[z])
        if k < n_js:
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
                origin="" if tp.origin is None or tp.origin[a] < 0 else tp.origins[tp.origin[a]],
                file="" if tp.origin is None or tp.origin[a] < 0 else tp.origin_files[tp.origin[a]],
            )
        )
    return tuple(zones)
