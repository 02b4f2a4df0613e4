"""Machine descriptions: per-axis limits and the controller's times and tolerance.

The TOML file speaks the paper's units (m/min, m/s^2, m/s^3, s, mm); the
:class:`Machine` object speaks mm and s only::

    name = "..."
    [axes.X]                # also [axes.Y], [axes.Z]
    max_feed = 30.0         # m/min
    max_acceleration = 2.5  # m/s^2
    max_jerk = 5.0          # m/s^3 (inf: no jerk limit)
    [controller]
    interpolation_time = 0.012         # s, t_int (model 3)
    path_tolerance = 0.01              # mm, TIT (model 1)
    curvature_transition_time = 0.012  # s, dt (model 2)
    max_path_feed = 15.0               # m/min, all axes together (optional; default none)
    block_time_on_blends = true        # t_int caps the inserted corner arcs too (optional)
    corner_blending = "linuxcnc"       # how corners are blended: "paper" (default) or
                                       # LinuxCNC 2.9's planner (optional)

Optional, for the readers (:mod:`core.model.setup`) and rotary axes::

    [axes.A]                # also [axes.B], [axes.C]: rotary axes, degrees
    max_feed = 7200.0       # deg/min
    max_acceleration = 720  # deg/s^2
    max_jerk = 7200         # deg/s^3 (optional; default inf)
    [controller]
    default_path_mode = "exact_stop"   # or "continuous": where the program sets none
    home = [0.0, 0.0, 0.0]             # mm, G28 position (machine coordinates)
    home_g30 = [0.0, 0.0, 0.0]         # mm, G30 position
    tool_table = "tool.tbl"            # LinuxCNC tool table, beside this file
    subroutine_path = ["subs"]         # folders for subprogram files
    peck_clearance = 0.254             # mm, G73/G83 (Fanuc 5114/5115, Haas setting 22)
    [offsets]
    G54 = [100.0, 50.0, -200.0]        # mm, machine coordinates of the work origin
    [tools]
    T1 = { diameter = 10.0, length = 50.0 }   # mm

Optional, for ``ncperf diagnose`` (:mod:`core.diagnosis`)::

    [diagnosis]
    noise_floor = 12.0                 # mm/min, the held-out gap (ncperf calibrate writes it)
    trace_cycle = 0.001                # s, the controller cycle its traces sample once per
"""

from __future__ import annotations

import math
import re
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from core.model.errors import InputError, MachineError, UsageError
from core.model.inputs import read_input_text
from core.model.preset_files import DEFAULT_PRESET, preset_names, preset_text
from core.model.setup import PATH_MODES, ControllerSetup, Tool

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

# numpy is imported where a Machine is built, not with this module: the presets' names and
# titles (``ncperf machines``, the parser's help) cost no numpy.

AXES = ("X", "Y", "Z")
#: Rotary axes a machine file may add (degrees).
ROTARY_AXES = ("A", "B", "C")

#: TOML key -> factor from the file's unit to ncperf's internal unit.
AXIS_KEYS = {
    "max_feed": 1000.0 / 60.0,  # m/min -> mm/s
    "max_acceleration": 1000.0,  # m/s^2 -> mm/s^2
    "max_jerk": 1000.0,  # m/s^3 -> mm/s^3
}
CONTROLLER_KEYS = {
    "interpolation_time": 1.0,  # s
    "path_tolerance": 1.0,  # mm
    "curvature_transition_time": 1.0,  # s
}
#: Rotary axes' keys -> factor to deg/s, deg/s^2, deg/s^3 (max_jerk optional).
ROTARY_KEYS = {"max_feed": 1.0 / 60.0, "max_acceleration": 1.0, "max_jerk": 1.0}
#: Optional [controller] keys for the readers (see core.model.setup).
#: Optional [controller] keys of the planner: max_path_feed (m/min), block_time_on_blends,
#: corner_blending.
PLANNER_KEYS = ("max_path_feed", "block_time_on_blends", "corner_blending")
#: Corner blending models: the paper's (an arc of eq. 1 at each corner, crossed at constant
#: speed) and LinuxCNC 2.9's planner's (plugins/tangential.py).
CORNER_BLENDING = ("paper", "linuxcnc")
SETUP_KEYS = (
    "default_path_mode",
    "home",
    "home_g30",
    "tool_table",
    "subroutine_path",
    "peck_clearance",
)
TOP_KEYS = ("name", "axes", "controller")
OPTIONAL_TOP_KEYS = ("offsets", "tools", "diagnosis")
#: Keys that may be infinite ("no such limit"): LinuxCNC 2.9 has no jerk limit.
MAY_BE_INFINITE = {"max_jerk"}


