"""Text from inputs made safe to show: one function every sink uses (terminal, SVG, HTML, JSON).

File names, comments, block texts and machine names come from the user's files. Shown raw, an
ESC sequence recolours or clears the terminal, a CR overwrites the ``FILE:LINE`` prefix of an
error, a newline splits a one-line message, a control character makes an SVG ill-formed XML
and a byte that is not UTF-8 (a file name read with Python's ``surrogateescape``) makes the
UTF-8 writers raise. :func:`printable` replaces each such character by a visible escape
(``\\x1b``, ``\\u202e``), so nothing is lost and nothing acts.
"""

from __future__ import annotations

import re

#: C0 controls, DEL and C1 controls (ECMA-48: the C1 set includes CSI, 0x9b, which starts an
#: escape sequence on its own on some terminals).
_CONTROLS = [*range(0x00, 0x20), 0x7F, *range(0x80, 0xA0)]
#: Characters that reorder or hide text (Unicode bidi controls, line and paragraph separators,
#: zero-width no-break space): harmless to a parser, misleading on a screen ("Trojan source").
_FORMAT = [0x200E, 0x200F, *range(0x202A, 0x202F), *range(0x2066, 0x206A), 0x2028, 0x2029, 0xFEFF]


def _escape(c: int) -> str:
    return f"\\x{c:02x}" if c < 0x100 else f"\\u{c:04x}"


_ONE_LINE = {c: _escape(c) for c in [*_CONTROLS, *_FORMAT]}
_ONE_LINE[0x09] = " "  # a tab in a one-line message is a space
_LINES = dict(_ONE_LINE)
_LINES[0x0A] = "\n"  # multi-line text keeps its line ends and tabs
_LINES[0x09] = "\t"
_SURROGATE = re.compile("[\ud800-\udfff]")


def _surrogate(m: re.Match[str]) -> str:
    c = ord(m.group())
    # surrogateescape maps an undecodable byte b to U+DC00 + b.
    return f"\\x{c - 0xDC00:02x}" if 0xDC80 <= c <= 0xDCFF else _escape(c)


def printable(text: str, *, lines: bool = False) -> str:
    """``text`` with every control, formatting and undecodable character shown as an escape.

    ``lines=False`` (the default) gives one line: a newline becomes ``\\x0a``, a tab a space.
    ``lines=True`` keeps newlines and tabs, for the multi-line reports.
    """
    out = text.translate(_LINES if lines else _ONE_LINE)
    if _SURROGATE.search(out):
        out = _SURROGATE.sub(_surrogate, out)
    return out


def printable_tree(value: object) -> object:
    """A JSON-ready value with :func:`printable` applied to every string in it (keys too)."""
    if isinstance(value, str):
        return printable(value)
    if isinstance(value, dict):
        return {printable_tree(k): printable_tree(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [printable_tree(v) for v in value]
    return value
