"""G-code adapter: every supported word and mode, and every error path (naming its line)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from adapters.gcode import read_gcode
from core import ExtractOptions, InputError, MoveKind, PathMode, UsageError


def read(text: str, name: str = "t.nc", **kw):
    return read_gcode(text.encode(), name, **kw)


def fails(text: str, line: int, fragment: str, name: str = "t.nc", **kw) -> InputError:
    with pytest.raises(InputError) as info:
        read(text, name, **kw)
    msg = str(info.value)
    assert msg.startswith(f"{name}:{line}:"), msg
    assert fragment in msg, msg
    assert "\n" not in msg
    return info.value


def notices(tp) -> str:
    return "\n".join(str(n) for n in tp.notices)


# ------------------------------------------------------------------------------ lines
def test_lines_modal_motion_and_block_numbers():
    """G1 is modal; N words become block numbers; moves keep their 1-based source line."""
    tp = read("G21 G90 G17\nN10 G1 X10 Y0 Z0 F600\nN20 Y5\nX0\n")
    assert tp.n == 3
    assert list(tp.kind) == [MoveKind.LINE] * 3
    assert list(tp.line) == [2, 3, 4]
    assert list(tp.block) == [10, 20, -1]
    assert np.allclose(tp.end, [[10, 0, 0], [10, 5, 0], [0, 5, 0]])
    assert np.allclose(tp.feed, 10.0)  # 600 mm/min = 10 mm/s
    assert np.allclose(tp.length, [10, 5, 10])


def test_rapids_have_no_feed():
    """G0 moves are rapids with NaN feed; the next G1 needs its own F (modal F carries over)."""
    tp = read("G21\nG0 X5 Y5 Z5\nG1 Z0 F300\nG0 Z5\nG1 X6 Z0\n")
    assert list(tp.kind) == [0, 1, 0, 1]
    assert np.isnan(tp.feed[[0, 2]]).all()
    assert np.allclose(tp.feed[[1, 3]], 5.0)


def test_words_in_any_order_and_lowercase_and_spaces():
    """Word order in a block does not matter; lower case and spaces inside numbers are read."""
    tp = read("g21\nf600 x1 0 g1 y2\n")
    assert np.allclose(tp.end[0], [10, 2, 0])


def test_incremental_mode():
    """G91 adds to the position, G90 sets it again."""
    tp = read("G21 G90 G1 X1 Y1 F60\nG91 X2 Y-1\nX1\nG90 X0 Y0\n")
    assert np.allclose(tp.end, [[1, 1, 0], [3, 0, 0], [4, 0, 0], [0, 0, 0]])


def test_inch_program():
    """G20: positions and feeds in inch are converted to mm and mm/s."""
    tp = read("G20 G90\nG1 X1 Y0 F10\nX2\n")
    assert np.allclose(tp.end, [[25.4, 0, 0], [50.8, 0, 0]])
    assert np.allclose(tp.feed, 10 * 25.4 / 60)
    assert tp.units == "inch"


def test_units_switch_mid_program():
    """Units are modal per block: G21 after G20 reads the next words in mm."""
    tp = read("G20\nG1 X1 F10\nG21 X50 F600\n")
    assert np.allclose(tp.end[:, 0], [25.4, 50.0])
    assert np.allclose(tp.feed, [25.4 * 10 / 60, 10.0])


def test_siemens_g70_and_g700():
    """Siemens G70: geometry in inch, feed still mm/min; G700: both in inch."""
    tp = read("G70 G1 X1 F600\n", "t.mpf")
    assert tp.end[0, 0] == pytest.approx(25.4)
    assert tp.feed[0] == pytest.approx(10.0)
    tp = read("G700 G1 X1 F10\n", "t.mpf")
    assert tp.feed[0] == pytest.approx(10 * 25.4 / 60)


def test_no_units_word_assumes_mm_with_a_notice():
    """A program without G20/G21 is read in mm and says so."""
    tp = read("G1 X1. F60.\n")
    assert tp.end[0, 0] == 1.0
    assert "millimetres assumed" in notices(tp)


# ------------------------------------------------------------------------------ arcs
def test_arc_ijk_quarter_cw_and_ccw():
    """G2/G3 with incremental I J: the same end points give 270 deg one way, 90 deg the other."""
    # From (0,0), the bottom of the circle around (0,5), to (5,5), its right side:
    # counter-clockwise (G3) is the quarter, clockwise (G2) three quarters.
    cw = read("G21 G17 G1 X0 Y0 F60\nG2 X5 Y5 I0 J5\n")
    ccw = read("G21 G17 G1 X0 Y0 F60\nG3 X5 Y5 I0 J5\n")
    assert cw.kind[-1] == MoveKind.ARC_CW and ccw.kind[-1] == MoveKind.ARC_CCW
    assert np.allclose(cw.center[-1], [0, 5, 0])
    assert cw.sweep[-1] == pytest.approx(3 * math.pi / 2)
    assert ccw.sweep[-1] == pytest.approx(math.pi / 2)
    assert ccw.length[-1] == pytest.approx(2 * math.pi * 5 / 4)
    # clockwise from (0,0) around (0,5): the tangent at the start points to -X
    assert np.allclose(cw.tangent_start[-1], [-1, 0, 0])
    assert np.allclose(ccw.tangent_start[-1], [1, 0, 0])
    assert cw.curvature[-1] == pytest.approx(-0.2) and ccw.curvature[-1] == pytest.approx(0.2)


@pytest.mark.parametrize(
    "block,centre,sweep_deg",
    [
        ("G2 X10 Y0 R10", (5, -8.660254038, 0), 60),
        ("G2 X10 Y0 R-10", (5, 8.660254038, 0), 300),
        ("G3 X10 Y0 R10", (5, 8.660254038, 0), 60),
        ("G3 X10 Y0 R-10", (5, -8.660254038, 0), 300),
    ],
    ids=["G2 R+ short", "G2 R- long", "G3 R+ short", "G3 R- long"],
)
def test_arc_r_both_ways(block, centre, sweep_deg):
    """R > 0 takes the short way (< 180 deg), R < 0 the long way; chord 10, R 10: h = 8.66."""
    tp = read(f"G21 G17 G1 X0 Y0 F60\n{block}\n")
    assert np.allclose(tp.center[-1], centre)
    assert math.degrees(tp.sweep[-1]) == pytest.approx(sweep_deg)


def test_siemens_cr_is_a_radius():
    """Siemens CR= gives the radius like R."""
    tp = read("G71 G17 G1 X0 Y0 F60\nG2 X10 Y0 CR=10\n", "t.mpf")
    assert np.allclose(tp.center[-1], (5, -8.660254038, 0))


def test_full_circle():
    """End point = start point with I J: a full circle of 2 pi R."""
    tp = read("G21 G1 X0 Y0 F60\nG2 X0 Y0 I5 J0\n")
    assert tp.sweep[-1] == pytest.approx(2 * math.pi)
    assert tp.length[-1] == pytest.approx(10 * math.pi)


def test_full_circle_without_end_point():
    """Fanuc style: G2 I5 with no axis words is a full circle."""
    tp = read("G21 G1 X0 Y0 F60\nG2 I5\n")
    assert tp.length[-1] == pytest.approx(10 * math.pi)


def test_helix_and_turns():
    """A helical arc: length sqrt((R sweep)^2 + h^2); LinuxCNC P2 adds a turn."""
    tp = read("G21 G17 G1 X0 Y0 Z0 F60\nG3 X0 Y0 Z-2 I5 J0\n")
    assert tp.length[-1] == pytest.approx(math.hypot(10 * math.pi, 2))
    # pitch per radian -2/(2 pi); tangent has a -Z component
    assert tp.tangent_start[-1][2] < 0
    tp = read("G21 G17 G1 X0 Y0 Z0 F60\nG3 X0 Y0 Z-2 I5 J0 P2\n", "t.ngc")
    assert tp.sweep[-1] == pytest.approx(4 * math.pi)
    assert tp.length[-1] == pytest.approx(math.hypot(20 * math.pi, 2))
    # curvature of a helix: r / (r^2 + c^2), c = 2 / (4 pi)
    c = 2 / (4 * math.pi)
    assert abs(tp.curvature[-1]) == pytest.approx(5 / (25 + c * c))


def test_arc_absolute_centres_g90_1():
    """LinuxCNC G90.1: I J are absolute centre coordinates."""
    tp = read("G21 G1 X10 Y0 F60\nG90.1 G3 X0 Y10 I0 J0\n", "t.ngc")
    assert np.allclose(tp.center[-1], [0, 0, 0])
    assert tp.sweep[-1] == pytest.approx(math.pi / 2)


@pytest.mark.parametrize(
    "plane,block,normal,mid",
    [
        ("G18", "G2 X10 Z0 I5 K0", (0, 1, 0), (5, 0, -5)),
        ("G19", "G2 Y10 Z0 J5 K0", (1, 0, 0), (0, 5, 5)),
        ("G17", "G2 X10 Y0 I5 J0", (0, 0, 1), (5, 5, 0)),
    ],
    ids=["G18", "G19", "G17"],
)
def test_arc_planes(plane, block, normal, mid):
    """G17/G18/G19: G2 is clockwise seen from +Z, +Y and +X (ISO 6983)."""
    # G18 seen from +Y: Z points right, X up; from (x0,z0) to (x10,z0) clockwise passes z = -5.
    # G19 seen from +X: Y right, Z up; from y0 to y10 clockwise passes over the top, z = +5.
    tp = read(f"G21 G1 X0 Y0 Z0 F60\n{plane} {block}\n")
    assert np.allclose(tp.normal[-1], normal)
    from core.model.geometry import sample_arcs

    pts = sample_arcs(
        tp.start[-1:],
        tp.center[-1:],
        tp.normal[-1:],
        np.array([False]),
        tp.sweep[-1:],
        np.zeros(1),
        np.array([2]),
    )
    assert np.allclose(pts[1], mid, atol=1e-9)


def test_arc_end_tolerance_accepted():
    """An end point 0.01 mm off the circle is inside LinuxCNC's 0.028 mm tolerance."""
    tp = read("G21 G1 X0 Y0 F60\nG2 X10.01 Y0 I5 J0\n")
    assert tp.kind[-1] == MoveKind.ARC_CW


