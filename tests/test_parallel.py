"""Fits and alignment on worker processes (issue 13, ``--jobs``): the same diagnosis,
calibration and alignment, to the bit, as one task after the other; one after the other
where a process may not fork (a pool's worker); ``--jobs`` below 1 refused in one line.

The case: the zigzag recorded with a feed override of 0.8 and a 50 ms block time, so that
the diagnosis names one effect and the forward selection adds the other (both loops of
fits run on workers), with seven effects: 0.7 s one after the other.
"""

from __future__ import annotations

import dataclasses
import json
import multiprocessing

import numpy as np
import pytest

from core import Ncperf, make_plugin_manager
from core.diagnosis.align import align
from core.diagnosis.diagnose import Diagnosis
from core.diagnosis.parallel import fit_each
from core.engine.effects import Setup
from core.model.workers import can_fork, default_jobs
from tests.conftest import machine
from tests.test_diagnose import synthetic_trace, zigzag

INF = float("inf")

needs_fork = pytest.mark.skipif(
    "fork" not in multiprocessing.get_all_start_methods(), reason="no fork start method here"
)


def _case(nc: Ncperf) -> tuple:
    """The zigzag, its trace with an override and a block time aligned, the start setup."""
    tp = zigzag()
    m = machine(jerk=(INF, INF, INF))
    effects = nc.effects()
    base = Setup(machine=m)
    truth = effects["feed_override"].apply(base, {"scale": 0.8, "caps": 0.0})
    truth = effects["block_cycle_time"].apply(truth, {"t_block": 0.05})
    return tp, align(tp, synthetic_trace(nc, tp, truth)), base


#: The effects diagnosed: the two of the trace, and others that nearly fit it (the fits of
#: a stop at every corner and of per-axis dynamics are the longest).
EFFECTS = (
    "feed_override",
    "block_cycle_time",
    "corner_tolerance",
    "exact_stop",
    "lookahead_depth",
    "servo_lag",
    "axis_dynamics",
)


def _diagnosed(jobs: int) -> tuple[Diagnosis, list[str]]:
    nc = Ncperf(make_plugin_manager(entry_points=False))
    tp, al, base = _case(nc)
    effects = {k: nc.effects()[k] for k in EFFECTS}
    lines: list[str] = []
    d = nc.diagnose([(tp, [al], ["t"])], base, "profile", effects, lines.append, jobs=jobs)
    return d, lines


@pytest.fixture(scope="module")
def serial() -> tuple[Diagnosis, list[str]]:
    """The diagnosis with one fit after the other, and its progress lines."""
    return _diagnosed(1)


