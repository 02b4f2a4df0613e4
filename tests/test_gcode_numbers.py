"""The lexer's number reader (adapters.gcode.numbers) against C's parse (np.fromstring),
bit for bit, and its refusals."""

from __future__ import annotations

import numpy as np
import pytest

from adapters.gcode.lexer import Source, tokenize
from adapters.gcode.numbers import read_numbers


def spans(text: bytes) -> tuple[np.ndarray, np.ndarray]:
    """Letter positions and the next break (letter or newline) of each word."""
    c = np.frombuffer(text, dtype=np.uint8)
    brk = np.flatnonzero((c >= ord("A")) | (c == ord("\n")))
    letters = brk[c[brk] >= ord("A")]
    return letters, brk[np.searchsorted(brk, letters, side="right")]


def random_numbers(rng: np.random.Generator, n: int) -> list[str]:
    """Well-formed numbers of 1 to 20 characters: signs, leading and trailing dots, zeros."""
    out = []
    for _ in range(n):
        digits = "".join(rng.choice(list("0123456789"), int(rng.integers(1, 18))))
        form = int(rng.integers(0, 4))
        if form == 1:
            k = int(rng.integers(0, len(digits) + 1))
            digits = digits[:k] + "." + digits[k:]  # k = 0: ".5"; k = len: "5."
        elif form == 2:
            digits = "." + digits
        out.append(str(rng.choice(["", "-", "+"])) + digits)
    return out


@pytest.mark.parametrize("seed", range(4))
def test_same_bits_as_fromstring(seed):
    """Every value is the double C's strtod gives (lengths 1-20, with and without dots and
    signs, -0, at the text's very start)."""
    rng = np.random.default_rng(seed)
    nums = random_numbers(rng, 20_000) + ["-0", "-0.000", "0.", ".0", "+.5", "5.", "007"]
    letters = rng.choice(list("XYZIJKF"), len(nums))
    text = "\n".join(f"{a}{b}" for a, b in zip(letters, nums, strict=True)).encode() + b"\n"
    at, end = spans(text)
    got = read_numbers(text, at, end)
    want = np.array([float(x) for x in nums])
    assert np.array_equal(
        want.view(np.int64), np.fromstring(" ".join(nums), dtype=np.float64, sep=" ").view(np.int64)
    )
    assert got is not None
    assert np.array_equal(got.view(np.int64), want.view(np.int64))


@pytest.mark.parametrize(
    "bad",
    [b"1.2.3", b"--1", b"1-2", b".", b"-", b"+-1", b"1+", b"12345678.9.1", b"1234567890.12.34"],
)
@pytest.mark.parametrize("where", ["start", "middle"])
def test_refuses_what_is_not_a_number(bad, where):
    """A number that is not [+-]digits[.digits] or [+-].digits: None (the lexer's older
    path then blames its line)."""
    text = (b"X" + bad + b"\n") if where == "start" else (b"G21G90G17G94G64\nX1.5Z" + bad + b"\n")
    at, end = spans(text)
    assert read_numbers(text, at, end) is None


def test_lexer_blames_the_line_as_before():
    """A malformed number still makes its line an error with the line's number."""
    from core.model.errors import InputError

    with pytest.raises(InputError, match=":3:"):
        tokenize(Source("t.nc", b"G21 G90\nG1 X1.5 F100\nG1 X1.2.3\n"))
