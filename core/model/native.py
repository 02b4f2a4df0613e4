"""The C kernels (``core/model/_kernels.c``), loaded with ctypes, where they were built.

``pip install`` builds them where it finds a C compiler (an optional extension in
pyproject.toml: without a compiler the install goes on without them). They are the feed
profile's rounds (the marks, the dense rounds of the jerk iteration, the passes) move by
move with the same IEEE-754 operations in the same order as numpy's code: the same bits
(``tests/test_native.py``). Unlike numba's kernels (:mod:`core.model.jit`), which cost
0.4 s to import and so serve the diagnosis only, these load in about a millisecond: every
``ncperf analyze`` takes them (issue 13). ctypes lets go of the GIL while a kernel runs,
so the profile runs the rounds' two directions on two threads.

:func:`native` is None where the library is absent (no compiler at install, another
platform), was built for another version of this interface, or ``NCPERF_NO_JIT`` asks for
numpy's code: numpy's code runs there, with the same results.
"""

from __future__ import annotations

import ctypes
import importlib.machinery
import sys
from functools import cache
from pathlib import Path
from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from core.model.jit import compiled, disabled
from core.model.pieces import SPLIT, side_by_side, two_cores

#: The interface version _kernels.c reports (ncperf_kernels_version): a library built from
#: another version of the source is not loaded.
VERSION = 8

_P = ctypes.c_void_p
_I = ctypes.c_int64
_D = ctypes.c_double


def _ptr(x: NDArray, dtype: type) -> int:
    """The address of a contiguous array of ``dtype`` (the kernels write into some of them
    in place: a copy would lose what they write, so none is made)."""
    if x.dtype != dtype or not x.flags.c_contiguous:
        raise TypeError(f"C kernel argument: {x.dtype} {x.shape}, not contiguous {dtype}")
    return int(x.ctypes.data)


class Kernels:
    """The library's kernels with the arguments of :mod:`core.model.compiled`'s."""

    def __init__(self, lib: ctypes.CDLL) -> None:
        self.lib = lib
        lib.marks.argtypes = [_P, _I, _I, ctypes.c_int, *[_P] * 5, _D, _D, *[_P] * 5]
        lib.marks.restype = None
        lib.dense_round.argtypes = [ctypes.c_int, _I, *[_P] * 14, _D, *[_P] * 7]
        lib.dense_round.restype = _I
        lib.passes_forward.argtypes = [_I, *[_P] * 4]
        lib.passes_forward.restype = None
        lib.passes_backward.argtypes = [_I, *[_P] * 3]
        lib.passes_backward.restype = None
        lib.passes_join.argtypes = [_I, _I, *[_P] * 3]
        lib.passes_join.restype = None
        lib.corner_limits.argtypes = [_I, *[_P] * 8]
        lib.corner_limits.restype = None

    def marks(
        self,
        at: NDArray,
        every: bool,
        v: NDArray,
        a_up: NDArray,
        a_dn: NDArray,
        between: NDArray,
        cap: NDArray,
        tols: tuple[float, float],
        out: tuple[NDArray, NDArray, NDArray, NDArray, NDArray],
    ) -> None:
        """core.engine.profile._Rounds._all_marks (``every``) or _marks_of the moves ``at``
        into ``out`` = (peak, rise, fall, through_up, through_dn)."""
        f, b = np.float64, np.bool_
        n = a_up.size
        if v.size != n + 1 or not (a_dn.size == between.size == cap.size == n):
            raise ValueError("C kernel marks: columns of different lengths")
        peak, rise, fall, t_up, t_dn = out
        if not (peak.size == rise.size == fall.size == n and t_up.size == t_dn.size == n + 1):
            raise ValueError("C kernel marks: outputs of different lengths")
        count = n if every else at.size
        if not every and count and not (0 <= int(at.min()) and int(at.max()) < n):
            raise IndexError("C kernel marks: a move out of range")
        p_at = _ptr(at, np.intp) if at.size else None
        rest = (
            _ptr(v, f), _ptr(a_up, f), _ptr(a_dn, f), _ptr(between, f), _ptr(cap, f),
            tols[0], tols[1],
            _ptr(peak, f), _ptr(rise, b), _ptr(fall, b), _ptr(t_up, b), _ptr(t_dn, b),
        )  # fmt: skip
        if count < 2 * SPLIT or not two_cores():
            self.lib.marks(p_at, 0, count, int(every), *rest)
            return
        # each move's marks its own: the halves on two threads (disjoint outputs)
        half = count // 2
        side_by_side(
            lambda: self.lib.marks(p_at, 0, half, int(every), *rest),
            lambda: self.lib.marks(p_at, half, count - half, int(every), *rest),
        )

    def dense_round(
        self,
        rising: bool,
        phase: NDArray,
        through: NDArray,
        v0: NDArray,
        v1: NDArray,
        peak: NDArray,
        a: NDArray,
        last: NDArray,
        term: NDArray,
        off: NDArray,
        acc: NDArray,
        jerk: NDArray,
        between: NDArray,
        step: NDArray,
        moved: NDArray,
        nil_speed: float,
        finite: bool,
        fixed: tuple[NDArray, NDArray],
    ) -> tuple[float, bool, NDArray, NDArray]:
        """core.engine.profile._Rounds._dense: as :func:`core.model.compiled.dense_round`
        (``a``, ``off``, ``term`` in place, ``step`` and ``moved`` written; the largest
        relative change, whether the terms are still plain, the moves the damping held
        back and their targets). ``fixed``: ``acc / jerk`` and ``acc * acc / jerk`` made
        once for all the rounds (_Rounds.fixed)."""
        f, b = np.float64, np.bool_
        n = a.size
        cols = [phase, v0, v1, peak, last, term, off, acc, jerk, between, step, moved, *fixed]
        if through.size != n + 1 or any(c.size != n for c in cols):
            raise ValueError("C kernel dense_round: columns of different lengths")
        # (behind and wanted: pages the kernel does not write are never resident)
        behind = np.empty(n, dtype=np.intp)
        wanted = np.empty(n)
        work = np.empty(n)
        fin = ctypes.c_int(int(finite))
        change = ctypes.c_double(0.0)
        count = self.lib.dense_round(
            int(rising), n, _ptr(phase, b), _ptr(through, b),
            _ptr(v0, f), _ptr(v1, f), _ptr(peak, f), _ptr(a, f), _ptr(last, np.int8),
            _ptr(term, f), _ptr(off, b), _ptr(acc, f), _ptr(jerk, f), _ptr(between, f),
            _ptr(step, np.int8), _ptr(moved, b), nil_speed,
            ctypes.addressof(fin), ctypes.addressof(change),
            _ptr(behind, np.intp), _ptr(wanted, f), _ptr(work, f),
            _ptr(fixed[0], f), _ptr(fixed[1], f),
        )  # fmt: skip
        return change.value, bool(fin.value), behind[:count].copy(), wanted[:count].copy()

    def corner_limits(
        self,
        share_t: NDArray,
        share_n: NDArray,
        radius: NDArray,
        v_jerk: NDArray,
        max_feed: NDArray,
        a_n: NDArray,
    ) -> tuple[NDArray, NDArray]:
        """plugins.tangential._corner_feed_rows after its jerk column: as
        :func:`core.model.compiled.corner_limits` (each corner's lowest limit and which of
        the nine it is)."""
        f = np.float64
        m = radius.size
        if not (share_t.shape == share_n.shape == v_jerk.shape == (m, 3)) or not (
            max_feed.size == a_n.size == 3
        ):
            raise ValueError("C kernel corner_limits: columns of different shapes")
        feed = np.empty(m)
        limit = np.empty(m, dtype=np.int64)
        if m:
            self.lib.corner_limits(
                m, _ptr(share_t, f), _ptr(share_n, f), _ptr(radius, f), _ptr(v_jerk, f),
                _ptr(max_feed, f), _ptr(a_n, f), _ptr(feed, f), _ptr(limit, np.int64),
            )  # fmt: skip
        return feed, limit

    def plain_passes(
        self, b2: NDArray, up: NDArray, dn: NDArray, w: NDArray, bwd: NDArray, out: NDArray
    ) -> None:
        """core.engine.profile._passes_of with ``finite``, into ``out``."""
        f = np.float64
        n1 = b2.size
        if n1 == 0 or not (up.size == dn.size == n1 - 1 and w.size == bwd.size == out.size == n1):
            raise ValueError("C kernel plain_passes: columns of different lengths")
        p_b2, p_up, p_dn = _ptr(b2, f), _ptr(up, f), _ptr(dn, f)
        p_w, p_bwd, p_out = _ptr(w, f), _ptr(bwd, f), _ptr(out, f)

        def forward() -> None:
            self.lib.passes_forward(n1, p_b2, p_up, p_w, p_out)

        def backward() -> None:
            self.lib.passes_backward(n1, p_b2, p_dn, p_bwd)

        if n1 < SPLIT or not two_cores():
            forward()
            backward()
            self.lib.passes_join(0, n1, p_b2, p_bwd, p_out)
            return
        # the forward and the backward pass side by side, then their minimum (in halves)
        side_by_side(forward, backward)
        h = n1 // 2
        side_by_side(
            lambda: self.lib.passes_join(0, h, p_b2, p_bwd, p_out),
            lambda: self.lib.passes_join(h, n1 - h, p_b2, p_bwd, p_out),
        )


