"""Input generators for the fuzz harness: text and bytes only.

Shared by the property tests (``tests/test_fuzz_properties.py``, which drive them with a
Hypothesis ``randoms()`` so that failures shrink) and the long fuzz run
(``benchmarks/fuzz.py``, which drives them with ``random.Random``). Every generator takes a
``random.Random``-like object and returns ``str`` or ``bytes``; this module reads the bundled
example programs and machine presets as plain files and imports nothing from ``core``,
``adapters`` or ``plugins``.

Families:

* G-code: :func:`gcode_program` (grammar: motion, arcs, modal codes, dwell, offsets, cycles,
  comments with hostile characters, O-words, parameters and expressions, per dialect),
  :func:`gcode_mutant` (byte mutations of ``examples/*.ngc`` and ``tests/programs/*.ngc``);
* APT CL data: :func:`cl_program`, :func:`cl_mutant`;
* traces: :func:`csv_trace`, :func:`shdr_trace`, :func:`mutate_lines` (for traces made by
  ``ncperf profile``);
* machine files: :func:`machine_toml` (mutations of ``core/model/presets/*.toml``);
* anything: :func:`random_bytes`, :func:`mutate_bytes`;
* the command line: :func:`cli_case`.
"""

from __future__ import annotations

import math
import random
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
PROGRAMS = ROOT / "tests" / "programs"
PRESETS = ROOT / "core" / "model" / "presets"

Rng = random.Random

#: Extensions per reader (the G-code one picks the dialect: .ngc LinuxCNC, .mpf Siemens).
GCODE_EXTENSIONS = (".ngc", ".nc", ".mpf")
CL_EXTENSIONS = (".cl", ".apt", ".cls", ".clsf", ".ncl")
DIALECT_OF = {".ngc": "linuxcnc", ".nc": "fanuc", ".mpf": "siemens"}

# ------------------------------------------------------------------------------- atoms
#: Characters that act on a terminal or split a line, and text that is not plain ASCII.
HOSTILE = (
    "\x1b[31m",
    "\x1b]0;title\x07",
    "\x1b[2J",
    "\r",
    "\x7f",
    "\x85",
    "\x9b",
    "\x08",
    "\x0b",
    "\x0c",
    "\t",
    "\u2028",
    "\u2029",
    "\u202e",
    "\u200f",
    "\ufeff",
    "\x00",
    "é",
    "中文",
    "\U0001f600",
    "Ω",
    "\x1c",
)

#: Numbers at the edges: zero signs, subnormals, overflow, 400 digits, malformed text.
EDGE_NUMBERS = (
    "0",
    "-0",
    "-0.0",
    "0.",
    ".5",
    "-.5",
    "+3",
    "1e306",
    "-1e306",
    "1.7976931348623157e308",
    "1e308",
    "1e309",
    "5e-324",
    "1e-310",
    "1e-300",
    "2.2250738585072014e-308",
    "9" * 400,
    "-" + "9" * 400,
    "0." + "0" * 400 + "1",
    "1" + "0" * 40,
    "123456789012345678901234567890",
    "1e5",
    "1E-5",
    "2.5e+3",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "Infinity",
    "--3",
    "1.2.3",
    "0x10",
    "1_000",
    "\u0663",
    "\uff11",
    "1e",
    ".",
    "-",
    "",
    "4294967296",
    "9223372036854775807",
    "9223372036854775808",
    "-9223372036854775809",
    "18446744073709551616",
    "1e15",
    "1e-9",
    "0.000001",
    "360",
    "720",
    "1e6",
    "999999.9999",
    "1000000.0001",
)


def chance(rng: Rng, p: float) -> bool:
    return rng.random() < p


def plain_number(rng: Rng, lo: float = -200.0, hi: float = 200.0) -> str:
    """A number a CAM post could write."""
    x = rng.uniform(lo, hi)
    style = rng.randint(0, 4)
    if style == 0:
        return str(int(x))
    if style == 1:
        return f"{x:.3f}"
    if style == 2:
        return f"{x:.4f}".rstrip("0")
    if style == 3:
        return f"{x:.1f}"
    return repr(round(x, 6))


def number(rng: Rng, edge: float = 0.15, lo: float = -200.0, hi: float = 200.0) -> str:
    """Mostly plain numbers, sometimes one from :data:`EDGE_NUMBERS`."""
    if chance(rng, edge):
        return rng.choice(EDGE_NUMBERS)
    return plain_number(rng, lo, hi)


def positive(rng: Rng, edge: float = 0.15, lo: float = 1.0, hi: float = 6000.0) -> str:
    if chance(rng, edge):
        return rng.choice(EDGE_NUMBERS)
    return plain_number(rng, lo, hi).lstrip("-")


def hostile_text(rng: Rng, max_len: int = 12) -> str:
    """Short free text: letters, punctuation and characters that act on a terminal."""
    parts = []
    for _ in range(rng.randint(0, max_len)):
        r = rng.random()
        if r < 0.3:
            parts.append(rng.choice(HOSTILE))
        elif r < 0.4:
            parts.append(chr(rng.randint(0, 0x2FFF)))
        else:
            parts.append(rng.choice("abcXYZ 0123456789.,;:()[]#=/$%-+*"))
    return "".join(parts).replace("\x00", "" if chance(rng, 0.9) else "\x00")


def to_bytes(rng: Rng, text: str, corrupt: float = 0.05) -> bytes:
    """UTF-8, sometimes with a byte that is not UTF-8 or CR line ends."""
    data = text.encode("utf-8", "surrogatepass")
    if chance(rng, corrupt) and data:
        k = rng.randint(0, len(data))
        data = data[:k] + rng.choice((b"\xff", b"\xc3", b"\xed\xa0\x80", b"\x80")) + data[k:]
    if chance(rng, corrupt):
        data = data.replace(b"\n", rng.choice((b"\r\n", b"\r", b"\n\n")))
    return data


# ------------------------------------------------------------------------------- G-code
_FUNCS_NGC = ("SIN", "COS", "TAN", "ASIN", "ACOS", "SQRT", "ABS", "EXP", "LN", "ROUND", "FIX")
_OPS_NGC = ("+", "-", "*", "/", "MOD", "**", "AND", "OR", "XOR", "EQ", "NE", "LT", "GT", "LE")
_FUNCS_SIE = ("SIN", "COS", "TAN", "SQRT", "ABS", "POT", "TRUNC", "ROUND", "LN", "EXP", "ATAN2")
_OPS_SIE = ("+", "-", "*", "/", "DIV", "MOD", "==", "<>", ">", "<", ">=", "<=", "AND", "OR")
#: How wild a generated input is, chosen once per input: the chance of an edge number per
#: value, and (scaled) of constructs the readers refuse. 0: a program a CAM post could write.
EDGE_LEVELS = (0.0, 0.0, 0.01, 0.03, 0.1, 0.25)


