"""Compiled (numba) kernels of the diagnosis's hottest loops, element by element (and
``kernel``, their settings, with which core.engine.lookahead compiles LinuxCNC's walks).

Imported only through :func:`core.model.jit.compiled` (allowed by the diagnosis, numba
installed, ``NCPERF_NO_JIT`` not set). Every kernel does, for each element, the same
floating-point operations in the same order as the numpy code it stands in for (named in
its docstring), so that both give the same bits (``tests/test_jit.py``): no fastmath (no
reordering, no fused multiply-adds), x**2 written x * x as numpy's square, x**3 as
``math.pow`` (the C library's pow, as numpy's power), numpy's NaN rules for minimum,
maximum, clip and nan_to_num (:func:`vmin`, :func:`vmax`, :func:`clip`, :func:`finite`).
``error_model="numpy"``: a division by zero gives inf or NaN as in numpy, not an exception.
One computation is not numpy's where its bits cannot reach a result: the place inside a
jerk-limited ramp with its cubes as products (:func:`_place_guess`), for the guess's
Newton steps (a guess's bracket is taken only where the check proves it) and for the
check's comparisons where it is farther from the bound than the two places can differ
(:func:`_place_vs`; else numpy's operations decide).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: The kernels are compiled once and kept on disk (numba's cache: beside this file where
#: it can write, else the user's cache folder), so a later process loads them instead.
kernel = njit(cache=True, error_model="numpy", nogil=True)

#: np.nan_to_num's value for +inf.
FLOAT_MAX = float(np.finfo(np.float64).max)


@kernel
def vmax(a: float, b: float) -> float:
    """np.maximum of two floats: NaN if either is; the second of two equal values (numpy's
    vector loops take the CPU's max, which returns its second operand for +0.0 and -0.0:
    the sign of a zero as there)."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a > b else b


