"""Time and peak memory of ``ncperf diagnose PROGRAM TRACE --svg OUT``, end to end.

Not a test: from the repository root (package installed) run

    python benchmarks/bench_diagnose.py [--runs 1] [--t-block 0.024]

The trace is a whole program's recording at 1 ms: the bundled Z-level cavity of G1 chords
(examples/zlevel_cavity_chords.ngc) run on the reference interpreter (refvm) on the
``siemens-840d`` preset with its block time raised to ``--t-block`` (the README's picture).
The diagnosis aligns every sample, fits all registered effects and writes the SVG; each run
is a fresh ``python -m core diagnose`` process, wall time measured around it and peak memory
the child's maximum resident set size (os.wait4).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

from bench_analyze import run_ncperf  # benchmarks/ is on sys.path: the script's own folder

from core import Ncperf, load_preset
from refvm import simulate, write_csv

ROOT = Path(__file__).resolve().parents[1]

PROGRAM = ROOT / "examples" / "zlevel_cavity_chords.ngc"
PRESET = "siemens-840d"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--t-block", type=float, default=0.024, help="the controller's block time, s")
    args = ap.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        trace_path = Path(tmp) / "trace.csv"
        t0 = time.perf_counter()
        toolpath = Ncperf().extract(str(PROGRAM))
        trace = simulate(
            toolpath, load_preset(PRESET), "block_cycle_time", {"t_block": args.t_block}
        )
        write_csv(trace, trace_path)
        t_vm = time.perf_counter() - t0
        n = len(trace.t)
        walls, rss = [], []
        for _ in range(args.runs):
            w, r = run_ncperf(
                "diagnose",
                str(PROGRAM),
                str(trace_path),
                "--machine",
                PRESET,
                "--svg",
                str(Path(tmp) / "out.svg"),
            )
            walls.append(w)
            rss.append(r)

    today = datetime.date.today().isoformat()
    print(
        f"ncperf diagnose PROGRAM TRACE --svg OUT, {today}, {platform.machine()}, "
        f"Python {platform.python_version()}, {os.cpu_count()} cores; "
        f"trace recorded in {t_vm:.1f} s by the reference interpreter\n"
    )
    print(
        "| program | trace samples | trace length [s] | wall best [s] | wall median [s] "
        "| peak RSS [MB] |"
    )
    print("|---|---|---|---|---|---|")
    print(
        f"| {PROGRAM.name} on {PRESET}, t_block {args.t_block * 1000:g} ms | {n:,} | "
        f"{trace.t[-1] - trace.t[0]:.0f} | {min(walls):.1f} | {statistics.median(walls):.1f} | "
        f"{max(rss):.0f} |"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