def _bits(x: object) -> object:
    """``x`` with every float and array as its exact bits (equal only when identical)."""
    if isinstance(x, float):
        return x.hex()
    if isinstance(x, np.ndarray):
        return (x.dtype.str, x.shape, x.tobytes())
    if isinstance(x, dict):
        return {k: _bits(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_bits(v) for v in x]
    return x


def fingerprint(d: Diagnosis) -> object:
    """Everything a diagnosis decides and reports, to the bit: the effects in rank order
    (parameters, gaps, p values, held-out pieces, rapids), the named and chosen effects,
    the gaps and zones, the prediction after (its speed on the data) and the JSON report."""
    from core.cli.diagnosis_report import to_json

    effects = [
        (r.name, r.params, r.held_out_gap_before, r.held_out_gap_after)
        + (r.calibration_gap_after, r.moved, r.p, r.chunk_sq, r.rapid_gap)
        for r in d.effects
    ]
    after = [d.afters[0].speed_at(x.s) for x in d.data]
    summary = (d.best_effect, d.chosen, d.chosen_params, d.gap_rms_before, d.gap_rms_after)
    return _bits(
        [effects, summary, d.floor, d.reason, after, json.dumps(to_json(d), sort_keys=True)]
    )


@needs_fork
def test_fits_on_two_processes_give_the_diagnosis_of_one(serial):
    serial, lines_1 = serial
    assert serial.best_effect == "block_cycle_time"
    assert serial.chosen == ("block_cycle_time", "feed_override")  # the selection ran too
    parallel, lines_2 = _diagnosed(2)
    assert fingerprint(parallel) == fingerprint(serial)
    # the fits did run on workers: their progress says so, as each ended
    n = len(serial.effects)
    assert f"fitting {n} effects on 2 processes" in lines_2
    assert sum(x.startswith("fitted ") for x in lines_2) == n
    assert any(x.startswith("combining effects: fitted ") for x in lines_2)
    assert not any("processes" in x or "fitted" in x for x in lines_1)
    assert f"fitting feed_override (1 of {n} effects)" in lines_1


@needs_fork
def test_fit_each_returns_the_effects_in_their_order():
    """The longest fits are sent first, the results come back in the order of the effects."""
    nc = Ncperf(make_plugin_manager(entry_points=False))
    tp, al, base = _case(nc)
    from core.diagnosis.resample import resample, split

    data, _ = split([resample(tp, al, "t")])
    effects = nc.effects()
    few = {k: effects[k] for k in ("feed_override", "axis_dynamics", "exact_stop")}
    one = fit_each(nc.indicators, [tp], base, few, data, jobs=1)
    two = fit_each(nc.indicators, [tp], base, few, data, jobs=3)
    assert list(two) == list(few) == list(one)
    for name in few:
        assert _bits(two[name][0]) == _bits(one[name][0])
        # the parent's own path, not a copy, where a fit in the parent gives it
        assert (two[name][1][0].toolpath is tp) == (one[name][1][0].toolpath is tp)
        assert (two[name][1][0].path is tp) == (one[name][1][0].path is tp)
        s = data[0].s
        assert _bits(two[name][1][0].speed_at(s)) == _bits(one[name][1][0].speed_at(s))


def test_fits_start_longest_first(monkeypatch):
    """The order the fits start in: by the candidates each search lays out (a 1-D grid of
    11 points, 8 refinement rounds of two trials and the defaults check: 1 + 11 + 17 = 29;
    block_cycle_time's 31 points: 49; two parameters on a 6 x 6 grid, then both 11-point
    lines and their refinement: 1 + 36 + 22 + 34 = 93), a candidate of an effect that
    acts in time only (a servo lag: one plan, the motion filtered again) weighing
    FILTERED_COST; and no fit scores more candidates than laid out."""
    import core.diagnosis.fit as fit_module
    from core.diagnosis import parallel
    from core.diagnosis.fit import scores_planned

    nc = Ncperf(make_plugin_manager(entry_points=False))
    effects = nc.effects()
    tp, al, base = _case(nc)
    assert scores_planned(effects["exact_stop"]) == 1
    assert scores_planned(effects["corner_tolerance"]) == 29
    assert scores_planned(effects["block_cycle_time"]) == 49
    assert scores_planned(effects["feed_override"]) == 93
    assert parallel.cost(effects["servo_lag"], base) == 29 * parallel.FILTERED_COST
    assert parallel.cost(effects["corner_tolerance"], base) == 29

    from core.diagnosis.resample import resample, split

    data, _ = split([resample(tp, al, "t")])
    scored: dict[str, int] = {}
    real_fit = fit_module.fit

    def counted(indicators_of, tps, base_, eff, data_, objective=fit_module.FEED):
        seen = set()
        real_apply = eff.apply

        def apply(setup, values):
            seen.add(tuple(sorted(values.items())))
            return real_apply(setup, values)

        out = real_fit(indicators_of, tps, base_, dataclasses.replace(eff, apply=apply), data_)
        scored[eff.name] = len(seen)
        return out

    monkeypatch.setattr(parallel, "fit", counted)
    started: list[int] = []

    def in_turn(fn, count, workers, *, order=None, shared=(), done=None):
        started.extend(order)
        return [fn(k) for k in range(count)]

    monkeypatch.setattr(parallel, "forked_map", in_turn)
    names = ("exact_stop", "corner_tolerance", "feed_override", "servo_lag", "axis_dynamics")
    few = {k: effects[k] for k in names}
    fit_each(nc.indicators, [tp], base, few, data, jobs=2)
    assert [names[k] for k in started] == [
        "axis_dynamics", "servo_lag", "feed_override", "corner_tolerance", "exact_stop"
    ]  # fmt: skip
    for name, eff in few.items():
        assert 1 <= scored[name] <= scores_planned(eff), name


def _in_a_worker(jobs: int) -> tuple[object, list[str], bool]:
    d, lines = _diagnosed(jobs)
    return fingerprint(d), lines, can_fork()


@needs_fork
def test_a_pool_worker_fits_in_turn(serial):
    """A multiprocessing pool's worker may not have children (benchmarks/blind_linuxcnc.py
    diagnoses in a pool): asked for two jobs, it fits one effect after the other."""
    with multiprocessing.get_context("fork").Pool(1) as pool:
        got, lines, forks = pool.apply(_in_a_worker, (2,))
    assert not forks
    assert not any("processes" in x for x in lines)
    assert got == fingerprint(serial[0])


@needs_fork
def test_calibration_on_two_processes_is_the_calibration_of_one():
    """A block time and an override: the selection's rounds and the override's two
    parameters' range scans run on workers, to the same machine."""
    from tests.test_calibrate import cases_for, square_spiral

    nc = Ncperf(make_plugin_manager(entry_points=False))
    m = machine(jerk=(INF, INF, INF))
    effects = nc.effects()
    truth = effects["block_cycle_time"].apply(Setup(machine=m), {"t_block": 0.03})
    truth = effects["feed_override"].apply(truth, {"scale": 0.8, "caps": 0.0})
    cases = cases_for(nc, truth, (zigzag(), square_spiral()))
    wanted = {k: effects[k] for k in ("block_cycle_time", "corner_tolerance", "feed_override")}
    cals = [nc.calibrate(cases, Setup(machine=m), wanted, jobs=j) for j in (1, 2)]
    one, two = (
        _bits(
            [
                [
                    (c.name, c.params, c.folds, c.ranges, c.gap_before, c.gap_after)
                    for c in cal.effects
                ]
                + [cal.gap_before, cal.gap_after, cal.noise_floor]
            ]
        )
        for cal in cals
    )
    assert {c.name for c in cals[0].effects} == {"block_cycle_time", "feed_override"}
    assert two == one


@needs_fork
def test_alignment_on_two_processes_is_the_alignment_of_one(monkeypatch):
    """numpy's search (without the compiled kernels, core.model.jit) projects the samples
    of each program line on workers, pieces of lines each: the same arc lengths and
    distances to the bit, of the projection itself (the refinement after it would hide a
    difference) and of the alignment. (The kernel searches in this process:
    tests/test_jit.py checks it against numpy's.)"""
    import core.diagnosis.align as alignment
    from core.model.jit import NO_JIT_ENV

    monkeypatch.setenv(NO_JIT_ENV, "1")

    nc = Ncperf(make_plugin_manager(entry_points=False))
    tp = zigzag()
    tr = synthetic_trace(nc, tp, Setup(machine=machine(jerk=(INF, INF, INF))))
    tr = dataclasses.replace(tr, pos=tr.pos + np.array([0.3, -0.2, 0.0]))  # an offset too
    pieces, projected = [], []

    def counted(fn, count, workers, **kw):
        pieces.append((count, workers))
        return workers_map(fn, count, workers, **kw)

    def kept(tp, q, lines, path, jobs=1):
        out = project(tp, q, lines, path, jobs)
        projected.append(_bits(out))  # the offset's fit projects first, every sample last
        return out

    workers_map, project = alignment.forked_map, alignment._project
    monkeypatch.setattr(alignment, "forked_map", counted)
    monkeypatch.setattr(alignment, "_project", kept)
    one = align(tp, tr, jobs=1)
    last = projected[-1]
    two = align(tp, tr, jobs=2)
    assert projected[-1] == last
    # only the second ran on workers, in pieces of lines (up to LINE_PIECES a worker)
    ((count, workers),) = pieces
    assert workers == 2 and 2 < count <= 2 * alignment.LINE_PIECES
    for f in ("s", "v", "t", "line", "offset", "distance"):
        assert _bits(getattr(two, f)) == _bits(getattr(one, f))
    assert (two.coverage, two.far_share, two.message) == (one.coverage, one.far_share, one.message)
    assert np.linalg.norm(one.offset - [0.3, -0.2, 0.0]) < 0.05


@needs_fork
def test_a_task_that_fails_or_a_worker_that_dies_is_an_error_not_a_wait():
    """A task's exception comes back as itself; a worker killed (as the out-of-memory killer
    does, SIGKILL) is a MemoryError within POLL_S, not a wait for a result that never comes
    (a pool replaces the worker and loses its task)."""
    import os
    import signal
    import time

    from core.model.workers import POLL_S, forked_map

    def fails(k: int) -> int:
        if k == 2:
            raise ValueError(f"task {k} fails")
        return k * k

    assert forked_map(lambda k: k * k, 5, 2) == [0, 1, 4, 9, 16]
    with pytest.raises(ValueError, match="task 2 fails"):
        forked_map(fails, 5, 2)

    def dies(k: int) -> int:
        if k == 1:
            os.kill(os.getpid(), signal.SIGKILL)
        time.sleep(0.2)
        return k

    def hung(*_: object) -> None:
        raise TimeoutError("forked_map still waits 30 s after its worker died")

    old = signal.signal(signal.SIGALRM, hung)  # a hang fails the test rather than the run
    signal.alarm(30)
    try:
        t0 = time.monotonic()
        with pytest.raises(MemoryError, match="SIGKILL"):
            forked_map(dies, 4, 2)
        assert time.monotonic() - t0 < 10 * POLL_S
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def test_default_jobs_is_the_cpus_this_process_may_use():
    import os

    want = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    assert default_jobs() == max(want or 1, 1)


def _command_case(tmp_path):
    from tests.test_diagnose import synthetic_trace as trace_of

    prog = tmp_path / "p.ngc"
    prog.write_text("G21 G90 G64 P0.01\nG1 X40 F3000\nY20\nX0\nY40\nX40\nM2\n")
    nc = Ncperf()
    from core import load_preset

    tp = nc.extract(str(prog))
    eff = nc.effects()
    truth = eff["feed_override"].apply(Setup(machine=load_preset("linuxcnc-sim")), {"scale": 0.8})
    tr = trace_of(nc, tp, truth)
    csv = tmp_path / "t.csv"
    rows = np.column_stack([tr.t, tr.pos, tr.v, tr.line])
    np.savetxt(
        csv, rows, delimiter=",", header="t,x,y,z,v,line", comments="", fmt=["%.6f"] * 5 + ["%d"]
    )
    return prog, csv


@needs_fork
def test_diagnose_command_jobs(tmp_path, capsys):
    """--jobs 2 and --jobs 1 write the same JSON and report; --jobs 0 or -1 is one line on
    stderr, exit 2, no output."""
    from core.cli import main

    prog, csv = _command_case(tmp_path)
    common = ["diagnose", str(prog), str(csv), "--machine", "linuxcnc-sim", "--json"]
    outs = []
    for jobs in ("1", "2"):
        js = tmp_path / "d.json"  # the same name: the report prints it
        assert main([*common, str(js), "--jobs", jobs]) == 0
        outs.append((capsys.readouterr().out, js.read_bytes()))
        js.unlink()
    assert outs[0] == outs[1] and "best effect      feed_override" in outs[0][0]
    for bad in ("0", "-1"):
        assert main([*common, str(tmp_path / "x.json"), "--jobs", bad]) == 2
        err = capsys.readouterr().err
        assert err == f"ncperf: --jobs must be 1 or more worker processes, got {bad}\n"
        assert not (tmp_path / "x.json").exists()


def test_a_prediction_sent_back_keeps_its_motion_not_its_plans():
    """What a worker sends back of a fit (Prediction.unshared): the prediction's own
    filtered motion, not what the predictions of its plan share (the unfiltered signal,
    the other setups' filtered motions); pickled and read back, the same speeds, commanded
    and not, and the same signal -- its motion not made again."""
    import pickle

    import core.engine.predict as predict_module
    from core.engine.predict import predict, retimed

    nc = Ncperf(make_plugin_manager(entry_points=False))
    tp = zigzag()
    base = Setup(machine=machine(jerk=(INF, INF, INF)))
    first = predict(nc.indicators, tp, base.replace(servo_tau=0.01))
    pred = retimed(first, base.replace(servo_tau=0.02, filter_window=0.004))
    s = np.linspace(0.0, tp.end_s[-1], 3001)
    want = (pred.speed_at(s), pred.speed_at(s, commanded=True), *pred.signal())
    first.speed_at(s)  # (a second filtered motion in the plan's shared cache)
    assert len(pred.shared["filtered"]) == 2
    sent = pickle.loads(pickle.dumps(pred.unshared()))
    assert sent.shared == {}
    made = []
    real = predict_module._first_order
    predict_module._first_order = lambda *a: made.append(1) or real(*a)
    try:
        got = (sent.speed_at(s), sent.speed_at(s, commanded=True), *sent.signal())
    finally:
        predict_module._first_order = real
    assert not made
    assert _bits(got) == _bits(want)
    # what stays behind: at least the unfiltered signal and the other filtered motion
    left = sum(a.nbytes for a in pred.shared["raw"])
    (other,) = [f for f in pred.shared["filtered"].values() if f is not pred._filtered]
    left += sum(a.nbytes for a in other)
    assert len(pickle.dumps(pred)) - len(pickle.dumps(pred.unshared())) >= left
