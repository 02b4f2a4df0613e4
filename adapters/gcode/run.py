"""The full interpreter: runs a program block by block as the controller does.

Programs that are plain lists of words go through the vectorised reader
(:mod:`adapters.gcode.interp`); everything else comes here: parameters and expressions,
control flow, subprograms (in the file, or in files beside it), canned cycles, work
offsets and frames, home returns, cutter compensation, rotary axes. The runner executes
the control flow (:mod:`adapters.gcode.blocks` parses each line once), evaluates every
word with the parameters of the moment, and hands the block to the controller
(:mod:`adapters.gcode.control`), which keeps the modal state and emits the moves.

Every move keeps the line (and file) it came from, and the chain of calls that led there.
A run stops with an error after :data:`MAX_BLOCKS` blocks executed one by one (an endless
loop: a few seconds of interpretation per million) or :data:`control.MAX_MOVES` moves.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from adapters.gcode import blocks as B
from adapters.gcode import exprs as E
from adapters.gcode import words as W
from adapters.gcode.comp import CompError
from adapters.gcode.control import ControlError, Controller, MachineSetup, Move
from adapters.gcode.plain import MIN_RUN, PlainRuns
from adapters.source import Source, check_bytes
from core.model import geometry as g
from core.model.errors import InputError, Notes
from core.model.inputs import read_input
from core.model.tolerances import TOL
from core.model.toolpath import (
    POINTS_DROPPED,
    MoveKind,
    PathMode,
    RotaryMoves,
    ToolPath,
    drop_zero_length,
    empty_columns,
)

#: Most blocks a run may execute one by one (loops included; runs of plain lines handed to
#: the vectorised reader count towards the moves, not here): beyond it the program is taken
#: to loop forever. A million blocks are 12-25 s of interpretation (and most of an hour of
#: machining at 3 ms a block): a program that executes more is refused, not waited for.
MAX_BLOCKS = 1_000_000
#: Deepest subprogram nesting (Fanuc allows 10 M98 levels, LinuxCNC 10 call levels).
MAX_DEPTH = 50
#: Extensions tried for a subprogram in a file of its own, per dialect.
SUB_EXTENSIONS = {
    "linuxcnc": (".ngc", ".NGC", ".nc", ".NC"),
    "fanuc": ("", ".nc", ".NC", ".txt", ".TXT", ".tap", ".TAP"),
    "siemens": (".SPF", ".spf", ".MPF", ".mpf"),
}
#: Fanuc G65 argument letters -> local variables (argument specification I).
G65_ARGS = {
    "A": 1, "B": 2, "C": 3, "I": 4, "J": 5, "K": 6, "D": 7, "E": 8, "F": 9, "H": 11,
    "M": 13, "Q": 17, "R": 18, "S": 19, "T": 20, "U": 21, "V": 22, "W": 23, "X": 24,
    "Y": 25, "Z": 26,
}  # fmt: skip


@dataclass
class Unit:
    """One file of the program: its lines, parsed on demand, and what is in it."""

    index: int
    name: str
    src: Source
    dialect: str
    blocks: dict[int, B.Block | None] = field(default_factory=dict)
    parser: B.SiemensParser | None = None
    runs: PlainRuns | None = None  # runs of plain lines (LinuxCNC and Fanuc)
    _structure: dict[str, Any] | None = None

    @property
    def n(self) -> int:
        return self.src.n_lines

    def block(self, i: int) -> B.Block | None:
        if i in self.blocks:
            return self.blocks[i]
        text = self.src.text(i)
        try:
            if self.dialect == "linuxcnc":
                b = B.parse_linuxcnc(text, self.index, i)
            elif self.dialect == "fanuc":
                b = B.parse_fanuc(text, self.index, i)
            else:
                assert self.parser is not None
                b = self.parser.parse(text, self.index, i)
        except B.BlockError as exc:
            raise self.src.error(i, str(exc)) from None
        self.blocks[i] = b
        return b

    def structure(self) -> dict[str, Any]:
        """Where things are: subroutines, labels, block numbers, loop ends (parsed once)."""
        if self._structure is not None:
            return self._structure
        st: dict[str, Any] = {
            "subs": {},  # LinuxCNC label -> (sub line, endsub line)
            "o_lines": {},  # LinuxCNC label -> [(line, keyword)]
            "progs": {},  # Fanuc O number -> line
            "numbers": {},  # Fanuc N number -> [lines]
            "labels": {},  # Siemens label -> [lines]
            "pairs": {},  # line -> matching line (loops and ifs)
        }
        stack: list[tuple[Any, int, str]] = []
        sub_open: Any = None  # the LinuxCNC subroutine being defined
        for i in range(self.n):
            b = self.block(i)
            if b is None:
                continue
            if b.number is not None:
                st["numbers"].setdefault(int(b.number), []).append(i)
            if b.label is not None:
                st["labels"].setdefault(b.label, []).append(i)
            s = b.stmt
            if s is None:
                continue
            kind = s[0]
            if kind == "o":
                label, kw = s[1], s[2]
                if isinstance(label, tuple):  # o[expression]: a call resolved when it runs
                    if kw != "call":
                        raise self.src.error(
                            i, f"o[...] {kw}: only a call may name its label by an expression"
                        )
                    continue
                if kw == "sub":
                    if sub_open is not None:
                        raise self.src.error(
                            i, f"nested subroutine definition (o{_show(sub_open)} sub is open)"
                        )
                    sub_open = label
                elif kw == "endsub":
                    sub_open = None
                st["o_lines"].setdefault(_key(label), []).append((i, kw))
            elif kind == "prog":
                # a Fanuc program number; LinuxCNC reads a lone o<name> or o[expression]
                # too, and ignores it (its own interpreter, checked): no program to go to
                if isinstance(s[1], int | float):
                    st["progs"].setdefault(int(s[1]), i)
            elif kind in ("while", "if", "loop", "for", "repeat") and self.dialect == "siemens":
                stack.append((kind, i, ""))
            elif kind in ("endwhile", "endif", "endloop", "endfor", "until", "else"):
                if self.dialect != "siemens":
                    continue
                opener = {
                    "endwhile": "while",
                    "endif": "if",
                    "endloop": "loop",
                    "endfor": "for",
                    "until": "repeat",
                    "else": "if",
                }[kind]
                if not stack or stack[-1][0] != opener:
                    raise self.src.error(i, f"{kind.upper()} without its {opener.upper()}")
                if kind == "else":
                    st["pairs"][stack[-1][1]] = i
                    stack[-1] = ("if", i, "else")
                    continue
                _, at, _ = stack.pop()
                st["pairs"][at] = i
                st["pairs"][i] = at
            elif kind == "while" and self.dialect == "fanuc":
                stack.append(("do", i, str(s[2])))
            elif kind == "end" and self.dialect == "fanuc":
                m = str(s[1])
                if not stack or stack[-1][2] != m:
                    raise self.src.error(i, f"END{m} without its WHILE [..] DO{m}")
                _, at, _ = stack.pop()
                st["pairs"][at] = i
                st["pairs"][i] = at
        if stack and self.dialect in ("siemens", "fanuc"):
            kind, at, m = stack[-1]
            what = f"WHILE [..] DO{m}" if kind == "do" else kind.upper()
            raise self.src.error(at, f"{what} without its end")
        if self.dialect == "linuxcnc":
            self._o_pairs(st)
        self._structure = st
        return st

    def _o_pairs(self, st: dict[str, Any]) -> None:
        """Match LinuxCNC O-word statements of one label: sub/endsub, if/elseif/else/endif,
        while/endwhile, do/while, repeat/endrepeat."""
        for label, items in st["o_lines"].items():
            opens: list[tuple[int, str]] = []
            for i, kw in items:
                if kw == "sub":
                    opens.append((i, kw))
                elif kw == "endsub":
                    if not opens or opens[-1][1] != "sub":
                        raise self.src.error(i, f"o{_show(label)} endsub without its sub")
                    at, _ = opens.pop()
                    st["subs"][label] = (at, i)
                    st["pairs"][at] = i
                elif kw in ("if", "while", "do", "repeat"):
                    if kw == "while" and opens and opens[-1][1] == "do":
                        at, _ = opens.pop()
                        st["pairs"][at] = i
                        st["pairs"][i] = at
                        continue
                    opens.append((i, kw))
                elif kw in ("elseif", "else"):
                    if not opens or opens[-1][1] != "if":
                        raise self.src.error(i, f"o{_show(label)} {kw} without its if")
                    at, _ = opens[-1]
                    st["pairs"].setdefault(("chain", at), []).append(i)
                elif kw in ("endif", "endwhile", "endrepeat"):
                    want = {"endif": "if", "endwhile": "while", "endrepeat": "repeat"}[kw]
                    if not opens or opens[-1][1] != want:
                        raise self.src.error(i, f"o{_show(label)} {kw} without its {want}")
                    at, _ = opens.pop()
                    st["pairs"][at] = i
                    st["pairs"][i] = at
                    for e in st["pairs"].get(("chain", at), []):
                        st["pairs"][("end", e)] = i
            if opens:
                i, kw = opens[-1]
                raise self.src.error(i, f"o{_show(label)} {kw} without its end")


_COMMENT = re.compile(rb"\([^)\n]*\)|;[^\n]*")
_FEED_WORD = re.compile(rb"(?<![A-Za-z_])[Ff]\s*(\d+\.?\d*|\.\d+)")


def _first_feed_word(data: bytes) -> tuple[float, int] | None:
    """The first F word of a program with its number (outside comments) and 0-based line."""
    for k, raw in enumerate(data.split(b"\n")):
        m = _FEED_WORD.search(_COMMENT.sub(b" ", raw))
        if m:
            v = float(m.group(1))
            return (v, k) if v > 0 else None
    return None


def _key(label: Any) -> Any:
    return label if isinstance(label, str) else float(label)


def _show(label: Any) -> str:
    return f"<{label}>" if isinstance(label, str) else f"{label:g}"


@dataclass
class Frame:
    """A level of the call stack."""

    unit: Unit
    pc: int
    kind: str  # "main", "sub" (LinuxCNC), "m98", "g65", "spf"
    end: int = -1  # LinuxCNC: the endsub line
    repeats: int = 1
    start: int = 0
    saved: dict[int, Any] | None = None
    loops: list[list[Any]] = field(default_factory=list)
    call_id: int = -1
    args: list[Any] = field(default_factory=list)  # Siemens: values for the PROC parameters


class Runner:
    """Executes one program (see the module docstring)."""

    def __init__(
        self,
        name: str,
        data: bytes,
        dialect: str,
        setup: MachineSetup,
        block_delete: bool,
        search: list[Path] | None = None,
        plain_runs: bool = True,
    ) -> None:
        self.dialect = dialect
        self.block_delete = block_delete
        self.plain_runs = plain_runs and dialect in ("linuxcnc", "fanuc")
        self.notes = Notes(name)
        self.units: list[Unit] = []
        self.main = self._unit(name, data)
        self.search = search or [Path(name).resolve().parent, *map(Path, setup.search)]
        self.store = E.Store(vacant_zero=dialect != "fanuc")
        self.variables: list[dict[str, float]] = [{}]
        self.ctl = Controller(dialect, setup, self.notes, self.store)
        self.ctl.later_feed = _first_feed_word(self.main.src.data)
        self.calls: list[str] = []
        self.call_files: list[str] = []  # per call: the file of its lines ("" the main one)
        self._call_ids: dict[tuple, int] = {}
        self.executed = 0
        if dialect == "linuxcnc":
            for k, v in enumerate(setup.home):
                self.store.set(5161 + k, v)
            for k, v in enumerate(setup.home2):
                self.store.set(5181 + k, v)
            self.store.set(5220, 1.0)

    def _unit(self, name: str, data: bytes) -> Unit:
        src = Source(name, data)
        check_bytes(src, "G-code", "a G-code program")
        u = Unit(len(self.units), name, src, self.dialect)
        if self.dialect == "siemens":
            u.parser = B.SiemensParser()
        elif self.plain_runs:
            u.runs = PlainRuns(src, self.dialect)
        self.units.append(u)
        return u

    # ------------------------------------------------------------------ errors
    def error(self, unit: Unit, line: int, message: str) -> InputError:
        return unit.src.error(line, message)

    # ------------------------------------------------------------------ run
    def run(self) -> list[Move]:
        stack = [Frame(self.main, 0, "main")]
        self.stack = stack
        while stack:
            fr = stack[-1]
            if fr.pc >= fr.unit.n:
                if not self._fall_off(stack):
                    break
                continue
            i = fr.pc
            if fr.unit.runs is not None and self._plain_run(stack, fr, i):
                continue
            fr.pc += 1
            b = fr.unit.block(i)
            if b is None:
                continue
            self.executed += 1
            if self.executed > MAX_BLOCKS:
                raise self.error(
                    fr.unit,
                    i,
                    f"more than {MAX_BLOCKS:,} blocks executed one by one: the program loops "
                    "without end (or is longer than ncperf interprets)",
                )
            for note in b.notes:
                self.notes.add(note, i)
            if b.delete and self.block_delete:
                continue
            try:
                stop = self._execute(stack, fr, b)
            except (E.ExprError, ControlError, CompError) as exc:
                raise self.error(fr.unit, i, str(exc)) from None
            if stop:
                break
        self.ctl.comp.flush()
        return self.ctl.moves

    def _plain_run(self, stack: list[Frame], fr: Frame, i: int) -> bool:
        """Hand the run of plain lines at line i to the vectorised reader, when there is one
        worth it and the controller's state allows (:mod:`adapters.gcode.plain`)."""
        runs = fr.unit.runs
        assert runs is not None
        j = runs.run_at(i)
        if j == i:
            return False
        state = self.ctl.plain_state()
        if state is None or j - i < MIN_RUN:
            return False
        try:
            cols, final, reader = runs.read(i, j, state)
        except InputError:
            runs.refused.add(i)  # block by block gives the verdict
            return False
        self.notes.merge(reader.notes, i)
        try:
            self.ctl.take_run(cols, final, fr.unit.index, stack[-1].call_id)
        except ControlError as exc:
            raise self.error(fr.unit, i, str(exc)) from None
        fr.pc = j
        return True

    def _fall_off(self, stack: list[Frame]) -> bool:
        """The end of a file without M2/M30/M99: the main program ends, a subprogram
        returns."""
        if stack[-1].kind == "main":
            stack.pop()
            return False
        self._finish(stack)
        return bool(stack)

    def _finish(self, stack: list[Frame]) -> None:
        """The current subprogram ends: again from its start while repeats are left, else
        back to its caller."""
        fr = stack[-1]
        if fr.repeats > 1:
            fr.repeats -= 1
            fr.pc = fr.start
            return
        self._returned(stack.pop())

    def _returned(self, fr: Frame) -> None:
        if fr.saved is not None:
            for k, v in fr.saved.items():
                self.store.numbered[k] = v
        if fr.kind in ("sub", "g65", "spf"):
            if len(self.store.scopes) > 1:
                self.store.scopes.pop()
            if fr.kind == "spf" and len(self.variables) > 1:
                self.variables.pop()

    # ------------------------------------------------------------------ one block
    def _execute(self, stack: list[Frame], fr: Frame, b: B.Block) -> bool:
        """Run one block; True when the program ends."""
        s = b.stmt
        if s is not None:
            handled, stop = self._statement(stack, fr, b, s)
            if handled:
                return stop
        # parameter assignments: all values read before any is set; LinuxCNC also reads
        # the block's words before ("#3=6 G1 X#3" moves to the old #3: rs274ngc docs,
        # "Parameter Setting"); Fanuc and Siemens set them first
        values = [(t, self._eval(v)) for t, v in b.assigns]
        early = self.dialect == "linuxcnc" and (b.words or b.extra)
        words = self._words(b) if early else None
        for t, v in values:
            self._assign(t, v)
        if not b.words and not b.extra:
            return False
        if words is None:
            words = self._words(b)
        ctl = self.ctl
        ctl.line = b.line
        ctl.file = b.file
        ctl.call = stack[-1].call_id
        ctl.block_number = int(b.number) if b.number is not None else -1
        m = words.get("M", [])
        g = words.get("G", [])
        # subprogram calls of Fanuc: M98/M99/G65 (after the block's motion)
        if self.dialect in ("fanuc", "linuxcnc") and (98 in m or 99 in m or 650 in g):
            # LinuxCNC reads Fanuc-style M98/M99 subprograms too (2.8 and later)
            return self._fanuc_call(stack, fr, b, words)
        if self.dialect == "siemens" and (98 in m or 99 in m):
            raise ControlError(
                f"M{98 if 98 in m else 99} (Fanuc subprogram call/return) in a "
                f"{self.dialect} program"
            )
        if 90 in g:
            words["G"] = [c for c in g if c != 90]
        extra = self._extra(b.extra)
        ctl.block(words, extra)
        if 90 in g:
            ctl.exact_block()
        if "mcall" in extra:
            ctl.mcall = extra["mcall"]
        if any(c in W.M_END for c in m) or (self.dialect == "siemens" and 17 in m):
            if 17 in m and len(stack) > 1:
                self._finish(stack)
                return False
            return True
        return False

    def _words(self, b: B.Block) -> dict[str, Any]:
        """The block's words, evaluated: letter -> value; "G" (x 10, int) and "M" lists."""
        out: dict[str, Any] = {}
        gs: list[int] = []
        ms: list[int] = []
        for letter, node in b.words:
            v = self._eval(node)
            if v is None:  # a vacant Fanuc variable: the word is not there
                continue
            if not math.isfinite(v):
                raise ControlError(f"{letter} word out of range")
            if letter == "G":
                code = round(v * 10)
                if abs(v * 10 - code) > TOL.code_number:
                    raise ControlError(f"unknown G-code G{v:g}")
                gs.append(code)
            elif letter == "M":
                if v != round(v):
                    raise ControlError(f"M{v:g} is not an M-code ncperf knows")
                ms.append(int(round(v)))
            elif letter in out:
                raise ControlError(f"two {letter} words in one block")
            else:
                out[letter] = v
        if gs:
            out["G"] = gs
        if ms:
            out["M"] = ms
        return out

    def _extra(self, extra: dict[str, Any]) -> dict[str, Any]:
        """The Siemens specials of a block with their expressions evaluated."""
        if not extra:
            return extra
        out = dict(extra)
        for key in ("cycle", "mcall", "pattern", "swivel", "hsc"):
            call = extra.get(key)
            if call is not None:
                out[key] = (call[0], [None if a is None else self._eval(a) for a in call[1]])
        if "frame" in extra:
            kind, values = extra["frame"]
            out["frame"] = (kind, {k: self._eval(v) for k, v in values.items()})
        if "settings" in extra:
            out["settings"] = [(k, self._eval(v)) for k, v in extra["settings"]]
        return out

    def _eval(self, node: Any) -> float | None:
        if isinstance(node, float):
            return node
        return E.evaluate(node, self.store, self.variables[-1])

    def _assign(self, target: tuple, value: float | None) -> None:
        kind = target[0]
        if kind == "param":
            n = self._eval(target[1])
            if n is None:
                raise E.ExprError("parameter number from a vacant variable")
            self.store.set(n, value)
        elif kind == "named":
            self.store.set_named(target[1], 0.0 if value is None else value)
        else:
            self.variables[-1][target[1]] = 0.0 if value is None else value

    # ------------------------------------------------------------------ statements
    def _statement(self, stack: list[Frame], fr: Frame, b: B.Block, s: tuple) -> tuple[bool, bool]:
        """(handled, program ends)."""
        kind = s[0]
        if kind == "o":
            return True, self._oword(stack, fr, b, s)
        if kind == "prog":
            if self.dialect == "fanuc" and fr.kind == "main" and b.line > 0:
                # the next program of the file: the main one ends before it
                if self._program_started:
                    return True, True
            self._program_started = True
            return (not b.words and not b.assigns), False
        if self.dialect == "fanuc":
            return self._fanuc_statement(fr, b, s)
        if self.dialect == "siemens":
            return self._siemens_statement(stack, fr, b, s)
        return False, False

    _program_started = False

    # LinuxCNC O-words
    def _oword(self, stack: list[Frame], fr: Frame, b: B.Block, s: tuple) -> bool:
        _, label, kw, args = s
        if isinstance(label, tuple):
            v = self._eval(label[1])
            label = float(v or 0.0)
        key = _key(label)
        st = fr.unit.structure()
        pairs = st["pairs"]
        i = b.line
        if kw == "sub":
            fr.pc = pairs[i] + 1  # a definition: skip it
            return False
        if kw in ("endsub", "return"):
            value = self._eval(args[0]) if args else None
            if fr.kind != "sub":
                if kw == "endsub":
                    return False
                raise ControlError("o-word return outside a subroutine")
            self._returned(stack.pop())
            if value is not None:
                self.store.set_named("_value", value)
            self.store.set_named("_value_returned", 1.0 if value is not None else 0.0)
            return False
        if kw == "call":
            self._ocall(stack, fr, b, key, [self._eval(a) for a in args])
            return False
        if kw == "if" or kw == "elseif":
            if kw == "elseif":
                # reached by falling out of a taken branch: go to the endif
                fr.pc = pairs[("end", i)]
                return False
            branch = self._branch(fr, i, pairs, b)
            fr.pc = branch
            return False
        if kw == "else":
            fr.pc = pairs[("end", i)]
            return False
        if kw in ("endif",):
            return False
        if kw == "while":
            if i in pairs and pairs[i] < i:  # the end of a do ... while
                if self._eval(args[0]):
                    fr.pc = pairs[i] + 1
                return False
            if not self._eval(args[0]):
                fr.pc = pairs[i] + 1
            return False
        if kw == "endwhile":
            fr.pc = pairs[i]
            return False
        if kw == "do":
            return False
        if kw == "repeat":
            count = int(self._eval(args[0]) or 0)
            fr.loops.append([i, count])
            if count <= 0:
                fr.loops.pop()
                fr.pc = pairs[i] + 1
            return False
        if kw == "endrepeat":
            if fr.loops and fr.loops[-1][0] == pairs[i]:
                fr.loops[-1][1] -= 1
                if fr.loops[-1][1] > 0:
                    fr.pc = pairs[i] + 1
                else:
                    fr.loops.pop()
            return False
        if kw in ("break", "continue"):
            around = self._enclosing_loop(fr, key, i)
            if around is None:
                raise ControlError(f"o{_show(label)} {kw} outside a loop of that label")
            start, end = around
            if kw == "break":
                if fr.loops and fr.loops[-1][0] == start:
                    fr.loops.pop()
                fr.pc = end + 1
            else:
                fr.pc = end
            return False
        raise ControlError(f"o-word {kw} is not supported")

    def _branch(self, fr: Frame, i: int, pairs: dict, b: B.Block) -> int:
        """The first line to run after ``o.. if``: its body, an elseif's or else's, or the
        line after endif."""
        blk = fr.unit.block(i)
        assert blk is not None and blk.stmt is not None
        if self._eval(blk.stmt[3][0]):
            return i + 1
        for e in pairs.get(("chain", i), []):
            eb = fr.unit.block(e)
            assert eb is not None and eb.stmt is not None
            if eb.stmt[2] == "else":
                return e + 1
            if self._eval(eb.stmt[3][0]):
                return e + 1
        return pairs[i] + 1

    def _enclosing_loop(self, fr: Frame, key: Any, i: int) -> tuple[int, int] | None:
        st = fr.unit.structure()
        best = None
        for line, kw in st["o_lines"].get(key, []):
            if kw in ("while", "do", "repeat") and line < i:
                end = st["pairs"].get(line)
                if end is not None and end > i and (best is None or line > best[0]):
                    best = (line, end)
        return best

    def _ocall(self, stack, fr: Frame, b: B.Block, key: Any, args: list) -> None:
        unit = fr.unit
        target = unit.structure()["subs"].get(key)
        if target is None and unit is not self.main:
            target = self.main.structure()["subs"].get(key)
            unit = self.main if target is not None else unit
        if target is None:
            if not isinstance(key, str):
                raise ControlError(f"o{key:g} call: no subroutine o{key:g} in the program")
            unit = self._load(key, b)
            target = unit.structure()["subs"].get(key)
            if target is None:
                raise ControlError(f"o<{key}> call: {unit.name} has no o<{key}> sub")
        if len(stack) >= MAX_DEPTH:
            raise ControlError(f"subroutine calls nested deeper than {MAX_DEPTH}")
        saved = {k: self.store.numbered.get(k) for k in range(1, 31)}
        for k in range(1, 31):
            self.store.numbered.pop(k, None)
        for k, v in enumerate(args, start=1):
            self.store.set(k, v if v is not None else 0.0)
        self.store.scopes.append({})
        start, end = target
        new = Frame(unit, start + 1, "sub", end=end, saved=saved)
        new.call_id = self._register_call(stack, fr, b, f"o{_show(key)} call", unit)
        stack.append(new)

    def _register_call(
        self, stack: list[Frame], fr: Frame, b: B.Block, what: str, callee: Unit
    ) -> int:
        """The call chain's number (an index into ``calls``: "part.ngc:12 o<pocket> call >
        pocket.ngc", the file named when it is not the caller's)."""
        caller = stack[-1].call_id
        text = f"{Path(fr.unit.name).name}:{b.line + 1} {what}"
        if caller >= 0:
            text = f"{self.calls[caller]} > {text}"
        if callee is not fr.unit:
            text = f"{text} > {Path(callee.name).name}"
        key = (caller, fr.unit.index, b.line, what, callee.index)
        if key not in self._call_ids:
            self._call_ids[key] = len(self.calls)
            self.calls.append(text)
            self.call_files.append("" if callee is self.main else Path(callee.name).name)
        return self._call_ids[key]

    def _load(self, name: str, b: B.Block) -> Unit:
        """A subprogram in a file of its own, beside the program (or on the search path)."""
        for u in self.units:
            if Path(u.name).stem.lower() == name.lower() and u is not self.main:
                return u
        for folder in self.search:
            for ext in SUB_EXTENSIONS[self.dialect]:
                for cand in (name, name.lower(), name.upper()):
                    p = folder / f"{cand}{ext}"
                    if p.is_file():
                        return self._unit(str(p), read_input(p, what="a subprogram"))
        where = ", ".join(str(f) for f in self.search)
        raise ControlError(f"subprogram {name} not found (looked for {name}.* in {where})")

    # Fanuc
    def _fanuc_statement(self, fr: Frame, b: B.Block, s: tuple) -> tuple[bool, bool]:
        kind = s[0]
        st = fr.unit.structure()
        if kind == "goto":
            fr.pc = self._fanuc_goto(fr, self._eval(s[1]))
            return True, False
        if kind == "if_goto":
            if self._eval(s[1]):
                fr.pc = self._fanuc_goto(fr, self._eval(s[2]))
            return True, False
        if kind == "if_then":
            if self._eval(s[1]):
                values = [(t, self._eval(v)) for t, v in s[2]]
                for t, v in values:
                    self._assign(t, v)
            return True, False
        if kind == "while":
            if not self._eval(s[1]):
                fr.pc = st["pairs"][b.line] + 1
            return True, False
        if kind == "end":
            fr.pc = st["pairs"][b.line]
            return True, False
        return False, False

    def _fanuc_goto(self, fr: Frame, n: float | None) -> int:
        if n is None:
            raise ControlError("GOTO a vacant variable")
        lines = fr.unit.structure()["numbers"].get(int(n), [])
        if not lines:
            raise ControlError(f"GOTO {n:g}: no block N{n:g}")
        after = [x for x in lines if x >= fr.pc]
        return (after or lines)[0]

    def _fanuc_call(self, stack, fr: Frame, b: B.Block, words: dict[str, Any]) -> bool:
        m = words.get("M", [])
        g = words.get("G", [])
        rest = dict(words)
        rest["M"] = [c for c in m if c not in (98, 99)]
        if not rest["M"]:
            del rest["M"]
        if 650 in g:
            rest = {"G": [c for c in g if c != 650]} if len(g) > 1 else {}
        call_p = words.get("P")
        if 98 in m or 650 in g:
            for k in ("P", "L", "K"):
                rest.pop(k, None)
            if 650 in g:
                rest = {k: v for k, v in rest.items() if k in ("G", "N")}
        if rest:
            self.ctl.block(rest, b.extra)
        if 99 in m:
            if len(stack) == 1:
                self.notes.add(
                    "M99 at the end of the main program repeats it without end: run once",
                    b.line,
                )
                return True
            repeating = stack[-1].repeats > 1
            self._finish(stack)
            if "P" in words and not repeating:  # return to block N p of the caller
                caller = stack[-1]
                caller.pc = self._fanuc_goto(caller, words["P"])
            return False
        if call_p is None:
            raise ControlError("M98/G65 without the program number P")
        p = int(call_p)
        count = int(words.get("L", words.get("K", 1)))
        if 98 in m and p > 9999 and "L" not in words and "K" not in words:
            count, p = p // 10000, p % 10000  # P.... with the repeat count before the number
        unit, line = self._fanuc_program(fr, p, b)
        if len(stack) >= MAX_DEPTH:
            raise ControlError(f"subprogram calls nested deeper than {MAX_DEPTH}")
        new = Frame(unit, line + 1, "g65" if 650 in g else "m98", repeats=max(count, 1))
        new.start = line + 1
        if 650 in g:
            saved = {n: self.store.numbered.get(n) for n in range(1, 34)}
            for n in range(1, 34):
                self.store.numbered.pop(n, None)
            for letter, number in G65_ARGS.items():
                if letter in words and letter not in ("P", "L"):
                    self.store.set(number, words[letter])
            new.saved = saved
            self.store.scopes.append({})
        what = f"M98 P{p}" if 98 in m else f"G65 P{p}"
        new.call_id = self._register_call(stack, fr, b, what, unit)
        if count <= 0:
            return False
        stack.append(new)
        return False

    def _fanuc_program(self, fr: Frame, p: int, b: B.Block) -> tuple[Unit, int]:
        for unit in (fr.unit, self.main):
            line = unit.structure()["progs"].get(p)
            if line is not None:
                return unit, line
        for name in (f"O{p:04d}", f"O{p}", f"{p:04d}", f"{p}"):
            try:
                unit = self._load(name, b)
            except ControlError:
                continue
            line = unit.structure()["progs"].get(p)
            return unit, (line if line is not None else -1)
        raise ControlError(
            f"subprogram O{p} not found (not in this file, nor a file O{p} or {p} beside it)"
        )

    # Siemens
    def _siemens_statement(self, stack, fr: Frame, b: B.Block, s: tuple) -> tuple[bool, bool]:
        kind = s[0]
        st = fr.unit.structure()
        pairs = st["pairs"]
        i = b.line
        if kind in ("gotof", "gotob", "goto", "gotoc"):
            fr.pc = self._siemens_goto(fr, kind, s[1], i)
            return True, False
        if kind == "if_goto":
            if self._eval(s[1]):
                fr.pc = self._siemens_goto(fr, s[2], s[3], i)
            return True, False
        if kind == "if":
            if not self._eval(s[1]):
                fr.pc = pairs[i] + 1
            return True, False
        if kind == "else":
            fr.pc = pairs[i] + 1
            return True, False
        if kind == "proc":
            for name, value in zip(s[2], fr.args, strict=False):
                if value is not None:
                    self.variables[-1][name] = value
            return True, False
        if kind in ("endif", "loop", "repeat", "def"):
            if kind == "def" and b.assigns:
                return False, False
            return True, False
        if kind == "endloop":
            fr.pc = pairs[i] + 1
            return True, False
        if kind == "while":
            if not self._eval(s[1]):
                fr.pc = pairs[i] + 1
            return True, False
        if kind == "endwhile":
            fr.pc = pairs[i]
            return True, False
        if kind == "until":
            if not self._eval(s[1]):
                fr.pc = pairs[i] + 1
            return True, False
        if kind == "for":
            start = self._eval(s[2]) or 0.0
            end = self._eval(s[3]) or 0.0
            loop = [i, end]
            if not fr.loops or fr.loops[-1][0] != i:
                self._assign(s[1], start)
                fr.loops.append(loop)
            else:
                cur = self._eval(s[1] if s[1][0] == "param" else s[1]) or 0.0
                self._assign(s[1], cur + 1)
            value = self._eval(s[1]) or 0.0
            if value > fr.loops[-1][1]:
                fr.loops.pop()
                fr.pc = pairs[i] + 1
            return True, False
        if kind == "endfor":
            fr.pc = pairs[i]
            return True, False
        if kind == "ret":
            if len(stack) > 1:
                self._finish(stack)
                return True, False
            return True, True
        if kind == "call":
            name = s[1]
            reps = int(self._eval(s[2]) or 1) if s[2] is not None else 1
            if b.words or b.extra:
                words = self._words(b)
                self.ctl.line, self.ctl.file = b.line, b.file
                self.ctl.block(words, b.extra)
            unit = self._load(name, b)
            if len(stack) >= MAX_DEPTH:
                raise ControlError(f"subprogram calls nested deeper than {MAX_DEPTH}")
            new = Frame(unit, 0, "spf", repeats=reps)
            new.args = [self._eval(a) if a is not None else None for a in s[3]]
            new.call_id = self._register_call(stack, fr, b, name, unit)
            self.variables.append({})
            self.store.scopes.append({})
            stack.append(new)
            return True, False
        return False, False

    def _siemens_goto(self, fr: Frame, kind: str, label: str, i: int) -> int:
        st = fr.unit.structure()
        lines = list(st["labels"].get(label, []))
        if label.isdigit() or (label.startswith("N") and label[1:].isdigit()):
            lines += st["numbers"].get(int(label.lstrip("N")), [])
        if kind == "gotof":
            cand = [x for x in lines if x > i]
        elif kind == "gotob":
            cand = [x for x in lines if x < i]
            cand = cand[-1:] if cand else []
        else:
            cand = [x for x in lines if x > i] or [x for x in lines if x < i][-1:]
        if not cand:
            if kind == "gotoc":
                return i + 1
            raise ControlError(f"{kind.upper()} {label}: no such label")
        return cand[0]


