"""Stops the program asks for: exact stop (G61, G60, G9, M0/M1) and dwell (G4).

Not one of the paper's models, but a junction where the program itself
stops the machine has a predicted feed of zero whatever the geometry; the
paper's 840D experiments ran in continuous-path mode, where this never binds.
"""

from __future__ import annotations

import numpy as np

from core import Indicator, PathMode, ToolPath, hookimpl

NAME = "exact_stop"
LABELS = ("exact stop", "dwell")


@hookimpl
def ncperf_evaluate(toolpath: ToolPath) -> list[Indicator]:
    """Feed 0 at junctions after a block ending in exact stop or followed by a dwell."""
    tp = toolpath
    j = tp.junctions
    stop = tp.path_mode[j] == PathMode.EXACT_STOP
    dwell = tp.dwell[j] > 0
    sel = stop | dwell
    j = j[sel]
    return [
        Indicator(
            name=NAME,
            at="junction",
            index=j,
            feed=np.zeros(j.size),
            limit=np.where(dwell[sel] & ~stop[sel], 1, 0),
            labels=LABELS,
        )
    ]
