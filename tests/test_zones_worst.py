"""The worst point of every zone (core.view.zones._worst_points) against numpy's lexsort."""

from __future__ import annotations

import numpy as np

from core.view.zones import _worst_points


def _lexsort_heads(zone: np.ndarray, ratio: np.ndarray, n_z: int) -> np.ndarray:
    """The oracle: the first point of each zone in np.lexsort((ratio, zone)), -1 if none."""
    worst = np.full(n_z, -1, dtype=np.int64)
    if zone.size:
        order = np.lexsort((ratio, zone))
        zs = zone[order]
        head = np.ones(order.size, dtype=bool)
        head[1:] = zs[1:] != zs[:-1]
        worst[zs[head]] = order[head]
    return worst


def test_worst_point_by_hand():
    """Junctions in zones 0, 0, 2 and blocks in zones 0, 1, 2 (two runs). Zone 0: ratios
    0.5, 0.2 (junctions) and 0.2 (block): the lower, first in index order -> point 1. Zone 1:
    only NaN -> its point, 4. Zone 2: 0.9 (junction 2) and 0.9 (block 5): tie -> 2. Zone 3:
    none -> -1."""
    zone = np.array([0, 0, 2, 0, 1, 2])
    ratio = np.array([0.5, 0.2, 0.9, 0.2, np.nan, 0.9])
    assert _worst_points(zone, ratio, 4).tolist() == [1, 4, 2, -1]


def test_worst_point_agrees_with_lexsort_on_random_zones():
    """Two sorted runs of random zones with ties, -0.0, inf and NaN: the same heads as
    lexsort (which sorts NaN last, -0.0 equal to 0.0, ties by index)."""
    rng = np.random.default_rng(11)
    vals = np.array([0.0, -0.0, 0.25, 0.5, 0.5, 1.0, np.inf, np.nan])
    for t in range(3000):
        n_z = int(rng.integers(1, 10))
        zone = np.concatenate(
            [np.sort(rng.integers(0, n_z, rng.integers(0, 12))) for _ in range(2)]
        ).astype(np.int64)
        ratio = vals[rng.integers(0, vals.size, zone.size)] if t % 2 else rng.random(zone.size)
        assert np.array_equal(_worst_points(zone, ratio, n_z), _lexsort_heads(zone, ratio, n_z))
