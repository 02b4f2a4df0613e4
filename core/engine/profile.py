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
from core.engine.indicators import LCNC_TANGENTIAL_RATIO, Evaluation
from core.engine.lookahead import lazy_caps
from core.model.arrays import isin, nan_to_num, put_where, same_bits, select
from core.model.heap import release_free_heap
from core.model.jit import compiled
from core.model.native import kernels as round_kernels
from core.model.pieces import PIECE, SPLIT, pieces, piecewise, side_by_side, two_cores
from core.model.tolerances import SAMPLE_DT, TOL
from core.model.toolpath import PathMode, ToolPath

#: Most rounds of the jerk (effective acceleration) iteration, and when to stop early: the
#: effective accelerations fall monotonically (a lower A_eff gives lower peaks, hence smaller
#: speed changes, hence a lower A_eff), contracting by about 4 in log per round.
JERK_ROUNDS = 12
JERK_CONVERGED = 1e-4
#: Moves per piece of a round's elementwise work: its temporaries stay in the cache.
CACHE_PIECE = 1 << 14
#: A round finds the ramps again only around the moves whose marks changed when those are
#: at most 1 / LOCAL_SHARE of the moves, and the ramps through them at most 1 / LOCAL_REACH
#: (else over all of them: the same values).
LOCAL_SHARE = 32
LOCAL_REACH = 8
#: Most moves a ramp chain's ends are searched at a time (from 2, doubling).
CHAIN_WINDOW = 64
#: A round's direction works over whole columns (:meth:`_Rounds._dense`) where more than
#: 1 / DENSE_SHARE of the moves are in a ramp phase and the ramps are found everywhere.
DENSE_SHARE = 4


def effective_acceleration(
    dv: ArrayLike, acc: ArrayLike, jerk: ArrayLike, only: NDArray[np.bool_] | None = None
) -> NDArray[np.float64]:
    """A_eff = dv / T of S-curve speed changes (mm/s^2).

    Parameters
    ----------
    dv : (m,) float, mm/s
        Speed change of the ramp (>= 0).
    acc, jerk : (m,) float
        Tangential acceleration (mm/s^2) and jerk (mm/s^3, may be inf).
    only : (m,) bool, optional
        The changes that are ramps: ``acc`` elsewhere, put with the other moves that keep
        it (the rounds' targets in one pass).

    Returns
    -------
    (m,) float, mm/s^2
        ``acc`` where the jerk is infinite or the change is nil (or not ``only``).
    """
    dv = np.asarray(dv, dtype=np.float64)
    a = np.asarray(acc, dtype=np.float64)
    j = np.asarray(jerk, dtype=np.float64)
    if not (dv.ndim and dv.shape == a.shape == j.shape):
        with np.errstate(divide="ignore", invalid="ignore"):
            t_full = dv / a + a / j
            t_short = 2.0 * np.sqrt(dv / j)
            t = np.where(dv >= a * a / j, t_full, t_short)
            out = dv / t
        keep = np.isfinite(j) & (dv > TOL.nil_speed)
        return np.where(keep if only is None else keep & only, out, a)
    # Columns of one shape (the rounds'): the same operations in the same order, written
    # over their temporaries.
    with np.errstate(divide="ignore", invalid="ignore"):
        t_full = dv / a
        tmp = a / j
        t_full += tmp  # dv / a + a / j
        t_short = np.divide(dv, j, out=tmp)
        np.sqrt(t_short, out=t_short)
        t_short *= 2.0  # 2 sqrt(dv / j)
        lim = a * a
        lim /= j
        t = select(dv >= lim, t_full, t_short)  # t_full where dv >= A^2 / J
        del t_full, t_short, lim
        np.divide(dv, t, out=t)
        keep = np.isfinite(j)
        keep &= dv > TOL.nil_speed
        if only is not None:
            keep &= only
        put_where(t, a, ~keep)
    return t


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


#: Halvings of :func:`_bisect_ramp`: the share p of a ramp to 2^-26 (1.5e-8) of it.
HALVINGS = 26
#: Where the guess's last bracket cannot be told for certain, the bracket HALFWAY halvings
#: in is checked, and where it can, the halvings start from there.
HALFWAY = 13
#: Newton steps of the guess :func:`_bisect_ramp` checks before it bisects: from the
#: trapezoid ramp's place (off by ~1e-2 of the ramp), three leave 8 % of the places of the
#: diagnose benchmark (a jerk-limited machine) to the halvings -- half of them on ramps of
#: ~1e-5 mm/s, whose place is rounding noise -- four 5 %, for more work than they save.
NEWTON_STEPS = 3


#: :meth:`Profile.speed_at`'s ramps for the compiled kernel where there are none.
_NO_RAMPS = tuple(np.empty(0) for _ in range(6))


def _place_terms(
    lo: NDArray, dv: NDArray, a: NDArray, vb2: NDArray, span: NDArray, shape: tuple[NDArray, ...]
) -> tuple[NDArray, ...]:
    """What :func:`_place` needs of a ramp that does not change with p (computed once)."""
    r, c, rs = shape
    return (lo, dv, 2 * a, vb2, span, r, c, 6 * rs, c * r * r / 6, r * r, 0.5 * r, 1.0 - r)


def _place(
    p: NDArray, terms: tuple[NDArray, ...], rising: bool, out: tuple[NDArray, ...]
) -> NDArray:
    """x(p) of :func:`_bisect_ramp` (negated braking) into ``out[0]`` (``out``: four
    (m,) work arrays): the same operations on every element as evaluating the formula
    array-wide, each branch of G only where it applies."""
    lo, dv, two_a, vb2, span, r, c, six_rs, inner0, rr, half_r, one_r = terms
    x, pp, big_g, t = out
    # x = (v^2 - vb2) / (2 a), v = lo + p dv (rising) or lo + (1 - p) dv
    if rising:
        np.multiply(p, dv, out=x)
    else:
        np.subtract(1.0, p, out=x)
        np.multiply(x, dv, out=x)
    np.add(lo, x, out=x)
    np.multiply(x, x, out=x)
    np.subtract(x, vb2, out=x)
    np.divide(x, two_a, out=x)
    # G: the middle branch everywhere, then the ends of the ramp where p is in them
    np.multiply(p, p, out=pp)
    np.subtract(pp, rr, out=big_g)
    np.multiply(big_g, 0.5, out=big_g)
    np.subtract(p, r, out=t)
    np.multiply(half_r, t, out=t)
    np.subtract(big_g, t, out=big_g)
    np.multiply(c, big_g, out=big_g)
    np.add(inner0, big_g, out=big_g)
    first = p < r
    i = np.flatnonzero(first)
    if i.size:
        big_g[i] = c[i] * p[i] ** 3 / six_rs[i]
    i = np.flatnonzero(~first & (p > one_r))
    if i.size:
        qi = 1.0 - p[i]
        big_g[i] = 0.5 - qi + c[i] * qi**3 / six_rs[i]
    # x += span (G - p^2 / 2)   (0.5 p p: exactly half of p p)
    np.multiply(pp, 0.5, out=pp)
    np.subtract(big_g, pp, out=big_g)
    np.multiply(span, big_g, out=big_g)
    np.add(x, big_g, out=x)
    if not rising:
        np.negative(x, out=x)
    return x


def _bisect_ramp(
    lo: NDArray,
    dv: NDArray,
    a: NDArray,
    vb2: NDArray,
    span: NDArray,
    shape: tuple[NDArray, ...],
    goal: NDArray,
    rising: bool,
) -> tuple[NDArray, NDArray]:
    """The bracket (a_p, b_p) of the share p of a jerk-limited ramp where it is at the place
    ``goal`` (:meth:`Profile.speed_at`): HALVINGS halvings of where

        x(p) = (v(p)^2 - vb2) / (2 a) + span (G(p) - p^2 / 2),  v(p) = lo + p dv rising,
        lo + (1 - p) dv braking (x negated), G = :func:`s_curve_big_g`,

    is below ``goal`` (:func:`_place`). The bracket the halvings end in is found without
    them where it can be told for certain (:func:`_checked_guess`), the others bisected."""
    terms = _place_terms(lo, dv, a, vb2, span, shape)
    a_p, b_p, ok = _checked_guess(terms, shape, goal, rising)
    todo = np.flatnonzero(~ok)
    if todo.size == 0:
        return a_p, b_p
    # The others: the bracket the halvings pass through HALFWAY halvings in is the guess's
    # where that can be told for certain (as :func:`_checked_guess` tells the last one's),
    # else made by them from (0, 1); the rest of the halvings from there.
    sub = tuple(x[todo] for x in terms)
    goal = goal[todo]
    part = float(1 << HALFWAY)
    a_h = np.floor(a_p[todo] * part) / part
    b_h = a_h + 1.0 / part
    unsure = np.flatnonzero(~_sure(sub, goal, a_h, b_h, rising))
    if unsure.size:
        a_h[unsure], b_h[unsure] = _halvings(
            tuple(x[unsure] for x in sub), goal[unsure], rising, None, HALFWAY
        )
    a_p[todo], b_p[todo] = _halvings(sub, goal, rising, (a_h, b_h), HALVINGS - HALFWAY)
    return a_p, b_p


def _halvings(
    terms: tuple[NDArray, ...],
    goal: NDArray,
    rising: bool,
    ends: tuple[NDArray, NDArray] | None = None,
    count: int = HALVINGS,
) -> tuple[NDArray, NDArray]:
    """The bisection of :func:`_bisect_ramp`: ``count`` halvings of the brackets ``ends``
    (in place; default: HALVINGS halvings from (0, 1))."""
    n = goal.size
    a_p, b_p = (np.zeros(n), np.ones(n)) if ends is None else ends
    p = np.empty(n)
    work = tuple(np.empty(n) for _ in range(4))
    below = np.empty(n, dtype=bool)
    for _ in range(count):
        np.add(a_p, b_p, out=p)
        np.multiply(p, 0.5, out=p)
        x = _place(p, terms, rising, work)
        np.less(x, goal, out=below)
        np.copyto(a_p, p, where=below)
        np.logical_not(below, out=below)
        np.copyto(b_p, p, where=below)
    return a_p, b_p


def _checked_guess(
    terms: tuple[NDArray, ...], shape: tuple[NDArray, ...], goal: NDArray, rising: bool
) -> tuple[NDArray, NDArray, NDArray]:
    """The bracket the halvings of :func:`_bisect_ramp` end in, where a guess can be
    checked to be it, and which are (a_p, b_p, ok).

    The place x(p) of the formula, computed exactly, does not decrease with p (its
    derivative is dv / a times the S curve's speed, >= 0 for lo >= 0, dv >= 0, a > 0); the
    computed one is within E of it (E: the rounding of its ~30 operations, ~30 ulps of the
    terms' size T = ((lo + dv)^2 + vb2) / (2 a) + |span|). So where a bracket (a, b) of the
    last halving has x(a) < goal - 2 E and x(b) >= goal + 2 E as computed, every halving
    point at or left of a is below the goal and every one at or right of b is not: the
    halvings take the same steps to it. The guess: the trapezoid ramp's place, then
    NEWTON_STEPS Newton steps on x(p) = goal; the margin TOL.sure_compare x T (far above
    2 E). Where a check fails (the goal within the margin of a bracket's end, a guess off,
    or values not finite), ok is False and the caller bisects."""
    lo, dv, two_a, vb2, span = terms[:5]
    n = goal.size
    work = tuple(np.empty(n) for _ in range(4))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        dist = goal if rising else -goal
        u = (np.sqrt(np.maximum(vb2 + two_a * dist, 0.0)) - lo) / dv  # trapezoid
        p = np.clip(np.nan_to_num(u if rising else 1.0 - u), 0.0, 1.0)
        rate = dv / (0.5 * two_a)  # dx/dp = rate x (the S curve's speed)
        for _ in range(NEWTON_STEPS):
            g = s_curve_g(p, shape)
            speed = lo + dv * (g if rising else 1.0 - g)
            step = (_place(p, terms, rising, work) - goal) / (rate * speed)
            p = np.clip(np.nan_to_num(p - step), 0.0, 1.0)
        full = float(1 << HALVINGS)
        a_p = np.minimum(np.floor(p * full), full - 1.0) / full
        b_p = a_p + 1.0 / full
    return a_p, b_p, _sure(terms, goal, a_p, b_p, rising, work)


