"""The reports of ``ncperf diagnose``: the terminal text, the JSON file, and the machine-file
tables that fold the chosen effects into the machine (TOML).

Gaps in mm/min, times in s; the thresholds quoted come from :mod:`core.diagnosis.rules`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from core.diagnosis.diagnose import Diagnosis, EffectResult
from core.diagnosis.fit import bounded
from core.diagnosis.gaps import GapZone
from core.diagnosis.rules import ADD_SHARE, BEST_SHARE, GAP_SHARE, SIG_P, STOP_SHARE
from core.engine.effects import Effect
from core.model.machine import Machine


def _fmt_params(params: dict[str, float], eff: Effect) -> str:
    units = {p.name: p.unit for p in eff.params}
    return (
        ", ".join(
            f"{k}={v:.4g}{(' ' + units[k]) if units.get(k) else ''}" for k, v in params.items()
        )
        or "-"
    )


def warnings(d: Diagnosis, effects: Mapping[str, Effect], labels: list[str]) -> list[str]:
    """What makes the diagnosis doubtful: a trace poorly aligned on the program, or a
    suggested (or leading) effect whose fit ran to a bound of its parameters -- both the
    signs of a machine file that does not describe the machine."""
    out = [
        f"the trace {lab} is poorly aligned on the program ({al.message})"
        for lab, al in zip(labels, d.alignments, strict=True)
        if not al.ok
    ]
    names = list(d.chosen) or ([d.effects[0].name] if d.effects else [])
    fitted = {r.name: r.params for r in d.effects}
    for name in names:
        eff = effects.get(name)
        if eff is None:
            continue
        values = d.chosen_params.get(name, fitted.get(name, {}))
        for p in bounded(eff, values, d.befores[0].setup.machine):
            unit = f" {p.unit}" if p.unit else ""
            out.append(
                f"{name} fitted {p.name}={values[p.name]:.4g}{unit}, at its bound "
                f"({p.low:g} to {p.high:g}{unit}): the effect is stretched to its limit"
            )
    if out:
        out.append(
            "the machine file may not describe this machine: run ncperf calibrate on recordings "
            "of it (README, 'Calibrating a machine') before trusting the tables above"
        )
    return out


def toml_snippet(
    d: Diagnosis, machine: Machine | None = None, effects: Mapping[str, Effect] | None = None
) -> str:
    """The machine-file tables that make the chosen effects part of the model (for a scale
    the machine already folds in, the product of the two)."""
    out = []
    for name in d.chosen:
        values = dict(d.chosen_params[name])
        eff = effects.get(name) if effects is not None else None
        if machine is not None and eff is not None and eff.relative:
            before = eff.folded(machine)
            values = {
                k: v * before.get(k, 1.0) if k in eff.relative else v for k, v in values.items()
            }
        out.append(f"[effects.{name}]")
        out.extend(f"{k} = {v:.6g}" for k, v in values.items())
    return "\n".join(out)


def report(
    d: Diagnosis,
    *,
    program: str,
    machine: str,
    labels: list[str],
    effects: dict[str, Effect],
    machine_file: Machine | None = None,
) -> str:
    """The terminal report of ``ncperf diagnose`` (``machine_file``: the machine whose file
    the suggested tables go into)."""
    lines = [f"ncperf diagnose: {program} on {machine} (baseline: {d.baseline})"]
    for lab, al in zip(labels, d.alignments, strict=True):
        lines.append(
            f"  trace            {lab}: {al.t.size:,} samples over {al.t[-1]:.2f} s; {al.message}"
        )
        for note in al.notes:
            lines.append(f"                   {note}")
    lines.append(f"  held-out data    {d.held_out}")
    lines.append(
        f"  gap before       {d.gap_rms_before:.1f} mm/min RMS over time "
        "(measured - predicted feed on the feed moves)"
    )
    lines += _zone_table("  where it lies", d.zones)
    lines.append(
        "  effects          fitted on the calibration data; gap on the held-out data (mm/min):"
    )
    rapids = any(math.isfinite(r.rapid_gap) for r in d.effects)
    lines += _effect_table(d.effects, effects, ".1f", "rapids" if rapids else "")
    if rapids:
        lines.append(
            "                   (rapids: the gap on the rapids, which only the effects that act on "
            "them are fitted on; they decide between effects that fit the feed moves alike)"
        )
    lines.append(
        f"  to be named      an effect must remove at least {BEST_SHARE:.0%} of the held-out "
        f"gap, {d.floor:.1f} mm/min ({d.floor_source}), significant at p <= {SIG_P:g} over "
        "the held-out pieces"
    )
    if d.rapid_effects:
        lines.append(
            "  on the rapids    no effect cleared the floor on the feed moves: the effects "
            "that act on the rapids too,"
        )
        lines.append(
            "                   fitted on alternate rapids; gap on the other rapids (mm/min), "
            "and on the held-out feed moves:"
        )
        lines += _effect_table(d.rapid_effects, effects, ".0f", "feed")
        lines.append(
            f"                   (the same test, the rapids' floor {d.rapid_floor:.0f} mm/min; "
            "and the held-out feed moves' gap no worse than the floor)"
        )
    if d.clock_agrees:
        lines.append(
            f"  sample clock     every {d.sample_cycle * 1e3:.4g} ms, the machine file's cycle: "
            "its block time is the file's (block_cycle_time is not named from a fit)"
        )
    if d.clock is not None:
        c = d.clock
        lines.append(
            f"  sample clock     every {d.sample_cycle * 1e3:.4g} ms, not the machine file's "
            f"cycle: {c.name} {_fmt_params(c.params, effects[c.name])} (read, not fitted); "
            f"held-out gap "
            f"{c.held_out_gap_before:.1f} -> {c.held_out_gap_after:.1f} mm/min"
            + ("" if d.on_clock else ": contradicted by the feed moves, not named")
        )
    if d.best_effect is None:
        lines.append(
            f"  best effect      {d.reason} (what is left is noise, or an effect not in this list)"
        )
    else:
        lines.append(f"  best effect      {d.reason}")
        if d.on_rapids:
            lines.append(f"  chosen           {' + '.join(d.chosen)} (found on the rapids)")
        elif d.on_clock:
            lines.append(
                f"  chosen           {' + '.join(d.chosen)} (the first read off the sample "
                f"clock; each further one removing at least {ADD_SHARE:.0%} of what was left "
                f"on held-out data, until less than {STOP_SHARE:.0%} of the gap was left)"
            )
        else:
            lines.append(
                f"  chosen           {' + '.join(d.chosen)} (each removing at least "
                f"{ADD_SHARE:.0%} of what was left on held-out data, until less than "
                f"{STOP_SHARE:.0%} of the gap was left)"
            )
    lines.append(f"  gap after        {d.gap_rms_after:.1f} mm/min")
    if d.chosen:
        lines += _zone_table("  where it remains", d.zones_after[:5])
        lines.append("  to model it      add to the machine file (or replace there):")
        lines += [
            "                   " + t for t in toml_snippet(d, machine_file, effects).splitlines()
        ]
    for k, w in enumerate(warnings(d, effects, labels)):
        lines.append(f"  {'WARNING' if k == 0 else '':16s} {w}")
    return "\n".join(lines)


def _effect_table(
    results: Sequence[EffectResult], effects: Mapping[str, Effect], fmt: str, last: str
) -> list[str]:
    """The rows of an effects table: number, effect, fitted parameters, held-out gap before
    and after (format ``fmt``), the share removed, and, titled ``last`` (none if ""), the
    gap each leaves on the data beside (``rapid_gap``; blank where NaN)."""
    params = [_fmt_params(r.params, effects[r.name]) for r in results]
    width = max([len("parameters"), *map(len, params)])
    rows = [
        f"    {'#':>2s}  {'effect':28s} {'parameters':{width}s} {'before':>8s} "
        f"{'after':>8s} {'removed':>8s}" + (f" {last:>8s}" if last else "")
    ]
    for k, (r, ps) in enumerate(zip(results, params, strict=True), start=1):
        rows.append(
            f"    {k:2d}  {r.name:28s} {ps:{width}s} "
            f"{r.held_out_gap_before:8{fmt}} {r.held_out_gap_after:8{fmt}} "
            f"{r.removed * 100:7.0f}%"
            + (f" {r.rapid_gap:8.1f}" if last and math.isfinite(r.rapid_gap) else "")
        )
    return rows


def _zone_table(title: str, zones: tuple[GapZone, ...]) -> list[str]:
    if not zones:
        return [f"{title:18s} nowhere beyond {GAP_SHARE:.0%} of F"]
    out = [
        f"{title}:",
        f"    {'lines':13s} {'arc length [mm]':>19s} {'feature':20s} "
        f"{'RMS gap':>14s} {'time':>10s}",
    ]
    for z in zones:
        lines = f"{z.line_start}" if z.line_start == z.line_end else f"{z.line_start}-{z.line_end}"
        out.append(
            f"    {lines:13s} {z.s_start:9.1f}-{z.s_end:<9.1f} {z.feature:20s} "
            f"{z.gap_rms:8.0f} mm/min {z.time_s:+8.3f} s"
        )
    return out


def _clock_json(d: Diagnosis) -> dict | None:
    """The cycle read off the sample clock: whether it agrees with the machine file's and,
    where not, the block time it gives (None where the clock says nothing)."""
    c = d.clock
    if c is None and not d.clock_agrees:
        return None
    out: dict = {
        "sample_period_s": round(d.sample_cycle, 9),
        "machine_trace_cycle_s": d.before.setup.machine.trace_cycle,
        "agrees": d.clock_agrees,
    }
    if c is not None:
        out |= {
            "effect": c.name,
            "params": {k: round(v, 9) for k, v in c.params.items()},
            "held_out_gap_before": round(c.held_out_gap_before, 3),
            "held_out_gap_after": round(c.held_out_gap_after, 3),
            "p": round(c.p, 5),
            "named": d.on_clock,
        }
    return out


def to_json(
    d: Diagnosis, machine: Machine | None = None, effects: Mapping[str, Effect] | None = None
) -> dict:
    """The JSON report (gaps in mm/min, times in s: > 0 the machine is slower)."""

    def zone(z: GapZone) -> dict:
        return {
            "line_start": z.line_start,
            "line_end": z.line_end,
            "s_start_mm": round(z.s_start, 3),
            "s_end_mm": round(z.s_end, 3),
            "feature": z.feature,
            "gap_rms": round(z.gap_rms, 3),
            "time_s": round(z.time_s, 4),
        }

    return {
        "baseline": d.baseline,
        "held_out": d.held_out,
        "alignment": [
            {
                "method": a.method,
                "ok": a.ok,
                "message": a.message,
                "offset_mm": [round(float(x), 4) for x in a.offset],
                "coverage": round(a.coverage, 4),
            }
            for a in d.alignments
        ],
        "gap_rms_before": round(d.gap_rms_before, 3),
        "zones": [zone(z) for z in d.zones],
        "effects": [
            {
                "name": r.name,
                "params": {k: round(v, 6) for k, v in r.params.items()},
                "held_out_gap_before": round(r.held_out_gap_before, 3),
                "held_out_gap_after": round(r.held_out_gap_after, 3),
                "removed": round(r.removed, 4),
                "p": round(r.p, 5),
                "parameters_moved": r.moved,
                "rapid_gap": round(r.rapid_gap, 3) if math.isfinite(r.rapid_gap) else None,
            }
            for r in d.effects
        ],
        "rapid_effects": [
            {
                "name": r.name,
                "params": {k: round(v, 6) for k, v in r.params.items()},
                "held_out_rapid_gap_before": round(r.held_out_gap_before, 3),
                "held_out_rapid_gap_after": round(r.held_out_gap_after, 3),
                "removed": round(r.removed, 4),
                "p": round(r.p, 5),
                "parameters_moved": r.moved,
                "held_out_feed_gap": round(r.rapid_gap, 3),
            }
            for r in d.rapid_effects
        ],
        "best_effect": d.best_effect,
        "sample_clock": _clock_json(d),
        "decision": {
            "on": "sample clock" if d.on_clock else "rapids" if d.on_rapids else "feed moves",
            "rapid_floor_mm_min": (
                round(d.rapid_floor, 3) if math.isfinite(d.rapid_floor) else None
            ),
            "reason": d.reason,
            "floor_mm_min": round(d.floor, 3),
            "floor_source": d.floor_source,
            "p_required": SIG_P,
        },
        "chosen": list(d.chosen),
        "chosen_params": {
            k: {p: round(v, 6) for p, v in ps.items()} for k, ps in d.chosen_params.items()
        },
        "gap_rms_after": round(d.gap_rms_after, 3),
        "zones_after": [zone(z) for z in d.zones_after],
        "machine_file_tables": toml_snippet(d, machine, effects),
        "warnings": warnings(d, effects or {}, [f"#{k + 1}" for k in range(len(d.alignments))]),
    }
