"""The predicted feed profile along the whole program, and the cycle time.

The paper predicts the feed *at* discontinuities and caps short blocks; a real controller
also brakes before each slow point and accelerates after it (full look-ahead), so on dense
paths it may never reach the programmed feed. This module turns the A2 results into a feed
profile over the path:

* every move has a cruise cap: its own predicted feed (programmed F capped by the element
  indicators: block time, axis feed limits, plugins), rapids the axes' max feed along their
  direction;
* every boundary between moves has a cap: the junction's predicted feed where an indicator
  reported one, 0 at exact stops, dwells, rapid <-> feed changes, operation changes and the
  ends of the program;
* the tangential acceleration and jerk of a move are the machine's per-axis limits divided
  by each axis's largest share of the tangent over the move (as in model 1):
  A = min_k A_k / |t_k|, J = min_k J_k / |t_k|;
* a forward pass (accelerating out of every cap) and a backward pass (braking into every
  cap) give the speed at every boundary; between boundaries each move accelerates, cruises
  and brakes.

Vectorised passes
-----------------
With a constant acceleration a, the speed reachable at boundary j from any earlier cap i is
v_j^2 <= B_i^2 + 2 a (S_j - S_i), so the forward pass is a cumulative minimum of
B_i^2 - 2 a S_i. The acceleration varies from move to move here; the same holds with the
"acceleration-weighted length" W_j = sum_{k<j} 2 a_k L_k in place of 2 a S_j, because over
move k the square of the speed changes by at most 2 a_k L_k. Both passes are therefore one
``np.minimum.accumulate`` each, exact for piecewise-constant accelerations.

Jerk (the approximation)
------------------------
A jerk-limited (S-curve) speed change dv at acceleration A and jerk J takes
T = dv/A + A/J (when dv >= A^2/J) or T = 2 sqrt(dv/J) (when A is never reached), and, its
speed curve being point-symmetric, covers (v0 + v1)/2 * T. A trapezoid ramp with the
effective acceleration A_eff = dv / T has the same duration and the same distance. ncperf
therefore finds the acceleration and braking ramps of the trapezoid solution (chains of
moves accelerating or braking from one speed to another), gives every move of a ramp the
A_eff of the ramp's whole speed change, and solves again; a few rounds settle it. The
ramps' times and lengths are those of S-curves; the speed inside a ramp is drawn as a
straight line in time, not as the S. The normal acceleration that arcs already use is not
subtracted from the tangential budget.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from core import geometry as g
from core.indicators import Evaluation
from core.toolpath import MoveKind, PathMode, ToolPath

#: Most rounds of the jerk (effective acceleration) iteration, and when to stop early: the
#: effective accelerations fall monotonically (a lower A_eff gives lower peaks, hence smaller
#: speed changes, hence a lower A_eff), contracting by about 4 in log per round.
JERK_ROUNDS = 12
JERK_CONVERGED = 1e-4

_EPS = 1e-9


def effective_acceleration(dv: ArrayLike, acc: ArrayLike, jerk: ArrayLike) -> NDArray[np.float64]:
    """A_eff = dv / T of S-curve speed changes (mm/s^2).

    Parameters
    ----------
    dv : (m,) float, mm/s
        Speed change of the ramp (>= 0).
    acc, jerk : (m,) float
        Tangential acceleration (mm/s^2) and jerk (mm/s^3, may be inf).

    Returns
    -------
    (m,) float, mm/s^2
        ``acc`` where the jerk is infinite or the change is nil.
    """
    dv = np.asarray(dv, dtype=np.float64)
    a = np.asarray(acc, dtype=np.float64)
    j = np.asarray(jerk, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_full = dv / a + a / j
        t_short = 2.0 * np.sqrt(dv / j)
        t = np.where(dv >= a * a / j, t_full, t_short)
        out = dv / t
    return np.where(np.isfinite(j) & (dv > _EPS), out, a)


def tangential_limits(tp: ToolPath, acc: ArrayLike, jerk: ArrayLike) -> tuple[NDArray, NDArray]:
    """(n,) tangential acceleration and jerk of each move: min_k limit_k / share_k."""
    share = tp.axis_share
    acc = np.asarray(acc, dtype=np.float64)
    jerk = np.asarray(jerk, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(share > 0, acc[None, :] / share, np.inf).min(axis=1)
        j = np.where(share > 0, jerk[None, :] / share, np.inf).min(axis=1)
    # A move with no direction (zero length, NaN) gets the lowest axis limits.
    a = np.where(np.isfinite(a), a, acc.min())
    j = np.where(np.isnan(j) | (np.isinf(j) & np.isfinite(jerk).all()), jerk.min(), j)
    return a, j


@dataclass(frozen=True, eq=False)
class Samples:
    """A profile sampled at a fixed time step (the columns of a measured trace).

    Attributes
    ----------
    t : (m,) float, s
    s : (m,) float, mm
        Arc length from the program start (rapids included).
    x, y, z : (m,) float, mm
    v : (m,) float, mm/s
    line : (m,) int
        1-based program line of the move being run.
    """

    t: NDArray[np.float64]
    s: NDArray[np.float64]
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    z: NDArray[np.float64]
    v: NDArray[np.float64]
    line: NDArray[np.int64]


@dataclass(frozen=True, eq=False)
class Profile:
    """The predicted feed over the program.

    Attributes
    ----------
    evaluation : Evaluation
    cap : (n,) float, mm/s
        Cruise cap of each move.
    v_entry, v_peak, v_exit : (n,) float, mm/s
        Speed at the start, highest speed and speed at the end of each move.
    a_up, a_down : (n,) float, mm/s^2
        Effective tangential acceleration and braking used on each move (S-curve ramps).
    time : (n,) float, s
        Motion time of each move (its dwell not included).
    """

    evaluation: Evaluation
    cap: NDArray[np.float64]
    v_entry: NDArray[np.float64]
    v_peak: NDArray[np.float64]
    v_exit: NDArray[np.float64]
    a_up: NDArray[np.float64]
    a_down: NDArray[np.float64]
    time: NDArray[np.float64]

    @property
    def toolpath(self) -> ToolPath:
        return self.evaluation.toolpath

    @cached_property
    def cycle_time(self) -> float:
        """Predicted cycle time: motion of every move plus dwells (s)."""
        return float(self.time.sum() + self.toolpath.dwell.sum())

    @cached_property
    def start_time(self) -> NDArray[np.float64]:
        """(n,) time at which each move starts (s)."""
        span = self.time + self.toolpath.dwell
        return np.concatenate([[0.0], np.cumsum(span)[:-1]])

    @cached_property
    def start_s(self) -> NDArray[np.float64]:
        """(n,) arc length at which each move starts (mm)."""
        return np.concatenate([[0.0], np.cumsum(self.toolpath.length)[:-1]])

    @cached_property
    def _phases(self) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray]:
        """Durations and lengths of each move's acceleration, cruise and braking."""
        v0, v1, vp = self.v_entry, self.v_exit, self.v_peak
        au, ad = self.a_up, self.a_down
        t_up = (vp - v0) / au
        t_dn = (vp - v1) / ad
        d_up = (vp**2 - v0**2) / (2 * au)
        d_dn = (vp**2 - v1**2) / (2 * ad)
        d_cr = np.maximum(self.toolpath.length - d_up - d_dn, 0.0)
        return t_up, t_dn, d_up, d_dn, d_cr

    @cached_property
    def lost_time(self) -> NDArray[np.float64]:
        """(n,) time each feed move takes beyond length / F (s); 0 for rapids."""
        tp = self.toolpath
        with np.errstate(invalid="ignore"):
            extra = self.time - tp.length / tp.feed
        return np.where(tp.is_feed, extra, 0.0)

    def speed_at(self, s: ArrayLike) -> NDArray[np.float64]:
        """Predicted speed (mm/s) at arc lengths ``s`` (mm) from the program start."""
        s = np.asarray(s, dtype=np.float64)
        tp = self.toolpath
        k = np.clip(np.searchsorted(self.start_s, s, side="right") - 1, 0, tp.n - 1)
        d = np.clip(s - self.start_s[k], 0.0, tp.length[k])
        _, _, d_up, d_dn, d_cr = self._phases
        up = np.sqrt(np.maximum(self.v_entry[k] ** 2 + 2 * self.a_up[k] * d, 0.0))
        rest = tp.length[k] - d
        down = np.sqrt(np.maximum(self.v_exit[k] ** 2 + 2 * self.a_down[k] * rest, 0.0))
        return np.minimum(np.minimum(up, down), self.v_peak[k])

    def sample(self, dt: float = 0.001) -> Samples:
        """The profile every ``dt`` seconds from 0 to the cycle time (both ends included)."""
        if not dt > 0:
            raise ValueError(f"dt must be positive, got {dt}")
        tp = self.toolpath
        n_s = int(np.floor(self.cycle_time / dt + 1e-9)) + 1
        t = np.arange(n_s) * dt
        k = np.clip(np.searchsorted(self.start_time, t, side="right") - 1, 0, tp.n - 1)
        tau = t - self.start_time[k]
        t_up, t_dn, d_up, d_dn, d_cr = self._phases
        v0, vp, ad, au = self.v_entry[k], self.v_peak[k], self.a_down[k], self.a_up[k]
        tu, tdn, du = t_up[k], t_dn[k], d_up[k]
        with np.errstate(divide="ignore", invalid="ignore"):
            t_cr = np.where(vp > 0, d_cr[k] / vp, 0.0)
        tau = np.minimum(tau, tu + t_cr + tdn)  # a dwell holds the end of the move
        in_up = tau < tu
        in_cr = ~in_up & (tau < tu + t_cr)
        td = np.maximum(tau - tu - t_cr, 0.0)
        d = np.where(
            in_up,
            v0 * tau + 0.5 * au * tau**2,
            np.where(in_cr, du + vp * (tau - tu), du + d_cr[k] + vp * td - 0.5 * ad * td**2),
        )
        v = np.where(in_up, v0 + au * tau, np.where(in_cr, vp, vp - ad * td))
        d = np.clip(d, 0.0, tp.length[k])
        pts = points_along(tp, k, d)
        return Samples(
            t=t,
            s=self.start_s[k] + d,
            x=pts[:, 0],
            y=pts[:, 1],
            z=pts[:, 2],
            v=np.maximum(v, 0.0),
            line=tp.line[k],
        )


