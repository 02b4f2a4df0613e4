"""servo_lag: measured actual positions lag the setpoint.

A position loop follows its setpoint as a first-order system of time constant tau, so a
trace of actual positions shows the predicted speed passed through that lag. Parameter:
``tau`` (s).
"""

from __future__ import annotations

from core import hookimpl
from core.engine.effects import Effect, Param

EFFECT = Effect(
    name="servo_lag",
    params=(Param("tau", 0.0, 0.2, 0.0, unit="s"),),
    apply=lambda setup, p: setup.replace(servo_tau=p["tau"]),
    doc="actual positions lag the setpoint (first order, tau)",
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
