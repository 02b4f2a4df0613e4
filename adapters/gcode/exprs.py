"""Expressions of G-code programs: parameters, arithmetic, functions, comparisons.

Two notations, one evaluator:

* **Brackets** (LinuxCNC rs274ngc, Fanuc Macro B): ``[ ]`` group, parameters are ``#n``
  (``#[expr]``, ``##n``), LinuxCNC's named ``#<name>``; functions ``SIN[x]``, ``ATAN[y]/[x]``;
  binary operators ``** * / MOD + - EQ NE GT GE LT LE AND OR XOR``.
* **Infix** (Siemens 840D): ``( )`` group, R parameters ``R12`` and declared variables by
  name, functions ``SIN(x)``, ``ATAN2(y, x)``, ``POT(x)``; operators ``* / DIV MOD + - == <>
  > < >= <= AND OR XOR NOT``.

Angles are in degrees in both (LinuxCNC, Fanuc and Siemens trigonometry). A parsed
expression is a small tree of tuples evaluated against a parameter store; a vacant Fanuc
variable evaluates to :data:`VACANT` where a word or a comparison can tell it from 0.
Facts from the LinuxCNC G-code reference (O codes, expressions), the Fanuc Custom Macro B
chapter of the 0i/30i operator's manuals and the SINUMERIK 840D sl job-planning manual.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

#: A Fanuc variable that was never set ("vacant", #0): 0 in arithmetic, omitted as a word.
VACANT = None
#: LinuxCNC's TOLERANCE_EQUAL: EQ and NE compare within it (rs274ngc interp_internal.hh).
LINUXCNC_EQUAL = 1e-6

Node = Any  # float | tuple (a small expression tree)


class ExprError(Exception):
    """A malformed or unevaluable expression; the caller names the line."""


def _deg(f: Callable[[float], float]) -> Callable[[float], float]:
    return lambda x: f(math.radians(x))


def _round_half_away(x: float) -> float:
    return float(math.floor(abs(x) + 0.5)) * (1.0 if x >= 0 else -1.0)


def _checked(name: str, f: Callable[[float], float]) -> Callable[[float], float]:
    def g(x: float) -> float:
        try:
            return f(x)
        except (ValueError, OverflowError):
            raise ExprError(f"{name} of {x:g} is undefined") from None

    return g


#: One-argument functions, by name (both notations).
FUNCTIONS: dict[str, Callable[[float], float]] = {
    "ABS": abs,
    "ACOS": _checked("ACOS", lambda x: math.degrees(math.acos(x))),
    "ASIN": _checked("ASIN", lambda x: math.degrees(math.asin(x))),
    "COS": _deg(math.cos),
    "SIN": _deg(math.sin),
    "TAN": _deg(math.tan),
    "EXP": _checked("EXP", math.exp),
    "LN": _checked("LN", math.log),
    "SQRT": _checked("SQRT", math.sqrt),
    "FIX": lambda x: float(math.floor(x)),
    "FUP": lambda x: float(math.ceil(x)),
    # Fanuc Custom Macro B: FIX drops the fraction, FUP rounds away from zero
    # (FIX[-1.2] = -1, FUP[-1.2] = -2); LinuxCNC's are floor and ceil
    "FIX_FANUC": lambda x: float(math.trunc(x)),
    "FUP_FANUC": lambda x: float(math.copysign(math.ceil(abs(x)), x)),
    "ROUND": _round_half_away,
    # Fanuc
    "SQR": _checked("SQRT", math.sqrt),
    # Siemens
    "TRUNC": lambda x: float(math.trunc(x)),
    "POT": lambda x: x * x,
}

#: Binary operators: precedence (higher binds tighter) and function.
BINARY: dict[str, tuple[int, Callable[[float, float], float]]] = {
    "**": (5, lambda a, b: _power(a, b)),
    "*": (4, lambda a, b: a * b),
    "/": (4, lambda a, b: _divide(a, b)),
    "MOD": (4, lambda a, b: _mod(a, b)),
    "DIV": (4, lambda a, b: float(math.trunc(_divide(a, b)))),
    "+": (3, lambda a, b: a + b),
    "-": (3, lambda a, b: a - b),
    "EQ": (2, lambda a, b: float(a == b)),
    "NE": (2, lambda a, b: float(a != b)),
    # LinuxCNC: values within TOLERANCE_EQUAL (1e-6) are equal (G-code overview,
    # "Equality and floating-point values")
    "EQ~": (2, lambda a, b: float(abs(a - b) < LINUXCNC_EQUAL)),
    "NE~": (2, lambda a, b: float(abs(a - b) >= LINUXCNC_EQUAL)),
    "GT": (2, lambda a, b: float(a > b)),
    "GE": (2, lambda a, b: float(a >= b)),
    "LT": (2, lambda a, b: float(a < b)),
    "LE": (2, lambda a, b: float(a <= b)),
    "==": (2, lambda a, b: float(a == b)),
    "<>": (2, lambda a, b: float(a != b)),
    ">": (2, lambda a, b: float(a > b)),
    ">=": (2, lambda a, b: float(a >= b)),
    "<": (2, lambda a, b: float(a < b)),
    "<=": (2, lambda a, b: float(a <= b)),
    "AND": (1, lambda a, b: float(bool(a) and bool(b))),
    "OR": (1, lambda a, b: float(bool(a) or bool(b))),
    "XOR": (1, lambda a, b: float(bool(a) != bool(b))),
}
_ALPHA_OPS = sorted((k for k in BINARY if k.isalpha()), key=len, reverse=True)
_SYMBOL_OPS = sorted((k for k in BINARY if not k.isalpha()), key=len, reverse=True)


def _divide(a: float, b: float) -> float:
    if b == 0:
        raise ExprError("division by zero")
    return a / b


def _mod(a: float, b: float) -> float:
    """rs274ngc's MOD: fmod, made non-negative by adding |b| (7 MOD -3 = 1, -7 MOD 3 = 2)."""
    if b == 0:
        raise ExprError("MOD by zero")
    r = math.fmod(a, b)
    return r + abs(b) if r < 0 else r


