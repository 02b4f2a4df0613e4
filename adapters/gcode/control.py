"""The controller's modal machine: executed blocks -> moves, as the controller runs them.

:mod:`adapters.gcode.run` executes the program's control flow and hands every block, its
words evaluated, to :class:`Controller`, which keeps the modal state (units, distance
mode, plane, motion mode, feed, path mode, work offsets and frames, tool, cutter
compensation, canned-cycle state) and emits the moves: lines, arcs and helices in machine
coordinates, canned cycles expanded into their rapid and feed moves, home returns to the
machine file's home position, cutter compensation applied (:mod:`adapters.gcode.comp`).

The order of execution within a block is rs274ngc's (LinuxCNC G-code reference, "Order of
Execution"): feed, tool, dwell, plane, units, compensation, coordinate system, path mode,
distance mode, retract mode, G10/G28/G30/G52/G92, motion, stops. Fanuc and Siemens
differ where the dialect tables say so. Facts (cycle expansions, home moves, offsets) are
from the LinuxCNC 2.9 interpreter (rs274ngc interp_cycles.cc, interp_convert.cc at
f1270d6ed7, the build of Debian's linuxcnc-uspace 2.9), the Fanuc 0i-MF and Haas mill
operator's manuals and the SINUMERIK 840D sl programming manuals; no code is taken.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from adapters.gcode import words as W
from adapters.gcode.comp import Compensator
from adapters.gcode.interp import State
from adapters.gcode.setup import ORIGIN, MachineSetup, Vec
from core.model.errors import Notes
from core.model.limits import MAX_PECKS, MAX_TOOL
from core.model.tolerances import TOL
from core.model.toolpath import PathMode

INCH = 25.4
#: Plane -> (first axis, second axis, normal axis) indices; and the normal vector.
PLANES = {170: (0, 1, 2), 180: (2, 0, 1), 190: (1, 2, 0)}
NORMALS = {170: (0.0, 0.0, 1.0), 180: (0.0, 1.0, 0.0), 190: (1.0, 0.0, 0.0)}
CYCLES = {730, 740, 760, 810, 820, 830, 840, 850, 860, 870, 880, 890}
#: LinuxCNC 2.9's G73/G83 retract past the last peck depth (interp_internal.hh
#: G83_RAPID_DELTA): 0.010 inch, 0.254 mm. A Fanuc's is its parameters 5114 (G73) and 5115
#: (G83), a Haas's its setting 22: each machine its own, so the machine file's
#: ``peck_clearance``, else LinuxCNC's. Siemens CYCLE83 computes its own (below).
PECK_CLEARANCE_INCH = 0.010


#: Most moves a program may make (ten million: the tool path's arrays then take gigabytes);
#: beyond, the run stops with an error -- a loop without end, or a program too long.
MAX_MOVES = 10_000_000

#: Where the Fanuc external work offset (G10 L2 P0) is kept among the work offsets.
EXTERNAL_OFFSET = 0


class ControlError(Exception):
    """An error of the current block (the runner adds file, line and text)."""


@dataclass(slots=True)
class Move:
    """One move as the controller runs it (machine coordinates, mm; feed mm/s)."""

    kind: int  # 0 rapid, 1 line, 2 cw, 3 ccw
    start: Vec
    end: Vec
    feed: float
    line: int
    file: int
    call: int
    exact: bool = False
    dwell: float = 0.0
    tolerance: float = math.nan
    tool: int = -1
    block: int = -1
    center: Vec | None = None
    normal: Vec | None = None
    turns: int = 0  # extra full turns of an arc
    rot_start: Vec = ORIGIN  # A, B, C (deg)
    rot_end: Vec = ORIGIN
    op: int = 0
    inverse: float = math.nan  # G93: the move takes 1 / inverse minutes
    feed_unit: float = 1.0  # mm per program unit of F (a rotary move's F is deg/min)


def _vec(a: Any) -> Vec:
    return (float(a[0]), float(a[1]), float(a[2]))


def _add(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


class Frame:
    """Program -> machine coordinates: machine = M p + t (M a rotation, uniform scale or
    mirror; None for the identity)."""

    def __init__(self, m: tuple[Vec, Vec, Vec] | None = None, t: Vec = ORIGIN) -> None:
        self.m = m
        self.t = t

    def apply(self, p: Vec) -> Vec:
        m = self.m
        if m is None:
            return (p[0] + self.t[0], p[1] + self.t[1], p[2] + self.t[2])
        return (
            m[0][0] * p[0] + m[0][1] * p[1] + m[0][2] * p[2] + self.t[0],
            m[1][0] * p[0] + m[1][1] * p[1] + m[1][2] * p[2] + self.t[1],
            m[2][0] * p[0] + m[2][1] * p[1] + m[2][2] * p[2] + self.t[2],
        )

    def vector(self, v: Vec) -> Vec:
        m = self.m
        if m is None:
            return v
        return (
            m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
            m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
        )

    def inverse(self, q: Vec) -> Vec:
        d = _sub(q, self.t)
        m = self.m
        if m is None:
            return d
        inv = _inv3(m)
        return (
            inv[0][0] * d[0] + inv[0][1] * d[1] + inv[0][2] * d[2],
            inv[1][0] * d[0] + inv[1][1] * d[1] + inv[1][2] * d[2],
            inv[2][0] * d[0] + inv[2][1] * d[1] + inv[2][2] * d[2],
        )

    def scale(self) -> float:
        """The uniform scale of M (1 for the identity); -1 marks a mirror (det < 0)."""
        if self.m is None:
            return 1.0
        det = _det3(self.m)
        return math.copysign(abs(det) ** (1.0 / 3.0), det)


def _det3(m: tuple[Vec, Vec, Vec]) -> float:
    return (
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    )


def _inv3(m: tuple[Vec, Vec, Vec]) -> tuple[Vec, Vec, Vec]:
    d = _det3(m)
    if d == 0:
        raise ControlError("the coordinate frame is singular (a scale of 0)")
    a = m
    return (
        (
            (a[1][1] * a[2][2] - a[1][2] * a[2][1]) / d,
            (a[0][2] * a[2][1] - a[0][1] * a[2][2]) / d,
            (a[0][1] * a[1][2] - a[0][2] * a[1][1]) / d,
        ),
        (
            (a[1][2] * a[2][0] - a[1][0] * a[2][2]) / d,
            (a[0][0] * a[2][2] - a[0][2] * a[2][0]) / d,
            (a[0][2] * a[1][0] - a[0][0] * a[1][2]) / d,
        ),
        (
            (a[1][0] * a[2][1] - a[1][1] * a[2][0]) / d,
            (a[0][1] * a[2][0] - a[0][0] * a[2][1]) / d,
            (a[0][0] * a[1][1] - a[0][1] * a[1][0]) / d,
        ),
    )


def _matmul(a: tuple[Vec, Vec, Vec], b: tuple[Vec, Vec, Vec]) -> tuple[Vec, Vec, Vec]:
    return tuple(  # type: ignore[return-value]
        tuple(sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)) for i in range(3)
    )


def _rotation(plane: int, degrees: float) -> tuple[Vec, Vec, Vec]:
    """Rotation by ``degrees`` about the plane's normal (counter-clockwise seen from +N)."""
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    i, j, _ = PLANES[plane]
    m = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    m[i][i], m[i][j], m[j][i], m[j][j] = c, -s, s, c
    return (tuple(m[0]), tuple(m[1]), tuple(m[2]))  # type: ignore[return-value]