# ------------------------------------------------------------------------------ feed, modes
def test_feed_is_modal_and_converted():
    """F is modal and in mm/min at the edge, mm/s inside."""
    tp = read("G21 G1 X1 F1200\nX2\nX3 F600\n")
    assert np.allclose(tp.feed, [20, 20, 10])


def test_path_modes_g61_g64_g9_and_m0():
    """G61 (modal) and G9 (one block) and M0/M1 end a move at rest; G64 is continuous."""
    tp = read("G21 G64 G1 X1 F60\nG9 X2\nX3\nG61 X4\nX5\nG64 X6\nX7 M0\nX8\nM1\nX9\n")
    exact = PathMode.EXACT_STOP
    assert list(tp.path_mode) == [0, exact, 0, exact, exact, 0, exact, exact, 0]


def test_siemens_path_modes():
    """Siemens G60 is exact stop, G641/G642 continuous."""
    tp = read("G71 G60 G1 X1 F60\nG642 X2\nG641 X3\n", "t.mpf")
    assert list(tp.path_mode) == [PathMode.EXACT_STOP, 0, 0]


def test_linuxcnc_g64_p_sets_the_path_tolerance():
    """LinuxCNC G64 P0.02 is the path tolerance of the blocks it governs (mm; inch converted).
    (Q0: LinuxCNC would otherwise run the collinear X1, X2 as one segment.)"""
    tp = read("G21 G64 P0.02 Q0 G1 X1 F60\nX2\nG64 X3\nG20 G64 P0.001 X1\n", "t.ngc")
    assert np.allclose(tp.tolerance[:2], 0.02)
    assert np.isnan(tp.tolerance[2])
    assert tp.tolerance[3] == pytest.approx(0.0254)


