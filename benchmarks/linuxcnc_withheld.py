"""Withheld effects on a real controller: LinuxCNC 2.9 runs with a changed setting that
``ncperf diagnose`` is not told about. Does it name the change, and how far does the gap
shrink once it is modelled?

Not a test: ``PYTHONPATH=. python benchmarks/linuxcnc_withheld.py [--cache DIR]`` (needs
../shared and LinuxCNC, installed by ``../shared/tools/linuxcnc/install_linuxcnc.sh``; the
runs are sequential and in real time, about 40 s per variant).

Four programs of the visible suite (corners, arcs with curvature jumps, short blocks,
line-arc-line) run on the harness's default mill with one setting changed per variant: the
feed override, the axes' acceleration, the path tolerance the controller blends corners with
(the program still says G64 P0.01), the servo period. The diagnosis is given the unchanged
programs, the traces and the ``linuxcnc-sim`` preset (the default mill, with what the suite
diagnosis folded in); it fits every effect on alternate programs and measures it on the
others. The traces are cached in ``--cache``.
"""

from __future__ import annotations

import argparse
import datetime
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

from core import Ncperf
from core.align import align
from core.diagnose import diagnose_cases
from core.effects import setup_for
from core.machine import resolve_machine

SHARED = Path(__file__).resolve().parents[2] / "shared"
SUITE = SHARED / "data" / "linuxcnc" / "suite"
HARNESS = SHARED / "tools" / "linuxcnc" / "run_trace.sh"
INI = SHARED / "tools" / "linuxcnc" / "machines" / "default_mill_mm.ini"
PROGRAMS = (
    "02_polygons_f4000",
    "04_semicircle_spiral_f3000",
    "05_collinear_points_f6000",
    "09_line_arc_line_f5000",
)
ACCEL = [
    f"{sec}.MAX_ACCELERATION=1200"
    for sec in ("AXIS_X", "AXIS_Y", "AXIS_Z", "JOINT_0", "JOINT_1", "JOINT_2")
]
ACCEL += ["TRAJ.MAX_LINEAR_ACCELERATION=1200", "TRAJ.DEFAULT_LINEAR_ACCELERATION=1200"]

#: (label, effect expected, its true parameters, --set overrides, feed override, G64 P run)
VARIANTS = (
    ("unchanged", None, {}, [], 1.0, None),
    ("feed override 80 %", "feed_override", {"scale": 0.8}, [], 0.8, None),
    (
        "axis acceleration 1200 mm/s^2 (preset 2000)",
        "axis_dynamics",
        {"accel_scale": 0.6},
        ACCEL,
        1.0,
        None,
    ),
    (
        "corners blended with G64 P0.05 (program P0.01)",
        "corner_tolerance",
        {"tolerance": 0.05},
        [],
        1.0,
        "0.05",
    ),
    (
        "corners blended with G64 P0.002 (program P0.01)",
        "corner_tolerance",
        {"tolerance": 0.002},
        [],
        1.0,
        "0.002",
    ),
    (
        "servo period 4 ms (preset 1 ms)",
        "block_cycle_time",
        {"t_block": 0.00408},
        ["EMCMOT.SERVO_PERIOD=4000000"],
        1.0,
        None,
    ),
)


def run(prog: Path, out: Path, sets: list[str], override: float, tol: str | None) -> None:
    """Record one trace with the harness (skipped when ``out`` exists)."""
    if out.exists():
        return
    src = prog
    if tol is not None:
        src = out.with_suffix(".ngc")
        text = re.sub(r"G64 P0\.01", f"G64 P{tol}", prog.read_text())
        src.write_text(text)
    cmd = ["bash", str(HARNESS), str(src), str(INI), str(out) + ".part"]
    for s in sets:
        cmd += ["--set", s]
    if override != 1.0:
        cmd += ["--feed-override", str(override)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{src}: the LinuxCNC harness failed:\n{r.stderr[-2000:]}")
    Path(str(out) + ".part").rename(out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--cache",
        default="/tmp/ncperf-linuxcnc-withheld",
        help="where the traces are kept between runs",
    )
    args = ap.parse_args()
    if not SUITE.exists():
        print(f"{SUITE} not found: this benchmark needs ../shared", file=sys.stderr)
        return 1
    if shutil.which("linuxcnc") is None:
        print(
            "LinuxCNC is not installed: bash ../shared/tools/linuxcnc/install_linuxcnc.sh",
            file=sys.stderr,
        )
        return 1
    cache = Path(args.cache)
    cache.mkdir(parents=True, exist_ok=True)
    nc = Ncperf()
    effects = nc.effects()
    machine = resolve_machine("linuxcnc-sim")
    base = setup_for(machine, effects, ramps=True)
    tps = {p: nc.extract(str(SUITE / f"{p}.ngc")) for p in PROGRAMS}
    print(
        f"Withheld settings on LinuxCNC 2.9 (real planner, harness default mill), "
        f"{datetime.date.today()}; programs: {', '.join(PROGRAMS)}; model: preset "
        f"linuxcnc-sim"
    )
    print()
    print(
        "| run with | expected effect | ranked first | held-out gap before [mm/min] | "
        "after | removed | fitted (true) | wall [s] |"
    )
    print("|---|---|---|---|---|---|---|---|")
    score = []
    for k, (label, effect, params, sets, override, tol) in enumerate(VARIANTS):
        t0 = time.perf_counter()
        cases = []
        for p in PROGRAMS:
            out = cache / f"v{k}_{p}.csv"
            run(SUITE / f"{p}.ngc", out, sets, override, tol)
            cases.append((tps[p], [align(tps[p], nc.read_trace(str(out)))], [p]))
        d = diagnose_cases(nc, cases, base, "profile", effects)
        wall = time.perf_counter() - t0
        named = d.best_effect or "none"
        if effect is None:
            top = d.effects[0]
            print(
                f"| {label} | none | {named} | {top.held_out_gap_before:.1f} | "
                f"{top.held_out_gap_after:.1f} ({top.name}) | {top.removed:.0%} | - | "
                f"{wall:.0f} |"
            )
            continue
        row = next(r for r in d.effects if r.name == effect)
        fitted = ", ".join(f"{n}={row.params[n]:.4g} ({v:g})" for n, v in params.items())
        score.append(d.best_effect == effect)
        print(
            f"| {label} | {effect} | {named} | {row.held_out_gap_before:.1f} | "
            f"{row.held_out_gap_after:.1f} | {row.removed:.0%} | {fitted} | {wall:.0f} |"
        )
        sys.stdout.flush()
    print()
    print(f"changed setting named first: {sum(score)}/{len(score)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
