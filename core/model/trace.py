"""Measured traces: what a machine recorded while running a program.

A :class:`Trace` holds time and any of position, path feed and program line. Readers are
plugins (``ncperf_read_trace``); the core aligns a trace with a tool path
(:mod:`core.diagnosis.align`) and compares it with the prediction (:mod:`core.diagnosis.diagnose`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from core.model.errors import Notice


@dataclass(frozen=True)
class TraceOptions:
    """What the user says about a trace; readers use what applies to them.

    Attributes
    ----------
    units : {"mm", "inch"} or None
        Length unit of positions and feeds (None: the reader's default, mm).
    kind : {"setpoint", "actual"} or None
        Whether positions are the controller's setpoint or measured actual positions
        (None: the reader's default).
    """

    units: str | None = None
    kind: str | None = None


@dataclass(frozen=True, eq=False)
class Trace:
    """A measured trace, in mm and s.

    Attributes
    ----------
    t : (m,) float, s
        Sample times, strictly increasing.
    pos : (m, 3) float, mm, or None
        Positions, when recorded.
    v : (m,) float, mm/s, or None
        Path feed, when recorded.
    line : (m,) int, or None
        1-based program line (block number) being run; 0 where unknown.
    source : str
        File (or host) it came from.
    kind : {"setpoint", "actual"}
        What the positions are.
    units : str
        Length unit of the file ("mm" or "inch"; the arrays are always mm).
    notices : tuple of Notice
        What the reader assumed or passed over.
    """

    t: NDArray[np.float64]
    pos: NDArray[np.float64] | None
    v: NDArray[np.float64] | None
    line: NDArray[np.int64] | None
    source: str
    kind: str = "setpoint"
    units: str = "mm"
    notices: tuple[Notice, ...] = ()

    def __post_init__(self) -> None:
        t = np.ascontiguousarray(self.t, dtype=np.float64)
        if t.ndim != 1:
            raise ValueError(f"t must have shape (m,), got {t.shape}")
        m = t.size
        object.__setattr__(self, "t", t)
        if self.pos is not None:
            pos = np.ascontiguousarray(self.pos, dtype=np.float64)
            if pos.shape != (m, 3):
                raise ValueError(f"pos must have shape ({m}, 3), got {pos.shape}")
            object.__setattr__(self, "pos", pos)
        if self.v is not None:
            v = np.ascontiguousarray(self.v, dtype=np.float64)
            if v.shape != (m,):
                raise ValueError(f"v must have shape ({m},), got {v.shape}")
            object.__setattr__(self, "v", v)
        if self.line is not None:
            line = np.ascontiguousarray(self.line, dtype=np.int64)
            if line.shape != (m,):
                raise ValueError(f"line must have shape ({m},), got {line.shape}")
            object.__setattr__(self, "line", line)
        if self.kind not in ("setpoint", "actual"):
            raise ValueError(f"kind must be 'setpoint' or 'actual', got {self.kind!r}")
        if self.pos is None and self.v is None:
            raise ValueError("a trace needs positions or a feed")

    def __len__(self) -> int:
        return int(self.t.size)

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0]) if self.t.size else 0.0

    @property
    def period(self) -> float:
        """Median time between samples (s)."""
        return float(np.median(np.diff(self.t))) if self.t.size > 1 else 0.0
