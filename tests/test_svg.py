"""The SVG fallback display (A3): adapters/svg."""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import adapters.svg
from adapters.svg import render
from core import (
    FileTarget,
    Indicator,
    Ncperf,
    NcperfError,
    ToolPath,
    build_annotations,
    hookimpl,
    load_preset,
    make_plugin_manager,
)
from core.model import geometry as g
from core.model.toolpath import MoveKind, empty_columns, polyline
from core.view.targets import VIEWS

PLUGINS = (
    "plugins.tangential",
    "plugins.curvature",
    "plugins.ncu_capacity",
    "plugins.exact_stop",
    "adapters.svg",
)
NS = "{http://www.w3.org/2000/svg}"

# The 840D preset (core/model/presets/siemens-840d.toml), in mm and s.
T_INT = 0.012  # s
TIT = 0.01  # mm
JERK = 5.0 * 1000.0  # mm/s^3
COLOURS = ("#1a9850", "#91cf60", "#d9ef8b", "#fdae61", "#f46d43", "#d73027")
LENGTH_COLOURS = ("#d73027", "#fdae61", "#1a9850")
RAPID = "#9e9e9e"


def draw(tp: ToolPath, target: object, *, extra: tuple = ()) -> ET.Element:
    """Evaluate ``tp`` with a fresh plugin manager, display it on ``target``, parse it."""
    nc = Ncperf(make_plugin_manager(builtins=PLUGINS, entry_points=False, extra=extra))
    ann = build_annotations(nc.evaluate(tp, load_preset("siemens-840d")))
    out = nc.display(tp, ann, target)
    path = target.path if isinstance(target, FileTarget) else target
    assert out == os.fspath(path)
    return ET.parse(out).getroot()


def panels(root: ET.Element) -> list[ET.Element]:
    """The two panel groups (left: reduction, right: block length)."""
    found = [
        el for el in root.iter(f"{NS}g") if (el.get("transform") or "").startswith("translate(")
    ]
    assert len(found) == 2
    return found


def titled(root: ET.Element, tag: str, attr: str, colour: str) -> list[str]:
    """Titles of the ``tag`` elements drawn in a group whose ``attr`` is ``colour``."""
    out = []
    for grp in root.iter(f"{NS}g"):
        if grp.get(attr) == colour:
            out += [el.findtext(f"{NS}title") for el in grp.iter(f"{NS}{tag}")]
    return out


def points(el: ET.Element) -> np.ndarray:
    """(m, 2) int points of a <polyline> (0.1 px)."""
    return np.array([p.split(",") for p in el.get("points").split()], dtype=np.int64)


def all_text(root: ET.Element) -> str:
    return " ".join(root.itertext())


# ------------------------------------------------------------------ recognition
@pytest.mark.parametrize(
    "target",
    ["out.png", "out.svg.txt", Path("plot.pdf"), FileTarget("out.html"), 42, None, b"out.svg"],
    ids=["png", "svg-txt", "pathlike-pdf", "filetarget-html", "int", "none", "bytes"],
)
def test_other_targets_return_none(tmp_path, monkeypatch, target):
    """The hook returns None (and writes nothing) for anything but an .svg target."""
    tp = polyline([[0, 0, 0], [10, 0, 0]], 100.0)
    nc = Ncperf(make_plugin_manager(builtins=PLUGINS, entry_points=False))
    ann = build_annotations(nc.evaluate(tp, load_preset("siemens-840d")))
    monkeypatch.chdir(tmp_path)
    assert adapters.svg.ncperf_display(toolpath=tp, annotations=ann, target=target) is None
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "make",
    [lambda p: str(p / "a.svg"), lambda p: p / "b.SVG", lambda p: FileTarget(str(p / "c.Svg"))],
    ids=["str", "pathlike-upper", "filetarget-mixed-case"],
)
def test_svg_targets_are_written_and_returned_as_str(tmp_path, make):
    """str, os.PathLike and FileTarget names ending in .svg (any case) are drawn, path returned."""
    target = make(tmp_path)
    root = draw(polyline([[0, 0, 0], [10, 0, 0]], 100.0), target)
    assert root.tag == f"{NS}svg"


