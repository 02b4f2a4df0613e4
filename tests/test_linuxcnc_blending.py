"""LinuxCNC 2.9's corner blending (``corner_blending = "linuxcnc"``), against hand
calculations from the rules its planner documents in its source (tp.c tpSetupTangent,
blendmath.c blendComputeParameters, BLEND_ACC_RATIO_TANGENTIAL); the machine: every axis
2000 mm/s^2, no jerk limit, block time 1.02 ms (a 1 ms servo period), normal acceleration
factor 1 (a_n = 2000); the programs set G64 P0.01 (tolerance 0.01 mm) unless a test says
otherwise."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from core.engine.effects import Setup
from tests.conftest import machine, path

INF = float("inf")


def lcnc(mode="linuxcnc"):
    m = machine(acc=(2.0, 2.0, 2.0), jerk=(INF, INF, INF), t_int=0.00102)
    return dataclasses.replace(m, corner_blending=mode, block_time_on_blends=True)


def g64(moves, feed=100.0, tol=0.01):
    """A path run under G64 P``tol`` (None: G64 without P)."""
    tp = path(moves, feed=feed)
    if tol is None:
        return tp
    return dataclasses.replace(tp, tolerance=np.full(tp.n, float(tol)))


def turn(deg, length=10.0, feed=100.0, tol=0.01):
    """Two lines of ``length`` mm, the first along X, the second turned by ``deg`` in XY."""
    return chords(0.0, deg, length=length, feed=feed, tol=tol)


def tangential(nc, tp, m):
    return next(i for i in nc.indicators(tp, m) if i.name == "tangential")


def test_a_near_tangent_junction_has_no_arc(nc):
    """At 100 mm/s the turn within one servo period needs (100 / 0.001 + 2000) sin(b) /
    2000 = 51 sin(b) of an axis's acceleration: under the kink ratio 0.1 for b < 0.1123 deg.
    At 0.1 deg: run as tangent, no limit and nothing held; at 0.2 deg: an arc."""
    m = lcnc()
    near = tangential(nc, turn(0.1), m)
    assert near.feed[0] == INF
    assert near.values["hold_mm"][0] == 0.0
    arc = tangential(nc, turn(0.2), m)
    assert arc.values["hold_mm"][0] > 0.0
    # the paper's model puts an arc at both
    assert tangential(nc, turn(0.1), lcnc("paper")).values["hold_mm"][0] > 0.0


def test_an_arc_is_as_large_as_its_speed_needs(nc):
    """90 degrees at F 5 mm/s: the tolerance allows d = sin45 0.01 / (1 - cos45) =
    0.0241421 mm, R = d / tan45 = 0.0241421, sqrt(2000 R) = 6.949 mm/s > F, so v_plan = 5;
    a parabolic blend at 1000 mm/s^2 reaching min(sqrt(2 1000 d), 5) = 5 takes 5 / 1000 s
    over s = 0.025 mm: R_blend = s / (pi / 2) = 0.0159155, R_plan = max(5^2 / 2000, R_blend)
    = 0.0159155: tangent length R tan45 = 0.0159155 mm, half the arc R pi / 4 = 0.0125 mm.
    The paper's arc: eq. (1), R = 0.01 cos45 / (1 - cos45) = 0.0241421."""
    ind = tangential(nc, turn(90.0, feed=5.0), lcnc())
    assert ind.values["hold_mm"][0] == pytest.approx(0.0159155, rel=1e-5)
    assert ind.values["travel_mm"][0] == pytest.approx(0.0125, rel=1e-5)
    assert ind.feed[0] == pytest.approx(math.sqrt(2000 * 0.0241421), rel=1e-5)
    paper = tangential(nc, turn(90.0, feed=5.0), lcnc("paper"))
    assert paper.values["hold_mm"][0] == pytest.approx(0.0241421, rel=1e-5)


def test_speed_changes_along_an_arc_that_does_not_bind(nc):
    """Two 1 mm lines 1 degree apart at F 100, from rest to rest. The arc: d = min(0.5,
    0.5, sin(0.5deg) 0.01 / (1 - cos(0.5deg)) = 2.29) = 0.5 mm, R = 0.5 / tan(0.5deg) =
    57.29 mm, sqrt(2000 R) = 338 > F: it does not bind, and (kink 51 sin(1deg) = 0.89 > 0.1)
    it is inserted whole (R_blend = min(3.16 / 0.01745, R) = R). LinuxCNC accelerates along
    it at half of 2000: a ramp reaches 2000 x 0.5 + 1000 x 0.5 per side: the top speed
    sqrt(2 (1000 + 500)) = 54.772 at the junction. Piece by piece, each line takes
    sqrt(2000) / 2000 = 0.0223607 s on its straight half (to 44.721 mm/s) and
    (54.772 - 44.721) / 1000 = 0.0100505 s along the arc: 0.0324112 s (held arcs and a
    steeper ramp over the same reach, as before 2026-11-26 evening: 0.031950 s). The paper's
    model does not hold at a corner that does not bind: sqrt(2 2000 1) = 63.246, 2 x 2 x 1 /
    63.246 = 0.063246 s. (The second line, 1 degree off X, may brake at 2000 / cos(1deg) =
    2000.3: its stop takes 0.0316 % less time, hence rel=1e-4.)"""
    tp = g64(
        [
            {"end": (1.0, 0.0, 0.0)},
            {"end": (1 + math.cos(math.radians(1)), math.sin(math.radians(1)), 0.0)},
        ]
    )
    pr = nc.predict(tp, Setup(machine=lcnc(), ramps=True)).profile
    assert pr.v_exit[0] == pytest.approx(math.sqrt(3000.0), rel=1e-3)
    piece = math.sqrt(2000.0) / 2000.0 + (math.sqrt(3000.0) - math.sqrt(2000.0)) / 1000.0
    assert pr.cycle_time == pytest.approx(2 * piece, rel=1e-4)
    paper = nc.predict(tp, Setup(machine=lcnc("paper"), ramps=True)).profile
    assert paper.v_exit[0] == pytest.approx(math.sqrt(4000.0), rel=1e-6)
    assert paper.cycle_time == pytest.approx(4.0 / math.sqrt(4000.0), rel=1e-4)


