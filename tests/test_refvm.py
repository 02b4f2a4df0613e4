"""The reference interpreter (refvm): motion, effects, agreement with ncperf, independence.

Expected numbers are worked out by hand in each test; ncperf's own profile is used only in
the cycle-time agreement test, as the thing compared. ncperf reads the programs (its
adapters) and the machines; the interpreter imports nothing of it.
"""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys

import numpy as np
import pytest

from core import load_preset
from core.engine.profile import build_profile
from refvm import EFFECT_DOCS, EFFECTS, simulate, stop_distance
from tests.conftest import ROOT, machine, path, shared

INF = float("inf")
DT = 0.001


def lcnc(**kw):
    """LinuxCNC-like: 15 m/min, 2 m/s^2 per axis, no jerk limit, t_int 1.02 ms, TIT 0.01."""
    args = {"feed": (15.0,) * 3, "acc": (2.0,) * 3, "jerk": (INF,) * 3, "t_int": 0.00102}
    args.update(kw)
    return machine(**args)


def plateau(trace, s_lo, s_hi):
    """Speeds of the samples whose arc length is in (s_lo, s_hi)."""
    return trace.v[(trace.s > s_lo) & (trace.s < s_hi)]


# 90 deg corner, TIT 0.01 mm: R = 0.01 cos45 / (1 - cos45) = 0.0241421356 mm (eq. 1).
R90 = 0.01 * math.cos(math.pi / 4) / (1 - math.cos(math.pi / 4))
CORNER = [{"end": (20, 0, 0)}, {"end": (20, 20, 0)}]


# ----------------------------------------------------------------------------- motion
def test_single_line_is_an_almost_trapezoid(nc):
    """100 mm at F6000, A 2 m/s^2, J 1000 m/s^3: T = L/F + F/A = 1.05 s (+ A/J = 2 ms)."""
    # Each ramp: dv/A + A/J = 0.05 + 0.002 s over 100/2 * 0.052 = 2.6 mm; cruise 94.8 mm at
    # 100 mm/s = 0.948 s; total 1.052 s.
    m = machine(acc=(2.0,) * 3, jerk=(1000.0,) * 3)
    tr = simulate(path([{"end": (100, 0, 0)}], feed=100.0), m)
    assert tr.cycle_time == pytest.approx(1.05, rel=0.01)
    assert tr.cycle_time == pytest.approx(1.052, abs=DT)
    assert tr.v[0] == 0.0 and tr.v[-1] == 0.0
    assert tr.x[0] == 0.0 and tr.x[-1] == pytest.approx(100.0, abs=1e-9)
    assert np.all(np.diff(tr.x) >= 0)
    assert np.all(tr.y == 0.0) and np.all(tr.z == 0.0)
    assert set(tr.line.tolist()) == {1}


def test_no_chatter_at_the_cap(nc):
    """Between the ramps the speed is exactly F with zero acceleration, every cycle."""
    m = machine(acc=(2.0,) * 3, jerk=(1000.0,) * 3)
    tr = simulate(path([{"end": (100, 0, 0)}], feed=100.0), m)
    cruise = plateau(tr, 2.7, 97.3)  # past the 2.6 mm ramps
    assert cruise.size > 900
    assert np.all(cruise == 100.0)


def test_positions_follow_arcs(nc):
    """On a G3 semicircle of R 2 about (10, 2) every sample is 2 mm from the centre."""
    tp = path(
        [
            {"end": (10, 0, 0)},
            {"end": (10, 4, 0), "center": (10, 2, 0), "ccw": True},
            {"end": (0, 4, 0)},
        ],
        feed=100.0,
    )
    tr = simulate(tp, lcnc())
    on_arc = tr.move == 1
    r = np.hypot(tr.x[on_arc] - 10, tr.y[on_arc] - 2)
    assert on_arc.sum() > 50
    assert r == pytest.approx(2.0, abs=1e-9)
    assert np.all(tr.x[on_arc] >= 10 - 1e-9)  # counter-clockwise from (10, 0): the +X side


