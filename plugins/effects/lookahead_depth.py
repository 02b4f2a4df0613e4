"""lookahead_depth: the controller plans only N blocks ahead.

It must be able to stop at the end of the blocks it sees, so on runs of short blocks it
cannot reach the speed a full look-ahead would (Siemens LookAhead, LinuxCNC's
ARC_BLEND_OPTIMIZATION_DEPTH). Parameter: ``blocks`` (1-1000; 1000 is as good as full).
"""

from __future__ import annotations

from core import hookimpl
from core.engine.effects import Effect, Param

EFFECT = Effect(
    name="lookahead_depth",
    params=(Param("blocks", 1, 1000, 1000, log=True, integer=True),),
    apply=lambda setup, p: setup.replace(lookahead=int(round(p["blocks"]))),
    doc="planning only N blocks ahead",
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
