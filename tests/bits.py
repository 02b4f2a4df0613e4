"""Bit-for-bit comparison of results, for the tests of the compiled kernels against numpy's
code (tests/test_jit.py: numba; tests/test_native.py: C): arrays compared as their bytes
read as integers, so NaN, -0.0 and +0.0 are told apart and NaN equals only NaN."""

from __future__ import annotations

import dataclasses

import numpy as np


def as_bits(x: np.ndarray) -> np.ndarray:
    """The array's bytes as integers (floats as int64; other dtypes as they are)."""
    x = np.ascontiguousarray(x)
    return x.view(np.int64) if x.dtype == np.float64 else x


def same(a: object, b: object, what: str = "") -> None:
    """Assert ``a`` and ``b`` are the same bits: arrays of one dtype and shape, element for
    element; tuples and lists item by item; dataclasses field by field; a NaN float the
    same as a NaN float; anything else ``==``. ``what`` names the place in the message."""
    if isinstance(a, tuple | list):
        assert isinstance(b, type(a)) and len(a) == len(b), what
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            same(x, y, f"{what}[{i}]")
    elif isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape, what
        np.testing.assert_array_equal(as_bits(a), as_bits(b), err_msg=what)
    elif dataclasses.is_dataclass(a):
        assert type(a) is type(b), what
        for f in dataclasses.fields(a):
            same(getattr(a, f.name), getattr(b, f.name), f"{what}.{f.name}")
    elif isinstance(a, float) and a != a:
        assert isinstance(b, float) and b != b, what
    else:
        assert a == b, what