@pytest.mark.parametrize(
    "dialect,block,seconds",
    [
        ("linuxcnc", "G4 P1.5", 1.5),
        ("fanuc", "G4 P1500", 1.5),
        ("fanuc", "G4 X2.", 2.0),
        ("siemens", "G4 F2.5", 2.5),
    ],
    ids=["linuxcnc P s", "fanuc P ms", "fanuc X s", "siemens F s"],
)
def test_dwell(dialect, block, seconds):
    """G4 dwell is added after the last move, in each dialect's own units."""
    tp = read(f"G21 G1 X1 F60\n{block}\nX2\n", dialect=dialect)
    assert list(tp.dwell) == [seconds, 0.0]
    assert np.allclose(tp.end[:, 0], [1, 2])  # the dwell's X is not a position
    assert tp.feed[1] == 1.0  # Siemens G4 F does not change the feed


def test_tool_changes_make_operations():
    """T n M6 starts an operation with tool n."""
    tp = read("G21\nT1 M6\nG0 X0 Y1\nG1 X1 F60\nT2 M6\nG0 X5\nG1 X6\n")
    assert len(tp.op_names) == 2
    assert list(tp.op_offsets) == [0, 2, 4]
    assert list(tp.tool) == [1, 1, 2, 2]
    assert "T2" in tp.op_names[1]
    # no junction across the tool change
    assert 1 not in set(tp.junctions.tolist())


def test_words_that_do_not_change_the_path():
    """S, M3/M5/M8/M9, H with G43, D, G40, G49, G80, G94, G17 pass."""
    tp = read("G21 G17 G40 G49 G80 G94\nG0 G43 H1 Z5 S12000 M3 M8\nG1 X1 F60 D2\nM5 M9\n")
    assert tp.n == 2


