"""The C kernels (core/model/_kernels.c, loaded by core.model.native) against numpy's code
they stand in for: the same bits, on random columns with the values that trip arithmetic
up (NaN, infinities, zeros of both signs, huge and tiny numbers) and on whole profiles,
with the rounds' two directions on two threads. Skipped where the library was not built
(no C compiler at install), unless NCPERF_REQUIRE_NATIVE is set (CI sets it: there a
missing build is a failure, not a skip)."""

from __future__ import annotations

import dataclasses
import os

import numpy as np
import pytest

import core.engine.profile as prof
import core.model.native as nat
from adapters.gcode.lexer import _words_library
from core import Ncperf, load_preset
from core.engine.profile import Profile, build_profile
from core.model.jit import NO_JIT_ENV, disabled
from core.model.pieces import SPLIT, side_by_side, two_cores
from core.model.tolerances import TOL
from tests.bits import same
from tests.conftest import ROOT, shared

if nat.native() is None or _words_library() is None:
    if os.environ.get("NCPERF_REQUIRE_NATIVE"):
        raise RuntimeError("the C kernels were not built or do not load (NCPERF_REQUIRE_NATIVE)")
    why = "NCPERF_NO_JIT is set" if disabled() else "not built (no C compiler at install)"
    pytest.skip(f"the C kernels: {why}", allow_module_level=True)

EXAMPLES = sorted((ROOT / "examples").glob("*.ngc"))
PROGRAMS = sorted((ROOT / "tests" / "programs").glob("*"))


@pytest.fixture(autouse=True)
def _c_not_numba(monkeypatch):
    """The C kernels where kernels run: numba's (allowed by other tests' diagnoses in this
    process) would stand in first."""
    monkeypatch.setattr(nat, "compiled", lambda: None)


def _numpy_then_c(monkeypatch, fn):
    """``fn()`` with numpy's code, then with the C kernels."""
    monkeypatch.setenv(NO_JIT_ENV, "1")
    assert nat.kernels() is None
    plain = fn()
    monkeypatch.delenv(NO_JIT_ENV)
    assert isinstance(nat.kernels(), nat.Kernels)
    return plain, fn()


def _tricky(rng: np.random.Generator, n: int, lo: float, hi: float, share: float) -> np.ndarray:
    """n values uniform in [lo, hi), a ``share`` of them replaced by awkward ones."""
    x = rng.uniform(lo, hi, n)
    odd = np.array([0.0, -0.0, np.inf, -np.inf, np.nan, 1e-300, 1e300, 5e-324, -1.0, 1.0])
    k = rng.random(n) < share
    x[k] = rng.choice(odd, int(k.sum()))
    return x


def test_marks_are_numpys_on_awkward_columns():
    """The marks of every move and of some, against _marks_of (numpy), element for element:
    NaN, infinities, signed zeros and extremes in every column."""
    rng = np.random.default_rng(13)
    lib = nat.native()
    assert lib is not None
    for n, share in ((1, 0.5), (17, 0.3), (5_000, 0.05), (3 * SPLIT, 0.01)):
        v = _tricky(rng, n + 1, 0.0, 300.0, share)
        a_up, a_dn = _tricky(rng, n, 10.0, 5000.0, share), _tricky(rng, n, 10.0, 5000.0, share)
        between, cap = _tricky(rng, n, -1.0, 20.0, share), _tricky(rng, n, 0.0, 400.0, share)
        with np.errstate(all="ignore"):
            want = prof._marks_of(
                v[:-1], v[1:], a_up, a_dn, prof._denominator(a_up, a_dn), between, cap
            )
        out = (
            np.full(n, -7.0),
            np.zeros(n, bool),
            np.zeros(n, bool),
            np.zeros(n + 1, bool),
            np.zeros(n + 1, bool),
        )
        tols = (TOL.rel_equal, TOL.nil_distance)
        lib.marks(np.zeros(0, np.intp), True, v, a_up, a_dn, between, cap, tols, out)
        same(tuple(want[:3]), out[:3], f"every, n={n}")
        same(want[3], out[3][1:], f"through_up n={n}")
        same(want[4], out[4][1:], f"through_dn n={n}")
        # some moves only: the others keep what they had
        at = np.flatnonzero(rng.random(n) < 0.5)
        out2 = (np.full(n, -7.0), *(np.zeros(m, bool) for m in (n, n, n + 1, n + 1)))
        lib.marks(at, False, v, a_up, a_dn, between, cap, tols, out2)
        rest = np.setdiff1d(np.arange(n), at)
        same(out2[0][at], want[0][at], "peak at")
        assert (out2[0][rest] == -7.0).all()
        same(out2[3][at + 1], want[3][at], "through_up at")
        assert not out2[3][rest + 1].any()