class _Gcode:
    """The grammar of one G-code program: its dialect, its edge level, where the tool is
    (so that some arcs are consistent and go deep into the models)."""

    def __init__(self, rng: Rng, dialect: str, edge: float) -> None:
        self.rng, self.dialect, self.edge = rng, dialect, edge
        self.siemens = dialect == "siemens"

    # atoms
    def wild(self, p: float = 1.0) -> bool:
        """A construct that is often refused: never at edge level 0."""
        return self.rng.random() < p * self.edge * 1.5

    def num(self, lo: float = -200.0, hi: float = 200.0) -> str:
        return number(self.rng, self.edge, lo, hi)

    def pos(self, lo: float = 1.0, hi: float = 6000.0) -> str:
        if not self.edge and lo == 1.0:
            lo = 300.0  # a plain program's feeds: cycles of minutes, not hours
        return positive(self.rng, self.edge, lo, hi)

    def var(self) -> str:
        rng = self.rng
        if self.siemens:
            return rng.choice(("R1", "R2", "R10", "R99", f"R{rng.randint(0, 99)}"))
        choices = ["#1", "#2", "#3", "#100", "#101", f"#{rng.randint(1, 33)}"]
        if self.dialect == "linuxcnc":
            choices += ["#<a>", "#<_g>", "#<depth>"]
        if self.wild(0.3):
            choices += ["##1", "#5220", f"#{rng.randint(0, 99999)}", "#<undefined>", "#-1"]
        return rng.choice(choices)

    def expr(self, depth: int = 0) -> str:
        """An expression in the dialect's syntax (brackets for ISO, parentheses for Siemens)."""
        rng, sie = self.rng, self.siemens
        r = rng.random()
        if depth > 2 or r < 0.4:
            return self.num(-50, 50) if chance(rng, 0.6) else self.var()
        lb, rb = ("(", ")") if sie else ("[", "]")
        if r < 0.6:
            f = rng.choice(_FUNCS_SIE if sie else _FUNCS_NGC)
            if not self.edge:
                f = rng.choice(("SIN", "COS", "ABS", "ROUND"))
            if f == "ATAN2":
                return f"{f}({self.expr(depth + 1)},{self.expr(depth + 1)})"
            return f"{f}{lb}{self.expr(depth + 1)}{rb}"
        if r < 0.65 and not sie:
            return f"ATAN[{self.expr(depth + 1)}]/[{self.expr(depth + 1)}]"
        if r < 0.68 and self.dialect == "linuxcnc":
            return "EXISTS[#<a>]"
        op = rng.choice(_OPS_SIE if sie else _OPS_NGC) if self.edge else rng.choice("+-*")
        inner = f"{self.expr(depth + 1)} {op} "
        inner += self.expr(depth + 1)
        return f"{lb}{inner}{rb}" if chance(rng, 0.8) or not sie else inner

    def value(self, lo: float = -200.0, hi: float = 200.0) -> str:
        """A word value: a number, or (sometimes) a parameter or an expression."""
        if chance(self.rng, 0.08):
            e = self.expr()
            if self.siemens:
                return "=" + e
            return e if e.startswith(("[", "#")) else f"[{e}]"
        return self.num(lo, hi)

    def axes(self, letters: str = "XYZ") -> str:
        rng = self.rng
        picked = [a for a in letters if chance(rng, 0.6)] or [rng.choice(letters)]
        out = []
        for a in picked:
            if self.siemens and chance(rng, 0.05):
                out.append(f"{a}={rng.choice(('IC', 'AC'))}({self.num()})")
            else:
                out.append(f"{a}{self.value()}")
        return " ".join(out)

    def comment(self) -> str:
        rng = self.rng
        text = hostile_text(rng) if self.edge else "".join(rng.choices("abc XYZ 0123.,:-", k=9))
        r = rng.random()
        if r < 0.5 or (r < 0.8 and not self.siemens and self.dialect != "linuxcnc"):
            return "(" + text.replace("(", "").replace(")", "") + ")"
        if r < 0.8:
            return ";" + text
        if r < 0.9 and self.dialect == "linuxcnc":
            kind = rng.choice(("MSG", "DEBUG", "PRINT", "LOGOPEN", "LOG"))
            return f"({kind},{text.replace(')', '').replace('(', '')} #1)"
        return "(" + text if self.wild() else "(x)"

    # blocks
    def motion(self) -> str:
        rng = self.rng
        g = rng.choice(("G0", "G1", "G1", "G1", "G2", "G3", "G01", "G02"))
        if not self.edge:
            g = rng.choice(("G0", "G1", "G1", "G01"))  # arcs: only the consistent ones
        parts = [g, self.axes()]
        if g in ("G2", "G3", "G02"):
            if chance(rng, 0.6):
                parts.append(self.axes("IJ" if chance(rng, 0.9) else "IJK"))
            elif self.siemens and chance(rng, 0.5):
                parts.append(f"CR={self.num()}")
            else:
                parts.append(f"R{self.value()}")
            if chance(rng, 0.05):
                turns = rng.choice(("1", "2", "0", "-1", "1000000", "2.5", "99999999999"))
                parts.append(f"TURN={turns}" if self.siemens else f"P{turns}")
        if chance(rng, 0.05):
            parts.append(self.axes("ABC"))
        if chance(rng, 0.4):
            parts.append(f"F{self.pos()}")
        return " ".join(parts)

    def arc(self) -> list[str]:
        """A G17 arc that is consistent: a line to its start, then G2/G3 to its end."""
        rng = self.rng
        cx, cy = rng.uniform(-100, 100), rng.uniform(-100, 100)
        r = rng.choice((rng.uniform(0.01, 50), rng.uniform(1, 10), 1e-4, 500.0))
        a0 = rng.uniform(0, 2 * math.pi)
        a1 = a0 + rng.choice((rng.uniform(-6.3, 6.3),) * 4 + (0.0, math.pi, 1e-6))
        if not self.edge:
            a1 = a0 + rng.uniform(0.1, 3.0) * rng.choice((1, -1))
        sx, sy = cx + r * math.cos(a0), cy + r * math.sin(a0)
        ex, ey = cx + r * math.cos(a1), cy + r * math.sin(a1)
        g = rng.choice(("G2", "G3"))
        nd = rng.choice((3, 4, 6))
        end = f"X{ex:.{nd}f} Y{ey:.{nd}f}"
        if chance(rng, 0.15):
            end += f" Z{rng.uniform(-5, 5):.3f}"  # a helix
        if chance(rng, 0.7):
            centre = f"I{cx - sx:.{nd}f} J{cy - sy:.{nd}f}"
        elif self.siemens and chance(rng, 0.5):
            centre = f"CR={r:.{nd}f}"
        else:
            centre = f"R{r:.{nd}f}"
        feed = f" F{self.pos(100, 3000)}" if chance(rng, 0.5) else ""
        return [f"G1 X{sx:.{nd}f} Y{sy:.{nd}f}{feed}", f"{g} {end} {centre}"]

    def modal(self) -> str:
        rng = self.rng
        opts = ["G17", "G90", "G91", "G21", "G61", "G64", "G94", "G40", "G49", "G80"]
        opts += [f"S{self.pos()} M3", "M5", "M8", "M9", "M0", "M1", "G18", "G19", "G20"]
        if self.dialect == "linuxcnc":
            tol = self.pos(0.001, 1)
            opts += [f"G64 P{tol}", f"G64 P{tol} Q{tol}", "G61.1", "G90.1", "G91.1", "G43.1 Z1"]
        if self.siemens:
            opts += ["G60", "G641", "G642", "G643", "G644", "G645", "G70", "G71", "G700", "G710"]
            opts += [f"G642 ADIS={self.pos(0, 1)}", f"CTOL={self.pos(0, 1)}", "G500", "G505"]
            opts += ["SOFT", "BRISK", "FFWON", "COMPCAD", "COMPON", "COMPOF", "STOPRE", "CFC"]
            opts += ["SUPA G0 Z0", "G153 G0 Z0", f'MSG("{self.comment().strip("(;)")}")']
        if self.dialect == "fanuc":
            opts += ["G05.1 Q1", "G08 P1", "G61.1", "G54.1 P1", "G50", "G93", "G95", "G9 G1 X1"]
        if self.wild():
            opts += ["G15", "G16 X1", "G5.2 X1 Y1 P1", "G7", "G33.1 Z-1 K1", "TRAORI", "FLIN"]
            opts += ["G93", "G95", "G38.2 Z-1 F100", "G12 I5", "G47", "G28.1", "G10 L10 P1"]
        return rng.choice(opts)

    def setup(self) -> str:
        rng = self.rng
        n, p = self.num, self.pos
        opts = [
            f"G4 P{p(0, 5)}",
            f"T{rng.choice(('1', '2', '0', '99'))} M6",
            f"G43 H{rng.randint(0, 9)} Z{n()}",
            f"G41 D{rng.randint(0, 9)}",
            f"G42 D{rng.randint(0, 9)}",
            rng.choice(("G54", "G55", "G56", "G57", "G58", "G59")),
            f"G10 L2 P{rng.randint(1, 6)} X{n()} Y{n()} Z{n()}",
            f"G10 L20 P{rng.randint(1, 6)} X{n()} Y{n()}",
            f"G92 X{n()} Y{n()} Z{n()}",
            f"G52 X{n()} Y{n()}",
            f"G53 G0 Z{n()}",
            "G28",
            f"G28 Z{n()}",
            f"G30 X{n()}",
            f"G68 X{n()} Y{n()} R{n()}",
            "G69",
            f"G51 X{n()} Y{n()} P{p(0.1, 3)}",
            "G50",
            f"G51.1 X{n()}",
            "G50.1",
        ]
        if self.dialect == "linuxcnc":
            opts += [f"G41.1 D{p(0, 20)}", f"G42.1 D{p(0, 20)}", "G59.1", "G92.1", "G92.2"]
            opts += [f"G10 L1 P{rng.randint(1, 9)} R{p(0, 10)} Z{n()}"]
        if self.wild():
            opts += [f"G04 P{rng.choice(('100000', '86401', '1e9', '-1'))}", "T99999999999 M6"]
            opts += ["T-1 M6", "T1.5 M6", "G54.1 P300", "G59.3", "G92.3"]
        cyc = rng.choice(("G81", "G82", "G83", "G73", "G84", "G85", "G86", "G89", "G74", "G76"))
        opts.append(
            f"{rng.choice(('G98', 'G99', ''))} {cyc} X{n()} Y{n()} Z{n(-20, 0)} R{n(0, 10)}"
            + (f" Q{p(0.1, 5)}" if chance(rng, 0.5) else "")
            + (f" P{p(0, 2)}" if chance(rng, 0.3) else "")
            + (
                f" {rng.choice('LK')}{rng.choice(('0', '1', '3', '2.5'))}"
                if chance(rng, 0.2)
                else ""
            )
            + (f" F{p()}" if chance(rng, 0.7) else "")
        )
        if self.siemens:
            opts += [
                f"TRANS X{n()} Y{n()}",
                f"ATRANS Z{n()}",
                f"ROT RPL={n()}",
                f"SCALE X{p(0.1, 3)}",
                "MIRROR X0",
                f"CYCLE81({n()}, {n()}, {n()}, {n()})",
                f"CYCLE83({n()}, 0, 2, {n()}, , , 5, , , , , 0)",
                f"MCALL CYCLE82({n()}, 0, 2, , 6, 1.5)",
                "MCALL",
                f"G4 F{p(0, 5)}",
                f"G4 S{p(0, 5)}",
            ]
            if self.wild():
                opts += [f"CIP X{n()} Y{n()} I1={n()} J1={n()}", f"POLY X=PO[{n()},{n()}]"]
        if self.dialect == "fanuc" and self.wild():
            opts += [f"M98 P{rng.randint(0, 9999)}", "M99", f"G65 P{rng.randint(0, 99)} A{n()}"]
        return rng.choice(opts)

    def assignment(self) -> str:
        e = self.expr()
        if self.siemens:
            if chance(self.rng, 0.8):
                return f"R{self.rng.randint(0, 99)}={e}"
            return f"DEPTH={e}"
        return f"{self.var()}={e}"

    def body(self) -> list[str]:
        return [self.block() for _ in range(self.rng.randint(0, 3))]

    def control(self) -> list[str]:
        rng = self.rng
        if self.dialect == "linuxcnc":
            n = rng.choice(("100", "101", "<s>", "<sub_1>"))
            if self.wild(0.3):
                n = rng.choice(("[#1+100]", "999999999", "0", "<>"))
            cond = f"[{self.expr()}]"
            kind = rng.random()
            if kind < 0.3:
                out = [f"o{n} if {cond}", *self.body()]
                if chance(rng, 0.5):
                    out += [f"o{n} elseif {cond}", *self.body()]
                if chance(rng, 0.5):
                    out += [f"o{n} else", *self.body()]
                out.append(f"o{n} endif")
            elif kind < 0.45:
                out = ["#1 = 0", f"o{n} while [#1 LT 3]", *self.body(), "#1 = [#1 + 1]"]
                out.append(f"o{n} endwhile")
            elif kind < 0.6:
                times = rng.choice(("[3]", "[0]", "[2]")) if not self.wild() else f"[{self.num()}]"
                out = [f"o{n} repeat {times}", *self.body(), f"o{n} endrepeat"]
            else:
                args = " ".join(f"[{self.expr()}]" for _ in range(rng.randint(0, 3)))
                out = [f"o{n} sub", *self.body(), f"o{n} endsub", f"o{n} call {args}"]
                if self.wild(0.3):
                    out.insert(1, f"o{n} call")  # recursion
        elif self.dialect == "fanuc":
            op = rng.choice(("GT", "LT", "EQ", "NE", "GE"))
            cond = f"[{self.expr()} {op} {self.num()}]"
            label = rng.choice(("10", "20", "9999"))
            r = rng.random()
            if r < 0.4:
                k = rng.choice(("1", "2", "3"))
                out = ["#1=0", f"WHILE [#1 LT 3] DO{k}", *self.body(), "#1=#1+1", f"END{k}"]
            elif r < 0.8:
                out = [f"IF {cond} GOTO{label}", *self.body(), f"N{label} G1 X{self.num()}"]
            else:
                out = [f"IF {cond} THEN #1={self.expr()}"]
        else:
            cond = f"{self.expr()} {rng.choice(('>', '<', '==', '<>', '>=', '<='))} {self.num()}"
            label = rng.choice(("LAB1", "MARK", "L_2"))
            r = rng.random()
            if r < 0.25:
                out = [f"IF {cond}", *self.body(), "ELSE", *self.body(), "ENDIF"]
            elif r < 0.4:
                out = ["R1=0", "WHILE R1<3", *self.body(), "R1=R1+1", "ENDWHILE"]
            elif r < 0.5:
                out = ["R1=0", "REPEAT", *self.body(), "R1=R1+1", "UNTIL R1>=2"]
            elif r < 0.6:
                hi = rng.choice(("3", "1")) if not self.wild() else rng.choice(("1000000", "-5"))
                out = [f"FOR R1=1 TO {hi}", *self.body(), "ENDFOR"]
            elif r < 0.85:
                out = [f"IF {cond} GOTOF {label}", *self.body(), f"{label}:"]
            else:
                out = [f"{label}:", *self.body()]
                out += ["" if self.wild(0.3) else "R1=R1+1", f"IF R1<3 GOTOB {label}"]
        if self.wild(0.5) and out:
            out.pop(rng.randrange(len(out)))  # unbalanced
        return out

    def block(self) -> str:
        rng = self.rng
        r = rng.random()
        if r < 0.5:
            line = self.motion()
        elif r < 0.63:
            line = self.modal()
        elif r < 0.72:
            line = self.setup()
        elif r < 0.78:
            line = self.assignment()
        elif r < 0.86:
            line = self.comment()
        elif r < 0.9:
            line = f"F{self.pos()}"
        elif r < 0.96:
            line = self.axes()  # modal motion continues
        elif self.wild():
            line = "".join(rng.choice("GXYZIJKRFNPQ#[]=.-0123456789 ()") for _ in range(8))
        else:
            line = rng.choice(("", " ", "\t", "/G1 X1", "N10 G1 X2"))
        if chance(rng, 0.08):
            line = f"N{rng.choice(('10', '1', '99999', str(rng.randint(0, 10**4))))} {line}"
        if chance(rng, 0.03):
            line = "/" + line
        if chance(rng, 0.06):
            line = f"{line} {self.comment()}"
        if chance(rng, 0.03):
            line = line.lower()
        return line

    def program(self, max_lines: int) -> str:
        rng = self.rng
        lines: list[str] = []
        if chance(rng, 0.2):
            lines.append("%")
        if self.dialect == "fanuc" and chance(rng, 0.2):
            lines.append(rng.choice(("O1000", "O0001 (PART)")))
        if self.wild(0.3):
            lines.append(rng.choice(("O1000", "%_N_PART_MPF", "o<main> sub", "%%")))
        if self.siemens:
            if chance(rng, 0.3):
                lines.append(f"DEF REAL DEPTH={self.num(0, 10)}")
            units = rng.choice(("G71", "G21", "G710"))
            lines.append(f"{units} G90 G17 {rng.choice(('G642', 'G64', 'G60', ''))}")
        elif chance(rng, 0.85):
            modes = ("G64", "G61", "G64 P0.01", "") if self.dialect == "linuxcnc" else ("G64", "")
            lines.append(f"G21 G90 G17 {rng.choice(modes)}".strip())
        if self.dialect == "linuxcnc":
            lines.append(rng.choice(("#<a> = 1", "#<depth> = 2", "")))
        lines.append(f"G0 X{plain_number(rng)} Y{plain_number(rng)} Z{plain_number(rng, 0, 50)}")
        if chance(rng, 0.8):
            lines.append(
                f"G1 Z{plain_number(rng, -5, 0)} F{plain_number(rng, 100, 3000).lstrip('-')}"
            )
        budget = rng.randint(1, max_lines)
        while budget > 0:
            r = rng.random()
            if r < 0.07:
                block = self.control()
            elif r < 0.2:
                block = self.arc()
            else:
                block = [self.block()]
            lines += block
            budget -= len(block)
        end = ("M30", "M2", "M02", "M30\n%")
        if self.wild():
            end += ("RET", "M17", "M99", "%\nG1 X1", "")
        lines.append(rng.choice(end))
        return "\n".join(lines) + ("\n" if chance(rng, 0.95) else "")


