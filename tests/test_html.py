"""The interactive HTML display (A3): adapters/html -- the file it writes, read back here
without a browser (tests/test_html_browser.py runs it in Chromium)."""

from __future__ import annotations

import base64
import json
import re
import zlib
from pathlib import Path

import numpy as np
import pytest

import adapters.html
import adapters.svg
from core import FileTarget, HtmlTarget, Ncperf, load_preset, make_plugin_manager
from core.cli import main
from tests.conftest import ROOT, diagnose_page, path

PLUGINS = (
    "plugins.tangential",
    "plugins.curvature",
    "plugins.ncu_capacity",
    "plugins.exact_stop",
    "adapters.gcode",
    "adapters.html",
)
EXAMPLES = ROOT / "examples"
META_RE = re.compile(r'<script type="application/json" id="ncperf-meta">(.*?)</script>', re.S)
BLOB_RE = re.compile(
    r'<script type="application/octet-stream" id="(b\d+)">([A-Za-z0-9+/=]*)</script>'
)
DTYPES = {"i1": "<i1", "u1": "<u1", "i2": "<i2", "u2": "<u2", "i4": "<i4", "f4": "<f4"}


# ------------------------------------------------------------------ an independent reader
def read_page(file: Path) -> tuple[str, dict, dict[str, bytes]]:
    """The page's text, its JSON metadata and its base64 blocks by id."""
    text = file.read_text(encoding="utf-8")
    m = META_RE.search(text)
    assert m, "no metadata block"
    meta = json.loads(m.group(1))
    blobs = {k: v for k, v in BLOB_RE.findall(text)}
    return text, meta, blobs


def array(spec: dict, blobs: dict[str, str]) -> np.ndarray:
    """One embedded array, decoded as the module docstring of adapters/html/page.py says:
    base64, zlib, byte planes, little-endian, optional running sum per row."""
    raw = zlib.decompress(base64.b64decode(blobs[spec["id"]]))
    dt = np.dtype(DTYPES[spec["dtype"]])
    planes = np.frombuffer(raw, dtype=np.uint8).reshape(dt.itemsize, -1)
    a = np.frombuffer(planes.T.tobytes(), dtype=dt).reshape(spec["shape"])
    if spec["delta"]:
        a = np.cumsum(a.astype(np.int64), axis=-1).astype(np.int32)
    return a


