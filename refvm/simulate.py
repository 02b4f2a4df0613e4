"""The reference interpreter's run: a program through the time-stepping controller, with at
most one controller effect switched on, to the trace a real controller would record.

* Limits: the paper's models, written here (:mod:`refvm.models`, :mod:`refvm.limits`).
* Motion: a jerk-limited planner stepped at the controller's cycle with full (or
  ``lookahead_depth``) look-ahead (:mod:`refvm.planner`).
* Output: ``t, x, y, z, v, line`` every cycle from the first motion to rest at the end, the
  columns of the LinuxCNC traces of ``../shared/data/linuxcnc/suite``.

::

    from refvm import simulate
    trace = simulate(toolpath, machine, effect="feed_override", params={"scale": 0.8})

``toolpath`` and ``machine`` are any objects with the columns of :class:`refvm.program.Program`
and the attributes of :class:`refvm.machine.MachineLimits` (ncperf's ``ToolPath`` and
``Machine`` have them); this package reads them and imports nothing of ncperf.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from refvm.effects import EFFECT_DOCS, EFFECTS, resolve_effect
from refvm.limits import ControllerSetup, Segments, controller_setup
from refvm.machine import MachineAttributes, MachineLimits
from refvm.planner import Motion, plan_motion
from refvm.program import Program, ToolPathColumns

__all__ = ["EFFECTS", "EFFECT_DOCS", "Trace", "simulate", "write_csv"]

#: Servo lag: the trace goes on after the setpoint stops until every axis is within this
#: distance of it (mm): 1 um, a typical in-position window.
SETTLED = 1e-3

KINDS = ("setpoint", "actual")

#: Rows per chunk when mapping positions and writing CSV (bounded memory on long traces).
CHUNK = 200_000


@dataclass(frozen=True, eq=False)
class Trace:
    """A trace of the reference interpreter, one row per controller cycle.

    Attributes
    ----------
    t : (m,) float, s
    x, y, z : (m,) float, mm
    v : (m,) float, mm/s
        Path speed (setpoint), or the speed of the output positions after a servo lag or a
        jerk filter.
    line : (m,) int
        1-based program line of the move the setpoint is running (a corner arc: its first
        half the move before the corner, its second half the move after).
    s : (m,) float, mm
        Setpoint arc length from the program start along the path the controller runs
        (corner arcs instead of corner points; rapids included).
    move : (m,) int
        Index of that move in the tool path.
    segment : (m,) int
        Segment of :attr:`ControllerSetup.segments` being run.
    kind : str
        "setpoint" or "actual".
    effect : str or None
    params : dict of str to float
    setup : ControllerSetup
        The limits the controller ran with.
    boundary_speed : (n + 1,) float, mm/s
        Setpoint speed at each move boundary (exact, between samples; at a corner the speed
        at the middle of its arc).
    violation : float, mm/s
        Largest excess over a boundary cap the discrete steps left (normally ~0).
    """

    t: NDArray[np.float64]
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    z: NDArray[np.float64]
    v: NDArray[np.float64]
    line: NDArray[np.int64]
    s: NDArray[np.float64]
    move: NDArray[np.int64]
    segment: NDArray[np.int64]
    kind: str
    effect: str | None
    params: dict[str, float]
    setup: ControllerSetup
    boundary_speed: NDArray[np.float64]
    violation: float

    @property
    def cycle_time(self) -> float:
        """Time from the first motion to rest at the end (s)."""
        return float(self.t[-1])

    @property
    def xyz(self) -> NDArray[np.float64]:
        """(m, 3) positions, mm."""
        return np.column_stack([self.x, self.y, self.z])


def positions(
    program: Program, segments: Segments, seg: NDArray[np.int64], d: NDArray[np.float64]
) -> NDArray:
    """(m, 3) points at distance ``d`` (mm) into segments ``seg``."""
    sg = segments
    out = np.empty((seg.size, 3))
    for lo in range(0, seg.size, CHUNK):  # bounded temporaries on hours-long traces
        i = seg[lo : lo + CHUNK]
        dd = d[lo : lo + CHUNK]
        p = np.empty((i.size, 3))
        b = sg.blend[i]
        part = b < 0
        if part.any():
            p[part] = program.points(sg.move[i[part]], sg.offset[i[part]] + dd[part])
        if (~part).any():
            bb = b[~part]
            phi = (sg.phi0[i[~part]] + dd[~part] / sg.radius[bb])[:, None]
            r0 = sg.start_radial[bb]
            p[~part] = sg.center[bb] + r0 * np.cos(phi) + np.cross(sg.axis[bb], r0) * np.sin(phi)
        out[lo : lo + CHUNK] = p
    return out


def _speed(p: NDArray[np.float64], dt: float) -> NDArray[np.float64]:
    """|dp/dt| by central differences (one-sided at the ends)."""
    if p.shape[0] < 2:
        return np.zeros(p.shape[0])
    return np.linalg.norm(np.gradient(p, dt, axis=0), axis=1)


def servo_lag(p: NDArray[np.float64], dt: float, tau: float) -> NDArray[np.float64]:
    """First-order lag x_act' = (x_set - x_act) / tau of every axis, exact for a setpoint
    linear over each cycle, continued (setpoint held) until within :data:`SETTLED` mm.

    Parameters
    ----------
    p : (m, 3) float, mm
        Setpoint, one row per cycle, starting at rest.
    """
    p = np.asarray(p, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"p must have shape (m, 3), got {p.shape}")
    if tau <= 0:
        return p.copy()
    beta = math.exp(-dt / tau)
    c = tau * (1.0 - beta) / dt
    # y[k+1] = beta y[k] + (1 - c) x[k+1] + (c - beta) x[k]   (linear input over the cycle)
    m = p.shape[0]
    tail = int(math.ceil(tau / dt * math.log(max(np.ptp(p, axis=0).max(), 1.0) / SETTLED))) + 1
    x = np.vstack([p, np.repeat(p[-1:], tail, axis=0)])
    u = (1.0 - c) * x[1:] + (c - beta) * x[:-1]
    y = np.empty_like(x)
    y[0] = x[0]
    yk = x[0].tolist()
    uu = u.tolist()
    for k in range(x.shape[0] - 1):
        row = uu[k]
        yk = [beta * yk[0] + row[0], beta * yk[1] + row[1], beta * yk[2] + row[2]]
        y[k + 1] = yk
    settled = np.flatnonzero(np.abs(y - x).max(axis=1) > SETTLED)
    last = max(int(settled[-1]) + 1 if settled.size else 0, m - 1)
    return y[: last + 1]


def moving_average(p: NDArray[np.float64], samples: int) -> NDArray[np.float64]:
    """Causal moving average over ``samples`` rows (the first row held before the start),
    continued with the last row held until the output reaches it."""
    p = np.asarray(p, dtype=np.float64)
    if samples <= 1:
        return p.copy()
    x = np.vstack([np.repeat(p[:1], samples - 1, axis=0), p, np.repeat(p[-1:], samples - 1, 0)])
    c = np.cumsum(x, axis=0)
    c = np.vstack([np.zeros((1, 3)), c])
    out = (c[samples:] - c[:-samples]) / samples
    return out


def simulate(
    program: Program | ToolPathColumns,
    machine: MachineLimits | MachineAttributes,
    effect: str | None = None,
    params: Mapping[str, float] | None = None,
    *,
    dt: float = 0.001,
    kind: str | None = None,
) -> Trace:
    """Run a program on the reference controller with at most one effect.

    Parameters
    ----------
    program : Program, or a parsed tool path with its columns
    machine : MachineLimits, or a machine with its attributes
    effect : str or None
        An :data:`EFFECTS` name.
    params : mapping of str to float, optional
        The effect's parameters; missing ones take their defaults.
    dt : float, s
        Controller cycle.
    kind : {"setpoint", "actual"} or None
        What the positions are. None: "actual" with ``servo_lag``, else "setpoint".
        "actual" without ``servo_lag`` is the setpoint (a perfect servo).

    Raises
    ------
    ValueError
        Unknown effect or parameter, a value out of bounds, a bad dt or kind, an empty
        program, or ``servo_lag`` with kind "setpoint".
    """
    if not (isinstance(dt, int | float) and math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
    if kind is not None and kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    if effect == "servo_lag":
        if kind == "setpoint":
            raise ValueError("servo_lag records actual positions: kind 'setpoint' contradicts it")
        kind = "actual"
    kind = kind or "setpoint"
    m = MachineLimits.read(machine)
    p = resolve_effect(effect, params, m)
    prog = program if isinstance(program, Program) else Program.read(program)
    if prog.n == 0:
        raise ValueError(f"{prog.source}: no moves to run")
    setup = controller_setup(prog, m, effect, p)
    motion: Motion = plan_motion(setup.limits, dt)
    prog = setup.program
    sg = setup.segments
    seg = motion.move
    seg_start = np.concatenate([[0.0], np.cumsum(setup.limits.length)[:-1]])
    pts = positions(prog, sg, seg, motion.s - seg_start[seg])
    v = motion.v
    s = motion.s
    if effect == "jerk_filter" and round(p["window"] / dt) > 1:
        pts = moving_average(pts, int(round(p["window"] / dt)))
    elif effect == "servo_lag" and p["tau"] > 0:
        pts = servo_lag(pts, dt, p["tau"])
    extra = pts.shape[0] - motion.s.size
    if extra:
        seg = np.concatenate([seg, np.repeat(seg[-1:], extra)])
        s = np.concatenate([s, np.repeat(s[-1:], extra)])
    if effect in ("jerk_filter", "servo_lag"):
        v = _speed(pts, dt)
    move = sg.move[seg]
    t = np.arange(pts.shape[0], dtype=np.float64) * dt
    return Trace(
        t=t,
        x=pts[:, 0],
        y=pts[:, 1],
        z=pts[:, 2],
        v=v,
        line=np.asarray(prog.line, dtype=np.int64)[move],
        s=s,
        move=move,
        segment=seg,
        kind=kind,
        effect=effect,
        params=p,
        setup=setup,
        boundary_speed=motion.boundary_speed[sg.junction_boundary],
        violation=motion.violation,
    )


def write_csv(trace: Trace, path: str | os.PathLike) -> None:
    """Write ``t,x,y,z,v,line`` (s, mm, mm, mm, mm/s, line) as the LinuxCNC traces do;
    atomically (a failed write leaves no file)."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    try:
        with open(tmp, "w", encoding="ascii") as fh:
            fh.write("t,x,y,z,v,line\n")
            for lo in range(0, trace.t.size, CHUNK):
                sl = slice(lo, lo + CHUNK)
                cols = [trace.t[sl], trace.x[sl], trace.y[sl], trace.z[sl], trace.v[sl]]
                rows = zip(*(c.tolist() for c in cols), trace.line[sl].tolist(), strict=True)
                fh.write(
                    "".join(
                        f"{a:.6f},{b:.6f},{c:.6f},{d:.6f},{e:.6f},{n}\n"
                        for a, b, c, d, e, n in rows
                    )
                )
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
