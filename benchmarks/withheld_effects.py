"""Does ``ncperf diagnose`` find an effect it is not told about? A confusion table.

Not a test: ``PYTHONPATH=.:benchmarks python benchmarks/withheld_effects.py [--quick]``.

Every case runs a set of bundled example programs on the reference virtual machine
(``benchmarks/vm``, an interpolator independent of ``core.profile``) with **one** controller
effect switched on at a given strength, records 1 ms traces, and hands them to the diagnosis
without saying which effect was on. The diagnosis fits every effect it knows on alternate
programs and measures it on the others (profile baseline, the machine's own values as the
starting point). Reported per case: the effect ranked first, the held-out gap before and
after the withheld effect is modelled (and the share removed), the fitted parameter against
the true one. A control case with no effect checks that nothing is named when nothing is
there.

Effects that a machine cannot show are skipped (a jerk scale on a machine without a jerk
limit). An effect that leaves the traces as they were on these programs (its held-out gap
before modelling under VISIBLE times the control's) is reported as not visible and left out
of the score: nothing can be diagnosed from traces it did not change.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from core import Ncperf
from core.align import align
from core.diagnose import diagnose_cases
from core.effects import setup_for
from core.machine import resolve_machine
from core.trace import Trace

sys.path.insert(0, str(Path(__file__).resolve().parent))
from vm.virtual_machine import simulate  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: Corners at three feeds, arcs with curvature jumps, short blocks, a mould cavity of chords.
PROGRAMS = (
    "fig1_polygons_F4000",
    "fig3_semicircle_spiral",
    "fig4_points_d1",
    "fig1_polygons_F8000",
    "zlevel_cavity",
)
QUICK = ("fig1_polygons_F4000", "fig3_semicircle_spiral", "fig4_points_d1", "fig1_polygons_F8000")

#: (effect, parameters) cases; strengths a machine plausibly shows. None: no effect.
CASES: tuple[tuple[str | None, dict[str, float]], ...] = (
    (None, {}),
    ("feed_override", {"scale": 0.8}),
    ("feed_override", {"scale": 1.2}),
    ("block_cycle_time", {"t_block": 0.02}),
    ("corner_tolerance", {"tolerance": 0.05}),
    ("corner_tolerance", {"tolerance": 0.003}),
    ("normal_acceleration_factor", {"factor": 0.5}),
    ("arc_feed_limit", {}),
    ("axis_dynamics", {"accel_scale": 0.6}),
    ("axis_dynamics", {"jerk_scale": 0.5}),
    ("lookahead_depth", {"blocks": 4}),
    ("servo_lag", {"tau": 0.02}),
    ("jerk_filter", {"window": 0.03}),
    ("path_compression", {"max_angle": 10.0, "max_length": 5.0}),
)


#: An effect is visible when it at least doubles the held-out gap of the control case.
VISIBLE = 2.0


def observable(effect: str | None, params: dict[str, float], machine) -> bool:
    """Whether the effect can show on this machine at all."""
    if effect == "axis_dynamics" and "jerk_scale" in params:
        return bool(np.isfinite(machine.max_jerk).any())
    return True


def trace_of(sim, source: str) -> Trace:
    return Trace(
        t=sim.t,
        pos=np.column_stack([sim.x, sim.y, sim.z]),
        v=sim.v,
        line=sim.line,
        source=source,
        kind=sim.kind,
    )


def run_case(nc, effects, machine, programs, effect, params):
    cases = []
    for name in programs:
        prog = EXAMPLES / f"{name}.ngc"
        tp = nc.extract(str(prog))
        sim = simulate(tp, machine, effect, params, ncperf=nc)
        al = align(tp, trace_of(sim, f"vm:{name}"))
        cases.append((tp, [al], [name]))
    base = setup_for(machine, effects, ramps=True)
    return diagnose_cases(nc, cases, base, "profile", effects)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--machine",
        action="append",
        help="preset or TOML (repeatable; default linuxcnc-sim and siemens-840d)",
    )
    ap.add_argument("--quick", action="store_true", help="four small programs only")
    args = ap.parse_args()
    nc = Ncperf()
    effects = nc.effects()
    programs = QUICK if args.quick else PROGRAMS
    print(
        f"Withheld effects, virtual machine traces (1 ms), {datetime.date.today()}; "
        f"programs: {', '.join(programs)}"
    )
    print()
    print(
        "| machine | withheld effect | true | ranked first | held-out gap before "
        "[mm/min] | after | removed | fitted | wall [s] |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    firsts, removed, controls, hidden = [], [], [], []
    for spec in args.machine or ["linuxcnc-sim", "siemens-840d"]:
        # The machine as the controller's parameters describe it: nothing folded in.
        machine = dataclasses.replace(resolve_machine(spec), effects=())
        control_gap = None
        for effect, params in CASES:
            if not observable(effect, params, machine):
                continue
            t0 = time.perf_counter()
            d = run_case(nc, effects, machine, programs, effect, params)
            wall = time.perf_counter() - t0
            true = ", ".join(f"{k}={v:g}" for k, v in params.items()) or "-"
            short = machine.name.split(" (")[0]
            named = d.best_effect or "none"
            if effect is None:
                control_gap = d.effects[0].held_out_gap_before
                controls.append(d.best_effect is None)
                top = d.effects[0]
                print(
                    f"| {short} | none | - | {named} | {top.held_out_gap_before:.1f} "
                    f"| {top.held_out_gap_after:.1f} ({top.name}) | {top.removed:.0%} | - "
                    f"| {wall:.0f} |"
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
            print(
                f"| {short} | {effect} | {true} | {named} | "
                f"{row.held_out_gap_before:.1f} | {row.held_out_gap_after:.1f} | "
                f"{row.removed:.0%} | {fitted} | {wall:.0f} |"
            )
            sys.stdout.flush()
    print()
    print(
        f"withheld effect ranked first: {sum(firsts)}/{len(firsts)} "
        f"({sum(firsts) / max(len(firsts), 1):.0%}); median held-out gap removed by it: "
        f"{statistics.median(removed):.0%}; no effect named on unchanged traces: "
        f"{sum(controls)}/{len(controls)}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
