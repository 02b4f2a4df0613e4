"""block_cycle_time: the effective time per block differs from t_int.

Model 3 caps a block of length l at l / t_int; controllers use their own effective block
time (the 840D limits v <= 0.9 L / t_ipo, i.e. t_block = t_ipo / 0.9; LinuxCNC about 1.02
servo periods). Parameter: ``t_block`` (s), replacing the machine's interpolation time.
"""

from __future__ import annotations

import dataclasses

from core import hookimpl
from core.engine.effects import Effect, Param


def _apply(setup, p):
    return setup.replace(
        machine=dataclasses.replace(setup.machine, interpolation_time=p["t_block"])
    )


EFFECT = Effect(
    name="block_cycle_time",
    params=(
        Param(
            "t_block", 0.0001, 0.05, lambda m: m.interpolation_time, unit="s", log=True, points=31
        ),
    ),
    apply=_apply,
    doc="effective block time differs from t_int (model 3)",
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
