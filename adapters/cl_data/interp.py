"""CL records -> ToolPath: the modal state of the CL data, in file order.

The records other than plain GOTOs (:mod:`adapters.cl_data.records`) are
walked in file order and set the state (feed, units, tool, one-shot RAPID, a
pending CIRCLE...). Between two such records lies a run of plain GOTO records
read in bulk (:mod:`adapters.cl_data.source`); each run becomes one chunk of
moves sharing that state, so the walk costs one step per record that is not a
plain GOTO, and the moves themselves are assembled with numpy at the end.

Arc direction
-------------
A CIRCLE (or MOVARC) record gives the centre, the axis vector i,j,k and
(except SolidWorks CAM) the radius of the arc that the next GOTO ends. Two
conventions are in use:

* **APT, Creo, SolidWorks CAM, Fusion's MOVARC**: the tool turns
  counter-clockwise about i,j,k (right-hand rule). Creo documents it
  ((0,0,1) is CCW in XY, (0,0,-1) CW); Autodesk's ISO 4343 post negates the
  normal for clockwise arcs. Checked on SolidWorks CAM's ``boss.apt`` in
  ``../shared/data/apt``: read counter-clockwise, 1,153 arc ends continue the
  neighbouring GOTO line tangentially and 2 reverse against it (read
  clockwise, those numbers swap). Over all three SolidWorks files (1,731
  arcs, counting each arc once), 1,569 arcs fit counter-clockwise and 22
  clockwise; the rest meet the path at a corner either way.
* **NX CLSF**, recognised by its 11-value CIRCLE record
  ``CIRCLE/x,y,z,i,j,k,r,tol,ratio,diameter,corner`` (NX documents "the axis
  vector ... assuming a clockwise direction"): the tool turns clockwise about
  i,j,k. Checked on ``_3_PAZ_125_N2.cls``: read clockwise, 280 arc ends
  continue a neighbouring line and none reverses (counter-clockwise: the
  opposite); and the four arcs of ``_10_KONTUR_125_N2_162.cls`` on one
  circle add up to exactly one turn only when read clockwise (60 + 120 + 120
  + 60 degrees; the other way gives 1080). ``tests/test_cl_data_shared.py``
  repeats these checks.

Arcs are stored as ARC_CCW (or ARC_CW for NX) about the unit axis vector as
written. Whatever the source, the reader counts the arcs whose tangent
reverses against a neighbouring line and warns if they outnumber the tangent
ones: that is the signature of the other convention.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from adapters.cl_data import words as W
from adapters.cl_data.records import Record, leading_numbers, number, numbers, records
from adapters.cl_data.source import FastGotos, Source
from core.model import geometry as g
from core.model.errors import InputError, Notes
from core.model.limits import MAX_PECKS, MAX_TOOL
from core.model.tolerances import TOL
from core.model.toolpath import (
    POINTS_DROPPED,
    MoveKind,
    PathMode,
    ToolPath,
    drop_zero_length,
    empty_columns,
)

INCH = 25.4
#: CL drilling cycles ncperf expands (APT CYCLE/ records; NX and SolidWorks CAM write them).
CYCLE_KINDS = ("DRILL", "DEEP", "DEEP2", "BRKCHP", "TAP", "BORE", "REAM", "FACE", "CSINK")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


PLUS_Z = (0.0, 0.0, 1.0)
#: cos of the angle within which an arc counts as tangent to (or reversed against) a line:
#: 2e-3 rad, the tangency tolerance of the curvature model (TOL.tangent_angle).
_TANGENT_COS = np.cos(TOL.tangent_angle)

_FAST, _SLOW = 0, 1
_TOOL_PATH = re.compile(rb"(?im)^[ \t]*TOOL[ \t]+PATH[ \t]*/")


@dataclass
class Arc:
    """A CIRCLE or MOVARC record waiting for (or applied to) the GOTO that ends it."""

    line: int  # 0-based line of the CIRCLE record
    text: str
    word: str
    centre: tuple[float, float, float]  # mm
    axis: tuple[float, float, float]  # unit
    radius: float  # mm; NaN where the record has none (SolidWorks CAM)
    clockwise: bool  # the tool turns clockwise about the axis (NX CLSF)
    turns: int  # extra full turns (NX TIMES)
    angle: float  # rad, MOVARC ANGLE; NaN where absent


class Reader:
    """Walks the records of one CL file and builds its ToolPath (see module docstring)."""

    def __init__(self, src: Source, fast: FastGotos) -> None:
        self.src = src
        self.fast = fast
        self.notes = Notes(src.name)
        self.scale = 1.0  # mm per length unit of the file
        self.units_set = False
        self.any_inch = False
        self.feed = np.nan  # mm/s
        self.tool = -1
        self.rapid_pending: int | None = None  # line of a RAPID not yet applied
        self.arc_pending: Arc | None = None
        # (rapid, arc) of the GOTO statement just read, for the bare-number lines
        # that continue it (Creo writes the points of an arc that way).
        self.last_goto: tuple[bool, Arc | None] | None = None
        self.finished: int | None = None
        self.start = np.zeros(3)
        self.start_axis: NDArray[np.float64] | None = None
        self.has_from = False
        self.n = 0
        # Chunks of moves sharing one state: fast GOTO runs and single slow points.
        self.ch_src: list[int] = []
        self.ch_a: list[int] = []
        self.ch_b: list[int] = []
        self.ch_scale: list[float] = []
        self.ch_feed: list[float] = []
        self.ch_tool: list[int] = []
        self.sp_xyz: list[tuple[float, float, float]] = []
        self.sp_ijk: list[tuple[float, float, float]] = []
        self.sp_line: list[int] = []
        self.slow_axis_given = False
        self.fast_axis_given = bool(np.any(~np.isnan(fast.ijk[:, 0])))
        self.rapid_moves: list[int] = []
        self.arcs: list[tuple[int, Arc]] = []
        self.stops: list[int] = []
        self.dwells: list[tuple[int, float]] = []
        self.boundaries: list[tuple[int, str | None]] = []  # (first move, TOOL PATH name)
        self.passive: dict[str, list[int]] = {}
        self.tool_paths = bool(_TOOL_PATH.search(src.data))
        self.cycle: dict[str, Any] | None = None  # the active CYCLE/
        self.handlers = {
            "GOTO": self._goto,
            "FROM": self._from,
            "GOHOME": self._gohome,
            "GODLTA": self._godlta,
            "RAPID": self._rapid,
            "FEDRAT": self._fedrat,
            "CIRCLE": self._circle,
            "MOVARC": self._movarc,
            "UNITS": self._units,
            "UNIT": self._units,
            "MULTAX": self._multax,
            "LOADTL": self._loadtl,
            "LOAD": self._load,
            "TOOL PATH": self._tool_path,
            "END-OF-PATH": self._end_of_path,
            "CUTCOM": self._cutcom,
            "CYCLE": self._cycle,
            "DELAY": self._delay,
            "STOP": self._stop,
            "OPSTOP": self._stop,
            "END": self._stop,
            "FINI": self._fini,
            "MODE": self._mode,
            "INSERT": self._insert,
            "ROTABL": self._rotary,
            "ROTHED": self._rotary,
        }

    # ------------------------------------------------------------------ walk
    def run(self) -> ToolPath:
        src, fl = self.src, self.fast.line
        is_fast = np.zeros(src.n_lines, dtype=bool)
        is_fast[fl] = True
        ptr = 0
        for rec in records(src, np.flatnonzero(~is_fast)):
            k = int(np.searchsorted(fl, rec.line))
            if k > ptr:
                self._fast_run(ptr, k)
                ptr = k
            self._record(rec)
            if rec.last > rec.line:  # GOTO lines inside a continued record belong to it
                ptr = max(ptr, int(np.searchsorted(fl, rec.last, side="right")))
        if ptr < fl.size:
            self._fast_run(ptr, fl.size)
        if self.arc_pending is not None:
            raise self._not_ended(self.arc_pending, "the end of the file")
        return self._build()

    def _error(self, rec: Record, message: str) -> InputError:
        return self.src.error(rec.line, message)

    def _not_ended(self, arc: Arc, what: str) -> InputError:
        return InputError(
            f"{arc.word} is not followed by the GOTO that ends the arc (next: {what})",
            source=self.src.name,
            line=arc.line + 1,
            text=arc.text,
        )

    def _record(self, rec: Record) -> None:
        w = rec.word
        if w == "$$":
            self._comment(rec)
            return
        if self.finished is not None:
            self.notes.add("records after FINI (end of the CL data) ignored", rec.line)
            return
        if w == "":
            self._more_points(rec)
            return
        self.last_goto = None
        handler = self.handlers.get(w)
        if self.arc_pending is not None and w not in ("GOTO", "FEDRAT") and w not in W.PASSIVE:
            raise self._not_ended(self.arc_pending, f"{w} at line {rec.line + 1}")
        if handler is not None:
            handler(rec)
        elif w in W.ERRORS:
            raise self._error(rec, W.ERRORS[w])
        elif w in W.PART_PROGRAM:
            raise self._error(
                rec,
                f"{w} is an APT part-program statement: an APT processor computes the "
                "cutter path from it; ncperf reads CL data (GOTO records)",
            )
        elif w in W.PASSIVE:
            self.passive.setdefault(w, [rec.line, 0])[1] += 1
        elif w in W.FRAMES:
            self.notes.add(
                "MSYS/CSYS/TRNTYP (the post's coordinate system) passed over: the CL points "
                "are read as written",
                rec.line,
            )
        else:
            self.notes.add(
                f"{w}: not a word ncperf knows; passed over, assumed not to move the tool",
                rec.line,
            )

    def _comment(self, rec: Record) -> None:
        # NX writes "$$ centerline data" before the GOTOs of a tool path; with contact
        # output they are the points where the tool touches the part instead.
        if rec.comment is not None and rec.comment.strip().lower() == "contact data":
            raise self._error(
                rec,
                "contact data: the GOTO points are where the tool touches the part, not the "
                "tool centre; output centerline data",
            )

    # ------------------------------------------------------------------ motion
    def _take_pending(self) -> tuple[bool, Arc | None]:
        """Apply a pending RAPID and CIRCLE to the move starting now (index self.n)."""
        rapid, arc = self.rapid_pending is not None, self.arc_pending
        if rapid:
            self.rapid_moves.append(self.n)
        if arc is not None:
            self.arcs.append((self.n, arc))
        self.rapid_pending = self.arc_pending = None
        return rapid, arc

    def _chunk(self, src: int, a: int, b: int, scale: float) -> None:
        self.ch_src.append(src)
        self.ch_a.append(a)
        self.ch_b.append(b)
        self.ch_scale.append(scale)
        self.ch_feed.append(self.feed)
        self.ch_tool.append(self.tool)
        self.n += b - a

    def _fast_run(self, k0: int, k1: int) -> None:
        if self.finished is not None:
            self.notes.add(
                "records after FINI (end of the CL data) ignored",
                int(self.fast.line[k0]),
                k1 - k0,
            )
            return
        if self.cycle is not None:
            self._take_pending()
            for k in range(k0, k1):
                self._hole(int(self.fast.line[k]), self.fast.xyz[k] * self.scale)
            return
        rapid, arc = self._take_pending()
        self._chunk(_FAST, k0, k1, self.scale)
        self.last_goto = (rapid, arc) if k1 - k0 == 1 else (False, None)

    def _point(
        self,
        rec: Record,
        xyz: NDArray[np.float64] | list[float],
        ijk: list[float] | None,
        rapid: bool = False,
    ) -> None:
        """A move to ``xyz`` (mm) from a record; ``rapid`` forces a rapid."""
        if rapid:
            self.rapid_moves.append(self.n)
        j = len(self.sp_xyz)
        self.sp_xyz.append((float(xyz[0]), float(xyz[1]), float(xyz[2])))
        self.sp_ijk.append(
            (float(ijk[0]), float(ijk[1]), float(ijk[2])) if ijk is not None else (np.nan,) * 3
        )
        self.slow_axis_given |= ijk is not None
        self.sp_line.append(rec.line)
        self._chunk(_SLOW, j, j + 1, 1.0)

    def _position(self) -> NDArray[np.float64]:
        """Where the tool is now (mm)."""
        if not self.ch_src:
            return self.start.copy()
        b = self.ch_b[-1] - 1
        if self.ch_src[-1] == _FAST:
            return self.fast.xyz[b] * self.ch_scale[-1]
        return np.array(self.sp_xyz[b])

    def _axis_now(self) -> NDArray[np.float64]:
        """The current tool axis (the last i,j,k given, else FROM's, else +Z)."""
        default = self.start_axis if self.start_axis is not None else np.array(PLUS_Z)
        fast = self.fast.ijk
        if not (self.slow_axis_given or self.fast_axis_given):
            return default  # a 3-axis file: nothing to look back for
        chunks = zip(reversed(self.ch_src), reversed(self.ch_a), reversed(self.ch_b), strict=True)
        for src, a, b in chunks:
            rows = fast[a:b] if src == _FAST else np.array(self.sp_ijk[a:b])
            given = np.flatnonzero(~np.isnan(rows[:, 0]))
            if given.size:
                return g.unit(rows[given[-1:]])[0]
        return default

    def _xyz_ijk(self, rec: Record, what: str) -> tuple[NDArray[np.float64], list[float] | None]:
        vals = numbers(self.src, rec, rec.args or [], what)
        if len(vals) not in (3, 6):
            raise self._error(
                rec,
                f"{what} needs 3 values (x,y,z) or 6 (x,y,z,i,j,k), got {len(vals)}",
            )
        return np.array(vals[:3]) * self.scale, (vals[3:] if len(vals) == 6 else None)

    def _goto(self, rec: Record) -> None:
        xyz, ijk = self._xyz_ijk(rec, "GOTO")
        if self.cycle is not None:
            self._take_pending()
            self._hole(rec.line, xyz)
            return
        rapid, arc = self._take_pending()
        self._point(rec, xyz, ijk)
        self.last_goto = (rapid, arc)

    def _more_points(self, rec: Record) -> None:
        """A line of bare numbers: another point of the GOTO just read (Creo)."""
        if self.last_goto is None:
            raise self._error(rec, "numbers without a record word (not after a GOTO)")
        rapid, arc = self.last_goto
        xyz, ijk = self._xyz_ijk(rec, "GOTO point")
        if arc is not None:
            self.arcs.append((self.n, arc))
        self._point(rec, xyz, ijk, rapid=rapid)

    def _from(self, rec: Record) -> None:
        xyz, ijk = self._xyz_ijk(rec, "FROM")
        if self.n == 0:
            self.start, self.has_from = xyz, True
            if ijk is not None:
                self.start_axis = g.unit(np.array([ijk]))[0]
            return
        self.notes.add("FROM after motion read as a rapid move to its point", rec.line)
        self.rapid_pending = None
        self._point(rec, xyz, ijk, rapid=True)

    def _gohome(self, rec: Record) -> None:
        if rec.args:
            xyz, ijk = self._xyz_ijk(rec, "GOHOME")
        elif self.has_from:
            xyz, ijk = self.start, None
        else:
            raise self._error(rec, "GOHOME without a point, and no FROM record gave home")
        # NX posts output the return home as a rapid (MOM_gohome_move calls MOM_rapid_move).
        self.notes.add("GOHOME read as a rapid move to its point", rec.line)
        self.rapid_pending = None
        self._point(rec, xyz, ijk, rapid=True)

    def _godlta(self, rec: Record) -> None:
        vals = numbers(self.src, rec, rec.args or [], "GODLTA")
        if len(vals) == 1:
            delta = self._axis_now() * vals[0] * self.scale
        elif len(vals) == 3:
            delta = np.array(vals) * self.scale
        else:
            raise self._error(
                rec, f"GODLTA needs 1 value (along the tool axis) or 3 (dx,dy,dz), got {len(vals)}"
            )
        pos = self._position()
        self._take_pending()
        self._point(rec, pos + delta, None)

    def _rapid(self, rec: Record) -> None:
        if rec.args:
            raise self._error(
                rec,
                f"RAPID/{','.join(rec.args)} not understood: RAPID and RAPID/ make the next "
                "motion a rapid",
            )
        self.rapid_pending = rec.line

    def _arc_record(self, rec: Record, arc: Arc) -> None:
        if self.rapid_pending is not None:
            raise self._error(
                rec, f"RAPID before {arc.word}: an arc at rapid traverse is not defined"
            )
        self.arc_pending = arc

    def _arc_geometry(
        self, rec: Record, vals: list[float]
    ) -> tuple[tuple[float, float, float], tuple[float, float, float], float]:
        # Plain floats: numpy costs more than it saves on one 3-vector per record.
        sc = self.scale
        centre = (vals[0] * sc, vals[1] * sc, vals[2] * sc)
        i, j, k = vals[3:6]
        length = math.sqrt(i * i + j * j + k * k)
        if length < TOL.direction:
            raise self._error(rec, f"{rec.word} axis vector i,j,k is zero")
        radius = math.nan
        if len(vals) > 6:
            radius = vals[6] * sc
            if radius <= 0:
                raise self._error(rec, f"{rec.word} radius must be positive, got {vals[6]:g}")
        return centre, (i / length, j / length, k / length), radius

    def _circle(self, rec: Record) -> None:
        vals, rest = leading_numbers(self.src, rec, "CIRCLE")
        if len(vals) not in (6, 7, 11):
            raise self._error(
                rec,
                f"CIRCLE with {len(vals)} values: expected x,y,z,i,j,k (6), with the radius (7) "
                "or NX's x,y,z,i,j,k,r,tol,ratio,diameter,corner (11)",
            )
        turns = 0
        if rest:
            if rest[0] != "TIMES" or len(rest) != 2 or len(vals) != 11:
                raise self._error(rec, f"CIRCLE modifier {','.join(rest)} not understood")
            t = number(self.src, rec, rest[1], "CIRCLE TIMES")
            if t < 1 or t != int(t):
                raise self._error(rec, f"CIRCLE TIMES must be a positive whole number, got {t:g}")
            turns = int(t)
            self.notes.add(
                "CIRCLE ... TIMES,n (NX helix) read as n full turns before the arc to the "
                "GOTO point",
                rec.line,
            )
        centre, axis, radius = self._arc_geometry(rec, vals)
        self._arc_record(
            rec,
            Arc(rec.line, rec.text, "CIRCLE", centre, axis, radius, len(vals) == 11, turns, np.nan),
        )

    def _movarc(self, rec: Record) -> None:
        vals, rest = leading_numbers(self.src, rec, "MOVARC")
        if len(vals) not in (6, 7):
            raise self._error(
                rec, f"MOVARC with {len(vals)} values: expected x,y,z,i,j,k[,r][,ANGLE,degrees]"
            )
        angle = np.nan
        if rest:
            if rest[0] != "ANGLE" or len(rest) != 2:
                raise self._error(rec, f"MOVARC modifier {','.join(rest)} not understood")
            deg = number(self.src, rec, rest[1], "MOVARC ANGLE")
            if deg <= 0:
                raise self._error(rec, f"MOVARC ANGLE must be positive, got {deg:g}")
            angle = np.radians(deg)
        centre, axis, radius = self._arc_geometry(rec, vals)
        self._arc_record(
            rec, Arc(rec.line, rec.text, "MOVARC", centre, axis, radius, False, 0, angle)
        )

    # ------------------------------------------------------------------ modes
    def _fedrat(self, rec: Record) -> None:
        args = rec.args or []
        nums = [a for a in args if a[:1] in "0123456789+-."]
        unit = [a.upper() for a in args if a[:1] not in "0123456789+-."]
        if len(nums) != 1 or len(unit) > 1:
            raise self._error(rec, "FEDRAT needs one feed rate and at most one unit (MMPM, IPM)")
        f = number(self.src, rec, nums[0], "FEDRAT")
        if unit and unit[0] in W.FEED_UNSUPPORTED:
            raise self._error(rec, f"{W.FEED_UNSUPPORTED[unit[0]]} is not supported")
        if unit and unit[0] not in W.FEED_UNITS:
            raise self._error(rec, f"FEDRAT unit {unit[0]} not understood (MMPM, IPM)")
        if f <= 0:
            raise self._error(rec, f"feed rate must be positive, got {f:g}")
        # Without a unit word the feed is in the file's length unit per minute.
        per_min = W.FEED_UNITS[unit[0]] if unit else self.scale
        self.feed = f * per_min / 60.0

    def _units(self, rec: Record) -> None:
        arg = (rec.args or [""])[0].upper()
        if len(rec.args or []) != 1 or arg not in W.LENGTH_UNITS:
            raise self._error(rec, f"{rec.word}/ needs MM or INCHES")
        self.scale = W.LENGTH_UNITS[arg]
        self.units_set = True
        self.any_inch |= self.scale != 1.0

    def _multax(self, rec: Record) -> None:
        # GOTO records say themselves whether they carry i,j,k (3 or 6 values);
        # MULTAX only announces it.
        arg = [a.upper() for a in rec.args or []]
        if arg not in ([], ["ON"], ["OFF"]):
            raise self._error(rec, f"MULTAX/{','.join(arg)} not understood (ON, OFF)")

    def _tool_number(self, rec: Record, token: str) -> None:
        t = number(self.src, rec, token, f"{rec.word} tool number")
        if not (0 <= t <= MAX_TOOL and t == int(t)):
            raise self._error(rec, f"tool number must be a whole number 0 to {MAX_TOOL}, got {t:g}")
        self.tool = int(t)
        if not self.tool_paths:
            self.boundaries.append((self.n, None))

    def _loadtl(self, rec: Record) -> None:
        if not rec.args:
            raise self._error(rec, "LOADTL without a tool number")
        self._tool_number(rec, rec.args[0])

    def _load(self, rec: Record) -> None:
        args = rec.args or []
        if len(args) >= 2 and args[0].upper() == "TOOL":
            self._tool_number(rec, args[1])
        else:
            self.notes.add(f"LOAD/{','.join(args)} passed over (not LOAD/TOOL)", rec.line)

    def _tool_path(self, rec: Record) -> None:
        name = rec.args[0] if rec.args else "TOOL PATH"
        self.boundaries.append((self.n, name))

    def _end_of_path(self, rec: Record) -> None:
        self.boundaries.append((self.n, None))

    def _cutcom(self, rec: Record) -> None:
        arg = [a.upper() for a in rec.args or []]
        if arg[:1] == ["OFF"]:
            return
        # CL data is the cutter location (the tool centre) the CAM system computed;
        # CUTCOM asks the controller to add its own offset (its D register, usually
        # the wear) on top.
        self.notes.add(
            f"CUTCOM/{','.join(arg)}: controller cutter compensation; the path is read as "
            "the tool-centre path written in the CL data (an offset the controller adds is "
            "not modelled)",
            rec.line,
        )

    def _cycle(self, rec: Record) -> None:
        """CYCLE/type, FEDTO d, RAPTO r, RTRCTO c, MMPM|IPM f, STEP|1STPECK/SUBPECK,
        DWELL t (the keyword form NX and SolidWorks CAM write), or the standard APT form
        CYCLE/DRILL, d, IPM|MMPM, f, c (DEEP and BRKCHP: d, step, IPM|MMPM, f, c): while on,
        each GOTO is a hole whose top is the point (see :meth:`_hole`); CYCLE/OFF ends it,
        CYCLE/INIT (SolidWorks CAM) marks its start."""
        args = [a.strip().upper() for a in rec.args or []]
        if not args or args[0] == "OFF":
            self.cycle = None
            return
        if args[0] == "INIT":
            return
        kind = args[0]
        if kind not in CYCLE_KINDS:
            raise self._error(rec, f"CYCLE/{kind} is not a drilling cycle ncperf knows")
        c: dict[str, Any] = {"kind": kind, "line": rec.line}
        positional: list[float] = []
        k = 1
        while k < len(args):
            word = args[k]
            nxt = args[k + 1] if k + 1 < len(args) else None
            if _is_number(word):
                # the standard APT form: CYCLE/DRILL, d, IPM, f, c (DEEP/BRKCHP: d, s, ...)
                positional.append(float(word))
                k += 1
                continue
            if word in ("DEEP", "BRKCHP", "DRILL", "TAP", "BORE", "REAM", "FACE", "CSINK"):
                c["kind"] = word if kind == "DRILL" else kind
                k += 1
                continue
            if nxt is None or not _is_number(nxt):
                if word in ("RTRCTO",) and nxt == "AUTO":
                    k += 2
                    continue
                raise self._error(rec, f"CYCLE/{kind}: {word} without its value")
            v = float(nxt)
            if word in ("FEDTO", "DEPTH"):
                c["depth"] = abs(v) * self.scale
            elif word in ("RAPTO", "CLEAR"):
                c["clear"] = v * self.scale
            elif word == "RTRCTO":
                c["retract"] = v * self.scale
            elif word in ("MMPM", "IPM"):
                c["feed"] = v * (25.4 if word == "IPM" else 1.0) / 60.0
            elif word in ("STEP", "1STPECK"):
                c["peck"] = abs(v) * self.scale
            elif word == "SUBPECK":
                c["subpeck"] = abs(v) * self.scale
            elif word == "DWELL":
                c["dwell"] = v
            else:
                self.notes.add(f"CYCLE/{kind}: {word} passed over", rec.line)
            k += 2
        if positional:
            names = (
                ["depth", "peck", "clear"]
                if c["kind"] in ("DEEP", "BRKCHP")
                else ["depth", "clear"]
            )
            if len(positional) > len(names):
                raise self._error(
                    rec,
                    f"CYCLE/{kind}: {len(positional)} numbers where the APT form has "
                    f"{len(names)} ({', '.join(names)})",
                )
            for name, v in zip(names, positional, strict=False):
                c[name] = abs(v) * self.scale if name != "clear" else v * self.scale
        if "depth" not in c:
            raise self._error(rec, f"CYCLE/{kind} without its depth FEDTO")
        c.setdefault("clear", 0.0)
        if "feed" not in c and not np.isfinite(self.feed):
            raise self._error(rec, f"CYCLE/{kind} without a feed (MMPM/IPM) and no FEDRAT before")
        self.cycle = c
        self.notes.add(
            "CL drilling cycles expanded as the APT record says: rapid to RAPTO above each "
            "point, feed FEDTO below it (pecks STEP/1STPECK, SUBPECK with a full retract), "
            "rapid to RTRCTO (else RAPTO)",
            rec.line,
        )

    def _hole(self, line: int, top: NDArray[np.float64]) -> None:
        """The moves of the active cycle at one hole (top point ``top``, mm)."""
        c = self.cycle
        assert c is not None
        axis = self._axis_now()
        clear = top + axis * c["clear"]
        bottom = top - axis * c["depth"]
        retract = top + axis * max(c.get("retract", c["clear"]), c["clear"])
        saved = self.feed
        self.feed = c.get("feed", self.feed)
        rec = Record(
            line=line, last=line, word="GOTO", args=[], text="", literal=None, comment=None
        )

        def rapid(p: NDArray[np.float64]) -> None:
            self._point(rec, p, None, rapid=True)
            self.stops.append(self.n - 1)

        def feed(p: NDArray[np.float64]) -> None:
            self._point(rec, p, None)
            self.stops.append(self.n - 1)

        rapid(clear)
        kind = c["kind"]
        peck = c.get("peck")
        if kind in ("DEEP", "BRKCHP", "DEEP2") and peck:
            sub = c.get("subpeck") or peck  # SUBPECK 0: none, every peck is STEP
            smallest = min(peck, sub)
            if (c["depth"] + c["clear"]) / smallest > MAX_PECKS:
                raise self._error(
                    rec,
                    f"CYCLE/{kind}: pecks of {smallest:g} mm: more than {MAX_PECKS:,} in one hole",
                )
            step = peck
            reached = -c["clear"]
            while reached + step < c["depth"]:
                reached += step
                feed(top - axis * reached)
                if kind == "BRKCHP":
                    pass  # chip breaking: a stop, no retract
                else:
                    rapid(clear)
                    rapid(top - axis * reached)
                step = sub
        feed(bottom)
        if c.get("dwell", 0.0) > 0:
            self.dwells.append((self.n - 1, c["dwell"]))
        if kind in ("TAP", "BORE", "REAM"):
            feed(clear)
        rapid(retract)
        self.feed = saved

    def _delay(self, rec: Record) -> None:
        vals, rest = leading_numbers(self.src, rec, "DELAY")
        if len(vals) != 1 or rest not in ([], ["SEC"]):
            if "REV" in rest:
                raise self._error(rec, "DELAY in spindle revolutions is not supported")
            raise self._error(rec, "DELAY needs one time in seconds")
        if vals[0] < 0:
            raise self._error(rec, "negative DELAY")
        if self.n == 0:
            self.notes.add("DELAY before the first move ignored", rec.line)
            return
        self.dwells.append((self.n - 1, vals[0]))

    def _stop(self, rec: Record) -> None:
        if self.n == 0:
            self.notes.add(f"{rec.word} before the first move ignored", rec.line)
            return
        self.stops.append(self.n - 1)

    def _fini(self, rec: Record) -> None:
        self.finished = rec.line

    def _mode(self, rec: Record) -> None:
        arg = [a.upper() for a in rec.args or []]
        if arg[:1] == ["TURN"]:
            raise self._error(rec, "MODE/TURN: lathe CL data is not supported")
        self.passive.setdefault("MODE", [rec.line, 0])[1] += 1

    def _insert(self, rec: Record) -> None:
        # INSERT/ copies its text into the NC program; SolidWorks CAM writes tool
        # descriptions with it, but it could hold any block.
        self.notes.add("INSERT/ text for the NC program passed over (not interpreted)", rec.line)

    def _rotary(self, rec: Record) -> None:
        self.notes.add(
            f"{rec.word} (rotary positioning) passed over: the path is read in the frame of "
            "the CL data",
            rec.line,
        )

    # ------------------------------------------------------------------ build
    def _build(self) -> ToolPath:
        src, fast, n = self.src, self.fast, self.n
        if n == 0:
            raise InputError("no moves (GOTO records) in the CL data", source=src.name)
        ch_src = np.array(self.ch_src)
        a, b = np.array(self.ch_a, dtype=np.int64), np.array(self.ch_b, dtype=np.int64)
        cnt = b - a
        base = np.where(ch_src == _FAST, a, fast.line.size + a)
        rows = np.arange(n, dtype=np.int64) + np.repeat(base - (np.cumsum(cnt) - cnt), cnt)
        m = len(self.sp_xyz)
        xyz_tab = np.concatenate([fast.xyz, np.array(self.sp_xyz).reshape(m, 3)])
        ijk_tab = np.concatenate([fast.ijk, np.array(self.sp_ijk).reshape(m, 3)])
        line_tab = np.concatenate([fast.line, np.array(self.sp_line, dtype=np.int64)])

        cols = empty_columns(n)
        end = xyz_tab[rows]
        end *= np.repeat(np.array(self.ch_scale), cnt)[:, None]
        cols["end"] = end
        cols["start"][0] = self.start
        cols["start"][1:] = end[:-1]
        cols["line"] = line_tab[rows] + 1
        kind = cols["kind"]
        kind[self.rapid_moves] = MoveKind.RAPID
        feed = np.repeat(np.array(self.ch_feed), cnt)
        feed[kind == MoveKind.RAPID] = np.nan
        missing = np.isnan(feed) & (kind != MoveKind.RAPID)
        if missing.any():
            k = int(np.argmax(missing))
            raise src.error(
                int(cols["line"][k]) - 1, "feed move without a feed rate (no FEDRAT before it)"
            )
        cols["feed"] = feed
        cols["tool"] = np.repeat(np.array(self.ch_tool, dtype=np.int32), cnt)
        if not self.has_from and kind[0] != MoveKind.RAPID:
            self.notes.add(
                "no FROM record: the first move starts at the origin", int(cols["line"][0]) - 1
            )
        tool_axis = self._tool_axis(ijk_tab[rows], cols["line"])
        self._arcs(cols)
        self._stops_and_dwells(cols)
        offsets, names = self._operations(cols)
        cols["op_offsets"] = offsets
        self._passive_notice()
        if not self.units_set:
            self.notes.add("no UNITS record: millimetres assumed")

        tp = ToolPath(
            **cols,
            op_names=names,
            source=src.name,
            tool_axis=tool_axis,
            units="inch" if self.any_inch else "mm",
        )
        self._direction_check(tp)
        tp, removed = drop_zero_length(tp)
        if removed.size:
            self.notes.add(POINTS_DROPPED, int(cols["line"][removed[0]]) - 1, int(removed.size))
        if tp.n == 0:
            raise InputError("no moves of nonzero length in the CL data", source=src.name)
        return dataclasses.replace(tp, notices=self.notes.notices())

    def _tool_axis(
        self, ijk: NDArray[np.float64], line: NDArray[np.int64]
    ) -> NDArray[np.float64] | None:
        """(n, 3) unit tool axis, carried forward from the records that give one.

        None when no record gives one (a 3-axis file).
        """
        given = ~np.isnan(ijk[:, 0])
        if not given.any() and self.start_axis is None:
            return None
        length = g.norm(np.where(given[:, None], ijk, 1.0))
        bad = given & (np.abs(length - 1.0) > TOL.unit_vector)
        if bad.any():
            k = int(np.argmax(bad))
            raise self.src.error(
                int(line[k]) - 1, f"tool axis i,j,k is not a unit vector (length {length[k]:.6g})"
            )
        initial = self.start_axis if self.start_axis is not None else np.array(PLUS_Z)
        if self.start_axis is None and not given[0]:
            self.notes.add(
                "tool axis before the first GOTO with i,j,k taken as +Z", int(line[0]) - 1
            )
        idx = np.where(given, np.arange(given.size), -1)
        np.maximum.accumulate(idx, out=idx)
        axis = np.where((idx >= 0)[:, None], g.unit(ijk[np.maximum(idx, 0)]), initial)
        changed = np.abs(axis - axis[0]).max(axis=1) > TOL.direction
        if np.any(changed):
            k = int(np.argmax(changed))
            self.notes.add(
                "the tool axis changes (5-axis or indexed CL data): it is kept in the tool path, "
                "and the feed models evaluate the x,y,z path of the tool tip",
                int(line[k]) - 1,
            )
        return axis

    def _arcs(self, cols: dict[str, NDArray]) -> None:
        if not self.arcs:
            return
        idx = np.array([i for i, _ in self.arcs], dtype=np.int64)
        arcs = [a for _, a in self.arcs]
        centre = np.array([a.centre for a in arcs])
        axis = np.array([a.axis for a in arcs])
        radius = np.array([a.radius for a in arcs])
        ccw = ~np.array([a.clockwise for a in arcs])
        turns = np.array([a.turns for a in arcs])
        angle = np.array([a.angle for a in arcs])
        s, e = cols["start"][idx], cols["end"][idx]
        # The record's centre may lie anywhere on the axis (NX puts it at the end
        # point's level for a helix); the tool path keeps it in the start's plane.
        c = centre + g.dot(s - centre, axis)[:, None] * axis
        r0 = g.norm(g.radial(s, c, axis))
        r1 = g.norm(g.radial(e, c, axis))
        has_r = np.isfinite(radius)

        def tol(r: NDArray[np.float64]) -> NDArray[np.float64]:
            return np.maximum(TOL.arc_end_abs, TOL.arc_end_rel * r)

        off_start = has_r & (np.abs(r0 - radius) > tol(np.where(has_r, radius, 0.0)))
        if off_start.any():
            k = int(np.argmax(off_start))
            raise self._arc_error(
                arcs[k],
                arcs[k].line,
                f"the arc's start point (the previous point) is {abs(r0[k] - radius[k]):.4f} mm "
                f"off the circle of radius {radius[k]:.4f} mm",
            )
        ref = np.where(has_r, radius, r0)
        tiny = ref < TOL.min_arc_radius
        if tiny.any():
            k = int(np.argmax(tiny))
            raise self._arc_error(arcs[k], arcs[k].line, "arc with zero radius")
        off_end = np.abs(r1 - ref) > tol(ref)
        if off_end.any():
            k = int(np.argmax(off_end))
            raise self._arc_error(
                arcs[k],
                int(cols["line"][idx[k]]) - 1,
                f"arc end point is {abs(r1[k] - ref[k]):.4f} mm off the circle of radius "
                f"{ref[k]:.4f} mm ({arcs[k].word} at line {arcs[k].line + 1})",
            )
        sweep = g.arc_sweep(s, e, c, axis, ccw, turns)
        given = np.isfinite(angle)
        if given.any():
            # MOVARC gives the sweep itself: check it reaches the end point, then take it
            # (it tells a full circle from none, and counts the turns).
            sgn = np.where(ccw, 1.0, -1.0)[given]
            rv = g.radial(s, c, axis)[given]
            nv = axis[given]
            phi = (sgn * angle[given])[:, None]
            reach = rv * np.cos(phi) + np.cross(nv, rv) * np.sin(phi)
            miss = g.norm(reach - g.radial(e, c, axis)[given]) > tol(ref[given])
            if miss.any():
                k = int(np.flatnonzero(given)[np.argmax(miss)])
                raise self._arc_error(
                    arcs[k],
                    int(cols["line"][idx[k]]) - 1,
                    f"MOVARC ANGLE {np.degrees(angle[k]):g} does not reach the GOTO end point",
                )
            sweep[given] = angle[given]
        cols["kind"][idx] = np.where(ccw, MoveKind.ARC_CCW, MoveKind.ARC_CW)
        cols["center"][idx] = c
        cols["normal"][idx] = axis
        cols["sweep"][idx] = sweep

    def _arc_error(self, arc: Arc, line: int, message: str) -> InputError:
        text = arc.text if line == arc.line else self.src.text(line)
        return InputError(message, source=self.src.name, line=line + 1, text=text)

    def _stops_and_dwells(self, cols: dict[str, NDArray]) -> None:
        if self.stops:
            cols["path_mode"][self.stops] = PathMode.EXACT_STOP
        for i, t in self.dwells:
            cols["dwell"][i] += t

    def _operations(self, cols: dict[str, NDArray]) -> tuple[NDArray[np.int64], tuple[str, ...]]:
        """Operation offsets and names: one per TOOL PATH (else per tool change)."""
        n = self.n
        ops: list[tuple[int, str | None]] = [(0, None)]
        for i, name in self.boundaries:
            if i == ops[-1][0]:
                ops[-1] = (i, name)  # the operation before it is empty
            elif i < n:
                ops.append((i, name))
        if ops and ops[-1][0] >= n:
            ops.pop()
        names = []
        for i, name in ops:
            if name is None:
                t = int(cols["tool"][i])
                where = f"from line {int(cols['line'][i])}"
                name = f"T{t} {where}" if t >= 0 else where
            names.append(name)
        offsets = np.array([i for i, _ in ops] + [n], dtype=np.int64)
        return offsets, tuple(names)

    def _passive_notice(self) -> None:
        if not self.passive:
            return
        first = min(v[0] for v in self.passive.values())
        total = sum(v[1] for v in self.passive.values())
        listed = ", ".join(
            f"{w} ({W.PASSIVE.get(w, 'machining mode')})" for w in sorted(self.passive)
        )
        self.notes.add(f"passed over, they do not move the tool: {listed}", first, total)

    def _direction_check(self, tp: ToolPath) -> None:
        """Warn when arcs reverse against their neighbouring lines more often than they
        continue them: the arcs are then probably read in the wrong direction."""
        arc = np.flatnonzero(tp.is_arc)
        if arc.size == 0:
            return
        line = tp.kind == MoveKind.LINE
        op = tp.op_index
        tangent = reversed_ = 0
        for nb, mine, other in (
            (arc - 1, tp.tangent_start[arc], tp.tangent_end),
            (arc + 1, tp.tangent_end[arc], tp.tangent_start),
        ):
            ok = (nb >= 0) & (nb < tp.n)
            nbc = np.clip(nb, 0, tp.n - 1)
            ok &= line[nbc] & (op[nbc] == op[arc])
            cos = g.dot(mine[ok], other[nbc[ok]])
            tangent += int(np.count_nonzero(cos > _TANGENT_COS))
            reversed_ += int(np.count_nonzero(cos < -_TANGENT_COS))
        if reversed_ > tangent:
            self.notes.add(
                f"{reversed_} arc ends reverse against a neighbouring line and only {tangent} "
                "continue one: the arcs may turn the other way than this CAM system's CIRCLE "
                "convention says (see the adapter's documentation)",
                int(tp.line[arc[0]]) - 1,
            )


def interpret(src: Source, fast: FastGotos) -> ToolPath:
    """The ToolPath of a CL file whose plain GOTO records were read in bulk."""
    return Reader(src, fast).run()
