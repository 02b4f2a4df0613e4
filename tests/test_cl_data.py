"""CL data adapter: every supported record and mode, every error path (naming its line),
and the cross-check against a G-code program of the same path."""

from __future__ import annotations

import math

import numpy as np
import pytest

from adapters.cl_data import looks_like_cl, ncperf_extract, read_cl
from core import ExtractOptions, InputError, MoveKind, PathMode, load_preset

SQ2 = math.sqrt(2.0)


def read(text: str, name: str = "t.cls"):
    return read_cl(text.encode(), name)


def fails(text: str, line: int | None, fragment: str, name: str = "t.cls") -> InputError:
    with pytest.raises(InputError) as info:
        read(text, name)
    msg = str(info.value)
    where = f"{name}:{line}:" if line is not None else f"{name}:"
    assert msg.startswith(where), msg
    assert fragment in msg, msg
    assert "\n" not in msg
    return info.value


def notices(tp) -> str:
    return "\n".join(str(n) for n in tp.notices)


F600 = "FEDRAT/MMPM,600\n"  # 600 mm/min = 10 mm/s


# ------------------------------------------------------------------------------ GOTO, FEDRAT
def test_goto_lines_feed_and_source_lines():
    """GOTO records are line moves at the modal FEDRAT (mm/min -> mm/s); each move keeps the
    1-based line of its GOTO, and the first one starts at the origin without FROM."""
    tp = read("UNITS/MM\nFEDRAT/MMPM,600\nGOTO/10,0,0\n\nGOTO/10,5,0\nGOTO/0,5,0\n")
    assert tp.n == 3
    assert list(tp.kind) == [MoveKind.LINE] * 3
    assert list(tp.line) == [3, 5, 6]
    assert list(tp.block) == [-1, -1, -1]
    assert np.allclose(tp.start[0], [0, 0, 0])
    assert np.allclose(tp.end, [[10, 0, 0], [10, 5, 0], [0, 5, 0]])
    assert np.allclose(tp.feed, 10.0)
    assert np.allclose(tp.length, [10, 5, 10])
    assert tp.units == "mm" and tp.tool_axis is None
    assert list(tp.path_mode) == [PathMode.CONTINUOUS] * 3
    assert "no FROM record: the first move starts at the origin" in notices(tp)


@pytest.mark.parametrize(
    "record,mm_per_s",
    [
        ("FEDRAT/600,MMPM", 10.0),
        ("FEDRAT/MMPM,600", 10.0),
        ("FEDRAT / 600 , MMPM", 10.0),
        ("FEDRAT/mmpm,600.", 10.0),
        ("FEDRAT/600", 10.0),
        ("FEDRAT/10,IPM", 10 * 25.4 / 60),
        ("FEDRAT/IPM,10", 10 * 25.4 / 60),
    ],
    ids=["f,MMPM", "MMPM,f", "spaces", "lower case", "no unit (mm file)", "f,IPM", "IPM,f"],
)
def test_fedrat_both_orders_and_units(record, mm_per_s):
    """FEDRAT takes the value and the unit in either order; MMPM is mm/min, IPM inch/min, and
    no unit means the file's length unit per minute."""
    tp = read(f"UNITS/MM\n{record}\nGOTO/1,0,0\n")
    assert tp.feed[0] == pytest.approx(mm_per_s)


def test_fedrat_without_unit_in_an_inch_file():
    """In an inch file FEDRAT/f without a unit is inch/min: 10 in/min = 254/60 mm/s."""
    tp = read("UNITS/INCHES\nFEDRAT/10\nGOTO/1,0,0\n")
    assert tp.feed[0] == pytest.approx(254 / 60)


def test_feed_is_modal_and_changes():
    """A FEDRAT holds until the next one."""
    tp = read("FEDRAT/600,MMPM\nGOTO/1,0,0\nGOTO/2,0,0\nFEDRAT/1200,MMPM\nGOTO/3,0,0\n")
    assert np.allclose(tp.feed, [10, 10, 20])


@pytest.mark.parametrize("word", ["RAPID", "RAPID/", "rapid", "  RAPID  "])
def test_rapid_is_one_shot(word):
    """RAPID (with or without slash) makes only the next motion a rapid, with NaN feed."""
    tp = read(f"{F600}{word}\nGOTO/0,0,5\nGOTO/0,0,0\nGOTO/5,0,0\n")
    assert list(tp.kind) == [MoveKind.RAPID, MoveKind.LINE, MoveKind.LINE]
    assert np.isnan(tp.feed[0]) and np.allclose(tp.feed[1:], 10.0)


def test_rapid_survives_records_that_do_not_move():
    """A RAPID applies to the next motion even across FEDRAT, PAINT and comments."""
    tp = read("RAPID\nFEDRAT/MMPM,600\nPAINT/COLOR,42\n$$ here\nGOTO/0,0,5\nGOTO/1,0,5\n")
    assert list(tp.kind) == [MoveKind.RAPID, MoveKind.LINE]


def test_rapids_need_no_feed():
    """A file whose only motion is rapid needs no FEDRAT."""
    tp = read("RAPID\nGOTO/0,0,5\nRAPID\nGOTO/10,0,5\n")
    assert list(tp.kind) == [MoveKind.RAPID, MoveKind.RAPID]


def test_from_sets_the_start_point():
    """FROM is where the tool starts: no move, and the first GOTO starts there."""
    tp = read(f"FROM/1,2,3\n{F600}GOTO/4,6,3\n")
    assert tp.n == 1
    assert np.allclose(tp.start[0], [1, 2, 3])
    assert tp.length[0] == pytest.approx(5.0)  # 3-4-5 triangle
    assert "no FROM" not in notices(tp)


def test_from_after_motion_is_a_rapid():
    """A FROM after moves is read as a rapid to its point, with a notice."""
    tp = read(f"{F600}GOTO/1,0,0\nFROM/5,5,5\nGOTO/5,5,0\n")
    assert list(tp.kind) == [MoveKind.LINE, MoveKind.RAPID, MoveKind.LINE]
    assert np.allclose(tp.end[1], [5, 5, 5])
    assert "FROM after motion read as a rapid" in notices(tp)


