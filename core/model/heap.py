"""Give the C allocator's free heap pages back to the system between the analysis's stages.

numpy's large arrays are mapped and unmapped whole, but glibc's malloc serves arrays under
its (self-adjusting, up to 32 MB) mapping threshold, and the pieces of piecewise work, from
its heap: a stage that ends leaves holes there that the next stage's large arrays, mapped
on their own, never reuse, and that stay in the resident set (5M moves: about 300 MB after
the reader). ``malloc_trim`` hands those pages back; elsewhere this does nothing.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from functools import cache


@cache
def _malloc_trim() -> Callable[[int], int] | None:
    if not sys.platform.startswith("linux"):
        return None
    import ctypes

    try:
        fn = ctypes.CDLL(None).malloc_trim  # glibc; not every C library has it
    except (OSError, AttributeError):
        return None
    fn.argtypes = [ctypes.c_size_t]
    fn.restype = ctypes.c_int
    return fn


def release_free_heap() -> None:
    """Return the allocator's free heap memory to the system (glibc's ``malloc_trim``;
    nothing where it is not available). Values are untouched: only free pages go."""
    fn = _malloc_trim()
    if fn is not None:
        fn(0)
