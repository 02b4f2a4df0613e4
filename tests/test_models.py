"""The paper's three models (eq. 1-16), with numbers worked out by hand in each test."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from core.model import geometry as g
from plugins import curvature, tangential
from tests.conftest import machine, path

MM_MIN = 60.0  # mm/s -> mm/min


def _junction(ev, j):
    k = int(np.flatnonzero(ev.junction == j)[0])
    return (
        ev.junction_feed[k],
        ev.labels[ev.junction_limit[k]],
        ev.indicator_names[ev.junction_indicator[k]],
    )


# ----------------------------------------------------------------------------- model 1
def test_eq1_radius_90_degrees():
    """Eq. (1): 90 deg, TIT 0.01 mm, 10 mm blocks: R = 0.01 cos45/(1-cos45) = 0.0241421 mm."""
    # By hand: cos 45 = 0.70710678, 1 - cos 45 = 0.29289322, ratio 2.41421356;
    # the length term 10 / (2 sin 45) - 0.01 = 7.0610678 is larger.
    r = tangential.inserted_radius(np.array([math.pi / 2]), np.array([10.0]), 0.01)
    assert r[0] == pytest.approx(0.0241421356, rel=1e-8)


def test_eq1_radius_30_degrees():
    """Eq. (1): 30 deg, TIT 0.01 mm: R = 0.01 cos15/(1-cos15) = 0.2834774 mm."""
    # cos 15 = 0.96592583, 1 - cos 15 = 0.03407417 -> 0.2834774; 10/(2 sin 15) - 0.01 = 19.3085.
    r = tangential.inserted_radius(np.array([math.radians(30)]), np.array([10.0]), 0.01)
    assert r[0] == pytest.approx(0.2834774027, rel=1e-8)


def test_eq1_short_blocks_bound_the_radius():
    """Eq. (1): with 0.3 mm blocks at 90 deg the length term l/(2 sin(b/2)) - TIT binds."""
    # With TIT 0.01 the tolerance term 0.0241421 is below 0.3/(2 sin 45) - 0.01 = 0.2021320,
    # so take TIT 0.1:
    r = tangential.inserted_radius(np.array([math.pi / 2]), np.array([0.3]), 0.1)
    # tolerance term 0.1 * 2.41421356 = 0.2414214 > length term 0.2121320 - 0.1 = 0.1121320
    assert r[0] == pytest.approx(0.1121320344, rel=1e-8)


def test_eq1_too_short_blocks_give_a_stop():
    """Eq. (1) negative (blocks shorter than the tolerance allows) means R = 0: a stop."""
    r = tangential.inserted_radius(np.array([math.pi / 2]), np.array([0.01]), 0.01)
    assert r[0] == 0.0


def test_model1_90_degree_corner(models):
    """Eq. (4)-(6) at 90 deg on the 840D values: V = cbrt(J R^2) = 1.42837 mm/s (jerk binds)."""
    # R = 0.0241421 mm; sqrt(A R) = sqrt(2500 * 0.0241421) = 7.76887 mm/s;
    # cbrt(J R^2) = cbrt(5000 * 5.828427e-4) = cbrt(2.9142136) = 1.4283691 mm/s; Vmax 500.
    # Y jerk is lower (4 m/s^3) so that the binding axis is unambiguous:
    # cbrt(4000 * 5.828427e-4) = cbrt(2.3313709) = 1.3259 mm/s.
    tp = path([{"end": (10, 0, 0)}, {"end": (10, 10, 0)}], feed=100.0)
    ev = models.evaluate(tp, machine(jerk=(5.0, 4.0, 5.0)))
    feed, limit, ind = _junction(ev, 0)
    assert ind == "tangential"
    assert limit == "jerk Y"
    assert feed == pytest.approx((4000 * 0.0241421356237**2) ** (1 / 3), rel=1e-9)
    assert feed == pytest.approx(1.32587, rel=1e-4)


def test_model1_90_degree_corner_acceleration_binds(models):
    """Eq. (4): with a large jerk the feed is sqrt(A R) = 7.76887 mm/s."""
    tp = path([{"end": (10, 0, 0)}, {"end": (10, 10, 0)}], feed=100.0)
    ev = models.evaluate(tp, machine(jerk=(1000.0, 1000.0, 1000.0)))
    feed, limit, _ = _junction(ev, 0)
    assert feed == pytest.approx(7.768869870, rel=1e-8)
    assert limit in ("acceleration X", "acceleration Y")


def test_model1_30_degree_corner_per_axis_shares(models):
    """Eq. (7)-(10) at 30 deg from X: shares t_X 1, t_Y sin30, n_X sin30, n_Y 1; jerk X binds."""
    # R = 0.2834774 mm. Over the inserted arc phi in [0, 30 deg]:
    # tangent (cos phi, sin phi): max |t_X| = 1, max |t_Y| = 0.5;
    # normal (-sin phi, cos phi): max |n_X| = 0.5, max |n_Y| = 1.
    # acc X sqrt(2500 R / 0.5) = 37.6482, acc Y sqrt(2500 R) = 26.6213,
    # jerk X cbrt(5000 R^2) = 7.37908, jerk Y cbrt(5000 R^2 / 0.5) = 9.29706  -> 7.37908.
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    tp = path([{"end": (10, 0, 0)}, {"end": (10 + 10 * c, 10 * s, 0)}], feed=100.0)
    ev = models.evaluate(tp, machine())
    feed, limit, _ = _junction(ev, 0)
    assert limit == "jerk X"
    assert feed == pytest.approx(7.379081348, rel=1e-8)
    # The acceleration limits computed with the shares, directly:
    r = 0.2834774027
    f, lim = tangential.corner_feed(
        np.array([[1.0, 0, 0]]), np.array([[c, s, 0]]), np.array([r]), machine(jerk=(1e6, 1e6, 1e6))
    )
    assert tangential.LABELS[lim[0]] == "acceleration Y"
    assert f[0] == pytest.approx(26.621297992, rel=1e-8)


def test_model1_bisector_off_axis(models):
    """Per-axis limits when the corner's bisector is at 55 deg: share n_Y = cos 10, not 1."""
    # Tangents at 10 deg and 100 deg (beta 90 deg). Tangent angle sweeps [10, 100] deg:
    # max|t_X| = cos10 = 0.9848078, max|t_Y| = 1 (90 deg inside). Normal angle sweeps
    # [100, 190] deg: max|n_X| = 1 (180 inside), max|n_Y| = sin100 = 0.9848078.
    # A_X 2.5, A_Y 2.0 m/s^2, jerk high: acc X sqrt(2500 R) = 7.76887,
    # acc Y sqrt(2000 R / 0.9848078) = 7.00208 -> binds.
    a, b = math.radians(10), math.radians(100)
    p1 = (10 * math.cos(a), 10 * math.sin(a), 0)
    p2 = (p1[0] + 10 * math.cos(b), p1[1] + 10 * math.sin(b), 0)
    tp = path([{"end": p1}, {"end": p2}], feed=100.0)
    ev = models.evaluate(tp, machine(acc=(2.5, 2.0, 2.5), jerk=(1000.0, 1000.0, 1000.0)))
    feed, limit, _ = _junction(ev, 0)
    assert limit == "acceleration Y"
    assert feed == pytest.approx(7.002080688, rel=1e-8)


