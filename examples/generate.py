"""Generate the example G-code programs of ncperf.

The programs reproduce the test tool paths of Tapie, Mawussi and Anselmetti,
"Machining strategy choice: performance viewer" (sec. 2), plus a Z-level
finishing path of a small mould cavity like the one of the paper's Figure 10
(sec. 3.3). Run ``python examples/generate.py`` to rewrite all of them into the
folder of this script (``--out DIR`` to write elsewhere); the output depends on
nothing but this file, so it is the same at every run. Every program is checked
after it is written (see :func:`check_program`) and the script fails loudly if
one is not right.

Programs
--------
``fig1_polygons_F2000.ngc`` ... ``fig1_polygons_F12000.ngc``
    Figure 1 (tangential discontinuities, model 1, eq. 1-10). One file per
    programmed feed (2, 4, 8, 12 m/min). Each holds eight chains of 20 mm
    segments, one per direction-change angle alpha in 5, 10, 20, 30, 40, 60,
    90, 120 deg, side by side along X. The paper gives alpha "by the number of
    segments in the polygon", so alpha is the angle the direction turns at each
    corner of a regular 360/alpha-gon (alpha = 120 deg is a triangle). Polygons
    of up to 12 sides are closed (the triangle and the square twice round, so
    that each has at least five corners); for 20, 10 and 5 deg the 18-, 36- and
    72-gon would be 115 to 460 mm across, so only six consecutive sides (five
    corners) are run. Between chains the tool lifts to Z5 (G0) and plunges back
    to Z0 (G1).
``fig3_semicircle_spiral.ngc``
    Figure 3 (curvature discontinuities, model 2, eq. 11-15). A clockwise (G2)
    spiral of half circles whose radius grows by 2.5 mm at each half turn
    (5, 7.5, ..., 30 mm), then a second spiral of quarter circles whose radius
    grows by 1.25 mm at each quarter turn (5, 6.25, ..., 30 mm). Each arc starts
    on the normal line of the previous one, so the path is tangent-continuous
    and every radius change is a pure curvature discontinuity (eq. 14).
    F5000 mm/min.
``fig4_points_d0.5.ngc`` ... ``fig4_points_d5.ngc``
    Figure 4 (NCU calculation capacity, model 3, eq. 16). Along X, from A
    (X0) to B (X60) collinear points d apart (d = 0.5, 1, 2, 3, 5 mm), then
    one 30 mm block from B to C (X90), F10000 mm/min. With the 840D's
    t_int = 12 ms, eq. (16) gives L = 166.7 mm/s x 0.012 s = 2 mm: blocks of
    1 mm can run at 1 mm / 12 ms = 5 m/min, a 50 % reduction (the paper
    measured about 55 %); blocks of 3 mm and more reach the programmed feed.
``zlevel_cavity.ngc``
    The bundled demo, after Figure 10: Z-level finishing of a small mould
    cavity with a 6 mm ball-end mill, contours written as G1 lines, G2 corner
    arcs and G3 arcs fitted on an elliptical boss. See :func:`cavity_program`
    for the geometry.
``zlevel_cavity_chords.ngc``
    The same path as a CAM system without arc output writes it: every curved
    stretch as G1 chords within 0.005 mm. The second strategy to compare with
    the first: many blocks shorter than eq. (16)'s L.

Every program is plain ISO G-code that Fanuc-style controls, a Siemens 840D in
ISO mode and LinuxCNC accept: a header comment, ``G21 G90 G17 G94 G64``, G0 /
G1 / G2 / G3 with I J incremental arc centres, F in mm/min, ``M30``; at most 4
decimals, no block numbers, no tool change, comments in parentheses.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

# --- tolerances and format (one place; each says why it has its value) -------------------------

#: Decimals written for coordinates: 4 decimals in mm (0.1 um) is what CAM posts write for
#: HSM finishing, and what every target control reads.
DECIMALS = 4
#: Largest allowed |r_end - r_start| of an arc after rounding (mm). Rounding both end points
#: and the I J offsets to 4 decimals moves a radius by at most ~1.5e-4 mm, so 5e-4 mm leaves
#: margin while staying 50 times inside LinuxCNC's 0.028 mm acceptance (rs274ngc interp_arc).
ARC_END_TOL = 0.0005
#: Chordal tolerance (mm) of the G1 chords and of the arc fitting: a usual finishing value.
CHORD_TOL = 0.005
#: Longest line: many controls (and DNC links) refuse blocks of 256 characters or more.
MAX_LINE = 255
#: Clearance plane (mm) for rapids, and the plunge feed (mm/min).
SAFE_Z = 5.0
PLUNGE_FEED = 1000.0

GENERATOR = "examples/generate.py"

# --- Figure 1, 3, 4 parameters -----------------------------------------------------------------

FIG1_ALPHAS_DEG = (5, 10, 20, 30, 40, 60, 90, 120)
FIG1_FEEDS = (2000, 4000, 8000, 12000)  # mm/min = 2, 4, 8, 12 m/min
FIG1_SEGMENT = 20.0  # mm, the same for every segment of every polygon
FIG1_MAX_CLOSED_SIDES = 12  # larger polygons are run as a chain of FIG1_CHAIN segments
FIG1_CHAIN = 6  # segments = 5 corners per angle at least
FIG1_GAP = 10.0  # mm between the bounding boxes of neighbouring polygons

FIG3_FEED = 5000.0
FIG3_HALF_RADII = np.arange(5.0, 30.0 + 1e-9, 2.5)  # 11 half circles
FIG3_QUARTER_RADII = np.arange(5.0, 30.0 + 1e-9, 1.25)  # 21 quarter circles
FIG3_SECOND_ORIGIN = (100.0, 0.0)  # mm, where the quarter-circle spiral starts

FIG4_FEED = 10000.0
FIG4_SPACINGS = (0.5, 1.0, 2.0, 3.0, 5.0)  # mm
FIG4_AB = 60.0  # mm covered by the point series
FIG4_BC = 30.0  # mm, the single block of the paper


class GenerationError(Exception):
    """A generated block is wrong (arc end off its circle, zero-length move, line too long...).

    Parameters
    ----------
    message : str
        What is wrong.
    source : str
        Program (file) name.
    line : int
        1-based line number the block would have (or has) in the file.
    text : str
        The block.
    """

    def __init__(self, message: str, *, source: str, line: int, text: str) -> None:
        super().__init__(message)
        self.message, self.source, self.line, self.text = message, source, line, text

    def __str__(self) -> str:
        return f"{self.source}:{self.line}: {self.message}: {self.text}"


def fmt(value: float) -> str:
    """Format a number with at most :data:`DECIMALS` decimals and no trailing zeros.

    Parameters
    ----------
    value : float
        Number (mm or mm/min).

    Returns
    -------
    str
        ``"12.5"``, ``"-0.25"``, ``"0"`` (never ``"-0"``).
    """
    s = f"{round(value, DECIMALS):.{DECIMALS}f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def rnd(value: float) -> float:
    """Round to :data:`DECIMALS` decimals, the value the control will read."""
    return float(fmt(value))


class Program:
    """A G-code program being written, with the checks of every block.

    The program tracks the position as the control reads it (rounded to
    :data:`DECIMALS`), so arc centres are written relative to the rounded start
    and the end-point check sees exactly what the control will see.

    Parameters
    ----------
    name : str
        File stem, e.g. ``"fig3_semicircle_spiral"``.
    title : str
        One-line purpose, written in the header comment.
    notes : sequence of str
        Further header comment lines.
    """

    def __init__(self, name: str, title: str, notes: Sequence[str] = ()) -> None:
        self.name = name
        self.lines: list[str] = []
        self.pos = [math.nan, math.nan, math.nan]  # rounded X Y Z as the control reads them
        self.feed: float | None = None
        self.comment(f"{name} - {title}")
        for note in notes:
            self.comment(note)
        self.comment(f"generated by {GENERATOR} - do not edit, rerun the script")
        self._emit("G21 G90 G17 G94 G64")

    # -- low level --------------------------------------------------------------------------
    def _fail(self, message: str, text: str) -> None:
        raise GenerationError(
            message, source=f"{self.name}.ngc", line=len(self.lines) + 1, text=text
        )

    def _emit(self, text: str) -> None:
        if len(text) > MAX_LINE:
            self._fail(f"line has {len(text)} characters, more than {MAX_LINE}", text[:60])
        self.lines.append(text)

    def comment(self, text: str) -> None:
        """Write a comment line ``(text)``; parentheses inside would nest, so they fail.

        Parameters
        ----------
        text : str
            Comment text, ASCII, without ``(``, ``)`` or ``;``.
        """
        if any(c in text for c in "();") or not text.isascii():
            self._fail("comment holds a parenthesis, a semicolon or non-ASCII text", text)
        self._emit(f"({text})")

    def _words(self, target: Sequence[float | None], always_xy: bool = False) -> list[str]:
        words = []
        for i, (axis, v) in enumerate(zip("XYZ", target, strict=True)):
            if v is None:
                continue
            if (always_xy and i < 2) or rnd(v) != self.pos[i]:
                words.append(f"{axis}{fmt(v)}")
        return words

    def _move(
        self,
        code: str,
        target: Sequence[float | None],
        feed: float | None,
        extra: Sequence[str] = (),
        always_xy: bool = False,
    ) -> None:
        words = self._words(target, always_xy)
        new = [self.pos[i] if v is None else rnd(v) for i, v in enumerate(target)]
        text = " ".join([code, *words, *extra])
        if not words or new == self.pos:
            asked = [f"{a}{fmt(v)}" for a, v in zip("XYZ", target, strict=True) if v is not None]
            self._fail("zero-length move after rounding", " ".join([code, *asked]))
        if feed is not None and feed != self.feed:
            text += f" F{fmt(feed)}"
            self.feed = feed
        if code in ("G1", "G2", "G3") and self.feed is None:
            self._fail("feed move before any F word", text)
        self._emit(text)
        self.pos = new

    # -- moves ------------------------------------------------------------------------------
    def rapid(self, x: float | None = None, y: float | None = None, z: float | None = None) -> None:
        """Write ``G0`` to the given (mm) coordinates; unchanged axes are left out."""
        self._move("G0", (x, y, z), None)

    def retract(self) -> None:
        """Write ``G0 Z`` to the clearance plane :data:`SAFE_Z`, unless the tool is there."""
        if self.pos[2] != rnd(SAFE_Z):
            self.rapid(z=SAFE_Z)

    def line(
        self,
        x: float | None = None,
        y: float | None = None,
        z: float | None = None,
        feed: float | None = None,
    ) -> None:
        """Write ``G1`` to the given (mm) coordinates, with ``F`` (mm/min) when it changes."""
        self._move("G1", (x, y, z), feed)

    def arc(
        self, x: float, y: float, cx: float, cy: float, cw: bool, feed: float | None = None
    ) -> None:
        """Write a ``G2`` (``cw``) or ``G3`` arc in the XY plane at constant Z.

        Parameters
        ----------
        x, y : float, mm
            End point.
        cx, cy : float, mm
            Centre (absolute); written as I J incremental from the rounded start.
        cw : bool
            Clockwise (G2) seen from +Z, else counter-clockwise (G3).
        feed : float, mm/min, optional
            Feed, written when it changes.

        Raises
        ------
        GenerationError
            If the rounded end point is more than :data:`ARC_END_TOL` off the
            circle through the rounded start, or the arc has zero length.
        """
        sx, sy = self.pos[0], self.pos[1]
        if math.isnan(sx) or math.isnan(sy):
            self._fail("arc from an unknown position", f"G{2 if cw else 3}")
        i, j = rnd(cx - sx), rnd(cy - sy)
        ex, ey = rnd(x), rnd(y)
        r_start = math.hypot(i, j)
        r_end = math.hypot(ex - (sx + i), ey - (sy + j))
        text = f"G{2 if cw else 3} X{fmt(x)} Y{fmt(y)} I{fmt(i)} J{fmt(j)}"
        if abs(r_end - r_start) > ARC_END_TOL:
            self._fail(
                f"arc end point is {abs(r_end - r_start):.6f} mm off the circle "
                f"(limit {ARC_END_TOL} mm)",
                text,
            )
        if r_start == 0.0:
            self._fail("arc of zero radius", text)
        self._move(
            "G2" if cw else "G3", (x, y, None), feed, (f"I{fmt(i)}", f"J{fmt(j)}"), always_xy=True
        )

    def path(self, elements: Iterable[tuple], feed: float | None = None) -> None:
        """Write a chain of elements from :func:`rounded_rectangle` or the fitters.

        Parameters
        ----------
        elements : iterable of tuple
            ``("L", x, y)`` lines and ``("A", x, y, cx, cy, cw)`` arcs, mm.
        feed : float, mm/min, optional
            Feed of the first element.
        """
        for e in elements:
            if e[0] == "L":
                self.line(e[1], e[2], feed=feed)
            else:
                self.arc(e[1], e[2], e[3], e[4], e[5], feed=feed)
            feed = None

    def text(self) -> str:
        """The whole program, ending with ``M30``."""
        return "\n".join([*self.lines, "M30"]) + "\n"


# --- Figure 1 ------------------------------------------------------------------------------------


def polygon_chain(alpha_deg: float, length: float = FIG1_SEGMENT) -> NDArray[np.float64]:
    """Vertices of a chain of equal segments turning left by ``alpha_deg`` at each corner.

    Parameters
    ----------
    alpha_deg : float, deg
        Direction change at each corner; the chain lies on the regular
        ``360 / alpha``-gon.
    length : float, mm
        Segment length.

    Returns
    -------
    (n + 1, 2) float, mm
        Vertices from the start, with the bounding box's lower-left corner at
        the origin. Polygons of up to :data:`FIG1_MAX_CLOSED_SIDES` sides are
        closed (run round as many times as needed for :data:`FIG1_CHAIN`
        segments); larger ones are a chain of :data:`FIG1_CHAIN` segments,
        symmetric about the Y axis direction.
    """
    sides = round(360.0 / alpha_deg)
    if sides <= FIG1_MAX_CLOSED_SIDES:
        n = sides * math.ceil(FIG1_CHAIN / sides)
        heading0 = 0.0
    else:
        n = FIG1_CHAIN
        heading0 = math.pi / 2 - (n - 1) * math.radians(alpha_deg) / 2
    headings = heading0 + math.radians(alpha_deg) * np.arange(n)
    steps = length * np.column_stack([np.cos(headings), np.sin(headings)])
    pts = np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
    if sides <= FIG1_MAX_CLOSED_SIDES:
        pts[sides::sides] = 0.0  # closing vertices exactly at the start, not 1e-15 off
    return pts - pts.min(axis=0)


def fig1_program(feed: float) -> Program:
    """Figure 1: the polygons of all corner angles at one programmed feed.

    Parameters
    ----------
    feed : float, mm/min
        Programmed feed.

    Returns
    -------
    Program
    """
    p = Program(
        f"fig1_polygons_F{feed:g}",
        f"Figure 1 of Tapie et al.: tangential discontinuities at F{feed:g} mm/min",
        [
            f"regular polygon chains, {FIG1_SEGMENT:g} mm segments, direction change alpha "
            f"{' '.join(str(a) for a in FIG1_ALPHAS_DEG)} deg, side by side along X",
            "alpha = 360 / number of sides, up to 12 sides closed, else 6 consecutive sides",
            "air cut at Z0, lift to Z5 between polygons",
        ],
    )
    p.retract()
    x0 = 0.0
    for alpha in FIG1_ALPHAS_DEG:
        pts = polygon_chain(alpha)
        pts[:, 0] += x0
        sides = round(360 / alpha)
        n = len(pts) - 1
        kind = f"closed {sides}-gon" if sides <= FIG1_MAX_CLOSED_SIDES else f"{sides}-gon"
        p.comment(
            f"alpha {alpha} deg: {kind}, {n} segments of {FIG1_SEGMENT:g} mm, {n - 1} corners"
        )
        p.retract()
        p.rapid(x=pts[0, 0], y=pts[0, 1])
        p.line(z=0.0, feed=PLUNGE_FEED)
        f = feed
        for x, y in pts[1:]:
            p.line(x, y, feed=f)
            f = None
        x0 = pts[:, 0].max() + FIG1_GAP
    p.retract()
    return p


# --- Figure 3 ------------------------------------------------------------------------------------


def arc_spiral(start: Sequence[float], radii: Sequence[float], sweep: float) -> list[tuple]:
    """Tangent-continuous clockwise spiral of arcs whose radius changes at each arc.

    Each arc's centre lies on the normal of the previous arc at their common
    point, so the tangent is continuous and only the curvature jumps, from
    ``1/radii[k]`` to ``1/radii[k+1]``.

    Parameters
    ----------
    start : (2,) float, mm
        Start point; the first centre is ``radii[0]`` to its right (+X).
    radii : (n,) float, mm
        Radius of each arc.
    sweep : float, rad
        Angle swept by each arc (pi: half circles, pi/2: quarter circles).

    Returns
    -------
    list of tuple
        ``("A", x, y, cx, cy, True)`` elements for :meth:`Program.path`.
    """
    radii = np.asarray(radii, dtype=np.float64)
    if radii.ndim != 1 or len(radii) == 0 or np.any(radii <= 0):
        raise ValueError(f"radii must be a non-empty (n,) array of positive mm, got {radii!r}")
    point = np.asarray(start, dtype=np.float64)
    centre = point + np.array([radii[0], 0.0])
    c, s = math.cos(-sweep), math.sin(-sweep)  # clockwise rotation
    rot = np.array([[c, -s], [s, c]])
    out = []
    for k, r in enumerate(radii):
        end = centre + rot @ (point - centre)
        out.append(("A", end[0], end[1], centre[0], centre[1], True))
        if k + 1 < len(radii):
            centre = end + (centre - end) * (radii[k + 1] / r)
        point = end
    return out


def fig3_program() -> Program:
    """Figure 3: a half-circle spiral, then a quarter-circle spiral, both G2.

    Returns
    -------
    Program
    """

    def radii_text(radii: NDArray[np.float64]) -> str:
        return f"R {fmt(radii[0])}, {fmt(radii[1])}, {fmt(radii[2])} ... {fmt(radii[-1])} mm"

    p = Program(
        "fig3_semicircle_spiral",
        "Figure 3 of Tapie et al.: curvature discontinuities on G2 spirals",
        [
            f"spiral 1: {len(FIG3_HALF_RADII)} half circles, {radii_text(FIG3_HALF_RADII)}",
            f"spiral 2: {len(FIG3_QUARTER_RADII)} quarter circles, "
            f"{radii_text(FIG3_QUARTER_RADII)}",
            "tangent continuous, the radius changes at every arc end, "
            f"F{FIG3_FEED:g} mm/min, air cut at Z0",
        ],
    )
    for label, radii, sweep, origin in (
        ("half circles", FIG3_HALF_RADII, math.pi, (0.0, 0.0)),
        ("quarter circles", FIG3_QUARTER_RADII, math.pi / 2, FIG3_SECOND_ORIGIN),
    ):
        p.comment(f"spiral of {len(radii)} {label}, {len(radii) - 1} curvature discontinuities")
        p.retract()
        p.rapid(x=origin[0], y=origin[1])
        p.line(z=0.0, feed=PLUNGE_FEED)
        p.path(arc_spiral(origin, radii, sweep), feed=FIG3_FEED)
    p.retract()
    return p


# --- Figure 4 ------------------------------------------------------------------------------------


def fig4_program(d: float) -> Program:
    """Figure 4: collinear points ``d`` apart from A to B, then one 30 mm block to C.

    Parameters
    ----------
    d : float, mm
        Distance between consecutive points on AB; must divide :data:`FIG4_AB`.

    Returns
    -------
    Program
    """
    n = round(FIG4_AB / d)
    if abs(n * d - FIG4_AB) > 1e-9:
        raise ValueError(f"d = {d} mm does not divide AB = {FIG4_AB} mm")
    t_int = 0.012  # s, the 840D interpolation time the paper uses (sec. 3.2, model 3)
    v = FIG4_FEED / 60.0
    limit = min(1.0, d / (v * t_int))  # eq. (16): a block lasts at least t_int
    p = Program(
        f"fig4_points_d{d:g}",
        f"Figure 4 of Tapie et al.: NCU calculation capacity, points {d:g} mm apart",
        [
            f"A X0 to B X{FIG4_AB:g}: {n} collinear G1 blocks of {d:g} mm, "
            f"B to C X{FIG4_AB + FIG4_BC:g}: one {FIG4_BC:g} mm block, F{FIG4_FEED:g} mm/min",
            f"eq. 16 with t_int 12 ms: L = {v * t_int:g} mm, predicted feed on AB "
            f"{100 * limit:.0f} percent of F",
        ],
    )
    p.retract()
    p.rapid(x=0.0, y=0.0)
    p.line(z=0.0, feed=PLUNGE_FEED)
    p.comment(f"A to B: {n} points {d:g} mm apart")
    xs = d * np.arange(1, n + 1)
    p.line(xs[0], feed=FIG4_FEED)
    for x in xs[1:]:
        p.line(x)
    p.comment(f"B to C: one {FIG4_BC:g} mm block")
    p.line(FIG4_AB + FIG4_BC)
    p.retract()
    return p


# --- the Z-level cavity (Figure 10) --------------------------------------------------------------


@dataclass(frozen=True)
class Cavity:
    """Geometry of the demo mould cavity and of its finishing (mm, deg, mm/min).

    The cavity is a pocket from the top face Z0 to a flat floor, its walls
    drafted (the pocket narrows downwards) and joined to the floor by a
    concave fillet. In its middle stands an elliptical boss, drafted the other
    way (it widens downwards) and joined to the floor by the same fillet.
    Every section normal to a wall has the same profile, so the tool-centre
    contour at each level is an offset of the top outline (see
    :func:`tool_offset`).
    """

    #: Pocket top outline: rounded rectangle, full sizes and corner radius.
    length: float = 60.0
    width: float = 40.0
    corner: float = 8.0
    depth: float = 12.0
    #: Boss top outline: ellipse semi-axes, and its top face height.
    boss_a: float = 9.0
    boss_b: float = 5.0
    boss_top: float = -4.0
    draft_deg: float = 3.0
    #: Floor fillet radius; must exceed the tool radius, else the ball centre
    #: stays at the fillet centre and the fillet is cut in a single level.
    fillet: float = 5.0
    #: Ball-end mill radius (6 mm diameter).
    tool_radius: float = 3.0
    step_down: float = 0.25
    feed: float = 3000.0


def tool_offset(
    z_tip: NDArray[np.float64],
    z_top: float,
    z_floor: float,
    draft_deg: float,
    fillet: float,
    tool_radius: float,
) -> NDArray[np.float64]:
    """Horizontal offset of the ball centre from a drafted wall's top edge, per Z level.

    The wall profile, in a section normal to it, is a sharp top edge at
    ``z_top``, a straight wall leaning by ``draft_deg`` (away from the tool
    downwards), and a concave fillet of radius ``fillet`` tangent to the wall
    and to the floor at ``z_floor``. A ball of radius ``tool_radius`` whose tip
    is at ``z_tip`` touches, from top to bottom: the top edge, the wall, the
    fillet (where the offset grows faster per level: the surface turns
    towards the horizontal).

    Parameters
    ----------
    z_tip : (n,) float, mm
        Tool tip heights, between ``z_floor`` and ``z_top``.
    z_top, z_floor : float, mm
        Height of the top edge and of the floor.
    draft_deg : float, deg
        Draft angle of the wall.
    fillet, tool_radius : float, mm
        Fillet and ball radii; ``fillet > tool_radius``.

    Returns
    -------
    (n,) float, mm
        Offset of the ball centre from the top edge, measured horizontally away
        from the material (inwards for a pocket, outwards for a boss).
    """
    z_tip = np.asarray(z_tip, dtype=np.float64)
    if z_tip.ndim != 1:
        raise ValueError(f"z_tip must have shape (n,), got {z_tip.shape}")
    if not fillet > tool_radius:
        raise ValueError(f"fillet radius {fillet} mm must exceed the tool radius {tool_radius} mm")
    if np.any(z_tip > z_top) or np.any(z_tip < z_floor - 1e-12):
        raise ValueError(f"z_tip must lie in [{z_floor}, {z_top}] mm")
    th = math.radians(draft_deg)
    rt, rf = tool_radius, fillet
    zc = z_tip + rt  # ball centre
    zf = z_floor + rf  # fillet centre
    uf = rf / math.cos(th) - (zf - z_top) * math.tan(th)  # fillet centre offset
    wall_top = z_top + rt * math.sin(th)  # above: the ball touches the sharp edge
    wall_bottom = zf - (rf - rt) * math.sin(th)  # below: the ball touches the fillet
    with np.errstate(invalid="ignore"):
        edge = np.sqrt(rt**2 - (zc - z_top) ** 2)
        wall = rt / math.cos(th) - (zc - z_top) * math.tan(th)
        wz = np.clip((zc - zf) / (rf - rt), -1.0, 1.0)
        fil = uf - (rf - rt) * np.sqrt(1.0 - wz**2)
    return np.select([zc > wall_top, zc >= wall_bottom], [edge, wall], fil)


def rounded_rectangle(
    half_x: float, half_y: float, radius: float, chord_tol: float | None
) -> list[tuple]:
    """Closed clockwise rounded rectangle from the middle of its lower side.

    Parameters
    ----------
    half_x, half_y : float, mm
        Half sizes.
    radius : float, mm
        Corner radius, ``0 < radius <= min(half_x, half_y)``.
    chord_tol : float or None, mm
        ``None``: corners as G2 arcs; else as G1 chords inscribed in the arcs
        with this chordal deviation at most.

    Returns
    -------
    list of tuple
        ``("L", x, y)`` and ``("A", x, y, cx, cy, True)`` elements, ending at
        the start point ``(0, -half_y)``.
    """
    if not 0.0 < radius <= min(half_x, half_y):
        raise ValueError(
            f"corner radius {radius} mm does not fit half sizes {half_x} x {half_y} mm"
        )
    hx, hy = half_x - radius, half_y - radius
    # corners in clockwise order from the lower left, with the angle (deg) where each starts
    corners = ((-hx, -hy, 270.0), (-hx, hy, 180.0), (hx, hy, 90.0), (hx, -hy, 0.0))
    out: list[tuple] = []
    for cx, cy, a0 in corners:
        start = (cx + radius * math.cos(math.radians(a0)), cy + radius * math.sin(math.radians(a0)))
        out.append(("L", *start))
        end_a = math.radians(a0 - 90.0)
        end = (cx + radius * math.cos(end_a), cy + radius * math.sin(end_a))
        if chord_tol is None:
            out.append(("A", *end, cx, cy, True))
        else:
            n = math.ceil((math.pi / 2) / (2 * math.acos(1 - chord_tol / radius)))
            a = np.radians(a0) - (math.pi / 2) * np.arange(1, n + 1) / n
            out.extend(
                ("L", x, y)
                for x, y in zip(cx + radius * np.cos(a), cy + radius * np.sin(a), strict=True)
            )
    out.append(("L", 0.0, -half_y))
    return out


def offset_ellipse(
    a: float, b: float, offset: float, phi: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Points and unit tangents of the outward offset of an ellipse, by normal angle.

    Parameters
    ----------
    a, b : float, mm
        Semi-axes along X and Y.
    offset : float, mm
        Outward offset (>= 0).
    phi : (n,) float, rad
        Angle of the outward normal; the offset curve has the same normal as
        the ellipse there.

    Returns
    -------
    points : (n, 2) float, mm
    tangents : (n, 2) float
        Unit tangents, counter-clockwise.
    """
    phi = np.asarray(phi, dtype=np.float64)
    t = np.arctan2(b * np.sin(phi), a * np.cos(phi))  # ellipse parameter with that normal
    normal = np.column_stack([np.cos(phi), np.sin(phi)])
    pts = np.column_stack([a * np.cos(t), b * np.sin(t)]) + offset * normal
    return pts, np.column_stack([-normal[:, 1], normal[:, 0]])


