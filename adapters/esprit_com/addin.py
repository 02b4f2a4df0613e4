"""The add-in entry point the ESPRIT extension shim (``csharp/NcperfShim.cs``) calls.

The shim runs inside ESPRIT, starts Python through pythonnet's embedding API and calls
:func:`run` with ESPRIT's ``Application`` object; the analysis is drawn into the active
document and the summary comes back as text for ESPRIT's event window.
"""

from __future__ import annotations

import os

from adapters.esprit_com.clr_host import as_host
from adapters.esprit_com.command import analyze_and_draw
from adapters.esprit_com.extract import EspritSource
from adapters.esprit_com.object_model import ComObject
from core.cli.report import summary
from core.facade import Ncperf
from core.model.machine import resolve_machine

#: Machine preset name or TOML file for the add-in (it has no command line).
MACHINE_ENV = "NCPERF_MACHINE"


def run(app: ComObject, machine: str | None = None, scope: str = "auto") -> str:
    """Analyse the selected operations (or all: ``scope``) of ESPRIT's active document and
    draw the predicted feed reduction on the layer "ncperf performance".

    Parameters
    ----------
    app : ESPRIT Application
        As the shim receives it (a COM object; the emulation's objects work too).
    machine : str, optional
        Preset name or TOML file; default ``$NCPERF_MACHINE``, else the default preset.
    scope : {"auto", "selected", "all"}

    Returns
    -------
    str
        The warnings and the summary, for the event window.

    Raises
    ------
    NcperfError
        With a one-line message (the shim shows it); nothing is left half-drawn.
    """
    nc = Ncperf()
    m = resolve_machine(machine or os.environ.get(MACHINE_ENV) or None)
    analysis, drawing = analyze_and_draw(nc, EspritSource(as_host(app), scope), m)
    lines = [str(n) for n in analysis.toolpath.notices]
    lines.append(summary(analysis))
    lines.append(f"  esprit           {drawing}")
    return "\n".join(lines)
