"""CL text -> lines, and the plain GOTO records read in bulk with numpy.

A CL file of a finishing path is mostly ``GOTO/x,y,z`` lines. Those whose
value part holds nothing but numbers, commas and blanks are found and
converted over the whole file at once (one ``np.fromstring`` call), without a
Python object per record. Every other line -- CIRCLE, FEDRAT, RAPID, comments,
continuations, and GOTO lines with anything unusual -- goes through the
per-record reader (:mod:`adapters.cl_data.records`), which also gives the
errors: a GOTO line the bulk path cannot take is simply left to it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from adapters.source import Source

LF, CR, TAB, SPACE = 10, 13, 9, 32
SLASH, COMMA = ord("/"), ord(",")

_NUMBER = np.zeros(256, dtype=bool)
for _ch in b"0123456789.+-eE":
    _NUMBER[_ch] = True
_BLANK = np.zeros(256, dtype=bool)
for _ch in (SPACE, TAB, CR):
    _BLANK[_ch] = True
#: Bytes a value span of the bulk path may hold (LF ends the span).
_SPAN_OK = _NUMBER | _BLANK
_SPAN_OK[COMMA] = _SPAN_OK[LF] = True
_SEPARATOR = np.zeros(256, dtype=bool)
_SEPARATOR[COMMA] = _SEPARATOR[LF] = True


@dataclass
class FastGotos:
    """The GOTO lines read in bulk, in file order.

    Attributes
    ----------
    line : (k,) int64
        0-based line of each record.
    xyz : (k, 3) float
        Point, in the file's length unit.
    ijk : (k, 3) float
        Tool axis of 6-value records; NaN for 3-value records.
    """

    line: NDArray[np.int64]
    xyz: NDArray[np.float64]
    ijk: NDArray[np.float64]

    @classmethod
    def empty(cls) -> FastGotos:
        return cls(np.zeros(0, dtype=np.int64), np.zeros((0, 3)), np.zeros((0, 3)))


def _spans(size: int, a: NDArray[np.int64], e: NDArray[np.int64]) -> NDArray[np.bool_]:
    """Mask of the bytes in the disjoint, sorted ranges [a, e) of a buffer of ``size`` bytes."""
    d = np.zeros(size + 1, dtype=np.int8)
    d[a] = 1
    d[e] = -1
    # int8 keeps the running sum (0 or 1) at one byte per byte of the file.
    return np.cumsum(d[:-1], dtype=np.int8).view(bool)


def _candidates(src: Source) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Lines starting "GOTO/" or "GOTO /", and where their values start."""
    buf, starts, ends = src.buf, src.starts, src.ends
    last = buf.size - 1

    def at(k: int) -> NDArray[np.uint8]:
        return buf[np.minimum(starts + k, last)]

    cand = ends - starts >= 6
    for k, ch in enumerate(b"GOTO"):
        cand &= at(k) == ch
    b4, b5 = at(4), at(5)
    slash = np.where(b4 == SLASH, 4, np.where(((b4 == SPACE) | (b4 == TAB)) & (b5 == SLASH), 5, 0))
    cand &= slash > 0
    lines = np.flatnonzero(cand)
    first = starts[lines] + slash[lines] + 1
    keep = ends[lines] > first
    return lines[keep], first[keep]


def _value_bytes(
    src: Source, first: NDArray[np.int64], lines: NDArray[np.int64]
) -> tuple[NDArray[np.uint8], NDArray[np.int64]]:
    """The value parts of ``lines``, each ended by LF, and the LF positions in them."""
    size = src.buf.size
    end = np.minimum(src.ends[lines] + 1, size)  # take the line's LF along as its terminator
    vb = src.buf[_spans(size, first, end)]
    if vb.size == 0 or vb[-1] != LF:
        vb = np.append(vb, np.uint8(LF))  # the last line had no newline
    return vb, np.flatnonzero(vb == LF)


