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
differently in five ways the profile feels:

* a junction whose direction change at the segments' speed v over one servo period T needs
  little acceleration -- a = (v / T + A) |t2 - t1|_k / A_k below ``ARC_BLEND_KINK_RATIO``
  = 0.1 on every axis k, twice that share next to a programmed arc -- is run through as
  tangent, without an arc (``tpSetupTangent``): no hold, no corner limit. v is the slower
  segment's speed limit as the test sees it, a short segment's clamped to its length over
  ONE servo period (``tcClampVelocityByLength`` when the line is added), not over the
  1.02 periods the motion later keeps (``TP_MIN_SEGMENT_CYCLES``): on 0.05 mm chords that
  is 2 % more speed, enough to turn the 2-quantum direction changes of 4-decimal
  coordinates (kink 0.0995) into corners, as the traces show (drawn8's freeform_81003 on
  the unchanged machine: 223 -> 38 mm/min). (A kink's speed, v kink_ratio / kink, below,
  keeps the segments' speeds over 1.02 periods: with the test's v that trace's gap is
  233 mm/min.)
* the arc's tangent length is at most half of each block and what the tolerance allows,
  d = min(l1 / 2, l2 / 2, sin(b/2) TIT / (1 - cos(b/2))), its radius R = d cot(b/2), its
  speed v_plan the lower of sqrt(a_n R) and the faster segment's feed; but the arc is only
  as large as that speed needs: R_plan = max(v_plan^2 / a_n, min(s / b, R)) with s the
  distance of a parabolic blend at half the acceleration (``blendComputeParameters``);
* along the arc the speed may change at half the acceleration of its plane
  (``BLEND_ACC_RATIO_TANGENTIAL``): the profile takes that from the holds (core.engine.profile);
* a junction that is not a kink gets the blend arc only where it promises more speed than
  the two other ways through (``tpChooseBestBlend``): a parabolic blend (the segments overlap;
  both keep half their acceleration over their whole length) and a tangent kink at
  v kink_ratio / kink; and next to a programmed arc only where the arc's plane holds the
  blend (a helix's does not): there the choice is between the other two
  (:func:`linuxcnc_choice`). A short blend arc at a long servo period, or a line into a
  helix, is run as a parabolic blend;
* a kink costs both segments its share of their acceleration (``tcSetKinkProperties``);
* next to a programmed arc (``blendInit3FromArcLine``, ``...LineArc``, ``...ArcArc``) the blend
  is laid between a line and the arc's secant where the other segment turns towards the
  arc's centre (convex): the arc keeps at most phi_max = min(2/3 of its angle (the arc
  before the corner; 1/3 the arc after), theta) for the blend, the intersection half-angle
  theta = (pi - b) / 2 drops to theta - phi_max / 4, and the arc side reaches
  sin(phi_max / 4) R (else phi_max R, theta unchanged); between two arcs a theta below
  pi / 12 gets no arc. A near-tangent line leaving an arc outward-bending then corners like
  a 30 degree turn (:func:`arc_blend_geometry`).