def test_corner_minimum_speed_equals_the_junction_feed(nc):
    """90 deg corner with jerk (840D values): the sampled minimum is cbrt(J R^2) = 1.4284 mm/s
    within 2 %, and ncperf's junction feed is that value."""
    # cbrt(5000 * 0.0241421^2) = cbrt(2.914214) = 1.428369; sqrt(A R) = 7.77 and F = 100 are
    # higher. The S-curve lands with zero acceleration: the samples around it are within
    # J dt^2 / 2 = 0.0025 mm/s of it.
    m = machine()
    tp = path(CORNER, feed=100.0)
    want = (5000 * R90**2) ** (1 / 3)
    tr = simulate(tp, m)
    ev = nc.evaluate(tp, m)
    assert ev.junction_feed[0] == pytest.approx(want, rel=1e-6)
    near = plateau(tr, 15, 25)
    assert near.min() == pytest.approx(want, rel=0.02)
    assert tr.boundary_speed[1] == pytest.approx(want, rel=1e-3)


def test_corner_without_jerk_limit_is_passed_at_the_junction_feed(nc):
    """No jerk limit: the corner is passed at sqrt(A R) = 6.9487 mm/s (between two samples);
    the sampled minimum is at most A dt = 2 mm/s above it (documented behaviour)."""
    # sqrt(2000 * 0.0241421) = 6.948688
    want = math.sqrt(2000 * R90)
    tr = simulate(path(CORNER, feed=100.0), lcnc())
    assert tr.boundary_speed[1] == pytest.approx(want, rel=1e-3)
    low = plateau(tr, 15, 25).min()
    assert want - 1e-6 <= low <= want + 2000 * DT


def test_acceleration_and_jerk_stay_within_the_limits(nc):
    """On the Fig. 1 polygons (840D preset) every cycle keeps |a| <= A and, away from stops,
    |da/dt| <= J of the moves involved."""
    m = load_preset("siemens-840d")
    tr = simulate(nc.extract(str(ROOT / "examples" / "fig1_polygons_F4000.ngc")), m)
    lim = tr.setup.limits  # per segment (moves, and the arcs inserted at corners)
    a = np.diff(tr.v) / DT
    mv = tr.segment
    acc = np.maximum(lim.acc[mv[:-1]], lim.acc[mv[1:]])
    assert np.all(np.abs(a) <= acc * (1 + 1e-9))
    j = np.diff(a) / DT
    jerk = np.maximum.reduce([lim.jerk[mv[:-2]], lim.jerk[mv[1:-1]], lim.jerk[mv[2:]]])
    # a stop and a restart inside one cycle show as a kink of the per-cycle mean acceleration
    moving = np.minimum.reduce([tr.v[:-2], tr.v[1:-1], tr.v[2:]]) > 0.05
    assert np.all(np.abs(j[moving]) <= jerk[moving] * (1 + 1e-6))
    assert tr.violation < 1e-3


def test_dwell_and_exact_stop(nc, tmp_path):
    """G4 P0.25 rests 0.25 s at the end of its line; G61 blocks end at rest."""
    prog = tmp_path / "stops.ngc"
    prog.write_text("G21 G90 G17 G94 G64\nG1 X10 F3000\nG4 P0.25\nG1 Y10\nG61\nG1 X0\nG1 Y0\nM2\n")
    tr = simulate(nc.extract(str(prog)), lcnc())
    # moves: X10 (line 2), Y10 (4), X0 (6, G61), Y0 (7, G61)
    corner = pytest.approx(math.sqrt(2000 * R90), rel=1e-4)
    assert tr.boundary_speed.tolist() == [0.0, 0.0, corner, 0.0, 0.0]
    resting = (tr.v == 0) & (tr.line == 2) & (tr.t > 0)  # t = 0: rest before the start
    assert resting.sum() * DT == pytest.approx(0.25, abs=2 * DT)
    assert tr.x[resting] == pytest.approx(10.0)
    assert tr.line[0] == 2 and tr.line[-1] == 7


def test_stop_distance_closed_forms():
    """Braking distances: (v^2 - w^2) / 2A without jerk; v * sqrt(v / J) for 0 -> rest with
    A never reached; 0 when already slow enough."""
    # trapezoid: (100^2 - 20^2) / (2 * 2000) = 2.4 mm
    assert stop_distance(100.0, 0.0, 20.0, 2000.0, INF) == pytest.approx(2.4)
    # S-curve from a = 0 to rest, A^2/J = 1250 > 100: T = 2 sqrt(100/5000), D = v/2 T
    want = 50.0 * 2 * math.sqrt(100.0 / 5000.0)
    assert stop_distance(100.0, 0.0, 0.0, 2500.0, 5000.0) == pytest.approx(want)
    # A reached (J 50000, A 2500: A^2/J = 125 < 400): T = 400/2500 + 2500/50000 = 0.21 s
    assert stop_distance(400.0, 0.0, 0.0, 2500.0, 50000.0) == pytest.approx(200 * 0.21)
    assert stop_distance(10.0, -50.0, 20.0, 2500.0, 5000.0) == 0.0


