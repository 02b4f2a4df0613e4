"""Model 1: crossing a tangential discontinuity (Tapie et al., sec. 3.2, eq. 1-10).

The controller replaces the corner between two blocks by an arc of radius R
(eq. 1) and crosses it at constant speed, where the normal acceleration
V^2/R (eq. 2) and the tangential jerk V^3/R^2 (eq. 3) must stay within the
machine's limits:

    R  = min(TIT cos(b/2) / (1 - cos(b/2)),  l / (2 sin(b/2)) - TIT),  l = min(l1, l2)   (1)
    Vf = min(Vmax, sqrt(A R), cbrt(J R^2))                                           (4-6)

with b the direction change between the blocks.

Per-axis limits, in 3-D
-----------------------
The inserted arc lies in the plane of the two tangents t1, t2. With u the unit
vector of that plane perpendicular to t1 (towards t2), the arc's tangent and
normal at sweep angle phi in [0, b] are

    t(phi) = cos(phi) t1 + sin(phi) u,    n(phi) = -sin(phi) t1 + cos(phi) u.

Along the arc the feed and the jerk (eq. 3, along t) load axis k with the
share |t_k(phi)|, the acceleration (eq. 2, along n) with |n_k(phi)|. Each
axis limit is divided by that axis's largest share over the sweep:

    Vmax = min_k Vmax_k / max|t_k|,   A = min_k A_k / max|n_k|,   J = min_k J_k / max|t_k|.

``a cos(phi) + b sin(phi)`` peaks in absolute value at sqrt(a^2 + b^2) where
phi = atan2(b, a) (mod pi); if that angle is inside [0, b] the share is that
peak, else the larger of the two ends. In the XY case of the paper, t1 and u
span the XY plane, so for X the peak is 1 at the angle where t is along X:
that is eq. (7) (t(alpha).Y_m = 0); inside the sweep it gives J = J_X (eq. 8),
outside it the share of the nearer end, |X1.Y_m| or |X2.Y_m| in the paper's
notation (eq. 9, 10). The same holds for Y, for the feed and, with n in place
of t, for the acceleration. A 3-D corner adds the Z share the same way.

TIT is the machine's path tolerance, or the program's own where it sets one
(LinuxCNC ``G64 P``).

LinuxCNC 2.9's planner (``corner_blending = "linuxcnc"``)
---------------------------------------------------------
Its source (``src/emc/tp/tp.c``, ``blendmath.c``; facts, not code, carried over) blends
differently in three ways the profile feels on chord paths:

* a junction whose direction change at the segments' speed v over one servo period T needs
  little acceleration -- a = (v / T + A) |t2 - t1|_k / A_k below ``ARC_BLEND_KINK_RATIO``
  = 0.1 on every axis k, twice that share next to a programmed arc -- is run through as
  tangent, without an arc (``tpSetupTangent``): no hold, no corner limit;
* the arc's tangent length is at most half of each block and what the tolerance allows,
  d = min(l1 / 2, l2 / 2, sin(b/2) TIT / (1 - cos(b/2))), its radius R = d cot(b/2), its
  speed v_plan the lower of sqrt(a_n R) and the faster segment's feed; but the arc is only
  as large as that speed needs: R_plan = max(v_plan^2 / a_n, min(s / b, R)) with s the
  distance of a parabolic blend at half the acceleration (``blendComputeParameters``);
* along the arc the speed may change at half the acceleration of its plane
  (``BLEND_ACC_RATIO_TANGENTIAL``): the profile takes that from the holds (core.engine.profile).

The servo period is the machine's block time over ``TP_MIN_SEGMENT_CYCLES`` = 1.02.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from core import TOL, Indicator, Machine, ToolPath, hookimpl
from core.engine.indicators import LCNC_KINK_RATIO, LCNC_MIN_SEGMENT_CYCLES, LCNC_TANGENTIAL_RATIO
from core.model import geometry as g

NAME = "tangential"
AXES = ("X", "Y", "Z")
#: Corners computed together: the temporaries of :func:`corner_feed` stay a few MB however
#: long the program (every corner is computed on its own row, so the pieces change nothing).
CHUNK = 65_536
#: A corner the program allows no deviation at (LinuxCNC G61, exact path: tolerance 0) is a
#: stop whatever the axes could do; it is named for that, not for an axis.
NO_BLEND = "exact path: no blending"
LABELS = (*(f"{q} {ax}" for q in ("feed", "acceleration", "jerk") for ax in AXES), NO_BLEND)


def inserted_radius(
    beta: NDArray[np.float64], length: NDArray[np.float64], tit: NDArray[np.float64] | float
) -> NDArray[np.float64]:
    """Eq. (1): radius (mm) of the arc inserted at a corner of direction change ``beta``.

    Parameters
    ----------
    beta : (m,) float, rad
        Direction change, (0, pi].
    length : (m,) float, mm
        The shorter of the two adjacent blocks.
    tit : float or (m,) float, mm
        Trajectory interpolation tolerance.

    Returns
    -------
    (m,) float, mm
        Never negative: blocks too short for the tolerance give 0 (a stop).
    """
    beta = np.asarray(beta, dtype=np.float64)
    half = beta / 2.0
    # 1 - cos(b/2) = 2 sin^2(b/4), without cancellation for small angles.
    with np.errstate(divide="ignore", invalid="ignore"):
        r_tol = tit * np.cos(half) / (2.0 * np.sin(beta / 4.0) ** 2)
        r_len = np.asarray(length, dtype=np.float64) / (2.0 * np.sin(half)) - tit
    return np.maximum(np.fmin(r_tol, r_len), 0.0)


def _in_plane_normal(t1: NDArray[np.float64], t2: NDArray[np.float64]) -> NDArray[np.float64]:
    """Unit u perpendicular to t1 in the plane (t1, t2), pointing towards t2."""
    u = t2 - g.dot(t1, t2)[:, None] * t1
    n = g.norm(u)
    bad = n < TOL.reversal  # a reversal (beta = pi): any perpendicular does, R is 0 anyway
    if bad.any():
        tb = t1[bad]
        helper = np.eye(3)[np.argmin(np.abs(tb), axis=1)]
        u[bad] = np.cross(tb, helper)
        n[bad] = g.norm(u[bad])
    return u / n[:, None]


def corner_feed(
    t1: NDArray[np.float64],
    t2: NDArray[np.float64],
    radius: NDArray[np.float64],
    machine: Machine,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Eq. (4)-(10) in 3-D: the feed on inserted arcs and the limit that binds.

    Parameters
    ----------
    t1, t2 : (m, 3) float
        Unit tangents before and after the corner.
    radius : (m,) float, mm
        Inserted arc radius (eq. 1).
    machine : Machine

    Returns
    -------
    feed : (m,) float, mm/s
    limit : (m,) int
        Index into :data:`LABELS`.
    """
    m = radius.shape[0]
    if m > CHUNK:
        # Each corner on its own: in pieces, the (m, 9) temporaries stay small (the same
        # arithmetic row by row; 1M corners: 150 MB less at the peak).
        feed = np.empty(m)
        limit = np.empty(m, dtype=np.int64)
        for a in range(0, m, CHUNK):
            b = min(a + CHUNK, m)
            feed[a:b], limit[a:b] = corner_feed(t1[a:b], t2[a:b], radius[a:b], machine)
        return feed, limit
    beta = g.angle_between(t1, t2)
    u = _in_plane_normal(t1, t2)
    b = beta[:, None]
    share_t = g.max_share(t1, u, b)
    share_n = g.max_share(u, -t1, b)
    R = radius[:, None]
    inf = np.inf
    # An axis with no share over the arc sets no limit.
    with np.errstate(divide="ignore", invalid="ignore"):
        v_feed = np.where(share_t > 0, machine.max_feed / share_t, inf)
        # The normal acceleration may use only a share of A (an effect; 1 in the paper).
        a_n = machine.max_acceleration * machine.normal_acceleration_factor
        v_acc = np.where(share_n > 0, np.sqrt(a_n * R / share_n), inf)
        v_jerk = np.where(share_t > 0, np.cbrt(machine.max_jerk * R**2 / share_t), inf)
    # inf jerk times a zero radius is NaN: no radius means a stop.
    cand = np.nan_to_num(np.concatenate([v_feed, v_acc, v_jerk], axis=1), nan=0.0, posinf=inf)
    limit = np.argmin(cand, axis=1)
    return cand[np.arange(cand.shape[0]), limit], limit


