"""G-code text -> words (letter, number, line), vectorised over the whole file.

Plain lines -- letters, numbers, spaces and balanced ``( )`` comments, the
bulk of any CAM program -- are tokenised over the whole file at once:
``bytes.translate`` and numpy on its bytes, one C parse of all the numbers.
Lines with anything else (``;`` comments, ``%``, block delete ``/``,
keywords, ``=``, ``#``, non-ASCII text...) are few; they go through a
per-line Python tokeniser that knows the rare syntax and names the line in
its errors. Both produce the same columns.
"""

from __future__ import annotations

import ctypes
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from adapters.gcode import words as W
from adapters.gcode.numbers import read_numbers
from adapters.source import Source, check_bytes
from core.model.arrays import isin, unique
from core.model.jit import disabled
from core.model.native import load_library

SPACE, TAB, CR, LF, VT, FF = 32, 9, 13, 10, 11, 12

#: Bytes a plain line may hold (besides its newline).
_PLAIN_BYTES = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789.+- \t\r()\x0b\x0c"
_LETTER = np.zeros(256, dtype=bool)
_LETTER[ord("A") : ord("Z") + 1] = True


@dataclass
class Words:
    """Words of a program, sorted by line.

    Attributes
    ----------
    line : (w,) int64
        0-based line index.
    letter : (w,) uint8
        ASCII code of the upper-case letter.
    value : (w,) float64
    bare : (w,) bool
        A dimension word (X Y Z I J K R) with a nonzero integer written without a decimal
        point: Fanuc controls may read X10 as 10 mm or as 10 least increments.
    n_lines : int
    block_delete : set of int
        Lines starting with "/".
    keywords : list of (line, keyword)
        Siemens keywords seen (for notices and dialect detection).
    settings : list of (line, name, value)
        Siemens settings ncperf reads (CTOL, the contour tolerance), in program units.
    """

    line: NDArray[np.int64]
    letter: NDArray[np.uint8]
    value: NDArray[np.float64]
    bare: NDArray[np.bool_]
    n_lines: int
    block_delete: set[int] = field(default_factory=set)
    keywords: list[tuple[int, str]] = field(default_factory=list)
    settings: list[tuple[int, str, float]] = field(default_factory=list)
    special_lines: int = 0


# ----------------------------------------------------------------------- vectorised path
# The whole-file passes are bytes.translate (one C loop over the bytes, a table per byte)
# where they can be: several times faster than numpy's table look-ups and comparisons.

#: 1 at a byte the vectorised path does not take (a line with one goes to the per-line
#: path, wherever it is, comments included), else 0.
_ODD = bytes(0 if ch in _PLAIN_BYTES or ch == LF else 1 for ch in range(256))
#: Lower-case letters to upper case (the whitespace in _WHITESPACE is deleted with it).
_UPPER = bytes.maketrans(b"abcdefghijklmnopqrstuvwxyz", b"ABCDEFGHIJKLMNOPQRSTUVWXYZ")
_WHITESPACE = bytes([SPACE, TAB, CR, VT, FF])
#: After _UPPER: 1 at the breaks between words (letters, newlines), else 0.
_BREAK = bytes(1 if _LETTER[ch] or ch == LF else 0 for ch in range(256))
#: After _UPPER: letters and newlines to spaces, leaving the numbers space separated.
_NUMBERS = bytes(SPACE if _BREAK[ch] else ch for ch in range(256))
#: A ( ) comment closed on its line, with no parenthesis inside.
_COMMENT = re.compile(rb"\([^()\n]*\)")


def _lines_of(lf: NDArray[np.int64], pos: NDArray[np.int64]) -> NDArray[np.int64]:
    """0-based lines of the byte offsets ``pos`` in a text whose newlines are at ``lf``."""
    return np.searchsorted(lf, pos, side="left")


