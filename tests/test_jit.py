"""The compiled kernels (numba, the optional extra ``fast``) against numpy's code they stand
in for: the same bits (core.model.jit). Skipped where numba is not installed."""

from __future__ import annotations

import dataclasses
from functools import partial

import numpy as np
import pytest

from core import Ncperf, load_preset
from core.engine.profile import Profile, build_profile
from core.model.jit import NO_JIT_ENV, allow, compiled
from core.model.sampling import PROJECTION_STEP
from tests.bits import same
from tests.conftest import ROOT
from tests.test_projection import _cases

pytest.importorskip("numba", reason="numba (the extra 'fast') is not installed")

PROGRAM = ROOT / "examples" / "zlevel_cavity_chords.ngc"


@pytest.fixture(autouse=True)
def _allowed() -> None:
    allow()  # (as the diagnosis does)


def _both(monkeypatch, fn):
    """``fn()`` with numpy's code, then with the kernels."""
    monkeypatch.setenv(NO_JIT_ENV, "1")
    assert compiled() is None
    plain = fn()
    monkeypatch.delenv(NO_JIT_ENV)
    assert compiled() is not None
    return plain, fn()


@pytest.mark.parametrize("preset", ["siemens-840d", "linuxcnc-sim"])
def test_profile_and_its_speeds_are_numpys(monkeypatch, preset):
    """The rounds over whole columns (dense_round) and the speed at arc lengths
    (profile_speed), with a jerk limit (840D: the ramps' bisection) and without."""
    nc = Ncperf()
    ev = nc.evaluate(nc.extract(str(PROGRAM)), load_preset(preset))
    plain, fast = _both(monkeypatch, lambda: build_profile(ev))
    for f in dataclasses.fields(Profile):
        if f.name != "evaluation":
            same(getattr(plain, f.name), getattr(fast, f.name))
    assert (plain.ramps is None) == (preset == "linuxcnc-sim")
    tp = ev.toolpath
    rng = np.random.default_rng(5)
    s = np.concatenate(
        [
            np.linspace(-1.0, tp.end_s[-1] + 1.0, 200_001),
            tp.start_s,  # the moves' boundaries
            np.nextafter(tp.start_s, np.inf),
            rng.uniform(0.0, tp.end_s[-1], 50_000),  # out of order
            [np.nan, np.inf, -np.inf, 0.0, -0.0],
        ]
    )
    a, b = _both(monkeypatch, lambda: plain.speed_at(s))
    same(a, b)


@pytest.mark.parametrize("newton", [0, 1, 2, 4])
def test_ramp_speeds_do_not_depend_on_the_guess(monkeypatch, newton):
    """Inside a jerk-limited ramp the speed is the bracket the halvings end in; a guess
    (the trapezoid's place and NEWTON_STEPS Newton steps, the kernel's on products for
    cubes) is taken only where the check proves it that bracket. So with fewer or more
    Newton steps -- none: most places go through the halvings -- the kernel's speeds are
    the bits of numpy's with three."""
    from core.engine import profile as profile_module

    nc = Ncperf()
    ev = nc.evaluate(nc.extract(str(PROGRAM)), load_preset("siemens-840d"))
    prof = build_profile(ev)
    assert prof.ramps is not None
    tp = ev.toolpath
    s = np.linspace(0.0, tp.end_s[-1], 100_001)
    monkeypatch.setenv(NO_JIT_ENV, "1")
    reference = prof.speed_at(s)  # numpy's code, three steps
    monkeypatch.delenv(NO_JIT_ENV)
    monkeypatch.setattr(profile_module, "NEWTON_STEPS", newton)
    same(reference, prof.speed_at(s))


