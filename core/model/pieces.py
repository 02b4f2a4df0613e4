"""Work over the moves in pieces: bounded temporaries on million-move programs.

An elementwise computation gives the same numbers whether it runs over all moves at once or
over consecutive pieces of them; in pieces, its temporaries are a few MB instead of several
copies of every column.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np
from numpy.typing import NDArray

#: Moves per piece (2^18: a float64 temporary of a piece is 2 MB).
PIECE = 1 << 18


def pieces(n: int, size: int = PIECE) -> Iterator[slice]:
    """Consecutive slices of at most ``size`` covering ``0..n``."""
    for i in range(0, n, size):
        yield slice(i, min(i + size, n))


def piecewise(n: int, dtype: type, f: Callable[[slice], NDArray], size: int = PIECE) -> NDArray:
    """``f`` over ``0..n`` piece by piece into one (n,) array of ``dtype``: ``f`` is
    elementwise, so the values are those of ``f`` over all of it at once."""
    out: NDArray = np.empty(n, dtype=dtype)
    for s in pieces(n, size):
        out[s] = f(s)
    return out