def _plain_text(src: Source, special: NDArray[np.bool_]) -> bytes:
    """The plain lines' words without spaces, comments and case: letters (upper case),
    number characters and one newline per line of the file (a special line keeps only its
    newline, so a word's line is the count of newlines before it). Marks ``special`` the
    lines the vectorised path cannot take: one with a byte it does not take, or with
    parentheses that are not ( ) comments one after the other (unclosed, nested, a ")"
    first)."""
    odd = np.flatnonzero(np.frombuffer(src.data.translate(_ODD), dtype=bool))
    if odd.size:
        special[unique(_lines_of(src.nl, odd))] = True
    del odd
    text = src.data.translate(_UPPER, _WHITESPACE)  # a newline stays where it was, in lines
    lf: NDArray[np.int64] | None = None
    if b"(" in text or b")" in text:
        # Every well-formed comment goes; a parenthesis left over marks its line. (A line
        # whose parentheses alternate "(...)(...)" loses them all; one that nests or does
        # not close keeps one at least.)
        # (from the first "(" to the last ")": every comment is there, the rest is not
        # searched; a CAM program's header comment, then 1M plain lines)
        first, end = text.find(b"("), text.rfind(b")") + 1
        if 0 <= first < end:
            text = text[:first] + _COMMENT.sub(b"", text[first:end]) + text[end:]
        if b"(" in text or b")" in text:
            t = np.frombuffer(text, dtype=np.uint8)
            lf = np.flatnonzero(t == LF)
            left = np.flatnonzero((t == ord("(")) | (t == ord(")")))
            special[unique(_lines_of(lf, left))] = True
            del t, left
    sp = np.flatnonzero(special)
    if sp.size:
        # The special lines' bytes go, their newlines stay: the text between them is kept.
        if lf is None:
            # the newlines up to the last special line's (a CAM header's: a few kB read;
            # all of them where it is not in the first quarter of the lines)
            end = min(len(text), 1 << 16) if 4 * sp[-1] < src.n_lines else len(text)
            while end < len(text) and text.count(b"\n", 0, end) <= sp[-1]:
                end = min(len(text), 4 * end)
            lf = np.flatnonzero(np.frombuffer(text, dtype=np.uint8, count=end) == LF)
        a = np.concatenate([[0], lf + 1])[sp]  # [a, b): line sp in text, without newline
        b = np.concatenate([lf, [len(text)]])[sp]
        keep_from = np.concatenate([[0], b]).tolist()
        keep_to = np.concatenate([a, [len(text)]]).tolist()
        text = b"".join([text[i:j] for i, j in zip(keep_from, keep_to, strict=True)])
    if not text.endswith(b"\n"):
        text += b"\n"  # every word then ends at a break
    return text


def tokenize(src: Source) -> Words:
    """All words of the program (see module docstring)."""
    check_bytes(src, "G-code", "a G-code program")
    special = np.zeros(src.n_lines, dtype=bool)
    text = _plain_text(src, special)
    c = np.frombuffer(text, dtype=np.uint8)
    lib = _words_library()
    if lib is not None:
        line, letter, value, at, e, bad = _words_in_c(lib, text)
    else:
        line, letter, value, at, e, bad = _words_in_numpy(text, c)
    if bad:
        special[np.array(sorted(bad), dtype=np.int64)] = True
    bare = _bare_integers(c, at, e, letter, value)

    result = Words(line=line, letter=letter, value=value, bare=bare, n_lines=src.n_lines)
    sp = np.flatnonzero(special)
    result.special_lines = int(sp.size)
    rows = [r for i in sp for r in tokenize_line(src, int(i), result)]
    if rows:
        line = np.concatenate([line, np.array([r[0] for r in rows], dtype=np.int64)])
        letter = np.concatenate([letter, np.array([r[1] for r in rows], dtype=np.uint8)])
        value = np.concatenate([value, np.array([r[2] for r in rows], dtype=np.float64)])
        bare = np.concatenate([bare, np.array([r[3] for r in rows], dtype=bool)])
        order = np.argsort(line, kind="stable")
        result.line, result.letter = line[order], letter[order]
        result.value, result.bare = value[order], bare[order]
    return result


Found = tuple[NDArray, NDArray, NDArray, NDArray, NDArray, set[int]]


