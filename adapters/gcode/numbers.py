"""The numbers of the lexer's words, read eight bytes at a time with integer arithmetic.

The lexer's plain text holds, between two breaks (a letter, a newline), only the bytes
``0-9 . + -``. A well-formed number there is ``[+-]digits[.digits]`` or ``[+-].digits``;
:func:`read_numbers` reads a number of up to 16 bytes as one or two little-endian 64-bit
words ending where it ends (a strided view of the text, no copy): the bytes before the
number are set to ``'0'``, the digits become their values (0 at the sign), those before
the dot move up a byte onto it, and three multiply-shift-mask steps combine the eight
into their integer (pairs, then fours, then the eight). With the dot's position that
gives the number's digits as one integer m below 2**53 and the count k of digits after
the dot, so the value is ``m / 10**k``: both exact doubles, one correctly rounded
division, the double nearest to the decimal -- what C's strtod (numpy's ``fromstring``)
returns, bit for bit. Numbers of other lengths (rare) are read by ``float`` of their
text, the same correctly rounded conversion, as are those of more than MAX_DIGITS digits.

When a number is not well formed the reader gives up (None) and the lexer takes its
older path, which parses and finds the lines to blame.
"""

from __future__ import annotations

import re

import numpy as np
from numpy.typing import NDArray

from core.model.arrays import unique

#: Words per piece: the pieces' temporaries stay in the cache.
PIECE = 1 << 15

_U64 = np.uint64
_ONES = _U64(0x0101010101010101)  # one bit per byte
_ZEROS = _U64(0x3030303030303030)  # eight '0'
_LOW4 = _U64(0x0F0F0F0F0F0F0F0F)
_FULL = 0xFFFFFFFFFFFFFFFF
#: [L]: the top L bytes of a word (the L bytes of a number that ends at the word's end).
_KEEP = np.array([0] + [(_FULL << (8 * (8 - n))) & _FULL for n in range(1, 9)], dtype=np.uint64)
#: [L]: the lowest bit of the first of those L bytes (where a sign may be).
_FIRST = np.array([0] + [1 << (8 * (8 - n)) for n in range(1, 9)], dtype=np.uint64)
_POW10 = 10.0 ** np.arange(16)  # exact doubles
#: Digits a number read here may have: its integer stays below 2**53.
MAX_DIGITS = 15
_WELL_FORMED = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)")


def _eight(v: NDArray[np.uint64]) -> NDArray[np.uint64]:
    """The integer of eight digit values, the first (most significant) in the lowest byte
    (in place)."""
    v *= _U64(10 * 256 + 1)
    v >>= _U64(8)
    v &= _U64(0x00FF00FF00FF00FF)
    v *= _U64(100 * 65536 + 1)
    v >>= _U64(16)
    v &= _U64(0x0000FFFF0000FFFF)
    v *= _U64(10000 * 2**32 + 1)
    v >>= _U64(32)
    return v


class _Word:
    """One word of up to eight bytes of numbers (``keep``: the bytes that are the number's)."""

    def __init__(self, w: NDArray[np.uint64], keep: NDArray[np.uint64]) -> None:
        w &= keep
        w |= _ZEROS & ~keep
        # '+' 0x2B, '-' 0x2D and '.' 0x2E have bit 4 clear, the digits 0x30-0x39 set;
        # of those three, '.' has bit 0 clear and '-' bit 1
        nd = ~(w >> _U64(4)) & _ONES
        self.other = nd
        self.dot = nd & ~w
        self.sign = nd & w
        self.minus = self.sign & ~(w >> _U64(1))
        dig = w & _LOW4
        dig &= (~nd & _ONES) * _U64(15)
        below = self.dot - _U64(1)  # the bytes before the dot (all where there is none)
        self.has_dot = self.dot != 0
        # the digits before the dot move up a byte, onto it: the digits without the dot
        # (a 0 first), read as one integer
        before = dig & below
        dig &= ~below
        before <<= self.has_dot.astype(np.uint64) << _U64(3)
        dig |= before
        #: the digits' integer, the dot skipped
        self.value = _eight(dig)
        #: digits after the dot (7 - the bytes before it), where there is one
        self.after = 7 - (np.bitwise_count(below).astype(np.int64) >> 3)


