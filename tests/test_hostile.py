"""Hostile and broken input (issue 12): each class of what once crashed, blew up memory or
clobbered a file, run through the command as a user runs it. The property everywhere: exit 0
with finite output, or exit 1/2 with one line on stderr; no traceback, no control character
on the terminal, no output left behind by a failed run, nothing replaced that is not a
regular output file."""

from __future__ import annotations

import errno
import importlib
import json
import os
import re
import stat
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest

from core.cli import main
from tests.conftest import ROOT

PROGRAM = "G21 G90 G17 G64\nG0 X0 Y0 Z1\nG1 Z0 F6000\nG1 X10\nG1 Y10\nG1 X11\nM30\n"
#: What no terminal output may contain: C0 controls but tab and newline, DEL, C1 controls.
CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")


def cli(capsys, *args):
    """Exit code, stdout, the error lines of stderr (warnings left out)."""
    rc = main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert not CONTROL.search(out) and not CONTROL.search(err), (out, err)
    assert "Traceback" not in err
    errors = [ln for ln in err.splitlines() if " warning: " not in ln and "... and " not in ln]
    if rc:
        assert len(errors) == 1, err
    return rc, out, errors


def strict_json(path):
    """The JSON, refusing NaN and Infinity (which are not JSON)."""

    def refuse(c):
        raise ValueError(f"{c} in JSON")

    return json.loads(path.read_text(encoding="utf-8"), parse_constant=refuse)


@pytest.fixture
def program(tmp_path):
    p = tmp_path / "part.nc"
    p.write_text(PROGRAM)
    return p


# ----------------------------------------------------------------- non-finite numbers
@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        # 1e7 mm is ten kilometres: beyond the 1 km any coordinate may have
        ("G21 G90\nG0 X0 Y0 Z0\nG1 X10000000 F100\n", "beyond 1e+06 mm"),
        # a 400-digit feed is infinite as a float
        ("G21 G90\nG0 X0 Y0 Z0\nG1 X10 F" + "9" * 400 + "\n", "out of range"),
        # 1e12 mm/min is beyond the 6e9 mm/min any feed may have
        ("G21 G90\nG0 X0 Y0 Z0\nG1 X10 F1000000000000\n", "feed outside"),
        # a helix of a million turns on one block
        ("G21 G90 G17\nG0 X10 Y0 Z0\nG2 X10 Y0 Z-1 I-10 J0 P1000000 F1000\n", "turns"),
        # 100,000 s of dwell (LinuxCNC G4 P is seconds): 28 hours
        ("G21 G90\nG0 X0 Y0 Z0\nG1 X10 F100\nG4 P100000\n", "dwell outside"),
        ("G21 G90\nT99999999999 M6\nG0 X0 Y0 Z0\nG1 X10 F100\n", "tool number"),
    ],
)
def test_numbers_out_of_range_are_one_line_errors(tmp_path, capsys, text, fragment):
    p = tmp_path / "p.ngc"
    p.write_text(text + "M30\n")
    js, svg = tmp_path / "o.json", tmp_path / "o.svg"
    rc, _, errors = cli(capsys, "analyze", p, "--json", js, "--svg", svg)
    assert rc == 1 and fragment in errors[0] and errors[0].startswith(f"{p}:")
    assert not js.exists() and not svg.exists()


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("FEDRAT/1e308\nGOTO/0,0,0\nGOTO/10,0,0\nFINI\n", "feed outside"),
        ("FEDRAT/100\nGOTO/1e300,0,0\nGOTO/10,0,0\nFINI\n", "beyond 1e+06 mm"),
        ("LOAD/TOOL,9999999999\nFEDRAT/1000\nGOTO/0,0,0\nGOTO/10,0,0\nFINI\n", "tool number"),
    ],
)
def test_cl_data_out_of_range(tmp_path, capsys, text, fragment):
    p = tmp_path / "p.cl"
    p.write_text(text)
    rc, _, errors = cli(capsys, "analyze", p)
    assert rc == 1 and fragment in errors[0]