def test_gohome_is_a_rapid_to_its_point_or_to_from():
    """GOHOME/x,y,z is a rapid to the point (NX posts move home at rapid); GOHOME alone goes
    back to the FROM point."""
    tp = read(f"FROM/0,0,50\n{F600}GOTO/10,0,0\nGOHOME/0,0,60\nGOHOME\n")
    assert list(tp.kind) == [MoveKind.LINE, MoveKind.RAPID, MoveKind.RAPID]
    assert np.allclose(tp.end[1:], [[0, 0, 60], [0, 0, 50]])
    assert "GOHOME read as a rapid move" in notices(tp)


def test_godlta_moves_by_a_delta_or_along_the_tool_axis():
    """GODLTA/dx,dy,dz moves by the delta; GODLTA/d moves d along the tool axis."""
    tp = read(f"{F600}GOTO/1,1,1,0,0.6,0.8\nGODLTA/1,2,3\nGODLTA/5\n")
    assert np.allclose(tp.end[1], [2, 3, 4])
    assert np.allclose(tp.end[2], [2, 3 + 5 * 0.6, 4 + 5 * 0.8])


def test_units_inches_convert_to_mm():
    """UNITS/INCHES: points, radii and IPM feeds become mm and mm/s; the path says inch."""
    tp = read(
        "UNITS/INCHES\nFEDRAT/10,IPM\nGOTO/1,0,0\nCIRCLE/0,0,0,0,0,1,1\nGOTO/0,1,0\n", "i.apt"
    )
    assert tp.units == "inch"
    assert np.allclose(tp.end, [[25.4, 0, 0], [0, 25.4, 0]])
    assert tp.radius[1] == pytest.approx(25.4)
    assert tp.feed[0] == pytest.approx(10 * 25.4 / 60)
    assert "no UNITS" not in notices(tp)


def test_units_can_change_mid_file():
    """Units are modal: UNITS/MM after UNITS/INCHES reads the next points in mm."""
    tp = read("UNITS/INCHES\nFEDRAT/10,IPM\nGOTO/1,0,0\nUNITS/MM\nGOTO/50,0,0\n")
    assert np.allclose(tp.end[:, 0], [25.4, 50.0])


def test_unit_mm_solidworks_and_no_units_notice():
    """SolidWorks CAM's UNIT/MM counts as a units record; a file without one is read in mm
    and says so."""
    assert "no UNITS" not in notices(read(f"UNIT/MM\n{F600}GOTO/1,0,0\n"))
    assert "no UNITS record: millimetres assumed" in notices(read(f"{F600}GOTO/1,0,0\n"))


# ------------------------------------------------------------------------------ arcs
def test_circle_with_radius_counter_clockwise_about_its_axis():
    """APT CIRCLE: the tool turns counter-clockwise about i,j,k. From (10,0) around the origin
    to (0,10) about +Z is a quarter circle: sweep pi/2, length 2 pi 10 / 4 = 5 pi."""
    tp = read(f"{F600}GOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10\nGOTO/0,10,0\n")
    assert tp.kind[1] == MoveKind.ARC_CCW
    assert np.allclose(tp.center[1], [0, 0, 0]) and np.allclose(tp.normal[1], [0, 0, 1])
    assert tp.sweep[1] == pytest.approx(math.pi / 2)
    assert tp.length[1] == pytest.approx(5 * math.pi)
    assert np.allclose(tp.tangent_start[1], [0, 1, 0])
    assert tp.line[1] == 4  # the GOTO that ends the arc
    assert tp.feed[1] == pytest.approx(10.0)


def test_circle_about_minus_z_is_clockwise_in_xy():
    """The same end points about (0,0,-1): counter-clockwise about -Z is clockwise seen from
    +Z, the long way round: 270 degrees, 15 pi long, leaving (10,0) towards -Y."""
    tp = read(f"{F600}GOTO/10,0,0\nCIRCLE/0,0,0,0,0,-1,10\nGOTO/0,10,0\n")
    assert tp.kind[1] == MoveKind.ARC_CCW and np.allclose(tp.normal[1], [0, 0, -1])
    assert tp.sweep[1] == pytest.approx(3 * math.pi / 2)
    assert tp.length[1] == pytest.approx(15 * math.pi)
    assert np.allclose(tp.tangent_start[1], [0, -1, 0])


def test_circle_without_radius_solidworks():
    """SolidWorks CAM writes CIRCLE/x,y,z,i,j,k without the radius: it is the distance from the
    centre to the start point (here 5 from (3,4))."""
    tp = read(f"{F600}GOTO/3,4,0\nCIRCLE/0,0,0,0,0,1.\nGOTO/-4,3,0\n")
    assert tp.radius[1] == pytest.approx(5.0)
    # (3,4) -> (-4,3) is +90 degrees (the second is the first turned by 90 degrees)
    assert tp.sweep[1] == pytest.approx(math.pi / 2)


def test_nx_circle_is_clockwise_about_its_axis():
    """NX's 11-value CIRCLE (r, tolerance, ratio, tool diameter, corner radius) gives the axis
    for a clockwise turn: (10,0) -> (0,10) about +Z is then 270 degrees, stored ARC_CW."""
    tp = read(f"{F600}GOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10,0.06,0.5,16,0.8\nGOTO/0,10,0\n")
    assert tp.kind[1] == MoveKind.ARC_CW and np.allclose(tp.normal[1], [0, 0, 1])
    assert tp.sweep[1] == pytest.approx(3 * math.pi / 2)
    assert np.allclose(tp.tangent_start[1], [0, -1, 0])