def _power(a: float, b: float) -> float:
    try:
        v = a**b
    except (ZeroDivisionError, OverflowError):
        raise ExprError(f"{a:g} ** {b:g} is undefined") from None
    if isinstance(v, complex):
        raise ExprError(f"{a:g} ** {b:g} is undefined")
    return float(v)


@dataclass
class Cursor:
    """Text being parsed (upper-cased, original spacing) and the position in it."""

    text: str
    pos: int = 0

    def skip(self) -> None:
        while self.pos < len(self.text) and self.text[self.pos] in " \t":
            self.pos += 1

    def peek(self, n: int = 1) -> str:
        self.skip()
        return self.text[self.pos : self.pos + n]

    def take(self, s: str) -> bool:
        self.skip()
        if self.text.startswith(s, self.pos):
            self.pos += len(s)
            return True
        return False

    def expect(self, s: str, what: str) -> None:
        if not self.take(s):
            rest = self.text[self.pos : self.pos + 12]
            raise ExprError(f"expected {what!s} at '{rest}'" if rest else f"expected {what}")

    def at_end(self) -> bool:
        self.skip()
        return self.pos >= len(self.text)


def read_number(c: Cursor) -> float | None:
    """An unsigned decimal number at the cursor (digits with at most one point), or None.
    (LinuxCNC and Fanuc lines have their spaces removed before they are parsed.)"""
    c.skip()
    t, i = c.text, c.pos
    j = i
    seen_digit = seen_dot = False
    while j < len(t):
        ch = t[j]
        if ch.isdigit():
            seen_digit = True
        elif ch == "." and not seen_dot:
            seen_dot = True
        else:
            break
        j += 1
    if not seen_digit:
        return None
    c.pos = j
    value = float(t[i:j])
    if not math.isfinite(value):  # hundreds of digits: beyond a double
        raise ExprError(f"number {t[i : i + 12]}... ({j - i} digits) is out of range")
    return value


