"""What the controller holds before a program runs: the part of a machine file the readers
use (A1), not the models.

A program that calls ``G28`` goes to the home position the controller has stored, ``G55``
to the offset set at the machine, ``G41 D1`` offsets by the radius in the tool table. A
program alone does not say; the machine file does (``[controller]`` home positions and
default path mode, ``[offsets]``, ``[tools]`` or a LinuxCNC tool table). Every field has
the default LinuxCNC's own sample configuration has (home and offsets at machine zero, no
tools), so a program that uses none of it reads the same with or without a machine file.
"""

from __future__ import annotations

from dataclasses import dataclass, field

Vec3 = tuple[float, float, float]

#: Values of ``default_path_mode``.
PATH_MODES = ("exact_stop", "continuous")


@dataclass(frozen=True)
class Tool:
    """One tool of the table: radius for cutter compensation, length for G43 (mm; None:
    not given)."""

    radius: float | None = None
    length: float | None = None


@dataclass(frozen=True)
class ControllerSetup:
    """The controller's state before the program (mm, machine coordinates).

    Attributes
    ----------
    default_path_mode : {"exact_stop", "continuous"} or None
        Where the program sets no path mode: a Siemens 840D powers on in exact stop G60
        (MD20150 GCODE_RESET_VALUES), Fanuc and LinuxCNC in continuous path. None: the
        dialect's own default (continuous).
    home, home_g30 : (3,) float
        The G28 and G30 positions.
    work_offsets : dict name -> (3,) float
        Work offsets by G-code ("G54", "G55", ... "G59.3", Siemens "G505"...).
    tools : dict number -> Tool
    tool_table : str or None
        A LinuxCNC tool table file (``T1 P1 D10 Z50``...), read by the G-code reader; its
        entries come after ``tools``.
    subroutine_path : tuple of str
        Folders searched for subprogram files after the program's own folder.
    tool_radius : float or None
        ``--tool-radius``: the radius of every tool for cutter compensation.
    peck_clearance : float or None
        How far above the last peck G73 and G83 come back down (Fanuc parameters 5114 and
        5115, Haas setting 22; each machine its own); None: LinuxCNC's 0.254 mm.
    """

    default_path_mode: str | None = None
    home: Vec3 = (0.0, 0.0, 0.0)
    home_g30: Vec3 = (0.0, 0.0, 0.0)
    work_offsets: dict[str, Vec3] = field(default_factory=dict)
    tools: dict[int, Tool] = field(default_factory=dict)
    tool_table: str | None = None
    subroutine_path: tuple[str, ...] = ()
    tool_radius: float | None = None
    peck_clearance: float | None = None
