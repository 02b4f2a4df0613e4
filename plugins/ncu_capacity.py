"""Model 3: the controller's block cycle time (Tapie et al., sec. 2.2 and 3.2, eq. 16).

The controller needs at least the interpolation time t_int per block, so at
programmed feed Vp the shortest block it runs at full feed is

    L = Vp t_int                                                     (16)

and a block of length l < L is run at l / t_int at most. (Figure 4: 1 mm
points at 10 m/min with t_int = 12 ms: L = 2 mm, so 5 m/min, a 50 %
reduction; the paper measured about 55 %.)
"""

from __future__ import annotations

import numpy as np

from core import Indicator, Machine, ToolPath, hookimpl, min_block_length

NAME = "ncu_capacity"
LABELS = ("block time",)


@hookimpl
def ncperf_evaluate(toolpath: ToolPath, machine: Machine) -> list[Indicator]:
    """Cap every feed block shorter than L at length / t_int."""
    tp = toolpath
    t_int = machine.interpolation_time
    L = min_block_length(tp.feed, t_int)
    i = np.flatnonzero(tp.is_feed & (tp.length < L))
    return [
        Indicator(
            name=NAME,
            at="element",
            index=i,
            feed=tp.length[i] / t_int,
            limit=np.zeros(i.size, dtype=np.int64),
            labels=LABELS,
            values={"min_length_mm": L[i]},
        )
    ]
