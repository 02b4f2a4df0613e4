"""One line of G-code -> one :class:`Block`: its words (with expressions), parameter
assignments and control statement, for the full interpreter (:mod:`adapters.gcode.run`).

Three front ends share the block shape:

* **LinuxCNC** (rs274ngc): ``#n``, ``#<name>``, ``[expr]`` values, ``#.. = ..``
  assignments (several on a line, all read before any is set), O-word statements
  (``o100 sub``, ``o<name> call [args]``, ``if``/``elseif``/``else``/``endif``, ``while``,
  ``do``, ``repeat``, ``break``, ``continue``, ``return``), ``( )`` and ``;`` comments.
* **Fanuc** (Custom Macro B): ``#n`` values and assignments, ``IF [..] GOTO n``,
  ``IF [..] THEN ..``, ``WHILE [..] DOm`` / ``ENDm``, ``GOTO n``, ``O1234`` program and
  subprogram numbers; M98/M99/G65 calls are words the interpreter acts on.
* **Siemens 840D**: ``R`` parameters and ``DEF`` variables, ``X=expr`` values,
  ``AC()``/``IC()``, labels, ``IF .. GOTOF/GOTOB``, ``GOTOF``/``GOTOB``, block ``IF``/
  ``ELSE``/``ENDIF``, ``LOOP``, ``WHILE``, ``FOR``, ``REPEAT``/``UNTIL``, subprogram calls by
  name (``L123``, ``PART1``, ``CALL``), ``MCALL``, ``CYCLE81``-``CYCLE83``, ``T="name"``,
  frames ``TRANS``/``ATRANS``/``ROT``/``AROT``/``SCALE``/``ASCALE``/``MIRROR``/``AMIRROR``.

Errors name the construct and quote the line as written (the caller adds file and line).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

from adapters.gcode import exprs as E
from adapters.gcode import words as W


class BlockError(Exception):
    """A line that cannot be read; ``note``: read, but with a warning (not an error)."""


@dataclass
class Block:
    """One line of a program, parsed.

    Attributes
    ----------
    file, line : int
        File index (0: the program) and 0-based line in it.
    delete : bool
        The line starts with "/" (block delete).
    words : list of (letter, value)
        NC words in order; values are expression nodes (floats when constant).
    assigns : list of (target, value)
        Parameter assignments: targets ("param", node), ("named", name), ("var", name).
    stmt : tuple or None
        A control statement (see the module docstring), e.g. ("o", label, "call", args).
    extra : dict
        Siemens specials: "tool" (T="name"), "cycle" (name, args), "mcall", "frame"
        (kind, {axis: node}), "ic"/"ac" (axes written IC()/AC()), "keywords", "settings".
    notes : list of str
        Warnings about the line (a nested comment read as one, text after "%").
    """

    file: int
    line: int
    delete: bool = False
    words: list[tuple[str, Any]] = field(default_factory=list)
    assigns: list[tuple[tuple, Any]] = field(default_factory=list)
    stmt: tuple | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    number: float | None = None  # N word (Fanuc GOTO target)
    label: str | None = None  # Siemens label ("MARK1:")


# ----------------------------------------------------------------------------- comments
def strip_comments(text: str, dialect: str, notes: list[str]) -> tuple[str, list[str]]:
    """(code without comments, the comments' texts). ``( )`` comments (a nested one is read
    as one comment, with a note); ``;`` to the end of the line. Siemens ``( )`` are
    parentheses of expressions and calls, not comments."""
    if "(" not in text and ")" not in text and ";" not in text and '"' not in text:
        return text, []
    out: list[str] = []
    comments: list[str] = []
    depth = 0
    buf: list[str] = []
    in_string = False
    for ch in text:
        if in_string:
            out.append(ch)
            if ch == '"':
                in_string = False
            continue
        if depth == 0:
            if ch == ";":
                comments.append(text[text.index(";") + 1 :] if ";" in text else "")
                break
            if ch == '"' and dialect == "siemens":
                in_string = True
                out.append(ch)
            elif ch == "(" and (dialect != "siemens" or _siemens_comment(out)):
                depth = 1
                buf = []
                out.append(" ")
            elif ch == ")" and dialect != "siemens":
                raise BlockError("')' without '('")
            else:
                out.append(ch)
        else:
            if ch == "(":
                depth += 1
                if depth == 2:
                    notes.append("nested comment: read as one comment")
                buf.append(ch)
            elif ch == ")":
                depth -= 1
                if depth == 0:
                    comments.append("".join(buf))
                else:
                    buf.append(ch)
            else:
                buf.append(ch)
    if depth:
        raise BlockError("comment '(' is not closed on its line")
    return "".join(out), comments


#: Words after which a Siemens "(" opens an expression, not a comment.
_S_EXPR_BEFORE = {"IF", "WHILE", "UNTIL", "AND", "OR", "XOR", "NOT", "ELSEIF", "RET", "TO"}


def _siemens_comment(before: list[str]) -> bool:
    """Old Sinumerik lines carry "( text )" comments: a "(" after a space, not after an
    operator, a comma or a condition keyword (those open expressions)."""
    text = "".join(before)
    if text and not text[-1].isspace():
        return False  # NAME(args), =(..), ((..): part of the code
    stripped = text.rstrip()
    if not stripped:
        return True
    if stripped[-1] in "=+-*/<>,(":
        return False
    last = stripped.split()[-1].upper()
    return last not in _S_EXPR_BEFORE


_CONTROL = re.compile(r"[\x00-\x08\x0e-\x1f\x7f]")


def _printable(code: str) -> None:
    if code.isascii() and not _CONTROL.search(code):
        return
    for ch in code:
        if ord(ch) > 127:
            raise BlockError(f"non-ASCII character {ch!r} outside a comment")
        if ord(ch) < 32 and ch not in "\t\r\x0b\x0c":
            raise BlockError(f"control character 0x{ord(ch):02x}; not a G-code program")


# ----------------------------------------------------------------------------- LinuxCNC
O_KEYWORDS = (
    "SUB",
    "ENDSUB",
    "CALL",
    "RETURN",
    "IF",
    "ELSEIF",
    "ELSE",
    "ENDIF",
    "WHILE",
    "ENDWHILE",
    "DO",
    "REPEAT",
    "ENDREPEAT",
    "BREAK",
    "CONTINUE",
)
_BRACKETS = E.BracketParser(named=True)
_FANUC = E.BracketParser(named=False)


def _head(text: str, delete_ok: bool = True) -> tuple[str, bool]:
    t = text.strip()
    delete = False
    if t.startswith("//"):
        return "", False  # a "//" comment line (some controls' and editors' style)
    if t.startswith("/") and delete_ok:
        delete = True
        t = t[1:]
        if t[:1].isdigit():  # Fanuc "/2": block-delete switch number
            t = t[1:]
    return t, delete


def _token(text: str, pos: int) -> str:
    """The text from ``pos`` up to the next letter that starts a word (for messages)."""
    j = pos
    while j < len(text) and not (text[j].isalpha() and j > pos and text[j - 1] not in "#"):
        j += 1
    return text[pos:j] or text[pos : pos + 1]


def _alpha_run(text: str, pos: int) -> str:
    j = pos
    while j < len(text) and text[j].isalpha():
        j += 1
    return text[pos:j]


def _function_at(text: str, pos: int) -> bool:
    """Whether a function name (SIN[...], ATAN[...]) starts at ``pos``."""
    j = pos
    while j < len(text) and text[j].isalpha():
        j += 1
    return text[pos:j] in E.FUNCTIONS or text[pos:j] in ("ATAN", "EXISTS")


#: A line of plain words only (letters and numbers, spaces between): the common case, read
#: without the expression parser.
_PLAIN_LINE = re.compile(r"(?:\s*[A-Za-z]\s*[-+]?(?:\d+\.?\d*|\.\d+))+\s*")
_PLAIN_WORD = re.compile(r"([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")


def _plain(text: str, file: int, line: int) -> Block | None:
    """The block of a plain line, or None when the line needs the full parser."""
    if not _PLAIN_LINE.fullmatch(text):
        return None
    b = Block(file, line)
    words = [(ch.upper(), float(num)) for ch, num in _PLAIN_WORD.findall(text)]
    if words and words[0][0] == "N":
        b.number = words[0][1]
        words = words[1:]
    for ch, _ in words:
        if ch == "O":
            return None
    b.words = words
    return b


def parse_linuxcnc(text: str, file: int, line: int) -> Block | None:
    """A LinuxCNC line (rs274ngc: spaces outside comments do not count, case neither)."""
    fast = _plain(text, file, line)
    if fast is not None:
        return fast
    b = Block(file, line)
    code, comments = strip_comments(text, "linuxcnc", b.notes)
    code, b.delete = _head(code)
    if code.startswith("%"):
        if code.strip("% \t"):
            b.notes.append("text after '%' ignored")
        return b
    _printable(code)
    c = E.Cursor("".join(code.split()).upper())
    if c.at_end():
        return b
    _n_word(c, b)
    if c.peek() == "O":
        c.take("O")
        b.stmt = _o_statement(c)
        if not c.at_end():
            raise BlockError(f"unexpected '{c.text[c.pos :]}' after the O-word statement")
        return b
    _words(c, b, _BRACKETS)
    return b


def _n_word(c: E.Cursor, b: Block) -> None:
    if c.peek() == "N" and c.text[c.pos + 1 : c.pos + 2].isdigit():
        c.take("N")
        b.number = E.read_number(c)


def _o_statement(c: E.Cursor) -> tuple:
    """After "O": the label (number, <name>, or an expression) and the keyword."""
    if c.take("<"):
        j = c.text.find(">", c.pos)
        if j < 0:
            raise BlockError("O-word name without '>'")
        label: Any = c.text[c.pos : j].lower()
        c.pos = j + 1
    elif c.peek() == "[" or c.peek() == "#":
        try:
            label = ("expr", _BRACKETS.value(c))
        except E.ExprError as exc:
            raise BlockError(f"O-word number: {exc}") from None
    else:
        n = E.read_number(c)
        if n is None:
            raise BlockError("O-word without a number or <name>")
        label = n
    kw = ""
    for k in sorted(O_KEYWORDS, key=len, reverse=True):
        if c.text.startswith(k, c.pos):
            kw = k
            c.pos += len(k)
            break
    if not kw:
        if c.at_end():
            # A program number on its own line ("O1000"): Fanuc-style, ignored by LinuxCNC too
            return ("prog", label)
        raise BlockError(f"unknown O-word keyword '{c.text[c.pos : c.pos + 12]}'")
    args: list[Any] = []
    try:
        if kw in ("IF", "ELSEIF", "WHILE", "REPEAT"):
            args.append(_BRACKETS.value(c))
        elif kw in ("CALL",):
            while not c.at_end():
                args.append(_BRACKETS.value(c))
        elif kw in ("RETURN", "ENDSUB") and not c.at_end():
            args.append(_BRACKETS.value(c))
    except E.ExprError as exc:
        raise BlockError(f"O-word {kw.lower()}: {exc}") from None
    return ("o", label, kw.lower(), args)


def _words(c: E.Cursor, b: Block, parser: E.BracketParser) -> None:
    """Words and #-assignments up to the end of the (normalised) line."""
    while not c.at_end():
        ch = c.peek()
        if ch == "#":
            try:
                target = parser.param(c)
            except E.ExprError as exc:
                raise BlockError(f"parameter: {exc}") from None
            if not c.take("="):
                raise BlockError("a parameter alone is not a word: '#' needs '= value'")
            try:
                value = parser.value(c) if parser.named else parser.expr(c)
            except E.ExprError as exc:
                raise BlockError(f"assignment: {exc}") from None
            b.assigns.append((target, value))
            continue
        if ch == "/":
            raise BlockError("'/' inside a block (block delete must start the line)")
        if ch == "," and not parser.named and c.text[c.pos + 1 : c.pos + 2] in ("R", "C"):
            # Fanuc ",R" corner rounding, ",C" chamfer
            c.pos += 1
            letter = "," + c.text[c.pos]
            c.pos += 1
            b.words.append((letter, parser.value(c)))
            continue
        if not (ch.isalpha() or (ch in "@^" and parser.named)):
            raise BlockError(f"malformed number or word '{_token(c.text, c.pos)}'")
        c.take(ch)
        if ch == "O":
            if c.text[c.pos : c.pos + 1].isalpha():
                name = "O" + _alpha_run(c.text, c.pos)
                raise BlockError(
                    f"program name {name} (Okuma OSP): the Okuma dialect is not supported"
                )
            raise BlockError("O word with other words in the block (a program number stands alone)")
        start = c.pos
        nxt = c.text[c.pos : c.pos + 1]
        if not nxt or (nxt.isalpha() and len(_alpha_run(c.text, c.pos)) == 1):
            raise BlockError(f"word '{ch}' has no number")
        if nxt.isalpha() and not _function_at(c.text, c.pos):
            raise BlockError(f"unknown word '{ch}{_alpha_run(c.text, c.pos)}'")
        try:
            value = parser.value(c)
        except E.ExprError as exc:
            if nxt in "0123456789.+-":
                raise BlockError(f"malformed number '{_token(c.text, start)}' after {ch}") from None
            if nxt.isalpha():
                raise BlockError(f"unknown word '{ch}{_token(c.text, start)}'") from None
            raise BlockError(f"word {ch}: {exc}") from None
        follow = c.text[c.pos : c.pos + 1]
        if follow and (follow.isdigit() or follow == "."):
            raise BlockError(f"malformed number '{_token(c.text, start)}' after {ch}")
        if isinstance(value, float) and not math.isfinite(value):
            raise BlockError("number out of range")
        b.words.append((ch, value))


