"""Write a trace of the reference interpreter (refvm) for a program: ``t,x,y,z,v,line``.

    python benchmarks/vm_trace.py PROGRAM OUT.csv [--machine PRESET|FILE]
        [--effect NAME --param k=v ...] [--dt 0.001] [--kind setpoint|actual]

The glue between the two sides: ncperf reads the program and the machine file (its
adapters and presets), the reference interpreter runs them. Exit 0, 1 for a program or
machine ncperf cannot read (one line), 2 for a bad effect request.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

from core import Ncperf, NcperfError, resolve_machine
from refvm import EFFECTS, simulate, write_csv
from refvm.simulate import KINDS


def _param(text: str) -> tuple[str, float]:
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"--param takes k=v, got {text!r}")
    try:
        return key.strip(), float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--param {key}: not a number: {value!r}") from None


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (see the module docstring); returns the exit status."""
    ap = argparse.ArgumentParser(
        prog="vm_trace.py",
        description="Reference time-stepping controller with one effect; writes t,x,y,z,v,line.",
        epilog="effects: "
        + "; ".join(f"{k}({', '.join(v) or 'no parameters'})" for k, v in EFFECTS.items()),
    )
    ap.add_argument("program")
    ap.add_argument("out", help="CSV trace to write")
    ap.add_argument("--machine", default=None, help="preset name or TOML file")
    ap.add_argument("--effect", choices=sorted(EFFECTS), default=None)
    ap.add_argument("--param", type=_param, action="append", default=[], metavar="K=V")
    ap.add_argument("--dt", type=float, default=0.001, help="controller cycle, s")
    ap.add_argument("--kind", choices=KINDS, default=None)
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    try:
        machine = resolve_machine(args.machine)
        toolpath = Ncperf().extract(args.program)
    except NcperfError as exc:
        print(exc, file=sys.stderr)
        return 1
    try:
        trace = simulate(
            toolpath, machine, args.effect, dict(args.param), dt=args.dt, kind=args.kind
        )
    except ValueError as exc:
        print(f"vm_trace.py: {exc}", file=sys.stderr)
        return 2
    wall = time.perf_counter() - t0
    write_csv(trace, args.out)
    print(
        f"{args.program}: {trace.t.size} cycles, cycle time {trace.cycle_time:.3f} s, "
        f"{trace.kind} trace, effect {trace.effect or 'none'} {trace.params or ''}, "
        f"{wall:.2f} s wall -> {args.out}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
