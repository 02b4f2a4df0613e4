"""The physical range of what a tool path may hold, checked once for every adapter.

A reader turns text into numbers; whatever it reads, the numbers that reach the models must
be finite and of a size a machine tool can have, or squares and sums later overflow to
``inf`` and ``nan`` (a feed of 1e306 mm/min squared, a coordinate of 1e300 mm). The ranges
are generous -- a kilometre of travel, a hundred metres a second -- and exist to stop
nonsense, not to judge machines: :func:`check_toolpath` runs after every extraction and names
the source line of the first value outside them.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from core.model.errors import InputError
from core.model.toolpath import ToolPath

#: Largest coordinate or arc centre, mm (1 km: no machine tool's travel comes near).
MAX_COORD = 1e6
#: Programmed feed range, mm/s: 1e-6 mm/min to 6e9 mm/min (LinuxCNC's own stress test
#: LHchips4.ngc programs F9,991,300 mm/min; it is capped by the machine, not refused).
FEED_RANGE = (1.0 / 6e7, 1e8)
#: Longest dwell, s (a day). G4 P100000 is 28 hours of nothing: a typing error.
MAX_DWELL = 86_400.0
#: Largest sweep of one arc or helix, rad: 10,000 turns. A helix of a million turns on one
#: block is a typing error, and the profile of it would need gigabytes.
MAX_SWEEP = 2 * np.pi * 1e4


def _first_bad(bad: ArrayLike) -> int | None:
    idx = np.flatnonzero(bad)
    return int(idx[0]) if idx.size else None


def _all_in_range(tp: ToolPath) -> bool:
    """Whether no move has a value out of range: the checks of :func:`check_toolpath` over
    whole columns, without the per-move masks that find the first bad move (a million
    moves: 0.1 s less). A comparison with NaN is false, so NaN fails as it does there."""
    arc = tp.is_arc
    feed = tp.feed[tp.is_feed]
    return bool(
        (np.abs(tp.start) <= MAX_COORD).all()
        and (np.abs(tp.end) <= MAX_COORD).all()
        and (np.abs(tp.center[arc]) <= MAX_COORD).all()
        and ((tp.sweep[arc] > 0) & (tp.sweep[arc] <= MAX_SWEEP)).all()
        and ((feed >= FEED_RANGE[0]) & (feed <= FEED_RANGE[1])).all()
        and ((tp.dwell >= 0) & (tp.dwell <= MAX_DWELL)).all()
        and (np.isnan(tp.tolerance) | ((tp.tolerance >= 0) & (tp.tolerance <= MAX_COORD))).all()
    )


def check_toolpath(tp: ToolPath) -> None:
    """Raise :class:`InputError` at the line of the first move with a value out of range."""
    if tp.n == 0:
        return
    if _all_in_range(tp):
        return
    arc = tp.is_arc
    feed_move = tp.is_feed
    checks = (
        (
            ~(np.isfinite(tp.start).all(axis=1) & np.isfinite(tp.end).all(axis=1))
            | (np.abs(tp.start) > MAX_COORD).any(axis=1)
            | (np.abs(tp.end) > MAX_COORD).any(axis=1),
            f"a coordinate beyond {MAX_COORD:g} mm (or not a number)",
        ),
        (
            arc
            & ~(np.isfinite(tp.center).all(axis=1) & (np.abs(tp.center) <= MAX_COORD).all(axis=1)),
            f"an arc centre beyond {MAX_COORD:g} mm (or not a number)",
        ),
        (
            arc & ~((tp.sweep > 0) & (tp.sweep <= MAX_SWEEP)),
            f"an arc of more than {MAX_SWEEP / (2 * np.pi):,.0f} turns (or of none)",
        ),
        (
            feed_move & ~((tp.feed >= FEED_RANGE[0]) & (tp.feed <= FEED_RANGE[1])),
            f"a feed outside {FEED_RANGE[0] * 60:g} to {FEED_RANGE[1] * 60:g} mm/min",
        ),
        (
            ~((tp.dwell >= 0) & (tp.dwell <= MAX_DWELL)),
            f"a dwell outside 0 to {MAX_DWELL:g} s",
        ),
        (
            ~(np.isnan(tp.tolerance) | ((tp.tolerance >= 0) & (tp.tolerance <= MAX_COORD))),
            "a path tolerance below 0 or beyond 1 km",
        ),
    )
    found = [(k, msg) for bad, msg in checks if (k := _first_bad(bad)) is not None]
    if found:
        k, msg = min(found)
        raise InputError(f"move with {msg}", source=tp.source, line=int(tp.line[k]))


#: Largest tool number (the tool column is int32; T9999999999 would wrap around).
MAX_TOOL = 2**31 - 1

#: Most pecks in one drilled hole (G73/G83, Siemens CYCLE83, APT CYCLE/DEEP): a 100 mm hole
#: in 0.01 mm pecks. Q0.0001 on a 1 m hole would be ten million moves of nothing.
MAX_PECKS = 10_000
