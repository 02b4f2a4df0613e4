"""Runs of plain lines inside a program the full interpreter runs.

Most of a program that needs the full interpreter -- a macro at the top, a home return at
the end, a few drilling cycles -- is still CAM output: lines of G0/G1/G2/G3 words. The
full interpreter hands long runs of such lines to the vectorised reader
(:class:`adapters.gcode.interp.Interpreter`) with the modal state it has reached and
takes the state at their end back, so such programs read at nearly the vectorised
reader's speed. A line is *plain* when it holds only the words and codes whose meaning
does not depend on anything the vectorised reader does not track (below); a run is taken
only when the controller is in a state the vectorised reader models (no cutter
compensation, no canned cycle, no rotation or scaling, feed per minute...). Anything the
vectorised reader refuses in a run sends that run back to block-by-block execution,
which gives the verdict.
"""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from adapters.gcode.interp import Interpreter, State
from adapters.gcode.lexer import Words, tokenize
from adapters.source import Source

#: Shortest run worth handing over (below it, block by block is as fast).
MIN_RUN = 32

_NUM = rb"[ \t]*[-+]?(?:\d+\.?\d*|\.\d+)"
#: G-codes a plain line may hold: motion, plane, units, G40 (with compensation off),
#: exact-stop / continuous modes without arguments, distance modes, feed per minute.
_G = (
    rb"G[ \t]*0*(?:[0-3]|1[789]|2[01]|40|61|64|9[014])(?:\.0*)?(?![\d.])"
    rb"|G[ \t]*0*(?:61|9[01])\.1(?![\d])"
)
#: M-codes: spindle and coolant only (no stops, tool changes, ends or calls).
_M = rb"M[ \t]*0*[3-57-9](?:\.0*)?(?![\d.])"
_WORD = rb"(?:" + _G + rb"|" + _M + rb"|[XYZIJKRFSN]" + _NUM + rb")"
_PLAIN_LINE = re.compile(
    rb"(?im)^[ \t]*(?:(?:" + _WORD + rb"|\([^()\r\n]*\))[ \t]*)*\r?$",
)


def plain_runs(src: Source) -> NDArray[np.int64]:
    """For each line, the end (exclusive) of the run of plain lines that starts there
    (the line itself when it is not plain)."""
    n = src.n_lines
    plain = np.zeros(n + 1, dtype=bool)
    starts = np.fromiter((m.start() for m in _PLAIN_LINE.finditer(src.data)), dtype=np.int64)
    if starts.size:
        lines = np.searchsorted(src.starts, starts, side="left")
        ok = (lines < n) & (src.starts[np.minimum(lines, n - 1)] == starts)
        plain[lines[ok]] = True
    # next non-plain line at or after i
    idx = np.where(plain, n, np.arange(n + 1))
    end = np.minimum.accumulate(idx[::-1])[::-1]
    return end[:n].astype(np.int64)


class PlainRuns:
    """The runs of one file, and the words of the runs already read (a loop body is
    tokenised once)."""

    def __init__(self, src: Source, dialect: str) -> None:
        self.src = src
        self.dialect = dialect
        self.end = plain_runs(src)
        self.refused: set[int] = set()
        self._words: dict[tuple[int, int], Words] = {}

    def run_at(self, i: int) -> int:
        """End of the run starting at line i worth handing over, or i."""
        j = int(self.end[i])
        if j - i < MIN_RUN or i in self.refused:
            return i
        return j

    def read(self, i: int, j: int, state: State) -> tuple[dict | None, State, Interpreter]:
        """Lines [i, j) from ``state``: the moves' columns (lines 1-based, in the file) and
        the state at the end. Raises InputError when the vectorised reader refuses them."""
        key = (i, j)
        words = self._words.get(key)
        src = Source(self.src.name, self.src.data[self.src.starts[i] : self.src.ends[j - 1]])
        if words is None:
            words = tokenize(src)
            self._words[key] = words
        interp = Interpreter(src, replace(words), self.dialect, False, initial=state)
        cols, final = interp.chunk()
        if cols is not None:
            cols["line"] = cols["line"] + i
        return cols, final, interp