def _move_columns(moves: list[Move]) -> dict[str, Any]:
    """Columns of Move objects (as the vectorised reader's, plus file, call and op)."""
    n = len(moves)
    cols = empty_columns(n)
    del cols["op_offsets"]
    start = np.array([mv.start for mv in moves], dtype=np.float64).reshape(n, 3)
    end = np.array([mv.end for mv in moves], dtype=np.float64).reshape(n, 3)
    kind = np.array([mv.kind for mv in moves], dtype=np.int8)
    cols["kind"] = kind
    cols["start"] = start
    cols["end"] = end
    cols["line"] = np.array([mv.line + 1 for mv in moves], dtype=np.int64)
    cols["block"] = np.array([mv.block for mv in moves], dtype=np.int64)
    cols["feed"] = np.array([mv.feed for mv in moves], dtype=np.float64)
    cols["tool"] = np.array([mv.tool for mv in moves], dtype=np.int32)
    cols["path_mode"] = np.array(
        [PathMode.EXACT_STOP if mv.exact else PathMode.CONTINUOUS for mv in moves], dtype=np.int8
    )
    cols["dwell"] = np.array([mv.dwell for mv in moves], dtype=np.float64)
    cols["tolerance"] = np.array([mv.tolerance for mv in moves], dtype=np.float64)
    arc = np.flatnonzero(kind >= MoveKind.ARC_CW)
    if arc.size:
        centre = np.array([moves[k].center for k in arc], dtype=np.float64)
        normal = np.array([moves[k].normal for k in arc], dtype=np.float64)
        turns = np.array([moves[k].turns for k in arc], dtype=np.float64)
        sweep = g.arc_sweep(
            start[arc], end[arc], centre, normal, kind[arc] == MoveKind.ARC_CCW, turns
        )
        cols["center"][arc] = centre
        cols["normal"][arc] = normal
        cols["sweep"][arc] = sweep
    cols["file"] = np.array([mv.file for mv in moves], dtype=np.int32)
    cols["call"] = np.array([mv.call for mv in moves], dtype=np.int32)
    cols["op"] = np.array([mv.op for mv in moves], dtype=np.int64)
    cols["inverse"] = np.array([mv.inverse for mv in moves], dtype=np.float64)
    cols["rot"] = np.array([mv.rot_end for mv in moves], dtype=np.float64).reshape(n, 3) - np.array(
        [mv.rot_start for mv in moves], dtype=np.float64
    ).reshape(n, 3)
    cols["feed_unit"] = np.array([mv.feed_unit for mv in moves], dtype=np.float64)
    return cols


