"""A3: the SVG fallback display, the paper's Figures 10 and 11 in one file.

Recognises ``.svg`` targets: a path (``str`` or ``os.PathLike``, drawn in the
top view) or a :class:`~core.view.targets.FileTarget` (its own view). The
drawing itself is in :mod:`adapters.svg.render` (imported when a drawing is made, like
the diagnosis a :class:`~core.diagnosis.diagnose.DiagnosisTarget` comes from: the adapter
costs nothing to load).
"""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING, Any, TypeGuard

from core import Annotations, ComparisonTarget, FileTarget, ToolPath, hookimpl
from core.cli.output import atomic_writer

if TYPE_CHECKING:
    from adapters.svg.render import render_comparison, render_svg, write_svg
    from core.diagnosis.diagnose import DiagnosisTarget

__all__ = ["ncperf_display", "render_comparison", "render_svg", "svg_target", "write_svg"]


def __getattr__(name: str) -> Any:
    """The drawing functions this package exports, from :mod:`adapters.svg.render`."""
    if name in ("render_comparison", "render_svg", "write_svg"):
        from adapters.svg import render

        return getattr(render, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _is_diagnosis(target: object) -> TypeGuard[DiagnosisTarget]:
    """Whether ``target`` is a DiagnosisTarget, without importing the diagnosis: one exists
    only once its module is loaded."""
    module = sys.modules.get("core.diagnosis.diagnose")
    return module is not None and isinstance(target, module.DiagnosisTarget)


def svg_target(target: object) -> tuple[str, str] | None:
    """(path, view) if ``target`` is an SVG file, else None.

    Parameters
    ----------
    target : str, os.PathLike or FileTarget
        A name ending in ``.svg`` (any case); a FileTarget brings its view.
    """
    if isinstance(target, FileTarget | ComparisonTarget) or _is_diagnosis(target):
        path, view = target.path, target.view
    elif isinstance(target, str | os.PathLike):
        path, view = target, "xy"
    else:
        return None
    name = os.fspath(path)
    if not isinstance(name, str) or not name.lower().endswith(".svg"):
        return None
    return name, view


@hookimpl
def ncperf_display(toolpath: ToolPath, annotations: Annotations, target: object) -> str | None:
    """Write the annotations to an ``.svg`` target; None for any other target."""
    found = svg_target(target)
    if found is None:
        return None
    path, view = found
    from adapters.svg.render import render_comparison, render_diagnosis, write_svg

    if isinstance(target, ComparisonTarget) or _is_diagnosis(target):
        data = (
            render_comparison(target.panels, view, target.colour)
            if isinstance(target, ComparisonTarget)
            else render_diagnosis(toolpath, annotations, target.diagnosis, view)
        )
        with atomic_writer(path, binary=True) as fh:
            fh.write(data)
        return path
    colour = target.colour if isinstance(target, FileTarget) else "speed"
    return write_svg(toolpath, annotations, path, view, colour)
