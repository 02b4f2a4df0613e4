"""The LinuxCNC model (preset ``linuxcnc-sim``) against LinuxCNC 2.9's real trajectory
planner: programs written here are run headless through the shared harness
(``../shared/tools/linuxcnc/run_trace.sh``, 1 ms rows) and ncperf's predicted times are
compared with the recorded ones. The cases are the planner's other ways through a corner
than a blend arc (plugins/tangential.py, ``linuxcnc_choice``): a line into a helix and out
of it (no arc: not coplanar), and corners whose blend arc is too short for a 5 ms servo
period; and the segments LinuxCNC's interpreter makes of nearly collinear blocks under
G64 P without Q (its naive-CAM detector, adapters/gcode/naivecam.py); the kink test on
short diagonal chords (the added line's own acceleration), a blend arc's limit along its
whole length (free-form chords out of a tight spot) and the speeds the lazy look-ahead
leaves lowered on chords before a long line. Skipped where the harness or LinuxCNC
is absent (a fresh clone has no ../shared)."""

from __future__ import annotations

import dataclasses
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from core import Ncperf, load_preset
from core.diagnosis.align import align
from core.diagnosis.diagnose import sample_cycle
from core.engine.effects import setup_for

ROOT = Path(__file__).resolve().parents[1]
TOOLS = ROOT.parent / "shared" / "tools" / "linuxcnc"
HARNESS = TOOLS / "run_trace.sh"
INI = TOOLS / "machines" / "default_mill_mm.ini"

pytestmark = pytest.mark.skipif(
    not HARNESS.exists() or shutil.which("linuxcnc") is None,
    reason="needs ../shared/tools/linuxcnc and LinuxCNC (scripts/setup_linuxcnc.sh)",
)

THREAD = """(a line into a 3-turn helix and out of it, F1800, G64 P0.01)
G21 G17 G90 G94
G64 P0.01 Q0
G0 X0 Y0 Z2
G1 Z-3 F600
G1 X5 F1800
G2 X5 Y0 Z-1 I-5 J0 P3
G1 X0
G0 Z5
M2
"""
#: the lead-in line and the line out of the helix (1-based program lines)
THREAD_LINES = (6, 8)

SQUARES = """(squares of 2 mm at F1200 with a fine path tolerance, G64 P0.001)
G21 G17 G90 G94
G64 P0.001 Q0
G0 X0 Y0 Z1
G1 Z-0.5 F600
G1 X2 F1200
G1 Y2
G1 X0
G1 Y0
G1 X2
G1 Y2
G1 X0
G1 Y0
G0 Z5
M2
"""


#: one more square of SQUARES (from its start corner, X0 Y0)
_SQUARE = ("G1 X2\n", "G1 Y2\n", "G1 X0\n", "G1 Y0\n")


def record(tmp: Path, name: str, text: str, servo_ns: int | None = None) -> dict:
    prog = tmp / f"{name}.ngc"
    prog.write_text(text)
    out = tmp / f"{name}.csv"
    cmd = ["bash", str(HARNESS), str(prog), str(INI), str(out)]
    if servo_ns is not None:
        cmd += ["--set", f"EMCMOT.SERVO_PERIOD={servo_ns}"]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    data = np.genfromtxt(out, delimiter=",", names=True)
    return {"prog": prog, "csv": out, "t": data["t"], "line": data["line"].astype(int)}


def line_time(t: np.ndarray, line: np.ndarray, k: int) -> float:
    dt = np.diff(t, append=t[-1])
    return float(dt[line == k].sum())


def predicted(prog: Path, servo_s: float = 0.001):
    nc = Ncperf()
    m = load_preset("linuxcnc-sim")
    m = dataclasses.replace(m, interpolation_time=servo_s * 1.02)
    return nc.predict(nc.extract(str(prog)), setup_for(m, nc.effects())).profile


