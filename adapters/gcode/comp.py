"""Cutter radius compensation (G41/G42, G41.1/G42.1) as LinuxCNC's interpreter computes it.

With compensation on, the tool centre runs at the tool radius R to the left (G41) or right
(G42) of the programmed path, in the selected plane:

* **Entry** (the first move after G41/G42, a straight line): from the current point to the
  programmed end point pushed R sideways, perpendicular to the line from the current point
  to it (rs274ngc convert_straight_comp1; the move must be longer than R).
* **Lines and arcs** run on their offsets: lines shifted by R, arcs with the radius r - R
  (the tool inside the arc) or r + R (outside).
* **Corners**: where the offsets of two elements leave a gap (a convex corner, the tool on
  the outside), an arc of radius R around the programmed corner joins them; where they
  overlap (concave), both are cut back to their intersection.
* **Exit**: after G40 the next move runs from the compensated point to its programmed end.

With no radius known (no tool table entry, no ``--tool-radius``) the programmed path is
used with a warning: CAM programs that compensate "in control" for wear only program the
centre line and run with D0. The geometry is worked in the plane's two coordinates; moves
along the plane's normal keep the offset.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from core.model.tolerances import TOL

if TYPE_CHECKING:
    from adapters.gcode.control import Controller

Vec = tuple[float, float, float]
PLANES = {170: (0, 1, 2), 180: (2, 0, 1), 190: (1, 2, 0)}
#: In-plane lengths (mm) below this are no direction (a move along the plane's normal).
FLAT = TOL.direction


class CompError(Exception):
    pass


class Compensator:
    """The compensation state of a controller (see the module docstring)."""

    def __init__(self, ctl: Controller) -> None:
        self.ctl = ctl
        self.side = 0  # +1 left (G41), -1 right (G42), 0 off
        self.radius = 0.0
        self.first = False
        self.prog: Vec | None = None  # programmed end of the last move (machine coordinates)
        self.pending: dict[str, Any] | None = None  # the last offset element, not yet emitted
        self.warned = False

    @property
    def active(self) -> bool:
        return self.side != 0 and self.radius > 0

    # ------------------------------------------------------------------ switching
    def mode(self, code: int, words: dict[str, Any], radius: float | None) -> None:
        ctl = self.ctl
        if code == 400:
            self.flush()
            self.side = 0
            return
        if self.side != 0:
            raise CompError("cutter compensation is already on (G40 first)")
        self.side = 1 if code in (410, 411) else -1
        if code in (411, 421):  # G41.1/G42.1 D = the tool's diameter
            if "D" not in words:
                raise CompError(f"G{code / 10:g} without the tool diameter D")
            r: float | None = abs(words["D"]) * ctl.scale / 2.0
        else:
            r = radius
            if "D" in words and int(words["D"]) == 0:
                r = 0.0
        if r is None:
            if not self.warned:
                ctl.notes.add(
                    "cutter compensation G41/G42 without a known tool radius (no tool table "
                    "or --tool-radius): the programmed path is used",
                    ctl.line,
                )
                self.warned = True
            r = 0.0
        self.radius = r
        self.first = True
        self.pending = None
        self.prog = None

    # ------------------------------------------------------------------ geometry
    def _plane(self) -> tuple[int, int, int]:
        return PLANES[self.ctl.plane]

    def _uv(self, p: Vec) -> tuple[float, float]:
        i, j, _ = self._plane()
        return p[i], p[j]

    def _from_uv(self, u: float, v: float, w: float) -> Vec:
        i, j, k = self._plane()
        p = [0.0, 0.0, 0.0]
        p[i], p[j], p[k] = u, v, w
        return (p[0], p[1], p[2])

    def _normal_of(self, du: float, dv: float) -> tuple[float, float]:
        """The unit normal on the compensation side of direction (du, dv)."""
        n = math.hypot(du, dv)
        return (-dv / n * self.side, du / n * self.side)

    # ------------------------------------------------------------------ moves
    def line(self, kind: int, end: Vec, rot_end: Vec) -> None:
        ctl = self.ctl
        i, j, k = self._plane()
        R = self.radius
        if self.first:
            cu, cv = self._uv(ctl.pos)
            pu, pv = self._uv(end)
            dist = math.hypot(pu - cu, pv - cv)
            if dist <= R:
                raise CompError("cutter compensation entry move is not longer than the tool radius")
            nu, nv = self._normal_of(pu - cu, pv - cv)
            # queued, not emitted: a concave corner after it moves its end point
            self.pending = {
                "src": self._src(),
                "type": "line",
                "kind": kind,
                "start": (cu, cv),
                "end": (pu + R * nu, pv + R * nv),
                "w1": end[k],
                "rot": rot_end,
                "dir0": (pu - cu, pv - cv),
                "dir1": (pu - cu, pv - cv),
            }
            self.first = False
            self.prog = end
            return
        assert self.prog is not None
        pu, pv = self._uv(self.prog)
        eu, ev = self._uv(end)
        du, dv = eu - pu, ev - pv
        if math.hypot(du, dv) <= FLAT:
            # along the plane's normal: keep the offset
            self.flush()
            cur = ctl.pos
            ctl.add(kind, cur, self._from_uv(self._uv(cur)[0], self._uv(cur)[1], end[k]), rot_end)
            self.prog = end
            return
        nu, nv = self._normal_of(du, dv)
        start_off = (pu + R * nu, pv + R * nv)
        end_off = (eu + R * nu, ev + R * nv)
        element = {
            "src": self._src(),
            "type": "line",
            "kind": kind,
            "start": start_off,
            "end": end_off,
            "w1": end[k],
            "rot": rot_end,
            "dir0": (du, dv),
            "dir1": (du, dv),
        }
        self._join(element)
        self.prog = end

    def arc(self, kind: int, end: Vec, centre: Vec, normal: Vec, turns: int, rot_end: Vec) -> None:
        if self.first:
            raise CompError("cutter compensation entry move must be a straight line, not an arc")
        assert self.prog is not None
        i, j, k = self._plane()
        R = self.radius
        # the plane's normal and the arc's: the same or opposite (a mirrored frame)
        pn = self._from_uv(0.0, 0.0, 1.0)
        flip = sum(a * b for a, b in zip(pn, normal, strict=True)) < 0
        ccw = (kind == 3) != flip
        cu, cv = self._uv(centre)
        pu, pv = self._uv(self.prog)
        eu, ev = self._uv(end)
        r = math.hypot(pu - cu, pv - cv)
        # the tool is inside the arc when the compensation side is the centre's side
        inside = (self.side == 1) == ccw
        r_off = r - R if inside else r + R
        if r_off <= FLAT:
            raise CompError("tool radius not less than the arc's radius with compensation")
        s_ang = math.atan2(pv - cv, pu - cu)
        e_ang = math.atan2(ev - cv, eu - cu)
        start_off = (cu + r_off * math.cos(s_ang), cv + r_off * math.sin(s_ang))
        end_off = (cu + r_off * math.cos(e_ang), cv + r_off * math.sin(e_ang))
        turn = 1.0 if ccw else -1.0
        t0 = (-(pv - cv) * turn, (pu - cu) * turn)
        t1 = (-(ev - cv) * turn, (eu - cu) * turn)
        element = {
            "src": self._src(),
            "type": "arc",
            "kind": kind,
            "start": start_off,
            "end": end_off,
            "w1": end[k],
            "rot": rot_end,
            "centre": (cu, cv),
            "r": r_off,
            "ccw": ccw,
            "turns": turns,
            "normal": normal,
            "centre3": centre,
            "dir0": t0,
            "dir1": t1,
        }
        self._join(element)
        self.prog = end

    # ------------------------------------------------------------------ corners
    def _join(self, el: dict[str, Any]) -> None:
        """Queue ``el`` after the pending element, joining them at the corner."""
        ctl = self.ctl
        prev = self.pending
        cur = prev["end"] if prev else self._uv(ctl.pos)
        su, sv = el["start"]
        if math.hypot(su - cur[0], sv - cur[1]) > FLAT:
            prev_dir = prev["dir1"] if prev else el["dir0"]
            cross = prev_dir[0] * el["dir0"][1] - prev_dir[1] * el["dir0"][0]
            convex = cross * self.side < 0  # the path turns away from the tool's side
            x = None if convex or prev is None else _intersection(prev, el, cur)
            if x is not None and prev is not None:
                prev["end"] = x
                el["start"] = x
            else:
                self.flush()
                assert self.prog is not None
                corner: dict[str, Any] = {
                    "src": el["src"],  # a corner belongs to the block it leads into
                    "type": "arc" if convex else "line",
                    "start": cur,
                    "end": (su, sv),
                    "w1": None,
                    "rot": ctl.rot,
                    "centre": self._uv(self.prog),
                    "ccw": self.side == -1,
                    "turns": 0,
                }
                self._emit(corner)
        self.flush()
        self.pending = el

    def flush(self) -> None:
        if self.pending is not None:
            el = self.pending
            self.pending = None
            self._emit(el)

    def _src(self) -> tuple[int, int, int, int]:
        """The block an element comes from (it is emitted when the next one is known)."""
        ctl = self.ctl
        return (ctl.line, ctl.file, ctl.call, ctl.block_number)

    def _emit(self, el: dict[str, Any]) -> None:
        ctl = self.ctl
        now = self._src()
        ctl.line, ctl.file, ctl.call, ctl.block_number = el["src"]
        try:
            self._add(el)
        finally:
            ctl.line, ctl.file, ctl.call, ctl.block_number = now

    def _add(self, el: dict[str, Any]) -> None:
        ctl = self.ctl
        i, j, k = self._plane()
        cur = ctl.pos
        w1 = el["w1"] if el["w1"] is not None else cur[k]
        end = self._from_uv(el["end"][0], el["end"][1], w1)
        if el["type"] == "line":
            ctl.add(el.get("kind", 1), cur, end, el["rot"])
            return
        if math.dist(cur, end) <= FLAT and el.get("turns", 0) == 0 and el["w1"] is None:
            return  # a corner arc of no length (a tangent join)
        cu, cv = el["centre"]
        centre = self._from_uv(cu, cv, cur[k])
        normal = self._from_uv(0.0, 0.0, 1.0)
        kind = 3 if el["ccw"] else 2
        ctl.add(kind, cur, end, el["rot"], center=centre, normal=normal, turns=el["turns"])


def _intersection(a: dict[str, Any], b: dict[str, Any], near: tuple[float, float]):
    """The intersection of two offset elements (lines or arcs) nearest ``near``, or None.

    A line is taken as the line through its end (the earlier element ``a``) or its start
    (the later ``b``) parallel to its *programmed* direction, as rs274ngc's concave corner
    does (convert_straight_comp2: the end moves back by R / tan(half the corner) along the
    programmed direction): the same for ordinary lines, not for the entry move, whose
    offset is not parallel to its programmed line."""
    if a["type"] == "line" and b["type"] == "line":
        p, r = a["end"], a["dir1"]
        q, s = b["start"], b["dir0"]
        den = r[0] * s[1] - r[1] * s[0]
        if abs(den) <= TOL.float_slack * math.hypot(*r) * math.hypot(*s):
            return None  # parallel
        t = ((q[0] - p[0]) * s[1] - (q[1] - p[1]) * s[0]) / den
        return (p[0] + t * r[0], p[1] + t * r[1])
    pts: list[tuple[float, float]] = []
    if a["type"] == "arc" and b["type"] == "arc":
        pts = _circles(a["centre"], a["r"], b["centre"], b["r"])
    else:
        if a["type"] == "line":
            ar = b
            base, d = a["end"], a["dir1"]
        else:
            ar = a
            base, d = b["start"], b["dir0"]
        other = (base[0] + d[0], base[1] + d[1])
        pts = _line_circle(base, other, ar["centre"], ar["r"])
    if not pts:
        return None
    return min(pts, key=lambda x: math.hypot(x[0] - near[0], x[1] - near[1]))


def _line_circle(p, q, c, r):
    dx, dy = q[0] - p[0], q[1] - p[1]
    fx, fy = p[0] - c[0], p[1] - c[1]
    a = dx * dx + dy * dy
    b = 2 * (fx * dx + fy * dy)
    cc = fx * fx + fy * fy - r * r
    disc = b * b - 4 * a * cc
    if a == 0 or disc < 0:
        return []
    sq = math.sqrt(disc)
    return [(p[0] + t * dx, p[1] + t * dy) for t in ((-b - sq) / (2 * a), (-b + sq) / (2 * a))]


def _circles(c0, r0, c1, r1):
    d = math.hypot(c1[0] - c0[0], c1[1] - c0[1])
    if d == 0 or d > r0 + r1 or d < abs(r0 - r1):
        return []
    a = (r0 * r0 - r1 * r1 + d * d) / (2 * d)
    h = math.sqrt(max(r0 * r0 - a * a, 0.0))
    mx = c0[0] + a * (c1[0] - c0[0]) / d
    my = c0[1] + a * (c1[1] - c0[1]) / d
    ox, oy = -(c1[1] - c0[1]) / d * h, (c1[0] - c0[0]) / d * h
    return [(mx + ox, my + oy), (mx - ox, my - oy)]