def _left(v: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.column_stack([-v[:, 1], v[:, 0]])


def _rowdot(u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.einsum("ij,ij->i", u, v)


def biarcs(
    p0: NDArray[np.float64],
    t0: NDArray[np.float64],
    p1: NDArray[np.float64],
    t1: NDArray[np.float64],
) -> tuple[NDArray[np.float64], ...]:
    """Equal-tangent-length biarcs between points with given tangents (vectorised).

    Parameters
    ----------
    p0, t0 : (n, 2) float
        Start points (mm) and unit tangents there.
    p1, t1 : (n, 2) float
        End points (mm) and unit tangents there.

    Returns
    -------
    joint : (n, 2) float, mm
        Point where the two arcs meet (tangent-continuously).
    c1, c2 : (n, 2) float, mm
        Centres of the first and second arc.
    r1, r2 : (n,) float, mm
        Signed radii: positive when the arc turns left (counter-clockwise).
    """
    v = p1 - p0
    vt = _rowdot(v, t0 + t1)
    vv = _rowdot(v, v)
    one_minus_c = 1.0 - _rowdot(t0, t1)
    # root of 2(1-c) d^2 + 2 (v.t) d - v.v = 0, in the form that stays exact as c -> 1
    d = vv / (vt + np.sqrt(vt**2 + 2.0 * one_minus_c * vv))
    joint = 0.5 * (p0 + d[:, None] * t0 + p1 - d[:, None] * t1)
    q1, q2 = joint - p0, joint - p1
    n0, n1 = _left(t0), _left(t1)
    r1 = _rowdot(q1, q1) / (2.0 * _rowdot(n0, q1))
    r2 = _rowdot(q2, q2) / (2.0 * _rowdot(n1, q2))
    return joint, p0 + r1[:, None] * n0, p1 + r2[:, None] * n1, r1, r2


def ellipse_contour(a: float, b: float, offset: float, chord_tol: float, arcs: bool) -> list[tuple]:
    """Closed counter-clockwise offset ellipse from its lowest point, within ``chord_tol``.

    Parameters
    ----------
    a, b : float, mm
        Ellipse semi-axes.
    offset : float, mm
        Outward offset.
    chord_tol : float, mm
        Largest distance between the written path and the exact curve.
    arcs : bool
        ``True``: fit tangent-continuous biarcs (G3), as a CAM system with arc
        fitting does, with pieces of equal turning angle; ``False``: G1 chords
        spaced so that each chord's deviation is about ``chord_tol``.

    Returns
    -------
    list of tuple
        ``("L", x, y)`` or ``("A", x, y, cx, cy, False)`` elements.
    """

    def test_points(phi: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
        # 9 points inside each piece [phi[k], phi[k+1]] of the exact curve, and their piece
        u = np.linspace(0.0, 1.0, 11)[1:-1]
        q, _ = offset_ellipse(a, b, offset, (phi[:-1, None] + np.diff(phi)[:, None] * u).ravel())
        return q, np.repeat(np.arange(len(phi) - 1), len(u))

    if arcs:
        n = 8
        while True:
            phi = np.linspace(-np.pi / 2, 1.5 * np.pi, n + 1)
            p, t = offset_ellipse(a, b, offset, phi)
            joint, c1, c2, r1, r2 = biarcs(p[:-1], t[:-1], p[1:], t[1:])
            q, piece = test_points(phi)
            first = _rowdot(q - joint[piece], (p[1:] - p[:-1])[piece]) < 0
            c = np.where(first[:, None], c1[piece], c2[piece])
            r = np.where(first, np.abs(r1[piece]), np.abs(r2[piece]))
            dev = np.abs(np.hypot(*(q - c).T) - r)
            if dev.max() <= chord_tol and np.all(r1 > 0) and np.all(r2 > 0):
                break
            n = math.ceil(n * 1.25)
        out: list[tuple] = []
        for k in range(n):
            out.append(("A", *joint[k], *c1[k], False))
            out.append(("A", *p[k + 1], *c2[k], False))
        return out
    # chords: one chord spans 2 acos(1 - tol / rho) of normal angle on a curve of radius rho
    fine = np.linspace(-np.pi / 2, 1.5 * np.pi, 4097)
    tt = np.arctan2(b * np.sin(fine), a * np.cos(fine))
    rho = (a**2 * np.sin(tt) ** 2 + b**2 * np.cos(tt) ** 2) ** 1.5 / (a * b) + offset
    density = 1.0 / (2.0 * np.arccos(1.0 - 0.95 * chord_tol / rho))
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(fine))])
    n = math.ceil(cum[-1])
    while True:
        phi = np.interp(np.linspace(0.0, cum[-1], n + 1), cum, fine)
        p, _ = offset_ellipse(a, b, offset, phi)
        q, piece = test_points(phi)
        chord = (p[1:] - p[:-1])[piece]
        rel = q - p[:-1][piece]
        dev = np.abs(chord[:, 0] * rel[:, 1] - chord[:, 1] * rel[:, 0]) / np.hypot(*chord.T)
        if dev.max() <= chord_tol:
            break
        n += max(1, n // 50)
    return [("L", x, y) for x, y in p[1:]]


def cavity_program(chords: bool, cav: Cavity = Cavity()) -> Program:
    """The Z-level finishing demo: pocket walls level by level, then the boss.

    Each level is a closed contour at constant Z, climb milled with a spindle
    turning clockwise (the pocket clockwise: G2 corners; the boss
    counter-clockwise: G3 arcs), from the middle of its lower side. Levels are
    joined by a straight G1 step-down in X Y Z (by a G1 off the wall then a G1
    down where the straight link would cut into the top edge); the two
    regions by a retract, a rapid and a 1000 mm/min plunge.

    Parameters
    ----------
    chords : bool
        ``False``: arcs (``zlevel_cavity``); ``True``: every arc as G1 chords
        within :data:`CHORD_TOL` (``zlevel_cavity_chords``).
    cav : Cavity
        Geometry and cutting data.

    Returns
    -------
    Program
    """
    z_floor = -cav.depth
    n_levels = round(cav.depth / cav.step_down)
    levels = -cav.step_down * np.arange(1, n_levels + 1)
    kw = dict(
        z_floor=z_floor, draft_deg=cav.draft_deg, fillet=cav.fillet, tool_radius=cav.tool_radius
    )
    u_pocket = tool_offset(levels, 0.0, **kw)
    boss_levels = levels[levels < cav.boss_top]
    u_boss = tool_offset(boss_levels, cav.boss_top, **kw)
    tol = CHORD_TOL if chords else None

    name = "zlevel_cavity_chords" if chords else "zlevel_cavity"
    how = (
        "all curves as G1 chords within 0.005 mm, as a CAM system without arc output"
        if chords
        else "G1 lines, G2 corner arcs, G3 arcs fitted on the boss within 0.005 mm"
    )
    p = Program(
        name,
        "Z-level finishing of a mould cavity, after Figure 10 of Tapie et al.",
        [
            f"pocket {cav.length:g} x {cav.width:g} mm at Z0, corner R{cav.corner:g}, "
            f"{cav.depth:g} mm deep, {cav.draft_deg:g} deg draft, floor fillet R{cav.fillet:g}",
            f"elliptical boss {2 * cav.boss_a:g} x {2 * cav.boss_b:g} mm at its top "
            f"Z{cav.boss_top:g}, same draft and fillet",
            f"tool: ball-end mill D{2 * cav.tool_radius:g}, Z is the tool tip, no tool change",
            f"step-down {cav.step_down:g} mm, climb milling, "
            f"F{cav.feed:g}, plunge F{PLUNGE_FEED:g}",
            how,
        ],
    )

    def zone(z: float, z_top: float) -> str:
        zc = z + cav.tool_radius
        th = math.radians(cav.draft_deg)
        if zc > z_top + cav.tool_radius * math.sin(th):
            return "top edge"
        if zc >= z_floor + cav.fillet - (cav.fillet - cav.tool_radius) * math.sin(th):
            return "wall"
        return "floor fillet"

    for region, zs, us in (("pocket walls", levels, u_pocket), ("boss", boss_levels, u_boss)):
        p.comment(f"region: {region}, {len(zs)} levels Z{fmt(zs[0])} to Z{fmt(zs[-1])}")
        for k, (z, u) in enumerate(zip(zs, us, strict=True)):
            if region == "boss":
                contour = ellipse_contour(cav.boss_a, cav.boss_b, u, CHORD_TOL, arcs=not chords)
                start_y = -(cav.boss_b + u)
                z_top = cav.boss_top
            else:
                contour = rounded_rectangle(
                    cav.length / 2 - u, cav.width / 2 - u, cav.corner - u, tol
                )
                start_y = -(cav.width / 2 - u)
                z_top = 0.0
            p.comment(f"level {k + 1} Z{fmt(z)}: {zone(z, z_top)}, offset {fmt(u)} mm")
            if k == 0:
                p.retract()
                p.rapid(x=0.0, y=start_y)
                p.line(z=z, feed=PLUNGE_FEED)
            else:
                # Along the top edge the ball-centre locus bulges away from the material
                # (a circle round the edge), so a straight X Y Z link would cut 0.01 mm
                # into the edge: there, move off the wall first, then down.
                z_mid = 0.5 * (zs[k - 1] + z)
                u_mid = tool_offset(np.array([z_mid]), z_top, **kw)[0]
                if u_mid > 0.5 * (us[k - 1] + u) + CHORD_TOL / 10:
                    p.line(0.0, start_y, feed=cav.feed)
                    p.line(z=z)
                else:
                    p.line(0.0, start_y, z, feed=cav.feed)  # straight step-down link
            p.path(contour, feed=cav.feed)
        p.retract()
    return p


# --- checking the written files ------------------------------------------------------------------

_WORD = r"[GXYZIJFMT]-?\d+(?:\.\d{1,4})?"
_BLOCK = re.compile(rf"^(?:\s*(?:\([^()]*\)|{_WORD}))*\s*$")
_WORDS = re.compile(r"([GXYZIJFMT])(-?\d+(?:\.\d{1,4})?)")


def check_program(path: Path) -> dict[str, int]:
    """Re-read a written program and check it independently of the writer.

    Checks: every line is empty, comments in parentheses (not nested) or
    G/X/Y/Z/I/J/F/M/T words with at most 4 decimals; no line reaches 256
    characters; the header names the generator and sets ``G21 G90 G17 G94
    G64``; every arc end point is within :data:`ARC_END_TOL` of its circle; no
    move has zero length; no feed move before an F word; the last line is
    ``M30``.

    Parameters
    ----------
    path : Path
        Program file.

    Returns
    -------
    dict of str to int
        Counts: ``lines``, ``G0``, ``G1``, ``G2``, ``G3``, ``moves`` (all four).

    Raises
    ------
    GenerationError
        On the first line that fails a check.
    """
    text = path.read_text(encoding="ascii")
    lines = text.split("\n")
    if lines[-1] == "":
        lines.pop()
    counts = {"lines": len(lines), "G0": 0, "G1": 0, "G2": 0, "G3": 0}
    pos = {"X": math.nan, "Y": math.nan, "Z": math.nan}
    motion, feed = None, None

    def fail(no: int, message: str) -> None:
        raise GenerationError(message, source=path.name, line=no, text=lines[no - 1])

    if not any(f"generated by {GENERATOR}" in s for s in lines[:8]):
        fail(1, "header does not name the generator")
    if "G21 G90 G17 G94 G64" not in lines[:10]:
        fail(1, "no G21 G90 G17 G94 G64 line in the header")
    if lines[-1] != "M30":
        fail(len(lines), "program does not end with M30")
    for no, line in enumerate(lines, 1):
        if len(line) > MAX_LINE:
            fail(no, f"line has {len(line)} characters")
        if not _BLOCK.match(line):
            fail(no, "not made of comments and G/X/Y/Z/I/J/F/M/T words")
        words = _WORDS.findall(re.sub(r"\([^()]*\)", "", line))
        target = dict(pos)
        ij = {}
        for letter, value in words:
            if letter == "G" and value in ("0", "1", "2", "3"):
                motion = "G" + value
            elif letter in "XYZ":
                target[letter] = float(value)
            elif letter in "IJ":
                ij[letter] = float(value)
            elif letter == "F":
                feed = float(value)
        if not any(letter in "XYZ" for letter, _ in words):
            continue
        if motion in ("G1", "G2", "G3") and feed is None:
            fail(no, "feed move before any F word")
        if all(not math.isnan(pos[a]) for a in "XYZ") and target == pos:
            fail(no, "zero-length move")
        if motion in ("G2", "G3"):
            if set(ij) != {"I", "J"} or target["Z"] != pos["Z"]:
                fail(no, "arc without both I and J, or not at constant Z")
            cx, cy = pos["X"] + ij["I"], pos["Y"] + ij["J"]
            r_start = math.hypot(ij["I"], ij["J"])
            miss = abs(math.hypot(target["X"] - cx, target["Y"] - cy) - r_start)
            if miss > ARC_END_TOL:
                fail(no, f"arc end point is {miss:.6f} mm off the circle")
        counts[motion] += 1
        pos = target
    counts["moves"] = sum(counts[g] for g in ("G0", "G1", "G2", "G3"))
    return counts


def build_all() -> list[Program]:
    """Every example program, in the order of the module docstring.

    Returns
    -------
    list of Program
    """
    return [
        *(fig1_program(f) for f in FIG1_FEEDS),
        fig3_program(),
        *(fig4_program(d) for d in FIG4_SPACINGS),
        cavity_program(chords=False),
        cavity_program(chords=True),
    ]


def main(argv: Sequence[str] | None = None) -> int:
    """Write every program into the output folder, check it, print a table of counts.

    Parameters
    ----------
    argv : sequence of str, optional
        Command-line arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0, or 1 after printing the first failed check.
    """
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--out",
        type=Path,
        default=Path(__file__).resolve().parent,
        help="output folder (default: the folder of this script)",
    )
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    try:
        rows = []
        for prog in build_all():
            path = args.out / f"{prog.name}.ngc"
            path.write_text(prog.text(), encoding="ascii", newline="\n")
            rows.append((path.name, check_program(path)))
    except GenerationError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    print(f"{'file':<30} {'lines':>6} {'G0':>4} {'G1':>6} {'G2':>5} {'G3':>5} {'moves':>6}")
    for name, c in rows:
        print(
            f"{name:<30} {c['lines']:>6} {c['G0']:>4} {c['G1']:>6} {c['G2']:>5} {c['G3']:>5} "
            f"{c['moves']:>6}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
