"""The ``ncperf`` command line.

Exit status: 0 success, 1 bad input (one line ``FILE:LINE: what is wrong``),
2 usage errors.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import io
import math
import os
import sys
import time
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

from core._version import __version__
from core.cli.output import atomic_writer, check_outputs, transaction
from core.model.errors import InputError, NcperfError, UsageError
from core.model.preset_files import DEFAULT_PRESET
from core.model.text import printable, printable_tree
from core.model.tolerances import SAMPLE_DT
from core.view.targets import COLOURINGS, VIEWS

# The parser and the light commands (--help, --version, machines) import neither numpy nor
# the plugins: each command imports what it uses (issue 13: --help in under 0.15 s).
if TYPE_CHECKING:
    from core.facade import Ncperf
    from core.model.machine import Machine
    from core.model.toolpath import ExtractOptions, ToolPath

DEMO_PROGRAM = "zlevel_cavity.ngc"
DEMO_SVG = "ncperf-demo.svg"
MAX_NOTICES = 10
#: ``profile --dt`` range, s: 1 us (a thousand times finer than a servo cycle) to 1 min.
MIN_DT = 1e-6
MAX_DT = 60.0
#: Most rows ``profile`` writes: 20 million (5.5 hours at 1 ms, about 1.2 GB of CSV, written
#: in about a minute and a half); the samples are computed and written in pieces of
#: SAMPLE_PIECE, so memory stays bounded. Longer cycles take a larger --dt.
MAX_SAMPLES = 20_000_000
SAMPLE_PIECE = 262_144
#: A command shows its progress on a terminal once it has run this long (s): shorter work
#: needs none, and a line flashing past would only distract.
PROGRESS_DELAY = 2.0


def demo_program() -> str:
    """Path of the bundled Z-level demo program."""
    import importlib.util

    # the bundled programs ship as files of the ``examples`` package (found, not imported)
    spec = importlib.util.find_spec("examples")
    if spec is None or spec.origin is None:
        raise UsageError("the bundled examples are not installed (reinstall ncperf)")
    return os.path.join(os.path.dirname(spec.origin), DEMO_PROGRAM)


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line usage error (its own prints the usage block first)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, printable(f"{self.prog}: {message} (see {self.prog} --help)") + "\n")


def _parser(nc: Ncperf) -> argparse.ArgumentParser:
    p = _Parser(
        prog="ncperf",
        description="Predict where a machine tool will fall below the programmed feed, and why "
        "(Tapie, Mawussi, Anselmetti: machining strategy choice, performance viewer).",
    )
    p.add_argument("--version", action="version", version=f"ncperf {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    a = sub.add_parser("analyze", help="predicted feed reduction of a program, and why")
    a.set_defaults(run=cmd_analyze)
    a.add_argument("program", nargs="?", help="tool path file (G-code); none: the bundled demo")
    a.add_argument("--demo", action="store_true", help="run on the bundled Z-level demo program")
    _common(a)
    a.add_argument("--svg", metavar="OUT", help="write the coloured tool path as SVG")
    a.add_argument("--json", metavar="OUT", help="write junctions and elements as JSON")
    _html_options(a, "the interactive viewer: one self-contained HTML file")
    a.add_argument("--view", choices=VIEWS, default="xy", help="SVG projection (default xy)")
    _colour_option(a)

    pr = sub.add_parser("profile", help="the predicted feed profile as a trace (CSV)")
    pr.set_defaults(run=cmd_profile)
    pr.add_argument("program", help="tool path file (G-code)")
    _common(pr)
    pr.add_argument(
        "--csv",
        metavar="OUT",
        required=True,
        help="write t,x,y,z,v,line (s, mm, mm/s, 1-based line) every --dt",
    )
    pr.add_argument(
        "--dt", type=float, default=SAMPLE_DT, help=f"time step in s (default {SAMPLE_DT:g})"
    )

    c = sub.add_parser("compare", help="rank machining strategies by predicted cycle time")
    c.set_defaults(run=cmd_compare)
    c.add_argument("programs", nargs="+", metavar="PROGRAM", help="two or more tool path files")
    _common(c)
    c.add_argument("--svg", metavar="OUT", help="the programs side by side, one colour scale")
    _html_options(c, "the programs side by side in the interactive viewer, with the ranking")
    c.add_argument("--view", choices=VIEWS, default="xy", help="SVG projection (default xy)")
    _colour_option(c)

    d = sub.add_parser(
        "diagnose",
        help="where and why a measured trace differs from the "
        "prediction, and which unmodelled effect explains it",
    )
    d.set_defaults(run=cmd_diagnose)
    d.add_argument("program", help="tool path file (G-code or CL data)")
    d.add_argument(
        "traces",
        nargs="+",
        metavar="TRACE",
        help="measured traces (CSV t,x,y,z[,v][,line]; MTConnect SHDR)",
    )
    _common(d)
    d.add_argument(
        "--baseline",
        choices=("paper", "profile"),
        default="profile",
        help="the paper's point model or the full feed profile (default)",
    )
    d.add_argument(
        "--effects", metavar="A,B,...", help="only these effects (default: every registered effect)"
    )
    _trace_options(d, "the trace's")
    _jobs_option(d, "the alignment and the effects' fits")
    d.add_argument("--json", metavar="OUT", help="write the diagnosis as JSON")
    d.add_argument("--svg", metavar="OUT", help="the path coloured by gap, and feed plots")
    _html_options(d, "the interactive viewer, coloured by gap, measured and predicted feed")
    d.add_argument("--view", choices=VIEWS, default="xy", help="SVG projection (default xy)")

    cal = sub.add_parser(
        "calibrate",
        help="fit a machine file to measured traces (checked on programs or runs it was not "
        "fitted on)",
    )
    cal.set_defaults(run=cmd_calibrate)
    cal.add_argument("program", help="tool path file (G-code or CL data)")
    cal.add_argument("traces", nargs="+", metavar="TRACE", help="its measured traces")
    cal.add_argument(
        "--also",
        nargs="+",
        action="append",
        metavar="PROGRAM_OR_TRACE",
        help="another program and its traces (repeat for more programs)",
    )
    _common(cal)
    cal.add_argument(
        "--out", metavar="MACHINE.toml", required=True, help="the machine file to write"
    )
    cal.add_argument(
        "--effects",
        metavar="A,B,...",
        help="only these controller effects (default: every one ncperf calibrates)",
    )
    cal.add_argument(
        "--objective",
        choices=("auto", "feed", "block-time"),
        default="auto",
        help="what the fit minimises: the feed gap along the path, or the time between "
        "observed program-line changes over feed blocks (default auto: block time when every "
        "trace carries program lines and samples coarser than 50 ms, as MTConnect does)",
    )
    _trace_options(cal, "the traces'")
    _jobs_option(cal, "the alignments and the fits of each round of the selection")

    m = sub.add_parser("machines", help="list machine presets (the names --machine takes)")
    m.set_defaults(run=cmd_machines, plugins=False)
    pl = sub.add_parser("plugins", help="list registered plugins and the hooks they implement")
    pl.set_defaults(run=cmd_plugins)
    nc.add_commands(sub)  # the plugins' own commands
    return p


def _html_options(p: argparse.ArgumentParser, what: str) -> None:
    p.add_argument("--html", metavar="OUT", help=f"write {what}")
    p.add_argument("--open", action="store_true", help="open the written HTML in a web browser")


def _check_open(args: argparse.Namespace) -> None:
    if args.open and not args.html:
        raise UsageError("--open opens the file --html writes: give --html OUT.html")


def _html_written(args: argparse.Namespace, written: object) -> None:
    """Print the HTML file written; with --open, have it opened once the run has succeeded
    (its outputs are renamed into place at the end of the transaction)."""
    print(f"  html             {written}")
    if args.open:
        args.open_after = str(written)


def _open_html(path: str) -> None:
    """Open ``path`` in the user's web browser, as a ``file:`` URI."""
    import webbrowser

    if not webbrowser.open(Path(path).resolve().as_uri()):
        print(f"ncperf: no web browser found to open {path}", file=sys.stderr)