# ----------------------------------------------------------------------------- brackets
class BracketParser:
    """LinuxCNC / Fanuc expressions (see the module docstring).

    ``named``: LinuxCNC named parameters ``#<name>`` are allowed.
    """

    def __init__(self, named: bool = True) -> None:
        self.named = named

    def value(self, c: Cursor) -> Node:
        """A real value: a number with an optional sign, a parameter, ``[expr]``, a function
        call, or a unary minus/plus before any of them."""
        c.skip()
        if c.peek() in ("-", "+"):
            sign = c.text[c.pos]
            c.pos += 1
            if c.peek() in ("-", "+"):
                raise ExprError("two signs in a row")
            inner = self.value(c)
            return ("neg", inner) if sign == "-" else inner
        if c.peek() == "[":
            c.take("[")
            e = self.expr(c)
            c.expect("]", "']'")
            return e
        if c.peek() == "#":
            return self.param(c)
        n = read_number(c)
        if n is not None:
            return n
        name = self._name(c)
        if name:
            return self.function(c, name)
        rest = c.text[c.pos : c.pos + 12]
        raise ExprError(f"expected a number, parameter or expression at '{rest}'")

    def _name(self, c: Cursor) -> str:
        c.skip()
        i = c.pos
        while c.pos < len(c.text) and c.text[c.pos].isalpha():
            c.pos += 1
        return c.text[i : c.pos]

    def function(self, c: Cursor, name: str) -> Node:
        if name == "EXISTS":
            c.expect("[", "'[' after EXISTS")
            c.skip()
            if not self.named or not c.take("#<"):
                raise ExprError("EXISTS takes a named parameter #<name>")
            ident = self._ident(c)
            c.expect("]", "']'")
            return ("exists", ident)
        if name == "ATAN":
            c.expect("[", "'[' after ATAN")
            y = self.expr(c)
            if c.take(","):  # Fanuc ATAN[y, x]
                x = self.expr(c)
                c.expect("]", "']'")
                return ("atan", y, x)
            c.expect("]", "']'")
            if c.take("/"):
                c.expect("[", "'[' in ATAN[y]/[x]")
                x = self.expr(c)
                c.expect("]", "']'")
                return ("atan", y, x)
            return ("atan1", y)
        if name in FUNCTIONS:
            c.expect("[", f"'[' after {name}")
            e = self.expr(c)
            c.expect("]", "']'")
            if not self.named and name in ("FIX", "FUP"):
                name = f"{name}_FANUC"
            return ("fn", name, e)
        raise ExprError(f"unknown function or operator '{name}'")

    def _ident(self, c: Cursor) -> str:
        """The name of #<name> up to '>', spaces removed, lower case (case-insensitive)."""
        j = c.text.find(">", c.pos)
        if j < 0:
            raise ExprError("named parameter without '>'")
        ident = c.text[c.pos : j].replace(" ", "").replace("\t", "").lower()
        if not ident:
            raise ExprError("empty parameter name #<>")
        c.pos = j + 1
        return ident

    def param(self, c: Cursor) -> Node:
        c.expect("#", "'#'")
        c.skip()
        if self.named and c.take("<"):
            return ("named", self._ident(c))
        return ("param", self.value_no_sign(c))

    def value_no_sign(self, c: Cursor) -> Node:
        c.skip()
        if c.peek() == "#":
            return self.param(c)
        if c.peek() == "[":
            c.take("[")
            e = self.expr(c)
            c.expect("]", "']'")
            return e
        n = read_number(c)
        if n is None:
            raise ExprError("expected a parameter number after '#'")
        return n

    def _operator(self, c: Cursor) -> str | None:
        c.skip()
        rest = c.text[c.pos :]
        for op in _SYMBOL_OPS:
            if op in ("==", "<>", ">", ">=", "<", "<="):
                continue  # infix notation only
            if rest.startswith(op):
                return op
        for op in _ALPHA_OPS:
            if op == "DIV":
                continue
            if rest.startswith(op) and not rest[len(op) : len(op) + 1].isalpha():
                return op
        return None

    def expr(self, c: Cursor, min_prec: int = 0) -> Node:
        """Precedence climbing over the binary operators (all left-associative)."""
        left = self.value(c)
        while True:
            op = self._operator(c)
            if op is None:
                return left
            prec = BINARY[op][0]
            if prec < min_prec:
                return left
            c.take(op)
            right = self.expr(c, prec + 1)
            if self.named and op in ("EQ", "NE"):
                op = f"{op}~"  # LinuxCNC's tolerant equality
            left = ("bin", op, left, right)