# ----------------------------------------------------------------------------- effects
def test_feed_override_scales_the_plateau(nc):
    """feed_override 0.8: the plateau of a 100 mm line at F6000 is 80 mm/s."""
    tp = path([{"end": (100, 0, 0)}], feed=100.0)
    tr = simulate(tp, lcnc(), "feed_override", {"scale": 0.8})
    assert plateau(tr, 10, 90) == pytest.approx(80.0)


def test_block_cycle_time_doubled_halves_the_short_block_plateau(nc):
    """1 mm blocks at F10000, t_int 12 ms: l / t_int = 83.3 mm/s; t_block 24 ms: 41.7 mm/s."""
    moves = [{"end": (i + 1, 0, 0)} for i in range(60)] + [{"end": (90, 0, 0)}]
    tp = path(moves, feed=10000 / 60)
    m = machine()
    base = simulate(tp, m)
    slow = simulate(tp, m, "block_cycle_time", {"t_block": 0.024})
    assert np.median(plateau(base, 20, 50)) == pytest.approx(1 / 0.012)
    assert np.median(plateau(slow, 20, 50)) == pytest.approx(1 / 0.024)
    assert slow.cycle_time > base.cycle_time


def test_lookahead_depth_one_caps_collinear_blocks(nc):
    """0.5 mm collinear blocks at F6000, A 2000: seeing one block ahead bounds every block end
    by sqrt(2 A l) = 44.72 mm/s (peaks sqrt(3 A l) = 54.77 mid-block); 20 blocks see 10 mm
    (sqrt(2 A 10) = 200 > F): full feed."""
    tp = path([{"end": (0.5 * (i + 1), 0, 0)} for i in range(100)], feed=100.0)
    one = simulate(tp, lcnc(), "lookahead_depth", {"blocks": 1})
    full = simulate(tp, lcnc(), "lookahead_depth", {})
    assert one.boundary_speed[20:80].max() == pytest.approx(math.sqrt(2 * 2000 * 0.5), rel=1e-3)
    assert plateau(one, 10, 40).max() <= math.sqrt(3 * 2000 * 0.5) * (1 + 1e-3)
    assert plateau(full, 10, 40) == pytest.approx(100.0)
    assert one.cycle_time > full.cycle_time


def test_corner_tolerance_scales_the_corner_radius(nc):
    """TIT 0.04 instead of 0.01: R x 4, so sqrt(A R) doubles: 13.897 mm/s."""
    tp = path(CORNER, feed=100.0)
    tr = simulate(tp, lcnc(), "corner_tolerance", {"tolerance": 0.04})
    assert tr.boundary_speed[1] == pytest.approx(2 * math.sqrt(2000 * R90), rel=1e-3)


def test_normal_acceleration_factor_only_slows_corners(nc):
    """factor 0.5: the corner is passed at sqrt(0.5 A R) = 4.9135 mm/s; a straight line keeps
    the full tangential acceleration (same time)."""
    tp = path(CORNER, feed=100.0)
    tr = simulate(tp, lcnc(), "normal_acceleration_factor", {"factor": 0.5})
    assert tr.boundary_speed[1] == pytest.approx(math.sqrt(0.5 * 2000 * R90), rel=1e-3)
    line = path([{"end": (100, 0, 0)}], feed=100.0)
    a = simulate(line, lcnc())
    b = simulate(line, lcnc(), "normal_acceleration_factor", {"factor": 0.5})
    assert b.cycle_time == a.cycle_time


def test_normal_acceleration_factor_caps_programmed_arcs(nc):
    """factor 0.5 on an R 2 semicircle at F6000: v <= sqrt(0.5 A R) = 44.72 mm/s on the arc."""
    tp = path(
        [
            {"end": (10, 0, 0)},
            {"end": (10, 4, 0), "center": (10, 2, 0), "ccw": True},
            {"end": (0, 4, 0)},
        ],
        feed=100.0,
    )
    tr = simulate(tp, lcnc(), "normal_acceleration_factor", {"factor": 0.5})
    assert plateau(tr, 10.5, 10 + 2 * math.pi - 0.5) == pytest.approx(math.sqrt(0.5 * 2000 * 2))


