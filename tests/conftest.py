"""Shared fixtures: fresh plugin managers, machines, hand-built tool paths, ../shared data."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from core import Machine, Ncperf, ToolPath, make_plugin_manager
from core.model.toolpath import MoveKind, empty_columns

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("NCPERF_SHARED", ROOT.parent / "shared"))

MODELS = (
    "plugins.tangential",
    "plugins.curvature",
    "plugins.ncu_capacity",
    "plugins.exact_stop",
    "plugins.feed_limit",
)


def shared(*parts: str) -> Path:
    """A file under ../shared, or skip the test when the folder is absent."""
    p = SHARED.joinpath(*parts)
    if not p.exists():
        pytest.skip(f"{p} not present (../shared is only on developer machines)")
    return p


@pytest.fixture
def nc() -> Ncperf:
    """A facade over a fresh plugin manager with every built-in and no entry points."""
    return Ncperf(make_plugin_manager(entry_points=False))


@pytest.fixture
def models() -> Ncperf:
    """A facade over a fresh plugin manager with only the model plugins."""
    return Ncperf(make_plugin_manager(builtins=MODELS, entry_points=False))


def machine(
    feed=(30.0, 30.0, 30.0),
    acc=(2.5, 2.5, 2.5),
    jerk=(5.0, 5.0, 5.0),
    t_int=0.012,
    tit=0.01,
    dt=0.012,
) -> Machine:
    """A machine in the paper's units (m/min, m/s^2, m/s^3); defaults as the 840D preset."""
    return Machine.from_user_units(
        "test machine",
        max_feed_m_min=feed,
        max_acceleration_m_s2=acc,
        max_jerk_m_s3=jerk,
        interpolation_time=t_int,
        path_tolerance=tit,
        curvature_transition_time=dt,
    )


def path(moves: list[dict], feed: float = 100.0) -> ToolPath:
    """A tool path from move dicts: {"end": (x, y, z)} lines, or arcs with
    {"end", "center", "ccw", "normal" (default +Z)}; the first move starts at the origin
    unless it has "start". ``feed`` in mm/s."""
    cols = empty_columns(len(moves))
    pos = np.asarray(moves[0].get("start", (0.0, 0.0, 0.0)), dtype=float)
    for i, m in enumerate(moves):
        cols["start"][i] = m.get("start", pos)
        cols["end"][i] = m["end"]
        cols["feed"][i] = m.get("feed", feed)
        if "center" in m:
            cols["kind"][i] = MoveKind.ARC_CCW if m["ccw"] else MoveKind.ARC_CW
            cols["center"][i] = m["center"]
            cols["normal"][i] = m.get("normal", (0.0, 0.0, 1.0))
        elif m.get("rapid"):
            cols["kind"][i] = MoveKind.RAPID
            cols["feed"][i] = np.nan
        pos = np.asarray(m["end"], dtype=float)
    arcs = cols["kind"] >= MoveKind.ARC_CW
    if arcs.any():
        from core.model.geometry import arc_sweep

        cols["sweep"][arcs] = arc_sweep(
            cols["start"][arcs],
            cols["end"][arcs],
            cols["center"][arcs],
            cols["normal"][arcs],
            cols["kind"][arcs] == MoveKind.ARC_CCW,
        )
    return ToolPath(**cols)


def diagnose_page(tmp_path: Path) -> Path:
    """The HTML page of ``ncperf diagnose --html`` on the Fig. 3 spiral against its own
    predicted trace (``ncperf profile``, linuxcnc-sim), the feed override alone tried."""
    from core.cli import main

    prog = ROOT / "examples" / "fig3_semicircle_spiral.ngc"
    trace = tmp_path / "t.csv"
    assert main(["profile", str(prog), "--machine", "linuxcnc-sim", "--csv", str(trace)]) == 0
    out = tmp_path / "d.html"
    args = ["diagnose", str(prog), str(trace), "--machine", "linuxcnc-sim"]
    assert main([*args, "--effects", "feed_override", "--html", str(out)]) == 0
    return out
