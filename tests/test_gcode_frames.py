"""Work offsets, frames, home returns, cutter compensation, the machine file's controller
setup and rotary axes of the G-code reader.

Every expected number is worked by hand (the derivation is in the comment beside it) from
the LinuxCNC 2.9 G-code reference (docs/src/gcode/g-code.adoc, coordinates.adoc,
tool-compensation.adoc), the Fanuc 0i-MF / Siemens 840D programming manuals, and the
closed forms of rest-to-rest moves. Where the program is LinuxCNC's, the same numbers came
out of LinuxCNC's own interpreter (benchmarks/lcnc_oracle.py, machine coordinates);
compensation with G41.1/G42.1 D (the diameter in the program) was checked there too.

Programs are written one block per list item: block k is line k (1-based). Paths are
reported in the coordinate system in force at the first move (the part's), so a move's
expected point is its machine position minus that system's offset.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from adapters.gcode import read_gcode
from adapters.gcode.control import MachineSetup
from adapters.gcode.run import run_program
from adapters.gcode.setup import machine_setup, read_tool_table
from core import InputError, MachineError, load_preset
from core.engine.rotary import rest_to_rest_time
from core.model.machine import load_machine_file, machine_from_toml_text
from core.model.toolpath import POINTS_DROPPED
from core.view.analysis import totals

RAPID, LINE, CW, CCW = 0, 1, 2, 3


def prog(*blocks: str) -> bytes:
    return ("\n".join(blocks) + "\n").encode()


def read(data: bytes, name: str = "t.ngc", dialect: str | None = None, **setup):
    return read_gcode(data, name, dialect=dialect, setup=MachineSetup(**setup))


def check(tp, expected, *, lines: bool = True) -> None:
    """``expected``: every move of the path in order, as (line, kind, end) or
    (line, kind, end, centre) for arcs; the path must be connected."""
    assert [int(k) for k in tp.kind] == [e[1] for e in expected], tp.kind
    if lines:
        assert [int(x) for x in tp.line] == [e[0] for e in expected]
    np.testing.assert_allclose(tp.end, [e[2] for e in expected], atol=1e-9)
    for k, e in enumerate(expected):
        if len(e) > 3:
            np.testing.assert_allclose(tp.center[k], e[3], atol=1e-9)
    np.testing.assert_allclose(tp.start[1:], tp.end[:-1], atol=1e-9)


def messages(tp) -> list[str]:
    return [n.message for n in tp.notices]


# ============================================================================ work offsets
def test_g10_l2_offsets_place_g55_moves_relative_to_g54():
    # G54 = (10, 20), G55 = (100, 50): the path is drawn in G54 (the first move's system),
    # so G55's X0 Y0 lands at G55 - G54 = (90, 30). LinuxCNC: machine (10,20) (20,20)
    # (100,50) (110,50), the same less (10, 20).
    tp = read(prog(
        "G21 G90 G17",
        "G10 L2 P1 X10 Y20",
        "G10 L2 P2 X100 Y50",
        "G54 G0 X0 Y0",
        "G1 X10 F600",
        "G55 G0 X0 Y0",
        "G1 X10",
        "M2",
    ))  # fmt: skip
    check(tp, [
        (4, RAPID, (0, 0, 0)),
        (5, LINE, (10, 0, 0)),
        (6, RAPID, (90, 30, 0)),
        (7, LINE, (100, 30, 0)),
    ])  # fmt: skip
    # the program starts at machine zero, which is (-10, -20) in G54
    np.testing.assert_allclose(tp.start[0], (-10, -20, 0))


def test_g10_l20_makes_the_current_point_the_given_coordinates():
    # At machine (30, 40) G10 L20 P1 X0 Y0 sets G54 = (30, 40): X10 is machine (40, 40).
    # G10 L20 P2 X5 Y5 there sets G55 = (40, 40) - (5, 5) = (35, 35): G55 X5 Y5 is where the
    # tool is (no move), X0 Y0 is machine (35, 35). The first move ran in G54 = 0.
    tp = read(prog(
        "G21 G90 G17",
        "G0 X30 Y40 Z0",
        "G10 L20 P1 X0 Y0",
        "G1 X10 F600",
        "G10 L20 P2 X5 Y5",
        "G55 G1 X5 Y5",
        "G1 X0 Y0",
        "M2",
    ))  # fmt: skip
    check(tp, [(2, RAPID, (30, 40, 0)), (4, LINE, (40, 40, 0)), (7, LINE, (35, 35, 0))])


def test_offsets_of_the_machine_setup_g54_and_g55():
    # offsets are machine coordinates: G54 = (100, 50, -200), G55 = (300, 50, -200).
    # Machine zero is (-100, -50, 200) in G54; G55 X0 Y0 = G55 - G54 = (200, 0), Z stays 10.
    tp = read(
        prog("G21 G90 G54 G0 X0 Y0 Z10", "G1 X10 F600", "G55 G0 X0 Y0", "M2"),
        offsets={540: (100.0, 50.0, -200.0), 550: (300.0, 50.0, -200.0)},
    )
    check(tp, [(1, RAPID, (0, 0, 10)), (2, LINE, (10, 0, 10)), (3, RAPID, (200, 0, 10))])
    np.testing.assert_allclose(tp.start[0], (-100, -50, 200))


def test_g52_local_offset_on_top_of_g54():
    # G54 = (100, 50); G52 X10 Y5 moves the origin by (10, 5) inside G54; G52 X0 Y0 clears
    # it. LinuxCNC: machine (101,51) (110,55) (120,55) (100,50).
    tp = read(prog(
        "G21 G90 G17",
        "G10 L2 P1 X100 Y50",
        "G54 G0 X1 Y1 Z0",
        "G52 X10 Y5",
        "G1 X0 Y0 F600",
        "G1 X10",
        "G52 X0 Y0",
        "G1 X0 Y0",
        "M2",
    ))  # fmt: skip
    check(tp, [
        (3, RAPID, (1, 1, 0)),
        (5, LINE, (10, 5, 0)),
        (6, LINE, (20, 5, 0)),
        (8, LINE, (0, 0, 0)),
    ])  # fmt: skip


def test_g92_suspend_restore_and_clear():
    # At (10, 10) G92 X0 Y0 makes the offset (10, 10): X5 is (15, 10). G92.2 suspends it:
    # X5 is (5, 10) (Y is still 10). G92.3 restores (10, 10): X0 with program Y 0 is
    # (10, 10). G92.1 clears: X0 Y0 is (0, 0). LinuxCNC gives the same machine points.
    tp = read(prog(
        "G21 G90 G17",
        "G0 X10 Y10 Z0",
        "G92 X0 Y0",
        "G1 X5 F600",
        "G92.2",
        "G1 X5",
        "G92.3",
        "G1 X0",
        "G92.1",
        "G1 X0 Y0",
        "M2",
    ))  # fmt: skip
    check(tp, [
        (2, RAPID, (10, 10, 0)),
        (4, LINE, (15, 10, 0)),
        (6, LINE, (5, 10, 0)),
        (8, LINE, (10, 10, 0)),
        (10, LINE, (0, 0, 0)),
    ])  # fmt: skip


def test_g92_3_right_after_g92_keeps_that_offset():
    # LinuxCNC: G92 writes its offset to #5211-#5219 and G92.3 sets the offset from them
    # (g-code.adoc "G92.3"; interp_convert.cc convert_axis_offsets): G92 X0 at X10 gives 10,
    # G92.3 restores 10, so X5 is machine 15. LinuxCNC 2.9: line 5 ends at X15.
    tp = read(prog("G21 G90 G17", "G0 X10 Y0 Z0", "G92 X0", "G92.3", "G1 X5 F600", "M2"))
    check(tp, [(2, RAPID, (10, 0, 0)), (5, LINE, (15, 0, 0))])


def test_g52_replaces_g92_in_linuxcnc():
    # LinuxCNC: "G52 and G92 share the same offset registers. Therefore, setting G52 will
    # override any earlier G92 setting" (coordinates.adoc): after G92 X0 at X10 (offset 10),
    # G52 X5 makes the offset 5, so X0 is machine 5. LinuxCNC 2.9: line 5 ends at X5.
    tp = read(prog("G21 G90 G17", "G0 X10 Y0 Z0", "G92 X0", "G52 X5", "G1 X0 F600", "M2"))
    check(tp, [(2, RAPID, (10, 0, 0)), (5, LINE, (5, 0, 0))])


def test_g92_1_clears_a_g52_offset_in_linuxcnc():
    # Shared registers again: G92.1 zeroes them, so the G52 X5 is gone too and X0 is machine
    # 0 (interp_convert.cc convert_axis_offsets, G_92_1). LinuxCNC 2.9: line 5 ends at X0.
    tp = read(prog("G21 G90 G17", "G0 X10 Y0 Z0", "G52 X5", "G92.1", "G1 X0 F600", "M2"))
    check(tp, [(2, RAPID, (10, 0, 0)), (5, LINE, (0, 0, 0))])


def test_g10_l2_r_rotates_the_coordinate_system():
    # G54 = (10, 0) rotated 90 deg CCW: machine = R90 p + (10, 0). X10 Y0 -> (0, 10) + (10, 0)
    # = (10, 10); X10 Y10 -> (-10, 10) + (10, 0) = (0, 10) (LinuxCNC 2.9 the same). The path
    # is reported less the first move's translation (10, 0): (0, 10) and (-10, 10).
    tp = read(prog(
        "G21 G90 G17",
        "G10 L2 P1 X10 Y0 R90",
        "G54 G0 X10 Y0 Z0",
        "G1 X10 Y10 F600",
        "M2",
    ))  # fmt: skip
    check(tp, [(3, RAPID, (0, 10, 0)), (4, LINE, (-10, 10, 0))])


def test_g53_moves_in_machine_coordinates():
    # G54 = (100, 50, -200): G53 X0 Y0 goes to machine (0, 0) with Z at machine -195,
    # which is (-100, -50, 5) in G54.
    tp = read(
        prog("G21 G90", "G54 G0 X10 Y10 Z5", "G53 G0 X0 Y0", "M2"),
        offsets={540: (100.0, 50.0, -200.0)},
    )
    check(tp, [(2, RAPID, (10, 10, 5)), (3, RAPID, (-100, -50, 5))])


def test_g53_in_incremental_mode_is_an_error_in_linuxcnc():
    # LinuxCNC refuses G53 with G91 ("Cannot use g53 incremental", rs274ngc
    # NCE_CANNOT_USE_G53_INCREMENTAL; LinuxCNC 2.9 stops at line 3).
    with pytest.raises(InputError) as e:
        read(prog("G21 G90 G17", "G0 X10 Y0 Z0", "G91 G53 G0 X5", "M2"))
    assert str(e.value).startswith("t.ngc:3:")


def test_g28_g30_go_home_in_machine_coordinates_with_g54_in_force():
    # G54 = (100, 50, -200) set by G10 L2; home = machine zero (LinuxCNC's default
    # parameters). Machine points (LinuxCNC 2.9 the same), then less G54:
    #   line 3: (110, 60, -195)
    #   G28 Z20: to G54 Z20 = machine -180, then Z alone home: (110, 60, 0)
    #   line 5: (100, 50, -195); bare G28: every axis home (0, 0, 0)
    #   line 7: (110, 60, -195); G30 X20: to G54 X20 = 120, then X alone home: (0, 60, -195)
    tp = read(prog(
        "G21 G90 G17",
        "G10 L2 P1 X100 Y50 Z-200",
        "G54 G0 X10 Y10 Z5",
        "G28 Z20",
        "G0 X0 Y0 Z5",
        "G28",
        "G0 X10 Y10 Z5",
        "G30 X20",
        "M2",
    ))  # fmt: skip
    check(tp, [
        (3, RAPID, (10, 10, 5)),
        (4, RAPID, (10, 10, 20)),
        (4, RAPID, (10, 10, 200)),
        (5, RAPID, (0, 0, 5)),
        (6, RAPID, (-100, -50, 200)),
        (7, RAPID, (10, 10, 5)),
        (8, RAPID, (20, 10, 5)),
        (8, RAPID, (-100, 10, 5)),
    ])  # fmt: skip


def test_g28_and_g30_go_to_the_machine_files_home_positions():
    # home (500, 400, 0) and home2 (1, 2, 3) in machine coordinates, G54 = (100, 50, -200):
    # in G54 they are (400, 350, 200) and (-99, -48, 203).
    setup = dict(
        offsets={540: (100.0, 50.0, -200.0)}, home=(500.0, 400.0, 0.0), home2=(1.0, 2.0, 3.0)
    )
    tp = read(prog("G21 G90", "G0 X10 Y10 Z5", "G28", "G0 X10 Y10 Z5", "G30", "M2"), **setup)
    check(tp, [
        (2, RAPID, (10, 10, 5)),
        (3, RAPID, (400, 350, 200)),
        (4, RAPID, (10, 10, 5)),
        (5, RAPID, (-99, -48, 203)),
    ])  # fmt: skip


def test_fanuc_g91_g28_z0_sends_z_alone_home():
    # G91 G28 Z0: the intermediate point is the current one (an increment of 0), then Z
    # alone goes to its home, machine 0 = 200 in G54 (Z offset -200). Then G28 X5. Y5.:
    # via (5, 5, 200) to the home X Y, machine (500, 400) = (400, 350) in G54.
    tp = read(
        prog(
            "G21 G90 G17",
            "G54 G0 X10. Y10. Z5.",
            "G91 G28 Z0.",
            "G90 G0 X0. Y0.",
            "G28 X5. Y5.",
            "M30",
        ),
        "t.nc",
        "fanuc",
        offsets={540: (100.0, 50.0, -200.0)},
        home=(500.0, 400.0, 0.0),
    )
    check(tp, [
        (2, RAPID, (10, 10, 5)),
        (3, RAPID, (10, 10, 200)),
        (4, RAPID, (0, 0, 200)),
        (5, RAPID, (5, 5, 200)),
        (5, RAPID, (400, 350, 200)),
    ])  # fmt: skip


def test_fanuc_g10_l2_in_g91_adds_to_the_offset():
    # Fanuc: G10 L2 with an incremental command adds to the offset: G54 X = 10 + 5 = 15.
    # The first move is in G54 = 15 (X0 there is reported 0); G10 L2 P1 X0. (G90) makes G54
    # 0, so X0 is machine 0 = -15 in the path's system.
    tp = read(
        prog(
            "G21 G90 G17",
            "G10 L2 P1 X10.",
            "G91 G10 L2 P1 X5.",
            "G90 G54 G0 X0. Y0. Z5.",
            "G10 L2 P1 X0.",
            "G0 X0.",
            "M30",
        ),
        "t.nc",
        "fanuc",
    )
    check(tp, [(4, RAPID, (0, 0, 5)), (6, RAPID, (-15, 0, 5))])
    np.testing.assert_allclose(tp.start[0], (-15, 0, 0))


def test_fanuc_g10_l2_p0_external_offset_shifts_every_system():
    # Fanuc: G10 L2 P0 sets the external workpiece zero point offset, which is added to
    # every system G54-G59 (0i-MF operator's manual, "Changing workpiece coordinate
    # system"). G54 = 0 + 10, G55 = 100 + 10: G55 X0 is G55 - G54 = 100 in the path.
    tp = read(
        prog(
            "G21 G90 G17",
            "G10 L2 P0 X10.",
            "G10 L2 P2 X100.",
            "G54 G0 X0. Y0. Z5.",
            "G55 G0 X0.",
            "M30",
        ),
        "t.nc",
        "fanuc",
    )
    check(tp, [(4, RAPID, (0, 0, 5)), (5, RAPID, (100, 0, 5))])


def test_g43_adds_the_tool_length_of_the_machine_setup():
    # LinuxCNC G43 H1 with tool 1 50 mm long: program Z10 is machine Z60; G49 cancels.
    # The first move ran without a length offset, so the path is machine coordinates.
    data = prog("G21 G90", "G0 X0 Y0 Z10", "G43 H1", "G0 Z10", "G49", "G0 Z10", "M2")
    expected = [(2, RAPID, (0, 0, 10)), (4, RAPID, (0, 0, 60)), (6, RAPID, (0, 0, 10))]
    setup = MachineSetup(tool_length={1: 50.0})
    # both readers: the one read_gcode chooses and the full interpreter
    check(run_program("t.ngc", data, "linuxcnc", False, setup), expected)
    check(read_gcode(data, "t.ngc", setup=setup), expected)


# ============================================================================ frames
def test_fanuc_g68_rotation_about_a_centre_then_g69():
    # G68 X10 Y0 R90: p -> c + R90 (p - c), c = (10, 0), R90 (x, y) = (-y, x):
    #   (20, 0)  -> (10, 0) + R90 (10, 0)  = (10, 0) + (0, 10)   = (10, 10)
    #   (20, 10) -> (10, 0) + R90 (10, 10) = (10, 0) + (-10, 10) = (0, 10)
    # G69 cancels: X0 Y0 is (0, 0).
    tp = read(
        prog(
            "G21 G90 G17",
            "G0 X0. Y0. Z5.",
            "G68 X10. Y0. R90.",
            "G1 X20. Y0. F600.",
            "G1 X20. Y10.",
            "G69",
            "G1 X0. Y0.",
            "M30",
        ),
        "t.nc",
        "fanuc",
    )
    check(tp, [
        (2, RAPID, (0, 0, 5)),
        (4, LINE, (10, 10, 5)),
        (5, LINE, (0, 10, 5)),
        (7, LINE, (0, 0, 5)),
    ])  # fmt: skip


def test_fanuc_g68_rotates_arcs():
    # G68 X0 Y0 R90: the line to (10, 0) ends at (0, 10); the CCW quarter (10, 0) -> (0, 10)
    # about (0, 0) becomes (0, 10) -> (-10, 0), centre (0, 0), still CCW (a rotation keeps
    # the direction).
    tp = read(
        prog(
            "G21 G90 G17",
            "G0 X0. Y0. Z5.",
            "G68 X0. Y0. R90.",
            "G1 X10. Y0. F600.",
            "G3 X0. Y10. I-10. J0.",
            "G69",
            "M30",
        ),
        "t.nc",
        "fanuc",
    )
    check(tp, [
        (2, RAPID, (0, 0, 5)),
        (4, LINE, (0, 10, 5)),
        (5, CCW, (-10, 0, 5), (0, 0, 5)),
    ])  # fmt: skip
    assert tp.radius[2] == pytest.approx(10.0)


def test_fanuc_g51_uniform_scaling_of_lines_and_arcs():
    # G51 X0 Y0 P2.0: p -> 2 p. (10, 0) -> (20, 0); the CCW quarter to (0, 10) about (0, 0)
    # -> to (0, 20) about (0, 0), radius 20. G51 X10 Y10 P2.0: p -> c + 2 (p - c):
    # (20, 10) -> (10, 10) + 2 (10, 0) = (30, 10).
    tp = read(
        prog(
            "G21 G90 G17",
            "G0 X0. Y0. Z5.",
            "G51 X0. Y0. P2.0",
            "G1 X10. Y0. F600.",
            "G3 X0. Y10. I-10. J0.",
            "G50",
            "G51 X10. Y10. P2.0",
            "G1 X20. Y10.",
            "G50",
            "M30",
        ),
        "t.nc",
        "fanuc",
    )
    check(tp, [
        (2, RAPID, (0, 0, 5)),
        (4, LINE, (20, 0, 5)),
        (5, CCW, (0, 20, 5), (0, 0, 5)),
        (8, LINE, (30, 10, 5)),
    ])  # fmt: skip
    assert tp.radius[2] == pytest.approx(20.0)


def test_fanuc_arc_under_non_uniform_scaling_is_refused():
    # X scaled 2, Y scaled 1: the circle would be an ellipse; ncperf names the line.
    with pytest.raises(InputError) as e:
        read(
            prog(
                "G21 G90 G17",
                "G0 X10. Y0. Z5.",
                "G51 X0. Y0. I2.0 J1.0",
                "G3 X0. Y10. I-10. J0. F600.",
                "M30",
            ),
            "t.nc",
            "fanuc",
        )
    assert str(e.value).startswith("t.nc:4:")


def test_fanuc_g51_1_mirror_about_x0_reverses_arcs():
    # G51.1 X0: x -> -x. (10, 0) -> (-10, 0); the CW half circle (10, 0) -> (20, 0) about
    # (15, 0) -> (-10, 0) -> (-20, 0) about (-15, 0), counter-clockwise (G2 <-> G3).
    tp = read(
        prog(
            "G21 G90 G17",
            "G0 X0. Y0. Z5.",
            "G51.1 X0.",
            "G1 X10. Y0. F600.",
            "G2 X20. Y0. I5. J0.",
            "G50.1",
            "G1 X0. Y0.",
            "M30",
        ),
        "t.nc",
        "fanuc",
    )
    check(tp, [
        (2, RAPID, (0, 0, 5)),
        (4, LINE, (-10, 0, 5)),
        (5, CCW, (-20, 0, 5), (-15, 0, 5)),
        (7, LINE, (0, 0, 5)),
    ])  # fmt: skip


def test_fanuc_g51_1_mirror_about_a_point_is_no_move():
    # G51.1 X10.: mirror about the line X = 10 (the axis word is the "position and axis of
    # symmetry", Fanuc 0i-MF "Programmable mirror image"; SINUMERIK ISO dialect manual,
    # G51.1): x -> 20 - x. G51.1 and G50.1 move nothing.
    #   X0 Y0 -> (20, 0);  X5 Y5 -> (15, 5)
    #   G2 (5, 5) -> (10, 10) about (10, 5) -> (15, 5) -> (10, 10) about (10, 5), now G3
    tp = read(
        prog(
            "G21 G90 G17",
            "G0 X0. Y0. Z5.",
            "G51.1 X10.",
            "G1 X0. Y0. F600.",
            "G1 X5. Y5.",
            "G2 X10. Y10. I5. J0.",
            "G50.1 X10.",
            "G1 X0. Y0.",
            "M30",
        ),
        "t.nc",
        "fanuc",
    )
    check(tp, [
        (2, RAPID, (0, 0, 5)),
        (4, LINE, (20, 0, 5)),
        (5, LINE, (15, 5, 5)),
        (6, CCW, (10, 10, 5), (10, 5, 5)),
        (8, LINE, (0, 0, 5)),
    ])  # fmt: skip


def test_siemens_trans_arot_atrans_rot():
    # 840D frames (programming manual "Coordinate transformations (frames)"):
    #   TRANS X10; AROT RPL=90: rotation about the translated origin:
    #     X10 Y0 -> (10, 0) + R90 (10, 0) = (10, 0) + (0, 10) = (10, 10)
    #   ATRANS X5 after the rotation is along the rotated X: origin (10, 0) + R90 (5, 0)
    #     = (10, 5); X0 Y0 -> (10, 5)
    #   ROT RPL=90 (absolute) replaces the whole programmable frame (TRANS gone):
    #     X10 Y0 -> (0, 10)
    #   TRANS alone clears the programmable frame: X10 Y0 -> (10, 0)
    tp = read(
        prog(
            "G71 G90 G17 G64",
            "G0 X0 Y0 Z5",
            "TRANS X10",
            "AROT RPL=90",
            "G1 X10 Y0 F600",
            "ATRANS X5",
            "G1 X0 Y0",
            "ROT RPL=90",
            "G1 X10 Y0",
            "TRANS",
            "G1 X10 Y0",
            "M30",
        ),
        "t.mpf",
    )
    check(tp, [
        (2, RAPID, (0, 0, 5)),
        (5, LINE, (10, 10, 5)),
        (7, LINE, (10, 5, 5)),
        (9, LINE, (0, 10, 5)),
        (11, LINE, (10, 0, 5)),
    ])  # fmt: skip


def test_siemens_scale_atrans_mirror_amirror():
    #   SCALE X2 Y2; ATRANS X5: an offset after SCALE is scaled: origin (10, 0)
    #     X0 Y0 -> (10, 0);  X5 Y0 -> (10, 0) + 2 (5, 0) = (20, 0)
    #   MIRROR X0 (absolute: scale and offset gone): x -> -x
    #     X10 -> (-10, 0); G2 (10, 0) -> (20, 0) about (15, 0) -> to (-20, 0) about
    #     (-15, 0), counter-clockwise
    #   TRANS X10; AMIRROR X0: mirror about the translated origin: X5 -> 10 - 5 = 5
    tp = read(
        prog(
            "G71 G90 G17 G64",
            "G0 X0 Y0 Z5",
            "SCALE X2 Y2",
            "ATRANS X5",
            "G1 X0 Y0 F600",
            "G1 X5 Y0",
            "MIRROR X0",
            "G1 X10 Y0",
            "G2 X20 Y0 I5 J0",
            "TRANS X10",
            "AMIRROR X0",
            "G1 X5 Y0",
            "M30",
        ),
        "t.mpf",
    )
    check(tp, [
        (2, RAPID, (0, 0, 5)),
        (5, LINE, (10, 0, 5)),
        (6, LINE, (20, 0, 5)),
        (8, LINE, (-10, 0, 5)),
        (9, CCW, (-20, 0, 5), (-15, 0, 5)),
        (12, LINE, (5, 0, 5)),
    ])  # fmt: skip


def test_siemens_arc_under_trans_and_arot():
    # TRANS X10; AROT RPL=90: p -> (10, 0) + R90 p.
    #   X10 Y0 -> (10, 10); G3 to (0, 10) about (0, 0) -> to (10, 0) + (-10, 0) = (0, 0)
    #   about (10, 0) + R90 (0, 0) = (10, 0), counter-clockwise, radius 10
    tp = read(
        prog(
            "G71 G90 G17 G64",
            "G0 X0 Y0 Z5",
            "TRANS X10",
            "AROT RPL=90",
            "G1 X10 Y0 F600",
            "G3 X0 Y10 I-10 J0",
            "TRANS",
            "G1 X0 Y-10",
            "M30",
        ),
        "t.mpf",
    )
    check(tp, [
        (2, RAPID, (0, 0, 5)),
        (5, LINE, (10, 10, 5)),
        (6, CCW, (0, 0, 5), (10, 0, 5)),
        (8, LINE, (0, -10, 5)),
    ])  # fmt: skip
    assert tp.radius[2] == pytest.approx(10.0)
    # a quarter circle of radius 10
    assert tp.length[2] == pytest.approx(math.pi * 10 / 2)


# ============================================================================ compensation
# An outside profile, G41 (tool on the left) going clockwise round the square
# (0,0)-(0,20)-(20,20)-(20,0), R = 5, every axis word written out.
#   entry (0,-10) -> (0,0), direction +Y: its end pushed R to the left (-X): (-5, 0)
#   up X0: x = -5, to (-5, 20) (straight on from the entry: no corner)
#   corner (0,20): the path turns right, away from the tool: convex, an arc of R about
#     (0, 20) from (-5, 20) to (0, 25), clockwise (angle 180 -> 90 deg)
#   along Y20 (direction +X, left is +Y): y = 25, to (20, 25)
#   corner (20,20): arc about (20, 20) from (20, 25) to (25, 20), clockwise
#   down X20 (direction -Y, left is +X): x = 25, to (25, 0)
#   G40 and the exit: from (25, 0) to the programmed (30, -10)
# LinuxCNC 2.9 with G41.1 D10 gives these points; it puts each move on its own block and
# the corner arcs on the block after the corner.
SQUARE = (
    "G21 G90 G17 G40",
    "G0 X0 Y-10 Z-1",
    "{comp}",
    "G1 X0 Y0 F600",
    "G1 X0 Y20",
    "G1 X20 Y20",
    "G1 X20 Y0",
    "G40",
    "G1 X30 Y-10",
    "M2",
)
SQUARE_PATH = [
    (2, RAPID, (0, -10, -1)),
    (4, LINE, (-5, 0, -1)),
    (5, LINE, (-5, 20, -1)),
    (6, CW, (0, 25, -1), (0, 20, -1)),
    (6, LINE, (20, 25, -1)),
    (7, CW, (25, 20, -1), (20, 20, -1)),
    (7, LINE, (25, 0, -1)),
    (9, LINE, (30, -10, -1)),
]


def square(comp: str) -> bytes:
    return prog(*(b.format(comp=comp) for b in SQUARE))


@pytest.mark.parametrize(
    "comp, setup",
    [
        ("G41 D1", {"tool_radius": {1: 5.0}}),  # D1: tool 1's radius from the machine file
        ("G41", {"tool_radius_override": 5.0}),  # --tool-radius
        ("G41 D1", {"tool_radius": {1: 2.0}, "tool_radius_override": 5.0}),  # it wins
        ("G41.1 D10", {}),  # D is the diameter
    ],
)
def test_comp_outside_square_geometry(comp, setup):
    tp = read(square(comp), **setup)
    check(tp, SQUARE_PATH, lines=False)
    assert tp.radius[3] == pytest.approx(5.0) and tp.radius[5] == pytest.approx(5.0)


def test_comp_radius_of_the_tool_in_the_spindle():
    # G41 without D: the radius of the tool loaded (T1 M6) -- the same square, one block later
    data = prog(*(b.format(comp="T1 M6\nG41") for b in SQUARE))
    tp = read(data, tool_radius={1: 5.0})
    check(tp, SQUARE_PATH, lines=False)


def test_comp_moves_belong_to_their_own_blocks():
    # LinuxCNC 2.9 reports the entry on line 4, the side X0 on line 5, Y20 on 6, X20 on 7:
    # a compensated move is its programmed block's, even though the controller only
    # finishes it when it reads the next block.
    tp = read(square("G41.1 D10"))
    assert [int(x) for x in tp.line] == [e[0] for e in SQUARE_PATH]


def test_comp_inside_corner_is_cut_back_to_the_intersection():
    # G41, R 5. Entry (-20,0) -> (0,0), direction +X, pushed left (+Y): (0, 5).
    # Along Y0 (+X): y = 5; then up X20 (+Y, left is -X): x = 15. The path turns left,
    # towards the tool: concave, both cut back to their intersection (15, 5).
    # Exit after G40: (15, 20) -> (30, 30). LinuxCNC 2.9 (G41.1 D10) the same.
    tp = read(prog(
        "G21 G90 G17 G40",
        "G0 X-20 Y0 Z-1",
        "G41.1 D10",
        "G1 X0 Y0 F600",
        "G1 X20 Y0",
        "G1 X20 Y20",
        "G40",
        "G1 X30 Y30",
        "M2",
    ))  # fmt: skip
    check(tp, [
        (2, RAPID, (-20, 0, -1)),
        (4, LINE, (0, 5, -1)),
        (5, LINE, (15, 5, -1)),
        (6, LINE, (15, 20, -1)),
        (8, LINE, (30, 30, -1)),
    ], lines=False)  # fmt: skip


def test_comp_axes_not_written_come_from_the_programmed_point():
    # The square with modal axis words (G1 Y20, G1 X20, G1 Y0): the same programmed path,
    # so the same compensated path (LinuxCNC 2.9 gives exactly SQUARE_PATH's points).
    tp = read(prog(
        "G21 G90 G17 G40",
        "G0 X0 Y-10 Z-1",
        "G41.1 D10",
        "G1 X0 Y0 F600",
        "G1 Y20",
        "G1 X20",
        "G1 Y0",
        "G40",
        "G1 X30 Y-10",
        "M2",
    ))  # fmt: skip
    check(tp, SQUARE_PATH, lines=False)


def test_comp_incremental_moves_from_the_programmed_point():
    # The same square in G91 after the entry: increments of the programmed path.
    tp = read(prog(
        "G21 G90 G17 G40",
        "G0 X0 Y-10 Z-1",
        "G41.1 D10",
        "G1 X0 Y0 F600",
        "G91 G1 X0 Y20",
        "G1 X20 Y0",
        "G1 X0 Y-20",
        "G40",
        "G90 G1 X30 Y-10",
        "M2",
    ))  # fmt: skip
    check(tp, SQUARE_PATH, lines=False)


def test_comp_arc_with_the_tool_inside_runs_at_r_minus_R():
    # G41 (left), R 5. Entry (20,-20) -> (20,0), direction +Y, pushed left (-X): (15, 0).
    # G3 about (0,0), r 20: the centre is on the left, the tool's side: inside, r - R = 15,
    # from (15, 0) to (0, 15), tangent to the entry (no corner). Then X-20 (direction -X,
    # left is -Y): y = 20 - 5 = 15, to (-20, 15). Exit to (-30, 0). LinuxCNC 2.9 the same.
    tp = read(prog(
        "G21 G90 G17 G40",
        "G0 X20 Y-20 Z-1",
        "G41.1 D10",
        "G1 X20 Y0 F600",
        "G3 X0 Y20 I-20 J0",
        "G1 X-20 Y20",
        "G40",
        "G1 X-30 Y0",
        "M2",
    ))  # fmt: skip
    check(tp, [
        (2, RAPID, (20, -20, -1)),
        (4, LINE, (15, 0, -1)),
        (5, CCW, (0, 15, -1), (0, 0, -1)),
        (6, LINE, (-20, 15, -1)),
        (8, LINE, (-30, 0, -1)),
    ], lines=False)  # fmt: skip
    assert tp.radius[2] == pytest.approx(15.0)


def test_comp_arc_with_the_tool_outside_runs_at_r_plus_R():
    # G42 (right), R 5: the entry is pushed right of +Y (+X): (25, 0); the centre of the
    # G3 is on the left, away from the tool: outside, r + R = 25, to (0, 25); the line X-20
    # (direction -X, right is +Y): y = 25. LinuxCNC 2.9 (G42.1 D10) the same.
    tp = read(prog(
        "G21 G90 G17 G40",
        "G0 X20 Y-20 Z-1",
        "G42.1 D10",
        "G1 X20 Y0 F600",
        "G3 X0 Y20 I-20 J0",
        "G1 X-20 Y20",
        "G40",
        "G1 X-30 Y0",
        "M2",
    ))  # fmt: skip
    check(tp, [
        (2, RAPID, (20, -20, -1)),
        (4, LINE, (25, 0, -1)),
        (5, CCW, (0, 25, -1), (0, 0, -1)),
        (6, LINE, (-20, 25, -1)),
        (8, LINE, (-30, 0, -1)),
    ], lines=False)  # fmt: skip
    assert tp.radius[2] == pytest.approx(25.0)


def test_comp_without_a_known_radius_uses_the_programmed_path_with_a_notice():
    tp = read(square("G41 D1"))
    check(tp, [
        (2, RAPID, (0, -10, -1)),
        (4, LINE, (0, 0, -1)),
        (5, LINE, (0, 20, -1)),
        (6, LINE, (20, 20, -1)),
        (7, LINE, (20, 0, -1)),
        (9, LINE, (30, -10, -1)),
    ])  # fmt: skip
    assert any("without a known tool radius" in m for m in messages(tp))
    # and the radius is known: no such notice
    assert not any("tool radius" in m for m in messages(read(square("G41.1 D10"))))


def test_comp_entry_not_longer_than_the_radius_is_an_error():
    # LinuxCNC: the lead-in must be at least as long as the tool radius: 4 mm < 5 mm
    with pytest.raises(InputError) as e:
        read(prog(
            "G21 G90 G17",
            "G0 X0 Y-4 Z-1",
            "G41.1 D10",
            "G1 X0 Y0 F600",
            "G1 X0 Y20",
            "M2",
        ))  # fmt: skip
    assert str(e.value).startswith("t.ngc:4:")


# ============================================================================ machine file
MACHINE = """\
name = "frames test"
[axes.X]
max_feed = 30.0
max_acceleration = 2.5
max_jerk = 5.0
[axes.Y]
max_feed = 30.0
max_acceleration = 2.5
max_jerk = 5.0
[axes.Z]
max_feed = 30.0
max_acceleration = 2.5
max_jerk = 5.0
[axes.A]
max_feed = 3600
max_acceleration = 360
[controller]
interpolation_time = 0.012
path_tolerance = 0.01
curvature_transition_time = 0.012
"""
#: the first line after MACHINE
NEXT = MACHINE.count("\n") + 1


def test_machine_toml_controller_offsets_tools_and_rotary_axis():
    text = MACHINE + (
        'default_path_mode = "exact_stop"\n'
        "home = [10.0, 20.0, 30.0]\n"
        "home_g30 = [1, 2, 3]\n"
        "[offsets]\n"
        "G54 = [100.0, 50.0, -200.0]\n"
        '"G59.3" = [1.0, 2.0, 3.0]\n'
        "[tools]\n"
        "T1 = { diameter = 10, length = 50 }\n"
        "T2 = { radius = 3 }\n"
    )
    m = machine_from_toml_text(text, "m.toml")
    s = m.setup
    assert s.default_path_mode == "exact_stop"
    assert s.home == (10.0, 20.0, 30.0) and s.home_g30 == (1.0, 2.0, 3.0)
    assert s.work_offsets == {"G54": (100.0, 50.0, -200.0), "G59.3": (1.0, 2.0, 3.0)}
    assert s.tools[1].radius == 5.0 and s.tools[1].length == 50.0  # diameter 10 -> r 5
    assert s.tools[2].radius == 3.0 and s.tools[2].length is None
    # A: 3600 deg/min = 60 deg/s, 360 deg/s^2, no jerk limit
    a = m.rotary["A"]
    assert (a.max_feed, a.max_acceleration, a.max_jerk) == (60.0, 360.0, math.inf)
    # what the G-code reader gets: codes x 10, radii and lengths by tool
    ms = machine_setup(s)
    assert ms.offsets == {540: (100.0, 50.0, -200.0), 593: (1.0, 2.0, 3.0)}
    assert ms.tool_radius == {1: 5.0, 2: 3.0} and ms.tool_length == {1: 50.0}
    assert ms.home == (10.0, 20.0, 30.0) and ms.home2 == (1.0, 2.0, 3.0)
    assert ms.default_path_mode == "exact_stop"


@pytest.mark.parametrize(
    "extra, line, words",
    [
        ('default_path_mode = "sometimes"\n', NEXT, "default_path_mode"),
        ("home = [1.0, 2.0]\n", NEXT, "home"),
        ("[offsets]\nG54 = [1, 2]\n", NEXT + 1, "G54"),
        ("[offsets]\nG99 = [1, 2, 3]\n", NEXT + 1, "G99"),
        ('[tools]\nT1 = { diameter = "ten" }\n', NEXT + 1, "diameter"),
        ("[tools]\nT1 = { diam = 10 }\n", NEXT + 1, "diam"),
        ("[tools]\nX1 = { diameter = 10 }\n", NEXT + 1, "X1"),
    ],
)
def test_machine_toml_bad_setup_names_file_and_line(extra, line, words):
    with pytest.raises(MachineError) as e:
        machine_from_toml_text(MACHINE + extra, "m.toml")
    assert str(e.value).startswith(f"m.toml:{line}:")
    assert words in str(e.value)


@pytest.mark.parametrize(
    "old, new, line",
    [
        ("max_feed = 3600", "max_feed = -1", 15),
        ("max_acceleration = 360", 'max_acceleration = "fast"', 16),
        ("max_acceleration = 360", "max_accel = 360", 16),
    ],
)
def test_machine_toml_bad_rotary_axis_names_file_and_line(old, new, line):
    assert MACHINE.splitlines()[line - 1] == old
    with pytest.raises(MachineError) as e:
        machine_from_toml_text(MACHINE.replace(old, new), "m.toml")
    assert str(e.value).startswith(f"m.toml:{line}:")


def test_840d_preset_defaults_to_exact_stop():
    assert load_preset("siemens-840d").setup.default_path_mode == "exact_stop"


@pytest.mark.parametrize("full", [False, True])
def test_default_exact_stop_where_the_program_sets_no_path_mode(full):
    body = ("G71 G90", "G0 X0 Y0 Z5", "G1 X10 F600", "G1 Y10", "M30")
    setup = MachineSetup(default_path_mode="exact_stop")

    def run(data):
        if full:
            return run_program("t.mpf", data, "siemens", False, setup, plain_runs=False)
        return read_gcode(data, "t.mpf", setup=setup)

    tp = run(prog(*body))
    assert tp.path_mode.tolist() == [1, 1, 1]
    assert any("exact stop" in m for m in messages(tp))
    tp = run(prog("G64", *body))
    assert tp.path_mode.tolist() == [0, 0, 0]
    assert not any("exact stop" in m for m in messages(tp))


def test_read_linuxcnc_tool_table(tmp_path):
    p = tmp_path / "tool.tbl"
    p.write_text(
        "T1 P1 D10 Z50 ;10 mm end mill\n\n; a comment line\nT2 P2 D6.0 Z+42.5 X0.1\nT3 P3 Z20\n"
    )
    # radius = D / 2, length = Z; no D: no radius
    assert read_tool_table(str(p)) == {1: (5.0, 50.0), 2: (3.0, 42.5), 3: (None, 20.0)}


@pytest.mark.parametrize(
    "text, line", [("T1 P1 D10 Z50\nT2 P2 Dx Z5\n", 2), ("P1 D10\n", 1), ("T1 P1 D10 junk\n", 1)]
)
def test_bad_tool_table_line_names_file_and_line(tmp_path, text, line):
    p = tmp_path / "tool.tbl"
    p.write_text(text)
    with pytest.raises(InputError) as e:
        read_tool_table(str(p))
    assert str(e.value).startswith(f"{p}:{line}:")


def test_tool_table_beside_the_machine_file_reaches_the_reader(tmp_path):
    (tmp_path / "tool.tbl").write_text("T1 P1 D10 Z50\n")
    (tmp_path / "m.toml").write_text(MACHINE + 'tool_table = "tool.tbl"\n')
    ms = machine_setup(load_machine_file(tmp_path / "m.toml").setup)
    assert ms.tool_radius == {1: 5.0} and ms.tool_length == {1: 50.0}
    # and G41 D1 offsets by its 5 mm
    tp = read_gcode(square("G41 D1"), "t.ngc", setup=ms)
    check(tp, SQUARE_PATH, lines=False)


# ============================================================================ rotary axes
ROTARY = prog(
    "G21 G90 G94 G64",
    "G0 X0 Y0 Z5",
    "G1 X100 A90 F3000",
    "G0 A180",
    "G1 A270 F1800",
    "G1 X110",
    "M2",
)


def test_rotary_axis_with_xyz_and_alone():
    tp = read(ROTARY)
    # the path: the rapid, X100 (A turns 90 deg with it), X110; the A moves alone are not
    # path moves
    check(tp, [(2, RAPID, (0, 0, 5)), (3, LINE, (100, 0, 5)), (6, LINE, (110, 0, 5))])
    np.testing.assert_allclose(tp.rotary, [(0, 0, 0), (90, 0, 0), (0, 0, 0)])
    rm = tp.rotary_only
    assert rm.line.tolist() == [4, 5] and rm.after.tolist() == [1, 1]  # both after X100
    np.testing.assert_allclose(rm.travel, [(90, 0, 0), (90, 0, 0)])
    assert math.isnan(rm.feed[0])  # a rapid
    assert rm.feed[1] == pytest.approx(30.0)  # F1800 deg/min = 30 deg/s
    # LinuxCNC: with X, Y or Z moving, F is the rate along X, Y, Z: 3000 mm/min = 50 mm/s
    assert tp.feed[1] == pytest.approx(50.0)


def test_fanuc_composite_feed_of_linear_and_rotary_axes():
    # Fanuc: F is along all axes, degrees counted as mm: the X rate is
    # F L / sqrt(L^2 + A^2) = 3000 * 100 / sqrt(100^2 + 90^2) = 300000 / 134.5362
    # = 2229.882 mm/min = 37.1647 mm/s. The X-only move keeps its F1800 (30 mm/s).
    tp = read(ROTARY, "t.nc", "fanuc")
    assert tp.feed[1] == pytest.approx(37.16470, rel=1e-5)
    assert tp.feed[2] == pytest.approx(30.0)
    assert any("linear and rotary axes together" in m for m in messages(tp))


INF = math.inf


@pytest.mark.parametrize(
    "d, v, a, j, t",
    [
        # trapezoid, top speed reached (D >= v^2/a = 10): T = D/v + v/a = 1.5 + 1/6
        (90.0, 60.0, 360.0, INF, 1.6666666667),
        # exactly at the knee: 10/60 + 60/360 = 2 sqrt(10/360) = 1/3
        (10.0, 60.0, 360.0, INF, 0.3333333333),
        # triangle (D < 10): T = 2 sqrt(D/a) = 2 sqrt(5/360) = 0.2357023
        (5.0, 60.0, 360.0, INF, 0.2357022604),
        # S-curve, v reached: ramp T(v) = v/a + a/j = 1/6 + 1/10 = 0.2667, needs
        # D >= v T(v) = 16: T = D/v + T(v) = 1.5 + 0.26667
        (90.0, 60.0, 360.0, 3600.0, 1.7666666667),
        (16.0, 60.0, 360.0, 3600.0, 0.5333333333),
        # S-curve, a reached but not v: u^2/a + u a/j = D -> u^2 + 36 u - 3600 = 0,
        # u = (-36 + sqrt(15696))/2 = 44.64184 (>= a^2/j = 36); T = 2 (u/a + a/j) = 0.448010
        (10.0, 60.0, 360.0, 3600.0, 0.4480102),
        # S-curve, a not reached: D = 2 j t^3, t = (1/7200)^(1/3) = 0.0517872, T = 4 t
        (1.0, 60.0, 360.0, 3600.0, 0.2071488),
        # no motion
        (0.0, 60.0, 360.0, INF, 0.0),
    ],
)
def test_rest_to_rest_time(d, v, a, j, t):
    got = rest_to_rest_time(np.array([d]), np.array([v]), np.array([a]), np.array([j]))
    assert got[0] == pytest.approx(t, rel=1e-6, abs=1e-12)


@pytest.mark.parametrize(
    "jerk, rapid, fed",
    [
        # A: 60 deg/s, 360 deg/s^2. G0 A90: 90/60 + 60/360 = 1.666667 s. G1 A30 at
        # F1800 (30 deg/s): 30/30 + 30/360 = 1.083333 s.
        ("", 1.6666667, 1.0833333),
        # with 3600 deg/s^3: G0 A90: 90/60 + (1/6 + 1/10) = 1.766667. G1 A30: 30 deg/s is
        # below a^2/j = 36, so the ramp to it never reaches 360 deg/s^2 and takes
        # 2 sqrt(30/3600) = 0.182574 s over 30 * 0.182574 = 5.48 deg < 30:
        # T = 30/30 + 0.182574 = 1.182574
        ("max_jerk = 3600\n", 1.7666667, 1.1825742),
    ],
)
def test_rotary_only_moves_take_their_rest_to_rest_time(nc, tmp_path, jerk, rapid, fed):
    text = MACHINE.replace("max_acceleration = 360\n", "max_acceleration = 360\n" + jerk)
    (tmp_path / "m.toml").write_text(text)
    machine = load_machine_file(tmp_path / "m.toml")
    path = tmp_path / "r.ngc"
    path.write_bytes(prog(
        "G21 G90 G64",
        "G0 X10 Y0 Z0",
        "G0 A90",
        "G1 X20 F600",
        "G1 A120 F1800",
        "G1 X30",
        "M2",
    ))  # fmt: skip
    an = nc.analyze(str(path), machine)
    # the rests after the first rapid and after X20 (no dwells)
    np.testing.assert_allclose(an.profile.pause, [rapid, fed, 0.0], rtol=1e-6)
    assert totals(an)["rotary_only_time_s"] == pytest.approx(rapid + fed, rel=1e-6)


# ============================================================================ resolution
@pytest.mark.parametrize("full", [False, True])
def test_arc_shorter_than_the_resolution_is_a_point(full):
    # a half circle of radius 0.00005 mm (0.00016 mm long, < 0.001 mm) between two lines:
    # dropped with a notice; the next line starts where X10 ended, (10, 0, 5), not at
    # the arc's end (10.0001, 0, 5).
    data = prog(
        "G21 G90 G64",
        "G0 X0 Y0 Z5",
        "G1 X10 F600",
        "G2 X10.0001 Y0 I0.00005 J0",
        "G1 X20",
        "M2",
    )
    if full:
        tp = run_program("t.ngc", data, "linuxcnc", False, MachineSetup(), plain_runs=False)
    else:
        tp = read(data)
    check(tp, [(2, RAPID, (0, 0, 5)), (3, LINE, (10, 0, 5)), (5, LINE, (20, 0, 5))])
    np.testing.assert_allclose(tp.start[2], (10, 0, 5), atol=0)
    assert [(n.line, n.message) for n in tp.notices if n.message == POINTS_DROPPED] == [
        (4, POINTS_DROPPED)
    ]
