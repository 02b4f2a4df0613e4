"""A prediction built from a :class:`~core.engine.effects.Setup`: the paper's models, the effects
switched on, and (with ramps) the feed profile -- as a speed over arc length and over time,
for comparison with measured traces (see :mod:`core.engine.effects` for the steps)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from core.engine.effects import Setup
from core.engine.indicators import Evaluation, Indicator, IndicatorSource, combine
from core.engine.profile import Profile, RoundsMemo, build_profile
from core.model.arrays import same_bits
from core.model.jit import compiled
from core.model.sampling import PROJECTION_STEP, isotonic
from core.model.tolerances import TOL
from core.model.toolpath import PathMode, ToolPath

#: Time step of the predicted signal when time-domain effects are on (s); longer programs
#: get a coarser step so that the signal stays under MAX_SAMPLES.
SIGNAL_DT = 0.001
MAX_SAMPLES = 400_000
#: Filtered motions (:attr:`Prediction._filtered`) the predictions of one plan keep, the
#: most recent: a fit's candidates whose filters come to the same samples (a window that
#: rounds to the same count) take the kept one instead of filtering and projecting again.
FILTERED_KEPT = 4


@dataclass(frozen=True, eq=False)
class Prediction:
    """Predicted speed along the path.

    Attributes
    ----------
    setup : Setup
    evaluation : Evaluation
    profile : Profile or None
        None for the paper's point model (no ramps).
    path : ToolPath or None
        The tool path as given, before the setup scaled its feeds or replaced its
        tolerances (the same geometry as ``evaluation.toolpath``): where filtered positions
        are placed on the path, so that every prediction of one program shares one sampling
        of it. None: the evaluation's.
    """

    setup: Setup
    evaluation: Evaluation
    profile: Profile | None
    path: ToolPath | None = None
    #: What predictions of one plan (:func:`retimed`) share: the unfiltered signal and
    #: its places on the path, computed once for all of them.
    shared: dict = dataclasses.field(default_factory=dict, repr=False)

    @property
    def toolpath(self) -> ToolPath:
        return self.evaluation.toolpath

    @cached_property
    def block_speed(self) -> NDArray[np.float64]:
        """(n,) each block's own predicted feed; rapids at the axes' max feed."""
        tp = self.toolpath
        v = self.evaluation.element_feed.copy()
        rapid = ~tp.is_feed
        if rapid.any():
            v[rapid] = self.setup.machine.rapid_speed(tp.tangent_start[rapid])
        return v

    def _raw_speed_at(self, s: NDArray[np.float64]) -> NDArray[np.float64]:
        if self.profile is not None:
            v = self.profile.speed_at(s)
            if self.evaluation.junction_blend is not None:
                v = self._through_overlaps(s, v)
            return v
        k = self.toolpath.move_at(s)
        return self.block_speed[k]

    @cached_property
    def _overlaps(self) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """(junctions, blend speeds, a_p, a_n) of the junctions the planner runs as an
        overlap of the two segments (:data:`core.engine.indicators.BLEND_SPEED`), ascending;
        made once per prediction, read by every :meth:`_through_overlaps`. The profile
        crosses such a junction at the speed that costs the overlap's time; the blend speed
        is taken lower alike where the profile's look-ahead crosses it lower than the
        evaluation."""
        ev, pr = self.evaluation, self.profile
        assert ev.junction_blend is not None and pr is not None
        have = np.flatnonzero(np.isfinite(ev.junction_blend))
        jj = ev.junction[have]
        u = ev.junction_feed[have]
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = np.where(u > 0.0, np.clip(pr.v_exit[jj] / u, 0.0, 1.0), 0.0)
        return jj, ev.junction_blend[have] * scale, pr.a_down[jj], pr.a_up[jj + 1]

    def _through_overlaps(self, s: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray:
        """The speeds ``v`` at arc lengths ``s`` with those near junctions the planner runs
        as an overlap of the two segments (:attr:`_overlaps`) as a trace shows them
        (:func:`overlap_column`)."""
        jj, v_b, a_p, a_n = self._overlaps
        if jj.size == 0:
            return v
        tp = self.toolpath
        k = tp.move_at(s)
        v = v.copy()
        for before in (True, False):
            # samples on the move before a blend (it ends there) or after one (it starts)
            at = k if before else k - 1
            i = np.minimum(np.searchsorted(jj, at), jj.size - 1)
            sel = np.flatnonzero(jj[i] == at)
            if sel.size == 0:
                continue
            ii, kk = i[sel], k[sel]
            if before:
                into = tp.start_s[kk] + tp.length[kk] - s[sel]
            else:
                into = s[sel] - tp.start_s[kk]
            col, inside = overlap_column(
                np.maximum(into, 0.0), v_b[ii], a_p[ii], a_n[ii], before=before
            )
            v[sel] = np.where(inside, col, np.fmin(v[sel], col))
        return v

    @cached_property
    def _filtered(self) -> tuple[NDArray, NDArray, NDArray, NDArray] | None:
        """(t, s, v, v_commanded) of the motion as a trace of the filtered positions shows
        it, or None without time-domain effects.

        The filters act on the positions, axis by axis, as a controller's setpoint filter
        and a position loop do: a centred moving average over ``filter_window``, then a
        first-order lag ``servo_tau``. The result is then read as a measured trace is
        (:mod:`core.diagnosis.align`): its place on the path is the projection of the
        filtered positions; its speed ``v`` is theirs -- at a corner or on an arc they cut
        inside the path, and their speed dips more than the filtered path speed would --
        and ``v_commanded`` is the speed a trace's commanded-feed column shows (read where
        the alignment took a trace's column as the commanded feed): the planner's path
        speed through the setpoint filter alone, in time (on a circle it stays the
        programmed feed while the filtered positions run a smaller circle more slowly; the
        position loop's lag is behind the command and does not reach it; through a junction
        the planner runs as an overlap of two segments, their speeds' sum:
        :meth:`_through_overlaps`).
        """
        su = self.setup
        if su.servo_tau <= 0 and su.filter_window <= 0:
            return None
        tp = self.path if self.path is not None else self.toolpath
        raw = self.shared.get("raw")
        if raw is None:
            t, s, v_raw = self.signal(raw=True)
            raw = self.shared["raw"] = (t, s, tp.point_at(s), v_raw)
        t, s, pos, v_raw = raw
        dt = t[1] - t[0] if t.size > 1 else SIGNAL_DT
        # Rest before and after, long enough for the filters' tails to carry the distance.
        head = int(np.ceil(0.5 * su.filter_window / dt)) + 1
        tail = head + int(np.ceil(8.0 * su.servo_tau / dt)) + 1
        k = max(int(round(su.filter_window / dt)), 1) if su.filter_window > 0 else 1
        # What the rest depends on besides the shared signal: setups of one plan whose
        # filters round to the same samples (a fit's window candidates) move alike.
        key = (head, tail, k, np.float64(su.servo_tau).tobytes())
        kept: dict = self.shared.setdefault("filtered", {})
        if key in kept:
            return kept[key]
        if self.evaluation.junction_blend is not None:
            # the planner's speed as its column shows it through overlaps of two segments
            v_raw = self._through_overlaps(s, v_raw)
        s = np.concatenate([np.full(head, s[0]), s, np.full(tail, s[-1])])
        t = (np.arange(s.size) - head) * dt + t[0]
        # (the points of the padded arc lengths: those of the ends repeated)
        pos = np.concatenate([np.repeat(pos[:1], head, 0), pos, np.repeat(pos[-1:], tail, 0)])
        # the planner's speed over the same times: at rest before and after
        v_cmd = np.concatenate([np.zeros(head), v_raw, np.zeros(tail)])
        if k > 1:
            # the positions and that speed, column by column, each end repeated (the speed's
            # ends are rest: it is padded with rest)
            kernel = np.ones(k) / k
            cols = np.column_stack([pos, v_cmd])
            pad = np.concatenate([np.repeat(cols[:1], k, 0), cols, np.repeat(cols[-1:], k, 0)])
            cols = np.column_stack(
                [np.convolve(pad[:, j], kernel, mode="same")[k:-k] for j in range(4)]
            )
            pos, v_cmd = cols[:, :3], cols[:, 3]
        if su.servo_tau > 0:
            a = np.exp(-dt / su.servo_tau)
            pos = _first_order(pos, a)
        v = _path_speed(pos, dt)
        # Where the filtered positions are on the path: near the setpoint of tau earlier
        # (within a millimetre of it).
        guess = np.interp(t - su.servo_tau, t, s)
        s_obs, _ = tp.sample(PROJECTION_STEP).project_near(pos, guess, half_width=1.0)
        out = t, isotonic(s_obs), v, v_cmd
        kept[key] = out
        while len(kept) > FILTERED_KEPT:
            del kept[next(iter(kept))]  # the oldest
        return out

    def unshared(self) -> Prediction:
        """This prediction without what the predictions of its plan share (the unfiltered
        signal, the filtered motions of other setups: 50 MB a fit of a servo lag on the
        diagnose benchmark), its own filtered motion kept: the same speeds and signal, for
        sending to another process. Whatever else is asked of it is made again, the
        same."""
        out = dataclasses.replace(self, shared={})
        if "_filtered" in self.__dict__:  # (cached_property's place)
            out.__dict__["_filtered"] = self.__dict__["_filtered"]
        return out

    def signal(self, *, raw: bool = False) -> tuple[NDArray, NDArray, NDArray]:
        """(t, s, v) of the predicted motion sampled in time (s, mm, mm/s)."""
        if not raw and self._filtered is not None:
            return self._filtered[:3]
        tp = self.toolpath
        if self.profile is not None:
            dt = max(SIGNAL_DT, self.profile.cycle_time / MAX_SAMPLES)
            smp = self.profile.sample(dt)
            return smp.t, smp.s, smp.v
        # The paper's point model as motion: each block at its own speed.
        v = self.block_speed
        dur = tp.length / v
        t_edges = np.concatenate([[0.0], np.cumsum(dur)])
        dt = max(SIGNAL_DT, float(t_edges[-1]) / MAX_SAMPLES)
        t = np.arange(0.0, t_edges[-1], dt)
        k = np.clip(np.searchsorted(t_edges, t, side="right") - 1, 0, tp.n - 1)
        s = tp.start_s[k] + (t - t_edges[k]) * v[k]
        return t, s, v[k]

    def speed_at(self, s: ArrayLike, *, commanded: bool = False) -> NDArray[np.float64]:
        """Predicted speed (mm/s) at arc lengths ``s`` (mm): that of the filtered positions,
        or with ``commanded`` what a trace's commanded-feed column shows (see
        :attr:`_filtered`; the two differ only with time-domain effects)."""
        s = np.asarray(s, dtype=np.float64)
        f = self._filtered
        if f is None:
            return self._raw_speed_at(s)
        _, ss, v_pos, v_cmd = f
        vv = v_cmd if commanded else v_pos
        keep = np.concatenate([[True], np.diff(ss) > TOL.same_s])
        return np.interp(s, ss[keep], vv[keep])

    @cached_property
    def cycle_time(self) -> float:
        """Predicted time (s): the profile's, or the point model's blocks plus dwells."""
        if self.profile is not None:
            return self.profile.cycle_time
        tp = self.toolpath
        return float(np.sum(tp.length / self.block_speed) + tp.dwell.sum())


def overlap_column(
    d: ArrayLike, v_b: ArrayLike, a_p: ArrayLike, a_n: ArrayLike, *, before: bool
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """The speed a trace's feed column shows at distance ``d`` (mm) before (``before``) or
    after a junction the planner runs as an overlap (LinuxCNC's parabolic blend, tp.c
    ``tpDoParabolicBlending``), and whether that place is inside the overlap.

    The segment before brakes at ``a_p`` (mm/s^2) to rest at the junction; when it is down
    to its blend speed ``v_b`` (mm/s), d_b = v_b^2 / (2 a_p) before the junction, the
    segment after starts from rest at ``a_n`` and the column shows the sum of the two
    speeds (``current_vel = tc->currentvel + nexttc->currentvel``, tp.c v2.9.8 line 3064)
    until the first stops, t_b = v_b / a_p later. A place is read as the distance the
    segment it lies on has left (before) or run (after) -- a trace's positions projected
    on the path at a right-angle corner; at other angles near enough:

    - before, d > d_b: the first alone, sqrt(2 a_p d);
    - before, d <= d_b: v1 = sqrt(2 a_p d) at t = (v_b - v1) / a_p into the overlap,
      the column v1 + a_n t;
    - after, t = sqrt(2 d / a_n) < t_b: the column v_b - a_p t + a_n t;
    - after, past the overlap: the second alone, a_n t = sqrt(2 a_n d).

    Outside the overlap this is the profile of a stop at the junction: the profile's own
    speed, which crosses it at the speed that costs the same time, is higher there and the
    caller takes the lower of the two."""
    d = np.asarray(d, dtype=np.float64)
    v_b, a_p, a_n = (np.asarray(x, dtype=np.float64) for x in (v_b, a_p, a_n))
    with np.errstate(divide="ignore", invalid="ignore"):
        if before:
            v1 = np.sqrt(2.0 * a_p * d)
            inside = v1 < v_b
            col = np.where(inside, v1 + a_n * (v_b - v1) / a_p, v1)
        else:
            t = np.sqrt(2.0 * d / a_n)
            inside = t < v_b / a_p
            col = np.where(inside, v_b + (a_n - a_p) * t, a_n * t)
    ok = np.isfinite(col)
    return np.where(ok, col, np.inf), inside & ok


def _path_speed(pos: NDArray[np.float64], dt: float) -> NDArray[np.float64]:
    """The speed of (m, 3) positions sampled every ``dt`` s: the norm of their gradient in
    time (central differences, one-sided at the ends)."""
    kernels = compiled()
    if kernels is not None and pos.shape[0] >= 2:  # the same operations point by point
        return kernels.path_speed(np.ascontiguousarray(pos), dt)
    return np.linalg.norm(np.gradient(pos, dt, axis=0), axis=1)


def _first_order(v: NDArray[np.float64], a: float) -> NDArray[np.float64]:
    """y[k] = a y[k-1] + (1 - a) v[k], y[0] = v[0], vectorised in blocks of a few thousand;
    ``v`` (m,) or (m, columns), each column on its own."""
    if a < TOL.negligible_pole or v.shape[0] == 0:
        return v.copy()
    out = np.empty_like(v)
    y = v[0].copy()
    n = v.shape[0]
    # a^-block must stay far from overflow: a^-block < e^25.
    block = int(max(1, min(2048, 25.0 / -np.log(a))))
    powers = a ** np.arange(1, block + 1)
    inverse = a ** np.arange(1, block + 1)
    kernels = compiled()
    if kernels is not None and v.ndim == 2:  # the same blocks element by element
        return kernels.first_order(np.ascontiguousarray(v), a, powers, inverse)
    if v.ndim == 2:
        powers, inverse = powers[:, None], inverse[:, None]
    for c in range(0, n, block):
        x = v[c : c + block]
        m = x.shape[0]
        p = powers[:m]
        # y_k = a^k y0 + (1 - a) sum_{i<=k} a^(k-i) x_i
        w = (1.0 - a) * x / inverse[:m]
        out[c : c + m] = p * (y + np.cumsum(w, axis=0))
        y = out[c + m - 1].copy()
    return out


def compression_runs(tp: ToolPath, max_angle: float, max_length: float) -> NDArray[np.bool_]:
    """(n - 1,) junctions inside runs a compressor merges: both blocks shorter than
    ``max_length`` (mm), feed moves of one operation, turning by less than ``max_angle`` (rad)."""
    if tp.n < 2:
        return np.zeros(0, dtype=bool)
    short = tp.is_feed & (tp.length < max_length)
    inside = np.zeros(tp.n - 1, dtype=bool)
    inside[tp.junctions] = True
    return inside & short[:-1] & short[1:] & (tp.turn_angle < max_angle)


#: The setup's fields that act on the motion in time only (:attr:`Prediction._filtered`):
#: the plan -- evaluation and profile -- does not depend on them.
TIME_DOMAIN = frozenset({"servo_tau", "filter_window"})


def _same(a: object, b: object) -> bool:
    """Whether two setup or evaluation values are certainly the same: one object, equal
    numbers of one type and sign, equal strings, arrays of one dtype and shape with the same
    bytes (NaNs and signed zeros included), tuples element by element."""
    if a is b:
        return True
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray) and isinstance(b, np.ndarray):
        return same_bits(a, b)
    if type(a) is type(b) and type(a) in (int, float, bool):
        return bool(a == b) and math.copysign(1.0, a) == math.copysign(1.0, b)  # type: ignore[arg-type]
    return type(a) is type(b) is str and a == b


def same_plan(a: Setup, b: Setup) -> bool:
    """Whether two setups plan the same motion (differ at most in :data:`TIME_DOMAIN`)."""
    return all(
        _same(getattr(a, f.name), getattr(b, f.name))
        for f in dataclasses.fields(a)
        if f.name not in TIME_DOMAIN
    )


def retimed(pred: Prediction, setup: Setup) -> Prediction:
    """The prediction of ``setup``, which plans as ``pred``'s does (:func:`same_plan`): its
    evaluation and profile, and the unfiltered signal shared."""
    if not same_plan(pred.setup, setup):
        raise ValueError("retimed: the setups plan differently")
    return Prediction(
        setup=setup,
        evaluation=pred.evaluation,
        profile=pred.profile,
        path=pred.path,
        shared=pred.shared,
    )


def same_evaluation(a: Evaluation, b: Evaluation) -> bool:
    """Whether two evaluations are the same input to :func:`build_profile`: one tool path
    and one machine (the same objects) and every other field bit for bit the same."""
    if a.toolpath is not b.toolpath or a.machine is not b.machine:
        return False
    return all(
        _same(getattr(a, f.name), getattr(b, f.name))
        for f in dataclasses.fields(a)
        if f.name not in ("toolpath", "machine")
    )


def _profile_of(
    ev: Evaluation, setup: Setup, earlier: Sequence[Prediction], memo: RoundsMemo | None
) -> Profile | None:
    """The profile of ``ev`` under ``setup``: that of an ``earlier`` prediction built from
    the same inputs (:func:`same_evaluation`, the same look-ahead, end and arc factors) --
    build_profile is a function of them alone, so its columns are the ones a new build
    gives -- with ``ev`` as its evaluation; else built (with ``memo``, the last rounds)."""
    if not setup.ramps:
        return None
    for old in reversed(earlier):
        su = old.setup
        if (
            old.profile is not None
            and su.ramps
            and _same(su.lookahead, setup.lookahead)
            and _same(su.end_factor, setup.end_factor)
            and _same(su.arc_factor, setup.arc_factor)
            and same_evaluation(old.evaluation, ev)
        ):
            return dataclasses.replace(old.profile, evaluation=ev)
    return build_profile(
        ev,
        lookahead=setup.lookahead,
        end_factor=setup.end_factor,
        arc_factor=setup.arc_factor,
        memo=memo,
    )


def predict(
    indicators_of: IndicatorSource,
    tp: ToolPath,
    setup: Setup,
    earlier: Sequence[Prediction] = (),
    memo: RoundsMemo | None = None,
) -> Prediction:
    """The prediction of ``setup`` on ``tp`` (see :mod:`core.engine.effects` for the steps).

    Parameters
    ----------
    indicators_of : callable (ToolPath, Machine) -> list of Indicator
        The A2 evaluation (every registered plugin's indicators), e.g.
        :meth:`core.facade.Ncperf.indicators`.
    tp : ToolPath
    setup : Setup
    earlier : sequence of Prediction
        Predictions made before (a fit's recent candidates): where one was built from the
        same evaluation, its profile is taken, not built again (the same values).
    memo : RoundsMemo, optional
        The last jerk rounds of this program's profiles (a fit's): where a profile's rounds
        have the same inputs, their outcome is taken (:func:`core.engine.profile.build_profile`).
    """
    tp2 = tp
    if setup.feed_scale != 1.0:
        tp2 = dataclasses.replace(tp2, feed=tp.feed * setup.feed_scale)
    if setup.tolerance is not None:
        tp2 = dataclasses.replace(tp2, tolerance=np.full(tp.n, float(setup.tolerance)))
    if setup.exact_stop:
        exact = np.full(tp.n, PathMode.EXACT_STOP, dtype=np.int8)
        tp2 = dataclasses.replace(tp2, path_mode=exact)
    m = setup.machine
    indicators = indicators_of(tp2, m)
    for extra in setup.element_caps:
        cap = np.asarray(extra.limit(tp2, m), dtype=np.float64)
        idx = np.flatnonzero(tp2.is_feed & np.isfinite(cap))
        indicators.append(
            Indicator(
                name=extra.indicator,
                at="element",
                index=idx,
                feed=cap[idx],
                limit=np.zeros(idx.size, dtype=np.int64),
                labels=(extra.label,),
            )
        )
    if setup.compression is not None:
        merged = compression_runs(tp2, *setup.compression)
        # A merged run becomes one segment (a spline): its blocks lose their own block-time
        # cap, the run as a whole gets L_run / t_int; merged junctions lose their limits.
        blocks = np.zeros(tp2.n, dtype=bool)
        blocks[:-1] |= merged
        blocks[1:] |= merged
        kept = []
        for ind in indicators:
            if ind.at == "junction":
                keep = ~merged[ind.index]
            else:
                keep = ~(blocks[ind.index] & (ind.name == "ncu_capacity"))
            if keep.all():
                kept.append(ind)
                continue
            kept.append(
                dataclasses.replace(
                    ind,
                    index=ind.index[keep],
                    feed=ind.feed[keep],
                    limit=ind.limit[keep],
                    values={k: np.asarray(v)[keep] for k, v in ind.values.items()},
                )
            )
        idx = np.flatnonzero(blocks)
        if idx.size:
            # Runs: consecutive blocks joined by merged junctions.
            starts = np.ones(idx.size, dtype=bool)
            starts[1:] = ~((idx[1:] == idx[:-1] + 1) & merged[idx[:-1]])
            run = np.cumsum(starts) - 1
            run_len = np.bincount(run, weights=tp2.length[idx])
            kept.append(
                Indicator(
                    name="ncu_capacity",
                    at="element",
                    index=idx,
                    feed=run_len[run] / m.interpolation_time,
                    limit=np.zeros(idx.size, dtype=np.int64),
                    labels=("block time (compressed run)",),
                )
            )
        indicators = kept
    if setup.cap_scale != 1.0:
        indicators = [
            dataclasses.replace(ind, feed=ind.feed * setup.cap_scale) for ind in indicators
        ]
    ev = combine(tp2, m, indicators)
    profile = _profile_of(ev, setup, earlier, memo)
    return Prediction(setup=setup, evaluation=ev, profile=profile, path=tp)
