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
from numpy.typing import NDArray

from core import Indicator, Machine, ToolPath, hookimpl

NAME = "feed_limit"
LABELS = ("feed X", "feed Y", "feed Z", "path feed")


@hookimpl
def ncperf_evaluate(toolpath: ToolPath, machine: Machine) -> list[Indicator]:
    """Cap feed blocks programmed above min_k Vmax_k / (share of axis k)."""
    tp = toolpath
    i = np.flatnonzero(tp.is_feed)
    share = tp.axis_share
    vmax = np.broadcast_to(np.asarray(machine.max_feed, dtype=np.float64), share.shape[1:])
    cap, axis = lowest_axis(share, i, vmax)
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


def lowest_axis(share_all: NDArray, i: NDArray, vmax: NDArray) -> tuple[NDArray, NDArray]:
    """min_k Vmax_k / share_k over the moves ``i`` (inf where an axis has no share) and the
    first axis k that gives it (any per-axis limit: the LinuxCNC corner model takes the
    accelerations' too): axis by axis, without (m, 3) temporaries (the same values
    as a row-wise argmin, which with no NaN is the first lowest)."""
    if np.isnan(vmax).any():  # argmin's NaN rule: the row-wise way
        share = share_all[i]
        with np.errstate(divide="ignore"):
            per_axis = np.where(share > 0, vmax / share, np.inf)
        axis = np.argmin(per_axis, axis=1)
        return per_axis[np.arange(i.size), axis], axis
    cap = np.full(i.size, np.inf)
    axis = np.zeros(i.size, dtype=np.intp)
    with np.errstate(divide="ignore", over="ignore"):  # a share near 0: inf, no limit
        for k in range(share_all.shape[1]):
            share = share_all[:, k][i]
            per = np.where(share > 0, vmax[k] / share, np.inf)
            lower = per < cap
            if k == 0:
                cap = per
            else:
                np.copyto(cap, per, where=lower)
                axis[lower] = k
    return cap, axis
