"""A1 + A3 adapter for ESPRIT (DP Technology / Hexagon), and its headless emulation.

The paper's viewer ran inside ESPRIT (Tapie et al., sec. 3): A1 read the tool paths of the
operations, A3 drew the colour annotations back into the workspace. This adapter does both
through ESPRIT's object model -- a live ESPRIT over COM on Windows (``ncperf esprit``, or the
add-in entry point :func:`adapters.esprit_com.addin.run`), or the emulation that implements the
same object model in .NET and in Python for tests and Linux (``ncperf esprit --emulate``).

* A1 claims ESPRIT Application and Document objects and :class:`EspritSource`; paths and
  anything else get None without pythonnet being imported.
* A3 claims the same objects as targets and draws on the layer "ncperf performance".

Importing this module imports neither numpy nor ``clr``: the hooks import what they run, and
``clr`` is loaded on first use (:mod:`adapters.esprit_com.clr_host`), so the command line's
parser can take ``ncperf esprit`` from here cheaply. What is assumed about ESPRIT is in one table,
:mod:`adapters.esprit_com.object_model`.
"""

from __future__ import annotations

import argparse
import importlib
import os
from typing import TYPE_CHECKING, Any

from core.hookspecs import hookimpl

if TYPE_CHECKING:
    from adapters.esprit_com.draw import Drawing, colorref, draw_annotations, plan_drawing
    from adapters.esprit_com.extract import EspritSource, document_of, read_esprit
    from core import Annotations, ExtractOptions, ToolPath

#: Public name -> the submodule that defines it (imported when first used).
_EXPORTS = {
    "Drawing": "adapters.esprit_com.draw",
    "colorref": "adapters.esprit_com.draw",
    "draw_annotations": "adapters.esprit_com.draw",
    "plan_drawing": "adapters.esprit_com.draw",
    "EspritSource": "adapters.esprit_com.extract",
    "document_of": "adapters.esprit_com.extract",
    "read_esprit": "adapters.esprit_com.extract",
}


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)


__all__ = [
    "Drawing",
    "EspritSource",
    "colorref",
    "document_of",
    "draw_annotations",
    "ncperf_add_commands",
    "ncperf_display",
    "ncperf_extract",
    "plan_drawing",
    "read_esprit",
]


@hookimpl
def ncperf_extract(source: object, options: ExtractOptions) -> ToolPath | None:
    """The operations of an ESPRIT document; None for anything that is not one."""
    if source is None or isinstance(source, str | bytes | os.PathLike):
        return None  # a file: nothing of ESPRIT's is imported
    from adapters.esprit_com.extract import document_of, read_esprit

    if document_of(source) is None:
        return None
    return read_esprit(source)


@hookimpl
def ncperf_display(toolpath: ToolPath, annotations: Annotations, target: object) -> Drawing | None:
    """Draw into an ESPRIT document; None for any other target."""
    from adapters.esprit_com.draw import draw_annotations
    from adapters.esprit_com.extract import document_of

    doc = document_of(target)
    if doc is None:
        return None
    return draw_annotations(doc, toolpath, annotations)


@hookimpl
def ncperf_add_commands(subparsers: argparse._SubParsersAction) -> None:
    """``ncperf esprit``."""
    from adapters.esprit_com.command import add_command

    add_command(subparsers)