def plane_acceleration(
    t1: NDArray[np.float64], t2: NDArray[np.float64], acc: NDArray
) -> tuple[NDArray, NDArray]:
    """(m,) the acceleration every direction in the plane of t1, t2 allows -- the lowest
    limit of the axes that plane moves (LinuxCNC's inscribed circle of the axis limits in the
    blend plane, for axis-aligned planes) -- and (m,) that axis (0, 1, 2)."""
    moved = (np.abs(t1) > TOL.direction) | (np.abs(t2) > TOL.direction)
    per_axis = np.where(moved, np.asarray(acc)[None, :], np.inf)
    axis = per_axis.argmin(axis=1)
    return per_axis[np.arange(axis.size), axis], axis


def linuxcnc_blends(
    tp: ToolPath, j: NDArray[np.int64], beta: NDArray, tit: NDArray, machine: Machine
) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray]:
    """LinuxCNC 2.9's corners (module docstring): the radius that limits the corner speed,
    the arc's radius as inserted (R_plan; 0 where the junction is run as tangent), whether
    it is tangent, and the normal speed limit sqrt(a_n R) of the plane's acceleration with
    the axis that sets it."""
    t1, t2 = tp.tangent_end[j], tp.tangent_start[j + 1]
    acc = machine.max_acceleration
    a_plane, axis = plane_acceleration(t1, t2, acc)
    a_n = a_plane * machine.normal_acceleration_factor
    t_int = machine.interpolation_time
    servo = t_int / LCNC_MIN_SEGMENT_CYCLES
    lp, ln = tp.length[j], tp.length[j + 1]
    # each segment's top speed: its feed, and its length over one block time
    cap_p = np.fmin(tp.feed[j], lp / t_int)
    cap_n = np.fmin(tp.feed[j + 1], ln / t_int)
    half = beta / 2.0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        d_tol = np.sin(half) * tit / (2.0 * np.sin(beta / 4.0) ** 2)
        d_geom = np.fmin(np.fmin(lp, ln) / 2.0, d_tol)
        r_geom = d_geom / np.tan(half)
        v_plan = np.fmin(np.sqrt(a_n * r_geom), np.fmax(cap_p, cap_n))
        a_par = LCNC_TANGENTIAL_RATIO * a_plane
        s_blend = np.fmin(np.sqrt(2.0 * a_par * d_geom), v_plan) / a_par * v_plan
        r_plan = np.fmin(np.fmax(v_plan * v_plan / a_n, np.fmin(s_blend / beta, r_geom)), r_geom)
        # tangent kinks: the acceleration of turning at full speed within one servo period
        a_inst = np.fmin(cap_p, cap_n) / servo + a_plane
        kink = np.max(np.abs(t2 - t1) * (a_inst[:, None] / acc[None, :]), axis=1)
    kink = np.where(tp.is_arc[j] | tp.is_arc[j + 1], kink / LCNC_TANGENTIAL_RATIO, kink)
    tangent = kink < LCNC_KINK_RATIO
    r_geom = np.nan_to_num(np.maximum(r_geom, 0.0), nan=0.0)
    r_plan = np.where(tangent, 0.0, np.nan_to_num(np.maximum(r_plan, 0.0), nan=0.0))
    return r_geom, r_plan, tangent, np.sqrt(a_n * r_geom), axis


