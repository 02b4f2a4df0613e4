"""exact_stop: the controller stops at every block end.

A Siemens 840D runs exact stop (G60) unless the program says G64 -- its reset value -- and a
LinuxCNC machine whose startup code or program says G61 does the same: the feed falls to 0
between every two blocks. No parameters: the prediction runs every block from rest to rest.
(The machine file says it with ``default_path_mode = "exact_stop"``, for programs that set no
path mode.)
"""

from __future__ import annotations

from core import hookimpl
from core.engine.effects import Effect

EFFECT = Effect(
    name="exact_stop",
    params=(),
    apply=lambda setup, p: setup.replace(exact_stop=True),
    doc="every block ends at rest (exact stop, G60/G61)",
)


@hookimpl
def ncperf_effects() -> list[Effect]:
    return [EFFECT]
