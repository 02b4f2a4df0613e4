"""LinuxCNC's naive-CAM detector (G64 P without Q) against its real planner, on programs
never looked at while modelling it.

Not a test: ``python benchmarks/linuxcnc_naivecam.py [--cache DIR] [--seed 70000]`` (needs
LinuxCNC and ../shared/tools/linuxcnc; traces are recorded in real time, a few minutes, and
cached).

One program per family of the blind benchmark (benchmarks/blind/families.py), drawn from
seeds of their own (70000 on: no other script uses them), written with ``G64 P<tol>`` and
no Q -- so LinuxCNC's interpreter joins nearly collinear blocks within tol (Q defaults to
P) -- tol drawn from 0.005, 0.01, 0.02, 0.05 mm per program. Each runs through LinuxCNC
2.9's planner on the harness's default mill, unchanged. Printed per program: the blocks and
the segments LinuxCNC ran (the distinct line numbers of the trace's moving samples), the
segments ncperf predicts with and without the detector (``--no-naive-cam``), how many of the
trace's segment lines ncperf's segments share, and the cycle time (trace length against the
``linuxcnc-sim`` preset's feed profile) both ways.
"""

from __future__ import annotations

import argparse
import datetime
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
from blind.families import FAMILIES, program  # benchmarks/ is the script's folder

from core import Ncperf
from core.model.machine import resolve_machine
from core.model.toolpath import ExtractOptions, MoveKind

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
HARNESS = SHARED / "tools" / "linuxcnc" / "run_trace.sh"
INI = SHARED / "tools" / "linuxcnc" / "machines" / "default_mill_mm.ini"
TOLERANCES = (0.005, 0.01, 0.02, 0.05)
#: The trace's motion type of a rapid (LinuxCNC's EMC_MOTION_TYPE_TRAVERSE).
TRAVERSE = 1


def record(prog: Path, out: Path) -> Path:
    if out.exists():
        return out
    cmd = ["bash", str(HARNESS), str(prog), str(INI), str(out) + ".part"]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{prog}: the LinuxCNC harness failed:\n{r.stderr[-2000:]}")
    Path(str(out) + ".part").rename(out)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", default="/tmp/ncperf-naivecam")
    ap.add_argument("--seed", type=int, default=70000)
    ap.add_argument(
        "--q0", action="store_true", help="keep the families' G64 P0.01 Q0 (no joining)"
    )
    ap.add_argument(
        "--record-only",
        action="store_true",
        help="record the traces and stop (a held-out set is recorded before it is looked at)",
    )
    args = ap.parse_args()
    cache = Path(args.cache)
    cache.mkdir(parents=True, exist_ok=True)
    if not HARNESS.exists():
        print(f"skipped: {HARNESS} not found (../shared is needed)")
        return 0
    rng = np.random.default_rng(args.seed)
    nc = Ncperf()
    machine = resolve_machine("linuxcnc-sim")
    rows = []
    for k, fam in enumerate(FAMILIES):
        seed = args.seed + k
        tol = float(rng.choice(TOLERANCES))
        text = program(fam, seed)
        if args.q0:
            tol = 0.0
        else:
            text = re.sub(r"G64 P0\.01 Q0", f"G64 P{tol:g}", text)
        prog = cache / f"{fam}_{seed}.ngc"
        if not prog.exists():
            prog.write_text(text)
        trace = record(prog, cache / f"{fam}_{seed}.csv")
        if args.record_only:
            continue
        t = np.genfromtxt(trace, delimiter=",", names=True)
        moving = (t["v"] > 0) & (t["mtype"] != TRAVERSE)
        trace_lines = set(np.unique(t["line"][moving].astype(int)).tolist())
        measured = float(t["t"][-1] - t["t"][0])
        out = {"name": prog.name, "tol": tol, "trace_segments": len(trace_lines)}
        for key, merge in (("joined", True), ("as_written", False)):
            opts = ExtractOptions(naive_cam=merge, setup=machine.setup)
            tp = nc.extract(str(prog), opts)
            a = nc.analyze(str(prog), machine, opts)
            feed = tp.kind != MoveKind.RAPID
            lines = set(np.unique(tp.line[feed]).tolist())
            cycle = float(a.profile.cycle_time) if a.profile is not None else math.nan
            out[key] = (len(lines), len(lines & trace_lines), cycle / measured - 1.0)
        out["blocks"] = out["as_written"][0]
        rows.append(out)
    if args.record_only:
        print(f"recorded in {cache}")
        return 0
    today = datetime.date.today().isoformat()
    print(
        f"LinuxCNC naive-CAM detector (G64 P, no Q), seeds {args.seed}-{args.seed + 9}, "
        f"{today}; linuxcnc-sim preset, unchanged machine\n"
    )
    print(
        "| program | G64 P [mm] | feed blocks | segments LinuxCNC ran | ncperf segments "
        "(shared with the trace) | cycle time error | as written: segments | as written: "
        "cycle time error |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        j, w = r["joined"], r["as_written"]
        print(
            f"| {r['name']} | {r['tol']:g} | {r['blocks']} | {r['trace_segments']} | "
            f"{j[0]} ({j[1]}) | {j[2]:+.1%} | {w[0]} | {w[2]:+.1%} |"
        )
    ej = [abs(r["joined"][2]) for r in rows]
    ew = [abs(r["as_written"][2]) for r in rows]
    print(
        f"\ncycle time |error|: with the detector max {max(ej):.1%}, mean {np.mean(ej):.1%}; "
        f"as written max {max(ew):.1%}, mean {np.mean(ew):.1%}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
