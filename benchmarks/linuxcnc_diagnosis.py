"""Diagnosing LinuxCNC 2.9's planner from the visible trace suite, and folding the result into
the machine preset.

Not a test: ``python benchmarks/linuxcnc_diagnosis.py [--machine PRESET]``
(needs ../shared). All ten programs of ``../shared/data/linuxcnc/suite/`` with their traces
are diagnosed together: effects are fitted on the even-numbered programs and measured on the
odd-numbered ones (other programs as held-out data), once against the paper's point model
and once against the full profile. The chosen effects, printed as ``[effects.NAME]`` tables,
are what ``core/model/presets/linuxcnc-sim.toml`` carries; with ``--machine linuxcnc-sim`` (the
folded preset) each program is then diagnosed on its own against the profile, where no
effect should stand out.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import sys
from pathlib import Path

from core import Ncperf
from core.cli.diagnosis_report import toml_snippet
from core.diagnosis.align import align
from core.engine.effects import setup_for
from core.model.machine import resolve_machine

SUITE = Path(__file__).resolve().parents[2] / "shared" / "data" / "linuxcnc" / "suite"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--machine", default="linuxcnc-sim")
    ap.add_argument(
        "--raw",
        action="store_true",
        help="drop the machine's [effects.NAME] tables (to find what to fold in)",
    )
    ap.add_argument(
        "--per-program",
        action="store_true",
        help="also diagnose every program on its own (profile baseline)",
    )
    args = ap.parse_args()
    if not SUITE.exists():
        print(f"{SUITE} not found: this benchmark needs ../shared", file=sys.stderr)
        return 1
    nc = Ncperf()
    effects = nc.effects()
    machine = resolve_machine(args.machine)
    if args.raw:
        machine = dataclasses.replace(machine, effects=())
    cases = []
    for prog in sorted(SUITE.glob("*.ngc")):
        tp = nc.extract(str(prog))
        al = align(tp, nc.read_trace(str(prog.with_suffix(".csv"))))
        cases.append((tp, [al], [prog.stem]))
    folded = ", ".join(f"{n} {p}" for n, p, _ in machine.effects) or "none"
    print(
        f"LinuxCNC suite diagnosis on {machine.name} ({machine.source}; effects folded in: "
        f"{folded}), {datetime.date.today()}"
    )
    for baseline in ("paper", "profile"):
        base = setup_for(machine, effects, ramps=baseline == "profile")
        d = nc.diagnose(cases, base, baseline, effects)
        print()
        print(f"baseline {baseline}: {d.held_out}")
        print(
            f"  gap {d.gap_rms_before:.1f} -> {d.gap_rms_after:.1f} mm/min; best effect "
            f"{d.best_effect}; chosen {' + '.join(d.chosen) or 'none'}"
        )
        print("  | effect | parameters | held-out gap before | after | removed |")
        print("  |---|---|---|---|---|")
        for r in d.effects:
            params = ", ".join(f"{k}={v:.4g}" for k, v in r.params.items()) or "-"
            print(
                f"  | {r.name} | {params} | {r.held_out_gap_before:.1f} | "
                f"{r.held_out_gap_after:.1f} | {r.removed:.0%} |"
            )
        if d.chosen:
            print("  fold into the machine file:")
            for line in toml_snippet(d, machine, effects).splitlines():
                print("    " + line)
    if args.per_program:
        print()
        print("Each program on its own, profile baseline:")
        print()
        print("| program | gap [mm/min] | best effect | removed |")
        print("|---|---|---|---|")
        base = setup_for(machine, effects, ramps=True)
        for tp, als, labels in cases:
            d = nc.diagnose([(tp, als, labels)], base, "profile", effects)
            top = d.effects[0]
            print(
                f"| {labels[0]} | {d.gap_rms_before:.1f} | {d.best_effect} | "
                f"{top.name} {top.removed:.0%} |"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
