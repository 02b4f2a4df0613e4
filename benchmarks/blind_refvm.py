"""The blind diagnosis benchmark on the reference interpreter: seeded programs, one effect.

Not a test: ``python benchmarks/blind_refvm.py --seeds tune|score [--per 4]`` (about 10 min
per seed set on 2 cores).

The same ten program families as ``benchmarks/blind_linuxcnc.py`` (seeded; the ``tune``
seeds 100-999 were used while developing, the ``score`` seeds 9000-9999 only for the
figures), run on the reference interpreter ``refvm`` (independent of core's planner: it
imports nothing of ncperf) on the ``linuxcnc-sim`` machine as its parameters describe it
(nothing folded in, and corners blended as the paper has them, as refvm runs them -- not
``corner_blending = "linuxcnc"``, which is LinuxCNC's planner, not the interpreter's), with
ONE of the interpreter's effects switched on at a random strength
(``benchmarks/withheld_effects.py``'s draws, seeded), or none (controls). Each trace is
diagnosed on its own: ``ncperf diagnose`` with the same machine, ``--baseline profile``. A
case whose effect leaves the trace as it was (held-out gap under VISIBLE times that of the
same program without the effect) is reported as not visible and left out of the score.
Printed: every case, the confusion table, the hit rate and the false alarms.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import multiprocessing as mp
import sys
from collections import Counter

import numpy as np
from blind.families import FAMILIES, program  # benchmarks/ is the script's folder
from withheld_effects import EFFECTS, VISIBLE, draw, trace_of

SEEDS = {"tune": 100, "score": 9000}
MACHINE = "linuxcnc-sim"


def cases(seeds: str, per: int) -> list[tuple[str | None, dict[str, float], str, int]]:
    """(effect, params, family, seed): ``per`` cases per effect, one control per family."""
    base = SEEDS[seeds]
    rng = np.random.default_rng(base + 7)
    from core.model.machine import resolve_machine

    m = dataclasses.replace(resolve_machine(MACHINE), effects=(), corner_blending="paper")
    fams = list(FAMILIES)
    out: list[tuple[str | None, dict[str, float], str, int]] = []
    for k, effect in enumerate(EFFECTS):
        for j in range(per):
            params = draw(effect, m, rng)
            if params is None:
                continue
            out.append(
                (effect, params, fams[int(rng.integers(len(fams)))], base + 700 + 10 * k + j)
            )
    for j, fam in enumerate(fams):
        out.append((None, {}, fam, base + 800 + j))
    return out


def run(case: tuple[str | None, dict[str, float], str, int]) -> dict:
    effect, params, fam, seed = case
    import tempfile
    from pathlib import Path

    from core import Ncperf
    from core.diagnosis.align import align
    from core.engine.effects import setup_for
    from core.model.machine import resolve_machine
    from refvm import simulate

    nc = Ncperf()
    effects = nc.effects()
    m = dataclasses.replace(resolve_machine(MACHINE), effects=(), corner_blending="paper")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"{fam}_{seed}.ngc"
        path.write_text(program(fam, seed))
        tp = nc.extract(str(path))
    base = setup_for(m, effects, ramps=True)
    gaps = {}
    named = {}
    for which, (eff, par) in {"control": (None, {}), "case": (effect, params)}.items():
        if which == "case" and effect is None:
            gaps["case"], named["case"] = gaps["control"], named["control"]
            break
        sim = simulate(tp, m, eff, par)
        d = nc.diagnose([(tp, [align(tp, trace_of(sim, "vm"))], ["vm"])], base, "profile", effects)
        gaps[which] = d.effects[0].held_out_gap_before
        named[which] = d.best_effect or "none"
    return {
        "effect": effect,
        "params": params,
        "name": f"{fam}_{seed}",
        "named": named["case"],
        "gap": gaps["case"],
        "control_gap": gaps["control"],
        "visible": effect is None or gaps["case"] >= VISIBLE * max(gaps["control"], 1e-9),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", choices=tuple(SEEDS), required=True)
    ap.add_argument("--per", type=int, default=4, help="cases per effect")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    todo = cases(args.seeds, args.per)
    with mp.get_context("fork").Pool(args.jobs) as pool:
        results = pool.map(run, todo)
    print(
        f"Blind diagnosis benchmark on the reference interpreter, seed set '{args.seeds}' "
        f"(seeds from {SEEDS[args.seeds]}), {datetime.date.today()}: one effect per trace, "
        f"`ncperf diagnose --machine {MACHINE} (nothing folded) --baseline profile`"
    )
    print()
    print("| program | effect | true | named first | gap [mm/min] | control gap |")
    print("|---|---|---|---|---|---|")
    conf: Counter = Counter()
    hits = n = alarms = controls = 0
    hidden = 0
    for r in results:
        exp = r["effect"] or "none"
        true = ", ".join(f"{k}={v:.4g}" for k, v in r["params"].items()) or "-"
        mark = "" if r["named"] == exp else " (x)"
        if not r["visible"]:
            mark = " (not visible)"
            hidden += 1
        print(
            f"| {r['name']} | {exp} | {true} | {r['named']}{mark} | {r['gap']:.1f} | "
            f"{r['control_gap']:.1f} |"
        )
        if not r["visible"]:
            continue
        conf[exp, r["named"]] += 1
        if r["effect"] is None:
            controls += 1
            alarms += r["named"] != "none"
        else:
            n += 1
            hits += r["named"] == exp
    cols = sorted({c for _, c in conf})
    print()
    print("| expected | " + " | ".join(cols) + " |")
    print("|---|" + "---|" * len(cols))
    for exp in sorted({e for e, _ in conf}):
        print(f"| {exp} | " + " | ".join(str(conf[exp, c] or "") for c in cols) + " |")
    print()
    print(f"effect named first: {hits}/{n} ({hits / max(n, 1):.0%}) of the visible cases")
    print(f"not visible (left out): {hidden}")
    print(f"false alarms on the unchanged runs: {alarms}/{controls}")
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