def _words_in_numpy(text: bytes, c: NDArray[np.uint8]) -> Found:
    """The words of the plain text (:func:`_plain_text`) on its good lines -- their lines,
    letters, numbers, places and numbers' ends -- and the bad lines (a word without a
    number or with one not well formed, number bytes before a line's first letter), which
    the per-line tokeniser reads: on numpy's arrays (see :func:`_words_in_c`)."""

    brk_mask = np.frombuffer(text.translate(_BREAK), dtype=bool)
    brk = np.flatnonzero(brk_mask)
    lf_at = c[brk] == LF
    lfpos = brk[lf_at]
    rank = np.flatnonzero(~lf_at)
    del lf_at
    lpos = brk[rank]
    # A word's line is the count of newlines before it: of the breaks before the i-th
    # letter (rank[i] of them), i are letters. (Per-word arrays are made in place and the
    # per-break ones go once spent: 5M lines of arcs are 25M words, 200 MB per array.)
    wline = np.arange(rank.size)
    np.subtract(rank, wline, out=wline)
    rank += 1
    span_end = brk[rank]  # text ends with a newline, so every letter has a next break
    del brk, rank
    empty = span_end == lpos + 1

    # Lines the plain path cannot read: a letter with no number (a keyword such as
    # Siemens SOFT, or "X" alone), or number characters before the line's first letter
    # (right after a newline, or at the start).
    bad = set(unique(wline[empty]).tolist())
    after = lfpos + 1
    after = after[after < c.size]
    orphan = after[~brk_mask[after]]
    if c.size and not brk_mask[0]:
        orphan = np.concatenate([[0], orphan])
    if orphan.size:
        bad.update(_lines_of(lfpos, orphan).tolist())

    del brk_mask, after, orphan
    values = None
    # The numbers straight from the text (adapters.gcode.numbers); where one is not well
    # formed, C's parse of them all and the search for the lines to blame below.
    want = ~empty
    if bad:
        want &= ~isin(wline, np.array(sorted(bad), dtype=np.int64))
    if want.all():
        values = read_numbers(text, lpos, span_end)
    elif want.any():
        vals = read_numbers(text, lpos[want], span_end[want])
        if vals is not None:
            values = np.full(lpos.size, np.nan)
            values[want] = vals
            del vals
    numbers = text.translate(_NUMBERS) if values is None else b""
    for attempt in range(2 if values is None else 0):
        bad_arr = np.array(sorted(bad), dtype=np.int64)
        if bad_arr.size:
            sep = np.frombuffer(numbers, dtype=np.uint8).copy()
            for a, b in _line_ranges(lfpos, c.size, bad_arr):
                sep[a:b] = SPACE
            numbers = sep.tobytes()
            del sep
        want = ~empty & ~isin(wline, bad_arr)
        if not want.any():
            break
        vals = _fromstring(numbers)
        if vals is not None and vals.size == np.count_nonzero(want):
            if vals.size == lpos.size:
                values = vals  # every word has its number: no copy
            else:
                # (made after the parse and copied, not kept: a 5M-line raster's peak
                # stays 35 MB lower so, in ru_maxrss)
                values = np.full(lpos.size, np.nan)
                values[want] = vals
            del vals
            break
        if attempt:  # pragma: no cover - the validation below finds every bad span
            raise AssertionError("G-code lexer: numbers could not be aligned with words")
        bad.update(unique(wline[want & ~_well_formed(c, lpos + 1, span_end)]).tolist())
    # The numbers' text is spent: it goes before the words are cut out.
    del numbers, lfpos
    if values is None:  # no word to read
        values = np.full(lpos.size, np.nan)
    if want.all():
        return wline, c[lpos], values, lpos, span_end, bad
    return wline[want], c[lpos[want]], values[want], lpos[want], span_end[want], bad


