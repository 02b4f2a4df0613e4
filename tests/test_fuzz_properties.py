"""Property tests over generated and mutated input (the fuzz harness's small, reproducible run).

The property for every reader: the call raises :class:`~core.model.errors.NcperfError` (any
subclass) or returns a result whose numbers are all finite; never any other exception, never
a hang (a time limit per input) and never unbounded memory (an address-space limit per input).

The property for the command line (``main(argv)`` in process): exit code 0, 1 or 2; no
traceback; no control character on stdout or stderr but newline and tab (no ESC, CR, DEL, C1
controls, nor Unicode line separators and bidi overrides); on failure exactly one line on
stderr besides the ``FILE:LINE: warning:`` notices; on failure none of the output files the
run was given exists afterwards (nor a temporary ``.part`` file); on success the JSON parses
without NaN or Infinity, the SVG is well-formed XML, the CSV holds finite numbers.

Inputs come from :mod:`tests.fuzz_inputs` (grammars of G-code, CL data, traces, mutated
examples and machine presets, random bytes), driven either by Hypothesis ``randoms()`` or by a
seeded ``random.Random`` (the seed is shown); ``derandomize=True`` makes every CI run try the
same inputs.
``benchmarks/fuzz.py`` runs the same generators and the same checks for minutes.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import random
import re
import resource
import shutil
import signal
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, note, settings
from hypothesis import strategies as st

from core.cli.main import main
from core.facade import Ncperf
from core.model.errors import NcperfError
from core.model.machine import Machine, machine_from_toml_text, resolve_machine
from core.model.toolpath import ExtractOptions, ToolPath
from core.model.trace import Trace, TraceOptions
from core.view.analysis import Analysis, totals
from tests import fuzz_inputs as F

#: Seconds one input may take (the slowest legitimate case here, a diagnosis, takes ~5 s).
TIME_LIMIT = 20
#: Address space one input may add to the process.
MEMORY_LIMIT = 3 << 30

#: No shrinking: an input that hangs or fills memory would be retried for minutes, and a
#: command line run costs up to seconds. A failure is reported as found, its input files in
#: Hypothesis' notes; ``benchmarks/fuzz.py`` minimizes what it finds.
FUZZ = settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    database=None,
    print_blob=True,
    suppress_health_check=list(HealthCheck),
    phases=[Phase.explicit, Phase.reuse, Phase.generate],
)

#: What no terminal output may contain: C0 controls but tab and newline, DEL, C1 controls,
#: Unicode line/paragraph separators and bidi overrides (printable() escapes them all).
CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]")
NOT_FINITE_WORD = re.compile(r"(?<![\w.])(nan|-?inf|infinity|n/a)(?![\w])", re.IGNORECASE)

NC = Ncperf()
MACHINES = {name: resolve_machine(name) for name in ("siemens-840d", "linuxcnc-sim")}
SMALL_PROGRAM = (F.EXAMPLES / "fig4_points_d5.ngc").read_bytes()


class PropertyViolation(AssertionError):
    """A result that breaks the property; ``kind`` names the rule (for deduplication)."""

    def __init__(self, kind: str, detail: str = "") -> None:
        super().__init__(f"{kind}: {detail}" if detail else kind)
        self.kind = kind


class InputTimeout(Exception):
    """One input ran past :data:`TIME_LIMIT`."""


def require(ok: object, kind: str, detail: str = "") -> None:
    if not ok:
        raise PropertyViolation(kind, detail)


# ----------------------------------------------------------------------------- limits
def _vm_size() -> int:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


@contextlib.contextmanager
def limits(seconds: int = TIME_LIMIT, memory: int = MEMORY_LIMIT) -> Iterator[None]:
    """A time limit (SIGALRM raises :class:`InputTimeout`) and an address-space limit for one
    input; both undone afterwards."""

    def expire(signum: int, frame: object) -> None:
        raise InputTimeout(f"input took more than {seconds} s")

    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    vm = _vm_size()
    if vm:
        cap = vm + memory
        if hard != resource.RLIM_INFINITY:
            cap = min(cap, hard)
        with contextlib.suppress(ValueError, OSError):
            resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    old = signal.signal(signal.SIGALRM, expire)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
        with contextlib.suppress(ValueError, OSError):
            resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


# ----------------------------------------------------------------------------- result checks
def _finite(name: str, a: Any) -> None:
    arr = np.asarray(a, dtype=np.float64)
    if not np.isfinite(arr).all():
        bad = arr[~np.isfinite(arr)].ravel()[:3]
        raise PropertyViolation(f"non-finite {name}", f"{bad}")


def check_toolpath(tp: ToolPath) -> None:
    """Positions, lengths, feeds of feed moves, arcs and dwells finite (NaN only where the
    ToolPath documents it: feeds of rapids, arc columns of lines, tolerance not set)."""
    require(isinstance(tp, ToolPath), "not a ToolPath", type(tp).__name__)
    _finite("toolpath.start", tp.start)
    _finite("toolpath.end", tp.end)
    _finite("toolpath.dwell", tp.dwell)
    require(bool((tp.dwell >= 0).all()), "negative toolpath.dwell")
    feed, arc = tp.is_feed, tp.is_arc
    _finite("toolpath.feed", tp.feed[feed])
    require(bool((tp.feed[feed] > 0).all()), "feed move without a positive feed")
    _finite("toolpath.center", tp.center[arc])
    _finite("toolpath.normal", tp.normal[arc])
    _finite("toolpath.sweep", tp.sweep[arc])
    require(not np.isinf(tp.tolerance).any(), "infinite toolpath.tolerance")
    if tp.tool_axis is not None:
        _finite("toolpath.tool_axis", tp.tool_axis)
    if tp.rotary is not None:
        _finite("toolpath.rotary", tp.rotary)
    if tp.rotary_only is not None:
        _finite("toolpath.rotary_only.travel", tp.rotary_only.travel)
    _finite("toolpath.length", tp.length)
    _finite("toolpath.feed_length", tp.feed_length)
    _finite("toolpath.programmed_time", tp.programmed_time)


def check_analysis(an: Analysis) -> None:
    """The tool path, the profile, the evaluation and the summary figures all finite."""
    check_toolpath(an.toolpath)
    pr, ev, tp = an.profile, an.evaluation, an.toolpath
    for name in (
        "cap",
        "v_entry",
        "v_peak",
        "v_exit",
        "a_up",
        "a_down",
        "time",
        "hold_start",
        "hold_end",
        "hold_start_ratio",
        "hold_end_ratio",
    ):
        _finite(f"profile.{name}", getattr(pr, name))
    _finite("profile.lead", pr.lead)
    _finite("profile.cycle_time", pr.cycle_time)
    _finite("evaluation.paper_time", ev.paper_time)
    for name in ("junction_programmed", "junction_feed", "junction_hold", "junction_travel"):
        _finite(f"evaluation.{name}", getattr(ev, name))
    _finite("evaluation.element_feed", ev.element_feed[tp.is_feed])
    for key, value in totals(an).items():  # InputError here is allowed: it is the safety net
        _finite(f"totals.{key}", value)


def check_trace(tr: Trace) -> None:
    require(isinstance(tr, Trace), "not a Trace", type(tr).__name__)
    _finite("trace.t", tr.t)
    require(tr.t.size == 0 or tr.t[0] == 0, "trace.t does not start at 0")
    require(bool((np.diff(tr.t) > 0).all()), "trace.t does not increase")
    if tr.pos is not None:
        _finite("trace.pos", tr.pos)
    if tr.v is not None:
        _finite("trace.v", tr.v)
    if tr.line is not None:
        require(bool((tr.line >= 0).all()), "negative trace.line")


def check_machine(m: Machine) -> None:
    require(isinstance(m, Machine), "not a Machine", type(m).__name__)
    for name in ("max_feed", "max_acceleration", "interpolation_time", "path_tolerance"):
        _finite(f"machine.{name}", getattr(m, name))
        require(bool(np.all(np.asarray(getattr(m, name)) > 0)), f"machine.{name} not positive")
    _finite("machine.curvature_transition_time", m.curvature_transition_time)
    require(bool(np.all(m.max_jerk > 0)), "machine.max_jerk not positive (or NaN)")
    require(m.max_path_feed > 0, "machine.max_path_feed not positive (or NaN)")
    _finite("machine.normal_acceleration_factor", m.normal_acceleration_factor)
    for _, params, _ in m.effects:
        _finite("machine effect parameter", list(params.values()))
    for ax in m.rotary.values():
        _finite("machine.rotary", [ax.max_feed, ax.max_acceleration])
    s = m.setup
    for name in ("home", "home_g30", "tool_radius", "peck_clearance"):
        value = getattr(s, name, None)
        if value is not None:
            _finite(f"machine.setup.{name}", value)
    for offset in s.work_offsets.values():
        _finite("machine.setup.work_offsets", offset)
    for tool in s.tools.values():
        _finite("machine.setup.tools", [v for v in (tool.radius, tool.length) if v is not None])


# ----------------------------------------------------------------------------- reader calls
def show(text: str) -> None:
    """A note in Hypothesis' report of a failing example (nothing outside a test)."""
    with contextlib.suppress(Exception):
        note(text)


