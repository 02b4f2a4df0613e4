"""path_compression: the controller merges runs of short blocks into splines.

Compressors (Siemens COMPCAD/COMPCURV, Fanuc AI contour/nano smoothing) fit one smooth curve
through runs of short, nearly collinear blocks: inside such a run the block-time cap and the
corner limits no longer apply. A run: consecutive feed blocks shorter than ``max_length``
(mm) whose junctions turn by less than ``max_angle`` (deg); its ends keep their limits.
"""

from __future__ import annotations

import math

from core import hookimpl
from core.engine.effects import Effect, Param


def _apply(setup, p):
    return setup.replace(compression=(math.radians(p["max_angle"]), p["max_length"]))


EFFECT = Effect(
    name="path_compression",
    params=(
        Param("max_angle", 0.5, 20.0, 5.0, unit="deg", log=True),
        Param("max_length", 0.5, 10.0, 3.0, unit="mm", log=True),
    ),
    apply=_apply,
    doc="short blocks merged into splines: no block-time cap on smooth point runs",
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
