"""refvm: the reference interpreter that ncperf's tests and benchmarks check it against.

A time-stepping controller (:mod:`refvm.planner`) runs a parsed program under the paper's
models (:mod:`refvm.models`) with at most one controller effect switched on
(:data:`refvm.effects.EFFECTS`), and records the trace a real controller would
(:func:`refvm.simulate.simulate`). It is an oracle: it is written independently of what it
checks and imports nothing of ncperf (``core``, ``adapters``, ``plugins``) -- a test keeps
it so. It reads a program and a machine from any objects with their columns and
attributes (ncperf's ``ToolPath`` and ``Machine`` have them).
"""

from __future__ import annotations

from refvm.effects import EFFECT_DOCS, EFFECTS, resolve_effect
from refvm.machine import MachineLimits
from refvm.planner import stop_distance
from refvm.program import Program
from refvm.simulate import Trace, simulate, write_csv

__all__ = [
    "EFFECTS",
    "EFFECT_DOCS",
    "MachineLimits",
    "Program",
    "Trace",
    "resolve_effect",
    "simulate",
    "stop_distance",
    "write_csv",
]