def _sure(
    terms: tuple[NDArray, ...],
    goal: NDArray,
    a_p: NDArray,
    b_p: NDArray,
    rising: bool,
    work: tuple[NDArray, ...] | None = None,
) -> NDArray[np.bool_]:
    """Where the halvings of :func:`_bisect_ramp` certainly pass through the bracket
    (``a_p``, ``b_p``) of one of them (see :func:`_checked_guess`): x(a_p) < goal - margin
    (or a_p = 0) and x(b_p) >= goal + margin (or b_p = 1)."""
    lo, dv, two_a, vb2, span = terms[:5]
    if work is None:
        work = tuple(np.empty(goal.size) for _ in range(4))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        margin = TOL.sure_compare * (((lo + dv) ** 2 + vb2) / two_a + np.abs(span))
        sane = (two_a > 0) & (lo >= 0) & (dv >= 0) & np.isfinite(margin)
        ok = sane & ((a_p == 0.0) | (_place(a_p, terms, rising, work) < goal - margin))
        ok &= (b_p == 1.0) | (_place(b_p, terms, rising, work) >= goal + margin)
    return ok


def tangential_limits(tp: ToolPath, acc: ArrayLike, jerk: ArrayLike) -> tuple[NDArray, NDArray]:
    """(n,) tangential acceleration and jerk of each move: min_k limit_k / share_k."""
    share = tp.axis_share
    acc = np.asarray(acc, dtype=np.float64)
    jerk = np.asarray(jerk, dtype=np.float64)
    # axis by axis (the minimum is exact, so the same values as over the (n, 3) array at
    # once, without its temporaries and its slow row-wise minimum)
    acc = np.broadcast_to(acc, share.shape[1:])  # (the shapes the (n, 3) way allowed)
    jerk = np.broadcast_to(jerk, share.shape[1:])
    a = np.full(share.shape[0], np.inf)
    j = np.full(share.shape[0], np.inf)
    # (in pieces, each column's quotient written where the axis moves into an array of inf:
    # the values of np.where(moves, limit / col, inf), without its (n,) temporaries)
    size = min(share.shape[0], CACHE_PIECE)
    col, quot = np.empty(size), np.empty(size)
    moves = np.empty(size, dtype=bool)
    for s in pieces(share.shape[0], CACHE_PIECE):
        m = s.stop - s.start
        c, q, mv = col[:m], quot[:m], moves[:m]
        for k in range(share.shape[1]):
            c[...] = share[s, k]
            np.greater(c, 0, out=mv)
            for limit, out in ((acc[k], a[s]), (jerk[k], j[s])):
                q.fill(np.inf)
                np.divide(limit, c, out=q, where=mv)
                np.minimum(out, q, out=out)
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
    arc_ramps : ArcRamps or None
        Holds whose speed changes along them (LinuxCNC's blend arcs between blocks of
        different feeds); None: every hold runs at its move's entry or exit speed.
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
    arc_ramps: ArcRamps | None = None

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
        if self.arc_ramps is not None:
            return _ramped_hold_times(
                self.arc_ramps,
                k,
                (hs, he, self.hold_start_ratio[k], self.hold_end_ratio[k]),
                self.v_entry[k],
                self.v_exit[k],
            )
        with np.errstate(divide="ignore", invalid="ignore"):
            h0 = np.where(hs > 0, self.hold_start_ratio[k] * hs / self.v_entry[k], 0.0)
            h1 = np.where(he > 0, self.hold_end_ratio[k] * he / self.v_exit[k], 0.0)
        return nan_to_num(h0, posinf=0.0), nan_to_num(h1, posinf=0.0)

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
        if self.arc_ramps is not None:
            return self._in_ramped_holds(s, self._speed_at(s))
        return self._speed_at(s)

    def _in_ramped_holds(self, s: NDArray, v: NDArray) -> NDArray[np.float64]:
        """The speeds ``v`` at arc lengths ``s`` with those in holds whose speed changes
        along them (:attr:`arc_ramps`) made again."""
        ar = self.arc_ramps
        assert ar is not None
        tp = self.toolpath
        k = tp.move_at(s)
        d = np.clip(s - tp.start_s[k], 0.0, tp.length[k])
        h0, h1 = self.hold_start[k], self.hold_end[k]
        for start in (True, False):
            if start:
                sel = np.flatnonzero((d < h0) & (ar.start[k] != self.v_entry[k]))
                kk = k[sel]
                r, h, into = self.hold_start_ratio[kk], h0[sel], d[sel]
                va, vb, acc_h = ar.start[kk], self.v_entry[kk], ar.a_start[kk]
            else:
                past = tp.length[k] - h1  # where the end hold begins
                sel = np.flatnonzero((d > past) & (h1 > 0) & (ar.end[k] != self.v_exit[k]))
                kk = k[sel]
                r, h, into = self.hold_end_ratio[kk], h1[sel], d[sel] - past[sel]
                va, vb, acc_h = self.v_exit[kk], ar.end[kk], ar.a_end[kk]
            if sel.size:
                v[sel] = ramped_hold_speed(r * into, r * h, va, vb, acc_h)
        return v

    def _speed_at(self, s: NDArray[np.float64]) -> NDArray[np.float64]:
        """:meth:`speed_at` of a 1-D ``s``, every hold at its move's entry or exit speed."""
        tp = self.toolpath
        kernels = compiled()
        if kernels is not None:  # the same operations element by element (core.model.jit)
            return kernels.profile_speed(
                np.ascontiguousarray(s),
                tp.start_s,
                tp.length,
                self.hold_start,
                self.hold_end,
                self.v_entry,
                self.v_exit,
                self.a_up,
                self.a_down,
                self.v_peak,
                self.ramps or _NO_RAMPS,
                self.ramps is not None,
                (TOL.nil_speed, TOL.tiny, TOL.sure_compare, HALVINGS, HALFWAY, NEWTON_STEPS),
            )
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
            goal = target if rising else -target
            a_p, b_p = _bisect_ramp(lo, dv, a, vb * vb, span, shape, goal, rising)
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
        in_h1 = ~(in_h0 | in_up | in_cr | in_dn)
        v = np.where(
            in_h0,
            v0,
            np.where(in_up, v0 + au * tr, np.where(in_cr, vp, np.where(in_dn, vp - ad * td, v1))),
        )
        ar = self.arc_ramps
        if ar is not None:  # holds whose speed changes along them: their travel and speed
            for start in (True, False):
                if start:
                    sel = np.flatnonzero(in_h0 & (ar.start[k] != v0))
                    kk = k[sel]
                    va, vb, acc_h = ar.start[kk], v0[sel], ar.a_start[kk]
                    h, r, tt = h0[sel], r0[sel], tau[sel]
                else:
                    sel = np.flatnonzero(in_h1 & (ar.end[k] != v1))
                    kk = k[sel]
                    va, vb, acc_h = v1[sel], ar.end[kk], ar.a_end[kk]
                    h, r, tt = self.hold_end[kk], r1[sel], th[sel]
                if sel.size == 0:
                    continue
                x, v[sel] = ramped_hold_motion(tt, r * h, va, vb, acc_h)
                with np.errstate(divide="ignore", invalid="ignore"):
                    prog = np.where(r > 0, x / r, h)
                (in_hold0 if start else in_hold1)[sel] = prog
        d = np.where(in_h0, in_hold0, h0 + d_ramps + np.where(in_h1, in_hold1, 0.0))
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


#: Share of the acceleration a planner uses along the arcs it inserts at corners, by the
#: machine's ``corner_blending``: the paper's speed is constant over the arc (sec. 2.1);
#: LinuxCNC 2.9 changes speed along its blend arcs at half the acceleration of their plane
#: (blendmath.h BLEND_ACC_RATIO_TANGENTIAL).
BLEND_ACCELERATION = {"paper": 0.0, "linuxcnc": LCNC_TANGENTIAL_RATIO}


