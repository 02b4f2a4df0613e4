"""A tool path sampled along its arc length, and projecting points onto it.

:meth:`core.model.toolpath.ToolPath.sample` builds a :class:`PathSamples`; measured traces
(:mod:`core.diagnosis.align`) and filtered predictions (:mod:`core.engine.predict`) use it
to find where a point lies on the path.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from core.model.tolerances import TOL

#: Path sampling step (mm) for projecting points on the path: measured samples
#: (:mod:`core.diagnosis.align`) and filtered predictions (:mod:`core.engine.predict`).
#: 0.05 mm keeps the nearest point within 25 um of the true projection.
PROJECTION_STEP = 0.05
#: Rows per block when projecting (bounded temporaries: rows x window x 3 floats).
PROJECT_BLOCK = 8192


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
        pts, s_p = self.points, self.s
        k_off = np.arange(-int(half_width / self.step), int(half_width / self.step) + 1)
        s = np.empty(q.shape[0])
        dist = np.empty(q.shape[0])
        for c in range(0, q.shape[0], PROJECT_BLOCK):
            part = slice(c, c + PROJECT_BLOCK)
            j = np.searchsorted(s_p, s_guess[part])
            cand = np.clip(j[:, None] + k_off[None, :], 0, s_p.size - 1)
            diff = pts[cand] - q[part][:, None, :]
            d2 = np.einsum("mkj,mkj->mk", diff, diff)
            # Points of two passes of the path that coincide (a plunge down the retract):
            # the one nearer the guess along the path.
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
