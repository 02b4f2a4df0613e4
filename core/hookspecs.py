"""The ncperf hook specifications: the paper's three tasks (sec. 3, Figure 5).

* A1 extract: a source (a file, a host document) -> a :class:`~core.model.toolpath.ToolPath`.
* A2 evaluate: tool path + machine -> indicator results.
* A3 display: tool path + colour annotations + a target -> an output.

Adapters implement A1 and A3, plugins implement A2. Implementations take only
the arguments they need (pluggy's opt-in arguments); the core calls every hook
by keyword, through :class:`core.facade.Ncperf` only.
"""

# Hook specifications have no bodies: pluggy calls the implementations, never these.
# mypy: disable-error-code="empty-body"

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

import pluggy

if TYPE_CHECKING:
    from core.engine.effects import Effect
    from core.engine.indicators import Indicator
    from core.model.machine import Machine
    from core.model.toolpath import ExtractOptions, ToolPath
    from core.model.trace import Trace, TraceOptions
    from core.view.annotations import Annotations

PROJECT = "ncperf"

hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


@hookspec(firstresult=True)
def ncperf_extract(source: object, options: ExtractOptions) -> ToolPath | None:
    """A1: read a tool path from ``source``.

    Stops at the first non-None result: an adapter returns None for a source it
    does not recognise (another extension, another host), and raises
    :class:`~core.model.errors.InputError` for a source it recognises but cannot read
    faithfully.

    :param source: a file path (``str`` or ``os.PathLike``) or a host object
        (e.g. an ESPRIT document).
    :param options: what the user said about the source (dialect, block delete);
        each adapter reads the fields that apply to it.
    :returns: the tool path, or None if the source is not for this adapter.
    """


@hookspec
def ncperf_evaluate(toolpath: ToolPath, machine: Machine) -> list[Indicator]:
    """A2: evaluate the machine's behaviour on the tool path.

    Every plugin runs (1:N); the core flattens the lists and keeps, at each
    junction and on each element, the lowest predicted feed.

    :param toolpath: the tool path (mm, s).
    :param machine: the machine's limits (mm, s).
    :returns: a list of indicator results, possibly empty.
    """


@hookspec(firstresult=True)
def ncperf_display(toolpath: ToolPath, annotations: Annotations, target: object) -> object | None:
    """A3: show the colour annotations on ``target``.

    Stops at the first non-None result: a display returns None for a target it
    does not handle (another file extension, another host).

    :param toolpath: the tool path that was evaluated.
    :param annotations: classes, colours, zones and legend to draw.
    :param target: a file path (``str`` or ``os.PathLike``, e.g. ``out.svg``)
        or a host document.
    :returns: what was written (e.g. the file path), or None.
    """


@hookspec
def ncperf_add_commands(subparsers: argparse._SubParsersAction) -> None:
    """Add subcommands to the ``ncperf`` command line (e.g. ``ncperf esprit``).

    Each subparser sets ``set_defaults(run=FUNCTION)``; the CLI calls
    ``FUNCTION(args, nc)`` with the parsed arguments and the :class:`~core.facade.Ncperf`
    facade, and exits with the int it returns.

    :param subparsers: the ``argparse`` sub-parser collection of ``ncperf``.
    :returns: nothing.
    """


@hookspec(firstresult=True)
def ncperf_read_trace(source: object, options: TraceOptions) -> Trace | None:
    """Read a measured trace (positions, feed, program lines over time).

    Stops at the first non-None result: a reader returns None for a source it does not
    recognise, and raises :class:`~core.model.errors.InputError` (file and line) for one it
    recognises but cannot read faithfully (non-monotone time, NaN rows...).

    :param source: a file path or a host object.
    :param options: units and kind (setpoint or actual) the user gave, if any.
    :returns: the trace (mm, s), or None.
    """


@hookspec
def ncperf_effects() -> list[Effect]:
    """Unmodelled effects this plugin knows (``ncperf diagnose``, ``[effects.NAME]``).

    Every plugin is called; the effects' names must be unique.

    :returns: a list of :class:`~core.engine.effects.Effect`.
    """
