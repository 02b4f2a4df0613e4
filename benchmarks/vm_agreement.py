"""The reference interpreter (refvm) without effect against ncperf's predicted cycle time.

Not a test: ``python benchmarks/vm_agreement.py [--all]`` from the repository root (ncperf
installed with the test set-up command); the one place where the two sides meet. Prints,
for the example programs on the ``linuxcnc-sim`` and ``siemens-840d`` presets, the
interpreter's cycle time (1 ms cycles), ncperf's (``core.engine.profile``), their
difference, and the interpreter's cycles per second of wall time. ``--all`` adds every
example and the programs of ../shared/data/linuxcnc/suite.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from core import Ncperf, load_preset
from core.engine.profile import build_profile
from refvm import simulate

ROOT = Path(__file__).resolve().parents[1]
PROGRAMS = ("fig1_polygons_F4000", "fig3_semicircle_spiral", "fig4_points_d1", "zlevel_cavity")
PRESETS = ("linuxcnc-sim", "siemens-840d")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--all", action="store_true", help="every example and the LinuxCNC suite")
    args = ap.parse_args(argv)
    files = [ROOT / "examples" / f"{p}.ngc" for p in PROGRAMS]
    if args.all:
        files = sorted((ROOT / "examples").glob("*.ngc"))
        files += sorted((ROOT.parent / "shared" / "data" / "linuxcnc" / "suite").glob("*.ngc"))
    nc = Ncperf()
    print(
        "| program | preset | moves | VM [s] | ncperf [s] | difference | VM wall [s] | cycles/s |"
    )
    print("|---|---|---|---|---|---|---|---|")
    worst = 0.0
    for f in files:
        tp = nc.extract(str(f))
        for preset in PRESETS:
            m = load_preset(preset)
            t0 = time.perf_counter()
            tr = simulate(tp, m)
            wall = time.perf_counter() - t0
            predicted = build_profile(nc.evaluate(tp, m)).cycle_time
            diff = tr.cycle_time / predicted - 1.0
            worst = max(worst, abs(diff))
            print(
                f"| {f.stem} | {preset} | {tp.n} | {tr.cycle_time:.3f} | {predicted:.3f} | "
                f"{100 * diff:+.2f} % | {wall:.2f} | {tr.t.size / wall:,.0f} |",
                flush=True,
            )
    print(f"\nlargest difference: {100 * worst:.2f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
