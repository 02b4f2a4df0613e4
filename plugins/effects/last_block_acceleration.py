"""last_block_acceleration: the program's last block runs with a share of the acceleration.

Some planners give the last block of a program a conservative ("parabolic") end condition:
LinuxCNC 2.9 halves the acceleration of the final segment (the shared harness measures
1000 mm/s^2, accelerating and braking, on the last move of a 2000 mm/s^2 machine, while
other stops brake at the full rate). Parameter: ``factor`` (0.2-1). Not in the issue's list;
added because LinuxCNC does it.
"""

from __future__ import annotations

from core import hookimpl
from core.engine.effects import Effect, Param

EFFECT = Effect(
    name="last_block_acceleration",
    params=(Param("factor", 0.2, 1.0, 1.0),),
    apply=lambda setup, p: setup.replace(end_factor=p["factor"]),
    doc="the program's last block with a share of A",
    documented=(
        ("factor", 0.5, "LinuxCNC 2.9 on the shared harness: 1000 of 2000 mm/s^2 on the last move"),
    ),
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