@pytest.mark.parametrize(
    "axis,start,end,centre_end_tangent",
    [
        # about +Y, +90 deg takes +X to -Z (x' = x cos + z sin, z' = -x sin + z cos)
        ((0, 1, 0), (10, 0, 0), (0, 0, -10), (0, 0, -1)),
        # about +X, +90 deg takes +Y to +Z
        ((1, 0, 0), (0, 10, 0), (0, 0, 10), (0, 0, 1)),
        # about (0,1,1)/sqrt2, +90 deg takes (10,0,0) to n x r = (0, 10, -10)/sqrt2
        ((0, 1, 1), (10, 0, 0), (0, 10 / SQ2, -10 / SQ2), (0, 1 / SQ2, -1 / SQ2)),
    ],
    ids=["ZX plane", "YZ plane", "oblique plane"],
)
def test_arcs_in_other_planes(axis, start, end, centre_end_tangent):
    """Quarter circles of radius 10 about the origin in the ZX, YZ and an oblique plane: the
    axis (normalised) is the normal, the sweep pi/2 and the length 5 pi."""
    i, j, k = axis
    text = f"{F600}GOTO/{start[0]},{start[1]},{start[2]}\nCIRCLE/0,0,0,{i},{j},{k},10\n"
    text += f"GOTO/{end[0]:.9f},{end[1]:.9f},{end[2]:.9f}\n"
    tp = read(text)
    assert np.allclose(tp.normal[1], np.array(axis) / np.linalg.norm(axis))
    assert tp.sweep[1] == pytest.approx(math.pi / 2)
    assert tp.length[1] == pytest.approx(5 * math.pi)
    assert np.allclose(tp.tangent_start[1], centre_end_tangent)


def test_full_circle():
    """A CIRCLE whose GOTO returns to the start point is a full circle: 2 pi, 2 pi r long."""
    tp = read(f"{F600}GOTO/5,0,0\nCIRCLE/0,0,0,0,0,1,5\nGOTO/5,0,0\n")
    assert tp.sweep[1] == pytest.approx(2 * math.pi)
    assert tp.length[1] == pytest.approx(10 * math.pi)


def test_helix():
    """A CIRCLE whose GOTO ends 2 mm higher is a helical quarter turn: length
    sqrt((5 pi)^2 + 2^2)."""
    tp = read(f"{F600}GOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10\nGOTO/0,10,2\n")
    assert tp.length[1] == pytest.approx(math.hypot(5 * math.pi, 2))
    assert tp.pitch[1] == pytest.approx(2 / (math.pi / 2))


def test_circle_centre_is_moved_into_the_start_plane():
    """The record may give the centre at any height on the axis (NX gives the end level of a
    helix); the tool path keeps it in the plane through the start point."""
    tp = read(f"{F600}GOTO/10,0,5\nCIRCLE/0,0,2,0,0,1,10\nGOTO/0,10,2\n")
    assert np.allclose(tp.center[1], [0, 0, 5])


def test_nx_times_adds_full_turns():
    """NX's CIRCLE ... TIMES,2 helix: two full turns before the arc to the GOTO point, read
    with a notice. About (0,0,-1) clockwise = counter-clockwise seen from +Z: (10,0) -> (0,10)
    is pi/2, plus 2 x 2 pi."""
    tp = read(f"{F600}GOTO/10,0,3\nCIRCLE/0,0,0,0,0,-1,10,0.06,0.5,16,0.8,TIMES,2\nGOTO/0,10,0\n")
    assert tp.kind[1] == MoveKind.ARC_CW
    assert tp.sweep[1] == pytest.approx(math.pi / 2 + 4 * math.pi)
    assert tp.length[1] == pytest.approx(math.hypot(10 * (4.5 * math.pi), 3))
    assert "TIMES,n (NX helix) read as n full turns" in notices(tp)


def test_movarc_with_angle():
    """Fusion's MOVARC/x,y,z,i,j,k,r,ANGLE,a: counter-clockwise about the axis; ANGLE gives
    the sweep, which also tells a full circle (360) and extra turns (450) apart."""
    base = f"{F600}GOTO/10,0,0\n"
    tp = read(base + "MOVARC/0,0,0,0,0,1,10,ANGLE,90\nGOTO/0,10,0\n")
    assert tp.kind[1] == MoveKind.ARC_CCW and tp.sweep[1] == pytest.approx(math.pi / 2)
    tp = read(base + "MOVARC/0,0,0,0,0,1,10,ANGLE,360\nGOTO/10,0,0\n")
    assert tp.sweep[1] == pytest.approx(2 * math.pi)
    tp = read(base + "MOVARC/0,0,0,0,0,1,10,ANGLE,450\nGOTO/0,10,0\n")
    assert tp.sweep[1] == pytest.approx(2.5 * math.pi)
    tp = read(base + "MOVARC/0,0,0,0,0,-1,10\nGOTO/0,-10,0\n")
    assert tp.sweep[1] == pytest.approx(math.pi / 2)


def test_creo_arc_points_on_bare_lines():
    """Creo writes the points of an arc after one GOTO on lines of bare numbers: each is a move
    on the same circle (here two 45-degree arcs)."""
    h = 10 / SQ2
    tp = read(f"{F600}GOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10\nGOTO/{h:.9f},{h:.9f},0\n0,10,0\n")
    assert list(tp.kind[1:]) == [MoveKind.ARC_CCW, MoveKind.ARC_CCW]
    assert np.allclose(tp.sweep[1:], math.pi / 4)
    assert list(tp.line) == [2, 4, 5]


def test_bare_lines_after_a_plain_goto_are_more_lines():
    """Bare-number lines after a plain GOTO are more points of it: line moves."""
    tp = read(f"{F600}GOTO/1,0,0\n2,0,0\n 3 , 0 , 0\n")
    assert np.allclose(tp.end[:, 0], [1, 2, 3])
    assert list(tp.kind) == [MoveKind.LINE] * 3


def test_creo_circle_continued_with_a_comment():
    """Creo's helix record: '$' continues the CIRCLE on the next line, after a '$$' comment."""
    tp = read(
        "FEDRAT / 12.0, IPM\nGOTO / 0.198, 0.0, -0.625\n"
        "CIRCLE / 0.0, 0.0, -0.625, $ $$ 1ST ORBIT\n0.0, 0.0, 1.0, 0.198\n"
        "GOTO / 0.198, 0.0, -0.583333\n"
    )
    assert tp.kind[1] == MoveKind.ARC_CCW
    assert tp.sweep[1] == pytest.approx(2 * math.pi)  # a full orbit, 1/24 in higher
    assert tp.radius[1] == pytest.approx(0.198)  # no UNITS record: mm
    assert tp.line[1] == 5