def test_an_arc_run_at_cruise_costs_nothing(nc):
    """Two 10 mm lines 1 degree apart at F 30: the arc (d = min(5, 2.29) mm, R = 262 mm,
    sqrt(2000 x 0.866 R) >> 30) neither binds nor is a kink ((30 / 0.001 + 2000) sin 1deg /
    2000 = 0.28 > 0.1). The speed is at F all along it, so its half acceleration changes
    nothing: 0 -> 30 mm/s at 2000 on the first line's straight start (0.015 s, 0.225 mm),
    the same stop at the end, cruise between: 2 x 0.015 + (20 - 0.45) / 30 = 0.681667 s.
    (One ramp at the line's mean acceleration, 2000 x 7.71 / 10 + 1000 x 2.29 / 10 = 1771,
    would take 0.0169 s to F.)"""
    pr = nc.predict(turn(1.0, feed=30.0), Setup(machine=lcnc(), ramps=True)).profile
    assert pr.cycle_time == pytest.approx(2 * 0.015 + (20.0 - 0.45) / 30.0, rel=1e-4)


def test_a_line_turning_towards_an_arcs_centre_corners_on_its_secant(nc):
    """A quarter circle of R 5 (G2 from (0, 5) to (5, 0) about the origin), then a 0.4 mm
    line turned 4 degrees towards the centre, at F 50 mm/s. Between the tangents the blend
    would be a 4 degree corner (theta_tan = 88 deg, d = 0.2 mm, R = 5.73 mm: F). LinuxCNC
    (blendInit3FromArcLine) lays it on the arc's secant instead: the line bends towards the
    centre (convex), phi_max = min(2/3 of pi/2, theta_tan) = 1.047198, theta = 1.535890 -
    phi_max / 4 = 1.274090; d_tol = cos(theta) 0.01 / (1 - sin(theta)) = 0.066912 mm (the
    arc side reaches sin(phi_max / 4) 5 = 1.294 mm, the line 0.2 mm), R = tan(theta) d =
    0.218860 mm, v = sqrt(2000 R) = 20.922 mm/s. (LHchips4's G19 quarter arcs, recorded:
    26.9 mm/s where ncperf had 83.)"""
    b = math.radians(4.0)
    quarter = {"start": (0.0, 5.0, 0.0), "end": (5.0, 0.0, 0.0), "center": (0.0, 0.0, 0.0)}

    def arc_then_line(x_off: float):
        end = (5.0 + x_off * 0.4 * math.sin(b), -0.4 * math.cos(b), 0.0)
        return g64([{**quarter, "ccw": False}, {"end": end}], feed=50.0)

    ind = tangential(nc, arc_then_line(-1.0), lcnc())
    assert ind.feed[0] == pytest.approx(math.sqrt(2000.0 * 0.218860), rel=1e-4)
    # turned away from the centre (concave) the tangents' corner stands: F
    assert tangential(nc, arc_then_line(+1.0), lcnc()).feed[0] > 45.0


def test_a_binding_arc_is_run_at_its_speed(nc):
    """A 90-degree corner of two 10 mm lines at F 100: the arc binds (6.949 mm/s, as above;
    LinuxCNC caps its speed there), so it is held over its whole tangent length as the
    paper has it, in both modes alike."""
    tp = turn(90.0)
    a = nc.predict(tp, Setup(machine=lcnc(), ramps=True)).profile
    b = nc.predict(tp, Setup(machine=lcnc("paper"), ramps=True)).profile
    assert a.v_exit[0] == pytest.approx(math.sqrt(2000 * 0.0241421), rel=1e-5)
    assert a.hold_end[0] == pytest.approx(0.0241421, rel=1e-5)
    assert b.hold_end[0] == pytest.approx(0.0241421, rel=1e-5)
    assert a.cycle_time == pytest.approx(b.cycle_time, rel=1e-9)


def test_machine_file_key(tmp_path):
    from core import MachineError
    from core.model.machine import load_machine_file

    text = tmp_path / "m.toml"
    base = """name = "m"
[axes.X]
max_feed = 15.0
max_acceleration = 2.0
max_jerk = inf
[axes.Y]
max_feed = 15.0
max_acceleration = 2.0
max_jerk = inf
[axes.Z]
max_feed = 15.0
max_acceleration = 2.0
max_jerk = inf
[controller]
interpolation_time = 0.00102
path_tolerance = 0.01
curvature_transition_time = 0.001
"""
    text.write_text(base + 'corner_blending = "linuxcnc"\n')
    assert load_machine_file(str(text)).corner_blending == "linuxcnc"
    text.write_text(base)
    assert load_machine_file(str(text)).corner_blending == "paper"
    text.write_text(base + 'corner_blending = "fanuc"\n')
    with pytest.raises(MachineError, match="corner_blending.*'paper', 'linuxcnc'"):
        load_machine_file(str(text))


def test_what_is_left_between_two_arcs_is_a_segment(nc):
    """A 0.1 mm line between two 90-degree corners at F 100: each arc binds (6.949 mm/s) and
    takes its tolerance's tangent length 0.0241421 mm; the rest, 0.1 - 2 x 0.0241421 =
    0.0517157 mm, would last 0.0517157 / 6.949 = 7.4 ms, over LinuxCNC's 4 servo periods:
    a segment of its own, at most 0.0517157 / 0.00102 = 50.70 mm/s."""
    tp = g64([{"end": (10, 0, 0)}, {"end": (10, 0.1, 0)}, {"end": (20, 0.1, 0)}])
    ev = nc.predict(tp, Setup(machine=lcnc())).evaluation
    assert ev.element_feed[1] == pytest.approx((0.1 - 2 * 0.0241421) / 0.00102, rel=1e-5)
    assert ev.labels[ev.element_limit[1]] == "block time (rest between blend arcs)"
    # the paper's mode keeps model 3 on the programmed block: 0.1 / 0.00102 = 98 mm/s
    paper = nc.predict(tp, Setup(machine=lcnc("paper"))).evaluation
    assert paper.element_feed[1] == pytest.approx(0.1 / 0.00102)


