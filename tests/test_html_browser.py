"""The HTML viewer in a real browser: Debian's Chromium driven by Playwright for Python
(``scripts/setup_browser.sh`` installs Chromium; ``pip install -e ".[test]"`` Playwright).
Playwright's own browser download is not used: the system Chromium is launched by path
(``NCPERF_CHROMIUM`` to choose another). Without Playwright or a Chromium the tests skip,
saying which is missing.

Pixels are read from screenshots (PNG, decoded here with zlib); the colours expected are the
classes' documented colours, written out below.
"""

from __future__ import annotations

import os
import shutil
import struct
import subprocess
import sys
import time
import zlib
from pathlib import Path

import numpy as np
import pytest

from core.cli import main
from tests.conftest import ROOT, diagnose_page

EXAMPLES = ROOT / "examples"
#: The reduction classes, green (0-10 %) to red (> 90 %) (paper Fig. 11).
REDUCTION = ("#1a9850", "#91cf60", "#d9ef8b", "#fdae61", "#f46d43", "#d73027")
#: The gap classes: 20 % slower or more ... within 10 % ... 20 % faster or more.
GAP = ("#b2182b", "#f4a582", "#1a9850", "#92c5de", "#2166ac")
#: Headless Chromium without a GPU renders WebGL with SwiftShader (software).
ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader"]


def chromium() -> str:
    """The Chromium to drive, or skip saying what is missing."""
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        pytest.skip("playwright is not installed (pip install -e '.[test]')")
    for name in (os.environ.get("NCPERF_CHROMIUM"), "chromium", "chromium-browser"):
        if name and (found := shutil.which(name)):
            return found
    pytest.skip("no Chromium (bash scripts/setup_browser.sh installs Debian's chromium)")


@pytest.fixture(scope="module")
def browser():
    exe = chromium()
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=exe, args=ARGS)
        yield b
        b.close()


class Page:
    """A loaded viewer page and everything it logged or requested."""

    def __init__(self, browser, file: Path, width: int = 1400, height: int = 900) -> None:
        self.page = browser.new_page(viewport={"width": width, "height": height})
        self.errors: list[str] = []
        self.requests: list[str] = []
        self.page.on("console", self._console)
        self.page.on("pageerror", lambda e: self.errors.append(f"pageerror: {e}"))
        self.page.on("request", lambda r: self.requests.append(r.url))
        self.url = file.resolve().as_uri()
        self.page.goto(self.url)
        # polled from here: Playwright's wait_for_function polls inside the page with eval,
        # which the viewer's Content-Security-Policy (no 'unsafe-eval') refuses once the page
        # is slow enough to need a second look (a million moves on a loaded machine)
        deadline = time.monotonic() + 60.0
        ready = "!!(window.ncperf && (window.ncperf.ready || window.ncperfErrors.length))"
        while not self.page.evaluate(ready):
            assert time.monotonic() < deadline, "the viewer did not get ready in 60 s"
            self.page.wait_for_timeout(50)
        assert self.page.evaluate("window.ncperfErrors") == []

    def _console(self, msg) -> None:
        if msg.type in ("error", "warning"):
            self.errors.append(f"console {msg.type}: {msg.text}")

    def pixels(self, selector: str = ".stage canvas.path") -> np.ndarray:
        """(h, w, 3) uint8 of a screenshot of the first element matching ``selector``."""
        return png_rgb(self.page.locator(selector).first.screenshot())

    def close(self) -> None:
        self.page.close()