class Controller:
    """The modal state of one program run (see the module docstring)."""

    def __init__(
        self,
        dialect: str,
        setup: MachineSetup,
        notes: Notes,
        params: Any,
    ) -> None:
        self.dialect = dialect
        self.setup = setup
        self.notes = notes
        self.params = params  # the runner's parameter store (LinuxCNC #5220...)
        self.moves: list[Move] = []
        #: runs of plain lines read by the vectorised reader: (index in moves they come
        #: before, their columns)
        self.segments: list[tuple[int, dict[str, Any]]] = []
        self.plain_moves = 0  # moves in the segments
        #: the translation of the coordinate system in force at the first move: the tool
        #: path is drawn in that system (the part's), not in machine coordinates
        self.origin: Vec | None = None
        # modal state
        self.units = 210 if dialect != "siemens" else 710
        self.units_set = False
        self.absolute = True
        self.arc_absolute = False
        self.plane = 170
        self.motion: int | None = None
        self.feed: float | None = None  # mm/s
        self.feed_units_inch = False
        self.path_mode: int | None = None  # None: never set by the program
        self.tolerance = math.nan
        self.wcs = 540 if dialect != "siemens" else 5000  # Siemens G500: no settable offset
        self.wcs_offsets: dict[int, Vec] = dict(setup.offsets)
        self.wcs_rotation: dict[int, float] = {}
        self.g92: Vec = ORIGIN
        self.g92_saved: Vec = ORIGIN
        self.g52: Vec = ORIGIN
        self.rotation: tuple[float, float, float] | None = None  # G68: cx, cy, degrees
        self.rotation_plane = 170
        self.scaling: tuple[Vec, Vec] | None = None  # G51: centre, factors
        self.mirror: Vec = (1.0, 1.0, 1.0)
        self.mirror_centre: Vec = ORIGIN
        self.siemens_frame: Frame | None = None  # TRANS/ROT/SCALE/MIRROR chain
        self.tool = -1
        self.tool_selected = -1
        self.tool_name: str | None = None
        self.named_tools: dict[str, int] = {}
        #: the program's first F (value, 0-based line), for feed moves before it
        self.later_feed: tuple[float, int] | None = None
        self.length_offset = 0.0  # G43, added to Z
        self.comp = Compensator(self)
        self.inverse_time = False  # G93: F is 1 / (minutes of the move)
        self.inverse_f = math.nan
        # G99 (back to R) or G98: LinuxCNC's interpreter starts in G99 (interp_setup.cc
        # retract_mode = R_PLANE) unless the startup code says G98; Fanuc powers on in G98
        self.retract_r_plane = dialect == "linuxcnc"
        self.canned: int | None = None  # the canned cycle in force (G73, G81...)
        self.spindle_speed = 0.0
        self.cycle: dict[str, float] = {}
        self.cycle_initial: float | None = None
        self.mcall: tuple | None = None
        self.spindle_cw: bool | None = None
        # position
        self.pos: Vec = ORIGIN  # machine coordinates, mm
        self.rot: Vec = ORIGIN
        self.rot_offset: Vec = ORIGIN  # G92 on rotary axes: machine - program angle
        self.known = [False, False, False]
        self.line = 0
        self.file = 0
        self.call = -1
        self.block_number = -1
        self.op = 0
        self.ended = False
        self._frame_cache: Frame | None = None
        self.ops_changes: list[int] = []
        self.probed: Vec | None = None
        self.corner: tuple[int, str, float] | None = None  # a Fanuc ,R/,C waiting
        self._system_parameters()

    def _system_parameters(self) -> None:
        """Read-only parameters a program may read: the current position, tool, offsets
        (LinuxCNC #5420-#5422, #5400, #5211-#5213, #5061-#5063; Fanuc #5041-#5043,
        #5001-#5003, #5021-#5023, #4120, #4001...; in program units)."""
        prov = self.params.providers

        def pos(k: int) -> Callable[[], float]:
            return lambda: self.program_pos()[k] / self.scale

        def mach(k: int) -> Callable[[], float]:
            return lambda: self.pos[k] / self.scale

        def probe(k: int) -> Callable[[], float]:
            return lambda: (self.frame().inverse(self.probed)[k] / self.scale
                            if self.probed is not None else 0.0)  # fmt: skip

        if self.dialect == "linuxcnc":
            for k in range(3):
                prov[5420 + k] = pos(k)
                prov[5211 + k] = lambda k=k: self.g92[k] / self.scale
                prov[5061 + k] = probe(k)
            prov[5400] = lambda: float(self.tool)
            prov[5070] = lambda: 1.0 if self.probed is not None else 0.0
        elif self.dialect == "fanuc":
            for k in range(3):
                prov[5001 + k] = pos(k)
                prov[5041 + k] = pos(k)
                prov[5021 + k] = mach(k)
                prov[5061 + k] = probe(k)
            prov[4001] = lambda: float((self.motion or 0) / 10)
            prov[4003] = lambda: 90.0 if self.absolute else 91.0
            prov[4006] = lambda: 20.0 if self.scale != 1.0 else 21.0
            prov[4014] = lambda: float(self.wcs / 10)
            prov[4109] = lambda: float(self.feed * 60.0 / self._feed_scale()) if self.feed else 0.0
            prov[4120] = lambda: float(self.tool_selected)

    # ------------------------------------------------------------------ coordinates
    @property
    def scale(self) -> float:
        """mm per program unit (geometry)."""
        return INCH if self.units in (200, 700, 7000) else 1.0

    def frame(self) -> Frame:
        """Program (mm) -> machine coordinates in the current state."""
        if self._frame_cache is not None:
            return self._frame_cache
        off = self.wcs_offsets.get(self.wcs, ORIGIN)
        if EXTERNAL_OFFSET in self.wcs_offsets and self.dialect == "fanuc":
            off = _add(off, self.wcs_offsets[EXTERNAL_OFFSET])
        local = _add(self.g92, self.g52)
        m: tuple[Vec, Vec, Vec] | None = None
        rot = self.wcs_rotation.get(self.wcs, 0.0)
        if rot:
            # LinuxCNC: machine = R (p + G92) + G5x (its G10 L2 R rotates the system)
            m = _rotation(170, rot)
            local = Frame(m).vector(local)
        t = _add(off, local)
        t = (t[0], t[1], t[2] + self.length_offset)
        if self.rotation is not None:
            cx, cy, ang = self.rotation
            r = _rotation(self.rotation_plane, ang)
            i, j, _ = PLANES[self.rotation_plane]
            c = [0.0, 0.0, 0.0]
            c[i], c[j] = cx, cy
            cvec: Vec = (c[0], c[1], c[2])
            # p -> c + R (p - c)
            shift = _sub(cvec, Frame(r).apply(cvec))
            m2 = r
            t_rot = shift
            if m is None:
                m, t = m2, _add(Frame(None, t).apply(t_rot), ORIGIN)
            else:
                t = _add(Frame(m).vector(t_rot), t)
                m = _matmul(m, m2)
        if self.scaling is not None or self.mirror != (1.0, 1.0, 1.0):
            # mirror about its centre, then scale about the scaling centre:
            # p -> cs + fs (cm + fm (p - cm) - cs) = (fs fm) p + cs (1 - fs) + fs cm (1 - fm)
            centre, fs = self.scaling or (ORIGIN, (1.0, 1.0, 1.0))
            fm, cm = self.mirror, self.mirror_centre
            f = (fs[0] * fm[0], fs[1] * fm[1], fs[2] * fm[2])
            s: tuple[Vec, Vec, Vec] = ((f[0], 0.0, 0.0), (0.0, f[1], 0.0), (0.0, 0.0, f[2]))
            shift = (
                centre[0] * (1 - fs[0]) + fs[0] * cm[0] * (1 - fm[0]),
                centre[1] * (1 - fs[1]) + fs[1] * cm[1] * (1 - fm[1]),
                centre[2] * (1 - fs[2]) + fs[2] * cm[2] * (1 - fm[2]),
            )
            if m is None:
                m = s
                t = _add(t, shift)
            else:
                t = _add(Frame(m).vector(shift), t)
                m = _matmul(m, s)
        if self.siemens_frame is not None:
            sf = self.siemens_frame
            if m is None:
                m = sf.m
                t = _add(t, sf.t)
            else:
                t = _add(Frame(m).vector(sf.t), t)
                m = _matmul(m, sf.m) if sf.m is not None else m
        self._frame_cache = Frame(m, t)
        return self._frame_cache

    def changed(self) -> None:
        self._frame_cache = None

    def program_pos(self) -> Vec:
        """The current point in program coordinates (mm): with cutter compensation on, the
        programmed point, not the tool's (axes not written and increments start there)."""
        if self.comp.side != 0 and self.comp.prog is not None:
            return self.frame().inverse(self.comp.prog)
        return self.frame().inverse(self.pos)

    # ------------------------------------------------------------------ runs of plain lines
    def plain_state(self) -> State | None:
        """The state to hand a run of plain lines to the vectorised reader with, or None when
        the controller is in a state that reader does not model (see adapters.gcode.plain)."""
        if (
            self.dialect not in ("linuxcnc", "fanuc")
            or self.comp.side != 0
            or self.comp.pending is not None
            or self.canned is not None
            or self.corner is not None
            or self.mcall is not None
            or self.inverse_time
            or self.units not in (200, 210)
            or self.motion not in (None, 0, 10, 20, 30)
        ):
            return None
        fr = self.frame()
        if fr.m is not None:
            return None
        p = fr.inverse(self.pos)
        pm = self.path_mode
        if pm is None:
            pm = W.exact_stop_codes(self.dialect)[0] if self._path_exact() else 640
        return State(
            motion=-1 if self.motion is None else self.motion,
            plane=self.plane,
            distance=900 if self.absolute else 910,
            arc_distance=901 if self.arc_absolute else 911,
            units=self.units,
            path_mode=pm,
            tolerance=self.tolerance,
            feed=math.nan if self.feed is None else self.feed,
            pos=p,
            known=(self.known[0], self.known[1], self.known[2]),
        )

    def take_run(self, cols: dict | None, final: State, file: int, call: int) -> None:
        """The moves and the end state of a run of plain lines read by the vectorised reader
        (program coordinates): moved to machine coordinates and appended, the last as a
        :class:`Move` so that what follows (a dwell, a stop) can still reach it."""
        t = self.frame().t
        if cols is not None:
            if self.origin is None:
                self.origin = t
            n = cols["kind"].size
            shift = np.array(t, dtype=np.float64)
            cols["start"] = cols["start"] + shift
            cols["end"] = cols["end"] + shift
            arc = cols["kind"] >= 2
            cols["center"] = np.where(arc[:, None], cols["center"] + shift, cols["center"])
            cols["tool"] = np.full(n, self.tool, dtype=np.int32)
            cols["file"] = file
            cols["call"] = call
            cols["op"] = self.op
            self._count(n)
            if n > 1:
                head = {k: v[:-1] if isinstance(v, np.ndarray) else v for k, v in cols.items()}
                self.segments.append((len(self.moves), head))
                self.plain_moves += n - 1
            k = n - 1
            kind = int(cols["kind"][k])
            self.moves.append(
                Move(
                    kind=kind,
                    start=_vec(cols["start"][k]),
                    end=_vec(cols["end"][k]),
                    feed=float(cols["feed"][k]),
                    line=int(cols["line"][k]) - 1,
                    file=file,
                    call=call,
                    exact=bool(cols["path_mode"][k] == PathMode.EXACT_STOP),
                    tolerance=float(cols["tolerance"][k]),
                    tool=self.tool,
                    block=int(cols["block"][k]),
                    center=_vec(cols["center"][k]) if kind >= 2 else None,
                    normal=_vec(cols["normal"][k]) if kind >= 2 else None,
                    rot_start=self.rot,
                    rot_end=self.rot,
                    op=self.op,
                )
            )
        self.motion = None if final.motion in (-1, 800) else final.motion
        self.plane = final.plane
        self.absolute = final.distance == 900
        self.arc_absolute = final.arc_distance == 901
        if final.units_set:
            self.units = final.units
            self.units_set = True
        if final.path_mode_set:
            self.path_mode = final.path_mode
        self.tolerance = final.tolerance
        if final.feed == final.feed:
            self.feed = final.feed
        self.pos = self.frame().apply(final.pos)
        self.known = list(final.known)

    def _count(self, more: int) -> None:
        if len(self.moves) + self.plain_moves + more > MAX_MOVES:
            raise ControlError(
                f"more than {MAX_MOVES:,} moves: the program loops without end, or is longer "
                "than ncperf reads"
            )

    # ------------------------------------------------------------------ words
    def block(self, words: dict[str, Any], extra: dict[str, Any]) -> None:
        """Execute one block (words: letter -> value, "G" and "M" -> lists of codes x 10
        and M numbers)."""
        g = words.get("G", [])
        m = words.get("M", [])
        if self.dialect == "fanuc" and (842 in g or 843 in g):
            # Fanuc rigid tapping G84.2 / G84.3 (left hand): G84 / G74 with the spindle
            # synchronised, the same moves
            g = words["G"] = [840 if c == 842 else 740 if c == 843 else c for c in g]
        table = W.FULL_TABLES[self.dialect]
        for code in g:
            entry = table.get(code)
            if entry is None:
                raise ControlError(f"unknown G-code G{code / 10:g} ({self.dialect} dialect)")
            if entry.group is None:
                raise ControlError(entry.message)
        self._check(words, g, m)
        self._modes(words, g, m, extra)
        self._motion(words, g, m, extra)
        self._stops(m)

    def _check(self, words: dict[str, Any], g: list[int], m: list[int]) -> None:
        """Two codes of one modal group, and words no code of the block uses: errors, never a
        silent misreading."""
        seen: dict[str, int] = {}
        lc = self.dialect == "linuxcnc"
        for code in g:
            group = _modal_group(code, lc)
            if group is None:
                continue
            if group in seen:
                raise ControlError("two G-codes of the same modal group in one block")
            seen[group] = code
        motion = seen.get("motion", self.motion if self.canned is None else None)
        cycle = seen.get("cycle", self.canned) if not lc else (motion if motion in CYCLES else None)
        if lc and "motion" not in seen and self.canned is not None:
            cycle = self.canned
        arc = motion in (20, 30) and cycle is None
        uses: set[str] = set()
        if arc:
            uses |= set("IJKR")
            if lc:
                uses.add("P")
            else:
                uses.add("L")
        if cycle is not None:
            uses |= set("RPQLK")
            if cycle == 870:
                uses |= set("IJ")
        if motion in (330, 331):
            uses.add("K")
        if motion == 10 and cycle is None and self.dialect == "fanuc":
            uses.add("R")  # corner rounding on a line
        for code in g:
            if code == 40:
                uses |= set("PX") | ({"F", "S"} if self.dialect == "siemens" else set())
            elif code == 100:
                uses |= set("LPRIJKQ")
            elif code in (120, 130):
                uses |= set("IKQDLR")
            elif code == 640 and lc:
                uses |= set("PQ")
            elif code in (680, 681):
                uses.add("R")
            elif code == 510:
                uses |= set("IJKP")
            elif code == 541:
                uses.add("P")
            elif code == 650:
                uses |= set(G65_LETTERS)
            elif code in (50, 51, 80):
                uses |= set("PQR")  # look-ahead modes (G05 P, G05.1 Q1, G08 P1)
        if m:
            uses |= set("PQLE")  # M-codes with arguments (M66, M98...)
        for letter in words:
            if letter in ("G", "M") or letter in "NFSTDHXYZABC@^":
                continue
            if letter in (",R", ",C"):
                if motion != 10 or cycle is not None:
                    raise ControlError(
                        f"{letter} (corner rounding, chamfer) on a block that is not a line"
                    )
                continue
            if letter in "UVW":
                raise ControlError(f"axis word {letter}: only X, Y, Z and A, B, C are supported")
            if letter not in "IJKRPQL":
                raise ControlError(f"unknown word {letter}")
            if letter not in uses:
                if letter in "IJKR" and not arc:
                    raise ControlError(f"{letter} word on a block that is not an arc")
                raise ControlError(f"{letter} word not used by any code in this block")

    # The table of the dialect decides what each G-code is; unknown ones raise.
    def _modes(self, words: dict[str, Any], g: list[int], m: list[int], extra: dict) -> None:
        d = self.dialect
        table = W.FULL_TABLES[d]
        for code in g:
            entry = table[code]
            if entry.message and entry.group == W.Group.PASS:
                self.notes.add(entry.message, self.line)
        # feed
        if 950 in g:
            raise ControlError("G95 feed per revolution is not supported")
        if 930 in g:
            self.inverse_time = True
        elif 940 in g:
            self.inverse_time = False
        self.inverse_f = math.nan
        if "F" in words and not (40 in g and d == "siemens"):
            f = words["F"]
            if f <= 0:
                raise ControlError("feed F must be positive")
            if self.inverse_time:
                self.inverse_f = f  # 1 / minutes for this block's move
            else:
                self.feed = f * self._feed_scale() / 60.0
        # tool
        if "T" in words:
            t = words["T"]
            if not (0 <= t <= MAX_TOOL and t == int(t)):
                raise ControlError(f"tool number must be a whole number 0 to {MAX_TOOL}")
            self.tool_selected = int(t)
        if "S" in words and d != "siemens" or ("S" in words and 40 not in g):
            self.spindle_speed = abs(words["S"])
        if "tool" in extra:
            self.tool_name = extra["tool"]
            # a named tool has no number: -2, -3, ... one per name, in order of appearance
            self.tool_selected = self.named_tools.setdefault(
                self.tool_name, -2 - len(self.named_tools)
            )
        if 6 in m or (d == "siemens" and ("T" in words or "tool" in extra) and 6 not in m):
            if 6 in m or d == "siemens":
                self._tool_change()
        if 3 in m:
            self.spindle_cw = True
        if 4 in m:
            self.spindle_cw = False
        if 5 in m:
            self.spindle_cw = None
        # dwell
        if 40 in g:
            self._dwell(words)
            if d == "fanuc":
                words.pop("X", None)  # Fanuc G4 X: seconds, not an axis
        for code in g:
            if code in (170, 180, 190):
                self.plane = code
            elif code in W.UNITS:
                self.units = code
                self.units_set = True
            elif code in (200, 210) and d != "siemens":
                self.units = code
                self.units_set = True
        # compensation
        for code in g:
            if code in (400, 410, 420, 411, 421):
                self.comp.mode(code, words, self._tool_radius(words))
        # length offset
        if 430 in g or 431 in g:
            h = int(words.get("H", self.tool if self.tool >= 0 else 0))
            self.length_offset = self.setup.tool_length.get(h, 0.0)
            self.changed()
        if 490 in g:
            self.length_offset = 0.0
            self.changed()
        # coordinate system
        for code in g:
            if 540 <= code <= 593 or (d == "siemens" and (code == 5000 or 5050 <= code <= 5990)):
                if code == 541 and d == "fanuc":  # G54.1 Pn: additional work offsets
                    code = 5400 + int(words.get("P", 1))
                if code != self.wcs and self.origin is not None and code not in self.wcs_offsets:
                    self.notes.add(
                        f"work offset changes to G{code / 10:g}, whose value is not known (no "
                        "G10 L2 in the program, no [offsets] in the machine file): 0 assumed, "
                        "so moves before and after may not be placed relative to each other",
                        self.line,
                    )
                self.wcs = code
                self.changed()
        # path mode
        for code in g:
            if code in (610, 611, 640, 600) or 6410 <= code <= 6450:
                self.path_mode = code
                if d == "linuxcnc":
                    # G64 P sets the path tolerance; G64 alone and G61.1 clear it; G61 is
                    # exact path, a tolerance of 0 (W.EXACT_PATH)
                    p = words.get("P") if code == 640 else None
                    self.tolerance = p * self.scale if p is not None and p > 0 else math.nan
                    if code == W.EXACT_PATH:
                        self.tolerance = 0.0
        if "settings" in extra:
            for name, value in extra["settings"]:
                if name == "CTOL":
                    self.tolerance = value * self.scale
        # distance mode
        for code in g:
            if code == 900:
                self.absolute = True
            elif code == 910:
                self.absolute = False
            elif code == 901:
                self.arc_absolute = True
            elif code == 911:
                self.arc_absolute = False
            elif code == 980 and d != "siemens":
                self.retract_r_plane = False
            elif code == 990 and d != "siemens":
                self.retract_r_plane = True
        if "frame" in extra:
            self._siemens_frame(*extra["frame"])
        # G10, G52, G92, G68, G51
        for code in g:
            if code == 100:
                self._g10(words)
            elif code == 520:
                self._g52(words)
            elif code in (920, 921, 922, 923):
                self._g92(code, words)
            elif code in (680, 681):
                self._g68(words)
            elif code == 690:
                self.rotation = None
                self.changed()
            elif code == 510 and d != "siemens":
                self._g51(words)
            elif code == 500 and d == "fanuc":
                self.scaling = None
                self.changed()
            elif code in (501, 511):
                self._mirror(code, words)

    def _feed_scale(self) -> float:
        """mm per program unit of feed (Siemens G70/G71 keep feeds in the basic system)."""
        return INCH if W.UNITS.get(self.units, (False, False))[1] else 1.0

    def _tool_radius(self, words: dict[str, Any]) -> float | None:
        if self.setup.tool_radius_override is not None:
            return self.setup.tool_radius_override
        d = words.get("D")
        key = int(d) if d is not None else self.tool
        return self.setup.tool_radius.get(key)

    def _tool_change(self) -> None:
        if self.tool_selected == self.tool and self.moves:
            return
        self.tool = self.tool_selected
        if self.moves:
            self.op += 1
        self.ops_changes.append(len(self.moves))

    def _dwell(self, words: dict[str, Any]) -> None:
        d = self.dialect
        if d == "linuxcnc":
            t = words.get("P")
        elif d == "fanuc":
            t = words["X"] if "X" in words else (words["P"] / 1000.0 if "P" in words else None)
            if t is None and "S" in words:
                # Marlin (and RepRap) G4 S: seconds, what Fusion's Marlin posts write
                t = words["S"]
                self.notes.add("G4 S read as seconds (Marlin)", self.line)
        else:
            if "S" in words and "F" not in words:
                raise ControlError("G4 S (dwell in spindle revolutions) is not supported")
            t = words.get("F")
        if t is None:
            raise ControlError("G4 dwell without a time")
        if t < 0:
            raise ControlError("negative dwell time")
        self._add_dwell(t)

    def _add_dwell(self, t: float) -> None:
        if self.moves:
            self.moves[-1].dwell += t
        elif t > 0:
            self.notes.add("G4 before the first move ignored", self.line)

    # ------------------------------------------------------------------ offsets
    def _axes(self, words: dict[str, Any]) -> dict[int, float]:
        return {k: words[a] * self.scale for k, a in enumerate("XYZ") if a in words}

    def _g10(self, words: dict[str, Any]) -> None:
        lv = words.get("L")
        if lv is None:
            raise ControlError("G10 without an L word")
        lv = int(lv)
        if lv in (2, 20):
            p = round(words.get("P", 0))
            if self.dialect == "fanuc" and p == 0:
                # the external work offset shifts every work coordinate system
                code = EXTERNAL_OFFSET
            else:
                code = self.wcs if p == 0 else 530 + 10 * p if 1 <= p <= 6 else 5400 + p
            if self.dialect == "linuxcnc" and 7 <= p <= 9:
                code = {7: 591, 8: 592, 9: 593}[p]
            old = self.wcs_offsets.get(code, ORIGIN)
            axes = self._axes(words)
            new = list(old)
            if lv == 2:
                for k, v in axes.items():
                    if self.dialect == "fanuc" and not self.absolute:
                        new[k] = old[k] + v
                    else:
                        new[k] = v
                if "R" in words:
                    self.wcs_rotation[code] = words["R"]
            else:  # L20: the current point gets these coordinates in that system
                here = self.pos
                for k, v in axes.items():
                    base = self.g92[k] + self.g52[k] + (self.length_offset if k == 2 else 0.0)
                    new[k] = here[k] - v - base
            self.wcs_offsets[code] = (new[0], new[1], new[2])
            self._store_offsets(code)
            self.changed()
        elif lv in (1, 10, 11, 12, 13, 3):
            t = int(words.get("P", -1))
            if "R" in words:
                self.setup.tool_radius[t] = abs(words["R"]) * self.scale
            elif "D" in words and lv != 3:
                self.setup.tool_radius[t] = abs(words["D"]) * self.scale / 2.0
            if "Z" in words and lv in (1, 10):
                self.setup.tool_length[t] = words["Z"] * self.scale
        else:
            raise ControlError(f"G10 L{lv} is not supported")

    def _store_offsets(self, code: int) -> None:
        if self.dialect != "linuxcnc" or not 540 <= code <= 593:
            return
        k = (code - 540) // 10 + 1 if code <= 590 else {591: 7, 592: 8, 593: 9}[code]
        off = self.wcs_offsets[code]
        for i in range(3):
            self.params.set(5201 + 20 * k + i, off[i] / self.scale)

    def _g52(self, words: dict[str, Any]) -> None:
        """G52 local offset. LinuxCNC keeps it in G92's registers (coordinates.adoc: G52 and
        G92 share them, so one replaces the other and G92.1 clears both); Fanuc adds it to
        the work system on its own."""
        if self.dialect == "linuxcnc":
            new = list(self.g92)
            for k, v in self._axes(words).items():
                new[k] = v
            self.g92 = self.g92_saved = (new[0], new[1], new[2])
            self.changed()
            return
        new = list(self.g52)
        for k, v in self._axes(words).items():
            new[k] = v
        self.g52 = (new[0], new[1], new[2])
        self.changed()

    def _g92(self, code: int, words: dict[str, Any]) -> None:
        if code == 920:
            axes = self._axes(words)
            rot = {k: words[a] for k, a in enumerate("ABC") if a in words}
            if not axes and not rot:
                raise ControlError("G92 without axis words")
            if rot:
                off = list(self.rot_offset)
                for k, v in rot.items():
                    off[k] = self.rot[k] - v
                self.rot_offset = (off[0], off[1], off[2])
            new = list(self.g92)
            wcs = self.wcs_offsets.get(self.wcs, ORIGIN)
            for k, v in axes.items():
                base = wcs[k] + self.g52[k] + (self.length_offset if k == 2 else 0.0)
                new[k] = self.pos[k] - base - v
            # LinuxCNC keeps the offset in #5211.. as well: G92.3 restores it from there
            self.g92 = self.g92_saved = (new[0], new[1], new[2])
        elif code in (921, 922):
            self.g92_saved = self.g92 if code == 922 else ORIGIN
            self.g92 = ORIGIN
            self.rot_offset = ORIGIN
        else:
            self.g92 = self.g92_saved
        self.changed()

    def _g68(self, words: dict[str, Any]) -> None:
        i, j, _ = PLANES[self.plane]
        here = self.program_pos()
        letters = "XYZ"
        cx = words[letters[i]] * self.scale if letters[i] in words else here[i]
        cy = words[letters[j]] * self.scale if letters[j] in words else here[j]
        ang = words.get("R")
        if ang is None:
            raise ControlError("G68 without a rotation angle R")
        if self.rotation is not None and not self.absolute:
            ang += self.rotation[2]
        self.rotation = (cx, cy, ang)
        self.rotation_plane = self.plane
        self.changed()

    def _g51(self, words: dict[str, Any]) -> None:
        here = self.program_pos()
        centre = tuple(
            words["XYZ"[k]] * self.scale if "XYZ"[k] in words else here[k] for k in range(3)
        )
        if "P" in words:
            f = (words["P"],) * 3
        else:
            f = tuple(words.get(c, 1.0) for c in "IJK")
        self.scaling = ((centre[0], centre[1], centre[2]), (f[0], f[1], f[2]))
        self.changed()

    def _mirror(self, code: int, words: dict[str, Any]) -> None:
        """Fanuc G51.1 X.. Y..: mirror about the given positions (axis words are the axes
        of symmetry, no move); G50.1 cancels it on the axes named (all without any)."""
        named = [k for k, c in enumerate("XYZ") if c in words]
        m = list(self.mirror)
        c = list(self.mirror_centre)
        if code == 501:
            for k in named or [0, 1, 2]:
                m[k], c[k] = 1.0, 0.0
        else:
            for k in named:
                m[k], c[k] = -1.0, words["XYZ"[k]] * self.scale
        self.mirror = (m[0], m[1], m[2])
        self.mirror_centre = (c[0], c[1], c[2])
        self.changed()

    def _siemens_frame(self, kind: str, values: dict[str, float]) -> None:
        additive = kind.startswith("A")
        base = self.siemens_frame if (additive and self.siemens_frame) else Frame()
        if not values and not additive:
            self.siemens_frame = None
            self.changed()
            return
        m = base.m
        t = base.t
        if kind.endswith("TRANS"):
            d = tuple(values.get(c, 0.0) * self.scale for c in "XYZ")
            t = _add(t, Frame(m).vector((d[0], d[1], d[2])))
        elif kind.endswith("ROT"):
            if "RPL" in values:
                r = _rotation(self.plane, values["RPL"])
            else:
                r = None
                for axis, plane in (("X", 190), ("Y", 180), ("Z", 170)):
                    if axis in values:
                        ra = _rotation(plane, values[axis])
                        r = ra if r is None else _matmul(r, ra)
            if r is not None:
                m = r if m is None else _matmul(m, r)
        elif kind.endswith("SCALE"):
            f = tuple(values.get(c, 1.0) for c in "XYZ")
            s: tuple[Vec, Vec, Vec] = ((f[0], 0.0, 0.0), (0.0, f[1], 0.0), (0.0, 0.0, f[2]))
            m = s if m is None else _matmul(m, s)
        elif kind.endswith("MIRROR"):
            f = tuple(-1.0 if c in values else 1.0 for c in "XYZ")
            s = ((f[0], 0.0, 0.0), (0.0, f[1], 0.0), (0.0, 0.0, f[2]))
            m = s if m is None else _matmul(m, s)
        self.siemens_frame = Frame(m, t)
        self.changed()

    # ------------------------------------------------------------------ motion
    def _motion(self, words: dict[str, Any], g: list[int], m: list[int], extra: dict) -> None:
        d = self.dialect
        home = [c for c in g if c in (280, 300)]
        machine = 530 in g or 1530 in g
        if machine:
            self._unknown_offset("G53")
        cycle_here = [c for c in g if c in CYCLES]
        for code in g:
            if code in (0, 10, 20, 30):
                self.motion = code
                self._end_cycle()
            elif code == 800:
                self._end_cycle()
                if d == "linuxcnc":
                    self.motion = None  # G80 is in G0's group: no motion mode after it
            elif code in CYCLES:
                self.canned = code
                if d == "linuxcnc":
                    self.motion = None
            elif code in (330, 331):
                self.motion = code
            elif code in (382, 383, 384, 385, 310):
                self.motion = code
            elif code in (120, 130):
                pass  # non-modal (Haas, Mach3)
        if home:
            self._home(home[0], words)
            return
        if "swivel" in extra:
            self._swivel(extra["swivel"])
        if "hsc" in extra:
            args = extra["hsc"][1]
            tol = args[0] if args and args[0] is not None else None
            if tol is not None and tol > 0:
                self.tolerance = tol * self.scale
            self.notes.add(
                "CYCLE832 (high-speed settings): its tolerance taken as the path "
                "tolerance; its smoothing is the machine's",
                self.line,
            )
        if "pattern" in extra:
            self._pattern(*extra["pattern"])
            return
        if any(c in g for c in (100, 920, 520, 680, 510, 501, 511)):
            return  # their axis words are data, not a move
        if "@" in words or "^" in words:
            self._polar(words)
        axis_words = [a for a in "XYZ" if a in words]
        rot_words = [a for a in "ABC" if a in words]
        if self.canned is not None and (axis_words or rot_words or cycle_here):
            if self.canned == 760 and d == "linuxcnc":
                raise ControlError("G76 threading cycle is not supported")
            self._cycle(self.canned, words, g)
            return
        pocket = [c for c in g if c in (120, 130)]
        if pocket:
            self._circle_pocket(pocket[0], words)
            return
        centre_words = any(c in words for c in "IJK")
        full_circle = (
            self.motion in (20, 30) and not axis_words and centre_words and (20 in g or 30 in g)
        )
        if not (axis_words or rot_words or full_circle):
            if "cycle" in extra:
                self._siemens_cycle(*extra["cycle"])
            return
        if self.motion is None:
            raise ControlError("axis words without a motion mode (G0, G1, G2 or G3)")
        unknown = "".join(a for a, k in zip("XYZ", self.known, strict=True) if not k)
        if unknown and self.motion != 0:
            self.notes.add(
                f"feed move starts before {unknown} was programmed: 0 assumed", self.line
            )
            self.known = [True, True, True]
        end, rot_end = self._target(words, machine, extra)
        if self.motion in (330, 331):
            self._tap(end, words, back=self.motion == 331)
            return
        if self.motion in (382, 383, 384, 385, 310):
            self.notes.add(
                "probing move: run to its programmed end (the probe would stop at contact)",
                self.line,
            )
            self._emit_line(1, end, rot_end)
            self.probed = end
            return
        kind = {0: 0, 10: 1, 20: 2, 30: 3}.get(self.motion)
        if kind is None:
            raise ControlError(f"motion mode G{self.motion / 10:g} with axis words")
        corner = self._corner_word(words, kind)
        if kind <= 1:
            self._emit_line(kind, end, rot_end)
        else:
            self._arc(kind, end, words, rot_end)
        if corner is not None:
            self.corner = (len(self.moves) - 1, *corner)
        if self.mcall is not None:
            self._siemens_cycle(*self.mcall)
        if "cycle" in extra:
            self._siemens_cycle(*extra["cycle"])

    def _swivel(self, call: tuple) -> None:
        """CYCLE800: no swivel (no angles, or all 0) changes nothing; a real swivel tilts the
        working plane, which needs the machine's kinematics."""
        args = call[1]
        angles = [a for a in args[7:10] if a is not None] if len(args) > 7 else []
        if any(abs(a) > 0 for a in angles):
            raise ControlError(
                "CYCLE800 swivelling the working plane is not supported (needs the "
                "machine's kinematics)"
            )

    def _pattern(self, name: str, args: list[float | None]) -> None:
        """Siemens HOLES1 (a row) and HOLES2 (a circle) of positions: each approached at
        rapid in the plane, the modal cycle (MCALL) run there."""

        def arg(k: int, default: float = 0.0) -> float:
            return args[k] if k < len(args) and args[k] is not None else default  # type: ignore

        sc = self.scale
        if name == "HOLES1":
            a0, b0, ang, fdis, dbh, num = (arg(k) for k in range(6))
            pts = [
                (a0 + (fdis + k * dbh) * math.cos(math.radians(ang)),
                 b0 + (fdis + k * dbh) * math.sin(math.radians(ang)))
                for k in range(int(num))
            ]  # fmt: skip
        else:
            ca, cb, rad, sta, inda, num = (arg(k) for k in range(6))
            n = int(num)
            step = inda if inda else 360.0 / max(n, 1)
            pts = [
                (ca + rad * math.cos(math.radians(sta + k * step)),
                 cb + rad * math.sin(math.radians(sta + k * step)))
                for k in range(n)
            ]  # fmt: skip
        i, j, nk = PLANES[self.plane]
        for a, b in pts:
            here = self.program_pos()
            p = list(here)
            p[i], p[j] = a * sc, b * sc
            self.add(0, self.pos, self.frame().apply((p[0], p[1], p[2])), self.rot)
            if self.mcall is not None:
                self._siemens_cycle(*self.mcall)

    def _corner_word(self, words: dict[str, Any], kind: int) -> tuple[str, float] | None:
        """Fanuc corner rounding (",R" / R on a G1) and chamfering (",C") at the end of this
        line: the corner to the next line is rounded or cut."""
        if ",R" in words or ",C" in words or (kind == 1 and "R" in words):
            if kind != 1:
                raise ControlError("corner rounding or chamfer on a block that is not a line")
            if ",R" in words or "R" in words:
                return ("R", abs(words.get(",R", words.get("R", 0.0))) * self.scale)
            return ("C", abs(words[",C"]) * self.scale)
        return None

    def _round_corner(self, end: Vec) -> None:
        """Cut the corner the last line left for rounding or chamfering: the line is
        shortened and a tangent arc (R) or a straight cut (C) joins it to the next line,
        which starts shortened by as much (Fanuc "optional chamfering and corner R")."""
        assert self.corner is not None
        index, how, size = self.corner
        self.corner = None
        last = self.moves[index]
        a, b, c = last.start, last.end, end
        d1 = _sub(b, a)
        d2 = _sub(c, b)
        l1, l2 = math.dist(a, b), math.dist(b, c)
        if l1 <= TOL.zero_length or l2 <= TOL.zero_length:
            return
        u1 = (d1[0] / l1, d1[1] / l1, d1[2] / l1)
        u2 = (d2[0] / l2, d2[1] / l2, d2[2] / l2)
        cosb = max(-1.0, min(1.0, u1[0] * u2[0] + u1[1] * u2[1] + u1[2] * u2[2]))
        beta = math.acos(cosb)
        if beta <= TOL.collinear_angle:
            return
        trim = size * math.tan(beta / 2.0) if how == "R" else size
        if trim >= min(l1, l2):
            raise ControlError("corner rounding or chamfer larger than its lines")
        p1 = _sub(b, (u1[0] * trim, u1[1] * trim, u1[2] * trim))
        p2 = _add(b, (u2[0] * trim, u2[1] * trim, u2[2] * trim))
        last.end = p1
        self.pos = p1
        if how == "C":
            self.add(1, p1, p2, self.rot)
            return
        # the arc's centre: from p1 towards the inside of the turn, at the radius
        inward = _sub(u2, u1)
        n_in = math.sqrt(inward[0] ** 2 + inward[1] ** 2 + inward[2] ** 2)
        bis = (inward[0] / n_in, inward[1] / n_in, inward[2] / n_in)
        dist = size / math.cos(beta / 2.0)
        centre = _add(b, (bis[0] * dist, bis[1] * dist, bis[2] * dist))
        nx = u1[1] * u2[2] - u1[2] * u2[1]
        ny = u1[2] * u2[0] - u1[0] * u2[2]
        nz = u1[0] * u2[1] - u1[1] * u2[0]
        nn = math.sqrt(nx * nx + ny * ny + nz * nz)
        self.add(3, p1, p2, self.rot, center=centre, normal=(nx / nn, ny / nn, nz / nn))

    def _end_cycle(self) -> None:
        self.canned = None
        self.cycle_initial = None
        self.cycle = {}

    def _polar(self, words: dict[str, Any]) -> None:
        """LinuxCNC polar words: @ radius, ^ angle (degrees) in the XY plane, about the
        origin (G90) or added to the current radius and angle (G91)."""
        if "X" in words or "Y" in words:
            raise ControlError("polar words @ ^ with X or Y in one block")
        here = self.program_pos()
        r0 = math.hypot(here[0], here[1]) / self.scale
        a0 = math.degrees(math.atan2(here[1], here[0]))
        if self.absolute:
            r = words.get("@", r0)
            a = words.get("^", a0)
        else:
            if r0 == 0:
                raise ControlError("incremental polar move from the origin is undefined")
            r = r0 + words.get("@", 0.0)
            a = a0 + words.get("^", 0.0)
        words["X"] = r * math.cos(math.radians(a))
        words["Y"] = r * math.sin(math.radians(a))
        if not self.absolute:
            words["X"] -= here[0] / self.scale
            words["Y"] -= here[1] / self.scale
        words.pop("@", None)
        words.pop("^", None)

    def _tap(self, end: Vec, words: dict[str, Any], back: bool) -> None:
        """G33 spindle-synchronised motion and G33.1 rigid tapping (LinuxCNC): to the end
        point (G33.1: and back out to the start) at the pitch K times the spindle speed (the
        current feed when the speed is unknown)."""
        k = words.get("K")
        if k is None:
            raise ControlError(f"G33{'.1' if back else ''} without the pitch K")
        start = self.pos
        v = abs(k) * self.scale * self.spindle_speed / 60.0 if self.spindle_speed else None
        saved = self.feed
        if v:
            self.feed = v
        elif self.feed is None:
            raise ControlError("G33.1 without a spindle speed S or a feed F")
        self.add(1, self.pos, end, self.rot, exact=back)
        if back:
            self.add(1, self.pos, start, self.rot, exact=True)
        self.feed = saved

    def _target(self, words: dict[str, Any], machine: bool, extra: dict) -> tuple[Vec, Vec]:
        """Machine coordinates of the block's end point (and the rotary axes, deg)."""
        sc = self.scale
        if machine:
            if not self.absolute and self.dialect == "linuxcnc":
                raise ControlError("G53 in incremental mode (G91): LinuxCNC refuses it")
            p = list(self.pos)
            for k, a in enumerate("XYZ"):
                if a in words:
                    p[k] = words[a] * sc if self.absolute else p[k] + words[a] * sc
        else:
            here = self.program_pos()
            p = list(here)
            inc = extra.get("ic", ())
            absw = extra.get("ac", ())
            for k, a in enumerate("XYZ"):
                if a in words:
                    v = words[a] * sc
                    relative = (not self.absolute or a in inc) and a not in absw
                    p[k] = here[k] + v if relative else v
                    self.known[k] = True
            p = list(self.frame().apply((p[0], p[1], p[2])))
        rot = list(self.rot)
        for k, a in enumerate("ABC"):
            if a in words:
                v = words[a]
                rot[k] = rot[k] + v if not self.absolute else v + self.rot_offset[k]
        return (p[0], p[1], p[2]), (rot[0], rot[1], rot[2])

    def _path_exact(self) -> bool:
        pm = self.path_mode
        if pm is None:
            dflt = self.setup.default_path_mode
            if dflt is None:
                return False
            return dflt == "exact_stop"
        return pm in W.exact_stop_codes(self.dialect)

    def _first_feed(self, error: str) -> None:
        """A feed move before any F: hobby CAM writes its first plunge before the F that
        follows (LinuxCNC's preview runs it; the machine would stop). Run it at the
        program's first F, and say so; with no F anywhere, the error."""
        if self.later_feed is None:
            raise ControlError(error)
        value, line = self.later_feed
        self.feed = value * self._feed_scale() / 60.0
        self.notes.add(
            f"feed moves before the first F: run at that F ({value:g}, line {line + 1}); the "
            "machine would refuse them",
            self.line,
        )

    def _emit_line(self, kind: int, end: Vec, rot_end: Vec, *, exact: bool | None = None) -> None:
        if kind == 1 and self.feed is None and not self.inverse_time:
            self._first_feed("feed move without a feed rate F")
        if self.comp.active:
            self.comp.line(kind, end, rot_end)
            return
        self.add(kind, self.pos, end, rot_end, exact=exact)

    def add(
        self,
        kind: int,
        start: Vec,
        end: Vec,
        rot_end: Vec,
        *,
        center: Vec | None = None,
        normal: Vec | None = None,
        turns: int = 0,
        exact: bool | None = None,
    ) -> None:
        """Append a move (machine coordinates) and make its end the current point."""
        if self.corner is not None and self.corner[0] == len(self.moves) - 1:
            if kind != 1:
                raise ControlError("corner rounding or chamfer before a move that is not a line")
            self._round_corner(end)
            start = self.pos
        if self.origin is None:
            self.origin = self.frame().t
        self._count(1)
        inverse = math.nan
        if self.inverse_time and kind != 0:
            if not self.inverse_f > 0:
                raise ControlError("G93 inverse-time feed move without its F")
            inverse = self.inverse_f
        self.moves.append(
            Move(
                kind=kind,
                start=start,
                end=end,
                feed=math.nan if kind == 0 else float(self.feed or math.nan),
                line=self.line,
                file=self.file,
                call=self.call,
                exact=self._path_exact() if exact is None else exact,
                tolerance=self.tolerance,
                tool=self.tool,
                block=self.block_number,
                center=center,
                normal=normal,
                turns=turns,
                rot_start=self.rot,
                rot_end=rot_end,
                op=self.op,
                inverse=inverse,
                feed_unit=self._feed_scale(),
            )
        )
        self.pos = end
        self.rot = rot_end

    def _arc(self, kind: int, end: Vec, words: dict[str, Any], rot_end: Vec) -> None:
        if self.feed is None and not self.inverse_time:
            self._first_feed("feed move without a feed rate F")
        f = self.frame()
        if f.m is not None:
            s = f.scale()
            if abs(abs(s) - 1.0) > TOL.float_slack and not _uniform(f.m):
                raise ControlError("an arc under non-uniform scaling is an ellipse: not supported")
        i, j, nk = PLANES[self.plane]
        start = self.pos
        sp = self.program_pos()
        ep = f.inverse(end)
        has_ijk = any(c in words for c in "IJK")
        has_r = "R" in words
        if has_ijk and has_r:
            raise ControlError("arc with both I/J/K and R")
        if not has_ijk and not has_r:
            raise ControlError("arc without I/J/K or R")
        normal_prog = NORMALS[self.plane]
        ccw = kind == 3
        if has_ijk:
            off = [0.0, 0.0, 0.0]
            for k, c in enumerate("IJK"):
                if c in words:
                    off[k] = words[c] * self.scale
            if off[nk] and abs(off[nk]) > TOL.zero_length:
                raise ControlError(
                    f"{'IJK'[nk]} word is not in the arc's plane (G{self.plane // 10})"
                )
            if self.arc_absolute:
                cp = [sp[0], sp[1], sp[2]]
                cp[i], cp[j] = off[i], off[j]
            else:
                cp = [sp[0] + off[0], sp[1] + off[1], sp[2] + off[2]]
            cp[nk] = sp[nk]
            centre_p: Vec = (cp[0], cp[1], cp[2])
        else:
            centre_p = _r_centre(sp, ep, i, j, nk, ccw, words["R"] * self.scale)
        turns = 0
        if "P" in words and self.dialect == "linuxcnc":
            pv = words["P"]
            if pv < 1 or pv != round(pv):
                raise ControlError("P on an arc must be a positive integer number of turns")
            turns = int(pv) - 1
        if "L" in words and self.dialect == "fanuc":
            turns = max(int(words["L"]) - 1, 0)
        r0 = math.hypot(sp[i] - centre_p[i], sp[j] - centre_p[j])
        r1 = math.hypot(ep[i] - centre_p[i], ep[j] - centre_p[j])
        if r0 < TOL.min_arc_radius:
            if math.dist(start, end) <= TOL.zero_length:
                # an arc of no radius back to its start (PCB drill files): a point
                self.notes.add("arcs of zero radius are points: skipped", self.line)
                return
            raise ControlError("arc with zero radius")
        mismatch = abs(r1 - r0)
        if mismatch > TOL.arc_end_abs and mismatch > TOL.arc_end_rel * r0:
            raise ControlError(
                f"arc end point is {mismatch:.4f} mm off the circle "
                f"(radius {r0:.4f} mm from the start)"
            )
        centre = f.apply(centre_p)
        normal = f.vector(normal_prog)
        nn = math.sqrt(normal[0] ** 2 + normal[1] ** 2 + normal[2] ** 2)
        normal = (normal[0] / nn, normal[1] / nn, normal[2] / nn)
        if f.scale() < 0:  # a mirror reverses the direction
            kind = 5 - kind
        if self.comp.active:
            self.comp.arc(kind, end, centre, normal, turns, rot_end)
            return
        self.add(kind, start, end, rot_end, center=centre, normal=normal, turns=turns)

    # ------------------------------------------------------------------ home
    def _unknown_offset(self, what: str) -> None:
        """A move in machine coordinates (G28, G30, G53) while the work offset in force has
        no value from the program or the machine file: say that it is taken as 0."""
        if self.wcs in self.wcs_offsets or self.dialect == "siemens":
            return
        self.notes.add(
            f"{what} moves in machine coordinates but the work offset G{self.wcs / 10:g} is "
            "not known (no G10 L2 in the program, no [offsets] in the machine file): 0 "
            "assumed, so the rapids to and from there are approximate",
            self.line,
        )

    def _home(self, code: int, words: dict[str, Any]) -> None:
        if self.comp.active:
            raise ControlError("G28/G30 with cutter compensation on")
        self._unknown_offset(f"G{code // 10}")
        mid, rot_mid = self._target(words, False, {})
        if any(a in words for a in "XYZ") or self.dialect == "linuxcnc":
            self.add(0, self.pos, mid, rot_mid)
        home = self.setup.home if code == 280 else self.setup.home2
        named = [k for k, a in enumerate("XYZ") if a in words]
        if not named and not any(a in words for a in "ABC"):
            named = [0, 1, 2]  # every axis (LinuxCNC, Haas; Fanuc wants the axes named)
        end = list(self.pos)
        for k in named:
            end[k] = home[k]
        self.add(0, self.pos, (end[0], end[1], end[2]), self.rot)

    # ------------------------------------------------------------------ stops
    def _stops(self, m: list[int]) -> None:
        if any(c in W.M_STOP for c in m) and self.moves:
            self.moves[-1].exact = True

    def exact_block(self) -> None:
        """G9 on the block: the block's last move ends at rest."""
        if self.moves:
            self.moves[-1].exact = True

    # ------------------------------------------------------------------ canned cycles
    def _cycle(self, code: int, words: dict[str, Any], g: list[int]) -> None:
        """G73, G74, G76 (Fanuc fine boring), G81-G89: rs274ngc's expansion for LinuxCNC
        (convert_cycle_xy), the Fanuc/Haas manuals' for Fanuc (initial level = the height
        when the cycle started, G98 back to it, G99 to R)."""
        if self.comp.active:
            raise ControlError("canned cycle with cutter compensation on")
        if self.feed is None and code not in (760,):
            self._first_feed("canned cycle without a feed rate F")
        i, j, nk = PLANES[self.plane]
        axis = "XYZ"
        sc = self.scale
        cy = self.cycle
        first = self.cycle_initial is None
        here = self.program_pos()
        if first:
            self.cycle_initial = here[nk]
        # LinuxCNC wants R and the depth whenever a cycle starts; Fanuc keeps them until G80
        starting = cy.get("code") != code and self.dialect == "linuxcnc"
        if "R" in words:
            cy["r"] = words["R"] * sc
        elif "r" not in cy or starting:
            raise ControlError("canned cycle without its R plane")
        if axis[nk] in words:
            cy["z"] = words[axis[nk]] * sc
        elif "z" not in cy or starting:
            raise ControlError(f"canned cycle without its depth {axis[nk]}")
        for w in "QPKIJ":
            if w in words:
                cy[w.lower()] = words[w] * (sc if w in "QIJK" else 1.0)
        cy["code"] = code
        repeats = int(words.get("L", words.get("K", 1) if self.dialect == "fanuc" else 1))
        if repeats < 0:
            raise ControlError("a canned cycle cannot repeat a negative number of times")
        if repeats > MAX_MOVES // 3:
            raise ControlError(f"{repeats:,} repeats of a canned cycle: more than ncperf reads")
        if repeats == 0 and self.dialect == "linuxcnc":
            raise ControlError("L0: LinuxCNC cannot do zero repeats of a canned cycle")
        if code == 860 and self.dialect == "linuxcnc" and self.spindle_cw is None:
            raise ControlError("G86 with the spindle not turning (M3 or M4 first)")
        old = here[nk] if self.cycle_initial is None else self.cycle_initial
        if self.absolute:
            r = cy["r"]
            bottom = cy["z"]
            aa = words[axis[i]] * sc if axis[i] in words else here[i]
            bb = words[axis[j]] * sc if axis[j] in words else here[j]
            da = db = 0.0
        else:
            r = cy["r"] + old  # incremental R: from the initial level (both dialects)
            bottom = r + cy["z"]
            aa, bb = here[i], here[j]
            da = words[axis[i]] * sc if axis[i] in words else 0.0
            db = words[axis[j]] * sc if axis[j] in words else 0.0
        if r < bottom:
            raise ControlError("the R plane is below the cycle's bottom")
        f = self.frame()

        def at(a: float, b: float, c: float) -> Vec:
            p = [0.0, 0.0, 0.0]
            p[i], p[j], p[nk] = a, b, c
            return f.apply((p[0], p[1], p[2]))

        def rapid(a: float, b: float, c: float) -> None:
            to = at(a, b, c)
            if math.dist(to, self.pos) > TOL.zero_length:  # a cycle's step in place is none
                self.add(0, self.pos, to, self.rot, exact=True)

        def feed(a: float, b: float, c: float) -> None:
            to = at(a, b, c)
            if math.dist(to, self.pos) > TOL.zero_length:
                self.add(1, self.pos, to, self.rot, exact=True)

        cur = here[nk]
        lc = self.dialect == "linuxcnc"
        if lc:
            if old < r:  # below the R plane: straight up to it first
                rapid(here[i], here[j], r)
                old = r
                cur = r
            clear = r if self.retract_r_plane else old
        else:
            # G99: back to R; G98: back to the initial level, or R when that is higher
            clear = r if self.retract_r_plane else max(old, r)
        for rep in range(max(repeats, 1) if repeats else 0):
            aa += da
            bb += db
            if lc:
                if rep == 0 and cur > r:
                    rapid(aa, bb, cur)
                    rapid(aa, bb, r)
                else:
                    rapid(aa, bb, clear)
                    if clear > r:
                        rapid(aa, bb, r)
            else:
                rapid(aa, bb, self.program_pos()[nk])
                if self.program_pos()[nk] != r:
                    rapid(aa, bb, r)
            self._cycle_body(code, aa, bb, r, clear, bottom, feed, rapid)
        if repeats == 0 and not lc:
            # Fanuc K0/L0: the cycle's data is stored, no hole drilled
            pass

    def _cycle_body(
        self,
        code: int,
        a: float,
        b: float,
        r: float,
        clear: float,
        bottom: float,
        feed: Callable[[float, float, float], None],
        rapid: Callable[[float, float, float], None],
    ) -> None:
        cy = self.cycle
        lc = self.dialect == "linuxcnc"
        peck_back = self.setup.peck_clearance
        if peck_back is None:
            peck_back = PECK_CLEARANCE_INCH * INCH  # 0.254 mm in both units (interp_cycles.cc)
            if not lc and code in (730, 830):
                self.notes.add(
                    "G73/G83 come back to 0.254 mm above the last peck (LinuxCNC's value; a "
                    "Fanuc's parameters 5114/5115 or a Haas's setting 22 may differ: "
                    "peck_clearance in the machine file)",
                    self.line,
                )
        dwell = cy.get("p", 0.0)
        if not lc:
            dwell = dwell / 1000.0  # Fanuc P in ms
        if code == 810:
            feed(a, b, bottom)
            rapid(a, b, clear)
        elif code == 820:
            feed(a, b, bottom)
            self._add_dwell(dwell)
            rapid(a, b, clear)
        elif code in (830, 730):
            q = cy.get("q")
            if q is None or q <= 0:
                raise ControlError(f"G{code // 10} without a positive peck depth Q")
            if (r - bottom) / q > MAX_PECKS:
                raise ControlError(
                    f"G{code // 10} pecks of Q{q:g} mm: more than {MAX_PECKS:,} in one hole"
                )
            depth = r - q
            while depth > bottom:
                feed(a, b, depth)
                if code == 830:
                    rapid(a, b, r)
                    rapid(a, b, depth + peck_back)
                else:
                    rapid(a, b, depth + peck_back)
                depth -= q
            feed(a, b, bottom)
            rapid(a, b, clear)
        elif code in (840, 740):
            if lc:
                want_cw = code == 840
                if self.spindle_cw is None or self.spindle_cw != want_cw:
                    raise ControlError(
                        f"G{code // 10} tapping with the spindle "
                        f"{'stopped' if self.spindle_cw is None else 'turning the wrong way'}"
                    )
            feed(a, b, bottom)
            self._add_dwell(dwell)
            feed(a, b, clear if lc else r)
            if not lc and clear != r:
                rapid(a, b, clear)
        elif code == 850:
            feed(a, b, bottom)
            feed(a, b, r)
            if clear != r:
                rapid(a, b, clear)
        elif code == 860:
            feed(a, b, bottom)
            self._add_dwell(dwell)
            rapid(a, b, clear)
        elif code == 890:
            feed(a, b, bottom)
            self._add_dwell(dwell)
            feed(a, b, clear if lc else r)
            if not lc and clear != r:
                rapid(a, b, clear)
        elif code == 880:
            feed(a, b, bottom)
            self._add_dwell(dwell)
            if self.moves:
                self.moves[-1].exact = True
            self.notes.add("G88: the operator retracts by hand; ncperf stops there", self.line)
            if not lc:
                rapid(a, b, clear)
        elif code == 760 and not lc:
            # Fanuc fine boring: feed in, oriented spindle stop, shift Q away from the wall,
            # rapid out, shift back (the direction is a machine parameter, 5101 RD1/RD2:
            # +X of the plane taken here)
            feed(a, b, bottom)
            self._add_dwell(dwell)
            q = self.cycle.get("q", 0.0)
            if q > 0:
                rapid(a + q, b, bottom)
                rapid(a + q, b, clear)
                rapid(a, b, clear)
            else:
                rapid(a, b, clear)
        elif code == 870:
            raise ControlError("G87 back boring is not supported")
        else:
            raise ControlError(f"canned cycle G{code / 10:g} is not supported")

    # ------------------------------------------------------------------ G12/G13
    def _circle_pocket(self, code: int, words: dict[str, Any]) -> None:
        """Haas/Mach3 G12 (clockwise) / G13 (counter-clockwise) circular pocket: from the
        centre out along +X to radius I (Haas: in steps of Q up to K), a full circle, and back
        to the centre."""
        if "I" not in words:
            raise ControlError(f"G{code // 10} circle pocket without its radius I")
        sc = self.scale
        kind = 2 if code == 120 else 3
        i, j, nk = PLANES[self.plane]
        f = self.frame()
        centre_p = self.program_pos()
        if "Z" in words:
            z = words["Z"] * sc
            c = list(centre_p)
            c[nk] = c[nk] + z if not self.absolute else z
            if self.feed is None:
                self._first_feed("feed move without a feed rate F")
            self.add(1, self.pos, f.apply((c[0], c[1], c[2])), self.rot)
            centre_p = (c[0], c[1], c[2])
        loops = int(words.get("L", 1))
        if loops < 1:
            raise ControlError(f"G{code // 10} with L{loops}: at least one pass")
        if loops > MAX_MOVES // 3:
            raise ControlError(f"G{code // 10} with L{loops:,}: more passes than ncperf reads")
        for rep in range(loops):
            if rep and "Z" in words:  # L repeats a G91 pocket deeper each time (Haas)
                c = list(centre_p)
                c[nk] = c[nk] + words["Z"] * sc if not self.absolute else c[nk]
                self.add(1, self.pos, f.apply((c[0], c[1], c[2])), self.rot)
                centre_p = (c[0], c[1], c[2])
            self._pocket_passes(kind, words, centre_p, f)

    def _pocket_passes(self, kind: int, words: dict[str, Any], centre_p: Vec, f: Frame) -> None:
        """One pass of a circle pocket at the current depth."""
        sc = self.scale
        i, _, _ = PLANES[self.plane]
        r_first = words["I"] * sc
        r_last = words.get("K", words["I"]) * sc
        step = words.get("Q", 0.0) * sc
        radii = [r_first]
        if "K" in words and step > 0 and (r_last - r_first) / step > MAX_MOVES:
            raise ControlError(f"G12/G13 steps of Q{step:g} from I to K: more than ncperf reads")
        if "K" in words and step > 0:
            rr = r_first
            while rr + step < r_last - TOL.zero_length:
                rr += step
                radii.append(rr)
            radii.append(r_last)
        normal = f.vector(NORMALS[self.plane])
        for rr in radii:
            p = list(centre_p)
            p[i] += rr
            pt = f.apply((p[0], p[1], p[2]))
            self.add(1, self.pos, pt, self.rot)
            self.add(kind, pt, pt, self.rot, center=f.apply(centre_p), normal=normal)
        self.add(1, self.pos, f.apply(centre_p), self.rot)

    # ------------------------------------------------------------------ Siemens cycles
    def _siemens_cycle(self, name: str, args: list[float | None]) -> None:
        """CYCLE81(RTP, RFP, SDIS, DP, DPR), CYCLE82(... , DTB), CYCLE83(RTP, RFP, SDIS, DP,
        DPR, FDEP, FDPR, DAM, DTB, DTS, FRF, VARI) at the current point (840D programming
        manual, drilling cycles): rapid to RFP + SDIS, feed to the depth (pecking for
        CYCLE83 with VARI = 1, chip breaking with VARI = 0), rapid back to RTP."""

        def arg(k: int, default: float | None = None) -> float | None:
            return args[k] if k < len(args) and args[k] is not None else default

        if name not in ("CYCLE81", "CYCLE82", "CYCLE83", "CYCLE84", "CYCLE85", "CYCLE86"):
            raise ControlError(f"Siemens cycle {name} is not supported")
        sc = self.scale
        rtp, rfp, sdis = arg(0), arg(1), arg(2, 0.0)
        dp, dpr = arg(3), arg(4)
        if rtp is None or rfp is None or (dp is None and dpr is None):
            raise ControlError(f"{name} needs RTP, RFP and a depth DP or DPR")
        assert rfp is not None and rtp is not None and sdis is not None
        depth = dp if dp is not None else rfp - abs(dpr or 0.0)
        i, j, nk = PLANES[self.plane]
        here = self.program_pos()
        f = self.frame()
        if self.feed is None:
            raise ControlError(f"{name} without a feed rate F")

        def at(c: float) -> Vec:
            p = list(here)
            p[nk] = c * sc
            return f.apply((p[0], p[1], p[2]))

        self.add(0, self.pos, at(rfp + sdis), self.rot, exact=True)
        if name == "CYCLE83":
            fdep, fdpr, dam = arg(5), arg(6), arg(7, 0.0)
            dtb = arg(8, 0.0) or 0.0
            vari = int(arg(11, 1.0) or 0.0)
            first = fdep if fdep is not None else rfp - abs(fdpr or 0.0)
            step = (rfp - first) if first is not None else rfp - depth
            level = first
            if level > depth and not (step > 0 and (level - depth) / step <= MAX_PECKS):
                raise ControlError(
                    f"{name} pecks of {step:g} mm: not positive, or more than {MAX_PECKS:,} "
                    "in one hole"
                )
            while level > depth:
                self.add(1, self.pos, at(level), self.rot, exact=True)
                self._add_dwell(dtb)
                if vari == 1:
                    self.add(0, self.pos, at(rfp + sdis), self.rot, exact=True)
                    self.add(0, self.pos, at(level + 1.0 / sc), self.rot, exact=True)
                else:
                    self.add(0, self.pos, at(level + 1.0 / sc), self.rot, exact=True)
                step = max(step - (dam or 0.0), dam or step)
                level -= step
        self.add(1, self.pos, at(depth), self.rot, exact=True)
        if name == "CYCLE82":
            self._add_dwell(arg(5, 0.0) or 0.0)
        if name in ("CYCLE84", "CYCLE85"):
            self.add(1, self.pos, at(rfp + sdis), self.rot, exact=True)
        self.add(0, self.pos, at(rtp), self.rot, exact=True)


