"""Model 2: crossing a curvature discontinuity (Tapie et al., sec. 3.2, eq. 11-15).

Where the tangent is continuous but the curvature jumps, the feed V is
constant and the normal acceleration changes by V^2 |dk| within the
elementary time dt, with at most the tangential jerk (eq. 11-12):

    V^2 |dk| = J dt   ->   V = sqrt(J dt / |dk|)

Line <-> arc of radius R: |dk| = 1/R, so V = sqrt(J dt R) (eq. 13).
Arc R1 <-> arc R2 turning the same way: |dk| = |1/R1 - 1/R2|, so
V = sqrt(R1 R2 J dt / |R1 - R2|) (eq. 14).

Departure from eq. (14): at an inflection (the arcs turn opposite ways) the
normal acceleration reverses, so the jump is 1/R1 + 1/R2, not |1/R1 - 1/R2|;
eq. (14) as printed would even predict no slow-down between two equal
opposite arcs. ncperf takes dk as the jump of the curvature vector (signed
curvature times principal normal), which gives both cases and also helices
and 3-D transitions.

Tangential jerk (eq. 15 generalised to 3-D): the jerk is along the tangent t,
so axis k sees J |t_k| and J = min_k J_k / |t_k|; in the XY plane with
t = (cos a, sin a, 0) this is min(J_X / |cos a|, J_Y / |sin a|).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from core import TOL, Indicator, Machine, ToolPath, hookimpl
from core.model import geometry as g
from core.model.pieces import pieces

NAME = "curvature"
LABELS = ("jerk X", "jerk Y", "jerk Z")


def tangential_jerk(t: NDArray[np.float64], machine: Machine) -> tuple[NDArray, NDArray]:
    """Eq. (15) in 3-D: min_k J_k / |t_k| (mm/s^3) and the axis k that gives it.

    Parameters
    ----------
    t : (m, 3) float
        Unit tangents.
    """
    share = np.abs(np.asarray(t, dtype=np.float64))
    with np.errstate(divide="ignore"):
        per_axis = np.where(share > 0, machine.max_jerk / share, np.inf)
    axis = np.argmin(per_axis, axis=1)
    return per_axis[np.arange(per_axis.shape[0]), axis], axis


def transition_feed(
    jerk: NDArray[np.float64], dt: float, curvature_jump: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Eq. (11)-(14): V = sqrt(J dt / |dk|) (mm/s) for a curvature jump |dk| (1/mm)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.sqrt(jerk * dt / curvature_jump)
    return np.where(np.isnan(v), np.inf, v)


@hookimpl
def ncperf_evaluate(toolpath: ToolPath, machine: Machine) -> list[Indicator]:
    """Model 2 at every tangent junction (direction change <= TOL.tangent_angle)
    whose curvature jumps by more than TOL.curvature_jump."""
    tp = toolpath
    j = tp.junctions
    keep = (tp.turn_angle[j] <= TOL.tangent_angle) & (tp.curvature_jump[j] > TOL.curvature_jump)
    j = j[keep]
    jump = tp.curvature_jump[j]
    # Row by row, in pieces: the same numbers without (m, 3) temporaries of every junction.
    jerk = np.empty(j.size)
    axis = np.empty(j.size, dtype=np.intp)
    for b in pieces(j.size):
        jb = j[b]
        # (np.take: the rows of tp.tangent_end[jb] ..., several times faster)
        t = g.unit(np.take(tp.tangent_end, jb, axis=0) + np.take(tp.tangent_start, jb + 1, axis=0))
        jerk[b], axis[b] = tangential_jerk(t, machine)
    feed = transition_feed(jerk, machine.curvature_transition_time, jump)
    return [
        Indicator(
            name=NAME,
            at="junction",
            index=j,
            feed=feed,
            limit=axis,
            labels=LABELS,
            # Constant speed while the normal acceleration changes, over dt (eq. 11-12).
            values={
                "curvature_jump_per_mm": jump,
                "hold_mm": np.where(
                    np.isfinite(feed), 0.5 * feed * machine.curvature_transition_time, 0.0
                ),
            },
        )
    ]
