"""Calibrating on the NIST box part by block times, and predicting runs it was not fitted on.

Not a test: ``python benchmarks/nist_blocktime.py [--out DIR]`` (needs ../shared, or its path in
NCPERF_SHARED as for the tests; about 10 s).
Data: NIST Smart Manufacturing Systems Test Bed, box part OP2 on a Hurco VMC (2017), see
benchmarks/nist_validation.py.

1. ``ncperf calibrate BOX_REV-A_OP2_Front.NC`` on the six calibration runs (08, 11, 13, 15,
   17, 19) from benchmarks/machines/hurco_vmc_assumed.toml, objective chosen automatically
   (block time: MTConnect polls every 0.16 s), every controller effect.
2. The calibrated file and the assumed one predict every run, the six held-out ones (09, 12,
   14, 16, 18, 20) included: per run, the feed-block time (the sum of the intervals between
   observed Block_Number changes over feed blocks only, as calibrate compares them) measured
   and predicted, the error, the median absolute error per interval, and the feed the
   recording shows on the feed blocks over F (an operator's override shows there).
"""

from __future__ import annotations

import argparse
import datetime
import os
import statistics
import sys
import tempfile
from pathlib import Path

import numpy as np

from core import Ncperf
from core.cli.main import main as ncperf_main
from core.diagnosis.align import align
from core.diagnosis.blocktime import block_data, expected, feed_lines
from core.engine.effects import setup_for
from core.model.machine import load_machine_file

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("NCPERF_SHARED", ROOT.parent / "shared")) / "data" / "nist-mtc-box-op2"
MACHINE = ROOT / "benchmarks" / "machines" / "hurco_vmc_assumed.toml"
PROGRAM = "BOX_REV-A_OP2_Front.NC"
CALIBRATION = ("08", "11", "13", "15", "17", "19")
HELD_OUT = ("09", "12", "14", "16", "18", "20")


def run_file(run: str) -> Path:
    return DATA / f"Box-OP2-Hurco02-{run}of20.txt"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="folder for the calibrated machine file (default: a temp dir)")
    args = ap.parse_args()
    if not DATA.exists():
        print(f"{DATA} not found: this benchmark needs ../shared", file=sys.stderr)
        return 1
    out_dir = Path(args.out or tempfile.mkdtemp(prefix="nist-blocktime-"))
    out_dir.mkdir(parents=True, exist_ok=True)
    calibrated = out_dir / "hurco_vmc_calibrated.toml"
    # Step 1, exactly as a user runs it: the calibration runs only.
    rc = ncperf_main(
        [
            "calibrate",
            str(DATA / PROGRAM),
            *(str(run_file(r)) for r in CALIBRATION),
            "--machine",
            str(MACHINE),
            "--out",
            str(calibrated),
        ]
    )
    if rc:
        return rc
    print()

    nc = Ncperf()
    tp = nc.extract(str(DATA / PROGRAM))
    effects = nc.effects()
    preds = {
        name: nc.predict(tp, setup_for(load_machine_file(path), effects))
        for name, path in (("assumed", MACHINE), ("calibrated", calibrated))
    }
    ok = feed_lines(tp)
    first_move = np.full(int(tp.line.max()) + 2, -1)
    first_move[tp.line[::-1]] = np.arange(tp.n)[::-1]

    print(
        f"NIST box OP2, Hurco VMC: feed-block time by run, {datetime.date.today()} "
        f"(calibrated on {', '.join(CALIBRATION)}; held out {', '.join(HELD_OUT)})"
    )
    print()
    print(
        "| run | data | intervals | measured [s] | assumed file [s] | error | calibrated file [s] "
        "| error | median abs. interval error, assumed / calibrated [s] | recorded feed / F |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    errs: dict[str, dict[str, list[float]]] = {"calibration": {}, "held out": {}}
    for run in sorted(CALIBRATION + HELD_OUT):
        what = "calibration" if run in CALIBRATION else "held out"
        tr = nc.read_trace(str(run_file(run)))
        d = block_data(tp, align(tp, tr), run)
        measured = float(d.measured.sum())
        cells, med = [], []
        for name, pred in preds.items():
            e = expected(pred, d)
            p = float(e.sum())
            err = p / measured - 1.0
            errs[what].setdefault(name, []).append(err)
            cells += [f"{p:.2f}", f"{err:+.1%}"]
            med.append(f"{float(np.median(np.abs(d.measured - e))):.3f}")
        on = ok[np.clip(tr.line, 0, ok.size - 1)] & (tr.v > 0)
        override = float(np.median(tr.v[on] / tp.feed[first_move[tr.line[on]]]))
        print(
            f"| {run} | {what} | {d.first.size} | {measured:.2f} | {' | '.join(cells)} "
            f"| {' / '.join(med)} | {override:.3f} |"
        )
    print()
    for what, by in errs.items():
        text = "; ".join(
            f"{name} file: median |error| {statistics.median(abs(x) for x in v):.1%}, "
            f"max {max(abs(x) for x in v):.1%}"
            for name, v in by.items()
        )
        print(f"{what} runs: {text}")
    print(f"calibrated machine file: {calibrated}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
