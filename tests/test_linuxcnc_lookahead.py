"""LinuxCNC 2.9's lazy look-ahead (core.engine.lookahead) on hand-worked queues.

The walk of tp.c ``tpRunOptimization``: each new block sets the final speed of the segment
before it to its open triangle (a L / 2), every earlier one v^2 + 2 a_t l from the one after
it, capped at the limit (and then marked "at max" for good); a walk stops once it has
passed more than 4 marked segments. Numbers below are squared speeds (mm^2/s^2).
"""

from __future__ import annotations

import numpy as np
import pytest

from core import Ncperf, load_preset
from core.engine.lookahead import OPEN_SHARE, lazy_walks

#: 40 chords of 0.06 mm run as blend arcs at a_t = 1000 mm/s^2 (2 a_t l = 120), limit
#: 0.06 / 1.02 ms = 58.82 mm/s (squared 3460); a long line of 1.2 mm at a = 2000 (its open
#: triangle a L / 2 = 1200; 2 a L = 4800, limit 250); the corner arc after it (limit 6.76
#: mm/s, squared 45.7; 2 a_t l = 40); the line after the corner, 2 mm (2 a L = 8000).
CHORD_DN, CHORD_LIM2 = 120.0, 3460.0
LONG_OPEN, LONG_DN, LONG_LIM = 1200.0, 4800.0, 250.0
CORNER_LIM2, CORNER_DN, AFTER_DN = 45.7, 40.0, 8000.0


def _queue():
    """Segments 0-39 the chords, 40 the long line, 41 the corner arc, 42 the line after;
    blocks: each chord, the long line (segments 40 and 41: its arc is made when the next
    block joins), the line after (segment 42)."""
    dn = np.array([CHORD_DN] * 40 + [LONG_DN, CORNER_DN, AFTER_DN])
    vmax2 = np.array([CHORD_LIM2] * 40 + [LONG_LIM**2, CORNER_LIM2, LONG_LIM**2])
    lim2 = np.minimum(vmax2, np.append(vmax2[1:], vmax2[-1]))
    tangent = np.ones(43, dtype=bool)
    tangent[-1] = False  # the program's end
    first = np.array(list(range(41)) + [42])
    open2 = np.array([0.5 * 2000.0 * 0.06] * 40 + [LONG_OPEN, 0.5 * 2000.0 * 2.0])
    return dn, lim2, tangent, first, open2


def test_chords_before_a_long_line_keep_the_speed_its_open_triangle_left():
    """The long line's walk lowers the chords before it to 1200 + 120 m (m chords back from
    the last one, segment 39) until that reaches their limit (m = 19: segment 20). The next
    block's walk (the line after the corner) caps the long line at the corner (marked),
    then passes the chords 39, 38, 37, 36 -- each at its limit again and marked -- and
    stops at the fifth mark, having set 35: chords 35-39 are back at their limit, 21-34
    keep 1200 + 120 (39 - s): the lowest, segment 34, 1800 (42.43 mm/s; LinuxCNC ran
    42.56 there, tests/test_linuxcnc_planner_traces.py)."""
    fv2 = lazy_walks(*_queue())
    s = np.arange(21, 35)
    np.testing.assert_allclose(fv2[s], LONG_OPEN + CHORD_DN * (39 - s), rtol=1e-15)
    assert np.sqrt(fv2[34]) == pytest.approx(42.426, abs=1e-3)
    np.testing.assert_array_equal(fv2[35:40], CHORD_LIM2)
    assert fv2[20] == CHORD_LIM2  # where the lowered chain reached the limit
    assert fv2[40] == CORNER_LIM2  # the long line ends at the corner's limit
    assert fv2[41] == CORNER_LIM2 and fv2[42] == 0.0  # the corner arc; the end, a stop


def test_a_walk_without_the_cutoff_raises_them_all():
    """Without the lazy cutoff every walk runs its 51 steps: the walk of the block after
    the corner passes all 40 chords and puts them back at their limit (LinuxCNC built
    without TP_OPTIMIZATION_LAZY)."""
    fv2 = lazy_walks(*_queue(), cutoff=10**9)
    np.testing.assert_array_equal(fv2[:40], CHORD_LIM2)


