"""The axes' feed limits on every block: no block runs faster than its axes allow.

Not one of the paper's three models, but eq. (6) already bounds the feed by Vmax at
discontinuities, and a controller clamps any block programmed above what its axes can do:
axis k moves at V |t_k|, so V <= min_k Vmax_k / max |t_k| over the block. Lines have one
direction; for arcs the planar part of the tangent turns with the sweep (its largest share
per axis as in model 1) and a helix adds its constant rise, bounded by adding its share. A
machine's path speed limit (all axes together, ``max_path_feed``) caps every block too.
"""

from __future__ import annotations

import numpy as np

from core import Indicator, Machine, ToolPath, hookimpl

NAME = "feed_limit"
LABELS = ("feed X", "feed Y", "feed Z", "path feed")


@hookimpl
def ncperf_evaluate(toolpath: ToolPath, machine: Machine) -> list[Indicator]:
    """Cap feed blocks programmed above min_k Vmax_k / (share of axis k)."""
    tp = toolpath
    i = np.flatnonzero(tp.is_feed)
    share = tp.axis_share[i]
    with np.errstate(divide="ignore"):
        per_axis = np.where(share > 0, machine.max_feed / share, np.inf)
    axis = np.argmin(per_axis, axis=1)
    cap = per_axis[np.arange(i.size), axis]
    # the path speed limit over all axes (LinuxCNC's [TRAJ]MAX_LINEAR_VELOCITY)
    path = cap > machine.max_path_feed
    cap = np.where(path, machine.max_path_feed, cap)
    axis = np.where(path, 3, axis)
    over = cap < tp.feed[i]
    return [
        Indicator(
            name=NAME,
            at="element",
            index=i[over],
            feed=cap[over],
            limit=axis[over],
            labels=LABELS,
        )
    ]
