"""ncperf calibrate (issue 11): a machine file fitted on traces and checked on others.

The traces are made by the model itself with a known machine (the "truth"), so the values
calibration must find are the truth's, by construction: an X axis with half the
acceleration (1250 of 2500 mm/s^2), a block time of 30 ms (12 ms in the start file), a
normal-acceleration share of 0.87 on arcs at their centripetal cap (the fit's range then
includes LinuxCNC's documented sqrt(3)/2 = 0.8660, which is written instead).
"""

from __future__ import annotations

import dataclasses
import math
import tomllib

import numpy as np
import pytest

from core.diagnosis.align import align
from core.engine.effects import Setup
from core.model.machine import machine_from_toml_text
from tests.conftest import machine, path
from tests.test_diagnose import synthetic_trace, zigzag

INF = float("inf")


def square_spiral(feed=100.0):
    """Corners in both directions, X and Y runs of several lengths, a run of 0.5 mm blocks."""
    moves, x, y = [], 0.0, 0.0
    for k in range(1, 9):
        d = 6.0 * k
        x += d if k % 2 else -d
        moves.append({"end": (x, y, 0)})
        y += d if k % 2 else -d
        moves.append({"end": (x, y, 0)})
    moves += [{"end": (x + 0.5 * (i + 1), y, 0)} for i in range(40)]
    return path(moves, feed=feed)


def waves(feed=150.0, radius=2.0, count=12):
    """Semicircles of R 2 mm alternating in direction (tangent-continuous), then a line: at
    F 150 mm/s the arcs run at their centripetal cap sqrt(f A R) (70.7 mm/s for f = 1)."""
    moves = [
        {
            "start": (2 * radius * i, 0, 0),
            "end": (2 * radius * (i + 1), 0, 0),
            "center": (2 * radius * i + radius, 0, 0),
            "ccw": i % 2 == 0,
        }
        for i in range(count)
    ]
    moves.append({"end": (2 * radius * count, 30, 0)})
    return path(moves, feed=feed)


def cases_for(nc, truth, programs=None):
    out = []
    programs = programs or (zigzag(), square_spiral(), zigzag(feed=60.0), square_spiral(140.0))
    for k, tp in enumerate(programs):
        tr = synthetic_trace(nc, tp, truth)
        out.append((tp, [align(tp, tr)], [f"p{k}"]))
    return out


def test_calibrate_finds_per_axis_acceleration_and_block_time(nc):
    start = machine(jerk=(INF, INF, INF))
    truth_m = dataclasses.replace(
        start,
        max_acceleration=np.array([1250.0, 2500.0, 2500.0]),
        interpolation_time=0.03,
    )
    effects = nc.effects()
    wanted = ("axis_dynamics", "block_cycle_time", "corner_tolerance", "exact_stop")
    cal = nc.calibrate(
        cases_for(nc, Setup(machine=truth_m)), Setup(machine=start), {k: effects[k] for k in wanted}
    )
    got = {c.name: c for c in cal.effects}
    assert set(got) == {"axis_dynamics", "block_cycle_time"}
    ad = got["axis_dynamics"].params
    assert ad["accel_scale"] * ad["accel_x"] == pytest.approx(0.5, rel=0.05)
    assert ad["accel_scale"] * ad["accel_y"] == pytest.approx(1.0, rel=0.05)
    assert got["block_cycle_time"].params["t_block"] == pytest.approx(0.03, rel=0.05)
    # checked on the programs it was not fitted on: nearly all of the gap is gone
    for before, after in zip(cal.gap_before, cal.gap_after, strict=True):
        assert after < 0.1 * before
    m = cal.setup.machine
    assert m.max_acceleration[0] == pytest.approx(1250, rel=0.05)
    assert m.interpolation_time == pytest.approx(0.03, rel=0.05)