def moves_xyz(p: dict, blobs: dict[str, str]) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) start and end of each move from the embedded polyline."""
    npts = array(p["npts"], blobs)
    pts = array(p["pts"], blobs).T * p["quantum"] + np.asarray(p["centre"])
    start, end, k = [], [], 0
    for f in npts.tolist():
        if f & 0x80:
            start.append(pts[k])
            k += 1
        else:
            start.append(pts[k - 1])
        k += f & 0x7F
        end.append(pts[k - 1])
    assert k == pts.shape[0]
    return np.array(start), np.array(end)


def write(tp, target, tmp_path: Path | None = None) -> Path:
    nc = Ncperf(make_plugin_manager(builtins=PLUGINS, entry_points=False))
    from core.engine.profile import build_profile
    from core.view.analysis import Analysis
    from core.view.annotations import build_annotations

    ev = nc.evaluate(tp, load_preset("siemens-840d"))
    pr = build_profile(ev)
    an = Analysis(tp, ev, pr, build_annotations(ev, pr))
    if callable(target):
        target = target(an)
    out = nc.display(tp, an.annotations, target)
    return Path(out)


SQUARE = [
    {"end": (10.0, 0.0, 0.0)},
    {"end": (10.0, 10.0, 0.0)},
    {"end": (0.0, 10.0, -1.5)},
    {"end": (0.0, 30.0, 5.0), "rapid": True},
    {"end": (20.0, 30.0, 5.0)},
    {"end": (30.0, 40.0, 5.0), "center": (20.0, 40.0, 5.0), "ccw": True},
]


# ------------------------------------------------------------------ the file
def test_recognises_html_targets_only(tmp_path):
    """The HTML display takes .html/.htm names and targets, and nothing else; the SVG
    display leaves .html targets alone."""
    assert adapters.html.html_target("a.HTML") == ("a.HTML", "xy")
    assert adapters.html.html_target(FileTarget(tmp_path / "a.htm", view="iso")) == (
        str(tmp_path / "a.htm"),
        "iso",
    )
    assert adapters.html.html_target("a.svg") is None
    assert adapters.html.html_target(object()) is None
    tp = path(SQUARE[:2])
    assert adapters.html.ncperf_display(toolpath=tp, annotations=None, target="a.svg") is None
    assert adapters.svg.ncperf_display(toolpath=tp, annotations=None, target="a.html") is None


def test_page_is_self_contained(tmp_path):
    """One file: every script and style inline, no URL of another resource, and a content
    policy that forbids the browser any request."""
    out = write(path(SQUARE), tmp_path / "p.html")
    text = out.read_text(encoding="utf-8")
    assert not re.search(r"https?://", text)
    assert not re.search(r"\b(src|href)\s*=", text, re.I)
    assert "@import" not in text and "url(" not in text
    assert "default-src 'none'" in text
    assert text.count("<script") == text.count("</script>")
    assert "<link" not in text


def test_decoded_arrays_are_the_tool_paths(tmp_path):
    """The embedded polyline gives back each move's start and end (to 0.1 um), its line and
    feed; a rapid stays a rapid and starts a new stroke where it does not join."""
    tp = path(SQUARE, feed=50.0)
    out = write(tp, HtmlTarget(str(tmp_path / "p.html")))
    _, meta, blobs = read_page(out)
    (p,) = meta["panels"]
    assert p["n"] == 6
    start, end = moves_xyz(p, blobs)
    expect_end = np.array([m["end"] for m in SQUARE])
    expect_start = np.vstack([[0.0, 0.0, 0.0], expect_end[:-1]])
    np.testing.assert_allclose(end, expect_end, atol=1e-4)
    np.testing.assert_allclose(start, expect_start, atol=1e-4)
    np.testing.assert_array_equal(array(p["kind"], blobs), [1, 1, 1, 0, 1, 2])
    feed = array(p["feed"], blobs)
    np.testing.assert_allclose(feed[[0, 1, 2, 4, 5]], 3000.0)  # 50 mm/s
    assert np.isnan(feed[3])
    lengths = [10.0, 10.0, np.hypot(10.0, 1.5), np.hypot(20.0, 6.5), 20.0, np.pi / 2 * 10.0]
    np.testing.assert_allclose(array(p["length"], blobs), lengths, rtol=1e-6)


def test_arcs_are_chords_on_the_circle(tmp_path):
    """An arc is drawn as several chords whose points lie on its circle."""
    tp = path(SQUARE)
    out = write(tp, tmp_path / "p.html")
    _, meta, blobs = read_page(out)
    (p,) = meta["panels"]
    npts = array(p["npts"], blobs)
    pts = array(p["pts"], blobs).T * p["quantum"] + np.asarray(p["centre"])
    k = int(npts[5] & 0x7F)
    assert k >= 2
    arc = pts[-k - 1 :]  # its start (the previous end) and its k points
    r = np.hypot(arc[:, 0] - 20.0, arc[:, 1] - 40.0)
    np.testing.assert_allclose(r, 10.0, atol=1e-3)
    assert np.all(np.diff(np.arctan2(arc[:, 1] - 40.0, arc[:, 0] - 20.0)) > 0)  # ccw


def test_predictions_embedded(tmp_path):
    """Speed share, classes and profile speeds are embedded per move, within their steps."""
    tp = path(SQUARE, feed=50.0)
    holder = {}

    def target(an):
        holder["an"] = an
        return HtmlTarget(str(tmp_path / "p.html"), (("square", an, None),))

    out = write(tp, target)
    an = holder["an"]
    _, meta, blobs = read_page(out)
    (p,) = meta["panels"]
    share = array(p["share"], blobs) / 65535.0
    feed = tp.is_feed
    expect = tp.length[feed] / (an.profile.time[feed] * 50.0)  # length / time / F
    np.testing.assert_allclose(share[feed], expect, atol=2e-5)
    v = array(p["v"], blobs) * (p["vmax"] / 65535.0) / 60.0
    np.testing.assert_allclose(v[2], an.profile.v_exit, atol=p["vmax"] / 60.0 / 60000)
    np.testing.assert_array_equal(array(p["lclass"], blobs), an.annotations.length_class)
    assert p["text_note"].startswith("program text not embedded")


def test_hostile_names_and_text_cannot_break_the_page(tmp_path):
    """A file name and comments made to close the script block or to act as markup stay
    text: escaped in the JSON, the title and the program text, controls shown as escapes."""
    name = "x<b onmouseover=alert(1)>\u2028\u202e&amp;.ngc"
    prog = tmp_path / name
    prog.write_text(
        "G21 G90 G17\nG1 X10 Y0 F1000 (</script><img src=x onerror=alert(2)>)\n"
        "G1 X10 Y10 (\x1b[31m \u202e evil)\nG1 X0 Y10\nM30\n",
        encoding="utf-8",
    )
    out = tmp_path / "page.html"
    assert main(["analyze", str(prog), "--html", str(out)]) == 0
    text, meta, blobs = read_page(out)
    assert "<b onmouseover" not in text and "<img" not in text and "</script><" not in text
    m = META_RE.search(text)
    block = m.group(1)
    assert "<" not in block and ">" not in block and "\u2028" not in block
    label = meta["panels"][0]["label"]
    assert label.startswith("x<b onmouseover")  # the same name, shown as text by the page
    assert "\\u202e" in label  # the bidi override as a visible escape
    title = re.search(r"<title>(.*?)</title>", text, re.S).group(1)
    assert "<" not in title
    src = bytes(array(meta["panels"][0]["text"], blobs)).decode("utf-8")
    lines = src.split("\n")
    assert lines[1] == "G1 X10 Y0 F1000 (</script><img src=x onerror=alert(2)>)"
    assert lines[2] == "G1 X10 Y10 (\\x1b[31m \\u202e evil)"


def test_large_program_stays_compact(tmp_path):
    """A 20,000-move raster takes well under 30 bytes a move (the 1M-move bound, 30 MB,
    is checked in the browser tests)."""
    n = 20_000
    x = np.tile([0.0, 100.0], n // 2 + 1)[: n + 1]
    pts = np.column_stack([x, np.arange(n + 1) * 0.3, np.sin(np.arange(n + 1))])
    from core.model.toolpath import polyline

    tp = polyline(pts, 100.0)
    out = write(tp, tmp_path / "big.html")
    assert out.stat().st_size < 30 * n


# ------------------------------------------------------------------ the command line
def test_analyze_html_and_open(tmp_path, monkeypatch):
    """--html writes the page (with the program text); --open opens it as a file: URI once
    it is in place, in the browser webbrowser picks (not opened here)."""
    import webbrowser

    out = tmp_path / "demo.html"
    opened = []

    def fake_open(url):
        opened.append((url, out.exists()))
        return True

    monkeypatch.setattr(webbrowser, "open", fake_open)
    prog = EXAMPLES / "fig1_polygons_F4000.ngc"
    assert main(["analyze", str(prog), "--html", str(out), "--open"]) == 0
    assert opened == [(out.resolve().as_uri(), True)]
    _, meta, blobs = read_page(out)
    p = meta["panels"][0]
    text = bytes(array(p["text"], blobs)).decode("utf-8").split("\n")
    assert text == prog.read_text(encoding="utf-8").split("\n")
    assert meta["kind"] == "analyze" and meta["default_mode"] == "speed"
    assert [m[0] for m in meta["modes"]] == ["speed", "junction", "length"]


def test_open_needs_html(tmp_path, capsys):
    """--open without --html is a usage error (exit 2), and nothing is opened."""
    assert main(["analyze", str(EXAMPLES / "fig1_polygons_F4000.ngc"), "--open"]) == 2
    assert "--html" in capsys.readouterr().err


def test_compare_html_ranked(tmp_path):
    """compare --html: one panel per program in ranked order, the ranked table, one centre
    (so that the panels share one scale and position)."""
    out = tmp_path / "c.html"
    a, b = EXAMPLES / "zlevel_cavity.ngc", EXAMPLES / "zlevel_cavity_chords.ngc"
    assert main(["compare", str(a), str(b), "--html", str(out)]) == 0
    _, meta, _ = read_page(out)
    assert meta["kind"] == "compare"
    labels = [p["label"] for p in meta["panels"]]
    header, *rows = meta["table"]
    assert header[:2] == ["#", "program"]
    assert [r[0] for r in rows] == ["1", "2"]
    assert labels == [f"#{r[0]} {r[1]}" for r in rows]
    assert sorted(r[1] for r in rows) == ["zlevel_cavity.ngc", "zlevel_cavity_chords.ngc"]
    assert meta["panels"][0]["centre"] == meta["panels"][1]["centre"]


def test_diagnose_html_has_gap(tmp_path):
    """diagnose --html opens coloured by gap, with the gap per move and the measured feed."""
    out = diagnose_page(tmp_path)
    _, meta, blobs = read_page(out)
    assert meta["kind"] == "diagnose" and meta["default_mode"] == "gap"
    (p,) = meta["panels"]
    gap = array(p["gap"], blobs)
    assert gap.shape == (p["n"],)
    # The trace is the prediction itself: the gap is small wherever it was measured.
    assert np.nanmax(np.abs(gap)) < 0.1
    (m,) = p["measured"]
    assert array(m["s"], blobs).size == array(m["v"], blobs).size > 10


@pytest.mark.parametrize("bad", ["folder.html", "missing/out.html"])
def test_html_output_checked_first(tmp_path, bad):
    """The --html output goes through the same checks as every output: a folder or a
    missing folder is a usage error (exit 2) and nothing is written."""
    (tmp_path / "folder.html").mkdir()
    prog = EXAMPLES / "fig1_polygons_F4000.ngc"
    assert main(["analyze", str(prog), "--html", str(tmp_path / bad)]) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder.html"]
