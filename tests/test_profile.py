"""The feed profile and cycle time (issue 4), against closed forms worked out by hand."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from core.engine.profile import build_profile, effective_acceleration
from tests.conftest import machine, path

INF = float("inf")


def profile(models, moves, feed=100.0, **mach):
    tp = path(moves, feed=feed)
    return build_profile(models.evaluate(tp, machine(**mach)))


def test_long_line_trapezoid(models):
    """100 mm at 100 mm/s, A 2500 mm/s^2, no jerk limit: T = L/F + F/A = 1.04 s."""
    pr = profile(models, [{"end": (100, 0, 0)}], jerk=(INF, INF, INF))
    assert pr.cycle_time == pytest.approx(1.04, rel=1e-12)
    assert pr.v_peak[0] == pytest.approx(100.0)


def test_long_line_s_curve_reaching_the_acceleration(models):
    """1000 mm at 400 mm/s, A 2500, J 50000 mm/s^3: A^2/J = 125 < 400, so each ramp takes
    dv/A + A/J = 0.16 + 0.05 = 0.21 s over 200 * 0.21 = 42 mm: T = 2.5 + 0.21 = 2.71 s."""
    pr = profile(models, [{"end": (1000, 0, 0)}], feed=400.0, jerk=(50.0, 50.0, 50.0))
    assert pr.cycle_time == pytest.approx(2.71, rel=1e-9)


def test_long_line_s_curve_never_reaching_the_acceleration(models):
    """100 mm at 100 mm/s, A 2500, J 5000 (the 840D preset): A^2/J = 1250 > 100, so each
    ramp takes 2 sqrt(dv/J) = 0.282843 s: T = 1 + 0.282843 = 1.282843 s."""
    pr = profile(models, [{"end": (100, 0, 0)}])
    assert pr.cycle_time == pytest.approx(1 + 2 * math.sqrt(100 / 5000), rel=1e-9)


def test_effective_acceleration_closed_forms():
    """A_eff = dv / T: 400 / 0.21 = 1904.76 (A reached); 100 / 0.282843 = 353.553 (not)."""
    got = effective_acceleration([400.0, 100.0, 0.0], [2500.0] * 3, [50000.0, 5000.0, 5000.0])
    assert got == pytest.approx([400 / 0.21, 100 / (2 * math.sqrt(100 / 5000)), 2500.0])
    assert effective_acceleration([100.0], [2500.0], [INF])[0] == 2500.0


def test_short_line_never_reaches_the_feed(models):
    """1 mm at F1000: peak sqrt(A L) = 50 mm/s, T = 2 * 50 / 2500 = 0.04 s."""
    pr = profile(models, [{"end": (1, 0, 0)}], feed=1000.0, jerk=(INF, INF, INF))
    assert pr.v_peak[0] == pytest.approx(50.0)
    assert pr.cycle_time == pytest.approx(0.04)


def test_short_jerk_limited_line(models):
    """1 mm between stops with J 5000: peak (L/2)^(2/3) J^(1/3) = 10.7722 mm/s."""
    pr = profile(models, [{"end": (1, 0, 0)}], feed=1000.0)
    assert pr.v_peak[0] == pytest.approx(0.5 ** (2 / 3) * 5000 ** (1 / 3), rel=1e-4)


def test_corner_braking_distance(models):
    """Two 10 mm lines with a 90 deg corner at v = 7.768870 mm/s (sqrt(A R)): the machine
    brakes over (F^2 - v^2) / (2 A) = 1.987929 mm, and holds v over the inserted arc, from
    R tan(45 deg) = R = 0.024142 mm of programmed path before the corner to as far after
    it; the tool runs the arc itself, R * pi / 4 = 0.018961 mm on each side."""
    pr = profile(models, [{"end": (10, 0, 0)}, {"end": (10, 10, 0)}], jerk=(INF, INF, INF))
    R = 0.0241421356237
    v = math.sqrt(2500 * R)
    brake = (100**2 - v**2) / 5000
    assert pr.v_exit[0] == pytest.approx(v)
    assert pr.hold_end[0] == pytest.approx(R) and pr.hold_start[1] == pytest.approx(R)
    assert pr.speed_at(10 - R - brake - 1e-9) == pytest.approx(100.0)
    assert pr.speed_at(10 - R - brake / 2) == pytest.approx(math.sqrt(v**2 + 2500 * brake))
    assert pr.speed_at(10 - R / 2) == pytest.approx(v)
    assert pr.speed_at(10 + R / 2) == pytest.approx(v)
    # each move: 0.04 s ramp from rest, (100 - v) / 2500 braking, R pi / 4 at v, the rest at F
    arc = R * math.pi / 4
    cruise = 10 - 2 - brake - R
    t_move = 0.04 + (100 - v) / 2500 + cruise / 100 + arc / v
    assert pr.cycle_time == pytest.approx(2 * t_move, rel=1e-12)
    # the sampled trace spends R pi / 4 / v at the corner speed on each side, and crosses
    # the corner point at the middle of that time
    s = pr.sample(0.0001)
    slow = np.isclose(s.v, v, atol=1e-6)
    assert slow.sum() * 0.0001 == pytest.approx(2 * arc / v, abs=0.0003)
    t_corner = s.t[np.argmin(np.abs(s.s - 10.0))]
    assert t_corner == pytest.approx(t_move, abs=0.0002)


def test_very_short_blocks_never_reach_feed(models):
    """50 collinear 0.5 mm blocks at F300: a 25 mm triangle from rest to rest, peak
    sqrt(A L) = 250 mm/s < F, T = 2 sqrt(L / A) = 0.2 s."""
    moves = [{"end": (0.5 * (i + 1), 0, 0)} for i in range(50)]
    pr = profile(models, moves, feed=300.0, jerk=(INF, INF, INF), t_int=0.001)
    assert pr.v_peak.max() == pytest.approx(250.0)
    assert pr.cycle_time == pytest.approx(0.2)
    assert (pr.v_peak < 300.0).all()


def test_exact_stop_and_dwell(models):
    """Two collinear 10 mm lines: continuous 20/100 + 0.04 = 0.24 s; with G61 on the first,
    each runs from rest to rest: 2 * (0.1 + 0.04) = 0.28 s; a 0.5 s dwell adds 0.5 s."""
    moves = [{"end": (10, 0, 0)}, {"end": (20, 0, 0)}]
    tp = path(moves)
    m = machine(jerk=(INF, INF, INF))
    assert build_profile(models.evaluate(tp, m)).cycle_time == pytest.approx(0.24)
    g61 = dataclasses.replace(tp, path_mode=np.array([1, 0]))
    assert build_profile(models.evaluate(g61, m)).cycle_time == pytest.approx(0.28)
    dwell = dataclasses.replace(tp, dwell=np.array([0.5, 0.0]))
    pr = build_profile(models.evaluate(dwell, m))
    assert pr.cycle_time == pytest.approx(0.78)
    assert pr.v_exit[0] == 0.0


def test_rapids_run_at_the_axes_max_feed(models):
    """G0 100 mm along X with Vmax 500 mm/s: a triangle to sqrt(A L) = 500 mm/s, 0.4 s."""
    pr = profile(models, [{"end": (100, 0, 0), "rapid": True}], jerk=(INF, INF, INF))
    assert pr.cap[0] == pytest.approx(500.0)
    assert pr.cycle_time == pytest.approx(0.4)


def test_diagonal_uses_the_per_axis_share(models):
    """A 45 deg line: each axis carries cos 45 of the tangent, so A_t = 2500 / 0.7071 =
    3535.53 mm/s^2 and 100 mm at F100 takes 1 + 100 / 3535.53 = 1.028284 s."""
    c = math.sqrt(0.5)
    pr = profile(models, [{"end": (100 * c, 100 * c, 0)}], jerk=(INF, INF, INF))
    assert pr.cycle_time == pytest.approx(1 + 100 / (2500 / c), rel=1e-12)


def test_samples_follow_the_profile(models):
    """Sampled every 1 ms: starts at rest, ends at rest at the cycle time, x moves forward,
    the speed never exceeds F and agrees with the position's derivative."""
    pr = profile(models, [{"end": (100, 0, 0)}], jerk=(INF, INF, INF))
    s = pr.sample(0.001)
    assert s.t[0] == 0.0 and s.t[-1] == pytest.approx(1.04)
    assert s.v[0] == 0.0 and s.v[-1] == pytest.approx(0.0, abs=1e-9)
    assert np.all(np.diff(s.x) >= 0) and s.x[-1] == pytest.approx(100.0)
    assert s.v.max() == pytest.approx(100.0)
    mid = np.gradient(s.x, s.t)[100:-100]
    assert np.allclose(mid, s.v[100:-100], atol=1.5)
    assert set(s.line.tolist()) == {1}