def _colour_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--colour",
        choices=COLOURINGS,
        default="speed",
        help="colour blocks by the feed profile's mean speed over each against F (speed, "
        "default: where the time goes) or by each block's own cruise feed (paper, Fig. 11)",
    )


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--machine",
        metavar="PRESET|FILE",
        help=f"machine preset name or TOML file (default: {DEFAULT_PRESET})",
    )
    p.add_argument(
        "--dialect",
        choices=("fanuc", "siemens", "linuxcnc"),
        help="G-code dialect (default: from the file)",
    )
    p.add_argument(
        "--block-delete",
        action="store_true",
        help="skip blocks starting with '/' (block-delete switch on)",
    )
    p.add_argument(
        "--no-naive-cam",
        dest="naive_cam",
        action="store_false",
        help="LinuxCNC programs: read every block as a segment of its own (by default nearly "
        "collinear blocks under G64 P/Q run as the one segment LinuxCNC makes of them)",
    )
    p.add_argument(
        "--tool-radius",
        type=float,
        metavar="MM",
        help="tool radius for cutter compensation G41/G42 (default: the machine's tool table)",
    )


def _trace_options(p: argparse.ArgumentParser, whose: str) -> None:
    p.add_argument("--trace-units", choices=("mm", "inch"), help="trace units (default mm)")
    p.add_argument(
        "--trace-kind",
        choices=("setpoint", "actual"),
        help=f"what {whose} positions are (default: from the reader)",
    )


