"""corner_tolerance: the effective path tolerance (TIT) of corner blends differs.

Model 1's inserted radius (eq. 1) grows with the tolerance. Parameter: ``tolerance`` (mm),
replacing the machine's TIT and any tolerance the program sets (G64 P, CTOL).
"""

from __future__ import annotations

import dataclasses

from core import hookimpl
from core.engine.effects import Effect, Param


def _apply(setup, p):
    tol = p["tolerance"]
    return setup.replace(
        machine=dataclasses.replace(setup.machine, path_tolerance=tol), tolerance=tol
    )


EFFECT = Effect(
    name="corner_tolerance",
    params=(Param("tolerance", 0.0005, 1.0, lambda m: m.path_tolerance, unit="mm", log=True),),
    apply=_apply,
    doc="effective corner tolerance (TIT) differs (model 1)",
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