def test_a_short_rest_is_run_as_part_of_the_next_arc(nc):
    """Lines of 10, 0.2 and 10 mm turning 30 degrees twice at F 100: the tolerance allows
    d = sin15 0.01 / (1 - cos15) = 0.075957 mm (< 0.1, half the short line), R = d / tan15
    = 0.283477 mm, sqrt(2000 R) = 23.811 mm/s. The rest 0.2 - 2 d = 0.048086 mm lasts
    under 4 servo periods at 23.811 (0.095 mm): it joins the second arc, R pi/6 + 0.048086 =
    0.196512 mm long (cap 192.7 mm/s, not binding), and has no cap of its own."""
    b = math.radians(30)
    p1 = (10 + 0.2 * math.cos(b), 0.2 * math.sin(b), 0.0)
    p2 = (p1[0] + 10 * math.cos(2 * b), p1[1] + 10 * math.sin(2 * b), 0.0)
    tp = g64([{"end": (10, 0, 0)}, {"end": p1}, {"end": p2}])
    m = lcnc()
    blend = [
        i for i in nc.indicators(tp, m) if i.name == "tangential"
    ]  # the arcs as LinuxCNC sizes them
    assert blend[0].values["hold_mm"] == pytest.approx([0.075957, 0.075957], rel=1e-4)
    ev = nc.predict(tp, Setup(machine=m)).evaluation
    assert ev.element_feed[1] == 100.0
    assert ev.junction_feed == pytest.approx([23.811, 23.811], rel=1e-4)
    # the profile runs the merged rest as the second arc's: the short line is all arc, at
    # the corners' speed (both bind)
    pr = nc.predict(tp, Setup(machine=m, ramps=True)).profile
    assert pr.hold_start[1] == pytest.approx(0.075957, rel=1e-4)
    assert pr.hold_end[1] == pytest.approx(0.2 - 0.075957, rel=1e-4)
    assert pr.v_peak[1] == pytest.approx(23.811, rel=1e-4)


def test_an_arc_the_neighbours_keep_below_its_limit_changes_speed_along_it(nc):
    """Two 0.3 mm lines 20 degrees apart, from rest to rest, F 100: the tolerance allows
    d = sin10 0.01 / (1 - cos10) = 0.114301 mm (under 0.15), R = d / tan10 = 0.648236 mm,
    sqrt(2000 R) = 36.01 mm/s < F: the arc binds. But from rest the first line reaches only
    sqrt(2 2000 (0.3 - d)) = 27.25 mm/s before it: the neighbours keep the arc below its
    limit, so LinuxCNC changes speed along it, at half of 2000: 0.3 - d at 2000 and d at
    1000 give sqrt(2 2000 (0.3 - d) + 2 1000 d) = 31.17 mm/s at the corner (the second line,
    20 degrees off X, brakes at 2000 / cos20 = 2128.4: 31.92 from its end). The rest after
    the arc (0.186 mm) is longer than 4 servo periods at 36 mm/s (0.144 mm): not merged."""
    b = math.radians(20)
    tp = g64([{"end": (0.3, 0, 0)}, {"end": (0.3 + 0.3 * math.cos(b), 0.3 * math.sin(b), 0)}])
    d = 0.01 * math.sin(math.radians(10)) / (1 - math.cos(math.radians(10)))
    pr = nc.predict(tp, Setup(machine=lcnc(), ramps=True)).profile
    assert pr.v_exit[0] == pytest.approx(math.sqrt(4000 * (0.3 - d) + 2000 * d), rel=1e-4)
    assert pr.v_exit[0] == pytest.approx(31.17, abs=0.01)
    held = nc.predict(tp, Setup(machine=lcnc("paper"), ramps=True)).profile
    assert held.v_exit[0] < 27.3


def helix_corner(rise=1.0, feed=40.0):
    """A 10 mm line along +X, then a quarter turn clockwise about +Z from (10, 0) round
    (6, 0) rising ``rise`` mm: a 90 degree corner (the helix starts along -Y, tilted by its
    rise)."""
    return g64(
        [
            {"end": (10.0, 0.0, 0.0)},
            {"end": (6.0, -4.0, rise), "center": (6.0, 0.0, 0.0), "ccw": False},
        ],
        feed=feed,
    )


