"""LinuxCNC's naive-CAM detector: under G64 P (Q defaulting to P) or G64 Q, LinuxCNC's
interpreter sends nearly collinear G1 blocks to its planner as one segment (LinuxCNC 2.9
emccanon.cc, ``see_segment``/``linkable``; rs274ngc ``convert_control_mode``). Expected
segments are worked out by hand from those rules; LinuxCNC's real planner is the oracle in
tests/test_linuxcnc_planner_traces.py."""

from __future__ import annotations

import math

import numpy as np
import pytest

from adapters.gcode import read_gcode
from core.model.toolpath import MoveKind


def read(text: str, **kw):
    return read_gcode(text.encode(), "t.ngc", **kw)


def segments(tp):
    """(line, start xy, end xy) of each feed move, rounded to 0.1 um."""
    feed = tp.kind != MoveKind.RAPID
    return [
        (int(ln), tuple(np.round(s[:2], 4)), tuple(np.round(e[:2], 4)))
        for ln, s, e in zip(tp.line[feed], tp.start[feed], tp.end[feed], strict=True)
    ]


def test_collinear_blocks_run_as_one_segment_with_the_last_line():
    """Three 1 mm blocks along X under G64 P0.01: one segment 0 -> 3, line 4 (as LinuxCNC's
    trace shows only the last block's line)."""
    tp = read("G21 G90 G64 P0.01\nG1 X1 F600\nX2\nX3\nM2\n")
    assert segments(tp) == [(4, (0.0, 0.0), (3.0, 0.0))]
    assert any("naive-CAM" in n.message for n in tp.notices)


def test_as_written_reads_every_block():
    tp = read("G21 G90 G64 P0.01\nG1 X1 F600\nX2\nX3\nM2\n", naive_cam=False)
    assert [s[0] for s in segments(tp)] == [2, 3, 4]


@pytest.mark.parametrize(
    "y, expected",
    [
        # (1, 0.009) is 0.009 mm from the segment (0,0)-(2,0): joined
        (0.009, [(3, (0.0, 0.0), (2.0, 0.0))]),
        # 0.011 mm: the collected point goes out alone, the next segment starts there
        (0.011, [(2, (0.0, 0.0), (1.0, 0.011)), (3, (1.0, 0.011), (2.0, 0.0))]),
    ],
)
def test_a_point_joins_only_within_the_tolerance(y, expected):
    tp = read(f"G21 G90 G64 P0.01\nG1 X1 Y{y} F600\nX2 Y0\nM2\n")
    assert segments(tp) == expected


def test_every_collected_point_is_tested():
    """Points (1, 0.004), (2, -0.004), (3, 0) join (each within 0.006 mm of the segment from
    (0,0) to the newest). The fifth point (4, 0.03) makes the segment y = 0.0075 x, from
    which (1, 0.004) is 0.0035 mm but (2, -0.004) 0.019 mm away (> 0.01): the first three
    blocks go out as one segment, (0,0)-(3,0) with line 4, and the fourth starts the next."""
    tp = read("G21 G90 G64 P0.01\nG1 X1 Y0.004 F600\nX2 Y-0.004\nX3 Y0\nX4 Y0.03\nM2\n")
    assert segments(tp) == [(4, (0.0, 0.0), (3.0, 0.0)), (5, (3.0, 0.0), (4.0, 0.03))]


def test_q_is_the_naive_cam_tolerance_and_q0_turns_it_off():
    text = "G21 G90 G64 P{p} Q{q}\nG1 X1 Y0.015 F600\nX2 Y0\nM2\n"
    assert len(segments(read(text.format(p=0.001, q=0.02)))) == 1
    assert len(segments(read(text.format(p=0.1, q=0)))) == 2


@pytest.mark.parametrize("mode", ["G64", "G61", "G61.1"])
def test_no_tolerance_no_joining(mode):
    """G64 without P or Q sets no naive-CAM tolerance; G61/G61.1 are not continuous."""
    tp = read(f"G21 G90 G64 P0.01\n{mode}\nG1 X1 F600\nX2\nM2\n")
    assert len(segments(tp)) == 2


@pytest.mark.parametrize(
    "between, joined",
    [
        ("F600", True),  # the same feed again: no flush
        ("F700", False),  # a new feed sends the collected points
        ("M8", False),  # coolant
        ("S2000", False),  # spindle speed
        ("G4 P0.5", False),  # dwell
        ("G64 P0.01", False),  # any path-mode block
        ("G18", True),  # a plane change sends nothing
        ("(a comment)", True),
    ],
)
def test_what_sends_the_collected_points(between, joined):
    tp = read(f"G21 G90 G64 P0.01\nG1 X1 F600\n{between}\nG1 X2\nM2\n")
    assert (len(segments(tp)) == 1) is joined