# ------------------------------------------------------------------ classes and colours
def test_sharp_corner_is_a_class_5_marker(tmp_path):
    """A 90 deg corner of 10 mm lines at 6 m/min (840D) is a > 90 % marker naming its lines."""
    # Eq. (1): R = min(TIT cos(b/2) / (1 - cos(b/2)), l / (2 sin(b/2)) - TIT);
    # eq. (6): V = cbrt(J R^2), the X jerk binding (t sweeps from X to Y: X's share peaks at 1).
    b = math.pi / 2
    radius = min(TIT * math.cos(b / 2) / (1 - math.cos(b / 2)), 10 / (2 * math.sin(b / 2)) - TIT)
    v = (JERK * radius**2) ** (1 / 3)
    assert 1.40 < v < 1.45  # mm/s: 98.6 % below 100 mm/s
    root = draw(
        polyline([[0, 0, 0], [10, 0, 0], [10, 10, 0]], 100.0),
        FileTarget(tmp_path / "c.svg", colour="paper"),
    )
    red = titled(root, "circle", "fill", COLOURS[5])
    assert red == [
        f"line 1/2: -{round(100 * (1 - v / 100))} % (tangential: jerk X), {round(v * 60)} mm/min"
    ]
    for cls in range(1, 5):
        assert titled(root, "circle", "fill", COLOURS[cls]) == []
    # Both 10 mm blocks run at the programmed feed (0-10 %) and are longer than 2 L = 2.4 mm.
    left, right = panels(root)
    assert titled(left, "polyline", "stroke", COLOURS[0]) == ["lines 1-2: reduction 0-10 %"]
    assert titled(right, "polyline", "stroke", LENGTH_COLOURS[2]) == [
        "lines 1-2: block 2 L and longer"
    ]
    assert f'fill="{COLOURS[5]}"' in (tmp_path / "c.svg").read_text()


def test_short_block_is_capped(tmp_path):
    """A 0.9 mm block at 10 m/min (L = 2 mm) runs at 0.9 / t_int: -55 % (class 3), below L."""
    feed = 10000 / 60
    assert 1 - (0.9 / T_INT) / feed == pytest.approx(0.55)
    tp = polyline([[0, 0, 0], [10, 0, 0], [10.9, 0, 0], [20.9, 0, 0]], feed)
    root = draw(tp, FileTarget(tmp_path / "s.svg", colour="paper"))
    left, right = panels(root)
    assert titled(left, "polyline", "stroke", COLOURS[3]) == ["line 2: reduction 50-70 %"]
    assert titled(left, "polyline", "stroke", COLOURS[0]) == [
        "line 1: reduction 0-10 %",
        "line 3: reduction 0-10 %",
    ]
    assert titled(right, "polyline", "stroke", LENGTH_COLOURS[0]) == [
        "line 2: block shorter than L (feed capped)"
    ]
    # Collinear blocks: no discontinuity marker at all.
    assert [
        c
        for c in root.iter(f"{NS}circle")
        if c.find(f"{NS}title") is not None and c.findtext(f"{NS}title").startswith("line ")
    ] == []


def test_gentle_corner_has_no_marker(tmp_path):
    """Junctions slowed by less than 10 % (class 0) get no marker."""
    a = math.radians(1.0)
    tp = polyline([[0, 0, 0], [10, 0, 0], [10 + 10 * math.cos(a), 10 * math.sin(a), 0]], 100.0)
    root = draw(tp, str(tmp_path / "g.svg"))
    assert [c for c in root.iter(f"{NS}circle") if c.find(f"{NS}title") is not None] == []


def test_titles_name_program_lines(tmp_path):
    """Consecutive moves of one class form one polyline whose title gives their line range."""
    cols = empty_columns(5)
    p = np.array([[10.0 * i, 0, 0] for i in range(6)])
    cols["start"], cols["end"] = p[:-1], p[1:]
    cols["feed"][:] = 100.0
    cols["line"] = np.array([120, 130, 140, 150, 245])
    root = draw(ToolPath(**cols), FileTarget(tmp_path / "t.svg", colour="paper"))
    left, right = panels(root)
    lines = left.findall(f".//{NS}polyline")
    assert [el.findtext(f"{NS}title") for el in lines] == ["lines 120-245: reduction 0-10 %"]
    assert len(right.findall(f".//{NS}polyline")) == 1