def _spliced(moves: list[Move], segments: list[tuple[int, dict[str, Any]]]) -> dict[str, Any]:
    """The columns of the moves with the runs read by the vectorised reader put back in
    their places."""
    cols = _move_columns(moves)
    if not segments:
        return cols
    pieces: list[dict[str, Any]] = []
    at = 0
    for where, seg in segments:
        pieces.append({k: v[at:where] for k, v in cols.items()})
        m = seg["kind"].size
        piece = {k: seg[k] for k in cols if k in seg and isinstance(seg[k], np.ndarray)}
        piece["file"] = np.full(m, seg["file"], dtype=np.int32)
        piece["call"] = np.full(m, seg["call"], dtype=np.int32)
        piece["op"] = np.full(m, seg["op"], dtype=np.int64)
        piece["inverse"] = np.full(m, np.nan)
        piece["rot"] = np.zeros((m, 3))
        piece["feed_unit"] = np.ones(m)
        pieces.append(piece)
        at = where
    pieces.append({k: v[at:] for k, v in cols.items()})
    return {k: np.concatenate([p[k] for p in pieces]) for k in cols}


def _rotary_only(every: dict[str, Any], dialect: str) -> RotaryMoves | None:
    """Take the moves that only turn rotary axes out of the columns (in place)."""
    rot = every["rot"]
    turns = (np.abs(rot) > TOL.resolution).any(axis=1)
    if not turns.any():
        return None
    chord = np.linalg.norm(every["end"] - every["start"], axis=1)
    only = turns & (chord <= TOL.resolution) & (every["kind"] < MoveKind.ARC_CW)
    if not only.any():
        return None
    k = np.flatnonzero(only)
    amount = np.linalg.norm(rot[k], axis=1)
    inverse = every["inverse"][k]
    # F of a rotary-only move is degrees per minute (G94), whatever the length units
    feed = np.where(
        np.isfinite(inverse), amount * inverse / 60.0, every["feed"][k] / every["feed_unit"][k]
    )
    feed = np.where(every["kind"][k] == MoveKind.RAPID, np.nan, feed)
    keep = ~only
    after = np.cumsum(keep)[k] - 1  # the last kept move before each
    moves = RotaryMoves(after=after, travel=rot[k], feed=feed, line=every["line"][k])
    for key in list(every):
        every[key] = every[key][keep]
    return moves