# ----------------------------------------------------------------------------- Fanuc
_F_IF = re.compile(r"IF\[")
_F_WHILE = re.compile(r"WHILE\[")
_F_END = re.compile(r"END(\d+)$")
_F_GOTO = re.compile(r"GOTO")


def parse_fanuc(text: str, file: int, line: int) -> Block | None:
    """A Fanuc (Custom Macro B) line."""
    fast = _plain(text, file, line)
    if fast is not None:
        return fast
    b = Block(file, line)
    if text.lstrip().startswith("$"):
        b.notes.append("'$' header line (Okuma, Mitsubishi file name) ignored")
        return b
    code, comments = strip_comments(text, "fanuc", b.notes)
    code, b.delete = _head(code)
    if code.startswith("%"):
        if code.strip("% \t"):
            b.notes.append("text after '%' ignored")
        return b
    _printable(code)
    c = E.Cursor("".join(code.split()).upper())
    if c.at_end():
        return b
    _n_word(c, b)
    rest = c.text[c.pos :]
    try:
        if rest.startswith("IF["):
            c.take("IF")
            cond = _FANUC.value(c)
            if c.take("GOTO"):
                b.stmt = ("if_goto", cond, _FANUC.value(c))
            elif c.take("THEN"):
                sub = Block(file, line)
                _words(c, sub, _FANUC)
                if sub.words:
                    raise BlockError("IF [..] THEN takes an assignment")
                b.stmt = ("if_then", cond, sub.assigns)
            else:
                raise BlockError("IF [..] without GOTO or THEN")
        elif rest.startswith("WHILE[") or rest.startswith("WH["):
            c.take("WHILE") or c.take("WH")
            cond = _FANUC.value(c)
            if not c.take("DO"):
                raise BlockError("WHILE [..] without DO")
            m = E.read_number(c)
            if m is None:
                raise BlockError("WHILE [..] DO without its number")
            b.stmt = ("while", cond, int(m))
        elif _F_END.match(rest):
            b.stmt = ("end", int(_F_END.match(rest).group(1)))  # type: ignore[union-attr]
            c.pos = len(c.text)
        elif rest.startswith("GOTO"):
            c.take("GOTO")
            b.stmt = ("goto", _FANUC.value(c))
        elif rest.startswith("O") and rest[1:2].isdigit():
            c.take("O")
            num = E.read_number(c)
            b.stmt = ("prog", num)
            if not c.at_end():
                raise BlockError(
                    "O word with other words in the block (a program number stands alone)"
                )
        elif rest.startswith(":") and rest[1:2].isdigit():
            c.take(":")
            b.stmt = ("prog", E.read_number(c))
        else:
            _words(c, b, _FANUC)
    except E.ExprError as exc:
        raise BlockError(str(exc)) from None
    if not c.at_end():
        raise BlockError(f"unexpected '{c.text[c.pos : c.pos + 12]}'")
    return b