# ------------------------------------------------------------------------------ syntax
def test_comments_percent_and_o_number():
    """( ) and ; comments, % lines and a program number O are passed over."""
    text = (
        "%\nO1234 (PART)\n(comment only)\nG21 (mm) G1 X1 F60 ; end comment\n"
        "; whole line\nX2 (a (b)\n%\n"
    )
    tp = read(text.replace("(a (b)", "(a b)"))
    assert np.allclose(tp.end[:, 0], [1, 2])
    assert list(tp.line) == [4, 6]
    # a nested comment is one comment, with a note (LinuxCNC refuses it; Fanuc and Haas
    # controls read "(" to the matching ")")
    tp = read("G21 G1 X1 F60\nX2 (a (b) c)\n")
    assert np.allclose(tp.end[:, 0], [1, 2])
    assert "t.nc:2: warning: nested comment: read as one comment" in notices(tp)


def test_block_delete_switch():
    """/ blocks run with the switch off (default, with a notice) and are skipped with it on."""
    text = "G21 G1 X1 F60\n/X5\nX2\n"
    off = read(text)
    assert np.allclose(off.end[:, 0], [1, 5, 2])
    assert "block-delete lines executed" in notices(off)
    on = read(text, block_delete=True)
    assert np.allclose(on.end[:, 0], [1, 2])


def test_program_end_stops_reading():
    """Nothing after M30 (or M2) is read; moves there are reported."""
    tp = read("G21 G1 X1 F60\nM30\nG1 X5\n")
    assert tp.n == 1
    assert "after the end of program" in notices(tp)


def test_zero_length_moves_are_dropped_with_a_notice():
    """A move to where the tool already is has no direction: dropped, counted, line named."""
    tp = read("G21 G1 X1 F60\nX1\nX1\nX2\n")
    assert tp.n == 2
    assert (
        "t.nc:2: warning: moves shorter than the 0.001 mm resolution dropped (points, not "
        "blocks) (2 lines)" in notices(tp)
    )
    # 0.0005 mm is a point too; the next line starts where the path was (1.0, not 1.0005)
    tp = read("G21 G1 X1 F60\nX1.0005\nX2\n")
    assert tp.n == 2 and tp.start[1, 0] == 1.0 and tp.end[1, 0] == 2.0


def test_fanuc_decimal_point_notice():
    """Fanuc: X10 without a decimal point may mean 0.010 mm; ncperf reads 10 mm and says so."""
    tp = read("G21 G1 X10 F60\n", dialect="fanuc")
    assert tp.end[0, 0] == 10.0
    assert "no decimal point" in notices(tp)
    assert "decimal point" not in notices(read("G21 G1 X10. F60.\n", dialect="fanuc"))


def test_work_offset_g28_g53_notices():
    """Offsets the program and the machine file leave unknown are taken as 0, with a notice
    naming the line, never silently (G28 and G53 go to machine coordinates)."""
    tp = read("G21 G54 G0 X0 Y0 Z5\nG1 X1 F60\nG91 G28 Z0\nG90 G55 G0 X5\nG53 G0 Z-10\n")
    text = notices(tp)
    assert "t.nc:3: warning: G28 moves in machine coordinates but the work offset G54" in text
    assert "t.nc:4: warning: work offset changes to G55, whose value is not known" in text
    assert "t.nc:5: warning: G53 moves in machine coordinates but the work offset G55" in text
    # G28 with Z named: to the intermediate point (here, incremental 0) then Z to home 0
    assert np.allclose(tp.end, [[0, 0, 5], [1, 0, 5], [1, 0, 0], [5, 0, 0], [5, 0, -10]])


def test_unknown_start_notice():
    """A feed move before every axis is set starts at 0 for the missing axes, with a notice."""
    tp = read("G21 G1 X1 F60\n")
    assert "feed move starts before XYZ was programmed: 0 assumed" in notices(tp)


@pytest.mark.parametrize(
    "name,text,dialect",
    [
        ("a.ngc", "G1 X1 F1", "linuxcnc"),
        ("a.mpf", "G1 X1 F1", "siemens"),
        ("a.nc", "G1 X1 F1\nSOFT", "siemens"),
        ("a.nc", "G64 P0.01\nG1 X1 F1", "linuxcnc"),
        ("a.nc", "G1 X1 F1", "fanuc"),
    ],
    ids=["ngc", "mpf", "siemens keyword", "G64 P", "plain"],
)
def test_dialect_detection(name, text, dialect):
    """Extension first, then the words used, else Fanuc/ISO."""
    from adapters.gcode.interp import detect_dialect
    from adapters.gcode.lexer import Source, tokenize

    src = Source(name, text.encode())
    assert detect_dialect(name, tokenize(src)) == dialect