def test_corner_tolerance_replaces_the_program_tolerance(nc, tmp_path):
    """With G64 P0.01 in the program, tolerance 0.04 still gives R x 4: 13.897 mm/s."""
    prog = tmp_path / "corner.ngc"
    prog.write_text("G21 G90 G17 G94 G64 P0.01\nG1 X20 F6000\nG1 Y20\nM2\n")
    base = simulate(nc.extract(str(prog)), lcnc())
    tr = simulate(nc.extract(str(prog)), lcnc(), "corner_tolerance", {"tolerance": 0.04})
    assert base.boundary_speed[1] == pytest.approx(math.sqrt(2000 * R90), rel=1e-3)
    assert tr.boundary_speed[1] == pytest.approx(2 * math.sqrt(2000 * R90), rel=1e-3)


def test_corner_is_cut_by_the_inserted_arc(nc):
    """At a 90 deg corner the path runs on the arc of eq. (1): it passes TIT = 0.01 mm inside
    the corner point, at the junction feed over the arc's length R pi / 2."""
    m = machine()
    tr = simulate(path(CORNER, feed=100.0), m)
    gap = np.hypot(tr.x - 20, tr.y).min()
    # the arc's middle is R / cos45 - R = 0.01 mm from the corner (the samples miss it by at
    # most half a cycle at 1.43 mm/s, under 1 um)
    assert gap == pytest.approx(0.01, abs=1e-3)
    assert gap >= 0.01 - 1e-9
    w = (5000 * R90**2) ** (1 / 3)
    on_arc = tr.setup.segments.blend[tr.segment] >= 0
    assert on_arc.sum() * DT == pytest.approx(R90 * math.pi / 2 / w, abs=2 * DT)
    assert tr.v[on_arc] == pytest.approx(w, rel=1e-3)


def test_arc_feed_limit_caps_programmed_arcs(nc):
    """R 2 semicircle at F6000, A 2000: v <= sqrt(A R / 1) = 63.246 mm/s on the arc only."""
    tp = path(
        [
            {"end": (10, 0, 0)},
            {"end": (10, 4, 0), "center": (10, 2, 0), "ccw": True},
            {"end": (0, 4, 0)},
        ],
        feed=100.0,
    )
    base = simulate(tp, lcnc())
    capped = simulate(tp, lcnc(), "arc_feed_limit")
    arc = (capped.s > 10.5) & (capped.s < 10 + 2 * math.pi - 0.5)
    assert capped.v[arc] == pytest.approx(math.sqrt(2000 * 2))
    assert plateau(base, 10.5, 10 + 2 * math.pi - 0.5) == pytest.approx(100.0)


def test_axis_dynamics_scales_the_ramps(nc):
    """accel_scale 2 on 100 mm at F6000 without jerk limit: T = L/F + F/(2A) = 1.025 s."""
    tp = path([{"end": (100, 0, 0)}], feed=100.0)
    tr = simulate(tp, lcnc(), "axis_dynamics", {"accel_scale": 2.0})
    assert tr.cycle_time == pytest.approx(1.025, abs=DT)


def test_axis_dynamics_feed_scale_caps_axis_speed_not_path_speed(nc):
    """feed_scale 0.2 on 250 mm/s axes: 50 mm/s per axis, under F = 100 mm/s. Along X the tool
    runs at 50 mm/s; on a line at 30 deg to X at min(50 / cos 30, 50 / sin 30) = 57.74 mm/s."""
    c, s = math.cos(math.pi / 6), math.sin(math.pi / 6)
    along = path([{"end": (100, 0, 0)}], feed=100.0)
    slant = path([{"end": (100 * c, 100 * s, 0)}], feed=100.0)
    tr_a = simulate(along, lcnc(), "axis_dynamics", {"feed_scale": 0.2})
    tr_s = simulate(slant, lcnc(), "axis_dynamics", {"feed_scale": 0.2})
    assert np.max(tr_a.v) == pytest.approx(50.0, rel=1e-6)
    assert np.median(plateau(tr_s, 20, 80)) == pytest.approx(50.0 / c, rel=1e-6)


