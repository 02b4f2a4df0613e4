"""The faster ways some computations take give the same bits as the plain ones (issue 13):
the array helpers against numpy, the profile's dense rounds against the sparse ones."""

from __future__ import annotations

import numpy as np
import pytest

from core.engine import profile as profile_module
from core.engine.profile import build_profile
from core.model.arrays import isin, put_where, same_bits, select, unique
from core.model.machine import resolve_machine
from core.model.toolpath import ExtractOptions


def test_unique_and_isin_are_numpys():
    rng = np.random.default_rng(13)
    for _ in range(200):
        a = rng.integers(-50, 50, rng.integers(0, 300))
        t = rng.integers(-50, 50, rng.integers(0, 60))  # both sides of ISIN_LOOP
        got, want = isin(a, t), np.isin(a, t)
        assert got.dtype == want.dtype and got.shape == want.shape
        assert np.array_equal(got, want)
        assert np.array_equal(isin(a, list(t)), np.isin(a, list(t)))
        u, w = unique(a), np.unique(a)
        assert u.dtype == w.dtype and np.array_equal(u, w)
        assert np.array_equal(unique(a > 0), np.unique(a > 0))
        f = rng.normal(size=80)
        f[::7] = np.nan
        tf = np.concatenate([f[:30], [np.nan, 0.0, -0.0]])
        assert np.array_equal(isin(f, tf), np.isin(f, tf))
        assert np.array_equal(isin(f, tf[:5]), np.isin(f, tf[:5]))
    grid = rng.integers(0, 9, (4, 5))
    assert np.array_equal(unique(grid), np.unique(grid))
    assert np.array_equal(isin(grid, [1, 2]), np.isin(grid, [1, 2]))


def test_same_bits_is_identity_of_bytes():
    """same_bits: equal only where dtype, shape and every byte are (a NaN equals its own
    bits, 0.0 not -0.0); strided views and Fortran order compared by their values' bytes;
    eight-byte and other items alike."""
    a = np.array([0.0, np.nan, 1.5, -np.inf])
    assert same_bits(a, a.copy())
    assert not same_bits(a, np.array([-0.0, np.nan, 1.5, -np.inf]))
    assert not same_bits(a, a.astype(np.float32))
    assert not same_bits(a, a[:3])
    assert same_bits(np.arange(12.0).reshape(3, 4)[:, 1], np.array([1.0, 5.0, 9.0]))
    assert same_bits(np.asfortranarray(np.eye(3)), np.eye(3))
    assert same_bits(np.array([1, 2], np.int8), np.array([1, 2], np.int8))
    assert not same_bits(np.array([1, 2], np.int8), np.array([1, 3], np.int8))
    assert same_bits(np.array([True, False]), np.array([True, False]))


def test_put_where_and_select_are_copyto_and_where():
    rng = np.random.default_rng(7)
    for share in (0.0, 0.02, 0.5, 1.0):
        dst = rng.normal(size=1000)
        src = rng.normal(size=1000)
        where = rng.random(1000) < share
        want = dst.copy()
        np.copyto(want, src, where=where)
        assert put_where(dst.copy(), src, where).tobytes() == want.tobytes()
        np.copyto(want, -1.5, where=~where)
        got = put_where(put_where(dst.copy(), src, where), -1.5, ~where)
        assert got.tobytes() == want.tobytes()
        src[::9] = np.nan
        dst[::11] = -0.0
        want = np.where(where, src, dst)
        assert select(where, src.copy(), dst.copy()).tobytes() == want.tobytes()


def _short_blocks(tmp_path) -> str:
    """A stellabee-like program: 3000 short chords of a wobbly curve (most moves in a
    ramp, the jerk rounds not settled), two feeds, an arc, a rapid."""
    rng = np.random.default_rng(2026)
    t = np.cumsum(rng.uniform(0.02, 0.3, 3000))
    x = 20 * np.cos(t / 7) + rng.normal(0, 0.01, t.size)
    y = 15 * np.sin(t / 5)
    lines = ["G21 G90 G17 G64", "G0 X20 Y0 Z1", "G1 Z0 F3000"]
    for k, (xi, yi) in enumerate(zip(x, y, strict=True)):
        f = " F6000" if k == 1000 else (" F2500" if k == 2000 else "")
        lines.append(f"G1 X{xi:.4f} Y{yi:.4f}{f}")
    lines += [f"G2 X{x[-1] + 2:.4f} Y{y[-1]:.4f} I1 J0", "G0 Z5", "M30"]
    p = tmp_path / "short_blocks.ngc"
    p.write_text("\n".join(lines) + "\n")
    return str(p)


FIELDS = ("v_entry", "v_peak", "v_exit", "a_up", "a_down", "time")


@pytest.mark.parametrize(("preset", "rounds"), [("siemens-840d", True), ("linuxcnc-sim", False)])
def test_dense_rounds_give_the_sparse_rounds_bits(nc, tmp_path, monkeypatch, preset, rounds):
    """(LinuxCNC has no jerk limit: no rounds, the same profile whatever the share.)"""
    m = resolve_machine(preset)
    tp = nc.extract(_short_blocks(tmp_path), ExtractOptions(setup=m.setup))
    ev = nc.evaluate(tp, m)
    dense_calls = []
    dense = profile_module._Rounds._dense

    def counted(self, *args):
        dense_calls.append(1)
        return dense(self, *args)

    monkeypatch.setattr(profile_module._Rounds, "_dense", counted)
    runs = {}
    for share in (profile_module.DENSE_SHARE, 0, 10**9):  # as shipped, never, always
        monkeypatch.setattr(profile_module, "DENSE_SHARE", share)
        for kw in ({}, {"lookahead": 40, "end_factor": 0.5}):
            pr = build_profile(ev, **kw)
            runs[share, tuple(kw)] = [getattr(pr, f).tobytes() for f in FIELDS] + [
                r.tobytes() for r in pr.ramps or ()
            ]
    assert bool(dense_calls) == rounds  # the dense rounds ran (jerk-limited)
    for (share, kw), got in runs.items():
        assert got == runs[0, kw], (share, kw)


def test_effective_acceleration_only_is_acc_outside():
    rng = np.random.default_rng(11)
    n = 5000
    dv = rng.uniform(0, 300, n)
    dv[::13] = 0.0
    acc = rng.uniform(100, 3000, n)
    jerk = rng.uniform(1e3, 1e5, n)
    jerk[::17] = np.inf
    only = rng.random(n) < 0.7
    want = np.where(only, profile_module.effective_acceleration(dv, acc, jerk), acc)
    got = profile_module.effective_acceleration(dv, acc, jerk, only)
    assert got.tobytes() == want.tobytes()
    # broadcast inputs take numpy's way, with the same answer
    got = profile_module.effective_acceleration(dv, acc[:1], jerk[:1], only)
    want = np.where(only, profile_module.effective_acceleration(dv, acc[:1], jerk[:1]), acc[0])
    assert got.tobytes() == want.tobytes()
