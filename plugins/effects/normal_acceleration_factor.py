"""normal_acceleration_factor: only a share of A is used for normal acceleration.

On corner blends (model 1's sqrt(A R)) and on arcs capped by their centripetal limit the
controller keeps part of the acceleration in reserve (LinuxCNC 2.9 uses (sqrt(3)/2) a on
blends). Parameter: ``factor`` (0.2-1).
"""

from __future__ import annotations

import dataclasses

from core import hookimpl
from core.effects import Effect, Param


def _apply(setup, p):
    return setup.replace(
        machine=dataclasses.replace(setup.machine, normal_acceleration_factor=p["factor"])
    )


EFFECT = Effect(
    name="normal_acceleration_factor",
    params=(Param("factor", 0.2, 1.0, 1.0),),
    apply=_apply,
    doc="only a share of A used for normal acceleration on corners and arcs",
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