def test_arc_samples_stay_on_the_circle(models):
    """Samples on a quarter arc of R 5 lie on the circle."""
    pr = profile(
        models, [{"end": (5, 5, 0), "center": (0, 5, 0), "ccw": True}], jerk=(INF, INF, INF)
    )
    s = pr.sample(0.001)
    r = np.hypot(s.x - 0.0, s.y - 5.0)
    assert np.allclose(r, 5.0)


def test_cycle_time_of_a_g_code_program(nc):
    """Through the adapter: G61 and G4 in a program add their stop and dwell."""
    from adapters.gcode import read_gcode
    from core import load_preset

    base = "G21 G64 G1 X10 F6000\nX20\n"
    m = load_preset("linuxcnc-sim")  # A 2000 mm/s^2, no jerk limit
    t0 = build_profile(nc.evaluate(read_gcode(base.encode(), "a.nc"), m)).cycle_time
    t1 = build_profile(
        nc.evaluate(read_gcode(b"G21 G61 G1 X10 F6000\nG64 X20\n", "b.nc"), m)
    ).cycle_time
    t2 = build_profile(
        nc.evaluate(read_gcode(b"G21 G64 G1 X10 F6000\nG4 P0.25\nX20\n", "c.ngc"), m)
    ).cycle_time
    # continuous: 20 mm at 100 mm/s plus one ramp 100 / 2000 = 0.05 s; stops: 2 * (0.1 + 0.05)
    assert t0 == pytest.approx(0.25)
    assert t1 == pytest.approx(0.30)
    assert t2 == pytest.approx(0.55)


