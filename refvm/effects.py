"""The controller effects the reference interpreter can switch on, one at a time.

:data:`EFFECTS` is ``{name: {param: (low, high, default)}}`` in the interpreter's units (s,
mm, degrees for angles); its names are those of ncperf's effects, so that a diagnosis can be
scored against the effect switched on here. A default of
``None`` means "the machine's own value" (named in :data:`MACHINE_DEFAULTS`).
:data:`EFFECT_DOCS` states the exact semantics of each switch; :func:`resolve_effect`
checks a request against the table.

``acceleration_ramps``, the diagnosis's 11th effect, is not a switch here: every real
interpolator has ramps, and so has this one.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from refvm.machine import MachineLimits

EFFECTS: dict[str, dict[str, tuple[float, float, float | None]]] = {
    "feed_override": {"scale": (0.5, 1.5, 1.0)},
    "block_cycle_time": {"t_block": (0.0002, 0.05, None)},
    "corner_tolerance": {"tolerance": (0.0005, 1.0, None)},
    "normal_acceleration_factor": {"factor": (0.2, 1.0, 1.0)},
    "arc_feed_limit": {},
    "axis_dynamics": {
        "accel_scale": (0.25, 4.0, 1.0),
        "jerk_scale": (0.25, 4.0, 1.0),
        "feed_scale": (0.05, 4.0, 1.0),
    },
    "lookahead_depth": {"blocks": (1, 200, 20)},
    "servo_lag": {"tau": (0.0, 0.2, 0.0)},
    "jerk_filter": {"window": (0.0, 0.1, 0.0)},
    "path_compression": {"max_angle": (0.5, 20.0, 5.0), "max_length": (0.5, 10.0, 3.0)},
}

#: Defaults taken from the machine: (effect, param) -> MachineLimits attribute.
MACHINE_DEFAULTS: dict[tuple[str, str], str] = {
    ("block_cycle_time", "t_block"): "interpolation_time",
    ("corner_tolerance", "tolerance"): "path_tolerance",
}

#: Parameters that count things (must be whole numbers).
INTEGER_PARAMS = {("lookahead_depth", "blocks")}

EFFECT_DOCS: dict[str, str] = {
    "lookahead_depth": (
        "blocks [1, 200], default 20: the planner sees the move being run and the next "
        "`blocks` moves, and must be able to stop, jerk-limited, at the end of the last one "
        "it sees (planned as a stop unless it is the program end anyway); the window slides "
        "by one move each time a move is completed. blocks = 1 on collinear blocks of length "
        "l bounds the speed at every block end by sqrt(2 A l) (trapezoid)."
    ),
    "block_cycle_time": (
        "t_block [0.0002, 0.05] s, default the machine's interpolation_time: every feed "
        "block of length l runs at most at l / t_block, replacing model 3's l / t_int "
        "(eq. 16 evaluated with t_int = t_block); rapids are not capped."
    ),
    "corner_tolerance": (
        "tolerance [0.0005, 1] mm, default the machine's path_tolerance: the TIT of model 1 "
        "(eq. 1 radius) is this value for every block, replacing the machine's TIT and any "
        "tolerance the program sets (LinuxCNC G64 P, Siemens CTOL); the tangential junction "
        "limits and the corner arcs are recomputed with it."
    ),
    "normal_acceleration_factor": (
        "factor [0.2, 1]: only factor * A_k of each axis is available for normal "
        "acceleration: on the arcs inserted at corners (model 1's sqrt(A R) part becomes "
        "sqrt(factor A R); feed and jerk parts unchanged) and on programmed arcs, which are "
        "capped at min_k sqrt(factor A_k rho / n_k) (as arc_feed_limit without its jerk "
        "part); the tangential acceleration stays A_k."
    ),
    "arc_feed_limit": (
        "no parameters: every programmed arc (G2/G3, helices too) is capped at "
        "min_k sqrt(A_k rho / n_k) and min_k cbrt(J_k rho^2 / t_k), rho the radius of "
        "curvature (R for planar arcs), n_k and t_k the largest share of axis k in the "
        "principal normal and in the tangent over the arc's sweep."
    ),
    "axis_dynamics": (
        "accel_scale, jerk_scale [0.25, 4], feed_scale [0.05, 4]: every axis's max "
        "acceleration, max jerk and max feed are multiplied by these, both in the corner, "
        "curvature and block feed limits (models 1, 2, the axes' share of each block's "
        "direction) and in the motion (tangential acceleration and jerk, rapids); an infinite "
        "jerk stays infinite."
    ),
    "feed_override": (
        "scale [0.5, 1.5]: every programmed feed F is multiplied by scale before anything "
        "else (model 3's L = F t_int follows); rapids unchanged; the axes' feed limits still "
        "cap the result."
    ),
    "servo_lag": (
        "tau [0, 0.2] s: the trace records actual positions, each axis a first-order lag of "
        "the setpoint (x_act' = (x_set - x_act) / tau, solved exactly for a setpoint linear "
        "over each cycle); v is |d x_act / dt| (central differences), line follows the "
        "setpoint; the trace goes on after the setpoint stops until the lag is below 1 um. "
        "Implies kind = actual."
    ),
    "jerk_filter": (
        "window [0, 0.1] s: the setpoint positions pass through a causal moving average over "
        "round(window / dt) cycles (a controller's FIR jerk filter after interpolation): the "
        "output lags by window / 2, corners are rounded, the trace is window longer; v is the "
        "speed of the smoothed positions (central differences); line follows the setpoint."
    ),
    "path_compression": (
        "max_angle [0.5, 20] deg, max_length [0.5, 10] mm: runs of two or more consecutive "
        "feed blocks, each shorter than max_length, joined by junctions turning less than "
        "max_angle (no stop or dwell between them), are merged into one smooth spline: inside "
        "a run the tangential and curvature junction limits are dropped and the block-time "
        "cap applies to the run as one block (L_run / t_int where L_run < F t_int) instead of "
        "block by block; the junctions at the run's ends keep their limits; the axes' feed "
        "limits and the tangential acceleration and jerk of each block stay."
    ),
}


def resolve_effect(
    effect: str | None, params: Mapping[str, object] | None, machine: MachineLimits
) -> dict[str, float]:
    """Check an effect request against :data:`EFFECTS` and fill in the defaults.

    Parameters
    ----------
    effect : str or None
        An :data:`EFFECTS` name; None for the controller without effect.
    params : mapping of str to number, optional
        Parameter values; missing ones take their default.
    machine : MachineLimits
        For the defaults that are the machine's own values.

    Returns
    -------
    dict of str to float
        Every parameter of the effect.

    Raises
    ------
    ValueError
        Unknown effect or parameter, a value that is not a number, not whole where it
        counts blocks, or outside the table's bounds.
    """
    params = dict(params or {})
    if effect is None:
        if params:
            raise ValueError(f"parameters {sorted(params)} given without an effect")
        return {}
    if effect not in EFFECTS:
        raise ValueError(f"unknown effect {effect!r}; effects: {', '.join(EFFECTS)}")
    table = EFFECTS[effect]
    for key in params:
        if key not in table:
            known = ", ".join(table) or "none"
            raise ValueError(
                f"unknown parameter {key!r} of effect {effect!r} (parameters: {known})"
            )
    out: dict[str, float] = {}
    for key, (low, high, default) in table.items():
        if key in params:
            raw = params[key]
            try:
                value = float(raw)  # type: ignore[arg-type]
            except (TypeError, ValueError):
                raise ValueError(f"{effect}.{key} must be a number, got {raw!r}") from None
        elif default is None:
            value = float(getattr(machine, MACHINE_DEFAULTS[(effect, key)]))
        else:
            value = float(default)
        if not math.isfinite(value):
            raise ValueError(f"{effect}.{key} must be finite, got {value!r}")
        if (effect, key) in INTEGER_PARAMS and value != int(value):
            raise ValueError(f"{effect}.{key} must be a whole number, got {value!r}")
        if key in params and not low <= value <= high:
            raise ValueError(f"{effect}.{key} = {value:g} is outside [{low:g}, {high:g}]")
        out[key] = value
    return out