# ----------------------------------------------------------------------------- Siemens
S_AXES = "XYZABCIJK"
#: Siemens function-style statements that do not move the tool.
S_PASS_CALLS = (
    "MSG", "SETMS", "SPOS", "SPOSA", "SETAL", "WORKPIECE", "FGROUP", "SOFT", "BRISK",
    "STOPRE", "WAITM", "WAITS", "SUPA", "TRAFOOF", "ORIWKS", "ORIAXES", "FFWON", "FFWOF",
    "G_TOLERANCE", "CFTCP", "CFC", "CFIN", "TRACYL", "TRANSMIT", "CORROF",
)  # fmt: skip
S_FRAMES = ("TRANS", "ATRANS", "ROT", "AROT", "SCALE", "ASCALE", "MIRROR", "AMIRROR")
S_CYCLES = ("CYCLE81", "CYCLE82", "CYCLE83", "CYCLE84", "CYCLE840", "CYCLE85", "CYCLE86")
_S_NAME = re.compile(r"[A-Z_][A-Z0-9_]*")
_S_WORD = re.compile(r"([A-Z])([-+]?(?:\d+\.?\d*|\.\d+))(?![\w.])")
_S_LABEL = re.compile(r"^([A-Z_][A-Z0-9_]{1,31}):(?!=)")
_S_DEF_TYPES = ("REAL", "INT", "BOOL", "CHAR", "STRING", "AXIS", "FRAME")