# ------------------------------------------------------------------------------ 5 axis
def test_multax_tool_axis_is_kept_and_carried_forward():
    """GOTO records with i,j,k give the tool axis; 3-value GOTOs keep the last one (NX writes
    it only when it changes); a change of axis is reported."""
    tp = read(f"MULTAX/ON\n{F600}GOTO/0,0,1,0,0,1\nGOTO/1,0,0,0,0.6,0.8\nGOTO/2,0,0\nMULTAX/OFF\n")
    assert tp.tool_axis is not None
    assert np.allclose(tp.tool_axis, [[0, 0, 1], [0, 0.6, 0.8], [0, 0.6, 0.8]])
    assert "the tool axis changes" in notices(tp)
    assert "x,y,z path" in notices(tp)


def test_tool_axis_from_from_and_default():
    """FROM's i,j,k is the axis until a GOTO gives one; without any, moves before the first
    i,j,k take +Z, with a notice; a path without any i,j,k has no tool axis."""
    tp = read(f"FROM/0,0,9,1,0,0\n{F600}GOTO/1,0,0\nGOTO/2,0,0,0,0,1\n")
    assert np.allclose(tp.tool_axis, [[1, 0, 0], [0, 0, 1]])
    tp = read(f"{F600}GOTO/1,0,0\nGOTO/2,0,0,1,0,0\n")
    assert np.allclose(tp.tool_axis, [[0, 0, 1], [1, 0, 0]])
    assert "taken as +Z" in notices(tp)
    assert read(f"{F600}GOTO/1,0,0\n").tool_axis is None


# ------------------------------------------------------------------------------ operations
def test_tool_path_records_are_operations():
    """Each TOOL PATH ... END-OF-PATH is an operation named after the tool path; tools come
    from LOADTL and LOAD/TOOL."""
    tp = read(
        "TOOL PATH/ROUGH,TOOL,EM10\nLOAD/TOOL,3\nFEDRAT/MMPM,600\nGOTO/1,0,0\nGOTO/2,0,0\n"
        "END-OF-PATH\nTOOL PATH/FINISH,TOOL,BALL6\nLOADTL/7\nGOTO/3,0,0\nEND-OF-PATH\n"
    )
    assert list(tp.op_offsets) == [0, 2, 3]
    assert tp.op_names == ("ROUGH", "FINISH")
    assert list(tp.tool) == [3, 3, 7]


def test_tool_changes_are_operations_without_tool_path_records():
    """Without TOOL PATH records each tool load starts an operation, named by tool and line."""
    tp = read(
        "PARTNO/1\nLOAD/TOOL,14\nFEDRAT/600,MMPM\nGOTO/1,0,0\nLOADTL/5,0,100.,0\nGOTO/2,0,0\n"
    )
    assert list(tp.op_offsets) == [0, 1, 2]
    assert tp.op_names == ("T14 from line 4", "T5 from line 6")
    assert list(tp.tool) == [14, 5]


# ------------------------------------------------------------------------------ syntax
def test_continuation_and_comments():
    """'$' at the end of a line continues the record; '$$' starts a comment anywhere."""
    tp = read(f"$$ a comment line\n{F600}GOTO/1,$\n 2,3 $$ the end point\nGOTO/4,5,6 $$ more\n")
    assert np.allclose(tp.end, [[1, 2, 3], [4, 5, 6]])
    assert list(tp.line) == [3, 5]


def test_goto_lines_continued_with_dollar_are_one_record():
    """A GOTO line continuing a record ending in '$' belongs to that record, not to the bulk
    reader; in PPRINT text a '$' is just a character."""
    tp = read(f"{F600}GOTO/1,0,0\nSPINDL/ 100, $\nGOTO/5,5,5\nPPRINT/ COST $\nGOTO/2,0,0\n")
    assert np.allclose(tp.end[:, 0], [1, 2])
    assert list(tp.line) == [2, 6]


def test_spaces_around_slash_and_commas():
    """Blanks around '/', ',' and at the start of a line do not matter; lower case is read."""
    tp = read(
        "FEDRAT / MMPM , 600\nGOTO / 1, 2, 3\n   GOTO/4 ,5 , 6\ngoto/7,8,9\nGOTO  /  1.5E+01,0,0\n"
    )
    assert np.allclose(tp.end, [[1, 2, 3], [4, 5, 6], [7, 8, 9], [15, 0, 0]])


def test_bulk_and_per_record_readers_agree():
    """Plain GOTO lines (read in bulk) and the same GOTOs written so that the per-record reader
    takes them (comments, continuations) give the same tool path."""
    pts = [(0.5, -1.25, 3.0), (10.125, 4.0, -0.0625), (1e-3, 2.5e2, 7.0)]
    plain = F600 + "".join(f"GOTO/{x},{y},{z}\n" for x, y, z in pts)
    fancy = F600 + "".join(f"GOTO/{x},$\n{y}, {z} $$ p\n" for x, y, z in pts)
    a, b = read(plain), read(fancy)
    assert np.array_equal(a.end, b.end) and np.array_equal(a.feed, b.feed)


@pytest.mark.parametrize(
    "token",
    ["1", "-1.", "+.5", "1.e5", "-2.5E-02", "007", "1e-999", "0.0000", "-0"],
)
def test_bulk_and_per_record_readers_agree_on_numbers(token):
    """A number written in any form APT allows reads the same in a plain GOTO line (bulk) and
    in one the per-record reader takes (a leading blank)."""
    text = f"{F600}GOTO/9,9,9\nGOTO/{token},1,{token}\nGOTO/2,{token},0\n"
    bulk, per_record = read(text), read(text.replace("\nGOTO", "\n GOTO"))
    assert np.array_equal(bulk.end, per_record.end)
    assert bulk.end[1, 0] == float(token)


@pytest.mark.parametrize(
    "token",
    ["1.2.3", "1e", "e1", "--1", "+-1", ".", "-", "", " ", "1 2", "0x1", "1_0", "nan", "inf"]
    + ["infinity", "1e999", "-1e999", "1e5e5", "1d0", "1,", "$", "1.5.", "+"],
)
def test_bulk_and_per_record_readers_agree_on_errors(token):
    """A malformed value is the same error on the same line whether the bulk reader or the
    per-record reader meets it first: numpy's lenient parsing (a blank value read as -1, "1 2"
    as two values) never reaches the tool path."""
    text = f"{F600}GOTO/1,0,0\nGOTO/{token},0,0\nGOTO/2,0,0\n"
    errors = []
    for t in (text, text.replace("\nGOTO", "\n GOTO")):
        with pytest.raises(InputError) as info:
            read(t)
        errors.append((info.value.line, info.value.message))
    assert errors[0] == errors[1]
    assert errors[0][0] == 3