@dataclass(frozen=True)
class RotaryAxis:
    """Limits of a rotary axis (deg/s, deg/s^2, deg/s^3; jerk may be inf)."""

    max_feed: float
    max_acceleration: float
    max_jerk: float = math.inf


@dataclass(frozen=True, eq=False)
class Machine:
    """A machine tool and its controller, in mm and s.

    Attributes
    ----------
    name : str
    max_feed : (3,) float, mm/s
        Per-axis feed limit (X, Y, Z); also the rapid speed.
    max_acceleration : (3,) float, mm/s^2
    max_jerk : (3,) float, mm/s^3
        May be inf (no jerk limit).
    interpolation_time : float, s
        Block cycle time t_int of model 3 (eq. 16).
    path_tolerance : float, mm
        Trajectory interpolation tolerance TIT of model 1 (eq. 1).
    curvature_transition_time : float, s
        Elementary time dt of model 2 (eq. 11-14).
    source : str
        Preset name or file the machine was loaded from.
    """

    name: str
    max_feed: NDArray[np.float64]
    max_acceleration: NDArray[np.float64]
    max_jerk: NDArray[np.float64]
    interpolation_time: float
    path_tolerance: float
    curvature_transition_time: float
    source: str = "<memory>"
    #: Share of the acceleration usable as normal acceleration (corners, capped arcs); the
    #: paper's model uses all of it. Set by the normal_acceleration_factor effect.
    normal_acceleration_factor: float = 1.0
    #: Effects the machine file switches on: (name, {param: value}, line of the table).
    effects: tuple[tuple[str, dict[str, float], int | None], ...] = ()
    #: Path speed limit over all axes together (mm/s; LinuxCNC's [TRAJ]MAX_LINEAR_VELOCITY),
    #: on feed moves and rapids alike; inf: the axes' own limits only.
    max_path_feed: float = math.inf
    #: The block time (model 3) also caps the blend arcs the controller inserts at corners,
    #: segments it executes like any block (LinuxCNC's planner); False: programmed blocks
    #: only, as the paper's model 3.
    block_time_on_blends: bool = False
    #: How the planner blends corners: "paper" (sec. 2.1: an arc of eq. 1 at every corner,
    #: crossed at constant speed) or "linuxcnc" (LinuxCNC 2.9's planner: near-tangent
    #: junctions run through without an arc, arcs sized by the speed they are run at, and
    #: the speed changes along them at half the acceleration; see plugins/tangential.py).
    corner_blending: str = "paper"
    #: The gap (mm/s RMS over time) a prediction of this machine leaves on data it was not
    #: fitted on: the noise floor of the diagnosis (``[diagnosis] noise_floor`` in mm/min,
    #: written by ``ncperf calibrate``); NaN: none given (estimated from each trace).
    noise_floor: float = math.nan
    #: The controller cycle (s) this machine's traces are sampled at, once per cycle
    #: (``[diagnosis] trace_cycle``; LinuxCNC's sampler on the servo thread: its servo
    #: period); NaN: its traces are sampled otherwise. A trace sampled every T s then ran with
    #: a cycle of T, and the diagnosis compares the two (core.diagnosis.diagnose).
    trace_cycle: float = math.nan
    #: Rotary axes the file describes ("A", "B", "C").
    rotary: dict[str, RotaryAxis] = field(default_factory=dict)
    #: What the controller holds before a program runs (home, offsets, tools...).
    setup: ControllerSetup = field(default_factory=ControllerSetup)

    def __post_init__(self) -> None:
        import numpy as np

        for key in AXIS_KEYS:
            a = np.array(getattr(self, key), dtype=np.float64)
            if a.shape != (3,):
                raise ValueError(f"{key} must have shape (3,), got {a.shape}")
            a.setflags(write=False)
            object.__setattr__(self, key, a)

    @classmethod
    def from_user_units(
        cls,
        name: str,
        *,
        max_feed_m_min: tuple[float, float, float],
        max_acceleration_m_s2: tuple[float, float, float],
        max_jerk_m_s3: tuple[float, float, float],
        interpolation_time: float,
        path_tolerance: float,
        curvature_transition_time: float,
        source: str = "<memory>",
    ) -> Machine:
        """Build a machine from the paper's units (m/min, m/s^2, m/s^3)."""
        import numpy as np

        return cls(
            name=name,
            max_feed=np.asarray(max_feed_m_min, dtype=float) * AXIS_KEYS["max_feed"],
            max_acceleration=np.asarray(max_acceleration_m_s2, dtype=float)
            * AXIS_KEYS["max_acceleration"],
            max_jerk=np.asarray(max_jerk_m_s3, dtype=float) * AXIS_KEYS["max_jerk"],
            interpolation_time=interpolation_time,
            path_tolerance=path_tolerance,
            curvature_transition_time=curvature_transition_time,
            source=source,
        )

    def rapid_speed(self, direction: NDArray[np.float64]) -> NDArray[np.float64]:
        """Path speed (mm/s) of straight moves along unit ``direction`` (n, 3) with every
        axis at most at its max feed: min over axes of Vmax_k / |u_k|."""
        import numpy as np

        with np.errstate(divide="ignore"):
            per_axis = self.max_feed[None, :] / np.abs(direction)
        return np.minimum(per_axis.min(axis=1), self.max_path_feed)


