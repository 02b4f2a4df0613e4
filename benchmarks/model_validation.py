"""The paper's point models against a real controller's planner (LinuxCNC 2.9), per point.

Not a test: from the repository root run ``python benchmarks/model_validation.py``
(needs ../shared). The programs and LinuxCNC's measured speeds come from the shared
harness (``../shared/tools/linuxcnc/programs``, ``../shared/data/linuxcnc/*.summary.txt``):

* corner sweeps at G64 P0.001 / P0.01 / P0.1 (40 mm legs, turn angles 5..150 deg,
  F6000): model 1 (eq. 1, 4-6) with the ``linuxcnc-sim`` preset, TIT from G64 P, against
  the speed minimum LinuxCNC reached at each corner;
* collinear short-segment series at F10000: model 3 (eq. 16) against the plateau speed.

Only the corner speeds are a validation: the preset's t_int = 1.02 ms was read off the
0.1 mm series, so model 3 agrees there by construction.
"""

from __future__ import annotations

import datetime
import re
import statistics
from pathlib import Path

import numpy as np

from core import Ncperf, load_preset

SHARED = Path(__file__).resolve().parents[2] / "shared"
PROGRAMS = SHARED / "tools" / "linuxcnc" / "programs"
DATA = SHARED / "data" / "linuxcnc"
MINIMUM = re.compile(r"v=([\d.]+) units/s .* at x=([-\d.]+) y=([-\d.]+) z=([-\d.]+) line (\d+)")
PER_LINE = re.compile(r"^\s+(\d+)\s+[\d.]+\s+[\d.]+\s+([\d.]+)\s+[\d.]+\s+[\d.]+$")


def corners(nc: Ncperf, tag: str) -> list[tuple[float, float, float]]:
    """(turn angle deg, measured mm/s, predicted mm/s) for each corner of one sweep."""
    prog = PROGRAMS / f"corner_sweep_{tag}.ngc"
    tp = nc.extract(str(prog))
    ev = nc.evaluate(tp, load_preset("linuxcnc-sim"))
    pts = tp.end[ev.junction]
    rows = []
    for m in MINIMUM.finditer((DATA / f"corner_sweep_{tag}.summary.txt").read_text()):
        v, x, y, z = (float(m.group(k)) for k in range(1, 5))
        k = int(np.argmin(np.linalg.norm(pts - [x, y, z], axis=1)))
        j = ev.junction[k]
        rows.append((float(np.degrees(tp.turn_angle[j])), v, float(ev.junction_feed[k])))
    return sorted(rows)


def plateau(nc: Ncperf, tag: str) -> tuple[float, float, float]:
    """(segment mm, measured plateau mm/s, predicted mm/s) of one short-segment series."""
    prog = PROGRAMS / f"shortseg_{tag}_f10000.ngc"
    tp = nc.extract(str(prog))
    ev = nc.evaluate(tp, load_preset("linuxcnc-sim"))
    med = [
        float(m.group(2))
        for line in (DATA / f"shortseg_{tag}_f10000.summary.txt").read_text().splitlines()
        if (m := PER_LINE.match(line))
    ]
    middle = med[len(med) // 4 : 3 * len(med) // 4]
    seg = float(np.median(tp.length[tp.is_feed]))
    return seg, statistics.median(middle), float(np.median(ev.element_feed[tp.is_feed]))


def main() -> None:
    if not DATA.exists():
        raise SystemExit(f"{DATA} not found: this benchmark needs ../shared")
    nc = Ncperf()
    print(
        f"Model 1 (tangential) vs LinuxCNC 2.9 corner speeds, {datetime.date.today()}; "
        "F6000 = 100 mm/s, preset linuxcnc-sim"
    )
    print()
    print("| G64 P [mm] | turn [deg] | LinuxCNC [mm/min] | model 1 [mm/min] | model / LinuxCNC |")
    print("|---|---|---|---|---|")
    ratios = []
    for tag, p in (("p0001", 0.001), ("p001", 0.01), ("p01", 0.1)):
        for angle, meas, pred in corners(nc, tag):
            ratio = pred / meas
            if meas < 99.9:  # corners LinuxCNC took at full feed say nothing about the model
                ratios.append(ratio)
            print(f"| {p:g} | {angle:.0f} | {meas * 60:.0f} | {pred * 60:.0f} | {ratio:.3f} |")
    print()
    print(
        f"Slowed corners: model / LinuxCNC = {statistics.median(ratios):.3f} (median), "
        f"{min(ratios):.3f} .. {max(ratios):.3f}; sqrt(2 / sqrt(3)) = "
        f"{np.sqrt(2 / np.sqrt(3)):.3f} is what LinuxCNC's normal-acceleration budget "
        "a_n = (sqrt(3)/2) a predicts."
    )
    print()
    print("Model 3 (block time) vs LinuxCNC plateau on collinear segments, F10000 = 166.7 mm/s")
    print()
    print("| segment [mm] | LinuxCNC [mm/min] | model 3 [mm/min] |")
    print("|---|---|---|")
    for tag in ("0p1mm", "0p2mm", "0p5mm", "1p0mm", "2p0mm"):
        if not (PROGRAMS / f"shortseg_{tag}_f10000.ngc").exists():
            continue
        seg, meas, pred = plateau(nc, tag)
        print(f"| {seg:g} | {meas * 60:.0f} | {pred * 60:.0f} |")


if __name__ == "__main__":
    main()