def png_rgb(data: bytes) -> np.ndarray:
    """Decode an 8-bit RGB or RGBA, non-interlaced PNG (what Chromium writes) to (h, w, 3)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind, body = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            w, h, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and colour in (2, 6) and interlace == 0
            ch = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(h, 1 + w * ch)
    out = np.zeros((h, w * ch), dtype=np.int32)
    prev = np.zeros(w * ch, dtype=np.int32)
    for y in range(h):
        f, line = raw[y, 0], raw[y, 1:].astype(np.int32)
        cur = np.zeros_like(prev)
        if f == 0:
            cur = line
        elif f == 2:
            cur = (line + prev) & 255
        else:
            for x in range(w * ch):  # sub, average, Paeth: left neighbours needed
                a = cur[x - ch] if x >= ch else 0
                b, c = prev[x], prev[x - ch] if x >= ch else 0
                if f == 1:
                    p = a
                elif f == 3:
                    p = (a + b) >> 1
                else:
                    pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                    p = a if pa <= pb and pa <= pc else b if pb <= pc else c
                cur[x] = (line[x] + p) & 255
        out[y] = cur
        prev = cur
    return out.reshape(h, w, ch)[:, :, :3].astype(np.uint8)


def nearest(px: np.ndarray, colours: tuple[str, ...]) -> np.ndarray:
    """Pixels drawn in each of ``colours``, antialiased edges included: a line of colour C
    blended into the white background is white + a (C - white), so 255 - pixel points the
    way 255 - C does whatever the coverage a; each clearly drawn pixel is counted for the
    colour whose direction it matches (cosine above 0.995), if any."""
    ref = 255.0 - np.array([[int(c[k : k + 2], 16) for k in (1, 3, 5)] for c in colours])
    p = 255.0 - px.reshape(-1, 3).astype(float)
    mag = np.linalg.norm(p, axis=1)
    p = p[mag > 40] / mag[mag > 40, None]
    cos = p @ (ref / np.linalg.norm(ref, axis=1)[:, None]).T
    k = np.argmax(cos, axis=1)
    return np.bincount(k[cos[np.arange(k.size), k] > 0.995], minlength=len(colours))


def share_of(px: np.ndarray, colour: str, tol: int = 6) -> float:
    """Share of the pixels within ``tol`` of ``colour`` on every channel."""
    rgb = np.array([int(colour[k : k + 2], 16) for k in (1, 3, 5)])
    return float(np.mean(np.all(np.abs(px.astype(int) - rgb) <= tol, axis=-1)))


@pytest.fixture(scope="module")
def demo_html(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("html") / "demo.html"
    assert main(["analyze", "--html", str(out)]) == 0
    return out


@pytest.fixture
def demo(browser, demo_html):
    p = Page(browser, demo_html)
    yield p
    p.close()


# ------------------------------------------------------------------ the tests
def test_demo_loads_without_error_or_request(demo):
    """The bundled demo's page loads with no JavaScript error, no console error or warning,
    no request but the file itself, and says it draws with WebGL."""
    assert demo.errors == []
    assert demo.requests == [demo.url]
    status = demo.page.text_content("#status")
    assert "1,947 moves" in status and "WebGL" in status


def test_path_drawn_in_several_colours(demo):
    """The canvas is not blank: the path is drawn in at least three of the reduction
    classes' colours, and the rapids toggle takes the grey rapids away."""
    px = demo.pixels()
    drawn = float(np.mean(np.any(px < 245, axis=-1)))
    assert drawn > 0.02
    present = [c for c in REDUCTION if share_of(px, c) > 0.0005]
    assert len(present) >= 3, present
    demo.page.uncheck("#rapids")
    demo.page.wait_for_timeout(300)
    gone = np.any(demo.pixels() != px, axis=-1)
    assert np.count_nonzero(gone) > 50
    p = px[gone].astype(int)  # what was there: the rapids' grey, lighter where antialiased
    grey = (np.abs(p[:, 0] - p[:, 1]) <= 4) & (np.abs(p[:, 1] - p[:, 2]) <= 4)
    assert np.mean(grey) > 0.9


def test_hover_shows_the_program_line(demo):
    """Hovering over a block shows its program line number and the line's text, and its
    programmed feed."""
    from core import ExtractOptions, Ncperf, load_preset, make_plugin_manager

    nc = Ncperf(make_plugin_manager(entry_points=False))
    tp = nc.extract(str(EXAMPLES / "zlevel_cavity.ngc"), ExtractOptions())
    del load_preset
    # The longest feed move: hovered at its middle after zooming in on it.
    k = int(np.argmax(np.where(tp.is_feed, tp.length, 0)))
    line = int(tp.line[k])
    text = (EXAMPLES / "zlevel_cavity.ngc").read_text().split("\n")[line - 1].strip()
    x, y = demo.page.evaluate(f"window.ncperf.screenOf(0, {k})")
    demo.page.mouse.move(x, y)
    for _ in range(4):
        demo.page.mouse.wheel(0, -400)
        demo.page.wait_for_timeout(100)
    x, y = demo.page.evaluate(f"window.ncperf.screenOf(0, {k})")
    demo.page.mouse.move(x + 1, y + 1)
    demo.page.mouse.move(x, y)
    tip = demo.page.locator("#tip")
    tip.wait_for(state="visible", timeout=5000)
    shown = tip.text_content()
    assert f"line {line} " in shown
    assert text in shown
    assert f"programmed F {tp.feed[k] * 60:,.0f} mm/min" in shown
    assert demo.errors == []


def test_click_selects_and_plots(demo):
    """Clicking a block selects it: the info box names its line and the speed plot is drawn."""
    blank = demo.pixels("#plot")
    x, y = demo.page.evaluate("window.ncperf.screenOf(0, 500)")
    demo.page.mouse.click(x, y)
    demo.page.wait_for_timeout(200)
    assert demo.page.evaluate("window.ncperf.state.sel") is not None
    assert "line " in demo.page.text_content("#info")
    plotted = demo.pixels("#plot")
    assert np.any(plotted != blank)
    assert share_of(plotted, "#d73027", 40) > 0  # the predicted speed, in red


