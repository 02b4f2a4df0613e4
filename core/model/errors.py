"""Errors and notices.

Every error a user can cause derives from :class:`NcperfError`. It keeps its
context (source, line, block text) as attributes and formats it in ``str()`` as
``source:line: message: text`` so the CLI can print it on one line.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass

from core.model.text import printable

#: Longest block text quoted in a message; a 50 MB line must not end up on the terminal.
MAX_QUOTED = 60


def quote_block(text: str | None) -> str | None:
    """Shorten a block for an error message (one line, at most MAX_QUOTED characters)."""
    if text is None:
        return None
    text = " ".join(text.split())
    if len(text) > MAX_QUOTED:
        text = text[: MAX_QUOTED - 3] + "..."
    return text


class NcperfError(Exception):
    """Base of every error caused by the user's input.

    Parameters
    ----------
    message : str
        What is wrong, in the user's terms.
    source : str, optional
        File name (or host object name) the error is in.
    line : int, optional
        1-based line number in ``source``.
    text : str, optional
        The offending block, quoted shortened.
    """

    def __init__(
        self,
        message: str,
        *,
        source: str | None = None,
        line: int | None = None,
        text: str | None = None,
    ) -> None:
        super().__init__(message)
        self.message = message
        self.source = source
        self.line = line
        self.text = quote_block(text)

    def __str__(self) -> str:
        where = ""
        if self.source is not None:
            where = f"{self.source}:"
            if self.line is not None:
                where += f"{self.line}:"
            where += " "
        elif self.line is not None:
            where = f"line {self.line}: "
        msg = f"{where}{self.message}"
        if self.text:
            msg += f": {self.text}"
        return printable(msg)  # one line, nothing from the input acts on a terminal


class InputError(NcperfError):
    """A tool path source cannot be read faithfully."""


class MachineError(NcperfError):
    """A machine description is missing a key, misspells one or holds an impossible value."""


class UsageError(NcperfError):
    """The caller asked for something that cannot be done (unknown preset, no adapter...)."""


@dataclass(frozen=True)
class Notice:
    """A warning about the input that does not stop the analysis.

    Attributes
    ----------
    source : str
        File name.
    line : int or None
        1-based line of the first occurrence.
    message : str
        What was assumed or passed over.
    count : int
        How many lines the same notice applies to.
    """

    source: str
    line: int | None
    message: str
    count: int = 1

    def __str__(self) -> str:
        where = f"{self.source}:{self.line}:" if self.line is not None else f"{self.source}:"
        more = f" ({self.count} lines)" if self.count > 1 else ""
        return printable(f"{where} warning: {self.message}{more}")


class Notes:
    """Collects warnings for one source: one :class:`Notice` per message, with the first
    line it happened on and a count."""

    def __init__(self, source: str) -> None:
        self.source = source
        self._first: dict[str, int | None] = {}
        self._count: dict[str, int] = defaultdict(int)

    def add(self, message: str, line: int | None = None, count: int = 1) -> None:
        """``line`` is 0-based (or None for the whole file)."""
        if message not in self._first:
            self._first[message] = None if line is None else line + 1
        self._count[message] += count

    def merge(self, other: Notes, offset: int = 0) -> None:
        """Add another collection's notes, their lines moved down by ``offset``."""
        for message, line in other._first.items():
            self.add(message, None if line is None else line - 1 + offset, other._count[message])

    def notices(self) -> tuple[Notice, ...]:
        return tuple(
            Notice(self.source, ln, msg, self._count[msg]) for msg, ln in self._first.items()
        )