def test_a_stop_ends_the_walk_at_the_second_one():
    """A walk skips the first segment that ends in a stop (its final speed is 0) and stops
    at the second: blocks after two stops leave what lies before them alone."""
    dn = np.full(6, 100.0)
    lim2 = np.full(6, 1e4)
    tangent = np.array([True, False, True, False, True, False])
    first = np.arange(6)
    open2 = np.full(6, 10.0)
    fv2 = lazy_walks(dn, lim2, tangent, first, open2)
    # block 1's walk gives segment 0 block 1's open triangle (10); the walks of blocks 2 and
    # 3 skip segment 1 (a stop, 0) and set 0 from it: 0 + 100; those of blocks 4 and 5 meet
    # two stops before it and never reach it
    assert fv2[0] == 100.0
    assert fv2[1] == 0.0 and fv2[3] == 0.0 and fv2[5] == 0.0
    assert fv2[2] == 100.0  # from segment 3's stop: 0 + 100, by block 5's walk
    assert fv2[4] == 100.0  # the end's walk: segment 5 a stop, then 0 + 100


def test_open_triangle_share():
    """A line added under G64 is PARABOLIC until blended: half its acceleration (tc.c)."""
    assert OPEN_SHARE == 0.5


CHORDS = 40


def _program() -> str:
    """Runs of 40 chords of 0.06 mm at headings of +-0.25 degrees, each followed by a long
    line, 1.2, 2.4 and 1.2 mm, with 90 degree turns between (the long lines end in a
    corner), and 40 chords after the last, at F4000 under G64 P0.01 Q0."""
    out = ["(lazy look-ahead)", "G21 G17 G90 G94", "G64 P0.01 Q0", "G0 X0 Y0 Z0"]
    out += ["G1 X0 Y0 Z-1 F600", "F4000"]
    x = y = 0.0
    for head, long in ((0.0, 1.2), (90.0, 2.4), (180.0, 1.2), (270.0, 0.0)):
        for i in range(CHORDS):
            a = np.radians(head + (0.25 if i % 2 == 0 else -0.25))
            x, y = x + 0.06 * np.cos(a), y + 0.06 * np.sin(a)
            out.append(f"G1 X{x:.5f} Y{y:.5f}")
        if long:
            a = np.radians(head)
            x, y = x + long * np.cos(a), y + long * np.sin(a)
            out.append(f"G1 X{x:.5f} Y{y:.5f}")
    out += ["G0 Z5", "M2"]
    return "\n".join(out) + "\n"


#: program lines of the long lines of :func:`_program`, how many lines before each the
#: lowest speed is looked for, and its value: sqrt(a L' / 2 + 2 a_t x 5 x 0.06), L' the
#: line less the tangent of the arc at its start (about 0.01 mm). (Before the 2.4 mm line
#: the speed climbs out of the turn at 1000 mm/s^2 and meets the lowered speeds 6 lines
#: before it: the window starts there.)
LONG_LINES = ((47, 8, 42.4), (88, 6, 54.7), (129, 8, 42.4))


def test_the_profile_slows_down_on_the_chords_before_the_long_line(tmp_path):
    """linuxcnc-sim: in the lines before each long line the lowest speed is the closed form
    of :data:`LONG_LINES`: 42.4 mm/s before a 1.2 mm line (2000 x 1.19 / 2 + 600), 54.7
    before the 2.4 mm one. (Without the lazy walks the chords' limit there, 0.06 / 1.02 ms
    = 58.82 mm/s.)"""
    from core.engine.profile import build_profile

    prog = tmp_path / "lazy.ngc"
    prog.write_text(_program())
    nc = Ncperf()
    ev = nc.evaluate(nc.extract(str(prog)), load_preset("linuxcnc-sim"))
    s = build_profile(ev).sample(0.001)
    for long, back, low in LONG_LINES:
        near = (s.line >= long - back) & (s.line < long)
        assert s.v[near].min() == pytest.approx(low, abs=1.0), long
