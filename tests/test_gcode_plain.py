"""The interpreter's hand-over of plain runs to the vectorised reader changes nothing.

Programs that need the full interpreter (a parameter, a subroutine, a home return...) have
long runs of plain G0/G1/G2/G3 lines; the interpreter hands those to the vectorised reader
with its modal state (adapters/gcode/plain.py). Each program here is read twice -- block by
block, and with the hand-over -- and must give the same tool path, column by column, and
the same notices; the hand-over must have happened (else the check proves nothing).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from adapters.gcode import plain
from adapters.gcode.control import MachineSetup
from adapters.gcode.run import run_program

COLUMNS = (
    "kind", "start", "end", "center", "normal", "sweep", "feed", "line", "block", "tool",
    "path_mode", "dwell", "tolerance", "op_offsets",
)  # fmt: skip


def _run(lines: int, body) -> str:
    return "\n".join(body(k) for k in range(lines))


def _circle(k: int, r: float = 20.0, z: float | None = None) -> str:
    a = k * 0.05
    zz = f" Z{z:.3f}" if z is not None else ""
    return f"X{r * math.cos(a):.4f} Y{r * math.sin(a):.4f}{zz}"


PROGRAMS = {
    "parameter and G28": (
        "linuxcnc",
        "G21 G90 G64 P0.02\n#<d> = -1\nG0 X20 Y0 Z5\nG1 Z#<d> F400\n"
        + _run(80, _circle)
        + "\nG91 G28 Z0\nG90\nM2\n",
    ),
    "incremental, inch, arcs": (
        "linuxcnc",
        "G20 G17 G90\n#1 = 0.1\nG0 X0 Y0 Z0.2\nG1 Z0 F20\nG91\n"
        + _run(60, lambda k: "G1 X0.05 Y0.01" if k % 3 else "G2 X0.1 Y0 R0.05")
        + "\nG18\n"
        + _run(40, lambda k: "G2 X0.1 Z0 I0.05 K0")
        + "\nG17 G21 G90 G90.1\nG0 X20 Y0\n"
        + _run(
            40, lambda k: f"G3 X{20 * math.cos(k * 0.1):.4f} Y{20 * math.sin(k * 0.1):.4f} I0 J0"
        )
        # block by block again: the run's G90.1 must still hold (centre I0 J0 absolute)
        + "\n#2 = 20\nG3 X[#2] Y0 I0 J0\nG53 G0 Z0\nM2\n",
    ),
    "offsets, G92, G61 and exact stop": (
        "linuxcnc",
        "G21 G90\nG10 L2 P2 X100 Y50 Z-10\nG0 X0 Y0 Z5\nG1 Z0 F300\n"
        + _run(40, _circle)
        + "\nG55\n"
        + _run(40, _circle)
        + "\nG92 X0 Y0\nG61\n"
        + _run(40, lambda k: _circle(k, 5.0))
        + "\nG64 P0.05\n"
        + _run(40, lambda k: _circle(k, 8.0))
        + "\nG92.1\nG28\nM2\n",
    ),
    "subroutine called in a loop": (
        "linuxcnc",
        "G21 G90 G64\no100 sub\n"
        + _run(50, lambda k: _circle(k, 10.0 + k * 0.1))
        + "\no100 endsub\nG0 X10 Y0 Z5\nG1 Z0 F600\n#1 = 0\no101 while [#1 LT 3]\n"
        "G1 Z[-#1]\no100 call\n#1 = [#1 + 1]\no101 endwhile\nG0 Z10\nM2\n",
    ),
    "fanuc macro and M98": (
        "fanuc",
        "G21 G90 G17\n#100 = 2.\nG0 X20. Y0. Z5.\nM98 P1000 L2\nG91 G28 Z0.\nM30\n"
        "O1000\nG90 G1 Z-#100 F500.\n" + _run(60, _circle) + "\nG0 Z5.\nM99\n",
    ),
    "tool change inside and a dwell": (
        "fanuc",
        "G21 G90\nG0 X20. Y0. Z5.\nT1 M6\nG43 H1 Z5.\nG1 Z0 F300.\n"
        + _run(40, _circle)
        + "\nG4 P500\n"
        + _run(40, lambda k: _circle(k, 15.0))
        + "\nT2 M6\nG43 H2 Z5.\n"
        + _run(40, lambda k: _circle(k, 10.0))
        + "\nG28 G91 Z0.\nM30\n",
    ),
}


@pytest.mark.parametrize("name", PROGRAMS)
@pytest.mark.parametrize("default_exact", [False, True], ids=["continuous", "exact_stop"])
def test_plain_runs_give_the_block_by_block_path(name, default_exact, monkeypatch):
    dialect, text = PROGRAMS[name]
    setup = MachineSetup(
        default_path_mode="exact_stop" if default_exact else None,
        tool_length={1: 50.0, 2: 80.0},
    )
    data = text.encode()
    slow = run_program("t.nc", data, dialect, setup=setup, plain_runs=False)
    handed = []
    read = plain.PlainRuns.read

    def counting(self, i, j, state):
        out = read(self, i, j, state)
        handed.append(j - i)
        return out

    monkeypatch.setattr(plain.PlainRuns, "read", counting)
    fast = run_program("t.nc", data, dialect, setup=setup, plain_runs=True)
    assert handed and sum(handed) >= 80, handed  # the hand-over happened
    assert fast.n == slow.n
    for col in COLUMNS:
        a, b = getattr(fast, col), getattr(slow, col)
        if a.dtype.kind == "f":
            assert np.allclose(a, b, rtol=0, atol=1e-9, equal_nan=True), col
        else:
            assert np.array_equal(a, b), col
    assert [str(n) for n in fast.notices] == [str(n) for n in slow.notices]
