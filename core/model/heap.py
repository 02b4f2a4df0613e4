"""The C allocator's memory between the analysis's stages: kept for reuse, or given back.

numpy's arrays come from glibc's malloc: from its heap under its mapping threshold
(self-adjusting, up to 32 MB), mapped and unmapped whole above it. Two costs pull apart:

* **Page faults.** Memory the process gets from the system is faulted in page by page on
  first touch, and on a virtual machine a fault costs several microseconds (this project's
  VM: 3-4.5 us a 4 kB page when idle, where filling the page takes 0.25 us). glibc's
  defaults hand freed memory back quickly -- arrays above the threshold are unmapped when
  freed, and the heap's top is trimmed once two thresholds are free -- so each stage's
  arrays fault their pages in again. :func:`keep_freed_memory` (the command line sets it)
  serves every array up to 32 MB from the heap and trims the heap only when asked.
* **The resident set.** A stage that ends leaves holes in the heap that the next stage's
  arrays do not always fit, and that stay resident (5M moves: 336 MB after the reader).
  :func:`release_free_heap` (``malloc_trim``) hands them back between stages -- where there
  is enough of them to matter (:data:`WORTH_TRIMMING`): below that, the next stage reuses
  the pages instead of faulting them in again.

``ncperf analyze`` on this project's VM, 2026-11-28 (12:19-12:22 UTC, idle; three runs in
turns, the 5M raster one; faults as counted by the kernel, time wall): stellabee1 60,300 ->
25,800 faults, 0.18-0.21 -> 0.06-0.09 s in the kernel, 1.03 -> 0.79 s (medians of 3 and of
9: it trims at no threshold tried), peak 115 -> 118 MB; the 1M raster with ``--svg``
67,000 -> 33,000 faults, 2.50 -> 2.29 s, 388 -> 403 MB; 5M 272,000 -> 242,000 faults, 12.7
-> 12.0 s, 1614 -> 1630 MB (the VM's cost per fault varies several-fold from run to run:
the faults are the steady figure).

The faults that are left can be taken on the second core: :func:`prefault_heap` (the
command line calls it for the programs it analyses, as soon as the arguments are read)
fills the heap's pages on a thread of its own while the main thread imports numpy and the
plugins, and hands them back to the heap, where the analysis's arrays then find them
faulted in. 2026-11-28 (23:00-23:17 UTC): stellabee1's faults after the imports 22,100-
23,000 -> 6,100-6,900 with 64 MB filled ahead (-> 80 with 96 MB), the imports no slower;
the whole command, in turns with and without (pairs of runs, mean difference +- its
standard error): stellabee1 (64 MB filled) 29 +- 12 ms faster of 0.76 s (30 pairs),
tiger.nc (28 MB) 29 +- 10 ms of 0.44 s (20 pairs), rasters with ``--svg`` of 200k moves
(72 MB) 52 +- 13 ms of 0.63 s (16 pairs) and 500k (96 MB) 100 +- 55 ms of 1.5 s (12
pairs); peaks 1-5 MB higher. The 1M raster (96 MB): 44 +- 111 ms and 398 -> 411 MB
(10 pairs), no gain to be seen: its columns of 8 MB take numpy's huge pages, 2 MB a fault.

Values are untouched either way: only where free memory lives changes. Elsewhere than glibc
all three do nothing; a glibc before 2.33 (no ``mallinfo2`` to measure the free heap with)
trims at every :func:`release_free_heap`, as before.
"""

from __future__ import annotations

import ctypes
import sys
import threading
from collections.abc import Callable
from functools import cache

#: glibc's mallopt parameters (malloc.h).
M_TRIM_THRESHOLD = -1
M_TOP_PAD = -2
M_MMAP_THRESHOLD = -3
M_ARENA_MAX = -8
#: One heap for every thread: the arrays the worker thread makes (core.model.pieces) and
#: frees go back where the main thread's next arrays are taken from. With a heap of its
#: own the worker's freed memory stayed resident beside the main heap: 5M moves' peak
#: 1659 -> 1790 MB (numpy's code, 2026-11-28). A few large allocations per call: no
#: contention to speak of.
ONE_ARENA = 1
#: Arrays up to this size come from the heap (glibc's largest mapping threshold; 4M moves'
#: columns of doubles). Larger ones are mapped, and unmapped when freed, as before.
HEAP_ARRAYS = 32 << 20
#: The heap's top is never trimmed on its own (only by :func:`release_free_heap`): the
#: largest value mallopt takes.
NEVER_TRIM = 2**31 - 1
#: What the heap grows by beyond a request, so that growing stages ask the system less often.
TOP_PAD = 16 << 20
#: :func:`release_free_heap` gives the free heap back from this size on. Below it the next
#: stage's arrays reuse the pages without faulting them in again (a 1M-move raster's stages
#: leave 65-192 MB, and trimming them left its peak as it was); above it (5M moves: 336 MB
#: after the reader) the resident set is what counts.
WORTH_TRIMMING = 256 << 20
#: :func:`prefault_heap`: the heap an analysis takes per byte of its program's file, about:
#: the memory faulted in after the imports, per byte of the file, was 19.3-25.9 (median 21.9)
#: on six programs of 0.15-3.6 MB (LHchips4, contour, flower_mold, tiger, zlevel_cavity_chords
#: and a 200k-move raster; 2026-11-28). Memory filled ahead that the analysis does not use
#: stays resident, so the median, not the most.
PREFAULT_PER_BYTE = 22
#: At most this much is filled ahead: larger programs' big arrays come from their own
#: mappings (above :data:`HEAP_ARRAYS`, or numpy's huge pages from 4 MB on), so that the
#: heap they fault in grows no more with the file (rasters of 0.5M and 1M moves: 129 and
#: 114 MB after the imports), and the thread is done within the imports (about 100 ms).
PREFAULT_MAX = 96 << 20
#: Nothing below this (a small program's few faults do not repay a thread).
PREFAULT_MIN = 16 << 20
#: The pieces it is filled in: each from the heap (below :data:`HEAP_ARRAYS`), all held
#: until the last is filled, so that they lie side by side, then freed together.
PREFAULT_PIECE = 4 << 20


