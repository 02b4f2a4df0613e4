"""Unmodelled effects: what a real controller does that the paper's models do not.

An :class:`Effect` has a name, parameters with bounds, and a function saying how it changes
the prediction: it takes a :class:`Setup` -- the machine and the few switches the prediction
is built from -- and returns a changed one. Effects are plugins (``ncperf_effects``); a
machine file switches them on with ``[effects.NAME]`` tables, and ``ncperf diagnose`` fits
their parameters to a measured trace.

The prediction built from a Setup (:func:`core.engine.predict.predict`):

1. the tool path, with the programmed feeds scaled by ``feed_scale`` (the indicators' feeds
   by ``cap_scale``) and, where
   ``tolerance`` is set, every block's path tolerance replaced;
2. the A2 evaluation on ``machine`` (whose limits, block time, TIT and normal-acceleration
   share effects may have changed), plus ``element_caps`` (extra block limits), minus the
   limits inside runs a path compressor merges (``compression``);
3. with ``ramps``, the feed profile (:mod:`core.engine.profile`) with a look-ahead of
   ``lookahead`` blocks, else the paper's point model (each block at its own feed);
4. time-domain filters on the predicted motion, for traces of actual positions
   (``servo_tau``: first-order lag; ``filter_window``: moving average).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from core.model import geometry as g
from core.model.errors import MachineError, UsageError
from core.model.machine import Machine
from core.model.toolpath import MoveKind, ToolPath

#: A fitted parameter counts as moved (part of the explanation) beyond this share of its
#: range (:meth:`Param.differs`).
MOVED_SHARE = 0.01


@dataclass(frozen=True)
class Param:
    """A parameter of an effect.

    Attributes
    ----------
    name : str
    low, high : float
        Bounds (in the unit below).
    default : float or callable
        Value that changes nothing, or a function of the machine giving it (e.g. the
        machine's own TIT).
    unit : str
    log : bool
        Search in log space (scale-like parameters spanning decades).
    integer : bool
    points : int, optional
        Points of the parameter's 1-D search grid (None: the fit's GRID_1D): more for a
        parameter whose effect on the gap has narrow valleys between the grid's points.
    """

    name: str
    low: float
    high: float
    default: float | Callable[[Machine], float]
    unit: str = ""
    log: bool = False
    integer: bool = False
    points: int | None = None

    def default_for(self, machine: Machine) -> float:
        d = self.default
        return float(d(machine)) if callable(d) else float(d)

    def differs(self, value: float, start: float) -> bool:
        """Whether a fit moved the parameter from ``start``: by more than MOVED_SHARE of its
        range (in log space for log parameters)."""
        if self.log and value > 0 and start > 0 and self.low > 0:
            return abs(math.log(value / start)) > MOVED_SHARE * math.log(self.high / self.low)
        return abs(value - start) > MOVED_SHARE * (self.high - self.low)


@dataclass(frozen=True)
class ElementCap:
    """An extra per-block feed limit an effect adds to the prediction.

    Attributes
    ----------
    limit : callable (ToolPath, Machine) -> (n,) float, mm/s
        The cap on every move (inf where there is none).
    indicator : str
        The name the reports give it (where it binds, like a plugin's indicator).
    label : str
        The limit's name ("centripetal limit").
    """

    limit: Callable[[ToolPath, Machine], NDArray[np.float64]]
    indicator: str
    label: str


@dataclass(frozen=True)
class Setup:
    """What a prediction is built from (see the module docstring).

    Attributes
    ----------
    machine : Machine
    ramps : bool
        False: the paper's point model; True: the full feed profile.
    feed_scale : float
        Scale on every programmed feed (the override).
    cap_scale : float
        Scale on every indicator's feed (corner, curvature, block-time and other caps): a
        controller that applies its override after planning (LinuxCNC) scales these too.
    tolerance : float or None, mm
    lookahead : int or None, blocks
    element_caps : tuple of ElementCap
        Extra per-block feed limits.
    compression : tuple (max_angle rad, max_length mm) or None
    servo_tau, filter_window : float, s
    end_factor, arc_factor : float
        Shares of the tangential acceleration used on the program's last block and on arcs.
    exact_stop : bool
        Every block ends at rest (the controller runs exact stop whatever the program says).
    """

    machine: Machine
    ramps: bool = True
    feed_scale: float = 1.0
    cap_scale: float = 1.0
    tolerance: float | None = None
    lookahead: int | None = None
    element_caps: tuple[ElementCap, ...] = ()
    compression: tuple[float, float] | None = None
    servo_tau: float = 0.0
    filter_window: float = 0.0
    end_factor: float = 1.0
    arc_factor: float = 1.0
    exact_stop: bool = False

    def replace(self, **changes: Any) -> Setup:
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True)
class Effect:
    """An unmodelled effect (see the module docstring).

    Attributes
    ----------
    name : str
    params : tuple of Param
    apply : callable (Setup, {name: value}) -> Setup
        How the effect changes the prediction.
    doc : str
        One line: what the controller does.
    relative : tuple of str
        Parameters that multiply what the setup already has (scales): fitted on a machine
        that already folds the effect in, they give the further factor. The others set a
        value, and a fit starts from the machine's own.
    stages : tuple of tuple of str
        Parameter groups fitted in turn (see the attribute).
    documented : tuple of (str, float, str)
        Documented values of parameters (see the attribute).
    size : callable ({name: value}) -> int, optional
        The parameters an explanation really uses (see the attribute).
    rapids : bool
        The effect acts on the rapids as on the feed moves (see the attribute).
    """

    name: str
    params: tuple[Param, ...]
    apply: Callable[[Setup, Mapping[str, float]], Setup] = field(repr=False)
    doc: str = ""
    relative: tuple[str, ...] = ()
    #: Groups of parameters fitted one after the other (the first on a grid, the later ones
    #: one parameter at a time from there), for effects with more parameters than a grid
    #: can search: () fits them all together.
    stages: tuple[tuple[str, ...], ...] = ()
    #: Values a controller's documentation gives: (parameter, value, where it is documented).
    #: ``ncperf calibrate`` writes the documented value when its fitted range includes it.
    documented: tuple[tuple[str, float, str], ...] = ()
    #: How many parameters a fitted effect really uses (the size of the explanation the
    #: decision rule compares), from its values; None: those moved from where the fit
    #: started. For parameterisations with redundancy (a uniform scale and per-axis factors).
    size: Callable[[Mapping[str, float]], int] | None = field(default=None, repr=False)
    #: The effect is a limit the rapids meet as the feed moves do (an axis's speed or
    #: acceleration, a path speed cap): where the feed moves show no effect, the diagnosis
    #: fits it on the rapids (:mod:`core.diagnosis.diagnose`). Feed overrides, tolerances,
    #: block times are not: they leave the rapids alone or do not show there.
    rapids: bool = False

    def folded(self, machine: Machine) -> dict[str, float]:
        """The parameters the machine's ``[effects.NAME]`` table gives (defaults filled in),
        or {} when it has none."""
        for name, params, _ in machine.effects:
            if name == self.name:
                return self.defaults(machine) | {k: float(v) for k, v in params.items()}
        return {}

    def start(self, machine: Machine) -> dict[str, float]:
        """Where a fit starts, the values that change nothing on top of ``machine``: the
        defaults, or the machine's folded values for an effect that sets them."""
        folded = self.folded(machine)
        return self.defaults(machine) | {k: v for k, v in folded.items() if k not in self.relative}

    def defaults(self, machine: Machine) -> dict[str, float]:
        return {p.name: p.default_for(machine) for p in self.params}

    def check(self, values: Mapping[str, float], *, where: str = "") -> dict[str, float]:
        """Complete and bound-check parameter values; errors name the effect and parameter."""
        known = {p.name: p for p in self.params}
        out = {}
        for key, value in values.items():
            if key not in known:
                names = ", ".join(known) or "none"
                raise UsageError(
                    f"{where}effect {self.name} has no parameter '{key}' (parameters: {names})"
                )
            p = known[key]
            if not (p.low <= float(value) <= p.high):
                raise UsageError(
                    f"{where}{self.name}.{key} = {value:g} is outside "
                    f"[{p.low:g}, {p.high:g}] {p.unit}".rstrip()
                )
            out[key] = float(round(value)) if p.integer else float(value)
        return out


def setup_for(machine: Machine, effects: Mapping[str, Effect], *, ramps: bool = True) -> Setup:
    """The Setup of a machine with the effects its file switches on."""
    setup = Setup(machine=machine, ramps=ramps)
    for name, params, line in machine.effects:
        if name not in effects:
            raise MachineError(
                f"unknown effect '{name}' (effects: {', '.join(sorted(effects))})",
                source=machine.source,
                line=line,
            )
        eff = effects[name]
        try:
            vals = eff.defaults(machine) | eff.check(params)
        except UsageError as exc:
            raise MachineError(exc.message, source=machine.source, line=line) from None
        setup = eff.apply(setup, vals)
    return setup


def scale_machine(
    machine: Machine,
    *,
    accel: float | NDArray[np.float64] = 1.0,
    jerk: float | NDArray[np.float64] = 1.0,
    feed: float | NDArray[np.float64] = 1.0,
) -> Machine:
    """The machine with its axis limits scaled (a scale, or one per axis X, Y, Z)."""
    return dataclasses.replace(
        machine,
        max_acceleration=machine.max_acceleration * np.asarray(accel, dtype=np.float64),
        max_jerk=machine.max_jerk * np.asarray(jerk, dtype=np.float64),
        max_feed=machine.max_feed * np.asarray(feed, dtype=np.float64),
    )


def arc_caps(tp: ToolPath, machine: Machine, *, jerk: bool = True) -> NDArray[np.float64]:
    """(n,) centripetal feed limit of every programmed arc (mm/s), inf elsewhere.

    On an arc of radius R at speed v the normal acceleration is v^2 / R and the jerk
    v^3 / R^2 (the paper's eq. 2-3 for model 1's arc). Per axis, as in model 1:
    v <= min_k sqrt(f A_k R / n_k) (and cbrt(J_k R^2 / t_k) with ``jerk``), with n_k and t_k
    the axis's largest share of the normal and of the tangent over the arc and f the
    machine's normal-acceleration share.
    """
    out = np.full(tp.n, np.inf)
    a = np.flatnonzero(tp.is_arc)
    if a.size == 0:
        return out
    n = tp.normal[a]
    u0 = g.unit(g.radial(tp.start[a], tp.center[a], n))
    ccw = (tp.kind[a] == MoveKind.ARC_CCW)[:, None]
    w0 = np.where(ccw, np.cross(n, u0), -np.cross(n, u0))
    share_n = g.max_share(u0, w0, tp.sweep[a][:, None])
    radius = 1.0 / np.abs(tp.curvature[a])
    acc = machine.max_acceleration * machine.normal_acceleration_factor
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        v = np.where(share_n > 0, np.sqrt(acc * radius[:, None] / share_n), np.inf).min(axis=1)
        if jerk:
            share_t = tp.axis_share[a]
            v_j = np.where(
                share_t > 0, np.cbrt(machine.max_jerk * radius[:, None] ** 2 / share_t), np.inf
            )
            v = np.minimum(v, v_j.min(axis=1))
    out[a] = v
    return out
