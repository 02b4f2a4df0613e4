"""What the reference controller runs: the moves cut into segments with their limits.

The limits are the paper's models (:mod:`refvm.models`), written here independently of
ncperf; one controller effect may change what they are evaluated with (the machine, the
program's feeds or tolerances) or edit them. Corners are run as model 1 describes them
(sec. 2.1, Fig. 2b): on the inserted arc of radius R, tangent to both blocks, at most at the
corner's feed over its whole length; a curvature jump holds its feed while the normal
acceleration changes (model 2: over the distance run in dt, half on each side).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from refvm import models
from refvm import vec as V
from refvm.machine import MachineLimits
from refvm.planner import Limits
from refvm.program import Program

#: Lengths (mm) below this are nil when cutting moves into segments (a picometre).
NIL = 1e-9


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
    """What the controller runs: the (possibly edited) program, the machine its motion uses,
    each move's cruise cap and each move boundary's cap, the segments and the planner's
    limits (per segment)."""

    program: Program
    machine: MachineLimits
    cap: NDArray[np.float64]
    boundary: NDArray[np.float64]
    segments: Segments
    limits: Limits


@dataclasses.dataclass(frozen=True)
class _Models:
    """The models' results on a program (junction dicts are keyed by junction index)."""

    corner_feed: dict[int, float]
    corner_radius: dict[int, float]
    transition_feed: dict[int, float]
    cap: list[float]


def compression_runs(
    p: Program, max_angle_deg: float, max_length: float
) -> tuple[set[int], list[int]]:
    """Runs of path compression: junctions inside a run (both blocks feed blocks shorter
    than ``max_length`` of one chain, turning less than ``max_angle_deg``, no stop or dwell
    between them), and the run of each move (-1 outside runs)."""
    inner = set()
    for j in models.junctions(p):
        short = p.length[j] < max_length and p.length[j + 1] < max_length
        turn = V.angle(p.t_end[j], p.t_start[j + 1])
        if short and turn < math.radians(max_angle_deg) and not models.stops_after(p, j):
            inner.add(j)
    run = [-1] * p.n
    current = -1
    for i in range(p.n):
        joined_before = (i - 1) in inner
        joined_after = i in inner
        if joined_after and not joined_before:
            current += 1
        run[i] = current if (joined_before or joined_after) else -1
    return inner, run


def evaluate(
    p: Program,
    m: MachineLimits,
    *,
    corner_machine: MachineLimits | None = None,
    compression: tuple[float, float] | None = None,
) -> _Models:
    """Models 1-3 and the axes' feed limits on ``p``; ``corner_machine`` evaluates model 1
    (a changed normal acceleration share); ``compression`` merges runs of short blocks."""
    inner: set[int] = set()
    run = [-1] * p.n
    if compression is not None:
        inner, run = compression_runs(p, *compression)
    cm = corner_machine or m
    corner_feed, corner_radius, transition_feed = {}, {}, {}
    for j in models.junctions(p):
        if j in inner:
            continue  # one spline: no corner or curvature limit inside a run
        c = models.corner(p, cm, j)
        if c is not None:
            corner_feed[j], corner_radius[j] = c
        t = models.transition(p, m, j)
        if t is not None:
            transition_feed[j] = t
    cap = [models.block_cap(p, m, i, block_time=run[i] < 0) for i in range(p.n)]
    if compression is not None:
        # A merged run is one block for the block time: L_run / t_int where L_run < F t_int.
        run_length: dict[int, float] = {}
        for i in range(p.n):
            if run[i] >= 0:
                run_length[run[i]] = run_length.get(run[i], 0.0) + p.length[i]
        for i in range(p.n):
            if run[i] >= 0:
                lr = run_length[run[i]]
                if lr < p.feed[i] * m.interpolation_time:
                    cap[i] = min(cap[i], lr / m.interpolation_time)
    return _Models(corner_feed, corner_radius, transition_feed, cap)


def boundary_caps(p: Program, mod: _Models) -> list[float]:
    """(n + 1) speed caps at the move boundaries: 0 at the program's ends and wherever the
    chain breaks (exact stops, dwells, rapids, operation changes); elsewhere the lower of
    the two moves' caps and the junction's model feeds."""
    b = [0.0] * (p.n + 1)
    for j in models.junctions(p):
        if models.stops_after(p, j):
            continue
        w = min(mod.cap[j], mod.cap[j + 1])
        w = min(w, mod.corner_feed.get(j, math.inf), mod.transition_feed.get(j, math.inf))
        b[j + 1] = w
    return b


