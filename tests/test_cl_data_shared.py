"""The CL data adapter on the real NX and SolidWorks CAM files in ../shared (skipped where
that folder is absent)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from adapters.cl_data import read_cl
from core import InputError, MoveKind, load_preset
from core.model import geometry as g
from tests.conftest import shared

READABLE = [
    "nx-clsf/_10_KONTUR_125_N2_162.cls",
    "nx-clsf/_3_PAZ_125_N2.cls",
    "nx-clsf/ust_a2.cls",
    "solidworks-cam/boss.apt",
    "solidworks-cam/basemach.apt",
    "solidworks-cam/wall-holes.apt",
]
# Files with records ncperf refuses, and the first such record (found in the test).
REFUSED = {
    "nx-clsf/nurbs.clsf": ("NURBS/", "NURBS/ spline motion is not supported"),
}
#: SolidWorks CAM files with drilling cycles (CYCLE/ ... CYCLE/OFF around GOTO points).
WITH_CYCLES = ["solidworks-cam/basemach.apt", "solidworks-cam/wall-holes.apt"]
WITH_ARCS = [
    "nx-clsf/_10_KONTUR_125_N2_162.cls",
    "nx-clsf/_3_PAZ_125_N2.cls",
    "solidworks-cam/boss.apt",
]
#: The files write 4 decimals (NX) or 6 (SolidWorks): end points sit within 1e-4 mm of their
#: circle; ten times that is rounding, more would be a misread arc.
ROUNDING = 1e-3


def load(rel: str):
    p = shared("data", "apt", *rel.split("/"))
    return p, read_cl(p.read_bytes(), str(p))


def lines_of(p) -> list[str]:
    return p.read_text(encoding="latin-1").splitlines()


def test_every_shared_file_is_covered():
    """Each CL file in ../shared/data/apt is either read or refused by a test here."""
    folder = shared("data", "apt")
    found = {str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file()}
    assert found == set(READABLE) | set(REFUSED)


@pytest.mark.parametrize("rel", READABLE, ids=[r.split("/")[-1] for r in READABLE])
def test_real_files_read_into_chained_moves(rel):
    """Real NX and SolidWorks CAM files read into finite moves that chain (each starts where
    the previous ended), with positive lengths and feeds."""
    p, tp = load(rel)
    assert tp.n > 0 and tp.source == str(p)
    assert np.isfinite(tp.start).all() and np.isfinite(tp.end).all()
    assert np.array_equal(tp.start[1:], tp.end[:-1])
    assert (tp.length > 0).all()
    assert (tp.feed[tp.is_feed] > 0).all() and np.isnan(tp.feed[~tp.is_feed]).all()


@pytest.mark.parametrize("rel", sorted(REFUSED), ids=[r.split("/")[-1] for r in sorted(REFUSED)])
def test_refused_files_name_the_first_record_ncperf_cannot_read(rel):
    """nurbs.clsf (NURBS/ splines) is refused with the line of the first such record."""
    p = shared("data", "apt", *rel.split("/"))
    word, message = REFUSED[rel]
    first = next(k for k, t in enumerate(lines_of(p), 1) if t.lstrip().startswith(word))
    with pytest.raises(InputError) as info:
        read_cl(p.read_bytes(), str(p))
    assert str(info.value).startswith(f"{p}:{first}: {message}")


@pytest.mark.parametrize("rel", WITH_CYCLES, ids=[r.split("/")[-1] for r in WITH_CYCLES])
def test_every_hole_of_a_cycle_is_drilled_to_its_depth(rel):
    """At every GOTO between CYCLE/<kind> (FEDTO d, RTRCTO r) and CYCLE/OFF a feed move ends
    d below the point along the tool axis (the GOTO's i,j,k: wall-holes drills sideways)
    and the hole's last move is a rapid to r above it (the records read here by splitting
    their text, not with ncperf)."""
    p, tp = load(rel)
    holes = []
    depth = retract = None
    for k, t in enumerate(lines_of(p), 1):
        if t.startswith("CYCLE/OFF"):
            depth = None
        elif t.startswith("CYCLE/") and "FEDTO" in t:
            words = t[6:].split(",")
            depth = float(words[words.index("FEDTO") + 1])
            retract = float(words[words.index("RTRCTO") + 1])
        elif t.startswith("GOTO/") and depth is not None:
            v = [float(s) for s in t[5:].split(",")]
            axis = np.array(v[3:6]) if len(v) == 6 else np.array([0.0, 0.0, 1.0])
            holes.append((k, np.array(v[:3]), axis, depth, retract))
    assert len(holes) >= 6
    for line, top, axis, d, r in holes:
        own = np.flatnonzero(tp.line == line)
        assert own.size >= 3, line
        bottom = tp.end[own][tp.kind[own] == MoveKind.LINE]
        assert np.allclose(bottom[-1], top - axis * d, atol=1e-9), line
        assert tp.kind[own[-1]] == MoveKind.RAPID
        assert np.allclose(tp.end[own[-1]], top + axis * r, atol=1e-9), line


def _circle_records(p) -> dict[int, tuple[np.ndarray, np.ndarray, float | None]]:
    """CIRCLE records by 1-based line: centre, unit axis, radius (None without)."""
    out = {}
    for k, t in enumerate(lines_of(p), 1):
        if t.startswith("CIRCLE/"):
            vals = [float(v) for v in t[7:].split(",") if re.fullmatch(r"[-+.\d]+", v)]
            axis = np.array(vals[3:6]) / np.linalg.norm(vals[3:6])
            out[k] = (np.array(vals[:3]), axis, vals[6] if len(vals) > 6 else None)
    return out


@pytest.mark.parametrize("rel", WITH_ARCS, ids=[r.split("/")[-1] for r in WITH_ARCS])
def test_arcs_follow_their_circle_records_and_end_on_them(rel):
    """Every CIRCLE record is one arc, ending at the next GOTO: its axis is the record's,
    its centre lies on the record's axis line, and start and end are at the record's radius
    (the start's distance where the record has none, as SolidWorks writes it)."""
    p, tp = load(rel)
    circles = _circle_records(p)
    arcs = np.flatnonzero(tp.is_arc)
    assert arcs.size == len(circles)
    owner = np.array(sorted(circles))
    for i in arcs:
        k = int(owner[np.searchsorted(owner, tp.line[i]) - 1])  # the CIRCLE before the GOTO
        assert k < tp.line[i]
        centre, axis, radius = circles[k]
        assert np.allclose(tp.normal[i], axis, atol=1e-9)
        off_axis = np.cross(tp.center[i] - centre, axis)
        assert np.linalg.norm(off_axis) < ROUNDING
        r0 = np.linalg.norm(g.radial(tp.start[i : i + 1], tp.center[i : i + 1], axis[None]))
        r1 = np.linalg.norm(g.radial(tp.end[i : i + 1], tp.center[i : i + 1], axis[None]))
        assert abs(r1 - r0) < ROUNDING
        if radius is not None:
            assert abs(r0 - radius) < ROUNDING


@pytest.mark.parametrize(
    "rel,tangent_at_least,reversed_at_most",
    [
        ("nx-clsf/_3_PAZ_125_N2.cls", 280, 0),
        ("solidworks-cam/boss.apt", 1150, 2),
    ],
    ids=["NX clockwise", "SolidWorks counter-clockwise"],
)
def test_arc_direction_conventions_continue_the_path(rel, tangent_at_least, reversed_at_most):
    """Read with their CAM system's convention (NX: clockwise about the CIRCLE axis; SolidWorks
    and APT: counter-clockwise), arcs continue their neighbouring GOTO lines tangentially and
    (almost) never reverse against them, and no direction warning is given."""
    _, tp = load(rel)
    arcs = np.flatnonzero(tp.is_arc)
    line = tp.kind == MoveKind.LINE
    tangent = reversed_ = 0
    for nb, mine, other in (
        (arcs - 1, tp.tangent_start[arcs], tp.tangent_end),
        (arcs + 1, tp.tangent_end[arcs], tp.tangent_start),
    ):
        ok = (nb >= 0) & (nb < tp.n)
        nbc = np.clip(nb, 0, tp.n - 1)
        ok &= line[nbc]
        cos = np.einsum("ij,ij->i", mine[ok], other[nbc[ok]])
        tangent += int(np.sum(cos > 0.99999))
        reversed_ += int(np.sum(cos < -0.99999))
    assert tangent >= tangent_at_least and reversed_ <= reversed_at_most
    assert "may turn the other way" not in "\n".join(str(n) for n in tp.notices)


def test_nx_circle_in_four_arcs_is_one_turn():
    """_10_KONTUR: four CIRCLE records on the circle about (1287.5, -293) run once around it
    (60 + 120 + 120 + 60 degrees), back to where they started, read clockwise about (0,0,-1)."""
    _, tp = load("nx-clsf/_10_KONTUR_125_N2_162.cls")
    on = tp.is_arc & np.all(np.isclose(tp.center[:, :2], [1287.5, -293.0]), axis=1)
    assert on.sum() == 4
    assert np.degrees(tp.sweep[on]).sum() == pytest.approx(360.0, abs=0.02)
    assert np.allclose(np.degrees(tp.sweep[on]), [60, 120, 120, 60], atol=0.02)
    assert set(tp.kind[on]) == {MoveKind.ARC_CW}


def test_nx_feed_rapids_and_operation():
    """_3_PAZ: one TOOL PATH, FEDRAT/MMPM,530 on every feed move, one rapid per RAPID record."""
    p, tp = load("nx-clsf/_3_PAZ_125_N2.cls")
    text = lines_of(p)
    assert tp.op_names == (text[0].split("/")[1].split(",")[0],)
    assert np.allclose(tp.feed[tp.is_feed], 530.0 / 60.0)
    assert (tp.kind == MoveKind.RAPID).sum() == sum(t.strip() == "RAPID" for t in text)


def test_nx_five_axis_tool_axis():
    """ust_a2.cls: the i,j,k of the 6-value GOTO records (carried forward over the 3-value
    ones) is the tool axis of every move, of unit length, and the change is reported."""
    p, tp = load("nx-clsf/ust_a2.cls")
    assert tp.tool_axis is not None and tp.tool_axis.shape == (tp.n, 3)
    assert np.allclose(np.linalg.norm(tp.tool_axis, axis=1), 1.0, atol=1e-12)
    expected, current = {}, None
    for k, t in enumerate(lines_of(p), 1):
        if t.startswith("GOTO/"):
            v = [float(x) for x in t[5:].split(",")]
            if len(v) == 6:
                current = np.array(v[3:]) / np.linalg.norm(v[3:])
                assert abs(np.linalg.norm(v[3:]) - 1.0) < 1e-6  # the file's own axes are unit
            expected[k] = current
    want = np.array([expected[int(ln)] for ln in tp.line])
    assert np.allclose(tp.tool_axis, want, atol=1e-12)
    assert len({tuple(np.round(a, 6)) for a in want}) > 100
    assert "the tool axis changes" in "\n".join(str(n) for n in tp.notices)


def test_solidworks_tools_feeds_and_notices():
    """boss.apt: an operation per LOAD/TOOL (tools 1 and 5, twice each), the feeds of its
    FEDRAT records in mm/min, and notices for CUTCOM and its private CSI_ words."""
    p, tp = load("solidworks-cam/boss.apt")
    text = lines_of(p)
    loads = [int(t.split(",")[1]) for t in text if t.startswith("LOAD/TOOL")]
    assert loads == [1, 5, 1, 5]
    assert [int(tp.tool[i]) for i in tp.op_offsets[:-1]] == loads
    fedrat = {float(t[7:].split(",")[0]) for t in text if t.startswith("FEDRAT/")}
    assert set(np.round(tp.feed[tp.is_feed] * 60, 6)) <= {round(f, 6) for f in fedrat}
    notes = "\n".join(str(n) for n in tp.notices)
    assert "CUTCOM/LEFT" in notes and "CSI_SET_FLUTE_LENGTH" in notes


@pytest.mark.parametrize("rel", READABLE, ids=[r.split("/")[-1] for r in READABLE])
def test_real_files_through_the_facade(nc, rel):
    """nc.extract reads the real files with the default plugins, and the models predict
    feeds no higher than programmed."""
    p = shared("data", "apt", *rel.split("/"))
    tp = nc.extract(str(p))
    ev = nc.evaluate(tp, load_preset("siemens-840d"))
    feed = tp.is_feed
    assert (ev.element_feed[feed] <= tp.feed[feed] * (1 + 1e-12)).all()
    assert (ev.junction_feed <= ev.junction_programmed * (1 + 1e-12)).all()