def test_marks_refuse_what_does_not_fit():
    lib = nat.native()
    assert lib is not None
    n = 4
    v, a = np.ones(n + 1), np.ones(n)
    out = (np.empty(n), *(np.zeros(m, bool) for m in (n, n, n + 1, n + 1)))
    tols = (TOL.rel_equal, TOL.nil_distance)
    with pytest.raises(IndexError):
        lib.marks(np.array([0, n]), False, v, a, a, a, a, tols, out)
    with pytest.raises(ValueError):
        lib.marks(np.zeros(0, np.intp), True, v[:-1], a, a, a, a, tols, out)
    with pytest.raises(TypeError):  # a strided view would be written beside its elements
        lib.marks(np.zeros(0, np.intp), True, v, a, a, a, np.ones(2 * n)[::2], tols, out)


def _rounds(rng: np.random.Generator, n: int, share: float) -> prof._Rounds:
    length = rng.uniform(0.01, 5.0, n)
    h = np.where(rng.random(n) < 0.2, rng.uniform(0.0, 1.0, n), 0.0)
    holds = prof._Holds(length, h, h[::-1].copy(), np.full(n, 0.5), np.full(n, 0.5))
    acc = rng.choice([800.0, 2000.0, 5000.0], n)
    jerk = rng.choice([2e4, 5e4, 2e5, np.inf], n)
    cap = rng.uniform(5.0, 250.0, n)
    caps = np.concatenate([[0.0], np.minimum(cap[:-1], cap[1:]) * rng.random(n - 1), [0.0]])
    if share:  # awkward values in the columns the kernels read
        acc = np.where(rng.random(n) < share, rng.choice([np.inf, 1e-300, 1e300]), acc)
        jerk = np.where(rng.random(n) < share, rng.choice([0.0, np.nan, 1e-300]), jerk)
        caps[rng.random(n + 1) < share] = np.inf
    return prof._Rounds(caps, cap, acc, jerk, holds)


def _new_rounds(seed: int, n: int, share: float) -> prof._Rounds:
    with np.errstate(all="ignore"):  # (the awkward values' terms)
        return _rounds(np.random.default_rng(seed), n, share)


def _run_rounds(rnd: prof._Rounds, rounds: int) -> list:
    """What each round leaves: the change, the speeds, and every column of the state."""
    seen = []
    with np.errstate(all="ignore"):
        for _ in range(rounds):
            v = rnd.passes().copy()
            change = rnd.step(v)
            state = (
                v,
                rnd.a_up.copy(),
                rnd.a_dn.copy(),
                rnd.term_up.copy(),
                rnd.term_dn.copy(),
                rnd.off_up.copy(),
                rnd.off_dn.copy(),
                rnd.step_up.copy(),
                rnd.step_dn.copy(),
                tuple(x.copy() for x in rnd.marks or ()),
                tuple(rnd.behind[d][i].copy() for d in (True, False) for i in (0, 1)),
            )
            seen.append((change, rnd.finite, state))
    return seen


