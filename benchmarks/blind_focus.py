"""A focused development run of the blind benchmark: the axis settings its held-out sets
missed most, on the families where they were missed, each beside its program's run on the
unchanged machine.

Not a test, and not held out: ``python benchmarks/blind_focus.py [--cache DIR]`` (needs
LinuxCNC and ../shared/tools/linuxcnc; 56 traces recorded in real time, about 15 min, then
about 5 min of diagnosis on 2 cores). Seeds 990000-990027, which no seed set of
``blind_linuxcnc.py`` uses: Z acceleration (drawn 300-1000 mm/s^2) on four domes, thread
millings, engravings and 2.5D parts; X acceleration on three trochoids and three free-form
paths; X speed on three free-form paths; all axes' speed on three 2.5D parts. Printed per
case: how much the setting moves LinuxCNC's own feed time (the unchanged run beside it),
the effect named first, the top effect's share of the held-out gap, the gap and the floor;
then the unchanged runs (controls).
"""

from __future__ import annotations

import argparse
import math
import multiprocessing as mp
import sys
from pathlib import Path

import blind_linuxcnc as blind  # benchmarks/ is the script's folder

FIRST_SEED = 990000
PLAN = (
    [("acc_z", f) for f in ("dome", "thread_milling", "engraving", "part_25d") for _ in range(4)]
    + [("acc_x", "trochoid")] * 3
    + [("acc_x", "freeform")] * 3
    + [("vel_x", "freeform")] * 3
    + [("vel_all", "part_25d")] * 3
)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", default="/tmp/ncperf-blind-focus")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    cache = Path(args.cache)
    cache.mkdir(parents=True, exist_ok=True)
    variants = {v.key: v for v in blind.VARIANTS}
    cases = [
        blind.Case(blind.drawn(variants[key], FIRST_SEED + k), fam, FIRST_SEED + k)
        for k, (key, fam) in enumerate(PLAN)
    ]
    twins = [blind.Case(blind.CONTROL, c.family, c.seed) for c in cases]
    for k, c in enumerate(cases + twins):
        blind.record(c, cache)
        print(f"recorded {k + 1}/{2 * len(cases)} {c.name} {c.variant.key}", file=sys.stderr)
    with mp.get_context("fork").Pool(args.jobs) as pool:
        res = pool.map(blind.diagnose_case, [(c, str(cache)) for c in cases + twins])
    print(
        "| program | changed | feed time moved | rapid time moved | named first | top effect "
        "| gap | floor |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for r in res:
        c = r["case"]
        feed, rapid = blind.visibility(c, cache) if c.variant.effect else (math.nan, math.nan)
        print(
            f"| {c.name} | {c.variant.label} | {feed:+.2%} | {rapid:+.2%} | {r['named']} | "
            f"{r['top']} {r['removed']:.0%} | {r['gap']:.1f} | {r['floor']:.1f} |"
        )
    hits = sum(r["named"] == r["case"].variant.effect for r in res[: len(cases)])
    alarms = sum(r["named"] != "none" for r in res[len(cases) :])
    print(f"\nnamed first: {hits}/{len(cases)}; named on the unchanged runs: {alarms}/{len(twins)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