def test_crlf_and_cr_line_ends():
    """CRLF (Windows) and CR-only line ends read like LF, and so does a missing final one."""
    text = f"{F600}GOTO/1,0,0\nRAPID\nGOTO/2,0,0\n"
    lf = read(text)
    for other in (text.replace("\n", "\r\n"), text.replace("\n", "\r"), text[:-1]):
        tp = read(other)
        assert np.array_equal(tp.end, lf.end) and list(tp.line) == [2, 4]
        assert np.array_equal(tp.kind, lf.kind)


def test_passed_over_words_give_one_notice():
    """Words that cannot move the tool are passed over, listed in one notice; PPRINT and
    PARTNO text may hold commas, '/' and '$'."""
    tp = read(
        "PARTNO/BRACKET, REV $A\nPPRINT/ COST $5, 1/2 DONE\nSPINDL/3000,RPM,CLW\n"
        "COOLNT/FLOOD\nSELECT/TOOL,4\nPAINT/COLOR,42\nTLDATA/MILL,10,0,50,0,0\n"
        f"{F600}GOTO/1,0,0\n"
    )
    text = notices(tp)
    for word in ("PARTNO", "PPRINT", "SPINDL", "COOLNT", "SELECT", "PAINT", "TLDATA"):
        assert word in text
    assert "(7 lines)" in text
    assert tp.n == 1


def test_unknown_words_are_passed_over_by_name():
    """A word ncperf does not know is passed over with a notice naming it."""
    tp = read(f"CSI_SET_FLUTE_LENGTH/19.\n{F600}GOTO/1,0,0\nCSI_SET_FLUTE_LENGTH/20.\n")
    assert "CSI_SET_FLUTE_LENGTH: not a word ncperf knows" in notices(tp)
    assert "(2 lines)" in notices(tp)


def test_insert_frames_and_rotary_words_are_noticed():
    """INSERT (text for the NC program), MSYS/CSYS (the post's frame) and ROTABL pass with
    their own notices."""
    tp = read(
        f"INSERT/G53 Z0\nMSYS/0,0,0,1,0,0,0,1,0\nCSYS/1,0,0,0,0,1,0,0,0,0,1,0\nROTABL/90,CCLW\n"
        f"{F600}GOTO/1,0,0\n"
    )
    text = notices(tp)
    assert "INSERT/ text" in text and "MSYS/CSYS/TRNTYP" in text and "ROTABL" in text


def test_cutcom_reads_the_tool_centre_path():
    """CUTCOM/LEFT asks the controller for compensation: the CL path is read as the tool
    centre it is, with a notice; CUTCOM/OFF is silent."""
    tp = read(f"{F600}CUTCOM/LEFT\nGOTO/1,0,0\nCUTCOM/OFF\nGOTO/2,0,0\n")
    assert np.allclose(tp.end[:, 0], [1, 2])
    assert "CUTCOM/LEFT: controller cutter compensation" in notices(tp)
    assert "CUTCOM/OFF" not in notices(tp)


def test_stops_and_delay():
    """STOP/OPSTOP end the move before them at rest; DELAY/t dwells t seconds after it."""
    tp = read(f"{F600}GOTO/1,0,0\nOPSTOP\nGOTO/2,0,0\nDELAY/1.5\nGOTO/3,0,0\nSTOP\n")
    assert list(tp.path_mode) == [PathMode.EXACT_STOP, PathMode.CONTINUOUS, PathMode.EXACT_STOP]
    assert list(tp.dwell) == [0.0, 1.5, 0.0]


def test_fini_ends_the_data():
    """Nothing after FINI is read; motion after it is reported."""
    tp = read(f"{F600}GOTO/1,0,0\nFINI\nGOTO/2,0,0\nNURBS/\n")
    assert tp.n == 1
    assert "records after FINI" in notices(tp)


def test_zero_length_moves_dropped():
    """A GOTO to the current point is dropped with a notice."""
    tp = read(f"{F600}GOTO/1,0,0\nGOTO/1,0,0\nGOTO/2,0,0\n")
    assert tp.n == 2 and list(tp.line) == [2, 4]
    assert "moves shorter than the 0.001 mm resolution dropped" in notices(tp)


def test_drilling_cycles_in_both_apt_forms():
    """CYCLE/DRILL, d, MMPM, f, c (the APT standard's positional form) and the keyword form
    (FEDTO, RAPTO, RTRCTO) expand at every GOTO until CYCLE/OFF: rapid to c above the point,
    feed d below it at f, rapid back (to RTRCTO where given)."""
    tp = read(f"{F600}GOTO/0,0,10\nCYCLE/DRILL,5,MMPM,120,3\nGOTO/1,0,0\nGOTO/5,0,0\nCYCLE/OFF\n")
    assert list(tp.kind[1:]) == [0, 1, 0, 0, 1, 0]
    # hole at (1,0,0): rapid to z = 0 + 3, feed to 0 - 5 at 120 mm/min = 2 mm/s, rapid to 3
    assert np.allclose(tp.end[1:4], [[1, 0, 3], [1, 0, -5], [1, 0, 3]])
    assert tp.feed[2] == pytest.approx(2.0)
    assert np.allclose(tp.end[4:7], [[5, 0, 3], [5, 0, -5], [5, 0, 3]])
    assert (tp.path_mode[1:] == 1).all()  # every step of a cycle ends at rest
    tp = read(
        f"{F600}GOTO/0,0,10\nCYCLE/INIT\nCYCLE/DEEP2,FEDTO,7,1STPECK,3,SUBPECK,2,MMPM,60,"
        "RAPTO,2,RTRCTO,20\nGOTO/0,0,0\nCYCLE/OFF\nGOTO/0,0,30\n"
    )
    # pecks from the RAPTO level (z = 2): 3 mm to z = -1, then 2 mm steps to -3, -5, then -7;
    # after each peck a rapid to z = 2 and back down to the last depth; retract to z = 20
    z = tp.end[:, 2]
    feeds = z[tp.kind == 1][1:-1]  # the first and last feed moves are the GOTOs around it
    assert np.allclose(feeds, [-1, -3, -5, -7])
    assert z[-2] == pytest.approx(20.0) and z[-1] == pytest.approx(30.0)


