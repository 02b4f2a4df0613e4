"""Speed, size and memory of the SVG display (A3) on million-move tool paths.

Not a test: from the repository root (package installed) run
``python benchmarks/bench_svg.py [moves]`` and read the table. Two paths of ``moves``
moves each (1,000,000 by default), both Archimedean spirals with 0.5 mm step-over and every
97th move an arc bulging off the spiral:

* ``uniform``: 0.05 mm segments at 6 m/min (every block shorter than
  L = F t_int, so one reduction class almost everywhere: long runs);
* ``random``: 0.05-0.25 mm segments at 1.5 m/min (L = 0.3 mm), so the
  reduction class changes nearly every move: the worst case for runs.

Targets: SVG step < 1.5 s and file < 10 MB for 1M moves.
"""

from __future__ import annotations

import os
import resource
import sys
import tempfile
import time
import tracemalloc

import numpy as np

from adapters.svg.render import write_svg
from core import Ncperf, build_annotations, load_preset, make_plugin_manager
from core.model import geometry as g
from core.model.toolpath import MoveKind, ToolPath, empty_columns

PLUGINS = (
    "plugins.tangential",
    "plugins.curvature",
    "plugins.ncu_capacity",
    "plugins.exact_stop",
    "adapters.svg",
)


def spiral(n: int, seg: np.ndarray, feed: float, arc_every: int = 97) -> ToolPath:
    """An Archimedean spiral of ``n`` moves of lengths ``seg`` (mm) at ``feed`` (mm/s).

    Every ``arc_every``-th move is a counter-clockwise arc over the same chord,
    bulging outwards by 10 % of the chord.
    """
    r0, b = 5.0, 0.5 / (2 * np.pi)  # start radius (mm), rise per radian (mm/rad)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    # Arc length of r = r0 + b theta is about r0 theta + b theta^2 / 2.
    theta = (-r0 + np.sqrt(r0**2 + 2 * b * s)) / b
    r = r0 + b * theta
    p = np.column_stack([r * np.cos(theta), r * np.sin(theta), np.zeros_like(r)])
    cols = empty_columns(n)
    cols["start"], cols["end"] = p[:-1], p[1:]
    cols["feed"][:] = feed
    arcs = np.arange(arc_every - 1, n, arc_every)
    st, en = p[arcs], p[arcs + 1]
    chord = en - st
    length = g.norm(chord)
    mid = 0.5 * (st + en)
    # Centre on the inner side of the chord so that a ccw arc bulges outwards.
    inward = np.column_stack([-chord[:, 1], chord[:, 0], np.zeros(arcs.size)]) / length[:, None]
    d = 0.5 * length * (1 - 0.2**2) / (2 * 0.2)  # sagitta 0.1 chord -> distance to centre
    center = mid + inward * d[:, None]
    normal = np.tile([0.0, 0.0, 1.0], (arcs.size, 1))
    cols["kind"][arcs] = MoveKind.ARC_CCW
    cols["center"][arcs] = center
    cols["normal"][arcs] = normal
    cols["sweep"][arcs] = g.arc_sweep(st, en, center, normal, np.ones(arcs.size, dtype=bool))
    return ToolPath(**cols, source=f"spiral-{n}")


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
    rng = np.random.default_rng(1)
    cases = {
        "uniform": spiral(n, np.full(n, 0.05), 6000 / 60),
        "random": spiral(n, rng.uniform(0.05, 0.25, n), 1500 / 60),
    }
    nc = Ncperf(make_plugin_manager(builtins=PLUGINS, entry_points=False))
    machine = load_preset("siemens-840d")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, tp in cases.items():
            t0 = time.perf_counter()
            ev = nc.evaluate(tp, machine)
            t1 = time.perf_counter()
            ann = build_annotations(ev)
            t2 = time.perf_counter()
            out = os.path.join(tmp, f"{name}.svg")
            # Best and worst of three: other processes on the machine add noise.
            times = []
            for _ in range(3):
                t = time.perf_counter()
                write_svg(tp, ann, out)
                times.append(time.perf_counter() - t)
            size = os.path.getsize(out) / 1e6
            # Peak of the SVG step alone, in a separate traced run (tracing slows it).
            tracemalloc.start()
            write_svg(tp, ann, out)
            peak = tracemalloc.get_traced_memory()[1] / 1e6
            tracemalloc.stop()
            rows.append((name, tp.n, t1 - t0, t2 - t1, min(times), max(times), size, peak))
    print(
        f"{'path':8} {'moves':>9} {'evaluate s':>10} {'annotate s':>10} {'svg s best':>10} "
        f"{'svg s worst':>11} {'svg MB':>7} {'svg peak MB':>11}"
    )
    for name, moves, te, ta, best, worst, size, peak in rows:
        print(
            f"{name:8} {moves:9d} {te:10.2f} {ta:10.2f} {best:10.2f} {worst:11.2f} "
            f"{size:7.2f} {peak:11.0f}"
        )
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"process peak RSS: {rss:.0f} MB")


if __name__ == "__main__":
    main()
