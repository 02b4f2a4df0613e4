"""jerk_filter: the setpoint is smoothed over a time window (a moving average).

Many controllers smooth the interpolated setpoint to limit jerk; the speed then changes
more slowly than the planner's profile. Parameter: ``window`` (s).
"""

from __future__ import annotations

from core import hookimpl
from core.engine.effects import Effect, Param

EFFECT = Effect(
    name="jerk_filter",
    params=(Param("window", 0.0, 0.1, 0.0, unit="s"),),
    apply=lambda setup, p: setup.replace(filter_window=p["window"]),
    doc="setpoint smoothing over a time window",
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