def test_a_subpeck_of_zero_means_every_peck_is_the_step():
    """CYCLE/DEEP2 with SUBPECK 0 (fuzzer: the read never ended, adding pecks of 0 mm): every
    peck is the STEP, 3 mm from the RAPTO level z = 2: to -1, -4, then the depth -7."""
    tp = read(
        f"{F600}GOTO/0,0,10\nCYCLE/DEEP2,FEDTO,7,STEP,3,SUBPECK,0,MMPM,60,RAPTO,2\n"
        "GOTO/0,0,0\nCYCLE/OFF\n"
    )
    z = tp.end[:, 2]
    assert np.allclose(z[tp.kind == 1][1:], [-1, -4, -7])


def test_cycle_off_alone_passes():
    """CYCLE/OFF without a cycle is harmless."""
    assert read(f"{F600}GOTO/1,0,0\nCYCLE/OFF\n").n == 1


# ------------------------------------------------------------------------------ errors
@pytest.mark.parametrize(
    "text,line,fragment",
    [
        ("   \n\n", None, "empty file"),
        (f"{F600}GOTO/1,2,x\n", 2, "'x' is not a number"),
        (f"{F600}GOTO/1..2,0,0\n", 2, "'1..2' is not a number"),
        (f"{F600}GOTO/1.2.3,0,0\n", 2, "'1.2.3' is not a number"),
        (f"{F600}GOTO/1 2,3,4\n", 2, "'1 2' is not a number"),
        (f"{F600}GOTO/1,,2,3\n", 2, "empty value between commas"),
        (f"{F600}GOTO/1, ,3\n", 2, "empty value between commas"),
        (f"{F600}GOTO/1,2,3,\n", 2, "empty value between commas"),
        (f"{F600}GOTO/nan,0,0\n", 2, "'nan' is not a number"),
        (f"{F600}GOTO/inf,0,0\n", 2, "'inf' is not a number"),
        (f"{F600}GOTO/1e999,0,0\n", 2, "number 1e999 out of range"),
        (f"{F600}GOTO/1,2\n", 2, "GOTO needs 3 values (x,y,z) or 6 (x,y,z,i,j,k), got 2"),
        (f"{F600}GOTO/1,2,3,4\n", 2, "got 4"),
        (f"{F600}GOTO\n", 2, "got 0"),
        (f"{F600}GOTO/1,0,0,0,0,2\n", 2, "tool axis i,j,k is not a unit vector (length 2)"),
        ("GOTO/1,0,0\n", 1, "feed move without a feed rate"),
        ("FEDRAT/600,MMPR\nGOTO/1,0,0\n", 1, "feed per revolution (MMPR) is not supported"),
        ("FEDRAT/INVERS,2\nGOTO/1,0,0\n", 1, "inverse-time feed"),
        ("FEDRAT/0,MMPM\n", 1, "feed rate must be positive"),
        ("FEDRAT/600,FPM\n", 1, "FEDRAT unit FPM not understood"),
        ("FEDRAT/MMPM\n", 1, "FEDRAT needs one feed rate"),
        ("FEDRAT/inf,MMPM\n", 1, "FEDRAT needs one feed rate"),
        ("UNITS/FEET\n", 1, "UNITS/ needs MM or INCHES"),
        ("RAPID/ON\n", 1, "RAPID/ON not understood"),
        ("MULTAX/MAYBE\n", 1, "MULTAX/MAYBE not understood"),
        (f"{F600}GOTO/1,0,0\nNURBS/\nKNOT/0,1\n", 3, "NURBS/ spline motion is not supported"),
        (f"{F600}CYCLE/SPIRAL,5\nGOTO/1,0,0\n", 2, "CYCLE/SPIRAL is not a drilling cycle"),
        (f"{F600}CYCLE/DRILL,RAPTO,3\nGOTO/1,0,0\n", 2, "CYCLE/DRILL without its depth"),
        (f"{F600}CYCLE/DRILL,5,MMPM,100,3,7\n", 2, "3 numbers where the APT form has 2"),
        (f"{F600}GOFWD/(CIRCLE/0,0,0,5),ON,L1\n", 2, "GOFWD is an APT part-program statement"),
        (f"{F600}INDIRV/1,0,0\n", 2, "INDIRV is an APT part-program statement"),
        ("PT1=POINT/1,2,3\n", 1, "'=' (a geometry definition"),
        ("COPY/1,TRANSL,10,0,0,2\n", 1, "COPY/ repeats motion"),
        ("TRACUT/MX1\n", 1, "TRACUT/ transforms"),
        ("MODE/TURN\n", 1, "lathe CL data is not supported"),
        (f"{F600}GOTO/1,0,0\nDELAY/100,REV\n", 3, "DELAY in spindle revolutions"),
        ("GOTO/1,0,$\n", 1, "continuation '$' at the end of the file"),
        ("1,2,3\n", 1, "numbers without a record word"),
        (
            "RAPID\nGOTO/1,0,0\n4,5,6\nFEDRAT/600\nGOTO/0,0,0\n7,8,9\nPAINT/X\n1,1,1\n",
            8,
            "numbers without a record word",
        ),
        ("GOTO/1,0,0 ; G1 X1\n", 1, "'0 ; G1 X1' is not a number"),
        ("/GOTO/1,0,0\n", 1, "malformed record"),
        ("GOTO/1,0,\u00e9\n", 1, "non-ASCII character"),
        ("GOTO/1,0,\x01\n", 1, "control character 0x01"),
        ("GOHOME\n", 1, "GOHOME without a point"),
        ("GODLTA/1,2\n", 1, "GODLTA needs 1 value"),
        ("LOADTL\n", 1, "LOADTL without a tool number"),
        ("LOADTL/2.5\n", 1, "tool number must be a whole number"),
        ("$$ contact data\nGOTO/1,0,0\n", 1, "contact data: the GOTO points are where the tool"),
        ("FROM/1,2\n", 1, "FROM needs 3 values"),
    ],
    ids=lambda v: v if isinstance(v, str) and len(v) < 40 and "\n" not in v else None,
)
def test_errors_name_file_and_line(text, line, fragment):
    """Every input ncperf cannot read faithfully is one error line naming file and line."""
    fails(text, line, fragment)