def test_rapids_are_dashed_grey_and_break_runs(tmp_path):
    """Rapids are drawn dashed in the rapid colour, apart from the feed moves around them."""
    cols = empty_columns(3)
    p = np.array([[0, 0, 5], [0, 0, 0], [10, 0, 0], [20, 5, 5.0]])
    cols["start"], cols["end"] = p[:-1], p[1:]
    cols["kind"][[0, 2]] = MoveKind.RAPID
    cols["feed"][1] = 100.0
    root = draw(ToolPath(**cols), str(tmp_path / "r.svg"))
    for panel in panels(root):
        grp = [el for el in panel.iter(f"{NS}g") if el.get("stroke") == RAPID]
        assert len(grp) == 1 and grp[0].get("stroke-dasharray")
        assert sorted(el.findtext(f"{NS}title") for el in grp[0].iter(f"{NS}polyline")) == [
            "line 1: rapid",
            "line 3: rapid",
        ]


class ThirdParty:
    """A plugin from outside the project: caps block 1 at half the programmed feed."""

    @hookimpl
    def ncperf_evaluate(self, toolpath):
        return [
            Indicator(
                name="spindle_probe",
                at="element",
                index=np.array([1]),
                feed=toolpath.feed[[1]] / 2,
                limit=np.array([0]),
                labels=("probe limit",),
            )
        ]


def test_legend_lists_indicators_with_counts(tmp_path):
    """The legend names every indicator that ran, a third-party one included, with its count."""
    tp = polyline([[0, 0, 0], [10, 0, 0], [20, 0, 0], [30, 0, 0]], 100.0)
    root = draw(tp, str(tmp_path / "l.svg"), extra=(ThirdParty(),))
    text = all_text(root)
    assert "spindle_probe 1" in text
    for name in ("tangential", "curvature", "ncu_capacity", "exact_stop"):
        assert name in text
    for label in ("0-10 %", "> 90 %", "shorter than L (feed capped)", "rapid"):
        assert label in text
    assert "10 %" in text and "only" in text  # markers drawn only from 10 % on
    assert "<polyline>" in text and "MIKRON" in text  # program and machine in the title


def test_zone_is_numbered_with_tooltip(tmp_path):
    """The worst zone gets its rank as label and a tooltip with lines, reduction, feed and cause."""
    root = draw(polyline([[0, 0, 0], [10, 0, 0], [10, 10, 0]], 100.0), str(tmp_path / "z.svg"))
    b = math.pi / 2
    radius = TIT * math.cos(b / 2) / (1 - math.cos(b / 2))
    v = (JERK * radius**2) ** (1 / 3)
    want = (
        f"zone 1: lines 1-2, worst -{round(100 * (1 - v / 100))} %, "
        f"min feed {v * 60:.0f} mm/min (tangential: jerk X)"
    )
    groups = [el for el in root.iter(f"{NS}g") if el.findtext(f"{NS}title") == want]
    assert len(groups) == 1 and groups[0].findtext(f"{NS}text") == "1"


# ------------------------------------------------------------------ geometry
AXIS_CASES = [  # view, direction of the move, expected sign of (dx, dy) on screen
    ("xy", (1, 0, 0), (1, 0)),
    ("xy", (0, 1, 0), (0, -1)),
    ("xz", (1, 0, 0), (1, 0)),
    ("xz", (0, 0, 1), (0, -1)),
    ("yz", (0, 1, 0), (1, 0)),
    ("yz", (0, 0, 1), (0, -1)),
    ("iso", (1, 0, 0), (1, -1)),
    ("iso", (0, 1, 0), (-1, -1)),
    ("iso", (0, 0, 1), (0, -1)),
]


