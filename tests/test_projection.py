"""The diagnosis's fast paths against the plain computations they replace: projecting onto
the path (a pruned window against the whole window at once) and the servo lag's filter
(three axes at once against one at a time)."""

from __future__ import annotations

import numpy as np

from core.engine.predict import _first_order
from core.model.sampling import PROJECTION_STEP
from core.model.toolpath import polyline
from tests.conftest import path


def _cases():
    rng = np.random.default_rng(7)
    # a zigzag of short chords, a path that runs back over itself (a retract and plunge
    # on one line), and arcs
    zig = np.column_stack([np.arange(40) * 0.4, (np.arange(40) % 2) * 0.3, np.zeros(40)])
    yield polyline(zig, 50.0), rng
    back = np.array([[0, 0, 0], [10, 0, 0], [10, 0, 5], [10, 0, 0], [0, 0, 0]], dtype=float)
    yield polyline(back, 50.0), rng
    arcs = path(
        [
            {"end": (5.0, 0.0, 0.0)},
            {"end": (5.0, 4.0, 0.0), "center": (5.0, 2.0, 0.0), "ccw": True},
            {"end": (0.0, 4.0, 1.0)},
        ]
    )
    yield arcs, rng


def test_project_near_is_the_whole_window_argmin():
    for tp, rng in _cases():
        samples = tp.sample(PROJECTION_STEP)
        half = int(1.0 / samples.step)
        # (guesses 0.02 mm off: mostly the nearest few points' answer, 0.4 mm: the window's)
        for spread, off in ((0.0, 0.4), (0.02, 0.4), (0.3, 0.4), (2.0, 0.4), (0.02, 0.02)):
            s_true = rng.uniform(-0.5, tp.end_s[-1] + 0.5, 3000)
            q = tp.point_at(s_true) + rng.normal(0.0, spread, (s_true.size, 3))
            guess = s_true + rng.normal(0.0, off, s_true.size)
            fast = samples.project_near(q, guess)
            plain = samples._project_near_gathered(q, guess, half)
            np.testing.assert_array_equal(fast[0], plain[0])
            np.testing.assert_array_equal(fast[1], plain[1])
        # points exactly on path samples and exactly between two of them (ties)
        q = samples.points[::3].copy()
        mid = 0.5 * (samples.points[1:] + samples.points[:-1])
        for pts, g in ((q, samples.s[::3]), (mid, 0.5 * (samples.s[1:] + samples.s[:-1]))):
            fast = samples.project_near(pts, g)
            plain = samples._project_near_gathered(pts, g, half)
            np.testing.assert_array_equal(fast[0], plain[0])
            np.testing.assert_array_equal(fast[1], plain[1])


def test_first_order_on_columns_is_per_column():
    rng = np.random.default_rng(3)
    for tau in (0.0005, 0.005, 0.2):
        a = float(np.exp(-0.001 / tau))
        for n in (1, 7, 2049, 20000):
            pos = np.cumsum(rng.normal(size=(n, 3)), axis=0)
            cols = np.column_stack(
                [_first_order(np.ascontiguousarray(pos[:, j]), a) for j in range(3)]
            )
            np.testing.assert_array_equal(_first_order(pos, a), cols)


def test_projection_lands_between_the_path_samples():
    """The foot of a point on the path, not the nearest of the 0.05 mm samples (which is up
    to 25 um off along the path: a 10 mm/s error in the measured speed 25 um before a stop
    at 2 m/s^2). A line from (0, 0, 0) to (10, 0, 0): the point (1.23456, 0.01, 0) has its
    foot at s = 1.23456 mm, 0.01 mm away (the nearest sample is at 1.25). A 10 mm line from
    (-10, 0, 0), then a counter-clockwise half circle of radius 2 about (0, 2, 0): the point
    at 0.3 rad and radius 2.002 has its foot at s = 10 + 2 x 0.3 = 10.6 mm, 0.002 mm away;
    between two samples the foot lies on their chord (its sagitta 0.05^2 / (8 x 2) = 0.16 um),
    its arc length interpolated along the chord: both within 0.2 um (the nearest sample
    alone: up to 25 um)."""
    line = polyline(np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]]), 50.0)
    samples = line.sample(PROJECTION_STEP)
    s, d = samples.project_near(np.array([[1.23456, 0.01, 0.0]]), np.array([1.2]))
    assert abs(s[0] - 1.23456) < 1e-12
    assert abs(d[0] - 0.01) < 1e-12
    arc = path(
        [
            {"start": (-10.0, 0.0, 0.0), "end": (0.0, 0.0, 0.0)},
            {"end": (0.0, 4.0, 0.0), "center": (0.0, 2.0, 0.0), "ccw": True},
        ]
    )
    samples = arc.sample(PROJECTION_STEP)
    phi = 0.3
    q = np.array([0.0, 2.0, 0.0]) + 2.002 * np.array([np.sin(phi), -np.cos(phi), 0.0])
    s, d = samples.project_near(q[None, :], np.array([10.5]))
    assert abs(s[0] - (10.0 + 2.0 * phi)) < 2e-4
    assert abs(d[0] - 0.002) < 2e-4