@pytest.mark.parametrize(
    "text,line,fragment",
    [
        (
            f"{F600}GOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,10\nGOTO/0,10.5,0\n",
            4,
            "arc end point is 0.5000 mm off the circle of radius 10.0000 mm (CIRCLE at line 3)",
        ),
        (
            f"{F600}GOTO/3,4,0\nCIRCLE/0,0,0,0,0,1\nGOTO/0,5.2,0\n",
            4,
            "arc end point is 0.2000 mm off the circle of radius 5.0000 mm",
        ),
        (
            f"{F600}GOTO/10,0,0\nCIRCLE/0,0,0,0,0,1,12\nGOTO/0,12,0\n",
            3,
            "the arc's start point (the previous point) is 2.0000 mm off the circle",
        ),
        (f"{F600}CIRCLE/0,0,0,0,0,1,10\nRAPID\nGOTO/0,10,0\n", 2, "next: RAPID at line 3"),
        (f"{F600}CIRCLE/0,0,0,0,0,1,10\nCIRCLE/0,0,0,0,0,1,10\n", 2, "next: CIRCLE at line 3"),
        (f"{F600}CIRCLE/0,0,0,0,0,1,10\nLOADTL/2\n", 2, "next: LOADTL at line 3"),
        (f"{F600}CIRCLE/0,0,0,0,0,1,10\n", 2, "next: the end of the file"),
        (f"{F600}CIRCLE/0,0,0,0,0,1,10\nGODLTA/0,0,1\n", 2, "next: GODLTA"),
        (f"{F600}RAPID\nCIRCLE/0,0,0,0,0,1,10\nGOTO/0,10,0\n", 3, "RAPID before CIRCLE"),
        (f"{F600}CIRCLE/0,0,0,0,0,1,10,1\n", 2, "CIRCLE with 8 values"),
        (f"{F600}CIRCLE/0,0,0,0,0,0,10\n", 2, "CIRCLE axis vector i,j,k is zero"),
        (f"{F600}CIRCLE/0,0,0,0,0,1,-10\n", 2, "CIRCLE radius must be positive"),
        (f"{F600}CIRCLE/0,0,0,0,0,1,10,TIMES,2\n", 2, "CIRCLE modifier TIMES,2 not understood"),
        (
            f"{F600}CIRCLE/0,0,0,0,0,1,10,.06,.5,16,.8,TIMES,1.5\n",
            2,
            "TIMES must be a positive whole number",
        ),
        (
            f"{F600}GOTO/0,0,0\nCIRCLE/0,0,0,0,0,1\nGOTO/0,0,0\n",
            3,
            "arc with zero radius",
        ),
        (
            f"{F600}GOTO/10,0,0\nMOVARC/0,0,0,0,0,1,10,ANGLE,180\nGOTO/0,10,0\n",
            4,
            "MOVARC ANGLE 180 does not reach the GOTO end point",
        ),
        (f"{F600}MOVARC/0,0,0,0,0,1,10,SWEEP,9\n", 2, "MOVARC modifier SWEEP,9 not understood"),
        (f"{F600}MOVARC/0,0,0,0,0,1,10,ANGLE,-9\n", 2, "MOVARC ANGLE must be positive"),
    ],
    ids=[
        "end off circle",
        "end off circle, no radius",
        "start off circle",
        "circle then rapid",
        "circle then circle",
        "circle then tool change",
        "circle at end of file",
        "circle then godlta",
        "rapid arc",
        "8 values",
        "zero axis",
        "negative radius",
        "times without nx fields",
        "fractional times",
        "zero radius",
        "movarc angle mismatch",
        "movarc modifier",
        "movarc negative angle",
    ],
)
def test_arc_errors_name_file_and_line(text, line, fragment):
    """Arcs that do not close on their circle, CIRCLEs without their GOTO and malformed arc
    records are errors naming the line (the GOTO's for end points, else the CIRCLE's)."""
    fails(text, line, fragment)


def test_binary_and_long_lines():
    """Binary data and absurdly long lines are rejected with the line they are on."""
    with pytest.raises(InputError, match=r"^b\.cls:2: binary file"):
        read_cl(b"GOTO/1,0,0\nGO\x00TO\n", "b.cls")
    with pytest.raises(InputError, match=r"^l\.cls:1: line is 5000 characters long"):
        read_cl(b"$$" + b"x" * 4998 + b"\n", "l.cls")


def test_no_moves():
    """A file without motion is an error naming it."""
    fails("PARTNO/X\nFEDRAT/600\n", None, "no moves (GOTO records)")
    fails("GOTO/1,0,0\n", 1, "feed move without a feed rate")
    fails(f"{F600}GOTO/0,0,0\n", None, "no moves of nonzero length")


def test_bad_number_deep_in_a_long_file_names_its_line():
    """A malformed number among thousands of plain GOTO lines (read in bulk) is found and
    named by its line."""
    lines = [F600.strip()] + [f"GOTO/{i}.5,0,0" for i in range(3000)]
    lines[2021] = "GOTO/1.2.3,0,0"
    fails("\n".join(lines) + "\n", 2022, "'1.2.3' is not a number")
    lines[2021] = "GOTO/1e400,0,0"
    fails("\n".join(lines) + "\n", 2022, "number 1e400 out of range")


def test_error_quotes_the_record():
    """The message ends with the offending record, shortened."""
    err = fails(f"{F600}NURBS/\n", 2, "NURBS/")
    assert str(err).endswith(": NURBS/")


# ------------------------------------------------------------------------------ direction check
def test_reversed_arcs_are_reported():
    """Arcs that reverse against both neighbouring lines (a CAM system using the other CIRCLE
    convention) give a notice; tangent ones do not."""
    # line +X to (10,0), then a half circle about (10,5) back to (10,10), then a line -X:
    # about (0,0,1) counter-clockwise the arc continues both lines tangentially.
    good = f"{F600}GOTO/10,0,0\nCIRCLE/10,5,0,0,0,1,5\nGOTO/10,10,0\nGOTO/0,10,0\n"
    assert "may turn the other way" not in notices(read(good))
    bad = good.replace("0,0,1,5", "0,0,-1,5")
    assert "2 arc ends reverse against a neighbouring line" in notices(read(bad))