@pytest.mark.parametrize(
    "view,axis,sign", AXIS_CASES, ids=[f"{v}-{'xyz'[a.index(1)]}" for v, a, _ in AXIS_CASES]
)
def test_views_orient_axes(tmp_path, view, axis, sign):
    """Each view draws its first axis to the right and its second up (SVG y flipped)."""
    tp = polyline([[0, 0, 0], [10 * a for a in axis]], 100.0)
    root = draw(tp, FileTarget(str(tmp_path / f"{view}.svg"), view))
    assert render.VIEW_NAMES[view] in root.findtext(f"{NS}title")
    pts = points(panels(root)[0].find(f".//{NS}polyline"))
    assert tuple(np.sign(pts[-1] - pts[0])) == sign


@pytest.mark.parametrize("view", VIEWS)
def test_unseen_axis_is_a_dot(tmp_path, view):
    """A move along the viewing direction (zero extent) is drawn as a zero-length polyline."""
    hidden = {"xy": (0, 0, 1), "xz": (0, 1, 0), "yz": (1, 0, 0), "iso": (1, 1, -1)}[view]
    tp = polyline([[0, 0, 0], [10 * a for a in hidden]], 100.0)
    root = draw(tp, FileTarget(str(tmp_path / f"{view}.svg"), view))
    pts = points(panels(root)[0].find(f".//{NS}polyline"))
    assert np.all(pts == pts[0])


def arc_path(kind: int) -> ToolPath:
    """A 10 mm line, then a quarter arc of radius 10 about the origin from (10, 0) to (0, 10)."""
    cols = empty_columns(2)
    cols["start"] = np.array([[10.0, -10, 0], [10, 0, 0]])
    cols["end"] = np.array([[10.0, 0, 0], [0, 10, 0]])
    cols["feed"][:] = 100.0
    cols["kind"][1] = kind
    cols["center"][1] = (0, 0, 0)
    cols["normal"][1] = (0, 0, 1)
    ccw = kind == MoveKind.ARC_CCW
    cols["sweep"][1] = g.arc_sweep(
        cols["start"][1:], cols["end"][1:], cols["center"][1:], cols["normal"][1:], [ccw]
    )[0]
    return ToolPath(**cols)


@pytest.mark.parametrize("kind", [MoveKind.ARC_CCW, MoveKind.ARC_CW], ids=["ccw", "cw"])
def test_arcs_are_curves(tmp_path, kind):
    """Arcs are sampled into many points on the circle, on the side their direction says."""
    tp = arc_path(kind)
    root = draw(tp, FileTarget(tmp_path / "a.svg", colour="paper"))
    pts = np.concatenate([points(el) for el in panels(root)[0].iter(f"{NS}polyline")])
    # Screen positions of the line's start (10, -10) and the centre (0, 0) fix the scale.
    p_line = pts[0].astype(float)
    corner = next(p for p in pts if p[1] < p_line[1] and p[0] == p_line[0]).astype(float)
    scale = (p_line[1] - corner[1]) / 10.0  # units per mm, the line being 10 mm long
    centre = corner - np.array([10.0 * scale, 0.0])
    on_arc = pts[np.abs(np.hypot(*(pts - centre).T) - 10 * scale) < 2]
    ccw = kind == MoveKind.ARC_CCW
    # ccw: a quarter turn through (7.07, 7.07); cw: three quarters through (-10, 0) and (0, -10).
    assert len(on_arc) >= (8 if ccw else 20)
    angles = np.degrees(np.arctan2(-(on_arc[:, 1] - centre[1]), on_arc[:, 0] - centre[0]))
    if ccw:
        assert angles.min() > -1 and angles.max() < 91
    else:
        assert angles.min() < -170 or angles.max() > 170
        assert not np.any((angles > 5) & (angles < 85))  # not the short way round


