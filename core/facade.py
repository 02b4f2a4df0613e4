"""The typed facade over the plugin manager: the only code that calls ``pm.hook``.

It runs the paper's three tasks in order: A1 extract -> A2 evaluate -> A3 display.
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING

from core.model.errors import Notice, UsageError

# Importing the facade costs no numpy and loads no plugin: each method imports what it runs
# (``ncperf --help`` builds an Ncperf for the plugins' commands only; issue 13).
if TYPE_CHECKING:
    import pluggy

    from core.diagnosis.align import Alignment
    from core.diagnosis.calibrate import Calibration
    from core.diagnosis.diagnose import Diagnosis
    from core.engine.effects import Effect, Setup
    from core.engine.indicators import Evaluation, Indicator
    from core.engine.predict import Prediction
    from core.model.machine import Machine
    from core.model.toolpath import ExtractOptions, ToolPath
    from core.model.trace import Trace, TraceOptions
    from core.view.analysis import Analysis
    from core.view.annotations import Annotations


class Ncperf:
    """Runs the hooks of one plugin manager (a fresh one by default)."""

    def __init__(self, pm: pluggy.PluginManager | None = None) -> None:
        if pm is None:
            from core.plugins import make_plugin_manager

            pm = make_plugin_manager()
        self.pm = pm

    # A1
    def extract(self, source: object, options: ExtractOptions | None = None) -> ToolPath:
        """Read a tool path; UsageError when no adapter recognises the source."""
        from core.model.limits import check_toolpath
        from core.model.toolpath import ExtractOptions, ToolPath

        tp = self.pm.hook.ncperf_extract(source=source, options=options or ExtractOptions())
        if tp is None:
            raise UsageError(
                f"{source}: no adapter recognises this source "
                f"(adapters: {', '.join(self.implementers('ncperf_extract'))})"
            )
        if not isinstance(tp, ToolPath):
            raise TypeError(f"ncperf_extract returned {type(tp).__name__}, not ToolPath")
        check_toolpath(tp)  # whatever the adapter, nothing out of range reaches the models
        return tp

    # A2
    def indicators(self, toolpath: ToolPath, machine: Machine) -> list[Indicator]:
        """Every plugin's indicator results, flattened."""
        from core.engine.indicators import Indicator

        out: list[Indicator] = []
        for result in self.pm.hook.ncperf_evaluate(toolpath=toolpath, machine=machine):
            for ind in result:
                if not isinstance(ind, Indicator):
                    raise TypeError(f"ncperf_evaluate returned {type(ind).__name__}, not Indicator")
                out.append(ind)
        return out

    def evaluate(self, toolpath: ToolPath, machine: Machine) -> Evaluation:
        """The combined prediction of all plugins."""
        from core.engine.indicators import combine

        return combine(toolpath, machine, self.indicators(toolpath, machine))

    # A3
    def display(self, toolpath: ToolPath, annotations: Annotations, target: object) -> object:
        """Draw annotations on a target; UsageError when no display handles it."""
        out = self.pm.hook.ncperf_display(toolpath=toolpath, annotations=annotations, target=target)
        if out is None:
            raise UsageError(
                f"{target}: no display handles this target "
                f"(displays: {', '.join(self.implementers('ncperf_display'))})"
            )
        return out

    # A1 -> A2 (-> A3)
    def analyze(
        self,
        source: object,
        machine: Machine,
        options: ExtractOptions | None = None,
        progress: Callable[[str], None] | None = None,
    ) -> Analysis:
        """A1 + A2: the tool path, its evaluation, feed profile and annotations.
        ``progress``, if given, is told each step as it starts (one short line)."""
        from core.engine.effects import setup_for
        from core.engine.profile import build_profile
        from core.model.heap import release_free_heap
        from core.view.analysis import Analysis
        from core.view.annotations import build_annotations

        say = progress or (lambda _: None)
        say("reading the program")
        tp = machine_notes(self.extract(source, options), machine)
        release_free_heap()  # the reader's holes (see core.model.heap)
        say(f"the models on {tp.n:,} moves")
        if machine.effects:
            # Effects the machine file switches on are part of its model (issue 5).
            pred = self.predict(tp, setup_for(machine, self.effects()))
            ev, profile = pred.evaluation, pred.profile
            assert profile is not None  # setup_for builds a profile (ramps) by default
        else:
            from core.engine.indicators import combine

            indicators = self.indicators(tp, machine)
            # What follows (combining, the profile) needs the axis shares, the start
            # tangents and the junctions only: the other derived columns go first (1M
            # moves: 96 MB).
            tp.release_derived(keep=("tangent_start", "axis_share", "junctions"))
            ev = combine(tp, machine, indicators)
            del indicators
            release_free_heap()
            say(f"the feed profile of {tp.n:,} moves")
            profile = build_profile(ev, release_directions=True)
        tp.release_derived()  # the models are done with them; the peak is in what follows
        release_free_heap()
        say("zones and colour classes")
        return Analysis(tp, ev, profile, build_annotations(ev, profile))

    def run(
        self,
        source: object,
        machine: Machine,
        target: object,
        options: ExtractOptions | None = None,
    ) -> tuple[Analysis, object]:
        """The paper's Figure 5: extract, evaluate, display."""
        analysis = self.analyze(source, machine, options)
        return analysis, self.display(analysis.toolpath, analysis.annotations, target)

    def predict(self, toolpath: ToolPath, setup: Setup) -> Prediction:
        """The prediction of a :class:`~core.engine.effects.Setup` (a machine and the effects
        switched on) on a tool path, with this manager's plugins."""
        from core.engine.predict import predict

        return predict(self.indicators, toolpath, setup)

    # traces
    def read_trace(self, source: object, options: TraceOptions | None = None) -> Trace:
        """Read a measured trace; UsageError when no reader recognises it."""
        from core.model.trace import Trace, TraceOptions

        tr = self.pm.hook.ncperf_read_trace(source=source, options=options or TraceOptions())
        if tr is None:
            raise UsageError(
                f"{source}: no trace reader recognises this source "
                f"(readers: {', '.join(self.implementers('ncperf_read_trace'))})"
            )
        if not isinstance(tr, Trace):
            raise TypeError(f"ncperf_read_trace returned {type(tr).__name__}, not Trace")
        return tr

    # effects
    def effects(self) -> dict[str, Effect]:
        """Every registered effect by name, in registration order."""
        from core.engine.effects import Effect

        out: dict[str, Effect] = {}
        for result in reversed(self.pm.hook.ncperf_effects()):
            for eff in result:
                if not isinstance(eff, Effect):
                    raise TypeError(f"ncperf_effects returned {type(eff).__name__}, not Effect")
                if eff.name in out:
                    raise ValueError(f"two plugins define the effect {eff.name!r}")
                out[eff.name] = eff
        return out

    def diagnose(
        self,
        cases: Sequence[tuple[ToolPath, Sequence[Alignment], Sequence[str]]],
        base: Setup,
        baseline: str,
        effects: Mapping[str, Effect],
        progress: Callable[[str], None] | None = None,
        *,
        jobs: int = 1,
    ) -> Diagnosis:
        """The diagnosis of programs against their aligned traces (each case: a tool path,
        its alignments and their labels), on one machine (``base``), with these effects
        (see :mod:`core.diagnosis.diagnose`). ``jobs``: worker processes for the fits (the
        same diagnosis, sooner; :mod:`core.diagnosis.parallel`); 1, in this process, unless
        asked."""
        from core.diagnosis.diagnose import diagnose_cases  # only the diagnosis pays for it

        return diagnose_cases(self.indicators, cases, base, baseline, effects, progress, jobs=jobs)

    def calibrate(
        self,
        cases: Sequence[tuple[ToolPath, Sequence[Alignment], Sequence[str]]],
        base: Setup,
        effects: Mapping[str, Effect],
        objective: str = "auto",
        *,
        jobs: int = 1,
        progress: Callable[[str], None] | None = None,
    ) -> Calibration:
        """The machine of ``base`` calibrated on programs and their aligned traces, with
        these (controller) effects, on the ``objective`` "auto", "feed" or "block-time"
        (see :mod:`core.diagnosis.calibrate`). ``jobs``: worker processes for the
        independent fits of each round of the selection (the same calibration, sooner); 1
        unless asked. ``progress``, if given, is told each round's fits."""
        from core.diagnosis.calibrate import calibrate  # only calibration pays for it

        return calibrate(
            self.indicators, cases, base, effects, objective, jobs=jobs, progress=progress
        )

    # command line
    def add_commands(self, subparsers: argparse._SubParsersAction) -> None:
        """Let plugins add ``ncperf`` subcommands."""
        self.pm.hook.ncperf_add_commands(subparsers=subparsers)

    # introspection
    def implementers(self, hook: str) -> list[str]:
        caller = getattr(self.pm.hook, hook)
        return [
            self.pm.get_name(impl.plugin) or repr(impl.plugin)
            for impl in reversed(caller.get_hookimpls())
        ]

    def plugins(self) -> list[tuple[str, list[str]]]:
        """(name, hooks it implements) for every registered plugin."""
        rows = []
        for name, plugin in sorted(self.pm.list_name_plugin(), key=lambda x: str(x[0])):
            if plugin is None:  # blocked (NCPERF_DISABLE_PLUGINS)
                continue
            hooks = sorted(c.name for c in self.pm.get_hookcallers(plugin) or [])
            rows.append((str(name), hooks))
        return rows

    def describe(self, name: str) -> str:
        """What the plugin registered as ``name`` does, in one line: the first line of its
        docstring (a module's, or an object's), or "" when it has none."""
        plugin = self.pm.get_plugin(name)
        doc = getattr(plugin, "__doc__", None) if plugin is not None else None
        if not isinstance(doc, str):
            return ""
        for line in doc.strip().splitlines():
            return line.strip()
        return ""


def machine_notes(tp: ToolPath, machine: Machine) -> ToolPath:
    """The path with what the machine file does not say about it added to its notices
    (rotary axes the program turns but the file gives no limits for)."""
    from core.engine.rotary import missing_axes

    missing = missing_axes(tp, machine)
    if not missing:
        return tp
    axes = ", ".join(missing)
    tables = ", ".join(f"[axes.{a}]" for a in missing)
    note = Notice(
        tp.source,
        None,
        f"rotary axis {axes} turns but {machine.source} has no {tables}: its speed and "
        "acceleration set no limit (rotary-only moves at their programmed rate, rapids "
        "take no time)",
    )
    return dataclasses.replace(tp, notices=(*tp.notices, note))