def test_the_place_with_products_for_cubes_is_within_the_slack_of_numpys():
    """The check of a ramp's bracket reads the place with products for cubes where it is
    farther than SURE_SLACK x margin from the bound (compiled._place_vs); that needs the two
    places within 11 u T of each other (T: the ramp's size, margin / TOL.sure_compare). On
    40,000 random ramps and shares, jerk-limited and not, the largest difference against
    that bound, and the slack at least 8 times it."""
    from core.engine.profile import HALFWAY, HALVINGS, NEWTON_STEPS
    from core.model import compiled as kernels
    from core.model.tolerances import TOL

    consts = (TOL.nil_speed, TOL.tiny, TOL.sure_compare, HALVINGS, HALFWAY, NEWTON_STEPS)
    rng = np.random.default_rng(11)
    u = 2.0**-53
    worst = 0.0
    for _ in range(40_000):
        lo, dv = rng.uniform(0, 500) * rng.random() ** 3, rng.uniform(1e-6, 500)
        a, acc = rng.uniform(10, 5000), rng.uniform(10, 5000)
        jerk = rng.choice([np.inf, rng.uniform(100, 1e6)])
        vb = rng.uniform(0, lo + 1.0)
        terms, _, _, margin, sane = kernels._ramp(lo, dv, a, vb, acc, jerk, consts)
        if not sane:
            continue
        size = margin / TOL.sure_compare
        p = rng.random() ** rng.choice([1, 4])  # (many near 0, inside the first branch)
        for rising in (True, False):
            exact = kernels._place(p, rising, *terms)
            guess = kernels._place_guess(p, rising, *terms)
            worst = max(worst, abs(guess - exact) / (u * size))
    assert worst <= 11.0
    assert kernels.SURE_SLACK * TOL.sure_compare >= 8 * 11.0 * u


def test_projection_is_numpys(monkeypatch):
    """project_near's window search and foot, point by point, on the paths of
    tests/test_projection.py (zigzag chords, a path over itself, arcs): guesses near and
    far, narrow and wide windows, points on the samples and between them (ties)."""
    for tp, rng in _cases():
        samples = tp.sample(PROJECTION_STEP)
        for half_width in (0.1, 1.0, 2.5):
            for spread, off in ((0.0, 0.4), (0.02, 0.02), (0.3, 0.4), (2.0, 0.4)):
                s_true = rng.uniform(-0.5, tp.end_s[-1] + 0.5, 20_000)
                q = tp.point_at(s_true) + rng.normal(0.0, spread, (s_true.size, 3))
                guess = s_true + rng.normal(0.0, off, s_true.size)
                same(*_both(monkeypatch, partial(samples.project_near, q, guess, half_width)))
        mid = 0.5 * (samples.points[1:] + samples.points[:-1])
        g = 0.5 * (samples.s[1:] + samples.s[:-1])
        same(*_both(monkeypatch, partial(samples.project_near, mid, g)))