def _jobs_option(p: argparse.ArgumentParser, what: str) -> None:
    p.add_argument(
        "--jobs",
        type=int,
        metavar="N",
        help=f"worker processes for {what} (default: the CPUs ncperf may use; 1: none, all "
        "in this process; the result is the same)",
    )


def _jobs(args: argparse.Namespace) -> int:
    """The worker processes --jobs asks for, or the default (the CPUs this process may use)."""
    from core.model.workers import default_jobs

    if args.jobs is None:
        return default_jobs()
    if args.jobs < 1:
        raise UsageError(f"--jobs must be 1 or more worker processes, got {args.jobs}")
    return int(args.jobs)


def _wanted(spec: str | None, known: list[str], unknown_message: str) -> list[str] | None:
    """The names of a comma-separated ``--effects`` (None when not given); a name not in
    ``known`` is a usage error: ``unknown_message`` formatted with ``names`` and ``known``."""
    if not spec:
        return None
    wanted = [e.strip() for e in spec.split(",") if e.strip()]
    unknown = [e for e in wanted if e not in known]
    if unknown:
        raise UsageError(unknown_message.format(names=", ".join(unknown), known=", ".join(known)))
    return wanted


def _aligned(
    nc: Ncperf,
    tp: ToolPath,
    paths: list[str],
    args: argparse.Namespace,
    purpose: str,
    progress: _Progress | None = None,
    jobs: int = 1,
) -> tuple[list, list[str]]:
    """Each trace read (its warnings printed, below a ``progress`` line if one is up) and
    aligned on ``tp`` (on ``jobs`` worker processes), and its label; a trace that does not
    align is an error ending "no ``purpose``"."""
    from core.diagnosis.align import align
    from core.model.jit import allow
    from core.model.trace import TraceOptions

    allow()  # the compiled kernels from the reading of the traces on (core.model.jit)
    options = TraceOptions(units=args.trace_units, kind=args.trace_kind)
    alignments, labels = [], []
    for path in paths:
        tr = nc.read_trace(path, options)
        if progress is not None and tr.notices:
            progress.clear()  # the warnings start on a line of their own
        _print_notices(tr.notices, sys.stderr)
        al = align(tp, tr, jobs=jobs)
        if not al.ok:
            raise InputError(f"{al.message}; no {purpose}", source=path)
        alignments.append(al)
        labels.append(Path(path).name)
    return alignments, labels