def _short(u8: NDArray[np.uint64], s: NDArray[np.int64], e: NDArray[np.int64]):
    """Numbers of 1 to 8 bytes ending at e >= 8: values, or None if one is not well formed."""
    n = e - s
    w = _Word(u8[e - 8], _KEEP[n])
    ok = np.bitwise_count(w.dot) <= 1
    ok &= (w.sign == 0) | (w.sign == _FIRST[n])
    ok &= np.bitwise_count(w.other) < n  # a digit at least
    if not ok.all():
        return None
    k = np.where(w.has_dot, w.after, 0)
    out = w.value.astype(np.float64)
    out /= _POW10[k]
    np.negative(out, out=out, where=w.minus != 0)
    return out


def _long(u8: NDArray[np.uint64], s: NDArray[np.int64], e: NDArray[np.int64]):
    """Numbers of 9 to 16 bytes ending at e >= 16: values (NaN where a number has more than
    MAX_DIGITS digits), or None if one is not well formed."""
    n = e - s
    hi = _Word(u8[e - 8], _KEEP[8])
    lo = _Word(u8[e - 16], _KEEP[n - 8])
    dots = np.bitwise_count(hi.dot) + np.bitwise_count(lo.dot)
    ok = dots <= 1
    ok &= hi.sign == 0
    ok &= (lo.sign == 0) | (lo.sign == _FIRST[n - 8])
    if not ok.all():  # (a dot and a sign at most: 7 digits at least)
        return None
    many = n - np.bitwise_count(hi.other) - np.bitwise_count(lo.other) > MAX_DIGITS
    # the digits: lo's, then hi's (seven of them after a dot in hi, eight otherwise)
    m = lo.value * np.where(hi.has_dot, _U64(10**7), _U64(10**8))
    m += hi.value
    k = np.where(hi.has_dot, hi.after, np.where(lo.has_dot, lo.after + 8, 0))
    out = m.astype(np.float64)
    out /= _POW10[k]
    np.negative(out, out=out, where=lo.minus != 0)
    out[many] = np.nan
    return out


def read_numbers(
    text: bytes, at: NDArray[np.int64], end: NDArray[np.int64]
) -> NDArray[np.float64] | None:
    """The numbers ``text[at[i] + 1 : end[i]]`` (each non-empty, of ``0-9 . + -`` only), or
    None if one is not well formed."""
    out = np.empty(at.size)
    if at.size == 0:
        return out
    if len(text) < 16:
        u8 = np.zeros(0, dtype=np.uint64)
    else:  # every 8 bytes of the text, at every offset (a view)
        u8 = np.ndarray((len(text) - 7,), dtype="<u8", buffer=text, strides=(1,))
    for a in range(0, at.size, PIECE):
        s = at[a : a + PIECE] + 1
        e = end[a : a + PIECE]
        o = out[a : a + PIECE]
        n = e - s
        short = (n <= 8) & (e >= 8) & (u8.size > 0)
        long = (n > 8) & (n <= 16) & (e >= 16) & (u8.size > 0)
        rest = np.flatnonzero(~(short | long))
        if short.all():
            v = _short(u8, s, e)
            if v is None:
                return None
            o[:] = v
            continue
        for mask, read in ((short, _short), (long, _long)):
            k = np.flatnonzero(mask)
            if k.size:
                v = read(u8, s[k], e[k])
                if v is None:
                    return None
                o[k] = v
        if long.any():  # 16 digits
            rest = unique(np.concatenate((rest, np.flatnonzero(long & np.isnan(o)))))  # union1d
        for i in rest.tolist():  # the text's first bytes, absurdly long numbers
            t = text[int(s[i]) : int(e[i])]
            if _WELL_FORMED.fullmatch(t) is None:
                return None
            o[i] = float(t)
    return out
