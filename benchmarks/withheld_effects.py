"""Does ``ncperf diagnose`` find an effect it is not told about? A confusion table.

Not a test: ``python benchmarks/withheld_effects.py [--seed N] [--draws K] [--full]`` (about
15 minutes on 2 cores with the defaults).

Every case runs a set of bundled example programs on the reference interpreter
(``refvm``, an interpreter that imports nothing of ncperf) with **one** controller
effect switched on at a random strength (seeded: the same seed gives the same cases),
records 1 ms traces, and hands them to the diagnosis without saying which effect was on. The
diagnosis fits every effect it knows on alternate programs and measures it on the others
(profile baseline, the machine's own values as the starting point). Reported per case: the
effect ranked first, the held-out gap before and after the withheld effect is modelled (and
the share removed), the fitted parameters against the true ones; then the confusion table
(true effect x named effect) and the summary. A control case per machine, with no effect,
checks that nothing is named when nothing is there.

axis_dynamics is drawn as an acceleration or jerk scale and, from a stream of its own (so
the other cases stay those of the seed), as axis speeds at 40-80 % of the highest programmed
feed. An effect a machine cannot show is not drawn there (a jerk scale without a jerk limit). An
effect that leaves the traces as they were on these programs (held-out gap before modelling
under VISIBLE times the control's) is reported as not visible and left out of the score:
nothing can be diagnosed from traces it did not change.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import statistics
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

from core import Ncperf
from core.diagnosis.align import align
from core.engine.effects import setup_for
from core.model.machine import Machine, resolve_machine
from core.model.trace import Trace
from refvm import EFFECTS as VM_EFFECTS
from refvm import simulate

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: Corners at two feeds, arcs with curvature jumps, short blocks; --full adds the cavity.
PROGRAMS = (
    "fig1_polygons_F4000",
    "fig3_semicircle_spiral",
    "fig4_points_d1",
    "fig1_polygons_F8000",
)
FULL = (*PROGRAMS, "zlevel_cavity")
MACHINES = ("linuxcnc-sim", "siemens-840d")
#: An effect is visible when it at least doubles the held-out gap of the control case.
VISIBLE = 2.0


def draw(effect: str, m: Machine, rng: np.random.Generator) -> dict[str, float] | None:
    """A random strength a machine plausibly shows, or None if ``m`` cannot show it."""
    u = rng.uniform
    if effect == "feed_override":
        return {"scale": float(u(0.6, 0.9) if rng.random() < 0.5 else u(1.1, 1.4))}
    if effect == "block_cycle_time":
        return {"t_block": float(max(m.interpolation_time, 0.008) * u(1.5, 3.0))}
    if effect == "corner_tolerance":
        return {"tolerance": float(m.path_tolerance * 10 ** (u(0.3, 0.7) * rng.choice([-1, 1])))}
    if effect == "normal_acceleration_factor":
        return {"factor": float(u(0.4, 0.75))}
    if effect == "arc_feed_limit":
        return {}
    if effect == "axis_dynamics":
        if np.isfinite(m.max_jerk).any() and rng.random() < 0.5:
            return {"jerk_scale": float(u(0.3, 0.6))}
        return {"accel_scale": float(u(0.4, 0.75))}
    if effect == "lookahead_depth":
        return {"blocks": float(rng.integers(2, 9))}
    if effect == "servo_lag":
        return {"tau": float(u(0.01, 0.04))}
    if effect == "jerk_filter":
        return {"window": float(u(0.02, 0.06))}
    if effect == "path_compression":
        return {"max_angle": float(u(5.0, 15.0)), "max_length": float(u(2.0, 6.0))}
    raise ValueError(effect)


#: The effects the reference interpreter can switch on (its table's names).
EFFECTS = tuple(VM_EFFECTS)


def trace_of(sim, source: str) -> Trace:
    return Trace(
        t=sim.t,
        pos=np.column_stack([sim.x, sim.y, sim.z]),
        v=sim.v,
        line=sim.line,
        source=source,
        kind=sim.kind,
    )


def run_case(nc, effects, machine, tps, effect, params):
    cases = []
    for name, tp in tps.items():
        sim = simulate(tp, machine, effect, params)
        cases.append((tp, [align(tp, trace_of(sim, f"vm:{name}"))], [name]))
    base = setup_for(machine, effects, ramps=True)
    return nc.diagnose(cases, base, "profile", effects)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--draws", type=int, default=2, help="strengths per effect and machine")
    ap.add_argument("--full", action="store_true", help="add the Z-level cavity (slower)")
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    speed_rng = np.random.default_rng(args.seed + 1)
    nc = Ncperf()
    effects = nc.effects()
    programs = FULL if args.full else PROGRAMS
    tps = {p: nc.extract(str(EXAMPLES / f"{p}.ngc")) for p in programs}
    print(
        f"Withheld effects, reference-interpreter traces (1 ms), {datetime.date.today()}; seed "
        f"{args.seed}, {args.draws} strengths per effect; programs: {', '.join(programs)}"
    )
    print()
    print(
        "| machine | withheld effect | true | ranked first | held-out gap before [mm/min] "
        "| after | removed | fitted | wall [s] |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    confusion: Counter = Counter()
    firsts, removed, controls, hidden = [], [], [], []
    t_all = time.perf_counter()
    for spec in MACHINES:
        # The machine as the controller's parameters describe it: nothing folded in, corners
        # blended as the paper has them (as refvm runs them).
        machine = dataclasses.replace(resolve_machine(spec), effects=(), corner_blending="paper")
        short = machine.name.split(" (")[0]
        cases: list[tuple[str | None, dict[str, float]]] = [(None, {})]
        for effect in EFFECTS:
            for _ in range(args.draws if effect != "arc_feed_limit" else 1):
                params = draw(effect, machine, rng)
                if params is not None:
                    cases.append((effect, params))
        # Axis speeds under the programmed feed (drawn from a stream of their own, so the
        # cases above stay those of the seed): 40-80 % of the highest feed.
        f_max = max(float(tp.feed[tp.is_feed].max()) for tp in tps.values())
        for _ in range(args.draws):
            share = float(speed_rng.uniform(0.4, 0.8))
            cases.append(("axis_dynamics", {"feed_scale": share * f_max / machine.max_feed.min()}))
        control_gap = None
        for effect, params in cases:
            t0 = time.perf_counter()
            d = run_case(nc, effects, machine, tps, effect, params)
            wall = time.perf_counter() - t0
            true = ", ".join(f"{k}={v:.4g}" for k, v in params.items()) or "-"
            named = d.best_effect or "none"
            if effect is None:
                control_gap = d.effects[0].held_out_gap_before
                controls.append(d.best_effect is None)
                confusion["none", named] += 1
                top = d.effects[0]
                print(
                    f"| {short} | none | - | {named} | {top.held_out_gap_before:.1f} | "
                    f"{top.held_out_gap_after:.1f} ({top.name}) | {top.removed:.0%} | - | "
                    f"{wall:.0f} |"
                )
                continue
            row = next(r for r in d.effects if r.name == effect)
            fitted = ", ".join(f"{k}={row.params[k]:.4g}" for k in params) or "-"
            if control_gap is not None and row.held_out_gap_before < VISIBLE * control_gap:
                hidden.append(f"{effect} ({true}) on {short}")
                named += " (not visible)"
            else:
                firsts.append(d.best_effect == effect)
                removed.append(row.removed)
                confusion[effect, d.best_effect or "none"] += 1
            print(
                f"| {short} | {effect} | {true} | {named} | {row.held_out_gap_before:.1f} | "
                f"{row.held_out_gap_after:.1f} | {row.removed:.0%} | {fitted} | {wall:.0f} |"
            )
            sys.stdout.flush()
    print()
    print("Confusion table (visible cases and the controls): rows the withheld effect, columns")
    print("the effect the diagnosis named first.")
    print()
    rows = ["none", *EFFECTS]
    cols = sorted(
        {c for _, c in confusion},
        key=lambda c: (c != "none", rows.index(c) if c in rows else 99, c),
    )
    print("| withheld \\ named | " + " | ".join(cols) + " |")
    print("|---|" + "---|" * len(cols))
    for r in rows:
        if not any(confusion[r, c] for c in cols):
            continue
        print(f"| {r} | " + " | ".join(str(confusion[r, c] or "") for c in cols) + " |")
    print()
    print(
        f"withheld effect ranked first: {sum(firsts)}/{len(firsts)} "
        f"({sum(firsts) / max(len(firsts), 1):.0%}); median held-out gap removed by it: "
        f"{statistics.median(removed):.0%}; no effect named on unchanged traces: "
        f"{sum(controls)}/{len(controls)}; {time.perf_counter() - t_all:.0f} s"
    )
    if hidden:
        print(f"not visible on these programs (left out): {'; '.join(hidden)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