def test_a_segment_collects_at_most_101_points():
    """150 collinear 0.1 mm blocks: 101 in the first segment (lines 2-102, ending at
    X10.1), the other 49 in the second (to X15)."""
    body = "\n".join(f"X{0.1 * k:.1f}" for k in range(2, 151))
    tp = read(f"G21 G90 G64 P0.01\nG1 X0.1 F600\n{body}\nM2\n")
    assert segments(tp) == [(102, (0.0, 0.0), (10.1, 0.0)), (151, (10.1, 0.0), (15.0, 0.0))]


def test_inch_tolerance():
    """G20 G64 P0.0005 is 0.0127 mm: a point 0.012 mm off joins, 0.013 mm does not."""
    for off, n in ((0.012, 1), (0.013, 2)):
        tp = read(f"G20 G90 G64 P0.0005\nG1 X1 Y{off / 25.4:.7f} F10\nX2 Y0\nM2\n")
        assert len(segments(tp)) == n


def test_a_flat_xy_arc_runs_as_lines_through_its_middle():
    """A G17 arc of radius 10 mm over 0.08 rad strays r (1 - cos 0.04) = 0.0079995 mm from
    its chord: below Q 0.01 it is read as two lines through the point halfway round,
    (10 cos 0.04, 10 sin 0.04) = (9.9920, 0.3999); that point is 0.0079995 mm from the chord,
    so both join into the chord itself."""
    x1, y1 = 10 * math.cos(0.08), 10 * math.sin(0.08)
    arc = f"G21 G90 G17 G64 P0.01\nG0 X10 Y0\nG3 X{x1:.6f} Y{y1:.6f} I-10 J0 F600\nM2\n"
    assert segments(read(arc)) == [(3, (10.0, 0.0), (round(x1, 4), round(y1, 4)))]
    # split, not joined, when the tolerance is below the deviation: Q 0.007 -> an arc kept
    tp = read(arc.replace("P0.01", "P0.007"))
    assert [int(k) for k in tp.kind] == [MoveKind.RAPID, MoveKind.ARC_CCW]
    # a G18 arc is never split (LinuxCNC tests the XY plane only)
    g18 = f"G21 G90 G18 G64 P0.01\nG0 X10 Z0\nG2 X{x1:.6f} Z{y1:.6f} I-10 K0 F600\nM2\n"
    assert int(read(g18).kind[-1]) == MoveKind.ARC_CW


def test_half_an_arc_joins_the_line_before_it():
    """A line up X1 from Y-1 to Y0, then a G3 arc of radius 1 mm over 0.2 rad (deviation
    1 - cos 0.1 = 0.004996 mm < 0.01: two lines through (cos 0.1, sin 0.1) =
    (0.99500, 0.09983)). The first half joins the line: (1, 0) is 0.0045 mm from the segment
    (1,-1)-(0.99500,0.09983) (0.005 x 1 / 1.09983). The arc's end (cos 0.2, sin 0.2) =
    (0.98007, 0.19867) does not: (1, 0) is 0.0166 mm from (1,-1)-(0.98007,0.19867)
    (0.01993 x 1 / 1.19867). Both segments carry the arc's line, 4. The line after the arc
    turns to -X: the arc's end is 0.0987 mm from (0.99500,0.09983)-(-5,0.19867)."""
    x1, y1 = math.cos(0.2), math.sin(0.2)
    text = (
        f"G21 G90 G17 G64 P0.01\nG0 X1 Y-1\nG1 X1 Y0 F600\n"
        f"G3 X{x1:.6f} Y{y1:.6f} I-1 J0\nG1 X-5 Y{y1:.6f}\nM2\n"
    )
    mid = (round(math.cos(0.1), 4), round(math.sin(0.1), 4))
    segs = segments(read(text))
    assert segs[:2] == [(4, (1.0, -1.0), mid), (4, mid, (round(x1, 4), round(y1, 4)))]
    assert [s[0] for s in segs[2:]] == [5]


def test_programs_the_full_interpreter_runs_are_joined_too():
    """A G28 sends the program to the full interpreter: the blocks before it still join."""
    tp = read("G21 G90 G64 P0.01\nG1 X1 F600\nX2\nX3\nG28\nM2\n")
    assert [s[0] for s in segments(tp)] == [4]


def test_words_the_plain_reader_cannot_take_leave_a_notice():
    """G64 P#1: the tolerance is an expression the plain tokenizer does not read; ncperf says
    the joining is not modelled and reads every block."""
    tp = read("#1=0.01\nG21 G90 G64 P#1\nG1 X1 F600\nX2\nX3\nM2\n")
    assert [s[0] for s in segments(tp)] == [3, 4, 5]
    assert any("not modelled" in n.message for n in tp.notices)
