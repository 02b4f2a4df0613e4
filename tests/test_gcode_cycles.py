"""Canned cycles as the full G-code interpreter expands them, and CL data drilling cycles.

Every expected path below is a hand calculation (the derivation is in the comments), from
the LinuxCNC 2.9 documentation (docs/src/gcode/g-code.adoc, "G80-G89 Canned Cycles") and
its interpreter (src/emc/rs274ngc/interp_cycles.cc: convert_cycle_xy, CYCLE_MACRO,
convert_cycle_g73/g83, G83_RAPID_DELTA = 0.010 in, 0.254 mm), the Fanuc/Haas
manuals (initial level, point R, K repeats, G73/G83 d = parameters 5114/5115, set to
0.1 mm here through the machine setup's peck_clearance), the Haas G12/G13 description
and the SINUMERIK 840D cycles guide (CYCLE81-83, MCALL). The LinuxCNC-dialect programs
were checked against LinuxCNC's own interpreter (benchmarks/lcnc_oracle.py and its
canonical calls); the numbers here are written out by hand, not computed by ncperf.

Move kinds: 0 rapid, 1 line. Feeds in mm/s (F mm/min / 60; F in/min * 25.4 / 60).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from adapters.cl_data import read_cl
from adapters.gcode import read_gcode
from adapters.gcode.control import MachineSetup
from core import InputError

R, F = 0, 1  # rapid, feed line


def read(src: str, name: str = "t.ngc", **kw):
    return read_gcode(src.encode(), name, **kw)


def on_line(tp, line: int) -> np.ndarray:
    return np.flatnonzero(tp.line == line)


def assert_moves(tp, line: int, expected: list[tuple[int, float, float, float]]) -> np.ndarray:
    """The moves of source ``line`` are exactly ``expected`` (kind, x, y, z of the end);
    each starts where the one before it ends. Returns their indices."""
    idx = on_line(tp, line)
    got = [(int(tp.kind[k]), *np.round(tp.end[k], 6)) for k in idx]
    assert len(idx) == len(expected), f"line {line}: {got}"
    assert [int(tp.kind[k]) for k in idx] == [e[0] for e in expected], f"line {line}: {got}"
    ends = np.array([e[1:] for e in expected], dtype=float)
    assert np.allclose(tp.end[idx], ends, atol=1e-6), f"line {line}: {got}"
    assert np.allclose(tp.start[idx[1:]], tp.end[idx[:-1]], atol=1e-9)
    return idx


def feeds_of(tp, idx) -> np.ndarray:
    return np.array([tp.feed[k] for k in idx if tp.kind[k] == F])


# ============================================================================ LinuxCNC
def test_lcnc_g81_g98_then_g99_and_moves_between_holes():
    """G81: preliminary XY rapid at the current level, rapid to R, feed to Z, rapid to clear
    Z (G98: the Z before the cycles, 10; G99: R). Between holes the XY rapid runs at the
    level the last hole left the tool at (g-code.adoc, Preliminary and In-Between Motion)."""
    tp = read(
        "G21 G90 G17\nG0 X0 Y0 Z10\nG98 G81 X5 Y5 Z-3 R2 F120\nX15\nG99 X25\nY15\nG80\nG0 Z20\nM2\n"
    )
    # line 3: old Z = 10 > R = 2: XY at Z10, down to R, feed to -3, back to old Z 10 (G98)
    a = assert_moves(tp, 3, [(R, 5, 5, 10), (R, 5, 5, 2), (F, 5, 5, -3), (R, 5, 5, 10)])
    # line 4: the tool is at 10 again: same four moves at X15
    b = assert_moves(tp, 4, [(R, 15, 5, 10), (R, 15, 5, 2), (F, 15, 5, -3), (R, 15, 5, 10)])
    # line 5: G99 -> clear Z = R = 2; the XY move still starts from Z10 (current Z > R)
    c = assert_moves(tp, 5, [(R, 25, 5, 10), (R, 25, 5, 2), (F, 25, 5, -3), (R, 25, 5, 2)])
    # line 6: the tool is at R: the XY rapid runs at Z2, no extra Z move
    d = assert_moves(tp, 6, [(R, 25, 15, 2), (F, 25, 15, -3), (R, 25, 15, 2)])
    # line 8: after G80 a plain rapid
    assert_moves(tp, 8, [(R, 25, 15, 20)])
    cyc = np.concatenate([a, b, c, d])
    assert np.allclose(feeds_of(tp, cyc), 120 / 60)  # F120 mm/min = 2 mm/s
    assert np.all(np.isnan(tp.feed[cyc][tp.kind[cyc] == R]))
    assert np.all(tp.path_mode[cyc] == 1)  # the cycle stops at every step


def test_lcnc_g82_dwell_p_seconds_and_sticky():
    """G82 = G81 with a dwell of P seconds at the bottom; P is sticky on the next block."""
    tp = read(
        "G21 G90 G17\nG0 X0 Y0 Z10\nG99 G82 X5 Y0 Z-3 R2 P0.5 F120\nX10\nG80\nM2\n",
        dialect="linuxcnc",
        name="t.nc",
    )
    a = assert_moves(tp, 3, [(R, 5, 0, 10), (R, 5, 0, 2), (F, 5, 0, -3), (R, 5, 0, 2)])
    b = assert_moves(tp, 4, [(R, 10, 0, 2), (F, 10, 0, -3), (R, 10, 0, 2)])
    assert np.allclose(tp.dwell[a], [0, 0, 0.5, 0])  # 0.5 s at the bottom only
    assert np.allclose(tp.dwell[b], [0, 0.5, 0])


def test_lcnc_g83_peck_mm():
    """G83 (mm): feed down Q, rapid out to R, rapid back to 0.254 mm (0.010 in) above the
    depth reached, repeat; last feed to Z, rapid to clear Z (G99: R)."""
    tp = read("G21 G90 G17\nG0 X0 Y0 Z10\nG99 G83 X0 Y0 Z-5 R1 Q2 F60\nG80\nM2\n")
    idx = assert_moves(
        tp,
        3,
        [
            (R, 0, 0, 1),  # XY already there: straight down to R = 1
            (F, 0, 0, -1),  # peck 1: 1 - 2 = -1
            (R, 0, 0, 1),  # out to R
            (R, 0, 0, -0.746),  # back to -1 + 0.254
            (F, 0, 0, -3),  # peck 2: -1 - 2 = -3
            (R, 0, 0, 1),
            (R, 0, 0, -2.746),  # -3 + 0.254
            (F, 0, 0, -5),  # -3 - 2 = -5 is not above Z-5: the last feed to Z
            (R, 0, 0, 1),  # G99: clear Z = R
        ],
    )
    assert np.allclose(feeds_of(tp, idx), 1.0)  # F60 mm/min


def test_lcnc_g83_peck_inch_clearance_is_0_010_inch():
    """In G20 the peck clearance is 0.010 in (= 0.254 mm), the retract to R between pecks
    honours neither G98 nor G99, the final retract does (G98: old Z 0.5 in)."""
    tp = read("G20 G90 G17\nG0 X0 Y0 Z0.5\nG98 G83 X1 Y1 Z-0.3 R0.1 Q0.15 F5\nG80\nM2\n")
    i = 25.4
    idx = assert_moves(
        tp,
        3,
        [
            (R, 1 * i, 1 * i, 0.5 * i),  # XY at the initial level 0.5 in = 12.7 mm
            (R, 1 * i, 1 * i, 0.1 * i),  # R = 2.54 mm
            (F, 1 * i, 1 * i, -0.05 * i),  # 0.1 - 0.15 = -0.05 in = -1.27 mm
            (R, 1 * i, 1 * i, 0.1 * i),
            (R, 1 * i, 1 * i, -0.04 * i),  # -0.05 + 0.010 = -0.04 in = -1.016 mm
            (F, 1 * i, 1 * i, -0.2 * i),  # -0.05 - 0.15 = -0.2 in = -5.08 mm
            (R, 1 * i, 1 * i, 0.1 * i),
            (R, 1 * i, 1 * i, -0.19 * i),  # -0.2 + 0.010 = -0.19 in = -4.826 mm
            (F, 1 * i, 1 * i, -0.3 * i),  # -0.35 is below Z: last feed to -0.3 in
            (R, 1 * i, 1 * i, 0.5 * i),  # G98: back to 0.5 in
        ],
    )
    assert np.allclose(feeds_of(tp, idx), 5 * 25.4 / 60)  # F5 in/min = 2.11667 mm/s


def test_lcnc_g73_chip_break_mm_and_inch():
    """G73: after each peck a rapid up of only 0.254 mm (0.010 in), no trip to R."""
    tp = read("G21 G90 G17\nG0 X10 Y0 Z1\nG98 G73 X10 Y0 Z-2.5 R1 Q1 F60\nG80\nM2\n")
    assert_moves(
        tp,
        3,
        [
            # the tool is at R already (Z1): no preliminary move at all
            (F, 10, 0, 0),  # 1 - 1 = 0
            (R, 10, 0, 0.254),  # 0 + 0.254
            (F, 10, 0, -1),
            (R, 10, 0, -0.746),  # -1 + 0.254
            (F, 10, 0, -2),
            (R, 10, 0, -1.746),  # -2 + 0.254
            (F, 10, 0, -2.5),  # -3 is below Z-2.5: last feed to Z
            (R, 10, 0, 1),  # G98, old Z = 1 = R
        ],
    )
    tp = read("G20 G90 G17\nG0 X0 Y0 Z0.5\nG99 G73 X0 Y0 Z-0.25 R0.1 Q0.1 F10\nG80\nM2\n")
    assert_moves(
        tp,
        3,
        [
            (R, 0, 0, 2.54),  # R 0.1 in
            (F, 0, 0, 0.0),  # 0.1 - 0.1 = 0
            (R, 0, 0, 0.254),  # 0 + 0.010 in
            (F, 0, 0, -2.54),  # -0.1 in
            (R, 0, 0, -2.286),  # -0.09 in
            (F, 0, 0, -5.08),  # -0.2 in
            (R, 0, 0, -4.826),  # -0.19 in
            (F, 0, 0, -6.35),  # -0.3 in is below Z: last feed to -0.25 in
            (R, 0, 0, 2.54),  # G99: R
        ],
    )


def test_lcnc_boring_g85_g86_g89():
    """G85: feed in, feed out to R, rapid on to clear Z. G86: feed in, dwell P, rapid out.
    G89: feed in, dwell P, feed out all the way to clear Z (convert_cycle_g85/g86/g89)."""
    tp = read(
        "G21 G90 G17\n"
        "M3 S1000\n"
        "G0 X0 Y0 Z10\n"
        "G98 G85 X10 Y0 Z-4 R2 F120\n"
        "G86 X20 Z-4 R2 P0.25\n"
        "G89 X30 Z-4 R2 P1.5\n"
        "G80\n"
        "M2\n"
    )
    # old Z = 10 for all three (no non-cycle motion between them)
    a = assert_moves(
        tp, 4, [(R, 10, 0, 10), (R, 10, 0, 2), (F, 10, 0, -4), (F, 10, 0, 2), (R, 10, 0, 10)]
    )
    b = assert_moves(tp, 5, [(R, 20, 0, 10), (R, 20, 0, 2), (F, 20, 0, -4), (R, 20, 0, 10)])
    c = assert_moves(tp, 6, [(R, 30, 0, 10), (R, 30, 0, 2), (F, 30, 0, -4), (F, 30, 0, 10)])
    assert np.allclose(tp.dwell[a], 0)
    assert np.allclose(tp.dwell[b], [0, 0, 0.25, 0])
    assert np.allclose(tp.dwell[c], [0, 0, 1.5, 0])
    assert np.allclose(feeds_of(tp, np.concatenate([a, b, c])), 2.0)


def test_lcnc_tapping_g84_g74_feed_in_and_out():
    """G84 (M3) and G74 (M4): feed in, dwell P, feed out to clear Z (G98: the old Z)."""
    tp = read(
        "G21 G90 G17\n"
        "M3 S500\n"
        "G0 X0 Y0 Z10\n"
        "G98 G84 X40 Y0 Z-6 R3 P0.2 F150\n"
        "G80\n"
        "M4\n"
        "G99 G74 X50 Y0 Z-6 R3 P0.3 F150\n"
        "G80\n"
        "M2\n"
    )
    a = assert_moves(tp, 4, [(R, 40, 0, 10), (R, 40, 0, 3), (F, 40, 0, -6), (F, 40, 0, 10)])
    b = assert_moves(tp, 7, [(R, 50, 0, 10), (R, 50, 0, 3), (F, 50, 0, -6), (F, 50, 0, 3)])
    assert np.allclose(tp.dwell[a], [0, 0, 0.2, 0])
    assert np.allclose(tp.dwell[b], [0, 0, 0.3, 0])
    assert np.allclose(feeds_of(tp, np.concatenate([a, b])), 150 / 60)


@pytest.mark.parametrize(
    "spindle,fragment",
    [("M4 S500\n", "G84 tapping with the spindle turning the wrong way"),
     ("", "G84 tapping with the spindle stopped")],
)  # fmt: skip
def test_lcnc_g84_needs_the_spindle_clockwise(spindle, fragment):
    """LinuxCNC refuses G84 unless the spindle turns clockwise ("Spindle turning
    counterclockwise in G84", "Spindle not turning in G84")."""
    src = f"G21 G90\n{spindle}G0 X0 Y0 Z10\nG98 G84 X5 Y0 Z-2 R3 F60\nM2\n"
    n = 3 if not spindle else 4
    with pytest.raises(InputError) as info:
        read(src)
    assert str(info.value).startswith(f"t.ngc:{n}: {fragment}")


def test_lcnc_initial_z_below_r_rapids_straight_up_first():
    """Old Z below R: one rapid straight up to R before any XY move; clear Z is then R
    even under G98 (the old Z is below R)."""
    tp = read("G21 G90 G17\nG0 X0 Y0 Z0\nG98 G81 X5 Y0 Z-2 R3 F60\nX10\nG80\nM2\n")
    assert_moves(tp, 3, [(R, 0, 0, 3), (R, 5, 0, 3), (F, 5, 0, -2), (R, 5, 0, 3)])
    assert_moves(tp, 4, [(R, 10, 0, 3), (F, 10, 0, -2), (R, 10, 0, 3)])


def test_lcnc_g91_l_repeats_r_from_the_initial_z():
    """G91: X Y are increments repeated L times, R is relative to the Z the cycles started
    at (convert_cycle_xy: r = R + old_cc, old_cc the initial level), Z relative to R."""
    tp = read("G21 G90 G17\nG0 X0 Y0 Z5\nG91 G98 G81 X10 Z-4 R-3 L3 F100\nG90 G80\nM2\n")
    # R: 5 + (-3) = 2; bottom: 2 + (-4) = -2; G98: clear = old Z 5; holes at X10, 20, 30
    assert_moves(
        tp,
        3,
        [
            (R, 10, 0, 5), (R, 10, 0, 2), (F, 10, 0, -2), (R, 10, 0, 5),
            (R, 20, 0, 5), (R, 20, 0, 2), (F, 20, 0, -2), (R, 20, 0, 5),
            (R, 30, 0, 5), (R, 30, 0, 2), (F, 30, 0, -2), (R, 30, 0, 5),
        ],
    )  # fmt: skip


def test_lcnc_g91_second_block_r_still_from_the_initial_z():
    """After G99 leaves the tool at R (Z2), the next G91 block's sticky R-3 is still taken
    from the initial Z5 (cycle_il), not from the current Z: the holes keep R2 and Z-2."""
    tp = read(
        "G21 G90 G17\nG0 X0 Y0 Z5\nG91 G99 G81 X10 Z-4 R-3 L2 F100\nY10 L2\nG90 G80\nG0 Z20\nM2\n"
    )
    assert_moves(
        tp,
        3,
        [(R, 10, 0, 5), (R, 10, 0, 2), (F, 10, 0, -2), (R, 10, 0, 2),
         (R, 20, 0, 2), (F, 20, 0, -2), (R, 20, 0, 2)],
    )  # fmt: skip
    # 5 + (-3) = 2 again (not 2 + (-3) = -1); increments Y10 from (20, 0)
    assert_moves(
        tp,
        4,
        [(R, 20, 10, 2), (F, 20, 10, -2), (R, 20, 10, 2),
         (R, 20, 20, 2), (F, 20, 20, -2), (R, 20, 20, 2)],
    )  # fmt: skip
    assert_moves(tp, 6, [(R, 20, 20, 20)])


def test_lcnc_g80_cancels_the_cycle_and_its_words():
    """After G80 there is no motion mode (axis words are an error) and a new cycle needs
    its R (and Z) again; a G0 after G80 is a plain rapid."""
    tp = read("G21 G90\nG0 X0 Y0 Z10\nG98 G81 X5 Y0 Z-2 R3 F60\nG80\nG0 X10\nM2\n")
    assert_moves(tp, 5, [(R, 10, 0, 10)])
    with pytest.raises(InputError) as info:
        read("G21 G90\nG0 X0 Y0 Z10\nG98 G81 X5 Y0 Z-2 R3 F60\nG80\nX10\nM2\n")
    assert str(info.value).startswith("t.ngc:5: ")
    with pytest.raises(InputError) as info:
        read("G21 G90\nG0 X0 Y0 Z10\nG98 G81 X5 Y0 Z-2 R3 F60\nG80\nG81 X10 Z-2\nM2\n")
    assert str(info.value).startswith("t.ngc:5: canned cycle without its R plane")
    # a different cycle without R: LinuxCNC wants R whenever the motion mode changes
    with pytest.raises(InputError) as info:
        read("G21 G90\nG0 X0 Y0 Z10\nG98 G81 X5 Y0 Z-2 R3 F60\nG82 X10 P1\nM2\n")
    assert str(info.value).startswith("t.ngc:4: canned cycle without its R plane")


def test_lcnc_l0_is_an_error():
    """LinuxCNC: "L=0 is not allowed" (g-code.adoc, Repeat Cycle; convert_cycle:
    NCE_CANNOT_DO_ZERO_REPEATS_OF_CYCLE, "Cannot do zero repeats of cycle")."""
    with pytest.raises(InputError) as info:
        read("G21 G90\nG0 X0 Y0 Z10\nG98 G81 X5 Y0 Z-2 R3 L0 F60\nM2\n")
    assert str(info.value).startswith("t.ngc:3: ")


def test_lcnc_g86_needs_the_spindle_turning():
    """G86 stops the spindle and restarts it: "It is an error if the spindle is not turning
    before this cycle is executed" (g-code.adoc G86; NCE_SPINDLE_NOT_TURNING_IN_G86)."""
    with pytest.raises(InputError) as info:
        read("G21 G90\nG0 X0 Y0 Z10\nG98 G86 X5 Y0 Z-2 R3 P1 F60\nM2\n")
    assert str(info.value).startswith("t.ngc:3: ")


# ============================================================================ Fanuc
def test_fanuc_g91_k_repeats():
    """Fanuc G91: R = distance from the initial level, Z = distance from R; K holes, each
    X10 further; G99 returns to R, so holes 2 and 3 are approached at the R level."""
    tp = read(
        "G21 G90 G17\nG0 X0 Y0 Z10\nG91 G99 G81 X10 Z-5 R-8 K3 F100\nG90 G80\nG0 Z20\nM30\n",
        "t.nc",
        dialect="fanuc",
    )
    # R: 10 - 8 = 2; bottom: 2 - 5 = -3
    idx = assert_moves(
        tp,
        3,
        [
            (R, 10, 0, 10), (R, 10, 0, 2), (F, 10, 0, -3), (R, 10, 0, 2),
            (R, 20, 0, 2), (F, 20, 0, -3), (R, 20, 0, 2),
            (R, 30, 0, 2), (F, 30, 0, -3), (R, 30, 0, 2),
        ],
    )  # fmt: skip
    assert np.allclose(feeds_of(tp, idx), 100 / 60)
    assert_moves(tp, 5, [(R, 30, 0, 20)])


def test_fanuc_g91_next_block_r_still_from_the_initial_level():
    """Fanuc: "R: in incremental mode, the distance from the initial level to point R";
    the initial level (Z10) is kept until G80, so the second hole's R is again 10 - 8 = 2
    and its bottom 2 - 5 = -3, although G99 left the tool at R."""
    tp = read(
        "G21 G90 G17\nG0 X0 Y0 Z10\nG91 G99 G81 X10 Z-5 R-8 F100\nX10\nG90 G80\nM30\n",
        "t.nc",
        dialect="fanuc",
    )
    assert_moves(tp, 3, [(R, 10, 0, 10), (R, 10, 0, 2), (F, 10, 0, -3), (R, 10, 0, 2)])
    assert_moves(tp, 4, [(R, 20, 0, 2), (F, 20, 0, -3), (R, 20, 0, 2)])


def test_fanuc_k0_stores_data_and_r_z_stay_modal_until_g80():
    """K0: the cycle's data is stored, no hole. Z and R (and P, Q) stay in force across
    blocks and across a change of cycle (G81 -> G82 -> G83) until G80."""
    tp = read(
        "G21 G90 G17\n"
        "G0 X0 Y0 Z10\n"
        "G98 G81 Z-3 R2 K0 F100\n"
        "X5 Y5\n"
        "G82 X10 P500\n"
        "G83 X20 Q2\n"
        "G80\n"
        "G0 Z20\n"
        "M30\n",
        "t.nc",
        dialect="fanuc",
        setup=MachineSetup(peck_clearance=0.1),  # parameter 5115 = 0.1 mm
    )
    assert len(on_line(tp, 3)) == 0  # K0: nothing moves
    assert_moves(tp, 4, [(R, 5, 5, 10), (R, 5, 5, 2), (F, 5, 5, -3), (R, 5, 5, 10)])
    # G82: P500 = 500 ms dwell at the bottom
    g82 = assert_moves(tp, 5, [(R, 10, 5, 10), (R, 10, 5, 2), (F, 10, 5, -3), (R, 10, 5, 10)])
    assert np.allclose(tp.dwell[g82], [0, 0, 0.5, 0])
    # G83 Q2, d = 0.1 mm (parameter 5115): pecks to 0 and -2, back to 0.1 above each
    assert_moves(
        tp,
        6,
        [
            (R, 20, 5, 10),
            (R, 20, 5, 2),
            (F, 20, 5, 0),  # 2 - 2
            (R, 20, 5, 2),  # out to R
            (R, 20, 5, 0.1),  # down to 0 + 0.1
            (F, 20, 5, -2),  # 0 - 2
            (R, 20, 5, 2),
            (R, 20, 5, -1.9),  # -2 + 0.1
            (F, 20, 5, -3),  # -4 is below Z-3: last feed to Z
            (R, 20, 5, 10),  # G98: initial level
        ],
    )
    assert_moves(tp, 8, [(R, 20, 5, 20)])


def test_fanuc_peck_clearance_defaults_to_linuxcnc_with_a_notice():
    """Without the machine's parameter, G83 comes back to 0.254 mm above the last peck
    (LinuxCNC's value), and says so: Q2 from R2 pecks to 0, out to R, down to 0.254."""
    tp = read(
        "G21 G90\nG0 X0 Y0 Z10\nG98 G83 X1 Y1 Z-3 R2 Q2 F100\nG80\nM30\n", "t.nc", dialect="fanuc"
    )
    z = tp.end[on_line(tp, 3), 2]
    assert np.allclose(z[:6], [10, 2, 0, 2, 0.254, -2])
    assert any("peck_clearance" in n.message for n in tp.notices)


def test_fanuc_g80_forgets_r_and_z():
    with pytest.raises(InputError) as info:
        read(
            "G21 G90\nG0 X0 Y0 Z10\nG98 G81 X5 Y0 Z-2 R3 F60\nG80\nG81 X10\nM30\n",
            "t.nc",
            dialect="fanuc",
        )
    assert str(info.value).startswith("t.nc:5: canned cycle without its R plane")


def test_fanuc_g73_high_speed_peck_returns_d():
    """G73: after each peck Q a rapid up of d = 0.1 mm (parameter 5114), then on."""
    tp = read(
        "G21 G90 G17\nG0 X0 Y0 Z10\nG99 G73 X3 Y4 Z-2.5 R1 Q1 F120\nG80\nM30\n",
        "t.nc",
        dialect="fanuc",
        setup=MachineSetup(peck_clearance=0.1),  # parameter 5114 = 0.1 mm
    )
    assert_moves(
        tp,
        3,
        [
            (R, 3, 4, 10),
            (R, 3, 4, 1),
            (F, 3, 4, 0),  # 1 - 1
            (R, 3, 4, 0.1),  # 0 + 0.1
            (F, 3, 4, -1),
            (R, 3, 4, -0.9),  # -1 + 0.1
            (F, 3, 4, -2),
            (R, 3, 4, -1.9),  # -2 + 0.1
            (F, 3, 4, -2.5),  # -3 is below Z: last feed to Z
            (R, 3, 4, 1),  # G99: R
        ],
    )


def test_fanuc_tapping_g84_g74_feed_back_to_r_then_rapid_to_initial():
    """Fanuc G84/G74 (G98): feed to Z, dwell P (ms), feed back to point R, then rapid to the
    initial level. G99 ends at R."""
    tp = read(
        "G21 G90 G17\n"
        "G0 X0 Y0 Z10\n"
        "M3 S500\n"
        "G98 G84 X20 Y0 Z-6 R3 P200 F150\n"
        "G80\n"
        "M4\n"
        "G99 G74 X30 Y0 Z-6 R3 P300 F150\n"
        "G80\n"
        "M30\n",
        "t.nc",
        dialect="fanuc",
    )
    a = assert_moves(
        tp, 4, [(R, 20, 0, 10), (R, 20, 0, 3), (F, 20, 0, -6), (F, 20, 0, 3), (R, 20, 0, 10)]
    )
    assert math.isclose(tp.dwell[a[2]], 0.2)  # P200 = 0.2 s at the bottom
    b = assert_moves(tp, 7, [(R, 30, 0, 10), (R, 30, 0, 3), (F, 30, 0, -6), (F, 30, 0, 3)])
    assert math.isclose(tp.dwell[b[2]], 0.3)
    assert np.allclose(feeds_of(tp, np.concatenate([a, b])), 150 / 60)


def test_fanuc_g76_fine_boring_shifts_q_before_leaving_the_hole():
    """G76: feed to Z, dwell P, oriented spindle stop, shift by Q away from the wall (the
    direction is a machine parameter: 5101 RD1/RD2, Haas setting 27), rapid out to the
    initial level (G98) at the shifted position, shift back over the hole."""
    tp = read(
        "G21 G90 G17\nG0 X0 Y0 Z10\nM3 S500\nG98 G76 X10 Y10 Z-5 R2 Q0.5 P1000 F100\nG80\nM30\n",
        "t.nc",
        dialect="fanuc",
    )
    idx = on_line(tp, 4)
    ends = tp.end[idx]
    assert np.allclose(ends[:3], [[10, 10, 10], [10, 10, 2], [10, 10, -5]])
    assert list(tp.kind[idx[:3]]) == [R, R, F]
    assert math.isclose(tp.dwell[idx[2]], 1.0)  # P1000 ms
    assert len(idx) == 6, np.round(ends, 4).tolist()
    shift, out, back = ends[3], ends[4], ends[5]
    assert math.isclose(shift[2], -5) and math.isclose(math.dist(shift[:2], (10, 10)), 0.5)
    assert np.allclose(out, [shift[0], shift[1], 10]) and tp.kind[idx[4]] == R
    assert np.allclose(back, [10, 10, 10])


# ============================================================================ G12/G13
def test_g13_single_circle_with_z():
    """Haas G13 I5 Z-2 from the centre (X10 Y20): feed to Z-2, out to the radius (ncperf:
    a line along +X), one counter-clockwise circle, back to the centre."""
    tp = read(
        "G21 G90 G17\nG0 X10 Y20 Z5\nG1 F600\nG13 I5 Z-2\nG0 Z10\nM30\n", "t.nc", dialect="fanuc"
    )
    idx = assert_moves(
        tp,
        4,
        [(F, 10, 20, -2), (F, 15, 20, -2), (3, 15, 20, -2), (F, 10, 20, -2)],
    )
    assert np.allclose(tp.center[idx[2]], [10, 20, -2])  # circle centre = start point
    assert np.allclose(tp.start[idx[2]], [15, 20, -2])  # full circle: start = end, r = 5
    assert np.allclose(tp.feed[idx], 600 / 60)
    assert_moves(tp, 5, [(R, 10, 20, 10)])


def test_g12_stepped_radii_i_q_k():
    """Haas G12 I2 K6 Q2: circles of radius I = 2, then + Q each up to K = 6 (2, 4, 6), all
    clockwise about the start point, then back to the centre."""
    tp = read("G21 G90 G17\nG0 X10 Y20 Z-1\nG1 F300\nG12 I2 K6 Q2\nM30\n", "t.nc", dialect="fanuc")
    idx = assert_moves(
        tp,
        4,
        [
            (F, 12, 20, -1), (2, 12, 20, -1),  # r = 2
            (F, 14, 20, -1), (2, 14, 20, -1),  # r = 4
            (F, 16, 20, -1), (2, 16, 20, -1),  # r = 6 = K
            (F, 10, 20, -1),
        ],
    )  # fmt: skip
    for k in idx[1::2][:3]:
        assert np.allclose(tp.center[k], [10, 20, -1])


def test_g13_l_repeats_deeper_with_g91():
    """Haas: "L Loop count for repeating deeper cuts" -- MULTIPLE Z DEPTH PASS "using I only
    (G91 and L)": G91 G13 I3 Z-1 L3 from Z-2 cuts the circle at Z-3, Z-4 and Z-5."""
    tp = read(
        "G21 G90 G17\nG0 X10 Y20 Z-2\nG1 F300\nG91 G13 I3 Z-1 L3\nG90 G0 Z10\nM30\n",
        "t.nc",
        dialect="fanuc",
    )
    assert_moves(
        tp,
        4,
        [
            (F, 10, 20, -3), (F, 13, 20, -3), (3, 13, 20, -3), (F, 10, 20, -3),
            (F, 10, 20, -4), (F, 13, 20, -4), (3, 13, 20, -4), (F, 10, 20, -4),
            (F, 10, 20, -5), (F, 13, 20, -5), (3, 13, 20, -5), (F, 10, 20, -5),
        ],
    )  # fmt: skip


# ============================================================================ Siemens
def test_siemens_cycle81_and_cycle82_called_directly():
    """CYCLE81(RTP, RFP, SDIS, DP): rapid to RFP + SDIS, feed to DP, rapid to RTP.
    CYCLE82(RTP, RFP, SDIS, DP, DPR, DTB): depth RFP - DPR, dwell DTB s at the bottom."""
    tp = read(
        "G17 G90 G71\nG0 X0 Y0 Z50\nF300\nCYCLE81(10, 0, 2, -5)\nG0 X20\n"
        "CYCLE82(10, 0, 2, , 6, 1.5)\nM30\n",
        "t.mpf",
    )
    a = assert_moves(tp, 4, [(R, 0, 0, 2), (F, 0, 0, -5), (R, 0, 0, 10)])  # 0 + 2; DP; RTP
    b = assert_moves(tp, 6, [(R, 20, 0, 2), (F, 20, 0, -6), (R, 20, 0, 10)])  # 0 - 6
    assert np.allclose(tp.dwell[a], 0)
    assert np.allclose(tp.dwell[b], [0, 1.5, 0])
    assert np.allclose(feeds_of(tp, np.concatenate([a, b])), 300 / 60)
    assert np.all(tp.path_mode[np.concatenate([a, b])] == 1)


def test_siemens_mcall_modal_then_cancelled():
    """MCALL CYCLE81(...) runs the cycle after every following positioning block; MCALL
    alone cancels it."""
    tp = read(
        "G17 G90 G71\nG0 X0 Y0 Z50\nF300\nMCALL CYCLE81(10, 0, 2, -5)\nX30 Y10\nX40\nMCALL\n"
        "X50\nM30\n",
        dialect="siemens",
        name="t.nc",
    )
    assert len(on_line(tp, 4)) == 0  # MCALL itself drills nothing
    assert_moves(tp, 5, [(R, 30, 10, 50), (R, 30, 10, 2), (F, 30, 10, -5), (R, 30, 10, 10)])
    assert_moves(tp, 6, [(R, 40, 10, 10), (R, 40, 10, 2), (F, 40, 10, -5), (R, 40, 10, 10)])
    assert_moves(tp, 8, [(R, 50, 10, 10)])  # cancelled: a plain G0


def test_siemens_cycle83_chip_breaking_vari0():
    """CYCLE83(RTP, RFP, SDIS, DP, DPR, FDEP, FDPR, DAM, DTB, DTS, FRF, VARI=0): infeeds of
    FDPR = 5 below RFP (DAM 0: all equal), 1 mm back after each for chip breaking, the
    last infeed to DP, rapid to RTP."""
    tp = read(
        "G17 G90 G71\nG0 X60 Y10 Z20\nF300\nCYCLE83(10, 0, 2, -12, , , 5, , , , , 0)\nM30\n",
        "t.mpf",
    )
    idx = on_line(tp, 4)
    assert np.allclose(
        tp.end[idx, 2],
        [
            2,  # RFP + SDIS
            -5,  # first depth RFP - FDPR
            -4,  # 1 mm back
            -10,  # -5 - 5
            -9,
            -12,  # -15 would pass DP: the last infeed to DP
            10,  # RTP
        ],
    )
    assert np.allclose(tp.end[idx, :2], [60, 10])
    k = tp.kind[idx]
    assert k[0] == R and k[-1] == R and all(k[[1, 3, 5]] == F)


def test_siemens_cycle83_swarf_removal_vari1():
    """VARI=1: after each infeed back out to RFP + SDIS, then rapid down to just above the
    depth reached (the 840D computes this lead-in distance; at most 1 mm for shallow
    holes) and on with the next infeed."""
    tp = read(
        "G17 G90 G71\nG0 X0 Y0 Z20\nF300\nCYCLE83(10, 0, 2, -12, , -5, , , , , , 1)\nM30\n",
        "t.mpf",
    )
    idx = on_line(tp, 4)
    z = tp.end[idx, 2]
    k = tp.kind[idx]
    feeds = z[k == F]
    assert np.allclose(feeds, [-5, -10, -12])  # FDEP = -5 absolute, then 5 more, then DP
    assert np.allclose(z[[0, 2, 5, -1]], [2, 2, 2, 10])  # RFP + SDIS, between pecks; RTP
    for lead_in, reached in ((z[3], -5), (z[6], -10)):
        assert reached < lead_in <= reached + 1.0


# ============================================================================ CL data
def cl(text: str):
    return read_cl(text.encode(), "t.apt")


def test_cl_drill_cycle_solidworks_init_form():
    """SolidWorks CAM: CYCLE/INIT, CYCLE/DRILL,FEDTO d,MMPM f,RAPTO c,RTRCTO r,DWELL t;
    each GOTO is a hole top: rapid to c above it, feed to d below it (dwell t), rapid to
    r above it. CYCLE/OFF ends it: the next GOTO is a move again."""
    tp = cl(
        "UNITS/MM\n"
        "FEDRAT/600,MMPM\n"
        "RAPID\n"
        "GOTO/25,50,25\n"
        "CYCLE/INIT\n"
        "CYCLE/DRILL,FEDTO,5.,MMPM,120,RAPTO,3.,RTRCTO,25.,DWELL,0.5\n"
        "GOTO/25,50,0\n"
        "GOTO/40,50,0\n"
        "CYCLE/OFF\n"
        "GOTO/40,50,30\n"
    )
    a = assert_moves(tp, 7, [(R, 25, 50, 3), (F, 25, 50, -5), (R, 25, 50, 25)])  # 0+3, 0-5, 0+25
    b = assert_moves(tp, 8, [(R, 40, 50, 3), (F, 40, 50, -5), (R, 40, 50, 25)])
    assert np.allclose(tp.dwell[a], [0, 0.5, 0]) and np.allclose(tp.dwell[b], [0, 0.5, 0])
    assert np.allclose(feeds_of(tp, np.concatenate([a, b])), 120 / 60)  # the cycle's MMPM
    assert np.all(tp.path_mode[np.concatenate([a, b])] == 1)
    assert_moves(tp, 10, [(F, 40, 50, 30)])  # after CYCLE/OFF: a feed at FEDRAT 600
    assert math.isclose(tp.feed[on_line(tp, 10)[0]], 10.0)


def test_cl_deep2_pecks_with_full_retract():
    """CYCLE/DEEP2, FEDTO 12, 1STPECK 5, SUBPECK 2, RAPTO 3, RTRCTO 10: the first peck goes
    5 below the RAPTO level, the others 2 further each; after each a rapid out to RAPTO and
    back down to the depth reached; the last feed ends at FEDTO."""
    tp = cl(
        "UNITS/MM\nRAPID\nGOTO/60,50,40\n"
        "CYCLE/DEEP2,FEDTO,12.,1STPECK,5.,SUBPECK,2.,MMPM,60,RAPTO,3.,RTRCTO,10.\n"
        "GOTO/60,50,0\nCYCLE/OFF\n"
    )
    z = [3.0]  # rapid to RAPTO
    for depth in (-2, -4, -6, -8, -10):  # 3 - 5 = -2, then 2 deeper each, while above -12
        z += [depth, 3.0, depth]
    z += [-12, 10]  # last feed to 0 - 12, rapid to RTRCTO 10
    idx = on_line(tp, 5)
    assert np.allclose(tp.end[idx, 2], z)
    assert np.allclose(tp.end[idx, :2], [60, 50])
    kinds = [R] + [F, R, R] * 5 + [F, R]
    assert list(tp.kind[idx]) == kinds
    assert np.allclose(feeds_of(tp, idx), 1.0)


def test_cl_brkchp_stops_without_retract():
    """CYCLE/BRKCHP with STEP: the feed stops at each step (no retract); RTRCTO absent ->
    back to RAPTO."""
    tp = cl(
        "UNITS/MM\nFEDRAT/300,MMPM\nRAPID\nGOTO/0,0,20\n"
        "CYCLE/BRKCHP,FEDTO,10,STEP,4,RAPTO,2\nGOTO/5,5,0\nCYCLE/OFF\n"
    )
    # 2 - 4 = -2, -6; -10 is FEDTO itself: the last feed
    assert_moves(tp, 6, [(R, 5, 5, 2), (F, 5, 5, -2), (F, 5, 5, -6), (F, 5, 5, -10), (R, 5, 5, 2)])
    assert np.all(tp.path_mode[on_line(tp, 6)] == 1)
    assert np.allclose(feeds_of(tp, on_line(tp, 6)), 5.0)  # FEDRAT 300 before the cycle


def test_cl_drill_along_the_tool_axis():
    """A hole along the GOTO's tool axis i,j,k = (-1,0,0): RAPTO 3 towards -X from the top
    point, FEDTO 7.5 into +X, RTRCTO 25 back towards -X (SolidWorks wall holes)."""
    tp = cl(
        "UNITS/MM\nMULTAX/ON\nRAPID\nGOTO/-25,25,-30,-1,0,0\n"
        "CYCLE/INIT\nCYCLE/DRILL,FEDTO,7.5,MMPM,600,RAPTO,3.,RTRCTO,25.,DWELL,0\n"
        "GOTO/0,25,-30,-1,0,0\nCYCLE/OFF\n"
    )
    # top (0, 25, -30): clear 0 - 3 = -3; bottom 0 + 7.5; retract 0 - 25
    assert_moves(tp, 7, [(R, -3, 25, -30), (F, 7.5, 25, -30), (R, -25, 25, -30)])
