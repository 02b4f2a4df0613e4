"""Program families for the blind LinuxCNC benchmark: ten kinds of tool path a shop runs,
each drawn from a seeded random generator (numpy's PCG64), so that a seed names a program
and the scoring seeds can be kept apart from the tuning seeds.

Every program is LinuxCNC G-code in mm (G21 G17 G90 G94), ``G64 P0.01 Q0`` (Q0: no
collinear merging), starting at X0 Y0 Z0 as the harness's machine does, with comment
lines under 255 characters. Feeds are drawn per program; motion times are 4-20 s on the
default mill (250 mm/s, 2000 mm/s^2).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

G64 = "G64 P0.01 Q0"


def _f(v: float) -> str:
    s = f"{v:.4f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


class Prog:
    """A program being written: a title, the header, words by line."""

    def __init__(self, title: str) -> None:
        self.lines = [f"({title[:200]})", "G21 G17 G90 G94", G64]

    def add(self, text: str) -> None:
        self.lines.append(text)

    def go(self, x: float, y: float, z: float | None = None) -> None:
        zz = "" if z is None else f" Z{_f(z)}"
        self.add(f"G0 X{_f(x)} Y{_f(y)}{zz}")

    def line(self, x: float, y: float, z: float | None = None, f: float | None = None) -> None:
        zz = "" if z is None else f" Z{_f(z)}"
        ff = "" if f is None else f" F{_f(f)}"
        self.add(f"G1 X{_f(x)} Y{_f(y)}{zz}{ff}")

    def text(self) -> str:
        return "\n".join([*self.lines, "G0 Z5", "M2"]) + "\n"


def random_polygons(rng: np.random.Generator) -> str:
    """Closed random polygons (6-14 corners of 10-175 degrees, sides 6-40 mm) at two depths."""
    feed = float(rng.choice([2000, 3000, 4000, 6000]))
    p = Prog(f"random polygons, F{feed:g}")
    for depth in (-1.0, -2.0):
        n = int(rng.integers(6, 15))
        ang = np.sort(rng.uniform(0, 2 * math.pi, n))
        rad = rng.uniform(8, 30, n)
        pts = np.column_stack([40 + rad * np.cos(ang), 40 + rad * np.sin(ang)])
        p.go(pts[0, 0], pts[0, 1], 5)
        p.line(pts[0, 0], pts[0, 1], depth, 800)
        for k, (x, y) in enumerate(pts[1:]):
            p.line(x, y, f=feed if k == 0 else None)
        p.line(pts[0, 0], pts[0, 1])
        p.go(pts[0, 0], pts[0, 1], 5)
    return p.text()


def trochoid(rng: np.random.Generator) -> str:
    """A trochoidal slot: full circles of radius 2-6 mm advancing 0.5-2 mm each (G2 arcs)."""
    feed = float(rng.choice([2000, 3000, 4000]))
    r = float(rng.uniform(2, 5))
    step = float(rng.uniform(0.5, 2))
    n = int(rng.integers(12, 24))
    p = Prog(f"trochoidal slot R{r:.2f} step {step:.2f}, F{feed:g}")
    x0, y0 = 10.0, 30.0
    p.go(x0, y0, 5)
    p.line(x0, y0, -2, 600)
    p.line(x0 + r, y0, f=feed)
    for k in range(n):
        cx = x0 + k * step
        ex = cx + step + r
        # a half circle back, a half circle forward onto the next circle's start
        p.add(f"G2 X{_f(cx - r)} Y{_f(y0)} I{_f(-r)} J0")
        p.add(f"G2 X{_f(ex)} Y{_f(y0)} I{_f(r + step / 2)} J0")
    return p.text()


def gear(rng: np.random.Generator) -> str:
    """An external gear profile (involute flanks, tip and root circles) as 0.05-0.4 mm chords."""
    teeth = int(rng.integers(10, 28))
    module = float(rng.uniform(1.5, 3))
    chord = float(rng.uniform(0.05, 0.4))
    feed = float(rng.choice([1500, 2500, 4000]))
    rp = module * teeth / 2
    ra, rf = rp + module, rp - 1.25 * module
    rb = rp * math.cos(math.radians(20))
    p = Prog(f"gear z={teeth} m={module:.2f}, chords {chord:.2f} mm, F{feed:g}")
    pts = []
    inv = lambda r: math.tan(math.acos(min(rb / r, 1))) - math.acos(min(rb / r, 1))  # noqa: E731
    half = math.pi / (2 * teeth) + inv(rp)
    for t in range(teeth):
        c = 2 * math.pi * t / teeth
        radii = np.linspace(max(rf, rb), ra, max(int((ra - max(rf, rb)) / chord), 2))
        left = [(r, c - half + inv(r)) for r in radii]
        right = [(r, c + half - inv(r)) for r in radii[::-1]]
        for r, a in left + right:
            pts.append((50 + r * math.cos(a), 50 + r * math.sin(a)))
        nxt = c + 2 * math.pi / teeth - half + inv(max(rf, rb))
        a0 = c + half - inv(max(rf, rb))
        m = max(int(rf * (nxt - a0) / chord), 1)
        for a in np.linspace(a0, nxt, m + 1)[1:-1]:
            pts.append((50 + rf * math.cos(a), 50 + rf * math.sin(a)))
    pts.append(pts[0])
    p.go(pts[0][0], pts[0][1], 5)
    p.line(pts[0][0], pts[0][1], -1, 600)
    p.line(pts[1][0], pts[1][1], f=feed)
    for x, y in pts[2:]:
        p.line(x, y)
    return p.text()


def freeform(rng: np.random.Generator) -> str:
    """A free-form curve (a sum of random sines) written as CAM chords of 0.05-1 mm."""
    chord = float(rng.choice([0.05, 0.1, 0.2, 0.5, 1.0]))
    feed = float(rng.choice([2000, 4000, 6000]))
    length = float(rng.uniform(150, 300))
    p = Prog(f"free-form chords {chord:g} mm, F{feed:g}")
    amps = rng.uniform(2, 12, 3)
    freqs = rng.uniform(0.02, 0.12, 3)
    phases = rng.uniform(0, 2 * math.pi, 3)
    x = np.arange(0, length / 3, chord / 3)
    waves = zip(amps, freqs, phases, strict=True)
    y = sum(a * np.sin(f * 2 * math.pi * x + ph) for a, f, ph in waves)
    # resample to the chord length along the curve
    s = np.concatenate([[0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    ss = np.arange(0, s[-1], chord)
    xs, ys = np.interp(ss, s, x) + 10, np.interp(ss, s, y) + 40
    p.go(xs[0], ys[0], 5)
    p.line(xs[0], ys[0], -1, 800)
    p.line(xs[1], ys[1], f=feed)
    for a, b in zip(xs[2:], ys[2:], strict=True):
        p.line(a, b)
    return p.text()


def spiral_pocket(rng: np.random.Generator) -> str:
    """A spiral pocket of tangent G3 half circles growing by a random stepover."""
    feed = float(rng.choice([3000, 4000, 5000]))
    step = float(rng.uniform(1.0, 2.5))
    turns = int(rng.integers(5, 10))
    p = Prog(f"spiral pocket stepover {step:.2f}, F{feed:g}")
    cx, cy = 50.0, 50.0
    p.go(cx, cy, 5)
    p.line(cx, cy, -1.5, 500)
    r = step / 2
    x = cx
    p.line(cx + r, cy, f=feed)
    x = cx + r
    side = 1
    for _ in range(2 * turns):
        nr = r + step / 2
        # half circle to the other side, centre shifted so the radius grows by step/2
        ex = cx - side * nr
        ci = (ex + x) / 2 - x
        p.add(f"G3 X{_f(ex)} Y{_f(cy)} I{_f(ci)} J0")
        x, r, side = ex, nr, -side
    return p.text()


def dome(rng: np.random.Generator) -> str:
    """A spherical dome finished by a zig-zag raster (Z follows the surface, 0.3-1 mm points)."""
    radius = float(rng.uniform(20, 35))
    height = float(rng.uniform(5, 12))
    step = float(rng.uniform(3, 6))
    pt = float(rng.uniform(0.4, 1.0))
    feed = float(rng.choice([1500, 3000, 4500]))
    p = Prog(f"dome R{radius:.1f} h{height:.1f}, stepover {step:.1f}, points {pt:.2f}, F{feed:g}")
    sphere_r = (radius**2 + height**2) / (2 * height)
    half = radius * 0.6
    ys = np.arange(-half, half + 1e-9, step)
    first = True
    for k, yv in enumerate(ys):
        xs = np.arange(-half, half + 1e-9, pt)
        if k % 2:
            xs = xs[::-1]
        for xv in xs:
            d2 = xv * xv + yv * yv
            zv = math.sqrt(max(sphere_r**2 - d2, 0)) - (sphere_r - height) if d2 < radius**2 else 0
            if first:
                p.go(50 + xv, 50 + yv, zv + 5)
                p.line(50 + xv, 50 + yv, zv, 800)
                p.add(f"F{_f(feed)}")
                first = False
            p.line(50 + xv, 50 + yv, zv)
    return p.text()


def engraving(rng: np.random.Generator) -> str:
    """Engraved strokes: short random polylines of 0.2-2 mm segments, rapids and plunges
    between them."""
    feed = float(rng.choice([800, 1200, 2000]))
    p = Prog(f"engraving strokes, F{feed:g}")
    for _ in range(int(rng.integers(8, 14))):
        x, y = rng.uniform(5, 95, 2)
        p.go(x, y, 2)
        p.line(x, y, -0.3, 300)
        h = rng.uniform(0, 2 * math.pi)
        for k in range(int(rng.integers(6, 20))):
            h += rng.normal(0, 0.6)
            seg = rng.uniform(0.2, 2)
            x, y = x + seg * math.cos(h), y + seg * math.sin(h)
            p.line(x, y, f=feed if k == 0 else None)
        p.go(x, y, 2)
    return p.text()


def thread_milling(rng: np.random.Generator) -> str:
    """Thread milling in 3-5 holes: a lead-in line, G2 helices of 2-4 turns (P), a lead-out."""
    feed = float(rng.choice([1200, 1800, 2400]))
    pitch = float(rng.choice([1.0, 1.25, 1.5, 2.0]))
    r = float(rng.uniform(2, 5))
    turns = int(rng.integers(2, 4))
    p = Prog(f"thread milling pitch {pitch:g}, R{r:.2f}, {turns} turns, F{feed:g}")
    for _ in range(int(rng.integers(2, 5))):
        cx, cy = rng.uniform(15, 85, 2)
        p.go(cx, cy, 5)
        p.line(cx, cy, -turns * pitch - 1, 800)
        p.line(cx + r, cy, f=feed)
        p.add(f"G2 X{_f(cx + r)} Y{_f(cy)} Z{_f(-1)} I{_f(-r)} J0 P{turns}")
        p.line(cx, cy)
        p.go(cx, cy, 5)
    return p.text()


def part_25d(rng: np.random.Generator) -> str:
    """A 2.5D part: a rounded rectangular pocket in two levels (lines and G3 fillets), its
    outline, and a row of drilled holes (G81)."""
    feed = float(rng.choice([3000, 4000, 5000]))
    w, h = rng.uniform(25, 45), rng.uniform(15, 30)
    fr = float(rng.uniform(1, 5))
    p = Prog(f"2.5D part {w:.0f} x {h:.0f}, fillets R{fr:.1f}, F{feed:g}")
    x0, y0 = 20.0, 20.0
    for depth in (-1.0, -2.0):
        for inset in (0.0, 4.0):
            a, b = x0 + inset, y0 + inset
            c, d = x0 + w - inset, y0 + h - inset
            rr = max(fr - inset / 3, 0.5)
            p.go(a + rr, b, 5)
            p.line(a + rr, b, depth, 600)
            p.line(c - rr, b, f=feed)
            p.add(f"G3 X{_f(c)} Y{_f(b + rr)} I0 J{_f(rr)}")
            p.line(c, d - rr)
            p.add(f"G3 X{_f(c - rr)} Y{_f(d)} I{_f(-rr)} J0")
            p.line(a + rr, d)
            p.add(f"G3 X{_f(a)} Y{_f(d - rr)} I0 J{_f(-rr)}")
            p.line(a, b + rr)
            p.add(f"G3 X{_f(a + rr)} Y{_f(b)} I{_f(rr)} J0")
            p.go(a + rr, b, 5)
    n = int(rng.integers(4, 9))
    p.go(x0, y0 + h + 8, 5)
    p.add(f"G98 G81 X{_f(x0)} Y{_f(y0 + h + 8)} Z-3 R1 F{_f(feed / 3)}")
    for k in range(1, n):
        p.add(f"X{_f(x0 + k * w / (n - 1))}")
    p.add("G80")
    return p.text()


def kinked_lines(rng: np.random.Generator) -> str:
    """Long lines with small kinks (1-12 degrees) every 5-30 mm, a zig-zag across the table."""
    feed = float(rng.choice([4000, 6000, 8000]))
    p = Prog(f"kinked lines, F{feed:g}")
    x, y, hd = 5.0, 5.0, 0.0
    p.go(x, y, 5)
    p.line(x, y, -0.5, 800)
    first = True
    for row in range(int(rng.integers(3, 6))):
        hd = 0.0 if row % 2 == 0 else math.pi
        travelled = 0.0
        while travelled < 90:
            seg = rng.uniform(5, 30)
            hd += math.radians(rng.uniform(1, 12)) * rng.choice([-1, 1])
            x, y = x + seg * math.cos(hd), y + seg * math.sin(hd)
            p.line(x, y, f=feed if first else None)
            first = False
            travelled += seg
        y += 10
        p.line(x, y)
    return p.text()


FAMILIES: dict[str, Callable[[np.random.Generator], str]] = {
    "random_polygons": random_polygons,
    "trochoid": trochoid,
    "gear": gear,
    "freeform": freeform,
    "spiral_pocket": spiral_pocket,
    "dome": dome,
    "engraving": engraving,
    "thread_milling": thread_milling,
    "part_25d": part_25d,
    "kinked_lines": kinked_lines,
}


def program(family: str, seed: int) -> str:
    """The program of ``family`` drawn with ``seed``."""
    return FAMILIES[family](np.random.default_rng(seed))
