"""Unmodelled effects as plugins (``ncperf_effects``), one module each.

Each names what a real controller does beyond the paper's models, its parameters with
bounds, and how it changes the prediction (:mod:`core.engine.effects`). ``ncperf diagnose`` fits
them to measured traces; a machine file switches them on with ``[effects.NAME]`` tables.
"""

from __future__ import annotations

#: The effect modules, in the order they are tried.
MODULES = (
    "plugins.effects.acceleration_ramps",
    "plugins.effects.lookahead_depth",
    "plugins.effects.block_cycle_time",
    "plugins.effects.corner_tolerance",
    "plugins.effects.normal_acceleration_factor",
    "plugins.effects.arc_feed_limit",
    "plugins.effects.axis_dynamics",
    "plugins.effects.feed_override",
    "plugins.effects.servo_lag",
    "plugins.effects.jerk_filter",
    "plugins.effects.path_compression",
    "plugins.effects.last_block_acceleration",
    "plugins.effects.arc_acceleration",
)
