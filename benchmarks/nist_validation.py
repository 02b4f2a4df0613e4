"""Predicted against measured block times on a real machine: the NIST Hurco recording.

Not a test: ``python benchmarks/nist_validation.py`` (needs ../shared).
Data: NIST Smart Manufacturing Systems Test Bed, box part OP2 on a Hurco VMC (2017),
``BOX_REV-A_OP2_Front.NC`` (Fanuc-style, inch) and 12 MTConnect SHDR recordings
(``timestamp|key|value``; ``Block_Number`` is the program line being run, sampled on change
about every 0.19 s). NIST public-domain data, acknowledged as the source, provided as is.

The Hurco's dynamics are unknown: benchmarks/machines/hurco_vmc_assumed.toml lists the values
assumed. For each run: the motion from the first block to PROGRAM_COMPLETED against the
predicted cycle time; and block by block, the time between two observed Block_Number changes
against the predicted time of the program lines in between.
"""

from __future__ import annotations

import datetime
import statistics
import sys
from datetime import datetime as dt
from pathlib import Path

import numpy as np

from core import Ncperf
from core.engine.profile import build_profile
from core.model.machine import load_machine_file

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data" / "nist-mtc-box-op2"
MACHINE = ROOT / "benchmarks" / "machines" / "hurco_vmc_assumed.toml"


def read_run(path: Path) -> tuple[np.ndarray, np.ndarray, float]:
    """(times s, block numbers) of Block_Number changes, and the completion time (s)."""
    t0 = None
    times, blocks, done = [], [], None
    for raw in path.read_text().splitlines():
        stamp, key, value = raw.split("|", 2)
        t = dt.fromisoformat(stamp.replace("Z", "+00:00")).timestamp()
        t0 = t if t0 is None else t0
        if key == "Block_Number" and int(value) > 0:
            times.append(t - t0)
            blocks.append(int(value))
        elif key == "Program_Status" and value == "PROGRAM_COMPLETED":
            done = t - t0
    return np.array(times), np.array(blocks), float(done)


def main() -> int:
    if not DATA.exists():
        print(f"{DATA} not found: this benchmark needs ../shared", file=sys.stderr)
        return 1
    nc = Ncperf()
    prog = DATA / "BOX_REV-A_OP2_Front.NC"
    tp = nc.extract(str(prog))
    pr = build_profile(nc.evaluate(tp, load_machine_file(MACHINE)))
    lines_text = prog.read_text().splitlines()
    per_line = np.bincount(tp.line, weights=pr.time + tp.dwell, minlength=len(lines_text) + 2)
    cum = np.concatenate([[0.0], np.cumsum(per_line)])  # predicted time before line L: cum[L]

    print(
        f"NIST box OP2 on a Hurco VMC vs ncperf ({MACHINE.name}: all dynamics assumed), "
        f"{datetime.date.today()}"
    )
    print()
    print(
        "| run | measured, first block to end [s] | predicted motion [s] | blocks compared "
        "| median abs. block error [s] |"
    )
    print("|---|---|---|---|---|")
    gaps: dict[int, list[float]] = {}
    totals, motion = [], []
    # Blocks whose time is not motion: tool changes, coolant and spindle waits, the optional
    # stop, the return home (G28, to a position ncperf does not know) and the program end.
    other = np.array(
        [
            any(w in text for w in ("M6", "M8", "M01", "M30", "G28"))
            for text in [""] + lines_text + [""]
        ]
    )
    for run in sorted(DATA.glob("Box-OP2-*.txt")):
        t, b, done = read_run(run)
        measured = done - t[0]
        spans_m = np.diff(np.append(t, done))
        ends = np.append(b[1:], len(lines_text) + 1)
        spans_p = cum[ends] - cum[b]
        err = spans_p - spans_m
        for start, e in zip(b.tolist(), err.tolist(), strict=True):
            gaps.setdefault(start, []).append(e)
        totals.append(measured)
        keep = ~other[b]
        motion.append((float(spans_m[keep].sum()), float(spans_p[keep].sum())))
        print(
            f"| {run.stem.split('-')[-1]} | {measured:.1f} | {pr.cycle_time:.1f} | {b.size} | "
            f"{statistics.median(np.abs(err)):.2f} |"
        )
    print()
    print(
        f"Measured {statistics.median(totals):.1f} s (median of {len(totals)} runs) against "
        f"{pr.cycle_time:.1f} s of predicted motion. Without the blocks of tool changes, M8, "
        f"M01, M30 and G28: measured {statistics.median([m for m, _ in motion]):.1f} s, "
        f"predicted {statistics.median([p for _, p in motion]):.1f} s."
    )
    print()
    print("Largest block-level gaps (predicted - measured, median over runs):")
    print()
    print("| from line | block | gap [s] |")
    print("|---|---|---|")
    worst = sorted(gaps.items(), key=lambda kv: statistics.median(kv[1]))[:8]
    for line, errs in worst:
        text = lines_text[line - 1].strip()[:40]
        print(f"| {line} | `{text}` | {statistics.median(errs):+.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