def test_servo_lag_positions_lag_by_v_tau(nc):
    """tau 20 ms at 100 mm/s on a straight line: the actual position is v tau = 2 mm behind the
    setpoint; its speed is still 100 mm/s; the trace is actual and longer."""
    tp = path([{"end": (100, 0, 0)}], feed=100.0)
    setpoint = simulate(tp, lcnc())
    actual = simulate(tp, lcnc(), "servo_lag", {"tau": 0.02})
    assert actual.kind == "actual"
    k = 500  # t = 0.5 s, mid-plateau (ramps end at 0.05 s, the lag settles in ~5 tau)
    assert setpoint.x[k] - actual.x[k] == pytest.approx(2.0, rel=1e-3)
    assert actual.v[k] == pytest.approx(100.0, rel=1e-6)
    assert actual.cycle_time > setpoint.cycle_time
    assert actual.x[-1] == pytest.approx(100.0, abs=1e-3)
    with pytest.raises(ValueError, match="servo_lag"):
        simulate(tp, lcnc(), "servo_lag", {"tau": 0.02}, kind="setpoint")


def test_jerk_filter_smooths_and_delays(nc):
    """window 50 ms: the trace is 49 cycles longer, the plateau is unchanged, and 10 ms in the
    smoothed speed is far below the unfiltered A t = 20 mm/s."""
    tp = path([{"end": (100, 0, 0)}], feed=100.0)
    base = simulate(tp, lcnc())
    tr = simulate(tp, lcnc(), "jerk_filter", {"window": 0.05})
    assert tr.t.size == base.t.size + 49
    assert tr.v[500] == pytest.approx(100.0)
    assert base.v[10] == pytest.approx(20.0)
    # causal mean over 50 samples of x = A t^2 / 2: speed about A t^2 / (2 window) = 2 mm/s
    assert tr.v[10] < 5.0
    assert tr.x[-1] == pytest.approx(100.0)


def test_path_compression_lifts_block_time_and_chord_corners(nc):
    """1 mm collinear blocks at F10000 (t_int 12 ms: 83.3 mm/s) merged into one 60 mm spline
    reach F = 166.7 mm/s; 1 mm chords turning 2.9 deg lose their corner limits."""
    moves = [{"end": (i + 1, 0, 0)} for i in range(60)] + [{"end": (90, 0, 0)}]
    tp = path(moves, feed=10000 / 60)
    tr = simulate(tp, machine(), "path_compression", {})
    assert plateau(tr, 20, 58).max() == pytest.approx(10000 / 60)
    # 1 mm chords of a circle R 12.7 mm turn by b = 2 asin(0.5 / 12.7) = 4.512 deg < 5 deg;
    # eq. (1): R = min(0.01 cos(b/2) / (1 - cos(b/2)), l / (2 sin(b/2)) - 0.01)
    #            = min(12.89, 12.69) = 12.69 mm; sqrt(A R) = 159.3 mm/s < F 200 where the
    # inserted arc's normal is along one axis (elsewhere A / max|n_k| is higher).
    ang = 2 * math.asin(0.5 / 12.7)
    r_corner = min(0.01 * math.cos(ang / 2) / (1 - math.cos(ang / 2)), 12.7 - 0.01)
    pts = [(12.7 * math.sin(k * ang), 12.7 - 12.7 * math.cos(k * ang), 0.0) for k in range(1, 40)]
    chords = path([{"end": p} for p in pts], feed=200.0)
    base = simulate(chords, lcnc())
    merged = simulate(chords, lcnc(), "path_compression", {})
    inner = slice(10, 30)
    assert base.boundary_speed[inner].min() == pytest.approx(math.sqrt(2000 * r_corner), rel=1e-3)
    assert base.boundary_speed[inner].max() < 190.0
    assert merged.boundary_speed[inner] == pytest.approx(200.0)


