"""normal_acceleration_factor: only a share of A is used for normal acceleration.

On corner blends (model 1's sqrt(A R)) and on programmed arcs the controller keeps part of the
acceleration in reserve: corners run at sqrt(f A R) and arcs are capped at their centripetal
limit sqrt(f A R) (:func:`core.engine.effects.arc_caps`). LinuxCNC 2.9 uses (sqrt(3)/2) a on blends
and arcs. Parameter: ``factor`` (0.2-1).
"""

from __future__ import annotations

import dataclasses
import math

from core import Machine, ToolPath, hookimpl
from core.engine.effects import Effect, ElementCap, Param, Setup, arc_caps


def _limit(tp: ToolPath, machine: Machine):
    return arc_caps(tp, machine, jerk=False)


_caps = ElementCap(_limit, indicator="normal_acceleration_factor", label="centripetal limit")


def _apply(setup: Setup, p):
    machine = dataclasses.replace(setup.machine, normal_acceleration_factor=p["factor"])
    return setup.replace(machine=machine, element_caps=setup.element_caps + (_caps,))


EFFECT = Effect(
    name="normal_acceleration_factor",
    params=(Param("factor", 0.2, 1.0, 1.0),),
    apply=_apply,
    doc="only a share of A used for normal acceleration on corners and arcs",
    documented=(
        (
            "factor",
            math.sqrt(3.0) / 2.0,
            "LinuxCNC 2.9 blendmath.h: BLEND_ACC_RATIO_NORMAL = sqrt(1 - 0.5^2)",
        ),
    ),
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