def _words_library() -> ctypes.CDLL | None:
    """The C scanner of the plain text (adapters/gcode/_words.c), or None: not built, not
    loadable, or ``NCPERF_NO_JIT`` set (numpy's code then)."""
    if disabled():
        return None
    lib = load_library(Path(__file__).parent, "_words", "ncperf_words_version", 1)
    if lib is not None and lib.gcode_words.argtypes is None:
        lib.gcode_letters.argtypes = [ctypes.c_char_p, ctypes.c_int64]
        lib.gcode_letters.restype = ctypes.c_int64
        lib.gcode_words.argtypes = [ctypes.c_char_p, ctypes.c_int64, *[ctypes.c_void_p] * 7]
        lib.gcode_words.restype = ctypes.c_int64
    return lib


#: gcode_words' kind of a well-formed number of more than MAX_DIGITS digits (_words.c).
_LONG = 3


def _words_in_c(lib: ctypes.CDLL, text: bytes) -> Found:
    """:func:`_words_in_numpy` in one pass of C over the text (the same arrays, bit for
    bit: tests/test_native.py); numbers of more digits than the C reads (MAX_DIGITS) by
    Python's float, as there."""
    size = len(text)
    count = lib.gcode_letters(text, size)
    wline = np.empty(count, dtype=np.int64)
    letter = np.empty(count, dtype=np.uint8)
    at = np.empty(count, dtype=np.int64)
    end = np.empty(count, dtype=np.int64)
    value = np.empty(count)
    kind = np.empty(count, dtype=np.uint8)
    bad_line = np.zeros(text.count(b"\n") + 1, dtype=bool)
    got = lib.gcode_words(
        text, size, *(a.ctypes.data for a in (wline, letter, at, end, value, kind, bad_line))
    )
    if got != count:  # pragma: no cover - a letter is a word
        raise AssertionError("G-code lexer: the C scanner's words are not the letters")
    for i in np.flatnonzero(kind == _LONG).tolist():  # (well formed: the C checked)
        value[i] = float(text[int(at[i]) + 1 : int(end[i])])
    bad = set(np.flatnonzero(bad_line).tolist())
    if not bad:
        return wline, letter, value, at, end, bad
    want = ~bad_line[wline]
    return wline[want], letter[want], value[want], at[want], end[want], bad


def _line_ranges(
    lfpos: NDArray[np.int64], size: int, lines: NDArray[np.int64]
) -> list[tuple[int, int]]:
    """[start, end) of the given lines in a buffer whose newlines are at ``lfpos``."""
    out = []
    for k in lines:
        a = int(lfpos[k - 1]) + 1 if k > 0 else 0
        b = int(lfpos[k]) if k < lfpos.size else size
        out.append((a, b))
    return out


