"""Where freed memory lives between the analysis's stages (core.model.heap), on glibc.

Each check runs in a fresh interpreter: the allocator's settings are the process's, and the
test process's own heap would blur the counts.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from core.model import heap

pytestmark = pytest.mark.skipif(
    heap.free_heap() is None, reason="the allocator is not glibc 2.33+ (nothing to check)"
)

MB = 1 << 20


def _run(body: str) -> list[int]:
    """Run ``body`` after ``keep_freed_memory()`` in a fresh interpreter; the integers it
    prints."""
    code = "import numpy as np\nfrom core.model import heap\nheap.keep_freed_memory()\n"
    code += textwrap.dedent(body)
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    return [int(x) for x in out.split()]


def test_freed_arrays_stay_in_the_heap_for_the_next_ones() -> None:
    # 12 arrays of 8 MB: under the 32 MB threshold, so from the heap (glibc's default would
    # have mapped the first and unmapped it when freed); freed, they stay there
    (free,) = _run(
        f"""
        a = [np.ones({MB}) for _ in range(12)]
        del a
        print(heap.free_heap())
        """
    )
    assert free >= 12 * 8 * MB


def test_a_small_free_heap_is_kept_and_a_large_one_given_back() -> None:
    small, after_small, large, after_large = _run(
        f"""
        a = [np.ones({MB}) for _ in range(4)]  # 4 x 8 MB: 32 MB, under WORTH_TRIMMING (256 MB)
        del a
        small = heap.free_heap()
        heap.release_free_heap()
        after_small = heap.free_heap()
        a = [np.ones({MB}) for _ in range(36)]  # 288 MB: trimmed
        del a
        large = heap.free_heap()
        heap.release_free_heap()
        print(small, after_small, large, heap.free_heap())
        """
    )
    assert 32 * MB <= small < heap.WORTH_TRIMMING
    assert after_small == small  # kept: the next stage reuses its pages
    assert large >= 288 * MB >= heap.WORTH_TRIMMING
    assert after_large < heap.WORTH_TRIMMING  # the freed top went back to the system


def test_a_threads_freed_arrays_serve_the_next_ones() -> None:
    # 12 x 8 MB made and freed on another thread (as core.model.pieces' worker does), then
    # 12 x 8 MB on this one: one heap for both, so the peak hardly grows (with a heap per
    # thread, glibc's default, it grew by the second 96 MB: the first stayed resident)
    first, second = _run(
        f"""
        import resource, threading
        def work():
            a = [np.ones({MB}) for _ in range(12)]
            del a
        t = threading.Thread(target=work)
        t.start()
        t.join()
        first = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        a = [np.ones({MB}) for _ in range(12)]
        print(first, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
        """
    )
    assert (second - first) * 1024 < 24 * MB
