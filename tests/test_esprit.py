"""The ESPRIT adapter (A1 + A3) against the Python twin and the .NET emulation (issue 3).

Every adapter test runs on three backends: the Python twin, the .NET emulation as pythonnet
shows it, and the .NET emulation reached by name through reflection -- the late-binding path
a live ESPRIT takes over COM. The .NET ones skip, with the reason, where Mono, pythonnet or
the emulation DLL (scripts/setup_esprit_emulation.sh) is missing.
"""

from __future__ import annotations

import math
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from adapters.esprit_com import EspritSource, colorref
from adapters.esprit_com import object_model as om
from adapters.esprit_com.addin import run as addin_run
from adapters.esprit_com.clr_host import DotnetUnavailable, LateBound, load_emulation
from adapters.esprit_com.command import analyze_and_draw
from adapters.esprit_com.draw import EspritError
from adapters.esprit_com.emulation import Backend, backend, fill_document, raw_document, recording
from adapters.gcode import read_gcode
from core import FileTarget, InputError, resolve_machine
from core.cli import main
from core.model.tolerances import TOL
from core.model.toolpath import MoveKind, ToolPath, empty_columns
from core.view.annotations import REDUCTION_COLOURS, Annotations
from tests.conftest import ROOT

BACKENDS = ("python-twin", "dotnet", "dotnet-latebound")
IT = om.ITEM_TYPES
LAYER = om.LAYER_NAME

#: Exact arcs (end points on the circle) in G17, G18 and G19, a full circle, rapids, two
#: tools and two feeds per tool: everything ESPRIT's items can hold.
ROUND_TRIP = b"""%
(two tools; arcs in the three planes; two feeds per tool)
G21 G90 G17 G64
T1 M6
G0 X0 Y0 Z5
G1 Z0 F600
G1 X20 F3000
G3 X30 Y10 I0 J10
G2 X40 Y20 I10 J0
G1 Y40
G2 X40 Y40 I0 J-10
G0 Z5
T2 M6
G0 X0 Y0 Z5
G1 Z-1 F500
G18 G2 X10 Z-11 I10 K0
G19 G3 Y10 Z-1 J10 K0
G17 G1 X30 F2500
M30
"""
COLUMNS = ("kind", "start", "end", "center", "normal", "sweep", "feed")


@pytest.fixture(scope="session")
def dotnet():
    """The .NET emulation, loaded once per test process (one .NET runtime per process),
    or why it cannot be."""
    try:
        return load_emulation()
    except DotnetUnavailable as exc:
        return exc


@pytest.fixture(params=BACKENDS)
def be(request, dotnet) -> Backend:
    """Each backend of the emulated object model."""
    if request.param == "python-twin":
        return backend("python-twin")
    if isinstance(dotnet, DotnetUnavailable):
        pytest.skip(f".NET ESPRIT emulation unavailable: {dotnet.reason}")
    return Backend(request.param, dotnet)


def program(data: bytes = ROUND_TRIP, name: str = "rt.ngc") -> ToolPath:
    return read_gcode(data, name)


def make_doc(be: Backend, ops, *, name: str = "part"):
    """An emulated Application with operations ``(name, xy_feed, z_feed, items or None)``;
    items are ``(type, aux, numbers)`` with the 12 numbers of ``Emulation.AddItems``."""
    app = be.ns.Application(name)
    doc = app.Document
    for op_name, xy, z, items in ops:
        op = be.ns.Emulation.AddOperation(doc, op_name, xy, z, items is not None)
        if items:
            types = np.array([t for t, _, _ in items])
            aux = np.array([a for _, a, _ in items])
            data = np.array([list(d) + [0.0] * (12 - len(d)) for _, _, d in items], dtype=float)
            be.ns.Emulation.AddItems(
                op, be.ints(types), be.ints(aux), be.doubles(data), om.AUX_RAPID
            )
    return app


