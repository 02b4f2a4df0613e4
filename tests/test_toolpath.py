"""ToolPath columns and derived quantities, geometry helpers, zones."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core import ToolPath
from core.engine.profile import build_profile
from core.model.toolpath import MoveKind, drop_zero_length, empty_columns, polyline
from core.view.annotations import build_annotations
from core.view.zones import find_zones
from tests.conftest import machine, path


def test_columns_are_checked_with_their_shapes():
    """Wrong column shapes raise with the expected and the actual shape."""
    cols = empty_columns(3)
    cols["start"] = np.zeros((2, 3))
    with pytest.raises(ValueError, match=r"start must have shape \(3, 3\), got \(2, 3\)"):
        ToolPath(**cols)
    cols = empty_columns(3)
    cols["op_offsets"] = np.array([0, 2])
    with pytest.raises(ValueError, match="op_offsets must rise from 0 to 3"):
        ToolPath(**cols)


def test_line_lengths_tangents_and_turn_angles():
    """A 3-4-5 triangle: lengths 3, 4, 5; turns 90 deg and 180 - 36.87 deg."""
    tp = polyline([[0, 0, 0], [3, 0, 0], [3, 4, 0], [0, 0, 0]], 10.0)
    assert np.allclose(tp.length, [3, 4, 5])
    assert np.allclose(tp.tangent_start[2], [-0.6, -0.8, 0])
    # at (3, 4) the path turns from (0, 1) to (-0.6, -0.8): the triangle's angle there is
    # atan(3/4) = 36.87 deg, so the direction changes by 143.13 deg
    assert np.degrees(tp.turn_angle) == pytest.approx([90.0, 180 - math.degrees(math.atan2(3, 4))])
    assert list(tp.junctions) == [0, 1]
    assert tp.feed_length == 12.0 and tp.programmed_time == pytest.approx(1.2)


def test_arc_derived_quantities():
    """Quarter arc R 5 ccw: length 7.854, tangents rotate by 90 deg, curvature +0.2."""
    tp = path([{"end": (5, 5, 0), "center": (0, 5, 0), "ccw": True}])
    assert tp.length[0] == pytest.approx(2.5 * math.pi)
    assert np.allclose(tp.tangent_start[0], [1, 0, 0]) and np.allclose(tp.tangent_end[0], [0, 1, 0])
    assert tp.curvature[0] == pytest.approx(0.2)
    assert np.allclose(tp.curvature_vector_start[0], [0, 0.2, 0])  # towards the centre
    assert np.allclose(tp.curvature_vector_end[0], [-0.2, 0, 0])


def test_curvature_jump_signs():
    """Line -> arc 1/R; same-way arcs |1/R1 - 1/R2|; inflection 1/R1 + 1/R2."""
    tp = path(
        [
            {"end": (10, 0, 0)},
            {"end": (20, 10, 0), "center": (10, 10, 0), "ccw": True},
            {"end": (15, 15, 0), "center": (15, 10, 0), "ccw": True},
            {"end": (10, 20, 0), "center": (15, 20, 0), "ccw": False},
        ]
    )
    assert tp.curvature_jump == pytest.approx([0.1, 0.1, 0.4])


def test_junctions_break_at_rapids_and_operations():
    """No junction next to a rapid, nor across an operation boundary."""
    cols = empty_columns(4)
    cols["end"] = np.array([[1, 0, 0], [2, 0, 0], [3, 0, 0], [4, 0, 0]], dtype=float)
    cols["start"] = np.concatenate([[[0, 0, 0]], cols["end"][:-1]])
    cols["feed"][:] = 10.0
    cols["kind"][1] = MoveKind.RAPID
    cols["feed"][1] = np.nan
    assert list(ToolPath(**cols).junctions) == [2]
    cols["op_offsets"] = np.array([0, 3, 4])
    assert list(ToolPath(**cols).junctions) == []


def test_drop_zero_length_keeps_stops_and_operations():
    """Zero-length moves go; their dwell moves to the move before; operations stay aligned."""
    cols = empty_columns(4)
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], dtype=float)
    cols["start"], cols["end"] = pts[:-1], pts[1:]
    cols["feed"][:] = 10.0
    cols["dwell"][1] = 2.0
    cols["op_offsets"] = np.array([0, 2, 4])
    tp, removed = drop_zero_length(ToolPath(**cols))
    assert list(removed) == [1]
    assert tp.n == 3 and list(tp.dwell) == [2.0, 0.0, 0.0]
    assert list(tp.op_offsets) == [0, 1, 3]


def test_zones_merge_close_corners_and_rank_by_time_lost(models):
    """Corners the machine cannot regain F between form one zone; a lone corner another. The
    time lost is worked out by hand for a trapezoidal profile (no jerk limit)."""
    # F = 100 mm/s, A = 2500 mm/s^2 (axis-aligned moves), t_int 1 ms (no block capped).
    # Three 90 deg corners: (10,0), (10,0.5), (30,0.5); each at sqrt(A R) with
    # R = 0.0241421 mm: v = 7.768870 mm/s. Between the first two (0.5 mm) the speed
    # peaks at sqrt(v^2 + A 0.5) = 36.199 mm/s < 0.9 F: one zone. The 10, 20 and 20 mm
    # moves reach F and separate zones.
    inf = float("inf")
    tp = path(
        [{"end": (10, 0, 0)}, {"end": (10, 0.5, 0)}, {"end": (30, 0.5, 0)}, {"end": (30, 20.5, 0)}],
        feed=100.0,
    )
    ev = models.evaluate(tp, machine(jerk=(inf, inf, inf), t_int=0.001))
    pr = build_profile(ev)
    R = 0.0241421356237  # the inserted arc's radius, and its tangent length at 90 deg
    v = math.sqrt(2500 * R)
    F, A = 100.0, 2500.0
    zones = find_zones(ev, pr)
    assert len(zones) == 2
    pair, single = zones  # the pair costs more
    assert (pair.first, pair.last) == (0, 2) and (pair.line_first, pair.line_last) == (1, 3)
    assert pair.discontinuities == 2 and pair.capped_blocks == 0
    # braking F -> v loses (F - v)^2 / (2 A F); running the inserted arc at v instead of
    # the tangent length R at F, (R pi / 4) / v - R / F; the same again leaving the corner
    arc = R * math.pi / 4
    ramp = (F - v) ** 2 / (2 * A * F) + arc / v - R / F
    assert single.time_lost == pytest.approx(2 * ramp, rel=1e-9)
    assert single.length == pytest.approx(2 * ((F**2 - v**2) / (2 * A) + R), rel=1e-9)
    # the 0.5 mm move: holds R at both ends, and up and down to sqrt(v^2 + A (0.5 - 2 R))
    peak = math.sqrt(A * (0.5 - 2 * R) + v * v)
    inner = 2 * (peak - v) / A + 2 * arc / v
    assert pair.time_lost == pytest.approx(2 * ramp + inner - 0.5 / F, rel=1e-9)
    assert pair.worst_reduction == pytest.approx(1 - v / F)
    assert pair.cause.startswith("tangential: acceleration")


def test_zones_of_lone_corners_keep_fractions(models):
    """A path whose every zone is a lone corner (no move wholly below 0.9 F) still reports
    the time and length each zone loses to the fraction: the sums start as floats."""
    # Issue 14: on the Fig. 1 polygons every zone said "lost 0.000 s" with whole-mm lengths
    # (a bincount over no inner moves gave integers that np.add.at then truncated).
    # Two 10 mm lines, one 90 deg corner, F 100 mm/s, A 2500 mm/s^2, no jerk limit: as in
    # the test above, 2 ((F - v)^2 / (2 A F) + (R pi / 4) / v - R / F) = 0.0384245 s over
    # 2 ((F^2 - v^2) / (2 A) + R) = 4.024142 mm.
    inf = float("inf")
    tp = path([{"end": (10, 0, 0)}, {"end": (10, 10, 0)}], feed=100.0)
    ev = models.evaluate(tp, machine(jerk=(inf, inf, inf), t_int=0.001))
    (zone,) = find_zones(ev, build_profile(ev))
    F, A, R = 100.0, 2500.0, 0.0241421356237
    v = math.sqrt(A * R)
    lost = 2 * ((F - v) ** 2 / (2 * A * F) + (R * math.pi / 4) / v - R / F)
    assert lost == pytest.approx(0.0384245, rel=1e-5)
    assert zone.time_lost == pytest.approx(lost, rel=1e-9)
    assert zone.length == pytest.approx(2 * ((F**2 - v**2) / (2 * A) + R), rel=1e-9)


def test_fig1_polygon_zones_lose_time():
    """On the bundled Fig. 1 polygons, every listed zone loses a positive time and the
    terminal report prints it (the zones there are lone corners: issue 14's 0.000 s)."""
    import contextlib
    import io
    from pathlib import Path

    from core.cli.main import main

    prog = Path(__file__).resolve().parents[1] / "examples" / "fig1_polygons_F2000.ngc"
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["analyze", str(prog), "--machine", "siemens-840d"]) == 0
    rows = [r for r in out.getvalue().splitlines() if " s  tangential: " in r]
    assert len(rows) >= 4, out.getvalue()
    assert all(" 0.000 s " not in r for r in rows), "\n".join(rows)


