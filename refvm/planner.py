"""The reference interpreter's planner: a jerk-limited path-speed planner stepped at the cycle.

This is the motion half of the reference controller, written without ncperf's profile: it
knows nothing of ncperf's forward/backward passes or effective accelerations. It takes the
limits (:class:`Limits`) and steps time. Its units are the segments of :mod:`refvm.limits`
(moves, parts of moves, corner arcs); below they are called moves.

State and step
--------------
The state is the arc length ``s`` from the program start, the path speed ``v`` and the
tangential acceleration ``a``. Each cycle of ``dt`` the planner picks the acceleration
``a'`` it will have at the end of the cycle; in between the acceleration ramps linearly
from ``a`` to ``a'`` (jerk ``(a' - a) / dt``), so ``|a'| <= A`` and ``|a' - a| <= J dt``
hold by construction. Without a jerk limit (``J = inf``) the acceleration is ``a'`` over
the whole cycle (LinuxCNC 2.9's trapezoid: position step ``(v + v') / 2 dt``).

It picks the **largest** ``a'`` whose end-of-cycle state is *safe*:

1. the speed, plus the overshoot ``a'^2 / (2 J)`` of bringing a positive acceleration to 0,
   stays within the block's cap;
2. for every upcoming limit ``w`` at distance ``d`` (boundary caps, and 0 at the end of the
   look-ahead window), :func:`stop_distance` from the new state to ``w`` is at most ``d``.

Safety only gets harder as ``a'`` grows, so the largest safe ``a'`` is found by bisection
between ``a - J dt`` and ``a + J dt``. Riding that boundary *is* the time-optimal
jerk-limited braking curve, so the speed follows S-curves without bang-bang chatter; at a
cap the speed is clamped to it with ``a = 0``.

Why checking every limit separately is enough: :func:`stop_distance` is the distance of the
hardest braking that ends exactly at ``w`` with zero acceleration. For a nearer limit ``w1``
and a farther lower one ``w2``, braking for ``w2`` is at every time below braking for
``w1`` (it keeps the jerk ``-J`` at least as long), so if each can be met alone, braking for
the lowest one meets them all. Limits that a nearer, lower one dominates are dropped. A
limit's braking uses the smallest tangential acceleration and jerk of the blocks between
here and there (conservative where the blocks' directions differ).

A cycle that reaches the end of a block is split there ("the remainder of the step is
carried into the next block"): the state at the boundary must meet the boundary's cap, and
the rest of the cycle is decided again in the next block with its own limits. At a stop
(exact stop, dwell, rapid <-> feed, operation change, program end) the machine lands at
rest on the boundary: once the remaining landing takes less than a cycle the position is
set on the boundary (an in-position window of at most one cycle of motion).
"""

from __future__ import annotations

import math
from array import array
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

INF = math.inf

#: Bisection rounds for the acceleration of a cycle: 2^-16 of the interval (|a' - a| <= J dt,
#: or 2 A without a jerk limit) is below 0.1 mm/s^2, i.e. below 1e-4 mm/s of speed per cycle.
BISECTION_ROUNDS = 16
#: Relative slack on speed comparisons (float rounding of v + a^2 / 2J against a cap).
SPEED_RTOL = 1e-12
#: Distance slack (mm) in the braking check: float rounding of the arc length.
DIST_TOL = 1e-9
#: A run stops with an error when the machine makes no progress for this long (s): only a
#: bug can do that (every limit is positive except at stops, which the machine leaves).
STALL_TIME = 5.0


