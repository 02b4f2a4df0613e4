#!/usr/bin/env bash
# Install Debian's Chromium for the HTML viewer's browser tests (tests/test_html_browser.py),
# which drive it with Playwright for Python (installed by `pip install -e ".[test]"`; its own
# browser download is not used: the tests launch the system Chromium by path).
#
# Installs with apt-get only when no chromium is on the PATH and we are root or have
# passwordless sudo (one `apt-get update`, then `chromium`, no recommends). Where Chromium
# cannot be had it says so in one line and exits 0: the set-up goes on and those tests skip
# with that reason. Idempotent.
set -uo pipefail

skip() {
    echo "setup_browser: $1; the HTML viewer's browser tests will be skipped" >&2
    exit 0
}

if command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1; then
    exit 0
fi
. "$(dirname "${BASH_SOURCE[0]}")/apt_install.sh"
apt_install setup_browser chromium "about 100 MB" "Chromium is missing"
command -v chromium >/dev/null 2>&1 || skip "chromium is installed but not on the PATH"
echo "setup_browser: $(chromium --version 2>/dev/null | head -n 1) is installed" >&2