def test_arc_segments_bound_chord_error():
    """Segment counts keep the sagitta below CHORD_PX, between 2 and 64 per arc."""
    r = np.array([0.0, 1.0, 100.0, 1e6, np.nan])
    sweep = np.array([1.0, 1.0, math.pi / 2, 2 * math.pi, 1.0])
    n = render.arc_segments(r, sweep)
    assert n.tolist()[0] == 2 and n.tolist()[-1] == 2 and n.tolist()[3] == 64
    sag = r[2] * (1 - math.cos(sweep[2] / n[2] / 2))
    assert sag <= render.CHORD_PX
    assert r[2] * (1 - math.cos(sweep[2] / (n[2] - 1) / 2)) > render.CHORD_PX  # not one too many


# ------------------------------------------------------------------ edge cases
def rapids_only() -> ToolPath:
    cols = empty_columns(2)
    cols["kind"][:] = MoveKind.RAPID
    cols["start"] = np.array([[0.0, 0, 0], [5, 0, 0]])
    cols["end"] = np.array([[5.0, 0, 0], [5, 5, 5]])
    return ToolPath(**cols)


EDGE = {
    "empty": lambda: ToolPath(**empty_columns(0)),
    "rapids-only": rapids_only,
    "single-move": lambda: polyline([[1, 2, 3], [4, 6, 3]], 50.0),
    "vertical-in-xy": lambda: polyline([[0, 0, 0], [0, 0, 10], [0, 0, 20]], 50.0),
    "zero-length": lambda: polyline([[1, 1, 1], [1, 1, 1]], 50.0),
    "horizontal": lambda: polyline([[0, 0, 0], [10, 0, 0]], 50.0),
}


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("name", list(EDGE))
def test_degenerate_paths(tmp_path, name):
    """No moves, rapids only, one move, zero extent: valid SVG, every move drawn, no warning."""
    tp = EDGE[name]()
    root = draw(tp, str(tmp_path / "e.svg"))
    for panel in panels(root):
        assert len(panel.findall(f".//{NS}polyline")) == (1 if tp.n else 0)
    assert all(np.isfinite(float(x)) for x in root.get("viewBox").split())


def test_annotations_must_fit_the_toolpath(tmp_path):
    """Annotations of another tool path are refused with the array and shapes named."""
    nc = Ncperf(make_plugin_manager(builtins=PLUGINS, entry_points=False))
    short = polyline([[0, 0, 0], [1, 0, 0]], 100.0)
    ann = build_annotations(nc.evaluate(short, load_preset("siemens-840d")))
    tp = polyline([[0, 0, 0], [1, 0, 0], [2, 0, 0]], 100.0)
    with pytest.raises(ValueError, match=r"move_class must have shape \(2,\).*got \(1,\)"):
        nc.display(tp, ann, str(tmp_path / "x.svg"))
    assert list(tmp_path.iterdir()) == []


def test_non_finite_points_are_refused(tmp_path):
    """A move with a NaN end point is refused with its source line, before anything is written."""
    tp = polyline([[0, 0, 0], [1, 0, 0], [np.nan, 0, 0]], 100.0, source="p.nc")
    nc = Ncperf(make_plugin_manager(builtins=PLUGINS, entry_points=False))
    ann = build_annotations(nc.evaluate(tp, load_preset("siemens-840d")))
    with pytest.raises(ValueError, match=r"p\.nc:2: move 1 has a non-finite end point"):
        nc.display(tp, ann, str(tmp_path / "x.svg"))
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------ output safety
def test_missing_folder_raises_and_leaves_nothing(tmp_path):
    """A target in a missing folder raises an NcperfError naming it, and nothing is created."""
    target = tmp_path / "no" / "such" / "out.svg"
    with pytest.raises(NcperfError, match="out.svg"):
        draw(polyline([[0, 0, 0], [10, 0, 0]], 100.0), str(target))
    assert list(tmp_path.iterdir()) == []


def test_failed_write_keeps_the_old_file(tmp_path, monkeypatch):
    """A failure while writing leaves the previous file intact and no temporary file behind."""
    target = tmp_path / "out.svg"
    target.write_text("old")
    monkeypatch.setattr(render, "render_svg", lambda *a, **k: "not bytes")  # write() raises
    with pytest.raises(TypeError):
        draw(polyline([[0, 0, 0], [10, 0, 0]], 100.0), str(target))
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.svg"]