# ----------------------------------------------------------------------------- infix
#: Siemens 840D operator priorities (SINUMERIK 840D sl programming manual, "Priority of the
#: operations"): comparisons bind least, so "R1>2 AND R2<3" needs brackets.
SIEMENS_PRECEDENCE = {
    "*": 6, "/": 6, "DIV": 6, "MOD": 6,
    "+": 5, "-": 5,
    "AND": 4, "XOR": 3, "OR": 2,
    "==": 1, "<>": 1, ">": 1, "<": 1, ">=": 1, "<=": 1,
}  # fmt: skip


class InfixParser:
    """Siemens 840D expressions: R parameters, variables by name, ``( )``."""

    def __init__(self, variables: Callable[[str], bool]) -> None:
        #: whether a name is a declared variable (DEF) or a known system variable
        self.variables = variables

    def value(self, c: Cursor) -> Node:
        c.skip()
        if c.take("-"):
            return ("neg", self.value(c))
        if c.take("+"):
            return self.value(c)
        if c.take("NOT"):
            return ("not", self.value(c))
        if c.take("("):
            e = self.expr(c)
            c.expect(")", "')'")
            return e
        n = read_number(c)
        if n is not None:
            return n
        c.skip()
        i = c.pos
        while c.pos < len(c.text) and (c.text[c.pos].isalnum() or c.text[c.pos] in "_$"):
            c.pos += 1
        name = c.text[i : c.pos]
        if not name:
            rest = c.text[c.pos : c.pos + 12]
            raise ExprError(f"expected a number, parameter or expression at '{rest}'")
        if name[0] == "R" and name[1:].isdigit():
            return ("param", float(name[1:]))
        if c.peek() == "[":  # R[expr], array element
            if name == "R":
                c.take("[")
                e = self.expr(c)
                c.expect("]", "']'")
                return ("param", e)
        if c.peek() == "(":
            if name == "ATAN2":
                c.take("(")
                y = self.expr(c)
                c.expect(",", "',' in ATAN2(y, x)")
                x = self.expr(c)
                c.expect(")", "')'")
                return ("atan", y, x)
            if name in FUNCTIONS or name in ("MINVAL", "MAXVAL"):
                c.take("(")
                a = self.expr(c)
                if name in ("MINVAL", "MAXVAL"):
                    c.expect(",", f"',' in {name}(a, b)")
                    b = self.expr(c)
                    c.expect(")", "')'")
                    return ("minmax", name, a, b)
                c.expect(")", "')'")
                return ("fn", name, a)
            raise ExprError(f"unknown function '{name}'")
        if name in ("TRUE", "FALSE"):
            return 1.0 if name == "TRUE" else 0.0
        if self.variables(name):
            return ("var", name)
        raise ExprError(f"unknown variable or function '{name}'")

    def _operator(self, c: Cursor) -> str | None:
        c.skip()
        rest = c.text[c.pos :]
        for op in _SYMBOL_OPS:
            if op == "**":
                continue
            if rest.startswith(op):
                return op
        for op in ("DIV", "MOD", "AND", "OR", "XOR"):
            if rest.startswith(op) and not rest[len(op) : len(op) + 1].isalnum():
                return op
        return None

    def expr(self, c: Cursor, min_prec: int = 0) -> Node:
        left = self.value(c)
        while True:
            op = self._operator(c)
            if op is None:
                return left
            prec = SIEMENS_PRECEDENCE[op]
            if prec < min_prec:
                return left
            c.take(op)
            right = self.expr(c, prec + 1)
            left = ("bin", op, left, right)