def test_model1_max_share_peak_inside_and_outside():
    """max |a cos + b sin| over [0, s]: sqrt(a^2 + b^2) if its angle is inside, else an end."""
    # a = 1, b = 0 (peak at 0): share 1. a = 0, b = 1 (peak at 90 deg): 1 if s >= 90 deg,
    # else sin(s). a = cos 10, b = -sin 10 (peak at -10 deg = 170 deg mod 180): for
    # s = 90 deg the ends give cos 10 = 0.98481 and |cos 100| = 0.17365.
    s90 = np.array([math.pi / 2])
    s30 = np.array([math.pi / 6])
    assert g.max_share(np.array([1.0]), np.array([0.0]), s90)[0] == 1.0
    assert g.max_share(np.array([0.0]), np.array([1.0]), s90)[0] == pytest.approx(1.0)
    assert g.max_share(np.array([0.0]), np.array([1.0]), s30)[0] == pytest.approx(0.5)
    a, b = math.cos(math.radians(10)), -math.sin(math.radians(10))
    got = g.max_share(np.array([a]), np.array([b]), s90)[0]
    assert got == pytest.approx(0.984807753, rel=1e-9)


def test_model1_uses_program_tolerance(models):
    """A program's own path tolerance (LinuxCNC G64 P) replaces the machine's TIT in eq. (1)."""
    # TIT 0.1 mm at 90 deg: R = 0.241421 mm; acceleration binds with high jerk:
    # sqrt(2500 * 0.2414214) = 24.56745 mm/s.
    tp = path([{"end": (10, 0, 0)}, {"end": (10, 10, 0)}], feed=100.0)
    tp2 = dataclasses.replace(tp, tolerance=np.array([0.1, 0.1]))
    ev = models.evaluate(tp2, machine(jerk=(1e6, 1e6, 1e6)))
    assert _junction(ev, 0)[0] == pytest.approx(math.sqrt(2500 * 0.1 * 2.414213562373095))


