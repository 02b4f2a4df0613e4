"""CL lines -> records: ``WORD/value,value,...`` statements, one Python object each.

This is the path for everything the bulk GOTO reader of
:mod:`adapters.cl_data.source` does not take: it joins ``$`` continuation
lines, strips ``$$`` comments, splits the major word from its comma-separated
values (blanks around ``/`` and ``,`` allowed) and names the line of anything
malformed. ``PARTNO``, ``PPRINT`` and ``INSERT`` carry text to the end of the
line, in which ``$`` and ``,`` are just characters.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from adapters.cl_data.source import Source
from adapters.cl_data.words import LITERAL

_LITERAL = re.compile(r"\s*(" + "|".join(sorted(LITERAL)) + r")\b\s*/?", re.IGNORECASE)
_WORD = re.compile(r"[A-Z][A-Z0-9_\-]*(?: [A-Z0-9_\-]+)*")
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_NUMBERS = re.compile(_NUMBER.pattern + r"(?:," + _NUMBER.pattern + r")*")
_NUMBER_START = frozenset("0123456789+-.")
_CONTROL = re.compile(r"[\x00-\x08\x0e-\x1f\x7f]")


@dataclass
class Record:
    """One CL statement.

    Attributes
    ----------
    line : int
        0-based line where it starts.
    last : int
        0-based line where it ends (after ``$`` continuations).
    word : str
        Major word, upper case, blanks collapsed ("TOOL PATH"); "$$" for a
        comment line; "" for a line of bare numbers (more points of a GOTO).
    args : list of str or None
        The comma-separated values, stripped; [] for "WORD/" with nothing
        after the slash, None for a word without a slash ("RAPID").
    text : str
        The statement's first line, for messages.
    literal : str or None
        Text after the word of PARTNO, PPRINT and INSERT.
    comment : str or None
        Text of a ``$$`` comment on the statement's lines.
    """

    line: int
    last: int
    word: str
    args: list[str] | None
    text: str
    literal: str | None = None
    comment: str | None = None


def _split_comment(text: str) -> tuple[str, str | None]:
    k = text.find("$$")
    if k < 0:
        return text, None
    return text[:k], text[k + 2 :].strip()


def _check_characters(src: Source, i: int, body: str) -> None:
    if not body.isascii():
        bad = next(ch for ch in body if ord(ch) > 127)
        raise src.error(i, f"non-ASCII character {bad!r} outside a comment")
    ctrl = _CONTROL.search(body)
    if ctrl:
        raise src.error(i, f"control character 0x{ord(ctrl.group()):02x}; not CL data", quote=False)


def statement(src: Source, i: int) -> Record | None:
    """The record starting at 0-based line ``i`` (None for a blank line)."""
    text = src.text(i)
    stripped = text.strip()
    if not stripped:
        return None
    m = _LITERAL.match(stripped)
    if m:
        return Record(i, i, m.group(1).upper(), None, stripped, literal=stripped[m.end() :])
    body, comment = _split_comment(stripped)
    last = i
    parts = [body]
    # "$" at the end of the statement continues it on the next line.
    while parts[-1].rstrip().endswith("$"):
        parts[-1] = parts[-1].rstrip()[:-1]
        last += 1
        if last >= src.n_lines:
            raise src.error(i, "continuation '$' at the end of the file")
        more, c2 = _split_comment(src.text(last).strip())
        comment = comment if c2 is None else (c2 if comment is None else f"{comment} {c2}")
        parts.append(more)
    body = "".join(parts).strip()
    _check_characters(src, i, body)
    if not body:
        return Record(i, last, "$$", None, stripped, comment=comment)
    if "=" in body:
        raise src.error(
            i,
            "'=' (a geometry definition or assignment) belongs to an APT part program; "
            "ncperf reads CL data (GOTO records)",
        )
    if body[0] in _NUMBER_START:
        return Record(i, last, "", _values(src, i, body), stripped, comment=comment)
    head, slash, rest = body.partition("/")
    word = " ".join(head.upper().split())
    if not _WORD.fullmatch(word):
        raise src.error(i, "malformed record: expected WORD or WORD/values")
    args = _values(src, i, rest) if slash else None
    return Record(i, last, word, args, stripped, comment=comment)


def _values(src: Source, i: int, rest: str) -> list[str]:
    if not rest.strip():
        return []
    out = [t.strip() for t in rest.split(",")]
    if "" in out:
        raise src.error(i, "empty value between commas")
    return out


def records(src: Source, lines: NDArray[np.int64]) -> Iterator[Record]:
    """The records starting on ``lines`` (sorted, 0-based), in order.

    A record continued with ``$`` takes the following lines along; those are
    not started again even if listed in ``lines``.
    """
    done = -1
    for i in lines.tolist():
        if i <= done:
            continue
        rec = statement(src, i)
        if rec is None:
            continue
        done = rec.last
        yield rec


def number(src: Source, rec: Record, token: str, what: str) -> float:
    """A finite number from one value of ``rec``; ``what`` names it in the error."""
    if not _NUMBER.fullmatch(token):
        raise src.error(rec.line, f"{what}: '{token}' is not a number")
    x = float(token)
    if not math.isfinite(x):
        raise src.error(rec.line, f"{what}: number {token} out of range")
    return x


def numbers(src: Source, rec: Record, tokens: list[str], what: str) -> list[float]:
    """Every value of ``tokens`` as a number (see :func:`number`)."""
    # One regex over the whole list first: the common, well-formed case costs no
    # Python step per value; the per-value path finds the bad one for the message.
    if _NUMBERS.fullmatch(",".join(tokens)):
        vals = list(map(float, tokens))
        if all(map(math.isfinite, vals)):
            return vals
    return [number(src, rec, t, what) for t in tokens]


def leading_numbers(src: Source, rec: Record, what: str) -> tuple[list[float], list[str]]:
    """The values of ``rec`` up to the first word, as numbers, and the words after them."""
    args = rec.args or []
    if _NUMBERS.fullmatch(",".join(args)):  # the usual case: numbers only
        vals = list(map(float, args))
        if all(map(math.isfinite, vals)):
            return vals, []
    k = 0
    while k < len(args) and args[k][:1] in _NUMBER_START:
        k += 1
    return numbers(src, rec, args[:k], what), [a.upper() for a in args[k:]]