def one_line(be: Backend, *extra, name: str = "part"):
    """A document with one operation 'Finish': a line, then ``extra`` items."""
    items = [
        (IT["tpiSTART_POINT"], 0, (0, 0, 0)),
        (IT["tpiSEG2"], om.AUX_CUT, (0, 0, 0, 10, 0, 0)),
        *extra,
    ]
    return make_doc(be, [("Finish", 1200.0, 300.0, items)], name=name)


# ----------------------------------------------------------------------------- the table
def test_colorref_worked_by_hand():
    """Colours go to ESPRIT as COLORREF 0x00BBGGRR: red in the low byte."""
    assert colorref("#d73027") == 0x002730D7
    assert colorref("#1a9850") == 0x0050981A
    assert colorref("#FFFFFF") == 0x00FFFFFF
    with pytest.raises(ValueError, match="#rrggbb"):
        colorref("red")


def test_item_type_table_is_one_partition():
    """Every espToolPathItemType is exactly one of point, segment or arc, values distinct."""
    groups = (om.POINT_ITEMS, om.SEGMENT_ITEMS, om.ARC_ITEMS)
    assert set().union(*groups) == set(om.ITEM_TYPES.values())
    assert sum(len(g) for g in groups) == len(om.ITEM_TYPES) == len(set(om.ITEM_TYPES.values()))


@pytest.mark.parametrize(
    ("enum", "table"),
    [
        ("espToolPathItemType", om.ITEM_TYPES),
        ("espGraphicObjectType", om.GRAPHIC_OBJECT_TYPES),
        ("espUnitType", om.UNIT_TYPES),
    ],
)
def test_dotnet_enums_equal_the_table(dotnet, enum, table):
    """The C# emulation's enums have the names and values of object_model's table."""
    if isinstance(dotnet, DotnetUnavailable):
        pytest.skip(f".NET ESPRIT emulation unavailable: {dotnet.reason}")
    names = list(dotnet.Emulation.EnumNames(enum))
    values = list(dotnet.Emulation.EnumValues(enum))
    assert dict(zip(names, values, strict=True)) == table