def test_model1_reversal_is_a_stop(models):
    """A 180 deg reversal: cos(90 deg) = 0 gives R = 0, so the feed is 0."""
    tp = path([{"end": (10, 0, 0)}, {"end": (0, 0, 0)}], feed=100.0)
    ev = models.evaluate(tp, machine())
    assert _junction(ev, 0)[0] == pytest.approx(0.0, abs=1e-9)


def test_model1_tiny_angle_is_not_reduced(models):
    """A 0.01 deg kink on 1 mm blocks: R = l/(2 sin(b/2)) - TIT = 5729.6 mm, no reduction."""
    b = math.radians(0.01)
    tp = path([{"end": (1, 0, 0)}, {"end": (1 + math.cos(b), math.sin(b), 0)}], feed=100.0)
    ev = models.evaluate(tp, machine())
    feed, limit, _ = _junction(ev, 0)
    assert feed == 100.0 and limit == "programmed feed"


# ----------------------------------------------------------------------------- model 2
def test_eq13_line_to_arc(models):
    """Eq. (13): line along X into an R 5 arc: V = sqrt(J dt R) = sqrt(5000*0.012*5) = 17.3205."""
    tp = path(
        [{"end": (10, 0, 0)}, {"end": (15, 5, 0), "center": (10, 5, 0), "ccw": True}], feed=100.0
    )
    ev = models.evaluate(tp, machine())
    feed, limit, ind = _junction(ev, 0)
    assert ind == "curvature" and limit == "jerk X"
    assert feed == pytest.approx(17.320508076, rel=1e-9)


def test_eq14_arc_to_arc_same_direction(models):
    """Eq. (14): R1 10 -> R2 5 turning the same way: V = sqrt(10*5*5000*0.012/5) = 24.4949."""
    # Arc 1: centre (0, 10), from (0, 0) ccw a quarter to (10, 10); tangent there (0, 1).
    # Arc 2: R 5, centre (5, 10), ccw, continues tangent upwards from (10, 10) to (5, 15).
    tp = path(
        [
            {"end": (10, 10, 0), "center": (0, 10, 0), "ccw": True},
            {"end": (5, 15, 0), "center": (5, 10, 0), "ccw": True},
        ],
        feed=100.0,
    )
    ev = models.evaluate(tp, machine())
    feed, limit, ind = _junction(ev, 0)
    assert ind == "curvature" and limit == "jerk Y"  # tangent along Y
    assert feed == pytest.approx(24.494897428, rel=1e-9)


