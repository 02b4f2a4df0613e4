"""The outputs of ``ncperf calibrate``: the calibrated machine file (commented TOML) and the
terminal report.

The machine file is the start machine's own file with the calibrated values put in: axis
limits scaled (``axis_dynamics``), the block time, path tolerance, path mode and path speed
limit set in ``[controller]``, the planner's acceleration shares as ``[effects.NAME]``
tables, and the noise floor as ``[diagnosis] noise_floor`` (calibrated on the feed gap
only); every calibrated value carries a comment with its fitted range and the folds'
values. Units as the file speaks them (m/min, m/s^2, m/s^3, s, mm; the noise floor in
mm/min).
"""

from __future__ import annotations

import json
import math
import tomllib
from collections.abc import Mapping
from typing import Any

from core.diagnosis.calibrate import Calibrated, Calibration
from core.engine.effects import Effect
from core.model.machine import Machine
from core.model.tolerances import TOL

AXES = ("X", "Y", "Z")
#: Effects written as [controller] keys: effect -> (parameter, key, factor to the file's unit).
CONTROLLER_KEYS = {
    "block_cycle_time": ("t_block", "interpolation_time", 1.0),
    "corner_tolerance": ("tolerance", "path_tolerance", 1.0),
    "path_feed_limit": ("max_feed", "max_path_feed", 60.0 / 1000.0),
}
Comments = dict[tuple[tuple[str, ...], str], str]
#: The file's units, written beside every value of these keys (the start file's own comments
#: do not survive reading it).
UNITS = {
    "max_feed": "m/min",
    "max_acceleration": "m/s^2",
    "max_jerk": "m/s^3",
    "interpolation_time": "s",
    "path_tolerance": "mm",
    "curvature_transition_time": "s",
    "max_path_feed": "m/min",
    "peck_clearance": "mm",
}


def _value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        if math.isnan(v):
            return "nan"
        text = f"{v:.6g}"
        return text if "e" in text or "." in text else text + ".0"  # a TOML float
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=True)
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def _key(k: str) -> str:
    bare = k.replace("_", "").replace("-", "").isalnum() and k.isascii()
    return k if bare else json.dumps(k, ensure_ascii=True)


def _emit(table: Mapping[str, Any], path: tuple[str, ...], comments: Comments, out: list[str]):
    scalars = {k: v for k, v in table.items() if not isinstance(v, dict)}
    tables = {k: v for k, v in table.items() if isinstance(v, dict)}
    if path and (scalars or not tables):
        out.append("")
        out.append("[" + ".".join(_key(p) for p in path) + "]")
    for k, v in scalars.items():
        line = f"{_key(k)} = {_value(v)}"
        note = comments.get((path, k))
        unit = UNITS.get(k) if path and path[0] in ("axes", "controller") else None
        if unit:
            note = f"{unit}; {note}" if note else unit
        out.append(f"{line:<32s} # {note}" if note else line)
    for k, v in tables.items():
        _emit(v, (*path, k), comments, out)


def _rng(c: Calibrated, p: str, factor: float = 1.0) -> str:
    lo, hi = c.ranges.get(p, (math.nan, math.nan))
    folds = " / ".join(f"{f[p] * factor:.4g}" for f in c.folds)
    text = f"fitted range {lo * factor:.4g}-{hi * factor:.4g}, folds {folds}"
    if p in c.documented:
        text += f"; documented value, inside the range ({c.documented[p]})"
    return text


