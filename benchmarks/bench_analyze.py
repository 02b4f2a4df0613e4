"""Time and peak memory of ``ncperf analyze PROGRAM --svg OUT``, end to end.

Not a test: from the repository root (package installed) run

    python benchmarks/bench_analyze.py [--runs 3] [--moves 1000000]

Programs: ``stellabee1.ngc`` (169k lines, LinuxCNC's trajectory-planner test suite, in
../shared; skipped when absent), the same with a parameter and a G28 (read by the full
interpreter, which hands the plain lines to the vectorised reader), and a generated zig-zag
finishing raster of 1,000,000 moves (benchmarks/gen_finishing.py). Each run is a fresh
``python -m core analyze`` process; wall time is measured around it and peak memory is the
child's maximum resident set size (os.wait4). A second table splits one in-process run into
its stages.

Target (issue 2): under 5 s and under 1 GB for the 1M-move program on one core.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from gen_finishing import generate  # benchmarks/ is on sys.path: the script's own folder

ROOT = Path(__file__).resolve().parents[1]

STELLABEE = ROOT.parent / "shared" / "data" / "gcode" / "linuxcnc-tp-tests" / "stellabee1.ngc"


def run_ncperf(*args: str) -> tuple[float, float]:
    """Wall time (s) and peak RSS (MB) of one ``ncperf ARGS`` process."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "core", *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    if status != 0:
        raise SystemExit(f"ncperf {' '.join(args)} failed with status {status}")
    return wall, usage.ru_maxrss / 1024.0


def run_cli(program: Path, svg: Path) -> tuple[float, float]:
    """Wall time (s) and peak RSS (MB) of one ``ncperf analyze`` process."""
    return run_ncperf("analyze", str(program), "--svg", str(svg))


def stages(program: Path, svg: Path) -> dict[str, float]:
    """Seconds per stage of one in-process run."""
    from core import FileTarget, Ncperf, build_annotations, load_preset
    from core.engine.profile import build_profile

    t = {}
    t0 = time.perf_counter()
    nc = Ncperf()
    tp = nc.extract(str(program))
    t["A1 extract (parse)"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    ev = nc.evaluate(tp, load_preset("siemens-840d"))
    t["A2 evaluate (models)"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    pr = build_profile(ev)
    t["feed profile (look-ahead, S-curve ramps)"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    ann = build_annotations(ev, pr)
    t["annotations + zones"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    nc.display(tp, ann, FileTarget(str(svg)))
    t["A3 display (SVG)"] = time.perf_counter() - t0
    t["moves"] = tp.n
    return t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--moves", type=int, default=1_000_000)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        programs = []
        if STELLABEE.exists():
            programs.append(("stellabee1.ngc (169k lines)", STELLABEE))
            # the same program with a parameter at the top and a home return at the end: the
            # full interpreter reads it, handing its plain runs to the vectorised reader
            mixed = tmp / "stellabee1_macro_g28.ngc"
            data = STELLABEE.read_bytes()
            mixed.write_bytes(b"#<depth> = 1.5\n" + data.replace(b"M2", b"G28\nM2"))
            programs.append(("stellabee1 + #<depth> and G28 (full interpreter)", mixed))
        gen = tmp / "finishing.nc"
        n = generate(str(gen), args.moves)
        programs.append((f"generated raster ({n:,} moves)", gen))
        print(
            f"ncperf analyze PROGRAM --svg OUT, {datetime.date.today()}, "
            f"{platform.processor() or platform.machine()}, Python {platform.python_version()}, "
            f"{os.cpu_count()} cores; best / median of {args.runs} runs"
        )
        print()
        print("| program | moves | wall best [s] | wall median [s] | peak RSS [MB] | SVG [MB] |")
        print("|---|---|---|---|---|---|")
        for name, prog in programs:
            svg = tmp / "out.svg"
            walls, rss = [], []
            for _ in range(args.runs):
                w, r = run_cli(prog, svg)
                walls.append(w)
                rss.append(r)
            st = stages(prog, svg)
            print(
                f"| {name} | {st['moves']:,} | {min(walls):.2f} | {statistics.median(walls):.2f} "
                f"| {max(rss):.0f} | {svg.stat().st_size / 1e6:.1f} |"
            )
            programs_stages = st
        print()
        print("Stages of the last program, one in-process run:")
        print()
        print("| stage | s |")
        print("|---|---|")
        for k, v in programs_stages.items():
            if k != "moves":
                print(f"| {k} | {v:.2f} |")


if __name__ == "__main__":
    main()
