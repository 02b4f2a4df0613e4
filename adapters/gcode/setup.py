"""The machine file's controller setup as the G-code interpreter holds it, and LinuxCNC
tool tables.

A LinuxCNC tool table (``[EMCIO] TOOL_TABLE``) has one tool per line::

    T1 P1 D10.000 Z+50.000 ;10 mm end mill

``T`` tool number, ``P`` pocket, ``D`` diameter, ``X Y Z A B C U V W`` offsets (``Z`` is
the tool length G43 uses), ``I J Q`` lathe data, ``;`` a comment (LinuxCNC 2.9 "Tool
Table Format", docs/src/config/tooltable). Values are in the machine's units; ncperf
takes them as mm (the ``--machine`` file's units).
"""

from __future__ import annotations

import re

from adapters.gcode.control import MachineSetup
from core.model.errors import InputError
from core.model.inputs import read_input
from core.model.setup import ControllerSetup

_WORD = re.compile(r"([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")
_OFFSET = re.compile(r"G(\d+)(?:\.(\d))?(?:P(\d+))?")


def offset_code(name: str) -> int:
    """ "G54" -> 540, "G59.3" -> 593, "G505" -> 5050, "G54.1P7" -> 5407 (the codes the
    controller keeps offsets under)."""
    m = _OFFSET.fullmatch(name.upper())
    if m is None:
        raise ValueError(name)
    number, tenth, extra = int(m.group(1)), m.group(2), m.group(3)
    if extra is not None:
        return 5400 + int(extra)
    return number * 10 + (int(tenth) if tenth else 0)


def read_tool_table(path: str) -> dict[int, tuple[float | None, float | None]]:
    """tool -> (radius, length) from a LinuxCNC tool table; errors name file and line."""
    text = read_input(path, what="a tool table").decode("utf-8", "replace")
    tools: dict[int, tuple[float | None, float | None]] = {}
    for k, raw in enumerate(text.splitlines(), start=1):
        code = raw.split(";", 1)[0].strip()
        if not code:
            continue
        words = {}
        pos = 0
        for m in _WORD.finditer(code):
            if code[pos : m.start()].strip():
                break
            words[m.group(1).upper()] = float(m.group(2))
            pos = m.end()
        if code[pos:].strip() or "T" not in words:
            raise InputError(
                "not a tool table line (T<number> P<pocket> D<diameter> Z<length> ...)",
                source=path,
                line=k,
                text=raw,
            )
        radius = abs(words["D"]) / 2.0 if "D" in words else None
        tools[int(words["T"])] = (radius, words.get("Z"))
    return tools


def machine_setup(cs: ControllerSetup) -> MachineSetup:
    """The interpreter's setup from the machine file's."""
    radius: dict[int, float] = {}
    length: dict[int, float] = {}
    for t, tool in cs.tools.items():
        if tool.radius is not None:
            radius[t] = tool.radius
        if tool.length is not None:
            length[t] = tool.length
    if cs.tool_table is not None:
        for t, (r, z) in read_tool_table(cs.tool_table).items():
            if r is not None:
                radius[t] = r
            if z is not None:
                length[t] = z
    return MachineSetup(
        home=cs.home,
        home2=cs.home_g30,
        offsets={offset_code(k): v for k, v in cs.work_offsets.items()},
        tool_radius=radius,
        tool_length=length,
        default_path_mode=cs.default_path_mode,
        tool_radius_override=cs.tool_radius,
        search=tuple(cs.subroutine_path),
        peck_clearance=cs.peck_clearance,
    )