def machine_toml(
    cal: Calibration,
    start_text: str,
    start: Machine,
    effects: Mapping[str, Effect],
    *,
    header: str,
) -> str:
    """The calibrated machine file (see the module docstring)."""
    data = tomllib.loads(start_text)
    comments: Comments = {}
    data["name"] = f"{start.name} (calibrated)"
    ctrl = data.setdefault("controller", {})
    for c in cal.effects:
        if c.name == "axis_dynamics":
            p = c.params
            for ax in AXES:
                t = data["axes"][ax]
                scales = {
                    "max_feed": ("feed_scale", f"feed_{ax.lower()}"),
                    "max_acceleration": ("accel_scale", f"accel_{ax.lower()}"),
                    "max_jerk": ("jerk_scale", None),
                }
                for key, (uni, per) in scales.items():
                    f = p.get(uni, 1.0) * (p.get(per, 1.0) if per else 1.0)
                    if abs(f - 1.0) < TOL.rel_equal:
                        continue
                    t[key] = float(t[key]) * f
                    parts = [_rng(c, uni)] if uni in c.ranges else []
                    if per and per in c.ranges:
                        parts.append(f"{per}: {_rng(c, per)}")
                    comments[(("axes", ax), key)] = (
                        f"x {f:.4g} calibrated ({uni}: " + "; ".join(parts) + ")"
                    )
        elif c.name in CONTROLLER_KEYS:
            pname, key, factor = CONTROLLER_KEYS[c.name]
            ctrl[key] = c.params[pname] * factor
            comments[(("controller",), key)] = "calibrated: " + _rng(c, pname, factor)
        elif c.name == "exact_stop":
            ctrl["default_path_mode"] = "exact_stop"
            comments[(("controller",), "default_path_mode")] = (
                "calibrated: the traces stop at every block end"
            )
        else:
            eff = effects[c.name]
            values = dict(c.params)
            if eff.relative:
                before = eff.folded(start)
                values = {
                    k: v * before.get(k, 1.0) if k in eff.relative else v for k, v in values.items()
                }
            data.setdefault("effects", {})[c.name] = values
            for pname in values:
                comments[(("effects", c.name), pname)] = "calibrated: " + _rng(c, pname)
    if cal.objective.name == "feed":
        # (the start file's other [diagnosis] keys, such as trace_cycle, stay)
        data.setdefault("diagnosis", {})["noise_floor"] = round(cal.noise_floor, 3)
        comments[(("diagnosis",), "noise_floor")] = (
            "mm/min: the held-out gap this file leaves (ncperf diagnose's floor)"
        )
    # Calibrated on block times, the file's noise floor (a feed gap) is not measured: the
    # start file's, if any, stays; the block-time figure is in the header.
    out = [f"# {line}".rstrip() for line in header.splitlines()]
    out.append("")
    _emit(data, (), comments, out)
    return "\n".join(out).replace("\n\n\n", "\n\n") + "\n"


def report(cal: Calibration, *, start: str, out: str, labels: list[str]) -> str:
    """The terminal report."""
    lines = [f"ncperf calibrate: {len(labels)} trace(s) on {start}"]
    obj = cal.objective
    lines.append(f"  objective        {obj.name}: {obj.what} ({cal.objective_reason})")
    lines.append(f"  held-out data    {cal.held_out}")
    for k, (b, a) in enumerate(zip(cal.gap_before, cal.gap_after, strict=True)):
        share = (b - a) / b if b > 0 else 0.0
        lines.append(
            f"  fold {'AB'[k]}           held-out gap {b:.1f} -> {a:.1f} {obj.unit} RMS "
            f"({share:.0%} removed)"
        )
    if not cal.effects:
        lines.append("  calibrated       nothing: no controller effect clears the test")
    for c in cal.effects:
        params = ", ".join(f"{k}={v:.4g}" for k, v in c.params.items()) or "-"
        doc = " (documented value)" if c.documented else ""
        lines.append(
            f"  calibrated       {c.name:28s} {params}{doc}  "
            f"(fold A: {c.gap_before:.1f} -> {c.gap_after:.1f} {obj.unit})"
        )
    floor = f"  noise floor      {cal.noise_floor:.1f} {obj.unit}"
    if obj.name != "feed":
        floor += " (a block-time error: not written as the file's feed-gap floor)"
    lines.append(floor)
    lines.append(f"  machine file     {out}")
    return "\n".join(lines)
