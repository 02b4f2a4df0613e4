"""The ncperf command: outputs, exit codes, one-line errors, no partial files."""

from __future__ import annotations

import json
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from core.cli import main
from tests.conftest import ROOT

PROGRAM = "G21 G90 G17 G64\nG0 X0 Y0 Z1\nG1 Z0 F6000\nG1 X10\nG1 Y10\nG1 X11\nG1 X12\nG1 X13\nM30\n"


@pytest.fixture
def program(tmp_path):
    p = tmp_path / "part.nc"
    p.write_text(PROGRAM)
    return p


def run(*args):
    """The command in a fresh interpreter (exactly as a user runs it)."""
    return subprocess.run(
        [sys.executable, "-m", "core", *map(str, args)], capture_output=True, text=True, cwd=ROOT
    )


def test_analyze_summary_json_and_svg(program, tmp_path, capsys):
    """Summary on stdout; JSON with the documented keys; SVG that parses."""
    js, svg = tmp_path / "r.json", tmp_path / "r.svg"
    assert main(["analyze", str(program), "--json", str(js), "--svg", str(svg)]) == 0
    out = capsys.readouterr().out
    assert "preset siemens-840d, the default" in out
    data = json.loads(js.read_text())
    for key in (
        "program",
        "machine",
        "moves",
        "feed_length_mm",
        "programmed_time_s",
        "junctions",
        "elements",
    ):
        assert key in data
    assert data["moves"] == 7
    # Z1 -> Z0 is 1 mm, X0 -> X10 10 mm, Y0 -> Y10 10 mm, then three 1 mm X steps: 24 mm.
    assert data["feed_length_mm"] == pytest.approx(24.0)
    # programmed time: 24 mm at 6000 mm/min = 100 mm/s -> 0.24 s
    assert data["programmed_time_s"] == pytest.approx(0.24)
    j = data["junctions"]
    # corners: plunge -> X (line 3/4), X -> Y (4/5), Y -> X (5/6): 90 deg each
    assert [(r["line"], r["next_line"]) for r in j] == [(3, 4), (4, 5), (5, 6)]
    for r in j:
        assert r["indicator"] == "tangential" and r["programmed_feed"] == 6000.0
        assert r["reduction"] == pytest.approx(1 - r["predicted_feed"] / 6000.0, abs=1e-6)
    # model 1 at 90 deg on the 840D preset (jerk binds): cbrt(5000 * 0.0241421^2) = 1.42837 mm/s
    assert j[1]["predicted_feed"] == pytest.approx(1.4283691 * 60, abs=1e-3)  # JSON: 3 decimals
    el = data["elements"]
    assert [e["kind"] for e in el] == ["rapid"] + ["line"] * 6
    # 1 mm blocks at F6000 with t_int 12 ms: L = 1.2 mm -> capped at 1/0.012 mm/s = 5000 mm/min
    assert el[-1]["min_length_mm"] == pytest.approx(1.2)
    assert el[-1]["predicted_feed"] == pytest.approx(5000.0)
    assert el[2]["predicted_feed"] == 6000.0
    ET.parse(svg)


def test_analyze_feed_length_line(program, capsys):
    """The summary's feed length is the sum of feed moves (24 mm here)."""
    main(["analyze", str(program)])
    assert "feed length      24.0 mm" in capsys.readouterr().out


