"""Time and peak memory of ``ncperf analyze``, beside LinuxCNC's own interpreter, in one run.

Not a test: from the repository root (package installed) run

    python benchmarks/bench_analyze.py [--runs 3] [--scaling 100000,1000000,5000000]

Three tables, all measured in this one run (ratios are what count on a shared VM, whose speed
changes from day to day):

1. ``stellabee1.ngc`` (169k lines, LinuxCNC's trajectory-planner test suite, in ../shared;
   skipped when absent): ``ncperf analyze`` (parse, the three models, the full profile,
   zones, the summary) and ``rs274 -g PROGRAM OUT`` (LinuxCNC 2.9's C++ interpreter reading
   the program and writing its canonical calls; installed by scripts/setup_linuxcnc.sh),
   run in turns, the ratio per turn; median of ``--runs``.
2. Scaling: generated zig-zag finishing rasters (benchmarks/gen_finishing.py) of 0.1M, 1M
   and 5M moves, ``ncperf analyze PROGRAM --svg OUT``: wall time, peak resident memory,
   microseconds and bytes per move (linear growth keeps both columns flat).
3. Start-up: ``ncperf --help`` and ``ncperf machines`` beside ``python -c pass``.

Every ncperf run is a fresh ``python -m core`` process, started in the temporary folder (the
installed ncperf, not the source tree a non-editable install would leave without its C
kernels): wall time around it, peak memory the child's maximum resident set size
(os.wait4). ncperf's bytecode is written first (as ``pip install .`` does), so no run pays
for compiling its modules. The header says whether the C kernels (core/model/native.py)
load. A last table splits one in-process run of the 1M raster into its stages.

Bars (issue 13, on this machine, as ratios in one run): stellabee1 at most 0.8 x rs274;
1M moves with --svg under 2.5 s and 500 MB; 5M under 2 GB, time linear; --help and
machines under 0.15 s.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from gen_finishing import generate  # benchmarks/ is on sys.path: the script's own folder

ROOT = Path(__file__).resolve().parents[1]

STELLABEE = ROOT.parent / "shared" / "data" / "gcode" / "linuxcnc-tp-tests" / "stellabee1.ngc"


def run(cmd: list[str]) -> tuple[float, float]:
    """Wall time (s) and peak RSS (MB) of one process; its output is thrown away."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        cmd,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        cwd=tempfile.gettempdir(),  # the installed ncperf, not the source tree beside it
    )
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    if status != 0:
        raise SystemExit(f"{' '.join(cmd)} failed with status {status}")
    return wall, usage.ru_maxrss / 1024.0


def compile_bytecode() -> None:
    """Write the bytecode of ncperf's packages, as ``pip install .`` does for a user (an
    editable install, or ``PYTHONDONTWRITEBYTECODE`` set, would otherwise make every timed
    run compile the modules it imports: 0.2 s of the stellabee1 run on 2026-11-28)."""
    import importlib.util

    folders = []
    for package in ("core", "adapters", "plugins"):
        spec = importlib.util.find_spec(package)
        if spec is not None and spec.submodule_search_locations:
            folders.extend(spec.submodule_search_locations)
    subprocess.run(
        [sys.executable, "-m", "compileall", "-q", *folders],
        check=True,
        stdout=subprocess.DEVNULL,
    )


def ncperf(*args: str) -> list[str]:
    return [sys.executable, "-m", "core", *args]


def run_ncperf(*args: str) -> tuple[float, float]:
    """Wall time (s) and peak RSS (MB) of one ``ncperf ARGS`` process (bench_diagnose.py
    times its runs with it too)."""
    return run(ncperf(*args))


def stages(program: Path, svg: Path) -> dict[str, float]:
    """Seconds per stage of one in-process run."""
    from core import FileTarget, Ncperf, build_annotations, load_preset
    from core.engine.profile import build_profile
    from core.model.heap import keep_freed_memory

    keep_freed_memory()  # as the command line does
    t = {}
    t0 = time.perf_counter()
    nc = Ncperf()
    t["plugin manager (imports the plugins)"] = time.perf_counter() - t0
    t0 = time.perf_counter()
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
    return t