def test_inflection_uses_sum_of_curvatures(models):
    """Inflection R1 10 ccw -> R2 5 cw: jump 1/10 + 1/5 = 0.3, V = sqrt(5000*0.012/0.3) = 14.1421.

    (Eq. 14 as printed, with |R1 - R2|, would give 24.4949 here.)"""
    # Arc 2: R 5 clockwise from (10, 10), tangent (0, 1), centre to the right: (15, 10).
    tp = path(
        [
            {"end": (10, 10, 0), "center": (0, 10, 0), "ccw": True},
            {"end": (15, 15, 0), "center": (15, 10, 0), "ccw": False},
        ],
        feed=100.0,
    )
    ev = models.evaluate(tp, machine())
    feed, _, ind = _junction(ev, 0)
    assert ind == "curvature"
    assert feed == pytest.approx(14.142135624, rel=1e-9)


def test_eq15_tangential_jerk():
    """Eq. (15): tangent at 30 deg: min(J_X/cos30, J_Y/sin30) = min(5773.50, 4000) = 4000 (Y)."""
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    j, axis = curvature.tangential_jerk(np.array([[c, s, 0.0]]), machine(jerk=(5.0, 2.0, 5.0)))
    assert axis[0] == 1 and j[0] == pytest.approx(4000.0)
    j, axis = curvature.tangential_jerk(np.array([[c, s, 0.0]]), machine())
    assert axis[0] == 0 and j[0] == pytest.approx(5773.502692, rel=1e-9)


def test_eq15_in_the_curvature_model(models):
    """Line at 30 deg into an R 5 arc: V = sqrt(5773.5027 * 0.012 * 5) = 18.6121 mm/s."""
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    p = (10 * c, 10 * s, 0)
    centre = (p[0] - 5 * s, p[1] + 5 * c, 0)  # left of the tangent, R 5
    end = (centre[0] + 5 * s, centre[1] + 5 * c, 0)  # the diametrically opposite point
    tp = path([{"end": p}, {"end": end, "center": centre, "ccw": True}], feed=100.0)
    ev = models.evaluate(tp, machine())
    feed, limit, _ = _junction(ev, 0)
    assert limit == "jerk X"
    assert feed == pytest.approx(math.sqrt(5773.502691896 * 0.012 * 5), rel=1e-9)
    assert feed == pytest.approx(18.6121, rel=1e-5)


def test_same_arc_twice_is_no_discontinuity(models):
    """Two consecutive arcs of one circle: no curvature jump, no junction record."""
    tp = path(
        [
            {"end": (10, 10, 0), "center": (0, 10, 0), "ccw": True},
            {"end": (0, 20, 0), "center": (0, 10, 0), "ccw": True},
        ],
        feed=100.0,
    )
    ev = models.evaluate(tp, machine())
    assert ev.junction.size == 0


# ----------------------------------------------------------------------------- model 3
def _points(d: float, n: int, feed: float):
    return path([{"end": (d * (i + 1), 0, 0)} for i in range(n)], feed=feed)


def test_eq16_figure4_one_millimetre_points(models):
    """Eq. (16), Figure 4: 1 mm points at 10 m/min, t_int 12 ms: L = 2 mm, 5 m/min (-50 %)."""
    # 10 m/min = 166.667 mm/s; L = 166.667 * 0.012 = 2 mm > 1 mm; cap 1 / 0.012 = 83.333 mm/s
    # = 5 m/min. (The paper measured about 55 %.)
    tp = _points(1.0, 20, 10000 / MM_MIN)
    ev = models.evaluate(tp, machine())
    assert np.allclose(ev.min_length, 2.0)
    assert np.allclose(ev.element_feed * MM_MIN, 5000.0)
    assert np.allclose(ev.element_reduction, 0.5)
    assert set(ev.labels[k] for k in ev.element_limit) == {"block time"}