def gcode_program(
    rng: Rng, dialect: str | None = None, max_lines: int = 24, edge: float | None = None
) -> str:
    """A G-code program from the grammar; ``dialect`` None picks one, ``edge`` (how many edge
    numbers and refused constructs, see :data:`EDGE_LEVELS`) None picks one."""
    dialect = dialect or rng.choice(("linuxcnc", "fanuc", "siemens"))
    level = rng.choice(EDGE_LEVELS) if edge is None else edge
    return _Gcode(rng, dialect, level).program(max_lines)


def expression(rng: Rng, dialect: str) -> str:
    """An expression in the dialect's syntax."""
    return _Gcode(rng, dialect, rng.choice(EDGE_LEVELS)).expr()


# ------------------------------------------------------------------------------- mutation
GCODE_TOKENS = (
    b"G0",
    b"G1",
    b"G2",
    b"G3",
    b"G4 P",
    b"G17",
    b"G18",
    b"G19",
    b"G20",
    b"G91",
    b"G61",
    b"G64 P",
    b"G41 D1",
    b"G42.1 D5",
    b"G40",
    b"G10 L2 P1 X",
    b"G92 X",
    b"G68 R",
    b"G81 R",
    b"G83 Q",
    b" R",
    b" I",
    b" J",
    b" K",
    b" F",
    b" X",
    b" Y",
    b" Z",
    b" A",
    b"#1=",
    b"#<a>",
    b"[",
    b"]",
    b"(",
    b")",
    b";",
    b"%",
    b"/",
    b"O100",
    b"o100 sub",
    b"o100 endsub",
    b"o100 call",
    b"o1 while [1]",
    b"o1 endwhile",
    b"M98 P",
    b"M99",
    b"R1=",
    b"CR=",
    b"GOTOB ",
    b"WHILE [1] DO1",
    b"END1",
    b"\x1b[2J",
    b"\r",
    b"\x00",
    b"\xff",
    b"\t",
)