def test_s_curve_inside_a_jerk_limited_ramp(models):
    """10 mm from rest to rest at F100, A 2500, J 1e5: the ramp 0 -> 100 mm/s reaches A
    (dv = 100 > A^2 / J = 62.5), t_j = A / J = 0.025 s, T = dv / A + t_j = 0.065 s, and
    covers 100 * T / 2 = 3.25 mm. Inside it, v = J t^2 / 2 up to t_j (5 mm/s at 10 ms,
    31.25 at 25 ms, where s = J t^3 / 6 = 0.260417 mm), then 31.25 + A (t - t_j)
    (68.75 at 40 ms), then F - J (T - t)^2 / 2 (88.75 at 50 ms). Braking mirrors it: the
    move ends at 2 * 0.065 + (10 - 6.5) / 100 = 0.165 s."""
    pr = profile(models, [{"end": (10, 0, 0)}], feed=100.0, jerk=(100.0, 100.0, 100.0))  # m/s^3
    assert pr.cycle_time == pytest.approx(0.165, rel=1e-9)
    smp = pr.sample(0.0001)
    at = {round(t, 4): i for i, t in enumerate(smp.t)}
    for t, v in [
        (0.01, 5.0),
        (0.025, 31.25),
        (0.04, 68.75),
        (0.05, 88.75),
        (0.1, 100.0),
        (0.165 - 0.01, 5.0),
        (0.165 - 0.04, 68.75),
    ]:
        assert smp.v[at[round(t, 4)]] == pytest.approx(v, abs=1e-6), t
    assert smp.s[at[0.025]] == pytest.approx(1e5 * 0.025**3 / 6, abs=1e-9)
    assert smp.s[at[0.065]] == pytest.approx(3.25, abs=1e-9)
    assert smp.s[at[0.1]] == pytest.approx(3.25 + 100 * 0.035, abs=1e-9)
    assert smp.s[at[0.165 - 0.025]] == pytest.approx(10 - 1e5 * 0.025**3 / 6, abs=1e-9)
    # Along the path: the same speeds at the same places, braking too.
    assert pr.speed_at(1e5 * 0.025**3 / 6) == pytest.approx(31.25, abs=1e-5)
    assert pr.speed_at(10 - 1e5 * 0.025**3 / 6) == pytest.approx(31.25, abs=1e-5)
    assert pr.speed_at(5.0) == pytest.approx(100.0)
    assert np.allclose(pr.speed_at(smp.s[1:-1]), smp.v[1:-1], atol=1e-4)


def test_linuxcnc_g61_runs_through_tangent_joints(models):
    """Three collinear 10 mm blocks at F3000 (50 mm/s), A 2500 mm/s^2, no jerk limit: under
    LinuxCNC's G61 (exact path) one ramp up and one down, T = 30 / 50 + 50 / 2500 = 0.62 s;
    under G61.1 (exact stop) three, T = 3 (10 / 50 + 50 / 2500) = 0.66 s."""
    from adapters.gcode import read_gcode

    for mode, want in (("G61", 0.62), ("G61.1", 0.66)):
        text = f"G21 G90 G0 X0 Y0 Z0\n{mode} G1 X10 F3000\nX20\nX30\n".encode()
        tp = read_gcode(text, "t.ngc")
        ev = models.evaluate(tp, machine(jerk=(INF, INF, INF)))
        pr = build_profile(ev)
        feed = tp.is_feed
        assert float(pr.time[feed].sum()) == pytest.approx(want, rel=1e-9), mode