# ----------------------------------------------------------------------------- evaluation
class Store:
    """Parameters of a running program.

    ``numbered``: #n (LinuxCNC 1-5602, Fanuc #1-#999 and system variables, Siemens R n),
    ``named``: LinuxCNC #<name> (a scope per subroutine call for local names, one global
    scope for names starting with "_"), Siemens variables. ``vacant_zero``: LinuxCNC reads
    an unset numbered parameter as 0; Fanuc's vacant variables are :data:`VACANT`.
    """

    def __init__(self, *, vacant_zero: bool) -> None:
        self.vacant_zero = vacant_zero
        self.numbered: dict[int, float | None] = {}
        #: read-only system parameters computed when read (the current position...)
        self.providers: dict[int, Callable[[], float | None]] = {}
        self.globals: dict[str, float] = {}
        self.scopes: list[dict[str, float]] = [{}]

    def get(self, n: float) -> float | None:
        k = int(n)
        if k != n or k < 0:
            raise ExprError(f"parameter number {n:g} is not a whole number")
        provider = self.providers.get(k)
        if provider is not None:
            return provider()
        v = self.numbered.get(k, None)
        if v is None and self.vacant_zero:
            return 0.0
        return v

    def set(self, n: float, value: float | None) -> None:
        k = int(n)
        if k != n or k < 0:
            raise ExprError(f"parameter number {n:g} is not a whole number")
        if k == 0 and not self.vacant_zero:
            raise ExprError("#0 (vacant) cannot be assigned")
        self.numbered[k] = value

    def get_named(self, name: str) -> float:
        scope = self.globals if name.startswith("_") else self.scopes[-1]
        if name not in scope:
            raise ExprError(f"named parameter #<{name}> is not defined")
        return scope[name]

    def set_named(self, name: str, value: float) -> None:
        (self.globals if name.startswith("_") else self.scopes[-1])[name] = value

    def exists(self, name: str) -> bool:
        return name in (self.globals if name.startswith("_") else self.scopes[-1])


def evaluate(node: Node, store: Store, variables: dict[str, float] | None = None) -> float | None:
    """The value of ``node`` (None: a vacant Fanuc variable read on its own)."""
    if isinstance(node, float):
        return node
    kind = node[0]
    if kind == "param":
        n = _num(evaluate(node[1], store, variables))
        return store.get(n)
    if kind == "named":
        return store.get_named(node[1])
    if kind == "var":
        if variables is None or node[1] not in variables:
            raise ExprError(f"variable {node[1]} has no value")
        return variables[node[1]]
    if kind == "exists":
        return 1.0 if store.exists(node[1]) else 0.0
    if kind == "neg":
        return -_num(evaluate(node[1], store, variables))
    if kind == "not":
        return float(not _num(evaluate(node[1], store, variables)))
    if kind == "fn":
        x = _num(evaluate(node[2], store, variables))
        try:
            result = FUNCTIONS[node[1]](x)
        except (ValueError, OverflowError):  # SIN of inf, FIX of nan ...
            raise ExprError(f"{node[1]} of {x:g} is undefined") from None
        if not math.isfinite(result):
            raise ExprError(f"{node[1]} of {x:g} gives a value out of range")
        return result
    if kind == "atan":
        y = _num(evaluate(node[1], store, variables))
        x = _num(evaluate(node[2], store, variables))
        return math.degrees(math.atan2(y, x))
    if kind == "atan1":
        return math.degrees(math.atan(_num(evaluate(node[1], store, variables))))
    if kind == "minmax":
        a = _num(evaluate(node[2], store, variables))
        b = _num(evaluate(node[3], store, variables))
        return min(a, b) if node[1] == "MINVAL" else max(a, b)
    if kind == "bin":
        op = node[1]
        va = evaluate(node[2], store, variables)
        vb = evaluate(node[3], store, variables)
        if op in ("EQ", "NE", "==", "<>", "EQ~", "NE~") and (va is None or vb is None):
            # Fanuc: a vacant variable equals only another vacant one (#0)
            same = (va is None) == (vb is None) and (va is None or va == vb)
            return float(same if op in ("EQ", "==", "EQ~") else not same)
        result = BINARY[op][1](_num(va), _num(vb))
        if not math.isfinite(result):
            raise ExprError(f"{op} gives a value out of range")
        return result
    raise ExprError(f"bad expression node {kind}")  # pragma: no cover - parser makes none


def _num(v: float | None) -> float:
    return 0.0 if v is None else v


def is_constant(node: Node) -> bool:
    return isinstance(node, float)