def test_a_helix_corner_gets_a_parabolic_blend(nc):
    """No blend arc between a line and a helix (the plane of the two tangents is not the
    helix's: tpCreateLineArcBlend's coplanarity check), so LinuxCNC chooses between a
    parabolic blend and a tangent kink (tpChooseBestBlend), by the speed each promises.
    Helix: 4 mm radius, quarter turn, rise 1: length sqrt(2 pi ^ 2 + 1) = 6.3623 mm, start
    tangent (0, -0.98757, 0.15718), beta = 90 deg. Its tangential acceleration: X and Y shares
    0.98757 and Z 0.15718 give 2000 / 0.98757 = 2025.2, half of it on an arc, 1012.6.
    - kink: (40 / 0.001 + 2000) |t2 - t1| / 2000 = 21 (X), twice next to an arc: 42; speed
      40 0.1 / 42 = 0.0952 mm/s;
    - parabolic, as planned (segments half available, acceleration x 0.5 x 0.9): line 900,
      helix 455.7; peaks min(sqrt(900 5), 40) = 40 and min(sqrt(455.7 3.181), 40) = 38.07;
      blend time min(10 / 40, 6.3623 / 38.07, max(40 / 900, 38.07 / 455.7)) = 0.08354 s;
      tolerance bound 2 sqrt(900 0.01 / sin 45) = 7.135 on both; promise cos45 7.135 / 2 =
      2.523 mm/s > 0.0952: parabolic.
    Run with the halved accelerations (line 1000, helix 1012.6 / 2 = 506.3). The blend speed's
    tolerance bound works with the angle between the directions the segments accelerate in
    (tpComputeBlendVelocity): the line's +X; the helix's start leans towards its centre,
    (0, -1, 0) 1012.6 + (-1, 0, 0) (40 / 2)^2 / 4 = (-100, -1012.6, 0), dot -0.09828,
    cos theta = sqrt((1 + 0.09828) / 2) = 0.74104 (the tangents' 90 degrees alone give
    0.70711): v_b = 2 sqrt(1000 0.01 / 0.74104) = 7.3468 mm/s. The line brakes from it to a
    stop while the helix starts from rest (the segments overlap), which costs the time of a
    corner crossed at the smaller root of A u^2 - (1 / 1000 + 1 / 506.3) u + v_b / 1000,
    A = 1 / (2 1000 v_b) + 1 / (2 506.3 40): u = 2.696 mm/s; both blocks keep half their
    acceleration."""
    ind = tangential(nc, helix_corner(), lcnc())
    dot = -100.0 / math.hypot(100.0, 1012.6)
    v_b = 2.0 * math.sqrt(1000.0 * 0.01 / math.sqrt((1.0 - dot) / 2.0))
    a_n = 2000.0 / (2 * math.pi / math.hypot(2 * math.pi, 1)) / 2 / 2
    big_a = 1 / (2 * 1000.0 * v_b) + 1 / (2 * a_n * 40.0)
    b = 1 / 1000.0 + 1 / a_n
    u = (b - math.sqrt(b * b - 4 * big_a * v_b / 1000.0)) / (2 * big_a)
    assert u == pytest.approx(2.696, abs=0.001)
    assert ind.feed[0] == pytest.approx(u)
    assert ind.labels[ind.limit[0]].startswith("parabolic blend")
    assert ind.values["hold_mm"][0] == 0.0  # no arc inserted
    assert ind.values["acceleration_share"][0] == 0.5
    prof = nc.predict(helix_corner(), Setup(machine=lcnc(), ramps=True)).profile
    assert prof.a_up[0] == pytest.approx(1000.0)
    assert prof.a_up[1] == pytest.approx(2000.0 / (2 * math.pi / math.hypot(2 * math.pi, 1)) / 2)
    # the same corner in the arc's plane (no rise) gets a blend arc: full accelerations
    flat = tangential(nc, helix_corner(rise=0.0), lcnc())
    assert flat.values["hold_mm"][0] > 0.0
    assert flat.values["acceleration_share"][0] == 1.0
    flat_prof = nc.predict(helix_corner(rise=0.0), Setup(machine=lcnc(), ramps=True)).profile
    assert flat_prof.a_up[0] == pytest.approx(2000.0)


def test_a_feed_column_through_a_parabolic_blend_shows_both_segments(nc):
    """The helix corner above as a trace's feed column shows it (LinuxCNC's current_vel is
    the sum of both segments' speeds while they overlap: tp.c v2.9.8 line 3064). Blend
    speed v_b = 7.3470 mm/s; the line brakes at a_p = 1000 (halved) to rest at the corner,
    d_b = v_b^2 / 2000 = 0.026989 mm before it, and from there the helix starts from rest
    at the acceleration the profile gives it (1012.6 mm/s^2, the test above) for t_b =
    v_b / 1000 = 7.3470 ms.
    - 0.1 mm before: the line alone, sqrt(2000 0.1) = 14.142 (the profile, which crosses
      the corner at u = 2.696, shows sqrt(u^2 + 200) = 14.397);
    - 0.01 mm before: the line at sqrt(20) = 4.4721, t = (7.3470 - 4.4721) / 1000 =
      2.8749 ms into the overlap, the helix at 1012.6 t = 2.9111: 7.3832;
    - 0.001 mm into the helix: t = sqrt(0.002 / 1012.6) = 1.4054 ms, the line at
      7.3470 - 1.4054 = 5.9416, the helix at 1.4231: 7.3647;
    - 0.5 mm into the helix, past the overlap: sqrt(2 1012.6 0.5) = 31.821.
    The profile and its time stay as they were (the corner speed costs the overlap's time)."""
    pred = nc.predict(helix_corner(), Setup(machine=lcnc(), ramps=True))
    ev = pred.evaluation
    assert ev.junction_blend is not None
    dot = -100.0 / math.hypot(100.0, 1012.6)
    v_b = 2.0 * math.sqrt(1000.0 * 0.01 / math.sqrt((1.0 - dot) / 2.0))
    assert ev.junction_blend[ev.junction == 0][0] == pytest.approx(v_b, rel=1e-5)
    a_n = 2000.0 / (2 * math.pi / math.hypot(2 * math.pi, 1)) / 2
    s = np.array([10.0 - 0.1, 10.0 - 0.01, 10.0 + 0.001, 10.0 + 0.5])
    t_before = (v_b - math.sqrt(20.0)) / 1000.0
    t_after = math.sqrt(0.002 / a_n)
    expected = [
        math.sqrt(200.0),
        math.sqrt(20.0) + a_n * t_before,
        v_b - 1000.0 * t_after + a_n * t_after,
        math.sqrt(2 * a_n * 0.5),
    ]
    assert expected == pytest.approx([14.142, 7.3832, 7.3647, 31.821], abs=2e-3)
    assert pred.speed_at(s) == pytest.approx(expected, abs=2e-3)
    assert pred.profile.speed_at(s[:1]) == pytest.approx([14.397], abs=2e-3)
    # far from the corner the two are one
    far = np.array([5.0, 13.0])
    assert pred.speed_at(far) == pytest.approx(pred.profile.speed_at(far), abs=1e-12)
    # a blend arc overlaps nothing
    flat = nc.predict(helix_corner(rise=0.0), Setup(machine=lcnc(), ramps=True))
    assert flat.evaluation.junction_blend is None


def test_the_column_through_an_overlap_closed_forms():
    """overlap_column by hand: v_b 6, a_p 500, a_n 1000 mm/s^2 (d_b = 0.036 mm, t_b = 12 ms):
    before, 0.1 mm: sqrt(100) = 10, not in the overlap; 0.009 mm: the first at 3, 6 ms in,
    the second at 6: 9; 0.036 mm: 6 either way. After, 0.0005 mm: 1 ms in, 6 - 0.5 + 1 =
    6.5; 0.072 mm: t_b, 0 + 12 = 12 either way; 0.2 mm: 20 ms, the second alone: 20."""
    from core.engine.predict import overlap_column

    col, inside = overlap_column([0.1, 0.009, 0.036 - 1e-12], 6.0, 500.0, 1000.0, before=True)
    assert col == pytest.approx([10.0, 9.0, 6.0], abs=1e-6)
    assert list(inside) == [False, True, True]
    col, inside = overlap_column([0.0005, 0.072 + 1e-12, 0.2], 6.0, 500.0, 1000.0, before=False)
    assert col == pytest.approx([6.5, 12.0, 20.0], abs=1e-6)
    assert list(inside) == [True, False, False]


