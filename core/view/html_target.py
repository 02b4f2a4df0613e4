"""The target of the interactive HTML display (``--html``): a file, and what the page shows
beyond the annotations. Kept apart from :mod:`core.view.targets` (the file targets of every
display), which it builds on."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from core.view.targets import file_target


@dataclass(frozen=True, eq=False)
class HtmlTarget:
    """An interactive HTML file (``--html``): the feed profile for the speed plot, the limits
    for the hover text, the program text.

    Attributes
    ----------
    path : str
        Output file (``.html`` or ``.htm``); kept as ``str``.
    panels : tuple of (label, Analysis, program or None)
        One per program, in display order (``compare``: ranked, drawn side by side at one
        scale). ``program`` is the main program's file, whose lines the hover shows; None:
        no text. ``diagnose`` gives one panel ``(label, None, program)`` and ``diagnosis``.
    table : tuple of tuple of str
        ``compare``'s ranked table: the header row, then one row per program.
    diagnosis : Diagnosis or None
        ``diagnose``: the path is coloured by the measured-minus-predicted gap by default and
        the speed plot shows the measured feed too.
    view : {"xy", "xz", "yz", "iso"}
        The view the page opens in (the page switches between all four and rotates).
    colour : {"speed", "paper"}
        The colouring the page opens with: the profile's mean speed over F, or the paper's
        reduction classes with the junctions marked (Fig. 11).
    """

    path: str
    panels: tuple = ()
    table: tuple = ()
    diagnosis: Any = None
    view: str = "xy"
    colour: str = "speed"

    def __post_init__(self) -> None:
        file_target(self)
        if self.colour not in ("speed", "paper"):
            raise ValueError(f"colour must be speed or paper, got {self.colour!r}")
