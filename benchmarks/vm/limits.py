"""The virtual machine's limits: ncperf's models, with one controller effect switched on.

The corner and block limits are the paper's models as ncperf's plugins compute them (that is
the point: the controller's *limits* are the models, its *motion* is independent of
``core.engine.profile``). Each effect either changes what the plugins are evaluated with (machine,
tool path), edits their indicator records before they are combined, or adds a cap.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from core import Indicator, Machine, Ncperf, PathMode, ToolPath, combine
from core.engine.effects import arc_caps
from core.engine.indicators import Evaluation
from core.engine.profile import boundary_caps
from core.model import geometry as g
from plugins import tangential

from .planner import Limits


@dataclasses.dataclass(frozen=True, eq=False)
class Segments:
    """The path the controller runs: the moves cut into segments, with arcs inserted at
    corners.

    Attributes
    ----------
    move : (m,) int
        Move each segment belongs to (the first half of a corner arc: the move before the
        corner; the second half: the move after).
    offset : (m,) float, mm
        Where a part of a move starts on that move (NaN for corner arcs).
    blend : (m,) int
        Corner arc of the segment, -1 for parts of moves.
    phi0 : (m,) float, rad
        Where a half corner arc starts on its arc.
    center, start_radial, axis : (k, 3) float
        Corner arcs: centre (mm), vector from the centre to the arc's start (mm), unit axis
        of rotation (the arc turns positively about it).
    radius : (k,) float, mm
    junction_boundary : (n + 1,) int
        Segment boundary at each move boundary (a corner's arc middle where one is inserted).
    """

    move: NDArray[np.int64]
    offset: NDArray[np.float64]
    blend: NDArray[np.int64]
    phi0: NDArray[np.float64]
    center: NDArray[np.float64]
    start_radial: NDArray[np.float64]
    axis: NDArray[np.float64]
    radius: NDArray[np.float64]
    junction_boundary: NDArray[np.int64]


@dataclasses.dataclass(frozen=True, eq=False)
class ControllerSetup:
    """What the controller runs: the (possibly edited) tool path, the machine its motion
    uses, the evaluation its limits come from, the segments and the planner's limits
    (per segment)."""

    toolpath: ToolPath
    machine: Machine
    evaluation: Evaluation
    segments: Segments
    limits: Limits


def tangential_limits(
    toolpath: ToolPath, machine: Machine
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(n,) tangential acceleration (mm/s^2) and jerk (mm/s^3, may be inf) of each move:
    min_k limit_k / share_k with the axis's largest share of the tangent over the move."""
    share = toolpath.axis_share
    with np.errstate(divide="ignore", invalid="ignore"):
        acc = np.where(share > 0, machine.max_acceleration / share, np.inf).min(axis=1)
        jerk = np.where(share > 0, machine.max_jerk / share, np.inf).min(axis=1)
    bad = ~np.isfinite(acc)  # no direction (cannot happen after zero-length moves are dropped)
    acc[bad] = machine.max_acceleration.min()
    jerk[bad] = machine.max_jerk.min()
    return acc, jerk


def _subset(ind: Indicator, keep: NDArray[np.bool_]) -> Indicator:
    return Indicator(
        name=ind.name,
        at=ind.at,
        index=ind.index[keep],
        feed=ind.feed[keep],
        limit=ind.limit[keep],
        labels=ind.labels,
        values={k: np.asarray(v)[keep] for k, v in ind.values.items()},
    )


def compression_runs(
    toolpath: ToolPath, max_angle_deg: float, max_length: float
) -> tuple[NDArray[np.bool_], NDArray[np.int64]]:
    """Runs of path compression.

    Returns
    -------
    inner : (n - 1,) bool
        Junctions inside a run (between two short feed blocks of one chain, turning less
        than ``max_angle_deg``, with no stop or dwell).
    run : (n,) int
        Run id of each move, -1 outside runs.
    """
    tp = toolpath
    n = tp.n
    inner = np.zeros(max(n - 1, 0), dtype=bool)
    run = np.full(n, -1, dtype=np.int64)
    if n < 2:
        return inner, run
    short = tp.is_feed & (tp.length < max_length)
    j = tp.junctions
    ok = (
        short[j]
        & short[j + 1]
        & (tp.turn_angle[j] < math.radians(max_angle_deg))
        & (tp.path_mode[j] != PathMode.EXACT_STOP)
        & (tp.dwell[j] <= 0)
    )
    inner[j[ok]] = True
    member = np.zeros(n, dtype=bool)
    member[:-1] |= inner
    member[1:] |= inner
    starts = member & ~np.concatenate([[False], inner])
    ids = np.cumsum(starts) - 1
    run[member] = ids[member]
    return inner, run


def _compress(
    toolpath: ToolPath, machine: Machine, indicators: Sequence[Indicator], max_angle, max_length
) -> list[Indicator]:
    tp = toolpath
    inner, run = compression_runs(tp, max_angle, max_length)
    out: list[Indicator] = []
    for ind in indicators:
        if ind.at == "junction" and ind.name in ("tangential", "curvature"):
            ind = _subset(ind, ~inner[ind.index])
        elif ind.at == "element" and ind.name == "ncu_capacity":
            ind = _subset(ind, run[ind.index] < 0)
        out.append(ind)
    members = np.flatnonzero(run >= 0)
    if members.size:
        run_len = np.bincount(run[members], weights=tp.length[members])
        lr = run_len[run[members]]
        capped = lr < tp.feed[members] * machine.interpolation_time
        i = members[capped]
        out.append(
            Indicator(
                name="ncu_capacity",
                at="element",
                index=i,
                feed=lr[capped] / machine.interpolation_time,
                limit=np.zeros(i.size, dtype=np.int64),
                labels=("block time",),
            )
        )
    return out


def build_segments(
    toolpath: ToolPath,
    machine: Machine,
    indicators: Sequence[Indicator],
    cap: NDArray[np.float64],
    boundary: NDArray[np.float64],
    acc: NDArray[np.float64],
    jerk: NDArray[np.float64],
    window: int | None,
) -> tuple[Segments, Limits]:
    """Cut the moves into the segments the controller runs, with their limits.

    * Corners (model 1, sec. 2.1, Fig. 2b): where the tangential model gives a radius R > 0
      at a junction the machine does not stop at, the corner is replaced by the arc of
      radius R tangent to both moves, from R tan(b/2) before the corner point to R tan(b/2)
      after it (at most half of each move; R shrinks with it), run at most at the junction's
      cap over its whole length R b: it is a segment of its own, split in two halves at the
      corner (each half carries the line of its move).
    * Curvature jumps (model 2, eq. 11-12): the speed is held at the junction's cap while the
      normal acceleration changes, over the distance run in dt: 0.5 V dt on each side.
    * Elsewhere a move is one segment with the move's cap; the boundary caps are the lower of
      the two sides' caps and, at the move boundaries, ncperf's boundary caps (0 at stops).
    """
    tp = toolpath
    n = tp.n
    L = tp.length
    w = boundary[1:-1]  # cap at each junction j (between moves j and j + 1); 0: a stop
    trim = np.zeros(max(n - 1, 0))
    radius = np.zeros(max(n - 1, 0))
    hold = np.zeros(max(n - 1, 0))
    for ind in indicators:
        if ind.at != "junction" or ind.index.size == 0:
            continue
        j = ind.index
        ok = w[j] > 0
        if ind.name == "tangential" and "radius_mm" in ind.values:
            r = np.asarray(ind.values["radius_mm"], dtype=np.float64)
            half = np.tan(tp.turn_angle[j] / 2.0)
            ok &= (r > 0) & np.isfinite(r) & (half > 0) & np.isfinite(half)
            tt = np.minimum(r * half, 0.5 * np.minimum(L[j], L[j + 1]))
            j, tt, half = j[ok], tt[ok], half[ok]
            trim[j] = tt
            radius[j] = tt / half
        elif ind.name == "curvature":
            ok &= np.isfinite(ind.feed)
            hold[j[ok]] = 0.5 * w[j[ok]] * machine.curvature_transition_time
    t1 = tp.tangent_end[:-1]
    t2 = tp.tangent_start[1:]
    axis_raw = np.cross(t1, t2)
    blended = (trim > 1e-9) & (g.norm(axis_raw) > 1e-12) if n > 1 else np.zeros(0, dtype=bool)
    hold = np.where(blended, 0.0, np.minimum(hold, 0.5 * np.minimum(L[:-1], L[1:])))
    trim = np.where(blended, trim, 0.0)

    # Corner arcs: centre on the bisector at R / cos(b/2) from the corner point.
    jb = np.flatnonzero(blended)
    beta = tp.turn_angle[jb]
    rb = radius[jb]
    bis = g.unit(t2[jb] - t1[jb])
    center = tp.end[jb] + bis * (rb / np.cos(beta / 2.0))[:, None]
    start = tp.end[jb] - t1[jb] * trim[jb][:, None]
    blend_id = np.full(max(n - 1, 0), -1, dtype=np.int64)
    blend_id[jb] = np.arange(jb.size)

    seg_move: list[int] = []
    seg_off: list[float] = []
    seg_blend: list[int] = []
    seg_phi: list[float] = []
    seg_len: list[float] = []
    seg_cap: list[float] = []
    seg_acc: list[float] = []
    seg_jerk: list[float] = []
    seg_dwell: list[float] = []
    jbound = np.zeros(n + 1, dtype=np.int64)
    Ll, capl, accl, jerkl, wl = L.tolist(), cap.tolist(), acc.tolist(), jerk.tolist(), w.tolist()
    triml, holdl, bl, dwl = trim.tolist(), hold.tolist(), blend_id.tolist(), tp.dwell.tolist()
    rl = radius.tolist()
    betal = tp.turn_angle.tolist() if n > 1 else []

    def part(k: int, u: float, length: float, c: float) -> None:
        seg_move.append(k)
        seg_off.append(u)
        seg_blend.append(-1)
        seg_phi.append(0.0)
        seg_len.append(length)
        seg_cap.append(c)
        seg_acc.append(accl[k])
        seg_jerk.append(jerkl[k])
        seg_dwell.append(0.0)

    for k in range(n):
        start_cut = triml[k - 1] if k > 0 else 0.0
        start_hold = holdl[k - 1] if k > 0 else 0.0
        end_cut = triml[k] if k < n - 1 else 0.0
        end_hold = holdl[k] if k < n - 1 else 0.0
        u = start_cut
        if start_hold > 0:
            part(k, u, start_hold, min(capl[k], wl[k - 1]))
            u += start_hold
        mid = Ll[k] - end_cut - end_hold - u
        if mid > 1e-12:
            part(k, u, mid, capl[k])
            u += mid
        if end_hold > 0:
            part(k, u, end_hold, min(capl[k], wl[k]))
        if seg_len and seg_move[-1] == k:
            seg_dwell[-1] = dwl[k]
        if k < n - 1 and bl[k] >= 0:
            arc = rl[k] * betal[k]
            for half, mv in ((0, k), (1, k + 1)):
                seg_move.append(mv)
                seg_off.append(math.nan)
                seg_blend.append(bl[k])
                seg_phi.append(0.5 * betal[k] * half)
                seg_len.append(0.5 * arc)
                seg_cap.append(wl[k])
                seg_acc.append(min(accl[k], accl[k + 1]))
                seg_jerk.append(min(jerkl[k], jerkl[k + 1]))
                seg_dwell.append(0.0)
                if half == 0:
                    jbound[k + 1] = len(seg_len)
        else:
            jbound[k + 1] = len(seg_len)
    m = len(seg_len)
    cap_s = np.asarray(seg_cap)
    bnd = np.zeros(m + 1)
    if m > 1:
        bnd[1:-1] = np.minimum(cap_s[:-1], cap_s[1:])
    bnd[jbound[1:-1]] = np.minimum(bnd[jbound[1:-1]], boundary[1:-1])
    bnd[0] = bnd[-1] = 0.0
    move = np.asarray(seg_move, dtype=np.int64)
    window_end = None
    if window is not None:
        window_end = jbound[np.minimum(move + window + 1, n)]
    segments = Segments(
        move=move,
        offset=np.asarray(seg_off),
        blend=np.asarray(seg_blend, dtype=np.int64),
        phi0=np.asarray(seg_phi),
        center=center,
        start_radial=start - center,
        axis=g.unit(axis_raw[jb]),
        radius=rb,
        junction_boundary=jbound,
    )
    limits = Limits(
        length=np.asarray(seg_len),
        cap=cap_s,
        boundary=bnd,
        acc=np.asarray(seg_acc),
        jerk=np.asarray(seg_jerk),
        dwell=np.asarray(seg_dwell),
        window_end=window_end,
    )
    return segments, limits


def controller_setup(
    toolpath: ToolPath,
    machine: Machine,
    effect: str | None,
    params: Mapping[str, float],
    ncperf: Ncperf,
) -> ControllerSetup:
    """The limits of the reference controller with ``effect`` (params already resolved)."""
    tp = toolpath
    m_eval = machine  # what the models are evaluated with
    m_motion = machine  # what the motion uses
    window: int | None = None
    if effect == "feed_override":
        tp = dataclasses.replace(tp, feed=tp.feed * params["scale"])
    elif effect == "block_cycle_time":
        m_eval = dataclasses.replace(machine, interpolation_time=params["t_block"])
    elif effect == "corner_tolerance":
        # The controller's effective tolerance: it replaces the machine's TIT and any the
        # program sets (G64 P, CTOL), as ncperf's diagnosis reads this effect.
        m_eval = dataclasses.replace(machine, path_tolerance=params["tolerance"])
        tp = dataclasses.replace(tp, tolerance=np.full(tp.n, params["tolerance"]))
    elif effect == "axis_dynamics":
        m_eval = m_motion = dataclasses.replace(
            machine,
            max_acceleration=machine.max_acceleration * params["accel_scale"],
            max_jerk=machine.max_jerk * params["jerk_scale"],
            max_feed=machine.max_feed * params["feed_scale"],
        )
    elif effect == "lookahead_depth":
        window = int(params["blocks"])

    indicators = ncperf.indicators(tp, m_eval)
    if effect == "normal_acceleration_factor":
        # Model 1 uses A only for the normal part (sqrt(A R)): evaluating the tangential plugin
        # with A scaled scales exactly that part (the radius is unchanged).
        scaled = dataclasses.replace(
            m_eval, max_acceleration=m_eval.max_acceleration * params["factor"]
        )
        indicators = [i for i in indicators if i.name != tangential.NAME]
        indicators += tangential.ncperf_evaluate(toolpath=tp, machine=scaled)
    elif effect == "path_compression":
        indicators = _compress(tp, m_eval, indicators, params["max_angle"], params["max_length"])
    ev = combine(tp, m_eval, indicators)

    cap = ev.element_feed.copy()
    rapid = ~tp.is_feed
    if rapid.any():
        cap[rapid] = m_motion.rapid_speed(tp.tangent_start[rapid])
    if effect == "arc_feed_limit":
        cap = np.minimum(cap, arc_caps(tp, m_motion))
    elif effect == "normal_acceleration_factor":
        # programmed arcs: their normal acceleration gets the same share (no jerk part)
        m_normal = dataclasses.replace(m_motion, normal_acceleration_factor=params["factor"])
        cap = np.minimum(cap, arc_caps(tp, m_normal, jerk=False))
    acc, jerk = tangential_limits(tp, m_motion)
    segments, limits = build_segments(
        tp, m_eval, indicators, cap, boundary_caps(ev, cap), acc, jerk, window
    )
    return ControllerSetup(
        toolpath=tp, machine=m_motion, evaluation=ev, segments=segments, limits=limits
    )