def slow_servo(servo):
    return dataclasses.replace(lcnc(), interpolation_time=servo * 1.02)


def test_a_blend_arc_too_short_for_the_servo_period_gives_way_to_a_parabolic_blend(nc):
    """90 degrees, 10 mm lines at 20 mm/s, tolerance 0.001 mm. The arc: d = sin45 0.001 /
    (1 - cos45) = R = 0.0024142 mm, speed sqrt(2000 R) = 2.1974, length R pi / 2 =
    0.0037922 mm, at most its length per servo period: 0.92946 mm/s at 4 ms, 0.74357 at
    5 ms (G64 P0.001). The parabolic blend promises cos45 2 sqrt(900 0.001 / sin45) / 2 =
    0.79776; the kink 20 0.1 / ((20 / T + 2000) / 2000) = 0.5714 (4 ms), 0.6667 (5 ms). At
    4 ms the arc is best, at 5 ms the parabolic blend: its blend speed 2 sqrt(1000 0.001 /
    sin45) = 2.3784 mm/s, braked to a stop while the next line starts from rest at the same
    acceleration. The overlap would last 2.4 ms, but the planner steps every 5 ms and the
    segments share a step: 5 ms, more than any corner up to the blend speed costs
    (A u^2 - (2 / 1000) u + 0.005 has no root, A = 1 / (2 1000 2.3784) + 1 / (2 1000 20)):
    the corner is crossed at the blend speed."""
    at4 = tangential(nc, turn(90.0, feed=20.0, tol=0.001), slow_servo(0.004))
    assert at4.values["hold_mm"][0] > 0.0
    assert at4.values["acceleration_share"][0] == 1.0
    at5 = tangential(nc, turn(90.0, feed=20.0, tol=0.001), slow_servo(0.005))
    assert at5.values["hold_mm"][0] == 0.0
    assert at5.values["acceleration_share"][0] == 0.5
    v_b = 2.0 * math.sqrt(1000.0 * 0.001 / math.sin(math.pi / 4))
    big_a = 1 / (2 * 1000.0 * v_b) + 1 / (2 * 1000.0 * 20.0)
    assert 0.002**2 - 4 * big_a * 0.005 < 0.0
    assert at5.feed[0] == pytest.approx(v_b)


def test_a_tangent_kink_takes_its_share_off_both_accelerations(nc):
    """0.1 degree at 100 mm/s: kink (100 / 0.001 + 2000) / 2000 max(1 - cos b, sin b) =
    51 sin(0.1 deg) = 0.0890117 < 0.1: run as tangent, and LinuxCNC takes that share off
    both segments' acceleration (tcSetKinkProperties, tcGetOverallMaxAccel): 2000 (1 -
    0.0890117) = 1821.98 mm/s^2."""
    ind = tangential(nc, turn(0.1), lcnc())
    kink = 51.0 * math.sin(math.radians(0.1))
    assert ind.values["acceleration_share"][0] == pytest.approx(1.0 - kink)
    prof = nc.predict(turn(0.1), Setup(machine=lcnc(), ramps=True)).profile
    assert prof.a_up[0] == pytest.approx(2000.0 * (1.0 - kink))


def test_without_a_tolerance_a_blend_arc_deviates_a_quarter_of_the_shorter_segment(nc):
    """G64 without P (tc.c tcFindBlendTolerance): the tolerance is a quarter of the shorter
    segment, 10 / 4 = 2.5 mm at a 90 degree corner of 10 mm lines; the arc's tangent length
    sin45 2.5 / (1 - cos45) = 6.04 mm is cut to half a segment, 5 mm: R = 5 / tan45 = 5 mm,
    sqrt(2000 5) = 100 mm/s. With P0.01 the same corner: R = 0.0241421 mm, 6.95 mm/s."""
    free = tangential(nc, turn(90.0, tol=None), lcnc())
    assert free.values["radius_mm"][0] == pytest.approx(5.0)
    assert free.feed[0] == pytest.approx(100.0)
    tight = tangential(nc, turn(90.0), lcnc())
    assert tight.values["radius_mm"][0] == pytest.approx(0.0241421, rel=1e-5)


def test_a_feed_above_the_machines_runs_at_the_machines(nc):
    """F 1000 mm/s where the axes allow 500 (tcGetMaxTargetVel): the kink test at 0.02 deg
    takes 500, (500 / 0.001 + 2000) / 2000 sin(0.02 deg) = 0.087620 < 0.1: tangent (with
    F 1000 it would be 0.1749, an arc)."""
    ind = tangential(nc, turn(0.02, feed=1000.0), lcnc())
    kink = 251.0 * math.sin(math.radians(0.02))
    assert ind.values["hold_mm"][0] == 0.0
    assert ind.values["acceleration_share"][0] == pytest.approx(1.0 - kink)


def test_the_kink_test_sees_a_short_segments_length_over_one_servo_period(nc):
    """0.05 mm chords at F6000 (100 mm/s) with t_int = 1.02 ms (servo T = 1 ms): the motion
    keeps them to 0.05 / 0.00102 = 49.02 mm/s, but the kink test (tpSetupTangent, on the
    speeds tcClampVelocityByLength set when the line was added: length / T) takes
    0.05 / 0.001 = 50 mm/s. At a turn of 0.2223 deg (sin = 0.0038799):
    (50 / 0.001 + 2000) / 2000 0.0038799 = 26 x 0.0038799 = 0.100877 > 0.1, a corner; with
    49.02 mm/s it would be (49019.6 + 2000) / 2000 x 0.0038799 = 0.098975, tangent.
    (LinuxCNC 2.9 traces: drawn8's freeform_81003, 4-decimal chords whose 2-quantum turns sit
    at kink 0.0995 by the 1.02-period speeds, run as corners.)"""
    ind = tangential(nc, turn(0.2223, length=0.05, feed=100.0), lcnc())
    assert ind.values["hold_mm"][0] > 0.0  # a blend arc (its speed limit finite)
    assert ind.feed[0] < INF
    # a 0.2153 deg turn: 26 sin(0.2153 deg) = 0.097700 < 0.1, tangent
    near = tangential(nc, turn(0.2153, length=0.05, feed=100.0), lcnc())
    assert near.feed[0] == INF
    assert near.values["hold_mm"][0] == 0.0


