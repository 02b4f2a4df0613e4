"""Trace readers: CSV with a header, and MTConnect SHDR text.

* CSV (``.csv``): a header naming the columns, ``t`` (s) and ``x,y,z`` (positions) and/or
  ``v`` (path feed, units/s), optionally ``line`` (1-based program line); other columns are
  ignored. The LinuxCNC traces of the shared harness are this format. Positions are taken as
  the controller's setpoint unless ``--trace-kind actual``.
* MTConnect SHDR (``timestamp|key|value`` lines, event-based): ``Feed_Rate`` (mm/s, the
  actual path feed), ``Block_Number`` (the program line), positions from ``Xact``/``Yact``/
  ``Zact`` (or ``Xabs``...) when recorded; every value is held until it changes, so each
  event time becomes a sample. Taken as actual values.

Both give one-line errors naming file and line for what they cannot read faithfully:
missing columns, malformed numbers, NaN, time going backwards.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from core import InputError, Notice, hookimpl
from core.model.inputs import read_input, read_input_text
from core.model.limits import FEED_RANGE, MAX_COORD

if TYPE_CHECKING:  # (the readers import it when they run: analyze never does)
    from core.model.trace import Trace, TraceOptions

INCH = 25.4
#: A pause longer than this many median sample periods is a gap in the recording.
GAP_PERIODS = 20

_SHDR = re.compile(r"^\s*\d{4}-\d\d-\d\dT[0-9:.]+Z?\|[^|]*\|")
_POS_KEYS = (("Xact", "Yact", "Zact"), ("Xabs", "Yabs", "Zabs"), ("Xpos", "Ypos", "Zpos"))
_CHANNEL = {"Feed_Rate": "v", "Block_Number": "line"}
#: Largest magnitude of each recorded value (s, mm or inch, units/s, line number): beyond
#: these a number is a corrupt record, and squaring it later would overflow.
TRACE_RANGE = {
    "t": 1e9,
    "x": MAX_COORD,
    "y": MAX_COORD,
    "z": MAX_COORD,
    "v": FEED_RANGE[1],
    "line": 2.0**53,
}


def _path(source: object) -> Path | None:
    return Path(source) if isinstance(source, str | os.PathLike) else None


def _scale(options: TraceOptions, name: str) -> tuple[float, str]:
    units = options.units or "mm"
    if units not in ("mm", "inch"):
        raise InputError(f"unknown trace units '{units}' (mm or inch)", source=name)
    return (INCH if units == "inch" else 1.0), units


def _time_checks(t: np.ndarray, name: str, first_line: int) -> list[Notice]:
    """Time must increase; long pauses in the recording are reported."""
    dt = np.diff(t)
    back = np.flatnonzero(dt <= 0)
    if back.size:
        k = int(back[0])
        raise InputError(
            f"time does not increase ({t[k]:g} s, then {t[k + 1]:g} s)",
            source=name,
            line=first_line + k + 1,
        )
    notes = []
    if dt.size:
        period = float(np.median(dt))
        gaps = np.flatnonzero(dt > GAP_PERIODS * period)
        if gaps.size:
            k = int(gaps[np.argmax(dt[gaps])])
            notes.append(
                Notice(
                    name,
                    first_line + k,
                    f"the recording pauses {gaps.size} times (longest {dt[k]:.3g} s; samples "
                    f"every {period:.3g} s elsewhere): nothing is known there",
                    int(gaps.size),
                )
            )
    return notes


# ---------------------------------------------------------------------------- CSV
def read_csv_trace(path: Path, options: TraceOptions) -> Trace:
    """A CSV trace with a header (see the module docstring)."""
    from core.model.trace import Trace

    name = str(path)
    header, _, body = read_input_text(path, what="a trace").partition("\n")
    cols = [c.strip().lower() for c in header.strip().split(",")]
    if not header.strip():
        raise InputError("empty trace file", source=name)
    if "t" not in cols:
        raise InputError(
            f"no 't' column in the header (columns: {', '.join(cols)})", source=name, line=1
        )
    has_pos = all(c in cols for c in ("x", "y", "z"))
    if not has_pos and any(c in cols for c in ("x", "y", "z")):
        raise InputError("positions need all of x, y and z", source=name, line=1)
    has_v = "v" in cols
    if not (has_pos or has_v):
        raise InputError("the trace needs x,y,z positions or a v column", source=name, line=1)
    if not body:
        raise InputError("no samples after the header", source=name, line=1)
    want = ["t"] + (["x", "y", "z"] if has_pos else []) + (["v"] if has_v else [])
    if "line" in cols:
        want.append("line")
    idx = [cols.index(c) for c in want]
    data = _parse_fast(body, idx, len(cols))
    lines = _Lines(body)
    if data is None:
        data = _parse_rows(lines.all, idx, len(cols), name)
    col = {c: data[:, k] for k, c in enumerate(want)}
    for c, values in col.items():
        bad = np.flatnonzero(np.abs(values) > TRACE_RANGE[c])
        if bad.size:
            k = int(bad[0])
            raise InputError(
                f"{c} beyond {TRACE_RANGE[c]:g}: not a value a machine records",
                source=name,
                line=k + 2,
                text=lines[k],
            )
    scale, units = _scale(options, name)
    notes = _time_checks(col["t"], name, 2)
    t = col["t"]
    line = None
    if "line" in col:
        line = col["line"].astype(np.int64)
        if np.any(line != col["line"]) or np.any(line < 0):
            k = int(np.flatnonzero((line != col["line"]) | (line < 0))[0])
            raise InputError(
                "line must be a non-negative whole number", source=name, line=k + 2, text=lines[k]
            )
    return Trace(
        t=t - t[0],
        pos=np.column_stack([col["x"], col["y"], col["z"]]) * scale if has_pos else None,
        v=col["v"] * scale if has_v else None,
        line=line,
        source=name,
        kind=options.kind or "setpoint",
        units=units,
        notices=tuple(notes),
    )


class _Lines:
    """The lines of a trace's body, split when a message first needs one (344k lines: 0.07 s
    a diagnosis need not spend)."""

    def __init__(self, body: str) -> None:
        self._body = body
        self._all: list[str] | None = None

    @property
    def all(self) -> list[str]:
        if self._all is None:
            self._all = self._body.splitlines()
        return self._all

    def __getitem__(self, k: int) -> str:
        return self.all[k]


def _parse_fast(body: str, idx: list[int], ncols: int) -> np.ndarray | None:
    """The wanted columns ``idx`` of every row by the compiled reader (core.model.jit:
    where the kernels are in use), the same numbers as :func:`_parse_rows`; None where the
    kernels are not in use or a row is not plain decimals (then :func:`_parse_rows`)."""
    from core.model.jit import compiled

    kernels = compiled()
    if kernels is None:
        return None
    to = np.full(ncols, -1, dtype=np.int64)
    to[idx] = np.arange(len(idx))
    out, bad = kernels.parse_rows(np.frombuffer(body.encode("utf-8"), dtype=np.uint8), ncols, to)
    return out if bad < 0 else None


def _parse_rows(lines: list[str], idx: list[int], ncols: int, name: str) -> np.ndarray:
    """Numbers of the wanted columns, with the file line of any bad row."""
    try:
        arr = np.loadtxt(lines, delimiter=",", usecols=idx, ndmin=2, dtype=np.float64)
        good = np.isfinite(arr).all(axis=1)
        if good.all() and arr.shape[0] == len(lines):
            return arr
    except ValueError:
        pass
    # Slow path: find the first bad row and say what is wrong with it.
    out = np.empty((len(lines), len(idx)))
    for k, text in enumerate(lines):
        parts = text.split(",")
        if len(parts) != ncols:
            raise InputError(
                f"{len(parts)} columns, the header has {ncols}", source=name, line=k + 2, text=text
            )
        for j, c in enumerate(idx):
            try:
                val = float(parts[c])
            except ValueError:
                raise InputError(
                    f"'{parts[c].strip()}' is not a number", source=name, line=k + 2, text=text
                ) from None
            if not np.isfinite(val):
                raise InputError(
                    f"'{parts[c].strip()}' (NaN or infinite) in a sample",
                    source=name,
                    line=k + 2,
                    text=text,
                )
            out[k, j] = val
    return out


# ---------------------------------------------------------------------------- SHDR
def _seconds(stamp: str) -> float:
    """Seconds since the epoch of an ISO timestamp with any number of fraction digits."""
    stamp = stamp.strip().rstrip("Z")
    main, dot, frac = stamp.partition(".")
    if dot and not (frac.isascii() and frac.isdigit()):
        raise ValueError(f"fraction of a second '{frac}' is not digits")
    from datetime import UTC, datetime

    base = datetime.strptime(main, "%Y-%m-%dT%H:%M:%S").replace(tzinfo=UTC)
    return base.timestamp() + (float("0." + frac) if frac else 0.0)


def read_shdr_trace(path: Path, options: TraceOptions) -> Trace:
    """An MTConnect SHDR recording (see the module docstring)."""
    from core.model.trace import Trace

    name = str(path)
    text = read_input_text(path, what="a trace")
    scale, units = _scale(options, name)
    events: dict[str, list[tuple[float, str, int]]] = {}
    first = None
    last_t = -np.inf
    for k, raw in enumerate(text.splitlines(), start=1):
        if not raw.strip():
            continue
        parts = raw.strip().split("|")
        if len(parts) < 3 or len(parts) % 2 == 0:
            raise InputError("not a 'timestamp|key|value' line", source=name, line=k, text=raw)
        try:
            t = _seconds(parts[0])
        except ValueError:
            raise InputError(f"bad timestamp '{parts[0]}'", source=name, line=k, text=raw) from None
        if t < last_t:
            raise InputError("time goes backwards", source=name, line=k, text=raw)
        last_t = t
        first = t if first is None else first
        for key, value in zip(parts[1::2], parts[2::2], strict=True):
            events.setdefault(key, []).append((t - first, value, k))
    partial = next(
        (p for p in _POS_KEYS if any(k in events for k in p) and not all(k in events for k in p)),
        None,
    )
    if partial:
        raise InputError(f"positions need all of {', '.join(partial)}", source=name)
    if "Feed_Rate" not in events and not any(p[0] in events for p in _POS_KEYS):
        raise InputError(
            "no Feed_Rate and no positions (Xact/Yact/Zact) in the recording", source=name
        )

    def numbers(key: str) -> tuple[np.ndarray, np.ndarray]:
        ts, vs = [], []
        for t, value, k in events.get(key, []):
            if value.strip().upper() == "UNAVAILABLE":
                v = np.nan
            else:
                try:
                    v = float(value)
                except ValueError:
                    raise InputError(
                        f"{key} '{value}' is not a number", source=name, line=k
                    ) from None
                if not np.isfinite(v):
                    raise InputError(f"{key} is {value}", source=name, line=k)
                limit = TRACE_RANGE[_CHANNEL.get(key, "x")]
                if abs(v) > limit:
                    raise InputError(
                        f"{key} beyond {limit:g}: not a value a machine records",
                        source=name,
                        line=k,
                    )
            ts.append(t)
            vs.append(v)
        return np.array(ts), np.array(vs)

    channels = {"v": numbers("Feed_Rate"), "line": numbers("Block_Number")}
    pos_keys = next((p for p in _POS_KEYS if p[0] in events), None)
    if pos_keys:
        for axis, key in zip("xyz", pos_keys, strict=True):
            channels[axis] = numbers(key)
    # Samples at every event time after every channel has a value (sample and hold).
    present = {c: ts for c, (ts, _) in channels.items() if ts.size}
    start = max(ts[0] for ts in present.values())
    times = np.unique(np.concatenate(list(present.values())))
    times = times[times >= start]
    held = {}
    for c, (ts, vs) in channels.items():
        if ts.size:
            held[c] = vs[np.searchsorted(ts, times, side="right") - 1]
    v = held.get("v")
    ok = np.ones(times.size, dtype=bool)
    for arr in held.values():
        ok &= np.isfinite(arr)
    notes = []
    if not ok.all():
        notes.append(
            Notice(name, None, "UNAVAILABLE values: those stretches are left out", int((~ok).sum()))
        )
    times = times[ok]
    if times.size < 2:
        raise InputError(
            f"{times.size} sample(s) where every recorded channel has a value "
            "(the rest UNAVAILABLE): nothing to diagnose",
            source=name,
        )
    # Event data: a long silence means nothing changed, not a gap in the recording.
    pos = None
    if pos_keys:
        pos = np.column_stack([held[a][ok] for a in "xyz"]) * scale
    line = held["line"][ok].astype(np.int64) if "line" in held else None
    return Trace(
        t=times - times[0],
        pos=pos,
        v=v[ok] * scale if v is not None else None,
        line=line,
        source=name,
        kind=options.kind or "actual",
        units=units,
        notices=tuple(notes),
    )


@hookimpl
def ncperf_read_trace(source: object, options: TraceOptions) -> Trace | None:
    """CSV traces by extension, SHDR recordings by their first line."""
    path = _path(source)
    if path is None:
        return None
    if path.suffix.lower() == ".csv":
        return read_csv_trace(path, options)
    head = read_input(path, limit=512, what="a trace").decode("utf-8", "replace")
    first = next((ln for ln in head.splitlines() if ln.strip()), "")
    if _SHDR.match(first):
        return read_shdr_trace(path, options)
    return None
