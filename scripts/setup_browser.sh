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
if [ "$(id -u)" -eq 0 ]; then
    as_root=()
elif command -v sudo >/dev/null 2>&1 && sudo -n true >/dev/null 2>&1; then
    as_root=(sudo -n)
else
    skip "Chromium is missing and installing it needs root or passwordless sudo"
fi
command -v apt-get >/dev/null 2>&1 || skip "Chromium is missing and there is no apt-get"
echo "setup_browser: installing chromium (about 100 MB, once)" >&2
export DEBIAN_FRONTEND=noninteractive
log="$(mktemp)"
if ! { "${as_root[@]}" apt-get update -qq &&
    "${as_root[@]}" apt-get install -y -qq --no-install-recommends chromium; } >"$log" 2>&1; then
    tail -n 5 "$log" >&2
    rm -f "$log"
    skip "apt-get could not install chromium"
fi
rm -f "$log"
command -v chromium >/dev/null 2>&1 || skip "chromium is installed but not on the PATH"
echo "setup_browser: $(chromium --version 2>/dev/null | head -n 1) is installed" >&2
