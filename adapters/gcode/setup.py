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
from dataclasses import dataclass, field

from core.model.errors import InputError
from core.model.inputs import read_input
from core.model.setup import ControllerSetup

Vec = tuple[float, float, float]
ORIGIN: Vec = (0.0, 0.0, 0.0)


@dataclass
class MachineSetup:
    """What the machine file says about the controller's state before the program runs.

    Attributes
    ----------
    home, home2 : (3,) mm
        G28 and G30 positions in machine coordinates (LinuxCNC's default parameter file
        has both at machine zero).
    offsets : dict code -> (3,) mm
        Work offsets (G54 = 540 ... G59.3 = 593, Siemens G505-G599) in machine coordinates.
    tool_radius : dict tool -> mm
        Tool radii for cutter compensation (LinuxCNC tool table, machine TOML [tools]).
    tool_length : dict tool -> mm
        Tool lengths for G43 (added to Z).
    default_path_mode : str or None
        "exact_stop" or "continuous": what the controller does where the program sets no
        path mode (None: the dialect's default).
    tool_radius_override : float or None
        --tool-radius: the radius of every tool for cutter compensation.
    search : tuple of str
        Folders for subprogram files after the program's own.
    peck_clearance : float or None
        mm above the last peck that G73/G83 come back to (None: LinuxCNC's 0.254 mm).
    """

    home: Vec = ORIGIN
    home2: Vec = ORIGIN
    offsets: dict[int, Vec] = field(default_factory=dict)
    tool_radius: dict[int, float] = field(default_factory=dict)
    tool_length: dict[int, float] = field(default_factory=dict)
    default_path_mode: str | None = None
    tool_radius_override: float | None = None
    search: tuple[str, ...] = ()
    peck_clearance: float | None = None


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
