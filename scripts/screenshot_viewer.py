"""Make the README's picture of the HTML viewer: the bundled demo in Chromium, a block
selected (its speed plot drawn) and another hovered.

    python scripts/screenshot_viewer.py [OUT.png]      (default docs/ncperf-viewer.png)

Needs Playwright (``pip install -e ".[test]"``) and a Chromium (``scripts/setup_browser.sh``;
``NCPERF_CHROMIUM`` to choose another).
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
from pathlib import Path

from playwright.sync_api import sync_playwright

from core.cli import main

ROOT = Path(__file__).resolve().parents[1]


def chromium() -> str:
    for name in (os.environ.get("NCPERF_CHROMIUM"), "chromium", "chromium-browser"):
        if name and (found := shutil.which(name)):
            return found
    sys.exit("screenshot_viewer: no Chromium (bash scripts/setup_browser.sh)")


def shoot(out: Path) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        page_file = Path(tmp) / "demo.html"
        if main(["analyze", "--html", str(page_file)]) != 0:
            sys.exit("screenshot_viewer: ncperf analyze failed")
        with sync_playwright() as pw:
            browser = pw.chromium.launch(
                executable_path=chromium(),
                args=["--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
            )
            page = browser.new_page(viewport={"width": 1400, "height": 860})
            page.goto(page_file.resolve().as_uri())
            page.wait_for_function("window.ncperf && window.ncperf.ready", timeout=60_000)
            x, y = page.evaluate("window.ncperf.screenOf(0, 14)")  # a block of zone 1
            page.mouse.click(x, y)
            x, y = page.evaluate("window.ncperf.screenOf(0, 900)")
            page.mouse.move(x, y)
            page.wait_for_timeout(300)
            page.screenshot(path=str(out))
            browser.close()


if __name__ == "__main__":
    target = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "docs" / "ncperf-viewer.png"
    shoot(target)
    print(f"screenshot_viewer: wrote {target} ({target.stat().st_size:,} bytes)")