#: Fanuc G65 argument letters (any of them may come with G65).
G65_LETTERS = "ABCDEFHIJKMQRSTUVWXYZ"

_GROUPS: dict[str, tuple[int, ...]] = {
    "motion": (0, 10, 20, 30, 330, 331, 382, 383, 384, 385, 310),
    "plane": (170, 180, 190),
    "distance": (900, 910),
    "arc distance": (901, 911),
    "units": (200, 210, 700, 710, 7000, 7100),
    "feed mode": (930, 940, 950),
    "path": (600, 610, 611, 640, 6410, 6420, 6430, 6440, 6450),
    "comp": (400, 410, 420, 411, 421),
    "length": (430, 431, 490),
    "retract": (980, 990),
    "rotation": (680, 681, 690),
    "scaling": (500, 510),
    "mirror": (501, 511),
}
_GROUP_OF = {code: name for name, codes in _GROUPS.items() for code in codes}


def _modal_group(code: int, linuxcnc: bool) -> str | None:
    if code in CYCLES or code == 800:
        return "motion" if linuxcnc else "cycle"
    if 540 <= code <= 593 or code == 5000 or 5050 <= code <= 5990:
        return "wcs"
    return _GROUP_OF.get(code)


def _uniform(m: tuple[Vec, Vec, Vec]) -> bool:
    cols = [math.sqrt(sum(m[r][c] ** 2 for r in range(3))) for c in range(3)]
    return max(cols) - min(cols) <= TOL.float_slack * max(cols)


