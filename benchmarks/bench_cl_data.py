"""Speed and memory of the CL data reader (A1, ``adapters.cl_data``) on million-GOTO files.

Not a test: from the repository root (package installed) run

    python benchmarks/bench_cl_data.py [GOTOS]

and read the table. Each case is a generated NX-style CLSF file of ``GOTOS`` GOTO records
(1,000,000 by default): a zig-zag finishing raster over a freeform surface, points every
0.2 mm at 4 decimals, each pass reached through a ``PAINT/COLOR`` record and one GOTO:

* ``3-axis``: ``GOTO/x,y,z`` -- the bulk (numpy) path only;
* ``5-axis``: ``GOTO/x,y,z,i,j,k`` on every record, the tool tilted along the surface;
* ``Creo spacing``: ``GOTO / x, y, z`` -- blanks around '/' and ',', still the bulk path;
* ``arcs 1 in 4``: every fourth move an NX ``CIRCLE`` record (11 values) and its GOTO, a
  2.5D-style file where one record in five goes through the per-record Python path.

The time is the whole ``ncperf_extract`` hook (file read, parse, ToolPath), best and worst
of three; the peak is the traced Python/numpy memory of one further run (tracemalloc, which
sees numpy's buffers), the bytes of the file included.

Target (issue 3): well under 3 s for 1,000,000 GOTO records.
"""

from __future__ import annotations

import os
import resource
import sys
import tempfile
import time
import tracemalloc

import numpy as np

from adapters.cl_data import ncperf_extract

STEP = 0.2  # mm between points along a pass
STEP_OVER = 0.3  # mm between passes
WIDTH = 200.0  # mm along X
HEADER = (
    "TOOL PATH/FINISH_CONTOUR,TOOL,BALL_MILL_6\n"
    "TLDATA/MILL,6.0000,3.0000,50.0000,0.0000,0.0000\n"
    "MSYS/0.0000,0.0000,0.0000,1.0000000,0.0000000,0.0000000,0.0000000,1.0000000,0.0000000\n"
    "$$ centerline data\n"
    "PAINT/PATH\n"
    "RAPID\n"
    "GOTO/0.0000,0.0000,50.0000\n"
    "FEDRAT/MMPM,6000.0000\n"
)


def surface(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Freeform height (mm): two bumps and a valley (as benchmarks/gen_finishing.py)."""
    return (
        8 * np.exp(-((x - 60) ** 2 + (y - 60) ** 2) / 900)
        + 5 * np.exp(-((x - 140) ** 2 + (y - 120) ** 2) / 600)
        - 4 * np.exp(-((x - 110) ** 2 + (y - 30) ** 2) / 400)
    )


def raster(n: int) -> np.ndarray:
    """(n, 3) points of the zig-zag raster, pass after pass."""
    per_pass = int(WIDTH / STEP) + 1
    k = np.arange(n)
    p, i = divmod(k, per_pass)
    x = np.where(p % 2 == 0, i, per_pass - 1 - i) * STEP
    y = p * STEP_OVER
    return np.column_stack([x, y, surface(x, y)])


def tilt(pts: np.ndarray) -> np.ndarray:
    """(n, 3) unit tool axes leaning with the surface gradient (a 5-axis finishing path)."""
    h = 1e-3
    gx = (surface(pts[:, 0] + h, pts[:, 1]) - pts[:, 2]) / h
    gy = (surface(pts[:, 0], pts[:, 1] + h) - pts[:, 2]) / h
    a = np.column_stack([-gx, -gy, np.ones(len(pts))])
    return a / np.linalg.norm(a, axis=1)[:, None]


def write(path: str, n: int, case: str) -> tuple[int, int]:
    """Write one case; returns (GOTO records, other records)."""
    pts = raster(n)
    per_pass = int(WIDTH / STEP) + 1
    if case == "5-axis":
        ax = tilt(pts)
        lines = [
            f"GOTO/{x:.4f},{y:.4f},{z:.4f},{i:.7f},{j:.7f},{k:.7f}"
            for (x, y, z), (i, j, k) in zip(pts.tolist(), ax.tolist(), strict=True)
        ]
    elif case == "Creo spacing":
        lines = [f"GOTO / {x:.4f}, {y:.4f}, {z:.4f}" for x, y, z in pts.tolist()]
    else:
        lines = [f"GOTO/{x:.4f},{y:.4f},{z:.4f}" for x, y, z in pts.tolist()]
    other = 0
    if case == "arcs 1 in 4":
        # Replace every 4th point by a half-millimetre bulge: a CIRCLE through the chord's
        # ends, one chord length to its right, level with the start (NX: clockwise about
        # the axis).
        for k in range(3, n, 4):
            (x0, y0, z), (x1, y1, _) = pts[k - 1], pts[k]
            mx, my = (x0 + x1) / 2, (y0 + y1) / 2
            dx, dy = x1 - x0, y1 - y0
            c = (mx + dy, my - dx)  # one chord length off the chord, on its right
            r = float(np.hypot(x1 - c[0], y1 - c[1]))
            lines[k] = (
                f"CIRCLE/{c[0]:.4f},{c[1]:.4f},{z:.4f},0.0000000,0.0000000,1.0000000,"
                f"{r:.4f},0.0100,0.5000,6.0000,3.0000\nGOTO/{x1:.4f},{y1:.4f},{z:.4f}"
            )
            other += 1
    # A PAINT record before every pass, as NX marks engage and cut moves.
    for k in range(per_pass, n, per_pass):
        lines[k] = "PAINT/COLOR,42\n" + lines[k]
        other += 1
    with open(path, "w") as fh:
        fh.write(HEADER)
        fh.write("\n".join(lines))
        fh.write("\nEND-OF-PATH\n")
    return n + 1, other + 7


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for case in ("3-axis", "5-axis", "Creo spacing", "arcs 1 in 4"):
            path = os.path.join(tmp, "part.cls")
            gotos, other = write(path, n, case)
            size = os.path.getsize(path) / 1e6
            times = []
            for _ in range(3):
                t = time.perf_counter()
                tp = ncperf_extract(source=path)
                times.append(time.perf_counter() - t)
            del tp
            tracemalloc.start()
            tp = ncperf_extract(source=path)
            peak = tracemalloc.get_traced_memory()[1] / 1e6
            tracemalloc.stop()
            rows.append((case, gotos, other, size, min(times), max(times), peak, tp.n))
            del tp
    print(
        f"{'case':14} {'GOTO':>9} {'other':>7} {'file MB':>8} {'best s':>7} {'worst s':>8} "
        f"{'peak MB':>8} {'moves':>9}"
    )
    for case, gotos, other, size, best, worst, peak, moves in rows:
        print(
            f"{case:14} {gotos:9d} {other:7d} {size:8.1f} {best:7.2f} {worst:8.2f} "
            f"{peak:8.0f} {moves:9d}"
        )
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"process peak RSS: {rss:.0f} MB")


if __name__ == "__main__":
    main()