# ---------------------------------------------------------------------------- loading
def _table_line(text: str, table: str) -> int | None:
    m = re.search(rf"^[ \t]*\[[ \t]*{re.escape(table)}[ \t]*\]", text, flags=re.MULTILINE)
    return text.count("\n", 0, m.start()) + 1 if m else None


def _line_of(text: str, key: str, table: str = "") -> int | None:
    """1-based line of ``key = ...`` inside ``[table]`` ("" for the top level)."""
    start, end = 0, len(text)
    if table:
        head = re.search(rf"^[ \t]*\[[ \t]*{re.escape(table)}[ \t]*\]", text, flags=re.MULTILINE)
        if head is None:
            return None
        start = head.end()
    nxt = re.compile(r"^[ \t]*\[", flags=re.MULTILINE).search(text, start)
    if nxt is not None:
        end = nxt.start()
    m = re.compile(rf"^[ \t]*\"?{re.escape(key)}\"?[ \t]*=", flags=re.MULTILINE).search(
        text, start, end
    )
    return text.count("\n", 0, m.start()) + 1 if m else None


def _check_keys(
    table: dict,
    expected: tuple[str, ...],
    name: str,
    source: str,
    text: str,
    optional: tuple[str, ...] = (),
    line: int | None = None,
) -> None:
    """Unknown and missing keys of ``[name]`` ("" for the top level; ``line``: where an
    inline table is written)."""
    where = f"[{name}]" if name else "the file"
    known = expected + optional
    for key in table:
        if key not in known:
            import difflib  # (a misspelt key only)

            close = difflib.get_close_matches(key, known, n=1)
            hint = (
                f"; did you mean '{close[0]}'?"
                if close
                else f"; expected one of {', '.join(known)}"
            )
            at = line if line is not None else _line_of(text, key, name)
            if at is None:  # a sub-table such as [axes.W]
                at = _table_line(text, f"{name}.{key}" if name else key)
            raise MachineError(f"unknown key '{key}' in {where}{hint}", source=source, line=at)
    for key in expected:
        if key not in table:
            at = line if line is not None else (_table_line(text, name) if name else None)
            raise MachineError(f"missing key '{key}' in {where}", source=source, line=at)


