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


def same_bits(a: NDArray, b: NDArray) -> bool:
    """Whether two arrays have one dtype, one shape and the same bytes (NaNs and signed
    zeros included: equal only where identical). Eight-byte items are compared as int64
    without a copy, others byte by byte."""
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    if a.dtype.itemsize == 8:
        return bool(np.array_equal(a.view(np.int64), b.view(np.int64)))
    x = np.ascontiguousarray(a).reshape(-1).view(np.uint8)
    y = np.ascontiguousarray(b).reshape(-1).view(np.uint8)
    return bool(np.array_equal(x, y))


def put_where(dst: NDArray, src: NDArray | float, where: NDArray) -> NDArray:
    """``np.copyto(dst, src, where=where)`` of 1-d arrays (``src`` an array of ``dst``'s
    shape or a number), the same values: through the indices of ``where``, which numpy's
    masked copy walks element by element (on a mask without long runs, 8 ns an element
    against 1-2 here). Returns ``dst``."""
    at = np.flatnonzero(where)
    if at.size:
        dst[at] = src[at] if isinstance(src, np.ndarray) else src
    return dst


def select(cond: NDArray, x: NDArray, y: NDArray) -> NDArray:
    """``np.where(cond, x, y)`` of 1-d float arrays that are the caller's scratch, written
    into one of them (returned): the side ``cond`` picks less often goes through its
    indices (:func:`put_where`), so a mask that is nearly all one way costs little."""
    if 2 * np.count_nonzero(cond) >= cond.size:
        return put_where(x, y, ~cond)
    return put_where(y, x, cond)


def unique(x: ArrayLike) -> NDArray:
    """``np.unique(x)`` (flattened, sorted, each value once) of an integer or bool array,
    the same array: numpy 2.4's own imports ``numpy.ma`` on its first call, to ask whether
    its input is masked (20-30 ms of every ``ncperf analyze``). Other dtypes (NaNs, signed
    zeros) are numpy's own."""
    a = np.asarray(x)
    if a.dtype.kind not in "biu":
        return np.unique(a)
    a = np.sort(a, axis=None)
    keep = np.empty(a.size, dtype=bool)
    keep[:1] = True
    np.not_equal(a[1:], a[:-1], out=keep[1:])
    return a[keep]


#: Test sets up to this size are compared one value at a time (:func:`isin`), as numpy
#: does with small ones; larger ones are sorted and searched.
ISIN_LOOP = 16


def isin(element: ArrayLike, test: ArrayLike) -> NDArray[np.bool_]:
    """``np.isin(element, test)``: whether each element equals one of ``test`` (element's
    shape), the same booleans without numpy 2.4's ``np.unique`` (which imports
    ``numpy.ma``, see :func:`unique`): a few ``==`` or a search in the sorted test set."""
    a = np.asarray(element)
    t = np.asarray(test).ravel()
    if t.size == 0:
        return np.zeros(a.shape, dtype=bool)
    if t.size <= ISIN_LOOP:
        out = a == t[0]
        for v in t[1:]:
            out |= a == v
        return out
    t = np.sort(t)
    at = np.searchsorted(t, a)
    np.minimum(at, t.size - 1, out=at)
    return t[at] == a