def _lines(data: bytes) -> list[bytes]:
    return data.split(b"\n")


_NUM_BYTES = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)")


def mutate_bytes(
    rng: Rng,
    data: bytes,
    tokens: Sequence[bytes] = GCODE_TOKENS,
    rounds: int = 3,
    max_size: int = 1 << 20,
) -> bytes:
    """``rounds`` random edits: bit flips, interesting bytes, deletions, line duplication and
    swaps, truncation, tokens and edge numbers inserted, splices."""
    for _ in range(rng.randint(1, max(1, rounds))):
        op = rng.randint(0, 11)
        n = len(data)
        if op == 0 and n:  # bit flip
            k = rng.randrange(n)
            data = data[:k] + bytes([data[k] ^ (1 << rng.randint(0, 7))]) + data[k + 1 :]
        elif op == 1 and n:  # interesting byte
            k = rng.randrange(n)
            b = rng.choice((0, 0xFF, 0x1B, 13, 10, 9, 0x7F, 0x80, ord("("), ord("["), ord("#")))
            data = data[:k] + bytes([b]) + data[k + 1 :]
        elif op == 2 and n:  # delete a range
            a = rng.randrange(n)
            data = data[:a] + data[a + rng.randint(1, 64) :]
        elif op == 3:  # duplicate a line
            ls = _lines(data)
            k = rng.randrange(len(ls))
            times = rng.choice((1, 2, 10, 100)) if len(data) < max_size // 128 else 1
            ls[k:k] = [ls[k]] * times
            data = b"\n".join(ls)
        elif op == 4:  # swap two lines
            ls = _lines(data)
            i, j = rng.randrange(len(ls)), rng.randrange(len(ls))
            ls[i], ls[j] = ls[j], ls[i]
            data = b"\n".join(ls)
        elif op == 5 and n:  # truncate
            data = data[: rng.randrange(n)]
        elif op == 6:  # insert a token
            k = rng.randint(0, n)
            data = data[:k] + rng.choice(tokens) + data[k:]
        elif op in (7, 8):  # replace a number with an edge number
            nums = list(_NUM_BYTES.finditer(data))
            if nums:
                m = rng.choice(nums)
                new = rng.choice(EDGE_NUMBERS).encode("utf-8")
                data = data[: m.start()] + new + data[m.end() :]
        elif op == 9 and n:  # splice a piece of itself elsewhere
            a = rng.randrange(n)
            piece = data[a : a + rng.randint(1, 200)]
            k = rng.randint(0, n)
            data = data[:k] + piece + data[k:]
        elif op == 10:  # delete a line
            ls = _lines(data)
            del ls[rng.randrange(len(ls))]
            data = b"\n".join(ls)
        else:  # line ends
            data = data.replace(b"\n", rng.choice((b"\r\n", b"\r", b"\n \n", b"\n")))
        data = data[:max_size]
    return data


@cache
def _seed_files(folder: str, pattern: str) -> tuple[tuple[str, bytes], ...]:
    return tuple((p.name, p.read_bytes()) for p in sorted(Path(folder).glob(pattern)))


def gcode_seeds(max_bytes: int | None = None) -> list[bytes]:
    """The bundled example programs and the test programs, each cut to ``max_bytes`` at a
    line end when given."""
    out = []
    for folder in (EXAMPLES, PROGRAMS):
        for _, data in _seed_files(str(folder), "*.ngc"):
            if max_bytes is not None and len(data) > max_bytes:
                data = data[: data.rfind(b"\n", 0, max_bytes) + 1]
            out.append(data)
    return out


def gcode_mutant(rng: Rng, seeds: Sequence[bytes], rounds: int = 4) -> bytes:
    """A seed program with a few mutations; sometimes two seeds spliced."""
    data = rng.choice(seeds)
    if chance(rng, 0.1):
        other = rng.choice(seeds)
        data = data[: rng.randint(0, len(data))] + other[rng.randint(0, len(other)) :]
    return mutate_bytes(rng, data, GCODE_TOKENS, rounds)


