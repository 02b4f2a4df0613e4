"""A3: the interactive HTML viewer, one self-contained file (``--html OUT.html``).

Recognises ``.html`` / ``.htm`` targets: a path, a :class:`~core.view.targets.FileTarget`,
a :class:`~core.view.targets.ComparisonTarget`, a
:class:`~core.diagnosis.diagnose.DiagnosisTarget`, or -- with the feed profile, the limits
and the program text that the page's speed plot and hover show -- a
:class:`~core.view.targets.HtmlTarget`. The page itself is built by :mod:`adapters.html.page`
(imported when a page is written: the adapter costs nothing to load) and drawn in the browser
by ``viewer.js`` with WebGL (a 2-D canvas where WebGL is missing).
"""

from __future__ import annotations

import os

from core import Annotations, ToolPath, hookimpl

__all__ = ["html_target", "ncperf_display", "write_html"]

SUFFIXES = (".html", ".htm")


def html_target(target: object) -> tuple[str, str] | None:
    """(path, view) if ``target`` is an HTML file, else None.

    Parameters
    ----------
    target : str, os.PathLike or a target with ``path`` and ``view``
        A name ending in ``.html`` or ``.htm`` (any case).
    """
    if isinstance(target, str | os.PathLike):
        path, view = target, "xy"
    elif hasattr(target, "path") and hasattr(target, "view"):
        path, view = target.path, target.view
    else:
        return None
    name = os.fspath(path)
    if not isinstance(name, str) or not name.lower().endswith(SUFFIXES):
        return None
    return name, str(view)


def write_html(toolpath: ToolPath, annotations: Annotations, target: object) -> str:
    """Build the page for ``target`` and write it atomically; returns the path written.

    Raises ValueError if ``target`` is not an HTML target.
    """
    from adapters.html.page import build
    from core.cli.output import atomic_writer

    found = html_target(target)
    if found is None:
        raise ValueError(f"{target!r} is not an .html target")
    path, view = found
    data = build(toolpath, annotations, target, view)
    with atomic_writer(path, binary=True) as fh:
        fh.write(data)
    return path


@hookimpl
def ncperf_display(toolpath: ToolPath, annotations: Annotations, target: object) -> str | None:
    """Write the interactive viewer to an ``.html`` target; None for any other target."""
    if html_target(target) is None:
        return None
    return write_html(toolpath, annotations, target)
