"""The ``ncperf`` command and its report writers (terminal, JSON, CSV, TOML snippets).

The top of the flow: it may import everything in :mod:`core`; nothing in core imports it.
"""

from __future__ import annotations

import os

# One BLAS thread, unless the user chose otherwise (before numpy loads OpenBLAS, which reads
# it then): ncperf's matrix products are small -- the alignment's, a few thousand samples
# by a few hundred path points by 3 -- and OpenBLAS's threads cost more than they bring
# (the diagnose benchmark's alignment on 2 cores: 11.8-17.0 s wall with them, 7.6 s without;
# the SVG's (n, 3) @ (3, 2) projection of 1M moves 0.5 s with them, 0.01 s without: their
# busy waiting after every call took a core from the analysis).
BLAS_THREADS = "1"
os.environ.setdefault("OPENBLAS_NUM_THREADS", BLAS_THREADS)

from core.cli.main import main  # noqa: E402

__all__ = ["main"]