def random_bytes(rng: Rng, max_len: int = 400) -> bytes:
    """Random bytes, random printable text, or random tokens of any of the formats."""
    n = rng.randint(0, max_len)
    r = rng.random()
    if r < 0.3:
        return rng.randbytes(n)
    if r < 0.6:
        alphabet = "GXYZIJKRFMNPQT0123456789.-+ \n\t()[]#=;/%,|$:ABCDEFHLOSUVW"
        return "".join(rng.choice(alphabet) for _ in range(n)).encode()
    toks = GCODE_TOKENS + CL_TOKENS + TRACE_TOKENS
    return b"".join(rng.choice(toks) for _ in range(n // 8 + 1))


# ------------------------------------------------------------------------------- CL data
CL_TOKENS = (
    b"GOTO/",
    b"FROM/",
    b"GOHOME",
    b"GODLTA/",
    b"RAPID",
    b"FEDRAT/",
    b"MMPM",
    b"IPM",
    b"CIRCLE/",
    b"MOVARC/",
    b"UNITS/INCHES",
    b"UNITS/MM",
    b"MULTAX/ON",
    b"LOADTL/",
    b"LOAD/TOOL,",
    b"TOOL PATH/",
    b"END-OF-PATH",
    b"CYCLE/DEEP,FEDTO,",
    b"CYCLE/OFF",
    b",STEP,",
    b"DELAY/",
    b"FINI",
    b"$",
    b"$$",
    b",",
    b"/",
    b"TIMES,",
    b"ANGLE,",
    b"PARTNO ",
    b"PPRINT ",
    b"=",
)

_CL_WORDS_PASSIVE = ("PAINT/COLOR,42", "SPINDL/3000,CLW", "COOLNT/ON", "MACHIN/MILL,1")
_CL_WORDS_ERR = ("NURBS/1,2", "CYCLE/THREAD", "COPY/1", "TRANS/1,2,3", "GO/TO,PL1", "IF/1")


def _cl_nums(rng: Rng, k: int, edge: float) -> str:
    return ",".join(number(rng, edge) for _ in range(k))


def _cl_arc(rng: Rng, edge: float) -> list[str]:
    """GOTO to the start, CIRCLE (APT 7 values, SolidWorks 6, NX 11) or MOVARC, GOTO to an
    end on the circle: an arc the reader accepts (unless the edge level says otherwise)."""
    cx, cy, z = rng.uniform(-100, 100), rng.uniform(-100, 100), rng.uniform(-10, 10)
    r = rng.choice((rng.uniform(0.01, 50), rng.uniform(1, 10), 1e-4, 500.0))
    a0 = rng.uniform(0, 2 * math.pi)
    sweep = rng.choice((rng.uniform(0.01, 6.28), math.pi, 2 * math.pi, 1e-6))
    a1 = a0 + sweep
    nd = rng.choice((4, 6))
    s = f"{cx + r * math.cos(a0):.{nd}f},{cy + r * math.sin(a0):.{nd}f},{z:.{nd}f}"
    e = f"{cx + r * math.cos(a1):.{nd}f},{cy + r * math.sin(a1):.{nd}f},"
    e += f"{z + (rng.uniform(-3, 3) if chance(rng, 0.2) else 0):.{nd}f}"
    axis = rng.choice(("0,0,1", "0,0,-1", "0.0000000,0.0000000,1.0000000"))
    c = f"{cx:.{nd}f},{cy:.{nd}f},{z:.{nd}f},{axis}"
    kind = rng.randint(0, 3)
    if kind == 0:
        rec = f"CIRCLE/{c},{r:.{nd}f}"
    elif kind == 1:
        rec = f"CIRCLE/{c}"
    elif kind == 2:
        times = f",TIMES,{rng.choice(('1', '2'))}" if chance(rng, 0.2) else ""
        rec = f"CIRCLE/{c},{r:.{nd}f},0.0600,0.5000,10.0000,0.0000{times}"
    else:
        rec = f"MOVARC/{c},{r:.{nd}f},ANGLE,{math.degrees(sweep):.4f}"
    if chance(rng, edge * 3):
        rec = mutate_bytes(rng, rec.encode(), CL_TOKENS, 1).decode("utf-8", "replace")
    return [f"GOTO/{s}", rec, f"GOTO/{e}"]


def _cl_record(rng: Rng, edge: float) -> str:
    wild = rng.random() < edge * 1.5
    r = rng.random()
    if r < 0.4:
        k = rng.choice((2, 4, 7, 1)) if wild else rng.choice((3, 3, 3, 6))
        sep = rng.choice(("/", "/", " / ", "/ "))
        vals = _cl_nums(rng, 3, edge)
        if k == 6:
            vals += "," + rng.choice(("0,0,1", "0.6,0,0.8", "0,0.7071068,0.7071068"))
        elif k != 3:
            vals = _cl_nums(rng, k, edge) if chance(rng, 0.7) else f"{vals},0,0,0"
        return f"GOTO{sep}{vals}"
    if r < 0.46:
        unit = rng.choice(("MMPM", "IPM", "MMPM", ""))
        if wild:
            unit = rng.choice(("MMPR", "IPR", "INVERS", "XYZ"))
        f = positive(rng, edge, 10, 3000)
        return rng.choice((f"FEDRAT/{unit},{f}", f"FEDRAT/{f},{unit}")).replace("/,", "/")
    if r < 0.5:
        return "RAPID"
    if r < 0.53:
        return f"UNITS/{rng.choice(('MM', 'INCHES', 'INCH', 'METRIC'))}"
    if r < 0.55:
        return f"FROM/{_cl_nums(rng, 3, edge)}"
    if r < 0.57:
        return rng.choice(("GOHOME", f"GOHOME/{_cl_nums(rng, 3, edge)}"))
    if r < 0.6:
        return f"GODLTA/{_cl_nums(rng, rng.choice((1, 3)), edge)}"
    if r < 0.63:
        t = rng.choice(("1", "2", "0", "99"))
        if wild:
            t = rng.choice(("-1", "1.5", "99999999999", "1e308", "nan"))
        return rng.choice((f"LOADTL/{t}", f"LOAD/TOOL,{t}", f"LOAD/{t}"))
    if r < 0.66:
        name = hostile_text(rng, 6).replace(",", "").replace("$", "") if edge else "ROUGH"
        return rng.choice((f"TOOL PATH/{name},TOOL,T1", "END-OF-PATH", "TOOL PATH/"))
    if r < 0.7:
        kind = rng.choice(("DRILL", "DEEP", "DEEP2", "BRKCHP", "TAP", "BORE", "OFF", "INIT"))
        parts = [f"CYCLE/{kind}", f"FEDTO,{positive(rng, edge, 0.1, 20)}"]
        for word in ("STEP", "1STPECK", "SUBPECK", "RAPTO", "RTRCTO", "MMPM", "DWELL"):
            if chance(rng, 0.3):
                parts.append(f"{word},{positive(rng, edge, 0.1, 20)}")
        if wild:
            parts.append(_cl_nums(rng, rng.randint(1, 4), 0.5))
        return ",".join(parts)
    if r < 0.72:
        return f"DELAY/{positive(rng, edge, 0, 5)}{rng.choice(('', ',SEC', ',REV' * wild))}"
    if r < 0.75:
        return rng.choice(("STOP", "OPSTOP", "END", "MULTAX/ON", "MULTAX", "CUTCOM/OFF"))
    if r < 0.8:
        text = hostile_text(rng) if edge else "operation 1"
        return rng.choice((f"PARTNO {text}", f"PPRINT {text}", f"INSERT/{text}", f"$$ {text}"))
    if r < 0.85:
        return rng.choice(_CL_WORDS_PASSIVE + ("MODE/MILL", "ROTABL/90,CLW", "MSYS/0,0,0"))
    if r < 0.88:
        return f"GOTO/{number(rng, edge)},$\n{number(rng, edge)},{number(rng, edge)}"
    if not wild:
        return f"GOTO/{_cl_nums(rng, 3, edge)}"
    r = rng.random()
    if r < 0.3:
        return rng.choice(_CL_WORDS_ERR + ("MODE/TURN", "$$ contact data", "FINI"))
    if r < 0.5:
        return _cl_nums(rng, rng.choice((3, 6)), edge)  # bare points continuing a GOTO
    if r < 0.6:
        return "CIRCLE/" + _cl_nums(rng, rng.choice((5, 6, 7, 11)), edge)
    if r < 0.7:
        return f"GOTO/{number(rng, edge)},$"  # a continuation at the end
    return "".join(rng.choice("ABCGOTFR/,.$0123456789= -") for _ in range(rng.randint(0, 20)))


def cl_program(rng: Rng, max_lines: int = 24, edge: float | None = None) -> str:
    """APT CL data from the records the reader knows, in mostly plausible order; ``edge``
    (edge numbers, refused records, see :data:`EDGE_LEVELS`) None picks one."""
    edge = rng.choice(EDGE_LEVELS) if edge is None else edge
    lines = []
    if chance(rng, 0.5):
        lines.append(f"PARTNO {hostile_text(rng, 6) if edge else 'PART'}")
    if chance(rng, 0.7):
        lines.append(rng.choice(("UNITS/MM", "UNITS/INCHES", "UNIT/MM")))
    if chance(rng, 0.4):
        lines.append("LOADTL/1")
    if chance(rng, 0.8) or not edge:
        lines.append(f"FEDRAT/MMPM,{plain_number(rng, 300, 3000).lstrip('-')}")
    if chance(rng, 0.6):
        lines.append(f"GOTO/{plain_number(rng)},{plain_number(rng)},{plain_number(rng)}")
    budget = rng.randint(1, max_lines)
    while budget > 0:
        recs = _cl_arc(rng, edge) if chance(rng, 0.15) else [_cl_record(rng, edge)]
        if chance(rng, edge):
            recs = [rec.lower() for rec in recs]
        if chance(rng, edge):
            recs[-1] += " $$ " + hostile_text(rng, 5)
        lines += recs
        budget -= len(recs)
    if chance(rng, 0.5):
        lines.append("FINI")
    return "\n".join(lines) + "\n"


CL_SEEDS = (
    # NX CLSF: TOOL PATH, 11-value CIRCLE, TIMES helix, 5-axis GOTO, DELAY, END-OF-PATH
    "TOOL PATH/ROUGH,TOOL,MILL_10\nTLDATA/MILL,10.0000,0.0000,75.0000,0.0000,0.0000\n"
    "MSYS/0.0000,0.0000,0.0000,1.0000000,0.0000000,0.0000000,0.0000000,1.0000000,0.0000000\n"
    "$$ centerline data\nPAINT/PATH\nPAINT/SPEED,10\nLOAD/TOOL,1\nSELECT/TOOL,2\n"
    "SPINDL/RPM,8000.000,CLW\nRAPID\nGOTO/10.0000,0.0000,5.0000,0.0000000,0.0000000,1.0000000\n"
    "FEDRAT/MMPM,600.0000\nGOTO/10.0000,0.0000,0.0000\n"
    "CIRCLE/0.0000,0.0000,0.0000,0.0000000,0.0000000,-1.0000000,10.0000,0.0600,0.5000,"
    "10.0000,0.0000\nGOTO/0.0000,10.0000,0.0000\nGOTO/-10.0000,10.0000,0.0000\n"
    "CIRCLE/0.0000,0.0000,0.0000,0.0000000,0.0000000,-1.0000000,10.0000,0.0600,0.5000,"
    "10.0000,0.0000,TIMES,2\nGOTO/-10.0000,0.0000,-1.0000\nDELAY/0.5\n"
    "GODLTA/5.0000\nEND-OF-PATH\n",
    # SolidWorks CAM APT: 6-value CIRCLE, CYCLE, inch
    "PARTNO boss\nMACHIN/MILL,1\nUNITS/INCHES\nLOADTL/1,IN,1,LENGTH,3.0\nCUTTER/0.25\n"
    "FEDRAT/IPM,20.0\nRAPID\nGOTO/1.0,0.0,0.5\nGOTO/1.0,0.0,0.0\nCIRCLE/0.0,0.0,0.0,0.0,0.0,1.0\n"
    "GOTO/0.0,1.0,0.0\nCYCLE/INIT\nCYCLE/DRILL,FEDTO,0.5,IPM,5,RAPTO,0.1,RTRCTO,1.0,DWELL,0.5\n"
    "GOTO/2.0,2.0,0.0\nGOTO/3.0,2.0,0.0\nCYCLE/OFF\nCOOLNT/OFF\nEND\nFINI\n",
    # Creo: blanks around / and , ; bare-number continuation points; $ continuation
    "$$ Creo\nPARTNO / PART1\nUNITS / MM\nFEDRAT / 1200.000000, MMPM\nFROM / 0.0, 0.0, 50.0\n"
    "GOTO / 10.0, 10.0, 5.0\n 20.0, 10.0, 5.0\n 20.0, 20.0, 5.0\n"
    "MOVARC / 15.0, 20.0, 5.0, 0.0, 0.0, 1.0, 5.0, ANGLE, 180\nGOTO / 10.0, 20.0, 5.0\n"
    "GOTO / 10.0, $\n 10.0, 4.0\nRAPID\nGOHOME / 0, 0, 50\nFINI\n",
)


def cl_mutant(rng: Rng, rounds: int = 4) -> bytes:
    """A CL seed (bundled or grammar-made) with a few byte mutations."""
    seed = rng.choice(CL_SEEDS) if chance(rng, 0.7) else cl_program(rng, 10)
    return mutate_bytes(rng, seed.encode(), CL_TOKENS, rounds)


# ------------------------------------------------------------------------------- traces
TRACE_TOKENS = (
    b"t,x,y,z",
    b"t,x,y,z,v,line",
    b"t,v",
    b",",
    b"nan",
    b"inf",
    b"-1",
    b"1e308",
    b"99999999999999999999",
    b"UNAVAILABLE",
    b"|",
    b"Feed_Rate",
    b"Block_Number",
    b"Xact",
    b"2024-01-01T00:00:00",
    b".5Z",
)

#: Headers of CSV traces: the ones the reader takes first, then ones it must refuse.
_CSV_HEADERS = (
    "t,x,y,z",
    "t,x,y,z,v",
    "t,x,y,z,v,line",
    "t,v",
    "t,v,line",
    "line,v,t",
    "T, X, Y, Z, V",
    "t,x,y,z,v,line,extra",
)
_CSV_BAD_HEADERS = ("t,x,y", "t,t,v", "x,y,z", "t", "", "\ufefft,v", "t;x;y;z", "t,line", "t,,v")


def _csv_value(rng: Rng, col: str, base: float, edge: float) -> str:
    if chance(rng, edge / 3):
        return rng.choice(EDGE_NUMBERS + ("UNAVAILABLE", " ", "1e20", "-1", "2.5"))
    if col == "line":
        return str(int(base))
    return f"{base:.6f}" if chance(rng, 0.8) else repr(base)


def csv_trace(rng: Rng, max_rows: int = 40) -> str:
    """A CSV trace: header variants, rising time, edge values, ragged rows."""
    edge = rng.choice(EDGE_LEVELS)
    header = rng.choice(_CSV_HEADERS)
    if chance(rng, edge * 2):
        header = rng.choice(_CSV_BAD_HEADERS)
    cols = [c.strip().lower().lstrip("\ufeff") for c in header.split(",")]
    rows = [header]
    t = rng.choice((0.0, 0.0, 0.0, 1e8, 12345.678))
    if chance(rng, edge):
        t = rng.choice((1e9, -5.0, 1e-300, 999999999.999))
    dt = rng.choice((0.001, 0.01, 0.1))
    if chance(rng, edge):
        dt = rng.choice((1.0, 1e-9, 1e-300, 0.0, 1e8))
    x = y = z = 0.0
    line = 1
    for _ in range(rng.randint(0, max_rows)):
        t += dt * (rng.choice((50, -1, 0, 1e6)) if chance(rng, edge) else 1)
        x += rng.uniform(-1, 1)
        y += rng.uniform(-1, 1)
        line += rng.choice((0, 0, 1))
        vals = {"t": t, "x": x, "y": y, "z": z, "v": rng.uniform(0, 100), "line": line}
        row = [_csv_value(rng, c, vals.get(c, rng.uniform(0, 9)), edge) for c in cols]
        if chance(rng, edge / 4):
            row = row[:-1] if chance(rng, 0.5) else [*row, "0"]
        rows.append(",".join(row))
        if chance(rng, edge / 4):
            rows.append(rng.choice(("", "# comment", " ", hostile_text(rng, 4))))
    return "\n".join(rows) + ("\n" if chance(rng, 0.9) else "")


_BAD_STAMPS = (
    "2024-13-01T00:00:00Z",
    "0000-01-01T00:00:00Z",
    "0001-01-01T00:00:00Z",
    "9999-12-31T23:59:59.999999Z",
    "2024-01-01T24:00:00Z",
    "2024-06-30T23:59:60Z",
    "2024-01-01T00:00:00.1e5Z",
    "2024-01-01T00:00:00+01:00",
    "2024-01-01T00:00:00.Z",
    "2024-01-01T00:00:00." + "9" * 40 + "Z",
    "2024-01-01T00:00:00." + "0" * 400 + "1Z",
    "2024-01-01 00:00:00Z",
    "2024-01-01T00:00:00.\u0661Z",
    "1969-12-31T23:59:59Z",
    "2024-01-01T0:0:0Z",
    "2024-01-01T00:00:00ZZ",
    "",
)


def _stamp(rng: Rng, t: float, edge: float) -> str:
    if chance(rng, edge / 4):
        return rng.choice(_BAD_STAMPS)
    whole = int(t)
    hh, mm, ss = whole // 3600 % 24, whole // 60 % 60, whole % 60
    day = 1 + whole // 86400 % 28
    frac = f"{t - whole:.9f}"[2 : 2 + rng.choice((0, 1, 3, 6, 7, 9))]
    return f"2024-02-{day:02d}T{hh:02d}:{mm:02d}:{ss:02d}" + (f".{frac}" if frac else "") + "Z"


#: Channel sets an SHDR recording may carry (an adapter records some of these).
_SHDR_SETS = (
    ("Feed_Rate",),
    ("Feed_Rate", "Block_Number"),
    ("Xact", "Yact", "Zact"),
    ("Xact", "Yact", "Zact", "Feed_Rate", "Block_Number"),
    ("Xabs", "Yabs", "Zabs", "Block_Number"),
    ("Xpos", "Ypos", "Zpos", "Feed_Rate", "avail", "execution"),
)
_SHDR_KEYS = ("Feed_Rate", "Block_Number", "Xact", "Yact", "Zact", "Xabs", "Zpos", "avail", "")


def _shdr_value(rng: Rng, key: str, k: int, edge: float) -> str:
    if chance(rng, max(edge / 3, 0.01)):
        return rng.choice(("UNAVAILABLE", "unavailable", " UNAVAILABLE "))
    if chance(rng, edge / 3):
        return rng.choice(EDGE_NUMBERS + ("1e20", "-1", "2.5", "9007199254740993", "1e16"))
    if key == "Block_Number":
        return str(k + 1)
    if key in ("avail", "execution", ""):
        return rng.choice(("AVAILABLE", "ACTIVE", "READY"))
    return plain_number(rng, 0, 100)


def shdr_trace(rng: Rng, max_lines: int = 40) -> str:
    """An MTConnect SHDR recording: timestamp|key|value[|key|value...] events."""
    edge = rng.choice(EDGE_LEVELS)
    keys = list(rng.choice(_SHDR_SETS))
    if chance(rng, edge * 2):
        keys = [k for k in _SHDR_KEYS if chance(rng, 0.4)] or ["Xact"]
    lines = []
    t = rng.uniform(0, 86400 * 3)
    for k in range(rng.randint(2, max_lines)):
        t += rng.choice((0.001, 0.01, 0.5))
        if chance(rng, edge):
            t += rng.choice((0.0, -1.0, 100.0, 1e-9))
        picked = keys if k == 0 or chance(rng, 0.5) else rng.sample(keys, rng.randint(1, len(keys)))
        pairs = []
        for key in picked:
            pairs += [key, _shdr_value(rng, key, k, edge)]
        if chance(rng, edge / 4):
            pairs.pop()
        line = "|".join([_stamp(rng, t, edge), *pairs])
        if chance(rng, edge / 4):
            line = rng.choice(("", " ", hostile_text(rng, 5), line + "|"))
        lines.append(line)
    return "\n".join(lines) + "\n"


def mutate_lines(rng: Rng, text: str, rounds: int = 3) -> str:
    """Edits of a line-based text (a trace made by ``ncperf profile``): a value replaced by an
    edge number, a line dropped, duplicated or moved, a column dropped, the text cut."""
    lines = text.split("\n")
    for _ in range(rng.randint(0, rounds)):
        if len(lines) < 2:
            break
        op = rng.randint(0, 5)
        k = rng.randrange(1, len(lines))
        if op == 0:
            cells = lines[k].split(",")
            j = rng.randrange(len(cells))
            cells[j] = rng.choice(EDGE_NUMBERS + ("UNAVAILABLE",))
            lines[k] = ",".join(cells)
        elif op == 1:
            del lines[k]
        elif op == 2:
            lines.insert(k, lines[k])
        elif op == 3:
            lines.insert(rng.randrange(1, len(lines)), lines.pop(k))
        elif op == 4:
            lines = lines[: rng.randint(1, len(lines))]
        else:
            lines[0] = rng.choice(_CSV_HEADERS + _CSV_BAD_HEADERS)
    return "\n".join(lines)


# ------------------------------------------------------------------------------- machine TOML
_TOML_NUMBER = re.compile(r"(?m)^(\s*[A-Za-z_]+\s*=\s*)([-+]?[0-9][0-9_.eE+-]*|inf|nan)")

TOML_VALUES = (
    "0",
    "-1",
    "1e-310",
    "1e308",
    "1.7976931348623157e308",
    "nan",
    "inf",
    "-inf",
    "+nan",
    "9" * 400,
    "-" + "9" * 400,
    "9007199254740993",
    "1e-9",
    "1e-12",
    "1e12",
    "1e13",
    "0.0",
    "-0.0",
    "5e-324",
    "true",
    '"5"',
    "[1, 2, 3]",
    "[1e308, 1e308, 1e308]",
    "{ a = 1 }",
    "0x10",
    "1_000",
    "[" * 12 + "1" + "]" * 12,
    "[" * 600 + "]" * 600,
    "1979-05-27T07:32:00Z",
)

_TOML_EXTRA = (
    "max_path_feed = {v}",
    "block_time_on_blends = {v}",
    'default_path_mode = "{s}"',
    "peck_clearance = {v}",
    "home = [{v}, {v}, {v}]",
    "home_g30 = [0, 0, {v}]",
    'tool_table = "{s}"',
    'subroutine_path = ["{s}"]',
)

_TOML_TABLES = (
    "[axes.A]\nmax_feed = {v}\nmax_acceleration = {v}\nmax_jerk = {v}\n",
    "[axes.C]\nmax_feed = {v}\nmax_acceleration = {v}\n",
    "[offsets]\nG54 = [{v}, {v}, {v}]\nG59.3 = [0, 0, {v}]\n",
    "[tools]\nT1 = {{ diameter = {v}, length = {v} }}\nT{n} = {{ radius = {v} }}\n",
    "[diagnosis]\nnoise_floor = {v}\ntrace_cycle = {v}\n",
    "[effects.{e}]\n{p} = {v}\n",
    "[effects.{e}]\n{p} = {v}\n",
    "[effects.{e}]\n{p} = {v}\n",
    "[effects.{e}]\n",
    "[a.b.c.d.e.f.g.h.i.j]\nx = 1\n",
)

#: Effects a machine file may switch on, with their parameters (and names that are not).
_EFFECTS = (
    ("acceleration_ramps", ""),
    ("lookahead_depth", "blocks"),
    ("block_cycle_time", "t_block"),
    ("corner_tolerance", "tolerance"),
    ("normal_acceleration_factor", "factor"),
    ("arc_feed_limit", ""),
    ("axis_dynamics", "accel_scale"),
    ("axis_dynamics", "jerk_scale"),
    ("axis_dynamics", "feed_x"),
    ("feed_override", "scale"),
    ("feed_override", "caps"),
    ("servo_lag", "tau"),
    ("jerk_filter", "window"),
    ("path_compression", "max_angle"),
    ("path_compression", "max_length"),
    ("last_block_acceleration", "factor"),
    ("arc_acceleration", "factor"),
    ("exact_stop", ""),
    ("path_feed_limit", "max_feed"),
    ("unknown_effect", "x"),
    ('"\\u202e\\u001b[31m"', "factor"),
)


def presets() -> list[str]:
    return [data.decode("utf-8") for _, data in _seed_files(str(PRESETS), "*.toml")]


def _toml_value(rng: Rng) -> str:
    if chance(rng, 0.5):
        return rng.choice(TOML_VALUES)
    return plain_number(rng, 0, 100).lstrip("-") or "1"


def machine_toml(rng: Rng, rounds: int = 3) -> str:
    """A preset machine file with numbers replaced by edge values, tables added or removed,
    keys duplicated, the name made hostile, or the text cut."""
    text = rng.choice(presets())
    for _ in range(rng.randint(1, rounds)):
        op = rng.randint(0, 7)
        if op <= 2:
            nums = list(_TOML_NUMBER.finditer(text))
            if nums:
                m = rng.choice(nums)
                text = text[: m.start(2)] + _toml_value(rng) + text[m.end(2) :]
        elif op == 3:
            extra = rng.choice(_TOML_EXTRA).format(
                v=_toml_value(rng), s=hostile_text(rng, 5).replace('"', "").replace("\\", "")
            )
            text = text.replace("[controller]\n", f"[controller]\n{extra}\n", 1)
        elif op == 4:
            effect, param = rng.choice(_EFFECTS)
            table = rng.choice(_TOML_TABLES).format(
                v=_toml_value(rng),
                n=rng.choice(("2", "99999999999999999999", "0")),
                e=effect,
                p=param or "x",
            )
            text += "\n" + table
        elif op == 5:
            name = hostile_text(rng, 8)
            escaped = "".join(
                c if c.isprintable() and c not in '"\\' else f"\\u{ord(c):04x}"
                for c in name
                if ord(c) <= 0xFFFF
            )
            m = re.search(r'(?m)^name = ".*"$', text)
            if m:
                text = f'{text[: m.start()]}name = "{escaped}"{text[m.end() :]}'
        elif op == 6:
            lines = text.split("\n")
            k = rng.randrange(len(lines))
            if chance(rng, 0.5):
                del lines[k]
            else:
                lines.insert(rng.randrange(len(lines)), lines[k])
            text = "\n".join(lines)
        else:
            raw = mutate_bytes(rng, text.encode(), (b"=", b"[", b"]", b"{", b'"', b"inf"), 1)
            text = raw.decode("utf-8", "replace")
    return text


# ------------------------------------------------------------------------------- command line
FILE_STEMS = (
    "part",
    "p 1",
    "a\x1b[31mred",
    "cr\rname",
    "nl\nname",
    "\u202eevil",
    "-dash",
    "é中",
    "tab\tname",
    "del\x7f",
    "c1\x9b",
    "bad\udcffbyte",
)


@dataclass
class CliCase:
    """One command line run: the command, its input files (name, bytes) and options.

    ``machine`` is None (default preset), a preset name, ``"missing"`` (a file that does not
    exist) or the text of a machine file. ``outputs`` maps an option (``--json``...) to an
    output file name, or to ``"<input>"`` (the program itself), ``"<dir>"`` (an existing
    folder), ``"<missing>/x"`` (a file in a folder that does not exist).
    ``trace`` is None (the harness makes one with ``ncperf profile`` and edits it with
    :func:`mutate_lines`) or the bytes of a trace file, named ``trace_name``.
    """

    command: str
    programs: list[tuple[str, bytes]]
    machine: str | None = None
    options: list[str] = field(default_factory=list)
    outputs: dict[str, str] = field(default_factory=dict)
    trace: bytes | None = None
    trace_name: str = "trace.csv"


def _program_file(rng: Rng, clean: bool) -> tuple[str, bytes]:
    stem = rng.choice(FILE_STEMS) if chance(rng, 0.25) else "part"
    r = rng.random()
    if clean:
        if r < 0.75:
            ext = rng.choice(GCODE_EXTENSIONS)
            return stem + ext, gcode_program(rng, DIALECT_OF[ext], 12, edge=0.0).encode()
        return stem + rng.choice(CL_EXTENSIONS), cl_program(rng, 12, edge=0.0).encode()
    if r < 0.55:
        ext = rng.choice(GCODE_EXTENSIONS)
        data = to_bytes(rng, gcode_program(rng, DIALECT_OF[ext], 12))
    elif r < 0.75:
        ext = rng.choice(GCODE_EXTENSIONS)
        data = gcode_mutant(rng, gcode_seeds(3000), 2)
    elif r < 0.9:
        ext = rng.choice(CL_EXTENSIONS)
        data = to_bytes(rng, cl_program(rng, 12)) if chance(rng, 0.6) else cl_mutant(rng, 2)
    else:
        ext = rng.choice((".ngc", ".cl", ".txt", "", ".csv"))
        data = random_bytes(rng, 200)
    return stem + ext, data


def _num_option(rng: Rng, clean: bool, good: Sequence[str]) -> str:
    if clean:
        return rng.choice(good)
    return rng.choice(("0", "-1", "nan", "inf", "1e-320", "1e308", "1e-7", "61", *good))


COMMAND_WEIGHTS = {
    "analyze": 40,
    "profile": 20,
    "compare": 12,
    "diagnose": 14,
    "calibrate": 4,
    "machines": 2,
    "plugins": 2,
}


def cli_case(rng: Rng, commands: Sequence[str] | None = None) -> CliCase:
    """A command line: one of ``commands`` (default: analyze, profile, compare, diagnose,
    calibrate and the listings, analyze most often). Half the cases are clean (a plausible
    program, a preset, options in range), the rest anything."""
    names = list(commands or COMMAND_WEIGHTS)
    pick = rng.random() * sum(COMMAND_WEIGHTS[c] for c in names)
    command = names[-1]
    for c in names:
        pick -= COMMAND_WEIGHTS[c]
        if pick < 0:
            command = c
            break
    clean = chance(rng, 0.5)
    n_programs = 0 if command in ("machines", "plugins") else 1
    if command == "compare":
        n_programs = rng.choice((2, 2, 3)) if clean else rng.choice((1, 2, 3))
    case = CliCase(command, [_program_file(rng, clean) for _ in range(n_programs)])
    if command in ("machines", "plugins"):
        return case
    r = rng.random()
    if r < 0.5:
        case.machine = None
    elif r < 0.7 or clean:
        presets = ("linuxcnc-sim", "siemens-840d")
        case.machine = rng.choice(presets if clean else (*presets, "no-such-preset"))
    elif r < 0.75:
        case.machine = "missing"
    else:
        case.machine = machine_toml(rng, 2)
    opts = case.options
    if not clean and chance(rng, 0.15):
        opts += ["--dialect", rng.choice(("fanuc", "siemens", "linuxcnc"))]
    if chance(rng, 0.1):
        opts.append("--block-delete")
    if chance(rng, 0.1):
        opts += ["--tool-radius", _num_option(rng, clean, ("0", "0.5", "5"))]
    if command in ("analyze", "compare", "diagnose") and chance(rng, 0.2):
        opts += ["--view", rng.choice(("xy", "xz", "yz", "iso"))]
    if command == "profile" and chance(rng, 0.4):
        opts += ["--dt", _num_option(rng, clean, ("0.001", "0.01", "0.1", "1e-5"))]
    if command in ("diagnose", "calibrate"):
        if chance(rng, 0.2):
            opts += ["--trace-units", rng.choice(("mm", "inch"))]
        if chance(rng, 0.2):
            opts += ["--trace-kind", rng.choice(("setpoint", "actual"))]
        if clean or chance(rng, 0.7):  # all effects: ~5 s a diagnosis; one or two: ~1 s
            effects = ["feed_override", "arc_acceleration", "servo_lag", "corner_tolerance"]
            if not clean:
                effects += ["x", "", "acceleration_ramps"]
            opts += ["--effects", ",".join(rng.sample(effects, rng.randint(1, 2)))]
        if command == "diagnose" and chance(rng, 0.3):
            opts += ["--baseline", rng.choice(("paper", "profile"))]
        r = rng.random()
        if r < 0.6 or clean:
            case.trace = None
        elif r < 0.8:
            case.trace, case.trace_name = to_bytes(rng, csv_trace(rng, 30)), "trace.csv"
        else:
            case.trace, case.trace_name = to_bytes(rng, shdr_trace(rng, 30)), "trace.shdr"
    wanted = {
        "analyze": ("--json", "--svg"),
        "profile": ("--csv",),
        "compare": ("--svg",),
        "diagnose": ("--json", "--svg"),
        "calibrate": ("--out",),
    }.get(command, ())
    for opt in wanted:
        if opt in ("--csv", "--out") or chance(rng, 0.6):
            r = rng.random()
            if r < 0.8 or clean:
                name = "out" + opt.replace("--", ".")
                if opt == "--out":
                    name = "out.toml"
            elif r < 0.85:
                name = "<input>"
            elif r < 0.9:
                name = "<dir>"
            elif r < 0.95:
                name = "<missing>/x"
            else:
                name = rng.choice(FILE_STEMS) + opt.replace("--", ".")
            case.outputs[opt] = name
    return case
