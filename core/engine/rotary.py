"""Rotary axes A, B, C in the feed profile (no machine kinematics).

ncperf has no kinematic model of a machine's rotary axes yet: X, Y, Z of the program are
taken as the tool path the paper's models read (the tool tip, as with TCPM/TRAORI), and
the rotary axes are limits on top:

* **with X, Y, Z** (a simultaneous move): each rotary axis turns in step with the path,
  |dA| degrees over the move's L mm, so at path speed v it turns at v |dA| / L deg/s and
  accelerates at a |dA| / L. Its speed limit caps the move's feed (the ``rotary`` element
  indicator, :mod:`plugins.rotary`); its acceleration and jerk limits cap the move's
  tangential acceleration and jerk here;
* **alone** (X, Y, Z stand still): the machine turns from rest to rest between two path
  moves, at the programmed rate (deg/min) or, for a rapid, the axes' limits, with the
  rotary axes' acceleration and jerk: a pause in the path, like a dwell.

A rotary axis the machine file does not describe (``[axes.A]``) sets no limit: its motion
takes no time, and the analysis says so.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from core.model.machine import ROTARY_AXES, Machine
from core.model.toolpath import ToolPath


def _limits(machine: Machine) -> tuple[NDArray, NDArray, NDArray]:
    """(3,) speed, acceleration and jerk limits of A, B, C (deg/s...; inf where absent)."""
    v = np.full(3, np.inf)
    a = np.full(3, np.inf)
    j = np.full(3, np.inf)
    for k, ax in enumerate(ROTARY_AXES):
        r = machine.rotary.get(ax)
        if r is not None:
            v[k], a[k], j[k] = r.max_feed, r.max_acceleration, r.max_jerk
    return v, a, j


def missing_axes(tp: ToolPath, machine: Machine) -> list[str]:
    """Rotary axes the path turns that the machine file gives no limits for."""
    turned = np.zeros(3, dtype=bool)
    if tp.rotary is not None:
        turned |= (tp.rotary != 0).any(axis=0)
    if tp.rotary_only is not None and len(tp.rotary_only):
        turned |= (tp.rotary_only.travel != 0).any(axis=0)
    return [ax for k, ax in enumerate(ROTARY_AXES) if turned[k] and ax not in machine.rotary]


def path_caps(tp: ToolPath, machine: Machine) -> tuple[NDArray, NDArray, NDArray]:
    """(n,) caps on the path speed (mm/s), tangential acceleration (mm/s^2) and jerk
    (mm/s^3) of each move from its rotary axes: limit_k L / |dA_k| (inf without rotation)."""
    n = tp.n
    if tp.rotary is None:
        inf = np.full(n, np.inf)
        return inf, inf.copy(), inf.copy()
    v, a, j = _limits(machine)
    turn = np.abs(tp.rotary)
    length = tp.length[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        per_mm = np.where(turn > 0, turn / length, 0.0)  # deg per mm of path
        caps = [
            np.where(per_mm > 0, lim[None, :] / per_mm, np.inf).min(axis=1) for lim in (v, a, j)
        ]
    return caps[0], caps[1], caps[2]


def rest_to_rest_time(dist: NDArray, v: NDArray, a: NDArray, j: NDArray) -> NDArray:
    """Time (s) of a move of ``dist`` from rest to rest at most at speed ``v``,
    acceleration ``a`` and jerk ``j`` (S-curve; a trapezoid where j is inf).

    Speeding up to u and braking from it takes T(u) = u / a + a / j (u >= a^2 / j) or
    2 sqrt(u / j) (below) each way and covers u T(u) in all; when ``dist`` allows the top
    speed v, the time is dist / v + T(v), else the peak u solves u T(u) = dist.
    """
    d = np.asarray(dist, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    a = np.asarray(a, dtype=np.float64)
    j = np.asarray(j, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        a_over_j = np.where(np.isfinite(j), a / j, 0.0)
        knee = a * a_over_j  # speed at which a is first reached

        def ramp(u: NDArray) -> NDArray:
            return np.where(u >= knee, u / a + a_over_j, 2.0 * np.sqrt(u / j))

        full = d >= v * ramp(v)
        t_full = d / v + ramp(v)
        # the peak below v: first with a reached (u^2 / a + u a / j = d) ...
        u_long = 0.5 * a * (np.sqrt(a_over_j**2 + 4.0 * d / a) - a_over_j)
        # ... else without (2 u^(3/2) / sqrt(j) = d)
        u_short = np.cbrt((0.5 * d) ** 2 * j)
        u = np.where(u_long >= knee, u_long, u_short)
        t_part = 2.0 * ramp(u)
        t = np.where(full, t_full, t_part)
    return np.where(d > 0, np.nan_to_num(t, nan=0.0, posinf=0.0), 0.0)


def pauses(tp: ToolPath, machine: Machine) -> tuple[NDArray[np.float64], float]:
    """(n,) time of the rotary-only moves after each move, and the time of those before the
    first move (s)."""
    out = np.zeros(tp.n)
    rm = tp.rotary_only
    if rm is None or len(rm) == 0:
        return out, 0.0
    v, a, j = _limits(machine)
    dist = np.linalg.norm(rm.travel, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.abs(rm.travel) / dist[:, None]
        share = np.where(u > 0, 1.0 / u, np.inf)
        v_lim = (v[None, :] * share).min(axis=1)
        a_lim = (a[None, :] * share).min(axis=1)
        j_lim = (j[None, :] * share).min(axis=1)
    speed = np.where(np.isnan(rm.feed), v_lim, np.minimum(rm.feed, v_lim))
    t = rest_to_rest_time(dist, speed, a_lim, j_lim)
    t = np.where(np.isfinite(speed), t, 0.0)
    before = rm.after < 0
    np.add.at(out, rm.after[~before], t[~before])
    return out, float(t[before].sum())