def _holds(ev: Evaluation) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """(n,) hold lengths at the start and end of every move (mm of programmed path), from the
    junctions' ``hold_mm``, at most half of each move; and the length actually run per mm of
    hold (``travel_mm / hold_mm``: below 1 where the tool cuts a corner on its arc)."""
    tp = ev.toolpath
    h_start = np.zeros(tp.n)
    h_end = np.zeros(tp.n)
    r_start = np.ones(tp.n)
    r_end = np.ones(tp.n)
    h = nan_to_num(ev.junction_hold, nan=0.0, posinf=0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(h > 0, ev.junction_travel / h, 1.0)
    ratio = np.clip(nan_to_num(ratio, nan=1.0), 0.0, 1.0)
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
    runs at the boundary's speed, which is slightly conservative.
    """
    return _passes_of(b * b, _pass_terms(a_up, inner), _pass_terms(a_dn, inner))


def _pass_terms(a: NDArray, inner: NDArray) -> NDArray:
    """(n,) 2 a L of every move: the steps of the acceleration-weighted length W."""
    tmp = np.multiply(a, inner)
    tmp *= 2.0
    return tmp


def _passes_of(
    b2: NDArray,
    up: NDArray,
    dn: NDArray,
    work: tuple[NDArray, NDArray] | None = None,
    *,
    out: NDArray | None = None,
    finite: bool = False,
) -> NDArray:
    """:func:`_passes` from the squared caps ``b2`` and the :func:`_pass_terms` of both
    directions (the rounds of :func:`build_profile` keep the terms and renew only those of
    the moves whose acceleration changed). (Written with ``out=``: the same operations in
    the same order, without a temporary per step; ``work``: two (n + 1,) arrays to write
    the sums and the backward pass into, which the rounds keep from pass to pass; ``out``:
    an (n + 1,) array for the speeds, else a new one.)

    ``finite``: the caller knows ``b2`` and the terms to be finite and the terms to be
    >= 0 (:func:`_plain_terms`). Then no sum or difference the passes take the minima of
    is NaN (the sums of terms >= 0 may overflow to inf, never to NaN) nor -0.0 (b2 >= +0,
    W >= +0), and fmin is minimum there, a third faster. Nor is a speed squared below 0
    there, so the last clamp at 0 is left out: W does not fall, so b2[j] - W[j] >= -W[i]
    for j <= i and the forward speed squared is >= -W[i] + W[i] = +0 (rounding is
    monotone); the backward one likewise; an overflowed W gives NaN, which the clamp kept
    too."""
    n1 = b2.size
    w, bwd = (np.empty(n1), np.empty(n1)) if work is None else work
    kernels = round_kernels() if finite and n1 else None
    if kernels is not None:  # the same sums and minima move by move (core.model.native)
        out = np.empty(n1) if out is None else out
        kernels.plain_passes(b2, up, dn, w, bwd, out)
        return out
    least = np.fmin if finite else np.minimum
    w[0] = 0.0
    np.cumsum(up, out=w[1:])
    fwd = np.subtract(b2, w, out=out)
    least.accumulate(fwd, out=fwd)
    fwd += w
    np.cumsum(dn, out=w[1:])
    np.add(b2, w, out=bwd)
    rev = bwd[::-1]
    least.accumulate(rev, out=rev)
    bwd -= w
    np.minimum(fwd, bwd, out=fwd)
    np.minimum(fwd, b2, out=fwd)
    if not finite:
        np.maximum(fwd, 0.0, out=fwd)
    return np.sqrt(fwd, out=fwd)


def _plain_terms(terms: NDArray) -> bool:
    """Whether pass terms are finite and >= 0 (``finite`` of :func:`_passes_of`)."""
    return bool(np.isfinite(terms).all() and not (terms < 0.0).any())


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


def _positive(h: NDArray) -> NDArray | slice:
    """Where ``h > 0``: its indices, or a slice where they are one run (a hold at every
    move but the first or last: 1M arcs, 8 MB of indices less)."""
    at = np.flatnonzero(h > 0)
    if at.size and at[-1] - at[0] + 1 == at.size:
        return slice(int(at[0]), int(at[-1]) + 1)
    return at


class _Holds:
    """The holds of every move, what the rounds of :func:`build_profile` reuse: the length
    left between them (``between``, may be < 0; :meth:`inner` = max(between, 0)) and where
    they are (most moves have none: their hold time is computed where they are only). The
    holds' own columns are kept as given (the profile's, not copies); what is made of them
    is made where used (5M moves: 120 MB less while the rounds run)."""

    def __init__(self, length, h_start, h_end, r_start, r_end) -> None:
        self.between = length - h_start - h_end
        self.at_start = _positive(h_start)
        self.at_end = _positive(h_end)
        self._columns = (h_start, h_end, r_start, r_end)

    def inner(self, k: NDArray | slice = slice(None)) -> NDArray:
        """max(between, 0) of the moves ``k`` (all by default)."""
        return np.maximum(self.between[k], 0.0)

    def time(self, v0: NDArray, v1: NDArray) -> NDArray:
        """(n,) time of the holds at entry speed ``v0`` and exit speed ``v1`` (0 where a
        hold would run at speed 0: a stop there is the ramps' business)."""
        h_start, h_end, r_start, r_end = self._columns
        a, b = self.at_start, self.at_end
        t = np.zeros(v0.size)
        with np.errstate(divide="ignore", invalid="ignore"):
            ts = r_start[a] * h_start[a]  # the length run in the hold, then its time
            ts /= v0[a]
            te = r_end[b] * h_end[b]
            te /= v1[b]
        # run >= 0 and v >= 0: a quotient is finite, +inf (v = 0) or NaN (0 / 0), both 0
        ts[~(ts < np.inf)] = 0.0
        te[~(te < np.inf)] = 0.0
        t[self.at_start] = ts
        t[self.at_end] += te
        return t


def _moves(v: NDArray, cap: NDArray, a_up: NDArray, a_dn: NDArray, holds: _Holds):
    """Entry, peak, exit speed and time of every move from its boundary speeds; the holds
    at its ends run at the entry and exit speed (over ``r * h`` of actual travel).
    (Elementwise, in pieces of :data:`CACHE_PIECE` moves, their temporaries in the cache:
    the same values as over all the moves at once.)"""
    v0, v1 = v[:-1], v[1:]
    t = holds.time(v0, v1)  # the holds' time, then the whole time
    n = v0.size
    peak, d_cr = np.empty(n), np.empty(n)
    for s in pieces(n, CACHE_PIECE):
        peak[s], d_cr[s], t[s] = _move_piece(
            v[s.start : s.stop + 1], cap[s], a_up[s], a_dn[s], holds.between[s], t[s]
        )
    return v0, peak, v1, t, d_cr


def _move_piece(v, cap, a_up, a_dn, length, t_hold):
    """:func:`_moves` of consecutive moves: peak speed, cruise length, time."""
    return _piece(v[:-1], v[1:], cap, a_up, a_dn, length, t_hold)


def _piece(v0, v1, cap, a_up, a_dn, length, t_hold):
    """:func:`_move_piece` of moves given by their entry and exit speeds."""
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
    up /= 2 * a_up
    d_cr = length - up
    np.subtract(pk2, v1sq, out=up)
    up /= 2 * a_dn
    d_cr -= up
    np.maximum(d_cr, 0.0, out=d_cr)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_cr = np.where(peak > 0, d_cr / peak, 0.0)
    t += t_cr
    t += t_dn
    t += t_hold
    return peak, d_cr, t


def _ramp_marks(v0, peak, v1, d_cr) -> tuple[NDArray, NDArray, NDArray]:
    """Which moves accelerate (peak above the entry speed), which brake (above the exit
    speed), and which cruise over no length, for :func:`_ramp_changes`."""
    tol = TOL.rel_equal * np.maximum(peak, 1.0)
    rise = peak > v0 + tol
    fall = peak > v1 + tol
    return rise, fall, d_cr <= TOL.nil_distance


def _ramp_changes(v0, peak, v1, marks, rising: bool) -> tuple[NDArray, NDArray, NDArray]:
    """For each move, whether it has an acceleration (or braking) phase, the whole speed
    change of the ramp that phase belongs to (chains of moves accelerating end to end), and
    the ramp's lower speed (where an acceleration starts, where a braking ends); ``marks``
    from :func:`_ramp_marks`."""
    n = v0.size
    rise, fall, flat = marks
    if rising:
        phase = rise
        through = phase & ~fall & flat  # accelerating to its very end
        cont = np.zeros(n, dtype=bool)
        cont[1:] = through[:-1] & phase[1:]
    else:
        phase = fall
        through = phase & ~rise & flat  # braking from its very start
        cont = np.zeros(n, dtype=bool)
        cont[1:] = through[1:] & phase[:-1]
        # a braking chain runs forward from its first move; "cont[k]" links k-1 -> k
    idx = np.flatnonzero(phase)
    if idx.size == 0:
        return phase, np.zeros(n), np.zeros(n)
    # the chain of each move in ``idx`` (every chain starts at a move in ``idx``)
    c = np.cumsum(~cont[idx])
    c -= 1
    del cont
    edge = c[1:] != c[:-1]
    first = idx[np.concatenate([[True], edge])]
    last = idx[np.concatenate([edge, [True]])]
    del edge
    # (np.where(through[k], v[k], peak[k]) as peak[k] with v[k] written where through: the
    # same values, fewer (n,) temporaries; this is the profile's peak on 5M arcs)
    if rising:
        lo = v0[first]
        hi = peak[last]
        k = last[through[last]]
        hi[through[last]] = v1[k]
    else:
        hi = peak[first]
        k = first[through[first]]
        hi[through[first]] = v0[k]
        lo = v1[last]
    del first, last, k
    hi -= lo  # the ramps' speed changes
    dv = np.zeros(n)
    dv[idx] = hi[c]
    del hi
    low = np.zeros(n)
    low[idx] = lo[c]
    return phase, dv, low


def _denominator(a_up: NDArray, a_dn: NDArray) -> NDArray:
    """1 / a_up + 1 / a_dn, the peak's denominator as :func:`_moves` makes it (made where
    used, not kept through the rounds: 8 MB a million moves off the profile's peak)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        den = 1.0 / a_up
        den += 1.0 / a_dn
    return den


def _marks_of(v0, v1, a_up, a_dn, den, between, cap) -> tuple[NDArray, ...]:
    """The marks of :meth:`_Rounds._all_marks` of moves from their columns (gathered): the
    peak, whether they accelerate and brake, and whether they accelerate through their end
    and brake from their start (the same operations on every element as there)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        pk = v0 * v0
        pk /= a_up
        li = np.multiply(between, 2.0)
        pk += li
        t = v1 * v1
        t /= a_dn
        pk += t
        pk /= den
        np.maximum(pk, 0.0, out=pk)
        np.sqrt(pk, out=pk)
        np.minimum(cap, pk, out=pk)
        np.maximum(v0, v1, out=t)
        np.maximum(pk, t, out=pk)
        np.maximum(pk, 1.0, out=t)
        t *= TOL.rel_equal
        r = pk > v0 + t
        f = pk > v1 + t
        one = r != f
        pk2 = pk * pk
        up = pk2 - v0 * v0
        up /= 2 * a_up
        d_cr = between - up
        up = pk2 - v1 * v1
        up /= 2 * a_dn
        d_cr -= up
        np.maximum(d_cr, 0.0, out=d_cr)
        flat = d_cr <= TOL.nil_distance
    flat &= one
    return pk, r, f, r & flat, f & flat


class _Rounds:
    """The rounds of the jerk iteration of :func:`build_profile`, without the (n,) work a
    round's result does not need.

    A round needs, of the speeds, only where each move accelerates or brakes (its peak
    against its entry and exit speed) and, on the moves that do one of them only, whether
    they cruise; the times, and the cruise lengths elsewhere, are for the last round alone
    (:func:`_moves`). The accelerations change on the moves in a ramp (a fifth of a
    finishing raster's) and where they had changed before, so the new accelerations, the
    damping and the terms the passes sum are computed there only, and ``a_up``, ``a_dn``
    (updated in place) keep the rest. Every value is the same arithmetic on the same
    numbers as :func:`_moves` and :func:`_ramp_changes` over all the moves (and as the
    effective accelerations and their damping over all of them were): the profile is bit
    for bit the same.
    """

    def __init__(self, caps, cap, acc, jerk, holds: _Holds) -> None:
        self.caps = caps
        self.cap, self.acc, self.jerk, self.holds = cap, acc, jerk, holds
        self.a_up, self.a_dn = acc.copy(), acc.copy()
        self.term_up = _pass_terms(self.a_up, holds.inner())
        self.term_dn = self.term_up.copy()
        n = acc.size
        self.step_up = np.zeros(n, dtype=np.int8)
        self.step_dn = np.zeros(n, dtype=np.int8)
        # where the acceleration is not the machine's
        self.off_up = self.a_up != acc
        self.off_dn = self.off_up.copy()
        # last round's ramps (moves, speed changes, effective accelerations) per direction
        self.last_up: tuple[NDArray, NDArray, NDArray] | None = None
        self.last_dn: tuple[NDArray, NDArray, NDArray] | None = None
        self.b2 = caps * caps
        self.work = (np.empty(caps.size), np.empty(caps.size))
        self.spare: NDArray | None = None  # (see passes)
        # the squared caps are finite and the terms finite and >= 0 (see _passes_of; the
        # two directions' terms are the same numbers yet)
        self.finite = bool(np.isfinite(self.b2).all()) and _plain_terms(self.term_up)
        # last round's marks (:meth:`step`): each move's peak, whether it accelerates or
        # brakes, and through[k + 1] (move k links its ramp to the next or previous one),
        # with the boundary speeds they were made from; None before the first round
        self.marks: tuple[NDArray, NDArray, NDArray, NDArray, NDArray] | None = None
        self.v_last = np.zeros(0)
        # moves whose accelerations (and so the peak's denominator) the last round changed
        self.moved: list[NDArray | slice] = []  # (indices, a slice or an (n,) mask)
        # per direction (True: accelerating): the moves whose acceleration the damping kept
        # off their target, and their targets
        self.behind = {d: (np.zeros(0, dtype=np.intp), np.zeros(0)) for d in (True, False)}
        # acc / jerk and acc * acc / jerk, which the kernels' dense rounds (numba's and C)
        # take instead of dividing again in every round (the quotients
        # effective_acceleration makes; made where those kernels run: :meth:`_fix`)
        self.fixed: tuple[NDArray, NDArray] | None = None

    def passes(self) -> NDArray:
        """:func:`_passes` at the current accelerations (the squared caps and the passes'
        work arrays made once for all the rounds). The speeds go into the older of two
        arrays the rounds take turns with: the newer is the last round's (``v_last``),
        the older no round reads any more."""
        out = self.spare
        self.spare = self.v_last if self.v_last.size else None
        return _passes_of(
            self.b2, self.term_up, self.term_dn, self.work, out=out, finite=self.finite
        )

    def step(self, v: NDArray) -> float:
        """One round from the boundary speeds ``v``: the accelerations of the next (in
        place); returns the largest relative change, as :func:`build_profile` measures it.

        The marks (peak, accelerating, braking, through) of a move depend on its boundary
        speeds, its accelerations and its fixed columns only: after the first round they
        are made again only where one of those changed (a few moves in a thousand once the
        speeds settle), the same arithmetic on the same numbers."""
        near = None
        self._fix()
        if self.marks is None:
            self.marks = self._all_marks(v)
        else:
            near = self._update_marks(v)
        self.v_last = v  # (the next passes write into the other of their two arrays)
        self.moved = []
        peak, rise, fall, through_up, through_dn = self.marks
        v0, v1 = v[:-1], v[1:]
        if near is None and self._parallel() and self._dense_ok(rise) and self._dense_ok(fall):
            # Both directions dense, each on its own columns (a_up, term_up, ... and
            # a_dn, ...), the kernels letting go of the GIL: on two threads. Their
            # ``finite`` (whether all terms are plain) is one flag that only falls: the
            # two results' conjunction is what one after the other gives.
            finite = self.finite
            (change_up, fin_up), (change_dn, fin_dn) = side_by_side(
                lambda: self._dense(True, rise, through_up, v0, v1, peak, finite),
                lambda: self._dense(False, fall, through_dn, v0, v1, peak, finite),
            )
            self.finite = fin_up and fin_dn
            return max(change_up, change_dn)
        change_up = self._direction(True, rise, through_up, v0, v1, peak, near)
        change_dn = self._direction(False, fall, through_dn, v0, v1, peak, near)
        return max(change_up, change_dn)

    def _parallel(self) -> bool:
        """Whether a round's two directions go on two threads: kernels that let go of the
        GIL (numpy's pieces hold it), enough moves to repay a thread, two cores."""
        return self.acc.size >= SPLIT and round_kernels() is not None and two_cores()

    def _dense_ok(self, phase: NDArray) -> bool:
        """Whether :meth:`_direction` (all marks new) takes :meth:`_dense` for ``phase``."""
        return bool(DENSE_SHARE * np.count_nonzero(phase) > phase.size)

    def _update_marks(self, v: NDArray) -> NDArray | None:
        """The marks of :meth:`_all_marks` made again where a move's boundary speeds or
        accelerations changed since the last round (in place); returns those moves (None:
        all of them were made again)."""
        assert self.marks is not None
        peak, rise, fall, through_up, through_dn = self.marks
        n = peak.size
        changed = v != self.v_last
        dirty = changed[:-1]
        dirty |= changed[1:]
        del changed
        for k in self.moved:
            if isinstance(k, np.ndarray) and k.dtype == bool:
                dirty |= k
            else:
                dirty[k] = True
        at = np.flatnonzero(dirty)
        del dirty
        if at.size == 0:
            return at
        if 2 * at.size > n:
            self.marks = self._all_marks(v)
            return None
        kernels = round_kernels()
        if kernels is not None:  # the same operations move by move (core.model.native)
            kernels.marks(
                at, False, v, self.a_up, self.a_dn, self.holds.between, self.cap,
                (TOL.rel_equal, TOL.nil_distance), self.marks,
            )  # fmt: skip
            return at
        for s in pieces(at.size, CACHE_PIECE):  # (elementwise: bounded temporaries)
            k = at[s]
            pk, r, f, t_up, t_dn = _marks_of(
                v[k],
                v[k + 1],
                self.a_up[k],
                self.a_dn[k],
                _denominator(self.a_up[k], self.a_dn[k]),
                self.holds.between[k],
                self.cap[k],
            )
            peak[k] = pk
            rise[k] = r
            fall[k] = f
            k = k + 1  # (a new array: ``at`` is returned)
            through_up[k] = t_up
            through_dn[k] = t_dn
        return at

    def _all_marks(self, v: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray]:
        """The marks of every move from the boundary speeds ``v`` (:func:`_marks_of`, in
        pieces, their temporaries in the cache)."""
        a_up, a_dn = self.a_up, self.a_dn
        between = self.holds.between
        n = a_up.size
        peak = np.empty(n)
        rise = np.empty(n, dtype=bool)
        fall = np.empty(n, dtype=bool)
        # through[k + 1]: move k accelerates to its very end (rising) or brakes from its very
        # start (falling) and so links its ramp to the next or the previous move
        through_up = np.zeros(n + 1, dtype=bool)
        through_dn = np.zeros(n + 1, dtype=bool)
        kernels = round_kernels()
        if kernels is not None:  # the same operations move by move (core.model.native)
            out = (peak, rise, fall, through_up, through_dn)
            kernels.marks(
                np.zeros(0, dtype=np.intp), True, v, a_up, a_dn, between, self.cap,
                (TOL.rel_equal, TOL.nil_distance), out,
            )  # fmt: skip
            return out
        size = min(n, CACHE_PIECE)
        sq, tmp, lim = np.empty(size + 1), np.empty(size), np.empty(size)
        one = np.empty(size, dtype=bool)
        # In pieces (elementwise: the same values), their temporaries in the cache.
        with np.errstate(divide="ignore", invalid="ignore"):
            for s in pieces(n, CACHE_PIECE):
                m = s.stop - s.start
                vv, q, t, li, pk = v[s.start : s.stop + 1], sq[: m + 1], tmp[:m], lim[:m], peak[s]
                v0, v1 = vv[:-1], vv[1:]
                # the peak of _moves: (2 L + v0^2 / a_up + v1^2 / a_dn) / (1/a_up + 1/a_dn)
                np.multiply(vv, vv, out=q)
                np.divide(q[:-1], a_up[s], out=pk)
                np.multiply(between[s], 2.0, out=li)
                pk += li
                np.divide(q[1:], a_dn[s], out=t)
                pk += t
                np.divide(1.0, a_up[s], out=li)
                np.divide(1.0, a_dn[s], out=t)
                li += t
                pk /= li  # (the peak's denominator, as _moves makes it)
                np.maximum(pk, 0.0, out=pk)
                np.sqrt(pk, out=pk)
                np.minimum(self.cap[s], pk, out=pk)
                np.maximum(v0, v1, out=t)
                np.maximum(pk, t, out=pk)
                # _ramp_changes: which moves accelerate (peak above v0), which brake (v1)
                np.maximum(pk, 1.0, out=t)
                t *= TOL.rel_equal
                np.add(v0, t, out=li)
                r = np.greater(pk, li, out=rise[s])
                np.add(v1, t, out=li)
                f = np.greater(pk, li, out=fall[s])
                # the cruise length (_moves' d_cr) of the moves that only accelerate or only
                # brake: through their end or from their start if it is nil
                only = np.not_equal(r, f, out=one[:m])
                if DENSE_SHARE * np.count_nonzero(only) > m:  # most of them: whole columns
                    # (2 L - (peak^2 - v0^2) / a_up - ... as below, over every move)
                    pk2 = pk * pk
                    np.subtract(pk2, q[:-1], out=t)
                    t /= 2 * a_up[s]
                    d_cr = between[s] - t
                    np.subtract(pk2, q[1:], out=t)
                    t /= 2 * a_dn[s]
                    d_cr -= t
                    np.maximum(d_cr, 0.0, out=d_cr)
                    flat = d_cr <= TOL.nil_distance
                    flat &= only
                    u = slice(s.start + 1, s.stop + 1)
                    np.logical_and(r, flat, out=through_up[u])
                    np.logical_and(f, flat, out=through_dn[u])
                    continue
                x = np.flatnonzero(only)
                if x.size == 0:
                    continue
                px = pk[x]
                pk2 = px * px
                vx = v0[x]
                up = pk2 - vx * vx
                up /= 2 * a_up[s][x]
                d_cr = between[s][x] - up
                vx = v1[x]
                up = pk2 - vx * vx
                up /= 2 * a_dn[s][x]
                d_cr -= up
                np.maximum(d_cr, 0.0, out=d_cr)
                flat = d_cr <= TOL.nil_distance
                at = x + (s.start + 1)
                through_up[at] = r[x] & flat
                through_dn[at] = f[x] & flat
        return peak, rise, fall, through_up, through_dn

    def _effective(self, rising: bool, idx: NDArray, dv: NDArray, at: NDArray | slice) -> NDArray:
        """:func:`effective_acceleration` of the moves ``idx`` in ramps of speed change
        ``dv``, recomputed only where ``dv`` is not last round's (from one round to the next,
        most ramps are the same)."""
        last = self.last_up if rising else self.last_dn
        if last is not None and np.array_equal(last[0], idx):
            eff = last[2].copy()
            new = np.flatnonzero(dv != last[1])
            if new.size:
                k = idx[new]
                eff[new] = effective_acceleration(dv[new], self.acc[k], self.jerk[k])
        elif isinstance(at, slice):  # every move: in pieces, without (n,) temporaries
            acc, jerk = self.acc, self.jerk
            eff = piecewise(
                dv.size, np.float64, lambda s: effective_acceleration(dv[s], acc[s], jerk[s])
            )
        else:
            eff = effective_acceleration(dv, self.acc[at], self.jerk[at])
        # kept for the next round where the ramps are a part of the moves only (where all
        # are, most change: 1M arcs, 48 MB for nothing)
        keep = (idx, dv, eff) if 4 * idx.size <= self.acc.size else None
        if rising:
            self.last_up = keep
        else:
            self.last_dn = keep
        return eff

    @staticmethod
    def _ramp_dv(rising, idx, at, start, through, v0, v1, peak) -> NDArray:
        """The speed change of each of the moves ``idx``'s ramp, from the ramp's first move
        to its last (``start``: a move begins its ramp; ramps chain moves end to end). Where
        every move is a ramp of its own, each is its own first and last: read through
        ``at`` (whole columns when every move is in a ramp), no chain gathered."""
        if start.all():
            first = last = at
            # (every move: the next moves' marks are a view, not gathered)
            after_first = after_last = slice(1, None) if isinstance(at, slice) else idx + 1
            chain = None
        else:
            chain = np.cumsum(start) - 1
            first = idx[start]
            last_of = np.empty(idx.size, dtype=bool)
            last_of[:-1] = start[1:]
            last_of[-1] = True
            last = idx[last_of]
            del last_of
            after_first, after_last = first + 1, last + 1
        if rising:
            lo = v0[first]
            hi = np.where(through[after_last], v1[last], peak[last])
        else:
            hi = np.where(through[after_first], v0[first], peak[first])
            lo = v1[last]
        hi -= lo  # the speed changes (in place: one (n,) array fewer at the profile's peak)
        return hi if chain is None else hi[chain]

    def _direction(self, rising, phase, through, v0, v1, peak, near) -> float:
        """The next accelerations of one direction (updated in place, with the passes'
        terms); returns the largest relative change.

        :func:`_ramp_changes` on the moves in a ramp phase gives each the speed change of
        its ramp, hence its effective acceleration (``acc`` elsewhere); where a move's
        A_eff turns back against its last step, the geometric mean of the old and the new
        (the damping). Both only where a ramp phase is or the acceleration is not
        ``acc``: elsewhere the new one is the old one. ``near``: the moves whose marks
        changed since the last round (None: all may have), whose ramps alone need to be
        found again (:meth:`_local`)."""
        if rising:
            a, last, term = self.a_up, self.step_up, self.term_up
        else:
            a, last, term = self.a_dn, self.step_dn, self.term_dn
        acc = self.acc
        off = self.off_up if rising else self.off_dn
        found = None if near is None else self._local(rising, near, v0, v1, peak)
        if found is None and self._dense_ok(phase):
            change, self.finite = self._dense(rising, phase, through, v0, v1, peak, self.finite)
            return change
        cand: NDArray | slice
        if found is None:
            cand, new, old = self._everywhere(rising, phase, through, v0, v1, peak)
        else:
            cand, new, old = found
        del found
        out, step, change = _damped(new, old, last, cand)
        # the moves whose new acceleration is still not their target (the damping held it
        # back), with their targets: the next round's candidates beside the changed ramps
        behind = out != new
        at_behind = np.flatnonzero(behind) if isinstance(cand, slice) else cand[behind]
        kept = (at_behind, new[behind])
        del behind, at_behind
        # the terms follow where the acceleration changed
        moved = out != old
        del new, old
        if not moved.all():
            cand = np.flatnonzero(moved) if isinstance(cand, slice) else cand[moved]
            out = out[moved]
        del moved
        a[cand] = out
        off[cand] = out != acc[cand]
        terms = _pass_terms(out, self.holds.inner(cand))
        term[cand] = terms
        if self.finite and not _plain_terms(terms):
            self.finite = False
        self._keep_round(rising, step, cand, kept)
        return change

    def _dense(self, rising, phase, through, v0, v1, peak, finite) -> tuple[float, bool]:
        """:meth:`_direction` over every move at once where most moves are in a ramp phase
        (stellabee1: three in four): the targets, the damping and the updates made on whole
        columns in pieces (their temporaries in the cache), not gathered on the candidates.

        The same values: a move is a candidate there exactly where its target (the ramp's
        A_eff in a ramp phase, ``acc`` elsewhere) is not its current acceleration (``off``
        is ``a != acc``); elsewhere the target is the current acceleration, whose damped
        step is nil (sign 0, the same acceleration), and a nil step changes nothing: no
        move, no term, a step sign 0, a relative change 0 (or NaN, which ``nanmax``
        skips). The signs are read from comparisons (``sign(x - y)`` of doubles is the sign
        of ``x`` against ``y``, and 0 where NaN as the int8 cast gives).

        ``finite``: whether the pass terms are plain so far (:attr:`finite`); returns the
        largest relative change and that flag after this direction's terms (the caller
        keeps it: :meth:`step` runs the two directions side by side)."""
        if rising:
            a, last, term, off = self.a_up, self.step_up, self.term_up, self.off_up
            self.last_up = None  # (kept by _effective for sparse ramps only)
        else:
            a, last, term, off = self.a_dn, self.step_dn, self.term_dn, self.off_dn
            self.last_dn = None
        acc, jerk, between = self.acc, self.jerk, self.holds.between
        n = a.size
        kernels = round_kernels()
        if kernels is not None:  # the same operations move by move (core.model.native)
            step = np.empty(n, dtype=np.int8)
            moved = np.empty(n, dtype=bool)
            assert self.fixed is not None  # (made by _fix where kernels run the rounds)
            change, finite, at, want = kernels.dense_round(
                rising, phase, through, v0, v1, peak, a, last, term, off, acc, jerk,
                between, step, moved, TOL.nil_speed, finite, fixed=self.fixed,
            )  # fmt: skip
            self._keep_round(rising, step, moved, (at, want))
            return float(change), bool(finite)
        dv = _chain_dv(rising, phase, through, v0, v1, peak)
        step = np.empty(n, dtype=np.int8)
        moved = np.empty(n, dtype=bool)
        at_behind, wanted = [], []
        change = 0.0
        for s in pieces(n, CACHE_PIECE):
            od = a[s]  # (a view: written where the acceleration moves)
            new = effective_acceleration(dv[s], acc[s], jerk[s], phase[s])  # the targets
            ls = last[s]
            back = new > od
            back &= ls < 0
            t = new < od
            t &= ls > 0
            back |= t
            out = new.copy()
            k = np.flatnonzero(back)
            if k.size:
                out[k] = np.sqrt(od[k] * new[k])
                held = out[k] != new[k]  # (only a damped step is off its target)
                if held.any():
                    at_behind.append(k[held] + s.start)
                    wanted.append(new[k[held]])
            t = np.greater(out, od, out=t)
            st = step[s]
            np.copyto(st, t, casting="unsafe")
            st -= out < od
            with np.errstate(divide="ignore", invalid="ignore"):
                rel = out / od
                rel -= 1.0
                np.abs(rel, out=rel)
                change = max(change, float(np.nanmax(rel, initial=0.0)))
            mv = np.not_equal(out, od, out=moved[s])
            if not mv.any():
                continue
            # where a move keeps its acceleration, ``out`` is that value (not NaN: NaN
            # moves), bit for bit unless a zero changes sign: written whole but then
            if (out == 0.0).any():
                put_where(od, out, mv)
            else:
                od[...] = out
            # ``off`` is a != acc, ``term`` the pass terms of ``a``: made whole again
            np.not_equal(od, acc[s], out=off[s])
            tm = _pass_terms(od, np.maximum(between[s], 0.0))
            term[s] = tm
            if finite and not _plain_terms(tm):  # (the others were plain)
                finite = False
        behind = (
            np.concatenate(at_behind) if at_behind else np.zeros(0, dtype=np.intp),
            np.concatenate(wanted) if wanted else np.zeros(0),
        )
        self._keep_round(rising, step, moved, behind)
        return change, finite

    def _fix(self) -> None:
        """:attr:`fixed` made where kernels (numba's or C) run the rounds (in the caller's
        thread, before the directions go side by side)."""
        if self.fixed is None and round_kernels() is not None:
            with np.errstate(divide="ignore", invalid="ignore"):
                lim = self.acc * self.acc
                lim /= self.jerk
                self.fixed = (self.acc / self.jerk, lim)

    def _keep_round(
        self, rising: bool, step: NDArray, moved: NDArray | slice, behind: tuple[NDArray, NDArray]
    ) -> None:
        """What a round of one direction leaves for the next: each move's step sign, the
        moves it changed (a mask over all of them, or their indices: :meth:`_direction`'s
        candidates), the moves the damping held back and their targets."""
        self.behind[rising] = behind
        self.moved.append(moved)
        if rising:
            self.step_up = step
        else:
            self.step_dn = step

    def _everywhere(self, rising, phase, through, v0, v1, peak):
        """The candidates of :meth:`_direction` over all the moves: where the target (the
        ramp's A_eff in a ramp phase, ``acc`` elsewhere) is not the current acceleration;
        (moves or a slice of all, their targets, their current accelerations)."""
        a = self.a_up if rising else self.a_dn
        acc = self.acc
        idx = np.flatnonzero(phase)
        # every move in a ramp (1M arcs): the whole columns, not gathered copies
        at: NDArray | slice = slice(None) if idx.size == a.size else idx
        if idx.size:
            # chains of moves accelerating (braking) end to end: a move continues the chain
            # of the one before when that one accelerates through its end (rising), or when
            # it brakes from its own start and the one before brakes too (falling)
            if rising:
                cont = through[idx]
            else:
                cont = through[idx + 1]
                cont[0] = False
                cont[1:] &= np.diff(idx) == 1
            start = ~cont
            del cont
            dv = self._ramp_dv(rising, idx, at, start, through, v0, v1, peak)
            del start
            eff = self._effective(rising, idx, dv, at)
            del dv
        else:
            eff = np.zeros(0)
        # The step (and the damping) is nil wherever the new acceleration is the current
        # one: in a ramp phase where A_eff is the current acceleration, outside wherever the
        # current one is the machine's (``off`` marks where it is not). So both only where
        # they differ: in the later rounds a few moves in a thousand.
        off = self.off_up if rising else self.off_dn
        old_in = a[at]
        differ = eff != old_in
        rest = np.flatnonzero(off & ~phase)
        if rest.size:
            return (
                np.concatenate([idx[differ], rest]),
                np.concatenate([eff[differ], acc[rest]]),
                np.concatenate([old_in[differ], a[rest]]),
            )
        if differ.all():  # every move in a ramp changes (arcs: the first rounds)
            return at, eff, old_in
        return idx[differ], eff[differ], old_in[differ]

    def _links(self, rising: bool, m: NDArray) -> NDArray:
        """Whether each move ``m`` (any ints; outside 1..n-1: no) continues the ramp chain
        of the move before (:meth:`_everywhere`'s ``cont``)."""
        assert self.marks is not None
        _, rise, fall, through_up, through_dn = self.marks
        n = rise.size
        if n < 2:
            return np.zeros(m.shape, dtype=bool)
        k = np.clip(m, 1, n - 1)
        if rising:
            out = rise[k] & through_up[k]
        else:
            out = fall[k] & through_dn[k + 1] & fall[k - 1]
        out &= (m >= 1) & (m < n)
        return out

    def _chain_ends(self, rising: bool, seeds: NDArray) -> tuple[NDArray, NDArray]:
        """The first and last move of the ramp chain of each of ``seeds`` (moves in a ramp
        phase), searched a few moves at a time (at most CHAIN_WINDOW)."""
        ends = []
        for back in (True, False):
            # back to the move that does not continue the one before, or on to the next
            at = seeds.copy() if back else seeds + 1
            todo = np.arange(seeds.size)
            width = 2
            while todo.size:
                w = -np.arange(width) if back else np.arange(width)
                m = at[todo, None] + w
                stop = ~self._links(rising, m)
                found = stop.any(axis=1)
                at[todo[found]] = m[found, stop[found].argmax(axis=1)]
                todo = todo[~found]
                at[todo] += -width if back else width
                width = min(2 * width, CHAIN_WINDOW)
            ends.append(at)
        return ends[0], ends[1] - 1

    def _local(self, rising, near, v0, v1, peak):
        """:meth:`_everywhere`'s candidates where the marks changed at the moves ``near``
        only: a ramp chain none of whose moves, nor the moves beside it, changed its marks
        is the same chain with the same speeds, hence the same targets, so only the chains
        around ``near`` are found again (their moves' targets made as there), and the
        moves the damping held back keep theirs. None where that is not worth it (many
        moves changed)."""
        assert self.marks is not None
        n = v0.size
        if LOCAL_SHARE * near.size > n:
            return None
        a = self.a_up if rising else self.a_dn
        phase = self.marks[1] if rising else self.marks[2]
        through = self.marks[3] if rising else self.marks[4]
        seeds = np.concatenate([near - 1, near, near + 1])
        seeds.sort()
        seeds = seeds[(seeds >= 0) & (seeds < n)]
        if seeds.size:
            seeds = seeds[np.concatenate([[True], seeds[1:] != seeds[:-1]])]
        in_ramp = phase[seeds]
        alone = seeds[~in_ramp]
        first, last = self._chain_ends(rising, seeds[in_ramp])
        if first.size:  # (sorted: the seeds are) one of each chain
            keep = np.concatenate([[True], first[1:] != first[:-1]])
            first, last = first[keep], last[keep]
        size = last - first + 1
        if LOCAL_REACH * (int(size.sum()) + alone.size) > n:
            return None
        # the ramps' speed changes, as _ramp_dv makes them
        if rising:
            lo = v0[first]
            dv = np.where(through[last + 1], v1[last], peak[last])
        else:
            dv = np.where(through[first + 1], v0[first], peak[first])
            lo = v1[last]
        dv -= lo
        ends = np.cumsum(size)
        total = int(ends[-1]) if size.size else 0
        moves = np.repeat(first - (ends - size), size) + np.arange(total)
        eff = effective_acceleration(np.repeat(dv, size), self.acc[moves], self.jerk[moves])
        found = np.concatenate([moves, alone])
        target = np.concatenate([eff, self.acc[alone]])
        del moves, eff
        behind, wanted = self.behind[rising]
        kept = ~isin(behind, found)
        cand = np.concatenate([behind[kept], found])
        new = np.concatenate([wanted[kept], target])
        old = a[cand]
        differ = new != old
        return cand[differ], new[differ], old[differ]


def _chain_dv(rising, phase, through, v0, v1, peak) -> NDArray:
    """(n,) the speed change of each move's ramp, as :meth:`_Rounds._ramp_dv` makes it for
    the moves in a ramp ``phase`` (any value elsewhere): the moves run in chains (a move
    continuing the one before, see :meth:`_Rounds._everywhere`) and the moves outside a
    phase one by one; a chain's change is from its first move's lower speed to its last
    move's upper one (rising: v0 of the first to v1 or the peak of the last; falling: v0
    or the peak of the first to v1 of the last). Every move first as a chain of its own
    (elementwise), then the chains of several moves from their ends, repeated over them."""
    n = phase.size
    # cont[k]: move k continues the chain of move k - 1 (cont[n]: no move there)
    cont = np.zeros(n + 1, dtype=bool)
    if rising:
        np.logical_and(through[:n], phase, out=cont[:n])
    else:
        c = cont[1:n]
        np.logical_and(through[2:], phase[1:], out=c)
        c &= phase[:-1]
    # the upper speed at the ramp's end of each move (rising: its end, falling: its start)
    upper = peak.copy()
    put_where(upper, v1 if rising else v0, through[1:])
    lower = v0 if rising else v1
    dv = upper - lower
    multi = cont[:n] | cont[1:]  # in a chain of several moves
    at = np.flatnonzero(multi)
    if at.size:
        first = np.flatnonzero(multi & ~cont[:n])
        last = np.flatnonzero(multi & ~cont[1:])
        if rising:
            hi = upper[last]
            hi -= lower[first]
        else:
            hi = upper[first]
            hi -= lower[last]
        dv[at] = np.repeat(hi, last - first + 1)
    return dv


def _damped(
    new: NDArray, old: NDArray, last: NDArray, cand: NDArray | slice
) -> tuple[NDArray, NDArray, float]:
    """The damping of :meth:`_Rounds._direction` on the moves ``cand`` (an index or a
    slice of all): their next accelerations (the geometric mean of ``old`` and ``new``
    where the step turns back against ``last``, the previous round's signs), the (n,) signs
    of this round's steps and the largest relative change. (Elementwise, in pieces: the
    same values as over all of them at once, without their (n,) temporaries.)"""
    out = np.empty(new.size)
    step = np.zeros(last.size, dtype=np.int8)
    change = 0.0
    size = min(new.size, PIECE)
    work = np.empty(size)
    back = np.empty(size, dtype=bool)
    for s in pieces(new.size):
        nw, od = new[s], old[s]
        where = s if isinstance(cand, slice) else cand[s]
        t, b, o = work[: nw.size], back[: nw.size], out[s]
        # (in place: the values of sign(nw - od) * last < 0, where(back, sqrt(od nw), nw),
        # sign(o - od) and |o / od - 1|)
        np.subtract(nw, od, out=t)
        np.sign(t, out=t)
        t *= last[where]
        np.less(t, 0, out=b)
        np.multiply(od, nw, out=o)
        np.sqrt(o, out=o)
        np.logical_not(b, out=b)
        np.copyto(o, nw, where=b)
        np.subtract(o, od, out=t)
        np.sign(t, out=t)
        step[where] = t.astype(np.int8)
        with np.errstate(divide="ignore", invalid="ignore"):
            np.divide(o, od, out=t)
            t -= 1.0
            np.abs(t, out=t)
            change = max(change, float(np.nanmax(t, initial=0.0)))
    return out, step, change


def _blend_holds(
    ev: Evaluation,
    cap: NDArray,
    caps: NDArray,
    acc: NDArray,
    a_blend: NDArray | None,
    h_start: NDArray,
    h_end: NDArray,
    r_end: NDArray,
    held: NDArray | None = None,
) -> tuple[NDArray, NDArray, NDArray, _FreeArcs | None]:
    """The holds of a planner that changes speed along its blend arcs at ``a_blend`` (None:
    held, as the paper has it), with the rests it runs as part of the next arc
    (``Evaluation.blend_rest``); and the arcs the speed changes along (None: none).
    ``held``: junctions whose arc stays held whatever the rest says (:func:`_arc_ramps`
    runs them).

    Along an arc the speed may change at a_blend instead of the move's acceleration: the
    ramps get the same reach (a (L - holds) + a_blend holds) when the holds they skip shrink
    by 1 - a_blend / a. An arc that is the slowest point around (its speed limit binds and
    the speeds on both sides reach it) is run at that speed, held, as the paper has it; one
    the neighbours keep below its limit is not, so a first pass with those arcs held tells
    which they are. An arc freed so whose limit the speed reaches once the arcs around it are
    free too keeps its limit along its whole length (LinuxCNC runs it as a segment whose top
    speed is its limit): its side where the speed beyond is higher is held at it, the other
    stays free (0.2 mm free-form chords out of a tight spot: 1.9-3.9 mm/s above LinuxCNC's
    speeds along the arcs' far halves before, within 1.5 now;
    tests/test_linuxcnc_planner_traces.py). A rest run as part of an arc is the arc's,
    straight (ratio 1), held or not with it.
    """
    tp = ev.toolpath
    keep = np.ones(tp.n)
    j = ev.junction
    if a_blend is not None:
        with np.errstate(divide="ignore", invalid="ignore"):
            keep = np.clip(np.nan_to_num(1.0 - a_blend / acc, nan=0.0), 0.0, 1.0)
    merged = np.zeros(tp.n) if ev.blend_rest is None else ev.blend_rest

    def holds(free: NDArray, free_after: NDArray | None = None) -> tuple[NDArray, NDArray, NDArray]:
        # (free: the arcs free on their side before the corner; free_after: after it, the
        # same where not given)
        after = free if free_after is None else free_after
        hs, he, re = h_start.copy(), h_end.copy(), r_end.copy()
        he[j[free]] *= keep[j[free]]
        hs[j[after] + 1] *= keep[j[after] + 1]
        # a rest belongs to the arc at its move's end (junction k for move k): it changes
        # speed where that arc does, and is held with it where the arc is held
        scale = np.ones(tp.n)
        scale[j[free]] = keep[j[free]]
        rest = merged * scale
        k = np.flatnonzero(rest > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = (re[k] * he[k] + rest[k]) / (he[k] + rest[k])
        re[k] = np.where(he[k] + rest[k] > 0, ratio, re[k])
        he[k] += rest[k]
        return hs, he, re

    def free_arcs(free: NDArray, free_after: NDArray | None = None) -> _FreeArcs | None:
        after = free if free_after is None else free_after
        if a_blend is None or not (free.any() or after.any()):
            return None
        fs, fe = np.zeros(tp.n), np.zeros(tp.n)
        fs[j[after] + 1] = h_start[j[after] + 1]
        fe[j[free]] = h_end[j[free]] + merged[j[free]]
        return _FreeArcs(fs, fe, np.fmin(acc, a_blend))

    binds = ev.junction_feed < np.minimum(cap[j], cap[j + 1]) * (1.0 - TOL.rel_equal)
    if held is not None:
        binds = binds | held
    if a_blend is None or not binds.any():
        # (without a_blend nothing is scaled: keep is 1)
        return (*holds(~binds), free_arcs(~binds))
    hs, he, _ = holds(~binds)
    v = _passes(caps, np.maximum(tp.length - hs - he, 0.0), acc, acc)
    below = v[j + 1] < ev.junction_feed * (1.0 - TOL.rel_equal)
    if held is not None:
        below &= ~held  # (held arcs are in binds: neither free nor freed)
    free = ~binds | below
    freed = binds & below
    if not freed.any():
        return (*holds(free), free_arcs(free))
    # An arc freed so may still reach its limit once its neighbours' arcs are free too: then
    # the speed may not pass its limit anywhere along it (LinuxCNC runs the arc as a segment
    # of its own, its limit its top speed), and the side where the speed beyond is higher is
    # held at the limit -- one side only: the other keeps changing speed along it.
    hs, he, _ = holds(free)
    v = _passes(caps, np.maximum(tp.length - hs - he, 0.0), acc, acc)
    hit = freed & (v[j + 1] >= ev.junction_feed * (1.0 - TOL.rel_equal))
    lim = ev.junction_feed * (1.0 + TOL.rel_equal)
    free_before = free & ~(hit & (v[j] > lim))
    free_after = free & ~(hit & (v[j + 2] > lim))
    return (*holds(free_before, free_after), free_arcs(free_before, free_after))


@dataclass(frozen=True)
class _FreeArcs:
    """Per move, the stretches along blend arcs whose speed changes along them, at its start
    (``start``) and at its end (``end``, with the rest run as part of the arc; mm, as
    programmed), and the acceleration there (``a_blend``, at most the move's)."""

    start: NDArray
    end: NDArray
    a_blend: NDArray


@dataclass(frozen=True)
class ArcRamps:
    """Holds whose speed changes along them: LinuxCNC's blend arcs between blocks of
    different feeds (:func:`_arc_ramps`). Per move, the speed at the corner end of its start
    hold (``start``: where the move begins) and of its end hold (``end``: where it ends),
    and the acceleration along each (``a_start``, ``a_end``, mm/s^2). A hold runs between
    that speed and its move's entry (exit) speed, the speed changing at its low end at that
    acceleration, then flat at the high one; where the two are equal it is flat, as every
    hold of a profile without them."""

    start: NDArray[np.float64]
    end: NDArray[np.float64]
    a_start: NDArray[np.float64]
    a_end: NDArray[np.float64]


def _ramp_shape(run, va, vb, a):
    """Low and high speed of a hold of ``run`` mm run from ``va`` to ``vb`` changing at
    ``a`` at its low end, the length of that change (at most ``run``) and the speed it
    reaches (the high one, but for rounding)."""
    lo, hi = np.minimum(va, vb), np.maximum(va, vb)
    with np.errstate(divide="ignore", invalid="ignore"):
        d_r = np.minimum(nan_to_num((hi * hi - lo * lo) / (2.0 * a), nan=0.0), run)
    top = np.minimum(np.sqrt(lo * lo + 2.0 * a * d_r), hi)
    return lo, hi, d_r, top


def ramped_hold_time(run, va, vb, a) -> NDArray[np.float64]:
    """Time (s) of holds of ``run`` mm of travel run from speed ``va`` to ``vb`` (in the
    order they are run), the speed changing at ``a`` at the low end, flat at the high one
    (``va == vb``: ``run / va``); 0 where a hold would run at speed 0."""
    lo, hi, d_r, top = _ramp_shape(run, va, vb, a)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (top - lo) / a + (run - d_r) / hi
    return nan_to_num(t, nan=0.0, posinf=0.0)


def _ramped_hold_times(
    ar: ArcRamps, k: NDArray | slice, holds: tuple[NDArray, ...], v0: NDArray, v1: NDArray
) -> tuple[NDArray, NDArray]:
    """Time (s) in the start and end hold of the moves ``k`` (0 where a move has none):
    ``holds`` their (h_start, h_end, r_start, r_end), ``v0`` and ``v1`` their entry and exit
    speeds, ``ar`` the profile's :class:`ArcRamps`."""
    hs, he, rs, re = holds
    t0 = ramped_hold_time(rs * hs, ar.start[k], v0, ar.a_start[k])
    t1 = ramped_hold_time(re * he, v1, ar.end[k], ar.a_end[k])
    return np.where(hs > 0, t0, 0.0), np.where(he > 0, t1, 0.0)


def ramped_hold_speed(x, run, va, vb, a) -> NDArray[np.float64]:
    """Speed (mm/s) ``x`` mm into holds of :func:`ramped_hold_time`."""
    lo, hi, d_r, top = _ramp_shape(run, va, vb, a)
    from_low = np.where(va <= vb, x, run - x)
    return np.minimum(np.sqrt(lo * lo + 2.0 * a * np.clip(from_low, 0.0, d_r)), top)


def ramped_hold_motion(tau, run, va, vb, a) -> tuple[NDArray, NDArray]:
    """Travel (mm) and speed (mm/s) ``tau`` s into holds of :func:`ramped_hold_time`."""
    lo, hi, d_r, top = _ramp_shape(run, va, vb, a)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_r = nan_to_num((top - lo) / a, nan=0.0, posinf=0.0)
        t_f = nan_to_num((run - d_r) / hi, nan=0.0, posinf=0.0)
    rising = va <= vb
    # rising: the change, then flat; falling: flat, then the change
    tc = np.clip(np.where(rising, tau, tau - t_f), 0.0, t_r)
    flat = np.where(rising, np.maximum(tau - t_r, 0.0), np.minimum(tau, t_f))
    x = np.where(
        rising,
        lo * tc + 0.5 * a * tc * tc + hi * flat,
        hi * flat + top * tc - 0.5 * a * tc * tc,
    )
    v = np.where(
        rising, np.where(tau < t_r, lo + a * tc, hi), np.where(tau < t_f, hi, top - a * tc)
    )
    return np.minimum(x, run), v


def _ramped_sides(ev: Evaluation, cap: NDArray) -> tuple[NDArray, NDArray] | None:
    """Per junction, whether LinuxCNC's blend arc there runs between two caps and above the
    lower (:func:`_arc_ramps`): the slower block before the corner (``rising``) or after it
    (``falling``); None where the planner inserts no such arcs."""
    arc_v = ev.junction_arc_feed
    if arc_v is None:
        return None
    tp = ev.toolpath
    j = ev.junction
    c0, c1 = cap[j], cap[j + 1]
    arc = (ev.junction_hold > 0) & (ev.junction_travel > 0) & tp.is_feed[j] & tp.is_feed[j + 1]
    arc &= arc_v > np.fmin(c0, c1) * (1.0 + TOL.rel_equal)
    # programmed feeds that differ (caps that differ for other reasons -- chords of one
    # feed -- are the arcs' own business: their limits are at the junctions already)
    f0, f1 = tp.feed[j], tp.feed[j + 1]
    arc &= (f0 < f1 * (1.0 - TOL.rel_equal)) | (f1 < f0 * (1.0 - TOL.rel_equal))
    return arc & (c0 < c1 * (1.0 - TOL.rel_equal)), arc & (c1 < c0 * (1.0 - TOL.rel_equal))


def _arc_ramps(
    ev: Evaluation,
    sides: tuple[NDArray, NDArray],
    speeds: tuple[NDArray, ...],
    cap: NDArray,
    a_up: NDArray,
    a_dn: NDArray,
    a_blend: NDArray,
    holds: tuple[NDArray, NDArray, NDArray, NDArray],
) -> tuple[tuple[NDArray, ...], ArcRamps | None]:
    """LinuxCNC's blend arcs between blocks of different feeds (a slow plunge into a fast
    cut, a cut into a slow one). The arc's requested speed is the higher of the two blocks'
    (blendmath.c ``blendParamKinematics``: v_req = fmax(v_req_prev, v_req_this)), its top
    speed its own limit (``Evaluation.junction_arc_feed``); so the planner leaves the slow
    block at its speed u at the arc's tangent point and changes speed along the whole arc
    at the arc's tangential acceleration a (half the plane's, ``a_blend``), up to the arc's
    limit -- where the profile's corner speed, shared by both blocks, is the slow one's.
    Here the slow block's half arc runs from u to v_mid = min(top, sqrt(u^2 + 2 a d_slow))
    at the corner, the fast block's half from v_mid to v_far = min(top, sqrt(v_mid^2 +
    2 a d_fast)), at most what the fast block can still brake from (accelerate to) over
    the rest of its length; the fast block's entry (exit) is v_far, its speeds and time
    made again, the slow block keeps its speeds. (The time-reversed shape where the slow
    block comes second.) ``sides``: :func:`_ramped_sides`; both halves of those arcs were
    held while the speeds were planned. Returns the speeds (v0, peak, v1, time, d_cr) and
    the holds' speeds (None: no arc changed)."""
    rising, falling = sides
    sel = np.flatnonzero(rising | falling)
    arc_v = ev.junction_arc_feed
    if sel.size == 0 or arc_v is None:
        return speeds, None
    v0, peak, v1, time, d_cr = speeds
    h_start, h_end, r_start, r_end = holds
    tp = ev.toolpath
    s = ev.junction[sel]
    f = s + 1
    up = rising[sel]
    u = v1[s]  # the planned corner speed (the slow block's)
    top = np.fmin(arc_v[sel], np.maximum(cap[s], cap[f]))
    a = np.minimum(a_blend[s], a_blend[f])
    run_s, run_f = r_end[s] * h_end[s], r_start[f] * h_start[f]
    slow_run, fast_run = np.where(up, run_s, run_f), np.where(up, run_f, run_s)
    mid = np.fmin(top, np.sqrt(u * u + 2.0 * a * slow_run))
    far = np.fmin(top, np.sqrt(mid * mid + 2.0 * a * fast_run))
    fast = np.where(up, f, s)
    inner = np.maximum(tp.length[fast] - h_start[fast] - h_end[fast], 0.0)
    other = np.where(up, v1[fast], v0[fast])  # the fast block's planned speed at its far end
    a_far = np.where(up, a_dn[fast], a_up[fast])
    far = np.fmin(far, np.sqrt(other * other + 2.0 * a_far * inner))
    mid = np.fmin(mid, far)
    ok = (far > u * (1.0 + TOL.rel_equal)) & (u > 0)
    if not ok.any():
        return speeds, None
    s, f, up, mid, far, a = s[ok], f[ok], up[ok], mid[ok], far[ok], a[ok]
    v0, v1 = v0.copy(), v1.copy()
    ramps = ArcRamps(v0.copy(), v1.copy(), np.ones(tp.n), np.ones(tp.n))
    ramps.end[s], ramps.a_end[s] = mid, a
    ramps.start[f], ramps.a_start[f] = mid, a
    v1[s[~up]] = far[~up]  # the fast block's body ends (starts) at the arc's far speed
    v0[f[up]] = far[up]
    k = np.unique(np.concatenate([s, f]))
    t0, t1 = _ramped_hold_times(
        ramps, k, (h_start[k], h_end[k], r_start[k], r_end[k]), v0[k], v1[k]
    )
    t_hold = t0 + t1
    peak, d_cr, time = peak.copy(), d_cr.copy(), time.copy()
    between = tp.length[k] - h_start[k] - h_end[k]
    peak[k], d_cr[k], time[k] = _piece(v0[k], v1[k], cap[k], a_up[k], a_dn[k], between, t_hold)
    return (v0, peak, v1, time, d_cr), ramps


def _piecewise_ramp(q, u, pieces) -> tuple[NDArray, NDArray]:
    """Distance and time over which v^2 / 2 grows by ``q`` from speed ``u`` along
    ``pieces`` ((length, acceleration) pairs, in order; what the last cannot take is
    taken at its acceleration beyond it)."""
    q = np.maximum(q, 0.0)
    d = np.zeros(q.shape)
    t = np.zeros(q.shape)
    u = u.copy()
    for i, (length, a) in enumerate(pieces):
        take = q if i == len(pieces) - 1 else np.minimum(q, a * length)
        with np.errstate(divide="ignore", invalid="ignore"):
            w = np.sqrt(u * u + 2.0 * take)
            dt = np.where(take > 0, (w - u) / a, 0.0)
            dd = np.where(take > 0, take / a, 0.0)
        t += dt
        d += dd
        q = q - take
        u = w
    return d, t


def _exact_blend_times(
    fa: _FreeArcs,
    sel: NDArray,
    length: NDArray,
    acc: NDArray,
    h_start: NDArray,
    h_end: NDArray,
    r_start: NDArray,
    r_end: NDArray,
    v0: NDArray,
    peak: NDArray,
    v1: NDArray,
) -> tuple[NDArray, NDArray, NDArray]:
    """For the moves ``sel`` with free arcs: the holds and the acceleration that run them
    in the time the planner takes -- speed changing at a_blend along the arcs and at the
    move's acceleration between them, piece by piece -- with the same entry, peak and exit
    speeds. The holds of a free arc are scaled by a factor in [0, 1] and the acceleration
    keeps the reach: 1 is the shortened holds (flat, then a steep ramp), 0 one ramp at the
    mean acceleration over the whole stretch; the factor is found by bisection (the time
    falls as it grows). Returns the new h_start, h_end and acceleration of ``sel``."""
    fs, fe, ab = fa.start[sel], fa.end[sel], fa.a_blend[sel]
    a = acc[sel]
    L = length[sel]
    hs, he = h_start[sel], h_end[sel]
    rs, re = r_start[sel], r_end[sel]
    u0, pk, u1 = v0[sel], peak[sel], v1[sel]
    # the shortened holds of the free ends (the rest is held: a binding arc)
    keep_s = np.where(fs > 0, hs, 0.0)
    keep_e = np.where(fe > 0, he, 0.0)
    held_s, held_e = hs - keep_s, he - keep_e
    with np.errstate(divide="ignore", invalid="ignore"):
        t_held = np.where(held_s > 0, rs * held_s / u0, 0.0) + np.where(
            held_e > 0, re * held_e / u1, 0.0
        )
    t_held = np.nan_to_num(t_held, nan=0.0, posinf=0.0)
    mid = np.maximum(L - held_s - held_e - fs - fe, 0.0)
    q_up = (pk * pk - u0 * u0) / 2.0
    q_dn = (pk * pk - u1 * u1) / 2.0
    d_up, t_up = _piecewise_ramp(q_up, u0, ((fs, ab), (mid, a), (fe, ab)))
    d_dn, t_dn = _piecewise_ramp(q_dn, u1, ((fe, ab), (mid, a), (fs, ab)))
    cruise = np.maximum(mid + fs + fe - d_up - d_dn, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_exact = t_held + t_up + t_dn + np.where(pk > 0, cruise / pk, 0.0)
    reach = a * (L - hs - he)  # the reach the shortened holds give (kept at every factor)

    def shape(lam: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        s0, s1 = held_s + lam * keep_s, held_e + lam * keep_e
        inner = np.maximum(L - s0 - s1, 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            a_l = np.where(inner > 0, reach / inner, a)
            t_h = np.where(s0 > 0, rs * s0 / u0, 0.0) + np.where(s1 > 0, re * s1 / u1, 0.0)
            t_r = (pk - u0) / a_l + (pk - u1) / a_l
            cr = inner - (pk * pk - u0 * u0) / (2 * a_l) - (pk * pk - u1 * u1) / (2 * a_l)
            t = np.nan_to_num(t_h, nan=0.0, posinf=0.0) + t_r
            t = t + np.where(pk > 0, np.maximum(cr, 0.0) / pk, 0.0)
        return s0, s1, a_l, t

    lo, hi = np.zeros(L.size), np.ones(L.size)
    t_lo, t_hi = shape(lo)[3], shape(hi)[3]
    for _ in range(BLEND_SHAPE_STEPS):
        mid_l = (lo + hi) / 2.0
        t_mid = shape(mid_l)[3]
        # the time falls from lam = 0 to 1 where the ramps' mean is slower than the pieces
        up = (t_mid - t_exact) * (t_lo - t_hi) > 0
        lo = np.where(up, mid_l, lo)
        hi = np.where(up, hi, mid_l)
    lam = (lo + hi) / 2.0
    lam = np.where(t_exact >= np.maximum(t_lo, t_hi), np.where(t_lo >= t_hi, 0.0, 1.0), lam)
    lam = np.where(t_exact <= np.minimum(t_lo, t_hi), np.where(t_lo <= t_hi, 0.0, 1.0), lam)
    s0, s1, a_l, _ = shape(lam)
    return s0, s1, a_l


#: Bisection steps for the shape of a move along free blend arcs (2^-30 of the factor).
BLEND_SHAPE_STEPS = 30


class RoundsMemo:
    """The last jerk rounds :func:`build_profile` ran with a memo: their inputs (the window
    caps, the caps, the accelerations and jerks, the lengths between the holds: all the
    rounds read) and their outcome (the boundary speeds, the accelerations up and down).

    A fit's candidates often plan the same: an axis factor on an axis the program hardly
    moves, an arc limit on a program without arcs (the diagnose benchmark: 75 of its 689
    profiles read the rounds' inputs of the one before, bit for bit; 175 came out the same,
    the others changing a cap or an acceleration where it does not bind). The rounds are a
    function of their inputs alone, so where a build's inputs are bit for bit the last
    ones, their outcome is the one iterating would give. One entry, copies of both: a few
    columns of the program.
    """

    def __init__(self) -> None:
        self._last: tuple[int, tuple[NDArray, ...], tuple[NDArray, ...]] | None = None

    def get(self, rounds: int, inputs: tuple[NDArray, ...]) -> tuple[NDArray, ...] | None:
        """Copies of the outcome of the last rounds if they had ``rounds`` and these
        ``inputs`` bit for bit (NaNs and signed zeros included), else None."""
        if self._last is None:
            return None
        n, kept, out = self._last
        if n != rounds or not all(same_bits(a, b) for a, b in zip(inputs, kept, strict=True)):
            return None
        return tuple(x.copy() for x in out)

    def put(self, rounds: int, inputs: tuple[NDArray, ...], out: tuple[NDArray, ...]) -> None:
        """Remember these rounds (copies: the caller keeps using its arrays)."""
        self._last = (rounds, tuple(x.copy() for x in inputs), tuple(x.copy() for x in out))


def build_profile(
    ev: Evaluation,
    *,
    rounds: int = JERK_ROUNDS,
    lookahead: int | None = None,
    end_factor: float = 1.0,
    arc_factor: float = 1.0,
    release_directions: bool = False,
    memo: RoundsMemo | None = None,
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
    memo : RoundsMemo, optional
        The last jerk rounds of the profiles built before (a fit's candidates): where
        this profile's rounds have the same inputs, their outcome is taken, not iterated
        again (the same values).
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
    # The share of the lowest moved axis's acceleration a planner uses along the arcs it
    # inserts at corners (where it changes speed at that rate, not at the move's), before
    # the directions go.
    along_blends = BLEND_ACCELERATION.get(m.corner_blending, 0.0)
    if along_blends > 0.0:
        a_blend = along_blends * np.where(tp.axis_share > 0, m.max_acceleration, np.inf).min(axis=1)
    if arc_factor != 1.0:
        acc = np.where(tp.is_arc, acc * arc_factor, acc)
    share = ev.acceleration_share
    if share is not None:
        # (the last block's share of a parabolic end is end_factor's: LinuxCNC halves once)
        last = acc[-1] * min(end_factor, share[-1])
        acc = acc * share
        acc[-1] = last
    elif end_factor != 1.0 and tp.n:
        acc[-1] *= end_factor
    if release_directions:
        tp.release_derived(keep=("junctions",))
    b = boundary_caps(ev, cap, pause)
    if release_directions:
        tp.release_derived()  # the junctions too, once the caps have them
    length = tp.length
    h_start, h_end, r_start, r_end = _holds(ev)
    if along_blends > 0.0 and m.corner_blending == "linuxcnc":
        # the final speeds LinuxCNC's lazy look-ahead leaves lowered (core.engine.lookahead)
        lazy = lazy_caps(
            length, cap, b, acc, a_blend, h_start, h_end, r_start, r_end, ev.blend_rest
        )
        np.minimum(b, lazy, out=b)
        del lazy
    caps = _window_caps(b, length, acc, jerk, lookahead)  # the same in every round
    jerk_limited = bool(np.isfinite(jerk).any())
    # LinuxCNC's blend arcs between blocks of different feeds (_arc_ramps; trapezoidal
    # ramps only: the S-curve ramps keep the holds flat)
    sides = None
    if along_blends > 0.0 and m.corner_blending == "linuxcnc" and not jerk_limited:
        sides = _ramped_sides(ev, cap)
        if sides is not None and not (sides[0].any() or sides[1].any()):
            sides = None
    free_arcs: _FreeArcs | None = None
    if along_blends > 0.0 or ev.blend_rest is not None:
        h_start, h_end, r_end, free_arcs = _blend_holds(
            ev,
            cap,
            caps,
            acc,
            a_blend if along_blends > 0.0 else None,
            h_start,
            h_end,
            r_end,
            None if sides is None else sides[0] | sides[1],
        )
    if along_blends > 0.0 and sides is None:
        del a_blend  # (used by the holds only)
    holds = _Holds(length, h_start, h_end, r_start, r_end)
    if jerk_limited:
        free_arcs = None  # (the S-curve ramps keep the shortened holds)
    # The rounds change the accelerations only (see _Rounds); the last one (the rounds' end,
    # or the first whose change is below JERK_CONVERGED) makes the speeds and times.
    inputs = (caps, cap, acc, jerk, holds.between)
    got = memo.get(rounds, inputs) if memo is not None and rounds >= 1 else None
    speeds = None
    if got is not None:  # the same inputs as the last rounds: their outcome
        v, a_up, a_dn = got
    else:
        rnd = _Rounds(caps, cap, acc, jerk, holds)
        a_up, a_dn = rnd.a_up, rnd.a_dn
        last_round = max(rounds, 1) - 1
        for r in range(max(rounds, 1)):
            v = rnd.passes()
            if r == rounds - 1 or not jerk_limited:
                break
            if r == last_round:  # rounds < 1: the speeds before the accelerations' update
                speeds = _moves(v, cap, a_up, a_dn, holds)
            # Where a move's A_eff turns back (a staircase of falling caps: small steps give
            # a low A_eff, which holds the speed under the caps, which gives one long ramp
            # and a high A_eff, ...), _Rounds takes the geometric mean of the last two: the
            # rounds then close in on the answer between the two states instead of
            # alternating.
            change = rnd.step(v)
            del v
            if change < JERK_CONVERGED:
                speeds = None
                v = rnd.passes()
                break
        del rnd  # the rounds' caches go before the speeds and times are made (1M moves: 50 MB)
        if memo is not None and rounds >= 1:
            memo.put(rounds, inputs, (v, a_up, a_dn))
    del b, caps, inputs  # (the boundary caps: the passes are done)
    if speeds is None:
        speeds = _moves(v, cap, a_up, a_dn, holds)
        sel = np.zeros(0, dtype=np.intp)
        if free_arcs is not None:
            sel = np.flatnonzero(free_arcs.start + free_arcs.end > 0)
        if free_arcs is not None and sel.size:
            # The planner's time along its free arcs, piece by piece, with the same speeds
            # at the blocks' ends and peaks: the holds and accelerations that give it.
            s0, s1, a_l = _exact_blend_times(
                free_arcs, sel, length, acc, h_start, h_end, r_start, r_end, *speeds[:3]
            )
            h_start, h_end = h_start.copy(), h_end.copy()
            h_start[sel], h_end[sel] = s0, s1
            a_up, a_dn = a_up.copy(), a_dn.copy()
            a_up[sel] = a_l
            a_dn[sel] = a_l
            holds = _Holds(length, h_start, h_end, r_start, r_end)
            speeds = _moves(v, cap, a_up, a_dn, holds)
        del v
    arc_ramps = None
    if sides is not None:
        speeds, arc_ramps = _arc_ramps(
            ev, sides, speeds, cap, a_up, a_dn, a_blend, (h_start, h_end, r_start, r_end)
        )
        del a_blend
    # The holds' times are in the speeds now: the lengths between them go before the ramps
    # are made, and the cruise lengths once the ramps' marks have them.
    del holds
    v0, peak, v1, time, d_cr = speeds
    del speeds
    if release_directions:  # a single analysis (not the many profiles of a fit)
        release_free_heap()  # the rounds' holes (5M arcs: 100 MB; see core.model.heap)
    if jerk_limited:
        marks = _ramp_marks(v0, peak, v1, d_cr)
        del d_cr
        _, dv_up, lo_up = _ramp_changes(v0, peak, v1, marks, rising=True)
        _, dv_dn, lo_dn = _ramp_changes(v0, peak, v1, marks, rising=False)
        del marks
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
        arc_ramps=arc_ramps,
    )
