"""Time and peak memory of ``ncperf diagnose PROGRAM TRACE --svg OUT``, end to end.

Not a test: from the repository root (package installed) run

    python benchmarks/bench_diagnose.py [--runs 1] [--t-block 0.024] [--jobs N]

The trace is a whole program's recording at 1 ms: the bundled Z-level cavity of G1 chords
(examples/zlevel_cavity_chords.ngc) run on the reference interpreter (refvm) on the
``siemens-840d`` preset with its block time raised to ``--t-block`` (the README's picture).
The diagnosis aligns every sample, fits all registered effects (on ``--jobs`` worker
processes; default, as the command's: the CPUs this process may use) and writes the SVG;
each run is a fresh ``python -m core diagnose`` process, wall time measured around it.

Memory, three figures: the ncperf process's own peak resident set (os.wait4: exact, but
without its workers); the sum of every process's peak resident set, the workers' read from
/proc every SAMPLE_S (an upper bound: the pages a worker shares with the process it was
forked from count in both, and peaks at different times are added); and the peak of the
process tree's proportional set size, sampled (shared pages divided among the processes
that share them: what the tree held at once, short of a peak between two samples). Without
/proc (not Linux) only the first. The sampling slows the diagnosis it watches (reading a
process's smaps_rollup walks its page tables: 0.4 s of 10 s on this project's VM,
2026-11-28), so the ``--runs`` timed runs are not sampled and one more run is, for the
workers' memory only.
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from bench_analyze import ncperf  # benchmarks/ is on sys.path: the script's own folder

from core import Ncperf, load_preset
from core.model.workers import default_jobs
from refvm import simulate, write_csv

ROOT = Path(__file__).resolve().parents[1]

PROGRAM = ROOT / "examples" / "zlevel_cavity_chords.ngc"
PRESET = "siemens-840d"
#: How often the process tree's memory is read from /proc (s): a few reads of
#: /proc/PID/smaps_rollup per sample, well under 1 % of a core.
SAMPLE_S = 0.1
PROC = Path("/proc")


@dataclass
class Usage:
    """What :func:`run_tree` measured (memory in MB; NaN: not measured)."""

    wall: float
    rss: float
    rss_sum: float = math.nan
    pss_tree: float = math.nan
    workers: int = 0


def _children(pid: int) -> list[int]:
    """The processes whose parent is ``pid`` (from /proc/*/stat)."""
    out = []
    for d in PROC.iterdir():
        if not d.name.isdigit():
            continue
        try:
            stat = (d / "stat").read_text()
        except OSError:  # gone meanwhile
            continue
        if int(stat.rpartition(")")[2].split()[1]) == pid:
            out.append(int(d.name))
    return out


def _kb(path: Path, key: str) -> float:
    """A "Key:  N kB" line of a /proc file, in kB; NaN when the process is gone."""
    try:
        for line in path.read_text().splitlines():
            if line.startswith(key):
                return float(line.split()[1])
    except OSError:
        pass
    return math.nan


def run_tree(cmd: list[str], *, sample: bool = True) -> Usage:
    """Wall time and memory of one process and the workers it forks (see the module
    docstring; ``sample`` False: the process's own peak only, nothing read from /proc while
    it runs); its output is thrown away."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    hwm: dict[int, float] = {}  # each worker's peak RSS seen (kB)
    pss_peak = [math.nan]
    done = threading.Event()

    def sample() -> None:
        while not done.wait(SAMPLE_S):
            workers = _children(proc.pid)
            pss = _kb(PROC / str(proc.pid) / "smaps_rollup", "Pss:")
            for w in workers:
                peak = _kb(PROC / str(w) / "status", "VmHWM:")
                if not math.isnan(peak):
                    hwm[w] = max(hwm.get(w, 0.0), peak)
                pss += _kb(PROC / str(w) / "smaps_rollup", "Pss:")
            if not math.isnan(pss):
                pss_peak[0] = pss if math.isnan(pss_peak[0]) else max(pss_peak[0], pss)

    sampler = threading.Thread(target=sample, daemon=True)
    if sample and PROC.joinpath("self", "smaps_rollup").exists():
        sampler.start()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    done.set()
    if sampler.is_alive():
        sampler.join()
    if status != 0:
        raise SystemExit(f"{' '.join(cmd)} failed with status {status}")
    rss = usage.ru_maxrss / 1024.0
    if not sampler.ident:
        return Usage(wall, rss)
    return Usage(wall, rss, rss + sum(hwm.values()) / 1024.0, pss_peak[0] / 1024.0, len(hwm))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--t-block", type=float, default=0.024, help="the controller's block time, s")
    ap.add_argument(
        "--jobs",
        type=int,
        default=default_jobs(),
        help="ncperf diagnose --jobs (default: the CPUs this process may use, as the command's)",
    )
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
        cmd = ncperf(
            "diagnose",
            str(PROGRAM),
            str(trace_path),
            "--machine",
            PRESET,
            "--svg",
            str(Path(tmp) / "out.svg"),
            "--jobs",
            str(args.jobs),
        )
        runs = [run_tree(cmd, sample=False) for _ in range(args.runs)]
        watched = run_tree(cmd)  # the workers' memory (not timed: the sampling slows it)
    walls = [u.wall for u in runs]

    today = datetime.date.today().isoformat()
    print(
        f"ncperf diagnose PROGRAM TRACE --svg OUT, {today}, {platform.machine()}, "
        f"Python {platform.python_version()}, {os.cpu_count()} cores; "
        f"trace recorded in {t_vm:.1f} s by the reference interpreter\n"
    )
    print(
        "| program | trace samples | trace length [s] | jobs (workers seen) | wall best [s] "
        "| wall median [s] | peak RSS, ncperf process [MB] | peak RSS summed, with workers "
        "[MB] | peak PSS, process tree [MB] |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    print(
        f"| {PROGRAM.name} on {PRESET}, t_block {args.t_block * 1000:g} ms | {n:,} | "
        f"{trace.t[-1] - trace.t[0]:.0f} | {args.jobs} ({watched.workers}) | "
        f"{min(walls):.1f} | {statistics.median(walls):.1f} | "
        f"{max(u.rss for u in [*runs, watched]):.0f} | {_mb(watched.rss_sum)} | "
        f"{_mb(watched.pss_tree)} |"
    )
    print(
        f"\nWall: {args.runs} run(s) not watched. Memory: the ncperf process's peak RSS from "
        "os.wait4 (without its workers; every run); the sum of every process's peak RSS, the "
        f"workers' sampled every {SAMPLE_S:g} s (an upper bound: pages shared with the parent "
        "count twice), and the process tree's peak proportional set size, sampled every "
        f"{SAMPLE_S:g} s, both of one more run (not timed: the sampling slows it)."
    )
    return 0


def _mb(x: float) -> str:
    return "n/a" if math.isnan(x) else f"{x:.0f}"


if __name__ == "__main__":
    sys.exit(main())
