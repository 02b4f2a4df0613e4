"""A third-party plugin, as a user would write one: it implements every ncperf hook.

* A1: reads ``SampleSource`` objects (a host that is not a file).
* A2: adds an element indicator ``arc_speed``: arcs capped at sqrt(A R), the centripetal
  limit of the lowest axis acceleration (LinuxCNC applies such a cap to G2/G3).
* A3: "draws" into a ``SampleCanvas`` (a list standing for a host document).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from core import Indicator, hookimpl
from core.model.toolpath import polyline

NAME = "arc_speed"


@dataclass
class SampleSource:
    points: list
    feed: float  # mm/s


@dataclass
class SampleCanvas:
    drawn: list = field(default_factory=list)


@hookimpl
def ncperf_extract(source, options):
    if not isinstance(source, SampleSource):
        return None
    return polyline(source.points, source.feed, source="sample host")


@hookimpl
def ncperf_evaluate(toolpath, machine):
    i = np.flatnonzero(toolpath.is_arc)
    cap = np.sqrt(machine.max_acceleration.min() * toolpath.radius[i])
    return [
        Indicator(
            name=NAME,
            at="element",
            index=i,
            feed=cap,
            limit=np.zeros(i.size, dtype=np.int64),
            labels=("centripetal acceleration",),
        )
    ]


@hookimpl
def ncperf_display(toolpath, annotations, target):
    if not isinstance(target, SampleCanvas):
        return None
    target.drawn.append((toolpath.n, annotations.move_class.tolist()))
    return target


def _run_sample(args, nc):
    print(f"sample plugin: {len(nc.plugins())} plugins, echo {args.echo}")
    return 0


@hookimpl
def ncperf_add_commands(subparsers):
    p = subparsers.add_parser("sample", help="a command added by the sample plugin")
    p.add_argument("--echo", default="hi")
    p.set_defaults(run=_run_sample)


@dataclass
class SampleTrace:
    """A host that hands over a recording directly."""

    t: list
    v: list
    line: list


@hookimpl
def ncperf_read_trace(source, options):
    if not isinstance(source, SampleTrace):
        return None
    from core.model.trace import Trace

    return Trace(t=source.t, pos=None, v=source.v, line=source.line, source="sample trace")


@hookimpl
def ncperf_effects():
    """A third-party effect: a spindle-load slowdown that scales every feed by ``share``."""
    from core.engine.effects import Effect, Param

    return [
        Effect(
            name="sample_spindle_load",
            params=(Param("share", 0.5, 1.0, 1.0),),
            apply=lambda setup, p: setup.replace(feed_scale=setup.feed_scale * p["share"]),
            doc="a sample effect",
        )
    ]