def test_vectorised_and_per_line_tokenisers_agree():
    """The numpy path and the per-line path read the same words from the same lines."""
    body = (
        "G21 G17 G90\nN10 G0 X1.5 Y-2 Z+.25\nG1 Z-0.125 F1200.\nG2 X3.5 Y0 I1 J1\n"
        "G3 X1.5 Y-2 R2.\nG1 X0 Y0 (c) Z1\n"
    )
    plain = read(body)
    # A ';' comment on every line sends every line through the per-line path.
    special = read("".join(line + " ;x\n" for line in body.splitlines()))
    for col in ("kind", "start", "end", "center", "sweep", "feed", "line", "block"):
        assert np.array_equal(getattr(plain, col), getattr(special, col), equal_nan=True), col


# ------------------------------------------------------------------------------ errors
ERRORS = [
    ("G21 G1 X1 F60\nG1 X2 E5\n", 2, "unknown word E"),
    ("G21 G1 X1 F60\nG1 X1" + "0" * 400 + "\n", 2, "X word out of range"),
    ("G21 G1 X1 F60\nG95 G1 X2 F0.1\n", 2, "G95 feed per revolution is not supported"),
    ("G21 G1 X1 F60\nM98 P100\n", 2, "subprogram O100 not found"),
    ("G21 G1 X1 F60\no100 sub\n", 2, "o100 sub without its end"),
    ("G21 G1 X1 F60\nG1 X[1+]\n", 2, "expression"),
    ("G21 G1 X1 F60\nG1 X#<undefined>\n", 2, "#<undefined>"),
    ("G21 G1 X1 F60\nG1 X1.2.3\n", 2, "malformed number '1.2.3' after X"),
    ("G21 G1 X1 F60\nG1 X--1\n", 2, "malformed number"),
    ("G21 G1 X1 F60\nG1 X.\n", 2, "malformed number"),
    ("G21 G1 X1 F60\nG1 X\n", 2, "word 'X' has no number"),
    ("G21 G1 X1 F60\nG1 XNAN\n", 2, "unknown word 'XNAN'"),
    ("G21 G1 X1 F60\nG1 X1 X2\n", 2, "two X words in one block"),
    ("G21 G1 X1 F60\nG1 G2 X2 I1\n", 2, "two G-codes of the same modal group"),
    ("G21\nX1\n", 2, "axis words without a motion mode"),
    ("G21 G1 X1\n", 1, "feed move without a feed rate F"),
    ("G21 G1 X1 F0\n", 1, "feed F must be positive"),
    ("G21 G1 X1 F60\nG95 X2\n", 2, "G95 feed per revolution is not supported"),
    ("G21 G1 X1 F60\nG123 X2\n", 2, "unknown G-code G123"),
    ("G21 G1 X1 F60\nG1.5 X2\n", 2, "unknown G-code G1.5"),
    ("G21 G1 X0 Y0 F60\nG2 X10 Y0 I4 J0\n", 2, "arc end point is 2.0000 mm off the circle"),
    ("G21 G1 X0 Y0 F60\nG2 X10 Y0 R4\n", 2, "R 4.0000 mm is less than half the chord"),
    ("G21 G1 X0 Y0 F60\nG2 X0 Y0 R4\n", 2, "R arc whose end point is its start point"),
    ("G21 G1 X0 Y0 F60\nG2 X10 Y0\n", 2, "arc without I/J/K or R"),
    ("G21 G1 X0 Y0 F60\nG2 X10 Y0 I5 R5\n", 2, "arc with both I/J/K and R"),
    ("G21 G1 X0 Y0 F60\nG17 G2 X10 Y0 I5 K1\n", 2, "K word is not in the arc's plane"),
    ("G21 G1 X0 Y0 F60\nG1 X1 I5\n", 2, "I word on a block that is not an arc"),
    ("G21 G1 X0 Y0 F60\nG1 X1 P5\n", 2, "P word not used by any code"),
    ("G21 G1 X0 Y0 F60\nG1 X1 Q5\n", 2, "Q word not used by any code"),
    ("G21 G1 X0 Y0 F60\nG1 X1 L5\n", 2, "L word"),
    ("G21 G1 X1 F60\nO100 G1 X2\n", 2, "O word with other words"),
    ("G21 G1 X1 F60\nG1 X2 (open\n", 2, "comment '(' is not closed"),
    ("G21 G1 X1 F60\nG1 X2 )\n", 2, "')' without '('"),
    ("G21 G1 X1 F60\nG1 X2 é\n", 2, "non-ASCII character"),
    ("G21 G1 X1 F60\nG1 X2 / Y3\n", 2, "'/' inside a block"),
    ("G21 G1 X1 F60\nG4\n", 2, "G4 dwell without a time"),
]


@pytest.mark.parametrize("text,line,fragment", ERRORS, ids=[e[2][:40] for e in ERRORS])
def test_errors_name_file_and_line(text, line, fragment):
    """Every error path: one line, 'FILE:LINE: what is wrong'."""
    fails(text, line, fragment)