def write_input(folder: Path, name: str, data: bytes) -> Path:
    """Write an input file, and show it in Hypothesis' report should the example fail."""
    path = folder / name
    path.write_bytes(data)
    show(f"{name}: {data[:3000]!r}")
    return path


def run_program(path: Path, machine: Machine, dialect: str | None, block_delete: bool) -> None:
    """Extract and analyze one program file; NcperfError is an answer, anything else not."""
    options = ExtractOptions(dialect=dialect, block_delete=block_delete, setup=machine.setup)
    try:
        check_toolpath(NC.extract(str(path), options))
    except NcperfError:
        return  # the analysis would stop at the same error
    try:
        an = NC.analyze(str(path), machine, options)
    except NcperfError:
        return
    check_analysis(an)


def run_trace(path: Path, units: str | None = None, kind: str | None = None) -> None:
    try:
        tr = NC.read_trace(str(path), TraceOptions(units=units, kind=kind))
    except NcperfError:
        return
    check_trace(tr)


def run_machine(text: str, folder: Path) -> None:
    """Load a machine file; when it loads, analyze a small program with it."""
    show(f"machine file: {text!r}")
    try:
        m = machine_from_toml_text(text, str(folder / "m.toml"))
    except NcperfError:
        return
    check_machine(m)
    run_program(write_input(folder, "p.ngc", SMALL_PROGRAM), m, None, False)


