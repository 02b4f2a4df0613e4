"""ncperf calibrate on block times (issue 11, item 5): the time between observed program-line
changes, for recordings that sample the motion coarsely (MTConnect, every 0.1-0.2 s).

The traces are the reference interpreter's (``refvm``, which imports nothing of ncperf),
reduced to what an MTConnect agent records: the line and the feed at polls every 0.2 s, at a
random phase and with a few ms of jitter. Expected values are the truth the interpreter ran,
or worked out by hand.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from core.diagnosis.align import align
from core.diagnosis.blocktime import block_data, feed_lines, is_coarse, windows
from core.diagnosis.calibrate import choose_objective
from core.engine.effects import Setup
from core.model.errors import UsageError
from core.model.trace import Trace
from refvm import simulate
from tests.conftest import ROOT, machine, path, shared

INF = float("inf")
POLL = 0.2  # s, an MTConnect agent's poll


def strokes(reps: int = 6, feed: float = 100.0):
    """Back and forth along X, strokes of 2, 5, 12 and 30 mm: stops at every reversal, the
    short strokes all ramp (triangles), the long ones reach F (trapezoids)."""
    moves, x = [], 0.0
    for k in range(4 * reps):
        step = (2.0, 5.0, 12.0, 30.0)[k % 4]
        x = x + step if k % 2 == 0 else x - step
        moves.append({"end": (x, 0.0, 0.0)})
    return path(moves, feed=feed)


def chords(count: int = 240, feed: float = 100.0):
    """0.4 mm chords along a sine: at F 100 mm/s a 30 ms block time caps them at 13.3 mm/s."""
    x = 0.4 * np.arange(1, count + 1)
    return path([{"end": (float(xi), 3.0 * np.sin(0.1 * xi), 0.0)} for xi in x], feed=feed)


def polled(tr, seed: int, period: float = POLL, jitter: float = 0.01) -> Trace:
    """What an agent polling every ``period`` s records of a refvm trace: line and feed at
    each poll (random phase, uniform jitter), nothing between."""
    rng = np.random.default_rng(seed)
    t = np.arange(rng.uniform(0, period), tr.t[-1], period)
    t = np.sort(np.clip(t + rng.uniform(-jitter, jitter, t.size), 0.0, tr.t[-1]))
    k = np.clip(np.searchsorted(tr.t, t, side="right") - 1, 0, tr.t.size - 1)
    return Trace(t=t - t[0], pos=None, v=tr.v[k], line=tr.line[k], source=f"poll{seed}")


def cases_of(tp, tr, seeds):
    runs = [polled(tr, s) for s in seeds]
    return [(tp, [align(tp, r) for r in runs], [r.source for r in runs])]


def test_feed_lines_leave_out_rapids_and_lines_without_motion():
    """Lines 1 rapid, 2-3 feed, (4 none), 5 feed, 6 rapid and feed, 7 feed: 2, 3, 5, 7."""
    tp = path(
        [
            {"end": (1, 0, 0), "rapid": True},
            {"end": (2, 0, 0)},
            {"end": (3, 0, 0)},
            {"end": (4, 0, 0)},
            {"end": (5, 0, 0), "rapid": True},
            {"end": (6, 0, 0)},
            {"end": (7, 0, 0)},
        ]
    )
    tp = dataclasses.replace(tp, line=np.array([1, 2, 3, 5, 6, 6, 7]))
    assert np.flatnonzero(feed_lines(tp)).tolist() == [2, 3, 5, 7]


def test_block_data_keeps_intervals_over_feed_lines_only(nc):
    """Samples at 0, 0.1 (line 2, running when the recording began: not a change), changes
    at 0.2, 0.5, 0.6, 1.0, 1.3 s to lines 3, 5, 7, 9, 10 of a program whose line 6 is a rapid:
    kept 3->5 (0.3 s), 7->9 (0.4 s), 9->10 (0.3 s); 5->7 runs the rapid and is left out."""
    moves = [{"end": (float(k), 0.0, 0.0)} for k in range(1, 11)]
    moves[5]["rapid"] = True
    tp = path(moves)
    t = np.array([0.0, 0.1, 0.2, 0.5, 0.6, 1.0, 1.3, 1.4])
    line = np.array([2, 2, 3, 5, 7, 9, 10, 10])
    tr = Trace(t=t, pos=None, v=np.full(t.size, 50.0), line=line, source="hand")
    d = block_data(tp, align(tp, tr), "hand")
    assert d.first.tolist() == [3, 7, 9]
    assert d.last.tolist() == [5, 9, 10]
    assert d.measured == pytest.approx([0.3, 0.4, 0.3])


def test_windows_cut_runs_of_consecutive_intervals():
    """Intervals 1->2->3->4 (0.4 s each), then 6->7 (not consecutive): windows of 1 s are
    [0, 0, 0, 1], then 2."""
    first = np.array([1, 2, 3, 4, 6])
    last = np.array([2, 3, 4, 5, 7])
    w = windows(first, last, np.full(5, 0.4), 1.0)
    assert w.tolist() == [0, 0, 0, 1, 2]


def test_objective_chosen_by_sampling(nc):
    """auto: block time for polls every 0.2 s with lines, the feed gap for a 1 ms trace or a
    trace without lines; block-time asked of a trace without lines is refused."""
    tp = strokes(reps=1)
    tr = simulate(tp, machine(jerk=(INF,) * 3))
    fine = Trace(t=tr.t, pos=None, v=tr.v, line=tr.line, source="fine")
    no_lines = Trace(t=tr.t, pos=tr.xyz, v=tr.v, line=None, source="nolines")
    coarse = polled(tr, 0)
    assert is_coarse([align(tp, coarse)])
    assert choose_objective("auto", [align(tp, coarse)])[0].name == "block-time"
    assert choose_objective("auto", [align(tp, fine)])[0].name == "feed"
    assert choose_objective("auto", [align(tp, no_lines)])[0].name == "feed"
    with pytest.raises(UsageError, match="block-time objective needs traces with program lines"):
        choose_objective("block-time", [align(tp, no_lines)])


def test_block_time_recovers_a_block_time_from_polled_lines(nc):
    """A controller needing 30 ms per block (the start file says 12 ms), polled every 0.2 s,
    four runs: the block-time objective finds t_block within 5 % of 30 ms."""
    tp = chords()
    start = machine(jerk=(INF,) * 3, t_int=0.012)
    tr = simulate(tp, start, "block_cycle_time", {"t_block": 0.03})
    eff = nc.effects()
    cal = nc.calibrate(
        cases_of(tp, tr, range(4)),
        Setup(machine=start),
        {"block_cycle_time": eff["block_cycle_time"]},
        "block-time",
    )
    assert cal.objective.name == "block-time"
    assert [c.name for c in cal.effects] == ["block_cycle_time"]
    assert cal.effects[0].params["t_block"] == pytest.approx(0.03, rel=0.05)
    assert all(a < 0.5 * b for a, b in zip(cal.gap_after, cal.gap_before, strict=True))


def test_block_time_recovers_acceleration_where_the_feed_gap_cannot(nc):
    """X acceleration 800 mm/s^2 where the start file says 2500 (scale 0.32), strokes polled
    every 0.2 s, six runs: on block times the fitted X acceleration is within 8 % of 800 mm/s^2
    and the calibrated machine predicts the true cycle time within 2 %; on the feed gap of the
    same polls the fit is drawn elsewhere (the held feed sits at the wrong place on the path)
    and its machine misses the cycle time by more than 5 %."""
    tp = strokes()
    start = machine(jerk=(INF,) * 3)
    truth = dataclasses.replace(start, max_acceleration=np.array([800.0, 800.0, 800.0]))
    tr = simulate(tp, truth)
    cases = cases_of(tp, tr, range(6))
    eff = {"axis_dynamics": nc.effects()["axis_dynamics"]}
    block = nc.calibrate(cases, Setup(machine=start), eff, "block-time")
    feed = nc.calibrate(cases, Setup(machine=start), eff, "feed")
    p = block.effects[0].params
    assert p["accel_scale"] * p["accel_x"] * 2500.0 == pytest.approx(800.0, rel=0.08)
    assert nc.predict(tp, block.setup).cycle_time == pytest.approx(tr.cycle_time, rel=0.02)
    off = abs(nc.predict(tp, feed.setup).cycle_time / tr.cycle_time - 1.0)
    assert off > 0.05


def test_calibrate_command_on_polled_lines_says_which_objective(tmp_path, capsys):
    """The CLI on polled traces (CSV t,v,line every 0.2 s) reports the block-time objective,
    in ms, and writes no feed-gap noise floor into the machine file."""
    from core.cli.main import main

    tp = chords(count=120)
    start = machine(jerk=(INF,) * 3, t_int=0.012)
    tr = simulate(tp, start, "block_cycle_time", {"t_block": 0.03})
    prog = tmp_path / "chords.ngc"
    prog.write_text(
        "G21 G90 G64 F6000\nG0 X0 Y0 Z0\n"
        + "".join(f"G1 X{x:.4f} Y{y:.4f}\n" for x, y in tp.end[:, :2])
        + "M2\n"
    )
    names = []
    for seed in range(2):
        r = polled(tr, seed)
        f = tmp_path / f"run{seed}.csv"
        rows = "".join(
            f"{a:.4f},{b:.4f},{c + 2}\n"
            for a, b, c in zip(r.t.tolist(), r.v.tolist(), r.line.tolist(), strict=True)
        )
        f.write_text("t,v,line\n" + rows)
        names.append(str(f))
    out = tmp_path / "cal.toml"
    toml = tmp_path / "start.toml"
    toml.write_text(
        'name = "start"\n'
        + "".join(
            f"[axes.{a}]\nmax_feed = 30.0\nmax_acceleration = 2.5\nmax_jerk = inf\n" for a in "XYZ"
        )
        + "[controller]\ninterpolation_time = 0.012\npath_tolerance = 0.01\n"
        + "curvature_transition_time = 0.012\n"
    )
    rc = main(["calibrate", str(prog), *names, "--machine", str(toml), "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0
    assert "objective        block-time" in text
    assert " ms RMS" in text
    assert "noise_floor" not in out.read_text()
    assert "# Objective: block-time" in out.read_text()


def test_nist_box_calibration_runs(nc):
    """The NIST box OP2 calibration runs (08, 11, 13, 15, 17, 19; the other six are held out
    and not read here) from the assumed Hurco file: auto chooses the block-time objective
    (MTConnect polls every 0.16 s), and the file predicts the feed-block time (the sum of the
    compared intervals) of the runs made at 100 % feed within 2 %. Run 08 was made at another
    feed override -- its recorded feed on the feed blocks is 7 % above F -- and runs its feed
    blocks 4-6 % faster than predicted: an operator's setting, which calibrate does not fit."""
    from core.diagnosis.blocktime import expected, feed_lines
    from core.engine.effects import setup_for
    from core.model.machine import load_machine_file

    folder = shared("data", "nist-mtc-box-op2")
    start = load_machine_file(ROOT / "benchmarks" / "machines" / "hurco_vmc_assumed.toml")
    tp = nc.extract(str(folder / "BOX_REV-A_OP2_Front.NC"))
    runs = [folder / f"Box-OP2-Hurco02-{r}of20.txt" for r in ("08", "11", "13", "15", "17", "19")]
    traces = [nc.read_trace(str(f)) for f in runs]
    als = [align(tp, tr) for tr in traces]
    effects = nc.effects()
    cal = nc.calibrate(
        [(tp, als, [f.name for f in runs])],
        setup_for(start, effects),
        {k: effects[k] for k in ("block_cycle_time", "corner_tolerance")},
    )
    assert cal.objective.name == "block-time"
    pred = nc.predict(tp, cal.setup)
    first_move = np.full(int(tp.line.max()) + 2, -1)
    first_move[tp.line[::-1]] = np.arange(tp.n)[::-1]
    ok = feed_lines(tp)
    for tr, al, f in zip(traces, als, runs, strict=True):
        d = block_data(tp, al, f.name)
        assert d.first.size > 250  # of 305-322 observed changes
        error = expected(pred, d).sum() / d.measured.sum() - 1.0
        on = ok[np.clip(tr.line, 0, ok.size - 1)] & (tr.v > 0)
        override = float(np.median(tr.v[on] / tp.feed[first_move[tr.line[on]]]))
        if "08of20" in f.name:
            assert override > 1.04
            assert 0.04 < error < 0.06
        else:
            assert override == pytest.approx(1.0, abs=0.02)
            assert abs(error) < 0.02, f.name