def _overlap_time(v_b, a_p, a_n, v_n, dt=1e-6):
    """LinuxCNC's parabolic blend stepped in time (tp.c tpDoParabolicBlending, as the traces
    show it): from the blend's start, the segment before brakes from v_b to a stop at a_p
    while the one after speeds up from rest at a_n to v_n; returns the time until both are
    done (the first stopped, the second at v_n) and the distance the second has run."""
    t = x = 0.0
    v1, v2 = v_b, 0.0
    while v1 > 0.0 or v2 < v_n:
        v1 = max(v1 - a_p * dt, 0.0)
        v2n = min(v2 + a_n * dt, v_n)
        x += 0.5 * (v2 + v2n) * dt
        v2 = v2n
        t += dt
    return t, x


def _corner_time(u, v_b, a_p, a_n, v_n, x_next):
    """The same stretch (the first segment's last v_b^2 / (2 a_p), the second's first
    ``x_next``) run as a corner crossed at u: the first at v_b until it brakes to u at its
    end, the second from u up to v_n and on at v_n."""
    d_p = v_b**2 / (2 * a_p)
    brake = (v_b**2 - u**2) / (2 * a_p)
    t = (d_p - brake) / v_b + (v_b - u) / a_p
    up = (v_n**2 - u**2) / (2 * a_n)
    return t + (v_n - u) / a_n + (x_next - up) / v_n


@pytest.mark.parametrize(
    ("v_b", "a_p", "a_n", "v_n"),
    [(7.5, 1000.0, 500.0, 30.0), (2.4, 1000.0, 1000.0, 20.0), (5.7, 700.0, 1000.0, 30.0)],
)
def test_a_parabolic_blend_costs_the_time_of_its_corner_speed(v_b, a_p, a_n, v_n):
    """The corner speed that stands for a parabolic blend, against the blend stepped in time
    every microsecond: a line into a helix (thread milling: 7.5 mm/s, 1000 / 500 mm/s^2), two
    lines at a 5 ms servo period, a corner whose second segment speeds up faster. The corner
    crossed at u takes the time of the overlap to within 10 us; at u +- 10 % it does not."""
    from plugins.tangential import parabolic_time_speed

    u, gain = parabolic_time_speed(np.array([v_b]), a_p, a_n, np.array([v_n]))
    u = float(u[0])
    assert float(gain[0]) == 0.0 and 0.0 < u < v_b
    t_l, x = _overlap_time(v_b, a_p, a_n, v_n)
    assert _corner_time(u, v_b, a_p, a_n, v_n, x) == pytest.approx(t_l, abs=1e-5)
    assert abs(_corner_time(0.9 * u, v_b, a_p, a_n, v_n, x) - t_l) > 1e-4
    assert abs(_corner_time(1.1 * u, v_b, a_p, a_n, v_n, x) - t_l) > 1e-4


def test_a_helix_into_a_line_overlaps_faster_than_a_corner_at_its_blend_speed():
    """The thread milling helix into its radial line out (drawn13's unchanged
    thread_milling_131007): blend speed 5.7 mm/s, the helix braking at 500, the line speeding
    up at 1000 mm/s^2 to 30 mm/s. The corner speed that would match is above the blend speed
    (5.98: the root), so the corner is crossed at 5.7 and the overlap saves what that still
    costs, A 5.7^2 - 0.003 5.7 + 0.0114 > 0."""
    from plugins.tangential import parabolic_time_speed

    u, gain = parabolic_time_speed(np.array([5.7]), 500.0, 1000.0, np.array([30.0]))
    assert float(u[0]) == 5.7
    t_l, x = _overlap_time(5.7, 500.0, 1000.0, 30.0)
    t_c = _corner_time(5.7, 5.7, 500.0, 1000.0, 30.0, x)
    assert t_c > t_l
    assert float(gain[0]) == pytest.approx(t_c - t_l, abs=1e-5)


def test_nearly_tangent_segments_at_full_speed_overlap_faster_than_any_corner():
    """A helix into a tangent line at F3000 (the suite's 10_helix_3d_polyline): blend speed
    50 mm/s, the helix braking at 500, the line speeding up at 1000 mm/s^2. Stepped in time,
    the two are done after 100 ms, the line 3.75 mm on; a corner crossed at full speed takes
    125 ms over that path: no corner speed matches (no root), the corner is crossed at
    50 mm/s and the overlap saves the 25 ms still left (gain, not modelled)."""
    from plugins.tangential import parabolic_time_speed

    u, gain = parabolic_time_speed(np.array([50.0]), 500.0, 1000.0, np.array([50.0]))
    t_l, x = _overlap_time(50.0, 500.0, 1000.0, 50.0)
    assert t_l == pytest.approx(0.1, abs=1e-5) and x == pytest.approx(3.75, abs=1e-4)
    assert float(u[0]) == 50.0
    t_c = _corner_time(50.0, 50.0, 500.0, 1000.0, 50.0, x)
    assert t_c == pytest.approx(0.125, abs=1e-5)
    assert float(gain[0]) == pytest.approx(t_c - t_l, abs=1e-5)


THREAD_3X2 = """(thread milling pitch 2, R3.36, 3 turns, F2400, as drawn9's thread_milling_91007)
G21 G17 G90 G94
G64 P0.01 Q0
G0 X83.6208 Y72.8935 Z5
G1 X83.6208 Y72.8935 Z-7 F800
G1 X86.9796 Y72.8935 F2400
G2 X86.9796 Y72.8935 Z-1 I-3.3589 J0 P3
G1 X83.6208 Y72.8935
G0 Z5
M2
"""