def test_clicking_a_zone_zooms_to_it(demo):
    """Clicking a row of the zones table zooms the view in on the zone and selects it."""
    before = demo.pixels()
    scale = demo.page.evaluate("window.ncperf.camera.scale")
    demo.page.click("#zones tbody tr:first-child")
    demo.page.wait_for_timeout(300)
    assert demo.page.evaluate("window.ncperf.camera.scale") > 2 * scale
    sel = demo.page.evaluate("window.ncperf.state.sel")
    assert sel is not None and sel["first"] <= sel["last"]
    assert np.mean(np.any(demo.pixels() != before, axis=-1)) > 0.05


def test_views_and_colour_modes_change_the_picture(demo):
    """XZ, YZ and iso show other pictures than XY; colouring by block length against L
    shows the length classes' colours."""
    pics = {}
    for v in ("XY", "XZ", "iso"):
        demo.page.click(f"#views button:text-is('{v}')")
        demo.page.wait_for_timeout(200)
        pics[v] = demo.pixels()
    assert np.mean(np.any(pics["XY"] != pics["XZ"], axis=-1)) > 0.01
    assert np.mean(np.any(pics["XY"] != pics["iso"], axis=-1)) > 0.01
    demo.page.select_option("#mode", "length")
    demo.page.wait_for_timeout(200)
    px = demo.pixels()
    assert share_of(px, "#1a9850") > 0.001  # 2 L and longer
    assert "block length" in demo.page.text_content("#legend")
    assert demo.errors == []


def test_screenshot(demo, tmp_path):
    """A full-page screenshot of the demo can be taken (scripts/screenshot_viewer.py makes
    the README's picture the same way)."""
    out = tmp_path / "viewer.png"
    demo.page.screenshot(path=str(out))
    assert out.stat().st_size > 10_000


def test_compare_page_side_by_side(browser, tmp_path):
    """compare --html: both programs drawn side by side at one scale, the ranked table."""
    out = tmp_path / "c.html"
    a, b = EXAMPLES / "zlevel_cavity.ngc", EXAMPLES / "zlevel_cavity_chords.ngc"
    assert main(["compare", str(a), str(b), "--html", str(out)]) == 0
    p = Page(browser, out)
    try:
        assert p.errors == []
        captions = p.page.locator(".panel .caption").all_text_contents()
        assert len(captions) == 2
        rows = p.page.locator("#ranking tbody tr")
        assert rows.count() == 2
        firsts = [rows.nth(k).locator("td").nth(1).text_content() for k in range(2)]
        assert captions == [f"#{k} {name}" for k, name in enumerate(firsts, start=1)]
        for k in range(2):
            px = p.pixels(f".panel:nth-child({k + 1}) canvas.path")
            assert float(np.mean(np.any(px < 245, axis=-1))) > 0.01
    finally:
        p.close()


def test_diagnose_page_coloured_by_gap(browser, tmp_path):
    """diagnose --html opens coloured by the gap: the 'within 10 %' colour is drawn, the
    legend says gap, and hovering shows the measured-minus-predicted share."""
    out = diagnose_page(tmp_path)
    p = Page(browser, out)
    try:
        assert p.errors == []
        assert p.page.input_value("#mode") == "gap"
        assert "gap" in p.page.text_content("#legend")
        counts = nearest(p.pixels(), GAP)
        # The trace is the prediction: the path is within 10 % nearly everywhere.
        assert counts[2] > 200 and counts[2] > 5 * (counts.sum() - counts[2]), counts
    finally:
        p.close()


def test_million_moves_interactive_within_5_s(browser, tmp_path):
    """A 1,000,000-move finishing raster: the page is under 30 MB and interactive (drawn,
    hover answering) within 5 s of navigation in headless Chromium on this 2-core VM."""
    prog = tmp_path / "raster.nc"
    subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "gen_finishing.py"), str(prog), "1000000"],
        check=True,
        capture_output=True,
    )
    out = tmp_path / "raster.html"
    assert main(["analyze", str(prog), "--html", str(out)]) == 0
    size = out.stat().st_size
    assert size < 30 * 2**20, size
    t0 = time.monotonic()
    p = Page(browser, out)
    try:
        ready_ms = p.page.evaluate("window.ncperf.readyAt")
        assert ready_ms < 5000, ready_ms
        x, y = p.page.evaluate("window.ncperf.screenOf(0, 400000)")
        p.page.mouse.move(x, y)
        p.page.locator("#tip").wait_for(state="visible", timeout=5000)
        assert "line " in p.page.text_content("#tip")
        assert time.monotonic() - t0 < 15  # page load, first hover (grid) included
        assert p.errors == []
        assert "1,000,001 moves" in p.page.text_content("#status")
    finally:
        p.close()
