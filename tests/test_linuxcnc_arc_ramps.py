"""LinuxCNC's blend arcs between blocks of different feeds (core.engine.profile._arc_ramps):
the arc's requested speed is the higher feed, so the planner leaves a slow plunge at its
feed at the arc's tangent point and accelerates along the arc at half the plane's
acceleration up to the arc's limit. The holds that run so, checked by hand; the profile's
sampled motion and its speed at places agree there; the recorded LinuxCNC motion is in
tests/test_linuxcnc_planner_traces.py."""

from __future__ import annotations

import numpy as np
import pytest

from core import Ncperf, load_preset
from core.engine.profile import (
    build_profile,
    ramped_hold_motion,
    ramped_hold_speed,
    ramped_hold_time,
)

A = np.array([1000.0])
RUN = np.array([1.0])


def _f(*xs: float) -> list[np.ndarray]:
    return [np.array([x]) for x in xs]


def test_a_ramped_hold_by_hand():
    """1 mm from 10 to 30 mm/s at 1000 mm/s^2: the change takes (900 - 100) / 2000 = 0.4 mm
    and 20 / 1000 = 0.02 s, the 0.6 mm left at 30 mm/s 0.02 s: 0.04 s, either way round."""
    lo, hi = _f(10.0, 30.0)
    assert ramped_hold_time(RUN, lo, hi, A)[0] == pytest.approx(0.04, rel=1e-12)
    assert ramped_hold_time(RUN, hi, lo, A)[0] == pytest.approx(0.04, rel=1e-12)
    # rising: sqrt(10^2 + 2 * 1000 * 0.2) = sqrt(500) 0.2 mm in, 30 beyond 0.4 mm
    x = np.array([0.0, 0.2, 0.5, 1.0])
    four = [np.repeat(v, 4) for v in (RUN, lo, hi, A)]
    r, a, b, acc = four
    np.testing.assert_allclose(
        ramped_hold_speed(x, r, a, b, acc), [10.0, np.sqrt(500.0), 30.0, 30.0], rtol=1e-12
    )
    # falling: flat at 30 until 0.6 mm, then down to 10 at the end (0.2 mm short: sqrt 500)
    np.testing.assert_allclose(
        ramped_hold_speed(np.array([0.0, 0.5, 0.8, 1.0]), r, b, a, acc),
        [30.0, 30.0, np.sqrt(500.0), 10.0],
        rtol=1e-12,
    )
    tau = np.array([0.0, 0.01, 0.03, 0.04])
    # rising: 10 * 0.01 + 500 * 0.01^2 = 0.15 mm at 20 mm/s; 0.4 + 30 * 0.01 = 0.7 at 30
    x_up, v_up = ramped_hold_motion(tau, r, a, b, acc)
    np.testing.assert_allclose(x_up, [0.0, 0.15, 0.7, 1.0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(v_up, [10.0, 20.0, 30.0, 30.0], rtol=1e-12)
    # falling: 30 * 0.01 = 0.3 at 30; 0.6 + 30 * 0.01 - 500 * 0.01^2 = 0.85 at 20
    x_dn, v_dn = ramped_hold_motion(tau, r, b, a, acc)
    np.testing.assert_allclose(x_dn, [0.0, 0.3, 0.85, 1.0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(v_dn, [30.0, 30.0, 20.0, 10.0], rtol=1e-12)


def test_a_flat_hold_is_run_over_speed():
    """Equal speeds: run / v, the speed the same everywhere; speed 0: time 0 (a stop is
    the ramps' business, as for every hold)."""
    v = np.array([20.0, 0.0])
    run = np.array([0.5, 0.5])
    acc = np.array([1000.0, 1000.0])
    np.testing.assert_allclose(ramped_hold_time(run, v, v, acc), [0.025, 0.0])
    np.testing.assert_allclose(ramped_hold_speed(np.array([0.3, 0.3]), run, v, v, acc), v)


PLUNGE = """(a plunge into a cut and a cut into a slow move, G64 P0.15)
G21 G17 G90 G94
G64 P0.15 Q0
G0 X0 Y0 Z2
G1 Z-1 F600
G1 X20 F5000
G1 Y10 F1200
G1 X0 F5000
G0 Z5
M2
"""


@pytest.fixture(scope="module")
def plunge(tmp_path_factory):
    prog = tmp_path_factory.mktemp("ramps") / "plunge.ngc"
    prog.write_text(PLUNGE)
    nc = Ncperf()
    tp = nc.extract(str(prog))
    return build_profile(nc.evaluate(tp, load_preset("linuxcnc-sim")))


def test_the_slow_side_of_a_plunge_corner_ramps_up_to_the_arcs_limit(plunge):
    """At the plunge's corner (line 5 -> 6) the plunge's half arc starts at its feed,
    10 mm/s, and rises at half of 2000 mm/s^2 (the X and Z limits of the simulated mill):
    sqrt(10^2 + 2 * 1000 * d) at the corner for the d mm of the arc run on the plunge's
    side, at most the arc's limit, which the cut then keeps or passes -- not 10 mm/s
    (the lower feed) all along the arc."""
    pr = plunge
    ar = pr.arc_ramps
    assert ar is not None
    tp = pr.toolpath
    s = int(np.flatnonzero(tp.line == 5)[0])  # the plunge
    assert pr.v_exit[s] == pytest.approx(10.0)
    d = pr.hold_end_ratio[s] * pr.hold_end[s]
    assert d > 0.1  # a coarse arc: 0.15 mm from the corner
    lim = pr.evaluation.junction_arc_feed[np.flatnonzero(pr.evaluation.junction == s)[0]]
    assert ar.a_end[s] == pytest.approx(1000.0)
    assert ar.end[s] == pytest.approx(min(lim, np.sqrt(100.0 + 2000.0 * d)), rel=1e-12)
    assert ar.end[s] > 20.0
    assert ar.start[s + 1] == ar.end[s]  # the cut starts its half arc at the corner speed
    assert pr.v_entry[s + 1] >= ar.end[s]
    # the hold's time by hand: from 10 at 1000 mm/s^2, then flat at the corner speed
    v_c = ar.end[s]
    d_r = (v_c**2 - 100.0) / 2000.0
    t_hold = (v_c - 10.0) / 1000.0 + (d - d_r) / v_c
    assert pr.hold_times[1][s] == pytest.approx(t_hold, rel=1e-12)
    assert t_hold < d / 10.0 * 0.6  # held at 10 mm/s it took more than half again as long


def test_a_cut_into_a_slower_block_ramps_down_along_the_slow_side(plunge):
    """Line 6 (F5000) into line 7 (F1200, 20 mm/s) at a 90 degree corner: the time-reversed
    shape -- the slow block's half arc falls from the corner speed to 20 mm/s at its end."""
    pr = plunge
    ar = pr.arc_ramps
    tp = pr.toolpath
    f = int(np.flatnonzero(tp.line == 7)[0])
    assert pr.v_entry[f] == pytest.approx(20.0)
    d = pr.hold_start_ratio[f] * pr.hold_start[f]
    lim = pr.evaluation.junction_arc_feed[np.flatnonzero(pr.evaluation.junction == f - 1)[0]]
    assert ar.a_start[f] == pytest.approx(1000.0)
    assert ar.start[f] == pytest.approx(min(lim, np.sqrt(400.0 + 2000.0 * d)), rel=1e-12)
    assert ar.start[f] > 25.0
    assert pr.v_exit[f - 1] >= ar.start[f] == ar.end[f - 1]


def test_sampled_motion_and_speed_at_places_agree_in_the_ramped_holds(plunge):
    """The profile's motion in time (Profile.sample) and its speed at places
    (Profile.speed_at) are two computations of the same holds; the travel never goes back
    and the samples' count is the cycle time's."""
    pr = plunge
    smp = pr.sample(0.0005)
    assert np.all(np.diff(smp.s) >= -1e-12)
    assert smp.t[-1] == pytest.approx(pr.cycle_time, abs=0.0005)
    np.testing.assert_allclose(pr.speed_at(smp.s), smp.v, atol=0.05)
    # the speed changes at most at the machine's 2000 mm/s^2 between samples
    assert np.max(np.abs(np.diff(smp.v))) / 0.0005 <= 2000.0 * (1 + 1e-9) + 1e-6