@pytest.mark.parametrize(
    ("turns", "pitch", "expected"), [(3, 2.0, "sqrt"), (2, 2.0, "sqrt"), (1, 1.0, 0.5)]
)
def test_linuxcnc_helix_tangential_share(tmp_path, turns, pitch, expected):
    """LinuxCNC's share of a helix's acceleration for speed changes along it
    (tcUpdateCircleAccRatio, pmCircleActualMaxVel), on the preset's mill (2000 mm/s^2,
    250 mm/s per axis). Canon: v_pl = sqrt(sqrt(3)/2 2000 3.3589) = 76.28 mm/s; S = 3.3589 2 pi
    turns, L = hypot(S, rise); v = L / (S / 76.28) (the end point's straight-line time, the
    rise at 250 mm/s, is shorter); a = L / (S / 2000). Both junctions parabolic: a_o = a / 2.
    LinuxCNC's helix radius over the whole rise, R_e = rise^2 / 3.3589 + 3.3589:
    - 3 turns of pitch 2 (drawn9's thread milling): rise 6, R_e = 14.077, a_n = v^2 / R_e =
      417 < a_o / 2 (502): share sqrt(1 - (a_n / a_o)^2) = 0.910 (the trace: 913 mm/s^2 of the
      1000 the halved acceleration leaves);
    - two turns of pitch 2: rise 4, R_e = 8.122, a_n = 723, between a_o / 2 and the cutoff
      sqrt(3)/2 a_o = 870 (blendmath.h BLEND_ACC_RATIO_NORMAL): share
      sqrt(1 - (723 / 1004.6)^2) = 0.694, not 0.5;
    - one turn of pitch 1: R_e = 3.6566, a_n = 1595 > sqrt(3)/2 a_o: 0.5.
    The profile's helix acceleration is the lowest axis's over its share times the preset's
    arc factor 0.5, the parabolic 0.5, and the share over 0.5."""
    from core import Ncperf, load_preset
    from core.engine.effects import setup_for

    text = THREAD_3X2.replace("Z-1 I", f"Z{-7 + turns * pitch:g} I").replace("P3", f"P{turns}")
    prog = tmp_path / "thread.ngc"
    prog.write_text(text)
    ncp = Ncperf()
    tp = ncp.extract(str(prog))
    m = load_preset("linuxcnc-sim")
    r, rise = 3.3589, turns * pitch
    s_len = r * 2 * math.pi * turns
    length = math.hypot(s_len, rise)
    v = length / (s_len / math.sqrt(math.sqrt(3) / 2 * 2000.0 * r))
    a_o = length / (s_len / 2000.0) / 2
    a_n = v * v / (rise * rise / r + r)
    share = math.sqrt(1 - (a_n / a_o) ** 2) if expected == "sqrt" else 0.5
    if (turns, pitch) == (3, 2.0):
        assert a_n < a_o / 2 and share == pytest.approx(0.909, abs=0.002)
    elif expected == "sqrt":
        assert a_o / 2 < a_n < math.sqrt(3) / 2 * a_o and share == pytest.approx(0.694, abs=0.002)
    else:
        assert a_n > math.sqrt(3) / 2 * a_o
    k = int(np.flatnonzero(tp.is_arc)[0])
    prof = ncp.predict(tp, setup_for(m, ncp.effects())).profile
    # the helix's tangential acceleration: lowest axis over its shares, the preset's 0.5, the
    # parabolic blends' 0.5, and LinuxCNC's share over 0.5
    from plugins.feed_limit import lowest_axis

    a_axes = lowest_axis(tp.axis_share, np.array([k]), np.asarray(m.max_acceleration))[0][0]
    assert prof.a_up[k] == pytest.approx(a_axes * 0.5 * 0.5 * share / 0.5, rel=1e-3)
    # A path speed limit of 40 mm/s (under v) leaves the share as it was: LinuxCNC sets the
    # segment's maxvel from canon's v (tcSetupMotion) and the limit (the planner's vLimit)
    # clips only the speed it runs at (tpGetRealTargetVel). Were v capped at 40, a_n would
    # be 1600 / 14.077 = 114 and the share 0.994.
    capped = dataclasses.replace(m, max_path_feed=40.0)
    prof40 = ncp.predict(tp, setup_for(capped, ncp.effects())).profile
    assert prof40.a_up[k] == pytest.approx(a_axes * 0.5 * 0.5 * share / 0.5, rel=1e-3)


def test_the_blend_plane_acceleration_is_the_inscribed_circle_of_the_axis_limits():
    """LinuxCNC 2.9's acceleration in a blend's plane (blendmath.c
    calculateInscribedDiameter with the plane's unit normal n): min over the axes of
    A_k / sqrt(1 - n_k^2), the length of the axis's unit vector projected onto the plane.
    X, Y 2000 and Z 870 mm/s^2:
    - a dome's raster corner, (0.928, 0, 0.371) into +Y: n = (-0.371, 0, 0.928), X 2000 /
      0.928 = 2154, Y 2000 / 1, Z 870 / 0.371 = 2345: 2000 (Y), though the plane moves Z;
    - (1, 0, 0) into (0, 0.6, 0.8): n = (0, -0.8, 0.6), X 2000, Y 2000 / 0.6 = 3333, Z
      870 / 0.8 = 1087.5 (Z);
    - an axis-aligned plane, +X into +Y: n = +Z, Z's projection nil: min(X, Y) = 2000 (X);
    - parallel directions (no plane): the lowest limit of the axes moved."""
    from plugins.tangential import plane_acceleration

    acc = np.array([2000.0, 2000.0, 870.0])
    u = np.array([0.928, 0.0, 0.371])
    u = u / np.linalg.norm(u)
    t1 = np.array([u, [1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.6, 0.0, 0.8]])
    t2 = np.array([[0.0, 1.0, 0.0], [0.0, 0.6, 0.8], [0.0, 1.0, 0.0], [0.6, 0.0, 0.8]])
    a, axis = plane_acceleration(t1, t2, acc)
    n0 = np.cross(u, [0.0, 1.0, 0.0])
    expected0 = min(2000.0 / math.sqrt(1 - n0[0] ** 2), 2000.0, 870.0 / math.sqrt(1 - n0[2] ** 2))
    assert expected0 == pytest.approx(2000.0)
    assert a == pytest.approx([expected0, 1087.5, 2000.0, 870.0], rel=1e-12)
    assert axis.tolist() == [1, 2, 0, 2]


