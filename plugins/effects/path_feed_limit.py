"""path_feed_limit: a machine-wide path speed cap below the axes' own limits.

LinuxCNC's ``[TRAJ]MAX_LINEAR_VELOCITY`` (and a Fanuc's maximum cutting feed) caps the speed
along the path whatever the axes could do, on feed moves and rapids alike. Parameter:
``max_feed`` (mm/s), the cap; its default is the machine's own (or its fastest axis).
"""

from __future__ import annotations

import dataclasses
import math

from core import Machine, hookimpl
from core.engine.effects import Effect, Param


def _default(machine: Machine) -> float:
    if math.isfinite(machine.max_path_feed):
        return machine.max_path_feed
    return float(machine.max_feed.max())


EFFECT = Effect(
    name="path_feed_limit",
    params=(Param("max_feed", 1.0, 2000.0, _default, unit="mm/s", log=True),),
    apply=lambda setup, p: setup.replace(
        machine=dataclasses.replace(setup.machine, max_path_feed=p["max_feed"])
    ),
    doc="a path speed limit over all axes (LinuxCNC MAX_LINEAR_VELOCITY)",
    rapids=True,
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
