"""Plugin manager, hooks and the facade: built-ins and third-party plugins alike."""

from __future__ import annotations

import importlib
import inspect
import json
import math
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import core
from core import Ncperf, UsageError, hookspecs, make_plugin_manager
from core.cli.report import write_json
from core.engine.profile import build_profile
from core.view.annotations import build_annotations
from tests.conftest import ROOT, machine, path
from tests.plugins import sample

HOOKS = sorted(
    n for n, f in inspect.getmembers(hookspecs, inspect.isfunction) if n.startswith("ncperf_")
)


def test_importing_core_builds_no_plugin_manager():
    """`import core` has no side effects: no plugin manager, no adapter or plugin imported."""
    code = (
        "import sys, core; print(any(m.startswith(('adapters', 'plugins')) for m in sys.modules))"
    )
    import subprocess

    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert out.stdout.strip() == "False"


def test_builtins_registered_with_their_hooks():
    """Built-ins come from one tuple and implement the hooks of their task."""
    nc = Ncperf(make_plugin_manager(entry_points=False))
    rows = dict(nc.plugins())
    assert rows["adapters.gcode"] == ["ncperf_extract"]
    assert rows["adapters.svg"] == ["ncperf_display"]
    for name in (
        "plugins.tangential",
        "plugins.curvature",
        "plugins.ncu_capacity",
        "plugins.exact_stop",
    ):
        assert rows[name] == ["ncperf_evaluate"]


def test_disable_plugins_by_environment(monkeypatch):
    """NCPERF_DISABLE_PLUGINS keeps named plugins out."""
    monkeypatch.setenv("NCPERF_DISABLE_PLUGINS", "plugins.curvature, plugins.tangential")
    nc = Ncperf(make_plugin_manager(entry_points=False))
    names = dict(nc.plugins())
    assert "plugins.curvature" not in names and "plugins.tangential" not in names
    tp = path([{"end": (10, 0, 0)}, {"end": (10, 10, 0)}])
    assert nc.evaluate(tp, machine()).junction.size == 0


def test_third_party_plugin_all_hooks(tmp_path):
    """A plugin registered like any other takes part in A1, A2 and A3; its indicator shows up
    in the evaluation, the JSON and the SVG."""
    pm = make_plugin_manager(entry_points=False, extra=[sample])
    nc = Ncperf(pm)
    # A1 through the plugin (a host object, not a file)
    tp = nc.extract(sample.SampleSource([[0, 0, 0], [10, 0, 0]], 50.0))
    assert tp.source == "sample host" and tp.n == 1
    # A2: an arc of R 2 at F 100 mm/s; A = 2500 mm/s^2 -> cap sqrt(2500 * 2) = 70.7107 mm/s
    arc = path([{"end": (4, 0, 0), "center": (2, 0, 0), "ccw": True}], feed=100.0)
    ev = nc.evaluate(arc, machine())
    assert "arc_speed" in ev.indicator_names
    assert ev.element_feed[0] == pytest.approx(math.sqrt(2500 * 2))
    assert ev.labels[ev.element_limit[0]] == "centripetal acceleration"
    ann = build_annotations(ev)
    # A3 into a host canvas
    canvas = sample.SampleCanvas()
    assert nc.display(arc, ann, canvas) is canvas
    assert canvas.drawn == [(1, [1])]  # 1 - 70.71/100 = 29 %: class 1, "10-30 %"
    # JSON and SVG name the indicator
    out = tmp_path / "r.json"
    from core import Analysis

    with open(out, "w") as fh:
        write_json(Analysis(arc, ev, build_profile(ev), ann), fh)
    data = json.loads(out.read_text())
    assert data["elements"][0]["limited_by"] == "arc_speed: centripetal acceleration"
    svg = nc.display(arc, ann, str(tmp_path / "r.svg"))
    text = Path(svg).read_text()
    ET.fromstring(text)
    assert "arc_speed" in text


