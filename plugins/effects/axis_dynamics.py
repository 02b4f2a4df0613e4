"""axis_dynamics: the axes' limits differ from the machine file, each axis its own.

Parameters: ``accel_scale``, ``jerk_scale`` (0.25-4) and ``feed_scale`` (0.05-4), multiplying
every axis's acceleration, jerk and maximum feed -- in the corner and curvature limits, the
blocks' feed limits, the rapids and the ramps alike -- and, on top of them, one factor per
axis for the acceleration and the feed (``accel_x``... ``feed_z``, 0.2-5): an X axis
slower than Y and Z is ``accel_x`` alone; the uniform scale is the special case where the
per-axis factors stay 1. The feed scale reaches further down: an axis speed limit only shows
once it falls under the programmed feeds, and machine files give axis speeds (rapids)
several times the cutting feeds. Fitted in two stages: the uniform scales on a grid, then
each axis's factors one at a time.
"""

from __future__ import annotations

import numpy as np

from core import hookimpl
from core.engine.effects import Effect, Param, scale_machine

AXES = "xyz"
UNIFORM = ("accel_scale", "jerk_scale", "feed_scale")
PER_AXIS = tuple(f"{kind}_{a}" for kind in ("accel", "feed") for a in AXES)


def _apply(setup, p):
    accel = p["accel_scale"] * np.array([p.get(f"accel_{a}", 1.0) for a in AXES])
    feed = p["feed_scale"] * np.array([p.get(f"feed_{a}", 1.0) for a in AXES])
    return setup.replace(
        machine=scale_machine(setup.machine, accel=accel, jerk=p["jerk_scale"], feed=feed)
    )


EFFECT = Effect(
    name="axis_dynamics",
    params=(
        Param("accel_scale", 0.25, 4.0, 1.0, log=True),
        Param("jerk_scale", 0.25, 4.0, 1.0, log=True),
        Param("feed_scale", 0.05, 4.0, 1.0, log=True),
        *(Param(name, 0.2, 5.0, 1.0, log=True) for name in PER_AXIS),
    ),
    apply=_apply,
    doc="per-axis acceleration, jerk and feed limits differ",
    relative=UNIFORM + PER_AXIS,
    stages=(UNIFORM, PER_AXIS),
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