def stop_distance(v: float, a: float, w: float, acc: float, jerk: float) -> float:
    """Shortest distance (mm) in which the speed can be brought to ``w`` and kept there.

    The hardest braking with jerk ``jerk`` and at most ``acc``: the acceleration falls at
    ``-jerk`` from ``a`` to ``-Ap`` (``Ap <= acc``), holds, and rises at ``+jerk`` to 0 just
    as the speed reaches ``w``. Zero when the speed can already stay at or below ``w`` (it
    is below and a positive ``a`` can be brought to 0 before overshooting). When the
    machine already brakes harder than needed (``a < 0`` and ``v - w < a^2 / 2J``), the
    distance until the speed crosses ``w`` with the acceleration rising at ``+jerk``.

    Parameters
    ----------
    v : float, mm/s
    a : float, mm/s^2
    w : float, mm/s
        Target speed.
    acc : float, mm/s^2
    jerk : float, mm/s^3 (may be inf)
    """
    if jerk == INF:
        if v <= w * (1.0 + SPEED_RTOL):
            return 0.0
        return (v * v - w * w) / (2.0 * acc)
    ap = a if a > 0.0 else 0.0
    if v + ap * ap / (2.0 * jerk) <= w * (1.0 + SPEED_RTOL) + 1e-12:
        return 0.0
    dv = v - w
    if a < 0.0 and dv <= a * a / (2.0 * jerk):
        disc = max(a * a - 2.0 * jerk * dv, 0.0)
        t = (-a - math.sqrt(disc)) / jerk
        return v * t + a * t * t / 2.0 + jerk * t**3 / 6.0
    peak = math.sqrt(a * a / 2.0 + jerk * dv)
    hold = 0.0
    if peak > acc:
        peak = acc
        hold = ((a * a - 2.0 * acc * acc) / (2.0 * jerk) + dv) / acc
    t1 = max((a + peak) / jerk, 0.0)
    d1 = v * t1 + a * t1 * t1 / 2.0 - jerk * t1**3 / 6.0
    v1 = v + a * t1 - jerk * t1 * t1 / 2.0
    d2 = v1 * hold - peak * hold * hold / 2.0
    t3 = peak / jerk
    d3 = w * t3 + jerk * t3**3 / 6.0
    return d1 + d2 + d3


def lim_s_end(end: float, v: float, w: float, acc: float, weight: float) -> float:
    """Last arc length (mm) in a move ending at ``end`` from which speed ``v`` can still be
    braked, without jerk limit at ``acc``, to ``w`` at a limit ``weight`` (sum of 2 A_k L_k
    of the moves in between) beyond the move's end."""
    return end - (v * v - w * w - weight) / (2.0 * acc)


def stop_time(v: float, a: float, acc: float, jerk: float) -> float:
    """Duration (s) of the braking of :func:`stop_distance` to rest (``w = 0``)."""
    if jerk == INF:
        return v / acc
    ap = a if a > 0.0 else 0.0
    if v + ap * ap / (2.0 * jerk) <= 0.0:
        return 0.0
    if a < 0.0 and v <= a * a / (2.0 * jerk):
        disc = max(a * a - 2.0 * jerk * v, 0.0)
        return (-a - math.sqrt(disc)) / jerk
    peak = math.sqrt(a * a / 2.0 + jerk * v)
    hold = 0.0
    if peak > acc:
        peak = acc
        hold = ((a * a - 2.0 * acc * acc) / (2.0 * jerk) + v) / acc
    return max((a + peak) / jerk, 0.0) + hold + peak / jerk


@dataclass(frozen=True, eq=False)
class Limits:
    """What the planner must respect, per segment (a move, a part of one, or a corner arc)
    and per segment boundary.

    Attributes
    ----------
    length : (n,) float, mm
    cap : (n,) float, mm/s
        Cruise cap of each segment.
    boundary : (n + 1,) float, mm/s
        Speed cap at each segment boundary (0 at the program ends and at stops).
    acc, jerk : (n,) float, mm/s^2 and mm/s^3
        Tangential acceleration and jerk of each segment (jerk may be inf).
    dwell : (n,) float, s
        Rest after each segment.
    window_end : (n,) int or None
        Look-ahead: while in segment i the planner sees up to boundary ``window_end[i]`` and
        must be able to stop there; None: full look-ahead.
    """

    length: NDArray[np.float64]
    cap: NDArray[np.float64]
    boundary: NDArray[np.float64]
    acc: NDArray[np.float64]
    jerk: NDArray[np.float64]
    dwell: NDArray[np.float64]
    window_end: NDArray[np.int64] | None = None

    def __post_init__(self) -> None:
        n = np.shape(self.length)[0]
        for name, size in (
            ("length", n),
            ("cap", n),
            ("boundary", n + 1),
            ("acc", n),
            ("jerk", n),
            ("dwell", n),
        ):
            a = np.asarray(getattr(self, name), dtype=np.float64)
            if a.shape != (size,):
                raise ValueError(f"{name} must have shape ({size},), got {a.shape}")
            object.__setattr__(self, name, a)
        if not (np.all(self.cap > 0) and np.all(self.acc > 0) and np.all(self.jerk > 0)):
            raise ValueError("caps, accelerations and jerks must be positive")
        if self.window_end is not None:
            we = np.asarray(self.window_end, dtype=np.int64)
            if we.shape != (n,):
                raise ValueError(f"window_end must have shape ({n},), got {we.shape}")
            object.__setattr__(self, "window_end", we)