SIEMENS_ERRORS = [
    ("G71 G1 X1 F60\nCIP X2 Y2 I1=1 J1=1\n", 2, "CIP"),
    ("G71 G1 X1 F60\nBSPLINE\n", 2, "spline interpolation"),
    ("G71 G1 X1 F60\nPOLY\n", 2, "POLY"),
    ("G71 G1 X1 F60\nG4 S10\n", 2, "G4 S"),
]


@pytest.mark.parametrize("text,line,fragment", SIEMENS_ERRORS, ids=[e[2] for e in SIEMENS_ERRORS])
def test_siemens_errors(text, line, fragment):
    """Siemens CIP, splines, polynomials, parameters, frames and cycles: errors with the line."""
    fails(text, line, fragment, name="t.mpf")


def test_siemens_pass_keywords_and_compressor_notice():
    """SOFT, FFWON, G642 pass; COMPCAD passes with a notice that compression is not modelled."""
    tp = read("G71 SOFT FFWON G642\nCOMPCAD\nG1 X1 F600\n", "t.mpf")
    assert tp.n == 1
    assert "compressor" in notices(tp)


def test_linuxcnc_spline_and_lathe_codes():
    """LinuxCNC G5 splines and G70/G71 lathe cycles are errors (not units)."""
    fails("G21 G1 X1 F60\nG5 X2 Y2 I1 J1 P1 Q1\n", 2, "cubic spline G5", name="t.ngc")
    fails("G21 G1 X1 F60\nG71 X2\n", 2, "lathe cycle", name="t.ngc")


def test_empty_and_blank_files():
    """An empty file and a file of blank lines: one-line error naming the file."""
    for text in ("", "\n\n  \n"):
        with pytest.raises(InputError, match=r"^t\.nc: empty file"):
            read(text)


def test_no_moves():
    """A program with words but no motion: an error, not an empty analysis."""
    with pytest.raises(InputError, match=r"^t\.nc: no moves"):
        read("G21 G90\nM30\n")


def test_binary_file():
    """A NUL byte: 'binary file' naming its line, without echoing the bytes."""
    with pytest.raises(InputError, match=r"^t\.nc:2: binary file") as info:
        read_gcode(b"G21\nG1\x00\x01\x02X1\n", "t.nc")
    assert "\x00" not in str(info.value)


