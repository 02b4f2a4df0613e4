"""Rotary axes on simultaneous moves: no block faster than its rotary axes can turn.

A move that turns rotary axis k by |dA_k| degrees over L mm of path turns it at
v |dA_k| / L deg/s at path speed v, so v <= min_k Vmax_k L / |dA_k| (the rotary axes'
max_feed in the machine file, ``[axes.A]``...). Their acceleration and jerk limits cap the
move's tangential acceleration in the feed profile (:mod:`core.engine.rotary`). Rotary
axes the machine file does not describe set no limit.
"""

from __future__ import annotations

import numpy as np

from core import Indicator, Machine, ToolPath, hookimpl
from core.engine.rotary import path_caps

NAME = "rotary"
LABELS = ("feed A", "feed B", "feed C")


@hookimpl
def ncperf_evaluate(toolpath: ToolPath, machine: Machine) -> list[Indicator]:
    """Cap feed moves whose rotary axes would turn faster than their max_feed."""
    tp = toolpath
    if tp.rotary is None or not machine.rotary:
        return []
    cap, _, _ = path_caps(tp, machine)
    i = np.flatnonzero(tp.is_feed & (cap < tp.feed))
    if i.size == 0:
        return []
    # the axis that binds: the largest share of its own limit
    limit = np.array([machine.rotary[ax].max_feed if ax in machine.rotary else np.inf
                      for ax in "ABC"])  # fmt: skip
    with np.errstate(divide="ignore", invalid="ignore"):
        load = np.abs(tp.rotary[i]) / limit[None, :]
    axis = np.argmax(np.nan_to_num(load), axis=1)
    return [Indicator(name=NAME, at="element", index=i, feed=cap[i], limit=axis, labels=LABELS)]