@pytest.mark.parametrize(
    ("effect", "params", "match"),
    [
        ("warp_drive", {}, "unknown effect"),
        ("feed_override", {"factor": 1.0}, "unknown parameter"),
        ("feed_override", {"scale": 2.0}, "outside"),
        ("servo_lag", {"tau": -0.1}, "outside"),
        ("lookahead_depth", {"blocks": 2.5}, "whole number"),
        ("arc_feed_limit", {"scale": 1.0}, "unknown parameter"),
        ("jerk_filter", {"window": "long"}, "must be a number"),
        (None, {"scale": 1.0}, "without an effect"),
    ],
    ids=["unknown", "bad-param", "above", "below", "fraction", "no-params", "text", "no-effect"],
)
def test_bad_effect_requests_raise(nc, effect, params, match):
    """Unknown effects and parameters, and values out of bounds, raise ValueError."""
    with pytest.raises(ValueError, match=match):
        simulate(path(CORNER, feed=100.0), lcnc(), effect, params)


def test_effects_table_is_consistent():
    """Every effect has (low, high, default) rows with low < high, the default inside (or None
    for the machine's value), and a documented semantics."""
    assert set(EFFECT_DOCS) == set(EFFECTS)
    assert len(EFFECTS) == 10
    for table in EFFECTS.values():
        for low, high, default in table.values():
            assert low < high
            assert default is None or low <= default <= high


# ----------------------------------------------------------------------------- ncperf
@pytest.mark.parametrize("preset", ["linuxcnc-sim", "siemens-840d"])
@pytest.mark.parametrize(
    "program",
    ["fig1_polygons_F4000", "fig3_semicircle_spiral", "fig4_points_d1", "zlevel_cavity"],
)
def test_cycle_time_agrees_with_ncperf(nc, program, preset):
    """Without effect the reference interpreter's cycle time is ncperf's prediction within 2 %.
    The reference interpreter runs the paper's corners with the machine's TIT where the
    program sets no tolerance; LinuxCNC has no machine tolerance (G64 without P: a quarter of
    the shorter segment, which ncperf's linuxcnc-sim follows), so there both get the TIT as
    G64 P."""
    m = load_preset(preset)
    tp = nc.extract(str(ROOT / "examples" / f"{program}.ngc"))
    if preset == "linuxcnc-sim":
        tol = np.where(np.isnan(tp.tolerance), m.path_tolerance, tp.tolerance)
        tp = dataclasses.replace(tp, tolerance=tol)
    tr = simulate(tp, m)
    predicted = build_profile(nc.evaluate(tp, m)).cycle_time
    assert tr.cycle_time == pytest.approx(predicted, rel=0.02)


def test_command_line_writes_a_linuxcnc_style_trace(tmp_path):
    """benchmarks/vm_trace.py writes t,x,y,z,v,line, the first columns of the LinuxCNC suite
    traces; an effect value out of bounds is exit 2."""
    out = tmp_path / "trace.csv"
    prog = ROOT / "examples" / "fig4_points_d1.ngc"
    script = ROOT / "benchmarks" / "vm_trace.py"
    args = [sys.executable, str(script), str(prog), str(out), "--machine", "linuxcnc-sim"]
    args += ["--effect", "feed_override"]
    done = subprocess.run([*args, "--param", "scale=0.9"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    lines = out.read_text().splitlines()
    assert lines[0] == "t,x,y,z,v,line"
    first = lines[1].split(",")
    assert float(first[0]) == 0.0 and float(first[4]) == 0.0
    bad = subprocess.run([*args, "--param", "scale=3"], capture_output=True, text=True)
    assert bad.returncode == 2 and "outside" in bad.stderr
    suite = shared("data", "linuxcnc", "suite", "01_polygons_f2000.csv")
    with open(suite) as fh:
        assert fh.readline().startswith(lines[0] + ",")


# ----------------------------------------------------------------------------- independence
CHECKED = ("core", "adapters", "plugins")


def test_refvm_imports_nothing_it_checks():
    """No module of refvm imports core, adapters or plugins, by its source (every import
    statement, also inside functions) or at run time (a fresh interpreter importing every
    refvm module has none of them loaded)."""
    import ast

    offenders = []
    for src in sorted((ROOT / "refvm").glob("*.py")):
        for node in ast.walk(ast.parse(src.read_text(), str(src))):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            offenders += [f"{src.name}: {n}" for n in names if n.split(".")[0] in CHECKED]
    assert offenders == []
    code = (
        "import importlib, pkgutil, sys, refvm\n"
        "for m in pkgutil.iter_modules(refvm.__path__):\n"
        "    importlib.import_module('refvm.' + m.name)\n"
        f"print(sorted(k for k in sys.modules if k.split('.')[0] in {CHECKED!r}))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert done.stdout.strip() == "[]"