def test_a_line_into_a_helix_and_out_of_it(tmp_path):
    """LinuxCNC runs both helix corners as parabolic blends: the lines and the helix at half
    their acceleration. Without that model the lines were 13 % short and the program 2.7 %
    (the blind benchmark's thread milling, a program like this one). Recorded 4.295 s;
    predicted 4.291 s with the blends' overlap (2026-11-27; 4.279 s with each blend crossed
    at its blend speed, 4.248 s with blend arcs at the helix, -1.1 %)."""
    tr = record(tmp_path, "thread", THREAD)
    prof = predicted(tr["prog"])
    measured = float(tr["t"][-1] - tr["t"][0])
    assert prof.cycle_time == pytest.approx(measured, rel=0.01)
    # one row per servo period of 1 ms, as linuxcnc-sim's [diagnosis] trace_cycle says
    assert sample_cycle([tr["t"]]) == pytest.approx(0.001, abs=1e-9)
    s = prof.sample(0.001)
    for k in THREAD_LINES:
        expected = line_time(tr["t"], tr["line"], k)
        assert line_time(s.t, s.line, k) == pytest.approx(expected, rel=0.05)


def test_the_feed_column_through_the_helix_blends(tmp_path):
    """LinuxCNC's feed column (current_vel) through a parabolic blend is the sum of both
    segments' speeds (tp.c v2.9.8 line 3064): the segment before brakes to rest at the
    corner, the one after starts from rest. The prediction (core.engine.predict,
    overlap_column) shows that within 0.4 mm of both helix corners; the profile alone,
    which crosses them at the speed that costs the overlap's time, is a constant 0.5-1 mm/s
    high there -- what made the blind benchmark's unchanged thread milling (score7's
    thread_milling_5000507) look like an exact stop. Measured on score7's trace:
    RMS 0.29 against 1.20 mm/s (helix end), 0.10 against 0.55 (start)."""
    tr = record(tmp_path, "thread", THREAD)
    nc = Ncperf()
    tp = nc.extract(str(tr["prog"]))
    m = dataclasses.replace(load_preset("linuxcnc-sim"), interpolation_time=0.00102)
    pred = nc.predict(tp, setup_for(m, nc.effects()))
    al = align(tp, nc.read_trace(str(tr["csv"])))
    helix = np.flatnonzero(tp.is_arc)
    for corner in (tp.start_s[helix], tp.start_s[helix] + tp.length[helix]):
        near = np.abs(al.s - corner[0]) < 0.4
        assert near.sum() > 20
        new = np.sqrt(np.mean((al.v[near] - pred.speed_at(al.s[near])) ** 2))
        old = np.sqrt(np.mean((al.v[near] - pred.profile.speed_at(al.s[near])) ** 2))
        assert new < 0.4
        assert new < 0.5 * old


def test_corners_whose_arc_is_too_short_for_the_servo_period(tmp_path):
    """At a 5 ms servo period the 90 degree corners' blend arcs at 0.001 mm would run at
    0.74 mm/s (their length per servo period); LinuxCNC blends them parabolically. Recorded
    1.275 s; predicted 1.277 s (with arcs, as before the choice was modelled: 1.261 s, -1.1 %)."""
    tr = record(tmp_path, "squares", SQUARES, servo_ns=5_000_000)
    prof = predicted(tr["prog"], servo_s=0.005)
    measured = float(tr["t"][-1] - tr["t"][0])
    assert prof.cycle_time == pytest.approx(measured, rel=0.005)


def _chords() -> str:
    """90 chords of 1 mm on a circle of radius 200 mm (sagitta 0.000625 mm each), at F6000
    under G64 P0.01 without Q: LinuxCNC's interpreter joins them in runs of about 4 mm (the
    run's sagitta L^2 / (8 R) stays under 0.01 mm), then a sharp turn and 30 collinear 1 mm
    blocks it joins into one segment."""
    r, step = 200.0, 1.0 / 200.0
    lines = ["(chords of a large circle, then collinear blocks, G64 P0.01 without Q)"]
    lines += ["G21 G17 G90 G94", "G64 P0.01", "G0 X0 Y0 Z0", "G1 F6000"]
    pts = [(r * np.sin(k * step), r - r * np.cos(k * step)) for k in range(1, 91)]
    lines += [f"X{x:.4f} Y{y:.4f}" for x, y in pts]
    x0, y0 = pts[-1]
    lines += [f"X{x0:.4f} Y{y0 + k:.4f}" for k in range(1, 31)]
    lines.append("M2")
    return "\n".join(lines) + "\n"