def _machine(args: argparse.Namespace) -> tuple:
    from core.model.machine import resolve_machine

    machine = resolve_machine(args.machine)
    note = "" if args.machine else f" [preset {DEFAULT_PRESET}, the default; --machine to choose]"
    return machine, note


def _options(args: argparse.Namespace, machine: Machine) -> ExtractOptions:
    from core.model.toolpath import ExtractOptions

    setup = machine.setup
    if args.tool_radius is not None:
        if not (math.isfinite(args.tool_radius) and args.tool_radius >= 0):
            raise UsageError(f"--tool-radius must be a length >= 0 (mm), got {args.tool_radius:g}")
        setup = dataclasses.replace(setup, tool_radius=args.tool_radius)
    return ExtractOptions(
        dialect=args.dialect,
        block_delete=args.block_delete,
        setup=setup,
        naive_cam=args.naive_cam,
    )


def _print_notices(tp_notices: tuple, stream) -> None:
    for n in tp_notices[:MAX_NOTICES]:
        print(n, file=stream)
    if len(tp_notices) > MAX_NOTICES:
        print(f"... and {len(tp_notices) - MAX_NOTICES} more warnings", file=stream)


def cmd_analyze(args: argparse.Namespace, nc: Ncperf) -> int:
    from core.cli.report import summary, write_json
    from core.view.targets import FileTarget

    demo = args.demo or args.program is None
    if args.demo and args.program:
        raise UsageError("give a program or --demo, not both")
    program = demo_program() if demo else args.program
    svg = args.svg if args.svg or not demo or args.html else DEMO_SVG
    _check_open(args)
    check_outputs((svg, args.json, args.html), (program, args.machine))
    machine, note = _machine(args)
    with _Progress("ncperf analyze", sys.stderr) as progress:
        analysis = nc.analyze(program, machine, _options(args, machine), progress)
        report = summary(analysis, machine_note=note)
        if args.json:
            progress("writing the JSON")
            with atomic_writer(args.json) as fh:
                write_json(analysis, fh)
        html = None
        if args.html:  # before the evaluation and profile go: the page shows them
            from core.view.html_target import HtmlTarget

            progress("writing the HTML")
            panel = (Path(program).name, analysis, program)
            page = HtmlTarget(args.html, (panel,), view=args.view, colour=args.colour)
            html = nc.display(analysis.toolpath, analysis.annotations, page)
        tp, ann = analysis.toolpath, analysis.annotations
        # What is left to draw needs the path and its classes only: the evaluation and the
        # profile go before the drawing's own peak (1M moves: about 300 MB less).
        del analysis
        written = None
        if svg:
            progress("writing the SVG")
            target = FileTarget(svg, view=args.view, colour=args.colour)
            written = nc.display(tp, ann, target)
    _print_notices(tp.notices, sys.stderr)
    print(report)
    if written is not None:
        print(f"  svg              {written}")
    if html is not None:
        _html_written(args, html)
    if args.json:
        print(f"  json             {args.json}")
    return 0


def cmd_profile(args: argparse.Namespace, nc: Ncperf) -> int:
    from core.cli.report import fmt_time, write_samples

    if not (MIN_DT <= args.dt <= MAX_DT):
        raise UsageError(f"--dt must be {MIN_DT:g} to {MAX_DT:g} s, got {args.dt:g}")
    check_outputs((args.csv,), (args.program, args.machine))
    machine, note = _machine(args)
    with _Progress("ncperf profile", sys.stderr) as progress:
        analysis = nc.analyze(args.program, machine, _options(args, machine), progress)
        pr = analysis.profile
        n = pr.n_samples(args.dt)
        if n > MAX_SAMPLES:
            raise UsageError(
                f"--dt {args.dt:g} s gives {n:,} samples over the {fmt_time(pr.cycle_time)} "
                f"cycle (at most {MAX_SAMPLES:,}, about {MAX_SAMPLES * 60 // 10**9} GB of CSV): "
                f"take --dt {pr.cycle_time / (MAX_SAMPLES - 1):.2g} or more"
            )
        with atomic_writer(args.csv) as fh:
            for first in range(0, n, SAMPLE_PIECE):  # bounded memory, however long the cycle
                progress(f"writing the samples: {first / n:.0%} of {n:,}")
                write_samples(
                    pr.sample(args.dt, first=first, count=SAMPLE_PIECE), fh, header=not first
                )
    _print_notices(analysis.toolpath.notices, sys.stderr)
    tp = analysis.toolpath
    print(f"ncperf profile: {tp.source} on {machine.name}{note}")
    print(
        f"  predicted cycle  {fmt_time(pr.cycle_time)} (programmed feed time "
        f"{fmt_time(tp.programmed_time)})"
    )
    print(f"  csv              {args.csv} ({n:,} samples every {args.dt:g} s)")
    return 0