The servo period is the machine's block time over ``TP_MIN_SEGMENT_CYCLES`` = 1.02.
"""

from __future__ import annotations

import weakref

import numpy as np
from numpy.typing import NDArray

from core import TOL, Indicator, Machine, ToolPath, hookimpl
from core.engine.indicators import (
    BLEND_SPEED,
    LCNC_KINK_RATIO,
    LCNC_MIN_SEGMENT_CYCLES,
    LCNC_TANGENTIAL_RATIO,
    junction_shares,
)
from core.model import geometry as g
from core.model.arrays import nan_to_num
from core.model.native import kernels as corner_kernels
from core.model.pieces import SPLIT, rows_in_pieces
from plugins.feed_limit import lowest_axis

NAME = "tangential"
AXES = ("X", "Y", "Z")
#: Corners computed together: the temporaries of :func:`corner_feed` stay a few MB however
#: long the program (every corner is computed on its own row, so the pieces change nothing).
CHUNK = 65_536
#: A corner the program allows no deviation at (LinuxCNC G61, exact path: tolerance 0) is a
#: stop whatever the axes could do; it is named for that, not for an axis.
NO_BLEND = "exact path: no blending"
LABELS = (*(f"{q} {ax}" for q in ("feed", "acceleration", "jerk") for ax in AXES), NO_BLEND)
#: LinuxCNC's other two ways through a corner (``corner_blending = "linuxcnc"``).
PARABOLIC = "parabolic blend (half acceleration)"
KINK = "tangent kink"
#: LinuxCNC 2.9 tp_types.h: a parabolic blend's tolerance bound holds only above
#: TP_MIN_ARC_ANGLE (rad, of the intersection angle's complement); two directions are the
#: same (a blend arc lies in an arc's plane) within TP_ANGLE_EPSILON (rad).
LCNC_MIN_ARC_ANGLE = 1e-3
#: tc.c tcFindBlendTolerance: the share of a segment a blend arc may deviate by.
LCNC_TOLERANCE_RATIO = 0.25
LCNC_ANGLE_EPSILON = 1e-6
#: blendmath.c blendInit3FromArcArc: a blend between two arcs whose intersection half-angle
#: is below this is not made (rad).
LCNC_ARC_ARC_THETA_MIN = np.pi / 12.0


def servo_period(machine: Machine) -> float:
    """LinuxCNC's servo period (s): the machine's block time over TP_MIN_SEGMENT_CYCLES."""
    return machine.interpolation_time / LCNC_MIN_SEGMENT_CYCLES


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


def _rows(a: NDArray, k: NDArray[np.int64]) -> NDArray:
    """``a[k]`` of (n, 3) columns at the junctions ``k`` (integers): the same rows, several
    times faster (np.take along axis 0; 1M rows, 9 ms, not 45)."""
    return np.take(a, k, axis=0)


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
    return _corner_feed(corner_shares(t1, t2), radius, machine)


def corner_shares(
    t1: NDArray[np.float64],
    t2: NDArray[np.float64],
    turn: NDArray[np.float64] | None = None,
    at: NDArray[np.int64] | None = None,
) -> tuple[NDArray, NDArray]:
    """The machine-free part of :func:`corner_feed`: (m, 3) every axis's largest share of
    the tangent and of the normal over the inserted arc of each corner. ``turn``, ``at``:
    where the corners are the junctions ``at`` of a tool path and ``turn`` its
    :attr:`ToolPath.turn_angle` (``g.angle_between`` of the same rows), the corners'
    angles are read from there, else made here."""
    m = t1.shape[0]
    if m <= CHUNK and m < SPLIT:
        return _corner_shares(t1, t2, turn, at)
    # Each corner on its own: in pieces, the (m, 9) temporaries stay small (the same
    # arithmetic row by row; 1M corners: 150 MB less at the peak), the two halves of the
    # corners on two threads where two cores are (numpy's arctan2, cos, hypot let go of
    # the GIL: stellabee1's 169k corners 53 -> 28 ms).
    share_t, share_n = np.empty((m, 3)), np.empty((m, 3))

    def fill(s: slice) -> None:
        share_t[s], share_n[s] = _corner_shares(t1[s], t2[s], turn, None if at is None else at[s])

    rows_in_pieces(m, CHUNK, fill)
    return share_t, share_n


def _corner_shares(
    t1: NDArray[np.float64],
    t2: NDArray[np.float64],
    turn: NDArray[np.float64] | None,
    at: NDArray[np.int64] | None,
) -> tuple[NDArray, NDArray]:
    """:func:`corner_shares` of corners all at once."""
    if turn is None or at is None:
        beta = g.angle_between(t1, t2)
    else:
        beta = turn[at]
    u = _in_plane_normal(t1, t2)
    b = beta[:, None]
    return g.max_share(t1, u, b), g.max_share(u, -t1, b)


def _corner_feed(
    shares: tuple[NDArray, NDArray], radius: NDArray[np.float64], machine: Machine
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """:func:`corner_feed` from the corners' :func:`corner_shares`."""
    m = radius.shape[0]
    if m <= CHUNK and m < SPLIT:
        return _corner_feed_rows(shares, radius, machine)
    # in pieces, as the shares (the same arithmetic row by row), two halves side by side
    feed = np.empty(m)
    limit = np.empty(m, dtype=np.int64)

    def fill(s: slice) -> None:
        piece = (shares[0][s], shares[1][s])
        feed[s], limit[s] = _corner_feed_rows(piece, radius[s], machine)

    rows_in_pieces(m, CHUNK, fill)
    return feed, limit


