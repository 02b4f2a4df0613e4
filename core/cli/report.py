"""Reports of an analysis: the terminal summary and the JSON file.

Units at this edge: feeds in mm/min (as F words), lengths in mm, times in s.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterator
from typing import IO

import numpy as np

from core.engine.indicators import REDUCTION_LABELS, reduction_class
from core.engine.profile import Samples
from core.model.pieces import pieces
from core.model.text import printable_tree
from core.model.toolpath import KIND_LABELS
from core.view.analysis import Analysis, totals

PER_MIN = 60.0


def fmt_time(seconds: float) -> str:
    """1 h 02 min 03.4 s / 2 min 03.4 s / 3.41 s."""
    if not math.isfinite(seconds):
        return "n/a"
    if seconds < 60:
        return f"{seconds:.2f} s"
    m, s = divmod(seconds, 60.0)
    if m < 60:
        return f"{int(m)} min {s:04.1f} s"
    h, m = divmod(m, 60.0)
    return f"{int(h)} h {int(m):02d} min {s:04.1f} s"


def class_table(an: Analysis) -> list[tuple[str, list[int]]]:
    """Per indicator: how many reported junctions fall in each reduction class."""
    ev = an.evaluation
    cls = reduction_class(ev.junction_reduction)
    rows = []
    for k, name in enumerate(ev.indicator_names):
        sel = ev.junction_indicator == k
        if sel.any():
            rows.append((name, np.bincount(cls[sel], minlength=6).tolist()))
    return rows


def summary(an: Analysis, *, machine_note: str = "") -> str:
    """The terminal summary of ``ncperf analyze``."""
    tp, ev, ann = an.toolpath, an.evaluation, an.annotations
    t = totals(an)
    m = ev.machine
    lines = [f"ncperf analyze: {tp.source}"]
    lines.append(f"  machine          {m.name}{machine_note}")
    lines.append(
        f"  moves            {t['moves']:,} ({t['feed_moves']:,} feed, of which {t['arcs']:,} "
        f"arcs; {t['rapids']:,} rapids) in {t['operations']} operation"
        f"{'s' if t['operations'] != 1 else ''}"
    )
    lines.append(f"  feed length      {t['feed_length_mm']:,.1f} mm")
    if t["rotary_moves"] or t["rotary_only_moves"]:
        lines.append(
            f"  rotary axes      turn on {t['rotary_moves']:,} moves with X/Y/Z and in "
            f"{t['rotary_only_moves']:,} moves of their own "
            f"({fmt_time(t['rotary_only_time_s'])} at rest on the path)"
        )
    lines.append(
        f"  programmed time  {fmt_time(t['programmed_time_s'])} (feed moves at F; rapids "
        f"{fmt_time(t['rapid_time_s'])} at max feed; dwell {fmt_time(t['dwell_time_s'])})"
    )
    prog = t["programmed_time_s"]
    extra = (t["paper_model_time_s"] / prog - 1) * 100 if prog else 0.0
    lines.append(
        f"  paper-model time {fmt_time(t['paper_model_time_s'])} (+{extra:.1f} %: short blocks "
        "capped by model 3; discontinuities are points and cost no time)"
    )
    base = prog + t["rapid_time_s"] + t["dwell_time_s"]
    extra = (t["predicted_cycle_time_s"] / base - 1) * 100 if base else 0.0
    lines.append(
        f"  predicted cycle  {fmt_time(t['predicted_cycle_time_s'])} (+{extra:.1f} % on programmed"
        f" + rapids + dwell: braking and accelerating around every slow point, look-ahead over"
        f" the whole path; {t['share_at_90_percent'] * 100:.1f} % of the feed length at 90 % of F"
        " or more)"
    )
    lines.append(
        f"  below L          {t['below_L_share'] * 100:.1f} % of the feed length is in "
        f"{t['blocks_below_L']:,} blocks shorter than L = F t_int "
        f"(t_int {m.interpolation_time * 1000:g} ms)"
    )
    n_j = int(ev.junction.size)
    lines.append(f"  discontinuities  {n_j:,} junctions reported, by predicted feed reduction:")
    rows = class_table(an)
    head = "".join(f"{lab:>9s}" for lab in REDUCTION_LABELS)
    lines.append(f"    {'':14s}{head}")
    for name, counts in rows:
        lines.append(f"    {name:14s}" + "".join(f"{c:9,d}" for c in counts))
    capped = ev.element_indicator >= 0
    if capped.any():
        for k, name in enumerate(ev.indicator_names):
            nk = int(np.count_nonzero(ev.element_indicator == k))
            if nk:
                lines.append(f"  blocks capped    {nk:,} by {name}")
    lines.append(
        "  worst zones (runs of blocks the profile keeps below 90 % of F around slow points,"
    )
    lines.append("  ranked by the time they lose against length / F):")
    if not ann.zones:
        lines.append("    none: no block or junction is predicted 10 % or more below F")
    else:
        lines.append(
            f"    {'#':>2s}  {'lines':13s} {'length':>9s} {'slow pts':>8s} {'worst':>6s} "
            f"{'min feed':>22s} {'lost':>9s}  cause"
        )
        for z in ann.zones:
            feed = f"{z.min_feed * PER_MIN:,.0f} of F{z.programmed_feed * PER_MIN:,.0f}"
            lines.append(
                f"    {z.rank:2d}  {z.lines:13s} {z.length:6.1f} mm "
                f"{z.discontinuities + z.capped_blocks:8d} {-z.worst_reduction * 100:5.0f}% "
                f"{feed:>15s} mm/min {z.time_lost:7.3f} s  {z.cause}"
            )
    return "\n".join(lines)


# ------------------------------------------------------------------------------ JSON
#: Rows of the JSON's per-move arrays made into Python objects at a time: a million-move
#: program's eleven columns as lists were most of ``analyze --json``'s peak (1M moves: 917 MB).
JSON_ROWS = 1 << 15


def _records(
    keys: tuple[str, ...], n: int, columns: Callable[[slice], list[list]]
) -> Iterator[str]:
    """The rows ``0..n`` as JSON objects, their columns made piece by piece."""
    for p in pieces(n, JSON_ROWS):
        for row in zip(*columns(p), strict=True):
            yield json.dumps(dict(zip(keys, row, strict=True)), allow_nan=False)


def _num(a: np.ndarray, digits: int) -> list:
    """Rounded floats for JSON; NaN and inf become null."""
    a = np.round(np.asarray(a, dtype=np.float64), digits)
    out = a.tolist()
    bad = ~np.isfinite(a)
    if bad.any():
        for i in np.flatnonzero(bad):
            out[i] = None
    return out


def write_json(an: Analysis, fh: IO[str]) -> None:
    """The JSON report (streamed: a million junctions do not build a million dicts at once)."""
    tp, ev = an.toolpath, an.evaluation
    t = totals(an)
    head = {
        "program": tp.source,
        "machine": ev.machine.name,
        "machine_source": ev.machine.source,
        "units_in_file": tp.units,
        "moves": t["moves"],
        "feed_length_mm": round(t["feed_length_mm"], 4),
        "programmed_time_s": round(t["programmed_time_s"], 4),
        "paper_model_time_s": round(t["paper_model_time_s"], 4),
        "predicted_cycle_time_s": round(t["predicted_cycle_time_s"], 4),
        "share_at_90_percent": round(t["share_at_90_percent"], 6),
        "rapid_time_s": round(t["rapid_time_s"], 4),
        "dwell_time_s": round(t["dwell_time_s"], 4),
        "rotary_only_time_s": round(t["rotary_only_time_s"], 4),
        "below_L_share": round(t["below_L_share"], 6),
        "indicators": list(ev.indicator_names),
        "notices": [str(n) for n in tp.notices],
        "zones": [
            {
                "rank": z.rank,
                "line_start": z.line_first,
                "line_end": z.line_last,
                "file": z.file,
                "called_by": z.origin,
                "length_mm": round(z.length, 4),
                "discontinuities": z.discontinuities,
                "capped_blocks": z.capped_blocks,
                "worst_reduction": round(z.worst_reduction, 6),
                "min_feed": round(z.min_feed * PER_MIN, 3),
                "cause": z.cause,
                "time_lost_s": round(z.time_lost, 4),
            }
            for z in an.annotations.zones
        ],
    }
    text = json.dumps(printable_tree(head), indent=1, allow_nan=False)
    fh.write(text[:-2] + ",\n")  # reopen the object for the two big arrays

    j = ev.junction
    names = np.array(ev.indicator_names + ("",), dtype=object)
    labels = np.array(ev.labels, dtype=object)

    def jcols(p: slice) -> list[list]:
        jp = j[p]
        return [
            tp.line[jp].tolist(),
            tp.line[jp + 1].tolist(),
            _num(ev.junction_programmed[p] * PER_MIN, 3),
            _num(ev.junction_feed[p] * PER_MIN, 3),
            _num(ev.junction_reduction[p], 6),
            names[ev.junction_indicator[p]].tolist(),
            labels[ev.junction_limit[p]].tolist(),
        ]

    fh.write(' "junctions": [')
    _write_rows(
        fh,
        _records(
            (
                "line",
                "next_line",
                "programmed_feed",
                "predicted_feed",
                "reduction",
                "indicator",
                "limit",
            ),
            j.size,
            jcols,
        ),
    )
    fh.write("],\n")

    kinds = np.array(KIND_LABELS, dtype=object)
    pr = an.profile

    def ecols(p: slice) -> list[list]:
        el_lim = np.where(ev.element_limit[p] >= 0, ev.element_limit[p], 0)
        el_ind = ev.element_indicator[p]
        el_cause = np.full(el_ind.size, None, dtype=object)
        capped = el_ind >= 0
        el_cause[capped] = (names[el_ind] + ": " + labels[el_lim])[capped]
        return [
            tp.line[p].tolist(),
            kinds[tp.kind[p]].tolist(),
            _num(tp.length[p], 5),
            _num(tp.feed[p] * PER_MIN, 3),
            _num(ev.element_feed[p] * PER_MIN, 3),
            _num(ev.min_length[p], 5),
            el_cause.tolist(),
            _num(pr.v_entry[p] * PER_MIN, 3),
            _num(pr.v_peak[p] * PER_MIN, 3),
            _num(pr.v_exit[p] * PER_MIN, 3),
            _num(pr.time[p], 6),
        ]

    fh.write(' "elements": [')
    _write_rows(
        fh,
        _records(
            (
                "line",
                "kind",
                "length_mm",
                "programmed_feed",
                "predicted_feed",
                "min_length_mm",
                "limited_by",
                "entry_feed",
                "peak_feed",
                "exit_feed",
                "time_s",
            ),
            tp.n,
            ecols,
        ),
    )
    fh.write("]\n}\n")


def _write_rows(fh: IO[str], rows: Iterator[str]) -> None:
    first = True
    for r in rows:
        fh.write(("\n  " if first else ",\n  ") + r)
        first = False


def write_samples(samples: Samples, fh: IO[str], *, header: bool = True) -> None:
    """A sampled profile as CSV: t,x,y,z,v,line (s, mm, mm/s, 1-based line), the columns
    of a measured trace (``header=False``: the rows only, for the pieces after the first)."""
    if header:
        fh.write("t,x,y,z,v,line\n")
    cols = np.column_stack(
        [samples.t, samples.x, samples.y, samples.z, samples.v, samples.line.astype(np.float64)]
    )
    np.savetxt(fh, cols, fmt=("%.6f", "%.6f", "%.6f", "%.6f", "%.6f", "%d"), delimiter=",")