def cmd_compare(args: argparse.Namespace, nc: Ncperf) -> int:
    from core.cli.compare import ranked
    from core.cli.compare import row as compare_row
    from core.cli.compare import table as compare_table
    from core.cli.report import fmt_time
    from core.view.targets import ComparisonTarget

    if len(args.programs) < 2:
        raise UsageError("compare needs two or more programs")
    _check_open(args)
    check_outputs((args.svg, args.html), (*args.programs, args.machine))
    machine, note = _machine(args)
    rows, panels = [], []
    with _Progress("ncperf compare", sys.stderr) as progress:
        for k, program in enumerate(args.programs, start=1):
            head = f"{Path(program).name} ({k} of {len(args.programs)})"

            def step(text: str, head: str = head) -> None:
                progress(f"{head}: {text}")

            an = nc.analyze(program, machine, _options(args, machine), step)
            progress.clear()  # the warnings on lines of their own
            _print_notices(an.toolpath.notices, sys.stderr)
            r = compare_row(Path(program).name, an)
            rows.append(r)
            panels.append((r, an))
    print(compare_table(rows, machine.name + note))
    if args.svg:
        order = {id(r): k for k, r in enumerate(ranked(rows), start=1)}
        items = tuple(
            (
                f"#{order[id(r)]} {r.label}: predicted {fmt_time(r.cycle_time)}",
                an.toolpath,
                an.annotations,
            )
            for r, an in panels
        )
        target = ComparisonTarget(args.svg, items, view=args.view, colour=args.colour)
        written = nc.display(items[0][1], items[0][2], target)
        print(f"  svg              {written}")
    if args.html:
        from core.cli.compare import html_table
        from core.view.html_target import HtmlTarget

        rank = {id(r): k for k, r in enumerate(ranked(rows), start=1)}
        by_rank = sorted(
            zip(rows, panels, args.programs, strict=True), key=lambda x: rank[id(x[0])]
        )
        html = HtmlTarget(
            args.html,
            tuple((f"#{rank[id(r)]} {r.label}", p[1], prog) for r, p, prog in by_rank),
            table=html_table(rows),
            view=args.view,
            colour=args.colour,
        )
        first = by_rank[0][1][1]
        _html_written(args, nc.display(first.toolpath, first.annotations, html))
    return 0


