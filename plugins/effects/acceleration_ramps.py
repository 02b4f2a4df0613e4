"""acceleration_ramps: the machine brakes into every slow point and accelerates out of it.

The paper predicts the feed at discontinuities and on blocks; between them it assumes the
programmed feed. A real interpolator ramps between them with its acceleration and jerk, with
look-ahead: this effect replaces the point model by the feed profile (:mod:`core.engine.profile`).
No parameters: the machine's own limits shape the ramps.
"""

from __future__ import annotations

from core import hookimpl
from core.engine.effects import Effect

EFFECT = Effect(
    name="acceleration_ramps",
    params=(),
    apply=lambda setup, p: setup.replace(ramps=True),
    doc="braking and accelerating between slow points (the feed profile)",
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