def library_path(folder: Path | None = None, name: str = "_kernels") -> Path | None:
    """Where a built library is (in ``folder``, by default this file's, named as a Python
    extension ``name``), or None."""
    here = Path(__file__).parent if folder is None else folder
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        path = here / f"{name}{suffix}"
        if path.is_file():
            return path
    return None


@cache
def load_library(folder: Path, name: str, version_symbol: str, version: int) -> ctypes.CDLL | None:
    """The C library ``name`` built beside the modules in ``folder`` (an optional
    extension of pyproject.toml), loaded with ctypes where its ``version_symbol()``
    returns ``version``; None where it is absent, does not load here, or is another
    version (a stale build beside newer Python code). 64-bit platforms only (the kernels'
    int64_t is numpy's intp there)."""
    if sys.maxsize != 2**63 - 1:
        return None
    path = library_path(folder, name)
    if path is None:
        return None
    try:
        lib = ctypes.CDLL(str(path))
        check = getattr(lib, version_symbol)
        check.restype = ctypes.c_int64
        check.argtypes = []
        return lib if check() == version else None
    except (OSError, AttributeError):  # not loadable here, or not this library
        return None


@cache
def _load() -> Kernels | None:
    lib = load_library(Path(__file__).parent, "_kernels", "ncperf_kernels_version", VERSION)
    return None if lib is None else Kernels(lib)


def native() -> Kernels | None:
    """The C kernels, or None: not built, not loadable, or ``NCPERF_NO_JIT`` set (read at
    every call, so a test may switch)."""
    if disabled():
        return None
    return _load()


def kernels() -> ModuleType | Kernels | None:
    """The kernels the profile's rounds take: numba's where the diagnosis allowed them
    (:func:`core.model.jit.compiled`: loaded anyway there), else the C kernels, else None
    (numpy's code). All three give the same bits."""
    return compiled() or native()