@pytest.mark.parametrize(
    ("n", "share", "seed"),
    [(200, 0.0, 1), (200, 0.02, 2), (3 * SPLIT, 0.0, 3), (3 * SPLIT, 0.001, 4)],
)
def test_rounds_are_numpys(monkeypatch, n, share, seed):
    """Twelve rounds of the jerk iteration on random moves (a quarter without a jerk limit,
    holds on a fifth), with and without awkward values: every column of the rounds' state
    after every round the same bits with the C kernels as with numpy's code -- the dense
    rounds, the marks of all moves and of the changed ones, the passes; above
    :data:`SPLIT` moves the two directions and the marks' halves on two threads."""
    plain, fast = _numpy_then_c(monkeypatch, lambda: _run_rounds(_new_rounds(seed, n, share), 12))
    for r, (a, b) in enumerate(zip(plain, fast, strict=True)):
        same(a, b, f"round {r}")


def test_big_rounds_take_two_threads(monkeypatch):
    """Above SPLIT moves (and on two cores) the dense rounds' directions run side by side;
    below, one after the other."""
    if not two_cores():
        pytest.skip("one core: the rounds run on one thread")
    calls = []
    real = prof.side_by_side

    def counted(first, second):
        calls.append(1)
        return real(first, second)

    monkeypatch.setattr(prof, "side_by_side", counted)
    _run_rounds(_new_rounds(7, 3 * SPLIT, 0.0), 3)
    assert calls
    calls.clear()
    _run_rounds(_new_rounds(7, 500, 0.0), 3)
    assert not calls


def test_side_by_side_returns_both_and_raises_either():
    assert side_by_side(lambda: 1, lambda: "b") == (1, "b")

    def boom() -> int:
        raise KeyError("first")

    with pytest.raises(KeyError, match="first"):
        side_by_side(boom, lambda: 2)
    with pytest.raises(KeyError, match="first"):
        side_by_side(lambda: 2, boom)


def _profiles_same(plain: Profile, fast: Profile) -> None:
    for f in dataclasses.fields(Profile):
        if f.name != "evaluation":
            same(getattr(plain, f.name), getattr(fast, f.name), f.name)


@pytest.mark.parametrize("preset", ["siemens-840d", "linuxcnc-sim"])
@pytest.mark.parametrize("program", EXAMPLES, ids=lambda p: p.name)
def test_profiles_of_the_examples_are_numpys(monkeypatch, program, preset):
    nc = Ncperf()
    ev = nc.evaluate(nc.extract(str(program)), load_preset(preset))
    _profiles_same(*_numpy_then_c(monkeypatch, lambda: build_profile(ev)))


def test_a_long_raster_profile_is_numpys(monkeypatch, tmp_path):
    """A finishing raster of 42k moves (above SPLIT: the threads), with the 840D's jerk."""
    lines = ["G21 G90 G17 G64", "G0 X0 Y0 Z5", "G1 Z0 F3000"]
    y = 0.0
    for row in range(420):
        xs = np.linspace(0.0, 60.0, 101)[1:]
        if row % 2:
            xs = xs[::-1] - 0.6
        lines += [f"X{x:.3f} Y{y + 0.02 * np.sin(x):.4f}" for x in xs]
        y += 0.3
        lines.append(f"Y{y:.4f}")
    path = tmp_path / "raster.ngc"
    path.write_text("\n".join([*lines, "M30", ""]))
    nc = Ncperf()
    ev = nc.evaluate(nc.extract(str(path)), load_preset("siemens-840d"))
    assert ev.toolpath.n > 2 * SPLIT
    _profiles_same(*_numpy_then_c(monkeypatch, lambda: build_profile(ev)))


def test_stellabee1_profile_is_numpys(monkeypatch):
    """LinuxCNC's 169k-line test program (../shared), the benchmark of issue 13."""
    program = shared("data", "gcode", "linuxcnc-tp-tests", "stellabee1.ngc")
    nc = Ncperf()
    ev = nc.evaluate(nc.extract(str(program)), load_preset("siemens-840d"))
    _profiles_same(*_numpy_then_c(monkeypatch, lambda: build_profile(ev)))


