"""The bundled examples: regenerated identically, and the paper's experiments predicted."""

from __future__ import annotations

import filecmp
import subprocess
import sys

import numpy as np
import pytest

from core import load_preset
from tests.conftest import ROOT

EX = ROOT / "examples"


def test_generator_reproduces_the_committed_programs(tmp_path):
    """examples/generate.py writes exactly the programs in examples/."""
    subprocess.run(
        [sys.executable, str(EX / "generate.py"), "--out", str(tmp_path)],
        check=True,
        capture_output=True,
    )
    written = sorted(p.name for p in tmp_path.glob("*.ngc"))
    assert written == sorted(p.name for p in EX.glob("*.ngc"))
    for name in written:
        assert filecmp.cmp(tmp_path / name, EX / name, shallow=False), name


@pytest.mark.parametrize(
    "d,expected", [(0.5, 2500.0), (1.0, 5000.0), (2.0, 10000.0), (3.0, 10000.0), (5.0, 10000.0)]
)
def test_figure4_point_series(nc, d, expected):
    """Fig. 4 at 10 m/min, t_int 12 ms: L = 2 mm; d < L runs at d / t_int (1 mm: 5 m/min)."""
    # 0.5 mm / 0.012 s = 41.667 mm/s = 2500 mm/min; 1 mm -> 5000; 2 mm and more: F10000.
    tp = nc.extract(str(EX / f"fig4_points_d{d:g}.ngc"))
    ev = nc.evaluate(tp, load_preset("siemens-840d"))
    ab = tp.is_feed & np.isclose(tp.length, d) & (tp.feed > 160)
    assert ab.sum() >= 10
    assert np.allclose(ev.element_feed[ab] * 60, expected)


def test_figure1_corner_speed_does_not_depend_on_the_programmed_feed(nc):
    """Fig. 1-2: 'the reduction of the feed rate is not dependent on that programmed': the 90 deg
    corners run at cbrt(J R^2) = 1.42837 mm/s (85.70 mm/min) at F2000 as at F12000."""
    m = load_preset("siemens-840d")
    for f in (2000, 4000, 8000, 12000):
        tp = nc.extract(str(EX / f"fig1_polygons_F{f}.ngc"))
        ev = nc.evaluate(tp, m)
        right = np.isclose(np.degrees(tp.turn_angle[ev.junction]), 90.0, atol=0.01)
        assert right.sum() >= 5
        assert np.allclose(ev.junction_feed[right] * 60, 85.702148, rtol=1e-6)


def test_chords_strategy_has_more_short_blocks(nc):
    """The chord version of the cavity puts far more feed length below L than the arc version."""
    m = load_preset("siemens-840d")
    shares, lengths = {}, {}
    for name in ("zlevel_cavity", "zlevel_cavity_chords"):
        tp = nc.extract(str(EX / f"{name}.ngc"))
        ev = nc.evaluate(tp, m)
        below = tp.is_feed & (tp.length < ev.min_length)
        shares[name] = tp.length[below].sum() / tp.feed_length
        lengths[name] = tp.feed_length
    # the same path (chords within 0.005 mm are a hair shorter than their arcs)
    assert lengths["zlevel_cavity_chords"] == pytest.approx(lengths["zlevel_cavity"], rel=1e-3)
    assert shares["zlevel_cavity_chords"] > 5 * shares["zlevel_cavity"]