def versus_rs274(runs: int, tmp: Path) -> None:
    print("## stellabee1.ngc: ncperf analyze beside LinuxCNC's rs274, in turns")
    print()
    rs274 = shutil.which("rs274")
    if not STELLABEE.exists() or rs274 is None:
        missing = "../shared" if not STELLABEE.exists() else "rs274 (scripts/setup_linuxcnc.sh)"
        print(f"skipped: {missing} not found")
        print()
        return
    ours, theirs, ratios, rss = [], [], [], []
    for _ in range(runs):
        w_rs, _ = run([rs274, "-g", str(STELLABEE), str(tmp / "canon.out")])
        w_nc, r_nc = run_ncperf("analyze", str(STELLABEE))
        ours.append(w_nc)
        theirs.append(w_rs)
        ratios.append(w_nc / w_rs)
        rss.append(r_nc)
    print("| run | rs274 -g [s] | ncperf analyze [s] | ratio | ncperf peak RSS [MB] |")
    print("|---|---|---|---|---|")
    for k in range(runs):
        print(f"| {k + 1} | {theirs[k]:.2f} | {ours[k]:.2f} | {ratios[k]:.2f} | {rss[k]:.0f} |")
    print(
        f"| median | {statistics.median(theirs):.2f} | {statistics.median(ours):.2f} "
        f"| {statistics.median(ratios):.2f} | {statistics.median(rss):.0f} |"
    )
    print()


def scaling(sizes: list[int], runs: int, tmp: Path) -> Path | None:
    print("## Scaling: generated finishing rasters, ncperf analyze PROGRAM --svg OUT")
    print()
    print(
        "| moves | file [MB] | runs | wall median [s] | peak RSS [MB] | us per move "
        "| bytes per move (peak) |"
    )
    print("|---|---|---|---|---|---|---|")
    one_million = None
    for size in sizes:
        prog = tmp / f"raster_{size}.nc"
        n = generate(str(prog), size)
        k = runs if size <= 1_000_000 else 1  # 5M: one run (about half a minute)
        walls, peaks = [], []
        for _ in range(k):
            w, r = run_ncperf("analyze", str(prog), "--svg", str(tmp / "out.svg"))
            walls.append(w)
            peaks.append(r)
        w, r = statistics.median(walls), max(peaks)
        print(
            f"| {n:,} | {prog.stat().st_size / 1e6:.0f} | {k} | {w:.2f} | {r:.0f} "
            f"| {w / n * 1e6:.2f} | {r * 2**20 / n:.0f} |"
        )
        if size == 1_000_000:
            one_million = prog
        else:
            prog.unlink()
    print()
    return one_million


def startup(runs: int) -> None:
    print(f"## Start-up (median of {runs})")
    print()
    print("| command | wall median [s] |")
    print("|---|---|")
    for label, cmd in (
        ("python -c pass (the interpreter alone)", [sys.executable, "-c", "pass"]),
        ("ncperf --help", ncperf("--help")),
        ("ncperf machines", ncperf("machines")),
    ):
        walls = [run(cmd)[0] for _ in range(runs)]
        print(f"| `{label}` | {statistics.median(walls):.3f} |")
    print()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument(
        "--scaling",
        default="100000,1000000,5000000",
        help="raster sizes in moves, comma separated (default 0.1M, 1M, 5M)",
    )
    args = ap.parse_args()
    print(
        f"ncperf analyze, {datetime.date.today()}, "
        f"{platform.processor() or platform.machine()}, Python {platform.python_version()}, "
        f"{os.cpu_count()} cores"
    )
    print()
    kernels = subprocess.run(
        [sys.executable, "-c", "from core.model.native import library_path, native\n"
         "print(library_path() if native() else 'not built: numpy code')"],
        capture_output=True, text=True, cwd=tempfile.gettempdir(), check=True,
    ).stdout.strip()  # fmt: skip
    print(f"C kernels (core/model/native.py): {kernels}")
    print()
    compile_bytecode()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        versus_rs274(args.runs, tmp)
        sizes = [int(s) for s in args.scaling.split(",") if s.strip()]
        prog = scaling(sizes, args.runs, tmp)
        startup(max(args.runs, 11))
        if prog is not None:
            print("## Stages of one in-process run of the 1M raster")
            print()
            print("| stage | s |")
            print("|---|---|")
            for k, v in stages(prog, tmp / "out.svg").items():
                print(f"| {k} | {v:.2f} |")


if __name__ == "__main__":
    main()