@hookimpl
def ncperf_evaluate(toolpath: ToolPath, machine: Machine) -> list[Indicator]:
    """Model 1 at every junction whose direction changes by more than TOL.collinear_angle."""
    tp = toolpath
    j = tp.junctions
    beta = tp.turn_angle[j]
    j = j[beta > TOL.collinear_angle]
    beta = tp.turn_angle[j]
    tol = tp.tolerance[j]
    tit = np.where(np.isnan(tol), machine.path_tolerance, tol)
    tangent = None
    if machine.corner_blending == "linuxcnc":
        radius, inserted, tangent, v_plane, axis = linuxcnc_blends(tp, j, beta, tit, machine)
    else:
        shorter = np.minimum(tp.length[j], tp.length[j + 1])
        radius = inserted = inserted_radius(beta, shorter, tit)
    feed, limit = corner_feed(tp.tangent_end[j], tp.tangent_start[j + 1], radius, machine)
    if tangent is not None:
        # LinuxCNC bounds the normal acceleration by the plane's, whatever the direction
        lower = v_plane < feed
        feed = np.where(lower, v_plane, feed)
        limit = np.where(lower, LABELS.index("acceleration X") + axis, limit)
        feed = np.where(tangent & (tit > 0.0), np.inf, feed)
    limit = np.where(tit == 0.0, LABELS.index(NO_BLEND), limit)
    return [
        Indicator(
            name=NAME,
            at="junction",
            index=j,
            feed=feed,
            limit=limit,
            labels=LABELS,
            # The speed stays constant over the inserted arc (sec. 2.1, Figure 2b): from
            # its tangent point R tan(beta/2) before the corner to the one after; the tool
            # runs the arc, R beta/2 on each side.
            values={
                "radius_mm": radius,
                "angle_deg": np.degrees(beta),
                "hold_mm": np.nan_to_num(inserted * np.tan(beta / 2.0), nan=0.0, posinf=0.0),
                "travel_mm": np.nan_to_num(inserted * beta / 2.0, nan=0.0, posinf=0.0),
            },
        )
    ]