def test_annotations_classes():
    """Move classes from each block's own reduction; junction classes from theirs."""
    from core import Ncperf, make_plugin_manager
    from tests.conftest import MODELS

    nc = Ncperf(make_plugin_manager(builtins=MODELS, entry_points=False))
    # 1 mm blocks at 10 m/min on t_int 12 ms: 50 % -> class 3 ("50-70 %" starts at 50 %).
    tp = polyline([[i, 0, 0] for i in range(4)], 10000 / 60)
    ann = build_annotations(nc.evaluate(tp, machine()))
    assert list(ann.move_class) == [3, 3, 3]
    assert list(ann.length_class) == [0, 0, 0]


def test_zone_of_capped_blocks(models):
    """20 collinear 1 mm blocks at 10 m/min, t_int 12 ms: one zone, all capped at 5 m/min."""
    # F = 166.667 mm/s, cap 1 / 0.012 = 83.333 mm/s < 0.9 F: no move reaches 90 % of F, so
    # the zone is the whole path, from rest to rest (trapezoid, A = 2500 mm/s^2):
    # ramps 83.333 / 2500 = 0.033333 s over 83.333^2 / 5000 = 1.388889 mm each, cruise
    # (20 - 2.777778) / 83.333 = 0.206667 s: 0.273333 s, against 20 / 166.667 = 0.12 s.
    inf = float("inf")
    tp = polyline([[i, 0, 0] for i in range(21)], 10000 / 60)
    ev = models.evaluate(tp, machine(jerk=(inf, inf, inf)))
    zones = find_zones(ev, build_profile(ev))
    assert len(zones) == 1
    z = zones[0]
    assert (z.capped_blocks, z.discontinuities) == (20, 0)
    assert z.length == pytest.approx(20.0)
    assert z.time_lost == pytest.approx(0.2733333 - 0.12, rel=1e-6)
    assert z.cause == "ncu_capacity: block time"
