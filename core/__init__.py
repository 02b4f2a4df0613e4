"""ncperf core: host- and format-independent tool path, machine, hooks and evaluation.

The names below are the public API, imported from the subpackage that holds each
(:mod:`core.model`, :mod:`core.engine`, :mod:`core.view`, :mod:`core.diagnosis`) when
first used: importing ``core`` builds no plugin manager, imports no adapter or plugin,
and costs only what a command uses.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from core._version import __version__

#: Public name -> module that defines it.
_EXPORTS: dict[str, str] = {
    "Annotations": "core.view.annotations",
    "build_annotations": "core.view.annotations",
    "Analysis": "core.view.analysis",
    "ComparisonTarget": "core.view.targets",
    "DiagnosisTarget": "core.diagnosis.diagnose",
    "FileTarget": "core.view.targets",
    "HtmlTarget": "core.view.html_target",
    "Zone": "core.view.zones",
    "InputError": "core.model.errors",
    "MachineError": "core.model.errors",
    "NcperfError": "core.model.errors",
    "Notice": "core.model.errors",
    "UsageError": "core.model.errors",
    "Machine": "core.model.machine",
    "load_machine_file": "core.model.machine",
    "load_preset": "core.model.machine",
    "preset_names": "core.model.machine",
    "resolve_machine": "core.model.machine",
    "TOL": "core.model.tolerances",
    "Tolerances": "core.model.tolerances",
    "ExtractOptions": "core.model.toolpath",
    "MoveKind": "core.model.toolpath",
    "PathMode": "core.model.toolpath",
    "ToolPath": "core.model.toolpath",
    "Evaluation": "core.engine.indicators",
    "Indicator": "core.engine.indicators",
    "combine": "core.engine.indicators",
    "min_block_length": "core.engine.indicators",
    "Effect": "core.engine.effects",
    "Param": "core.engine.effects",
    "Setup": "core.engine.effects",
    "Ncperf": "core.facade",
    "hookimpl": "core.hookspecs",
    "BUILTIN_PLUGINS": "core.plugins",
    "make_plugin_manager": "core.plugins",
}

if TYPE_CHECKING:
    from core.diagnosis.diagnose import DiagnosisTarget
    from core.engine.effects import Effect, Param, Setup
    from core.engine.indicators import Evaluation, Indicator, combine, min_block_length
    from core.facade import Ncperf
    from core.hookspecs import hookimpl
    from core.model.errors import InputError, MachineError, NcperfError, Notice, UsageError
    from core.model.machine import (
        Machine,
        load_machine_file,
        load_preset,
        preset_names,
        resolve_machine,
    )
    from core.model.tolerances import TOL, Tolerances
    from core.model.toolpath import ExtractOptions, MoveKind, PathMode, ToolPath
    from core.plugins import BUILTIN_PLUGINS, make_plugin_manager
    from core.view.analysis import Analysis
    from core.view.annotations import Annotations, build_annotations
    from core.view.html_target import HtmlTarget
    from core.view.targets import ComparisonTarget, FileTarget
    from core.view.zones import Zone


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'core' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # once imported, a plain attribute
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS])


__all__ = [
    "__version__",
    "Analysis",
    "Annotations",
    "BUILTIN_PLUGINS",
    "ComparisonTarget",
    "DiagnosisTarget",
    "Effect",
    "Evaluation",
    "ExtractOptions",
    "FileTarget",
    "HtmlTarget",
    "Indicator",
    "InputError",
    "Machine",
    "MachineError",
    "MoveKind",
    "Ncperf",
    "NcperfError",
    "Notice",
    "Param",
    "PathMode",
    "Setup",
    "TOL",
    "Tolerances",
    "ToolPath",
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
