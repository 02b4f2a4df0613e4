"""Machining-strategy choice (the paper's title): several programs on one machine, ranked
by predicted cycle time."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.cli.report import PER_MIN, fmt_time
from core.view.analysis import Analysis, at_feed_share, rapid_time
from core.view.zones import zone_count


@dataclass(frozen=True)
class Row:
    """One program of a comparison (lengths mm, times s, feeds mm/min)."""

    label: str
    feed_length: float
    programmed_time: float
    cycle_time: float
    share_at_90: float
    zones: int
    mean_feed: float  # NaN for a program without feed moves (printed as "-")
    worst_zone: str


def row(label: str, an: Analysis) -> Row:
    """The comparison figures of one analysed program."""
    tp, pr = an.toolpath, an.profile
    feed_time = float(pr.time[tp.is_feed].sum())
    worst = an.annotations.zones[0] if an.annotations.zones else None
    return Row(
        label=label,
        feed_length=tp.feed_length,
        programmed_time=tp.programmed_time + rapid_time(an) + float(tp.dwell.sum()),
        cycle_time=pr.cycle_time,
        share_at_90=at_feed_share(pr, 0.9),
        zones=zone_count(an.evaluation, pr),
        mean_feed=tp.feed_length / feed_time * PER_MIN if feed_time > 0 else float("nan"),
        worst_zone=(
            f"lines {worst.lines}: {worst.time_lost:.2f} s lost ({worst.cause})"
            if worst
            else "none"
        ),
    )


def ranked(rows: list[Row]) -> list[Row]:
    """Fastest predicted cycle first."""
    order = np.argsort([r.cycle_time for r in rows], kind="stable")
    return [rows[i] for i in order]


def table(rows: list[Row], machine: str) -> str:
    """The comparison as text, ranked by predicted cycle time."""
    rows = ranked(rows)
    best = rows[0].cycle_time if rows else 0.0
    head = (
        f"{'#':>2s}  {'program':28s} {'feed length':>12s} {'programmed':>12s} "
        f"{'predicted':>12s} {'vs best':>8s} {'>=90% F':>8s} {'zones':>6s} "
        f"{'mean feed':>14s}  worst zone"
    )
    out = [
        f"ncperf compare on {machine} (ranked by predicted cycle time; programmed = "
        "feed at F + rapids + dwell)",
        head,
    ]
    for k, r in enumerate(rows, start=1):
        slower = (r.cycle_time / best - 1) * 100 if best > 0 else 0.0
        name = r.label if len(r.label) <= 28 else "..." + r.label[-25:]
        mean = f"{r.mean_feed:7,.0f}" if np.isfinite(r.mean_feed) else f"{'-':>7s}"
        out.append(
            f"{k:2d}  {name:28s} {r.feed_length:9.1f} mm {fmt_time(r.programmed_time):>12s} "
            f"{fmt_time(r.cycle_time):>12s} {slower:+7.1f}% {r.share_at_90 * 100:7.1f}% "
            f"{r.zones:6d} {mean} mm/min  {r.worst_zone}"
        )
    return "\n".join(out)


def html_table(rows: list[Row]) -> tuple[tuple[str, ...], ...]:
    """The comparison as cells for the HTML viewer: the header, then the programs ranked by
    predicted cycle time (the columns of :func:`table`)."""
    rows = ranked(rows)
    best = rows[0].cycle_time if rows else 0.0
    out: list[tuple[str, ...]] = [
        (
            "#",
            "program",
            "feed length",
            "programmed",
            "predicted",
            "vs best",
            ">= 90 % F",
            "zones",
            "mean feed",
            "worst zone",
        )
    ]
    for k, r in enumerate(rows, start=1):
        slower = (r.cycle_time / best - 1) * 100 if best > 0 else 0.0
        mean = f"{r.mean_feed:,.0f} mm/min" if np.isfinite(r.mean_feed) else "-"
        out.append(
            (
                str(k),
                r.label,
                f"{r.feed_length:.1f} mm",
                fmt_time(r.programmed_time),
                fmt_time(r.cycle_time),
                f"{slower:+.1f} %",
                f"{r.share_at_90 * 100:.1f} %",
                str(r.zones),
                mean,
                r.worst_zone,
            )
        )
    return tuple(out)