def controller_setup(
    program: Program, machine: MachineLimits, effect: str | None, params: Mapping[str, float]
) -> ControllerSetup:
    """The limits of the reference controller with ``effect`` (params already resolved)."""
    p = program
    m_eval = machine  # what the models are evaluated with
    m_motion = machine  # what the motion uses
    m_corner = None
    window: int | None = None
    compression = None
    if effect == "feed_override":
        p = dataclasses.replace(p, feed=[f * params["scale"] for f in p.feed])
    elif effect == "block_cycle_time":
        m_eval = machine.replace(interpolation_time=params["t_block"])
    elif effect == "corner_tolerance":
        # The controller's effective tolerance: it replaces the machine's TIT and any the
        # program sets (G64 P, CTOL).
        m_eval = machine.replace(path_tolerance=params["tolerance"])
        p = dataclasses.replace(p, tolerance=[params["tolerance"]] * p.n)
    elif effect == "axis_dynamics":
        m_eval = m_motion = machine.scaled(
            accel=params["accel_scale"], jerk=params["jerk_scale"], feed=params["feed_scale"]
        )
    elif effect == "lookahead_depth":
        window = int(params["blocks"])
    elif effect == "normal_acceleration_factor":
        m_corner = m_eval.replace(normal_acceleration_factor=params["factor"])
    elif effect == "path_compression":
        compression = (params["max_angle"], params["max_length"])

    mod = evaluate(p, m_eval, corner_machine=m_corner, compression=compression)
    cap = list(mod.cap)
    if effect == "arc_feed_limit":
        cap = [min(c, models.arc_cap(p, m_motion, i)) for i, c in enumerate(cap)]
    elif effect == "normal_acceleration_factor":
        # programmed arcs: their normal acceleration gets the same share (no jerk part)
        m_normal = m_motion.replace(normal_acceleration_factor=params["factor"])
        cap = [min(c, models.arc_cap(p, m_normal, i, jerk=False)) for i, c in enumerate(cap)]
    mod = dataclasses.replace(mod, cap=cap)
    boundary = boundary_caps(p, mod)
    tang = [models.tangential_limits(p, m_motion, i) for i in range(p.n)]
    segments, limits = build_segments(p, m_eval, mod, boundary, tang, window)
    return ControllerSetup(
        program=p,
        machine=m_motion,
        cap=np.asarray(cap),
        boundary=np.asarray(boundary),
        segments=segments,
        limits=limits,
    )