def test_projection_in_two_halves_is_one_threads(monkeypatch):
    """A projection of many points (80k: two halves on two threads, cut between two of the
    kernel's blocks of points) gives the bits of one thread and of numpy's code, where
    the halves' blocks search differently (near points, far ones)."""
    import core.model.sampling as sampling
    from core.model.pieces import two_cores

    if not two_cores():
        pytest.skip("one core: nothing runs side by side")
    tp, rng = next(iter(_cases()))
    samples = tp.sample(PROJECTION_STEP)
    m = 80_000
    s_true = rng.uniform(0.0, tp.end_s[-1], m)
    spread = np.where(np.arange(m) < m // 2, 0.001, 0.3)[:, None]  # (the halves differ)
    q = tp.point_at(s_true) + rng.normal(0.0, 1.0, (m, 3)) * spread
    guess = s_true + rng.normal(0.0, 0.05, m)
    calls = []
    real = sampling.side_by_side
    monkeypatch.setattr(sampling, "side_by_side", lambda a, b: calls.append(1) or real(a, b))
    plain, two = _both(monkeypatch, partial(samples.project_near, q, guess))
    assert calls
    monkeypatch.setattr(sampling, "two_cores", lambda: False)
    calls.clear()
    one = samples.project_near(q, guess)
    assert not calls
    same(one, two)
    same(plain, two)


def test_line_search_is_numpys(monkeypatch):
    """core.diagnosis.align._project's search of each program line's samples (the kernel
    project_lines against numpy's line-by-line search): samples near the path and off it,
    lagging behind their line's move (within LAG_BACK and beyond), exactly on path points
    and halfway between two (ties), lines the program does not have (searched in windows
    after); and on a path that jumps."""
    from core.diagnosis.align import LAG_BACK, _project

    tp = Ncperf().extract(str(PROGRAM))
    path = tp.sample(PROJECTION_STEP)
    rng = np.random.default_rng(11)
    end = tp.end_s[-1]
    s_true = np.sort(rng.uniform(0.0, end, 40_000))
    q = tp.point_at(s_true) + rng.normal(0.0, 0.01, (s_true.size, 3))
    # a fifth of the samples carry the line of a place up to 1.5 LAG_BACK ahead (a lag)
    ahead = np.minimum(s_true + rng.uniform(0.0, 1.5 * LAG_BACK, s_true.size), end)
    line = np.where(
        rng.random(s_true.size) < 0.2, tp.line[tp.move_at(ahead)], tp.line[tp.move_at(s_true)]
    )
    far = rng.random(s_true.size) < 0.02
    q[far] += rng.normal(0.0, 3.0, (int(far.sum()), 3))
    # on path points and halfway between two, each on its own line's move
    k = np.sort(rng.integers(0, path.s.size - 1, 3000))
    on = np.concatenate([path.points[k], 0.5 * (path.points[k] + path.points[k + 1])])
    on_line = tp.line[np.concatenate([path.move[k], path.move[k + 1]])]
    q = np.concatenate([q, on])
    line = np.concatenate([line, on_line])
    unknown = rng.random(line.size) < 0.01
    line[unknown] = np.where(rng.random(int(unknown.sum())) < 0.5, 0, int(tp.line.max()) + 1000)
    plain, fast = _both(monkeypatch, lambda: _project(tp, q, line, path))
    same(plain, fast)
    assert np.isfinite(plain[1]).all()
    # a path that jumps (a move not starting where the one before ended): the second half's
    # points 0.5 mm over, the samples of every other line with them
    half = path.s.size // 2
    jumped = dataclasses.replace(path, points=path.points.copy())
    jumped.points[half:] += [0.5, 0.0, 0.0]
    over = (line % 2 == 1)[:, None] * np.array([0.5, 0.0, 0.0])
    plain, fast = _both(monkeypatch, lambda: _project(tp, q + over, line, jumped))
    same(plain, fast)
    # 46k samples: their lines in two halves on two threads where two cores are, the bits
    # of one thread
    import core.diagnosis.align as align_module
    from core.model.pieces import two_cores

    if two_cores():
        calls = []
        real = align_module.side_by_side
        monkeypatch.setattr(
            align_module, "side_by_side", lambda a, b: calls.append(1) or real(a, b)
        )
        two = _project(tp, q, line, path)
        assert calls
        monkeypatch.setattr(align_module, "two_cores", lambda: False)
        one = _project(tp, q, line, path)
        same(one, two)


def _numbers(rng: np.random.Generator, n: int) -> list[str]:
    """Decimals as recorders and people write them: fixed points of 0-9 places, signs,
    negative zeros, exponents, mantissas of up to 15 digits, whole numbers, leading and
    trailing points."""
    x = rng.normal(0.0, 10.0 ** rng.integers(-5, 4, n))
    out = []
    for k, v in enumerate(x):
        kind = k % 9
        if kind == 0:
            out.append(f"{v:.{k % 10}f}")
        elif kind == 1:
            out.append(f"{v:.{k % 15}e}")
        elif kind == 2:
            out.append(f"{v:.15g}")
        elif kind == 3:
            out.append(f"{v:.{k % 15 + 1}g}")
        elif kind == 4:
            out.append("-0.000000" if k % 2 else "+0")
        elif kind == 5:
            out.append(f"{int(v)}")
        elif kind == 6:
            out.append(f"{abs(v):.3f}".lstrip("0") or "0")
        elif kind == 7:
            out.append(f"{int(abs(v))}.")
        else:
            out.append(f"{v:.6f}E+{k % 3}")
    return out


def test_trace_reader_is_numpys(monkeypatch, tmp_path):
    """The compiled CSV reader (parse_rows) reads every number as numpy's reader does, bit
    for bit; rows it does not take (spaces, comments, NaN, a lone CR, an empty line, a
    missing field, non-ASCII text in a column not read) leave the file to numpy's reader,
    its numbers or its one-line error the same."""
    from adapters.traces import read_csv_trace
    from core.model.errors import InputError
    from core.model.trace import TraceOptions

    rng = np.random.default_rng(3)
    n = 4000
    t = [f"{0.001 * k:.6f}" for k in range(n)]
    cols = [_numbers(rng, n) for _ in range(4)]
    line = [str(k // 7) for k in range(n)]
    note = ["x" if k % 5 else "a note" for k in range(n)]  # text in a column not read
    rows = [",".join(r) for r in zip(t, *cols, note, line, strict=True)]
    plain = "t,x,y,z,v,note,line\n" + "\n".join(rows) + "\n"
    bodies = {
        "plain": plain,
        "crlf, no last newline": plain.replace("\n", "\r\n").rstrip("\r\n"),
    }
    for what, bad in (
        ("a space", " 1.5"),
        ("a comment", "1.5 # c"),
        ("nan", "nan"),
        ("a lone CR", "1.5\r2"),
        ("17 digits (beyond 2^53)", "0.12345678901234567"),
        ("20 digits", "1.2345678901234567890"),
        ("an exponent beyond 22", "1e30"),
        ("no digits", "-."),
    ):
        k = 2000
        broken = rows[k].split(",")
        broken[2] = bad
        bodies[what] = plain.replace(rows[k] + "\n", ",".join(broken) + "\n")
    bodies["an empty line"] = plain.replace(rows[9] + "\n", rows[9] + "\n\n")
    bodies["a missing field"] = plain.replace(rows[9] + "\n", rows[9].rsplit(",", 1)[0] + "\n")
    bodies["non-ASCII text not read"] = plain.replace("a note", "é", 3)

    def read(path):
        try:
            tr = read_csv_trace(path, TraceOptions())
        except InputError as exc:
            return str(exc)
        return (tr.t, tr.pos, tr.v, tr.line)

    kernels = compiled()
    to = np.array([0, 1, 2, 3, 4, -1, 5])
    for what, body in bodies.items():
        data = body.encode("utf-8")
        buf = np.frombuffer(data, dtype=np.uint8)[data.index(b"\n") + 1 :]
        taken = kernels.parse_rows(buf, 7, to)[1] < 0
        assert taken == (what in ("plain", "crlf, no last newline")), what
        path = tmp_path / "trace.csv"
        path.write_bytes(body.encode("utf-8"))
        a, b = _both(monkeypatch, partial(read, path))
        assert type(a) is type(b), what
        if isinstance(a, str):
            assert a == b, what
            assert not taken, f"{what}: {a}"
        else:
            same(a, b)


def test_lag_and_speed_of_filtered_positions_are_numpys(monkeypatch):
    """The first-order lag (first_order: the same blocks, each the closed form over a
    cumsum) and the speed of positions (path_speed: np.gradient's central and one-sided
    differences, np.linalg.norm's sum of squares), bit for bit: short and long columns
    (one block, many, a last short one), poles from negligible to slow, values of mixed
    magnitude and sign, zeros and signed zeros."""
    from core.engine.predict import _first_order, _path_speed

    rng = np.random.default_rng(11)
    for m in (2, 3, 7, 2049, 5000, 40_000):
        pos = np.cumsum(rng.normal(0.0, 0.02, (m, 3)), axis=0) + rng.normal(0.0, 300.0, 3)
        pos[rng.integers(0, m, m // 10 + 1), 1] = rng.choice([0.0, -0.0])
        for dt in (0.001, 0.0004):
            same(*_both(monkeypatch, partial(_path_speed, pos, dt)))
        for tau in (1e-4, 0.002, 0.02, 0.3):
            a = np.exp(-0.001 / tau)
            same(*_both(monkeypatch, partial(_first_order, pos, a)))
    # a (m,) column: numpy's code alone (the kernel takes (m, columns))
    v = rng.normal(size=3000)
    same(*_both(monkeypatch, partial(_first_order, v, 0.97)))


def test_filtered_prediction_is_numpys(monkeypatch):
    """A prediction through a servo lag and a setpoint filter (the lag and the speed of
    the filtered positions by the kernels, their projection onto the path): the motion a
    trace would show and its speeds at places, the same bits."""
    from core.engine.effects import setup_for
    from core.engine.predict import predict

    nc = Ncperf()
    tp = nc.extract(str(PROGRAM))
    base = setup_for(load_preset("siemens-840d"), nc.effects())
    s = np.linspace(0.0, tp.end_s[-1], 20_001)

    def motion():
        pred = predict(nc.indicators, tp, base.replace(servo_tau=0.012, filter_window=0.006))
        return (*pred._filtered, pred.speed_at(s), pred.speed_at(s, commanded=True))

    same(*_both(monkeypatch, motion))


def test_corner_limits_are_numpys(monkeypatch):
    """The corner model's nine limits per corner and the lowest (corner_limits after
    numpy's cube roots): shares of zero, -0.0 and NaN (no limit), radii of zero and inf
    (NaN as 0: a stop), machines with and without a jerk limit; and the evaluation of a
    whole program, bit for bit."""
    import plugins.tangential as tangential

    rng = np.random.default_rng(8)
    n = 5000
    share_t = np.abs(rng.normal(size=(n, 3)))
    share_n = np.abs(rng.normal(size=(n, 3)))
    for share in (share_t, share_n):
        share[rng.random((n, 3)) < 0.2] = 0.0
        share[rng.random((n, 3)) < 0.02] = -0.0
        share[rng.random((n, 3)) < 0.01] = np.nan
    radius = np.abs(rng.normal(0.0, 3.0, n))
    radius[rng.random(n) < 0.05] = 0.0
    radius[rng.random(n) < 0.01] = np.inf
    m = load_preset("siemens-840d")
    for mm in (m, dataclasses.replace(m, max_jerk=np.full(3, np.inf))):
        rows = partial(tangential._corner_feed_rows, (share_t, share_n), radius, mm)
        same(*_both(monkeypatch, rows))
    nc = Ncperf()
    tp = nc.extract(str(PROGRAM))
    plain, fast = _both(monkeypatch, lambda: nc.indicators(tp, m))
    assert [i.name for i in plain] == [i.name for i in fast]
    for a, b in zip(plain, fast, strict=True):
        same((a.index, a.feed, a.limit, a.labels), (b.index, b.feed, b.limit, b.labels))
        assert sorted(a.values) == sorted(b.values)
        for key in a.values:
            same(np.asarray(a.values[key]), np.asarray(b.values[key]))


def test_changed_moves_are_numpys(monkeypatch):
    """The moves where any of a profile's per-move values changed (the diagnosis's reuse
    of a recent candidate's speeds): (old != new).any(axis=0), one column at a time."""
    from core.diagnosis.resample import _changed_moves

    rng = np.random.default_rng(9)
    for rows, n in ((1, 1), (9, 7000), (15, 301)):
        old = rng.integers(-5, 5, (rows, n))
        new = old.copy()
        hit = rng.random((rows, n)) < 0.05
        new[hit] += 1
        got = _both(monkeypatch, partial(_changed_moves, old, new))
        same(*got)
        np.testing.assert_array_equal(got[1], hit.any(axis=0))


def test_sorted_places_are_searchsorteds():
    """sorted_places (each search from the last one's place) gives np.searchsorted's places:
    sorted and shuffled needles, values equal to the array's (duplicates among them), just
    above and below them, beyond both ends; an array of one value."""
    rng = np.random.default_rng(2)
    kernels = compiled()
    for trial in range(400):
        s = np.sort(np.round(rng.uniform(0.0, 10.0, int(rng.integers(1, 80))), 1))
        if trial % 4 == 3:
            s = np.full(s.size, 5.0)
        x = rng.uniform(-1.0, 11.0, int(rng.integers(1, 300)))
        for needles in (
            np.sort(x),
            x,
            np.concatenate([s, np.nextafter(s, np.inf), np.nextafter(s, -np.inf), [-9.0, 19.0]]),
        ):
            np.testing.assert_array_equal(
                kernels.sorted_places(s, needles), np.searchsorted(s, needles)
            )


def test_lazy_walks_are_pythons(monkeypatch):
    """LinuxCNC's lazy look-ahead walks (core.engine.lookahead.lazy_walks): random queues of
    short and long segments, limits that bind and do not, stops among them, blocks of one
    to three segments, depths and cutoffs small and large."""
    from core.engine.lookahead import lazy_walks

    rng = np.random.default_rng(11)
    for trial in range(300):
        n = int(rng.integers(1, 160))
        dn = np.where(rng.random(n) < 0.2, rng.uniform(1e3, 1e4, n), rng.uniform(0.0, 300.0, n))
        lim2 = rng.uniform(0.0, 4e3, n) ** (1.0 if trial % 3 else 0.5) * 10.0
        tangent = rng.random(n) > 0.05
        tangent[-1] = False
        first = np.unique(np.concatenate([[0], rng.integers(0, n, n // 2)])).astype(np.int64)
        open2 = rng.uniform(0.0, 3e3, first.size)
        depth, cutoff = (50, 4) if trial % 4 else (int(rng.integers(1, 9)), int(rng.integers(0, 6)))
        same(
            *_both(monkeypatch, partial(lazy_walks, dn, lim2, tangent, first, open2, depth, cutoff))
        )


def test_long_loops_take_the_kernels_unasked(monkeypatch):
    """compiled_for: without the diagnosis's leave, the kernels only for a loop of at least
    WORTH_LOADING steps, and never where NCPERF_NO_JIT is set."""
    from core.model import jit

    monkeypatch.setattr(jit, "_allowed", [False])
    assert jit.compiled_for(jit.WORTH_LOADING - 1) is None
    assert jit.compiled_for(jit.WORTH_LOADING) is not None
    monkeypatch.setenv(NO_JIT_ENV, "1")
    assert jit.compiled_for(jit.WORTH_LOADING) is None


def test_no_jit_switch(monkeypatch):
    for value, off in (("1", True), ("yes", True), ("0", False), ("", False)):
        monkeypatch.setenv(NO_JIT_ENV, value)
        assert (compiled() is None) == off


def test_analyze_does_not_load_numba():
    """`ncperf analyze` does not pay numba's start-up (core.model.jit): the kernels are the
    diagnosis's, allowed by it."""
    import subprocess
    import sys

    code = (
        "import sys; from core.cli import main\n"
        "try:\n    main(['analyze', sys.argv[1]])\nexcept SystemExit:\n    pass\n"
        "assert 'numba' not in sys.modules, 'numba imported'\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, str(PROGRAM)], capture_output=True, text=True, cwd=ROOT
    )
    assert out.returncode == 0, out.stderr