class SiemensParser:
    """Siemens 840D lines; knows the variables DEF declared so far (per file)."""

    def __init__(self) -> None:
        self.declared: set[str] = set()
        self.expr = E.InfixParser(lambda name: name in self.declared or name.startswith("$"))

    def parse(self, text: str, file: int, line: int) -> Block | None:
        b = Block(file, line)
        code, comments = strip_comments(text, "siemens", b.notes)
        code, b.delete = _head(code)
        bare = re.sub(r"^(?:N\s*\d+\s*)", "", code.strip(), flags=re.IGNORECASE)
        if bare.startswith("(") and bare.endswith(")") and "=" not in bare:
            return b  # old Sinumerik style "( text )": a comment line
        if code.startswith("%"):
            return b
        _printable(code)
        up = code.upper().strip()
        if not up:
            return b
        # N or ":" block number, then a label
        m = re.match(r"^(?:N\s*(\d+)|:\s*(\d+))\s*", up)
        if m:
            b.number = float(m.group(1) or m.group(2))
            up = up[m.end() :]
        m = _S_LABEL.match(up)
        if m:
            b.label = m.group(1)
            up = up[m.end() :].strip()
        if not up:
            return b
        try:
            self._statement(up, b)
        except E.ExprError as exc:
            raise BlockError(str(exc)) from None
        return b

    # ------------------------------------------------------------------ statements
    def _statement(self, up: str, b: Block) -> None:
        first = _S_NAME.match(up)
        word = first.group(0) if first else ""
        if word == "DEF":
            self._def(up[3:], b)
            return
        if word in ("PROC",):
            m = re.match(r"PROC\s+([A-Z_][A-Z0-9_]*)\s*(\((.*)\))?", up)
            if not m:
                raise BlockError("PROC without a name")
            params = []
            if m.group(3):
                for part in m.group(3).split(","):
                    toks = part.split()
                    if toks:
                        name = toks[-1].split("=")[0]
                        params.append(name)
                        self.declared.add(name)
            b.stmt = ("proc", m.group(1), params)
            return
        if word in ("EXTERN",):
            b.extra["keywords"] = ["EXTERN"]
            return
        if word == "IF":
            self._if(up[2:].strip(), b)
            return
        if word in ("GOTOF", "GOTOB", "GOTO", "GOTOC"):
            b.stmt = (word.lower(), up[len(word) :].strip().split()[0])
            return
        if word in ("ELSE", "ENDIF", "LOOP", "ENDLOOP", "ENDWHILE", "ENDFOR", "REPEAT"):
            if up.strip() != word:
                raise BlockError(f"{word} takes nothing after it")
            b.stmt = (word.lower(),)
            return
        if word == "WHILE":
            b.stmt = ("while", self._cond(up[5:]))
            return
        if word == "UNTIL":
            b.stmt = ("until", self._cond(up[5:]))
            return
        if word == "FOR":
            m = re.match(r"FOR\s*(R\d+|[A-Z_][A-Z0-9_]*)\s*=(.*)\bTO\b(.*)", up)
            if not m:
                raise BlockError("FOR needs 'FOR var = start TO end'")
            var = m.group(1)
            target = ("param", float(var[1:])) if re.fullmatch(r"R\d+", var) else ("var", var)
            b.stmt = ("for", target, self._value(m.group(2)), self._value(m.group(3)))
            return
        if word in ("RET", "M17"):
            b.stmt = ("ret",)
            return
        if word == "MCALL":
            rest = up[5:].strip()
            b.extra["mcall"] = self._call(rest) if rest else None
            return
        if word == "CALL":
            m = re.match(r'CALL\s*"?([A-Z_0-9]+)"?', up)
            if not m:
                raise BlockError("CALL without a program name")
            b.stmt = ("call", m.group(1), None, [])
            return
        if word in S_FRAMES:
            self._frame(word, up[len(word) :], b)
            return
        self._words(up, b)

    def _def(self, rest: str, b: Block) -> None:
        rest = rest.strip()
        typ = rest.split()[0] if rest else ""
        if typ not in _S_DEF_TYPES:
            raise BlockError(f"DEF {typ}: unknown type")
        body = rest[len(typ) :]
        assigns = []
        for part in _split_top(body, ","):
            part = part.strip()
            if not part:
                continue
            name, _, value = part.partition("=")
            name = name.strip()
            name = re.sub(r"\[.*\]$", "", name)  # arrays: declared, elements not read
            if not _S_NAME.fullmatch(name):
                raise BlockError(f"DEF {typ}: bad name '{name}'")
            self.declared.add(name)
            if value.strip() and typ not in ("STRING", "CHAR", "FRAME", "AXIS"):
                assigns.append((("var", name), self._value(value)))
            elif typ in ("REAL", "INT", "BOOL"):
                assigns.append((("var", name), 0.0))
        b.stmt = ("def",)
        b.assigns.extend(assigns)

    def _if(self, rest: str, b: Block) -> None:
        m = re.search(r"\b(GOTOF|GOTOB|GOTO|GOTOC)\s+([A-Z_0-9]+)\s*$", rest)
        if m:
            b.stmt = ("if_goto", self._cond(rest[: m.start()]), m.group(1).lower(), m.group(2))
        else:
            b.stmt = ("if", self._cond(rest))

    def _cond(self, text: str) -> Any:
        c = E.Cursor(text.strip())
        node = self.expr.expr(c)
        if not c.at_end():
            raise E.ExprError(f"unexpected '{c.text[c.pos :]}' in a condition")
        return node

    def _value(self, text: str) -> Any:
        c = E.Cursor(text.strip())
        node = self.expr.expr(c)
        if not c.at_end():
            raise E.ExprError(f"unexpected '{c.text[c.pos :]}'")
        return node

    def _call(self, text: str) -> tuple:
        m = re.match(r"([A-Z_][A-Z0-9_]*)\s*\((.*)\)\s*$", text)
        if not m:
            m2 = re.match(r"([A-Z_][A-Z0-9_]*)\s*$", text)
            if m2:
                return (m2.group(1), [])
            raise BlockError(f"malformed call '{text}'")
        args: list[Any] = []
        for part in _split_top(m.group(2), ","):
            part = part.strip()
            if len(part) >= 2 and part[0] == part[-1] == '"':
                args.append(None)  # a string (a swivel data record's name): no number
                continue
            args.append(self._value(part) if part else None)
        return (m.group(1), args)

    def _frame(self, word: str, rest: str, b: Block) -> None:
        values: dict[str, Any] = {}
        rest = rest.strip()
        for m in re.finditer(r"(RPL|[XYZ])\s*=?\s*([^\s=]+(?:\([^)]*\))?)", rest):
            values[m.group(1)] = self._value(m.group(2))
        b.extra["frame"] = (word, values)

    # ------------------------------------------------------------------ words
    def _words(self, up: str, b: Block) -> None:
        keywords: list[str] = []
        for part in _split_words(up):
            if not part:
                continue
            if "=" in part and not part.startswith("="):
                name, _, rhs = part.partition("=")
                self._assign(name.strip(), rhs.strip(), b)
                continue
            if re.fullmatch(r"L\d+", part):
                b.stmt = ("call", part, None, [])  # subprogram L<number>
                continue
            m = _S_WORD.fullmatch(part)
            if m:
                b.words.append((m.group(1), float(m.group(2))))
                continue
            m = re.fullmatch(r"([A-Z_][A-Z0-9_]*)\s*(\(.*\))?", part)
            if not m:
                raise BlockError(f"malformed word '{part}'")
            name = m.group(1)
            if m.group(2) is not None:
                self._function(name, part, b, keywords)
                continue
            if name in W.PASS_KEYWORDS:
                keywords.append(name)
                continue
            if re.fullmatch(r"L\d+", name):
                b.stmt = ("call", name, None, [])
                continue
            if name in ("P",) and b.stmt and b.stmt[0] == "call":
                continue
            if re.fullmatch(r"[A-Z]\d+", name):  # e.g. "G1" split oddly
                b.words.append((name[0], float(name[1:])))
                continue
            if name in W.ERROR_KEYWORDS:
                raise BlockError(W.ERROR_KEYWORDS[name])
            if name in ("MSG", "SETAL", "STOPRE", "WAITM", "SUPA", "CFIN", "CFC"):
                keywords.append(name)
                continue
            if m.group(2) is None and _S_NAME.fullmatch(name) and len(name) >= 2:
                # a subprogram called by its name
                b.stmt = ("call", name, None, [])
                continue
            raise BlockError(f"unknown word '{part}'")
        if keywords:
            b.extra["keywords"] = keywords
        # "L123 P3": the repeat count of a subprogram call
        if b.stmt and b.stmt[0] == "call":
            reps = [v for k, v in b.words if k == "P"]
            b.words = [(k, v) for k, v in b.words if k != "P"]
            if reps:
                b.stmt = ("call", b.stmt[1], reps[0], b.stmt[3])

    def _function(self, name: str, part: str, b: Block, keywords: list[str]) -> None:
        """NAME(args): a drilling cycle, a position pattern, a setting, or a subprogram
        called with parameters."""
        if name in S_CYCLES:
            b.extra["cycle"] = self._call(part)
        elif name in ("HOLES1", "HOLES2"):
            b.extra["pattern"] = self._call(part)
        elif name == "CYCLE800":
            b.extra["swivel"] = self._call(part)
        elif name == "CYCLE832":
            b.extra["hsc"] = self._call(part)
        elif name in S_PASS_CALLS:
            keywords.append(name)
        elif name.startswith("CYCLE") or name.startswith("POCKET") or name.startswith("SLOT"):
            raise BlockError(f"Siemens cycle {name} is not supported")
        else:
            call = self._call(part)
            b.stmt = ("call", name, None, call[1])

    def _assign(self, name: str, rhs: str, b: Block) -> None:
        if name == "T":  # T="name" or T=expr
            if rhs.startswith('"'):
                b.extra["tool"] = rhs.strip('"')
            else:
                b.words.append(("T", self._value(rhs)))
            return
        if name == "D" or name == "F" or name == "S":
            b.words.append((name, self._value(rhs)))
            return
        if name == "CR":
            b.words.append(("R", self._value(rhs)))
            b.extra.setdefault("keywords", []).append("CR=")
            return
        if name in S_AXES and len(name) == 1:
            m = re.fullmatch(r"(IC|AC)\s*\((.*)\)", rhs)
            if m:
                b.extra.setdefault(m.group(1).lower(), set()).add(name)
                rhs = m.group(2)
            b.words.append((name, self._value(rhs)))
            return
        if re.fullmatch(r"R\d+", name):
            b.assigns.append((("param", float(name[1:])), self._value(rhs)))
            return
        if name in W.PASS_ASSIGNMENTS:
            b.extra.setdefault("keywords", []).append(name + "=")
            if name in W.SETTINGS:
                b.extra.setdefault("settings", []).append((name, self._value(rhs)))
            return
        if name in self.declared:
            b.assigns.append((("var", name), self._value(rhs)))
            return
        if name.startswith("$"):
            b.extra.setdefault("keywords", []).append(name + "=")
            return
        raise BlockError(f"assignment to the unknown variable {name} (no DEF before it)")