def _bad_lines(vb: NDArray[np.uint8], lf: NDArray[np.int64]) -> NDArray[np.int64]:
    """Lines (indices into the span list) the bulk path must leave to the per-record reader.

    Bytes other than numbers, commas and blanks; empty values ("1,,2", "1, ,2", a
    trailing comma); numbers separated by blanks only ("1 2"); and records with
    other than 3 or 6 values. ``np.fromstring`` would read an empty value as -1 and
    "1 2" as two values, so these must be caught here.
    """
    bad = [np.flatnonzero(~_SPAN_OK[vb])]
    sep = _SEPARATOR[vb]
    bad.append(np.flatnonzero(sep[1:] & sep[:-1]) + 1)
    if sep[0]:
        bad.append(np.zeros(1, dtype=np.int64))
    blank = np.flatnonzero(_BLANK[vb])
    if blank.size:
        run_start = blank[np.concatenate([[True], np.diff(blank) > 1])]
        run_end = blank[np.concatenate([np.diff(blank) > 1, [True]])]
        left = np.where(run_start > 0, vb[np.maximum(run_start - 1, 0)], LF)
        right = vb[run_end + 1]  # vb ends with LF, which is not blank
        empty = _SEPARATOR[left] & _SEPARATOR[right]
        spaced = _NUMBER[left] & _NUMBER[right]
        bad.append(run_start[empty | spaced])
    pos = np.concatenate(bad)
    out = np.searchsorted(lf, pos, side="left")
    commas = np.flatnonzero(vb == COMMA)
    per_line = np.diff(np.concatenate([[0], np.searchsorted(commas, lf)])) + 1
    out = np.concatenate([out, np.flatnonzero((per_line != 3) & (per_line != 6))])
    return np.unique(out)


def _parse(vb: NDArray[np.uint8]) -> NDArray[np.float64] | None:
    """All numbers of comma-separated value bytes, or None if some text is not a number."""
    try:
        return np.fromstring(vb.tobytes(), dtype=np.float64, sep=",")
    except ValueError:
        return None


def _first_unparsable(vb: NDArray[np.uint8], lf: NDArray[np.int64]) -> int:
    """Index of the first line whose numbers np.fromstring cannot read (halving search)."""
    lo, hi = 0, lf.size  # the first failing line is in [lo, hi)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        a = int(lf[lo - 1]) + 1 if lo > 0 else 0
        if _parse(vb[a : int(lf[mid - 1]) + 1]) is None:
            hi = mid
        else:
            lo = mid
    return lo


def scan_gotos(src: Source) -> FastGotos:
    """The plain GOTO records of the file (see module docstring).

    A line the bulk path cannot take (unusual bytes, a malformed or
    out-of-range number, a wrong number of values) is left out, and so is every
    GOTO line after a malformed number: the per-record reader reads them and
    names the bad line in its error.
    """
    lines, first = _candidates(src)
    if lines.size == 0:
        return FastGotos.empty()
    vb, lf = _value_bytes(src, first, lines)
    bad = _bad_lines(vb, lf)
    if bad.size:
        keep = np.ones(lines.size, dtype=bool)
        keep[bad] = False
        lines, first = lines[keep], first[keep]
        if lines.size == 0:
            return FastGotos.empty()
        vb, lf = _value_bytes(src, first, lines)
    commas = np.flatnonzero(vb == COMMA)
    count = np.diff(np.concatenate([[0], np.searchsorted(commas, lf)])) + 1
    vb[lf] = COMMA
    vals = _parse(vb)
    if vals is None:
        k = _first_unparsable(vb, lf)
        lines, count = lines[:k], count[:k]
        vals = _parse(vb[: int(lf[k - 1]) + 1]) if k else np.zeros(0)
        assert vals is not None  # the lines before the first unparsable one parse
    offset = np.cumsum(count) - count
    finite = np.isfinite(vals)
    if not finite.all():
        k = int(np.searchsorted(offset, np.argmin(finite), side="right") - 1)
        lines, count, offset = lines[:k], count[:k], offset[:k]
    xyz = vals[offset[:, None] + np.arange(3)] if lines.size else np.zeros((0, 3))
    ijk = np.full((lines.size, 3), np.nan)
    six = np.flatnonzero(count == 6)
    if six.size:
        ijk[six] = vals[offset[six, None] + np.arange(3, 6)]
    return FastGotos(line=lines.astype(np.int64), xyz=xyz, ijk=ijk)
