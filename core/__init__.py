"""ncperf core: host- and format-independent tool path, machine, hooks and evaluation.

Importing ``core`` builds no plugin manager and imports no adapter or plugin.
"""

from __future__ import annotations

from core.view.annotations import (
    Annotations,
    ComparisonTarget,
    DiagnosisTarget,
    FileTarget,
    Zone,
    build_annotations,
)
from core.model.errors import InputError, MachineError, NcperfError, Notice, UsageError
from core.facade import Analysis, Ncperf
from core.hookspecs import hookimpl
from core.engine.indicators import Evaluation, Indicator, combine, min_block_length
from core.model.machine import Machine, load_machine_file, load_preset, preset_names, resolve_machine
from core.plugins import BUILTIN_PLUGINS, make_plugin_manager
from core.model.tolerances import TOL, Tolerances
from core.model.toolpath import ExtractOptions, MoveKind, PathMode, ToolPath

__version__ = "0.1.0"

__all__ = [
    "BUILTIN_PLUGINS",
    "TOL",
    "Analysis",
    "Annotations",
    "ComparisonTarget",
    "DiagnosisTarget",
    "Evaluation",
    "ExtractOptions",
    "FileTarget",
    "Indicator",
    "InputError",
    "Machine",
    "MachineError",
    "MoveKind",
    "Ncperf",
    "NcperfError",
    "Notice",
    "PathMode",
    "ToolPath",
    "Tolerances",
    "UsageError",
    "Zone",
    "build_annotations",
    "combine",
    "hookimpl",
    "load_machine_file",
    "load_preset",
    "make_plugin_manager",
    "min_block_length",
    "preset_names",
    "resolve_machine",
]
