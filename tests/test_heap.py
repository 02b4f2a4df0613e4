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


def test_the_heap_filled_ahead_is_sized_by_the_program_file() -> None:
    # 22 bytes of heap a byte of the file, in whole pieces of 4 MB (2^22 bytes), 16 MB at
    # least, 96 MB at most
    assert heap.prefault_size(0) == 0
    assert heap.prefault_size(700_000) == 0  # 15,400,000 bytes: 3 pieces, under 16 MB
    assert heap.prefault_size(800_000) == 16 * MB  # 17,600,000: 4 pieces (16,777,216)
    assert heap.prefault_size(3_238_873) == 64 * MB  # stellabee1, 71,255,206: 16 pieces
    assert heap.prefault_size(18_000_000) == 96 * MB  # 396,000,000: capped


def test_the_heap_filled_ahead_serves_the_next_arrays_without_faults() -> None:
    # 64 MB faulted in on the thread and handed back to the heap: 64 MB of arrays made after
    # it come from those pages (few faults on this thread), where the same arrays without
    # the filling fault in one page every 4 kB (16,384 for 64 MB; arrays of 2 MB: numpy
    # asks for huge pages from 4 MB on, which fault 2 MB at a time)
    from core.model.cpus import two_cores

    if not two_cores():
        pytest.skip("one CPU for this process: no heap is filled ahead (nothing to check)")
    body = f"""
        import resource
        def faults():
            return resource.getrusage(resource.RUSAGE_THREAD).ru_minflt
        {{fill}}
        before = faults()
        a = [np.ones({MB // 4}) for _ in range(32)]  # 32 x 2 MB
        print(heap.free_heap() if {{filled}} else 0, faults() - before)
        """
    free_after, filled_faults = _run(
        body.format(fill=f"heap.prefault_heap({64 * MB}).join()", filled="True")
    )
    _, plain_faults = _run(body.format(fill="pass", filled="False"))
    assert plain_faults >= 16_000
    assert filled_faults < 1_000
    # the arrays took the filled pages: what is free is about the pad the heap grows by
    assert free_after < heap.TOP_PAD + 4 * MB


def test_no_heap_is_filled_ahead_where_freed_memory_is_not_kept() -> None:
    # without keep_freed_memory the freed pieces would go back to the system: no thread
    out = subprocess.run(
        [
            sys.executable,
            "-c",
            f"from core.model import heap; print(heap.prefault_heap({64 * MB}) is None)",
        ],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert out.strip() == "True"


def test_the_commands_that_analyse_a_program_fill_the_heap_ahead(tmp_path, monkeypatch) -> None:
    import argparse
    import importlib

    cli = importlib.import_module("core.cli.main")  # (core.cli's main is the function)

    asked: list[int] = []
    monkeypatch.setattr(heap, "prefault_heap", lambda size: asked.append(size))
    big, small = tmp_path / "big.ngc", tmp_path / "small.ngc"
    big.write_bytes(b"G1 X1\n" * 500_000)  # 3,000,000 bytes: 66,000,000 -> 15 pieces of 4 MB
    small.write_bytes(b"G1 X1\n")

    def ask(run, **paths) -> list[int]:
        asked.clear()
        cli._fill_heap_ahead(argparse.Namespace(run=run, **paths))
        return list(asked)

    assert ask(cli.cmd_analyze, program=str(big)) == [60 * MB]
    assert ask(cli.cmd_profile, program=str(big)) == [60 * MB]
    assert ask(cli.cmd_compare, programs=[str(small), str(big)]) == [60 * MB]  # the largest
    assert ask(cli.cmd_analyze, program=str(small)) == [0]  # (prefault_heap starts no thread)
    assert ask(cli.cmd_analyze, program=None) == []  # the demo
    assert ask(cli.cmd_analyze, program=str(tmp_path / "missing.ngc")) == []
    # the fits' forked processes would fault the inherited pages in again
    assert ask(cli.cmd_diagnose, program=str(big)) == []
    assert ask(cli.cmd_calibrate, program=str(big)) == []
