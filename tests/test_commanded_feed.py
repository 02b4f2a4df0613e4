"""A trace's feed column read as the controller's commanded feed (issue 11).

A setpoint filter (a moving average over T) smooths the setpoint axis by axis. On a circle
of radius r run at v the filtered positions run a circle of radius r sin(x) / x, x =
(v / r) T / 2 -- inside the programmed one -- so their own speed is v sin(x) / x, while the
commanded path speed, smoothed in time, stays v. A trace whose v column is that commanded
speed (the blind benchmark's setpoint-filter traces, benchmarks/linuxcnc_withheld.py
post_process) differs from its positions' speed there; the alignment notices it and the
predictions are read the same way.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.diagnosis.align import align
from core.engine.effects import Setup
from core.model.trace import Trace
from tests.conftest import machine, path

INF = float("inf")
R, V = 2.0, 50.0  # mm, mm/s (F3000)
CIRCLES = 6


def circles():
    """20 mm along +X into the bottom of a circle of radius 2 about (0, 2), six full
    circles counter-clockwise (tangent in and out), then 20 mm on along +X."""
    moves = [{"start": (-20.0, 0.0, 0.0), "end": (0.0, 0.0, 0.0)}]
    for _ in range(CIRCLES):
        moves.append({"end": (0.0, 2 * R, 0.0), "center": (0.0, R, 0.0), "ccw": True})
        moves.append({"end": (0.0, 0.0, 0.0), "center": (0.0, R, 0.0), "ccw": True})
    moves.append({"end": (20.0, 0.0, 0.0)})
    return path(moves, feed=V)


def quick_machine():
    # 20 m/s^2: the circle's 1250 mm/s^2 normal acceleration is far inside it; no jerk limit
    return machine(acc=(20.0, 20.0, 20.0), jerk=(INF, INF, INF))


def test_on_a_circle_the_filtered_positions_run_slower_than_the_commanded_feed(nc):
    """40 samples of 1 ms averaged on a circle of radius 2 mm at 50 mm/s (omega 25 rad/s):
    the mean of 40 unit phasors 1 ms apart has length sin(40 x 0.0125) / (40 sin(0.0125))
    = 0.47943 / 0.49999 = 0.958876, so the filtered positions run at 47.944 mm/s (the
    continuous sin(0.5) / 0.5 = 0.958851); the commanded feed, a moving average of a
    steady 50 mm/s, stays 50."""
    tp = circles()
    pred = nc.predict(tp, Setup(machine=quick_machine(), filter_window=0.040))
    mid = 20.0 + 2 * math.pi * R * np.array([2.25, 2.5, 3.0, 3.75])  # in the third/fourth circle
    ratio = math.sin(40 * 0.0125) / (40 * math.sin(0.0125))
    assert pred.speed_at(mid) == pytest.approx(np.full(4, V * ratio), abs=0.05)
    assert pred.speed_at(mid, commanded=True) == pytest.approx(np.full(4, V), abs=0.05)
    # no time-domain effect: both readings are the profile's own
    raw = nc.predict(tp, Setup(machine=quick_machine()))
    assert raw.speed_at(mid) == pytest.approx(np.full(4, V), abs=1e-9)
    assert np.array_equal(raw.speed_at(mid, commanded=True), raw.speed_at(mid))


def filtered_trace(nc, tp, window, column, dt=0.001):
    """A trace of the machine behind a causal setpoint filter of ``window`` s, made here
    from the unfiltered prediction: positions averaged over the window axis by axis; the v
    column either the planner's speed averaged in time ("commanded", as the blind
    benchmark's post-processing writes it) or the filtered positions' own speed
    ("positions")."""
    t, s, v = nc.predict(tp, Setup(machine=quick_machine())).signal()
    k = int(round(window / dt))
    pos = np.concatenate([tp.point_at(s), np.repeat(tp.point_at(s[-1:]), k, axis=0)])
    v = np.concatenate([v, np.zeros(k)])
    kernel = np.ones(k) / k
    pad = np.concatenate([np.repeat(pos[:1], k - 1, axis=0), pos])
    fpos = np.column_stack([np.convolve(pad[:, j], kernel, "valid") for j in range(3)])
    t = np.arange(fpos.shape[0]) * dt
    if column == "commanded":
        col = np.convolve(np.concatenate([np.zeros(k - 1), v]), kernel, "valid")
    else:
        col = np.linalg.norm(np.gradient(fpos, dt, axis=0), axis=1)
    s_all = np.concatenate([s, np.full(k, s[-1])])
    return Trace(t=t, pos=fpos, v=col, line=tp.line[tp.move_at(s_all)], source="synthetic")


@pytest.mark.parametrize("column", ["commanded", "positions"])
def test_a_setpoint_filter_on_circles_is_named_whichever_speed_the_column_holds(nc, column):
    """A 30 ms filter on the six circles (x = 0.375: the positions 2.3 % slower, 1.2 mm/s):
    read with the wrong speed, the fit of the window is pulled off; read as the column is,
    jerk_filter is named with its window within 10 %."""
    tp = circles()
    tr = filtered_trace(nc, tp, 0.020, column)
    al = align(tp, tr)
    assert al.commanded == (column == "commanded")
    assert any("read as the commanded feed" in n for n in al.notes) == (column == "commanded")
    effects = nc.effects()
    d = nc.diagnose([(tp, [al], ["t"])], Setup(machine=quick_machine()), "profile", effects)
    assert d.best_effect == "jerk_filter"
    assert d.effects[0].params["window"] == pytest.approx(0.020, rel=0.1)
    assert d.gap_rms_after < 0.3 * d.gap_rms_before