# ------------------------------------------------------------------ size
def spiral(n: int, seg: np.ndarray, feed: float) -> ToolPath:
    """An Archimedean spiral (0.5 mm step-over) of ``n`` lines of lengths ``seg``."""
    s = np.concatenate([[0.0], np.cumsum(seg)])
    b = 0.5 / (2 * np.pi)
    theta = (-5.0 + np.sqrt(25.0 + 2 * b * s)) / b
    r = 5.0 + b * theta
    p = np.column_stack([r * np.cos(theta), r * np.sin(theta), np.zeros_like(r)])
    cols = empty_columns(n)
    cols["start"], cols["end"] = p[:-1], p[1:]
    cols["feed"][:] = feed
    return ToolPath(**cols)


def test_alternating_classes_stay_small(tmp_path):
    """200,000 moves whose class alternates every move give a file of a few MB with both colours."""
    n = 200_000
    # At 1.5 m/min, L = 25 mm/s * 12 ms = 0.3 mm: 0.05 mm blocks lose 83 % (70-90 %),
    # 0.25 mm blocks 17 % (10-30 %).
    seg = np.where(np.arange(n) % 2 == 0, 0.05, 0.25)
    target = tmp_path / "big.svg"
    root = draw(spiral(n, seg, 1500 / 60), str(target))
    assert target.stat().st_size < 4e6
    left, right = panels(root)
    assert titled(left, "polyline", "stroke", COLOURS[4])
    assert titled(right, "polyline", "stroke", LENGTH_COLOURS[0])
    assert len(left.findall(f".//{NS}polyline")) <= render.MAX_RUNS + 1