def points_along(tp: ToolPath, k: NDArray[np.int64], d: NDArray[np.float64]) -> NDArray:
    """(m, 3) points at distance ``d`` (mm) from the start of moves ``k``."""
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.where(tp.length[k] > 0, d / tp.length[k], 0.0)
    out = tp.start[k] + frac[:, None] * (tp.end[k] - tp.start[k])
    arc = tp.is_arc[k]
    if arc.any():
        ka = k[arc]
        out[arc] = g.arc_points(
            tp.start[ka],
            tp.center[ka],
            tp.normal[ka],
            tp.kind[ka] == MoveKind.ARC_CCW,
            tp.sweep[ka],
            tp.pitch[ka],
            frac[arc],
        )
    return out


def boundary_caps(ev: Evaluation, cap: NDArray[np.float64]) -> NDArray[np.float64]:
    """(n + 1,) speed cap at every move boundary (mm/s); 0 at the ends and at stops."""
    tp = ev.toolpath
    n = tp.n
    b = np.zeros(n + 1)
    if n < 2:
        return b
    inner = np.minimum(cap[:-1], cap[1:])
    joined = np.zeros(n - 1, dtype=bool)
    joined[tp.junctions] = True
    stop = (tp.path_mode[:-1] == PathMode.EXACT_STOP) | (tp.dwell[:-1] > 0)
    inner = np.where(joined & ~stop, inner, 0.0)
    inner[ev.junction] = np.minimum(inner[ev.junction], ev.junction_feed)
    b[1:-1] = inner
    return b


