"""What a display draws into: a file, several programs side by side (a diagnosis:
:class:`core.diagnosis.diagnose.DiagnosisTarget`).

A target names the output and the projection; its extension (or host) picks the display
(the A3 hook stops at the first display that handles it).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

VIEWS = ("xy", "xz", "yz", "iso")
#: What blocks are coloured by: the feed profile's mean speed over the block against F
#: (where the time goes; the default), or the block's own cruise feed (the paper's Fig. 11).
COLOURINGS = ("speed", "paper")


def file_target(target: Any) -> None:
    """Check a drawing target's view and keep its path as ``str`` (the targets are frozen)."""
    object.__setattr__(target, "path", os.fspath(target.path))
    if target.view not in VIEWS:
        raise ValueError(f"view must be one of {VIEWS}, got {target.view!r}")
    colour = getattr(target, "colour", "speed")
    if colour not in COLOURINGS:
        raise ValueError(f"colour must be one of {COLOURINGS}, got {colour!r}")


@dataclass(frozen=True)
class FileTarget:
    """A file to draw into, with the projection to use.

    Attributes
    ----------
    path : str or os.PathLike
        Output file; its extension picks the display (``.svg`` ...). Kept as ``str``.
    view : {"xy", "xz", "yz", "iso"}
        Top view (xy, default), front (xz), side (yz) or isometric.
    colour : {"speed", "paper"}
        What blocks are coloured by (:data:`COLOURINGS`).
    """

    path: str | os.PathLike[str]
    view: str = "xy"
    colour: str = "speed"

    def __post_init__(self) -> None:
        file_target(self)


@dataclass(frozen=True, eq=False)
class ComparisonTarget:
    """A file to draw several programs into, side by side (``ncperf compare``).

    Attributes
    ----------
    path : str
        Output file; its extension picks the display.
    panels : tuple of (label, ToolPath, Annotations)
        The programs, in drawing order.
    view : {"xy", "xz", "yz", "iso"}
    colour : {"speed", "paper"}
    """

    path: str
    panels: tuple
    view: str = "xy"
    colour: str = "speed"

    def __post_init__(self) -> None:
        file_target(self)