def test_markers_are_thinned_per_cell(tmp_path):
    """Discontinuities within a pixel keep one marker per class: the slowest, named by its lines."""
    zig = [[100 + 0.001 * (i % 2), 0.001 * (i // 2), 0] for i in range(400)]
    tp = polyline([[0, 0, 0], *zig], 100.0)
    nc = Ncperf(make_plugin_manager(builtins=PLUGINS, entry_points=False))
    ev = nc.evaluate(tp, load_preset("siemens-840d"))
    ann = build_annotations(ev)
    assert np.count_nonzero(ann.junction_class >= 1) > 300
    root = ET.fromstring(render.render_svg(tp, ann))
    marks = [c for c in root.iter(f"{NS}circle") if c.find(f"{NS}title") is not None]
    assert 1 <= len(marks) <= 2 * len(set(ann.junction_class.tolist()))
    slowest = tp.line[ann.junction[np.argmin(ann.junction_feed)]]
    assert any(m.findtext(f"{NS}title").startswith(f"line {slowest}/") for m in marks)


# ------------------------------------------------------------------ number formatting
def test_render_ints_matches_python_formatting():
    """The vectorised writer gives exactly str(value) + suffix for every value."""
    rng = np.random.default_rng(3)
    values = np.concatenate([[0, -1, 9, 10, -10, 99999], rng.integers(-(10**7), 10**7, 1000)])
    table = [b",", b" ", b"", b'</title>\n<polyline points="']
    suffix = rng.integers(0, len(table), values.size)
    want = b"".join(
        str(v).encode() + table[s] for v, s in zip(values.tolist(), suffix.tolist(), strict=True)
    )
    assert render.render_ints(values, suffix, table) == want
    assert render.render_ints([], [], table) == b""


def test_render_ints_short_values_after_long_ones():
    """Short values after long ones, with no text between (the digits of every value are
    written right-aligned in the widest value's places, the spare ones landing on the
    bytes before it): still exactly str(value) + suffix, the first value short too."""
    rng = np.random.default_rng(4)
    values = rng.choice([0, 7, -3, 12, -120, 98765432109, -5, 40], 5000)
    values[0] = 1
    table = [b"", b"-", b" ", b"ab"]
    suffix = rng.integers(0, len(table), values.size)
    want = b"".join(
        str(v).encode() + table[s] for v, s in zip(values.tolist(), suffix.tolist(), strict=True)
    )
    assert render.render_ints(values, suffix, table) == want


# ------------------------------------------------------------------ issue 14: what the picture says
def test_blocks_are_coloured_by_the_profile_by_default(tmp_path):
    """One 10 mm line at F 100 mm/s, A 2500 mm/s^2, no jerk limit, from rest to rest: ramps of
    F / A = 0.04 s over 2 mm each, 6 mm at F in 0.06 s: 0.14 s, a mean speed of 71.4 mm/s,
    28.6 % below F -- class 10-30 % by default (where the time goes). The paper's cruise
    class of the block is 0-10 % (it runs at F between its ramps): the ``paper`` colouring."""
    from tests.conftest import machine

    inf = float("inf")
    nc = Ncperf(make_plugin_manager(builtins=PLUGINS, entry_points=False))
    tp = polyline([[0, 0, 0], [10, 0, 0]], 100.0)
    ann = build_annotations(nc.evaluate(tp, machine(jerk=(inf, inf, inf))))
    assert ann.speed_share[0] == pytest.approx(10 / 0.14 / 100, rel=1e-6)
    for colour, cls, text in (("speed", 1, "speed below F by 10-30 %"), ("paper", 0, None)):
        out = nc.display(tp, ann, FileTarget(tmp_path / f"{colour}.svg", colour=colour))
        left = panels(ET.parse(out).getroot())[0]
        want = f"line 1: {text or 'reduction 0-10 %'}"
        assert titled(left, "polyline", "stroke", COLOURS[cls]) == [want]
    assert "where the time goes" in (tmp_path / "speed.svg").read_text()


def test_zone_labels_never_overlap_and_share_a_ring_at_one_point():
    """Zones at one point (Z-level step-downs) share a ring labelled "1, 2, 3"; labels of
    zones a few pixels apart are placed so that no two overlap and none covers a ring."""
    px = np.array([[100.0, 100.0], [100.0, 100.0], [101.0, 102.0], [112.0, 100.0], [100, 112]])
    rings = render.zone_labels(px, [1, 2, 3, 4, 5], 900.0, 600.0)
    assert [(r[2], r[3]) for r in rings] == [([0, 1, 2], "1, 2, 3"), ([3], "4"), ([4], "5")]
    boxes = [r[4] for r in rings]
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            assert a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1], (a, b)
        for j, (x, y, *_rest) in enumerate(rings):
            if j != i:  # no label on another zone's ring
                r = render.ZONE_RING_PX
                assert a[2] <= x - r or x + r <= a[0] or a[3] <= y - r or y + r <= a[1]
        assert 0 <= a[0] and a[2] <= 900 and 0 <= a[1] and a[3] <= 600


def test_demo_zone_labels_are_readable_and_title_is_the_file_name(tmp_path):
    """On the bundled Z-level cavity (ten zones, several at one XY point) every rank is
    written once, no two labels overlap, and the heading names the file, not its folders."""
    from core.cli.main import main

    out = tmp_path / "demo.svg"
    assert main(["analyze", "--demo", "--svg", str(out)]) == 0
    root = ET.parse(out).getroot()
    heading = root.findtext(f"{NS}text")
    assert heading.startswith("zlevel_cavity.ngc on ") and "/" not in heading.split(" on ")[0]
    left = panels(root)[0]
    labels = [
        el
        for grp in left.iter(f"{NS}g")
        if grp.get("font-size") == "13"
        for el in grp.iter(f"{NS}text")
    ]
    ranks = [int(r) for el in labels for r in el.text.split(", ")]
    assert sorted(ranks) == list(range(1, 11))
    boxes = []
    for el in labels:
        x, y = float(el.get("x")), float(el.get("y"))
        boxes.append((x, y - 11, x + render.LABEL_CHAR_PX * len(el.text), y + 2))
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            assert a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1], (a, b)
    # --colour paper: the paper's cruise classes instead (the title says which)
    assert main(["analyze", "--demo", "--svg", str(out), "--colour", "paper"]) == 0
    title = panels(ET.parse(out).getroot())[0].findtext(f"{NS}text")
    assert title.startswith("Predicted cruise feed reduction of each block")
