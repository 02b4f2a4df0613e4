"""The paper's three models (Tapie, Mawussi, Anselmetti, sec. 3.2), written here from the
paper for the reference interpreter, move by move and junction by junction.

A junction ``j`` is the point between moves ``j`` and ``j + 1`` when both are feed moves of
one operation (a rapid or an operation change breaks the chain: the machine stops there).

Model 1 -- a tangential discontinuity (eq. 1-10). The controller inserts an arc of radius

    R = min(TIT cos(b/2) / (1 - cos(b/2)),  l / (2 sin(b/2)) - TIT),  l = min(l1, l2)   (1)

at a corner of direction change b and runs it at constant speed, within every axis's feed,
normal acceleration (eq. 2, 4) and tangential jerk (eq. 3, 5). Along the arc the tangent
turns from t1 towards t2 in their plane; axis k carries the share |t_k| of the feed and the
jerk and |n_k| of the normal acceleration, at most its largest share over the turn
(eq. 7-10 in the paper's XY case), so

    V = min_k ( Vmax_k / max|t_k|,  sqrt(f A_k R / max|n_k|),  cbrt(J_k R^2 / max|t_k|) )

with f the share of the acceleration a controller allows for normal acceleration (1 in the
paper). TIT is the program's tolerance where it sets one, else the machine's.

Model 2 -- a curvature discontinuity (eq. 11-15). Where the tangent is continuous but the
curvature vector jumps by |dk|, the normal acceleration changes by V^2 |dk| within dt at
the tangential jerk, so V = sqrt(J dt / |dk|) (eq. 13, 14; at an inflection |dk| is
1/R1 + 1/R2), with J = min_k J_k / |t_k| along the common tangent (eq. 15).

Model 3 -- the block cycle time (eq. 16): a block of length l shorter than L = F t_int runs
at most at l / t_int.

Beyond the paper, as ncperf documents them: no block runs faster than its axes allow
(min_k Vmax_k / share_k); exact stops and dwells stop the machine; programmed arcs can be
capped by their centripetal acceleration and jerk (the ``arc_feed_limit`` effect).
"""

from __future__ import annotations

import math

from refvm import vec as V
from refvm.machine import MachineLimits
from refvm.program import EXACT_STOP, Program

#: Direction changes (rad) at or below this are not corners (rounding noise of the program's
#: decimals), the threshold ncperf documents for model 1.
COLLINEAR_ANGLE = 1e-6
#: Junctions turning by at most this (rad) are tangent for model 2: CAM writes tangent
#: line-arc transitions with 4-5 decimals (ncperf's documented value).
TANGENT_ANGLE = 2e-3
#: Curvature jumps (1/mm) at or below this are none.
CURVATURE_JUMP = 1e-6


def junctions(p: Program) -> list[int]:
    """Junctions: j with moves j and j + 1 feed moves of one operation."""
    return [
        j
        for j in range(p.n - 1)
        if p.is_feed(j) and p.is_feed(j + 1) and p.operation[j] == p.operation[j + 1]
    ]


def stops_after(p: Program, j: int) -> bool:
    """Whether the machine stops at the end of move ``j`` (exact stop, dwell)."""
    return p.path_mode[j] == EXACT_STOP or p.dwell[j] > 0.0


# ----------------------------------------------------------------------------- model 1
def corner_radius(beta: float, shorter: float, tit: float) -> float:
    """Eq. (1), never negative (blocks too short for the tolerance: 0, a stop).

    1 - cos(b/2) is computed as 2 sin^2(b/4), which keeps its digits at small angles.
    """
    half = beta / 2.0
    r_tol = tit * math.cos(half) / (2.0 * math.sin(beta / 4.0) ** 2)
    r_len = shorter / (2.0 * math.sin(half)) - tit
    return max(min(r_tol, r_len), 0.0)


def _perpendicular_towards(t1: V.Vec, t2: V.Vec) -> V.Vec:
    """Unit vector perpendicular to t1 in the plane (t1, t2), on t2's side (any perpendicular
    for a reversal)."""
    u = V.sub(t2, V.mul(t1, V.dot(t1, t2)))
    if V.length(u) < 1e-12:
        # t2 = -t1: pick the axis t1 has least of, then make it perpendicular
        k = min(range(3), key=lambda i: abs(t1[i]))
        e: V.Vec = (1.0 if k == 0 else 0.0, 1.0 if k == 1 else 0.0, 1.0 if k == 2 else 0.0)
        u = V.cross(t1, e)
    return V.unit(u)


