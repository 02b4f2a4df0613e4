#!/usr/bin/python3
"""LinuxCNC's own interpreter against ncperf's reading, line by line, in machine coordinates.

    /usr/bin/python3 benchmarks/lcnc_oracle.py NCPERF FILE... [--json]

The system Python's ``gcode`` module (Debian's linuxcnc-uspace 2.9; install with
``../shared/tools/linuxcnc/install_linuxcnc.sh``) reads each program and calls back its
canonical moves. Its coordinates are relative to the program origin, which it reports
separately (set_g5x_offset, set_g92_offset, set_xy_rotation); this oracle places every
move where the machine goes -- machine = rotate(program + G92) + G5x, as LinuxCNC's preview
does (lib/python/rs274/interpret.py) -- so that a change of work offset is not a jump of the
tool. ``../shared/tools/linuxcnc/lcnc_path_check.py`` is the same check without the offsets.
Feed and rapid lengths are summed per source line (mm) and compared with what
``ncperf analyze --json --no-naive-cam`` lists per line (the module lists every block;
LinuxCNC's task joins nearly collinear blocks under G64 P/Q afterwards, which ncperf models
by default and tests/test_naivecam.py and tests/test_linuxcnc_planner_traces.py check). One
line per file: SAME, RAPIDS (feed path the
same), DIFF, MISS (ncperf refuses what LinuxCNC reads) or SKIP (LinuxCNC refuses it).

The interpreter runs the startup code of the trace suite's millimetre machine
(default_mill_mm.ini: G21 G17 G90 G94 G40 G49 G80 G54), so a program without G20/G21 is
read in millimetres, as ncperf reads it; tools 1-999 have zero diameter and length (T
words, G43 and H are taken out of the copy it reads, as the shared check does: outside a
running LinuxCNC a tool change stops the module).
"""

from __future__ import annotations

import json
import math
import multiprocessing as mp
import os
import queue
import re
import subprocess
import sys
import tempfile
import time
from collections import defaultdict

MM_PER_INCH = 25.4
#: The machine's startup code: RS274NGC_STARTUP_CODE of
#: ../shared/tools/linuxcnc/machines/default_mill_mm.ini (the trace suite's millimetre mill),
#: so that a program without G20/G21 is read in millimetres as that machine reads it.
STARTUP_CODE = "G21 G17 G90 G94 G40 G49 G80 G54"
TOOL_WORDS = re.compile(r"(?i)(?:\bG\s*0*4[39](?:\.\d)?(?![\d.])|\bT\s*\d+|\bH\s*\d+)")
COMMENT = re.compile(r"\([^)]*\)|;.*$")