def _r_centre(sp: Vec, ep: Vec, i: int, j: int, nk: int, ccw: bool, r: float) -> Vec:
    """Centre of an R-format arc in its plane: R > 0 the short way, R < 0 the long way."""
    dx, dy = ep[i] - sp[i], ep[j] - sp[j]
    chord = math.hypot(dx, dy)
    if chord <= TOL.zero_length:
        raise ControlError("R arc whose end point is its start point (use I/J/K for a circle)")
    rad = abs(r)
    if rad < TOL.min_arc_radius:
        raise ControlError("arc with zero radius")
    h2 = rad * rad - (chord / 2) ** 2
    if h2 < 0 and chord / 2 - rad > TOL.arc_radius:
        raise ControlError(f"R {r:.4f} mm is less than half the chord ({chord / 2:.4f} mm)")
    h = math.sqrt(max(h2, 0.0))
    ux, uy = dx / chord, dy / chord
    left = (-uy, ux)
    sign = (1.0 if ccw else -1.0) * (1.0 if r > 0 else -1.0)
    c = [0.0, 0.0, 0.0]
    c[i] = sp[i] + dx / 2 + sign * h * left[0]
    c[j] = sp[j] + dy / 2 + sign * h * left[1]
    c[nk] = sp[nk]
    return (c[0], c[1], c[2])
