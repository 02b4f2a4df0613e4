"""axis_dynamics: the axes' limits differ from the machine file, each axis its own.

Parameters: ``accel_scale``, ``jerk_scale`` (0.25-4) and ``feed_scale`` (0.05-4), multiplying
every axis's acceleration, jerk and maximum feed -- in the corner and curvature limits, the
blocks' feed limits, the rapids and the ramps alike -- and, on top of them, one factor per
axis for the acceleration and the feed (``accel_x``... ``feed_z``, 0.2-5): an X axis
slower than Y and Z is ``accel_x`` alone; the uniform scale is the special case where the
per-axis factors stay 1. The feed scale reaches further down: an axis speed limit only shows
once it falls under the programmed feeds, and machine files give axis speeds (rapids)
several times the cutting feeds. Fitted in two stages: the uniform scales on a grid, then
each axis's factors one at a time.
"""

from __future__ import annotations

import numpy as np

from core import hookimpl
from core.engine.effects import Effect, Param, scale_machine

AXES = "xyz"
UNIFORM = ("accel_scale", "jerk_scale", "feed_scale")
PER_AXIS = tuple(f"{kind}_{a}" for kind in ("accel", "feed") for a in AXES)


def _apply(setup, p):
    accel = p["accel_scale"] * np.array([p.get(f"accel_{a}", 1.0) for a in AXES])
    feed = p["feed_scale"] * np.array([p.get(f"feed_{a}", 1.0) for a in AXES])
    return setup.replace(
        machine=scale_machine(setup.machine, accel=accel, jerk=p["jerk_scale"], feed=feed)
    )


#: A scale within this share of 1 (log) is unchanged, and scales of the three axes within it
#: of each other are one uniform scale (when counting an explanation's parameters).
SAME = 0.02


def _size(p):
    """Parameters the explanation uses: a uniform change of acceleration or feed is one, a
    change of some axes one per axis, a jerk scale one."""
    n = 0
    for kind in ("accel", "feed"):
        e = np.log([p[f"{kind}_scale"] * p.get(f"{kind}_{a}", 1.0) for a in AXES])
        changed = np.abs(e) > SAME
        if changed.all() and e.max() - e.min() <= SAME:
            n += 1
        else:
            n += int(changed.sum())
    return n + int(abs(np.log(p["jerk_scale"])) > SAME)


EFFECT = Effect(
    name="axis_dynamics",
    params=(
        Param("accel_scale", 0.25, 4.0, 1.0, log=True),
        Param("jerk_scale", 0.25, 4.0, 1.0, log=True),
        Param("feed_scale", 0.05, 4.0, 1.0, log=True),
        # (per-axis feed factors down to 0.105 were tried, 2026-11-27: an X speed of 46 of
        # 250 mm/s, 0.18, was then fitted on a free-form path's rapids; but calibrating on
        # polls every 0.2 s (tests/test_calibrate_blocktime.py) one fold then traded a slow
        # X speed for a fast X acceleration, 97.1 against the truth's 97.6 ms, and the
        # folds' mean missed the cycle time by 7 %: the range stays)
        *(Param(name, 0.2, 5.0, 1.0, log=True) for name in PER_AXIS),
    ),
    apply=_apply,
    doc="per-axis acceleration, jerk and feed limits differ",
    relative=UNIFORM + PER_AXIS,
    stages=(UNIFORM, PER_AXIS),
    size=_size,
    rapids=True,
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