def test_arc_ending_at_its_centre_is_finite_or_refused(tmp_path, capsys):
    """An arc whose end lies on its centre within the arc tolerance (radius 1e-7 mm)."""
    p = tmp_path / "p.ngc"
    p.write_text("G21 G90 G17\nG0 X0 Y0 Z0\nG1 X1 F100\nG2 X1.0000001 Y0 I0.0000001 J0\nM30\n")
    js = tmp_path / "o.json"
    rc, out, _ = cli(capsys, "analyze", p, "--json", js)
    if rc == 0:
        strict_json(js)
        assert not re.search(r"\b(nan|inf)\b", out)
    else:
        assert not js.exists()


def _machine_with(tmp_path, key, value):
    text = (ROOT / "core/model/presets/siemens-840d.toml").read_text()
    text, n = re.subn(rf"(?m)^({key}\s*=\s*).*$", lambda m: m.group(1) + value, text, count=1)
    assert n == 1
    m = tmp_path / "m.toml"
    m.write_text(text)
    return m, text


@pytest.mark.parametrize(
    ("key", "value", "fragment"),
    [
        ("max_jerk", "1e-310", "subnormal"),  # once NaN in the profile and the JSON
        ("max_jerk", "9" * 400, "400 digits"),  # once OverflowError
        ("max_acceleration", "1e-15", "physical range"),
        ("interpolation_time", "1e300", "physical range"),
    ],
)
def test_machine_values_out_of_range(tmp_path, capsys, program, key, value, fragment):
    m, text = _machine_with(tmp_path, key, value)
    line = next(k for k, ln in enumerate(text.splitlines(), 1) if ln.startswith(key))
    svg, js = tmp_path / "o.svg", tmp_path / "o.json"
    rc, _, errors = cli(capsys, "analyze", program, "--machine", m, "--svg", svg, "--json", js)
    assert rc == 1 and fragment in errors[0] and errors[0].startswith(f"{m}:{line}:")
    assert not svg.exists() and not js.exists()


@pytest.mark.parametrize(
    "bomb", ["[" * 100_000 + "]" * 100_000, "{b=" * 50_000 + "1" + "}" * 50_000]
)
def test_toml_nesting_bomb(tmp_path, capsys, program, bomb):
    m = tmp_path / "m.toml"
    m.write_text(f"a = {bomb}\n")
    rc, _, errors = cli(capsys, "analyze", program, "--machine", m)
    assert rc == 1 and "nested" in errors[0]


# ----------------------------------------------------------------- bounded work
def test_profile_dt_bounds(program, tmp_path, capsys):
    csv = tmp_path / "o.csv"
    for dt in ("1e-300", "inf", "nan", "0", "-1"):
        rc, _, errors = cli(capsys, "profile", program, "--csv", csv, "--dt", dt)
        assert rc == 2 and "--dt" in errors[0]
    assert not csv.exists()


def test_profile_refuses_more_rows_than_its_limit(tmp_path, capsys, monkeypatch):
    """The row limit is checked before any sample is made, and says what --dt would do."""
    cli_main = importlib.import_module("core.cli.main")

    monkeypatch.setattr(cli_main, "MAX_SAMPLES", 1000)
    p = tmp_path / "p.ngc"
    # 100 mm at F600 = 10 s of feed: at 1 ms more than 1000 samples
    p.write_text("G21 G90 G64\nG0 X0 Y0 Z0\nG1 X100 F600\nM30\n")
    csv = tmp_path / "o.csv"
    rc, _, errors = cli(capsys, "profile", p, "--csv", csv)
    assert rc == 2 and "at most 1,000" in errors[0] and not csv.exists()


def test_profile_written_in_pieces_equals_one_piece(tmp_path, capsys, monkeypatch):
    """Pieces of 7 samples give the same file as one piece."""
    cli_main = importlib.import_module("core.cli.main")

    p = tmp_path / "p.ngc"
    p.write_text(PROGRAM)
    one, pieces = tmp_path / "one.csv", tmp_path / "pieces.csv"
    assert cli(capsys, "profile", p, "--csv", one, "--dt", "0.01")[0] == 0
    monkeypatch.setattr(cli_main, "SAMPLE_PIECE", 7)
    assert cli(capsys, "profile", p, "--csv", pieces, "--dt", "0.01")[0] == 0
    assert one.read_text() == pieces.read_text()
    assert one.read_text().count("\n") > 20  # header + more than 3 pieces


