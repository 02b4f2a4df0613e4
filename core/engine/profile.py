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
A_eff of the ramp's whole speed change, and solves again; a few rounds settle it (where a
move's A_eff turns back and forth between rounds, the geometric mean of the last two). The
ramps' times and lengths are those of S-curves, and so is the speed inside a ramp (in time
and along the path, :func:`s_curve`): at the same share of the ramp's time the S curve
is at its own speed and a little behind (accelerating) or ahead (braking) of the
trapezoid, both meeting at the ramp's ends. The normal acceleration that arcs already use is
not subtracted from the tangential budget.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from core.engine import rotary
from core.engine.indicators import Evaluation
from core.model.tolerances import SAMPLE_DT, TOL
from core.model.toolpath import PathMode, ToolPath

#: Most rounds of the jerk (effective acceleration) iteration, and when to stop early: the
#: effective accelerations fall monotonically (a lower A_eff gives lower peaks, hence smaller
#: speed changes, hence a lower A_eff), contracting by about 4 in log per round.
JERK_ROUNDS = 12
JERK_CONVERGED = 1e-4


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
    return np.where(np.isfinite(j) & (dv > TOL.nil_speed), out, a)


def s_curve(
    p: ArrayLike, dv: ArrayLike, acc: ArrayLike, jerk: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The S shape of a jerk-limited speed change, normalised.

    A change ``dv`` at acceleration ``acc`` and jerk ``jerk`` reaches the peak acceleration
    a_p = min(A, sqrt(dv J)) after t_j = a_p / J and lasts T = dv / a_p + t_j; its
    acceleration is a trapezoid in time whose ramps take r = t_j / T of it. At the share
    ``p`` of T, returns the share g of ``dv`` gained and G = integral_0^p g (1/2 at p = 1,
    as for the straight line g = p, G = p^2 / 2 of an infinite jerk: same duration and
    distance, only the shape differs).
    """
    shape = s_curve_shape(dv, acc, jerk)
    return s_curve_g(p, shape), s_curve_big_g(p, shape)


def s_curve_shape(dv: ArrayLike, acc: ArrayLike, jerk: ArrayLike) -> tuple[NDArray, ...]:
    """What :func:`s_curve` needs of a speed change that does not depend on ``p``: the ramp
    share r, 1 / (1 - r) and r kept off zero (computed once for the many ``p`` a bisection
    tries)."""
    dv = np.asarray(dv, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        a_p = np.minimum(acc, np.sqrt(dv * jerk))
        t_j = a_p / jerk
        total = dv / a_p + t_j
        r = np.where((dv > TOL.nil_speed) & np.isfinite(jerk) & (total > 0), t_j / total, 0.0)
    r = np.clip(np.nan_to_num(r), 0.0, 0.5)
    c = 1.0 / (1.0 - r)
    rs = np.maximum(r, TOL.tiny)
    return r, c, rs


def s_curve_g(p: ArrayLike, shape: tuple[NDArray, ...]) -> NDArray[np.float64]:
    """The share g of :func:`s_curve` at ``p`` for a :func:`s_curve_shape`."""
    r, c, rs = shape
    p = np.clip(np.asarray(p, dtype=np.float64), 0.0, 1.0)
    q = 1.0 - p
    first, last = p < r, p > 1.0 - r
    return np.where(
        first, c * p * p / (2 * rs), np.where(last, 1.0 - c * q * q / (2 * rs), c * (p - 0.5 * r))
    )


def s_curve_big_g(p: ArrayLike, shape: tuple[NDArray, ...]) -> NDArray[np.float64]:
    """The integral G of :func:`s_curve` at ``p`` for a :func:`s_curve_shape`."""
    r, c, rs = shape
    p = np.clip(np.asarray(p, dtype=np.float64), 0.0, 1.0)
    q = 1.0 - p
    first, last = p < r, p > 1.0 - r
    return np.where(
        first,
        c * p**3 / (6 * rs),
        np.where(
            last,
            0.5 - q + c * q**3 / (6 * rs),
            c * r * r / 6 + c * (0.5 * (p * p - r * r) - 0.5 * r * (p - r)),
        ),
    )


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
    hold_start, hold_end : (n,) float, mm
        Stretches at the start and end of each move run at its entry and exit speed: the
        inserted arc of a corner, the transition of a curvature jump.
    hold_start_ratio, hold_end_ratio : (n,) float
        Length actually run per mm of hold (the arc of a corner is shorter than its tangent
        stretches: (beta/2) / tan(beta/2)); 1 elsewhere.
    ramps : tuple of (n,) arrays, or None
        With a jerk limit: the lower speed and whole speed change of the acceleration ramp
        and of the braking ramp each move's phases belong to, and the move's tangential
        acceleration and jerk limits (the S shape of the speed inside ramps).
    pause : (n,) float, s, or None
        Time at rest after each move: its dwell and the rotary axes' own moves
        (:mod:`core.engine.rotary`); None: the dwells alone.
    lead : float, s
        Time at rest before the first move (rotary axes turning).
    """

    evaluation: Evaluation
    cap: NDArray[np.float64]
    v_entry: NDArray[np.float64]
    v_peak: NDArray[np.float64]
    v_exit: NDArray[np.float64]
    a_up: NDArray[np.float64]
    a_down: NDArray[np.float64]
    time: NDArray[np.float64]
    hold_start: NDArray[np.float64]
    hold_end: NDArray[np.float64]
    hold_start_ratio: NDArray[np.float64]
    hold_end_ratio: NDArray[np.float64]
    ramps: tuple[NDArray, ...] | None = None
    pause: NDArray[np.float64] | None = None
    lead: float = 0.0

    @property
    def toolpath(self) -> ToolPath:
        return self.evaluation.toolpath

    @property
    def rest(self) -> NDArray[np.float64]:
        """(n,) time at rest after each move (s): dwells, rotary-only moves."""
        return self.toolpath.dwell if self.pause is None else self.pause

    @cached_property
    def cycle_time(self) -> float:
        """Predicted cycle time: motion of every move plus the rests between (s)."""
        return float(self.lead + self.time.sum() + self.rest.sum())

    @cached_property
    def start_time(self) -> NDArray[np.float64]:
        """(n,) time at which each move starts (s)."""
        span = self.time + self.rest
        return self.lead + np.concatenate([[0.0], np.cumsum(span)[:-1]])

    @cached_property
    def phases(self) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray]:
        """(n,) arrays of each move's acceleration time, braking time (s), acceleration
        length, braking length and cruise length (mm), between its holds."""
        return self.phases_of(slice(None))

    def phases_of(
        self, k: NDArray[np.int64] | slice
    ) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray]:
        """:attr:`phases` of the moves ``k`` only (the same arithmetic, no (n,) arrays)."""
        v0, v1, vp = self.v_entry[k], self.v_exit[k], self.v_peak[k]
        au, ad = self.a_up[k], self.a_down[k]
        t_up = (vp - v0) / au
        t_dn = (vp - v1) / ad
        d_up = (vp**2 - v0**2) / (2 * au)
        d_dn = (vp**2 - v1**2) / (2 * ad)
        inner = self.toolpath.length[k] - self.hold_start[k] - self.hold_end[k]
        d_cr = np.maximum(inner - d_up - d_dn, 0.0)
        return t_up, t_dn, d_up, d_dn, d_cr

    @cached_property
    def hold_times(self) -> tuple[NDArray, NDArray]:
        """(n,) time (s) each move spends in its start hold and in its end hold."""
        return self.hold_times_of(slice(None))

    def hold_times_of(self, k: NDArray[np.int64] | slice) -> tuple[NDArray, NDArray]:
        """:attr:`hold_times` of the moves ``k`` only."""
        hs, he = self.hold_start[k], self.hold_end[k]
        with np.errstate(divide="ignore", invalid="ignore"):
            h0 = np.where(hs > 0, self.hold_start_ratio[k] * hs / self.v_entry[k], 0.0)
            h1 = np.where(he > 0, self.hold_end_ratio[k] * he / self.v_exit[k], 0.0)
        return np.nan_to_num(h0, posinf=0.0), np.nan_to_num(h1, posinf=0.0)

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
        if s.ndim != 1:
            return self.speed_at(s.reshape(-1)).reshape(s.shape)
        tp = self.toolpath
        k = tp.move_at(s)
        d = np.clip(s - tp.start_s[k], 0.0, tp.length[k])
        h0, h1 = self.hold_start[k], self.hold_end[k]
        into = np.maximum(d - h0, 0.0)
        up = np.sqrt(np.maximum(self.v_entry[k] ** 2 + 2 * self.a_up[k] * into, 0.0))
        rest = np.maximum(tp.length[k] - h1 - d, 0.0)
        down = np.sqrt(np.maximum(self.v_exit[k] ** 2 + 2 * self.a_down[k] * rest, 0.0))
        v = np.minimum(np.minimum(up, down), self.v_peak[k])
        if self.ramps is None:
            return v
        # Inside a jerk-limited ramp: the ramp's share p where the S curve is at this place
        # (bisection; the place moves monotonically with p), then its speed there.
        lo_u, dv_u, lo_d, dv_d, acc, jerk = self.ramps
        for rising in (True, False):
            if rising:
                sel = np.flatnonzero(
                    (up <= down) & (up < self.v_peak[k]) & (dv_u[k] > TOL.nil_speed)
                )
            else:
                sel = np.flatnonzero(
                    (down < up) & (down < self.v_peak[k]) & (dv_d[k] > TOL.nil_speed)
                )
            if sel.size == 0:
                continue
            kk = k[sel]
            lo, dv = (lo_u[kk], dv_u[kk]) if rising else (lo_d[kk], dv_d[kk])
            a = self.a_up[kk] if rising else self.a_down[kk]
            vb = self.v_entry[kk] if rising else self.v_exit[kk]
            target = into[sel] if rising else rest[sel]
            span = dv * dv / a  # dv * T, T = dv / a the ramp's duration
            shape = s_curve_shape(dv, acc[kk], jerk[kk])  # once, not per bisection step
            vb2 = vb * vb

            def place(p, lo=lo, dv=dv, a=a, vb2=vb2, span=span, shape=shape, rising=rising):
                vt = lo + p * dv if rising else lo + (1.0 - p) * dv
                big_g = s_curve_big_g(p, shape)
                x = (vt * vt - vb2) / (2 * a) + span * (big_g - 0.5 * p * p)
                return x if rising else -x  # increasing in p either way

            a_p, b_p = np.zeros(sel.size), np.ones(sel.size)
            goal = target if rising else -target
            for _ in range(26):  # p to 1.5e-8 of the ramp
                mid = 0.5 * (a_p + b_p)
                below = place(mid) < goal
                a_p = np.where(below, mid, a_p)
                b_p = np.where(below, b_p, mid)
            g_share = s_curve_g(0.5 * (a_p + b_p), shape)
            v[sel] = lo + dv * g_share if rising else lo + dv * (1.0 - g_share)
        return v

    def n_samples(self, dt: float = SAMPLE_DT) -> int:
        """How many samples :meth:`sample` gives every ``dt`` seconds (both ends included)."""
        if not (dt > 0 and math.isfinite(dt)):
            raise ValueError(f"dt must be positive and finite, got {dt}")
        return int(math.floor(self.cycle_time / dt + TOL.rel_equal)) + 1

    def sample(self, dt: float = SAMPLE_DT, *, first: int = 0, count: int | None = None) -> Samples:
        """The profile every ``dt`` seconds from 0 to the cycle time (both ends included);
        with ``first`` and ``count``, only samples ``first`` to ``first + count - 1`` of
        them (a long profile is written in pieces of bounded memory)."""
        n_all = self.n_samples(dt)
        stop = n_all if count is None else min(n_all, first + count)
        tp = self.toolpath
        t = np.arange(first, max(stop, first), dtype=np.float64) * dt
        k = np.clip(np.searchsorted(self.start_time, t, side="right") - 1, 0, tp.n - 1)
        tau = t - self.start_time[k]
        t_up, t_dn, d_up, d_dn, d_cr = self.phases
        th0, th1 = self.hold_times
        v0, vp, ad, au = self.v_entry[k], self.v_peak[k], self.a_down[k], self.a_up[k]
        v1 = self.v_exit[k]
        tu, tdn, du = t_up[k], t_dn[k], d_up[k]
        h0, t0 = self.hold_start[k], th0[k]
        with np.errstate(divide="ignore", invalid="ignore"):
            t_cr = np.where(vp > 0, d_cr[k] / vp, 0.0)
        # Phases: hold at v0, accelerate, cruise, brake, hold at v1 (then any dwell).
        tau = np.minimum(tau, t0 + tu + t_cr + tdn + th1[k])
        in_h0 = tau < t0
        tr = np.maximum(tau - t0, 0.0)
        in_up = ~in_h0 & (tr < tu)
        in_cr = ~in_h0 & ~in_up & (tr < tu + t_cr)
        in_dn = ~in_h0 & ~in_up & ~in_cr & (tr < tu + t_cr + tdn)
        td = np.clip(tr - tu - t_cr, 0.0, tdn)
        th = np.maximum(tr - tu - t_cr - tdn, 0.0)
        d_ramps = np.where(
            in_up,
            v0 * tr + 0.5 * au * tr**2,
            np.where(in_cr, du + vp * (tr - tu), du + d_cr[k] + vp * td - 0.5 * ad * td**2),
        )
        # In a hold the tool runs r mm per mm of programmed path (the corner's arc).
        r0, r1 = self.hold_start_ratio[k], self.hold_end_ratio[k]
        with np.errstate(divide="ignore", invalid="ignore"):
            in_hold0 = np.where(r0 > 0, v0 * tau / r0, h0)
            in_hold1 = np.where(r1 > 0, v1 * th / r1, self.hold_end[k])
        d = np.where(
            in_h0, in_hold0, h0 + d_ramps + np.where(in_h0 | in_up | in_cr | in_dn, 0.0, in_hold1)
        )
        v = np.where(
            in_h0,
            v0,
            np.where(in_up, v0 + au * tr, np.where(in_cr, vp, np.where(in_dn, vp - ad * td, v1))),
        )
        d = np.clip(d, 0.0, tp.length[k])
        if self.ramps is not None:
            # Inside jerk-limited ramps: the S curve at the same share of the ramp's time;
            # it covers a little less (accelerating) or more (braking) than the straight
            # line until the ramp's end, where both meet.
            lo_u, dv_u, lo_d, dv_d, acc, jerk = (r[k] for r in self.ramps)
            shift = np.zeros(t.size)
            for rising in (True, False):
                sel = np.flatnonzero(
                    (in_up & (dv_u > TOL.nil_speed)) if rising else (in_dn & (dv_d > TOL.nil_speed))
                )
                if sel.size == 0:
                    continue
                lo, dv = (lo_u[sel], dv_u[sel]) if rising else (lo_d[sel], dv_d[sel])
                a = au[sel] if rising else ad[sel]
                p = (v[sel] - lo) / dv if rising else (lo + dv - v[sel]) / dv
                p = np.clip(p, 0.0, 1.0)
                g_share, big_g = s_curve(p, dv, acc[sel], jerk[sel])
                sign = 1.0 if rising else -1.0
                shift[sel] = sign * (dv * dv / a) * (big_g - 0.5 * p * p)
                v[sel] = lo + dv * g_share if rising else lo + dv * (1.0 - g_share)
            s_abs = tp.start_s[k] + d + shift
            k = tp.move_at(s_abs)
            d = np.clip(s_abs - tp.start_s[k], 0.0, tp.length[k])
        pts = tp.points_along(k, d)
        return Samples(
            t=t,
            s=tp.start_s[k] + d,
            x=pts[:, 0],
            y=pts[:, 1],
            z=pts[:, 2],
            v=np.maximum(v, 0.0),
            line=tp.line[k],
        )