class MachineCanon:
    """Canonical callbacks -> feed and rapid length per source line, machine coordinates."""

    def __init__(self) -> None:
        self.line = 0
        self.plane = 1
        self.here = (0.0, 0.0, 0.0)  # machine position (mm); ncperf starts at 0 too
        self.g5x = [0.0] * 3
        self.g92 = [0.0] * 3
        self.rot = 0.0
        self.feed: dict[int, float] = defaultdict(float)
        self.rapid: dict[int, float] = defaultdict(float)

    def __getattr__(self, name):
        answers = {
            "get_external_length_units": lambda: 1 / MM_PER_INCH,
            "get_external_angular_units": lambda: 1.0,
            "get_axis_mask": lambda: 7,
            "get_block_delete": lambda: False,
            "get_tool": lambda i: ((i if 0 < i < 1000 else -1),) + (0.0,) * 12 + (0,),
        }
        if name in answers:
            return answers[name]
        if name == "parameter_file":
            return ""
        if name.startswith("__"):
            raise AttributeError(name)
        return lambda *a, **k: None

    # offsets
    def set_g5x_offset(self, index, x, y, z, *rest):
        self.g5x = [x * MM_PER_INCH, y * MM_PER_INCH, z * MM_PER_INCH]

    def set_g92_offset(self, x, y, z, *rest):
        self.g92 = [x * MM_PER_INCH, y * MM_PER_INCH, z * MM_PER_INCH]

    def set_xy_rotation(self, theta):
        self.rot = math.radians(theta)

    def machine(self, x, y, z):
        p = [
            x * MM_PER_INCH + self.g92[0],
            y * MM_PER_INCH + self.g92[1],
            z * MM_PER_INCH + self.g92[2],
        ]
        if self.rot:
            c, s = math.cos(self.rot), math.sin(self.rot)
            p[0], p[1] = p[0] * c - p[1] * s, p[0] * s + p[1] * c
        return (p[0] + self.g5x[0], p[1] + self.g5x[1], p[2] + self.g5x[2])

    # moves
    def next_line(self, state):
        self.line = state.sequence_number

    def set_plane(self, plane):
        self.plane = plane

    def _to(self, table, x, y, z):
        end = self.machine(x, y, z)
        if self.here is not None:
            table[self.line] += math.dist(self.here, end)
        self.here = end

    def straight_traverse(self, x, y, z, *rest):
        self._to(self.rapid, x, y, z)

    def straight_feed(self, x, y, z, *rest):
        self._to(self.feed, x, y, z)

    def straight_probe(self, x, y, z, *rest):
        self._to(self.feed, x, y, z)

    def rigid_tap(self, x, y, z, *rest):
        start = self.here
        end = self.machine(x, y, z)
        if start is not None:
            self.feed[self.line] += 2 * math.dist(start, end)

    def arc_feed(self, first_end, second_end, first_axis, second_axis, rotation, axis_end, *rest):
        # the plane's axes: 1 XY (Z normal), 2 YZ (X normal), 3 XZ (Y normal)
        order = {1: (0, 1, 2), 2: (1, 2, 0), 3: (2, 0, 1)}[self.plane]
        prog_end = [0.0, 0.0, 0.0]
        prog_end[order[0]], prog_end[order[1]], prog_end[order[2]] = first_end, second_end, axis_end
        prog_c = [0.0, 0.0, 0.0]
        prog_c[order[0]], prog_c[order[1]] = first_axis, second_axis
        end = self.machine(*prog_end)
        centre = self.machine(*prog_c)
        start = self.here
        if start is None:
            self.here = end
            return
        i, j, k = order
        a0 = math.atan2(start[j] - centre[j], start[i] - centre[i])
        a1 = math.atan2(end[j] - centre[j], end[i] - centre[i])
        sweep = a1 - a0
        if rotation > 0:
            while sweep <= 1e-12:
                sweep += 2 * math.pi
            sweep += 2 * math.pi * (rotation - 1)
        else:
            while sweep >= -1e-12:
                sweep -= 2 * math.pi
            sweep -= 2 * math.pi * (-rotation - 1)
        r0 = math.hypot(start[i] - centre[i], start[j] - centre[j])
        r1 = math.hypot(end[i] - centre[i], end[j] - centre[j])
        self.feed[self.line] += math.hypot(abs(sweep) * (r0 + r1) / 2, end[k] - start[k])
        self.here = end


def _copy_without_tools(text: str) -> str:
    out = []
    for line in text.split("\n"):
        line = line.rstrip("\r")
        parts, last = [], 0
        for m in COMMENT.finditer(line):
            parts.append(TOOL_WORDS.sub(" ", line[last : m.start()]))
            parts.append(m.group(0))
            last = m.end()
        parts.append(TOOL_WORDS.sub(" ", line[last:]))
        out.append("".join(parts))
    return "\n".join(out) + "\n"


def _read(path, q):
    import gcode

    canon = MachineCanon()
    folder = os.path.dirname(os.path.abspath(path))
    with tempfile.TemporaryDirectory() as d:
        copy = os.path.join(d, "program.ngc")
        with open(path, errors="replace", newline="") as f, open(copy, "w") as g:
            g.write(_copy_without_tools(f.read()))
        # o<name> call finds name.ngc in the current folder: copies of the program's
        # neighbours go there (the interpreter also writes its parameter file there)
        for name in os.listdir(folder):
            if name.lower().endswith(".ngc") and name != os.path.basename(path):
                with open(os.path.join(folder, name), errors="replace", newline="") as f:
                    text = f.read()
                with open(os.path.join(d, name), "w") as g:
                    g.write(_copy_without_tools(text))
        cwd = os.getcwd()
        os.chdir(d)
        try:
            res, last = gcode.parse(copy, canon, "", STARTUP_CODE)
        finally:
            os.chdir(cwd)
    if res > gcode.MIN_ERROR:
        q.put((None, f"line {last}: {gcode.strerror(res)}"))
    else:
        q.put(((dict(canon.feed), dict(canon.rapid)), None))