def to_toolpath(runner: Runner, moves: list[Move], units_inch: bool) -> ToolPath:
    """The moves as a ToolPath, in the coordinate system in force at the first move (the
    machine coordinates shifted by that system's offset): the part's coordinates, whatever
    the offsets, as the vectorised reader gives them."""
    src = runner.main.src
    segments = runner.ctl.segments
    if not moves and not segments:
        raise InputError("no moves (G0, G1, G2, G3) in the program", source=src.name)
    every = _spliced(moves, segments)
    origin = np.array(runner.ctl.origin or (0.0, 0.0, 0.0))
    for key in ("start", "end", "center"):
        every[key] = every[key] - origin
    rotary_only = _rotary_only(every, runner.dialect)
    op = every.pop("op")
    inverse = every.pop("inverse")
    every.pop("file")
    call = every.pop("call")
    rot = every.pop("rot")
    every.pop("feed_unit")
    cols = every
    n = op.size
    if n == 0:
        raise InputError("no moves of X, Y or Z in the program", source=src.name)
    change = np.flatnonzero(np.diff(op) != 0) + 1
    offs = np.concatenate([[0], change, [n]]).astype(np.int64)
    names = []
    named = {v: k for k, v in runner.ctl.named_tools.items()}
    for a in offs[:-1]:
        t = int(cols["tool"][a])
        where = int(cols["line"][a])
        if t >= 0:
            names.append(f"T{t} from line {where}")
        elif t in named:
            names.append(f'T="{named[t]}" from line {where}')
        else:
            names.append(f"from line {where}")
    cols["op_offsets"] = offs
    tp = ToolPath(
        **cols,
        op_names=tuple(names),
        source=src.name,
        units="inch" if units_inch else "mm",
        origin=call if (call >= 0).any() else None,
        origins=tuple(runner.calls),
        origin_files=tuple(runner.call_files),
        rotary=rot if rot.any() else None,
        rotary_only=rotary_only,
    )
    timed = np.isfinite(inverse)
    if timed.any():
        # G93: each move takes 1 / F minutes, so its feed is its length times F
        feed = tp.feed.copy()
        feed[timed] = tp.length[timed] * inverse[timed] / 60.0
        tp = dataclasses.replace(tp, feed=feed)
    if tp.rotary is not None and runner.dialect == "fanuc":
        # Fanuc: with linear and rotary axes together F is the rate along all of them,
        # degrees counted as millimetres (Fanuc 0i-MF operator's manual, "Feedrate for
        # rotary axis"): the rate along X, Y, Z is F L / sqrt(L^2 + sum of rotations^2)
        turn = np.einsum("ij,ij->i", tp.rotary, tp.rotary)
        comp = tp.is_feed & (turn > 0) & ~timed
        if comp.any():
            feed = tp.feed.copy()
            L = tp.length[comp]
            feed[comp] *= L / np.sqrt(L * L + turn[comp])
            tp = dataclasses.replace(tp, feed=feed)
            runner.notes.add(
                "moves of linear and rotary axes together: F taken along all axes (Fanuc), "
                "the feed along X, Y, Z is lower",
                int(tp.line[np.argmax(comp)]) - 1,
                int(comp.sum()),
            )
    tp, removed = drop_zero_length(tp)
    if removed.size:
        runner.notes.add(POINTS_DROPPED, int(cols["line"][removed[0]] - 1), int(removed.size))
    if tp.n == 0:
        raise InputError("no moves (G0, G1, G2, G3) in the program", source=src.name)
    return tp


def run_program(
    name: str,
    data: bytes,
    dialect: str,
    block_delete: bool = False,
    setup: MachineSetup | None = None,
    *,
    plain_runs: bool = True,
) -> ToolPath:
    """The ToolPath of a program, run by the full interpreter (``plain_runs=False``: every
    block by itself, without handing runs of plain lines to the vectorised reader)."""
    runner = Runner(
        name, data, dialect, setup or MachineSetup(), block_delete, plain_runs=plain_runs
    )
    moves = runner.run()
    ctl = runner.ctl
    if not ctl.units_set:
        runner.notes.add("no G20/G21 (or G70/G71): millimetres assumed")
    if ctl.path_mode is None:
        note = W.path_mode_note(dialect, runner.ctl.setup.default_path_mode)
        if note:
            runner.notes.add(note)
    tp = to_toolpath(runner, moves, ctl.scale != 1.0)
    return dataclasses.replace(tp, notices=runner.notes.notices())
