"""A tool path sampled along its arc length, and projecting points onto it.

:meth:`core.model.toolpath.ToolPath.sample` builds a :class:`PathSamples`; measured traces
(:mod:`core.diagnosis.align`) and filtered predictions (:mod:`core.engine.predict`) use it
to find where a point lies on the path.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from core.model.tolerances import TOL

#: Path sampling step (mm) for projecting points on the path: measured samples
#: (:mod:`core.diagnosis.align`) and filtered predictions (:mod:`core.engine.predict`).
#: 0.05 mm keeps the nearest point within 25 um of the true projection.
PROJECTION_STEP = 0.05
#: Rows per block when projecting (bounded temporaries: rows x window x 3 floats).
PROJECT_BLOCK = 8192
#: Rows per block of :meth:`PathSamples.project_near` (a few (rows,) temporaries per offset).
NEAR_BLOCK = 65536


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
    def _columns(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """x, y and z of the points, each contiguous."""
        return tuple(np.ascontiguousarray(self.points[:, j]) for j in range(3))  # type: ignore[return-value]

    def project_near(
        self, q: ArrayLike, s_guess: ArrayLike, half_width: float = 1.0
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Arc length and distance of the nearest path point to each of ``q`` among those
        within +-``half_width`` mm of arc length of its guess: the guess decides which pass
        of the path, the projection where on it.

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
        # Offset by offset over the window of candidates, keeping the first nearest (as an
        # argmin over the window would): no (rows, window, 3) temporaries.
        px, py, pz = self._columns
        last = s_p.size - 1
        s = np.empty(q.shape[0])
        dist = np.empty(q.shape[0])
        for c in range(0, q.shape[0], NEAR_BLOCK):
            part = slice(c, c + NEAR_BLOCK)
            qx, qy, qz = q[part, 0], q[part, 1], q[part, 2]
            guess = s_guess[part]
            j = np.searchsorted(s_p, guess)
            best_key = best_d2 = np.empty(0)
            best_i = np.empty(0, dtype=np.int64)
            for off in range(-half, half + 1):
                cand = np.clip(j + off, 0, last)
                dx = px[cand] - qx
                dy = py[cand] - qy
                dz = pz[cand] - qz
                # (the order of the sum the gathered einsum takes: the same values)
                d2 = (dx * dx + dz * dz) + dy * dy
                # Points of two passes of the path that coincide (a plunge down the
                # retract): the one nearer the guess along the path.
                ds = s_p[cand] - guess
                key = d2 + (TOL.pass_tie * ds) ** 2
                if off == -half:
                    best_key, best_d2, best_i = key, d2, cand
                    continue
                better = key < best_key
                best_key[better] = key[better]
                best_d2[better] = d2[better]
                best_i[better] = cand[better]
            s[part] = s_p[best_i]
            dist[part] = np.sqrt(best_d2)
        return s, dist

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
            s[part] = s_p[cand[rows, best]]
            dist[part] = np.sqrt(d2[rows, best])
        return s, dist


def isotonic(y: ArrayLike) -> NDArray[np.float64]:
    """Least-squares non-decreasing fit of ``y`` (pool adjacent violators): arc lengths of
    samples in time, made to run forward only."""
    y = np.asarray(y, dtype=np.float64)
    if y.size == 0 or np.all(np.diff(y) >= 0):
        return y.copy()
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
