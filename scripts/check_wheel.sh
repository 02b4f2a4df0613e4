#!/usr/bin/env bash
# Build ncperf's wheel with `python -m build`, install it alone in a new virtual environment
# outside the repository, and run every command on the bundled data. A package, module or
# data file missing from the wheel shows up here, not on a user's machine.
#
#   bash scripts/check_wheel.sh      (from the repository root; needs Python 3.11+ and PyPI)
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

python3 -m venv "$WORK/build-env"
"$WORK/build-env/bin/pip" install -q build
"$WORK/build-env/bin/python" -m build -q --wheel --outdir "$WORK/dist" "$ROOT" >/dev/null
WHEEL=$(ls "$WORK"/dist/ncperf-*.whl)
echo "check_wheel: built $(basename "$WHEEL")"

# What the wheel holds: the packages and their data, nothing of tests or benchmarks.
python3 - "$WHEEL" <<'EOF'
import sys, zipfile
names = set(zipfile.ZipFile(sys.argv[1]).namelist())
need = [
    "core/__init__.py", "core/model/presets/siemens-840d.toml",
    "core/model/presets/linuxcnc-sim.toml", "core/py.typed", "adapters/traces/__init__.py",
    "plugins/effects/__init__.py", "examples/zlevel_cavity.ngc", "refvm/__init__.py",
    "adapters/esprit_com/csharp/NcperfShim.cs", "adapters/html/viewer.js",
    "adapters/html/viewer.css", "adapters/html/template.html",
]
missing = [n for n in need if n not in names]
stray = sorted(n for n in names if n.split("/")[0] in ("tests", "benchmarks", "scripts"))
if missing or stray:
    sys.exit(f"check_wheel: missing {missing}, should not be there {stray[:5]}")
print(f"check_wheel: {len(names)} files in the wheel, packages and data present")
EOF

python3 -m venv "$WORK/venv"
"$WORK/venv/bin/pip" install -q "$WHEEL"
cd "$WORK"  # nothing of the repository on the path
NC="$WORK/venv/bin/ncperf"
EX=$("$WORK/venv/bin/python" -c "import importlib.resources as r; print(r.files('examples'))")
run() { echo "check_wheel: ncperf $*"; "$NC" "$@" >"$WORK/out.txt" 2>"$WORK/err.txt" || {
    cat "$WORK/out.txt" "$WORK/err.txt"; echo "check_wheel: FAILED: ncperf $*"; exit 1; }; }
if command -v cc >/dev/null || command -v gcc >/dev/null; then
    "$WORK/venv/bin/python" -c "from core.model.native import native; from adapters.gcode.lexer import _words_library as w; assert native() and w()" ||
        { echo "check_wheel: the wheel's C kernels do not load"; exit 1; }
    echo "check_wheel: the C kernels load"
fi
run --help
run --version
run machines
run plugins
run analyze --svg "$WORK/demo.svg"
run analyze "$EX/fig1_polygons_F4000.ngc" --machine linuxcnc-sim --json "$WORK/a.json" --svg "$WORK/a.svg"
run profile "$EX/fig3_semicircle_spiral.ngc" --machine linuxcnc-sim --csv "$WORK/trace.csv"
run compare "$EX/zlevel_cavity.ngc" "$EX/zlevel_cavity_chords.ngc" --svg "$WORK/c.svg" \
    --html "$WORK/c.html"
run analyze --html "$WORK/demo.html"
run diagnose "$EX/fig3_semicircle_spiral.ngc" "$WORK/trace.csv" --machine linuxcnc-sim \
    --effects feed_override,servo_lag --json "$WORK/d.json" --html "$WORK/d.html"
run profile "$EX/fig1_polygons_F4000.ngc" --machine linuxcnc-sim --csv "$WORK/trace2.csv"
run calibrate "$EX/fig3_semicircle_spiral.ngc" "$WORK/trace.csv" \
    --also "$EX/fig1_polygons_F4000.ngc" "$WORK/trace2.csv" --machine linuxcnc-sim \
    --effects block_cycle_time,corner_tolerance --out "$WORK/cal.toml"
run analyze "$EX/fig1_polygons_F4000.ngc" --machine "$WORK/cal.toml"
cat >"$WORK/part.apt" <<'EOF'
PARTNO/WHEEL CHECK
UNITS/MM
FEDRAT/MMPM,3000
GOTO/0,0,0
GOTO/20,0,0
GOTO/20,20,0
FINI
EOF
run analyze "$WORK/part.apt"
for f in demo.svg a.json a.svg trace.csv c.svg d.json cal.toml demo.html c.html d.html; do
    [ -s "$WORK/$f" ] || { echo "check_wheel: $f not written"; exit 1; }
done
# bad input: one line, exit 1, no traceback
printf 'G21 G90\nG1 X1 Y1 F100\nG5 X2 Y2 I1 J1 P1 Q1\n' >"$WORK/bad.ngc"
set +e
"$NC" analyze "$WORK/bad.ngc" >/dev/null 2>"$WORK/err.txt"
rc=$?
set -e
if [ "$rc" -ne 1 ] || grep -q Traceback "$WORK/err.txt" ||
    [ "$(wc -l <"$WORK/err.txt")" -ne 1 ] || ! grep -q "bad.ngc:3: cubic spline G5" "$WORK/err.txt"; then
    cat "$WORK/err.txt"; echo "check_wheel: bad input gave exit $rc"; exit 1
fi
echo "check_wheel: the installed wheel runs every command"
