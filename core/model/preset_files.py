"""The shipped machine presets as files: their names and texts, read without building a
machine.

This module imports no numpy, no TOML parser and not :mod:`importlib.resources` (together
about 0.2 s on a small machine): the command line's parser and ``ncperf machines`` use it
(issue 13). The presets ship as ordinary files next to this module (package data of
``core.model``, see pyproject.toml), so a path is all it takes to read them.
"""

from __future__ import annotations

import os

DEFAULT_PRESET = "siemens-840d"

#: The folder of the shipped ``NAME.toml`` files.
PRESET_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "presets")


def preset_names() -> list[str]:
    """Names of the shipped presets (what ``--machine`` takes)."""
    return sorted(f[: -len(".toml")] for f in os.listdir(PRESET_DIR) if f.endswith(".toml"))


def preset_text(name: str) -> str:
    """The TOML text of a shipped preset (``name`` from :func:`preset_names`)."""
    with open(os.path.join(PRESET_DIR, f"{name}.toml"), encoding="utf-8") as fh:
        return fh.read()


def preset_title(name: str) -> str:
    """The ``name`` a shipped preset gives its machine."""
    import tomllib

    return str(tomllib.loads(preset_text(name))["name"])