def _passes(b: NDArray, length: NDArray, a_up: NDArray, a_dn: NDArray) -> NDArray:
    """Boundary speeds (n + 1,) from the forward and backward passes (see module docstring)."""
    w_up = np.concatenate([[0.0], np.cumsum(2.0 * a_up * length)])
    w_dn = np.concatenate([[0.0], np.cumsum(2.0 * a_dn * length)])
    b2 = b * b
    fwd = np.minimum.accumulate(b2 - w_up) + w_up
    bwd = np.minimum.accumulate((b2 + w_dn)[::-1])[::-1] - w_dn
    return np.sqrt(np.maximum(np.minimum(np.minimum(fwd, bwd), b2), 0.0))


def _window_caps(b: NDArray, length: NDArray, a_dn: NDArray, lookahead: int | None) -> NDArray:
    """Boundary caps of a planner that sees ``lookahead`` blocks: from every boundary it must
    be able to stop by the end of the blocks it sees."""
    n = length.size
    if lookahead is None or lookahead >= n:
        return b
    w_dn = np.concatenate([[0.0], np.cumsum(2.0 * a_dn * length)])
    ahead = np.minimum(np.arange(n + 1) + int(lookahead), n)
    return np.minimum(b, np.sqrt(np.maximum(w_dn[ahead] - w_dn, 0.0)))


