"""feed_override: a constant override scales every programmed feed (rapids unchanged).

Parameter: ``scale`` (0.5-1.5).
"""

from __future__ import annotations

from core import hookimpl
from core.effects import Effect, Param

EFFECT = Effect(
    name="feed_override",
    params=(Param("scale", 0.5, 1.5, 1.0),),
    apply=lambda setup, p: setup.replace(feed_scale=setup.feed_scale * p["scale"]),
    doc="constant scale on F",
    relative=True,
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
