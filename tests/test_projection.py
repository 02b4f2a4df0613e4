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