#: Deepest nesting of tables and arrays in a machine file (its own schema needs 3).
MAX_DEPTH = 8
#: Largest integer taken as a number: larger ones are not exactly a float, and one of 400
#: digits is not a float at all.
MAX_INT = 2**53
#: Range of every positive machine value in mm and s (1 nm/min to 1e12 mm/s^3): outside it
#: a value is a typing error, and a subnormal jerk (1e-310) turns the profile into NaN.
PHYSICAL_MIN = 1e-9
PHYSICAL_MAX = 1e12


def _check_numbers(data: dict, source: str, text: str) -> None:
    """Every number in the file an exact, normal float; nesting bounded."""
    stack: list[tuple[object, str, str, int]] = [(data, "", "", 0)]
    while stack:
        value, key, table, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise MachineError(
                f"'{key}' nested {depth} deep (a machine file needs at most {MAX_DEPTH})",
                source=source,
                line=_line_of(text, key, table) if key else None,
            )
        if isinstance(value, dict):
            sub = f"{table}.{key}" if table and key else key
            stack.extend((v, str(k), sub, depth + 1) for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((v, key, table, depth + 1) for v in value)
        elif isinstance(value, bool):
            continue
        elif isinstance(value, int) and abs(value) > MAX_INT:
            raise MachineError(
                f"'{key}' is an integer of {len(str(abs(value)))} digits; not a machine value",
                source=source,
                line=_line_of(text, key, table),
            )
        elif isinstance(value, float) and 0 < abs(value) < sys.float_info.min:
            raise MachineError(
                f"'{key}' = {value!r} is too small to compute with (subnormal)",
                source=source,
                line=_line_of(text, key, table),
            )


def _number(value: object, key: str, name: str, source: str, text: str) -> float:
    where = f"[{name}]"
    line = _line_of(text, key, name)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise MachineError(
            f"'{key}' in {where} must be a number, got {value!r}", source=source, line=line
        )
    v = float(value)
    if math.isnan(v) or v <= 0 or (math.isinf(v) and key not in MAY_BE_INFINITE):
        allowed = "a positive number" + (" or inf" if key in MAY_BE_INFINITE else "")
        raise MachineError(
            f"'{key}' in {where} must be {allowed}, got {value!r}", source=source, line=line
        )
    scale = AXIS_KEYS.get(key) or CONTROLLER_KEYS.get(key) or ROTARY_KEYS.get(key) or 1.0
    lo, hi = PHYSICAL_MIN, PHYSICAL_MAX
    if math.isfinite(v) and not lo <= v * scale <= hi:
        raise MachineError(
            f"'{key}' in {where} = {value!r} is outside the physical range of a machine",
            source=source,
            line=line,
        )
    return v


def machine_from_toml_text(text: str, source: str) -> Machine:
    """Parse a machine TOML text; every problem is a :class:`MachineError` naming file and line."""
    import numpy as np

    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"\(at line (\d+), column \d+\)", str(exc))
        msg = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        raise MachineError(
            f"not valid TOML: {msg}", source=source, line=int(m.group(1)) if m else None
        ) from None
    except RecursionError:
        raise MachineError(
            "not valid TOML for a machine: arrays or tables nested too deeply", source=source
        ) from None
    except ValueError:
        # tomllib converts integers with int(): one of over 4,300 digits raises ValueError
        # (Python's integer-string limit), not TOMLDecodeError.
        raise MachineError(
            f"not valid TOML for a machine: an integer longer than {sys.get_int_max_str_digits():,}"
            " digits",
            source=source,
        ) from None
    _check_numbers(data, source, text)
    effects = _effects(data.pop("effects", {}), source, text)
    _check_keys(data, TOP_KEYS, "", source, text, OPTIONAL_TOP_KEYS)
    name = data["name"]
    if not isinstance(name, str) or not name.strip():
        raise MachineError(
            "'name' must be a non-empty string", source=source, line=_line_of(text, "name")
        )
    axes = data["axes"]
    if not isinstance(axes, dict):
        raise MachineError("'axes' must be a table", source=source, line=_line_of(text, "axes"))
    _check_keys(axes, AXES, "axes", source, text, ROTARY_AXES)
    rotary = {ax: _rotary(axes[ax], ax, source, text) for ax in ROTARY_AXES if ax in axes}
    per_axis: dict[str, list[float]] = {k: [] for k in AXIS_KEYS}
    for ax in AXES:
        table = axes[ax]
        tname = f"axes.{ax}"
        if not isinstance(table, dict):
            raise MachineError(f"[{tname}] must be a table", source=source)
        _check_keys(table, tuple(AXIS_KEYS), tname, source, text)
        for key, factor in AXIS_KEYS.items():
            per_axis[key].append(_number(table[key], key, tname, source, text) * factor)
    ctrl = data["controller"]
    if not isinstance(ctrl, dict):
        raise MachineError(
            "'controller' must be a table", source=source, line=_line_of(text, "controller")
        )
    _check_keys(ctrl, tuple(CONTROLLER_KEYS), "controller", source, text, SETUP_KEYS + PLANNER_KEYS)
    planner: dict[str, Any] = {}
    if "max_path_feed" in ctrl:
        v = _number(ctrl["max_path_feed"], "max_path_feed", "controller", source, text)
        planner["max_path_feed"] = v * AXIS_KEYS["max_feed"]
    if "block_time_on_blends" in ctrl:
        flag = ctrl["block_time_on_blends"]
        if not isinstance(flag, bool):
            raise MachineError(
                f"'block_time_on_blends' in [controller] must be true or false, got {flag!r}",
                source=source,
                line=_line_of(text, "block_time_on_blends", "controller"),
            )
        planner["block_time_on_blends"] = flag
    if "corner_blending" in ctrl:
        mode = ctrl["corner_blending"]
        if mode not in CORNER_BLENDING:
            raise MachineError(
                f"'corner_blending' in [controller] must be one of "
                f"{', '.join(repr(c) for c in CORNER_BLENDING)}, got {mode!r}",
                source=source,
                line=_line_of(text, "corner_blending", "controller"),
            )
        planner["corner_blending"] = mode
    c = {k: _number(ctrl[k], k, "controller", source, text) * f for k, f in CONTROLLER_KEYS.items()}
    noise_floor = math.nan
    diag = data.get("diagnosis", {})
    if not isinstance(diag, dict):
        raise MachineError(
            "'diagnosis' must be a table", source=source, line=_line_of(text, "diagnosis")
        )
    _check_keys(diag, (), "diagnosis", source, text, ("noise_floor", "trace_cycle"))
    if "noise_floor" in diag:
        noise_floor = _number(diag["noise_floor"], "noise_floor", "diagnosis", source, text) / 60.0
    trace_cycle = math.nan
    if "trace_cycle" in diag:
        trace_cycle = _number(diag["trace_cycle"], "trace_cycle", "diagnosis", source, text)
    setup = _setup(ctrl, data.get("offsets", {}), data.get("tools", {}), source, text)
    return Machine(
        rotary=rotary,
        setup=setup,
        max_path_feed=planner.get("max_path_feed", math.inf),
        block_time_on_blends=planner.get("block_time_on_blends", False),
        corner_blending=planner.get("corner_blending", "paper"),
        noise_floor=noise_floor,
        trace_cycle=trace_cycle,
        name=name.strip(),
        max_feed=np.array(per_axis["max_feed"]),
        max_acceleration=np.array(per_axis["max_acceleration"]),
        max_jerk=np.array(per_axis["max_jerk"]),
        source=source,
        effects=effects,
        interpolation_time=c["interpolation_time"],
        path_tolerance=c["path_tolerance"],
        curvature_transition_time=c["curvature_transition_time"],
    )


