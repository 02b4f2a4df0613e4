"""A tool path sampled along its arc length, and projecting points onto it.

:meth:`core.model.toolpath.ToolPath.sample` builds a :class:`PathSamples`; measured traces
(:mod:`core.diagnosis.align`) and filtered predictions (:mod:`core.engine.predict`) use it
to find where a point lies on the path.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from core.model.jit import compiled
from core.model.pieces import SPLIT, side_by_side, two_cores
from core.model.tolerances import TOL

#: Path sampling step (mm) for projecting points on the path: measured samples
#: (:mod:`core.diagnosis.align`) and filtered predictions (:mod:`core.engine.predict`).
#: 0.05 mm keeps the nearest point within 25 um of the true projection; the foot on the
#: chords next to it (:meth:`PathSamples.project_near`) closes the rest.
PROJECTION_STEP = 0.05
#: Rows per block when projecting (bounded temporaries: rows x window x 3 floats).
PROJECT_BLOCK = 8192
#: Rows per block of :meth:`PathSamples.project_near` (a few (rows,) temporaries per offset:
#: 128 kB each at 16384, a block's working set in a core's cache; 6-10 % less CPU than 65536
#: on the diagnose benchmark's projections).
NEAR_BLOCK = 16384
#: :meth:`PathSamples.project_near` looks at every COARSE-th candidate first; NEAR_SLACK (mm)
#: covers the rounding of the distances it compares.
COARSE = 5
NEAR_SLACK = 1e-9
#: :meth:`PathSamples.project_near` first looks at the NEAR_FIRST points on either side of
#: the guess (the nearest is one of them for 98 % of a filtered prediction's points); that
#: is the answer where every other point of the window is certainly further away: those
#: CLEAR_FROM or more points from it along the path, by their distance to it
#: (:meth:`PathSamples._clearance`), those nearer by having been looked at.
NEAR_FIRST = 3
CLEAR_FROM = 2
#: ... where it pays: the first look costs 2 NEAR_FIRST + 1 distances a point, the window's
#: search ~17, so a block of points takes it where it answers for NEAR_WORTH of every
#: NEAR_PROBE-th point (a servo lag of 0.2 s puts the filtered positions a millimetre off
#: the path, where it answers for few).
NEAR_PROBE = 64
NEAR_WORTH = 0.5
#: Relative margin on the polyline lengths that bound distances along the path (their sums'
#: rounding).
REACH_SLACK = 1e-12
#: Bound on the rounding of one merge of :func:`isotonic`'s pool, relative to the largest
#: |value| (a weighted mean of two: two products, a sum and a quotient, ~4 units in the last
#: place, 2^-52 each).
POOL_ROUNDING = 4 * 2.0**-52


def _sum3(x: NDArray[np.float64], y: NDArray[np.float64], z: NDArray[np.float64]) -> NDArray:
    """x + y + z in the order numpy's einsum takes over the rows of an (m, 3) array,
    (x + z) + y: column-wise sums of products give the same bits as the row-wise einsums
    (:meth:`PathSamples._project_near_gathered`; the row-wise foot the drawn10 and drawn11
    benchmark sets were scored with)."""
    return (x + z) + y


@dataclass(frozen=True, eq=False)
class PathSamples:
    """Points along a tool path, about every ``step`` mm (each move's ends included).

    Attributes
    ----------
    points : (p, 3) float, mm
    s : (p,) float, mm
        Arc length of each point from the program start (non-decreasing).
    move : (p,) int
        Move each point lies on.
    step : float, mm
        The sampling step (at most; each move gets ceil(length / step) intervals).
    """

    points: NDArray[np.float64]
    s: NDArray[np.float64]
    move: NDArray[np.int64]
    step: float

    @cached_property
    def columns(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """x, y and z of the points, each contiguous."""
        return tuple(np.ascontiguousarray(self.points[:, j]) for j in range(3))  # type: ignore[return-value]

    def project_near(
        self, q: ArrayLike, s_guess: ArrayLike, half_width: float = 1.0
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Arc length and distance of the projection of each of ``q`` on the path: the
        nearest path point among those within +-``half_width`` mm of arc length of its
        guess (the guess decides which pass of the path, the projection where on it), then
        the foot on the nearer of the two chords next to it (:meth:`_between`).

        Parameters
        ----------
        q : (m, 3) float, mm
        s_guess : (m,) float, mm
        half_width : float, mm

        Returns
        -------
        s : (m,) float, mm
        distance : (m,) float, mm
        """
        q = np.asarray(q, dtype=np.float64)
        s_guess = np.asarray(s_guess, dtype=np.float64)
        if q.ndim != 2 or q.shape[1] != 3 or s_guess.shape != (q.shape[0],):
            raise ValueError(
                f"q must have shape (m, 3) and s_guess (m,), got {q.shape} and {s_guess.shape}"
            )
        s_p = self.s
        half = int(half_width / self.step)
        if not (np.isfinite(q).all() and np.isfinite(s_guess).all()):
            return self._project_near_gathered(q, s_guess, half)
        kernels = compiled()
        if kernels is not None:  # the same search point by point (core.model.jit)
            px, py, pz = self.columns
            q = np.ascontiguousarray(q)
            s_guess = np.ascontiguousarray(s_guess)
            j = kernels.sorted_places(np.ascontiguousarray(s_p), s_guess)
            path = (
                px,
                py,
                pz,
                np.ascontiguousarray(s_p),
                self._reach,
                self._clearance(half + NEAR_FIRST) if half >= NEAR_FIRST else np.empty(0),
                half,
                (NEAR_BLOCK, NEAR_PROBE, NEAR_FIRST, CLEAR_FROM, COARSE),
                (NEAR_WORTH, NEAR_SLACK, TOL.pass_tie),
            )
            # two halves on two threads (a nogil kernel), cut between two of its blocks:
            # each block of points decides on its own how it searches, so the same search
            h = q.shape[0] // 2 // NEAR_BLOCK * NEAR_BLOCK
            if h < SPLIT or not two_cores():
                return kernels.project_near(q, s_guess, j, *path)
            (s1, d1), (s2, d2) = side_by_side(
                lambda: kernels.project_near(q[:h], s_guess[:h], j[:h], *path),
                lambda: kernels.project_near(q[h:], s_guess[h:], j[h:], *path),
            )
            return np.concatenate([s1, s2]), np.concatenate([d1, d2])
        # The nearest few points first, where that pays and tells (:meth:`_near_first`);
        # elsewhere the window (:meth:`_window`): every COARSE-th offset of it for all
        # points, then the offsets between two of them only for the points they might be
        # nearer for: by the triangle inequality none of them is nearer than half (sum of
        # the two distances - the path length between the two points). Ties go to the
        # earlier offset, as an argmin over the whole window would: the same point as
        # before.
        s = np.empty(q.shape[0])
        dist = np.empty(q.shape[0])
        for c in range(0, q.shape[0], NEAR_BLOCK):
            part = slice(c, c + NEAR_BLOCK)
            qx, qy, qz = q[part, 0], q[part, 1], q[part, 2]
            guess = s_guess[part]
            j = np.searchsorted(s_p, guess)
            probe = slice(None, None, NEAR_PROBE)
            _, _, ok = self._near_first(
                j[probe], qx[probe], qy[probe], qz[probe], guess[probe], half
            )
            if ok.size and ok.mean() >= NEAR_WORTH:
                best_i, best_d2, ok = self._near_first(j, qx, qy, qz, guess, half)
            else:
                best_i, best_d2 = np.empty(j.size, dtype=np.int64), np.empty(j.size)
                ok = np.zeros(j.size, dtype=bool)
            rest = np.flatnonzero(~ok)
            if rest.size:
                best_i[rest], best_d2[rest] = self._window(
                    j[rest], qx[rest], qy[rest], qz[rest], guess[rest], half
                )
            s[part], dist[part] = self._between(q[part], best_i, best_d2)
        return s, dist

    def _between(
        self, q: NDArray[np.float64], i: NDArray[np.int64], d2: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Arc length and distance of the foot of each of ``q`` on the path between its
        nearest path point ``i`` (squared distance ``d2``) and the neighbour on either side:
        the nearer foot on the two chords, its arc length interpolated along the chord. The
        points are ``step`` apart, and the nearest point alone is up to step / 2 off along
        the path: 25 um, a 10 mm/s error in the speed 25 um before a stop at 2 m/s^2
        (sqrt(2 a d)). Where a chord has no length or the foot is not finite, the point."""
        s_p = self.s
        last = s_p.size - 1
        px, py, pz = self.columns
        qx, qy, qz = q[:, 0], q[:, 1], q[:, 2]
        s = s_p[i]
        best = d2.copy()
        # (in place where the values allow: the same operations on the same numbers)
        for a in (np.maximum(i - 1, 0), i):
            b = np.minimum(a + 1, last)
            ax, ay, az = px[a], py[a], pz[a]
            abx, aby, abz = px[b], py[b], pz[b]
            abx -= ax
            aby -= ay
            abz -= az
            aqx, aqy, aqz = qx - ax, qy - ay, qz - az
            l2 = _sum3(abx * abx, aby * aby, abz * abz)
            u = _sum3(aqx * abx, aqy * aby, aqz * abz)
            with np.errstate(invalid="ignore", divide="ignore"):
                u /= l2
            np.clip(u, 0.0, 1.0, out=u)
            abx *= u
            aqx -= abx
            aby *= u
            aqy -= aby
            abz *= u
            aqz -= abz
            aqx *= aqx
            aqy *= aqy
            aqz *= aqz
            e2 = _sum3(aqx, aqy, aqz)
            better = l2 > 0.0
            better &= e2 < best
            # s_p[a] + u (s_p[b] - s_p[a])
            s_a, s_b = s_p[a], s_p[b]
            s_b -= s_a
            s_b *= u
            s_b += s_a
            np.copyto(s, s_b, where=better)
            np.copyto(best, e2, where=better)
        return s, np.sqrt(best)

    def _near_first(
        self,
        j: NDArray[np.int64],
        qx: NDArray[np.float64],
        qy: NDArray[np.float64],
        qz: NDArray[np.float64],
        guess: NDArray[np.float64],
        half: int,
    ) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.bool_]]:
        """The nearest (by :meth:`_key`, ties to the earlier point) of the NEAR_FIRST points
        on either side of path point ``j``, its squared distance, and where it is the
        nearest of the whole window of ``half`` points on either side: the points within
        CLEAR_FROM - 1 of it were looked at, and every other is further from it than
        CLEAR_FROM points' :meth:`_clearance`, hence (triangle inequality) from ``q``
        further than that minus its distance -- kept clear of the best key by NEAR_SLACK
        (the rounding of the distances compared), as :meth:`project_near` bounds."""
        last = self.s.size - 1
        n = j.size
        if half < NEAR_FIRST:
            return np.zeros(n, dtype=np.int64), np.zeros(n), np.zeros(n, dtype=bool)
        best_key, best_d2, best_o = self._best_of(
            range(-NEAR_FIRST, NEAR_FIRST + 1), j, qx, qy, qz, guess
        )
        best_i = self._clipped(j + best_o)
        # the points within CLEAR_FROM - 1 of the best (on the path) were looked at
        seen_lo = np.maximum(j - NEAR_FIRST, 0)
        seen_hi = np.minimum(j + NEAR_FIRST, last)
        near = CLEAR_FROM - 1
        ok = np.maximum(best_i - near, 0) >= seen_lo
        ok &= np.minimum(best_i + near, last) <= seen_hi
        # the window's others: from j +-half, at most half + NEAR_FIRST points from the best
        low = self._clearance(half + NEAR_FIRST)[best_i] - np.sqrt(best_d2) - NEAR_SLACK
        ok &= (low > 0) & (low * low > best_key)
        return best_i, best_d2, ok

    def _clearance(self, reach: int) -> NDArray[np.float64]:
        """(p,) every point's distance to the nearest point CLEAR_FROM to ``reach`` points
        away along the path (inf where there is none); kept per ``reach``."""
        hit = self._clearances.get(reach)
        if hit is None:
            pts = self.points
            c2 = np.full(pts.shape[0], np.inf)
            for o in range(CLEAR_FROM, min(reach, pts.shape[0] - 1) + 1):
                d = pts[o:] - pts[:-o]
                d2 = np.einsum("ij,ij->i", d, d)
                np.minimum(c2[:-o], d2, out=c2[:-o])
                np.minimum(c2[o:], d2, out=c2[o:])
            hit = self._clearances[reach] = np.sqrt(c2)
        return hit

    @cached_property
    def _clearances(self) -> dict[int, NDArray[np.float64]]:
        return {}

    def _window(
        self,
        j: NDArray[np.int64],
        qx: NDArray[np.float64],
        qy: NDArray[np.float64],
        qz: NDArray[np.float64],
        guess: NDArray[np.float64],
        half: int,
    ) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        """The nearest point (by :meth:`_key`, ties to the earlier point) of the window of
        ``half`` points on either side of path point ``j``, and its squared distance."""
        coarse = list(range(-half, half + 1, COARSE))
        if coarse[-1] != half:
            coarse.append(half)
        reach = self._reach
        seen: list[NDArray] = []
        best_key, best_d2, best_o = self._best_of(coarse, j, qx, qy, qz, guess, seen)
        for (o1, o2), d1, d2 in zip(
            zip(coarse[:-1], coarse[1:], strict=True), seen[:-1], seen[1:], strict=True
        ):
            if o2 - o1 < 2:
                continue
            # (reach at the interval's first point, j + o1 clipped to the path)
            low = 0.5 * (d1 + d2 - np.take(reach, j + o1, mode="clip")) - NEAR_SLACK
            rows = np.flatnonzero(~((low > 0) & (low * low > best_key)))
            if rows.size:
                best = (best_key, best_d2, best_o)
                self._fill(rows, o1, o2, j, qx, qy, qz, guess, best)
        return self._clipped(j + best_o), best_d2

    def _fill(
        self,
        rows: NDArray[np.intp],
        o1: int,
        o2: int,
        j: NDArray[np.int64],
        qx: NDArray[np.float64],
        qy: NDArray[np.float64],
        qz: NDArray[np.float64],
        guess: NDArray[np.float64],
        best: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]],
    ) -> None:
        """The offsets ``o1`` + 1 .. ``o2`` - 1 tried for ``rows``: their ``best`` key,
        squared distance and offset updated in place (ties to the earlier offset), the
        rows' own copies offset by offset, written back once."""
        best_key, best_d2, best_o = best
        jr, qxr, qyr, qzr, gr = j[rows], qx[rows], qy[rows], qz[rows], guess[rows]
        bk, bd, bo = best_key[rows], best_d2[rows], best_o[rows]
        at = np.empty(rows.size, dtype=np.int64)
        for off in range(o1 + 1, o2):
            key, d2r = self._key(np.add(jr, off, out=at), qxr, qyr, qzr, gr)
            better = key < bk
            better |= (key == bk) & (off < bo)
            np.copyto(bk, key, where=better)
            np.copyto(bd, d2r, where=better)
            np.copyto(bo, off, where=better)
        best_key[rows], best_d2[rows], best_o[rows] = bk, bd, bo

    def _clipped(self, at: NDArray[np.int64]) -> NDArray[np.int64]:
        """Path point indices ``at`` clipped to the path, in place."""
        np.maximum(at, 0, out=at)
        return np.minimum(at, self.s.size - 1, out=at)

    def _best_of(
        self,
        offsets: Sequence[int],
        j: NDArray[np.int64],
        qx: NDArray[np.float64],
        qy: NDArray[np.float64],
        qz: NDArray[np.float64],
        guess: NDArray[np.float64],
        seen: list[NDArray] | None = None,
    ) -> tuple[NDArray, NDArray, NDArray[np.int64]]:
        """The nearest (by :meth:`_key`, ties to the earlier offset) of the path points
        ``j + offsets`` (clipped to the path): its key, squared distance and offset;
        ``seen`` gets every offset's distances."""
        best_key = best_d2 = np.empty(0)
        best_o = np.full(j.size, offsets[0])
        at = np.empty(j.size, dtype=np.int64)
        better = np.empty(j.size, dtype=bool)
        for off in offsets:
            key, d2 = self._key(np.add(j, off, out=at), qx, qy, qz, guess)
            if seen is not None:
                seen.append(np.sqrt(d2))
            if off == offsets[0]:
                best_key, best_d2 = key, d2
                continue
            np.less(key, best_key, out=better)
            np.copyto(best_key, key, where=better)
            np.copyto(best_d2, d2, where=better)
            np.copyto(best_o, off, where=better)
        return best_key, best_d2, best_o

    def _key(
        self,
        at: NDArray[np.int64],
        qx: NDArray[np.float64],
        qy: NDArray[np.float64],
        qz: NDArray[np.float64],
        guess: NDArray[np.float64],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """What :meth:`project_near` minimises for the path points ``at`` (clipped to the
        path): squared distance plus the pass tie-break, and the squared distance."""
        px, py, pz = self.columns
        dx = np.take(px, at, mode="clip")
        dx -= qx
        dy = np.take(py, at, mode="clip")
        dy -= qy
        dz = np.take(pz, at, mode="clip")
        dz -= qz
        dx *= dx
        dy *= dy
        dz *= dz
        d2 = _sum3(dx, dy, dz)
        # Points of two passes of the path that coincide (a plunge down the retract): the
        # one nearer the guess along the path.
        tie = np.take(self.s, at, mode="clip")
        tie -= guess
        tie *= TOL.pass_tie
        tie *= tie
        tie += d2
        return tie, d2

    @cached_property
    def _reach(self) -> NDArray[np.float64]:
        """(p,) the length of the polyline through points i .. i + COARSE (at least the
        distance from point i to any of them)."""
        seg = np.sqrt(np.sum(np.diff(self.points, axis=0) ** 2, axis=1))
        seg = np.concatenate([seg, np.zeros(COARSE)])
        out = np.zeros(self.points.shape[0])
        for k in range(COARSE):
            out += seg[k : k + out.size]
        return out * (1.0 + REACH_SLACK)

    def _project_near_gathered(
        self, q: NDArray[np.float64], s_guess: NDArray[np.float64], half: int
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`project_near` over the whole window at once (argmin's NaN rules: used
        where a point or a guess is not finite)."""
        pts, s_p = self.points, self.s
        k_off = np.arange(-half, half + 1)
        s = np.empty(q.shape[0])
        dist = np.empty(q.shape[0])
        for c in range(0, q.shape[0], PROJECT_BLOCK):
            part = slice(c, c + PROJECT_BLOCK)
            j = np.searchsorted(s_p, s_guess[part])
            cand = np.clip(j[:, None] + k_off[None, :], 0, s_p.size - 1)
            diff = pts[cand] - q[part][:, None, :]
            d2 = np.einsum("mkj,mkj->mk", diff, diff)
            ds = s_p[cand] - s_guess[part][:, None]
            best = np.argmin(d2 + (TOL.pass_tie * ds) ** 2, axis=1)
            rows = np.arange(best.size)
            s[part], dist[part] = self._between(q[part], cand[rows, best], d2[rows, best])
        return s, dist


def isotonic(y: ArrayLike) -> NDArray[np.float64]:
    """Least-squares non-decreasing fit of ``y`` (pool adjacent violators): arc lengths of
    samples in time, made to run forward only.

    Pooling never crosses a place where everything before is clearly below everything after
    (the largest value before + the pooled means' rounding < the smallest after - it): the
    stretches between such places are pooled each on its own, one after the other, as one
    pass over all of ``y`` would pool them (the same operations on the same numbers), and
    a stretch of one sample is that sample."""
    y = np.asarray(y, dtype=np.float64)
    if y.size == 0 or np.all(np.diff(y) >= 0):
        return y.copy()
    out = y.copy()
    # A pooled mean is within POOL_ROUNDING x (its merges) x max |y| of the exact mean of
    # its samples, hence within that of the range of the values it pools.
    with np.errstate(invalid="ignore", over="ignore"):
        margin = 2.0 * POOL_ROUNDING * y.size * float(np.max(np.abs(y)))
        below = np.maximum.accumulate(y)[:-1]
        above = np.minimum.accumulate(y[::-1])[::-1][1:]
        cut = above - below > margin  # (False where a value is not finite)
    edges = np.concatenate([[0], np.flatnonzero(cut) + 1, [y.size]])
    for k in np.flatnonzero(np.diff(edges) > 1).tolist():
        a, b = int(edges[k]), int(edges[k + 1])
        out[a:b] = _pooled(y[a:b])
    return out


def _pooled(y: NDArray[np.float64]) -> NDArray[np.float64]:
    """:func:`isotonic` of ``y`` in one pass (the pool of adjacent violators)."""
    vals: list[float] = []
    counts: list[int] = []
    for v in y.tolist():
        vals.append(v)
        counts.append(1)
        while len(vals) > 1 and vals[-2] > vals[-1]:
            c = counts[-2] + counts[-1]
            vals[-2] = (vals[-2] * counts[-2] + vals[-1] * counts[-1]) / c
            counts[-2] = c
            vals.pop()
            counts.pop()
    return np.repeat(np.array(vals), np.array(counts))
