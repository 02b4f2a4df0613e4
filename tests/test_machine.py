"""Machine TOML files and presets: units at the edge, strict keys, one-line errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core import MachineError, UsageError, load_machine_file, load_preset, preset_names
from core.model.machine import resolve_machine

GOOD = """name = "Test mill"
[axes.X]
max_feed = 30.0
max_acceleration = 2.5
max_jerk = 5.0
[axes.Y]
max_feed = 24.0
max_acceleration = 2.0
max_jerk = 4.0
[axes.Z]
max_feed = 12.0
max_acceleration = 1.0
max_jerk = inf
[controller]
interpolation_time = 0.012
path_tolerance = 0.01
curvature_transition_time = 0.008
"""


def write(tmp_path, text):
    p = tmp_path / "m.toml"
    p.write_text(text)
    return p


def test_units_converted_to_mm_and_s(tmp_path):
    """m/min -> mm/s (x 1000/60), m/s^2 -> mm/s^2 and m/s^3 -> mm/s^3 (x 1000)."""
    m = load_machine_file(write(tmp_path, GOOD))
    assert m.name == "Test mill"
    assert np.allclose(m.max_feed, [500.0, 400.0, 200.0])
    assert np.allclose(m.max_acceleration, [2500.0, 2000.0, 1000.0])
    assert m.max_jerk[0] == 5000.0 and m.max_jerk[1] == 4000.0 and math.isinf(m.max_jerk[2])
    assert (m.interpolation_time, m.path_tolerance, m.curvature_transition_time) == (
        0.012,
        0.01,
        0.008,
    )


@pytest.mark.parametrize(
    "change,line,message",
    [
        (
            ("max_acceleration = 2.0", "max_acel = 2.0"),
            8,
            "unknown key 'max_acel' in [axes.Y]; did you mean 'max_acceleration'?",
        ),
        (("max_jerk = 4.0\n", ""), 6, "missing key 'max_jerk' in [axes.Y]"),
        (("max_feed = 24.0", "max_feed = -24.0"), 7, "'max_feed' in [axes.Y] must be a positive"),
        (("max_feed = 24.0", "max_feed = 0"), 7, "must be a positive number"),
        (("max_feed = 24.0", "max_feed = inf"), 7, "must be a positive number, got inf"),
        (("max_feed = 24.0", "max_feed = nan"), 7, "must be a positive number"),
        (("max_feed = 24.0", 'max_feed = "fast"'), 7, "must be a number, got 'fast'"),
        (
            ("interpolation_time = 0.012", "interpolation_time = 0.0"),
            15,
            "'interpolation_time' in [controller] must be a positive",
        ),
        (("path_tolerance = 0.01", "path_tolerence = 0.01"), 16, "did you mean 'path_tolerance'"),
        (("[axes.Z]", "[axes.W]"), 10, "unknown key 'W' in [axes]"),
        (('name = "Test mill"', 'name = "Test mill'), 1, "not valid TOML"),
    ],
    ids=[
        "misspelt",
        "missing",
        "negative",
        "zero",
        "inf feed",
        "nan",
        "string",
        "zero t_int",
        "misspelt controller",
        "axis W",
        "bad toml",
    ],
)
def test_bad_files_name_file_line_and_key(tmp_path, change, line, message):
    """Missing, misspelt, negative, zero and non-numeric values: one line naming file and line."""
    old, new = change
    p = write(tmp_path, GOOD.replace(old, new, 1))
    with pytest.raises(MachineError) as info:
        load_machine_file(p)
    msg = str(info.value)
    assert message in msg, msg
    assert msg.startswith(f"{p}:{line}:"), msg


def test_missing_file(tmp_path):
    """A machine file that does not exist: an error naming it."""
    with pytest.raises(MachineError, match="nope.toml: cannot read: No such file"):
        load_machine_file(tmp_path / "nope.toml")


def test_presets_load_and_the_840d_keeps_the_papers_t_int():
    """Shipped presets load; the 840D's t_int is the paper's 12 ms; LinuxCNC's is 1.02 ms."""
    names = preset_names()
    assert {"siemens-840d", "linuxcnc-sim"} <= set(names)
    m = load_preset("siemens-840d")
    assert m.interpolation_time == 0.012
    lc = load_preset("linuxcnc-sim")
    assert np.allclose(lc.max_feed, 250.0) and np.allclose(lc.max_acceleration, 2000.0)
    assert np.isinf(lc.max_jerk).all()
    # [TRAJ] MAX_LINEAR_VELOCITY = 250 mm/s of default_mill_mm.ini: a rapid along (0.6, 0.8),
    # whose axes would allow 250 / 0.8 = 312.5 mm/s, runs at 250
    assert lc.max_path_feed == pytest.approx(250.0)
    assert lc.rapid_speed(np.array([[0.6, 0.8, 0.0]]))[0] == pytest.approx(250.0)
    # the harness samples once per servo period, SERVO_PERIOD = 1000000 ns; the 840D's
    # file does not say how its traces are sampled
    assert lc.trace_cycle == 0.001 and math.isnan(m.trace_cycle)


def test_the_trace_cycle_of_a_machine_file(tmp_path):
    """``[diagnosis] trace_cycle`` (s) loads as given; zero or negative is an error naming
    file and line."""
    m = load_machine_file(write(tmp_path, GOOD + "[diagnosis]\ntrace_cycle = 0.002\n"))
    assert m.trace_cycle == 0.002
    p = write(tmp_path, GOOD + "[diagnosis]\ntrace_cycle = 0\n")
    with pytest.raises(MachineError) as info:
        load_machine_file(p)
    n = (GOOD + "[diagnosis]\n").count("\n") + 1
    assert str(info.value).startswith(f"{p}:{n}:")
    assert "'trace_cycle' in [diagnosis] must be a positive number" in str(info.value)


def test_840d_preset_marks_its_assumptions():
    """Every value of the 840D preset but t_int (from the paper) and the default path mode
    (from Siemens' documentation) is flagged as an assumption next to it."""
    from importlib import resources

    text = (resources.files("core.model") / "presets" / "siemens-840d.toml").read_text()
    for line in text.splitlines():
        if "=" in line and not line.startswith(("#", "name")):
            key = line.split("=")[0].strip()
            expect = {
                "interpolation_time": "FROM THE PAPER",
                "default_path_mode": "FROM SIEMENS",
            }.get(key, "ASSUMED")
            assert expect in line, line


def test_resolve_machine(tmp_path):
    """--machine takes a preset name or a TOML path; an unknown name lists the presets."""
    assert resolve_machine(None).source == "preset siemens-840d"
    assert resolve_machine("linuxcnc-sim").source == "preset linuxcnc-sim"
    assert resolve_machine(str(write(tmp_path, GOOD))).name == "Test mill"
    with pytest.raises(UsageError, match="unknown machine preset 'fanuc'; presets: "):
        resolve_machine("fanuc")
