"""arc_acceleration: programmed arcs get only a share of the tangential acceleration.

The normal acceleration an arc needs is taken from the same budget, so some planners scale
the tangential acceleration on G2/G3 (LinuxCNC 2.9's source: by 0.5). Parameter: ``factor``
(0.2-1). Not in the issue's list; added because LinuxCNC does it.
"""

from __future__ import annotations

from core import hookimpl
from core.engine.effects import Effect, Param

EFFECT = Effect(
    name="arc_acceleration",
    params=(Param("factor", 0.2, 1.0, 1.0),),
    apply=lambda setup, p: setup.replace(arc_factor=p["factor"]),
    doc="tangential acceleration on arcs is a share of A",
    documented=(("factor", 0.5, "LinuxCNC 2.9 blendmath.h: BLEND_ACC_RATIO_TANGENTIAL = 0.5"),),
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
