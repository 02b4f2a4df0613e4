"""The machine the reference interpreter runs: per-axis limits and controller times, in mm
and s, read from any machine object with the attributes below (ncperf's ``Machine``)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from refvm import vec as V

Axes = tuple[float, float, float]


class MachineAttributes(Protocol):
    """What :meth:`MachineLimits.read` reads (ncperf's ``Machine`` has these, in mm and s)."""

    max_feed: Any  # (3,) mm/s
    max_acceleration: Any  # (3,) mm/s^2
    max_jerk: Any  # (3,) mm/s^3
    interpolation_time: float
    path_tolerance: float
    curvature_transition_time: float


def _axes(x: Any) -> Axes:
    a = [float(v) for v in np.asarray(x, dtype=np.float64).reshape(-1).tolist()]
    if len(a) != 3:
        raise ValueError(f"expected three axis values (X, Y, Z), got {len(a)}")
    return (a[0], a[1], a[2])


@dataclass(frozen=True)
class MachineLimits:
    """Attributes
    ----------
    name : str
    max_feed, max_acceleration, max_jerk : (X, Y, Z), mm/s, mm/s^2, mm/s^3 (jerk may be inf)
    interpolation_time : s, the block cycle time of model 3 (eq. 16)
    path_tolerance : mm, the TIT of model 1 (eq. 1)
    curvature_transition_time : s, the dt of model 2 (eq. 11-14)
    normal_acceleration_factor : share of each axis's acceleration usable as normal
        acceleration (1: the paper's models)
    """

    name: str
    max_feed: Axes
    max_acceleration: Axes
    max_jerk: Axes
    interpolation_time: float
    path_tolerance: float
    curvature_transition_time: float
    normal_acceleration_factor: float = 1.0

    @classmethod
    def read(cls, machine: MachineAttributes | MachineLimits) -> MachineLimits:
        if isinstance(machine, MachineLimits):
            return machine
        m = machine
        return cls(
            name=str(getattr(m, "name", "machine")),
            max_feed=_axes(m.max_feed),
            max_acceleration=_axes(m.max_acceleration),
            max_jerk=_axes(m.max_jerk),
            interpolation_time=float(m.interpolation_time),
            path_tolerance=float(m.path_tolerance),
            curvature_transition_time=float(m.curvature_transition_time),
            normal_acceleration_factor=float(getattr(m, "normal_acceleration_factor", 1.0)),
        )

    def replace(self, **changes: Any) -> MachineLimits:
        return dataclasses.replace(self, **changes)

    def scaled(self, accel: float = 1.0, jerk: float = 1.0, feed: float = 1.0) -> MachineLimits:
        """Every axis's limits multiplied (an infinite jerk stays infinite)."""
        ax, ay, az = self.max_acceleration
        jx, jy, jz = self.max_jerk
        fx, fy, fz = self.max_feed
        return self.replace(
            max_acceleration=(ax * accel, ay * accel, az * accel),
            max_jerk=(jx * jerk, jy * jerk, jz * jerk),
            max_feed=(fx * feed, fy * feed, fz * feed),
        )

    def per_share(self, limits: Axes, share: V.Vec) -> float:
        """min over the axes of limit_k / share_k (an axis with no share sets no limit)."""
        best = math.inf
        for lim, sh in zip(limits, share, strict=True):
            if sh > 0.0:
                best = min(best, lim / sh)
        return best

    def rapid_speed(self, direction: V.Vec) -> float:
        """A straight move along ``direction`` with every axis at most at its max feed."""
        return self.per_share(
            self.max_feed, (abs(direction[0]), abs(direction[1]), abs(direction[2]))
        )
