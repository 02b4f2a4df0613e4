"""The columnar tool path: a few numpy arrays over moves.

There is no move object. A program of a million moves is a handful of
contiguous arrays; derived quantities (length, tangents, curvature) are
computed once, vectorised, on first use. A column that holds one value over the
whole program (the arc columns of a program of lines, dwell, tolerance ...) is
kept as a read-only broadcast of that value (:data:`COMPACT_COLUMNS`): same
values, shape and dtype, no memory per move; columns are read, never written.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from enum import IntEnum
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from core.model import geometry as g
from core.model.arrays import unique
from core.model.errors import Notice
from core.model.pieces import halves, pieces, piecewise
from core.model.sampling import PathSamples
from core.model.setup import ControllerSetup
from core.model.tolerances import TOL


class MoveKind(IntEnum):
    """What a move is; stored as int8 in :attr:`ToolPath.kind`."""

    RAPID = 0
    LINE = 1
    ARC_CW = 2
    ARC_CCW = 3

    @property
    def label(self) -> str:
        return ("rapid", "line", "arc_cw", "arc_ccw")[self]


class PathMode(IntEnum):
    """How a move ends; stored as int8 in :attr:`ToolPath.path_mode`."""

    #: Continuous path (G64 and Siemens G641..G645): the controller blends into the next move.
    CONTINUOUS = 0
    #: Exact stop (G61, G60, G9, or a program stop M0/M1): the move ends at rest.
    EXACT_STOP = 1


KIND_LABELS = ("rapid", "line", "arc_cw", "arc_ccw")


@dataclass(frozen=True)
class ExtractOptions:
    """What the user tells A1 about a source; adapters read the fields that apply.

    Attributes
    ----------
    dialect : str or None
        Controller dialect of the source (G-code: "fanuc", "siemens",
        "linuxcnc"); None lets the adapter decide from the file.
    block_delete : bool
        The block-delete switch: True skips blocks starting with "/".
    setup : ControllerSetup
        What the controller holds before the program (home, work offsets, tools, default
        path mode; from the machine file).
    naive_cam : bool
        LinuxCNC programs: run nearly collinear blocks under G64 P/Q as the one segment
        LinuxCNC's interpreter makes of them (its naive-CAM detector); False: every block as
        written.
    """

    dialect: str | None = None
    block_delete: bool = False
    setup: ControllerSetup = field(default_factory=ControllerSetup)
    naive_cam: bool = True


def _uniform(x: ArrayLike, dtype: type) -> NDArray | None:
    """``x`` itself when it is already a compact column (:func:`_compact`) of ``dtype``."""
    if isinstance(x, np.ndarray) and x.ndim and x.strides[0] == 0 and x.dtype == dtype:
        return x
    return None


def _column(x: ArrayLike, n: int, name: str, dtype: type) -> NDArray:
    a = _uniform(x, dtype)
    if a is None:
        a = np.ascontiguousarray(x, dtype=dtype)
    if a.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got {a.shape}")
    return a


def _points(x: ArrayLike, n: int, name: str) -> NDArray[np.float64]:
    a = _uniform(x, np.float64)
    if a is None:
        a = np.ascontiguousarray(x, dtype=np.float64)
    if a.shape != (n, 3):
        raise ValueError(f"{name} must have shape ({n}, 3), got {a.shape}")
    return a


#: Columns this long or longer whose every row is the same are kept as one row (below).
COMPACT_MIN = 4096
#: The columns that are often one value over a whole program: arc columns of a program of
#: lines (NaN), dwell, tolerance, block numbers, tool, path mode.
COMPACT_COLUMNS = ("center", "normal", "sweep", "block", "tool", "path_mode", "dwell", "tolerance")


def _compact(a: NDArray) -> NDArray:
    """``a``, or when every row equals the first (NaN equal to NaN) a read-only broadcast of
    a copy of that row: the same values and shape at no memory per move (a million-line
    raster has no arcs: 56 MB of NaN arc columns otherwise)."""
    if a.shape[0] < COMPACT_MIN or a.strides[0] == 0:
        return a
    first = a[0]
    # A column that varies shows it on a sparse sample of its rows, most often: the whole
    # column is compared only when the sample is one value (1M moves: 30 ms less).
    for rows in (a[:: COMPACT_MIN // 4], a):
        same = rows == first
        if a.dtype.kind == "f":
            same |= np.isnan(rows) & np.isnan(first)
        if not same.all():
            return a
    return np.broadcast_to(np.array(first, dtype=a.dtype), a.shape)


@dataclass(frozen=True, eq=False)
class RotaryMoves:
    """Moves of the rotary axes alone (A, B, C turn, X, Y, Z stand still): no length on
    the tool path, so not moves of it; the machine turns between two moves, from rest to
    rest.

    Attributes
    ----------
    after : (m,) int64
        The tool path move they follow (-1: before the first).
    travel : (m, 3) float, deg
        Signed rotation of A, B and C.
    feed : (m,) float, deg/s
        Programmed rate along the rotation (all axes together); NaN for rapids.
    line : (m,) int64
        1-based source line.
    """

    after: NDArray[np.int64]
    travel: NDArray[np.float64]
    feed: NDArray[np.float64]
    line: NDArray[np.int64]

    def __post_init__(self) -> None:
        after = np.ascontiguousarray(self.after, dtype=np.int64)
        m = after.shape[0]
        object.__setattr__(self, "after", after)
        object.__setattr__(self, "travel", _points(self.travel, m, "travel"))
        object.__setattr__(self, "feed", _column(self.feed, m, "feed", np.float64))
        object.__setattr__(self, "line", _column(self.line, m, "line", np.int64))

    def __len__(self) -> int:
        return int(self.after.shape[0])


@dataclass(frozen=True, eq=False)
class ToolPath:
    """A tool path as columns over its ``n`` moves.

    Attributes
    ----------
    kind : (n,) int8
        :class:`MoveKind` of each move.
    start, end : (n, 3) float, mm
        End points of each move.
    center : (n, 3) float, mm
        Arc centre, in the plane through the arc's start point; NaN for lines.
    normal : (n, 3) float
        Unit normal of the arc's plane (G17 +Z, G18 +Y, G19 +X); NaN for lines.
        Counter-clockwise (G3) is a positive rotation about it.
    sweep : (n,) float, rad
        Unsigned sweep angle of arcs (full circles 2 pi, multi-turn helices
        more); NaN for lines.
    feed : (n,) float, mm/s
        Programmed feed; NaN for rapids.
    line : (n,) int64
        1-based source line of the block.
    block : (n,) int64
        Block number (N word), -1 where none.
    tool : (n,) int32
        Tool number, -1 where unknown.
    path_mode : (n,) int8
        :class:`PathMode` at the end of each move.
    dwell : (n,) float, s
        Dwell (G4) after the move.
    tolerance : (n,) float, mm
        Path tolerance the program sets for the move (LinuxCNC ``G64 P``);
        NaN where the machine's own TIT applies.
    op_offsets : (k + 1,) int64
        Moves ``op_offsets[i]:op_offsets[i + 1]`` form operation ``i``.
    op_names : tuple of str
        One name per operation.
    source : str
        Where the path came from (file name or host document).
    notices : tuple of Notice
        What the adapter assumed or passed over.
    tool_axis : (n, 3) float or None
        Tool axis of 5-axis sources; None for 3-axis paths.
    units : str
        Units the source was written in ("mm" or "inch"); the arrays are always mm.
    origin : (n,) int32 or None
        Where a move's block was run from: an index into ``origins``, -1 for the main
        program's own blocks; None when every block is the main program's. ``line`` is the
        line in the file the origin names.
    origins : tuple of str
        The call chains, e.g. "part.ngc:12 o<pocket> call > pocket.ngc".
    origin_files : tuple of str
        Per origin, the file its lines are in ("" for the main program's file).
    rotary : (n, 3) float, deg, or None
        Signed rotation of the rotary axes A, B, C during each move (they turn with the
        tool along X, Y, Z: F is the feed along the path); None without rotary axes.
    rotary_only : RotaryMoves or None
        Moves of the rotary axes alone, between the moves of the path.
    """

    kind: NDArray[np.int8]
    start: NDArray[np.float64]
    end: NDArray[np.float64]
    center: NDArray[np.float64]
    normal: NDArray[np.float64]
    sweep: NDArray[np.float64]
    feed: NDArray[np.float64]
    line: NDArray[np.int64]
    block: NDArray[np.int64]
    tool: NDArray[np.int32]
    path_mode: NDArray[np.int8]
    dwell: NDArray[np.float64]
    tolerance: NDArray[np.float64]
    op_offsets: NDArray[np.int64]
    op_names: tuple[str, ...] = ()
    source: str = "<memory>"
    notices: tuple[Notice, ...] = ()
    tool_axis: NDArray[np.float64] | None = None
    units: str = "mm"
    origin: NDArray[np.int32] | None = None
    origins: tuple[str, ...] = ()
    origin_files: tuple[str, ...] = ()
    rotary: NDArray[np.float64] | None = None
    rotary_only: RotaryMoves | None = None

    def __post_init__(self) -> None:
        kind = np.ascontiguousarray(self.kind, dtype=np.int8)
        if kind.ndim != 1:
            raise ValueError(f"kind must have shape (n,), got {kind.shape}")
        n = kind.shape[0]
        set_ = object.__setattr__
        set_(self, "kind", kind)
        for name in ("start", "end", "center", "normal"):
            set_(self, name, _points(getattr(self, name), n, name))
        for name, dtype in (
            ("sweep", np.float64),
            ("feed", np.float64),
            ("line", np.int64),
            ("block", np.int64),
            ("tool", np.int32),
            ("path_mode", np.int8),
            ("dwell", np.float64),
            ("tolerance", np.float64),
        ):
            set_(self, name, _column(getattr(self, name), n, name, dtype))
        offs = np.ascontiguousarray(self.op_offsets, dtype=np.int64)
        if (
            offs.ndim != 1
            or offs.size < 1
            or offs[0] != 0
            or offs[-1] != n
            or np.any(np.diff(offs) < 0)
        ):
            raise ValueError(f"op_offsets must rise from 0 to {n}, got {offs[:5]}...")
        set_(self, "op_offsets", offs)
        names = tuple(self.op_names) or tuple(f"operation {i + 1}" for i in range(offs.size - 1))
        if len(names) != offs.size - 1:
            raise ValueError(f"op_names has {len(names)} names for {offs.size - 1} operations")
        set_(self, "op_names", names)
        if self.tool_axis is not None:
            set_(self, "tool_axis", _points(self.tool_axis, n, "tool_axis"))
        if self.origin is not None:
            origin = _column(self.origin, n, "origin", np.int32)
            if origin.size and (origin.min() < -1 or origin.max() >= len(self.origins)):
                raise ValueError("origin must index origins (or be -1)")
            set_(self, "origin", origin)
            set_(self, "origins", tuple(self.origins))
            files = tuple(self.origin_files) or ("",) * len(self.origins)
            if len(files) != len(self.origins):
                raise ValueError("origin_files must have one entry per origin")
            set_(self, "origin_files", files)
        for name in COMPACT_COLUMNS:
            set_(self, name, _compact(getattr(self, name)))
        if self.rotary is not None:
            set_(self, "rotary", _points(self.rotary, n, "rotary"))
        if self.rotary_only is not None:
            after = self.rotary_only.after
            if after.size and (after.min() < -1 or after.max() >= n):
                raise ValueError("rotary_only.after must index the moves (or be -1)")

    def where(self, k: int) -> str:
        """Move ``k``'s source, for messages and tooltips: "line 12", or "line 3 of
        part.ngc:12 o<pocket> call > pocket.ngc" for a block run by a call."""
        line = f"line {int(self.line[k])}"
        if self.origin is None or self.origin[k] < 0:
            return line
        return f"{line} of {self.origins[int(self.origin[k])]}"

    #: Derived columns the models need once: :meth:`release_derived` frees them. The (n, 3)
    #: directions, the junctions' (n,) angles, curvature jumps, operations and indices (the
    #: profile reads the indices last), and the arcs' radii and pitches (the lengths, once
    #: made, are kept; a drawing makes these again).
    _DERIVED = (
        "tangent_start",
        "tangent_end",
        "curvature_vector_start",
        "curvature_vector_end",
        "axis_share",
        "_samples",
        "turn_angle",
        "curvature_jump",
        "op_index",
        "junctions",
        "_arc",
    )

    def release_derived(self, keep: tuple[str, ...] = ()) -> None:
        """Forget the derived columns but those named in ``keep`` (recomputed if asked for
        again): 152 bytes a move, and 25 an arc, that a finished analysis no longer needs."""
        for name in self._DERIVED:
            if name not in keep:
                self.__dict__.pop(name, None)

    def release_arc_shapes(self) -> None:
        """Forget the arcs' radii and pitches (recomputed if asked for again): a drawing that
        has sampled its arcs is done with them (5M arcs: 200 MB)."""
        for name in ("_arc", "radius", "pitch"):
            self.__dict__.pop(name, None)

    # ------------------------------------------------------------------ basics
    def __len__(self) -> int:
        return int(self.kind.shape[0])

    @property
    def n(self) -> int:
        """Number of moves."""
        return len(self)

    @cached_property
    def is_arc(self) -> NDArray[np.bool_]:
        return self.kind >= MoveKind.ARC_CW

    @cached_property
    def is_feed(self) -> NDArray[np.bool_]:
        """Feed moves (lines and arcs), i.e. everything but rapids."""
        return self.kind != MoveKind.RAPID

    @cached_property
    def op_index(self) -> NDArray[np.int64]:
        """(n,) operation of each move."""
        return np.repeat(np.arange(self.op_offsets.size - 1), np.diff(self.op_offsets))

    # ------------------------------------------------------------------ arcs
    @cached_property
    def _arc(self) -> dict[str, NDArray]:
        """The arcs' indices, senses, radii and pitches; their radius vectors are recomputed
        where used, in pieces (:meth:`_radial`): 48 bytes an arc not kept for the whole
        analysis."""
        idx = np.flatnonzero(self.is_arc)
        radius, pitch = np.empty(idx.size), np.empty(idx.size)
        for b in pieces(idx.size):
            k = idx[b]
            s, e, nrm = self.start[k], self.end[k], self.normal[k]
            radius[b] = g.norm(g.radial(s, self.center[k], nrm))
            pitch[b] = g.arc_pitch(s, e, nrm, self.sweep[k])
        return {
            "idx": idx,
            "ccw": self.kind[idx] == MoveKind.ARC_CCW,
            "radius": radius,
            "pitch": pitch,
        }

    def _radial(self, points: NDArray[np.float64], k: NDArray[np.int64]) -> NDArray[np.float64]:
        """In-plane vectors from the centres of arcs ``k`` to their ``points`` rows."""
        return g.radial(points[k], self.center[k], self.normal[k])

    @cached_property
    def radius(self) -> NDArray[np.float64]:
        """(n,) arc radius at the start (mm); NaN for lines."""
        out = np.full(self.n, np.nan)
        out[self._arc["idx"]] = self._arc["radius"]
        return out

    @cached_property
    def pitch(self) -> NDArray[np.float64]:
        """(n,) helix rise per radian along the normal (mm/rad); NaN for lines."""
        out = np.full(self.n, np.nan)
        out[self._arc["idx"]] = self._arc["pitch"]
        return out

    # ------------------------------------------------------------------ derived
    @cached_property
    def length(self) -> NDArray[np.float64]:
        """(n,) path length of each move, mm."""
        out = g.norm(self.end - self.start)
        a = self._arc
        out[a["idx"]] = g.arc_length(a["radius"], self.sweep[a["idx"]], a["pitch"])
        return out

    def _arc_tangents(self, points: NDArray[np.float64], other: str) -> NDArray[np.float64]:
        """Unit tangents at ``points`` (the moves' starts or ends): the chord's on lines,
        copied from the ``other`` end's where those are made (the same rows), and the
        arcs' own."""
        made = self.__dict__.get(other)
        out = made.copy() if made is not None else g.unit(self.end - self.start)
        a = self._arc
        for b in pieces(a["idx"].size):
            k = a["idx"][b]
            out[k] = g.arc_tangent(
                self._radial(points, k), self.normal[k], a["ccw"][b], a["pitch"][b]
            )
        return out

    @cached_property
    def tangent_start(self) -> NDArray[np.float64]:
        """(n, 3) unit tangent at the start of each move."""
        return self._arc_tangents(self.start, "tangent_end")

    @cached_property
    def tangent_end(self) -> NDArray[np.float64]:
        """(n, 3) unit tangent at the end of each move."""
        return self._arc_tangents(self.end, "tangent_start")

    @cached_property
    def curvature(self) -> NDArray[np.float64]:
        """(n,) signed curvature, 1/mm: 0 for lines, + for counter-clockwise arcs
        and - for clockwise arcs about their plane normal (helices r/(r^2+c^2))."""
        out = np.zeros(self.n)
        a = self._arc
        k = g.arc_curvature(a["radius"], a["pitch"])
        out[a["idx"]] = np.where(a["ccw"], k, -k)
        return out

    def _arc_curvature_vectors(self, points: NDArray[np.float64], i: NDArray | slice) -> NDArray:
        """(m, 3) curvature vectors at ``points`` of the arcs ``i`` (rows of the arc table):
        kappa along the principal normal, which on a helix points from the point to the
        axis: -r / |r|."""
        a = self._arc
        kappa = g.arc_curvature(a["radius"][i], a["pitch"][i])
        return -g.unit(self._radial(points, a["idx"][i])) * kappa[:, None]

    def _curvature_vector(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        out = np.zeros((self.n, 3))
        idx = self._arc["idx"]
        for b in pieces(idx.size):
            out[idx[b]] = self._arc_curvature_vectors(points, b)
        return out

    def _curvature_vector_rows(self, points: NDArray[np.float64], lo: int, hi: int) -> NDArray:
        """Rows ``lo:hi`` of :meth:`_curvature_vector` (the same numbers, for those rows
        only)."""
        out = np.zeros((hi - lo, 3))
        idx = self._arc["idx"]
        i0, i1 = np.searchsorted(idx, [lo, hi])
        out[idx[i0:i1] - lo] = self._arc_curvature_vectors(points, slice(i0, i1))
        return out

    def _curvature_vector_at(self, points: NDArray[np.float64], k: NDArray[np.int64]) -> NDArray:
        """Rows ``k`` (sorted moves) of :meth:`_curvature_vector` (the same numbers, for
        those rows only)."""
        out = np.zeros((k.size, 3))
        idx = self._arc["idx"]
        at = np.searchsorted(idx, k)
        arc = at < idx.size
        arc[arc] = idx[at[arc]] == k[arc]
        out[arc] = self._arc_curvature_vectors(points, at[arc])
        return out

    @cached_property
    def curvature_vector_start(self) -> NDArray[np.float64]:
        """(n, 3) curvature vector (kappa times principal normal) at each move's start, 1/mm."""
        return self._curvature_vector(self.start)

    @cached_property
    def curvature_vector_end(self) -> NDArray[np.float64]:
        """(n, 3) curvature vector at each move's end, 1/mm."""
        return self._curvature_vector(self.end)

    @cached_property
    def axis_share(self) -> NDArray[np.float64]:
        """(n, 3) largest share |t_k| of each axis in the unit tangent over each move.

        Lines have one direction. On arcs the in-plane part of the tangent turns with the
        sweep (its largest share per axis: :func:`core.model.geometry.max_share`); a helix adds
        its constant rise along the normal, bounded by adding its share (|a + b| <= |a| + |b|).
        An axis moving at path speed V runs at V times its share: what per-axis feed,
        acceleration and jerk limits are divided by.
        """
        share = np.abs(self.tangent_start)
        a = self._arc
        for b in pieces(a["idx"].size):
            idx = a["idx"][b]
            ccw = a["ccw"][b]
            n = self.normal[idx]
            c = a["pitch"][b]
            r = a["radius"][b]
            h = np.hypot(r, c)
            t0 = g.unit(
                np.where(ccw[:, None], 1.0, -1.0) * np.cross(n, self._radial(self.start, idx))
            )
            turned = np.where(ccw[:, None], np.cross(n, t0), -np.cross(n, t0))  # +90 deg
            inplane = g.max_share(t0, turned, self.sweep[idx][:, None]) * (r / h)[:, None]
            share[idx] = np.minimum(inplane + np.abs(n * (c / h)[:, None]), 1.0)
        return share

    # ------------------------------------------------------------------ junctions
    @cached_property
    def junctions(self) -> NDArray[np.int64]:
        """Indices ``j`` of the points between feed moves ``j`` and ``j + 1`` of one operation.

        These are the points where a tangential or curvature discontinuity can
        be; a rapid or an operation boundary in between breaks the chain.
        """
        if self.n < 2:
            return np.zeros(0, dtype=np.int64)
        f = self.is_feed
        op = self.op_index
        ok = f[:-1] & f[1:] & (op[:-1] == op[1:])
        return np.flatnonzero(ok)

    @cached_property
    def turn_angle(self) -> NDArray[np.float64]:
        """(n - 1,) direction change beta (rad, [0, pi]) from move j's end to move j+1's start."""
        if self.n < 2:
            return np.zeros(0)
        t1, t2 = self.tangent_end[:-1], self.tangent_start[1:]
        out = np.empty(self.n - 1)

        def rows(s: slice) -> None:  # (each junction's own: the halves side by side)
            out[s] = g.angle_between(t1[s], t2[s])

        if not halves(self.n - 1, rows):
            return g.angle_between(t1, t2)
        return out

    @cached_property
    def curvature_jump(self) -> NDArray[np.float64]:
        """(n - 1,) norm of the jump of the curvature vector at each junction, 1/mm.

        For coplanar moves this is the jump of the signed curvature:
        |1/R1 - 1/R2| for arcs turning the same way, 1/R1 + 1/R2 at an inflection,
        1/R between a line and an arc.
        """
        if self.n < 2:
            return np.zeros(0)
        # Between two lines both vectors are zero, and so is the jump (sqrt(0)): where few
        # junctions touch an arc, only those are computed (each row from its own two moves:
        # the same numbers).
        arcs = self._arc["idx"]
        near = np.concatenate([arcs - 1, arcs])
        near = unique(near[(near >= 0) & (near < self.n - 1)])
        if 2 * near.size <= self.n - 1:
            out = np.zeros(self.n - 1)
            for b in pieces(near.size):
                j = near[b]
                out[j] = g.norm(
                    self._curvature_vector_at(self.end, j)
                    - self._curvature_vector_at(self.start, j + 1)
                )
            return out
        # In pieces, from the curvature vectors of each piece's moves only: no (n, 3)
        # columns of them (5M moves: 230 MB off the models' peak).
        return piecewise(
            self.n - 1,
            np.float64,
            lambda b: g.norm(
                self._curvature_vector_rows(self.end, b.start, b.stop)
                - self._curvature_vector_rows(self.start, b.start + 1, b.stop + 1)
            ),
        )

    # ------------------------------------------------------------------ arc length
    @cached_property
    def start_s(self) -> NDArray[np.float64]:
        """(n,) arc length (mm) from the program start at which each move starts (rapids
        included)."""
        return np.concatenate([[0.0], np.cumsum(self.length)[:-1]])

    @cached_property
    def end_s(self) -> NDArray[np.float64]:
        """(n,) arc length (mm) at which each move ends."""
        return self.start_s + self.length

    def move_at(self, s: ArrayLike) -> NDArray[np.int64]:
        """Index of the move at arc lengths ``s`` (mm): the later move at a boundary, the
        first or last move before the start or past the end."""
        s = np.asarray(s, dtype=np.float64)
        return np.clip(np.searchsorted(self.start_s, s, side="right") - 1, 0, self.n - 1)

    def points_along(self, k: ArrayLike, d: ArrayLike) -> NDArray[np.float64]:
        """(m, 3) points at distances ``d`` (mm, (m,)) from the start of moves ``k`` ((m,)),
        on the move's line or (helical) arc."""
        k = np.asarray(k, dtype=np.int64)
        d = np.asarray(d, dtype=np.float64)
        if k.shape != d.shape or k.ndim != 1:
            raise ValueError(f"k and d must have one shape (m,), got {k.shape} and {d.shape}")
        with np.errstate(divide="ignore", invalid="ignore"):
            frac = np.where(self.length[k] > 0, d / self.length[k], 0.0)
        out = self.start[k] + frac[:, None] * (self.end[k] - self.start[k])
        arc = self.is_arc[k]
        if arc.any():
            ka = k[arc]
            out[arc] = g.arc_points(
                self.start[ka],
                self.center[ka],
                self.normal[ka],
                self.kind[ka] == MoveKind.ARC_CCW,
                self.sweep[ka],
                self.pitch[ka],
                frac[arc],
            )
        return out

    def point_at(self, s: ArrayLike) -> NDArray[np.float64]:
        """(m, 3) points at arc lengths ``s`` (mm, (m,)), clipped to the path."""
        s = np.asarray(s, dtype=np.float64)
        k = self.move_at(s)
        d = np.clip(s - self.start_s[k], 0.0, self.length[k])
        return self.points_along(k, d)

    def sample(self, step: float) -> PathSamples:
        """Points about every ``step`` mm along the path, each move's ends included (kept:
        the same step asked again costs nothing)."""
        hit = self._samples.get(step)
        if hit is None:
            counts = np.maximum(np.ceil(self.length / step).astype(np.int64), 1)
            owner = np.repeat(np.arange(self.n), counts + 1)
            first = np.cumsum(counts + 1) - (counts + 1)
            k = np.arange(owner.size) - first[owner]
            d = k / counts[owner] * self.length[owner]
            hit = PathSamples(
                points=self.points_along(owner, d),
                s=self.start_s[owner] + d,
                move=owner,
                step=float(step),
            )
            self._samples[step] = hit
        return hit

    @cached_property
    def _samples(self) -> dict[float, PathSamples]:
        return {}

    # ------------------------------------------------------------------ totals
    @cached_property
    def feed_length(self) -> float:
        """Total length of feed moves, mm."""
        return float(self.length[self.is_feed].sum())

    @cached_property
    def programmed_time(self) -> float:
        """Sum of length / F over feed moves, s."""
        f = self.is_feed
        return float(np.sum(self.length[f] / self.feed[f]))

    def describe_lines(self, i: int, j: int | None = None) -> str:
        """Source line (range) of move ``i`` (to ``j``) for messages."""
        a = int(self.line[i])
        b = a if j is None else int(self.line[j])
        lo, hi = min(a, b), max(a, b)
        return f"{lo}" if lo == hi else f"{lo}-{hi}"


def empty_columns(n: int) -> dict[str, Any]:
    """Default columns for ``n`` moves, for adapters and tests to fill in."""
    return {
        "kind": np.full(n, MoveKind.LINE, dtype=np.int8),
        "start": np.zeros((n, 3)),
        "end": np.zeros((n, 3)),
        "center": np.full((n, 3), np.nan),
        "normal": np.full((n, 3), np.nan),
        "sweep": np.full(n, np.nan),
        "feed": np.full(n, np.nan),
        "line": np.arange(1, n + 1, dtype=np.int64),
        "block": np.full(n, -1, dtype=np.int64),
        "tool": np.full(n, -1, dtype=np.int32),
        "path_mode": np.zeros(n, dtype=np.int8),
        "dwell": np.zeros(n),
        "tolerance": np.full(n, np.nan),
        "op_offsets": np.array([0, n], dtype=np.int64),
    }


def polyline(points: ArrayLike, feed: float, *, source: str = "<polyline>") -> ToolPath:
    """A tool path of G1 lines through ``points`` at one feed.

    Parameters
    ----------
    points : (m, 3) float, mm
        At least two points.
    feed : float, mm/s
    """
    p = g.as_points(points, "points")
    if p.shape[0] < 2:
        raise ValueError(f"points must have at least 2 rows, got {p.shape}")
    cols = empty_columns(p.shape[0] - 1)
    cols["start"] = p[:-1]
    cols["end"] = p[1:]
    cols["feed"][:] = feed
    return ToolPath(**cols, source=source)


#: What :func:`drop_zero_length` tells the user it did (adapters add it as a notice).
POINTS_DROPPED = "moves shorter than the 0.001 mm resolution dropped (points, not blocks)"


def drop_zero_length(tp: ToolPath) -> tuple[ToolPath, NDArray[np.int64]]:
    """Remove moves no longer than :attr:`Tolerances.resolution`: points, not blocks.

    A run of such moves is walked from the path's last point: a move that takes the path
    further than the resolution from there is kept, as a line from there (a stair of
    0.7 um steps, a V-carve written with six decimals in inches, stays the path LinuxCNC
    runs, in fewer, longer blocks); the others are points and go (an isolated 0.0001 mm
    corner arc). Returns the cleaned path and the indices of the removed moves. A dwell or
    exact stop on a removed move moves to the move before it; a line after removed moves
    starts where the last kept move ended, at most the resolution away (an arc keeps its
    start).
    """
    res = TOL.resolution
    zero = tp.length <= res
    if tp.rotary is not None:
        if (zero & (np.abs(tp.rotary) > res).any(axis=1)).any():
            raise ValueError("a move that only turns rotary axes belongs in rotary_only")
    if not zero.any():
        return tp, np.zeros(0, dtype=np.int64)
    keep = ~zero
    start = tp.start.copy()
    kind = tp.kind.copy()
    center, normal, sweep = tp.center.copy(), tp.normal.copy(), tp.sweep.copy()
    idx = np.flatnonzero(zero)
    first_of_run = np.ones(idx.size, dtype=bool)
    first_of_run[1:] = idx[1:] != idx[:-1] + 1
    end = tp.end
    anchor = end[0]
    for k, new_run in zip(idx.tolist(), first_of_run.tolist(), strict=True):
        if new_run:
            anchor = end[k - 1] if k > 0 else tp.start[k]
        d = end[k] - anchor
        if float(d @ d) > res * res:
            keep[k] = True
            start[k] = anchor
            anchor = end[k]
            if kind[k] >= MoveKind.ARC_CW:  # what is left of a tiny arc is a short line
                kind[k] = MoveKind.LINE
                center[k] = normal[k] = np.nan
                sweep[k] = np.nan
    zero = ~keep
    removed = np.flatnonzero(zero)
    if removed.size == 0:
        merged = dataclasses.replace(tp, start=start, kind=kind, center=center, normal=normal)
        return dataclasses.replace(merged, sweep=sweep), removed
    # Carry stops and dwells of removed moves back to the last kept move before them.
    last_kept = np.maximum.accumulate(np.where(keep, np.arange(tp.n), -1))
    target = last_kept[removed]
    has = target >= 0
    dwell = tp.dwell.copy()
    np.add.at(dwell, target[has], tp.dwell[removed[has]])
    mode = tp.path_mode.copy()
    np.maximum.at(mode, target[has], tp.path_mode[removed[has]])
    offs = np.concatenate([[0], np.cumsum(keep)])[tp.op_offsets].astype(np.int64)
    # kept lines right after removed moves: from the end of the last kept move before
    after = np.flatnonzero(keep[1:] & zero[:-1]) + 1
    after = after[(kind[after] < MoveKind.ARC_CW) & (last_kept[after - 1] >= 0)]
    start[after] = tp.end[last_kept[after - 1]]
    cols: dict[str, Any] = {
        "kind": kind[keep],
        "start": start[keep],
        "end": tp.end[keep],
        "center": center[keep],
        "normal": normal[keep],
        "sweep": sweep[keep],
        "feed": tp.feed[keep],
        "line": tp.line[keep],
        "block": tp.block[keep],
        "tool": tp.tool[keep],
        "path_mode": mode[keep],
        "dwell": dwell[keep],
        "tolerance": tp.tolerance[keep],
    }
    names = tp.op_names
    # Drop operations left empty.
    sizes = np.diff(offs)
    if np.any(sizes == 0):
        keep_op = np.flatnonzero(sizes > 0)
        names = tuple(names[i] for i in keep_op)
        offs = np.concatenate([[0], offs[1:][keep_op]])
    return rebuilt(tp, np.flatnonzero(keep), cols, offs, names), removed


def rebuilt(
    tp: ToolPath,
    rows: NDArray[np.intp],
    cols: dict[str, Any],
    op_offsets: NDArray[np.int64],
    op_names: tuple[str, ...],
) -> ToolPath:
    """A tool path of ``tp``'s moves ``rows`` (ascending indices, a move repeated where it
    became several) with the move columns ``cols`` made for them and their operations; the
    optional per-move columns (tool axis, origin, rotary axes) are ``tp``'s at ``rows``, a
    rotary-only move follows the last row of the move it followed, the rest is ``tp``'s."""
    return ToolPath(
        **cols,
        op_offsets=op_offsets,
        op_names=op_names,
        source=tp.source,
        notices=tp.notices,
        tool_axis=None if tp.tool_axis is None else tp.tool_axis[rows],
        units=tp.units,
        origin=None if tp.origin is None else tp.origin[rows],
        origins=tp.origins,
        origin_files=tp.origin_files,
        rotary=None if tp.rotary is None else tp.rotary[rows],
        rotary_only=_reindexed(tp.rotary_only, rows),
    )


def _reindexed(rm: RotaryMoves | None, rows: NDArray[np.intp]) -> RotaryMoves | None:
    """Rotary-only moves re-pointed to the rows of a path of some moves (:func:`rebuilt`):
    each follows the last row of the last move kept at or before the one it followed."""
    if rm is None:
        return None
    last = np.searchsorted(rows, rm.after, side="right") - 1
    after = np.where(rm.after >= 0, last, -1)
    return RotaryMoves(after=after, travel=rm.travel, feed=rm.feed, line=rm.line)