def build_segments(
    p: Program,
    m: MachineLimits,
    mod: _Models,
    boundary: list[float],
    tang: list[tuple[float, float]],
    window: int | None,
) -> tuple[Segments, Limits]:
    """Cut the moves into the segments the controller runs, with their limits.

    * Corners (model 1): where the inserted radius R > 0 at a junction the machine does not
      stop at, the corner is replaced by the arc of radius R tangent to both moves, from
      R tan(b/2) before the corner point to R tan(b/2) after it (at most half of each move;
      R shrinks with it), run at most at the junction's cap over its whole length R b: a
      segment of its own, split in two halves at the corner (each half carries the line of
      its move).
    * Curvature jumps (model 2): the speed is held at the junction's cap while the normal
      acceleration changes, over the distance run in dt: 0.5 V dt on each side.
    * Elsewhere a move is one segment with the move's cap; the boundary caps are the lower of
      the two sides' caps and, at the move boundaries, the boundary caps (0 at stops).
    """
    n = p.n
    L = p.length
    trim = [0.0] * max(n - 1, 0)
    radius = [0.0] * max(n - 1, 0)
    hold = [0.0] * max(n - 1, 0)
    beta = [V.angle(p.t_end[j], p.t_start[j + 1]) for j in range(n - 1)]
    for j, r in mod.corner_radius.items():
        w = boundary[j + 1]
        half = math.tan(beta[j] / 2.0)
        if w > 0 and r > 0 and math.isfinite(r) and half > 0 and math.isfinite(half):
            trim[j] = min(r * half, 0.5 * min(L[j], L[j + 1]))
            radius[j] = trim[j] / half
    for j, v in mod.transition_feed.items():
        w = boundary[j + 1]
        if w > 0 and math.isfinite(v):
            hold[j] = 0.5 * w * m.curvature_transition_time
    blended = [False] * max(n - 1, 0)
    corner_arcs: list[tuple[V.Vec, V.Vec, V.Vec, float]] = []  # centre, start radial, axis, R
    blend_id = [-1] * max(n - 1, 0)
    for j in range(n - 1):
        t1, t2 = p.t_end[j], p.t_start[j + 1]
        axis = V.cross(t1, t2)
        if trim[j] > NIL and V.length(axis) > 1e-12:
            blended[j] = True
            # centre on the bisector, R / cos(b/2) from the corner point
            bis = V.unit(V.sub(t2, t1))
            centre = V.add(p.end[j], V.mul(bis, radius[j] / math.cos(beta[j] / 2.0)))
            start = V.sub(p.end[j], V.mul(t1, trim[j]))
            blend_id[j] = len(corner_arcs)
            corner_arcs.append((centre, V.sub(start, centre), V.unit(axis), radius[j]))
            hold[j] = 0.0
        else:
            trim[j] = 0.0
            hold[j] = min(hold[j], 0.5 * min(L[j], L[j + 1]))

    seg_move: list[int] = []
    seg_off: list[float] = []
    seg_blend: list[int] = []
    seg_phi: list[float] = []
    seg_len: list[float] = []
    seg_cap: list[float] = []
    seg_acc: list[float] = []
    seg_jerk: list[float] = []
    seg_dwell: list[float] = []
    jbound = [0] * (n + 1)
    cap = mod.cap

    def part(k: int, u: float, length: float, c: float) -> None:
        seg_move.append(k)
        seg_off.append(u)
        seg_blend.append(-1)
        seg_phi.append(0.0)
        seg_len.append(length)
        seg_cap.append(c)
        seg_acc.append(tang[k][0])
        seg_jerk.append(tang[k][1])
        seg_dwell.append(0.0)

    for k in range(n):
        start_cut = trim[k - 1] if k > 0 else 0.0
        start_hold = hold[k - 1] if k > 0 else 0.0
        end_cut = trim[k] if k < n - 1 else 0.0
        end_hold = hold[k] if k < n - 1 else 0.0
        u = start_cut
        if start_hold > 0:
            part(k, u, start_hold, min(cap[k], boundary[k]))
            u += start_hold
        mid = L[k] - end_cut - end_hold - u
        if mid > 1e-12:
            part(k, u, mid, cap[k])
            u += mid
        if end_hold > 0:
            part(k, u, end_hold, min(cap[k], boundary[k + 1]))
        if seg_len and seg_move[-1] == k:
            seg_dwell[-1] = p.dwell[k]
        if k < n - 1 and blended[k]:
            arc = radius[k] * beta[k]
            for half_no, mv in ((0, k), (1, k + 1)):
                seg_move.append(mv)
                seg_off.append(math.nan)
                seg_blend.append(blend_id[k])
                seg_phi.append(0.5 * beta[k] * half_no)
                seg_len.append(0.5 * arc)
                seg_cap.append(boundary[k + 1])
                seg_acc.append(min(tang[k][0], tang[k + 1][0]))
                seg_jerk.append(min(tang[k][1], tang[k + 1][1]))
                seg_dwell.append(0.0)
                if half_no == 0:
                    jbound[k + 1] = len(seg_len)
        else:
            jbound[k + 1] = len(seg_len)
    count = len(seg_len)
    bnd = [0.0] * (count + 1)
    for i in range(1, count):
        bnd[i] = min(seg_cap[i - 1], seg_cap[i])
    for k in range(1, n):
        b = jbound[k]
        bnd[b] = min(bnd[b], boundary[k])
    bnd[0] = bnd[count] = 0.0
    move = np.asarray(seg_move, dtype=np.int64)
    window_end = None
    if window is not None:
        window_end = np.asarray(jbound)[np.minimum(move + window + 1, n)]
    arcs = corner_arcs or [((0.0,) * 3, (0.0,) * 3, (0.0,) * 3, 0.0)][:0]
    segments = Segments(
        move=move,
        offset=np.asarray(seg_off),
        blend=np.asarray(seg_blend, dtype=np.int64),
        phi0=np.asarray(seg_phi),
        center=np.asarray([a[0] for a in arcs], dtype=np.float64).reshape(-1, 3),
        start_radial=np.asarray([a[1] for a in arcs], dtype=np.float64).reshape(-1, 3),
        axis=np.asarray([a[2] for a in arcs], dtype=np.float64).reshape(-1, 3),
        radius=np.asarray([a[3] for a in arcs], dtype=np.float64),
        junction_boundary=np.asarray(jbound, dtype=np.int64),
    )
    limits = Limits(
        length=np.asarray(seg_len),
        cap=np.asarray(seg_cap),
        boundary=np.asarray(bnd),
        acc=np.asarray(seg_acc),
        jerk=np.asarray(seg_jerk),
        dwell=np.asarray(seg_dwell),
        window_end=window_end,
    )
    return segments, limits
