"""A text file's bytes and line offsets, shared by the file adapters (G-code, CL data): line
numbers and quoted lines for error messages, and the checks every text format makes first."""

from __future__ import annotations

from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from core.model.errors import InputError

#: A line longer than this is not a program (LinuxCNC stops at 256 characters, Fanuc at a
#: few hundred, CAM systems continue longer CL records with "$"); without the limit a 50 MB
#: line would be echoed and parsed.
MAX_LINE = 4096

LF, SPACE = 10, 32

#: Extensions CAM posts use for G-code.
GCODE_EXTENSIONS = frozenset(
    {
        ".nc",
        ".ngc",
        ".gcode",
        ".gc",
        ".g",
        ".tap",
        ".cnc",
        ".mpf",
        ".spf",
        ".ptp",
        ".eia",
        ".iso",
        ".min",
        ".din",
        ".fnc",
        ".nci",
    }
)


class Source:
    """The raw bytes and line offsets of a file, for the readers and for messages."""

    def __init__(self, name: str, data: bytes) -> None:
        self.name = name
        if b"\n" not in data and b"\r" in data:
            data = data.replace(b"\r", b"\n")  # old Mac line ends: CR only
        self.data = data
        buf = np.frombuffer(data, dtype=np.uint8)
        self.buf = buf
        nl = np.flatnonzero(buf == LF)
        # Line i spans [starts[i], ends[i]) without its newline. The ends are the newlines
        # and then the end of the file: one array, of which the newlines are a view (a
        # million lines: 8 MB, not 16); the starts are made when asked for (:attr:`starts`).
        ends = np.empty(nl.size + 1, dtype=np.int64)
        ends[:-1] = nl
        ends[-1] = buf.size
        del nl
        self.nl = ends[:-1]
        if self.nl.size and self.nl[-1] + 1 == buf.size:
            ends = ends[:-1]  # a final newline does not start another line
        self.ends = ends
        self.n_lines = int(ends.size)

    @cached_property
    def starts(self) -> NDArray[np.int64]:
        """(lines,) byte offset where each line starts: 0, then after each newline."""
        starts = np.empty(self.n_lines, dtype=np.int64)
        starts[:1] = 0
        np.add(self.nl[: self.n_lines - 1], 1, out=starts[1:])
        return starts

    def starts_of(self, lines: NDArray[np.int64]) -> NDArray[np.int64]:
        """:attr:`starts` of the 0-based ``lines`` only (no array over every line)."""
        lines = np.asarray(lines, dtype=np.int64)
        out = np.zeros(lines.size, dtype=np.int64)
        later = lines > 0
        out[later] = self.nl[lines[later] - 1] + 1
        return out

    def text(self, i: int) -> str:
        """Line i (0-based) as text, without its line end."""
        start = int(self.nl[i - 1]) + 1 if i > 0 else 0
        return self.data[start : self.ends[i]].decode("utf-8", "replace").rstrip("\r")

    def line_of(self, pos: int) -> int:
        """0-based line of byte offset ``pos``."""
        return int(np.searchsorted(self.nl, pos, side="left"))

    def error(self, i: int, message: str, *, quote: bool = True) -> InputError:
        """An InputError at 0-based line ``i``, quoting the line."""
        return InputError(
            message, source=self.name, line=i + 1, text=self.text(i) if quote else None
        )


def check_bytes(src: Source, content: str, verdict: str) -> None:
    """Empty, binary and absurdly long input: one-line errors naming the line. ``content``
    names what an empty file lacks ("G-code"), ``verdict`` what the file is not ("a G-code
    program")."""
    buf = src.buf
    # (a printable byte is most often in the first kB: the whole file only when not)
    if buf.size == 0 or not (np.any(buf[:1024] > SPACE) or np.any(buf > SPACE)):
        raise InputError(f"empty file: no {content} in it", source=src.name)
    if b"\x00" in src.data:
        raise src.error(
            src.line_of(src.data.index(b"\x00")),
            f"binary file (NUL byte); not {verdict}",
            quote=False,
        )
    # ends - starts, without the starts (0, then after each newline) kept for every line
    lengths = src.ends.copy()
    lengths[1:] -= src.nl[: src.n_lines - 1]
    lengths[1:] -= 1
    long_ = np.flatnonzero(lengths > MAX_LINE)
    if long_.size:
        i = int(long_[0])
        raise src.error(
            i,
            f"line is {int(lengths[i])} characters long (limit {MAX_LINE}); not {verdict}",
            quote=False,
        )
