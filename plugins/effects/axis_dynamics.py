"""axis_dynamics: the axes' acceleration and jerk differ from the machine file.

Parameters: ``accel_scale`` and ``jerk_scale`` (0.25-4), multiplying every axis's
acceleration and jerk -- in the corner and curvature limits and in the ramps alike.
"""

from __future__ import annotations

from core import hookimpl
from core.effects import Effect, Param, scale_machine


def _apply(setup, p):
    return setup.replace(
        machine=scale_machine(setup.machine, accel=p["accel_scale"], jerk=p["jerk_scale"])
    )


EFFECT = Effect(
    name="axis_dynamics",
    params=(
        Param("accel_scale", 0.25, 4.0, 1.0, log=True),
        Param("jerk_scale", 0.25, 4.0, 1.0, log=True),
    ),
    apply=_apply,
    doc="per-axis acceleration and jerk differ",
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
