"""arc_feed_limit: programmed arcs are capped by their centripetal acceleration and jerk.

On a G2/G3 arc of radius R at constant speed v the normal acceleration is v^2 / R and the
jerk v^3 / R^2 (eq. 2-3 of the paper, for the inserted arc of model 1). Per axis, as in
model 1: v <= min_k sqrt(f A_k R / n_k), cbrt(J_k R^2 / t_k), with n_k and t_k the axis's
largest share of the normal and of the tangent over the arc, and f the normal-acceleration
share (normal_acceleration_factor). No parameters.
"""

from __future__ import annotations

import numpy as np

from core import geometry as g
from core import hookimpl
from core.effects import Effect


def arc_caps(tp, machine) -> np.ndarray:
    """(n,) centripetal feed limit of every arc (mm/s), inf elsewhere."""
    out = np.full(tp.n, np.inf)
    a = np.flatnonzero(tp.is_arc)
    if a.size == 0:
        return out
    n = tp.normal[a]
    u0 = g.unit(g.radial(tp.start[a], tp.center[a], n))
    ccw = (tp.kind[a] == 3)[:, None]
    w0 = np.where(ccw, np.cross(n, u0), -np.cross(n, u0))
    share_n = g.max_share(u0, w0, tp.sweep[a][:, None])
    share_t = tp.axis_share[a]
    radius = 1.0 / np.abs(tp.curvature[a])
    acc = machine.max_acceleration * machine.normal_acceleration_factor
    with np.errstate(divide="ignore", invalid="ignore"):
        v_acc = np.where(share_n > 0, np.sqrt(acc * radius[:, None] / share_n), np.inf)
        v_jerk = np.where(
            share_t > 0, np.cbrt(machine.max_jerk * radius[:, None] ** 2 / share_t), np.inf
        )
    out[a] = np.minimum(v_acc.min(axis=1), v_jerk.min(axis=1))
    return out


arc_caps.indicator = "arc_feed_limit"
arc_caps.label = "centripetal limit"


def _apply(setup, p):
    return setup.replace(element_caps=setup.element_caps + (arc_caps,))


EFFECT = Effect(
    name="arc_feed_limit",
    params=(),
    apply=_apply,
    doc="programmed arcs capped by centripetal acceleration and jerk",
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