def test_demo_runs_without_a_program(tmp_path):
    """`ncperf analyze` alone runs the bundled Z-level demo and writes an SVG."""
    r = subprocess.run(
        [sys.executable, "-m", "core", "analyze"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env={"PYTHONPATH": str(ROOT), "PATH": ""},
    )
    assert r.returncode == 0, r.stderr
    assert "zlevel_cavity.ngc" in r.stdout
    ET.parse(tmp_path / "ncperf-demo.svg")


def test_machines_and_plugins_commands():
    """`ncperf machines` lists presets name first; `ncperf plugins` says in one line what
    each plugin does (its docstring's first line) and lists its hooks."""
    r = run("machines")
    assert r.returncode == 0
    names = [line.split("\t")[0] for line in r.stdout.splitlines()]
    assert "siemens-840d" in names and "linuxcnc-sim" in names
    r = run("plugins")
    lines = r.stdout.splitlines()
    k = next(i for i, t in enumerate(lines) if t.startswith("plugins.tangential "))
    assert "Model 1: crossing a tangential discontinuity" in lines[k]
    assert lines[k + 1].split() == ["hooks:", "ncperf_evaluate"]
    k = next(i for i, t in enumerate(lines) if t.startswith("adapters.gcode "))
    assert "G-code" in lines[k] and lines[k + 1].split() == ["hooks:", "ncperf_extract"]


@pytest.mark.parametrize(
    "text,line,fragment",
    [
        ("", None, "empty file"),
        ("G21 G1 X1 F60\nG1 X2 E5\n", 2, "unknown word E"),
        ("G21 G1 X1 F60\nG1 X1.2.3\n", 2, "malformed number"),
        ("G21 G1 X1 F60\nG1 X1" + "0" * 400 + "\n", 2, "X word out of range"),
        ("G21 G1 X0 Y0 F60\nG2 X1 Y0 I0 J0\n", 2, "arc with zero radius"),
    ],
    ids=["empty", "unknown word", "malformed", "inf", "zero radius"],
)
def test_bad_input_one_line_exit_1_no_output(tmp_path, text, line, fragment):
    """Bad input: exit 1, one line naming file (and line), no traceback, no output files."""
    p = tmp_path / "bad.nc"
    p.write_text(text)
    js, svg = tmp_path / "o.json", tmp_path / "o.svg"
    r = run("analyze", p, "--json", js, "--svg", svg)
    assert r.returncode == 1
    err = r.stderr.strip()
    assert "\n" not in err and "Traceback" not in err
    where = f"{p}:{line}:" if line else f"{p}:"
    assert err.startswith(where) and fragment in err
    assert not js.exists() and not svg.exists()
    assert list(tmp_path.iterdir()) == [p]


def test_binary_file(tmp_path):
    """A binary file: exit 1, one line."""
    p = tmp_path / "bin.nc"
    p.write_bytes(bytes(range(256)) * 10)
    r = run("analyze", p)
    assert r.returncode == 1 and r.stderr.count("\n") == 1
    assert "binary file" in r.stderr


def test_missing_program_and_bad_machine(tmp_path, program):
    """A missing file and a broken machine TOML are bad input (exit 1, one line)."""
    r = run("analyze", tmp_path / "nope.nc")
    assert r.returncode == 1 and "cannot read" in r.stderr
    m = tmp_path / "m.toml"
    m.write_text('name = "x"\n[axes.X]\nmax_feed = -1\n')
    r = run("analyze", program, "--machine", m)
    assert r.returncode == 1 and r.stderr.count("\n") == 1
    assert f"{m}:" in r.stderr


def test_usage_errors_exit_2(program, tmp_path):
    """Unknown options, presets and missing output folders are usage errors (exit 2)."""
    assert run("analyze", program, "--view", "top").returncode == 2
    r = run("analyze", program, "--machine", "nonsense")
    assert r.returncode == 2 and "unknown machine preset" in r.stderr
    r = run("analyze", program, "--svg", tmp_path / "no" / "dir" / "x.svg")
    assert r.returncode == 2 and "does not exist" in r.stderr
    assert run().returncode == 2


def test_views(program, tmp_path):
    """--view xz|yz|iso write SVGs."""
    for view in ("xz", "yz", "iso"):
        out = tmp_path / f"{view}.svg"
        assert main(["analyze", str(program), "--svg", str(out), "--view", view]) == 0
        assert view in out.read_text().lower()


def test_profile_command_writes_a_trace(tmp_path, capsys):
    """`ncperf profile --csv` writes t,x,y,z,v,line every dt, from rest to rest, up to the
    predicted cycle time: one 100 mm line at F6000 on LinuxCNC's machine (A 2000 mm/s^2, no
    jerk limit) takes 100/100 + 100/2000 = 1.05 s."""
    p = tmp_path / "line.ngc"
    p.write_text("G21 G90 G64 P0.01\nG1 X100 F6000\nM2\n")
    out = tmp_path / "p.csv"
    # LinuxCNC's ini limits without the effects the preset folds in
    m = tmp_path / "lc.toml"
    axes = "".join(
        f"[axes.{a}]\nmax_feed = 15.0\nmax_acceleration = 2.0\nmax_jerk = inf\n" for a in "XYZ"
    )
    m.write_text(
        f'name = "lc"\n{axes}[controller]\ninterpolation_time = 0.00102\n'
        "path_tolerance = 0.01\ncurvature_transition_time = 0.001\n"
    )
    assert main(["profile", str(p), "--machine", str(m), "--csv", str(out), "--dt", "0.01"]) == 0
    assert "predicted cycle  1.05 s" in capsys.readouterr().out
    rows = out.read_text().splitlines()
    assert rows[0] == "t,x,y,z,v,line"
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert data.shape == (106, 6)  # 0, 0.01, ..., 1.05
    assert data[-1, 0] == pytest.approx(1.05)
    assert data[0, 4] == 0.0 and data[-1, 4] == pytest.approx(0.0, abs=1e-6)
    assert data[:, 4].max() == pytest.approx(100.0)
    assert data[-1, 1] == pytest.approx(100.0)
    assert set(data[:, 5].astype(int)) == {2}


def test_compare_ranks_the_slower_strategy_last(tmp_path, capsys):
    """The same 60 mm line as 1 mm points (capped at 1/0.012 mm/s by model 3) and as 3 mm
    points (not capped): the 1 mm version is predicted slower and ranked second."""
    fine, coarse = tmp_path / "fine.nc", tmp_path / "coarse.nc"
    for path, step in ((fine, 1), (coarse, 3)):
        body = "".join(f"X{x}.\n" for x in range(step, 61, step))
        path.write_text(f"G21 G90 G64\nG1 X0. Y0. Z0. F10000.\n{body}M30\n")
    svg = tmp_path / "c.svg"
    assert main(["compare", str(fine), str(coarse), "--svg", str(svg)]) == 0
    out = capsys.readouterr().out
    first = out.index("coarse.nc")
    second = out.index("fine.nc")
    assert first < second
    text = svg.read_text()
    ET.fromstring(text)
    assert "#1 coarse.nc" in text and "#2 fine.nc" in text


def test_compare_needs_two_programs(program):
    """One program is not a comparison: a usage error."""
    r = run("compare", program)
    assert r.returncode == 2 and "two or more" in r.stderr


def test_progress_waits_for_long_work_then_ticks():
    """Work shorter than the delay shows nothing; a step still running after it is shown
    by the ticker (with its seconds), and the line is blanked at the end (issue 14)."""
    import io
    import time

    from core.cli.main import _Progress

    class Tty(io.StringIO):
        def isatty(self) -> bool:
            return True

    quick = Tty()
    with _Progress("ncperf analyze", quick, delay=5.0) as progress:
        progress("reading the program")
        progress("the models on 12 moves")
    assert quick.getvalue() == ""
    slow = Tty()
    with _Progress("ncperf analyze", slow, delay=0.2) as progress:
        progress("the feed profile of 1,000,000 moves")  # before the delay: not drawn yet
        assert slow.getvalue() == ""
        time.sleep(0.45)  # the ticker draws it at 0.2 s
        assert slow.getvalue().startswith(
            "\rncperf analyze: the feed profile of 1,000,000 moves [0 s]"
        )
    width = len("ncperf analyze: the feed profile of 1,000,000 moves [0 s]")
    assert slow.getvalue().endswith("\r" + " " * width + "\r")


def test_progress_line_on_a_terminal_only():
    """A long command's progress: one line a terminal overwrites (escaped text, cleared at the
    end); nothing at all on a stream that is not a terminal."""
    import io

    from core.cli.main import _Progress

    class Tty(io.StringIO):
        def isatty(self) -> bool:
            return True

    tty, log = Tty(), io.StringIO()
    for stream in (tty, log):
        with _Progress("ncperf diagnose", stream, delay=0) as progress:
            progress("aligning a\x1b[2Jb.csv")
            progress.clear()  # a warning follows on a line of its own
            stream.write("b.csv:3: warning\n")
            progress("fitting servo_lag (9 of 15 effects)")
    import re

    out = re.sub(r"\[\d+ s\]", "[T s]", tty.getvalue())  # the seconds since the start
    assert log.getvalue() == "b.csv:3: warning\n"
    first = "ncperf diagnose: aligning a\\x1b[2Jb.csv [T s]"
    assert "\r" + " " * len(first) + "\rb.csv:3: warning\n" in out  # blanked, then the warning
    assert out.startswith("\rncperf diagnose: aligning a\\x1b[2Jb.csv [T s]")
    assert "\rncperf diagnose: fitting servo_lag (9 of 15 effects) [T s]" in out
    assert "\x1b" not in out and out.count("\n") == 1
    assert out.endswith("\r" + " " * len(out.split("\r")[-3]) + "\r")


def test_one_blas_thread_unless_the_environment_says():
    """A command runs numpy's BLAS on one thread (its spare threads' busy waiting took a core
    from the analysis on a busy 2-core machine), set before numpy loads it; a value in the
    environment stays."""
    code = (
        "import os, sys\n"
        "from core.cli import main\n"
        "assert 'numpy' not in sys.modules\n"
        "main(['machines'])\n"
        "print(os.environ['OPENBLAS_NUM_THREADS'])\n"
    )
    env = {"PYTHONPATH": str(ROOT), "PATH": ""}
    for given, want in ((None, "1"), ("2", "2")):
        e = env if given is None else {**env, "OPENBLAS_NUM_THREADS": given}
        r = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=e
        )
        assert r.returncode == 0, r.stderr
        assert r.stdout.splitlines()[-1] == want


def test_the_process_ends_at_once_with_its_output_flushed(program, tmp_path):
    """`ncperf` ends its process without the interpreter's teardown (core.cli.main:
    _end_process): the summary and the files are complete, the status is the command's --
    0, 1 for bad input, 2 for a usage error -- and a pipe read by `head` is no error."""
    js = tmp_path / "r.json"
    ok = run("analyze", program, "--json", js)
    assert ok.returncode == 0, ok.stderr
    assert ok.stdout.rstrip().endswith(f"json             {js}")
    assert json.loads(js.read_text())["moves"] > 0
    bad = tmp_path / "bad.nc"
    bad.write_text("G1 X1 F100\nG1 X2 Y\n")
    r = run("analyze", bad)
    assert r.returncode == 1 and r.stderr.count("\n") == 1 and "bad.nc:2" in r.stderr
    assert run("analyze", program, "--dt", "1").returncode == 2
    head = subprocess.run(
        ["bash", "-c", f'"{sys.executable}" -m core analyze "{program}" | head -c 1; '
         "exit ${PIPESTATUS[0]}"],
        capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    assert head.returncode == 0 and "Traceback" not in head.stderr, head.stderr
