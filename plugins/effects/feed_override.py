"""feed_override: a constant override scales every programmed feed (rapids unchanged).

Parameters: ``scale`` (0.5-1.5), and ``caps`` (0-1): whether the override also scales the
limits the models put on corners, arcs and short blocks. A controller that applies the
override to the programmed feed only, under the same dynamic limits, has caps = 0 (what
Siemens documents for its feed override); one that plans the path at 100 % and scales the
planned velocities afterwards has caps = 1 (LinuxCNC 2.9: its blend and arc speeds come out
scaled by the override, measured on the shared harness).
"""

from __future__ import annotations

from core import hookimpl
from core.engine.effects import Effect, Param


def _apply(setup, p):
    scale = p["scale"]
    caps = 1.0 + p.get("caps", 0.0) * (scale - 1.0)
    return setup.replace(feed_scale=setup.feed_scale * scale, cap_scale=setup.cap_scale * caps)


SCALE = Param("scale", 0.5, 1.5, 1.0)

EFFECT = Effect(
    name="feed_override",
    params=(SCALE, Param("caps", 0.0, 1.0, 0.0)),
    apply=_apply,
    doc="constant scale on F",
    relative=("scale",),
    # one explanation, the override; caps says how this controller applies it
    size=lambda p: int(SCALE.differs(p["scale"], 1.0)),
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
