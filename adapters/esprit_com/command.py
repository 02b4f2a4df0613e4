"""``ncperf esprit``: analyse an ESPRIT document and draw the result into it.

Without ``--emulate`` it attaches to the running ESPRIT (Windows, pythonnet, COM); with
``--emulate PROGRAM`` it fills the headless emulation from a G-code or CL file and runs the same
flow: extract (A1), evaluate (A2), draw into the document (A3), print the summary.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, cast

from core.model.errors import UsageError
from core.model.preset_files import DEFAULT_PRESET

# Adding the command to the parser imports no numpy (``ncperf --help``); running it does.
if TYPE_CHECKING:
    from adapters.esprit_com.draw import Drawing
    from adapters.esprit_com.extract import EspritSource
    from core.facade import Ncperf
    from core.model.machine import Machine
    from core.view.analysis import Analysis

MAX_NOTICES = 10


def add_command(subparsers: argparse._SubParsersAction) -> None:
    """Add ``ncperf esprit`` to the CLI."""
    p = subparsers.add_parser(
        "esprit",
        help="analyse the operations of the running ESPRIT (or of the headless emulation) and "
        "draw the predicted feed reduction into the document",
    )
    p.add_argument(
        "--all",
        action="store_true",
        help="read every operation (default: the selected ones, or all if none is selected)",
    )
    p.add_argument(
        "--machine",
        metavar="PRESET|FILE",
        help=f"machine preset name or TOML file (default: {DEFAULT_PRESET})",
    )
    p.add_argument(
        "--emulate",
        metavar="PROGRAM",
        help="no ESPRIT: fill the emulated document from a G-code or CL file and run headless",
    )
    p.add_argument(
        "--python-twin",
        action="store_true",
        help="with --emulate: the Python twin instead of the .NET emulation",
    )
    p.add_argument(
        "--svg", metavar="OUT", help="with --emulate: draw what was drawn into the document as SVG"
    )
    p.add_argument(
        "--dialect",
        choices=("fanuc", "siemens", "linuxcnc"),
        help="with --emulate: G-code dialect (default: from the file)",
    )
    p.set_defaults(run=run_command)


def analyze_and_draw(
    nc: Ncperf, source: EspritSource, machine: Machine
) -> tuple[Analysis, Drawing]:
    """A1 -> A2 -> A3 on one ESPRIT document: the paper's Figure 5 inside ESPRIT."""
    from adapters.esprit_com.draw import Drawing

    analysis = nc.analyze(source, machine)
    # Ncperf.display returns what the claiming ncperf_display hook returned (typed object);
    # for an EspritSource that is this adapter's Drawing.
    drawing = cast(Drawing, nc.display(analysis.toolpath, analysis.annotations, source))
    return analysis, drawing


def run_command(args: argparse.Namespace, nc: Ncperf) -> int:
    from adapters.esprit_com.clr_host import DotnetUnavailable, attach_running_esprit
    from adapters.esprit_com.extract import EspritSource
    from adapters.esprit_com.object_model import LAYER_NAME
    from core.cli.report import summary
    from core.model.machine import resolve_machine
    from core.model.toolpath import ExtractOptions

    if (args.python_twin or args.svg or args.dialect) and not args.emulate:
        raise UsageError("--python-twin, --svg and --dialect need --emulate PROGRAM")
    if args.svg:
        folder = Path(args.svg).parent
        if str(folder) and not folder.is_dir():
            raise UsageError(f"{args.svg}: folder {folder} does not exist")
    machine = resolve_machine(args.machine)
    note = "" if args.machine else f" [preset {DEFAULT_PRESET}, the default; --machine to choose]"
    scope = "all" if args.all else "auto"
    if args.emulate:
        from adapters.esprit_com.emulation import backend, fill_document

        try:
            be = backend("python-twin" if args.python_twin else "dotnet")
        except DotnetUnavailable as exc:
            raise UsageError(
                f"the .NET ESPRIT emulation is unavailable: {exc.reason} "
                "(--python-twin runs the Python twin)"
            ) from None
        program = nc.extract(args.emulate, ExtractOptions(dialect=args.dialect))
        app = fill_document(program, be)
        host = be.host(app)
    else:
        host = attach_running_esprit()
    analysis, drawing = analyze_and_draw(nc, EspritSource(host, scope), machine)
    notices = analysis.toolpath.notices
    for n in notices[:MAX_NOTICES]:
        print(n, file=sys.stderr)
    if len(notices) > MAX_NOTICES:
        print(f"... and {len(notices) - MAX_NOTICES} more warnings", file=sys.stderr)
    print(summary(analysis, machine_note=note))
    print(f"  esprit           {drawing}")
    if args.svg:
        from adapters.esprit_com.emulation import recording, write_recording_svg

        rec = recording(app, be).on_layer(LAYER_NAME)
        write_recording_svg(rec, args.svg, title=f"{drawing.document}: {LAYER_NAME}")
        print(f"  svg              {args.svg}")
    return 0