def _split_top(text: str, sep: str) -> list[str]:
    """Split at ``sep`` outside parentheses and strings."""
    out: list[str] = []
    cur: list[str] = []
    depth, in_str = 0, False
    for ch in text:
        if ch == '"':
            in_str = not in_str
        if not in_str:
            if ch == "(":
                depth += 1
            elif ch == ")":
                depth -= 1
            elif ch == sep and depth == 0:
                out.append("".join(cur))
                cur = []
                continue
        cur.append(ch)
    out.append("".join(cur))
    return out


_S_OPERATOR_END = ("=", "+", "-", "*", "/", "<", ">")
_S_OPERATOR_START = ("=", "+", "-", "*", "/", "<", ">")
_S_WORD_OPERATORS = {"DIV", "MOD", "AND", "OR", "XOR", "NOT", "B_AND", "B_OR", "B_XOR", "B_NOT"}


def _split_words(up: str) -> list[str]:
    """Siemens words: separated by spaces outside parentheses and strings; ``X = 5`` is one
    word; letter-number words written together (``G1X10Y5``) are split."""
    raw: list[str] = []
    cur: list[str] = []
    depth, in_str = 0, False
    for ch in up:
        if ch == '"':
            in_str = not in_str
        if not in_str:
            if ch == "(":
                depth += 1
            elif ch == ")":
                depth -= 1
            elif ch in " \t" and depth == 0:
                raw.append("".join(cur))
                cur = []
                continue
        cur.append(ch)
    raw.append("".join(cur))
    # join "X", "=", "5" and "X=", "5"; and expressions written with blanks around their
    # operators: "R2 = R1 / 15", "R3 = R1 DIV 2" (a word starts with a letter, never with
    # an operator, and no word ends with one)
    merged: list[str] = []
    for tok in raw:
        if not tok:
            continue
        if merged and (
            merged[-1].endswith(_S_OPERATOR_END)
            or tok.startswith(_S_OPERATOR_START)
            or tok in _S_WORD_OPERATORS
            or merged[-1].split(" ")[-1] in _S_WORD_OPERATORS
        ):
            merged[-1] += " " + tok
        else:
            merged.append(tok)
    out: list[str] = []
    for tok in merged:
        if "=" in tok or "(" in tok or '"' in tok:
            out.append(tok)
            continue
        pieces = re.findall(r"[A-Z][-+]?(?:\d+\.?\d*|\.\d+)|[A-Z_][A-Z0-9_]*", tok)
        if "".join(pieces) == tok and all(
            re.fullmatch(r"[A-Z][-+]?(?:\d+\.?\d*|\.\d+)", p) for p in pieces
        ):
            out.extend(pieces)
        else:
            out.append(tok)
    return out