def test_linuxcnc_g61_corner_is_a_stop_named_for_the_path_mode(models):
    """Under LinuxCNC's G61 the 90 deg corner after X30 is a stop (no blending: tolerance 0)
    and says why; the collinear joints before it report nothing."""
    from adapters.gcode import read_gcode

    tp = read_gcode(b"G21 G90 G0 X0 Y0 Z0\nG61 G1 X10 F3000\nX20\nX30\nY10\n", "t.ngc")
    ev = models.evaluate(tp, machine())
    corner = int(np.flatnonzero(tp.line == 5)[0]) - 1  # junction: end of the X30 move
    k = np.flatnonzero(ev.junction == corner)
    assert k.size == 1 and ev.junction_feed[k[0]] == 0.0
    assert ev.labels[ev.junction_limit[k[0]]] == "exact path: no blending"
    assert set(ev.junction[ev.junction_feed < 50.0].tolist()) == {corner}


@pytest.mark.parametrize("rising", [True, False])
def test_ramp_place_guess_gives_the_halvings_bracket(rising):
    """speed_at's place inside a jerk-limited ramp: the checked Newton guess of _bisect_ramp
    ends in the bracket the halvings alone end in, bit for bit -- on ramps of every size,
    including speed changes of 1e-6 mm/s whose place is rounding noise (those are bisected),
    places at the ramp's ends and beyond them, and a NaN."""
    from core.engine.profile import _bisect_ramp, _halvings, _place_terms, s_curve_shape

    rng = np.random.default_rng(7)
    n = 20_000
    lo = np.where(rng.random(n) < 0.3, 0.0, rng.uniform(0.0, 200.0, n))
    dv = 10.0 ** rng.uniform(-6.0, 2.5, n)
    acc = rng.uniform(100.0, 5000.0, n)
    jerk = np.where(rng.random(n) < 0.2, np.inf, rng.uniform(1e3, 1e6, n))
    a = acc * rng.uniform(0.3, 1.0, n)  # the effective acceleration
    vb = lo + dv * np.where(rng.random(n) < 0.5, 0.0, rng.random(n))
    span = dv * dv / a
    shape = s_curve_shape(dv, acc, jerk)
    length = ((lo + dv) ** 2 - vb * vb) / (2 * a)
    target = length * rng.uniform(-0.1, 1.1, n)
    target[::97] = 0.0
    target[5] = np.nan
    goal = target if rising else -target
    a_p, b_p = _bisect_ramp(lo, dv, a, vb * vb, span, shape, goal, rising)
    a_h, b_h = _halvings(_place_terms(lo, dv, a, vb * vb, span, shape), goal, rising)
    assert np.array_equal(a_p, a_h) and np.array_equal(b_p, b_h)


def test_rounds_memo_gives_the_rounds_of_the_same_inputs(nc, monkeypatch):
    """A fit's memo of the last jerk rounds (RoundsMemo): a profile whose rounds have the
    inputs of the last ones (the same evaluation, or a machine that differs where the
    rounds do not read: its name) takes their outcome without iterating; one whose inputs
    differ (a lower acceleration) iterates; every profile, bit for bit, the one built
    without a memo."""
    import core.engine.profile as profile_module
    from core import load_preset
    from core.engine.profile import Profile, RoundsMemo
    from tests.bits import same
    from tests.conftest import ROOT

    tp = nc.extract(str(ROOT / "examples" / "zlevel_cavity_chords.ngc"))
    m = load_preset("siemens-840d")
    renamed = dataclasses.replace(m, name="another name")
    slower = dataclasses.replace(m, max_acceleration=m.max_acceleration * 0.5)
    evs = [nc.evaluate(tp, x) for x in (m, m, renamed, slower, m)]
    iterated = []
    real = profile_module._Rounds

    def counted(*args, **kw):
        iterated.append(True)
        return real(*args, **kw)

    monkeypatch.setattr(profile_module, "_Rounds", counted)
    memo = RoundsMemo()
    with_memo = [build_profile(ev, memo=memo) for ev in evs]
    # the first iterates, the same and the renamed take its rounds, the slower iterates, the
    # last (as the first) iterates again: the memo keeps the last rounds only
    assert len(iterated) == 3
    for ev, got in zip(evs, with_memo, strict=True):
        want = build_profile(ev)
        for f in dataclasses.fields(Profile):
            if f.name != "evaluation":
                same(getattr(got, f.name), getattr(want, f.name))
    assert not np.array_equal(with_memo[3].a_up, with_memo[0].a_up)
    # what a hit gives is a copy: a profile's columns are its own
    assert with_memo[1].a_up is not with_memo[0].a_up