def cmd_diagnose(args: argparse.Namespace, nc: Ncperf) -> int:
    from core.cli.diagnosis_report import report, to_json
    from core.engine.effects import setup_for

    _check_open(args)
    jobs = _jobs(args)
    check_outputs((args.json, args.svg, args.html), (args.program, *args.traces, args.machine))
    machine, note = _machine(args)
    effects = nc.effects()
    wanted = _wanted(args.effects, list(effects), "unknown effect {names} (effects: {known})")
    if wanted is not None:
        effects = {k: effects[k] for k in wanted}
    tp = nc.extract(args.program, _options(args, machine))
    _print_notices(tp.notices, sys.stderr)
    with _Progress("ncperf diagnose", sys.stderr) as progress:
        progress(f"aligning {len(args.traces)} trace(s) on {Path(args.program).name}")
        alignments, labels = _aligned(nc, tp, args.traces, args, "diagnosis", progress, jobs)
        base = setup_for(machine, nc.effects(), ramps=args.baseline == "profile")
        d = nc.diagnose(
            [(tp, alignments, labels)], base, args.baseline, effects, progress, jobs=jobs
        )
    print(
        report(
            d,
            program=tp.source,
            machine=machine.name + note,
            labels=labels,
            effects=nc.effects(),
            machine_file=machine,
        )
    )
    if args.json:
        import json

        with atomic_writer(args.json) as fh:
            data = printable_tree(to_json(d, machine, nc.effects()))
            json.dump(data, fh, indent=1, allow_nan=False)
            fh.write("\n")
        print(f"  json             {args.json}")
    if args.svg:
        from core.diagnosis.diagnose import DiagnosisTarget

        written = nc.display(tp, d.annotations(), DiagnosisTarget(args.svg, d, view=args.view))
        print(f"  svg              {written}")
    if args.html:
        from core.view.html_target import HtmlTarget

        panel = (Path(args.program).name, None, args.program)
        target = HtmlTarget(args.html, (panel,), diagnosis=d, view=args.view)
        _html_written(args, nc.display(tp, d.annotations(), target))
    return 0


def cmd_calibrate(args: argparse.Namespace, nc: Ncperf) -> int:
    import datetime

    from core.cli.calibration_report import machine_toml
    from core.cli.calibration_report import report as cal_report
    from core.diagnosis.calibrate import CONTROLLER_EFFECTS
    from core.engine.effects import setup_for
    from core.model.machine import machine_from_toml_text, machine_text

    jobs = _jobs(args)
    groups = [[args.program, *args.traces], *(args.also or [])]
    check_outputs((args.out,), (*(f for g in groups for f in g), args.machine))
    for g in groups:
        if len(g) < 2:
            raise UsageError(f"--also {g[0]}: give the program and at least one trace")
    machine, note = _machine(args)
    effects = nc.effects()
    names = [e for e in CONTROLLER_EFFECTS if e in effects]
    wanted = _wanted(args.effects, names, "cannot calibrate {names} (controller effects: {known})")
    if wanted is not None:
        names = wanted
    cases, all_labels = [], []
    with _Progress("ncperf calibrate", sys.stderr) as progress:
        for program, *traces in groups:
            progress(f"reading {Path(program).name}")
            tp = nc.extract(program, _options(args, machine))
            progress.clear()
            _print_notices(tp.notices, sys.stderr)
            progress(f"aligning {len(traces)} trace(s) on {Path(program).name}")
            als, labels = _aligned(nc, tp, traces, args, "calibration", progress, jobs)
            cases.append((tp, als, labels))
            all_labels += labels
        base = setup_for(machine, effects, ramps=True)
        progress(f"calibrating {len(names)} effect(s) on {len(all_labels)} trace(s)")
        cal = nc.calibrate(
            cases,
            base,
            {k: effects[k] for k in names},
            args.objective,
            jobs=jobs,
            progress=progress,
        )
    header = "\n".join(
        [
            f"Made by ncperf calibrate ({__version__}) on {datetime.date.today()} from",
            f"the machine {machine.name!r} and {len(all_labels)} trace(s) of "
            f"{len(groups)} program(s):",
            *(f"  {Path(g[0]).name}: {', '.join(Path(t).name for t in g[1:])}" for g in groups),
            f"Held out: {cal.held_out}.",
            f"Objective: {cal.objective.name} ({cal.objective_reason}).",
            f"Held-out gap ({cal.objective.what}), start -> calibrated: "
            + "; ".join(
                f"fold {'AB'[k]} {b:.1f} -> {a:.1f} {cal.objective.unit}"
                for k, (b, a) in enumerate(zip(cal.gap_before, cal.gap_after, strict=True))
            ),
            f"Effects tried: {', '.join(cal.tried)}.",
            "Calibrated: " + (", ".join(c.name for c in cal.effects) or "nothing") + ".",
        ]
    )
    # File names from the command line may hold controls or bytes that are not UTF-8.
    header = printable(header, lines=True)
    text = machine_toml(cal, machine_text(args.machine), machine, effects, header=header)
    machine_from_toml_text(text, args.out)  # what is written must load
    with atomic_writer(args.out) as fh:
        fh.write(text)
    print(cal_report(cal, start=machine.name + note, out=args.out, labels=all_labels))
    return 0