def _moves(v: NDArray, length: NDArray, cap: NDArray, a_up: NDArray, a_dn: NDArray):
    """Entry, peak, exit speed and time of every move from its boundary speeds."""
    v0, v1 = v[:-1], v[1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        peak2 = (2.0 * length + v0**2 / a_up + v1**2 / a_dn) / (1.0 / a_up + 1.0 / a_dn)
    peak = np.minimum(cap, np.sqrt(np.maximum(peak2, 0.0)))
    peak = np.maximum(peak, np.maximum(v0, v1))
    t_up = (peak - v0) / a_up
    t_dn = (peak - v1) / a_dn
    d_cr = np.maximum(length - (peak**2 - v0**2) / (2 * a_up) - (peak**2 - v1**2) / (2 * a_dn), 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_cr = np.where(peak > 0, d_cr / peak, 0.0)
    return v0, peak, v1, t_up + t_cr + t_dn, d_cr


def _ramp_changes(v0, peak, v1, d_cr, rising: bool) -> tuple[NDArray, NDArray]:
    """For each move, whether it has an acceleration (or braking) phase, and the whole speed
    change of the ramp that phase belongs to (chains of moves accelerating end to end)."""
    n = v0.size
    tol = 1e-9 * np.maximum(peak, 1.0)
    if rising:
        phase = peak > v0 + tol
        through = phase & ~(peak > v1 + tol) & (d_cr <= 1e-9)  # accelerating to its very end
        cont = np.zeros(n, dtype=bool)
        cont[1:] = through[:-1] & phase[1:]
    else:
        phase = peak > v1 + tol
        through = phase & ~(peak > v0 + tol) & (d_cr <= 1e-9)  # braking from its very start
        cont = np.zeros(n, dtype=bool)
        cont[1:] = through[1:] & phase[:-1]
        # a braking chain runs forward from its first move; "cont[k]" links k-1 -> k
    start = phase & ~cont
    cid = np.cumsum(start) - 1
    idx = np.flatnonzero(phase)
    if idx.size == 0:
        return phase, np.zeros(n)
    c = cid[idx]
    n_c = int(c.max()) + 1
    first = np.full(n_c, n, dtype=np.int64)
    last = np.full(n_c, -1, dtype=np.int64)
    np.minimum.at(first, c, idx)
    np.maximum.at(last, c, idx)
    if rising:
        lo = v0[first]
        hi = np.where(through[last], v1[last], peak[last])
    else:
        hi = np.where(through[first], v0[first], peak[first])
        lo = v1[last]
    dv = np.zeros(n)
    dv[idx] = (hi - lo)[c]
    return phase, dv


def build_profile(
    ev: Evaluation, *, rounds: int = JERK_ROUNDS, lookahead: int | None = None
) -> Profile:
    """The predicted feed profile of an evaluated tool path (see the module docstring).

    ``lookahead``: plan only that many blocks ahead -- the speed at every boundary must let
    the machine stop at the end of the blocks it sees (None: the whole program).
    """
    tp = ev.toolpath
    m = ev.machine
    cap = ev.element_feed.copy()
    rapid = ~tp.is_feed
    if rapid.any():
        cap[rapid] = m.rapid_speed(tp.tangent_start[rapid])
    acc, jerk = tangential_limits(tp, m.max_acceleration, m.max_jerk)
    b = boundary_caps(ev, cap)
    length = tp.length
    a_up, a_dn = acc.copy(), acc.copy()
    for r in range(max(rounds, 1)):
        v = _passes(_window_caps(b, length, a_dn, lookahead), length, a_up, a_dn)
        v0, peak, v1, time, d_cr = _moves(v, length, cap, a_up, a_dn)
        if r == rounds - 1 or not np.isfinite(jerk).any():
            break
        up, dv_up = _ramp_changes(v0, peak, v1, d_cr, rising=True)
        dn, dv_dn = _ramp_changes(v0, peak, v1, d_cr, rising=False)
        new_up = np.where(up, effective_acceleration(dv_up, acc, jerk), acc)
        new_dn = np.where(dn, effective_acceleration(dv_dn, acc, jerk), acc)
        with np.errstate(divide="ignore", invalid="ignore"):
            change = max(
                float(np.nanmax(np.abs(new_up / a_up - 1.0), initial=0.0)),
                float(np.nanmax(np.abs(new_dn / a_dn - 1.0), initial=0.0)),
            )
        a_up, a_dn = new_up, new_dn
        if change < JERK_CONVERGED:
            v = _passes(_window_caps(b, length, a_dn, lookahead), length, a_up, a_dn)
            v0, peak, v1, time, d_cr = _moves(v, length, cap, a_up, a_dn)
            break
    return Profile(
        evaluation=ev,
        cap=cap,
        v_entry=v0,
        v_peak=peak,
        v_exit=v1,
        a_up=a_up,
        a_down=a_dn,
        time=time,
    )