def test_trace_line_number_beyond_int32_allocates_nothing_big(tmp_path, capsys, program):
    """A trace line of 2**31 once sized an array by it (16 GiB); now it is a line the
    program lacks. Peak memory of the diagnosis stays far below that."""
    import tracemalloc

    tr = tmp_path / "t.csv"
    rows = "".join(f"{k * 0.01:.2f},100,{3 if k < 50 else 2147483648}\n" for k in range(100))
    tr.write_text("t,v,line\n" + rows)
    tracemalloc.start()
    rc, _, _ = cli(capsys, "diagnose", program, tr)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert rc in (0, 1) and peak < 200e6


# ----------------------------------------------------------------- documented traces
def _predicted_trace(tmp_path, capsys, program, columns):
    full = tmp_path / "full.csv"
    assert cli(capsys, "profile", program, "--csv", full)[0] == 0
    lines = full.read_text().splitlines()
    head = lines[0].split(",")
    keep = [head.index(c) for c in columns]
    out = tmp_path / ("trace_" + "".join(columns) + ".csv")
    out.write_text("\n".join(",".join(r.split(",")[k] for k in keep) for r in lines) + "\n")
    return out


def test_csv_trace_with_only_t_and_v(tmp_path, capsys, program):
    """The README names CSV `t,v`: it is diagnosed (placed by its feed), with finite JSON.
    The trace is ncperf's own predicted profile, so the gap must be small."""
    tr = _predicted_trace(tmp_path, capsys, program, ["t", "v"])
    js = tmp_path / "d.json"
    rc, out, _ = cli(capsys, "diagnose", program, tr, "--json", js)
    assert rc == 0, out
    strict_json(js)
    assert "feed alone" in out


def _shdr(lines):
    return "".join(f"2020-01-01T00:00:{k // 10:02d}.{k % 10}|{body}\n" for k, body in lines)


def test_shdr_with_only_feed_rate(tmp_path, capsys, program):
    tr = tmp_path / "t.shdr"
    tr.write_text(_shdr([(k, f"Feed_Rate|{min(k * 10, 100)}") for k in range(40)]))
    js = tmp_path / "d.json"
    rc, _, _ = cli(capsys, "diagnose", program, tr, "--json", js)
    assert rc in (0, 1)
    if rc == 0:
        strict_json(js)
    else:
        assert not js.exists()


def test_shdr_all_unavailable(tmp_path, capsys, program):
    tr = tmp_path / "t.shdr"
    body = "Xact|UNAVAILABLE|Yact|UNAVAILABLE|Zact|UNAVAILABLE|Feed_Rate|UNAVAILABLE"
    tr.write_text(_shdr([(k, body) for k in range(30)]))
    rc, _, errors = cli(capsys, "diagnose", program, tr)
    assert rc == 1 and "UNAVAILABLE" in errors[0]


def test_shdr_exponent_in_timestamp_is_refused(tmp_path, capsys, program):
    """'01.5e3' once read as 500 s after the minute: a bad timestamp at its line."""
    tr = tmp_path / "t.shdr"
    tr.write_text(
        "2020-01-01T00:00:00.0|Xact|0|Yact|0|Zact|1|Feed_Rate|0\n"
        "2020-01-01T00:00:01.5e3|Xact|0|Yact|0|Zact|0|Feed_Rate|0\n"
    )
    rc, _, errors = cli(capsys, "diagnose", program, tr)
    assert rc == 1 and errors[0].startswith(f"{tr}:2: bad timestamp")


# ----------------------------------------------------------------- outputs
def test_output_folder_symlink_fifo_and_input_are_refused(tmp_path, capsys, program):
    folder = tmp_path / "d"
    folder.mkdir()
    precious = tmp_path / "precious.txt"
    precious.write_text("keep me\n")
    link = tmp_path / "link.json"
    link.symlink_to(precious)
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    for out, kind in ((folder, "a folder"), (link, "a symbolic link"), (fifo, "a FIFO")):
        rc, _, errors = cli(capsys, "analyze", program, "--json", out)
        assert rc == 2 and kind in errors[0]
    assert link.is_symlink() and precious.read_text() == "keep me\n"
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    # the program itself, by another spelling
    rc, _, errors = cli(capsys, "analyze", program, "--json", tmp_path / "." / program.name)
    assert rc == 2 and "is an input" in errors[0]
    assert program.read_text() == PROGRAM
    rc, _, errors = cli(
        capsys, "analyze", program, "--json", tmp_path / "a", "--svg", tmp_path / "a"
    )
    assert rc == 2 and "two outputs" in errors[0]