# ----------------------------------------------------------------------------- command line
Call = Callable[[list[str]], tuple[int, str, str]]


def exit_code(argv: list[str]) -> int:
    """``main(argv)`` as the console script sees it (argparse exits with SystemExit)."""
    try:
        return main(argv)
    except SystemExit as exc:
        if exc.code is None:
            return 0
        return exc.code if isinstance(exc.code, int) else 1


def call_with_streams(argv: list[str]) -> tuple[int, str, str]:
    """Run ``main`` in process with stdout and stderr captured (outside pytest)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = exit_code(argv)
    return rc, out.getvalue(), err.getvalue()


def strict_json(path: Path) -> object:
    def refuse(c: str) -> float:
        raise PropertyViolation("NaN or Infinity in the JSON", c)

    return json.loads(path.read_text(encoding="utf-8"), parse_constant=refuse)


def check_run(rc: int, out: str, err: str, outputs: list[Path], folder: Path) -> None:
    """The command-line property for one run (see the module docstring)."""
    require(rc in (0, 1, 2), "exit code not 0, 1 or 2", str(rc))
    require("Traceback" not in err, "traceback on stderr", err[-300:])
    for stream, text in (("stdout", out), ("stderr", err)):
        m = CONTROL.search(text)
        require(m is None, f"control character on {stream}", repr(m and m.group()))
    parts = folder.rglob("*.part")
    require(not any(parts), "temporary .part file left behind")
    if rc:
        errors = [
            ln
            for ln in err.split("\n")
            if ln and " warning: " not in ln and not ln.startswith("... and ")
        ]
        require(len(errors) == 1, "stderr on failure is not one line", repr(err[-300:]))
        left = [p for p in outputs if p.exists()]
        require(not left, "output file left by a failed run", str(left))
        return
    word = NOT_FINITE_WORD.search(out)
    if word is not None:
        raise PropertyViolation("non-finite number on stdout", repr(out[word.start() - 60 :][:120]))
    for p in outputs:
        if p.suffix == ".json" and p.is_file():
            strict_json(p)
        elif p.suffix == ".svg" and p.is_file():
            try:
                ET.parse(p)
            except ET.ParseError as exc:
                raise PropertyViolation("SVG not well-formed", str(exc)) from None
        elif p.suffix == ".csv" and p.is_file():
            _finite("profile CSV", _csv_numbers(p))


def _csv_numbers(path: Path, piece: int = 4 << 20) -> np.ndarray:
    """The numbers of a CSV output after its header; of its first and last ``piece`` bytes when
    it is larger (a profile may have 20 million rows)."""
    size = path.stat().st_size
    with path.open("rb") as fh:
        data = fh.read() if size <= 2 * piece else fh.read(piece)
        if size > 2 * piece:
            fh.seek(size - piece)
            tail = fh.read()
            data = data[: data.rfind(b"\n") + 1] + tail[tail.find(b"\n") + 1 :]
    lines = [ln for ln in data.decode("utf-8").split("\n")[1:] if ln]
    return np.loadtxt(lines, delimiter=",", ndmin=2) if lines else np.zeros((0, 6))


def _output_path(name: str, folder: Path, first_input: Path | None) -> tuple[Path, bool]:
    """The output path of a :class:`~tests.fuzz_inputs.CliCase` name, and whether it is new
    (only new names must be absent after a failed run)."""
    if name == "<input>" and first_input is not None:
        return first_input, False
    if name == "<dir>":
        d = folder / "adir"
        d.mkdir(exist_ok=True)
        return d, False
    if name == "<missing>/x":
        return folder / "missing" / "x", True
    return folder / name.replace("<input>", "in"), True


def run_cli_case(case: F.CliCase, folder: Path, rng: Any, call: Call) -> None:
    """Write the case's files into ``folder``, run it (making a trace with ``ncperf profile``
    where the case has none), and check every run."""
    argv: list[str] = [case.command]
    programs = []
    for k, (name, data) in enumerate(case.programs):
        programs.append(write_input(folder, f"{k}{name}" if k else name, data))
    argv += [str(p) for p in programs]
    machine_opt: list[str] = []
    if case.machine == "missing":
        machine_opt = ["--machine", str(folder / "nope.toml")]
    elif case.machine is not None and "\n" in case.machine:
        machine_opt = ["--machine", str(write_input(folder, "m.toml", case.machine.encode()))]
    elif case.machine is not None:
        machine_opt = ["--machine", case.machine]
    if case.command in ("diagnose", "calibrate"):
        trace = folder / case.trace_name
        if case.trace is None:
            made = folder / "made.csv"
            rc, out, err = call(["profile", str(programs[0]), "--csv", str(made), "--dt", "0.02"])
            check_run(rc, out, err, [made], folder)
            text = made.read_text(encoding="utf-8") if rc == 0 else F.csv_trace(rng, 30)
            lines = text.split("\n")
            if len(lines) > 3000:  # a long cycle: every k-th sample
                lines = lines[:1] + lines[1 :: len(lines) // 3000 + 1]
            trace.write_text(F.mutate_lines(rng, "\n".join(lines)), encoding="utf-8")
        else:
            trace.write_bytes(case.trace)
        argv.append(str(trace))
    outputs = []
    for opt, name in case.outputs.items():
        path, new = _output_path(name, folder, programs[0] if programs else None)
        argv += [opt, str(path)]
        if new:
            outputs.append(path)
    argv += machine_opt + case.options
    show(f"argv: {argv!r}")
    rc, out, err = call(argv)
    check_run(rc, out, err, outputs, folder)


def _capsys_call(capsys: pytest.CaptureFixture[str]) -> Call:
    def call(argv: list[str]) -> tuple[int, str, str]:
        capsys.readouterr()
        rc = exit_code(argv)
        out, err = capsys.readouterr()
        return rc, out, err

    return call


@contextlib.contextmanager
def example_folder(tmp_path: Path) -> Iterator[Path]:
    """A fresh folder per Hypothesis example (tmp_path is shared by all of them)."""
    folder = Path(tempfile.mkdtemp(dir=tmp_path))
    try:
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)


# ----------------------------------------------------------------------------- strategies
class SeededRandom(random.Random):
    """A ``random.Random`` that shows its seed when Hypothesis reports a failure."""

    def __init__(self, seed: int) -> None:
        super().__init__(seed)
        self.seed_value = seed

    def __repr__(self) -> str:
        return f"SeededRandom({self.seed_value})"


#: Hypothesis' own random (it favours the first choice of every draw: small, plain inputs) or a
#: seeded ``random.Random`` (spread evenly over the generators' choices, as the long fuzz run).
rngs = st.one_of(st.randoms(use_true_random=False), st.integers(0, 2**32 - 1).map(SeededRandom))
machines = st.sampled_from(sorted(MACHINES))


# ----------------------------------------------------------------------------- G-code


@FUZZ
@given(
    rng=rngs,
    ext=st.sampled_from(F.GCODE_EXTENSIONS),
    machine=machines,
    block_delete=st.booleans(),
)
def test_gcode_grammar(
    tmp_path: Path, rng: random.Random, ext: str, machine: str, block_delete: bool
) -> None:
    text = F.gcode_program(rng, F.DIALECT_OF[ext], max_lines=16)
    with example_folder(tmp_path) as folder, limits():
        path = write_input(folder, f"p{ext}", F.to_bytes(rng, text))
        run_program(path, MACHINES[machine], None, block_delete)


@FUZZ
@given(
    rng=rngs,
    ext=st.sampled_from(F.GCODE_EXTENSIONS),
    machine=machines,
    dialect=st.sampled_from((None, "fanuc", "siemens", "linuxcnc")),
)
def test_gcode_mutated_examples(
    tmp_path: Path, rng: random.Random, ext: str, machine: str, dialect: str | None
) -> None:
    data = F.gcode_mutant(rng, F.gcode_seeds(max_bytes=4000), rounds=3)
    with example_folder(tmp_path) as folder, limits():
        run_program(write_input(folder, f"p{ext}", data), MACHINES[machine], dialect, False)


@FUZZ
@given(
    data=st.binary(max_size=300) | rngs.map(F.random_bytes),
    ext=st.sampled_from((*F.GCODE_EXTENSIONS, *F.CL_EXTENSIONS, ".txt")),
)
def test_random_bytes_as_a_program(tmp_path: Path, data: bytes, ext: str) -> None:
    with example_folder(tmp_path) as folder, limits():
        run_program(write_input(folder, f"p{ext}", data), MACHINES["siemens-840d"], None, False)


# ----------------------------------------------------------------------------- CL data
@FUZZ
@given(
    rng=rngs,
    ext=st.sampled_from(F.CL_EXTENSIONS),
    machine=machines,
    mutant=st.booleans(),
)
def test_cl_data(tmp_path: Path, rng: random.Random, ext: str, machine: str, mutant: bool) -> None:
    data = F.cl_mutant(rng, 3) if mutant else F.to_bytes(rng, F.cl_program(rng, 16))
    with example_folder(tmp_path) as folder, limits():
        run_program(write_input(folder, f"p{ext}", data), MACHINES[machine], None, False)


# ----------------------------------------------------------------------------- traces
units = st.sampled_from((None, "mm", "inch"))


@pytest.mark.parametrize(("make", "name"), [(F.csv_trace, "t.csv"), (F.shdr_trace, "t.shdr")])
@FUZZ
@given(rng=rngs, unit=units, mutant=st.booleans())
def test_trace(
    tmp_path: Path,
    make: Callable[[random.Random, int], str],
    name: str,
    rng: random.Random,
    unit: str | None,
    mutant: bool,
) -> None:
    text = make(rng, 30)
    data = F.mutate_bytes(rng, text.encode(), F.TRACE_TOKENS, 2) if mutant else text.encode()
    with example_folder(tmp_path) as folder, limits():
        run_trace(write_input(folder, name, data), unit)


# ----------------------------------------------------------------------------- machine files
@FUZZ
@given(rng=rngs)
def test_machine_toml(tmp_path: Path, rng: random.Random) -> None:
    text = F.machine_toml(rng, rounds=3)
    with example_folder(tmp_path) as folder, limits():
        run_machine(text, folder)


# ----------------------------------------------------------------------------- command line
@settings(FUZZ, max_examples=60)
@given(rng=rngs)
def test_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str], rng: random.Random) -> None:
    case = F.cli_case(rng, ("analyze", "profile", "compare", "machines", "plugins"))
    with example_folder(tmp_path) as folder, limits():
        run_cli_case(case, folder, rng, _capsys_call(capsys))


@settings(FUZZ, max_examples=6)
@given(rng=rngs)
def test_cli_diagnose(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], rng: random.Random
) -> None:
    case = F.cli_case(rng, ("diagnose", "calibrate"))
    with example_folder(tmp_path) as folder, limits():
        run_cli_case(case, folder, rng, _capsys_call(capsys))


def test_checks_can_fail(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The checks are not vacuous: a NaN, a control character, a second error line and a
    file left by a failed run are each caught."""
    with pytest.raises(PropertyViolation, match="non-finite"):
        _finite("x", [1.0, math.nan])
    with pytest.raises(PropertyViolation, match="control character"):
        check_run(1, "", "a\x1b[31m\n", [], tmp_path)
    with pytest.raises(PropertyViolation, match="not one line"):
        check_run(1, "", "one\ntwo\n", [], tmp_path)
    left = tmp_path / "o.json"
    left.write_text("{}")
    with pytest.raises(PropertyViolation, match="left by a failed run"):
        check_run(1, "", "p.ngc:1: bad\n", [left], tmp_path)
    left.write_text('{"a": NaN}')
    with pytest.raises(PropertyViolation, match="NaN"):
        check_run(0, "", "", [left], tmp_path)
    assert os.path.exists(left)