def corner(p: Program, m: MachineLimits, j: int) -> tuple[float, float] | None:
    """Model 1 at junction ``j``: (feed mm/s, inserted radius mm), or None when the direction
    does not change (more than COLLINEAR_ANGLE)."""
    t1, t2 = p.t_end[j], p.t_start[j + 1]
    beta = V.angle(t1, t2)
    if not beta > COLLINEAR_ANGLE:
        return None
    tol = p.tolerance[j]
    tit = m.path_tolerance if math.isnan(tol) else tol
    R = corner_radius(beta, min(p.length[j], p.length[j + 1]), tit)
    u = _perpendicular_towards(t1, t2)
    # on the arc: t(phi) = cos(phi) t1 + sin(phi) u, n(phi) = -sin(phi) t1 + cos(phi) u
    share_t = tuple(V.peak_of_turning(t1[k], u[k], beta) for k in range(3))
    share_n = tuple(V.peak_of_turning(u[k], -t1[k], beta) for k in range(3))
    a_n = tuple(a * m.normal_acceleration_factor for a in m.max_acceleration)
    v = math.inf
    for k in range(3):
        if share_t[k] > 0.0:
            v = min(v, m.max_feed[k] / share_t[k])
            jerk_part = m.max_jerk[k] * R * R / share_t[k]
            # an infinite jerk on a zero radius: no radius is a stop
            v = min(v, 0.0 if math.isnan(jerk_part) else math.cbrt(jerk_part))
        if share_n[k] > 0.0:
            v = min(v, math.sqrt(a_n[k] * R / share_n[k]))
    return v, R


# ----------------------------------------------------------------------------- model 2
def transition(p: Program, m: MachineLimits, j: int) -> float | None:
    """Model 2 at junction ``j``: the feed (mm/s, may be inf), or None where the junction is
    not tangent or the curvature does not jump."""
    t1, t2 = p.t_end[j], p.t_start[j + 1]
    if V.angle(t1, t2) > TANGENT_ANGLE:
        return None
    jump = V.length(V.sub(p.k_end[j], p.k_start[j + 1]))
    if not jump > CURVATURE_JUMP:
        return None
    t = V.unit(V.add(t1, t2))
    jerk = m.per_share(m.max_jerk, (abs(t[0]), abs(t[1]), abs(t[2])))
    v = math.sqrt(jerk * m.curvature_transition_time / jump) if math.isfinite(jerk) else math.inf
    return v


# ----------------------------------------------------------------------------- blocks
def block_cap(p: Program, m: MachineLimits, i: int, *, block_time: bool = True) -> float:
    """The most a move runs at: a feed move its F, model 3 (eq. 16, with ``block_time``) and
    its axes' feed limits; a rapid its axes' max feed along its direction."""
    if not p.is_feed(i):
        return m.rapid_speed(p.t_start[i])
    cap = min(p.feed[i], m.per_share(m.max_feed, p.share[i]))
    if block_time and p.length[i] < p.feed[i] * m.interpolation_time:
        cap = min(cap, p.length[i] / m.interpolation_time)
    return cap


def arc_cap(p: Program, m: MachineLimits, i: int, *, jerk: bool = True) -> float:
    """Centripetal cap of a programmed arc (inf for other moves): on a helix of curvature
    radius rho, v^2 / rho normal acceleration and v^3 / rho^2 jerk; per axis with its
    largest share of the principal normal (which turns with the arc) and of the tangent;
    the normal acceleration gets the machine's normal share f:
    v <= min_k sqrt(f A_k rho / n_k) and (with ``jerk``) cbrt(J_k rho^2 / t_k)."""
    if not p.is_arc(i):
        return math.inf
    n = p.normal[i]
    turn = 1.0 if p.kind[i] == 3 else -1.0
    radial = V.sub(p.start[i], p.center[i])
    r0 = V.unit(V.sub(radial, V.mul(n, V.dot(radial, n))))
    w0 = V.mul(V.cross(n, r0), turn)
    share_n = tuple(V.peak_of_turning(r0[k], w0[k], p.sweep[i]) for k in range(3))
    r, c = p.radius[i], p.pitch[i]
    rho = (r * r + c * c) / r
    acc = [a * m.normal_acceleration_factor for a in m.max_acceleration]
    v = math.inf
    for k in range(3):
        if share_n[k] > 0.0:
            v = min(v, math.sqrt(acc[k] * rho / share_n[k]))
        if jerk and p.share[i][k] > 0.0:
            v = min(v, math.cbrt(m.max_jerk[k] * rho * rho / p.share[i][k]))
    return v


def tangential_limits(p: Program, m: MachineLimits, i: int) -> tuple[float, float]:
    """Tangential acceleration and jerk of move ``i``: min_k A_k / share_k, J_k / share_k."""
    acc = m.per_share(m.max_acceleration, p.share[i])
    jerk = m.per_share(m.max_jerk, p.share[i])
    if not math.isfinite(acc):  # no direction at all
        acc = min(m.max_acceleration)
        jerk = min(m.max_jerk)
    return acc, jerk
