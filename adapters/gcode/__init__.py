"""A1 adapter: ISO 6983 G-code as CAM posts write it for Fanuc/ISO, Siemens 840D and LinuxCNC.

Two readers, one result:

* the **vectorised reader** takes programs that are lists of words -- the bulk of CAM
  output -- with numpy over the whole file (:mod:`adapters.gcode.lexer`, then the modal
  state and the moves in :mod:`adapters.gcode.interp`);
* the **full interpreter** (:mod:`adapters.gcode.run`) runs everything else block by block
  as the controller does: parameters and expressions, control flow, subprograms, canned
  cycles, work offsets and frames, home returns, cutter compensation, rotary axes.

A program goes to the full interpreter when the vectorised reader finds something it does
not read (it then stands aside; the full interpreter's verdict is the one reported).
Anything neither can interpret faithfully is an error naming the file and line; what they
assume is a notice on the tool path.
"""

from __future__ import annotations

import dataclasses
import os
import re
from pathlib import Path

from adapters.gcode import naivecam
from adapters.gcode.interp import NeedsInterpreter, detect_dialect, detect_dialect_text, interpret
from adapters.gcode.lexer import Source, tokenize
from adapters.gcode.setup import MachineSetup, machine_setup
from adapters.gcode.words import DIALECTS
from adapters.source import GCODE_EXTENSIONS
from core import ExtractOptions, InputError, ToolPath, UsageError, hookimpl
from core.model.errors import Notes
from core.model.inputs import read_input

#: Extensions CAM posts use for G-code (shared with the CL reader, which never claims them).
EXTENSIONS = GCODE_EXTENSIONS

_LOOKS_LIKE_GCODE = re.compile(rb"^[ \t]*(?:%|[Nn]\d+[ \t]*)?[GgMm]\d", re.MULTILINE)


def read_gcode(
    data: bytes,
    name: str,
    *,
    dialect: str | None = None,
    block_delete: bool = False,
    setup: MachineSetup | None = None,
    naive_cam: bool = True,
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
    setup : MachineSetup, optional
        What the machine file says the controller holds before the program runs (home
        positions, work offsets, tool radii); a program that uses any of it is run by the
        full interpreter.
    naive_cam : bool
        LinuxCNC dialect: run nearly collinear blocks under G64 P/Q as the one segment
        LinuxCNC's interpreter sends for them (:mod:`adapters.gcode.naivecam`); False reads
        every block as a move of its own, as LinuxCNC's stand-alone interpreter lists them.
    """
    if dialect is not None and dialect not in DIALECTS:
        raise UsageError(f"unknown G-code dialect '{dialect}'; dialects: {', '.join(DIALECTS)}")
    _refuse_heidenhain(data, name)
    src = Source(name, data)
    setup = setup or MachineSetup()
    lines: naivecam.LineInfo | None = None
    scanned = False
    try:
        words = tokenize(src)
        d = dialect or detect_dialect(name, words)
        if d == "linuxcnc" and naive_cam:
            # before the reader, which lets the words go as it goes
            lines, scanned = naivecam.scan(words, block_delete), True
        tp = interpret(
            src,
            words,
            d,
            block_delete,
            default_path_mode=setup.default_path_mode,
            offsets_known=bool(setup.offsets),
            lengths_known=bool(setup.tool_length),
        )
    except (InputError, NeedsInterpreter):
        # The full interpreter is imported when a program needs it (its modules are a third
        # of the adapter's start-up).
        from adapters.gcode.run import run_program

        d = dialect or detect_dialect_text(name, data)
        tp = run_program(name, data, d, block_delete, setup)
        if d == "linuxcnc" and naive_cam and not scanned and _G64_PQ.search(data):
            # words the plain tokenizer does not take ([expressions], #parameters)
            return _with_notice(tp, name, NAIVE_CAM_UNREAD, _G64_PQ.search(data))
    if lines is None:
        return tp
    notes = Notes(name)
    out = naivecam.join(tp, lines, notes)
    return dataclasses.replace(out, notices=out.notices + notes.notices())


#: A G64 block with a P or Q word (LinuxCNC: the naive-CAM detector may be on).
_G64_PQ = re.compile(rb"(?im)^[^(;\n]*G0*64(?![\d.])[^\n]*[PQ]")
NAIVE_CAM_UNREAD = (
    "G64 P/Q: LinuxCNC may run nearly collinear blocks as one segment (naive-CAM detector); "
    "not modelled for this program (its words need the full interpreter): every block is "
    "predicted as written"
)


def _with_notice(tp: ToolPath, name: str, message: str, m: re.Match[bytes] | None) -> ToolPath:
    notes = Notes(name)
    line = None
    if m is not None:
        line = m.string.count(b"\n", 0, m.start())
    notes.add(message, line)
    return dataclasses.replace(tp, notices=tp.notices + notes.notices())


# (horizontal blanks only, and one way to match each: with \s* around \d* a line of blanks
# after many empty lines backtracked for minutes -- 2000 newlines and 5000 blanks, 285 s)
_HEIDENHAIN = re.compile(rb"^[ \t]*(?:\d+[ \t]*)?BEGIN[ \t]+PGM\b", re.MULTILINE | re.IGNORECASE)


def _refuse_heidenhain(data: bytes, name: str) -> None:
    """A Heidenhain conversational (Klartext) program is not G-code: one line, exit 1."""
    m = _HEIDENHAIN.search(data[:65536])
    if m is None:
        return
    line = data.count(b"\n", 0, m.start()) + 1
    raise InputError(
        "Heidenhain conversational (Klartext) program: ncperf has no reader for it yet",
        source=name,
        line=line,
    )


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
    if suffix not in EXTENSIONS:
        head = read_input(path, limit=4096, what="a program")
        if not (_LOOKS_LIKE_GCODE.search(head) or _HEIDENHAIN.search(head)):
            return None
    data = read_input(path, what="a program")
    return read_gcode(
        data,
        str(path),
        dialect=options.dialect,
        block_delete=options.block_delete,
        setup=machine_setup(options.setup),
        naive_cam=options.naive_cam,
    )
