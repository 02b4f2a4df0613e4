"""The program the reference interpreter runs, and its geometry, computed here on its own.

A :class:`Program` is read from the columns of any parsed tool path (an object with the
attributes below, as ncperf's adapters produce): the moves as the program states them.
Everything derived -- lengths, tangents, curvature, each axis's share of the direction,
points along the moves -- is computed here, move by move, from those columns and the
definitions below, not taken from the object it came from.

Moves
-----
* kind 0 is a rapid, 1 a line, 2 a clockwise and 3 a counter-clockwise arc about ``normal``
  (the unit normal of the arc's plane: counter-clockwise is a positive rotation about it).
* An arc turns by ``sweep`` (rad, unsigned) about ``center`` (in the plane of its start);
  a helix also rises along the normal, evenly over the sweep: pitch c = rise / sweep (mm/rad).
  Its length is sweep sqrt(r^2 + c^2), its curvature r / (r^2 + c^2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Protocol

import numpy as np

from refvm import vec as V

RAPID, LINE, ARC_CW, ARC_CCW = 0, 1, 2, 3
#: ``path_mode`` of a move that ends in an exact stop.
EXACT_STOP = 1


class ToolPathColumns(Protocol):
    """What :meth:`Program.read` reads: the columns of a parsed program (n moves)."""

    kind: Any  # (n,) int
    start: Any  # (n, 3) mm
    end: Any  # (n, 3) mm
    center: Any  # (n, 3) mm, NaN for lines
    normal: Any  # (n, 3), NaN for lines
    sweep: Any  # (n,) rad, NaN for lines
    feed: Any  # (n,) mm/s, NaN for rapids
    line: Any  # (n,) 1-based source line
    path_mode: Any  # (n,) int, EXACT_STOP where the move ends at rest
    dwell: Any  # (n,) s
    tolerance: Any  # (n,) mm, NaN: the machine's
    op_offsets: Any  # (k + 1,) moves op_offsets[i]:op_offsets[i+1] form operation i


def _floats(a: Any) -> list[float]:
    return [float(x) for x in np.asarray(a, dtype=np.float64).tolist()]


def _ints(a: Any) -> list[int]:
    return [int(x) for x in np.asarray(a).tolist()]


def _rows(a: Any) -> list[V.Vec]:
    arr = np.asarray(a, dtype=np.float64)
    return [(float(x), float(y), float(z)) for x, y, z in arr.tolist()]


@dataclass(frozen=True, eq=False)
class Program:
    """Moves as lists (one entry per move), with the geometry derived here.

    Attributes (as read)
    --------------------
    kind, start, end, center, normal, sweep, feed (mm/s, NaN for rapids), line,
    path_mode, dwell (s), tolerance (mm, NaN: the machine's), operation (index of each
    move's operation), source.

    Attributes (derived)
    --------------------
    length : mm
    t_start, t_end : unit tangents at each move's ends
    k_start, k_end : curvature vectors (1/mm) at each move's ends (0 for lines)
    share : the largest share |t_k| of each axis in the unit tangent over the move
    radius, pitch : of arcs (NaN for lines)
    """

    kind: list[int]
    start: list[V.Vec]
    end: list[V.Vec]
    center: list[V.Vec]
    normal: list[V.Vec]
    sweep: list[float]
    feed: list[float]
    line: list[int]
    path_mode: list[int]
    dwell: list[float]
    tolerance: list[float]
    operation: list[int]
    source: str
    length: list[float]
    t_start: list[V.Vec]
    t_end: list[V.Vec]
    k_start: list[V.Vec]
    k_end: list[V.Vec]
    share: list[V.Vec]
    radius: list[float]
    pitch: list[float]

    @property
    def n(self) -> int:
        return len(self.kind)

    def is_feed(self, i: int) -> bool:
        return self.kind[i] != RAPID

    def is_arc(self, i: int) -> bool:
        return self.kind[i] in (ARC_CW, ARC_CCW)

    @classmethod
    def read(cls, toolpath: ToolPathColumns) -> Program:
        """The program of a parsed tool path (any object with the columns of the module
        docstring and ``op_offsets``)."""
        tp = toolpath
        kind = _ints(tp.kind)
        n = len(kind)
        offs = _ints(tp.op_offsets)
        operation = [0] * n
        for op in range(len(offs) - 1):
            for i in range(offs[op], offs[op + 1]):
                operation[i] = op
        cols: dict[str, Any] = {
            "kind": kind,
            "start": _rows(tp.start),
            "end": _rows(tp.end),
            "center": _rows(tp.center),
            "normal": _rows(tp.normal),
            "sweep": _floats(tp.sweep),
            "feed": _floats(tp.feed),
            "line": _ints(tp.line),
            "path_mode": _ints(tp.path_mode),
            "dwell": _floats(tp.dwell),
            "tolerance": _floats(tp.tolerance),
            "operation": operation,
            "source": str(getattr(tp, "source", "<program>")),
        }
        derived: dict[str, Any] = {
            k: [] for k in ("length", "t_start", "t_end", "k_start", "k_end", "share")
        }
        derived["radius"] = []
        derived["pitch"] = []
        for i in range(n):
            g = _geometry(
                kind[i],
                cols["start"][i],
                cols["end"][i],
                cols["center"][i],
                cols["normal"][i],
                cols["sweep"][i],
            )
            for key, value in g.items():
                derived[key].append(value)
        return cls(**cols, **derived)

    # ------------------------------------------------------------------ positions
    @cached_property
    def _arrays(self) -> dict[str, np.ndarray]:
        return {
            "kind": np.asarray(self.kind),
            "start": np.asarray(self.start, dtype=np.float64).reshape(-1, 3),
            "end": np.asarray(self.end, dtype=np.float64).reshape(-1, 3),
            "center": np.asarray(self.center, dtype=np.float64).reshape(-1, 3),
            "normal": np.asarray(self.normal, dtype=np.float64).reshape(-1, 3),
            "sweep": np.asarray(self.sweep, dtype=np.float64),
            "pitch": np.asarray(self.pitch, dtype=np.float64),
            "length": np.asarray(self.length, dtype=np.float64),
        }

    def points(self, k: np.ndarray, d: np.ndarray) -> np.ndarray:
        """(m, 3) points ``d`` mm into moves ``k`` (arrays of one length m), clipped to the
        moves: :meth:`point` for many samples at once."""
        a = self._arrays
        k = np.asarray(k, dtype=np.int64)
        L = a["length"][k]
        with np.errstate(divide="ignore", invalid="ignore"):
            frac = np.clip(np.where(L > 0, np.asarray(d, dtype=np.float64) / L, 0.0), 0.0, 1.0)
        s, e = a["start"][k], a["end"][k]
        out = s + (e - s) * frac[:, None]
        arc = (a["kind"][k] == ARC_CW) | (a["kind"][k] == ARC_CCW)
        if arc.any():
            ka = k[arc]
            n, c, sa = a["normal"][ka], a["center"][ka], s[arc]
            rel = sa - c
            along = np.sum(rel * n, axis=1)[:, None]
            r0 = rel - along * n
            turn = np.where(a["kind"][ka] == ARC_CCW, 1.0, -1.0)
            swept = frac[arc] * a["sweep"][ka]
            phi = (turn * swept)[:, None]
            rot = r0 * np.cos(phi) + np.cross(n, r0) * np.sin(phi)
            out[arc] = c + along * n + rot + (a["pitch"][ka] * swept)[:, None] * n
        return out

    def point(self, i: int, d: float) -> V.Vec:
        """The point ``d`` mm into move ``i`` (clipped to the move)."""
        L = self.length[i]
        frac = min(max(d / L, 0.0), 1.0) if L > 0 else 0.0
        s, e = self.start[i], self.end[i]
        if not self.is_arc(i):
            return V.add(s, V.mul(V.sub(e, s), frac))
        n, c = self.normal[i], self.center[i]
        r0 = _in_plane(V.sub(s, c), n)
        turn = 1.0 if self.kind[i] == ARC_CCW else -1.0
        phi = turn * frac * self.sweep[i]
        axis_point = V.add(c, V.mul(n, V.dot(V.sub(s, c), n)))  # centre in the start's plane
        rise = V.mul(n, self.pitch[i] * frac * self.sweep[i])
        return V.add(V.add(axis_point, V.rotate(r0, n, phi)), rise)


def _in_plane(r: V.Vec, n: V.Vec) -> V.Vec:
    """``r`` without its component along the unit normal ``n``."""
    return V.sub(r, V.mul(n, V.dot(r, n)))


def _geometry(kind: int, s: V.Vec, e: V.Vec, c: V.Vec, n: V.Vec, sweep: float) -> dict[str, Any]:
    if kind not in (ARC_CW, ARC_CCW):
        chord = V.sub(e, s)
        t = V.unit(chord)
        return {
            "length": V.length(chord),
            "t_start": t,
            "t_end": t,
            "k_start": V.ZERO,
            "k_end": V.ZERO,
            "share": (abs(t[0]), abs(t[1]), abs(t[2])),
            "radius": math.nan,
            "pitch": math.nan,
        }
    turn = 1.0 if kind == ARC_CCW else -1.0
    r0 = _in_plane(V.sub(s, c), n)
    r1 = _in_plane(V.sub(e, c), n)
    radius = V.length(r0)
    pitch = V.dot(V.sub(e, s), n) / sweep
    h = math.hypot(radius, pitch)

    def tangent(r: V.Vec) -> V.Vec:
        # d/dphi of (c + rot(turn phi) r0 + pitch phi n) = turn n x r + pitch n
        return V.unit(V.add(V.mul(V.cross(n, r), turn), V.mul(n, pitch)))

    def curvature(r: V.Vec) -> V.Vec:
        # a helix's principal normal points from the point to its axis
        return V.mul(V.unit(r), -radius / (radius * radius + pitch * pitch))

    # Axis shares: the in-plane direction turns from u0 towards u0 turned +90 deg (in the
    # direction of travel); its largest share per axis over the sweep, scaled by r / h,
    # plus the helix's constant rise share |n_k| c / h -- an upper bound, at most 1.
    u0 = V.unit(V.mul(V.cross(n, r0), turn))
    u90 = V.mul(V.cross(n, u0), turn)
    sx, sy, sz = (
        min(V.peak_of_turning(u0[k], u90[k], sweep) * radius / h + abs(n[k]) * abs(pitch) / h, 1.0)
        for k in range(3)
    )
    return {
        "length": sweep * h,
        "t_start": tangent(r0),
        "t_end": tangent(r1),
        "k_start": curvature(r0),
        "k_end": curvature(r1),
        "share": (sx, sy, sz),
        "radius": radius,
        "pitch": pitch,
    }