class _Mallinfo2(ctypes.Structure):
    _fields_ = [
        (name, ctypes.c_size_t)
        for name in (
            "arena",
            "ordblks",
            "smblks",
            "hblks",
            "hblkhd",
            "usmblks",
            "fsmblks",
            "uordblks",
            "fordblks",
            "keepcost",
        )
    ]


@cache
def _glibc() -> ctypes.CDLL | None:
    """The C library when it is glibc (``malloc_trim`` and ``mallopt``), else None."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        lib = ctypes.CDLL(None)
        lib.malloc_trim.argtypes = [ctypes.c_size_t]
        lib.malloc_trim.restype = ctypes.c_int
        lib.mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
        lib.mallopt.restype = ctypes.c_int
    except (OSError, AttributeError):  # not glibc (musl has neither)
        return None
    return lib


_kept = [False]  # whether keep_freed_memory ran (a list: set without a global statement)


def keep_freed_memory() -> None:
    """Let freed memory stay with the process for its next arrays (module docstring): every
    array up to :data:`HEAP_ARRAYS` from the heap, the heap trimmed only by
    :func:`release_free_heap`, one heap for all threads (:data:`ONE_ARENA`). For a process
    that runs one analysis (the command line):
    it changes where memory lives, not what is computed."""
    lib = _glibc()
    if lib is None:
        return
    lib.mallopt(M_MMAP_THRESHOLD, HEAP_ARRAYS)
    lib.mallopt(M_TRIM_THRESHOLD, NEVER_TRIM)
    lib.mallopt(M_TOP_PAD, TOP_PAD)
    lib.mallopt(M_ARENA_MAX, ONE_ARENA)
    _kept[0] = True


def prefault_size(program_bytes: int) -> int:
    """How much :func:`prefault_heap` fills ahead of the analysis of a program file of
    ``program_bytes``: :data:`PREFAULT_PER_BYTE` a byte, whole pieces, at most
    :data:`PREFAULT_MAX`; 0 below :data:`PREFAULT_MIN`."""
    size = min(PREFAULT_PER_BYTE * max(program_bytes, 0), PREFAULT_MAX)
    size -= size % PREFAULT_PIECE
    return size if size >= PREFAULT_MIN else 0


def prefault_heap(size: int) -> threading.Thread | None:
    """Fill ``size`` bytes of the heap on a thread of its own and free them again (module
    docstring), where it pays: glibc, :func:`keep_freed_memory` in force (else the freed
    pieces would go back to the system), two cores (on one, the faults cost the same time
    on the only core), ``size`` at least :data:`PREFAULT_MIN`. Returns the thread (a
    daemon: the process does not wait for it), or None. Only where memory lives changes."""
    from core.model.cpus import two_cores

    lib = _glibc()
    if lib is None or not _kept[0] or size < PREFAULT_MIN or not two_cores():
        return None
    try:
        malloc, memset, free = lib.malloc, lib.memset, lib.free
    except AttributeError:
        return None
    malloc.argtypes, malloc.restype = [ctypes.c_size_t], ctypes.c_void_p
    memset.argtypes, memset.restype = [ctypes.c_void_p, ctypes.c_int, ctypes.c_size_t], None
    free.argtypes, free.restype = [ctypes.c_void_p], None

    def fill() -> None:
        # (ctypes lets go of the GIL in each call: the faults are taken beside the main
        # thread's work)
        held = []
        try:
            for _ in range(size // PREFAULT_PIECE):
                piece = malloc(PREFAULT_PIECE)
                if not piece:
                    break  # (no memory: nothing filled ahead is needed)
                held.append(piece)
                memset(piece, 0, PREFAULT_PIECE)
        finally:
            for piece in held:
                free(piece)

    thread = threading.Thread(target=fill, name="ncperf-prefault", daemon=True)
    thread.start()
    return thread


@cache
def _mallinfo2() -> Callable[[], _Mallinfo2] | None:
    """glibc's ``mallinfo2`` (2.33+), or None."""
    lib = _glibc()
    info = None if lib is None else getattr(lib, "mallinfo2", None)
    if info is not None:
        info.argtypes = []
        info.restype = _Mallinfo2
    return info


def free_heap() -> int | None:
    """Bytes free in the allocator's heap (glibc's ``mallinfo2().fordblks``), or None (not
    glibc, or one before 2.33)."""
    info = _mallinfo2()
    return None if info is None else int(info().fordblks)


def release_free_heap() -> None:
    """Return the allocator's free heap memory to the system (glibc's ``malloc_trim``)
    when it is :data:`WORTH_TRIMMING` (always where :func:`free_heap` cannot tell); nothing
    where glibc is not there. Values are untouched: only free pages go."""
    lib = _glibc()
    if lib is None:
        return
    free = free_heap()
    if free is None or free >= WORTH_TRIMMING:
        lib.malloc_trim(0)