def cmd_machines(_: argparse.Namespace, nc: Ncperf | None) -> int:
    from core.model.preset_files import preset_names, preset_title

    for name in preset_names():
        default = "  (default)" if name == DEFAULT_PRESET else ""
        print(f"{name}\t{preset_title(name)}{default}")
    return 0


def cmd_plugins(_: argparse.Namespace, nc: Ncperf) -> int:
    rows = nc.plugins()
    width = max((len(name) for name, _ in rows), default=0)
    for name, hooks in rows:
        what = nc.describe(name) or "(no description: the plugin has no docstring)"
        print(f"{name:{width}s}  {what}")
        print(f"{'':{width}s}  hooks: {', '.join(hooks)}")
    return 0


class _Progress:
    """What a long command is doing, on one line of a terminal that each step overwrites
    (with the time since the start); nothing when the stream is not a terminal (a log or a
    pipe gets the report only). Nothing either for work shorter than ``delay`` seconds:
    from then on the line shows the current step and, while a step lasts, its seconds tick
    (a background thread redraws it twice a second). As a context manager it clears the
    line at the end. The step's text goes through :func:`printable`; only the carriage
    returns are its own."""

    def __init__(self, command: str, stream: Any, *, delay: float = PROGRESS_DELAY) -> None:
        import threading

        self._t0 = time.monotonic()
        self._command = command
        self._stream = getattr(stream, "raw_stream", stream)  # past _Printable: "\r" stays
        self._on = bool(getattr(stream, "isatty", lambda: False)())
        self._width = 0
        self._delay = delay
        self._step = ""
        self._paused = False
        self._lock = threading.Lock()
        self._done = threading.Event()
        self._ticker: threading.Thread | None = None
        if self._on and delay > 0:
            self._ticker = threading.Thread(target=self._tick, name="ncperf-progress", daemon=True)
            self._ticker.start()

    def __call__(self, step: str) -> None:
        if not self._on:
            return
        with self._lock:
            self._step, self._paused = step, False
            if time.monotonic() - self._t0 >= self._delay:
                self._draw()

    def _tick(self) -> None:
        if self._done.wait(self._delay):
            return
        while True:
            with self._lock:
                if self._step and not self._paused:
                    self._draw()
            if self._done.wait(0.5):
                return

    def _draw(self) -> None:
        line = printable(f"{self._command}: {self._step} [{time.monotonic() - self._t0:.0f} s]")
        self._stream.write("\r" + line.ljust(self._width))
        self._stream.flush()
        self._width = len(line)

    def __enter__(self) -> _Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        self._done.set()
        if self._ticker is not None:
            self._ticker.join()
        self.clear()

    def clear(self) -> None:
        """Blank the line (before other output; the next step writes it again)."""
        with self._lock:
            self._paused = True
            if self._on and self._width:
                self._stream.write("\r" + " " * self._width + "\r")
                self._stream.flush()
                self._width = 0