def _fromstring(sep: bytes) -> NDArray[np.float64] | None:
    """Parse space-separated numbers in C; None if some text is not a number."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            return np.fromstring(sep, dtype=np.float64, sep=" ")
        except (DeprecationWarning, ValueError):
            return None


def _well_formed(
    c: NDArray[np.uint8], s: NDArray[np.int64], e: NDArray[np.int64]
) -> NDArray[np.bool_]:
    """Spans ``c[s:e]`` of the form [+-]digits[.digits] or [+-].digits (error path only)."""

    def count(mask: NDArray[np.bool_]) -> NDArray[np.int64]:
        cs = np.concatenate([[0], np.cumsum(mask, dtype=np.int64)])
        return cs[e] - cs[s]

    n_dot = count(c == ord("."))
    is_sign = (c == ord("+")) | (c == ord("-"))
    n_sign = count(is_sign)
    n_digit = count((c >= ord("0")) & (c <= ord("9")))
    first_sign = is_sign[np.minimum(s, c.size - 1)]
    return (
        (n_digit + n_dot + n_sign == e - s) & (n_dot <= 1) & (n_sign == first_sign) & (n_digit >= 1)
    )


#: Numbers up to this many characters are checked for a decimal point column by column.
SHORT_NUMBER = 24

_DIMENSION = np.zeros(256, dtype=bool)
for _ch in b"XYZIJKR":
    _DIMENSION[_ch] = True


def _bare_integers(
    c: NDArray[np.uint8],
    at: NDArray[np.int64],
    e: NDArray[np.int64],
    letter: NDArray[np.uint8],
    value: NDArray[np.float64],
) -> NDArray[np.bool_]:
    """Dimension words with a nonzero integer value and no decimal point (see Words.bare);
    word i is its letter at ``c[at[i]]``, then its number ``c[at[i] + 1 : e[i]]``."""
    bare = np.zeros(at.size, dtype=bool)
    cand = np.flatnonzero(_DIMENSION[letter] & (value == np.round(value)) & (value != 0))
    if cand.size:
        # (the candidates' arrays only, made in place: a 5M-line program of arcs has a
        # candidate on every line, and this is the lexer's peak)
        start = at[cand]
        start += 1
        last = e[cand]
        last -= 1
        lens = last - start
        lens += 1
        dot = np.zeros(cand.size, dtype=bool)
        # Character k of every number at once (k up to SHORT_NUMBER; a shorter number looks
        # at its own last character again): memory per word, not per character.
        short = lens <= SHORT_NUMBER
        long = np.flatnonzero(~short)  # absurdly long numbers: character by character
        ll = lens[long]
        width = int(np.max(lens, where=short, initial=0))
        del lens, short
        pos = np.empty(cand.size, dtype=np.int64)
        for k in range(width):
            np.add(start, k, out=pos)
            np.minimum(pos, last, out=pos)
            dot |= c[pos] == ord(".")
        del pos
        if long.size:
            owner = np.repeat(np.arange(long.size), ll)
            offs = np.arange(owner.size) - np.repeat(np.cumsum(ll) - ll, ll)
            isdot = c[start[long][owner] + offs] == ord(".")
            dot[long] = np.bincount(owner, weights=isdot, minlength=long.size) > 0
        bare[cand] = ~dot
    return bare


# ----------------------------------------------------------------------- per-line path
_TOKEN = re.compile(
    r"""\s*(?:
      (?P<assign>[A-Z_$][A-Z0-9_$]*)\s*=\s*(?P<rhs>[^\s]*)
    | (?P<kw>[A-Z_$]{2,}[A-Z0-9_]*)(?P<args>\([^)]*\))?
    | (?P<letter>[A-Z])\s*(?P<num>[-+]?(?:\d+\.?\d*|\.\d+))(?![\d.])
    | (?P<colon>:)\s*(?P<cnum>\d+)
    | (?P<bad>\S+)
    )""",
    re.VERBOSE,
)
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)$")


def _is_call(text: str, k: int) -> bool:
    """Whether the "(" at ``text[k]`` opens the arguments of a keyword (Siemens IC(5),
    MSG("..."), CYCLE832(...)) rather than a comment: the word before it starts with two
    letters. G1(...), X10(...) and N10(...) are single-letter words: comments."""
    j = k
    while j > 0 and (text[j - 1].isalnum() or text[j - 1] == "_"):
        j -= 1
    word = text[j:k]
    return len(word) >= 2 and word[0].isalpha() and word[1].isalpha()


def _strip_comments(src: Source, i: int, text: str) -> str:
    """Remove ( ) and ; comments from one line; errors for unclosed or nested ( )."""
    out = []
    depth = 0
    call = 0  # open parentheses of keyword arguments
    for k, ch in enumerate(text):
        if depth == 0:
            if ch == ";":
                break
            if ch == "(" and (call or _is_call(text, k)):
                call += 1
                out.append(ch)
            elif ch == ")" and call:
                call -= 1
                out.append(ch)
            elif ch == "(":
                depth = 1
                out.append(" ")
            elif ch == ")":
                raise src.error(i, "')' without '('")
            else:
                out.append(ch)
        else:
            if ch == "(":
                raise src.error(i, "nested comment '(' inside '( )'")
            if ch == ")":
                depth = 0
            out.append(" ")
    if depth:
        raise src.error(i, "comment '(' is not closed on its line")
    return "".join(out)


def tokenize_line(src: Source, i: int, words: Words) -> list[tuple[int, int, float, bool]]:
    """Words of one unusual line (0-based ``i``), with its own errors."""
    raw = src.text(i)
    text = _strip_comments(src, i, raw)
    stripped = text.strip()
    if not stripped:
        return []
    if stripped.startswith("%"):
        if stripped.strip("%").strip():
            raise src.error(i, "text after '%' (program start/end marker)")
        return []
    if stripped.startswith("/"):
        words.block_delete.add(i)
        stripped = stripped[1:]
        if stripped[:1].isdigit():  # Fanuc "/2": block-delete switch number
            stripped = stripped[1:]
    try:
        stripped.encode("ascii")
    except UnicodeEncodeError:
        bad = next(ch for ch in stripped if ord(ch) > 127)
        raise src.error(i, f"non-ASCII character {bad!r} outside a comment") from None
    ctrl = [ch for ch in stripped if ord(ch) < 32 and ch not in "\t\r\x0b\x0c"]
    if ctrl:
        raise src.error(
            i, f"control character 0x{ord(ctrl[0]):02x}; not a G-code program", quote=False
        )
    up = stripped.upper()
    if "#" in up or "[" in up or "]" in up:
        raise src.error(i, "macro variables and expressions (#, [ ]) are not supported")
    rows: list[tuple[int, int, float, bool]] = []
    for m in _TOKEN.finditer(up):
        if m.group("letter"):
            num = m.group("num").replace(" ", "")
            letter, value = m.group("letter"), float(num)
            bare = letter in "XYZIJKR" and "." not in num and value != 0
            rows.append((i, ord(letter), value, bare))
        elif m.group("kw"):
            kw = m.group("kw")
            _keyword(src, i, kw, words)
        elif m.group("assign"):
            name, rhs = m.group("assign"), m.group("rhs")
            if name == "CR":  # Siemens radius of a circle: the same as R
                if not _NUMBER.match(rhs):
                    raise src.error(i, f"CR={rhs} is not a number")
                rows.append((i, ord("R"), float(rhs), False))
                words.keywords.append((i, "CR="))
            elif name in W.PASS_ASSIGNMENTS:
                words.keywords.append((i, name + "="))
                if name in W.SETTINGS:
                    if not _NUMBER.match(rhs):
                        raise src.error(i, f"{name}={rhs} is not a number")
                    words.settings.append((i, name, float(rhs)))
            else:
                raise src.error(
                    i,
                    f"assignment {name}={rhs} (parameters, IC()/AC(), system variables) "
                    "is not supported",
                )
        elif m.group("colon"):
            rows.append((i, ord("N"), float(m.group("cnum")), False))
        elif m.group("bad"):
            tok = m.group("bad")
            if tok[0] == "/":
                raise src.error(i, "'/' inside a block (block delete must start the line)")
            if tok[0].isalpha():
                rest = tok[1:]
                if not rest or rest[0] not in "0123456789.+-":
                    raise src.error(i, f"word '{tok[0]}' has no number")
                raise src.error(i, f"malformed number '{rest}' after {tok[0]}")
            raise src.error(i, f"malformed number or word '{tok}'")
    return rows


def _keyword(src: Source, i: int, kw: str, words: Words) -> None:
    if kw in W.PASS_KEYWORDS:
        words.keywords.append((i, kw))
        return
    if kw in W.ERROR_KEYWORDS:
        raise src.error(i, W.ERROR_KEYWORDS[kw])
    if kw in W.CONTROL_FLOW:
        raise src.error(i, f"control flow or subprogram '{kw}' (O-words, macros) is not supported")
    if kw.startswith("CYCLE") or kw.startswith("POCKET") or kw.startswith("SLOT"):
        raise src.error(i, f"Siemens cycle call {kw} is not supported")
    if kw.startswith("SPLINE") or kw.endswith("SPLINE"):
        raise src.error(i, "spline interpolation is not supported")
    if kw.startswith("O"):
        raise src.error(i, "O-word subprograms and control flow are not supported")
    raise src.error(i, f"unknown word '{kw}'")