@pytest.mark.skipif(os.geteuid() != 0, reason="making a device node needs root")
def test_output_device_node_is_not_replaced(tmp_path, capsys, program):
    node = tmp_path / "null"
    os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    rc, _, errors = cli(capsys, "analyze", program, "--json", node)
    assert rc == 2 and "character device" in errors[0]
    assert stat.S_ISCHR(os.lstat(node).st_mode)


def test_failure_after_the_svg_leaves_no_output(tmp_path, capsys, program, monkeypatch):
    """The JSON fails after the SVG was written: neither exists afterwards, and a file the
    run would have replaced keeps its old content."""
    report = importlib.import_module("core.cli.report")  # analyze takes write_json from it

    def disk_full(*_a, **_k):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(report, "write_json", disk_full)
    svg, js = tmp_path / "o.svg", tmp_path / "o.json"
    svg.write_text("old")
    rc, _, errors = cli(capsys, "analyze", program, "--svg", svg, "--json", js)
    assert rc == 1 and "No space left on device" in errors[0] and str(js) in errors[0]
    assert svg.read_text() == "old" and not js.exists()
    assert not [f for f in os.listdir(tmp_path) if f.endswith(".part")]


# ----------------------------------------------------------------- text from inputs
def test_control_characters_from_names_and_comments_are_escaped(tmp_path, capsys):
    name = "p\x1b[31mred\rx\nz.ngc"
    p = tmp_path / name
    p.write_text("G21 G90\n(\x1b[2J evil \x7f)\nG0 X0 Y0 Z0\nG1 X10 F100\nG1 X1 Q\x1b[31m5\n")
    rc, _, errors = cli(capsys, "analyze", p)
    assert rc == 1
    assert "\\x1b[31mred\\x0dx\\x0az.ngc:5:" in errors[0]  # one line, the prefix intact


def test_machine_name_and_file_name_in_svg_and_json(tmp_path, capsys, program):
    m, _ = _machine_with(tmp_path, "name", '"evil\\u001b[31m\\r\\u0007 \\u0001 <x>&"')
    bad = os.fsdecode(b"p\xff\xfe.nc")  # a file name that is not UTF-8
    p = tmp_path / bad
    p.write_text(PROGRAM)
    svg, js = tmp_path / "o.svg", tmp_path / "o.json"
    rc, out, _ = cli(capsys, "analyze", p, "--machine", m, "--svg", svg, "--json", js)
    assert rc == 0
    assert "p\\xff\\xfe.nc" in out and "evil\\x1b[31m" in out
    ET.parse(svg)  # well-formed: no control character, valid UTF-8
    data = strict_json(js)
    assert not CONTROL.search(data["machine"]) and "\\x07" in data["machine"]