def test_corner_limits_are_numpys(monkeypatch):
    """The corner model's nine limits per corner and the lowest (corner_limits after
    numpy's cube roots): shares of zero, -0.0, NaN, inf and tiny (no limit, or limits of
    every size), radii of zero, inf and NaN, machines with and without a jerk limit; and
    the corner model of stellabee1 (two threads), bit for bit."""
    from plugins import tangential

    rng = np.random.default_rng(4)
    n = 6000
    share_t = np.abs(_tricky(rng, 3 * n, 0.0, 1.0, 0.3)).reshape(n, 3)
    share_n = _tricky(rng, 3 * n, 0.0, 1.0, 0.3).reshape(n, 3)
    radius = _tricky(rng, n, 0.0, 5.0, 0.1)
    m = load_preset("siemens-840d")
    for mm in (m, dataclasses.replace(m, max_jerk=np.full(3, np.inf))):
        rows = lambda mm=mm: tangential._corner_feed_rows((share_t, share_n), radius, mm)  # noqa: E731
        same(*_numpy_then_c(monkeypatch, rows))
    program = shared("data", "gcode", "linuxcnc-tp-tests", "stellabee1.ngc")
    nc = Ncperf()
    tp = nc.extract(str(program))

    def corners() -> list:
        inds = tangential.ncperf_evaluate(toolpath=tp, machine=m)
        return [
            (i.name, i.index, i.feed, i.limit, *(i.values[k] for k in sorted(i.values)))
            for i in inds
        ]

    same(*_numpy_then_c(monkeypatch, corners))


def test_no_jit_switch_keeps_numpy(monkeypatch):
    monkeypatch.setenv(NO_JIT_ENV, "1")
    assert nat.native() is None
    monkeypatch.setenv(NO_JIT_ENV, "0")
    assert nat.native() is not None


def test_halves_on_two_threads_are_one_threads(monkeypatch, tmp_path):
    """The corner model's shares and feeds of 50k random corners and the turn angles of a
    50k-move random polyline (above SPLIT: two halves on two threads,
    core.model.pieces.halves) are those of one thread, bit for bit; and the threads did
    run."""
    import core.model.pieces as pieces_module
    from plugins import tangential

    if not two_cores():
        pytest.skip("one core: nothing runs side by side")
    rng = np.random.default_rng(11)
    m = 50_000
    t1 = rng.standard_normal((m, 3))
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    t2 = rng.standard_normal((m, 3))
    t2[::7] = t1[::7]  # (straight on: no turn)
    t2[::11] = -t1[::11]  # (reversal)
    t2 /= np.linalg.norm(t2, axis=1)[:, None]
    radius = rng.uniform(0.0, 2.0, m)
    radius[::13] = 0.0
    machine = load_preset("siemens-840d")
    points = np.cumsum(rng.uniform(-1.0, 1.0, (m, 3)), axis=0)
    path = tmp_path / "polyline.ngc"
    body = "\n".join(f"G1 X{x:.4f} Y{y:.4f} Z{z:.4f}" for x, y, z in points)
    path.write_text(f"G21 G90 G64 F3000\n{body}\nM30\n")
    tp = Ncperf().extract(str(path))
    assert tp.n > 2 * SPLIT

    def run() -> tuple:
        tp.__dict__.pop("turn_angle", None)  # (a cached property: made again)
        shares = tangential.corner_shares(t1, t2)
        return (*shares, *tangential._corner_feed(shares, radius, machine), tp.turn_angle)

    calls = []
    real = pieces_module.side_by_side
    monkeypatch.setattr(pieces_module, "side_by_side", lambda a, b: calls.append(1) or real(a, b))
    two = run()
    assert len(calls) == 3
    monkeypatch.setattr(pieces_module, "two_cores", lambda: False)
    calls.clear()
    one = run()
    assert not calls
    same(one, two)


