"""Which real programs ncperf reads: every file of a folder through ``ncperf analyze``.

Not a test: ``python benchmarks/corpus_read.py FOLDER [--manifest manifest.json] [--lcnc]``.
The corpus is kept out of the repository (real programs from public repositories, under
their own licences). Prints one row per file -- read, or refused with ncperf's one-line
reason -- and a table per CAM system / dialect when a manifest (a JSON list of objects with
``local_path``, ``system`` and ``dialect``) names them. A traceback or a hang is reported as
a crash. ``--lcnc`` also runs LinuxCNC's own interpreter on each file through
``benchmarks/lcnc_oracle.py`` (needs LinuxCNC) and says whether both read the same path,
line by line, rapids included.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: LinuxCNC's interpreter in machine coordinates (work offsets applied) with the trace
#: machine's startup code; ../shared/tools/linuxcnc/lcnc_path_check.py is the same check
#: without offsets (a change of work offset looks like a jump there).
CHECK = ROOT / "benchmarks" / "lcnc_oracle.py"
SKIP = {".md", ".json", ".txt"}


def ncperf() -> str:
    exe = shutil.which("ncperf")
    if exe is None:
        raise SystemExit("corpus_read.py: ncperf is not installed in this environment")
    return exe


def read(path: Path, timeout: float) -> tuple[str, str, float]:
    """(status, one-line reason, seconds): status read, refused or crash."""
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        try:
            done = subprocess.run(
                [ncperf(), "analyze", str(path), "--json", os.path.join(tmp, "out.json")],
                capture_output=True,
                text=True,
                timeout=timeout,
            )
        except subprocess.TimeoutExpired:
            return "crash", f"no answer within {timeout:g} s", timeout
        wall = time.perf_counter() - t0
    err = done.stderr.strip().splitlines()
    if "Traceback" in done.stderr:
        return "crash", err[-1][:160] if err else "traceback", wall
    if done.returncode == 0:
        return "read", "", wall
    reason = err[-1] if err else f"exit {done.returncode}"
    return "refused", reason.replace(str(path), path.name)[:200], wall


def lcnc(path: Path) -> str:
    done = subprocess.run(
        ["/usr/bin/python3", str(CHECK), ncperf(), str(path)],
        capture_output=True,
        text=True,
        timeout=900,
    )
    lines = [ln for ln in done.stdout.splitlines() if ln.startswith(path.name + ":")]
    return lines[-1][len(path.name) + 2 :][:160] if lines else "(no answer)"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path)
    ap.add_argument("--manifest", type=Path, help="JSON list: local_path, system, dialect")
    ap.add_argument("--lcnc", action="store_true", help="cross-check with LinuxCNC's reading")
    ap.add_argument("--timeout", type=float, default=300.0)
    args = ap.parse_args()
    meta: dict[str, dict] = {}
    if args.manifest:
        for row in json.loads(args.manifest.read_text()):
            meta[str((args.manifest.parent / row["local_path"]).resolve())] = row
    files = sorted(
        p for p in args.folder.rglob("*") if p.is_file() and p.suffix.lower() not in SKIP
    )
    print(f"ncperf on {len(files)} files of {args.folder}, {datetime.date.today()}\n")
    print(
        "| file | system | dialect | result | reason | s |" + (" LinuxCNC |" if args.lcnc else "")
    )
    print("|---|---|---|---|---|---|" + ("---|" if args.lcnc else ""))
    per: dict[tuple[str, str], Counter] = defaultdict(Counter)
    total: Counter = Counter()
    for f in files:
        m = meta.get(str(f.resolve()), {})
        system, dialect = m.get("system", "?"), m.get("dialect", "?")
        status, reason, wall = read(f, args.timeout)
        extra = f" {lcnc(f)} |" if args.lcnc else ""
        print(
            f"| {f.relative_to(args.folder)} | {system} | {dialect} | {status} | {reason} | "
            f"{wall:.2f} |{extra}",
            flush=True,
        )
        per[(system, dialect)][status] += 1
        total[status] += 1
    print("\n| CAM system / origin | dialect | read | refused | crash |")
    print("|---|---|---|---|---|")
    for (system, dialect), c in sorted(per.items()):
        print(f"| {system} | {dialect} | {c['read']} | {c['refused']} | {c['crash']} |")
    print(
        f"\nread {total['read']} of {len(files)}, refused {total['refused']}, "
        f"crashed {total['crash']}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