def test_nearly_collinear_blocks_run_as_the_segments_linuxcnc_makes(tmp_path):
    """The segments (the trace's line numbers while moving) are the ones ncperf predicts: 28
    of the 120 blocks' lines. Recorded 1.344 s, predicted 1.343 s; read block by block (as
    before the detector was modelled) 1.327 s, -1.3 %."""
    tr = record(tmp_path, "chords", _chords())
    nc = Ncperf()
    tp = nc.extract(str(tr["prog"]))
    data = np.genfromtxt(tmp_path / "chords.csv", delimiter=",", names=True)
    moving = data["v"] > 0
    ran = set(np.unique(data["line"][moving].astype(int)).tolist())
    assert set(tp.line.tolist()) == ran
    assert len(ran) < 40  # about 90 / 4 + 1
    prof = predicted(tr["prog"])
    measured = float(tr["t"][-1] - tr["t"][0])
    assert prof.cycle_time == pytest.approx(measured, rel=0.005)


def _diagonal_chords() -> tuple[str, list[int]]:
    """0.05 mm chords near 45 degrees at F6000 under G64 P0.01 Q0 (each block its own
    segment), runs of 40 with a turn of 0.309 or 0.305 degrees between runs, and the
    program lines after the turns. By the kink test with the added line's own acceleration
    (tests/test_linuxcnc_blending.py) six turns are corners (kink 0.10017-0.10151) and the
    fourth, from 45.305 back to 45 degrees, is tangent (0.09969); with the plane's 2000
    mm/s^2 all seven were tangent (0.09813-0.09994)."""
    lines = ["(0.05 mm chords near 45 deg, turns of 0.309 and 0.305 deg, G64 P0.01 Q0)"]
    lines += ["G21 G17 G90 G94", "G64 P0.01 Q0", "G0 X0 Y0 Z0", "G1 X0 Y0 Z0 F6000"]
    x = y = 0.0
    ang = np.radians(45.0)
    after = []
    for run in range(8):
        for _ in range(40):
            x, y = x + 0.05 * np.cos(ang), y + 0.05 * np.sin(ang)
            lines.append(f"G1 X{x:.9f} Y{y:.9f}")
        after.append(len(lines) + 1)
        turn = 0.309 if run % 2 == 0 else 0.305
        ang += np.radians(turn if (run // 2) % 2 == 0 else -turn)
    lines.append("M2")
    return "\n".join(lines) + "\n", after[:7]


def test_short_diagonal_chords_corner_where_their_kink_says(tmp_path):
    """At each of the seven turns the lowest speed within three lines is the one LinuxCNC
    runs: a corner's blend arc leaves half of each 0.05 mm chord, run at 0.025 / 0.00102 =
    24.51 mm/s; a tangent kink keeps 0.05 / 0.00102 = 49.02 mm/s. Recorded 2026-11-28:
    24.51 at six turns, 49.02 at the fourth; 0.384 s (predicted 0.383 s; 0.347 s, -9.6 %,
    with the plane's acceleration in the kink test)."""
    text, after = _diagonal_chords()
    tr = record(tmp_path, "diagonal", text)
    data = np.genfromtxt(tr["csv"], delimiter=",", names=True)
    s = predicted(tr["prog"]).sample(0.001)
    for k in after:
        near = np.abs(tr["line"] - k) <= 3
        ours = np.abs(s.line - k) <= 3
        assert s.v[ours].min() == pytest.approx(data["v"][near].min(), abs=0.5), k
    measured = float(tr["t"][-1] - tr["t"][0])
    assert s.t[-1] == pytest.approx(measured, rel=0.01)


#: 32 free-form chords of about 0.2 mm (a stretch of the blind benchmark's generated
#: free-form family, benchmarks/blind/families.py) through a tight spot: blend arcs of
#: 0.8-10 mm radius at P0.01, each taking half of both chords next to it.
_TIGHT_SPOT = (
    "X15.1075 Y49.7036",
    "X15.1952 Y49.8833",
    "X15.2867 Y50.0611",
    "X15.3822 Y50.2368",
    "X15.4824 Y50.4099",
    "X15.588 Y50.5797",
    "X15.7002 Y50.7453",
    "X15.8198 Y50.9055",
    "X15.9486 Y51.0585",
    "X16.0885 Y51.2014",
    "X16.2415 Y51.3299",
    "X16.4098 Y51.4375",
    "X16.5942 Y51.5142",
    "X16.7907 Y51.5482",
    "X16.9896 Y51.5329",
    "X17.1795 Y51.4716",
    "X17.3545 Y51.3754",
    "X17.514 Y51.2549",
    "X17.6597 Y51.118",
    "X17.7936 Y50.9695",
    "X17.9178 Y50.8128",
    "X18.034 Y50.65",
    "X18.1437 Y50.4828",
    "X18.2474 Y50.3118",
    "X18.3464 Y50.1381",
    "X18.441 Y49.9619",
    "X18.5322 Y49.7839",
    "X18.6197 Y49.604",
    "X18.7044 Y49.4229",
    "X18.7867 Y49.2406",
    "X18.8667 Y49.0573",
    "X18.9443 Y48.8729",
)


def test_speed_stays_under_a_blend_arcs_limit_along_the_whole_arc(tmp_path):
    """Out of the tight spot (program lines 21-27) each blend arc's limit sqrt(0.866 x 2000
    R) holds along the whole arc (LinuxCNC runs it as a segment of its own, the limit its
    top speed): the speed climbs from arc to arc. Recorded 2026-11-28: top speeds on those
    lines 38.3, 42.7, 47.7, 51.7, 55.7, 58.7, 61.7 mm/s; ncperf within 1.5 mm/s (1.9-3.9
    mm/s above them while an arc's far half was left to climb past its limit); RMS over
    time 0.67 mm/s (1.26 before); 0.505 s for the recorded 0.510 s (0.503 s before)."""
    text = "(0.2 mm free-form chords through a tight spot, F6000, G64 P0.01 Q0)\n"
    text += "G21 G17 G90 G94\nG64 P0.01 Q0\nG0 X15.0227 Y49.5224 Z0\n"
    text += "G1 X15.0227 Y49.5224 Z0 F6000\n"
    text += "".join(f"G1 {xy}\n" for xy in _TIGHT_SPOT) + "M2\n"
    tr = record(tmp_path, "tight", text)
    data = np.genfromtxt(tr["csv"], delimiter=",", names=True)
    s = predicted(tr["prog"]).sample(0.001)
    for k in range(21, 28):
        top = data["v"][tr["line"] == k].max()
        assert s.v[s.line == k].max() == pytest.approx(top, abs=1.6), k
    t = np.arange(0.0, min(tr["t"][-1] - tr["t"][0], s.t[-1]), 0.001)
    measured = np.interp(t, tr["t"] - tr["t"][0], data["v"])
    assert np.sqrt(np.mean((np.interp(t, s.t, s.v) - measured) ** 2)) < 0.9


def test_a_servo_period_is_read_off_the_traces_clock(tmp_path):
    """Twelve 2 mm squares at F1200 recorded with a 3 ms servo period: LinuxCNC's sampler
    writes one row per servo period, 3 ms apart, where linuxcnc-sim's traces sample its
    1 ms period. The diagnosis names block_cycle_time from the clock, t_block = 1.02 x 3 =
    3.06 ms, and the feed moves do not contradict it: its held-out gap is no worse than the
    machine file's by more than the floor."""
    text = SQUARES.replace("G0 Z5", "".join(_SQUARE * 10) + "G0 Z5")
    tr = record(tmp_path, "squares3", text, servo_ns=3_000_000)
    assert sample_cycle([tr["t"]]) == pytest.approx(0.003, abs=1e-9)
    nc = Ncperf()
    tp = nc.extract(str(tr["prog"]))
    effects = nc.effects()
    base = setup_for(load_preset("linuxcnc-sim"), effects)
    trace = nc.read_trace(str(tr["csv"]))
    d = nc.diagnose([(tp, [align(tp, trace)], ["t"])], base, "profile", effects)
    assert d.on_clock and d.chosen[0] == "block_cycle_time"
    assert d.chosen_params["block_cycle_time"]["t_block"] == pytest.approx(0.00306, rel=1e-6)
    assert d.clock is not None
    assert d.clock.held_out_gap_after <= d.clock.held_out_gap_before + d.floor


def test_chords_slow_down_before_a_long_line_where_the_lazy_look_ahead_left_them(tmp_path):
    """Runs of 0.06 mm chords into a 1.2, 2.4 and 1.2 mm line, each ending in a 90 degree
    corner (tests/test_linuxcnc_lookahead.py): LinuxCNC's lazy walks leave the chords five
    and more before each long line at sqrt(a L / 2 + 2 a_t l ...) (core.engine.lookahead).
    Recorded 2026-11-28 (a study program of the same shape): lowest speeds 42.56, 54.81 and
    42.37 mm/s in the lines before the long lines, where ncperf now gives 43.00, 55.16 and
    43.01 (58.82, the chords' limit, before); RMS over time 1.19 mm/s (9.48 before); 0.679 s
    for the recorded 0.681 s (0.668 s before)."""
    from tests.test_linuxcnc_lookahead import LONG_LINES, _program

    tr = record(tmp_path, "lazy", _program())
    data = np.genfromtxt(tr["csv"], delimiter=",", names=True)
    s = predicted(tr["prog"]).sample(0.001)
    for long, back, _ in LONG_LINES:
        near = (tr["line"] >= long - back) & (tr["line"] < long)
        ours = (s.line >= long - back) & (s.line < long)
        assert s.v[ours].min() == pytest.approx(data["v"][near].min(), abs=1.0), long
    t = np.arange(0.0, min(tr["t"][-1] - tr["t"][0], s.t[-1]), 0.001)
    measured = np.interp(t, tr["t"] - tr["t"][0], data["v"])
    assert np.sqrt(np.mean((np.interp(t, s.t, s.v) - measured) ** 2)) < 2.0
    assert s.t[-1] == pytest.approx(float(tr["t"][-1] - tr["t"][0]), rel=0.01)


def test_blend_arcs_between_feeds_ramp_along_the_arc(tmp_path):
    """A plunge at F600 into a cut at F5000, the cut into a move at F1200 and that into
    a cut at F5000, under G64 P0.15 (tests/test_linuxcnc_arc_ramps.py): LinuxCNC's blend
    arc at each corner asks for the higher feed, so the speed leaves the slow block at its
    tangent point and changes along the arc at 1000 mm/s^2 (half the plane's 2000) up to
    the arc's limit (core.engine.profile._arc_ramps). Before, ncperf held the corner at
    the lower feed over both halves of the arc: the plunge's corner 20-25 ms slow (as on
    the blind benchmark's coarse-G64 2.5D parts). Recorded 2026-11-28: 1.542 s; predicted
    1.540 s, RMS over time 0.69 mm/s (the code before: 1.578 s, +2.3 %, RMS 18.2 mm/s)."""
    from tests.test_linuxcnc_arc_ramps import PLUNGE

    tr = record(tmp_path, "plunge", PLUNGE)
    data = np.genfromtxt(tr["csv"], delimiter=",", names=True)
    s = predicted(tr["prog"]).sample(0.001)
    measured_t = float(tr["t"][-1] - tr["t"][0])
    assert s.t[-1] == pytest.approx(measured_t, abs=0.004)
    # the time from the plunge's start to the end of the cut after the slow move
    t = np.arange(0.0, min(measured_t, s.t[-1]), 0.001)
    measured = np.interp(t, tr["t"] - tr["t"][0], data["v"])
    assert np.sqrt(np.mean((np.interp(t, s.t, s.v) - measured) ** 2)) < 2.0
