"""A reference "virtual machine": a time-stepping interpolator with one controller effect.

ncperf's ``diagnose`` compares a measured feed trace with ncperf's prediction and names the
unmodelled effect behind the gap. To check it on traces whose effect is withheld, this
controller produces traces with exactly one effect switched on at a given strength
(:data:`~vm.effects.EFFECTS`).

* Limits: the paper's models as ncperf's plugins evaluate them (:mod:`vm.limits`): junction
  feeds, block caps, rapids at the axes' max feed along their direction. Corners are run as
  model 1 says (sec. 2.1, Fig. 2b): on the arc of radius R (eq. 1) tangent to both blocks,
  at most at the corner feed over its whole length; curvature jumps hold their feed over
  the transition time dt (model 2). The path is cut into segments accordingly.
* Motion: an independent jerk-limited planner stepped at the controller's cycle with full
  (or ``lookahead_depth``) look-ahead (:mod:`vm.planner`); ``core.engine.profile`` is not used.
* Output: ``t, x, y, z, v, line`` every cycle from the first motion to rest at the end, the
  columns of the LinuxCNC traces of ``../shared/data/linuxcnc/suite``.

As a module (``benchmarks/`` on sys.path)::

    from vm.virtual_machine import simulate, EFFECTS
    trace = simulate("part.ngc", "linuxcnc-sim", effect="feed_override", params={"scale": 0.8})

As a script::

    python benchmarks/vm/virtual_machine.py PROGRAM OUT.csv [--machine PRESET|FILE]
        [--effect NAME --param k=v ...] [--dt 0.001] [--kind setpoint|actual]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

if __name__ == "__main__" and not __package__:
    # Run as a script: make this folder's package (`vm`) and the repository's `core`
    # importable, then import relatively as a module would (PEP 366).
    _here = Path(__file__).resolve()
    sys.path[:0] = [str(_here.parents[1]), str(_here.parents[2])]
    __package__ = "vm"  # noqa: A001
    import vm  # noqa: F401

import numpy as np
from numpy.typing import NDArray

from core import Machine, Ncperf, ToolPath, resolve_machine
from core.engine.profile import boundary_caps as _unused  # noqa: F401
from core.model import geometry as g

from .effects import EFFECT_DOCS, EFFECTS, resolve_effect
from .limits import ControllerSetup, Segments, controller_setup
from .planner import Motion, plan_motion

__all__ = ["EFFECTS", "EFFECT_DOCS", "Trace", "simulate", "write_csv", "main"]

#: Servo lag: the trace goes on after the setpoint stops until every axis is within this
#: distance of it (mm): 1 um, a typical in-position window.
SETTLED = 1e-3

KINDS = ("setpoint", "actual")

#: Rows per chunk when mapping positions and writing CSV (bounded memory on long traces).
CHUNK = 200_000


@dataclass(frozen=True, eq=False)
class Trace:
    """A trace of the virtual machine, one row per controller cycle.

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
    toolpath: ToolPath, segments: Segments, seg: NDArray[np.int64], d: NDArray[np.float64]
) -> NDArray:
    """(m, 3) points at distance ``d`` (mm) into segments ``seg``."""
    tp = toolpath
    sg = segments
    out = np.empty((seg.size, 3))
    for lo in range(0, seg.size, CHUNK):  # bounded temporaries on hours-long traces
        i = seg[lo : lo + CHUNK]
        dd = d[lo : lo + CHUNK]
        p = np.empty((i.size, 3))
        b = sg.blend[i]
        part = b < 0
        if part.any():
            # On the program's own moves: the program's geometry (ncperf's, not its planner).
            k = sg.move[i[part]]
            p[part] = tp.points_along(k, np.clip(sg.offset[i[part]] + dd[part], 0.0, tp.length[k]))
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
    return g.norm(np.gradient(p, dt, axis=0))


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
    source: str | os.PathLike | ToolPath,
    machine: Machine | str | None = None,
    effect: str | None = None,
    params: Mapping[str, float] | None = None,
    *,
    dt: float = 0.001,
    kind: str | None = None,
    ncperf: Ncperf | None = None,
) -> Trace:
    """Run a program on the virtual machine with at most one effect.

    Parameters
    ----------
    source : path or ToolPath
        A program any ncperf adapter reads, or a tool path.
    machine : Machine, preset name, TOML path or None
        None: ncperf's default preset.
    effect : str or None
        An :data:`EFFECTS` name.
    params : mapping of str to float, optional
        The effect's parameters; missing ones take their defaults.
    dt : float, s
        Controller cycle.
    kind : {"setpoint", "actual"} or None
        What the positions are. None: "actual" with ``servo_lag``, else "setpoint".
        "actual" without ``servo_lag`` is the setpoint (a perfect servo).
    ncperf : Ncperf, optional
        The facade whose adapters and plugins are used (a fresh default one otherwise).

    Raises
    ------
    ValueError
        Unknown effect or parameter, a value out of bounds, a bad dt or kind, or
        ``servo_lag`` with kind "setpoint".
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
    m = machine if isinstance(machine, Machine) else resolve_machine(machine)
    p = resolve_effect(effect, params, m)
    nc = ncperf if ncperf is not None else Ncperf()
    tp = source if isinstance(source, ToolPath) else nc.extract(os.fspath(source))
    if tp.n == 0:
        raise ValueError(f"{tp.source}: no moves to run")
    setup = controller_setup(tp, m, effect, p, nc)
    motion: Motion = plan_motion(setup.limits, dt)
    tp = setup.toolpath
    sg = setup.segments
    seg = motion.move
    seg_start = np.concatenate([[0.0], np.cumsum(setup.limits.length)[:-1]])
    pts = positions(tp, sg, seg, motion.s - seg_start[seg])
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
    t = np.arange(pts.shape[0]) * dt
    return Trace(
        t=t,
        x=pts[:, 0],
        y=pts[:, 1],
        z=pts[:, 2],
        v=v,
        line=tp.line[move],
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


def _param(text: str) -> tuple[str, float]:
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"--param takes k=v, got {text!r}")
    try:
        return key.strip(), float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--param {key}: not a number: {value!r}") from None


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (see the module docstring); returns the exit status."""
    ap = argparse.ArgumentParser(
        prog="virtual_machine.py",
        description="Reference time-stepping controller with one effect; writes t,x,y,z,v,line.",
        epilog="effects: "
        + "; ".join(f"{k}({', '.join(v) or 'no parameters'})" for k, v in EFFECTS.items()),
    )
    ap.add_argument("program")
    ap.add_argument("out", help="CSV trace to write")
    ap.add_argument("--machine", default=None, help="preset name or TOML file")
    ap.add_argument("--effect", choices=sorted(EFFECTS), default=None)
    ap.add_argument("--param", type=_param, action="append", default=[], metavar="K=V")
    ap.add_argument("--dt", type=float, default=0.001, help="controller cycle, s")
    ap.add_argument("--kind", choices=KINDS, default=None)
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    try:
        trace = simulate(
            args.program,
            args.machine,
            args.effect,
            dict(args.param),
            dt=args.dt,
            kind=args.kind,
        )
    except ValueError as exc:
        print(f"virtual_machine.py: {exc}", file=sys.stderr)
        return 2
    wall = time.perf_counter() - t0
    write_csv(trace, args.out)
    print(
        f"{args.program}: {trace.t.size} cycles, cycle time {trace.cycle_time:.3f} s, "
        f"{trace.kind} trace, effect {trace.effect or 'none'} {trace.params or ''}, "
        f"{wall:.2f} s wall -> {args.out}"
    )
    return 0


if __name__ == "__main__":
    from core.model.errors import NcperfError

    try:
        sys.exit(main())
    except NcperfError as exc:
        print(exc, file=sys.stderr)
        sys.exit(1)