def _rotary(table: object, ax: str, source: str, text: str) -> RotaryAxis:
    tname = f"axes.{ax}"
    if not isinstance(table, dict):
        raise MachineError(f"[{tname}] must be a table", source=source)
    _check_keys(table, ("max_feed", "max_acceleration"), tname, source, text, ("max_jerk",))
    v = {
        k: _number(table[k], k, tname, source, text) * f
        for k, f in ROTARY_KEYS.items()
        if k in table
    }
    return RotaryAxis(**v)


def _vec3(value: object, key: str, name: str, source: str, text: str) -> tuple[float, float, float]:
    line = _line_of(text, key, name)
    if (
        not isinstance(value, list)
        or len(value) != 3
        or any(isinstance(x, bool) or not isinstance(x, int | float) for x in value)
        or not all(math.isfinite(float(x)) for x in value)
    ):
        raise MachineError(
            f"'{key}' in [{name}] must be three finite numbers [x, y, z] in mm, got {value!r}",
            source=source,
            line=line,
        )
    return (float(value[0]), float(value[1]), float(value[2]))


_OFFSET_NAME = re.compile(r"G5[4-9](?:\.[1-3])?|G5[0-9]{2}|G54\.1P[0-9]+")


def _setup(ctrl: dict, offsets: object, tools: object, source: str, text: str) -> ControllerSetup:
    """The optional reader settings of a machine file (see core.model.setup)."""
    mode = ctrl.get("default_path_mode")
    if mode is not None and mode not in PATH_MODES:
        raise MachineError(
            f"'default_path_mode' in [controller] must be one of {', '.join(PATH_MODES)}, "
            f"got {mode!r}",
            source=source,
            line=_line_of(text, "default_path_mode", "controller"),
        )
    kw: dict = {"default_path_mode": mode}
    if "peck_clearance" in ctrl:
        kw["peck_clearance"] = _number(
            ctrl["peck_clearance"], "peck_clearance", "controller", source, text
        )
    for key in ("home", "home_g30"):
        if key in ctrl:
            kw[key] = _vec3(ctrl[key], key, "controller", source, text)
    if "tool_table" in ctrl:
        tt = ctrl["tool_table"]
        if not isinstance(tt, str) or not tt:
            raise MachineError(
                "'tool_table' in [controller] must be a file name",
                source=source,
                line=_line_of(text, "tool_table", "controller"),
            )
        folder = Path(source).parent if not source.startswith("preset ") else Path(".")
        kw["tool_table"] = str(folder / tt)
    if "subroutine_path" in ctrl:
        sp = ctrl["subroutine_path"]
        if not isinstance(sp, list) or not all(isinstance(x, str) and x for x in sp):
            raise MachineError(
                "'subroutine_path' in [controller] must be a list of folder names",
                source=source,
                line=_line_of(text, "subroutine_path", "controller"),
            )
        folder = Path(source).parent if not source.startswith("preset ") else Path(".")
        kw["subroutine_path"] = tuple(str(folder / x) for x in sp)
    if not isinstance(offsets, dict):
        raise MachineError("'offsets' must be a table", source=source)
    wo = {}
    for name, value in offsets.items():
        code = name.upper().replace(" ", "")
        if not _OFFSET_NAME.fullmatch(code):
            raise MachineError(
                f"[offsets] key '{name}' is not a work offset (G54 ... G59.3, G505 ...)",
                source=source,
                line=_line_of(text, name, "offsets"),
            )
        wo[code] = _vec3(value, name, "offsets", source, text)
    kw["work_offsets"] = wo
    if not isinstance(tools, dict):
        raise MachineError("'tools' must be a table", source=source)
    tt_map = {}
    for name, value in tools.items():
        line = _line_of(text, name, "tools")
        m = re.fullmatch(r"[Tt]?(\d+)", name)
        if m is None or not isinstance(value, dict):
            raise MachineError(
                f"[tools] entries are T<number> = {{ diameter = ..., length = ... }}, got '{name}'",
                source=source,
                line=line,
            )
        _check_keys(
            value, (), f"tools.{name}", source, text, ("diameter", "radius", "length"), line
        )
        entry = {}
        for key in ("diameter", "radius", "length"):
            if key in value:
                x = value[key]
                if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
                    raise MachineError(
                        f"'{key}' of tool {name} must be a finite number (mm), got {x!r}",
                        source=source,
                        line=line,
                    )
                entry[key] = float(x)
        radius = entry.get("radius", entry["diameter"] / 2 if "diameter" in entry else None)
        tt_map[int(m.group(1))] = Tool(radius=radius, length=entry.get("length"))
    kw["tools"] = tt_map
    return ControllerSetup(**kw)