def _plain_texts(rng: np.random.Generator) -> list[bytes]:
    """Plain texts as the lexer's scanner sees them (upper-case letters, 0-9 . + -, one
    newline per line): well-formed and broken numbers of every length up to 20 bytes and
    past MAX_DIGITS digits, signed zeros, empty words, numbers before a line's first
    letter, empty lines, a text shorter than eight bytes."""
    spans = [b"", b"0", b"-0", b"+0", b"-0.0", b".5", b"-.5", b"5.", b"1.2.3", b"+-1", b"1-",
             b"-", b".", b"+.", b"123456789012345", b"1234567890123456", b"-0.000000000000001",
             b"99999999999999999999", b"12345678.12345678", b"0000000000000000001", b"3.14159",
             b"-123.456", b"1e5"[:1], b"007", b"2.50000000000000000"]  # fmt: skip
    texts = [b"G1\n", b"X1\n", b"1X1\n", b"\n\n", b"G1X.5Y-.5\nM30\n"]
    for _ in range(60):
        lines = []
        for _ in range(int(rng.integers(1, 40))):
            words = []
            if rng.random() < 0.05:
                words.append(spans[int(rng.integers(len(spans)))] or b"7")
            for _ in range(int(rng.integers(0, 6))):
                letter = bytes([int(rng.integers(ord("A"), ord("Z") + 1))])
                if rng.random() < 0.7:
                    digits = rng.integers(0, 10, int(rng.integers(1, 18))).astype(np.uint8) + 48
                    body = bytes(digits)
                    if rng.random() < 0.6:
                        k = int(rng.integers(0, len(body) + 1))
                        body = body[:k] + b"." + body[k:]
                    if rng.random() < 0.4:
                        body = b"-" + body
                else:
                    body = spans[int(rng.integers(len(spans)))]
                words.append(letter + body)
            lines.append(b"".join(words))
        texts.append(b"\n".join(lines) + b"\n")
    return texts


def test_gcode_scanner_is_numpys():
    """The lexer's plain path in C (adapters/gcode/_words.c) against its numpy code: the
    same words, lines, numbers (bits: signed zeros, the correctly rounded decimal) and bad
    lines, on random plain texts and on every line of the examples."""
    from adapters.gcode import lexer
    from adapters.gcode.lexer import _plain_text
    from adapters.source import Source

    lib = lexer._words_library()
    assert lib is not None, "the G-code scanner was not built"
    texts = _plain_texts(np.random.default_rng(21))
    for program in [*EXAMPLES, *PROGRAMS]:
        src = Source(str(program), program.read_bytes())
        texts.append(_plain_text(src, np.zeros(src.n_lines, dtype=bool)))
    for text in texts:
        c = np.frombuffer(text, dtype=np.uint8)
        same(lexer._words_in_numpy(text, c)[:5], lexer._words_in_c(lib, text)[:5], repr(text))
        assert lexer._words_in_numpy(text, c)[5] == lexer._words_in_c(lib, text)[5], text


def test_tokens_of_real_programs_are_numpys(monkeypatch):
    """Whole programs through the lexer (numpy's code, then the C scanner): the same
    Words -- the examples, the tests' programs (cycles, subprograms, comments) and
    stellabee1 (169k lines, ../shared)."""
    from adapters.source import Source

    stellabee1 = shared("data", "gcode", "linuxcnc-tp-tests", "stellabee1.ngc")
    for program in [*EXAMPLES, *PROGRAMS, stellabee1]:
        src = Source(str(program), program.read_bytes())
        plain, fast = _numpy_then_c(monkeypatch, lambda: _tokens(src))  # noqa: B023
        same(plain, fast, program.name)


def _tokens(src: object) -> object:
    """The lexer's Words, or its error's text (a program in another dialect)."""
    from adapters.gcode.lexer import tokenize
    from core.model.errors import InputError

    try:
        return tokenize(src)  # type: ignore[arg-type]
    except InputError as exc:
        return str(exc)