def test_import_and_file_sources_never_load_pythonnet():
    """Importing the adapter and reading a G-code file through all adapters imports no clr."""
    code = (
        "import sys; from core import Ncperf; nc = Ncperf(); "
        "nc.extract('examples/fig1_polygons_F2000.ngc'); "
        "print(sorted(m for m in ('clr', 'pythonnet', 'clr_loader') if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert out.stdout.strip() == "[]"


@pytest.mark.parametrize(
    "source", ["part.ngc", ROOT / "examples" / "zlevel_cavity.ngc", object(), FileTarget("a.svg")]
)
def test_hooks_decline_what_is_not_esprit(source):
    """A1 and A3 return None for paths, file targets and foreign objects."""
    from adapters import esprit_com

    assert esprit_com.ncperf_extract(source=source, options=None) is None
    assert esprit_com.ncperf_display(toolpath=None, annotations=None, target=source) is None


# ----------------------------------------------------------------------------- A1
def test_round_trip_gcode_through_esprit(nc, be):
    """G-code -> emulated ESPRIT document -> A1 gives back the tool path read from the G-code:
    same moves, arcs, planes and feeds, one operation per tool, line = item index."""
    direct = program()
    app = fill_document(direct, be)
    back = nc.extract(EspritSource(be.host(app)))
    assert back.source == "ESPRIT document rt.ngc"
    assert back.op_names == direct.op_names
    assert back.op_offsets.tolist() == direct.op_offsets.tolist()
    for key in COLUMNS:
        np.testing.assert_allclose(getattr(back, key), getattr(direct, key), atol=1e-9, err_msg=key)
    # Each operation's items: 1 is the start point, the moves are items 2..m+1.
    sizes = np.diff(direct.op_offsets)
    assert back.line.tolist() == np.concatenate([np.arange(2, m + 2) for m in sizes]).tolist()
    assert back.units == "mm" and back.notices == ()


@pytest.mark.parametrize("name", ["python-twin", "dotnet"])
def test_round_trip_bundled_cavity(nc, dotnet, name):
    """The bundled Z-level cavity survives the round trip; arc end points move only onto the
    circle (ESPRIT arcs hold centre, radius and angles), within the G-code's own tolerance."""
    if name == "dotnet" and isinstance(dotnet, DotnetUnavailable):
        pytest.skip(f".NET ESPRIT emulation unavailable: {dotnet.reason}")
    be = backend(name)
    direct = nc.extract(str(ROOT / "examples" / "zlevel_cavity.ngc"))
    back = nc.extract(fill_document(direct, be))
    for key in ("kind", "start", "center", "normal", "sweep", "feed"):
        np.testing.assert_allclose(getattr(back, key), getattr(direct, key), atol=1e-9, err_msg=key)
    off = np.abs(np.linalg.norm(direct.end - direct.center, axis=1) - direct.radius)
    moved = np.linalg.norm(back.end - direct.end, axis=1)
    assert np.all(moved <= np.where(direct.is_arc, off, 0.0) + 1e-9)
    assert np.all(moved <= TOL.arc_end_abs)


def test_inch_document_is_scaled(nc, be):
    """A document in inches comes out in mm: coordinates and per-minute feeds times 25.4."""
    app = one_line(be)
    raw_document(app).SystemUnit = be.ns.espUnitType.espInch
    tp = nc.extract(be.host(app))
    assert tp.units == "inch"
    np.testing.assert_allclose(tp.end[0], [254.0, 0.0, 0.0])
    assert tp.feed[0] == pytest.approx(1200.0 * 25.4 / 60.0)


def test_arc_angles_wrap_and_planes_flip(nc, be):
    """An arc from StartAngle 3pi/2 to EndAngle pi/2 turns pi; with V = -Y its plane's normal
    is -Z, which ncperf writes as +Z and clockwise (G2)."""
    arc_ccw = (2.0, 0, 0, 2.0, 1, 0, 0, 0, 1, 0, 1.5 * math.pi, 0.5 * math.pi)
    arc_cw = (2.0, 0, 0, 2.0, 1, 0, 0, 0, -1, 0, 0.5 * math.pi, 1.5 * math.pi)
    items = [(IT["tpiARC2"], om.AUX_CUT, arc_ccw), (IT["tpiARC2"], om.AUX_CUT, arc_cw)]
    tp = nc.extract(be.host(make_doc(be, [("Arcs", 1200.0, 0.0, items)])))
    # centre (2,0), radius 2: angle 3pi/2 is (2,-2), pi/2 is (2,2); with V = -Y they swap.
    np.testing.assert_allclose(tp.start, [[2, -2, 0], [2, -2, 0]], atol=1e-12)
    np.testing.assert_allclose(tp.end, [[2, 2, 0], [2, 2, 0]], atol=1e-12)
    assert tp.kind.tolist() == [MoveKind.ARC_CCW, MoveKind.ARC_CW]
    np.testing.assert_allclose(tp.normal, [[0, 0, 1], [0, 0, 1]])
    np.testing.assert_allclose(tp.sweep, [math.pi, math.pi])


def test_selected_operations_or_all(nc, be):
    """Scope auto reads the selection if it holds operations, else all; 'all' reads all;
    'selected' with nothing selected is an error."""
    line = [(IT["tpiSEG3"], om.AUX_CUT, (0, 0, 0, 5, 0, 0))]
    app = make_doc(be, [("Rough", 1200.0, 0.0, line), ("Finish", 600.0, 0.0, line)])
    assert nc.extract(EspritSource(be.host(app))).op_names == ("Rough", "Finish")
    with pytest.raises(InputError, match="no operation is selected"):
        nc.extract(EspritSource(be.host(app), "selected"))
    doc = raw_document(app)
    be.ns.Emulation.Select(doc, doc.PartOperations[2])
    assert nc.extract(EspritSource(be.host(app))).op_names == ("Finish",)
    assert nc.extract(EspritSource(be.host(app), "all")).op_names == ("Rough", "Finish")


def test_feed_and_rapid_lengths_are_cross_checked(nc, be):
    """When ESPRIT's LengthOfFeed/LengthOfRapid disagree with the items read as feed and rapid,
    a warning says the AuxCode table may not hold; when they agree, none."""
    app = one_line(be, (IT["tpiSEG3"], om.AUX_RAPID, (10, 0, 0, 10, 0, 7)))
    assert nc.extract(be.host(app)).notices == ()
    be.ns.Emulation.SetLengths(raw_document(app).PartOperations[1], 17.0, 0.0)
    (notice,) = nc.extract(be.host(app)).notices
    assert "items give 10.000 mm of feed and 7.000 of rapid" in notice.message
    assert "LengthOfFeed 17.000 and LengthOfRapid 0.000" in notice.message
    assert "AuxCode table" in notice.message


def test_aux_codes_pick_feeds(nc, be):
    """AuxCode 0 runs at XYFeedratePM, 2 at ZFeedratePM, 1 is a rapid (mm/min -> mm/s)."""
    app = one_line(
        be,
        (IT["tpiSEG3"], om.AUX_PLUNGE, (10, 0, 0, 10, 0, -2)),
        (IT["tpiSEG3"], om.AUX_RAPID, (10, 0, -2, 10, 0, 5)),
    )
    tp = nc.extract(be.host(app))
    assert tp.kind.tolist() == [MoveKind.LINE, MoveKind.LINE, MoveKind.RAPID]
    np.testing.assert_allclose(tp.feed, [20.0, 5.0, np.nan])


# ----------------------------------------------------------------------------- A1 errors
def test_operation_without_tool_path(nc, be):
    """An operation with no tool path: an error naming document and operation, nothing drawn."""
    app = make_doc(be, [("Roughing", 1200.0, 0.0, None)])
    with pytest.raises(InputError) as err:
        analyze_and_draw(nc, EspritSource(be.host(app)), resolve_machine(None))
    assert str(err.value) == (
        "ESPRIT document part: operation 'Roughing': has no tool path "
        "(compute it in ESPRIT, or leave it out)"
    )
    rec = recording(app, be)
    assert rec.layers == ("Default",) and not rec.transaction_open and rec.undo_steps == 0


def test_unknown_item_type(nc, be):
    """An item type not in the table: an error naming operation, item and the table."""
    app = one_line(be, (99, om.AUX_CUT, (10, 0, 0, 20, 0, 0)))
    with pytest.raises(InputError) as err:
        analyze_and_draw(nc, EspritSource(be.host(app)), resolve_machine(None))
    assert err.value.line == 3
    assert str(err.value).startswith(
        "ESPRIT document part:3: operation 'Finish': item 3 has type 99, none of the "
        "espToolPathItemType values ncperf knows (tpiSTART_POINT = 0"
    )
    assert "object_model.py ITEM_TYPES" in str(err.value)
    assert recording(app, be).layers == ("Default",)


def test_unknown_aux_code(nc, be):
    """An AuxCode not in the table is an error, not a guess."""
    app = one_line(be, (IT["tpiSEG2"], 7, (10, 0, 0, 20, 0, 0)))
    with pytest.raises(InputError, match=r"part:3: operation 'Finish': item 3 has AuxCode 7"):
        nc.extract(be.host(app))


def test_zero_radius_arc_item(nc, be):
    """An arc item of radius 0: an error naming the item; nothing drawn."""
    zero = (IT["tpiARC2"], om.AUX_CUT, (10, 0, 0, 0.0, 1, 0, 0, 0, 1, 0, 0.0, math.pi))
    app = one_line(be, zero)
    with pytest.raises(InputError) as err:
        analyze_and_draw(nc, EspritSource(be.host(app)), resolve_machine(None))
    assert str(err.value) == (
        "ESPRIT document part:3: operation 'Finish': item 3 is an arc with zero radius (0)"
    )
    assert recording(app, be).layers == ("Default",)


# ----------------------------------------------------------------------------- A3
def _corner_path() -> tuple[ToolPath, Annotations]:
    """Ten moves with hand-set classes; see test_one_element_per_zone."""
    moves = [  # kind, start, end, centre
        (MoveKind.LINE, (0, 0), (10, 0), None),
        (MoveKind.LINE, (10, 0), (20, 0), None),
        (MoveKind.LINE, (20, 0), (30, 0), None),
        (MoveKind.LINE, (30, 0), (30, 10), None),
        (MoveKind.ARC_CCW, (30, 10), (20, 20), (20, 10)),
        (MoveKind.ARC_CCW, (20, 20), (10, 10), (20, 10)),
        (MoveKind.ARC_CCW, (10, 10), (20, 0), (20, 10)),
        (MoveKind.RAPID, (20, 0), (50, 50), None),
        (MoveKind.LINE, (50, 50), (60, 50), None),
        (MoveKind.LINE, (60, 50), (70, 50), None),
    ]
    cols = empty_columns(len(moves))
    for i, (kind, s, e, c) in enumerate(moves):
        cols["kind"][i] = kind
        cols["start"][i, :2], cols["end"][i, :2] = s, e
        if c is not None:
            cols["center"][i] = (*c, 0.0)
            cols["normal"][i] = (0.0, 0.0, 1.0)
            cols["sweep"][i] = math.pi / 2
    cols["feed"][:] = 50.0
    cols["feed"][7] = np.nan
    tp = ToolPath(**cols)
    junction = np.array([0, 2, 5])
    ann = Annotations(
        title="corner",
        machine="m",
        move_class=np.array([0, 0, 0, 2, 2, 2, 5, -1, 1, 1], dtype=np.int8),
        junction=junction,
        junction_class=np.array([1, 4, 0], dtype=np.int8),
        junction_feed=np.array([40.0, 10.0, 49.0]),
        junction_reduction=np.array([0.2, 0.8, 0.02]),
        junction_cause=np.zeros(3, dtype=np.int64),
        junction_limit=np.zeros(3, dtype=np.int64),
        length_class=np.full(10, 2, dtype=np.int8),
        zones=(),
        indicator_names=("x",),
        indicator_counts=(3,),
        labels=("limit",),
    )
    return tp, ann


def test_one_element_per_zone(nc, be):
    """A3 draws one segment per run of collinear moves of a class, one arc per run of arcs of
    a class on one circle, one point per discontinuity of class >= 1, nothing for rapids --
    in the class colours, on the layer "ncperf performance", as one undo step."""
    tp, ann = _corner_path()
    app = be.ns.Application("blank")
    drawing = nc.display(tp, ann, be.host(app))
    assert (drawing.segments, drawing.arcs, drawing.points) == (3, 2, 2)
    rec = recording(app, be)
    assert rec.layers == ("Default", LAYER)
    assert (rec.undo_steps, rec.cancelled, rec.transaction_open) == (1, 0, False)
    green, light, pale, orange, red = 0x0050981A, 0x0060CF91, 0x008BEFD9, 0x00436DF4, 0x002730D7
    seg = sorted(rec.segments.tolist())
    assert seg == sorted(
        [
            [0, 0, 0, 30, 0, 0, green, 1],  # moves 0-2: collinear, class 0
            [30, 0, 0, 30, 10, 0, pale, 1],  # move 3: class 2, turns 90 degrees from move 2
            [50, 50, 0, 70, 50, 0, light, 1],  # moves 8-9 (after the undrawn rapid)
        ]
    )
    arcs = rec.arcs[np.argsort(rec.arcs[:, 10] - rec.arcs[:, 11])]  # longest first
    # moves 4-5: one half circle about (20, 10), class 2; move 6: a quarter, class 5.
    assert arcs[:, 12].tolist() == [pale, red]
    np.testing.assert_allclose(arcs[:, 0:4], [[20, 10, 0, 10], [20, 10, 0, 10]])
    sweep = arcs[:, 11] - arcs[:, 10]
    np.testing.assert_allclose(sweep, [math.pi, math.pi / 2])
    c, r, u, v = arcs[:, 0:3], arcs[:, 3:4], arcs[:, 4:7], arcs[:, 7:10]
    a0, a1 = arcs[:, 10:11], arcs[:, 11:12]
    np.testing.assert_allclose(
        c + r * (np.cos(a0) * u + np.sin(a0) * v), [[30, 10, 0], [10, 10, 0]], atol=1e-12
    )
    np.testing.assert_allclose(
        c + r * (np.cos(a1) * u + np.sin(a1) * v), [[10, 10, 0], [20, 0, 0]], atol=1e-12
    )
    assert sorted(rec.points.tolist()) == sorted([[10, 0, 0, light, 1], [30, 0, 0, orange, 1]])


def test_drawing_again_replaces_the_layer(nc, be):
    """A second run replaces the layer and its content: still one layer, as many elements."""
    tp, ann = _corner_path()
    app = be.ns.Application("blank")
    nc.display(tp, ann, be.host(app))
    nc.display(tp, ann, be.host(app))
    rec = recording(app, be)
    assert rec.layers == ("Default", LAYER)
    assert (len(rec.segments), len(rec.arcs), len(rec.points), rec.undo_steps) == (3, 2, 2, 2)


def test_refused_element_cancels_the_whole_drawing(nc, be):
    """When ESPRIT refuses an element (a zero-radius arc) after others were drawn, the undo
    transaction is closed with cancel: no layer, no element left, a message naming the item."""
    cols = empty_columns(3)
    cols["start"][:, 0] = [0.0, 10.0, 20.0]
    cols["end"][:, 0] = [10.0, 20.0, 20.0]
    cols["end"][1, 1] = 5.0
    cols["start"][2, 1] = cols["end"][2, 1] = 5.0
    cols["kind"][2] = MoveKind.ARC_CCW
    cols["center"][2] = (20.0, 5.0, 0.0)
    cols["normal"][2] = (0.0, 0.0, 1.0)
    cols["sweep"][2] = math.pi
    cols["feed"][:] = 50.0
    tp = ToolPath(**cols, op_names=("Finish",))
    ann = Annotations(
        "t", "m", np.zeros(3, np.int8), np.zeros(0, np.int64), np.zeros(0, np.int8), np.zeros(0),
        np.zeros(0), np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(3, np.int8), (), (),
        (), (),
    )  # fmt: skip
    app = be.ns.Application("part")
    with pytest.raises(EspritError) as err:
        nc.display(tp, ann, be.host(app))
    assert str(err.value) == (
        "ESPRIT document part: ESPRIT refused the arc of operation 'Finish', item 3: "
        "arc radius must be positive, got 0; the drawing was cancelled"
    )
    rec = recording(app, be)
    assert rec.layers == ("Default",)
    assert (len(rec.segments), len(rec.arcs), len(rec.points)) == (0, 0, 0)
    assert (rec.undo_steps, rec.cancelled, rec.transaction_open) == (0, 1, False)


# ----------------------------------------------------------------------------- entry points
def test_addin_entry_point(be):
    """The add-in entry point analyses the document it is given, draws, returns the summary."""
    app = fill_document(program(), be)
    text = addin_run(be.host(app), machine="siemens-840d")
    assert "ncperf analyze: ESPRIT document rt.ngc" in text
    assert f"esprit           layer '{LAYER}' of ESPRIT document rt.ngc" in text
    assert recording(app, be).undo_steps == 1


def test_late_binding_reports_missing_members(dotnet):
    """Through late binding a member the object lacks is an AttributeError (as for COM)."""
    if isinstance(dotnet, DotnetUnavailable):
        pytest.skip(f".NET ESPRIT emulation unavailable: {dotnet.reason}")
    doc = LateBound(dotnet.Application("x")).Document
    assert doc.Name == "x"
    with pytest.raises(AttributeError, match="has no member NoSuchThing"):
        doc.NoSuchThing  # noqa: B018


def test_missing_dll_says_how_to_build_it(monkeypatch, tmp_path):
    """Without the compiled emulation the reason names the set-up script."""
    monkeypatch.setenv("NCPERF_ESPRIT_EMULATION_DLL", str(tmp_path / "none.dll"))
    with pytest.raises(DotnetUnavailable, match=r"not built .*none\.dll.*setup_esprit_emulation"):
        load_emulation.__wrapped__()


# ----------------------------------------------------------------------------- ncperf esprit
@pytest.mark.parametrize("twin", [True, False], ids=["python-twin", "dotnet"])
def test_cli_emulate_draws_and_renders(capsys, tmp_path, dotnet, twin):
    """`ncperf esprit --emulate PROGRAM --svg OUT` runs A1-A3 on the emulation, prints the
    summary and the drawing, and renders what was drawn."""
    if not twin and isinstance(dotnet, DotnetUnavailable):
        pytest.skip(f".NET ESPRIT emulation unavailable: {dotnet.reason}")
    src = tmp_path / "rt.ngc"
    src.write_bytes(ROUND_TRIP)
    out = tmp_path / "esprit.svg"
    argv = ["esprit", "--emulate", str(src), "--svg", str(out)] + (
        ["--python-twin"] if twin else []
    )
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "ncperf analyze: ESPRIT document rt.ngc" in text
    assert f"esprit           layer '{LAYER}'" in text
    root = ET.fromstring(out.read_text())
    strokes = {p.get("stroke") for p in root.iter("{http://www.w3.org/2000/svg}path")}
    assert strokes and strokes <= set(REDUCTION_COLOURS)


@pytest.mark.skipif(sys.platform == "win32", reason="on Windows ncperf esprit tries COM")
def test_cli_without_esprit_exits_2(capsys):
    """Without ESPRIT (not Windows) `ncperf esprit` exits 2 with one line saying why."""
    assert main(["esprit"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(
        "ncperf: ESPRIT could not be reached: ESPRIT runs on Windows"
    )


def test_cli_svg_needs_emulate(capsys):
    """--svg without --emulate is a usage error."""
    assert main(["esprit", "--svg", "x.svg"]) == 2
    assert "need --emulate PROGRAM" in capsys.readouterr().err


@pytest.mark.skipif(shutil.which("mcs") is None, reason="Mono's mcs is not installed")
def test_setup_script_is_idempotent():
    """Run again with the DLL up to date, the set-up script does nothing and says nothing."""
    script = ROOT / "scripts" / "setup_esprit_emulation.sh"
    subprocess.run(["bash", str(script)], check=True, capture_output=True)
    dll = ROOT / "adapters" / "esprit_com" / "build" / "EspritEmulation.dll"
    before = dll.stat().st_mtime_ns
    out = subprocess.run(["bash", str(script)], check=True, capture_output=True, text=True)
    assert (out.stdout, out.stderr) == ("", "")
    assert dll.stat().st_mtime_ns == before


def test_twin_enums_are_the_object_model_tables():
    """The Python twin's enums (spelled out for the type checker) hold exactly the names and
    values of object_model's tables, so the two cannot drift apart."""
    from adapters.esprit_com import object_model as om
    from adapters.esprit_com import twin

    for enum, table in (
        (twin.espToolPathItemType, om.ITEM_TYPES),
        (twin.espGraphicObjectType, om.GRAPHIC_OBJECT_TYPES),
        (twin.espUnitType, om.UNIT_TYPES),
    ):
        assert {m.name: int(m.value) for m in enum} == dict(table)