class _Printable(io.TextIOBase):
    """A terminal stream that shows every control character from an input as an escape
    (:func:`printable`): whatever reaches the terminal, from any report, cannot act on it."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream

    @property
    def raw_stream(self) -> Any:
        """The terminal itself, for a writer that escapes its own text (:class:`_Progress`)."""
        return self._stream

    def write(self, s: str) -> int:
        self._stream.write(printable(s, lines=True))
        return len(s)

    def flush(self) -> None:
        self._stream.flush()

    def isatty(self) -> bool:
        return bool(self._stream.isatty())

    def fileno(self) -> int:
        return int(self._stream.fileno())


def main(argv: list[str] | None = None) -> int:
    """The ``ncperf`` command: ``argv`` (the process's arguments if None: then the process
    ends here, see :func:`_end_process`); returns the exit status."""
    # (numpy's BLAS threads: set in core/cli/__init__.py, before anything loads numpy)
    out, err = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = _Printable(out), _Printable(err)
    try:
        rc = _main(argv)
    finally:
        sys.stdout, sys.stderr = out, err
    if argv is None:  # the program itself (the console script, python -m core)
        _end_process(rc)
    return rc


def _end_process(rc: int) -> None:
    """End the process with status ``rc`` once its output is flushed, without the
    interpreter's teardown -- freeing every module and array one by one, which nothing
    needs once the outputs are written and closed (they are: atomic_writer renames each
    file into place before the command returns): stellabee1's analyze 0.05 s of 0.8
    (2026-11-28). The normal way where something still has to run at exit: worker
    processes alive, or a profiler or tracer that writes its report then."""
    mp = sys.modules.get("multiprocessing")
    if (mp is not None and mp.active_children()) or sys.getprofile() or sys.gettrace():
        sys.exit(rc)
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except BrokenPipeError:  # (read by a pipe that closed early: not an error of ours)
            pass
        except OSError as exc:  # (a full disk under a redirection, say)
            with contextlib.suppress(OSError):
                os.write(2, f"ncperf: cannot write the output: {exc}\n".encode())
            rc = rc or 1
    os._exit(rc)


def _fill_heap_ahead(args: argparse.Namespace) -> None:
    """The heap's pages faulted in on the second core ahead of an analysis
    (:func:`core.model.heap.prefault_heap`), sized by the largest program file of
    ``analyze``, ``profile`` or ``compare`` (their analyses reuse each other's memory). Not
    for ``diagnose`` and ``calibrate``: their fits run on forked processes, whose first
    write to a page inherited from this one faults it in again, as a new page does."""
    if args.run not in (cmd_analyze, cmd_profile, cmd_compare):
        return
    from core.model.heap import prefault_heap, prefault_size

    paths = getattr(args, "programs", None) or [getattr(args, "program", None)]
    # (a path that is not a file: its error comes with the reading)
    sizes = [os.path.getsize(p) for p in paths if p and os.path.isfile(p)]
    if sizes:
        prefault_heap(prefault_size(max(sizes)))


def _main(argv: list[str] | None) -> int:
    from core.facade import Ncperf
    from core.plugins import command_plugin_manager, complete_plugin_manager

    try:
        # The parser needs only the plugins that add commands; the others (and numpy) are
        # loaded once a command that uses them is chosen (--help, machines: never).
        nc = Ncperf(command_plugin_manager())
        args = _parser(nc).parse_args(argv)
        if getattr(args, "plugins", True):
            # a command that analyses: its stages reuse each other's freed memory
            # (core.model.heap: stellabee1 60,300 -> 25,800 page faults)
            from core.model.heap import keep_freed_memory

            keep_freed_memory()
            _fill_heap_ahead(args)  # (while the plugins and numpy are imported)
            nc = Ncperf(complete_plugin_manager(nc.pm))
    except NcperfError as exc:
        print(f"ncperf: {exc}", file=sys.stderr)
        return 2
    try:
        # a failure leaves none of the run's outputs behind; numpy's floating-point warnings
        # (an overflow to inf that the models read as "no limit") are not for the user:
        # results are checked finite where they are made, and bad input is a line error
        with transaction(), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            rc = int(args.run(args, nc))
        if rc == 0 and getattr(args, "open_after", None):
            _open_html(args.open_after)  # once the file is in place
        return rc
    except UsageError as exc:
        print(f"ncperf: {exc}", file=sys.stderr)
        return 2
    except NcperfError as exc:
        print(str(exc), file=sys.stderr)
        return 1
    except MemoryError:
        print(
            f"ncperf: out of memory ({args.command}); the input needs more than this machine has",
            file=sys.stderr,
        )
        return 1
    except KeyboardInterrupt:
        print("ncperf: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # stdout closed early (e.g. piped into head): not an error of ours.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