# ------------------------------------------------------------------------------ cross-check
GCODE = """G21 G90 G17 G64
G0 X0 Y0 Z5
G1 Z0 F600
X10
G3 X20 Y10 I0 J10
G1 Y20 F1200
G2 X30 Y30 I10 J0
G1 X40 Z-1
G18 G2 X50 Z-1 I5 K0
G0 Z5
"""

CL = """UNITS/MM
RAPID
GOTO/0,0,5
FEDRAT/600,MMPM
GOTO/0,0,0
GOTO/10,0,0
CIRCLE/10,10,0,0,0,1,10
GOTO/20,10,0
FEDRAT/MMPM,1200
GOTO/20,20,0
CIRCLE/30,20,0,0,0,-1,10
GOTO/30,30,0
GOTO/40,30,-1
CIRCLE/45,30,-1,0,-1,0,5
GOTO/50,30,-1
RAPID/
GOTO/50,30,5
"""


def test_same_path_as_gcode_gives_the_same_toolpath_and_feeds():
    """A CL file and a G-code program of one path (a rapid, lines, arcs both ways in XY and in
    ZX, two feeds) give the same tool path within 1e-6 mm and the same predicted feeds. A G2
    about +Z is the CL's counter-clockwise arc about -Z: compared as the signed axis."""
    from adapters.gcode import read_gcode
    from core import Ncperf, make_plugin_manager

    g = read_gcode(GCODE.encode(), "t.nc")
    c = read(CL)
    assert g.n == c.n == 9
    for name in ("start", "end", "length", "tangent_start", "tangent_end", "feed"):
        assert np.allclose(getattr(g, name), getattr(c, name), atol=1e-6, equal_nan=True), name
    for name in ("center", "sweep", "radius", "curvature_vector_start", "curvature_vector_end"):
        assert np.allclose(getattr(g, name), getattr(c, name), atol=1e-6, equal_nan=True), name
    assert np.array_equal(g.is_arc, c.is_arc) and np.array_equal(g.is_feed, c.is_feed)

    def rotation(tp):  # the arc's axis signed by its direction: the same arc, however written
        return tp.normal * np.where(tp.kind == MoveKind.ARC_CCW, 1.0, -1.0)[:, None]

    assert np.allclose(rotation(g), rotation(c), equal_nan=True)
    assert list(g.path_mode) == list(c.path_mode) and list(g.op_offsets) == list(c.op_offsets)

    nc = Ncperf(make_plugin_manager(entry_points=False))
    machine = load_preset("siemens-840d")
    eg, ec = nc.evaluate(g, machine), nc.evaluate(c, machine)
    assert eg.junction.size > 0
    assert np.array_equal(eg.junction, ec.junction)
    assert np.allclose(eg.junction_feed, ec.junction_feed, rtol=1e-9)
    assert np.allclose(eg.element_feed, ec.element_feed, rtol=1e-9, equal_nan=True)
    assert np.array_equal(eg.junction_limit, ec.junction_limit)


# ------------------------------------------------------------------------------ hook
def test_extract_hook_claims_cl_files_and_never_gcode(tmp_path):
    """The A1 hook takes CL extensions and APT-looking files of other extensions, and returns
    None for G-code (whatever it holds), other text and host objects."""
    body = f"{F600}GOTO/1,0,0\n"
    for ext in (".cls", ".clsf", ".apt", ".cl", ".aptsource", ".cldata", ".APT"):
        p = tmp_path / f"part{ext}"
        p.write_text(body)
        assert ncperf_extract(source=str(p)).n == 1, ext
    q = tmp_path / "part.ncl.1"  # Creo
    q.write_text("$$* Pro/CLfile Version Wildfire 5.0\n" + body)
    assert ncperf_extract(source=q).n == 1
    for name, text in (
        ("part.nc", body),
        ("part.ngc", "GOTO/1,0,0\n"),
        ("prog.txt", "%\nG21 G1 X1 F60\n"),
        ("notes.txt", "hello\n"),
    ):
        p = tmp_path / name
        p.write_text(text)
        assert ncperf_extract(source=str(p)) is None, name
    assert ncperf_extract(source=object()) is None
    assert ncperf_extract(source=str(tmp_path / "missing.txt")) is None
    with pytest.raises(InputError, match="cannot read"):
        ncperf_extract(source=str(tmp_path / "missing.cls"))
    (tmp_path / "dir.cls").mkdir()
    with pytest.raises(InputError, match="is a folder"):
        ncperf_extract(source=str(tmp_path / "dir.cls"))


@pytest.mark.parametrize(
    "head,claimed",
    [
        (b"TOOL PATH/FINISH,TOOL,BALL\n", True),
        (b"\n\n  PARTNO/1\n", True),
        (b"PARTNO BRACKET\n", True),
        (b"$$ centerline data\n", True),
        (b"GOTO / 1, 2, 3\n", True),
        (b"UNIT/MM\n", True),
        (b"G21 G1 X1\n", False),
        (b"%\nO1000\n", False),
        (b"(GOTO/1,2,3)\n", False),
        (b"GOTO/1,2,3\x00\n", False),
    ],
)
def test_looks_like_cl(head, claimed):
    """A file of another extension is CL data if its first non-blank line is an APT record."""
    assert looks_like_cl(head) is claimed


def test_extract_through_the_facade(nc, tmp_path):
    """nc.extract reads a .cls file with the default plugin manager, and an APT file with a
    foreign extension; options meant for G-code are ignored."""
    p = tmp_path / "part.cls"
    p.write_text(CL)
    tp = nc.extract(str(p))
    assert tp.n == 9 and tp.source == str(p)
    q = tmp_path / "part.txt"
    q.write_text("TOOL PATH/A,TOOL,B\n" + CL)
    tp = nc.extract(q, ExtractOptions(dialect="fanuc", block_delete=True))
    assert tp.n == 9 and tp.op_names == ("A",)
    nc.evaluate(tp, load_preset("siemens-840d"))