# ----------------------------------------------------------------- other
@pytest.mark.parametrize("role", ["program", "trace", "machine"])
def test_fifo_as_an_input_does_not_hang(tmp_path, role):
    """Opening a FIFO without a writer once blocked forever; now it is refused at once."""
    fifo = tmp_path / {"program": "f.ngc", "trace": "f.csv", "machine": "f.toml"}[role]
    os.mkfifo(fifo)
    program = tmp_path / "p.ngc"
    program.write_text(PROGRAM)
    args = {
        "program": ["analyze", fifo],
        "trace": ["diagnose", program, fifo],
        "machine": ["analyze", program, "--machine", fifo],
    }[role]
    r = subprocess.run(
        [sys.executable, "-m", "core", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,
    )
    assert r.returncode == 1 and "is a FIFO" in r.stderr and "Traceback" not in r.stderr


def test_usage_errors_are_one_line(program, capsys):
    """argparse's own error prints the usage block first; ncperf's is one line, exit 2."""
    with pytest.raises(SystemExit) as exc:
        main(["analyze", str(program), "--view", "bogus\x1b[31m"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "invalid choice" in err and not CONTROL.search(err)


def test_shdr_with_part_of_the_positions(tmp_path, capsys, program):
    """Xact recorded without Yact and Zact (found by the fuzzer: a KeyError)."""
    tr = tmp_path / "t.shdr"
    tr.write_text(_shdr([(k, f"Xact|{k}|Feed_Rate|100") for k in range(30)]))
    rc, _, errors = cli(capsys, "diagnose", program, tr)
    assert rc == 1 and "positions need all of Xact, Yact, Zact" in errors[0]


def test_compare_a_program_without_feed_moves(tmp_path, capsys, program):
    """Its mean feed is "-", not "nan" (found by the fuzzer)."""
    rapids = tmp_path / "rapids.nc"
    rapids.write_text("G21 G90\nG0 X0 Y0 Z5\nG0 X10 Y10\nM30\n")
    rc, out, _ = cli(capsys, "compare", program, rapids)
    assert rc == 0 and not re.search(r"\bnan\b", out)
    assert re.search(r"rapids\.nc .* - mm/min", out)


@pytest.mark.parametrize(
    ("name", "text"),
    [
        # 1000 mm in pecks of 0.0001 mm: ten million pecks (it hung)
        ("p.ngc", "G21 G90 G17\nG0 X0 Y0 Z10\nG83 X1 Y0 Z-1000 R1 Q0.0001 F100\nG80\nM30\n"),
        ("p.ngc", "G21 G90 G17\nG0 X0 Y0 Z10\nG73 X1 Y0 Z-1000 R1 Q0.0001 F100\nG80\nM30\n"),
        (
            "p.cl",
            "FEDRAT/100\nGOTO/0,0,10\nCYCLE/DEEP,FEDTO,1000,STEP,0.00001,RAPTO,1,MMPM,100\n"
            "GOTO/1,0,0\nCYCLE/OFF\nFINI\n",
        ),
    ],
)
def test_pecks_are_bounded(tmp_path, capsys, name, text):
    p = tmp_path / name
    p.write_text(text)
    rc, _, errors = cli(capsys, "analyze", p)
    assert rc == 1 and "more than 10,000 in one hole" in errors[0]


def test_calibrate_with_a_file_name_that_is_not_utf8(tmp_path, capsys):
    """The written TOML's header quotes the program's name: it crashed the UTF-8 writer
    (found by tests/test_fuzz_properties.py)."""
    p = tmp_path / os.fsdecode(b"bad\xffbyte.ngc")
    p.write_text("G21 G90 G17 G64\nG0 X0 Y0 Z1\nG1 Z0 F600\nG1 X10\nG1 Y10\nG1 X0\nM30\n")
    trace = tmp_path / "t.csv"
    assert cli(capsys, "profile", p, "--csv", trace, "--machine", "linuxcnc-sim")[0] == 0
    out = tmp_path / "m.toml"
    rc, _, _ = cli(
        capsys,
        "calibrate",
        p,
        trace,
        "--machine",
        "linuxcnc-sim",
        "--out",
        out,
        "--effects",
        "block_cycle_time",
    )
    assert rc == 0
    assert "bad\\xffbyte.ngc" in out.read_text(encoding="utf-8")


def test_toml_integer_beyond_pythons_digit_limit(tmp_path, capsys, program):
    """5,000 digits: tomllib raises ValueError (Python's 4,300-digit int limit), which once
    escaped as a traceback."""
    m = tmp_path / "m.toml"
    m.write_text("a = " + "9" * 5000 + "\n")
    rc, _, errors = cli(capsys, "analyze", program, "--machine", m)
    assert rc == 1 and "integer longer than" in errors[0] and errors[0].startswith(f"{m}:")


def test_no_numpy_warning_reaches_the_terminal(tmp_path):
    """A rapid whose Y component is 1e-310 mm (a subnormal: every axis limit divided by it
    overflows to inf, which the models take as "no limit"): numpy's RuntimeWarnings, with
    their source lines, were printed on the terminal; the command line keeps them off it
    and the result is finite. Run as a user runs it (pytest would catch the warnings)."""
    p = tmp_path / "tiny.cls"
    p.write_text("FEDRAT/MMPM,600\nGOTO/0,0,0\nRAPID\nGOTO/100,1e-310,0\nGOTO/200,0,0\n")
    js = tmp_path / "out.json"
    r = subprocess.run(
        [sys.executable, "-m", "core", "analyze", str(p), "--json", str(js)],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert r.returncode == 0, r.stderr
    assert "Warning" not in r.stderr, r.stderr
    assert "nan" not in js.read_text().lower()
