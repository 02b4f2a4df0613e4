"""arc_feed_limit: programmed arcs are capped by their centripetal acceleration and jerk.

On a G2/G3 arc of radius R at constant speed v the normal acceleration is v^2 / R and the
jerk v^3 / R^2 (eq. 2-3 of the paper, for the inserted arc of model 1); the paper's models
leave programmed arcs at F. Per axis, as in model 1 (:func:`core.engine.effects.arc_caps`). No
parameters (a normal_acceleration_factor scales the acceleration part).
"""

from __future__ import annotations

from core import Machine, ToolPath, hookimpl
from core.engine.effects import Effect, ElementCap, Setup, arc_caps


def _limit(tp: ToolPath, machine: Machine):
    return arc_caps(tp, machine, jerk=True)


_caps = ElementCap(_limit, indicator="arc_feed_limit", label="centripetal limit")


def _apply(setup: Setup, p):
    return setup.replace(element_caps=setup.element_caps + (_caps,))


EFFECT = Effect(
    name="arc_feed_limit",
    params=(),
    apply=_apply,
    doc="programmed arcs capped by centripetal acceleration and jerk",
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
