"""axis_dynamics: the axes' limits differ from the machine file.

Parameters: ``accel_scale``, ``jerk_scale`` (0.25-4) and ``feed_scale`` (0.05-4), multiplying
every axis's acceleration, jerk and maximum feed -- in the corner and curvature limits, the
blocks' feed limits, the rapids and the ramps alike. The feed scale reaches further down: an
axis speed limit only shows once it falls under the programmed feeds, and machine files give
axis speeds (rapids) several times the cutting feeds.
"""

from __future__ import annotations

from core import hookimpl
from core.engine.effects import Effect, Param, scale_machine


def _apply(setup, p):
    return setup.replace(
        machine=scale_machine(
            setup.machine, accel=p["accel_scale"], jerk=p["jerk_scale"], feed=p["feed_scale"]
        )
    )


EFFECT = Effect(
    name="axis_dynamics",
    params=(
        Param("accel_scale", 0.25, 4.0, 1.0, log=True),
        Param("jerk_scale", 0.25, 4.0, 1.0, log=True),
        Param("feed_scale", 0.05, 4.0, 1.0, log=True),
    ),
    apply=_apply,
    doc="per-axis acceleration, jerk and feed limits differ",
    relative=("accel_scale", "jerk_scale", "feed_scale"),
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