def boundary_caps(
    ev: Evaluation, cap: NDArray[np.float64], rest: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """(n + 1,) speed cap at every move boundary (mm/s).

    0 at the program's ends and wherever the chain breaks: exact stops (G61/G60/G9, M0/M1),
    dwells and other rests (``rest``, s, after each move: rotary-only moves), rapid <-> feed
    and rapid <-> rapid changes, operation changes. Elsewhere the lower of the two moves'
    caps and the junction's predicted feed.
    """
    tp = ev.toolpath
    n = tp.n
    b = np.zeros(n + 1)
    if n < 2:
        return b
    inner = np.minimum(cap[:-1], cap[1:])
    joined = np.zeros(n - 1, dtype=bool)
    joined[tp.junctions] = True  # feed -> feed within one operation
    rest = tp.dwell if rest is None else rest
    stop = (tp.path_mode[:-1] == PathMode.EXACT_STOP) | (rest[:-1] > 0)
    inner = np.where(joined & ~stop, inner, 0.0)
    inner[ev.junction] = np.minimum(inner[ev.junction], ev.junction_feed)
    b[1:-1] = inner
    return b


def _holds(ev: Evaluation) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """(n,) hold lengths at the start and end of every move (mm of programmed path), from the
    junctions' ``hold_mm``, at most half of each move; and the length actually run per mm of
    hold (``travel_mm / hold_mm``: below 1 where the tool cuts a corner on its arc)."""
    tp = ev.toolpath
    h_start = np.zeros(tp.n)
    h_end = np.zeros(tp.n)
    r_start = np.ones(tp.n)
    r_end = np.ones(tp.n)
    h = np.nan_to_num(ev.junction_hold, nan=0.0, posinf=0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(h > 0, ev.junction_travel / h, 1.0)
    ratio = np.clip(np.nan_to_num(ratio, nan=1.0), 0.0, 1.0)
    h_end[ev.junction] = h
    h_start[ev.junction + 1] = h
    r_end[ev.junction] = ratio
    r_start[ev.junction + 1] = ratio
    half = 0.5 * tp.length
    return np.minimum(h_start, half), np.minimum(h_end, half), r_start, r_end


def _passes(b: NDArray, inner: NDArray, a_up: NDArray, a_dn: NDArray) -> NDArray:
    """Boundary speeds (n + 1,) from the forward and backward passes (see module docstring).

    The machine changes speed only between the holds at the ends of each move (the inserted
    arc of a corner, a curvature transition): the passes use the length left between them,
    ``inner`` = max(length - holds, 0). At a boundary whose cap does not bind, the hold then
    runs at the boundary's speed, which is slightly conservative. (Written with ``out=``:
    the same operations in the same order, without a temporary per step.)
    """
    n1 = b.size
    b2 = b * b
    w = np.empty(n1)
    w[0] = 0.0
    tmp = np.multiply(a_up, inner)
    tmp *= 2.0
    np.cumsum(tmp, out=w[1:])
    fwd = np.subtract(b2, w)
    np.minimum.accumulate(fwd, out=fwd)
    fwd += w
    np.multiply(a_dn, inner, out=tmp)
    tmp *= 2.0
    np.cumsum(tmp, out=w[1:])
    bwd = np.add(b2, w)
    rev = bwd[::-1]
    np.minimum.accumulate(rev, out=rev)
    bwd -= w
    np.minimum(fwd, bwd, out=fwd)
    np.minimum(fwd, b2, out=fwd)
    np.maximum(fwd, 0.0, out=fwd)
    return np.sqrt(fwd, out=fwd)


def stop_speed(dist: ArrayLike, acc: ArrayLike, jerk: ArrayLike) -> NDArray[np.float64]:
    """The highest speed (mm/s) from which a jerk-limited stop takes at most ``dist`` mm.

    A stop from v takes v T / 2 with T = 2 sqrt(v / J) while v < A^2 / J, so
    v = (d^2 J)^(1/3); beyond, T = v / A + A / J and v^2 / A + v A / J = 2 d gives
    v = (A / 2) (sqrt(A^2 / J^2 + 8 d / A) - A / J); sqrt(2 A d) without a jerk limit.
    """
    d = np.maximum(np.asarray(dist, dtype=np.float64), 0.0)
    a = np.asarray(acc, dtype=np.float64)
    j = np.asarray(jerk, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        short = np.cbrt(d * d * j)
        r = a / j
        long = 0.5 * a * (np.sqrt(r * r + 8.0 * d / a) - r)
        v = np.where(short <= a * r, short, long)
    return np.where(np.isfinite(j), v, np.sqrt(2.0 * a * d))


def _window_caps(
    b: NDArray, length: NDArray, acc: NDArray, jerk: NDArray, lookahead: int | None
) -> NDArray:
    """Boundary caps of a planner that sees ``lookahead`` blocks: from every boundary it must
    be able to stop, jerk-limited, by the end of the blocks it sees (at the limits of the
    first of them)."""
    n = length.size
    if lookahead is None or lookahead >= n:
        return b
    s = np.concatenate([[0.0], np.cumsum(length)])
    ahead = np.minimum(np.arange(n + 1) + int(lookahead), n)
    k = np.minimum(np.arange(n + 1), n - 1)
    return np.minimum(b, stop_speed(s[ahead] - s, acc[k], jerk[k]))


class _Holds:
    """The holds of every move, what the rounds of :func:`build_profile` reuse: the length
    left between them (``between``, may be < 0; ``inner`` = max(between, 0)) and where they
    are (most moves have none: their hold time is computed where they are only)."""

    def __init__(self, length, h_start, h_end, r_start, r_end) -> None:
        self.between = length - h_start - h_end
        self.inner = np.maximum(self.between, 0.0)
        self.at_start = np.flatnonzero(h_start > 0)
        self.at_end = np.flatnonzero(h_end > 0)
        self.run_start = (r_start * h_start)[self.at_start]
        self.run_end = (r_end * h_end)[self.at_end]

    def time(self, v0: NDArray, v1: NDArray) -> NDArray:
        """(n,) time of the holds at entry speed ``v0`` and exit speed ``v1`` (0 where a
        hold would run at speed 0: a stop there is the ramps' business)."""
        t = np.zeros(v0.size)
        with np.errstate(divide="ignore", invalid="ignore"):
            ts = self.run_start / v0[self.at_start]
            te = self.run_end / v1[self.at_end]
        # run >= 0 and v >= 0: a quotient is finite, +inf (v = 0) or NaN (0 / 0), both 0
        ts[~(ts < np.inf)] = 0.0
        te[~(te < np.inf)] = 0.0
        t[self.at_start] = ts
        t[self.at_end] += te
        return t


def _moves(v: NDArray, cap: NDArray, a_up: NDArray, a_dn: NDArray, holds: _Holds):
    """Entry, peak, exit speed and time of every move from its boundary speeds; the holds
    at its ends run at the entry and exit speed (over ``r * h`` of actual travel).
    (Written with ``out=``: the same operations in the same order, fewer temporaries.)"""
    v0, v1 = v[:-1], v[1:]
    t_hold = holds.time(v0, v1)
    length = holds.between
    v0sq = v0 * v0  # v**2 of a float64 array is v * v
    v1sq = v1 * v1
    with np.errstate(divide="ignore", invalid="ignore"):
        # peak2 = (2 L + v0^2 / a_up + v1^2 / a_dn) / (1 / a_up + 1 / a_dn)
        peak = 2.0 * length
        peak += v0sq / a_up
        peak += v1sq / a_dn
        den = 1.0 / a_up
        den += 1.0 / a_dn
        peak /= den
        del den  # (each temporary goes once spent: 1M moves, the profile's peak)
    np.maximum(peak, 0.0, out=peak)
    np.sqrt(peak, out=peak)
    np.minimum(cap, peak, out=peak)
    np.maximum(peak, np.maximum(v0, v1), out=peak)
    t = peak - v0
    t /= a_up  # t_up
    t_dn = peak - v1
    t_dn /= a_dn
    pk2 = peak * peak
    # d_cr = max(L - (peak^2 - v0^2) / (2 a_up) - (peak^2 - v1^2) / (2 a_dn), 0)
    up = pk2 - v0sq
    del v0sq
    up /= 2 * a_up
    d_cr = length - up
    np.subtract(pk2, v1sq, out=up)
    del pk2, v1sq
    up /= 2 * a_dn
    d_cr -= up
    del up
    np.maximum(d_cr, 0.0, out=d_cr)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_cr = np.where(peak > 0, d_cr / peak, 0.0)
    t += t_cr
    del t_cr
    t += t_dn
    t += t_hold
    return v0, peak, v1, t, d_cr


def _ramp_changes(v0, peak, v1, d_cr, rising: bool) -> tuple[NDArray, NDArray, NDArray]:
    """For each move, whether it has an acceleration (or braking) phase, the whole speed
    change of the ramp that phase belongs to (chains of moves accelerating end to end), and
    the ramp's lower speed (where an acceleration starts, where a braking ends)."""
    n = v0.size
    tol = TOL.rel_equal * np.maximum(peak, 1.0)
    if rising:
        phase = peak > v0 + tol
        through = (
            phase & ~(peak > v1 + tol) & (d_cr <= TOL.nil_distance)
        )  # accelerating to its very end
        cont = np.zeros(n, dtype=bool)
        cont[1:] = through[:-1] & phase[1:]
    else:
        phase = peak > v1 + tol
        through = (
            phase & ~(peak > v0 + tol) & (d_cr <= TOL.nil_distance)
        )  # braking from its very start
        cont = np.zeros(n, dtype=bool)
        cont[1:] = through[1:] & phase[:-1]
        # a braking chain runs forward from its first move; "cont[k]" links k-1 -> k
    del tol  # (each temporary goes once spent: this is the profile's peak)
    start = phase & ~cont
    cid = np.cumsum(start)
    cid -= 1
    idx = np.flatnonzero(phase)
    if idx.size == 0:
        return phase, np.zeros(n), np.zeros(n)
    c = cid[idx]  # non-decreasing; every chain has its start move in ``idx``
    del cid
    edge = c[1:] != c[:-1]
    first = idx[np.concatenate([[True], edge])]
    last = idx[np.concatenate([edge, [True]])]
    if rising:
        lo = v0[first]
        hi = np.where(through[last], v1[last], peak[last])
    else:
        hi = np.where(through[first], v0[first], peak[first])
        lo = v1[last]
    dv = np.zeros(n)
    dv[idx] = (hi - lo)[c]
    low = np.zeros(n)
    low[idx] = lo[c]
    return phase, dv, low


def _ramp_acceleration(phase: NDArray, dv: NDArray, acc: NDArray, jerk: NDArray) -> NDArray:
    """``acc`` with the effective acceleration of its ramp on every move in a ramp phase
    (computed on those moves only: on long programs most moves cruise)."""
    out = acc.copy()
    idx = np.flatnonzero(phase)
    out[idx] = effective_acceleration(dv[idx], acc[idx], jerk[idx])
    return out


def _damped(a: NDArray, new: NDArray, last: NDArray) -> tuple[NDArray, NDArray]:
    """The next accelerations of the jerk iteration, and the sign of each step (-1, 0, 1):
    the geometric mean of ``a`` and ``new`` where the step reverses the last one."""
    step = np.sign(new - a)
    back = step * last < 0
    out = np.where(back, np.sqrt(a * new), new)
    return out, np.sign(out - a).astype(np.int8)  # -1, 0, 1: one byte a move


def build_profile(
    ev: Evaluation,
    *,
    rounds: int = JERK_ROUNDS,
    lookahead: int | None = None,
    end_factor: float = 1.0,
    arc_factor: float = 1.0,
    release_directions: bool = False,
) -> Profile:
    """The predicted feed profile of an evaluated tool path (see the module docstring).

    Parameters
    ----------
    lookahead : int, optional
        Plan only that many blocks ahead: the speed at every boundary must let the machine
        stop at the end of the blocks it sees (None: the whole program).
    end_factor : float
        Share of the tangential acceleration used on the program's last block.
    arc_factor : float
        Share of the tangential acceleration used on programmed arcs.
    release_directions : bool
        Forget the tool path's direction columns once read (:meth:`ToolPath.release_derived`;
        recomputed if asked for again): for a single analysis, 48 bytes a move off the
        peak; not for fits that build many profiles of one path.
    """
    tp = ev.toolpath
    m = ev.machine
    cap = ev.element_feed.copy()
    rapid = ~tp.is_feed
    if rapid.any():
        cap[rapid] = m.rapid_speed(tp.tangent_start[rapid])
    acc, jerk = tangential_limits(tp, m.max_acceleration, m.max_jerk)
    pause: NDArray[np.float64] | None = None
    lead = 0.0
    if tp.rotary is not None or tp.rotary_only is not None:
        _, acc_rot, jerk_rot = rotary.path_caps(tp, m)
        acc, jerk = np.minimum(acc, acc_rot), np.minimum(jerk, jerk_rot)
        turning, lead = rotary.pauses(tp, m)
        pause = tp.dwell + turning
    if arc_factor != 1.0:
        acc = np.where(tp.is_arc, acc * arc_factor, acc)
    if end_factor != 1.0 and tp.n:
        acc[-1] *= end_factor
    if release_directions:
        tp.release_derived()
    b = boundary_caps(ev, cap, pause)
    length = tp.length
    h_start, h_end, r_start, r_end = _holds(ev)
    holds = _Holds(length, h_start, h_end, r_start, r_end)
    caps = _window_caps(b, length, acc, jerk, lookahead)  # the same in every round
    a_up, a_dn = acc.copy(), acc.copy()
    step_up = np.zeros(tp.n, dtype=np.int8)
    step_dn = np.zeros(tp.n, dtype=np.int8)
    for r in range(max(rounds, 1)):
        v = _passes(caps, holds.inner, a_up, a_dn)
        v0, peak, v1, time, d_cr = _moves(v, cap, a_up, a_dn, holds)
        if r == rounds - 1 or not np.isfinite(jerk).any():
            break
        del time  # (not this round's result: the next round makes its own)
        up, dv_up, _ = _ramp_changes(v0, peak, v1, d_cr, rising=True)
        dn, dv_dn, _ = _ramp_changes(v0, peak, v1, d_cr, rising=False)
        # This round's speeds are spent: free them before the next round makes its own
        # (1M moves: 40 MB off the profile's peak).
        del v, v0, peak, v1, d_cr
        new_up = _ramp_acceleration(up, dv_up, acc, jerk)
        new_dn = _ramp_acceleration(dn, dv_dn, acc, jerk)
        del up, dv_up, dn, dv_dn
        # Where a move's A_eff turns back (a staircase of falling caps: small steps give a low
        # A_eff, which holds the speed under the caps, which gives one long ramp and a high
        # A_eff, ...), take the geometric mean of the last two: the rounds then close in on
        # the answer between the two states instead of alternating.
        new_up, step_up = _damped(a_up, new_up, step_up)
        new_dn, step_dn = _damped(a_dn, new_dn, step_dn)
        with np.errstate(divide="ignore", invalid="ignore"):
            change = max(
                float(np.nanmax(np.abs(new_up / a_up - 1.0), initial=0.0)),
                float(np.nanmax(np.abs(new_dn / a_dn - 1.0), initial=0.0)),
            )
        a_up, a_dn = new_up, new_dn
        if change < JERK_CONVERGED:
            v = _passes(caps, holds.inner, a_up, a_dn)
            v0, peak, v1, time, d_cr = _moves(v, cap, a_up, a_dn, holds)
            break
    if np.isfinite(jerk).any():
        _, dv_up, lo_up = _ramp_changes(v0, peak, v1, d_cr, rising=True)
        _, dv_dn, lo_dn = _ramp_changes(v0, peak, v1, d_cr, rising=False)
        ramps = (lo_up, dv_up, lo_dn, dv_dn, acc, jerk)
    else:
        ramps = None
    return Profile(
        evaluation=ev,
        cap=cap,
        v_entry=v0,
        v_peak=peak,
        v_exit=v1,
        a_up=a_up,
        a_down=a_dn,
        time=time,
        hold_start=h_start,
        hold_end=h_end,
        hold_start_ratio=r_start,
        hold_end_ratio=r_end,
        ramps=ramps,
        pause=pause,
        lead=lead,
    )