@dataclass(frozen=True, eq=False)
class Motion:
    """The setpoint at every cycle, from rest at the start to rest at the end.

    Attributes
    ----------
    s : (m,) float, mm
        Arc length from the program start.
    v : (m,) float, mm/s
        Path speed.
    move : (m,) int
        Segment being run (during a dwell, the segment before it).
    boundary_speed : (n + 1,) float, mm/s
        Speed at which each segment boundary was passed (exact, not sampled; 0 at stops).
    violation : float, mm/s
        Largest speed above a boundary cap at a crossing (discretisation; normally ~0).
    """

    s: NDArray[np.float64]
    v: NDArray[np.float64]
    move: NDArray[np.int64]
    boundary_speed: NDArray[np.float64]
    violation: float


class _Planner:
    """One run of the planner over :class:`Limits` (pure-Python scalars: the hot loop)."""

    def __init__(self, lim: Limits, dt: float) -> None:
        self.lim = lim
        self.dt = dt
        self.n = int(lim.length.size)
        self.S = np.concatenate([[0.0], np.cumsum(lim.length)])
        self.S_l = self.S.tolist()
        self.cap = lim.cap.tolist()
        self.bnd = lim.boundary.tolist()
        self.acc = lim.acc.tolist()
        self.jerk = lim.jerk.tolist()
        self.dwell = lim.dwell.tolist()
        self.acc_min = float(lim.acc.min()) if self.n else 1.0
        self.jerk_min = float(lim.jerk.min()) if self.n else INF

    # ----------------------------------------------------------------- look-ahead
    def targets(self, b: int) -> list[tuple[float, float, float, float, float]]:
        """(position, cap, acc, jerk, weight) of the limits ahead of move ``b`` that can bind.

        Without a jerk limit braking is exact over moves of different accelerations: the
        square of the speed falls by at most 2 A_k L_k over move k, and ``weight`` is the sum
        of 2 A_k L_k over the whole moves between move ``b`` and the limit.
        """
        lim = self.lim
        S = self.S
        reach = stop_distance(self.cap[b], self.acc[b], 0.0, self.acc_min, self.jerk_min)
        hi = int(np.searchsorted(S, S[b + 1] + reach + DIST_TOL, side="right")) - 1
        hi = min(max(hi, b + 1), self.n)
        window_end = False
        if lim.window_end is not None and lim.window_end[b] < hi:
            hi = max(int(lim.window_end[b]), b + 1)
            window_end = hi < self.n
        w = lim.boundary[b + 1 : hi + 1].copy()
        if window_end:
            w[-1] = 0.0  # the planner has not seen beyond: it must be able to stop there
        # Braking to boundary m runs on moves b..m-1: with a jerk limit it gets their lowest
        # limits (conservative where their directions differ).
        acc = np.minimum.accumulate(lim.acc[b:hi])
        jerk = np.minimum.accumulate(lim.jerk[b:hi])
        weight = np.concatenate(
            [[0.0], np.cumsum(2.0 * lim.acc[b + 1 : hi] * lim.length[b + 1 : hi])]
        )
        # Keep only new lows: a limit behind a nearer, lower one is met by meeting that one.
        prev = np.concatenate([[np.inf], np.minimum.accumulate(w)[:-1]])
        keep = np.flatnonzero(w < prev)
        pos = S[b + 1 : hi + 1]
        return list(
            zip(
                pos[keep].tolist(),
                w[keep].tolist(),
                acc[keep].tolist(),
                jerk[keep].tolist(),
                weight[keep].tolist(),
                strict=True,
            )
        )

    # ----------------------------------------------------------------- one cycle
    @staticmethod
    def _advance(s, v, a, a_new, h, jerk, end):
        """Integrate ``h`` seconds ending at acceleration ``a_new``; stop at ``end``.

        Returns (time used, s, v, a, reached end).
        """
        if jerk == INF:
            a0, j = a_new, 0.0
        else:
            a0, j = a, (a_new - a) / h
        v1 = v + a0 * h + j * h * h / 2.0
        s1 = s + v * h + a0 * h * h / 2.0 + j * h**3 / 6.0
        # Lowest speed over the cycle: braking may reach rest inside it.
        vmin = min(v, v1)
        tmin = h if v1 <= v else 0.0
        if j > 0.0 and a0 < 0.0 and -a0 / j < h:
            tmin = -a0 / j
            vmin = v + a0 * tmin + j * tmin * tmin / 2.0
        if vmin < 0.0:
            # rest inside the cycle: the first root of v + a0 t + j t^2 / 2 = 0
            if j == 0.0:
                t0 = -v / a0
            else:
                t0 = (-a0 - math.sqrt(max(a0 * a0 - 2.0 * j * v, 0.0))) / j
            t0 = min(max(t0, 0.0), h)
            s0 = s + v * t0 + a0 * t0 * t0 / 2.0 + j * t0**3 / 6.0
            if s0 >= end:
                return _Planner._cross(s, v, a0, j, end, t0)
            return t0, s0, 0.0, 0.0, False
        if s1 >= end:
            return _Planner._cross(s, v, a0, j, end, h)
        return h, s1, v1, a0 + j * h, False

    @staticmethod
    def _cross(s, v, a0, j, end, h):
        """State where the arc length reaches ``end`` within ``h`` (s is monotone there)."""
        # Newton from the far end, kept inside the bracket [lo, hi] (s'' may change sign).
        lo, hi = 0.0, h
        t = hi
        for _ in range(60):
            f = s + v * t + a0 * t * t / 2.0 + j * t**3 / 6.0 - end
            if abs(f) <= 1e-13 or hi - lo < 1e-15:
                break
            if f > 0:
                hi = t
            else:
                lo = t
            fp = v + a0 * t + j * t * t / 2.0
            tn = t - f / fp if fp > 0 else 0.5 * (lo + hi)
            t = tn if lo < tn < hi else 0.5 * (lo + hi)
        return t, end, max(v + a0 * t + j * t * t / 2.0, 0.0), a0 + j * t, True

    def run(self) -> Motion:
        n = self.n
        dt = self.dt
        S = self.S_l
        # array('d') holds 8 bytes a sample (a list of floats 32): hours of 1 ms cycles fit.
        out_s = array("d", [0.0])
        out_v = array("d", [0.0])
        out_b = array("q", [0])
        if n == 0:
            return Motion(np.zeros(1), np.zeros(1), np.zeros(1, dtype=np.int64), np.zeros(1), 0.0)
        s = v = a = 0.0
        b = 0
        passed = [0.0] * (n + 1)
        tg = self.targets(0)
        rest = 0.0
        done = False
        violation = 0.0
        stalled = 0.0
        last_s = -1.0
        while True:
            # ------------------------------------------------ cruise at the cap: skip ahead
            cap = self.cap[b] if b < n else 0.0
            if not done and rest <= 0.0 and a == 0.0 and v == cap and v > 0.0:
                lim_s = S[b + 1]
                A_b = self.acc[b]
                for d, w, A, J, W in tg:
                    if J == INF:
                        if v > w:
                            lim_s = min(lim_s, lim_s_end(S[b + 1], v, w, A_b, W))
                    else:
                        lim_s = min(lim_s, d - stop_distance(v, 0.0, w, A, J))
                k = int((lim_s - s) / (v * dt)) - 1
                if k >= 2:
                    step = v * dt
                    out_s.extend(s + step * i for i in range(1, k + 1))
                    out_v.extend(array("d", [v]) * k)
                    out_b.extend(array("q", [b]) * k)
                    s += step * k
                    continue
            h = dt
            while h > 1e-15:
                if rest > 0.0:
                    use = min(rest, h)
                    rest -= use
                    h -= use
                    continue
                if done:
                    break
                end = S[b + 1]
                A = self.acc[b]
                J = self.jerk[b]
                cap = self.cap[b]
                r = end - s
                if self.bnd[b + 1] == 0.0:
                    # a stop at the end of this move: land on it once the landing fits in h
                    if r <= DIST_TOL or (
                        stop_time(v, a, A, J) <= h
                        and r <= stop_distance(v, a, 0.0, A, J) + v * h + DIST_TOL
                    ):
                        used = min(stop_time(v, a, A, J), h) if r > DIST_TOL else 0.0
                        h -= used
                        s, v, a = end, 0.0, 0.0
                        rest = self.dwell[b]
                        b += 1
                        if b == n:
                            done = True
                        else:
                            tg = self.targets(b)
                        continue
                # Bringing a positive acceleration to 0 at the cap may end in the next move:
                # the lower of the two jerks (the braking checks use each move's own).
                J_cap = J if b + 1 >= n or self.bnd[b + 1] == 0.0 else min(J, self.jerk[b + 1])
                a_new = self._decide(s, v, a, h, b, tg, A, J, J_cap, cap, end)
                used, s, v, a, crossed = self._advance(s, v, a, a_new, h, J, end)
                h -= used
                if crossed:
                    passed[b + 1] = v
                    over = v - self.bnd[b + 1]
                    if over > violation:
                        violation = over
                    b += 1
                    if b == n:
                        done = True
                        v = a = 0.0
                        rest = self.dwell[n - 1]
                        continue
                    if self.bnd[b] == 0.0:
                        v = a = 0.0
                    else:
                        v = min(v, self.cap[b])
                    A1 = self.acc[b]
                    a = min(max(a, -A1), A1)
                    tg = self.targets(b)
                    if self.dwell[b - 1] > 0.0:
                        rest = self.dwell[b - 1]
                elif v >= cap * (1.0 - 1e-9):
                    # at the cap: hold it exactly (no chatter)
                    v = cap
                    if J == INF or abs(a) <= J * dt:
                        a = 0.0
            out_s.append(s)
            out_v.append(v)
            out_b.append(min(b, n - 1) if not (done or rest > 0.0) else max(b - 1, 0))
            if done and rest <= 0.0:
                break
            if s > last_s + 1e-12:
                last_s = s
                stalled = 0.0
            elif rest <= 0.0:
                stalled += dt
                if stalled > STALL_TIME:
                    raise RuntimeError(
                        f"reference interpreter stalled at s = {s:.6f} mm in move {b} "
                        f"(v = {v}, a = {a})"
                    )
        return Motion(
            s=np.frombuffer(out_s, dtype=np.float64).copy(),
            v=np.frombuffer(out_v, dtype=np.float64).copy(),
            move=np.frombuffer(out_b, dtype=np.int64).copy(),
            boundary_speed=np.asarray(passed),
            violation=violation,
        )

    def _decide(self, s, v, a, h, b, tg, A, J, J_cap, cap, end):
        """The largest safe acceleration at the end of the (sub)cycle of ``h`` seconds."""
        if J == INF:
            lo, hi = -A, A
            hi = min(hi, (cap - v) / h)
        else:
            lo, hi = max(a - J * h, -A), min(a + J * h, A)
            # cap: v' + a'^2 / (2 J_cap) <= cap with v' = v + (a + a') h / 2
            c = v + a * h / 2.0 - cap
            disc = h * h / 4.0 - 2.0 * c / J_cap
            bound = J_cap * (-h / 2.0 + math.sqrt(disc)) if disc >= 0.0 else -INF
            if bound < 0.0:
                bound = 2.0 * (cap - v) / h - a
            hi = min(hi, bound)
        if hi <= lo:
            return lo
        if self._safe(s, v, a, hi, h, tg, A, J, end):
            return hi
        if not self._safe(s, v, a, lo, h, tg, A, J, end):
            return lo
        for _ in range(BISECTION_ROUNDS):
            mid = 0.5 * (lo + hi)
            if self._safe(s, v, a, mid, h, tg, A, J, end):
                lo = mid
            else:
                hi = mid
        return lo

    def _safe(self, s, v, a, a_new, h, tg, A_b, J, end):
        """Whether the state after the (sub)cycle ending at ``a_new`` can meet every limit."""
        _, s1, v1, a1, crossed = self._advance(s, v, a, a_new, h, J, end)
        for d, w, A, Jt, W in tg:
            r = d - s1
            if r < -DIST_TOL:
                continue
            if Jt == INF:
                if v1 * v1 - w * w > 2.0 * A_b * (end - s1) + W + 2.0 * A_b * DIST_TOL:
                    return False
            elif stop_distance(v1, a1, w, A, Jt) > r + DIST_TOL:
                return False
        return True


def plan_motion(limits: Limits, dt: float) -> Motion:
    """Step the planner at ``dt`` (s) from rest at the start to rest at the end."""
    if not dt > 0:
        raise ValueError(f"dt must be positive, got {dt}")
    return _Planner(limits, dt).run()
