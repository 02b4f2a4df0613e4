"""LinuxCNC's naive-CAM detector for a program read in the LinuxCNC dialect: which blocks
may run as one segment, from the program's words (the joining itself is core's,
:mod:`core.model.segments`, which cites LinuxCNC 2.9's rules).

What sends the collected points out (LinuxCNC 2.9 emccanon.cc, every canonical call with
``flush_segments``): a rapid, an arc it keeps, a probe or a tap, a change of feed (a
repeated F of the same value does not), of feed mode or of path mode (any G61, G61.1 or
G64 block), a work offset or G92, a tool length offset, a dwell, spindle speed and
direction, coolant, a tool change, program stops and ends, messages, I/O. Here: any block
with an M, S or T word, or with one of the G codes of :data:`FLUSHING_G`, between two lines
(or on the second). The tolerance is Q of the last G64 (P without Q; 0 without both or
after G61/G61.1), in the units in force on its block.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

from adapters.gcode.interp import ffill
from adapters.gcode.lexer import Words
from core.model.arrays import isin, unique
from core.model.errors import Notes
from core.model.segments import chord_deviation, included_angle, merge_lines, split_flat_arcs
from core.model.toolpath import MoveKind, PathMode, ToolPath

#: G codes (x 10) whose canonical calls send the collected points (see module docstring):
#: motion other than G1/G2/G3 (rapids, G28/G30, probing, threading, canned cycles), dwell,
#: G10 and offsets (G5x, G92, G43/G49, G52), path mode (G61, G61.1, G64), feed mode
#: (G93/G94/G95), spindle mode (G96/G97), cutter compensation changes (G40/G41/G42).
FLUSHING_G = frozenset(
    [0, 40, 100, 280, 281, 300, 301, 330, 331, 382, 383, 384, 385, 520, 530]
    + [540, 550, 560, 570, 580, 590, 591, 592, 593, 610, 611, 640, 730, 760]
    + [810, 820, 830, 840, 850, 860, 870, 880, 890, 920, 921, 922, 923]
    + [930, 940, 950, 960, 970, 400, 410, 411, 420, 421, 430, 431, 432, 490]
)
_LETTERS_THAT_FLUSH = (ord("M"), ord("S"), ord("T"))
MM_PER_INCH = 25.4


@dataclasses.dataclass(frozen=True)
class LineInfo:
    """Per line of the file (0-based): the naive-CAM tolerance in force after it (mm) and
    how many lines up to and including it send the collected points (a running count)."""

    tol: NDArray[np.float64]
    flushes: NDArray[np.int64]


def scan(words: Words, block_delete: bool = False) -> LineInfo | None:
    """The lines' tolerances and flushes, or None when no G64 sets a naive-CAM tolerance
    (the detector is off: nothing joins)."""
    n = words.n_lines
    letter, value, line = words.letter, words.value, words.line
    if block_delete and words.block_delete:
        keep = ~isin(line, np.fromiter(words.block_delete, dtype=np.int64))
        letter, value, line = letter[keep], value[keep], line[keep]
    is_g = letter == ord("G")
    code = np.where(is_g & (np.abs(value) < 1e6), np.rint(value * 10), -1).astype(np.int64)
    g64_lines = unique(line[code == 640])
    if g64_lines.size == 0:
        return None

    def per_line(ch: str) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        sel = letter == ord(ch)
        v = np.full(n, np.nan)
        v[line[sel]] = value[sel]
        return v, ~np.isnan(v)

    p, has_p = per_line("P")
    q, has_q = per_line("Q")
    on = (has_p & (p > 0)) | (has_q & (q > 0))
    if not on[g64_lines].any():
        return None
    # units in force on each line (G20 inch, G21 mm; the machine starts in mm)
    unit_set = np.full(n, np.nan)
    unit_set[line[code == 200]] = MM_PER_INCH
    unit_set[line[code == 210]] = 1.0
    scale = ffill(unit_set, ~np.isnan(unit_set), 1.0)
    # the tolerance set on each path-mode line: G64 Q, else G64 P, else 0; G61/G61.1: 0
    mode_lines = unique(line[isin(code, [610, 611, 640])])
    g64 = np.zeros(n, dtype=bool)
    g64[g64_lines] = True
    set_tol = np.where(has_q & (q >= 0), q, np.where(has_p & (p >= 0), p, 0.0)) * scale
    set_tol = np.where(g64, set_tol, 0.0)
    is_mode = np.zeros(n, dtype=bool)
    is_mode[mode_lines] = True
    tol = ffill(set_tol, is_mode, 0.0)
    flush = np.zeros(n, dtype=bool)
    flush[line[isin(letter, _LETTERS_THAT_FLUSH)]] = True
    flush[line[isin(code, list(FLUSHING_G))]] = True
    return LineInfo(tol=tol, flushes=np.cumsum(flush))


def join(tp: ToolPath, info: LineInfo, notes: Notes | None = None) -> ToolPath:
    """``tp`` as LinuxCNC's interpreter sends it to the planner: flat XY arcs as two lines,
    runs of joinable lines as one segment each (see the module docstring)."""
    if tp.tool_axis is not None:
        return tp
    n_lines = info.tol.size
    own = np.ones(tp.n, dtype=bool) if tp.origin is None else tp.origin < 0
    idx = np.clip(tp.line - 1, 0, n_lines - 1)
    tol = np.where(own & (tp.line >= 1) & (tp.line <= n_lines), info.tol[idx], 0.0)
    xy = (tp.normal[:, 2] > 0.5) if tp.kind.size else np.zeros(0, dtype=bool)
    arc = (tp.kind == MoveKind.ARC_CW) | (tp.kind == MoveKind.ARC_CCW)
    radius = np.linalg.norm(tp.start - tp.center, axis=1)
    with np.errstate(invalid="ignore"):
        flat = arc & xy & (tol > 0) & (chord_deviation(radius, included_angle(tp.sweep)) < tol)
    tp2, src = split_flat_arcs(tp, flat)
    tol2 = tol[src]
    line = tp2.line
    k = np.arange(1, tp2.n)
    lines_ok = np.zeros(tp2.n, dtype=bool)
    if tp2.n > 1:
        same_block = src[k] == src[k - 1]  # the two halves of one arc
        no_flush = info.flushes[idx[src[k]]] == info.flushes[idx[src[k - 1]]]
        lines_ok[1:] = same_block | ((line[k] > line[k - 1]) & no_flush)
    line_move = (tp2.kind == MoveKind.LINE) & np.isfinite(tp2.feed) & (tol2 > 0)
    if tp2.rotary is not None:
        line_move &= ~(tp2.rotary != 0.0).any(axis=1)
    can = np.zeros(tp2.n, dtype=bool)
    if tp2.n > 1:
        can[1:] = (
            line_move[k]
            & line_move[k - 1]
            & lines_ok[k]
            & (tp2.feed[k] == tp2.feed[k - 1])
            & (tol2[k] == tol2[k - 1])
            & (tp2.dwell[k - 1] == 0.0)
            & (tp2.path_mode[k - 1] == PathMode.CONTINUOUS)
            & (tp2.tool[k] == tp2.tool[k - 1])
        )
    can[tp2.op_offsets[:-1]] = False
    if tp2.rotary_only is not None:
        after = tp2.rotary_only.after
        can[after[(after >= 0) & (after + 1 < tp2.n)] + 1] = False
    out, joined = merge_lines(tp2, tol2, can)
    split = int(flat.sum())
    if notes is not None and (joined or split):
        first = int(tp2.line[np.argmax(can)]) if joined else int(tp.line[np.argmax(flat)])
        what = f"{joined} of {tp2.n} blocks run as part of the next" if joined else ""
        arcs = f"{split} flat arcs run as two lines" if split else ""
        notes.add(
            "LinuxCNC's naive-CAM detector (G64 P/Q): "
            + "; ".join(x for x in (what, arcs) if x)
            + " (their segments carry the last block's line)",
            first - 1,
        )
    return out