def linuxcnc(path):
    """((feed per line, rapid per line), None) or (None, why LinuxCNC does not read it)."""
    ctx = mp.get_context("fork")
    q = ctx.Queue()
    p = ctx.Process(target=_read, args=(path, q))
    p.start()
    t0 = time.time()
    while True:
        try:
            out = q.get(timeout=0.2)
            break
        except queue.Empty:
            if not p.is_alive() and q.empty():
                out = (None, f"the LinuxCNC interpreter module died (exit {p.exitcode})")
                break
            if time.time() - t0 > 300:
                p.kill()
                out = (None, "the LinuxCNC interpreter took over 300 s")
                break
    p.join(5)
    return out


def ncperf(exe, path):
    with tempfile.TemporaryDirectory() as d:
        j = os.path.join(d, "o.json")
        # --no-naive-cam: the module lists every block, as the interpreter reads it; LinuxCNC's
        # task joins nearly collinear ones afterwards (tests/test_naivecam.py checks that)
        cmd = [exe, "analyze", path, "--json", j, "--no-naive-cam"]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            lines = (r.stderr or r.stdout).strip().splitlines() or [f"exit {r.returncode}"]
            return None, lines[-1][:200]
        with open(j) as fh:
            elements = json.load(fh).get("elements", [])
    feed, rapid = defaultdict(float), defaultdict(float)
    for e in elements:
        (rapid if e["kind"] == "rapid" else feed)[int(e["line"])] += float(e["length_mm"])
    return (feed, rapid), None


def first_difference(a, b):
    """The first line whose lengths differ by more than 10 um + 0.1 % (arcs whose end is
    off their circle are measured a few microns apart), or None."""
    for line in sorted(set(a) | set(b)):
        x, y = a.get(line, 0.0), b.get(line, 0.0)
        if abs(x - y) > 1e-2 + 1e-3 * x:
            return line, x, y
    return None


def check(exe, path):
    ref, why = linuxcnc(path)
    if ref is None:
        return "skip", f"LinuxCNC does not read it ({why})"
    got, why = ncperf(exe, path)
    if got is None:
        return "miss", f"ncperf refuses what LinuxCNC reads: {why}"
    d = first_difference(ref[0], got[0])
    if d:
        return "diff", f"feed differs from line {d[0]}: {d[2]:.5f} mm vs LinuxCNC's {d[1]:.5f} mm"
    d = first_difference(ref[1], got[1])
    if d:
        return (
            "rapids",
            f"rapids differ from line {d[0]}: {d[2]:.4f} mm vs LinuxCNC's {d[1]:.4f} mm",
        )
    return "same", f"same path ({len(ref[0]) + len(ref[1])} lines with motion)"


def main(argv):
    as_json = "--json" in argv
    args = [a for a in argv if a != "--json"]
    exe, files = args[0], args[1:]
    results = []
    for f in files:
        status, text = check(exe, f)
        results.append({"file": f, "status": status, "text": text})
        if not as_json:
            print(f"{os.path.basename(f)}: {status.upper()} {text}", flush=True)
    counts = defaultdict(int)
    for r in results:
        counts[r["status"]] += 1
    n = len(files) - counts["skip"]
    if as_json:
        print(json.dumps(results))
    else:
        print(
            f"LinuxCNC cross-check (machine coordinates): {counts['same']}/{n} programs LinuxCNC "
            f"reads give the same path ({counts['rapids']} differ in rapids only, "
            f"{counts['diff']} in the feed path, {counts['miss']} refused)"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
