"""A1 adapter: APT CL data / CLSF as NX, CATIA, SolidWorks CAM, Creo and ESPRIT write it.

Reads ``GOTO``, ``FROM``, ``GOHOME``, ``GODLTA``, one-shot ``RAPID``,
``FEDRAT`` (either order of value and unit), ``CIRCLE`` and ``MOVARC`` arcs
(direction conventions: :mod:`adapters.cl_data.interp`), ``UNITS``,
``MULTAX`` and 5-axis GOTO records (the tool axis is kept in the tool path),
tool loads, ``TOOL PATH ... END-OF-PATH`` operations, ``DELAY``, ``STOP``,
``$`` continuations and ``$$`` comments. Plain GOTO lines are read in bulk
with numpy (:mod:`adapters.cl_data.source`), everything else record by record
(:mod:`adapters.cl_data.records`, :mod:`adapters.cl_data.interp`). Words that
cannot move the tool are passed over with a notice; splines, canned cycles,
APT part-program statements and anything else that cannot be read faithfully
are an error naming the file and line.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from adapters.source import GCODE_EXTENSIONS, Source, check_bytes  # G-code: never claimed
from core import InputError, ToolPath, hookimpl
from core.model.inputs import read_input

#: Extensions CAM systems give CL data (NX .cls/.clsf, Creo .ncl, SolidWorks CAM .apt...).
EXTENSIONS = frozenset({".cls", ".clsf", ".apt", ".cl", ".aptsource", ".cldata", ".ncl"})

#: The first non-blank line of CL data in a file with another extension.
_LOOKS_LIKE_CL = re.compile(
    rb"\A\s*(?:\$\$|(?:TOOL[ \t]+PATH|PARTNO|GOTO|FROM|PPRINT|UNITS?|MULTAX|LOADTL|MACHIN"
    rb"|CUTTER|TLDATA|MSYS)[ \t]*/|PARTNO\b)",
    re.IGNORECASE,
)


def read_cl(data: bytes, name: str) -> ToolPath:
    """Parse APT CL data (bytes) into a ToolPath.

    Parameters
    ----------
    data : bytes
        The CL file.
    name : str
        File name, for messages and :attr:`ToolPath.source`.

    Returns
    -------
    ToolPath
        Positions in mm, feeds in mm/s, ``line`` the 1-based line of the GOTO
        ending each move, one operation per TOOL PATH (else per tool load),
        ``tool_axis`` when GOTO records carry i,j,k.
    """
    # The reader is imported when a CL file is read: a G-code run does not load it.
    from adapters.cl_data.interp import interpret
    from adapters.cl_data.source import scan_gotos

    src = Source(name, data)
    check_bytes(src, "CL data", "CL data")
    return interpret(src, scan_gotos(src))


def looks_like_cl(head: bytes) -> bool:
    """Whether the first bytes of a file are APT CL data (its first non-blank line)."""
    return b"\x00" not in head and bool(_LOOKS_LIKE_CL.match(head))


def _path_of(source: object) -> Path | None:
    if isinstance(source, str | os.PathLike):
        return Path(source)
    return None


@hookimpl
def ncperf_extract(source: object) -> ToolPath | None:
    """CL files by extension (or, for an unknown extension, by their first line); never G-code."""
    path = _path_of(source)
    if path is None:
        return None
    suffix = path.suffix.lower()
    if suffix in GCODE_EXTENSIONS:
        return None
    try:
        if suffix not in EXTENSIONS:
            if not looks_like_cl(read_input(path, limit=4096, what="CL data")):
                return None
        data = read_input(path, what="CL data")
    except InputError:
        if suffix in EXTENSIONS:
            raise
        return None  # not ours to judge: another adapter, or "no adapter reads it"
    return read_cl(data, str(path))


__all__ = ["EXTENSIONS", "looks_like_cl", "ncperf_extract", "read_cl"]