def test_fifty_megabyte_line():
    """A 50 MB line without a newline: an error naming line 1 and its length, quickly."""
    data = b"G1X1" * (50 * 1024 * 1024 // 4)
    with pytest.raises(InputError) as info:
        read_gcode(data, "big.nc")
    msg = str(info.value)
    assert msg.startswith("big.nc:1: line is 52428800 characters long")
    assert len(msg) < 200


def test_unknown_dialect_is_a_usage_error():
    """--dialect with an unknown name is the caller's mistake, not the file's."""
    with pytest.raises(UsageError, match="unknown G-code dialect 'heidenhain'"):
        read("G1 X1 F1", dialect="heidenhain")


def test_extract_hook_recognises_by_extension_and_content(tmp_path):
    """The A1 hook takes G-code extensions and G-code-looking files, and returns None otherwise."""
    from adapters import gcode

    opts = ExtractOptions()
    p = tmp_path / "part.nc"
    p.write_text("G21 G1 X1 F60\n")
    assert gcode.ncperf_extract(source=str(p), options=opts).n == 1
    q = tmp_path / "part.txt"
    q.write_text("%\nG21 G1 X1 F60\n")
    assert gcode.ncperf_extract(source=q, options=opts).n == 1
    r = tmp_path / "part.cls"
    r.write_text("GOTO/1,2,3\n")
    assert gcode.ncperf_extract(source=str(r), options=opts) is None
    assert gcode.ncperf_extract(source=object(), options=opts) is None
    with pytest.raises(InputError, match="cannot read"):
        gcode.ncperf_extract(source=str(tmp_path / "missing.nc"), options=opts)


def test_line_endings():
    """CRLF (Windows) and CR-only (old Mac) line ends read like LF."""
    lf = read("G21\nG1 X1 F60\nX2\n")
    for text in ("G21\r\nG1 X1 F60\r\nX2\r\n", "G21\rG1 X1 F60\rX2\r"):
        tp = read(text)
        assert np.array_equal(tp.end, lf.end) and list(tp.line) == [2, 3]


def test_siemens_ctol_sets_the_path_tolerance():
    """Siemens CTOL= is the path tolerance of the blocks after it (inch programs converted)."""
    tp = read("G71 G642\nG1 X1 F600\nCTOL=0.02\nX2\nG70 X1\n", "t.mpf")
    assert np.isnan(tp.tolerance[0])
    assert tp.tolerance[1] == pytest.approx(0.02)
    assert tp.tolerance[2] == pytest.approx(0.02 * 25.4)


# ------------------------------------------------------------------------------ issue 10
def test_r_on_a_line_is_an_error_in_linuxcnc_but_corner_rounding_in_fanuc():
    """LinuxCNC refuses R on G1; Fanuc reads G1 X.. R.. as corner rounding."""
    fails("G21 G1 X0 Y0 F60\nG1 X1 R5\n", 2, "R word on a block that is not an arc", "t.ngc")
    # Fanuc: a 90 degree corner at (10, 0) rounded with R2: the first line stops 2 mm
    # short (R tan(45 deg) = 2), a quarter arc of radius 2 centred at (8, 2), then the
    # second line from (10, 2)
    tp = read("G21 G90 G1 X0 Y0 F600\nG1 X10 R2\nG1 Y10\n", dialect="fanuc")
    ends = tp.end[tp.length > 0]
    assert np.allclose(ends[-3:], [[8, 0, 0], [10, 2, 0], [10, 10, 0]])
    arc = int(np.flatnonzero(tp.is_arc)[0])
    assert np.allclose(tp.center[arc], [8, 2, 0]) and tp.kind[arc] == MoveKind.ARC_CCW


def test_zero_radius_arc_is_a_point():
    """A full circle of radius 0 moves nothing: a point with a notice, not an error."""
    tp = read("G21 G1 X0 Y0 Z0 F60\nG1 X5\nG2 X5 Y0 I0 J0\nG1 X6\n", "t.ngc")
    assert np.allclose(tp.end[:, 0], [5, 6])
    assert "t.ngc:3: warning: arcs of zero radius are points" in notices(tp)


def test_heidenhain_klartext_is_refused_with_one_line():
    """A Heidenhain conversational file: FILE:LINE, exit 1 (no adapter yet), not 'unknown'."""
    fails("0 BEGIN PGM 1 MM\n1 L X+10 R0 FMAX\n2 END PGM 1 MM\n", 1, "Heidenhain", "part.h")


def test_a_heidenhain_header_indented_or_numbered_is_found_and_blank_lines_do_not_stall():
    """The Klartext header with blanks or a block number before it, and a file of 2000 empty
    lines and 5000 blanks (the old pattern, blanks on both sides of an optional number,
    backtracked about 285 s on it): the header is found; the blanks are an empty program."""
    fails("\n  12 BEGIN PGM 1 MM\n", 2, "Heidenhain", "part.h")
    fails("\t BEGIN PGM 1 MM\n", 1, "Heidenhain", "part.h")
    with pytest.raises(InputError, match="empty"):
        read("\n" * 2000 + " " * 5000, "blank.nc")


def test_free_text_after_the_program_end_is_not_read():
    """Nothing after M30 runs, so text there (even non-ASCII) refuses nothing."""
    tp = read("G21 G1 X1 F60\nM30\nthis is free text \u00e9 #[\n")
    assert tp.n == 1


def test_the_first_offending_line_is_named_quoted_as_written():
    """Two constructs ncperf refuses: the first is named, its line quoted in its own case."""
    err = fails("G21 G1 X1 F60\nG76 p1 z-1\nG5 X1 Y2\n", 2, "G76 threading cycle", "t.ngc")
    assert str(err).endswith(": G76 p1 z-1")


def test_fanuc_rigid_tapping_g84_2_and_look_ahead_codes():
    """G84.2 (Fanuc rigid tapping) runs G84's moves: rapid over the hole at the initial
    level 10 (G98), rapid to R 2, feed to -10 and back to R, rapid up to 10; G05.1 Q1 and
    G08 P1 (look-ahead modes) are read with a note."""
    tp = read("G21 G90\nG0 X0 Y0 Z10\nM3 S500\nG84.2 X5 Y5 Z-10 R2 F625\nG80\nM30\n")
    assert np.allclose(
        tp.end, [[0, 0, 10], [5, 5, 10], [5, 5, 2], [5, 5, -10], [5, 5, 2], [5, 5, 10]]
    )
    assert list(tp.kind) == [0, 0, 0, 1, 1, 0]
    for code in ("G05.1 Q1", "G08 P1"):
        tp = read(f"G21 G90\n{code}\nG0 X0 Y0 Z5\nG1 X10 F500\nM30\n")
        assert "look-ahead" in notices(tp) or "contour control" in notices(tp)


def test_siemens_cycle800_without_a_swivel_passes_and_with_one_is_refused():
    """CYCLE800 with its swivel data record's name (a string) and all angles 0 changes
    nothing; with an angle (argument 8, _A) it needs the machine's kinematics: refused."""
    call = 'CYCLE800(1,"TC1",0,57,0,0,0,{a},0,0,0,0,0,1)'
    tp = read(f"G71 G90\n{call.format(a=0)}\nG0 X0 Y0 Z10\nG1 X10 F100\nM30\n", "t.mpf")
    assert np.allclose(tp.end, [[0, 0, 10], [10, 0, 10]])
    fails(f"G71 G90\n{call.format(a=30)}\nG1 X10 F100\n", 2, "CYCLE800 swivelling", "t.mpf")


def test_siemens_expressions_with_blanks_around_operators():
    """840D programs write "R2 = R1 / 15": the blanks do not split the expression.
    D = 30: R1 = 30 / 15 = 2, R2 = 2 * 2 + 1 = 5, R3 = 7 DIV 2 = 3 (integer division)."""
    tp = read(
        "G71 G90\nDEF REAL D=30\nR1 = D / 15\nR2 = R1 * 2 + 1\nR3 = 7 DIV 2\n"
        "G1 X=R1 Y=R2 Z=R3 F100\nM30\n",
        "t.mpf",
    )
    assert np.allclose(tp.end, [[2, 5, 3]])


def test_marlin_dwell_s_in_seconds_and_haas_engraving_named():
    """Fusion's Marlin post writes G4 S2 (2 s); Haas G47 engraving is refused by name."""
    tp = read("G21 G90\nG0 X0 Y0 Z5\nG1 X10 F100\nG4 S2\nG1 X20\nM30\n", "t.gcode")
    assert np.allclose(tp.dwell, [0, 2, 0])
    assert "G4 S read as seconds (Marlin)" in notices(tp)
    fails(
        "G21 G90\nG0 X0 Y0\nG47 P0 (ABC) X0 Y0 I0 J.5 R.05 Z-.005 F15. E10.\n",
        3,
        "G47 text engraving",
    )


def test_feed_moves_before_the_first_f_run_at_it_with_a_notice():
    """Hobby CAM writes its first plunge before the F that follows: run at that F (800 mm/min
    = 13.33 mm/s, on line 4), said; with no F in the whole program, still the error."""
    tp = read("G21\nG0 X0 Y0 Z5\nG1 Z-1\nG1 X10 F800\nM2\n")
    assert np.allclose(tp.feed[1:], 800 / 60)
    assert "t.nc:3: warning: feed moves before the first F: run at that F (800, line 4)" in notices(
        tp
    )
    fails(
        "G21\nG0 X0 Y0 Z5\nG1 Z-1 (F800 is a comment)\nM2\n", 3, "feed move without a feed rate F"
    )


@pytest.mark.parametrize("prefix", ["", "#1 = 10\n"], ids=["vectorised", "full-interpreter"])
def test_linuxcnc_g61_is_exact_path_and_g61_1_exact_stop(prefix):
    """LinuxCNC's G61 is exact *path*: no blending, so a corner is a stop, but blocks that run
    on tangent do not stop; G61.1 is exact stop. Measured in LinuxCNC 2.9's planner
    (2026-11-26, ../shared/tools/linuxcnc, F3000): 50 mm/s kept through the joints of G1 X10,
    X20, X30 under G61, 0 at the 90 deg corner after them and at every block end under G61.1.
    ncperf reads G61 there as a continuous path of tolerance 0 (Fanuc's G61 stays exact stop:
    test_path_modes_g61_g64_g9_and_m0)."""
    tp = read(prefix + "G21 G61 G1 X10 F3000\nX20\nX30\nY10\nG61.1 X40\nX50\nG64 X60\n", "t.ngc")
    exact = PathMode.EXACT_STOP
    assert list(tp.path_mode) == [0, 0, 0, 0, exact, exact, 0]
    assert list(tp.tolerance[:4]) == [0.0, 0.0, 0.0, 0.0]
    assert np.isnan(tp.tolerance[4:]).all()


def test_numbers_without_decimal_point_short_and_absurdly_long():
    """A dimension word is "bare" (no decimal point, integer, nonzero) however long its
    number: X10, Z-3, Y+3, I5 and a 40-digit X are; Y2.5, X1., Y.5, J5. and a 30-digit Y
    ending in ".0" are not; G words never are."""
    from adapters.gcode.lexer import Source, tokenize

    text = (
        b"G1 X10 Y2.5 Z-3\nX" + b"1" * 40 + b" Y" + b"2" * 30 + b".0\nX1. Y.5 Z0007\n"
        b"G1 X-12 Y+3 I5 J5.\n"
    )
    w = tokenize(Source("t.nc", text))
    got = [(chr(c), bool(b)) for c, b in zip(w.letter, w.bare, strict=True)]
    assert got == [
        ("G", False), ("X", True), ("Y", False), ("Z", True),
        ("X", True), ("Y", False),
        ("X", False), ("Y", False), ("Z", True),
        ("G", False), ("X", True), ("Y", True), ("I", True), ("J", False),
    ]  # fmt: skip
