#!/usr/bin/env bash
# Install LinuxCNC's interpreter (Debian's linuxcnc-uspace, which gives the system Python the
# `gcode` module) for the tests that read programs with LinuxCNC and compare: the oracle for
# reading G-code (tests/test_gcode_linuxcnc.py, benchmarks/lcnc_oracle.py).
#
# Installs with apt-get only when /usr/bin/python3 cannot import gcode and we are root or
# have passwordless sudo (about 80 MB download, +270 MB on disk, no recommends: no RT
# kernel, no GUI). Where LinuxCNC cannot be had it says so in one line and exits 0: the
# set-up goes on and those tests skip with that reason. Idempotent.
set -uo pipefail

skip() {
    echo "setup_linuxcnc: $1; the LinuxCNC cross-check tests will be skipped" >&2
    exit 0
}

if /usr/bin/python3 -c "import gcode" >/dev/null 2>&1; then
    exit 0
fi
. "$(dirname "${BASH_SOURCE[0]}")/apt_install.sh"
apt_install setup_linuxcnc linuxcnc-uspace "about 80 MB" "LinuxCNC is missing"
/usr/bin/python3 -c "import gcode" >/dev/null 2>&1 ||
    skip "linuxcnc-uspace is installed but /usr/bin/python3 cannot import gcode"
echo "setup_linuxcnc: LinuxCNC's interpreter is installed" >&2