def test_the_path_speed_limit_does_not_plan_the_blend(nc):
    """The path speed limit ([TRAJ]MAX_LINEAR_VELOCITY) clips only the speed a segment runs
    at (tp.c tpGetRealTargetVel); the blend is planned with the segment's own top speed
    (blendmath.c blendParamKinematics, tcGetMaxTargetVel). The 90 degree turn at F 5 above
    (R_plan 0.0159155 mm, half the arc 0.0125 mm) stays as it is under a 3 mm/s limit;
    planned with 3 mm/s it would be s = min(6.95, 3) / 1000 x 3 = 0.009 mm, R_plan =
    max(3^2 / 2000, 0.009 / (pi / 2)) = 0.0057296 mm."""
    capped = dataclasses.replace(lcnc(), max_path_feed=3.0)
    ind = tangential(nc, turn(90.0, feed=5.0), capped)
    assert ind.values["hold_mm"][0] == pytest.approx(0.0159155, rel=1e-5)
    assert ind.values["travel_mm"][0] == pytest.approx(0.0125, rel=1e-5)
    assert ind.feed[0] == pytest.approx(math.sqrt(2000 * 0.0241421), rel=1e-5)


def chords(first_deg, turn_deg, length=0.05, feed=100.0, tol=0.01):
    """Two lines of ``length`` mm in XY, the first at ``first_deg`` from X, the second
    turned by ``turn_deg``."""
    a0, a1 = math.radians(first_deg), math.radians(first_deg + turn_deg)
    p1 = (length * math.cos(a0), length * math.sin(a0), 0.0)
    p2 = (p1[0] + length * math.cos(a1), p1[1] + length * math.sin(a1), 0.0)
    return g64([{"end": p1}, {"end": p2}], feed=feed, tol=tol)


def test_the_kink_test_adds_the_next_lines_own_acceleration(nc):
    """tpSetupTangent's a_inst = v_max / T + tc->maxaccel, tc the line being added: its
    path acceleration from canon (getStraightAcceleration), min_k A_k / |t_k|, above every
    axis's 2000 off the axes. 0.05 mm chords at F6000 (v_max 0.05 / 0.001 = 50 mm/s):
    - 45.309 -> 45.614 deg: |t2 - t1| = (0.0037943, 0.0037337), the second line's
      acceleration 2000 / sin(45.614 deg) = 2798.60; kink 0.0037943 (50000 + 2798.60) /
      2000 = 0.100167 > 0.1: a corner (with the plane's 2000: 0.098652, tangent);
    - 45.305 -> 45.0 deg: (0.0037741, 0.0037541), 2000 / sin 45 = 2828.43; kink
      0.0037741 x 52828.43 / 2000 = 0.099690 < 0.1: tangent.
    LinuxCNC 2.9 ran both as said (tests/test_linuxcnc_planner_traces.py records them)."""
    corner = tangential(nc, chords(45.309, 0.305), lcnc())
    assert corner.values["hold_mm"][0] > 0.0
    assert corner.feed[0] < INF
    kink = tangential(nc, chords(45.305, -0.305), lcnc())
    assert kink.feed[0] == INF
    assert kink.values["hold_mm"][0] == 0.0
    assert kink.values["acceleration_share"][0] == pytest.approx(1.0 - 0.099690, abs=2e-6)


def test_past_a_reached_limit_the_arc_runs_at_it_to_its_end(nc):
    """A 5 mm line along X, a 0.2 mm chord turned by 14 deg, a 10 mm line turned by 13 deg
    more, and 10 mm on: both corners' arcs take half the chord (d = 0.1 mm; the tolerance
    would allow 0.16 and 0.18), R = 0.1 / tan 7deg = 0.81443 and 0.1 / tan 6.5deg = 0.87769
    mm, limits sqrt(2000 R) = 40.359 and 41.897 mm/s. From the first arc's end (the chord's
    middle, 40.359) the speed climbs along the second arc at half the acceleration, 1000
    mm/s^2: 41.580 after 0.05 mm, the limit 41.897 at the corner. LinuxCNC runs the arc as a
    segment whose top speed is its limit (tests/test_linuxcnc_planner_traces.py): along its
    other half, the first 0.1 mm of the line, the speed stays 41.897; then the line's own
    acceleration, 2000 / cos 27deg = 2244.7 mm/s^2: sqrt(41.897^2 + 2 x 2244.7 x 0.05) =
    44.495 at 0.15 mm. (Before, the arc's far half was left to climb: 44.34 at 0.1 mm.)"""
    ang = math.radians(14.0)
    p1 = (5.0 + 0.2 * math.cos(ang), 0.2 * math.sin(ang), 0.0)
    ang += math.radians(13.0)
    p2 = (p1[0] + 10 * math.cos(ang), p1[1] + 10 * math.sin(ang), 0.0)
    p3 = (p2[0] + 10 * math.cos(ang), p2[1] + 10 * math.sin(ang), 0.0)
    tp = g64([{"end": (5.0, 0.0, 0.0)}, {"end": p1}, {"end": p2}, {"end": p3}])
    prof = nc.predict(tp, Setup(machine=lcnc(), ramps=True)).profile
    corner = 5.2
    v = prof.speed_at(corner + np.array([-0.1, -0.05, 0.0, 0.05, 0.1, 0.15]))
    v_a = math.sqrt(2000 * 0.1 / math.tan(math.radians(7)))
    v_b = math.sqrt(2000 * 0.1 / math.tan(math.radians(6.5)))
    assert v[0] == pytest.approx(v_a, rel=1e-9)
    assert v[1] == pytest.approx(math.sqrt(v_a**2 + 2 * 1000 * 0.05), rel=1e-9)
    assert v[2:5] == pytest.approx([v_b] * 3, rel=1e-9)
    a_line = 2000 / math.cos(math.radians(27))
    assert v[5] == pytest.approx(math.sqrt(v_b**2 + 2 * a_line * 0.05), rel=1e-9)