def test_entry_point_plugin_is_loaded(tmp_path, monkeypatch):
    """A package declaring [project.entry-points.ncperf] is registered by the factory."""
    pkg = tmp_path / "ncperf_ep_demo.py"
    pkg.write_text(inspect.getsource(sample))
    dist = tmp_path / "ncperf_ep_demo-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: ncperf-ep-demo\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text("[ncperf]\ndemo = ncperf_ep_demo\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    pm = make_plugin_manager()
    assert pm.get_plugin("demo") is not None
    nc = Ncperf(pm)
    arc = path([{"end": (4, 0, 0), "center": (2, 0, 0), "ccw": True}], feed=100.0)
    assert "arc_speed" in nc.evaluate(arc, machine()).indicator_names


def test_unrecognised_source_and_target():
    """No adapter for a source, no display for a target: a usage error naming them."""
    nc = Ncperf(make_plugin_manager(entry_points=False))
    with pytest.raises(UsageError, match="no adapter recognises"):
        nc.extract(object())
    tp = path([{"end": (10, 0, 0)}])
    ann = build_annotations(nc.evaluate(tp, machine()))
    with pytest.raises(UsageError, match=r"out\.bmp: no display handles"):
        nc.display(tp, ann, "out.bmp")


def test_bad_indicator_type_is_caught():
    """A plugin returning something else than Indicators fails loudly, naming the type."""

    class Bad:
        @core.hookimpl
        def ncperf_evaluate(self):
            return ["not an indicator"]

    nc = Ncperf(make_plugin_manager(builtins=(), entry_points=False, extra=[Bad()]))
    with pytest.raises(TypeError, match="returned str, not Indicator"):
        nc.evaluate(path([{"end": (1, 0, 0)}]), machine())


def test_indicator_validates_shapes():
    """An Indicator with mismatched columns says which and what shape."""
    with pytest.raises(ValueError, match=r"feed must have shape \(2,\), got \(3,\)"):
        core.Indicator(
            name="x", at="junction", index=[0, 1], feed=[1, 2, 3], limit=[0, 0], labels=("a",)
        )
    with pytest.raises(ValueError, match="repeated junction indices"):
        core.Indicator(
            name="x", at="junction", index=[0, 0], feed=[1, 2], limit=[0, 0], labels=("a",)
        )


def test_combine_keeps_the_lowest_feed_per_junction():
    """Several indicators at one junction: the lowest feed wins and names its limit."""
    tp = path([{"end": (10, 0, 0)}, {"end": (20, 0, 0)}, {"end": (30, 0, 0)}], feed=100.0)
    a = core.Indicator(
        name="a", at="junction", index=[0, 1], feed=[50.0, 200.0], limit=[0, 0], labels=("a limit",)
    )
    b = core.Indicator(
        name="b", at="junction", index=[1, 0], feed=[80.0, 60.0], limit=[0, 0], labels=("b limit",)
    )
    ev = core.combine(tp, machine(), [a, b])
    assert list(ev.junction) == [0, 1]
    assert list(ev.junction_feed) == [50.0, 80.0]
    assert [ev.indicator_names[k] for k in ev.junction_indicator] == ["a", "b"]
    assert [ev.labels[k] for k in ev.junction_limit] == ["a limit", "b limit"]
    assert np.allclose(ev.junction_reduction, [0.5, 0.2])


# ----------------------------------------------------------------------------- meta
def test_every_hook_has_a_test_plugin_implementation():
    """The test plugin implements every hookspec (so each hook is exercised end to end)."""
    impl = {n for n in dir(sample) if n.startswith("ncperf_")}
    assert impl == set(HOOKS)


@pytest.mark.parametrize("hook", HOOKS)
def test_every_hook_is_documented_and_tested(hook):
    """Each hook has a documentation entry and is called in at least one test."""
    assert f"`{hook}(" in (ROOT / "docs" / "plugins.md").read_text()
    spec = getattr(hookspecs, hook)
    spec_doc = spec.__doc__
    assert ":returns:" in spec_doc
    for name in inspect.signature(spec).parameters:
        assert f":param {name}:" in spec_doc
    tests = "".join(p.read_text() for p in (ROOT / "tests").glob("test_*.py"))
    method = {
        "ncperf_extract": "extract(",
        "ncperf_evaluate": "evaluate(",
        "ncperf_display": "display(",
        "ncperf_add_commands": "add_commands(",
        "ncperf_read_trace": "read_trace(",
        "ncperf_effects": "effects(",
    }[hook]
    assert f"nc.{method}" in tests