def _corner_feed_rows(
    shares: tuple[NDArray, NDArray], radius: NDArray[np.float64], machine: Machine
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """:func:`_corner_feed` of corners all at once."""
    share_t, share_n = shares
    R = radius[:, None]
    inf = np.inf
    # An axis with no share over the arc sets no limit.
    with np.errstate(divide="ignore", invalid="ignore"):
        # The normal acceleration may use only a share of A (an effect; 1 in the paper).
        a_n = machine.max_acceleration * machine.normal_acceleration_factor
        v_jerk = np.where(share_t > 0, np.cbrt(machine.max_jerk * R**2 / share_t), inf)
        kernels = corner_kernels()
        if kernels is not None:  # the rest row by row, the same operations (numba's or C)
            f = np.float64
            return kernels.corner_limits(
                np.ascontiguousarray(share_t, dtype=f),
                np.ascontiguousarray(share_n, dtype=f),
                np.ascontiguousarray(radius, dtype=f),
                np.ascontiguousarray(v_jerk, dtype=f),
                np.ascontiguousarray(machine.max_feed, dtype=f),
                np.ascontiguousarray(a_n, dtype=f),
            )
        v_feed = np.where(share_t > 0, machine.max_feed / share_t, inf)
        v_acc = np.where(share_n > 0, np.sqrt(a_n * R / share_n), inf)
    # inf jerk times a zero radius is NaN: no radius means a stop.
    cand = np.concatenate([v_feed, v_acc, v_jerk], axis=1)
    nan_to_num(cand, copy=False, nan=0.0, posinf=inf)  # (in place: a new array)
    limit = np.argmin(cand, axis=1)
    return cand[np.arange(cand.shape[0]), limit], limit


def plane_acceleration(
    t1: NDArray[np.float64], t2: NDArray[np.float64], acc: NDArray
) -> tuple[NDArray, NDArray]:
    """(m,) the acceleration every direction in the plane of t1, t2 allows, and (m,) the axis
    (0, 1, 2) that sets it: LinuxCNC 2.9's inscribed circle of the axis limits in the blend
    plane (blendmath.c ``calculateInscribedDiameter``, called with the plane's unit normal
    n, the binormal): each axis's limit over the length of its unit vector projected onto
    the plane, A_k / sqrt(1 - n_k^2), the least of the three. In an axis-aligned plane that
    is the lower limit of the two axes it moves (the third's projection is nil); in a tilted
    one an axis is met only in part: a corner from (0.93, 0, 0.37) into +Y (n = (-0.37, 0,
    0.93)) with Z at 870 mm/s^2 and X, Y at 2000 allows min(2000 / 0.93, 2000, 870 / 0.37)
    = 2000. Where the directions are parallel (no plane) the lowest limit of the axes they
    move."""
    acc = np.asarray(acc, dtype=np.float64)
    moved = (np.abs(t1) > TOL.direction) | (np.abs(t2) > TOL.direction)
    per_axis = np.where(moved, acc[None, :], np.inf)
    n = np.cross(t1, t2)
    size = np.linalg.norm(n, axis=1)
    plane = size > TOL.direction
    with np.errstate(divide="ignore", invalid="ignore"):
        unit = n / size[:, None]
        scale = np.sqrt(np.clip(1.0 - unit * unit, 0.0, 1.0))
        inscribed = acc[None, :] / np.maximum(scale, TOL.direction)
    per_axis = np.where(plane[:, None], inscribed, per_axis)
    axis = per_axis.argmin(axis=1)
    return per_axis[np.arange(axis.size), axis], axis


def _next_acceleration(
    tp: ToolPath, j: NDArray[np.int64], machine: Machine, a_plane: NDArray
) -> NDArray:
    """(m,) the acceleration limit of the segment after each junction ``j`` as LinuxCNC's
    kink test adds it (tp.c ``tpSetupTangent``: a_inst = v_max / T + tc->maxaccel, tc the
    segment being added): a line's is canon's path acceleration (emccanon.cc
    ``getStraightAcceleration``: its length over the longest of the axes' times,
    min_k A_k / |t_k|), which a diagonal line has above every axis's; an arc's the
    lower limit of its plane's axes (``ARC_FEED``'s a_max_axes), the plane's acceleration
    ``a_plane`` the arc's corner is laid in. At 45 degrees with 2000 mm/s^2 a line has
    2828.4: 0.05 mm chords (50 mm/s over one servo period) turning by 0.3 degrees run as
    corners where the plane's 2000 would keep them tangent (LinuxCNC 2.9 traces)."""
    k = j + 1
    return np.where(tp.is_arc[k], a_plane, _path_acceleration(tp, k, machine))


def linuxcnc_blends(
    tp: ToolPath,
    j: NDArray[np.int64],
    tit: NDArray,
    machine: Machine,
    caps: tuple[NDArray, NDArray],
    geometry: tuple[NDArray, NDArray, NDArray],
    kink_caps: tuple[NDArray, NDArray],
) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray]:
    """LinuxCNC 2.9's corners (module docstring): the radius that limits the corner speed,
    the arc's radius as inserted (R_plan; 0 where the junction is run as tangent), whether
    it is tangent, the normal speed limit sqrt(a_n R) of the plane's acceleration with
    the axis that sets it, and the kink: the largest axis share of the acceleration turning
    at speed in one servo period needs (tangent below LCNC_KINK_RATIO). ``caps``: the two
    segments' top speeds (:func:`segment_caps`); ``geometry``: the direction change the arc
    is laid for and its reach before and after (:func:`arc_blend_geometry`); ``kink_caps``:
    the segments' top speeds the kink test sees (their lengths over one servo period)."""
    t1, t2 = _rows(tp.tangent_end, j), _rows(tp.tangent_start, j + 1)
    acc = machine.max_acceleration
    a_plane, axis = plane_acceleration(t1, t2, acc)
    a_n = a_plane * machine.normal_acceleration_factor
    servo = servo_period(machine)
    phi, reach_p, reach_n = geometry
    cap_p, cap_n = caps
    half = phi / 2.0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        d_tol = np.sin(half) * tit / (2.0 * np.sin(phi / 4.0) ** 2)
        d_geom = np.fmin(np.fmin(reach_p, reach_n), d_tol)
        r_geom = d_geom / np.tan(half)
        v_plan = np.fmin(np.sqrt(a_n * r_geom), np.fmax(cap_p, cap_n))
        a_par = LCNC_TANGENTIAL_RATIO * a_plane
        s_blend = np.fmin(np.sqrt(2.0 * a_par * d_geom), v_plan) / a_par * v_plan
        r_plan = np.fmin(np.fmax(v_plan * v_plan / a_n, np.fmin(s_blend / phi, r_geom)), r_geom)
        # tangent kinks: the acceleration of turning at full speed within one servo period,
        # plus the acceleration of the segment after (tc->maxaccel: a line's path
        # acceleration min_k A_k / |t_k|, more than the plane's off the axes; an arc's,
        # canon's a_max_axes of its plane, the plane's)
        a_inst = np.fmin(*kink_caps) / servo + _next_acceleration(tp, j, machine, a_plane)
        kink = np.max(np.abs(t2 - t1) * (a_inst[:, None] / acc[None, :]), axis=1)
    kink = np.where(tp.is_arc[j] | tp.is_arc[j + 1], kink / LCNC_TANGENTIAL_RATIO, kink)
    tangent = kink < LCNC_KINK_RATIO
    r_geom = nan_to_num(np.maximum(r_geom, 0.0), nan=0.0)
    r_plan = np.where(tangent, 0.0, nan_to_num(np.maximum(r_plan, 0.0), nan=0.0))
    return r_geom, r_plan, tangent, np.sqrt(a_n * r_geom), axis, kink


