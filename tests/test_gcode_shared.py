"""The G-code adapter on real programs from ../shared (skipped where that folder is absent)."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from adapters.gcode import read_gcode
from core.model.geometry import sample_arcs
from core.model.toolpath import MoveKind
from tests.conftest import SHARED, shared

REAL = [
    "gcode/camotics/flower_mold.nc",
    "gcode/camotics/tiger.nc",
    "gcode/linuxcnc-tp-tests/51MeanderAve.ngc",
    "gcode/linuxcnc-tp-tests/Cereal.ngc",
    "gcode/linuxcnc-tp-tests/LHchips4.ngc",
    "gcode/linuxcnc-tp-tests/contour.ngc",
    "gcode/linuxcnc-tp-tests/linearc-stellabee.ngc",
    "gcode/linuxcnc-tp-tests/spiral_lines.ngc",
    "gcode/linuxcnc-tp-tests/stellabee1.ngc",
    "gcode/linuxcnc-tp-tests/straight_short_lines_X.ngc",
    "gcode/linuxcnc-tp-tests/tight-corner-tolerance.ngc",
    "nist-mtc-box-op2/BOX_REV-A_OP2_Front.NC",
]


@pytest.mark.parametrize("rel", REAL, ids=[r.split("/")[-1] for r in REAL])
def test_real_programs_parse(rel):
    """Real CAM and test-suite programs read without error into finite, chained moves."""
    p = shared("data", *rel.split("/"))
    tp = read_gcode(p.read_bytes(), str(p))
    assert tp.n > 0
    assert np.isfinite(tp.start).all() and np.isfinite(tp.end).all()
    assert np.isfinite(tp.length).all() and (tp.length > 0).all()
    # Moves chain: each starts where the previous one ended.
    assert np.allclose(tp.start[1:], tp.end[:-1])
    feed = tp.kind != MoveKind.RAPID
    assert (tp.feed[feed] > 0).all()


def test_flower_mold_is_inch():
    """CAMotics' flower_mold.nc is G20: its 2.249 in raster is 57.12 mm long."""
    p = shared("data", "gcode", "camotics", "flower_mold.nc")
    tp = read_gcode(p.read_bytes(), str(p))
    assert tp.units == "inch"
    assert tp.end[:, 0].max() == pytest.approx(2.2490 * 25.4)
    assert tp.feed[np.isfinite(tp.feed)].max() == pytest.approx(20.0 * 25.4 / 60)


def test_nist_box_program_notices():
    """The NIST Fanuc-style program: two tools; G28 (home in machine coordinates) and the
    G54 -> G58 change with offsets nobody gave are reported."""
    p = shared("data", "nist-mtc-box-op2", "BOX_REV-A_OP2_Front.NC")
    tp = read_gcode(p.read_bytes(), str(p))
    assert len(tp.op_names) == 2
    assert set(tp.tool.tolist()) == {3, 21}
    text = "\n".join(str(n) for n in tp.notices)
    assert "G28 moves in machine coordinates but the work offset G54 is not known" in text
    assert "work offset changes to G58, whose value is not known" in text


def _segments(tp, step=0.05):
    """The path as straight segments (arcs sampled finely)."""
    pts_a, pts_b = [], []
    lines = ~tp.is_arc
    pts_a.append(tp.start[lines])
    pts_b.append(tp.end[lines])
    a = np.flatnonzero(tp.is_arc)
    if a.size:
        counts = np.maximum(2, np.ceil(tp.length[a] / step)).astype(np.int64)
        pts = sample_arcs(
            tp.start[a],
            tp.center[a],
            tp.normal[a],
            tp.kind[a] == MoveKind.ARC_CCW,
            tp.sweep[a],
            tp.pitch[a],
            counts,
        )
        first = np.cumsum(counts + 1) - (counts + 1)
        keep = np.ones(len(pts), dtype=bool)
        keep[first + counts] = False  # the last point of each arc starts no segment
        idx = np.flatnonzero(keep)
        pts_a.append(pts[idx])
        pts_b.append(pts[idx + 1])
    return np.concatenate(pts_a), np.concatenate(pts_b)


def _distance_to_path(points, a, b, chunk=400):
    ab = b - a
    ab2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-30)
    out = np.empty(len(points))
    for s in range(0, len(points), chunk):
        p = points[s : s + chunk, None, :]
        t = np.clip(np.einsum("pij,ij->pi", p - a[None], ab) / ab2, 0, 1)
        d = p - (a[None] + t[..., None] * ab[None])
        out[s : s + chunk] = np.sqrt(np.einsum("pij,pij->pi", d, d).min(axis=1))
    return out


SUITE = sorted(p.name for p in (SHARED / "data" / "linuxcnc" / "suite").glob("*.ngc")) or [
    "01_polygons_f2000.ngc"
]


@pytest.mark.parametrize("name", SUITE)
def test_linuxcnc_trace_lies_on_the_parsed_path(name):
    """The positions LinuxCNC's planner commanded every 1 ms lie within its G64 P0.01 blend
    tolerance of the path ncperf read (arcs go the right way in every plane, helices turn
    the right number of times). Only its parabolic blends at non-tangent helix ends stray
    further (up to 0.12 mm, on a handful of samples)."""
    prog = shared("data", "linuxcnc", "suite", name)
    trace = prog.with_suffix(".csv")
    tp = read_gcode(prog.read_bytes(), str(prog))
    with open(trace, newline="") as fh:
        rows = list(csv.DictReader(fh))
    pts = np.array([[float(r["x"]), float(r["y"]), float(r["z"])] for r in rows])
    a, b = _segments(tp)
    d = _distance_to_path(pts, a, b)
    off = d > 0.015
    # Non-tangent junctions next to an arc get LinuxCNC's parabolic blend.
    j = np.flatnonzero((tp.turn_angle > 0.01) & (tp.is_arc[:-1] | tp.is_arc[1:]))
    if off.any() and j.size:
        near = np.linalg.norm(pts[off][:, None, :] - tp.end[j][None], axis=2).min(axis=1)
        off[np.flatnonzero(off)[near < 3.5]] = False
    assert not off.any(), f"{off.sum()} samples off the path, worst {d[off].max():.4f} mm"
    assert d.max() < 0.2, f"max distance {d.max():.4f} mm at sample {int(d.argmax())}"
