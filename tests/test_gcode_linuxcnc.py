"""ncperf's reading of G-code against LinuxCNC's own interpreter, line by line.

The oracle is LinuxCNC 2.9's rs274ngc (the system Python's ``gcode`` module, installed by
``scripts/setup_linuxcnc.sh``), driven by ``benchmarks/lcnc_oracle.py``: it sums the feed
and rapid length of every source line in machine coordinates and compares them with what
``ncperf analyze --json`` lists per line. Neither side imports the other: the oracle runs
ncperf as a command. Skipped, with the reason, where LinuxCNC is not installed.

* ``tests/programs/*.ngc``: programs written for this test, one per area (cycles,
  parameters and subroutines, offsets and home returns, arcs in inches, cutter
  compensation), plus a long plain program with a parameter and a G28 that goes through the
  interpreter's plain-run hand-over (generated here).
* ``NCPERF_CORPUS``: a folder of real programs (kept out of the repository; see
  ``benchmarks/corpus_read.py``): every program there that LinuxCNC reads must give the
  same path, rapids included.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ORACLE = ROOT / "benchmarks" / "lcnc_oracle.py"
PROGRAMS = ROOT / "tests" / "programs"
SYSTEM_PYTHON = "/usr/bin/python3"


def _linuxcnc_missing() -> str | None:
    if not Path(SYSTEM_PYTHON).exists():
        return f"{SYSTEM_PYTHON} is missing"
    r = subprocess.run([SYSTEM_PYTHON, "-c", "import gcode"], capture_output=True)
    if r.returncode:
        return "LinuxCNC's gcode module is not installed (scripts/setup_linuxcnc.sh)"
    return None


def _ncperf() -> str:
    exe = Path(sys.executable).with_name("ncperf")
    return str(exe) if exe.exists() else shutil.which("ncperf") or "ncperf"


def _oracle(files: list[Path]) -> list[dict]:
    why = _linuxcnc_missing()
    if why:
        pytest.skip(why)
    r = subprocess.run(
        [SYSTEM_PYTHON, str(ORACLE), _ncperf(), *map(str, files), "--json"],
        capture_output=True,
        text=True,
        timeout=1800,
    )
    assert r.returncode == 0, r.stderr[-2000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


def _hybrid_program(folder: Path) -> Path:
    """4000 plain lines around a circle between a parameter and a G28: the interpreter hands
    the plain lines to the vectorised reader."""
    lines = ["G21 G90 G64 P0.01", "#<z> = -1", "G0 X0 Y0 Z5", "G1 Z#<z> F500"]
    for k in range(4000):
        a = k * 0.01
        feed = " F2000" if k == 0 else ""
        lines.append(f"X{50 + 40 * math.cos(a):.4f} Y{50 + 40 * math.sin(a):.4f}{feed}")
    lines += ["G91 G28 Z0", "G90", "M2"]
    p = folder / "hybrid.ngc"
    p.write_text("\n".join(lines) + "\n")
    return p


def test_written_programs_read_as_linuxcnc_reads_them(tmp_path):
    """Every program of tests/programs (but the subroutine file, which has no moves of its
    own) gives LinuxCNC's path, line by line, feed and rapids."""
    for p in PROGRAMS.glob("*.ngc"):
        shutil.copy(p, tmp_path / p.name)
    files = [tmp_path / p.name for p in sorted(PROGRAMS.glob("*.ngc")) if p.name != "pocket.ngc"]
    files.append(_hybrid_program(tmp_path))
    results = _oracle(files)
    assert [(Path(r["file"]).name, r["status"]) for r in results] == [
        (f.name, "same") for f in files
    ], "\n".join(f"{r['file']}: {r['status']} {r['text']}" for r in results)


def test_corpus_programs_that_linuxcnc_reads_read_the_same():
    """Every program of the real corpus (NCPERF_CORPUS) that LinuxCNC reads gives the same
    path in ncperf, rapids included."""
    folder = os.environ.get("NCPERF_CORPUS")
    if not folder or not Path(folder).is_dir():
        pytest.skip("NCPERF_CORPUS (a folder of real programs, kept out of the repository) not set")
    exts = {".ngc", ".nc", ".tap", ".gcode", ".cnc", ".txt", ".mpf", ".spf", ".nci"}
    files = sorted(p for p in Path(folder).rglob("*") if p.is_file() and p.suffix.lower() in exts)
    results = _oracle(files)
    bad = [r for r in results if r["status"] in ("diff", "rapids", "miss")]
    assert not bad, "\n".join(f"{r['file']}: {r['status']} {r['text']}" for r in bad)
