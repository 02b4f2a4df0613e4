"""A1 adapter: ISO 6983 G-code as CAM posts write it for Fanuc/ISO, Siemens 840D and LinuxCNC.

Reads the whole file with numpy (:mod:`adapters.gcode.lexer`), then the modal
state and the moves (:mod:`adapters.gcode.interp`). Anything it cannot
interpret faithfully -- macros, subprograms, cutter compensation, splines,
canned cycles, inverse-time feed -- is an error naming the file and line;
what it assumes is a notice on the tool path.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from adapters.gcode.interp import interpret
from adapters.gcode.lexer import Source, tokenize
from adapters.gcode.words import DIALECTS
from adapters.source import GCODE_EXTENSIONS
from core import ExtractOptions, InputError, ToolPath, UsageError, hookimpl

#: Extensions CAM posts use for G-code (shared with the CL reader, which never claims them).
EXTENSIONS = GCODE_EXTENSIONS

_LOOKS_LIKE_GCODE = re.compile(rb"^[ \t]*(?:%|[Nn]\d+[ \t]*)?[GgMm]\d", re.MULTILINE)


def read_gcode(
    data: bytes, name: str, *, dialect: str | None = None, block_delete: bool = False
) -> ToolPath:
    """Parse G-code text (bytes) into a ToolPath.

    Parameters
    ----------
    data : bytes
        The program.
    name : str
        File name for messages (and dialect detection by extension).
    dialect : {"fanuc", "siemens", "linuxcnc"} or None
        None: ``.ngc`` is LinuxCNC, ``.mpf``/``.spf`` Siemens, else from the words used
        (Siemens keywords, LinuxCNC ``G64 P``), else Fanuc/ISO.
    block_delete : bool
        Skip blocks starting with "/" (the block-delete switch on).
    """
    if dialect is not None and dialect not in DIALECTS:
        raise UsageError(f"unknown G-code dialect '{dialect}'; dialects: {', '.join(DIALECTS)}")
    src = Source(name, data)
    words = tokenize(src)
    return interpret(src, words, dialect, block_delete)


def _path_of(source: object) -> Path | None:
    if isinstance(source, str | os.PathLike):
        return Path(source)
    return None


@hookimpl
def ncperf_extract(source: object, options: ExtractOptions) -> ToolPath | None:
    """G-code files by extension (or, for other extensions, by their first lines)."""
    path = _path_of(source)
    if path is None:
        return None
    suffix = path.suffix.lower()
    try:
        if suffix not in EXTENSIONS:
            with open(path, "rb") as fh:
                head = fh.read(4096)
            if not _LOOKS_LIKE_GCODE.search(head):
                return None
        data = path.read_bytes()
    except IsADirectoryError:
        raise InputError("is a folder, not a program", source=str(path)) from None
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror}", source=str(path)) from None
    return read_gcode(data, str(path), dialect=options.dialect, block_delete=options.block_delete)
