"""Elementwise helpers over move columns that numpy has, made cheaper where most entries
need nothing done: the same values as numpy's."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def nan_to_num(
    x: ArrayLike,
    *,
    copy: bool = True,
    nan: float = 0.0,
    posinf: float | None = None,
    neginf: float | None = None,
) -> NDArray:
    """``np.nan_to_num`` of a float64 array, the same values: only the entries that are not
    finite go through numpy's (on a path, a few of a million: three passes over the column,
    not eight). ``copy=False`` replaces them in place, as numpy's. Other dtypes, 0-d input
    and a strided array to change in place are numpy's own."""
    a = np.asarray(x)
    if a.dtype != np.float64 or a.ndim == 0 or not (copy or a.flags.c_contiguous):
        return np.nan_to_num(x, copy=copy, nan=nan, posinf=posinf, neginf=neginf)
    out = a.copy() if copy else a
    flat = out.reshape(-1)  # (a view: the copy is contiguous, numpy's in-place input too)
    odd = np.flatnonzero(~np.isfinite(flat))
    if odd.size:
        flat[odd] = np.nan_to_num(flat[odd], nan=nan, posinf=posinf, neginf=neginf)
    return out
