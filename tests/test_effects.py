"""Unmodelled effects (issue 5): each changes the prediction as its docstring says, with
numbers worked out by hand; machine files switch them on."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from core import MachineError, UsageError
from core.engine.effects import Setup, setup_for
from core.model.machine import machine_from_toml_text
from tests.conftest import machine, path

INF = float("inf")
NAMES = [
    "acceleration_ramps",
    "lookahead_depth",
    "block_cycle_time",
    "corner_tolerance",
    "normal_acceleration_factor",
    "arc_feed_limit",
    "axis_dynamics",
    "feed_override",
    "servo_lag",
    "jerk_filter",
    "path_compression",
    "last_block_acceleration",
    "arc_acceleration",
    "exact_stop",
    "path_feed_limit",
]


@pytest.fixture
def effects(nc):
    return nc.effects()


def run(nc, effects, tp, m, name=None, ramps=True, **params):
    setup = Setup(machine=m, ramps=ramps)
    if name:
        eff = effects[name]
        setup = eff.apply(setup, eff.defaults(m) | eff.check(params))
    return nc.predict(tp, setup)


def test_the_built_in_effects(nc):
    """The built-in effects (issue 5's eleven, two of its own, issue 11's two) are
    registered, by these names."""
    assert list(nc.effects()) == NAMES


def test_acceleration_ramps_turn_the_point_model_into_the_profile(nc, effects):
    """Without ramps a 100 mm line runs at F all along (1 s); with them 1 + F/A = 1.04 s."""
    tp = path([{"end": (100, 0, 0)}])
    m = machine(jerk=(INF, INF, INF))
    assert run(nc, effects, tp, m, ramps=False).cycle_time == pytest.approx(1.0)
    p = run(nc, effects, tp, m, "acceleration_ramps", ramps=False)
    assert p.cycle_time == pytest.approx(1.04)


def test_feed_override(nc, effects):
    """Scale 0.8: 100 mm at 80 mm/s plus one ramp 80 / 2500: 1.25 + 0.032 = 1.282 s."""
    tp = path([{"end": (100, 0, 0)}])
    p = run(nc, effects, tp, machine(jerk=(INF, INF, INF)), "feed_override", scale=0.8)
    assert p.cycle_time == pytest.approx(1.282)


def test_block_cycle_time(nc, effects):
    """t_block 24 ms on 1 mm blocks: 1 / 0.024 = 41.667 mm/s (t_int 12 ms gives 83.333)."""
    tp = path([{"end": (i + 1, 0, 0)} for i in range(10)], feed=10000 / 60)
    p = run(nc, effects, tp, machine(), "block_cycle_time", t_block=0.024)
    assert np.allclose(p.evaluation.element_feed, 1 / 0.024)


def test_corner_tolerance(nc, effects):
    """TIT 0.1 mm at 90 deg: R = 0.1 x 2.414214 = 0.241421 mm, sqrt(2500 R) = 24.567 mm/s."""
    tp = path([{"end": (10, 0, 0)}, {"end": (10, 10, 0)}])
    p = run(nc, effects, tp, machine(jerk=(INF, INF, INF)), "corner_tolerance", tolerance=0.1)
    assert p.evaluation.junction_feed[0] == pytest.approx(math.sqrt(2500 * 0.2414213562))


def test_normal_acceleration_factor(nc, effects):
    """Factor 0.5 at a 90 deg corner: sqrt(0.5 x 2500 x 0.0241421) = 5.4934 mm/s."""
    tp = path([{"end": (10, 0, 0)}, {"end": (10, 10, 0)}])
    p = run(
        nc, effects, tp, machine(jerk=(INF, INF, INF)), "normal_acceleration_factor", factor=0.5
    )
    assert p.evaluation.junction_feed[0] == pytest.approx(math.sqrt(0.5 * 2500 * 0.0241421356))


def test_arc_feed_limit(nc, effects):
    """A quarter arc of R 5 in XY at F 200: both axes reach the full normal over it, so the
    arc is capped at sqrt(2500 x 5) = 111.80 mm/s; with factor 0.5 at sqrt(1250 x 5)."""
    tp = path([{"end": (5, 5, 0), "center": (0, 5, 0), "ccw": True}], feed=200.0)
    m = machine(jerk=(INF, INF, INF))
    p = run(nc, effects, tp, m, "arc_feed_limit")
    assert p.evaluation.element_feed[0] == pytest.approx(math.sqrt(2500 * 5))
    assert p.evaluation.indicator_names[p.evaluation.element_indicator[0]] == "arc_feed_limit"
    both = effects["normal_acceleration_factor"].apply(Setup(machine=m), {"factor": 0.5})
    both = effects["arc_feed_limit"].apply(both, {})
    assert nc.predict(tp, both).evaluation.element_feed[0] == pytest.approx(math.sqrt(6250))


def test_axis_dynamics(nc, effects):
    """Acceleration x 2 on a 100 mm line: 1 + 100 / 5000 = 1.02 s."""
    tp = path([{"end": (100, 0, 0)}])
    p = run(nc, effects, tp, machine(jerk=(INF, INF, INF)), "axis_dynamics", accel_scale=2.0)
    assert p.cycle_time == pytest.approx(1.02)


def test_lookahead_depth(nc, effects):
    """Looking one 0.5 mm block ahead, the machine must stop within it: v^2 <= 2 A 0.5,
    v <= 50 mm/s at every inner boundary; full look-ahead runs the 20 mm as one triangle
    peaking at sqrt(A 20) = 223.607 mm/s."""
    tp = path([{"end": (0.5 * (i + 1), 0, 0)} for i in range(40)], feed=300.0)
    m = machine(jerk=(INF, INF, INF), t_int=0.0001)
    p = run(nc, effects, tp, m, "lookahead_depth", blocks=1)
    assert np.allclose(p.profile.v_entry[1:], 50.0)
    assert run(nc, effects, tp, m).profile.v_peak.max() == pytest.approx(math.sqrt(50000))


def test_lookahead_depth_with_a_jerk_limit(nc, effects):
    """Jerk-limited stops: from v a stop takes v sqrt(v / J) while v < A^2 / J, so within
    4 mm (four 1 mm blocks) at J 5000, A 2500: v = (16 x 5000)^(1/3) = 43.089 mm/s; at
    J 50000 within 100 mm: v^2 / A + v A / J = 200 gives v = 647.36 mm/s."""
    from core.engine.profile import stop_speed

    v = stop_speed([4.0, 100.0, 0.5], [2500.0, 2500.0, 2500.0], [5000.0, 50000.0, INF])
    assert v == pytest.approx([80000 ** (1 / 3), 1250 * (math.sqrt(0.0025 + 0.32) - 0.05), 50.0])
    tp = path([{"end": (i + 1.0, 0, 0)} for i in range(40)], feed=100.0)
    p = run(nc, effects, tp, machine(t_int=0.0001), "lookahead_depth", blocks=4)
    assert p.profile.v_entry[10:30] == pytest.approx(np.full(20, 80000 ** (1 / 3)))


def test_servo_lag_and_jerk_filter_delay_the_speed(nc, effects):
    """Lag and smoothing keep the distance but slow the speed's rise: at 20 ms into a
    ramp to 100 mm/s (A 2500: raw 50 mm/s) the lagged speed (tau 20 ms) is lower."""
    tp = path([{"end": (100, 0, 0)}])
    m = machine(jerk=(INF, INF, INF))
    raw = run(nc, effects, tp, m)
    for name, params in (("servo_lag", {"tau": 0.02}), ("jerk_filter", {"window": 0.04})):
        p = run(nc, effects, tp, m, name, **params)
        t, s, v = p.signal()
        assert s[-1] == pytest.approx(100.0, abs=0.05)
        k = int(round(0.02 / (t[1] - t[0])))
        assert v[k] < raw.signal()[2][k] - 5
        # first-order lag of a ramp a t: a (t - tau (1 - exp(-t / tau))) = 18.4 mm/s
        if name == "servo_lag":
            assert v[k] == pytest.approx(2500 * (0.02 - 0.02 * (1 - math.exp(-1))), abs=0.8)


def test_path_compression_merges_runs_into_one_segment(nc, effects):
    """20 collinear 1 mm blocks at 10 m/min (each capped at 1 / 0.012 = 83.333 mm/s by t_int
    12 ms): compressed (blocks < 3 mm, angles < 5 deg) they are one 20 mm segment, capped at
    20 / 0.012 = 1666.7 mm/s, so every block keeps F. 20 blocks of 0.05 mm: one 1 mm
    segment, 83.333 mm/s on all of them (uncompressed: 0.05 / 0.012 = 4.1667 mm/s); with
    a 1 deg turn between the 10th and 11th, max_angle 0.5 deg splits it in two 0.5 mm
    segments at 41.667 mm/s."""
    tp = path([{"end": (i + 1, 0, 0)} for i in range(20)], feed=10000 / 60)
    p = run(nc, effects, tp, machine(), "path_compression", max_angle=5.0, max_length=3.0)
    assert np.allclose(p.evaluation.element_feed, 10000 / 60)
    tp = path([{"end": (0.05 * (i + 1), 0, 0)} for i in range(20)], feed=10000 / 60)
    p = run(nc, effects, tp, machine(), "path_compression", max_angle=5.0, max_length=3.0)
    assert np.allclose(p.evaluation.element_feed, 1 / 0.012)
    a = math.radians(1.0)
    bent = [(0.05 * (i + 1), 0, 0) for i in range(10)]
    bent += [
        (0.5 + 0.05 * (i + 1) * math.cos(a), 0.05 * (i + 1) * math.sin(a), 0) for i in range(10)
    ]
    tp = path([{"end": e} for e in bent], feed=10000 / 60)
    p = run(nc, effects, tp, machine(), "path_compression", max_angle=0.5, max_length=3.0)
    assert np.allclose(p.evaluation.element_feed, 0.5 / 0.012)


def test_parameters_are_bound_checked(effects):
    """Out-of-bounds or unknown parameters: a usage error naming effect and parameter."""
    with pytest.raises(UsageError, match=r"servo_lag.tau = 0.5 is outside \[0, 0.2\] s"):
        effects["servo_lag"].check({"tau": 0.5})
    with pytest.raises(UsageError, match="has no parameter 'tua'"):
        effects["servo_lag"].check({"tua": 0.1})


MACHINE = """name = "m"
[axes.X]
max_feed = 30.0
max_acceleration = 2.5
max_jerk = 5.0
[axes.Y]
max_feed = 30.0
max_acceleration = 2.5
max_jerk = 5.0
[axes.Z]
max_feed = 30.0
max_acceleration = 2.5
max_jerk = 5.0
[controller]
interpolation_time = 0.012
path_tolerance = 0.01
curvature_transition_time = 0.012
"""


def test_machine_file_switches_effects_on(nc, effects):
    """[effects.NAME] tables become part of the model: feed_override 0.5 halves the feed."""
    m = machine_from_toml_text(MACHINE + "[effects.feed_override]\nscale = 0.5\n", "m.toml")
    setup = setup_for(m, effects)
    assert setup.feed_scale == 0.5
    tp = path([{"end": (100, 0, 0)}])
    assert nc.predict(tp, setup).evaluation.element_feed[0] == pytest.approx(50.0)


@pytest.mark.parametrize(
    "table,line,message",
    [
        ("[effects.servo_lagg]\ntau = 0.01\n", 18, "unknown effect 'servo_lagg'"),
        ("[effects.servo_lag]\ntau = 0.5\n", 18, "servo_lag.tau = 0.5 is outside"),
        ('[effects.servo_lag]\ntau = "x"\n', 19, "must be a finite number"),
    ],
    ids=["unknown", "bounds", "not a number"],
)
def test_machine_file_effect_errors(effects, table, line, message):
    """Bad effect tables in a machine file: file, line and what is wrong."""
    with pytest.raises(MachineError) as info:
        setup_for(machine_from_toml_text(MACHINE + table, "m.toml"), effects)
    assert str(info.value).startswith(f"m.toml:{line}:") and message in str(info.value)


def test_axis_dynamics_per_axis(nc, effects):
    """Each axis its own limits (A = 2500 mm/s^2, F 100 mm/s, no jerk limit):
    - Y acceleration x 0.5 on a 100 mm line along Y: 100 / 100 + 100 / 1250 = 1.08 s;
    - X acceleration x 0.5 on the 45-degree line to (100, 100): the tangential acceleration
      is X's 1250 / cos 45 = 1767.77 mm/s^2, so 141.421 / 100 + 100 / 1767.77 = 1.470782 s;
    - X speed x 0.2 (100 mm/s, of 500) under F 150 on the same line: the path runs at
      100 / cos 45 = 141.421 mm/s with the full tangential acceleration 2500 / cos 45 =
      3535.53 mm/s^2: 141.421 / 141.421 + 141.421 / 3535.53 = 1.04 s."""
    m = machine(jerk=(INF, INF, INF))
    along_y = path([{"end": (0, 100, 0)}])
    diagonal = path([{"end": (100, 100, 0)}])
    assert run(nc, effects, along_y, m, "axis_dynamics", accel_y=0.5).cycle_time == pytest.approx(
        1.08
    )
    assert run(nc, effects, diagonal, m, "axis_dynamics", accel_x=0.5).cycle_time == pytest.approx(
        math.hypot(100, 100) / 100 + 100 / (1250 * math.sqrt(2))
    )
    fast = path([{"end": (100, 100, 0)}], feed=150.0)
    slow_x = run(nc, effects, fast, m, "axis_dynamics", feed_x=0.2).cycle_time
    assert slow_x == pytest.approx(1.04)
    # the uniform scale is the one-parameter special case of the per-axis factors
    uniform = run(nc, effects, diagonal, m, "axis_dynamics", accel_scale=0.5).cycle_time
    per_axis = run(
        nc, effects, diagonal, m, "axis_dynamics", accel_x=0.5, accel_y=0.5, accel_z=0.5
    ).cycle_time
    assert uniform == pytest.approx(per_axis)


def test_path_feed_limit(nc, effects):
    """A 60 mm/s path cap under F 100 on a 100 mm line: 100 / 60 + 60 / 2500 = 1.690667 s,
    the binding limit labelled "path feed"."""
    tp = path([{"end": (100, 0, 0)}])
    p = run(nc, effects, tp, machine(jerk=(INF, INF, INF)), "path_feed_limit", max_feed=60.0)
    assert p.cycle_time == pytest.approx(100 / 60 + 60 / 2500)
    ev = p.evaluation
    assert ev.element_feed[0] == pytest.approx(60.0)


def test_exact_stop(nc, effects):
    """Two 10 mm lines at F 100 (A 2500, no jerk limit), each from rest to rest: 2 mm up in
    0.04 s, 6 mm at F in 0.06 s, 2 mm down in 0.04 s: 2 x 0.14 = 0.28 s -- collinear or at a
    corner. Without it the collinear pair runs through: 20 / 100 + 100 / 2500 = 0.24 s."""
    m = machine(jerk=(INF, INF, INF))
    straight = path([{"end": (10, 0, 0)}, {"end": (20, 0, 0)}])
    corner = path([{"end": (10, 0, 0)}, {"end": (10, 10, 0)}])
    assert run(nc, effects, straight, m).cycle_time == pytest.approx(0.24)
    assert run(nc, effects, straight, m, "exact_stop").cycle_time == pytest.approx(0.28)
    assert run(nc, effects, corner, m, "exact_stop").cycle_time == pytest.approx(0.28)


def test_block_time_on_blend_arcs(nc):
    """A 90-degree corner with TIT 0.01 mm: the blend arc has R = 0.01 sin45 / (1 - sin45) =
    0.0241421 mm and length R pi / 2 = 0.0379224 mm; lasting at least t_int = 12 ms, the
    corner runs at 0.0379224 / 0.012 = 3.1602 mm/s, under model 1's sqrt(2500 R) = 7.7689.
    Off (the paper's model 3: programmed blocks only), the corner keeps 7.7689."""
    tp = path([{"end": (10, 0, 0)}, {"end": (10, 10, 0)}])
    m = machine(jerk=(INF, INF, INF))
    r = 0.01 * math.sin(math.pi / 4) / (1 - math.sin(math.pi / 4))
    off = nc.predict(tp, Setup(machine=m)).evaluation
    assert off.junction_feed[0] == pytest.approx(math.sqrt(2500 * r))
    on = nc.predict(tp, Setup(machine=dataclasses.replace(m, block_time_on_blends=True)))
    ev = on.evaluation
    assert ev.junction_feed[0] == pytest.approx(r * math.pi / 2 / 0.012)
    assert ev.indicator_names[ev.junction_indicator[0]] == "ncu_capacity"