def _effects(table: object, source: str, text: str) -> tuple:
    """``[effects.NAME]`` tables: names and numeric parameters (checked against the effects
    ncperf knows when they are used)."""
    if not isinstance(table, dict):
        raise MachineError(
            "'effects' must hold tables [effects.NAME]",
            source=source,
            line=_line_of(text, "effects"),
        )
    out = []
    for name, params in table.items():
        line = _table_line(text, f"effects.{name}")
        if not isinstance(params, dict):
            raise MachineError(
                f"[effects.{name}] must be a table of parameters", source=source, line=line
            )
        vals = {}
        for key, value in params.items():
            if (
                isinstance(value, bool)
                or not isinstance(value, int | float)
                or not math.isfinite(float(value))
            ):
                raise MachineError(
                    f"'{key}' in [effects.{name}] must be a finite number, got {value!r}",
                    source=source,
                    line=_line_of(text, key, f"effects.{name}"),
                )
            vals[key] = float(value)
        out.append((name, vals, line))
    return tuple(out)


def load_machine_file(path: str | Path) -> Machine:
    """Load a machine TOML file."""
    return machine_from_toml_text(_read_machine_file(path), str(path))


def _read_machine_file(path: str | Path) -> str:
    """A machine file's text; what cannot be read is a :class:`MachineError`."""
    try:
        return read_input_text(path, what="a machine file")
    except InputError as exc:
        raise MachineError(exc.message, source=exc.source, line=exc.line) from None


# ---------------------------------------------------------------------------- presets
def load_preset(name: str) -> Machine:
    """Load a shipped preset by name."""
    names = preset_names()
    if name not in names:
        raise UsageError(f"unknown machine preset '{name}'; presets: {', '.join(names)}")
    return machine_from_toml_text(preset_text(name), f"preset {name}")


def machine_text(spec: str | None) -> str:
    """The TOML text of a preset name or a machine file (None: the default preset), for
    tools that write a changed copy (``ncperf calibrate``)."""
    if spec is None or spec in preset_names():
        return preset_text(spec or DEFAULT_PRESET)
    return _read_machine_file(spec)


def resolve_machine(spec: str | None) -> Machine:
    """A preset name or a TOML file path (None: the default 840D preset)."""
    if spec is None:
        return load_preset(DEFAULT_PRESET)
    if spec in preset_names():
        return load_preset(spec)
    if spec.endswith(".toml") or Path(spec).exists():
        return load_machine_file(spec)
    return load_preset(spec)  # raises with the list of presets