def test_plugin_adds_a_command(capsys):
    """A plugin's ncperf_add_commands subcommand runs through the CLI with the facade."""
    import argparse

    nc = Ncperf(make_plugin_manager(entry_points=False, extra=[sample]))
    parser = argparse.ArgumentParser(prog="ncperf")
    sub = parser.add_subparsers(dest="command")
    nc.add_commands(sub)
    args = parser.parse_args(["sample", "--echo", "yo"])
    assert args.run(args, nc) == 0
    assert "echo yo" in capsys.readouterr().out


def test_plugin_reads_a_trace():
    """A plugin's ncperf_read_trace serves a host recording through the facade."""
    nc = Ncperf(make_plugin_manager(entry_points=False, extra=[sample]))
    tr = nc.read_trace(sample.SampleTrace(t=[0.0, 0.1, 0.2], v=[0.0, 5.0, 0.0], line=[1, 1, 2]))
    assert tr.source == "sample trace" and len(tr) == 3 and tr.pos is None
    with pytest.raises(UsageError, match="no trace reader recognises"):
        nc.read_trace(object())


@pytest.mark.parametrize("args", [["--help"], ["--version"], ["machines"]])
def test_light_commands_load_no_numpy_and_no_model_plugin(args):
    """--help, --version and machines build the parser from the plugins that add commands
    only: neither numpy nor a model or reader plugin is imported (issue 13, start-up)."""
    code = (
        "import sys\nfrom core.cli import main\n"
        f"try:\n    main({args!r})\nexcept SystemExit:\n    pass\n"
        "mods = [m for m in sys.modules if m == 'numpy' or m.startswith('plugins')"
        " or m.startswith(('adapters.gcode', 'adapters.svg', 'adapters.traces'))]\n"
        "print('LOADED', mods, file=sys.stderr)"
    )
    import subprocess

    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert "LOADED []" in out.stderr
    assert out.stdout  # the help, the version or the presets were printed


def test_command_plugins_are_the_builtins_that_add_commands():
    """COMMAND_PLUGINS (all the parser loads) lists exactly the built-ins with a command."""
    from core.plugins import BUILTIN_PLUGINS, COMMAND_PLUGINS

    adding = [
        name
        for name in BUILTIN_PLUGINS
        if hasattr(importlib.import_module(name), "ncperf_add_commands")
    ]
    assert list(COMMAND_PLUGINS) == adding


def test_completed_manager_runs_hooks_in_the_fresh_managers_order():
    """The command line's manager, completed after parsing, calls every hook's plugins in
    the order of a manager made in one go (first-result hooks pick the same adapter)."""
    from core.plugins import command_plugin_manager, complete_plugin_manager

    fresh = Ncperf(make_plugin_manager())
    completed = Ncperf(complete_plugin_manager(command_plugin_manager()))
    for hook in HOOKS:
        assert completed.implementers(hook) == fresh.implementers(hook), hook


@pytest.mark.parametrize(
    ("text", "declared"),
    [
        ("[console_scripts]\nx = a:b\n", False),
        ("[ncperf]\ndemo = demo_mod\n", True),
        ("[console_scripts]\nx = a:b\n\n  [ ncperf ]  \ndemo = demo_mod\n", True),
        ("[ncperf.extra]\ndemo = demo_mod\n", False),
    ],
)
def test_entry_point_group_shortcut(tmp_path, monkeypatch, text, declared):
    """The quick look for an ``[ncperf]`` section in the installed distributions' metadata
    (which saves importing importlib.metadata) finds it wherever pluggy's loader would."""
    from core.plugins import _declares_group

    dist = tmp_path / "demo-1.0.dist-info"
    dist.mkdir()
    (dist / "entry_points.txt").write_text(text)
    (tmp_path / "old-1.0.egg-info").write_text("Metadata-Version: 1.0\n")  # a file, no folder
    monkeypatch.setattr(sys, "path", [str(tmp_path)])
    assert _declares_group("ncperf") is declared