def test_calibrate_writes_a_documented_value_inside_the_range(nc):
    start = machine(jerk=(INF, INF, INF))
    effects = nc.effects()
    eff = effects["normal_acceleration_factor"]
    truth = eff.apply(Setup(machine=start), {"factor": 0.87})
    programs = (waves(), waves(120.0, 3.0), waves(150.0, 1.5), waves(100.0, 1.0))
    cal = nc.calibrate(cases_for(nc, truth, programs), Setup(machine=start), {eff.name: eff})
    (c,) = cal.effects
    lo, hi = c.ranges["factor"]
    assert lo <= 0.87 <= hi and lo <= math.sqrt(3) / 2 <= hi
    assert c.params["factor"] == math.sqrt(3) / 2
    assert "BLEND_ACC_RATIO_NORMAL" in c.documented["factor"]
    for f in c.folds:
        assert f["factor"] == pytest.approx(0.87, abs=0.02)


def test_calibrate_command(tmp_path, capsys):
    """The command writes a machine file that loads, with the calibrated block time, its
    range in a comment and the noise floor; a group without a trace is a usage error."""
    from core import Ncperf
    from core.cli import main

    nc = Ncperf()
    start_text = (
        'name = "start"\n'
        + "".join(
            f"[axes.{a}]\nmax_feed = 30.0\nmax_acceleration = 2.5\nmax_jerk = inf\n" for a in "XYZ"
        )
        + "[controller]\ninterpolation_time = 0.012\npath_tolerance = 0.01\n"
        + "curvature_transition_time = 0.012\n"
        + "[diagnosis]\ntrace_cycle = 0.001\n"
    )
    start_file = tmp_path / "start.toml"
    start_file.write_text(start_text)
    truth = Setup(
        machine=dataclasses.replace(
            machine_from_toml_text(start_text, "t"), interpolation_time=0.03
        )
    )
    args = []
    for k, g in enumerate(
        [
            "G21 G90 G64 P0.01 Q0\nG1 X10 F6000\n"
            + "".join(f"X{10 + 0.5 * i:.1f}\n" for i in range(1, 41)),
            "G21 G90 G64 P0.01 Q0\nG1 Y10 F6000\n"
            + "".join(f"Y{10 + 0.5 * i:.1f}\n" for i in range(1, 41)),
        ]
    ):
        prog = tmp_path / f"p{k}.ngc"
        prog.write_text(g + "M2\n")
        tp = nc.extract(str(prog))
        tr = synthetic_trace(nc, tp, truth)
        csv = tmp_path / f"p{k}.csv"
        rows = np.column_stack([tr.t, tr.pos, tr.v, tr.line])
        np.savetxt(
            csv,
            rows,
            delimiter=",",
            header="t,x,y,z,v,line",
            comments="",
            fmt=["%.6f"] * 5 + ["%d"],
        )
        args += [str(prog), str(csv)] if k == 0 else ["--also", str(prog), str(csv)]
    out = tmp_path / "cal.toml"
    code = main(
        [
            "calibrate",
            *args,
            "--machine",
            str(start_file),
            "--out",
            str(out),
            "--effects",
            "block_cycle_time,corner_tolerance",
        ]
    )
    assert code == 0
    text = out.read_text()
    m = machine_from_toml_text(text, str(out))
    assert m.interpolation_time == pytest.approx(0.03, rel=0.05)
    assert math.isfinite(m.noise_floor)
    line = next(x for x in text.splitlines() if x.startswith("interpolation_time"))
    assert "fitted range" in line and "folds" in line
    assert tomllib.loads(text)["diagnosis"]["noise_floor"] >= 0
    assert m.trace_cycle == 0.001  # the start file's other [diagnosis] keys stay
    assert "other programs" in capsys.readouterr().out
    bad = main(["calibrate", *args[:2], "--also", args[0], "--out", str(tmp_path / "x.toml")])
    assert bad == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "give the program and at least one trace" in err
    assert not (tmp_path / "x.toml").exists()
