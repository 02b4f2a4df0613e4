"""The result of one analysis, and the headline figures the reports read.

Units: lengths mm, times s, feeds mm/s (the reports convert at their edge).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from core.engine.indicators import Evaluation
from core.engine.profile import Profile
from core.model import geometry as g
from core.model.errors import InputError
from core.model.pieces import piecewise
from core.model.tolerances import TOL
from core.model.toolpath import ToolPath
from core.view.annotations import Annotations


@dataclass(frozen=True, eq=False)
class Analysis:
    """The result of A1 + A2: the tool path, the combined evaluation, its feed profile and
    its annotations."""

    toolpath: ToolPath
    evaluation: Evaluation
    profile: Profile
    annotations: Annotations


def rapid_time(an: Analysis) -> float:
    """Rapids at the axes' max feed (s)."""
    tp = an.toolpath
    r = np.flatnonzero(~tp.is_feed)
    if not r.size:
        return 0.0
    # Rapids are lines: their direction is the chord's (the rows ToolPath.tangent_start
    # would give them, without building it for every move).
    v = an.evaluation.machine.rapid_speed(g.unit(tp.end[r] - tp.start[r]))
    return float(np.sum(tp.length[r] / v))


def at_feed_share(profile: Profile, fraction: float = 0.9) -> float:
    """Share of the feed length run at ``fraction`` of the programmed feed or more."""
    tp = profile.toolpath
    feed = np.flatnonzero(tp.is_feed)
    if not feed.size:
        return 0.0
    length = tp.length

    def fast(s: slice) -> NDArray[np.float64]:  # the feed length run at fraction F or more
        k = feed[s]
        f: NDArray[np.int64] | slice = k
        if k[-1] - k[0] + 1 == k.size:  # (a run of moves: read as a slice, not gathered)
            f = slice(int(k[0]), int(k[-1]) + 1)
        thr = fraction * tp.feed[f]
        v0, v1, vp = profile.v_entry[f], profile.v_exit[f], profile.v_peak[f]
        up = np.maximum((thr**2 - v0**2) / (2 * profile.a_up[f]), 0.0)
        down = np.maximum((thr**2 - v1**2) / (2 * profile.a_down[f]), 0.0)
        holds = profile.hold_start[f] + profile.hold_end[f]  # run at the boundary speeds
        reaches = vp >= thr * (1 - TOL.float_slack)
        return np.where(reaches, np.maximum(length[f] - holds - up - down, 0.0), 0.0)

    # in pieces: bounded temporaries, the same numbers
    return float(piecewise(feed.size, np.float64, fast).sum() / length[feed].sum())


def totals(an: Analysis) -> dict[str, float | int]:
    """Headline numbers of the summary and the JSON file."""
    tp, ev = an.toolpath, an.evaluation
    feed = tp.is_feed
    below = feed & (tp.length < ev.min_length)
    out = {
        "moves": tp.n,
        "feed_moves": int(feed.sum()),
        "arcs": int(tp.is_arc.sum()),
        "rapids": int((~feed).sum()),
        "operations": len(tp.op_names),
        "feed_length_mm": tp.feed_length,
        "rapid_length_mm": float(tp.length[~feed].sum()),
        "programmed_time_s": tp.programmed_time,
        "rapid_time_s": rapid_time(an),
        "dwell_time_s": float(tp.dwell.sum()),
        "paper_model_time_s": ev.paper_time,
        "predicted_cycle_time_s": an.profile.cycle_time,
        "share_at_90_percent": at_feed_share(an.profile, 0.9),
        "below_L_share": float(tp.length[below].sum() / tp.feed_length) if tp.feed_length else 0.0,
        "blocks_below_L": int(below.sum()),
        "rotary_moves": 0 if tp.rotary is None else int((tp.rotary != 0).any(axis=1).sum()),
        "rotary_only_moves": 0 if tp.rotary_only is None else len(tp.rotary_only),
        "rotary_only_time_s": float(an.profile.lead + an.profile.rest.sum() - tp.dwell.sum()),
    }
    bad = [k for k, v in out.items() if not math.isfinite(v)]
    if bad:
        # The readers' range checks keep this from happening; should a new path slip through,
        # the user gets a one-line error, not "nan" in the summary or the JSON.
        raise InputError(
            f"the prediction is not finite ({', '.join(bad)}): a value in the program or the "
            "machine file is beyond what ncperf can compute with",
            source=tp.source,
        )
    return out