def linuxcnc_choice(
    tp: ToolPath,
    j: NDArray[np.int64],
    beta: NDArray,
    arc_feed: NDArray,
    r_plan: NDArray,
    kink: NDArray,
    caps: tuple[NDArray, NDArray],
    machine: Machine,
    phi: NDArray,
    refused: NDArray,
) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """LinuxCNC 2.9's choice at the junctions that are not tangent kinks (``tpHandleBlendArc``,
    ``tpChooseBestBlend``): the blend arc, a parabolic blend or a tangent kink, whichever
    promises the highest speed -- the arc's top speed (over its length in one block time too);
    half the speed a parabolic blend reaches (``estimateParabolicBlendPerformance`` / 2: it
    halves both segments' acceleration); the kink speed v kink_ratio / kink. An arc is tried
    only between lines, or where the arcs' planes hold the blend (no helix): else the choice
    is between the other two. Ties go to the parabolic blend (the first of the three).

    Returns, per junction: the mode (0 arc, 1 parabolic, 2 tangent kink), the speed it
    crosses the junction at (a parabolic blend: the speed that costs the time of the
    segments' overlap, :func:`parabolic_time_speed`, from the blend speed the planner
    computes while running with the segments' halved accelerations), and the share of the
    tangential acceleration both segments keep (1, 1/2, 1 - kink_ratio), and at a parabolic
    blend the speed the segment before starts it at (its blend speed, NaN elsewhere: the
    overlap a trace's feed column shows, :data:`BLEND_SPEED`). ``caps``: the two
    segments' top speeds (:func:`segment_caps`); ``phi``: the direction change the blend
    arc is laid for; ``refused``: junctions whose arc LinuxCNC refuses
    (:func:`arc_blend_geometry`).
    """
    k0, k1 = j, j + 1
    a_path = _path_acceleration(tp, np.concatenate([k0, k1]), machine)
    a0, a1 = a_path[: j.size], a_path[j.size :]
    t_int = machine.interpolation_time
    l0, l1 = tp.length[k0], tp.length[k1]
    f0, f1 = caps
    # (the angle between the segments' acceleration directions, not their tangents: an arc
    # after the junction leans towards its centre)
    sin_half, cos_half = _blend_half_angle(tp, j, a1)
    # the program's G64 P bounds a parabolic blend; without one (NaN) nothing does
    tol = np.nan_to_num(tp.tolerance[j], nan=0.0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # planning: the segments not yet finalised (half of each may go), their acceleration
        # halved (a parabolic end is the default) and reduced by the kink ratio
        plan = _parabolic_speed(
            a0 * 0.5 * (1.0 - LCNC_KINK_RATIO),
            a1 * 0.5 * (1.0 - LCNC_KINK_RATIO),
            l0 / 2.0,
            l1 / 2.0,
            l0,
            l1,
            f0,
            f1,
            tol,
            sin_half,
        )
        perf_parabolic = cos_half * (plan[0] + plan[1]) / 2.0 / 2.0
        perf_tangent = np.fmin(f0, f1) * LCNC_KINK_RATIO / kink
        arc_ok = _arc_blend_possible(tp, j) & ~refused
        arc_len = r_plan * phi
        perf_arc = np.where(arc_ok, np.fmin(arc_feed, arc_len / t_int), 0.0)
        run = _parabolic_speed(a0 * 0.5, a1 * 0.5, l0, l1, l0, l1, f0, f1, tol, sin_half)
    perf = np.stack([perf_arc, np.nan_to_num(perf_parabolic), np.nan_to_num(perf_tangent)])
    # the first of parabolic, tangent, arc that is strictly best (find_max_element)
    mode = np.where((perf[0] > perf[1]) & (perf[0] > perf[2]), 0, np.where(perf[2] > perf[1], 2, 1))
    with np.errstate(divide="ignore", invalid="ignore"):
        # a parabolic blend overlaps the segments: the one before brakes from its blend
        # speed to a stop while the one after starts from rest; it costs the time of a
        # corner crossed at u (what it saves beyond a corner at full speed is not modelled)
        u, _ = parabolic_time_speed(run[0], a0 * 0.5, a1 * 0.5, f1, servo_period(machine))
    speed = np.where(mode == 0, arc_feed, np.where(mode == 1, u, perf_tangent))
    share = np.where(mode == 1, 0.5, np.where(mode == 2, 1.0 - LCNC_KINK_RATIO, 1.0))
    return mode, speed, share, np.where(mode == 1, run[0], np.nan)


def segment_caps(
    tp: ToolPath, j: NDArray[np.int64], machine: Machine, *block_times: float
) -> list[tuple[NDArray, NDArray]]:
    """The top speed of the segments before and after junctions ``j`` (tcGetMaxTargetVel):
    the programmed feed within min_k Vmax_k / share_k (a program's F above the axes' runs at
    theirs), and the length over one block time: a (before, after) pair per block time of
    ``block_times`` (s).

    The path speed limit ([TRAJ]MAX_LINEAR_VELOCITY, the planner's vLimit) does not enter:
    canon gives each segment a maxvel from the axes' speeds alone (emccanon.cc
    ``getStraightVelocity``), the blend arcs and kinks are planned with it
    (blendmath.c ``blendParamKinematics``: v_goal from tcGetMaxTargetVel), and vLimit clips
    only the speed a segment is run at (tp.c ``tpGetRealTargetVel``). A 32 mm/s limit
    under a free-form path's F2000 (33.3 mm/s) leaves LinuxCNC's blend arcs, and the
    block-time dips between them, as they were; planned with the limit, the arcs shrank and
    the dips went (drawn26's freeform_260652, development data)."""
    k = np.concatenate([j, j + 1])
    v = lowest_axis(tp.axis_share, k, np.asarray(machine.max_feed, dtype=np.float64))[0]
    top = np.fmin(tp.feed[k], v)
    length = tp.length[k]
    out = []
    for t_block in block_times:
        capped = np.fmin(top, length / t_block)
        out.append((capped[: j.size], capped[j.size :]))
    return out


def _path_acceleration(tp: ToolPath, k: NDArray[np.int64], machine: Machine) -> NDArray:
    """(m,) the tangential acceleration of moves ``k`` (min_k A_k / share_k; arcs keep
    BLEND_ACC_RATIO_TANGENTIAL of it for their normal acceleration)."""
    acc = np.asarray(machine.max_acceleration, dtype=np.float64)
    a = lowest_axis(tp.axis_share, k, acc)[0]
    a = np.where(np.isfinite(a), a, acc.min())
    return np.where(tp.is_arc[k], a * LCNC_TANGENTIAL_RATIO, a)


def _blend_half_angle(
    tp: ToolPath, j: NDArray[np.int64], a_next: NDArray
) -> tuple[NDArray, NDArray]:
    """cos and sin of the intersection half-angle theta LinuxCNC's parabolic blend speed
    works with (tp.c ``tpComputeBlendVelocity``: theta = acos(-u1.u2) / 2): u1 the direction
    the segment before accelerates in at its end, u2 the one after at its start
    (tc.c ``tcGetEndAccelUnitVector``, ``tcGetStartAccelUnitVector``). A line's is its
    direction; an arc's end its tangent in its plane (a helix's rise left out); an arc's start
    the tangent in its plane at its overall acceleration ``a_next`` (mm/s^2) plus the
    direction to its centre at (F / 2)^2 / R, normalised. Between lines, with b the
    direction change, cos theta = sin(b / 2) and sin theta = cos(b / 2). A line into a
    helix of 4 mm radius at F3000 with 1000 mm/s^2: the start leans atan(156.25 / 1000) =
    8.9 deg towards the centre, a tolerance bound of 2 sqrt(1000 T / cos theta) with
    cos theta = sin(8.9 deg / 2) instead of a near tangent's."""
    u1 = tp.tangent_end[j].copy()
    u2 = tp.tangent_start[j + 1].copy()
    for u, k, start in ((u1, j, False), (u2, j + 1, True)):
        arc = tp.is_arc[k]
        if not arc.any():
            continue
        ka = k[arc]
        nrm = tp.normal[ka]
        t = u[arc]
        t -= g.dot(t, nrm)[:, None] * nrm  # in the arc's plane
        t = g.unit(t)
        if start:
            inward = -g.radial(tp.start[ka], tp.center[ka], nrm)
            r = g.norm(inward)
            with np.errstate(divide="ignore", invalid="ignore"):
                lean = (0.5 * tp.feed[ka]) ** 2 / r
                t = g.unit(t * a_next[arc][:, None] + inward / r[:, None] * lean[:, None])
        u[arc] = t
    dot = np.clip(g.dot(u1, u2), -1.0, 1.0)
    return np.sqrt((1.0 - dot) / 2.0), np.sqrt((1.0 + dot) / 2.0)


#: blendmath.h BLEND_ACC_RATIO_NORMAL: the share of an arc's acceleration LinuxCNC's canon
#: leaves for the normal acceleration when it caps an arc's speed (sqrt(3) / 2).
LCNC_NORMAL_RATIO = np.sqrt(3.0) / 2.0
#: A label for the arcs' acceleration shares (a share, not a limit: no feed).
ARC_SHARE = "LinuxCNC arc: tangential acceleration share"


def linuxcnc_arc_ratio(tp: ToolPath, k: NDArray[np.int64], machine: Machine, share: NDArray):
    """The share of the acceleration LinuxCNC 2.9 leaves for speed changes along the arcs
    ``k`` (tc.c ``tcUpdateCircleAccRatio`` when a segment is finalised, blendmath.c
    ``pmCircleActualMaxVel``): 0.5 (BLEND_ACC_RATIO_TANGENTIAL) where the arc's top speed
    needs more than sqrt(3)/2 (BLEND_ACC_RATIO_NORMAL) of its overall acceleration as normal
    acceleration, else sqrt(1 - (a_n / a)^2) -- which is 0.5 at that cutoff.

    - The top speed and acceleration are canon's (emccanon.cc ``ARC_FEED``): with a_p, v_p
      the lower of the plane's two axes' limits and R_c = sqrt(dr^2 + R^2) (dr the spiral's
      growth per radian), the planar speed v_pl = min(sqrt(sqrt(3)/2 a_p R_c), v_p); over the
      spiral length S = hypot(R |angle|, spiral) and the whole length L = hypot(S, rise),
      v = L / max(S / v_pl, straight-line time of the end point at the axes' speeds) and
      a = L / max(S / a_p, the same at the axes' accelerations); the top speed is then at
      most the arc's length over one servo period (``tcClampVelocityByLength``). The path
      speed limit ([TRAJ]MAX_LINEAR_VELOCITY, the planner's vLimit) does not enter:
      ``tcSetupMotion`` sets the segment's maxvel from canon's v above, and vLimit clips
      only the speed the segment is run at (``tpGetRealTargetVel``) -- a 55 mm/s limit
      above a spiral pocket's F3000 leaves LinuxCNC's feed moves as they were.
    - The overall acceleration a_o = a x ``share`` (what the arc's junctions take: a
      parabolic blend halves it, a kink its ratio; ``tcGetOverallMaxAccel``).
    - a_n = v^2 / R_e with LinuxCNC's effective radius of a helix,
      R_e = h^2 / R + R (``pmCircleEffectiveMinRadius``, h the WHOLE rise, not per turn):
      three turns of pitch 2 mm round R 3.36 mm have R_e = 36 / 3.36 + 3.36 = 14.07 mm, so
      at v = 76.6 mm/s a_n = 417 of a_o = 1000: the helix speeds up at
      sqrt(1 - 0.417^2) = 0.909 of a_o, 909 mm/s^2 (drawn9's unchanged thread milling:
      913); two turns of pitch 1 round R 2.69, R_e = 4.18, a_n = 1116 > 866: 0.5, 500
      mm/s^2 (drawn13's: 500); three turns of pitch 1 round R 2.54, R_e = 6.08, a_n = 727:
      sqrt(1 - 0.727^2) = 0.69 (drawn16's unchanged thread milling, where a cutoff at
      a_o / 2 predicted 0.5 and the diagnosis fitted an arc share of 0.66)."""
    nrm = tp.normal[k]
    start, end = tp.start[k], tp.end[k]
    r0 = g.norm(g.radial(start, tp.center[k], nrm))
    r1 = g.norm(g.radial(end, tp.center[k], nrm))
    angle = np.abs(tp.sweep[k])
    spiral = r1 - r0
    r_min = np.fmin(r0, r1)
    d = end - start
    rise = np.abs(g.dot(d, nrm))
    acc = np.asarray(machine.max_acceleration, dtype=np.float64)
    vel = np.asarray(machine.max_feed, dtype=np.float64)
    # the plane's two axes: all but the one the normal points along most
    plane = np.ones((k.size, 3), dtype=bool)
    plane[np.arange(k.size), np.argmax(np.abs(nrm), axis=1)] = False
    a_p = np.where(plane, acc, np.inf).min(axis=1)
    v_p = np.where(plane, vel, np.inf).min(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        dr = np.where(angle > 0.0, spiral / angle, 0.0)
        v_pl = np.fmin(np.sqrt(LCNC_NORMAL_RATIO * a_p * np.hypot(dr, r_min)), v_p)
        s_len = np.hypot(r_min * angle, spiral)
        length = np.hypot(s_len, rise)
        v = length / np.fmax(s_len / v_pl, (np.abs(d) / vel).max(axis=1))
        a = length / np.fmax(s_len / a_p, (np.abs(d) / acc).max(axis=1))
        v = np.fmin(v, tp.length[k] / servo_period(machine))
        a_o = a * share
        r_e = rise * rise / r_min + r_min
        a_n = v * v / r_e
        ratio = np.where(
            a_n > LCNC_NORMAL_RATIO * a_o,
            LCNC_TANGENTIAL_RATIO,
            np.sqrt(np.clip(1.0 - (a_n / a_o) ** 2, 0.0, 1.0)),
        )
    return np.where(np.isfinite(ratio), ratio, LCNC_TANGENTIAL_RATIO)


def _linuxcnc_arc_shares(
    tp: ToolPath, machine: Machine, j: NDArray[np.int64], share: NDArray | None
) -> list[Indicator]:
    """An element indicator of the feed arcs whose LinuxCNC share (:func:`linuxcnc_arc_ratio`)
    is not the 0.5 the ``linuxcnc-sim`` preset folds for all arcs (``arc_acceleration``):
    their ``acceleration_share``, relative to it (up to 2)."""
    k = np.flatnonzero(tp.is_arc & tp.is_feed)
    if k.size == 0:
        return []
    moves = np.ones(tp.n)
    if share is not None and j.size:
        junction_shares(moves, j, share)
    rel = linuxcnc_arc_ratio(tp, k, machine, moves[k]) / LCNC_TANGENTIAL_RATIO
    other = rel != 1.0
    if not other.any():
        return []
    k, rel = k[other], rel[other]
    return [
        Indicator(
            name=NAME,
            at="element",
            index=k,
            feed=np.full(k.size, np.inf),
            limit=np.zeros(k.size, dtype=np.int64),
            labels=(ARC_SHARE,),
            values={"acceleration_share": rel},
        )
    ]


def parabolic_time_speed(v_b, a_p, a_n, v_n, period=0.0):
    """How LinuxCNC's parabolic blend costs time (tp.c ``tpDoParabolicBlending``,
    ``tpUpdateBlend``): the speed ``u`` a corner crossed at constant speed would take to
    cost the same, and the time ``gain`` (s) the blend saves beyond a corner at ``u``.

    The segment before (tangential acceleration ``a_p``) brakes to a stop; when its speed
    falls below its blend speed ``v_b`` the segment after starts from rest and speeds up at
    its own acceleration ``a_n`` to its speed ``v_n`` while the first stops, over
    t_b = v_b / a_p; the two motions add. (tpUpdateBlend raises the second's target with the
    first's progress, up to its own blend speed; the traces show it does not bind: drawn13's
    unchanged thread_milling_131007, helix into the radial line out, the line speeds up at
    1000 mm/s^2 from the blend's start and runs at 11.2 mm/s when the helix stops, twice
    the 5.7 mm/s blend speed; the suite's 10_helix_3d_polyline, a helix into a tangent
    line at F3000, runs at up to 4414 mm/min while both move.)

    From the blend's start, the two reach "the first stopped, the second at v_n" after
    max(t_b, v_n / a_n); a corner crossed at u (the first brakes to u at its end, the second
    speeds up from u), over the same path, takes longer by
    A u^2 - (1 / a_p + 1 / a_n) u + t_b, A = 1 / (2 a_p v_b) + 1 / (2 a_n v_n). Equal at its
    smaller root: about v_b a_n / (a_p + a_n) where A u^2 is small (a third of the blend
    speed from a line into a helix, a_p 1000, a_n 500 mm/s^2). The planner steps once a
    servo ``period`` (s): the segments share at least the first's last step, so the overlap
    lasts at least one period (t_b = max(v_b / a_p, period); at 5 ms, 90 degree corners of
    lines blended at 2.38 mm/s and 1000 mm/s^2 overlap for one step, not 2.4 ms, and run
    as corners at the blend speed: the planner-trace test of squares). Where no u up to
    min(v_b, v_n) matches (the second segment speeding up faster than the first brakes; nearly
    tangent segments at full speed, whose motions add up to more than the feed) the corner
    is crossed at min(v_b, v_n) and the blend saves what that still costs (gain)."""
    b = 1.0 / a_p + 1.0 / a_n
    a = 0.5 / (a_p * v_b) + 0.5 / (a_n * v_n)
    t_b = np.fmax(v_b / a_p, period)
    disc = b * b - 4.0 * a * t_b
    top = np.fmin(v_b, v_n)
    with np.errstate(invalid="ignore"):
        u = (b - np.sqrt(disc)) / (2.0 * a)
    matched = (disc >= 0.0) & (u <= top)
    u = np.where(matched, u, top)
    gain = np.where(matched, 0.0, np.fmax(a * top * top - b * top + t_b, 0.0))
    return u, gain


def _parabolic_speed(a0, a1, reach0, reach1, l0, l1, f0, f1, tol, sin_half):
    """Both segments' speeds at a parabolic blend (tp.c ``tpComputeBlendVelocity``): each
    at most the peak it reaches over ``reach`` and its feed; the blend lasts at most the
    time either needs to cross its segment at that speed and at least the time the slower
    one needs to stop; a path tolerance bounds both by 2 sqrt(a0 T / sin(beta / 2))."""
    v0 = np.fmin(np.sqrt(a0 * reach0), f0)
    v1 = np.fmin(np.sqrt(a1 * reach1), f1)
    t_blend = np.fmin(np.fmin(l0 / v0, l1 / v1), np.fmax(v0 / a0, v1 / a1))
    v0 = np.fmin(v0, t_blend * a0)
    v1 = np.fmin(v1, t_blend * a1)
    bound = (tol > 0.0) & (sin_half > np.sin(LCNC_MIN_ARC_ANGLE))
    v_tol = np.where(bound, 2.0 * np.sqrt(a0 * tol / sin_half), np.inf)
    return np.fmin(v0, v_tol), np.fmin(v1, v_tol)


def arc_blend_geometry(
    tp: ToolPath, j: NDArray[np.int64], beta: NDArray
) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """LinuxCNC's blend geometry at junctions ``j`` (module docstring, last point): the
    direction change the blend arc is laid for (pi - 2 theta; ``beta`` between lines), how
    far it may reach along the segment before and after (half a line; an arc's secant
    share), and whether a blend between two arcs is refused (theta < pi / 12)."""
    theta_tan = (np.pi - beta) / 2.0
    theta = theta_tan.copy()
    reach_p = tp.length[j] / 2.0
    reach_n = tp.length[j + 1] / 2.0
    p = tp.end[j]
    for k, before in ((j, True), (j + 1, False)):
        arc = tp.is_arc[k]
        if not arc.any():
            continue
        a = np.flatnonzero(arc)
        ka = k[a]
        nrm = tp.normal[ka]
        r = p[a] - tp.center[ka]
        r = r - g.dot(r, nrm)[:, None] * nrm  # in the arc's plane (a helix rises along nrm)
        radius = g.norm(r)
        other = tp.tangent_start[ka + 1] if before else tp.tangent_end[ka - 1]
        d = g.dot(r, other)
        convex = d < 0.0 if before else d >= 0.0
        share = 2.0 / 3.0 if before else 1.0 / 3.0
        phi_max = np.fmin(tp.sweep[ka] * share, np.where(convex, theta_tan[a], np.pi / 2.0))
        theta[a] = np.where(convex, np.fmin(theta[a], theta_tan[a] - phi_max / 4.0), theta[a])
        reach = np.where(convex, np.sin(phi_max / 4.0) * radius, phi_max * radius)
        if before:
            reach_p[a] = reach
        else:
            reach_n[a] = reach
    both = tp.is_arc[j] & tp.is_arc[j + 1]
    refused = both & (theta < LCNC_ARC_ARC_THETA_MIN)
    return np.pi - 2.0 * theta, reach_p, reach_n, refused


def _arc_blend_possible(tp: ToolPath, j: NDArray[np.int64]) -> NDArray[np.bool_]:
    """Whether LinuxCNC tries a blend arc (``tpCheckBlendArcType``, the coplanarity checks
    of the line-arc, arc-line and arc-arc blends): always between lines; next to an arc only
    where the plane of the two tangents is the arc's plane, within LCNC_ANGLE_EPSILON (a
    helix's rise tilts it)."""
    t1, t2 = _rows(tp.tangent_end, j), _rows(tp.tangent_start, j + 1)
    ok = np.ones(j.size, dtype=bool)
    b = np.cross(t1, t2)
    nb = g.norm(b)
    for k in (j, j + 1):
        arc = tp.is_arc[k]
        if not arc.any():
            continue
        with np.errstate(invalid="ignore", divide="ignore"):
            cos = np.abs(g.dot(b, tp.normal[k])) / nb
        coplanar = cos > np.cos(LCNC_ANGLE_EPSILON)  # pmUnitCartsColinear
        ok &= ~arc | coplanar
    return ok


#: The corners' :func:`corner_shares` of tool paths evaluated more than once (a diagnosis
#: fits effects on hundreds of machines, one path), kept while the path lives; a path seen
#: once (analyze) keeps nothing (1M corners: 48 MB).
_SHARES: weakref.WeakKeyDictionary[ToolPath, tuple[NDArray, NDArray, NDArray]] = (
    weakref.WeakKeyDictionary()
)
_SEEN: weakref.WeakSet[ToolPath] = weakref.WeakSet()


def _shares_of(tp: ToolPath, j: NDArray[np.int64]) -> tuple[NDArray, NDArray]:
    """:func:`corner_shares` of the corners ``j`` of ``tp``, the second time on kept."""
    kept = _SHARES.get(tp)
    if kept is not None and np.array_equal(kept[0], j):
        return kept[1], kept[2]
    # (the corners' angles are the tool path's turn angles: the same rows, made once)
    shares = corner_shares(
        _rows(tp.tangent_end, j), _rows(tp.tangent_start, j + 1), tp.turn_angle, j
    )
    if tp in _SEEN:
        _SHARES[tp] = (j, *shares)
    else:
        _SEEN.add(tp)
    return shares


@hookimpl
def ncperf_evaluate(toolpath: ToolPath, machine: Machine) -> list[Indicator]:
    """Model 1 at every junction whose direction changes by more than TOL.collinear_angle."""
    tp = toolpath
    j = tp.junctions
    beta = tp.turn_angle[j]
    j = j[beta > TOL.collinear_angle]
    beta = tp.turn_angle[j]
    tol = tp.tolerance[j]
    if machine.corner_blending == "linuxcnc":
        # tc.c tcFindBlendTolerance: a blend arc deviates at most a quarter of either
        # segment, and that much where the program sets no tolerance (G64 without P)
        quarter = np.fmin(tp.length[j], tp.length[j + 1]) * LCNC_TOLERANCE_RATIO
        tit = np.where(np.isnan(tol), quarter, np.fmin(tol, quarter))
    else:
        tit = np.where(np.isnan(tol), machine.path_tolerance, tol)
    tangent = None
    phi = beta
    if machine.corner_blending == "linuxcnc":
        servo = servo_period(machine)
        caps, kink_caps = segment_caps(tp, j, machine, machine.interpolation_time, servo)
        phi, reach_p, reach_n, refused = arc_blend_geometry(tp, j, beta)
        radius, inserted, tangent, v_plane, axis, kink = linuxcnc_blends(
            tp, j, tit, machine, caps, (phi, reach_p, reach_n), kink_caps
        )
    else:
        shorter = np.minimum(tp.length[j], tp.length[j + 1])
        radius = inserted = inserted_radius(beta, shorter, tit)
    feed, limit = _corner_feed(_shares_of(tp, j), radius, machine)
    labels = LABELS
    extra = {}
    if tangent is not None:
        # LinuxCNC bounds the normal acceleration by the plane's, whatever the direction
        lower = v_plane < feed
        feed = np.where(lower, v_plane, feed)
        limit = np.where(lower, LABELS.index("acceleration X") + axis, limit)
        # the junctions that are not kinks: arc, parabolic blend or kink, the fastest
        share = 1.0 - np.where(tangent, kink, 0.0)
        blend = np.full(j.size, np.nan)
        choose = np.flatnonzero(~tangent & (tit > 0.0))
        if choose.size:
            mode, speed, sh, v_blend = linuxcnc_choice(
                tp,
                j[choose],
                beta[choose],
                feed[choose],
                inserted[choose],
                kink[choose],
                (caps[0][choose], caps[1][choose]),
                machine,
                phi[choose],
                refused[choose],
            )
            other = mode > 0
            c = choose[other]
            feed[c] = speed[other]
            limit[c] = np.where(mode[other] == 1, len(LABELS), len(LABELS) + 1)
            inserted[c] = 0.0
            share[choose] = sh
            blend[choose] = v_blend
        labels = (*LABELS, PARABOLIC, KINK)
        extra = {"acceleration_share": share, BLEND_SPEED: blend}
        feed = np.where(tangent & (tit > 0.0), np.inf, feed)
    limit = np.where(tit == 0.0, LABELS.index(NO_BLEND), limit)
    arcs: list[Indicator] = []
    if machine.corner_blending == "linuxcnc":
        arcs = _linuxcnc_arc_shares(tp, machine, j, extra.get("acceleration_share"))
    return [
        *arcs,
        Indicator(
            name=NAME,
            at="junction",
            index=j,
            feed=feed,
            limit=limit,
            labels=labels,
            # The speed stays constant over the inserted arc (sec. 2.1, Figure 2b): from
            # its tangent point R tan(beta/2) before the corner to the one after; the tool
            # runs the arc, R beta/2 on each side.
            values={
                "radius_mm": radius,
                "angle_deg": np.degrees(beta),
                "hold_mm": nan_to_num(inserted * np.tan(phi / 2.0), nan=0.0, posinf=0.0),
                "travel_mm": nan_to_num(inserted * phi / 2.0, nan=0.0, posinf=0.0),
            }
            | extra,
        ),
    ]
