"""The ``ncperf`` command and its report writers (terminal, JSON, CSV, TOML snippets).

The top of the flow: it may import everything in :mod:`core`; nothing in core imports it.
"""

from __future__ import annotations

from core.cli.main import main

__all__ = ["main"]