def test_eq16_figure4_three_millimetre_points(models):
    """Eq. (16), Figure 4: 3 mm points at 10 m/min are longer than L = 2 mm: no reduction."""
    tp = _points(3.0, 20, 10000 / MM_MIN)
    ev = models.evaluate(tp, machine())
    assert np.allclose(ev.element_feed * MM_MIN, 10000.0)
    assert np.all(ev.element_indicator == -1)


def test_eq16_paper_time(models):
    """Paper-model time: 20 x 1 mm at 5 m/min = 20 mm / 83.333 mm/s = 0.24 s (vs 0.12 s at F)."""
    tp = _points(1.0, 20, 10000 / MM_MIN)
    ev = models.evaluate(tp, machine())
    assert tp.programmed_time == pytest.approx(0.12)
    assert ev.paper_time == pytest.approx(0.24)


# ----------------------------------------------------------------------------- exact stop
def test_exact_stop_and_dwell(models):
    """G61/G9 blocks and dwells end at rest: predicted junction feed 0, named as such."""
    tp = path([{"end": (10, 0, 0)}, {"end": (20, 0, 0)}, {"end": (30, 0, 0)}], feed=100.0)
    tp2 = dataclasses.replace(tp, path_mode=np.array([1, 0, 0]), dwell=np.array([0.0, 2.0, 0.0]))
    ev = models.evaluate(tp2, machine())
    assert list(ev.junction) == [0, 1]
    assert list(ev.junction_feed) == [0.0, 0.0]
    assert [ev.labels[k] for k in ev.junction_limit] == ["exact stop", "dwell"]


# ----------------------------------------------------------------------------- feed limit
def test_feed_limit_on_a_line(models):
    """A line at 30 deg in XY: V <= min(Vmax_X / cos30, Vmax_Y / sin30) = min(577.35, 800)."""
    # Vmax_X 30 m/min = 500 mm/s, Vmax_Y 24 m/min = 400 mm/s: 500/0.866 = 577.35 (X binds).
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    tp = path([{"end": (10 * c, 10 * s, 0)}], feed=1000.0)
    ev = models.evaluate(tp, machine(feed=(30.0, 24.0, 30.0)))
    assert ev.element_feed[0] == pytest.approx(500 / c)
    assert ev.labels[ev.element_limit[0]] == "feed X"
    assert ev.indicator_names[ev.element_indicator[0]] == "feed_limit"


def test_feed_limit_on_an_arc(models):
    """A quarter arc whose tangent turns from (0, 1) to (-1, 0): Y's share is 1 at the start,
    X's 1 at the end, so the cap is min(500 / 1, 400 / 1) = 400 mm/s (Y)."""
    tp = path(
        [{"start": (5, 0, 0), "end": (0, 5, 0), "center": (0, 0, 0), "ccw": True}], feed=1000.0
    )
    ev = models.evaluate(tp, machine(feed=(30.0, 24.0, 30.0)))
    assert ev.element_feed[0] == pytest.approx(400.0)
    assert ev.labels[ev.element_limit[0]] == "feed Y"


def test_feed_limit_does_not_touch_reachable_feeds(models):
    """A block programmed below its axes' limits is not reported."""
    tp = path([{"end": (10, 0, 0)}], feed=100.0)
    ev = models.evaluate(tp, machine())
    assert ev.element_indicator[0] == -1


def test_cross_is_numpys_bit_for_bit():
    """core.model.geometry.cross (no input copies) gives np.cross's bits: zeros of both
    signs, infinities, NaN, broadcasting one row."""
    from core.model import geometry as g

    rng = np.random.default_rng(8)
    a = rng.standard_normal((5000, 3)) * 10.0 ** rng.integers(-300, 300, (5000, 3))
    b = rng.standard_normal((5000, 3))
    a[::7] = -0.0
    b[::11, 1] = np.inf
    a[::13, 2] = np.nan
    with np.errstate(all="ignore"):
        for x, y in ((a, b), (b, a), (a, b[:1]), (a[:1], b)):
            assert g.cross(x, y).tobytes() == np.cross(x, y).tobytes()
