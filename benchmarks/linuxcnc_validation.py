"""Predicted profile and cycle time against LinuxCNC 2.9's real trajectory planner.

Not a test: from the repository root run ``python benchmarks/linuxcnc_validation.py``
(needs ../shared). For every program of ``../shared/data/linuxcnc/suite/`` (traces recorded
at 1 ms from LinuxCNC's planner on the simulated mill of the ``linuxcnc-sim`` preset):

* cycle time: the trace's motion time against the predicted cycle time;
* feed: each trace sample is placed on the program's arc length (projected on the move of
  its program line, kept monotone), the measured speed is resampled every 0.05 mm, and the
  RMS of (predicted - measured) is taken over the feed moves as a share of the programmed
  feed -- for the paper's point model (each block at its own predicted feed: F, capped by
  model 3 and the axes' feed limits; junction dips are points) and for the full profile.

Two predictions: the paper's models and the profile alone on the machine's ini values plus
the 1.02 ms block time the harness measured on 0.1 mm segments (nothing tuned to these
traces), and what ``ncperf analyze`` predicts with the preset, whose ``[effects]`` tables were
fitted on these same traces by ``ncperf diagnose`` (benchmarks/linuxcnc_diagnosis.py; its
held-out figures, and benchmarks/linuxcnc_withheld.py, measure it on data it did not see).
"""

from __future__ import annotations

import dataclasses
import datetime
import sys
from pathlib import Path

import numpy as np

from core import Ncperf, load_preset
from core.engine.effects import setup_for
from core.engine.profile import build_profile
from core.model.toolpath import MoveKind

SHARED = Path(__file__).resolve().parents[2] / "shared"
SUITE = SHARED / "data" / "linuxcnc" / "suite"
STEP = 0.05  # mm between comparison points along the path


def read_trace(path: Path) -> dict[str, np.ndarray]:
    """Columns of a LinuxCNC trace CSV (t,x,y,z,v,line,...)."""
    with open(path) as fh:
        names = fh.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return {n: data[:, k] for k, n in enumerate(names)}


def arc_length_of_samples(tp, pts: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """Arc length (mm) of each sample, projected on the move of its program line."""
    start_s = tp.start_s
    # The last move of each line (LinuxCNC reports a line for the whole block).
    line_to_move = {int(line): k for k, line in enumerate(tp.line)}
    k = np.array([line_to_move.get(int(v), -1) for v in lines])
    k_prev = np.maximum.accumulate(np.where(k >= 0, np.arange(k.size), 0))
    k = np.where(k >= 0, k, np.where(k_prev > 0, k[k_prev], 0))
    k = np.maximum(k, 0)
    a, b = tp.start[k], tp.end[k]
    d = np.zeros(len(k))
    line = tp.kind[k] != MoveKind.ARC_CW
    line &= tp.kind[k] != MoveKind.ARC_CCW
    ab = b - a
    t = np.einsum("ij,ij->i", pts - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-30)
    d = np.where(line, np.clip(t, 0, 1) * tp.length[k], 0.0)
    arc = ~line
    if arc.any():
        ka = k[arc]
        n = tp.normal[ka]
        c = tp.center[ka]
        r0 = tp.start[ka] - c
        r0 -= np.einsum("ij,ij->i", r0, n)[:, None] * n
        p = pts[arc] - c
        p -= np.einsum("ij,ij->i", p, n)[:, None] * n
        sgn = np.where(tp.kind[ka] == MoveKind.ARC_CCW, 1.0, -1.0)
        ang = np.arctan2(np.einsum("ij,ij->i", n, np.cross(r0, p)), np.einsum("ij,ij->i", r0, p))
        ang = np.mod(sgn * ang, 2 * np.pi)
        # near the start, a full-turn helix may read 2 pi: keep the turn closest to time order
        frac = np.clip(ang / tp.sweep[ka], 0, 1)
        d[arc] = frac * tp.length[ka]
    return np.maximum.accumulate(start_s[k] + d)


def paper_speed(ev, cap, s: np.ndarray) -> np.ndarray:
    tp = ev.toolpath
    return cap[tp.move_at(s)]


def validate(nc: Ncperf, prog: Path) -> dict[str, float]:
    tp = nc.extract(str(prog))
    preset = load_preset("linuxcnc-sim")
    ev = nc.evaluate(tp, dataclasses.replace(preset, effects=()))
    pr = build_profile(ev)
    folded = nc.predict(tp, setup_for(preset, nc.effects(), ramps=True))
    tr = read_trace(prog.with_suffix(".csv"))
    t, v = tr["t"], tr["v"]
    pts = np.column_stack([tr["x"], tr["y"], tr["z"]])
    s_meas = arc_length_of_samples(tp, pts, tr["line"])
    # Resample the measured speed on arc length (samples with a new arc length only).
    keep = np.concatenate([[True], np.diff(s_meas) > 1e-9])
    grid = np.arange(0.0, float(tp.length.sum()), STEP)
    v_meas = np.interp(grid, s_meas[keep], v[keep])
    k = tp.move_at(grid)
    feed = tp.is_feed[k]
    f = tp.feed[k][feed]
    v_full = pr.speed_at(grid)[feed]
    v_paper = paper_speed(ev, pr.cap, grid)[feed]
    v_folded = folded.speed_at(grid)[feed]
    vm = v_meas[feed]
    return {
        "moves": tp.n,
        "measured": float(t[-1] - t[0]),
        "predicted": pr.cycle_time,
        "paper": float(ev.paper_time),
        "rms_paper": float(np.sqrt(np.mean(((v_paper - vm) / f) ** 2))),
        "rms_profile": float(np.sqrt(np.mean(((v_full - vm) / f) ** 2))),
        "folded": folded.cycle_time,
        "rms_folded": float(np.sqrt(np.mean(((v_folded - vm) / f) ** 2))),
    }


def main() -> int:
    if not SUITE.exists():
        print(f"{SUITE} not found: this benchmark needs ../shared", file=sys.stderr)
        return 1
    nc = Ncperf()
    print(f"LinuxCNC 2.9 trace suite vs ncperf (preset linuxcnc-sim), {datetime.date.today()}")
    print()
    print(
        "| program | moves | measured [s] | predicted [s] | error | RMS feed error, paper "
        "model | RMS feed error, profile | with the preset's effects [s] | error | RMS feed "
        "error |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    worst = worst_folded = 0.0
    for prog in sorted(SUITE.glob("*.ngc")):
        r = validate(nc, prog)
        err = (r["predicted"] / r["measured"] - 1) * 100
        err_f = (r["folded"] / r["measured"] - 1) * 100
        worst = max(worst, abs(err))
        worst_folded = max(worst_folded, abs(err_f))
        print(
            f"| {prog.stem} | {r['moves']} | {r['measured']:.3f} | {r['predicted']:.3f} | "
            f"{err:+.1f} % | {r['rms_paper'] * 100:.1f} % | {r['rms_profile'] * 100:.1f} % | "
            f"{r['folded']:.3f} | {err_f:+.1f} % | {r['rms_folded'] * 100:.1f} % |"
        )
    print()
    print(
        f"largest cycle-time error {worst:.1f} % (profile), {worst_folded:.1f} % (with the "
        "preset's effects)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
