"""The ``ncperf`` command line.

Exit status: 0 success, 1 bad input (one line ``FILE:LINE: what is wrong``),
2 usage errors.
"""

from __future__ import annotations

import argparse
import os
import sys
from importlib import resources
from pathlib import Path

from core import __version__
from core.annotations import VIEWS, FileTarget
from core.errors import NcperfError, UsageError
from core.facade import Ncperf
from core.machine import DEFAULT_PRESET, load_preset, preset_names, resolve_machine
from core.output import atomic_writer
from core.report import summary, write_json
from core.toolpath import ExtractOptions

DEMO_PROGRAM = "zlevel_cavity.ngc"
DEMO_SVG = "ncperf-demo.svg"
MAX_NOTICES = 10


def demo_program() -> str:
    """Path of the bundled Z-level demo program."""
    return str(resources.files("examples") / DEMO_PROGRAM)


def _parser(nc: Ncperf) -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="ncperf",
        description="Predict where a machine tool will fall below the programmed feed, and why "
        "(Tapie, Mawussi, Anselmetti: machining strategy choice, performance viewer).",
    )
    p.add_argument("--version", action="version", version=f"ncperf {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    a = sub.add_parser("analyze", help="predicted feed reduction of a program, and why")
    a.set_defaults(run=cmd_analyze)
    a.add_argument("program", nargs="?", help="tool path file (G-code); none: the bundled demo")
    a.add_argument("--demo", action="store_true", help="run on the bundled Z-level demo program")
    a.add_argument(
        "--machine",
        metavar="PRESET|FILE",
        help=f"machine preset name or TOML file (default: {DEFAULT_PRESET})",
    )
    a.add_argument("--svg", metavar="OUT", help="write the coloured tool path as SVG")
    a.add_argument("--json", metavar="OUT", help="write junctions and elements as JSON")
    a.add_argument("--view", choices=VIEWS, default="xy", help="SVG projection (default xy)")
    a.add_argument(
        "--dialect",
        choices=("fanuc", "siemens", "linuxcnc"),
        help="G-code dialect (default: from the file)",
    )
    a.add_argument(
        "--block-delete",
        action="store_true",
        help="skip blocks starting with '/' (block-delete switch on)",
    )

    m = sub.add_parser("machines", help="list machine presets (the names --machine takes)")
    m.set_defaults(run=cmd_machines)
    pl = sub.add_parser("plugins", help="list registered plugins and the hooks they implement")
    pl.set_defaults(run=cmd_plugins)
    nc.add_commands(sub)
    return p


def _check_output(path: str | None) -> None:
    if path is None:
        return
    folder = Path(path).parent
    if str(folder) and not folder.is_dir():
        raise UsageError(f"{path}: folder {folder} does not exist")


def _print_notices(tp_notices: tuple, stream) -> None:
    for n in tp_notices[:MAX_NOTICES]:
        print(n, file=stream)
    if len(tp_notices) > MAX_NOTICES:
        print(f"... and {len(tp_notices) - MAX_NOTICES} more warnings", file=stream)


def cmd_analyze(args: argparse.Namespace, nc: Ncperf) -> int:
    demo = args.demo or args.program is None
    if args.demo and args.program:
        raise UsageError("give a program or --demo, not both")
    program = demo_program() if demo else args.program
    svg = args.svg if args.svg or not demo else DEMO_SVG
    for out in (svg, args.json):
        _check_output(out)
    machine = resolve_machine(args.machine)
    note = "" if args.machine else f" [preset {DEFAULT_PRESET}, the default; --machine to choose]"
    analysis = nc.analyze(
        program, machine, ExtractOptions(dialect=args.dialect, block_delete=args.block_delete)
    )
    _print_notices(analysis.toolpath.notices, sys.stderr)
    print(summary(analysis, machine_note=note))
    if svg:
        target = FileTarget(svg, view=args.view)
        written = nc.display(analysis.toolpath, analysis.annotations, target)
        print(f"  svg              {written}")
    if args.json:
        with atomic_writer(args.json) as fh:
            write_json(analysis, fh)
        print(f"  json             {args.json}")
    return 0


def cmd_machines(_: argparse.Namespace, nc: Ncperf) -> int:
    for name in preset_names():
        m = load_preset(name)
        default = "  (default)" if name == DEFAULT_PRESET else ""
        print(f"{name}\t{m.name}{default}")
    return 0


def cmd_plugins(_: argparse.Namespace, nc: Ncperf) -> int:
    for name, hooks in nc.plugins():
        print(f"{name}\t{', '.join(hooks)}")
    return 0


def main(argv: list[str] | None = None) -> int:
    try:
        nc = Ncperf()
    except NcperfError as exc:
        print(f"ncperf: {exc}", file=sys.stderr)
        return 2
    parser = _parser(nc)
    args = parser.parse_args(argv)
    try:
        return int(args.run(args, nc))
    except UsageError as exc:
        print(f"ncperf: {exc}", file=sys.stderr)
        return 2
    except NcperfError as exc:
        print(str(exc), file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("ncperf: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # stdout closed early (e.g. piped into head): not an error of ours.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