@kernel
def vmin(a: float, b: float) -> float:
    """np.minimum of two floats: NaN if either is; the second of two equal values."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a < b else b


@kernel
def clip(x: float, lo: float, hi: float) -> float:
    """np.clip of a float (NaN stays NaN)."""
    return vmin(vmax(x, lo), hi)


@kernel
def finite(x: float) -> float:
    """np.nan_to_num of a float: NaN 0, +-inf the largest float of its sign."""
    if x != x:
        return 0.0
    if x == np.inf:
        return FLOAT_MAX
    if x == -np.inf:
        return -FLOAT_MAX
    return x


@kernel
def _place_of(
    exact: bool,
    p: float,
    rising: bool,
    lo: float,
    dv: float,
    two_a: float,
    vb2: float,
    span: float,
    r: float,
    c: float,
    six_rs: float,
    inner0: float,
    rr: float,
    half_r: float,
    one_r: float,
) -> float:
    """core.engine.profile._place for one element (``exact``), or with its cubes as
    products (:func:`_place_guess`)."""
    x = p * dv if rising else (1.0 - p) * dv
    x = lo + x
    x = x * x
    x = x - vb2
    x = x / two_a
    pp = p * p
    # G: the ends of the ramp where p is in them, else the middle (numpy computes the
    # middle everywhere and writes the ends over it: the same values)
    if p < r:
        big_g = c * (math.pow(p, 3.0) if exact else pp * p) / six_rs
    elif p > one_r:
        q = 1.0 - p
        big_g = 0.5 - q + c * (math.pow(q, 3.0) if exact else q * q * q) / six_rs
    else:
        big_g = inner0 + c * ((pp - rr) * 0.5 - half_r * (p - r))
    big_g = big_g - pp * 0.5
    big_g = span * big_g
    x = x + big_g
    return -x if not rising else x


@kernel
def _place(p: float, rising: bool, *terms: float) -> float:
    """core.engine.profile._place for one element (``terms``: its _place_terms)."""
    return _place_of(True, p, rising, *terms)


@kernel
def _place_guess(p: float, rising: bool, *terms: float) -> float:
    """:func:`_place` with the cubes as products (p * p * p: within two roundings of pow's,
    several times cheaper than the C library's pow), for the Newton steps of
    :func:`_ramp_speed`'s guess and, where it decides, :func:`_sure`'s comparisons
    (:func:`_place_vs`). A guess's bits do not reach the result: the bracket it names is
    taken only where :func:`_sure` proves the halvings end in it, else the halvings run --
    core.engine.profile._checked_guess's argument, which holds for any guess. The diagnose
    benchmark's speeds at its calibration places: 22-27 % less time for the guess, the
    same bits (2026-11-28)."""
    return _place_of(False, p, rising, *terms)


@kernel
def _g(p: float, r: float, c: float, rs: float) -> float:
    """core.engine.profile.s_curve_g for one element."""
    p = clip(p, 0.0, 1.0)
    q = 1.0 - p
    if p < r:
        return c * p * p / (2.0 * rs)
    if p > 1.0 - r:
        return 1.0 - c * q * q / (2.0 * rs)
    return c * (p - 0.5 * r)


#: :func:`_place_vs`'s slack, a share of the ramp's margin (TOL.sure_compare x T). The place
#: with products for cubes (:func:`_place_guess`) is within 11 u T of numpy's (u = 2^-53):
#: the cubes differ by at most 4 u of their size (two roundings against pow's one, within
#: an ulp), and that difference, below 1/12 in G, moves G, G - p^2 / 2, span (...) and the
#: sum with the quadratic part (each at most T, lo and dv >= 0 where the ramp is sane) by at
#: most one rounding each: 2.5 u, 4.5 u and 6.5 u |span|, then + 4 u T. 1e-14 T is 8 times that.
SURE_SLACK = 0.1


@kernel
def _place_vs(p: float, bound: float, slack: float, rising: bool, terms: tuple) -> int:
    """core.engine.profile._place at ``p`` against ``bound``: -1 below, 1 at or above, 0
    neither (NaN). Told by :func:`_place_guess` where it is more than ``slack`` off the bound
    (farther than the two places can differ: :data:`SURE_SLACK`), else by :func:`_place`."""
    x = _place_guess(p, rising, *terms)
    if x < bound - slack:
        return -1
    if x >= bound + slack:
        return 1
    x = _place(p, rising, *terms)
    return -1 if x < bound else (1 if x >= bound else 0)


@kernel
def _sure(
    a_p: float, b_p: float, goal: float, rising: bool, margin: float, sane: bool, terms: tuple
) -> bool:
    """core.engine.profile._sure for one element (``margin`` and ``sane`` of its ramp): the
    same answers, each comparison told by :func:`_place_vs` (the place with products for
    cubes where that decides it, about 20 % of the speeds' time)."""
    if not sane:
        return False
    slack = SURE_SLACK * margin
    if not (a_p == 0.0 or _place_vs(a_p, goal - margin, slack, rising, terms) < 0):
        return False
    return b_p == 1.0 or _place_vs(b_p, goal + margin, slack, rising, terms) > 0


@kernel
def _ramp(
    lo: float,
    dv: float,
    a: float,
    vb: float,
    acc: float,
    jerk: float,
    consts: tuple[float, float, float, int, int, int],
) -> tuple:
    """What the place inside a ramp needs of the ramp alone (computed once per move and
    direction): :func:`_place`'s terms, then rs, the rate dx/dp / speed, the margin of
    :func:`_sure` and whether the ramp is sane there (s_curve_shape, _place_terms)."""
    nil_speed, tiny, sure_compare = consts[0], consts[1], consts[2]
    span = dv * dv / a
    a_p = vmin(acc, math.sqrt(dv * jerk))
    t_j = a_p / jerk
    total = dv / a_p + t_j
    r = t_j / total if (dv > nil_speed and math.isfinite(jerk) and total > 0) else 0.0
    r = clip(finite(r), 0.0, 0.5)
    c = 1.0 / (1.0 - r)
    rs = vmax(r, tiny)
    vb2 = vb * vb
    two_a = 2.0 * a
    e = lo + dv
    margin = sure_compare * ((e * e + vb2) / two_a + abs(span))
    sane = two_a > 0 and lo >= 0 and dv >= 0 and math.isfinite(margin)
    terms = (lo, dv, two_a, vb2, span, r, c, 6.0 * rs, c * r * r / 6.0, r * r, 0.5 * r, 1.0 - r)
    return terms, rs, dv / (0.5 * two_a), margin, sane


@kernel
def _ramp_speed(
    target: float,
    rising: bool,
    ramp: tuple,
    consts: tuple[float, float, float, int, int, int],
) -> float:
    """The speed inside a jerk-limited ramp of core.engine.profile.Profile.speed_at for one
    element of a :func:`_ramp`: _bisect_ramp (_checked_guess, _sure, _halvings) and
    s_curve_g; the guess's Newton steps on :func:`_place_guess` (the same bits: see there)."""
    halvings, halfway, newton = consts[3], consts[4], consts[5]
    terms, rs, rate, margin, sane = ramp
    lo, dv, two_a, vb2 = terms[0], terms[1], terms[2], terms[3]
    r, c = terms[5], terms[6]
    goal = target if rising else -target
    # _checked_guess
    dist = goal if rising else -goal
    u = (math.sqrt(vmax(vb2 + two_a * dist, 0.0)) - lo) / dv
    p = clip(finite(u if rising else 1.0 - u), 0.0, 1.0)
    for _ in range(newton):
        g = _g(p, r, c, rs)
        speed = lo + dv * (g if rising else 1.0 - g)
        step = (_place_guess(p, rising, *terms) - goal) / (rate * speed)
        p = clip(finite(p - step), 0.0, 1.0)
    full = float(1 << halvings)
    lo_p = vmin(math.floor(p * full), full - 1.0) / full
    hi_p = lo_p + 1.0 / full
    if not _sure(lo_p, hi_p, goal, rising, margin, sane, terms):
        part = float(1 << halfway)
        a_h = math.floor(lo_p * part) / part
        b_h = a_h + 1.0 / part
        if not _sure(a_h, b_h, goal, rising, margin, sane, terms):
            a_h, b_h = 0.0, 1.0
            for _ in range(halfway):
                m = (a_h + b_h) * 0.5
                if _place(m, rising, *terms) < goal:
                    a_h = m
                else:
                    b_h = m
        for _ in range(halvings - halfway):
            m = (a_h + b_h) * 0.5
            if _place(m, rising, *terms) < goal:
                a_h = m
            else:
                b_h = m
        lo_p, hi_p = a_h, b_h
    g_share = _g(0.5 * (lo_p + hi_p), r, c, rs)
    return lo + dv * g_share if rising else lo + dv * (1.0 - g_share)


@kernel
def move_at(x: float, start_s: np.ndarray, hint: int) -> int:
    """core.model.toolpath.ToolPath.move_at of one arc length: the number of ``start_s``
    (sorted) at or below ``x``, less one, clipped to the moves (NaN: the last, as numpy's
    searchsorted puts NaN past every number); looked for from the move ``hint`` on where
    ``x`` lies there or after it, else by halving."""
    n = start_s.size
    if x != x:
        return n - 1
    lo, hi = 0, n  # below lo every start is at or below x, from hi on above it
    if 0 <= hint < n and start_s[hint] <= x:
        bound = 1  # (galloping from the hint: most samples stay on or near its move)
        while hint + bound < n and start_s[hint + bound] <= x:
            bound *= 2
        lo, hi = hint + bound // 2 + 1, min(hint + bound, n)
    while lo < hi:
        mid = (lo + hi) // 2
        if start_s[mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    return min(max(lo - 1, 0), n - 1)


@kernel
def profile_speed(
    s: np.ndarray,
    start_s: np.ndarray,
    length: np.ndarray,
    hold_start: np.ndarray,
    hold_end: np.ndarray,
    v_entry: np.ndarray,
    v_exit: np.ndarray,
    a_up: np.ndarray,
    a_down: np.ndarray,
    v_peak: np.ndarray,
    ramps: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    with_ramps: bool,
    consts: tuple[float, float, float, int, int, int],
) -> np.ndarray:
    """core.engine.profile.Profile.speed_at at arc lengths ``s`` (with ToolPath.move_at):
    ``ramps`` the profile's (lo_u, dv_u, lo_d, dv_d, acc, jerk) where
    ``with_ramps``; ``consts`` (TOL.nil_speed, TOL.tiny, TOL.sure_compare, HALVINGS,
    HALFWAY, NEWTON_STEPS)."""
    lo_u, dv_u, lo_d, dv_d, acc, jerk = ramps
    nil_speed = consts[0]
    out = np.empty(s.size)
    m = 0  # the last sample's move: the next is searched from there
    # the last move's ramps (samples come along the path: most share their move's)
    at_up = at_dn = -1
    ramp_up = ramp_dn = _ramp(1.0, 1.0, 1.0, 0.0, 1.0, 1.0, consts)
    for i in range(s.size):
        m = move_at(s[i], start_s, m)
        length_m = length[m]
        d = clip(s[i] - start_s[m], 0.0, length_m)
        into = vmax(d - hold_start[m], 0.0)
        ve = v_entry[m]
        up = math.sqrt(vmax(ve * ve + 2.0 * a_up[m] * into, 0.0))
        rest = vmax(length_m - hold_end[m] - d, 0.0)
        vx = v_exit[m]
        down = math.sqrt(vmax(vx * vx + 2.0 * a_down[m] * rest, 0.0))
        vp = v_peak[m]
        v = vmin(vmin(up, down), vp)
        if with_ramps:
            if up <= down and up < vp and dv_u[m] > nil_speed:
                if m != at_up:
                    ramp_up = _ramp(lo_u[m], dv_u[m], a_up[m], ve, acc[m], jerk[m], consts)
                    at_up = m
                v = _ramp_speed(into, True, ramp_up, consts)
            elif down < up and down < vp and dv_d[m] > nil_speed:
                if m != at_dn:
                    ramp_dn = _ramp(lo_d[m], dv_d[m], a_down[m], vx, acc[m], jerk[m], consts)
                    at_dn = m
                v = _ramp_speed(rest, False, ramp_dn, consts)
        out[i] = v
    return out


@kernel
def _key(
    at: int,
    qx: float,
    qy: float,
    qz: float,
    guess: float,
    px: np.ndarray,
    py: np.ndarray,
    pz: np.ndarray,
    s_p: np.ndarray,
    pass_tie: float,
) -> tuple[float, float]:
    """core.model.sampling.PathSamples._key for one point (``at`` clipped to the path)."""
    at = min(max(at, 0), s_p.size - 1)
    dx = px[at] - qx
    dy = py[at] - qy
    dz = pz[at] - qz
    d2 = (dx * dx + dz * dz) + dy * dy
    tie = (s_p[at] - guess) * pass_tie
    return tie * tie + d2, d2


@kernel
def project_near(
    q: np.ndarray,
    guess: np.ndarray,
    j: np.ndarray,
    px: np.ndarray,
    py: np.ndarray,
    pz: np.ndarray,
    s_p: np.ndarray,
    reach: np.ndarray,
    clearance: np.ndarray,
    half: int,
    ints: tuple[int, int, int, int, int],
    floats: tuple[float, float, float],
) -> tuple[np.ndarray, np.ndarray]:
    """core.model.sampling.PathSamples.project_near of finite points ``q`` ((m, 3)) with
    finite guesses, ``j`` = searchsorted(s_p, guess) (:func:`sorted_places`): the same
    blocks, the same first look where its probe says it pays, the same window search and
    foot, point by point.
    ``reach`` and ``clearance``: PathSamples._reach and _clearance(half + NEAR_FIRST)
    (empty where half < NEAR_FIRST); ``ints`` (NEAR_BLOCK, NEAR_PROBE, NEAR_FIRST,
    CLEAR_FROM, COARSE), ``floats`` (NEAR_WORTH, NEAR_SLACK, TOL.pass_tie)."""
    block, probe, first, clear_from, coarse_step = ints
    worth, slack, pass_tie = floats
    m = q.shape[0]
    last = s_p.size - 1
    best_i = np.empty(m, dtype=np.int64)
    best_d2 = np.empty(m)
    # the window's coarse offsets (PathSamples._window)
    n_coarse = (2 * half) // coarse_step + 1
    if -half + (n_coarse - 1) * coarse_step != half:
        n_coarse += 1
    coarse = np.empty(n_coarse, dtype=np.int64)
    for c in range(n_coarse):
        coarse[c] = min(-half + c * coarse_step, half)
    seen = np.empty(n_coarse)
    for start in range(0, m, block):
        stop = min(start + block, m)
        use_first = False
        if half >= first:
            probed = 0
            hits = 0
            for i in range(start, stop, probe):
                probed += 1
                if _near_first(
                    i, q, guess, j, px, py, pz, s_p, clearance, first, clear_from, last,
                    slack, pass_tie, best_i, best_d2,
                ):  # fmt: skip
                    hits += 1
            use_first = probed > 0 and hits / probed >= worth
        for i in range(start, stop):
            if use_first and _near_first(
                i, q, guess, j, px, py, pz, s_p, clearance, first, clear_from, last,
                slack, pass_tie, best_i, best_d2,
            ):  # fmt: skip
                continue
            _window(
                i, q, guess, j, px, py, pz, s_p, reach, coarse, seen, last, slack, pass_tie,
                best_i, best_d2,
            )  # fmt: skip
    return _between(q, best_i, best_d2, px, py, pz, s_p)


@kernel
def _near_first(
    i: int,
    q: np.ndarray,
    guess: np.ndarray,
    j: np.ndarray,
    px: np.ndarray,
    py: np.ndarray,
    pz: np.ndarray,
    s_p: np.ndarray,
    clearance: np.ndarray,
    first: int,
    clear_from: int,
    last: int,
    slack: float,
    pass_tie: float,
    best_i: np.ndarray,
    best_d2: np.ndarray,
) -> bool:
    """PathSamples._near_first for point ``i``: its best point and squared distance into
    ``best_i``, ``best_d2``, and whether it is the window's."""
    ji = j[i]
    qx, qy, qz, g = q[i, 0], q[i, 1], q[i, 2], guess[i]
    bk, bd = _key(ji - first, qx, qy, qz, g, px, py, pz, s_p, pass_tie)
    bo = -first
    for off in range(-first + 1, first + 1):
        key, d2 = _key(ji + off, qx, qy, qz, g, px, py, pz, s_p, pass_tie)
        if key < bk:
            bk, bd, bo = key, d2, off
    b = min(max(ji + bo, 0), last)
    best_i[i] = b
    best_d2[i] = bd
    near = clear_from - 1
    if max(b - near, 0) < max(ji - first, 0) or min(b + near, last) > min(ji + first, last):
        return False
    low = clearance[b] - math.sqrt(bd) - slack
    return low > 0 and low * low > bk


@kernel
def _window(
    i: int,
    q: np.ndarray,
    guess: np.ndarray,
    j: np.ndarray,
    px: np.ndarray,
    py: np.ndarray,
    pz: np.ndarray,
    s_p: np.ndarray,
    reach: np.ndarray,
    coarse: np.ndarray,
    seen: np.ndarray,
    last: int,
    slack: float,
    pass_tie: float,
    best_i: np.ndarray,
    best_d2: np.ndarray,
) -> None:
    """PathSamples._window (_best_of over the coarse offsets, then _fill between two of
    them where the triangle inequality does not rule them out) for point ``i``."""
    ji = j[i]
    qx, qy, qz, g = q[i, 0], q[i, 1], q[i, 2], guess[i]
    bk, bd = _key(ji + coarse[0], qx, qy, qz, g, px, py, pz, s_p, pass_tie)
    bo = coarse[0]
    seen[0] = math.sqrt(bd)
    for c in range(1, coarse.size):
        key, d2 = _key(ji + coarse[c], qx, qy, qz, g, px, py, pz, s_p, pass_tie)
        seen[c] = math.sqrt(d2)
        if key < bk:
            bk, bd, bo = key, d2, coarse[c]
    for c in range(coarse.size - 1):
        o1, o2 = coarse[c], coarse[c + 1]
        if o2 - o1 < 2:
            continue
        low = 0.5 * (seen[c] + seen[c + 1] - reach[min(max(ji + o1, 0), last)]) - slack
        if low > 0 and low * low > bk:
            continue
        for off in range(o1 + 1, o2):
            key, d2 = _key(ji + off, qx, qy, qz, g, px, py, pz, s_p, pass_tie)
            if key < bk or (key == bk and off < bo):
                bk, bd, bo = key, d2, off
    best_i[i] = min(max(ji + bo, 0), last)
    best_d2[i] = bd


@kernel
def _between(
    q: np.ndarray,
    best_i: np.ndarray,
    best_d2: np.ndarray,
    px: np.ndarray,
    py: np.ndarray,
    pz: np.ndarray,
    s_p: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """PathSamples._between, point by point."""
    m = q.shape[0]
    last = s_p.size - 1
    s = np.empty(m)
    dist = np.empty(m)
    for i in range(m):
        qx, qy, qz = q[i, 0], q[i, 1], q[i, 2]
        bi = best_i[i]
        si = s_p[bi]
        best = best_d2[i]
        for a in (max(bi - 1, 0), bi):
            b = min(a + 1, last)
            ax, ay, az = px[a], py[a], pz[a]
            abx, aby, abz = px[b] - ax, py[b] - ay, pz[b] - az
            aqx, aqy, aqz = qx - ax, qy - ay, qz - az
            l2 = (abx * abx + abz * abz) + aby * aby
            u = clip(((aqx * abx + aqz * abz) + aqy * aby) / l2, 0.0, 1.0)
            ex = aqx - abx * u
            ey = aqy - aby * u
            ez = aqz - abz * u
            e2 = (ex * ex + ez * ez) + ey * ey
            if l2 > 0.0 and e2 < best:
                si = (s_p[b] - s_p[a]) * u + s_p[a]
                best = e2
        s[i] = si
        dist[i] = math.sqrt(best)
    return s, dist


@kernel
def chain_dv(
    rising: bool,
    phase: np.ndarray,
    through: np.ndarray,
    v0: np.ndarray,
    v1: np.ndarray,
    peak: np.ndarray,
) -> np.ndarray:
    """core.engine.profile._chain_dv, move by move, in one pass: each run of moves where a
    move continues the chain of the one before (rising: it accelerates through its start,
    through[k] and phase[k]; falling: it and the one before brake, through[k + 1]) gets
    the speed change from the chain's first move to its last; a move alone its own."""
    n = phase.size
    dv = np.empty(n)
    k = 0
    while k < n:
        first = k
        if rising:
            while k + 1 < n and through[k + 1] and phase[k + 1]:
                k += 1
        else:
            while k + 1 < n and through[k + 2] and phase[k + 1] and phase[k]:
                k += 1
        last = k
        if rising:
            hi = (v1[last] if through[last + 1] else peak[last]) - v0[first]
        else:
            hi = (v0[first] if through[first + 1] else peak[first]) - v1[last]
        for m in range(first, last + 1):
            dv[m] = hi
        k += 1
    return dv


@kernel
def dense_round(
    rising: bool,
    phase: np.ndarray,
    through: np.ndarray,
    v0: np.ndarray,
    v1: np.ndarray,
    peak: np.ndarray,
    a: np.ndarray,
    last: np.ndarray,
    term: np.ndarray,
    off: np.ndarray,
    acc: np.ndarray,
    jerk: np.ndarray,
    between: np.ndarray,
    step: np.ndarray,
    moved: np.ndarray,
    nil_speed: float,
    finite: bool,
    fixed: tuple[np.ndarray, np.ndarray],
) -> tuple[float, bool, np.ndarray, np.ndarray]:
    """core.engine.profile._Rounds._dense, move by move: the accelerations ``a`` and their
    ``off``, ``term`` updated in place, this round's ``step`` and ``moved`` written; returns
    the largest relative change, whether the terms are still plain, and the moves the
    damping held back with their targets. numpy's code writes ``off`` and ``term`` again
    over every piece of moves where one moved; here only the moves that moved are written:
    the others' are the same values already (``off`` is a != acc and ``term`` the pass
    term of ``a`` wherever they are made, and each term was checked for ``finite`` when it
    was made). ``fixed``: ``acc / jerk`` and ``acc * acc / jerk`` (_Rounds.fixed), the
    quotients numpy's effective_acceleration makes, made once for all the rounds."""
    n = a.size
    aj, lim = fixed
    dv = chain_dv(rising, phase, through, v0, v1, peak)
    behind = np.empty(n, dtype=np.int64)
    wanted = np.empty(n)
    n_behind = 0
    change = 0.0
    for k in range(n):
        od = a[k]
        # effective_acceleration(dv, acc, jerk, only=phase)
        d, ak, jk = dv[k], acc[k], jerk[k]
        new = ak  # (the quotients only where they are kept)
        if math.isfinite(jk) and d > nil_speed and phase[k]:
            t_full = d / ak + aj[k]
            t_short = math.sqrt(d / jk) * 2.0
            t = t_full if d >= lim[k] else t_short
            new = d / t
        # the damping
        ls = last[k]
        o = new
        if (new > od and ls < 0) or (new < od and ls > 0):
            o = math.sqrt(od * new)
            if o != new:
                behind[n_behind] = k
                wanted[n_behind] = new
                n_behind += 1
        step[k] = (1 if o > od else 0) - (1 if o < od else 0)
        mv = o != od
        moved[k] = mv
        if mv:  # (where o == od, o / od - 1 is 0 or NaN: no change either way)
            rel = abs(o / od - 1.0)
            if rel > change:  # (NaN skipped, as nanmax)
                change = rel
            a[k] = o
            off[k] = o != acc[k]
            tm = o * vmax(between[k], 0.0) * 2.0
            term[k] = tm
            if not (math.isfinite(tm) and not tm < 0.0):
                finite = False
    return change, finite, behind[:n_behind].copy(), wanted[:n_behind].copy()


@kernel
def plain_passes(
    b2: np.ndarray, up: np.ndarray, dn: np.ndarray, w: np.ndarray, bwd: np.ndarray, out: np.ndarray
) -> None:
    """core.engine.profile._passes_of with ``finite`` (no NaN, no -0.0, terms >= 0: fmin is
    a plain comparison and the clamp at 0 is left out) into ``out``: the sums sequential
    as np.cumsum's (the first term itself, then one term after the other), the minima
    running as np.fmin.accumulate's (a NaN only past them, where a sum overflowed); ``w``
    and ``bwd`` work arrays of b2's size."""
    n1 = b2.size
    # forward: both sums (the braking one into bwd) and the forward pass, three chains
    # that overlap; backward: the backward pass, then the lower of the two and the cap
    wu = wd = 0.0
    least = b2[0]
    for i in range(n1):
        if i:
            wu = up[0] if i == 1 else wu + up[i - 1]
            wd = dn[0] if i == 1 else wd + dn[i - 1]
        w[i] = wu
        bwd[i] = wd
        x = b2[i] - wu
        if x < least:
            least = x
        out[i] = least + wu
    least = b2[n1 - 1] + bwd[n1 - 1]
    for i in range(n1 - 1, -1, -1):
        wd = bwd[i]
        x = b2[i] + wd
        if x < least:
            least = x
        # (an overflowed sum gives NaN here: np.minimum's rules)
        out[i] = math.sqrt(vmin(vmin(out[i], least - wd), b2[i]))


@kernel
def marks(
    at: np.ndarray,
    every: bool,
    v: np.ndarray,
    a_up: np.ndarray,
    a_dn: np.ndarray,
    between: np.ndarray,
    cap: np.ndarray,
    tols: tuple[float, float],
    out: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> None:
    """core.engine.profile._Rounds._all_marks (``every``: all moves) or _marks_of of the
    moves ``at``, move by move into ``out`` = (peak, rise, fall, through_up, through_dn)
    (through_*[k + 1] of move k); ``tols`` (TOL.rel_equal, TOL.nil_distance)."""
    peak, rise, fall, through_up, through_dn = out
    rel_equal, nil_distance = tols
    count = a_up.size if every else at.size
    for i in range(count):
        k = i if every else at[i]
        v0, v1, au, ad, lk = v[k], v[k + 1], a_up[k], a_dn[k], between[k]
        q0 = v0 * v0
        q1 = v1 * v1
        pk = q0 / au + lk * 2.0 + q1 / ad
        pk = pk / (1.0 / au + 1.0 / ad)
        pk = vmax(vmin(cap[k], math.sqrt(vmax(pk, 0.0))), vmax(v0, v1))
        t = vmax(pk, 1.0) * rel_equal
        r = pk > v0 + t
        f = pk > v1 + t
        peak[k] = pk
        rise[k] = r
        fall[k] = f
        flat = False
        if r != f:  # the cruise length of a move that only accelerates or only brakes
            pk2 = pk * pk
            d_cr = lk - (pk2 - q0) / (2.0 * au)
            d_cr = d_cr - (pk2 - q1) / (2.0 * ad)
            flat = vmax(d_cr, 0.0) <= nil_distance
        through_up[k + 1] = r and flat
        through_dn[k + 1] = f and flat


@kernel
def _bisect_left(a: np.ndarray, v: float, lo: int, hi: int) -> int:
    """The first place in lo..hi-1 of sorted ``a`` whose value is at least ``v``, else hi
    (np.searchsorted's left side, within lo..hi)."""
    while lo < hi:
        mid = (lo + hi) // 2
        if a[mid] < v:
            lo = mid + 1
        else:
            hi = mid
    return lo


@kernel
def _gallop_left(a: np.ndarray, v: float, k: int, hi: int) -> int:
    """:func:`_bisect_left` of k..hi-1, looked for from k in steps that double (the answer
    is most often a few places on)."""
    if k >= hi or a[k] >= v:
        return k
    step = 1
    while k + step < hi and a[k + step] < v:
        step *= 2
    return _bisect_left(a, v, k + step // 2 + 1, min(k + step, hi))


@kernel
def _key_at(
    x: float, y: float, z: float, e: float, k: int, px, py, pz, s_p, seq_tie: float
) -> tuple[float, float]:
    """core.diagnosis.align._nearest's key of path point k for one point, and its squared
    distance."""
    dx = x - px[k]
    dy = y - py[k]
    dz = z - pz[k]
    d2 = dx * dx + dy * dy + dz * dz
    t = (s_p[k] - e) * seq_tie
    return d2 + t * t, d2


@kernel
def _nearest_in(
    x: float,
    y: float,
    z: float,
    e: float,
    r0: int,
    r1: int,
    px: np.ndarray,
    py: np.ndarray,
    pz: np.ndarray,
    s_p: np.ndarray,
    seq_tie: float,
    slack: float,
    best: int,
    best_key: float,
    best_d2: float,
) -> tuple[int, float, float]:
    """core.diagnosis.align._nearest for one point over path points r0..r1-1 (in arc
    length) and the best of earlier ones (``best``; -1: none yet): np.argmin's least key,
    the first of equal ones, a NaN key least. The point whose arc length is nearest ``e``
    is tried first, so that most others are skipped (below); ``slack`` (mm): how much the
    distance of two path points may exceed their arc lengths' difference (the path's
    jumps, and rounding)."""
    if r1 <= r0:
        return best, best_key, best_d2
    first = min(_bisect_left(s_p, e, r0, r1), r1 - 1)  # the first point at or beyond e
    key, d2 = _key_at(x, y, z, e, first, px, py, pz, s_p, seq_tie)
    if (
        best < 0
        or (key != key and best_key == best_key)
        or key < best_key
        or (key == best_key and first < best)
    ):
        best, best_key, best_d2 = first, key, d2
    k = r0
    while k < r1:
        key, d2 = _key_at(x, y, z, e, k, px, py, pz, s_p, seq_tie)
        if key != key or best_key != best_key:
            # NaN (np.argmin: the first NaN): this point where it is one before the best
            if key != key and (best_key == best_key or k < best):
                best, best_key, best_d2 = k, key, d2
            k += 1
            continue
        if key < best_key or (key == best_key and k < best):
            best, best_key, best_d2 = k, key, d2
        # The points after k within (d_k - d_best - slack) of arc length are farther than
        # the best (the path between two points is no shorter than their distance, but for
        # its jumps): their keys, at least their squared distances, exceed the best key, so
        # none of them is the least or ties with it. Skipped.
        reach = math.sqrt(d2) - math.sqrt(best_key) - slack
        k += 1
        if reach > 0.0:
            k = _gallop_left(s_p, s_p[k - 1] + reach, k, r1)
    return best, best_key, best_d2


@kernel
def project_lines(
    qx: np.ndarray,
    qy: np.ndarray,
    qz: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    start: np.ndarray,
    own: np.ndarray,
    win: np.ndarray,
    px: np.ndarray,
    py: np.ndarray,
    pz: np.ndarray,
    s_p: np.ndarray,
    ties: tuple[float, float],
    slack: float,
) -> tuple[np.ndarray, np.ndarray]:
    """core.diagnosis.align._project's search of each program line's samples, line by line
    (path points in arc length): the samples lo[j]..hi[j]-1 of line j (positions qx, qy,
    qz, in time order) run on from the arc length ``start[j]`` by their own travel
    (_run_on); each takes the nearest of the line's own path points own[j, 0]..own[j, 1]-1,
    and the nearest of its window (win[j, 0]..win[j, 1]-1, then win[j, 2]..win[j, 3]-1)
    where the window has more points and that is nearer by more than pass_tie. ``ties``:
    (TOL.sequence_tie, TOL.pass_tie); ``slack``: see :func:`_nearest_in`. Returns the arc
    length and distance of every sample (NaN outside the lines)."""
    seq_tie, pass_tie = ties
    s_out = np.full(qx.size, np.nan)
    d_out = np.full(qx.size, np.nan)
    for j in range(lo.size):
        n_own = own[j, 1] - own[j, 0]
        n_win = (win[j, 1] - win[j, 0]) + (win[j, 3] - win[j, 2])
        run = 0.0
        for i in range(lo[j], hi[j]):
            if i > lo[j]:
                dx = qx[i] - qx[i - 1]
                dy = qy[i] - qy[i - 1]
                dz = qz[i] - qz[i - 1]
                run += math.sqrt(dx * dx + dy * dy + dz * dz)
            e = start[j] + run
            k, _, d2 = _nearest_in(
                qx[i], qy[i], qz[i], e, own[j, 0], own[j, 1], px, py, pz, s_p, seq_tie,
                slack, -1, np.inf, 0.0,
            )  # fmt: skip
            s = s_p[k]
            d = math.sqrt(d2)
            if n_win > n_own:
                k2, key2, d2b = _nearest_in(
                    qx[i], qy[i], qz[i], e, win[j, 0], win[j, 1], px, py, pz, s_p, seq_tie,
                    slack, -1, np.inf, 0.0,
                )  # fmt: skip
                k2, _, d2b = _nearest_in(
                    qx[i], qy[i], qz[i], e, win[j, 2], win[j, 3], px, py, pz, s_p, seq_tie,
                    slack, k2, key2, d2b,
                )  # fmt: skip
                d2nd = math.sqrt(d2b)
                if d2nd < d - pass_tie:
                    s = s_p[k2]
                    d = d2nd
            s_out[i] = s
            d_out[i] = d
    return s_out, d_out


#: 10^0 .. 10^22: the powers of ten a double holds exactly (Clinger's fast path).
_TENS = np.array([10.0**k for k in range(23)])
#: The largest whole number below which every whole number is a double (2^53).
_EXACT = 2**53


@kernel
def _row_count(buf: np.ndarray) -> int:
    """Rows of ``buf``: its newlines, and one more where the last row has none."""
    n = 0
    for b in buf:
        if b == 10:
            n += 1
    if buf.size and buf[buf.size - 1] != 10:
        n += 1
    return n


@kernel
def _digit_run(buf: np.ndarray, i: int, mant: int, digits: int) -> tuple[int, int, int, int]:
    """The digits of ``buf`` from ``i`` on, appended to the whole number ``mant`` from the
    first non-zero one (``digits``: how many it has): the index after them, the whole
    number, its significant digits, and how many digits were read."""
    count = 0
    while i < buf.size and 48 <= buf[i] <= 57:
        d = buf[i] - 48
        if digits or d:
            digits += 1
            mant = mant * 10 + d
        count += 1
        i += 1
    return i, mant, digits, count


@kernel
def parse_rows(buf: np.ndarray, ncols: int, want: np.ndarray) -> tuple[np.ndarray, int]:
    """Rows of comma-separated numbers (``buf``: UTF-8 bytes, rows ending in a newline or
    CR LF; ``ncols`` fields a row, field j going to column want[j] of the result, -1: not
    wanted) as ``float(field)`` reads them -- where every wanted field is a plain decimal
    (a sign, digits, a point, digits, an exponent) of at most 18 significant digits whose
    whole number is below 2^53 and whose power of ten is within 10^+-22: then the number is
    that whole number times or over an exact power of ten, one IEEE operation, the correctly
    rounded double float() gives (Clinger's fast path). Returns the (rows, wanted) numbers
    and -1, or the index of the first row the fast path cannot take (any other byte, field
    count or number: numpy's reader, with its messages, does the file)."""
    rows = _row_count(buf)
    width = 0
    for c in want:
        if c >= 0:
            width += 1
    out = np.empty((rows, width))
    i = 0
    n = buf.size
    for r in range(rows):
        if i >= n or buf[i] == 10 or buf[i] == 13:
            return out, r  # an empty line
        for j in range(ncols):
            col = want[j]
            if col < 0:
                while i < n and buf[i] != 44 and buf[i] != 10 and buf[i] != 13:
                    b = buf[i]
                    if b >= 128 or b == 11 or b == 12 or (28 <= b <= 30) or b == 35:
                        return out, r  # another line break to Python, or a comment
                    i += 1
            else:
                neg = False
                if i < n and (buf[i] == 45 or buf[i] == 43):
                    neg = buf[i] == 45
                    i += 1
                # the digits before and after the point (significant ones from the first
                # non-zero one)
                i, mant, digits, seen = _digit_run(buf, i, 0, 0)
                scale = 0
                if i < n and buf[i] == 46:
                    i, mant, digits, scale = _digit_run(buf, i + 1, mant, digits)
                    seen += scale
                if seen == 0 or digits > 18:
                    return out, r
                e10 = 0
                if i < n and (buf[i] == 101 or buf[i] == 69):
                    i += 1
                    eneg = False
                    if i < n and (buf[i] == 45 or buf[i] == 43):
                        eneg = buf[i] == 45
                        i += 1
                    ed = 0
                    while i < n and 48 <= buf[i] <= 57:
                        if ed < 6:
                            e10 = e10 * 10 + (buf[i] - 48)
                        ed += 1
                        i += 1
                    if ed == 0 or ed >= 6:
                        return out, r
                    if eneg:
                        e10 = -e10
                e10 -= scale
                if mant > _EXACT:
                    return out, r
                v = float(mant)
                if mant != 0:
                    if -22 <= e10 < 0:
                        v = v / _TENS[-e10]
                    elif 0 < e10 <= 22:
                        v = v * _TENS[e10]
                    elif e10 != 0:
                        return out, r
                out[r, col] = -v if neg else v
            if j < ncols - 1:
                if i >= n or buf[i] != 44:
                    return out, r  # fewer fields, or something after a number
                i += 1
        if i < n and buf[i] == 13:
            i += 1
            if i >= n or buf[i] != 10:
                return out, r  # a lone CR: a line break of its own to Python
        if i < n:
            if buf[i] != 10:
                return out, r  # more fields, or something after a number
            i += 1
    return out, -1


@kernel
def sorted_places(s_p: np.ndarray, x: np.ndarray) -> np.ndarray:
    """np.searchsorted(s_p, x) (the first place whose value is at least x) of finite ``x``
    in sorted ``s_p``, each searched from the place of the one before in steps that double
    (points along a path come in order: a few steps each, not a whole bisection)."""
    n = s_p.size
    out = np.empty(x.size, dtype=np.int64)
    k = 0
    for i in range(x.size):
        v = x[i]
        if k < n and s_p[k] < v:  # on from k
            at = _gallop_left(s_p, v, k, n)
        else:  # at k or before it: back in steps that double, then halving
            hi, step = k, 1
            while k - step >= 0 and s_p[k - step] >= v:
                hi = k - step
                step *= 2
            at = _bisect_left(s_p, v, max(k - step + 1, 0), hi)
        out[i] = at
        k = min(at, n - 1) if n else 0
    return out


@kernel
def first_order(v: np.ndarray, a: float, powers: np.ndarray, inverse: np.ndarray) -> np.ndarray:
    """core.engine.predict._first_order of an (m, columns) ``v``, element by element: the
    same blocks of ``powers.size`` rows, in each y_k = a^k (y_0 + sum_{i<=k} (1 - a) x_i /
    a^i) with the sum running as np.cumsum's (``powers``: a^1..a^block, ``inverse`` the
    same numbers, the divisors)."""
    m, cols = v.shape
    out = np.empty((m, cols))
    block = powers.size
    one_minus = 1.0 - a
    for j in range(cols):
        y = v[0, j]
        for c in range(0, m, block):
            rows = min(block, m - c)
            run = 0.0
            for i in range(rows):
                w = one_minus * v[c + i, j] / inverse[i]
                run = w if i == 0 else run + w
                out[c + i, j] = powers[i] * (y + run)
            y = out[c + rows - 1, j]
    return out


@kernel
def path_speed(pos: np.ndarray, dt: float) -> np.ndarray:
    """np.linalg.norm(np.gradient(pos, dt, axis=0), axis=1) of (m, 3) positions (m >= 2)
    at even steps ``dt``, point by point: central differences inside, one-sided at the
    ends; the squares summed as numpy's reduction over a row of three sums them."""
    m = pos.shape[0]
    out = np.empty(m)
    two_dt = 2.0 * dt
    for i in range(m):
        if i == 0:
            lo, hi, div = 0, 1, dt
        elif i == m - 1:
            lo, hi, div = m - 2, m - 1, dt
        else:
            lo, hi, div = i - 1, i + 1, two_dt
        gx = (pos[hi, 0] - pos[lo, 0]) / div
        gy = (pos[hi, 1] - pos[lo, 1]) / div
        gz = (pos[hi, 2] - pos[lo, 2]) / div
        out[i] = math.sqrt(gx * gx + gy * gy + gz * gz)
    return out


@kernel
def corner_limits(
    share_t: np.ndarray,
    share_n: np.ndarray,
    radius: np.ndarray,
    v_jerk: np.ndarray,
    max_feed: np.ndarray,
    a_n: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """plugins.tangential._corner_feed_rows after its jerk column ``v_jerk`` ((m, 3):
    numpy's cube roots, which may be SIMD code of its own): each corner's feed limits of
    the axes' speeds (max_feed / share_t), normal accelerations (sqrt(a_n R / share_n))
    and jerks, inf where an axis has no share, NaN as 0 and -inf as the lowest double
    (np.nan_to_num), and the lowest of the nine with the first of equals (np.argmin)."""
    m = radius.size
    feed = np.empty(m)
    limit = np.empty(m, dtype=np.int64)
    lowest = -1.7976931348623157e308
    for i in range(m):
        best = 0.0
        at = 0
        for c in range(9):
            j = c % 3
            if c < 3:
                x = max_feed[j] / share_t[i, j] if share_t[i, j] > 0 else np.inf
            elif c < 6:
                x = math.sqrt(a_n[j] * radius[i] / share_n[i, j]) if share_n[i, j] > 0 else np.inf
            else:
                x = v_jerk[i, j]
            if math.isnan(x):
                x = 0.0
            elif x == -np.inf:
                x = lowest
            if c == 0 or x < best:
                best = x
                at = c
        feed[i] = best
        limit[i] = at
    return feed, limit


@kernel
def changed_moves(old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """(old != new).any(axis=0) of two (columns, moves) int64 arrays: the moves where any
    column differs."""
    rows, n = new.shape
    out = np.zeros(n, dtype=np.bool_)
    for r in range(rows):
        for j in range(n):
            if old[r, j] != new[r, j]:
                out[j] = True
    return out
