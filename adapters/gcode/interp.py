"""Words -> ToolPath: modal state and moves, vectorised over lines.

Modal values (motion mode, plane, units, distance mode, feed, path mode...)
are forward-filled over the lines that carry words; positions are a
segmented cumulative sum (absolute words reset it, incremental words add).
Nothing loops over moves in Python.
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from adapters.gcode import words as W
from adapters.gcode.lexer import Source, Words
from core.model import geometry as g
from core.model.arrays import isin, unique
from core.model.errors import InputError, Notes
from core.model.limits import MAX_TOOL
from core.model.pieces import pieces, piecewise
from core.model.tolerances import TOL
from core.model.toolpath import (
    POINTS_DROPPED,
    MoveKind,
    PathMode,
    ToolPath,
    drop_zero_length,
)

INCH = 25.4
AXIS_LETTERS = "XYZ"
CENTRE_LETTERS = "IJK"
ALLOWED = set("GMXYZIJKRFPQNSTHDO")
EXTRA_AXES = set("ABCUVW")


class NeedsInterpreter(Exception):
    """The program needs the full interpreter (adapters.gcode.run), not an error."""


#: Constructs that name a dialect, in the text of a program (for the full interpreter,
#: when the vectorised reader stood aside).
_SIEMENS_TEXT = re.compile(
    rb"(?im)^[^;(\n]*(?:\bDEF\s+(?:REAL|INT|BOOL|STRING)\b|\bR\d+\s*=|\bT\s*=\s*\"|"
    rb"\bMCALL\b|\bCYCLE8\d\b|\bG64[1-5]\b|\bGOTO[FB]\b|\bENDIF\b|\bENDLOOP\b|"
    rb"\bTRANS\b|\bAROT\b|\bG500\b|\bM17\b|\bPROC\s)"
)
_LINUXCNC_TEXT = re.compile(
    rb"(?im)^\s*(?:n\d+\s*)?o\s*(?:<[^>]*>|\d+)\s*(?:sub|call|if|while|do|repeat)\b|#<|"
    rb"\bG0?64\s*P"
)
_FANUC_TEXT = re.compile(rb"(?im)\bM98\b|\bM99\b|\bG65\b|\bWHILE\s*\[|\bIF\s*\[|\bGOTO\s*\d")


def _dialect_of_extension(path: str) -> str | None:
    """LinuxCNC for .ngc, Siemens for .mpf/.spf, else None (the content decides)."""
    ext = Path(path).suffix.lower()
    if ext == ".ngc":
        return "linuxcnc"
    if ext in (".mpf", ".spf"):
        return "siemens"
    return None


def detect_dialect_text(path: str, data: bytes) -> str:
    """Dialect from the extension, else from the constructs in the text, else Fanuc/ISO."""
    by_ext = _dialect_of_extension(path)
    if by_ext:
        return by_ext
    if _SIEMENS_TEXT.search(data):
        return "siemens"
    if _LINUXCNC_TEXT.search(data) and not _FANUC_TEXT.search(data):
        return "linuxcnc"
    return "fanuc"


def detect_dialect(path: str, words: Words) -> str:
    """Dialect from the extension, else from what the program uses."""
    by_ext = _dialect_of_extension(path)
    if by_ext:
        return by_ext
    if words.keywords:
        return "siemens"
    g_values = words.value[words.letter == ord("G")]
    # a G word out of range (G1e999) is refused where it is read; here it only must not be
    # cast to an integer
    g_codes = unique(np.rint(g_values[np.abs(g_values) < 1e6] * 10).astype(np.int64))
    if isin(g_codes, [600, 6410, 6420, 6430, 6440, 6450, 7000, 7100, 5000]).any():
        return "siemens"
    if isin(g_codes, [901, 911, 611]).any():
        return "linuxcnc"
    g64_lines = words.line[(words.letter == ord("G")) & (np.rint(words.value * 10) == 640)]
    p_lines = words.line[words.letter == ord("P")]
    if isin(g64_lines, p_lines).any():
        return "linuxcnc"
    return "fanuc"


#: The interpreter's per-line arrays (attributes), let go once the columns are built.
_PER_LINE = (
    "g",
    "vals",
    "pres",
    "pos",
    "known",
    "kind",
    "arc",
    "is_move",
    "motion",
    "plane",
    "distance",
    "arc_distance",
    "units",
    "path_mode",
    "scale",
    "feed_scale",
    "dwell_time",
    "consumed",
    "m_stop",
    "m_tool",
    "has_m",
    "g_pass_line",
    "home",
)


#: :func:`ffill` repeats the values set, run by run, where at most one position in this
#: many is set (a modal code on a few lines of a million: one pass, not five).
FFILL_SPARSE = 16


def ffill(values: NDArray, is_set: NDArray[np.bool_], initial: float | int) -> NDArray:
    """Forward-fill ``values`` from the positions where ``is_set``; ``initial`` before the first."""
    if not is_set.any():
        return np.full(values.shape, initial, dtype=np.result_type(values, type(initial)))
    at = np.flatnonzero(is_set)
    if FFILL_SPARSE * at.size <= values.size:
        # the runs' values, in the dtype (and with the casts) of the np.where below
        run = np.empty(at.size + 1, dtype=np.where(True, values[:1], initial).dtype)
        run[0] = initial
        run[1:] = values[at]
        return np.repeat(run, np.diff(at, prepend=0, append=values.size))
    del at
    idx = np.where(is_set, np.arange(values.size), -1)
    np.maximum.accumulate(idx, out=idx)
    out = values[np.maximum(idx, 0)]
    return np.where(idx >= 0, out, initial)


def _line_index(line: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.intp]]:
    """``np.unique(line, return_inverse=True)`` of the words' lines, which are sorted (the
    lexer's order): the lines that carry words and each word's index among them, without
    the sort (1M lines: 0.1 s)."""
    first = np.empty(line.size, dtype=bool)  # the word starts its line's words
    first[:1] = True
    np.not_equal(line[1:], line[:-1], out=first[1:])
    return line[first], np.cumsum(first, dtype=np.intp) - 1


@dataclasses.dataclass
class State:
    """The modal state at the start or end of a run of plain lines (G-codes x 10).

    The full interpreter hands long runs of plain lines to this reader with the state it
    has reached, and takes the state at their end back (:meth:`Interpreter.chunk`)."""

    motion: int  # -1: no motion mode
    plane: int
    distance: int
    arc_distance: int
    units: int
    path_mode: int
    tolerance: float  # mm, NaN: none
    feed: float  # mm/s, NaN: none
    pos: tuple[float, float, float]  # program coordinates, mm
    known: tuple[bool, bool, bool]
    units_set: bool = False
    path_mode_set: bool = False


class Interpreter:
    """Turns the words of one program into a ToolPath (see module docstring)."""

    #: per G-code group and line, its code x 10 (-1: none): a row per group (read-only
    #: where the program uses none of the group's codes); after :meth:`_release_per_line`
    #: only the rows the columns read, indexed by group all the same
    g: Any
    #: per letter, its value on each line (NaN: absent) and whether it is there
    vals: dict[str, Any]
    pres: dict[str, Any]

    def __init__(
        self,
        src: Source,
        words: Words,
        dialect: str,
        block_delete: bool,
        initial: State | None = None,
        *,
        default_path_mode: str | None = None,
        offsets_known: bool = False,
        lengths_known: bool = False,
    ) -> None:
        self.src = src
        self.w = words
        self.dialect = dialect
        self.block_delete = block_delete
        self.notes = Notes(src.name)
        self.initial = initial
        self.default_path_mode = default_path_mode
        #: the machine file gives work offsets: a change of work offset needs the full
        #: interpreter (alone, one offset is the program's own origin)
        self.offsets_known = offsets_known
        #: the machine file gives tool lengths: G43 moves the axes, the full interpreter
        #: applies them
        self.lengths_known = lengths_known

    # ------------------------------------------------------------------ helpers
    def error(self, line: int, message: str) -> Exception:
        return self.src.error(int(line), message)

    def _drop(self, keep: NDArray[np.bool_]) -> None:
        w = self.w
        w.line, w.letter = w.line[keep], w.letter[keep]
        w.value, w.bare = w.value[keep], w.bare[keep]

    def _single(self, ch: str) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Per active line: the value of letter ``ch`` (NaN if absent); error if twice."""
        idx = np.zeros(0, dtype=np.intp)
        if self.letter_count[ord(ch)]:  # (a letter the program never writes: no search)
            idx = np.flatnonzero(self.w.letter == ord(ch))
        if idx.size == 0:
            # Read-only views of one value: a letter the program never writes costs nothing.
            return np.broadcast_to(np.nan, (self.na,)), np.broadcast_to(False, (self.na,))
        li = self.li[idx]
        if li.size > 1:
            dup = np.flatnonzero(li[1:] == li[:-1])
            if dup.size:
                raise self.error(self.w.line[idx[dup[0]]], f"two {ch} words in one block")
        vals = np.full(self.na, np.nan)
        vals[li] = self.w.value[idx]
        present = np.zeros(self.na, dtype=bool)
        present[li] = True
        return vals, present

    # ------------------------------------------------------------------ run
    def run(self) -> ToolPath:
        w = self.w
        self._prefilter()
        if w.line.size == 0:
            raise _no_moves(self.src)
        self.al, self.li = _line_index(w.line)
        self.na = self.al.size
        self._gcodes()
        self._mcodes()
        self._modal()
        self._axes()
        self._check_words()
        self._release_per_line()
        return self._build()

    def _release_words(self) -> None:
        """Let the word arrays go once every letter's values are per line (in _axes): what
        follows reads the per-line arrays (5M lines of arcs: 25M words, 430 MB off the
        reader's peak)."""
        w = self.w
        # Empty copies, not views: an empty view keeps its whole base array alive.
        w.line, w.letter = w.line[:0].copy(), w.letter[:0].copy()
        w.value, w.bare = w.value[:0].copy(), w.bare[:0].copy()
        del self.li

    def _release_per_line(self) -> None:
        """Let the per-line values the positions were made of go, and the G-code groups
        but the two the columns read (1M lines: 70 MB), before the columns are built."""
        for ch in "XYZQ":
            self.vals.pop(ch, None)
            self.pres.pop(ch, None)
        keep = (W.Group.PATH_MODE, W.Group.EXACT_STOP_BLOCK)
        self.g = {grp: self.g[grp].copy() for grp in keep}

    def chunk(self) -> tuple[dict | None, State]:
        """A run of plain lines from :attr:`initial`: the moves' columns (program
        coordinates; None when the lines move nothing) and the state at the end. Errors are
        raised as for a whole program; the caller then runs the lines block by block."""
        init = self.initial
        assert init is not None
        w = self.w
        self._prefilter()
        if w.line.size == 0:
            return None, init
        self.al, self.li = _line_index(w.line)
        self.na = self.al.size
        self._gcodes()
        self._mcodes()
        self._modal()
        self._axes()
        self._check_words()
        G = W.Group
        fvals, fpres = self.vals["F"], self.pres["F"]
        if (fpres & (fvals <= 0)).any():
            raise self.error(self.al[np.argmax(fpres & (fvals <= 0))], "feed F must be positive")
        feed_line = ffill(fvals * self.feed_scale, fpres, init.feed)
        pm = self.g[G.PATH_MODE]
        final = State(
            motion=int(self.motion[-1]),
            plane=int(self.plane[-1]),
            distance=int(self.distance[-1]),
            arc_distance=int(self.arc_distance[-1]),
            units=int(self.units[-1]),
            path_mode=int(self.path_mode[-1]),
            tolerance=float(self._tolerance_line()[-1]),
            feed=float(feed_line[-1]),
            pos=(float(self.pos[-1, 0]), float(self.pos[-1, 1]), float(self.pos[-1, 2])),
            known=(
                bool(self.known[-1, 0]),
                bool(self.known[-1, 1]),
                bool(self.known[-1, 2]),
            ),
            units_set=bool((self.g[G.UNITS] >= 0).any()),
            path_mode_set=bool((pm >= 0).any()),
        )
        if not self.is_move.any():
            return None, final
        return self._columns(np.flatnonzero(self.is_move)), final

    def _prefilter(self) -> None:
        """Non-finite numbers, block delete, end of program, letters ncperf does not read."""
        w, src = self.w, self.src
        bad = ~np.isfinite(w.value)
        if bad.any():
            raise self.error(w.line[np.argmax(bad)], "number out of range")
        if w.block_delete:
            lines = np.array(sorted(w.block_delete), dtype=np.int64)
            if self.block_delete:
                self._drop(~isin(w.line, lines))
                self.notes.add(
                    "block-delete lines skipped (block delete on)", int(lines[0]), lines.size
                )
            else:
                self.notes.add(
                    "block-delete lines executed (block delete off; --block-delete skips them)",
                    int(lines[0]),
                    lines.size,
                )
        is_m = w.letter == ord("M")
        mval = w.value[is_m]
        frac = mval != np.rint(mval)
        if frac.any():
            raise self.error(
                w.line[np.flatnonzero(is_m)[np.argmax(frac)]],
                f"M{mval[np.argmax(frac)]:g} is not an M-code ncperf knows",
            )
        ends = w.line[is_m][isin(mval, list(W.M_END))]
        if ends.size:
            e = int(ends.min())
            after = w.line > e
            motion = after & isin(w.letter, [ord(c) for c in "GXYZ"])
            if motion.any():
                self.notes.add(
                    "words after the end of program (M2/M30) ignored",
                    int(w.line[np.argmax(motion)]),
                )
            self._drop(~after)
        # the words per letter (kept: a letter no word has is not searched for); np.unique
        # of the letters without the sort (2M words: 12 ms, not 32)
        self.letter_count = np.bincount(w.letter, minlength=256)
        letters = np.flatnonzero(self.letter_count).astype(np.uint8)
        for code in letters:
            ch = chr(code)
            if ch in ALLOWED:
                continue
            first = w.line[np.argmax(w.letter == code)]
            if ch in EXTRA_AXES:
                raise self.error(
                    first, f"axis word {ch}: only X, Y and Z are supported (3-axis G-code)"
                )
            if ch == "L":
                raise self.error(first, "L word (repeat count or subprogram call) is not supported")
            raise src.error(int(first), f"unknown word {ch}")
        if w.keywords:
            for line, kw in w.keywords:
                note = W.PASS_KEYWORDS.get(kw, "")
                if note:
                    self.notes.add(f"{kw}: {note}", line)

    def _gcodes(self) -> None:
        w = self.w
        table = W.TABLES[self.dialect]
        gi = np.flatnonzero(w.letter == ord("G"))
        v = w.value[gi]
        with np.errstate(invalid="ignore", over="ignore"):  # G1e308: "unknown G-code" below
            code = np.rint(v * 10).astype(np.int64)
        group = np.full(gi.size, -1, dtype=np.int64)
        for c in unique(code):
            sel = code == c
            first = w.line[gi[np.argmax(sel)]]
            entry = table.get(int(c))
            if entry is None:
                raise self.error(first, f"unknown G-code G{c / 10:g} ({self.dialect} dialect)")
            if entry.group is None:
                raise self.error(first, entry.message)
            if entry.message:
                self.notes.add(entry.message, first)
            group[sel] = entry.group
        if self.lengths_known and isin(code, [430, 431, 432]).any():
            raise NeedsInterpreter("tool lengths from the machine file")
        exact = np.abs(v * 10 - code) < TOL.code_number
        if not exact.all():
            k = np.argmin(exact)
            raise self.error(w.line[gi[k]], f"unknown G-code G{v[k]:g}")
        li = self.li[gi]
        modal = group != W.Group.PASS
        key = li[modal] * W.N_GROUPS + group[modal]
        order = np.argsort(key, kind="stable")
        ks = key[order]
        dup = np.flatnonzero(ks[1:] == ks[:-1])
        if dup.size:
            k = gi[modal][order][dup[0] + 1]
            raise self.error(w.line[k], "two G-codes of the same modal group in one block")
        # A row per group the program uses (G-codes x 10 fit int32); a group it does not
        # use reads one row of -1, never written (1M lines: 4 MB a group not filled)
        none = np.broadcast_to(np.int32(-1), (self.na,))
        rows = [none] * W.N_GROUPS
        g_mod, li_mod, code_mod = group[modal], li[modal], code[modal]
        for grp in unique(g_mod).tolist():
            sel = g_mod == grp
            row = np.full(self.na, -1, dtype=np.int32)
            row[li_mod[sel]] = code_mod[sel]
            rows[grp] = row
        self.g = rows
        # Codes that only pass: remembered per line for the P/Q checks.
        self.g_pass_line = np.zeros(self.na, dtype=bool)
        self.g_pass_line[li[~modal]] = True

    def _mcodes(self) -> None:
        w = self.w
        mi = np.flatnonzero(w.letter == ord("M"))
        m = np.rint(w.value[mi]).astype(np.int64)
        for c, msg in W.M_ERRORS.items():
            hit = m == c
            if hit.any():
                raise self.error(w.line[mi[np.argmax(hit)]], msg)
        li = self.li[mi]
        self.has_m = np.zeros(self.na, dtype=bool)
        self.has_m[li] = True
        self.m_stop = np.zeros(self.na, dtype=bool)
        self.m_stop[li[isin(m, list(W.M_STOP))]] = True
        self.m_tool = np.zeros(self.na, dtype=bool)
        self.m_tool[li[m == W.M_TOOL_CHANGE]] = True

    def _modal(self) -> None:
        G = W.Group
        gg = self.g
        na = self.na

        def fill(group: W.Group, initial: int) -> NDArray[np.int64]:
            row = gg[group]
            return ffill(row, row >= 0, initial)

        init = self.initial
        self.motion = fill(G.MOTION, -1 if init is None else init.motion)
        self.plane = fill(G.PLANE, 170 if init is None else init.plane)
        self.distance = fill(G.DISTANCE, 900 if init is None else init.distance)
        self.arc_distance = fill(G.ARC_DISTANCE, 911 if init is None else init.arc_distance)
        units_set = gg[G.UNITS] >= 0
        if not units_set.any() and init is None:
            self.notes.add("no G20/G21 (or G70/G71): millimetres assumed")
        self.units = fill(G.UNITS, 210 if init is None else init.units)
        fm = gg[G.FEED_MODE]
        for code, name in ((930, "G93 inverse-time feed"), (950, "G95 feed per revolution")):
            hit = fm == code
            if hit.any():
                raise self.error(self.al[np.argmax(hit)], f"{name} is not supported")
        stop = W.exact_stop_codes(self.dialect)[0]  # the machine's default exact stop
        default = stop if self.default_path_mode == "exact_stop" else 640
        self.path_mode = fill(G.PATH_MODE, default if init is None else init.path_mode)
        if init is None and not (gg[G.PATH_MODE] >= 0).any():
            note = W.path_mode_note(self.dialect, self.default_path_mode)
            if note:
                self.notes.add(note)
        wcs_row = gg[G.WORK_OFFSET]
        wcs_set = np.flatnonzero(wcs_row >= 0)
        if wcs_set.size:
            codes = wcs_row[wcs_set]
            change = np.flatnonzero(codes[1:] != codes[:-1])
            if change.size and self.offsets_known:
                raise NeedsInterpreter("work offsets from the machine file")
            if change.size:
                k = wcs_set[change[0] + 1]
                self.notes.add(
                    f"work offset changes to G{codes[change[0] + 1] / 10:g}, whose value is not "
                    "known (no G10 L2 in the program, no [offsets] in the machine file): 0 "
                    "assumed, so moves before and after may not be placed relative to each other",
                    int(self.al[k]),
                )
        geom_inch = np.zeros(na, dtype=bool)
        feed_inch = np.zeros(na, dtype=bool)
        for code, (gi, fi) in W.UNITS.items():
            sel = self.units == code
            geom_inch[sel] = gi
            feed_inch[sel] = fi
        if self.dialect == "siemens" and (gg[G.UNITS] == 700).any():
            self.notes.add(
                "G70: feeds taken in mm/min (the basic system is assumed metric)",
                int(self.al[np.argmax(gg[G.UNITS] == 700)]),
            )
        # One value over the program (no inch lines) is a broadcast: no memory per line.
        na_shape = (na,)
        self.scale = (
            np.where(geom_inch, INCH, 1.0) if geom_inch.any() else np.broadcast_to(1.0, na_shape)
        )
        self.feed_scale = (  # -> mm/s
            np.where(feed_inch, INCH, 1.0) / 60.0
            if feed_inch.any()
            else np.broadcast_to(1.0 / 60.0, na_shape)
        )
        self.any_inch = bool(geom_inch.any())

    def _axes(self) -> None:
        """Positions, moves, dwells."""
        G = W.Group
        gg = self.g
        al = self.al
        vals = {}
        pres = {}
        for ch in "XYZIJKRFPQNT":
            vals[ch], pres[ch] = self._single(ch)
        self.vals, self.pres = vals, pres
        # Every letter's values are per line now: the words' own go before the positions
        # are worked out (1M lines of arcs: 38 MB), once the decimal-point notice, which
        # quotes one, is made (it is added where it always was: the notices keep their order).
        self._bare_notice = self._decimal_point_args() if self.dialect == "fanuc" else None
        self._o_word_line = self._o_word_mixed()
        # (the S words' lines: a Siemens G4 S is refused in _dwells)
        self._s_lines = (
            self.w.line[self.w.letter == ord("S")]
            if self.letter_count[ord("S")]
            else np.zeros(0, dtype=self.w.line.dtype)
        )
        self._release_words()

        dwell_line = gg[G.DWELL] >= 0
        self.dwell_time = np.broadcast_to(0.0, (self.na,))  # read only; _dwells sets it
        self.consumed = {ch: np.zeros(self.na, dtype=bool) for ch in "XPF"}
        if dwell_line.any():
            self._dwells(dwell_line)
        home = gg[G.HOME] >= 0
        machine = gg[G.MACHINE_COORDS] >= 0
        if home.any() or machine.any():
            # home returns and machine coordinates: the full interpreter models them
            raise NeedsInterpreter("G28/G30/G53")

        given = {}
        for ch in AXIS_LETTERS:
            gvn = pres[ch].copy()
            if ch == "X":
                gvn &= ~self.consumed["X"]
            given[ch] = gvn
        has_axis = given["X"] | given["Y"] | given["Z"]
        motion = self.motion
        explicit_arc = isin(gg[G.MOTION], [W.MOTION_CW, W.MOTION_CCW])
        centre_words = pres["I"] | pres["J"] | pres["K"]
        full_circle = explicit_arc & ~has_axis & centre_words
        no_mode = has_axis & ~home & ((motion < 0) | (motion == W.MOTION_NONE))
        if no_mode.any():
            raise self.error(
                al[np.argmax(no_mode)], "axis words without a motion mode (G0, G1, G2 or G3)"
            )
        if (machine & has_axis & (motion != W.MOTION_RAPID) & ~home).any():
            k = np.argmax(machine & has_axis & (motion != W.MOTION_RAPID))
            raise self.error(al[k], "G53 with a feed move: machine coordinates are unknown")
        if (home & has_axis).any():
            self.notes.add(
                "G28/G30: the move to the machine's home position is not modelled "
                "(home is unknown); the path continues from the intermediate point",
                int(al[np.argmax(home)]),
            )
        if (machine & has_axis).any():
            self.notes.add(
                "G53 machine coordinates taken as work coordinates (the offset is "
                "unknown); only rapids are affected",
                int(al[np.argmax(machine)]),
            )
        is_move = has_axis | full_circle
        self.is_move = is_move
        self.home = home

        # Positions: a segmented cumulative sum per axis.
        absolute = (self.distance == 900) | machine
        pos = np.zeros((self.na, 3))
        known = np.zeros((self.na, 3), dtype=bool)
        for axis, ch in enumerate(AXIS_LETTERS):
            gvn = given[ch]
            # (in place throughout: the same values as the expressions in the comments,
            # without their (lines,) temporaries; 5M lines, this is the reader's peak)
            mm = np.where(gvn, vals[ch], 0.0)
            mm *= self.scale
            abs_set = gvn & absolute
            incremental = gvn & ~absolute
            # the increments, then their sums; none (a program in G90 throughout): their
            # sums are +0.0 everywhere, added as the scalar (the same values, -0.0 + 0.0
            # included), not as an array of zeros
            csum: NDArray[np.float64] | float = 0.0
            if incremental.any():
                sums = np.where(incremental, mm, 0.0)
                np.cumsum(sums, out=sums)
                csum = sums
                del sums
            del incremental
            last = np.arange(self.na)  # np.where(abs_set, np.arange(na), -1), then its max
            last[~abs_set] = -1
            np.maximum.accumulate(last, out=last)
            before = 0.0 if self.initial is None else self.initial.pos[axis]
            # np.where(last >= 0, mm[i] - csum[i], before) + csum with i = max(last, 0)
            none = last < 0
            at = np.maximum(last, 0, out=last)
            base = mm[at]
            if not isinstance(csum, float):
                base -= csum[at]  # (x - 0.0 is x: nothing to take where there is none)
            base[none] = before
            np.add(base, csum, out=pos[:, axis])
            del mm, csum, last, at, none, base
            known[:, axis] = np.maximum.accumulate(gvn)
            if self.initial is not None and self.initial.known[axis]:
                known[:, axis] = True
        self.pos = pos
        self.known = known

        # Motion kind per move line.
        kind = np.full(self.na, -1, dtype=np.int64)
        kind[motion == W.MOTION_RAPID] = MoveKind.RAPID
        kind[motion == W.MOTION_LINE] = MoveKind.LINE
        kind[motion == W.MOTION_CW] = MoveKind.ARC_CW
        kind[motion == W.MOTION_CCW] = MoveKind.ARC_CCW
        kind[home] = MoveKind.RAPID
        self.kind = kind

    def _dwells(self, dwell_line: NDArray[np.bool_]) -> None:
        v, p = self.vals, self.pres
        al = self.al
        d = self.dialect
        t = np.full(self.na, np.nan)
        if d == "linuxcnc":
            if (dwell_line & p["X"]).any():
                raise self.error(al[np.argmax(dwell_line & p["X"])], "axis word on a G4 block")
            t = np.where(p["P"], v["P"], np.nan)
            self.consumed["P"] = dwell_line & p["P"]
        elif d == "fanuc":
            # Fanuc: G4 X (s) or G4 P (ms, no decimal point).
            t = np.where(p["X"], v["X"], np.where(p["P"], v["P"] / 1000.0, np.nan))
            self.consumed["X"] = dwell_line & p["X"]
            self.consumed["P"] = dwell_line & p["P"]
        else:  # siemens: G4 F (s); G4 S is in spindle revolutions
            s_lines = self._s_lines
            if isin(al[dwell_line], s_lines).any():
                k = np.flatnonzero(dwell_line)[isin(al[dwell_line], s_lines)][0]
                raise self.error(al[k], "G4 S (dwell in spindle revolutions) is not supported")
            t = np.where(p["F"], v["F"], np.nan)
            self.consumed["F"] = dwell_line & p["F"]
        missing = dwell_line & np.isnan(t)
        if missing.any():
            raise self.error(al[np.argmax(missing)], "G4 dwell without a time")
        if (dwell_line & (t < 0)).any():
            raise self.error(al[np.argmax(dwell_line & (t < 0))], "negative dwell time")
        self.dwell_time = np.where(dwell_line, t, 0.0)

    def _check_words(self) -> None:
        """Words no code on their block uses: an error, never a silent misreading."""
        G = W.Group
        p, al, gg = self.pres, self.al, self.g
        arc = self.is_move & isin(self.kind, [MoveKind.ARC_CW, MoveKind.ARC_CCW]) & ~self.home
        self.arc = arc
        for ch in "IJKR":
            bad = p[ch] & ~arc
            if bad.any():
                raise self.error(al[np.argmax(bad)], f"{ch} word on a block that is not an arc")
        g64 = gg[G.PATH_MODE] == 640
        lc = self.dialect == "linuxcnc"
        p_ok = self.consumed["P"] | self.has_m | self.g_pass_line | (gg[G.WORK_OFFSET] >= 0)
        if lc:
            p_ok |= g64 | arc
        bad = p["P"] & ~p_ok
        if bad.any():
            raise self.error(al[np.argmax(bad)], "P word not used by any code in this block")
        q_ok = self.has_m | self.g_pass_line | (g64 if lc else False)
        bad = p["Q"] & ~q_ok
        if bad.any():
            raise self.error(al[np.argmax(bad)], "Q word not used by any code in this block")
        if self._o_word_line is not None:
            raise self.error(
                self._o_word_line,
                "O word with other words in the block (subprograms are not "
                "supported; a program number stands alone)",
            )

    def _o_word_mixed(self) -> int | None:
        """The first line's word on a block with an O word and other words (other than N),
        if any: found while the words are at hand, reported by :meth:`_check_words`."""
        if not self.letter_count[ord("O")]:
            return None
        o = self.w.letter == ord("O")
        lines_o = self.li[o]
        others = isin(self.li, lines_o) & ~isin(self.w.letter, [ord("O"), ord("N")])
        return int(self.w.line[np.argmax(others)]) if others.any() else None

    # ------------------------------------------------------------------ build
    def _build(self) -> ToolPath:
        mi = np.flatnonzero(self.is_move)
        if mi.size == 0:
            raise _no_moves(self.src)
        cols = self._columns(mi)
        n = mi.size
        # Tools and operations.
        tvals, tpres = self.vals["T"], self.pres["T"]
        bad_t = tpres & ~((tvals >= 0) & (tvals <= MAX_TOOL) & (tvals == np.floor(tvals)))
        if bad_t.any():
            k = int(np.flatnonzero(bad_t)[0])
            raise self.error(self.al[k], f"tool number must be a whole number 0 to {MAX_TOOL}")
        t_sel = ffill(tvals, tpres, -1)
        if self.m_tool.any():
            tool_line = ffill(t_sel, self.m_tool, -1)
            change = np.flatnonzero(self.m_tool)
        else:
            tool_line = t_sel
            change = np.zeros(0, dtype=np.int64)
        cols["tool"] = tool_line[mi].astype(np.int32)
        first_move = np.searchsorted(mi, change, side="left")
        offs = unique(np.concatenate([[0], first_move[first_move < n], [n]]))
        names = []
        for a in offs[:-1]:
            t = int(cols["tool"][a])
            names.append(
                f"T{t} from line {int(cols['line'][a])}"
                if t >= 0
                else f"from line {int(cols['line'][a])}"
            )
        cols["op_offsets"] = offs

        if self._bare_notice is not None:
            self.notes.add(*self._bare_notice)

        # The per-line arrays are spent: they go before the tool path is checked and its
        # zero-length moves dropped (the reader's peak; 1M lines, 100 MB).
        for name in _PER_LINE:
            self.__dict__.pop(name, None)
        tp = ToolPath(
            **cols,
            op_names=tuple(names),
            source=self.src.name,
            units="inch" if self.any_inch else "mm",
        )
        del cols  # (columns of one value are now broadcasts: the full ones go)
        lines = tp.line
        tp, removed = drop_zero_length(tp)
        if removed.size:
            self.notes.add(POINTS_DROPPED, int(lines[removed[0]] - 1), int(removed.size))
        del lines
        if tp.n == 0:
            raise _no_moves(self.src)
        return dataclasses.replace(tp, notices=self.notes.notices())

    def _tolerance_line(self) -> NDArray[np.float64]:
        """Per line: the path tolerance in force (mm; LinuxCNC G64 P), NaN for none."""
        initial = math.nan if self.initial is None else self.initial.tolerance
        if self.dialect != "linuxcnc":
            return np.full(self.na, initial)
        pm = self.g[W.Group.PATH_MODE]
        p = self.vals["P"]
        tol = np.where((pm == 640) & self.pres["P"] & (p > 0), p * self.scale, np.nan)
        tol[pm == W.EXACT_PATH] = 0.0  # G61, exact path: no deviation at all
        return ffill(tol, pm >= 0, initial)

    def _columns(self, mi: NDArray[np.int64]) -> dict:
        """The columns of the moves on lines ``mi`` (all but tools and operations)."""
        al = self.al
        n = mi.size
        first = np.zeros(3) if self.initial is None else np.array(self.initial.pos)
        # Each move starts where the line before it left the axes (the first line: ``first``).
        # (np.take along axis 0: the rows of self.pos[...], several times faster)
        start = np.take(self.pos, np.maximum(mi - 1, 0), axis=0)
        if n and mi[0] == 0:
            start[0] = first
        end = np.take(self.pos, mi, axis=0)
        kind = self.kind[mi]
        # Only the columns no line fills start from their defaults (empty_columns' values):
        # the others are built once, not over a default (1M moves: 100 MB less at the peak).
        # The defaults that are replaced whole, not filled in, are read-only broadcasts of
        # their one value (as the tool path keeps such columns): no memory per move.
        # So are the arc columns until _arcs, which makes them once the arcs are worked out
        # (a program of lines has none: 1M lines, 56 MB of NaN less).
        cols: dict[str, Any] = {
            "center": np.broadcast_to(np.full(3, np.nan), (n, 3)),
            "normal": np.broadcast_to(np.full(3, np.nan), (n, 3)),
            "sweep": np.broadcast_to(np.nan, (n,)),
            "tool": np.broadcast_to(np.int32(-1), (n,)),
            "dwell": np.broadcast_to(0.0, (n,)),
            "tolerance": np.broadcast_to(np.nan, (n,)),
            "op_offsets": np.array([0, n], dtype=np.int64),
        }
        cols["kind"] = kind.astype(np.int8)
        cols["start"] = start
        cols["end"] = end
        cols["line"] = al[mi] + 1
        n_vals, n_pres = self.vals["N"], self.pres["N"]
        cols["block"] = np.where(n_pres[mi], n_vals[mi], -1).astype(np.int64)

        # Unknown start: a feed move before every axis was set.
        unknown = ~np.take(self.known, np.maximum(mi - 1, 0), axis=0)
        unknown[mi == 0] = True if self.initial is None else ~np.array(self.initial.known)
        feedmove = kind != MoveKind.RAPID
        bad = feedmove & (unknown[:, 0] | unknown[:, 1] | unknown[:, 2])  # (any, by column)
        if bad.any():
            k = int(np.argmax(bad))
            axes = "".join(a for a, u in zip(AXIS_LETTERS, unknown[k], strict=True) if u)
            self.notes.add(
                f"feed move starts before {axes} was programmed: 0 assumed", int(al[mi[k]])
            )

        # Feed (mm/s), modal.
        fvals, fpres = self.vals["F"], self.pres["F"] & ~self.consumed["F"]
        if (fpres & (fvals <= 0)).any():
            raise self.error(al[np.argmax(fpres & (fvals <= 0))], "feed F must be positive")
        initial_feed = math.nan if self.initial is None else self.initial.feed
        feed_line = ffill(fvals * self.feed_scale, fpres, initial_feed)
        feed = feed_line[mi]
        nofeed = feedmove & np.isnan(feed)
        if nofeed.any():
            raise self.error(al[mi[np.argmax(nofeed)]], "feed move without a feed rate F")
        cols["feed"] = np.where(feedmove, feed, np.nan)
        del feed_line, feed, kind  # (the reader's peak is in what follows: 1M lines, 24 MB)

        self._arcs(cols, mi)

        # Path mode: modal exact stop, G9 on the block, M0/M1 after the block.
        exact_line = isin(self.path_mode, W.exact_stop_codes(self.dialect)) | (
            self.g[W.Group.EXACT_STOP_BLOCK] >= 0
        )
        mode = np.where(exact_line[mi], PathMode.EXACT_STOP, PathMode.CONTINUOUS).astype(np.int8)
        stop_lines = np.flatnonzero(self.m_stop)
        if stop_lines.size:
            owner = np.searchsorted(mi, stop_lines, side="right") - 1
            mode[owner[owner >= 0]] = PathMode.EXACT_STOP
        cols["path_mode"] = mode

        # Dwell after the last move before (or on) the G4 block.
        dl = np.flatnonzero(self.dwell_time > 0)
        if dl.size:
            owner = np.searchsorted(mi, dl, side="right") - 1
            dwell = np.zeros(n)
            np.add.at(dwell, owner[owner >= 0], self.dwell_time[dl[owner >= 0]])
            if (owner < 0).any():
                self.notes.add("G4 before the first move ignored", int(al[dl[0]]))
            cols["dwell"] = dwell

        # Path tolerance from LinuxCNC G64 P.
        if self.dialect == "linuxcnc" or self.initial is not None:
            cols["tolerance"] = self._tolerance_line()[mi]
        ctol = [(line, v) for line, name, v in self.w.settings if name == "CTOL"]
        if ctol:
            at = np.array([line for line, _ in ctol])
            val = np.array([v for _, v in ctol])
            # The last CTOL at or before each move's line, in that line's units.
            last = np.searchsorted(at, al[mi], side="right") - 1
            cols["tolerance"] = np.where(
                last >= 0, val[np.maximum(last, 0)] * self.scale[mi], np.nan
            )

        return cols

    def _arcs(self, cols: dict, mi: NDArray[np.int64]) -> None:
        arc_l = np.flatnonzero(self.arc[mi])
        if arc_l.size == 0:
            return
        lines = mi[arc_l]
        al = self.al[lines]
        plane = self.plane[lines]
        normals = np.array([W.PLANE_NORMAL[int(p)] for p in (170, 180, 190)])
        if (plane == plane[0]).all():  # one plane (the usual case): one row, broadcast
            normal = np.broadcast_to(
                normals[np.searchsorted([170, 180, 190], plane[0])], (plane.size, 3)
            )
        else:
            normal = normals[np.searchsorted([170, 180, 190], plane)]
        # The arcs' rows of the start and end columns are read where needed, in pieces
        # (1M arcs: no 48 MB copies of them while the sweeps are worked out).
        start, end = cols["start"], cols["end"]
        ccw = self.kind[lines] == MoveKind.ARC_CCW
        scale = self.scale[lines]
        v, p = self.vals, self.pres
        has_ijk = p["I"][lines] | p["J"][lines] | p["K"][lines]
        has_r = p["R"][lines]
        both = has_ijk & has_r
        if both.any():
            raise self.error(al[np.argmax(both)], "arc with both I/J/K and R")
        neither = ~has_ijk & ~has_r
        if neither.any():
            raise self.error(al[np.argmax(neither)], "arc without I/J/K or R")
        off = np.stack([np.nan_to_num(v[c][lines]) for c in CENTRE_LETTERS], axis=1)
        r_idx = np.flatnonzero(has_r)
        r_val = v["R"][lines[r_idx]] * scale[r_idx] if r_idx.size else None
        # The per-line centre words are read: they go before the centres and sweeps are
        # worked out (1M arcs: 16 MB of I and J).
        for c in (*CENTRE_LETTERS, "R"):
            v.pop(c, None)
            p.pop(c, None)
        off *= scale[:, None]
        off_n = g.dot(off, normal)
        bad = has_ijk & (np.abs(off_n) > TOL.zero_length)
        if bad.any():
            k = int(np.argmax(bad))
            word = CENTRE_LETTERS[int(np.argmax(normal[k]))]
            raise self.error(
                al[k], f"{word} word is not in the arc's plane (G{int(plane[k]) // 10})"
            )
        off -= off_n[:, None] * normal  # the offset in the plane (in place: 24 MB per 1M arcs)
        off_in = off
        del off, off_n
        absolute = np.flatnonzero(self.arc_distance[lines] == 901)
        off_abs = off_in[absolute]
        m = arc_l.size
        for b in pieces(m):  # incremental centres (G91.1, the default), in place ...
            off_in[b] += start[arc_l[b]]
        centre = off_in
        if absolute.size:  # ... and absolute ones (G90.1): the offset in the start's plane
            sa, na = start[arc_l[absolute]], normal[absolute]
            centre[absolute] = off_abs + g.dot(sa, na)[:, None] * na
        del off_in, off_abs

        if r_val is not None:
            centre[r_idx] = self._r_centres(
                start[arc_l[r_idx]],
                end[arc_l[r_idx]],
                normal[r_idx],
                ccw[r_idx],
                r_val,
                al[r_idx],
            )
        # Row by row, in pieces: the same numbers, bounded (m, 3) temporaries.
        r0 = piecewise(
            m, np.float64, lambda b: g.norm(g.radial(start[arc_l[b]], centre[b], normal[b]))
        )
        r1 = piecewise(
            m, np.float64, lambda b: g.norm(g.radial(end[arc_l[b]], centre[b], normal[b]))
        )
        tiny = r0 < TOL.min_arc_radius
        if tiny.any():
            raise self.error(al[np.argmax(tiny)], "arc with zero radius")
        mismatch = np.abs(r1 - r0)
        off_circle = (mismatch > TOL.arc_end_abs) & (mismatch > TOL.arc_end_rel * r0)
        if off_circle.any():
            k = int(np.argmax(off_circle))
            raise self.error(
                al[k],
                f"arc end point is {mismatch[k]:.4f} mm off the circle "
                f"(radius {r0[k]:.4f} mm from the start)",
            )
        del r0, r1, mismatch
        turns = np.broadcast_to(0.0, (m,))  # (no memory per arc)
        if self.dialect == "linuxcnc":
            pt = p["P"][lines]
            pv = v["P"][lines]
            badp = pt & ((pv < 1) | (pv != np.rint(pv)))
            if badp.any():
                raise self.error(
                    al[np.argmax(badp)], "P on an arc must be a positive integer number of turns"
                )
            turns = np.where(pt, pv - 1, 0)
        sweep = piecewise(
            m,
            np.float64,
            lambda b: g.arc_sweep(
                start[arc_l[b]], end[arc_l[b]], centre[b], normal[b], ccw[b], turns[b]
            ),
        )
        # The moves' arc columns (NaN for lines), made now that the arcs' temporaries are gone.
        n = mi.size
        cols["center"] = np.full((n, 3), np.nan)
        cols["center"][arc_l] = centre
        centre = centre[:0].copy()  # it goes (rebound: the pieces' functions above read it)
        cols["normal"] = np.full((n, 3), np.nan)
        cols["normal"][arc_l] = normal
        cols["sweep"] = np.full(n, np.nan)
        cols["sweep"][arc_l] = sweep

    def _r_centres(
        self, s: NDArray, e: NDArray, normal: NDArray, ccw: NDArray, r: NDArray, lines: NDArray
    ) -> NDArray:
        """Centres of R-format arcs: R > 0 the short way, R < 0 the long way round."""
        chord = e - s
        chord = chord - g.dot(chord, normal)[:, None] * normal
        length = g.norm(chord)
        same = length <= TOL.zero_length
        if same.any():
            raise self.error(
                lines[np.argmax(same)],
                "R arc whose end point is its start point (use I/J/K for a circle)",
            )
        rad = np.abs(r)
        if (rad < TOL.min_arc_radius).any():
            raise self.error(lines[np.argmax(rad < TOL.min_arc_radius)], "arc with zero radius")
        h2 = rad**2 - (length / 2) ** 2
        short = h2 < 0
        too_short = short & (length / 2 - rad > TOL.arc_radius)
        if too_short.any():
            k = int(np.argmax(too_short))
            raise self.error(
                lines[k], f"R {r[k]:.4f} mm is less than half the chord ({length[k] / 2:.4f} mm)"
            )
        h = np.sqrt(np.maximum(h2, 0.0))
        left = np.cross(normal, chord / length[:, None])
        sign = np.where(ccw, 1.0, -1.0) * np.sign(r)
        return s + chord / 2 + (sign * h)[:, None] * left

    def _decimal_point_args(self) -> tuple[str, int, int] | None:
        """The notice (message, line, count) of dimension words without a decimal point."""
        w = self.w
        sel = w.bare
        if not sel.any():
            return None
        k = int(np.argmax(sel))
        return (
            f"{chr(w.letter[k])}{w.value[k]:g} has no decimal point: read as "
            f"{w.value[k]:g} (calculator-type input); a Fanuc control without it reads "
            "the least input increment (e.g. 0.001 mm)",
            int(w.line[k]),
            int(sel.sum()),
        )


def _no_moves(src: Source) -> InputError:
    return InputError("no moves (G0, G1, G2, G3) in the program", source=src.name)


def interpret(
    src: Source,
    words: Words,
    dialect: str | None,
    block_delete: bool,
    *,
    default_path_mode: str | None = None,
    offsets_known: bool = False,
    lengths_known: bool = False,
) -> ToolPath:
    """The ToolPath of a tokenised program."""
    d = dialect or detect_dialect(src.name, words)
    return Interpreter(
        src,
        words,
        d,
        block_delete,
        default_path_mode=default_path_mode,
        offsets_known=offsets_known,
        lengths_known=lengths_known,
    ).run()
