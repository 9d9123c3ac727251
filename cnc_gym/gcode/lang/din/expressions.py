"""The DIN 66025 family's expression language: R parameters, indirect P parameters, ``[ ]`` grouping,
``+ - * / ** MOD``, comparisons ``== != >= <= < >``, functions with their argument in brackets (AMK AZ-MC1
programming manual §2.4.1 "Mathematical expressions", §8 "Parameters").

An expression is read once, when the program is read, and compiled into a tree of small Python closures
(never ``eval``/``exec``): ``R1*SIN[R2*30]`` becomes ``mul(r(1), sin(mul(r(2), num(30))))``. Each closure
takes the parameter store (:class:`~cnc_gym.gcode.lang.din.parameters.ParameterStore`, a list of the
R values) and returns a float. That keeps a ``$WHILE`` loop at a few microseconds a block.

Grammar, highest precedence first (the manual says only "dot before dash" and "the brackets rule"; the
rest is C's, which the manual follows throughout):

1. operands: a number; ``R<n>`` or ``R[e]`` (the parameter numbered e); ``P<n>`` (indirect: the parameter
   whose number R<n> holds); ``NAME[e]`` (a function, blanks allowed before ``[``); ``[e]``;
2. ``**`` (right-associative);
3. ``*``, ``/``, ``MOD`` (C's ``fmod``: the sign of the dividend);
4. ``+``, ``-``;
5. ``== != >= <= < >`` (1.0 true, 0.0 false).

A sign may stand only at the start of an expression or right after ``[`` ("the sequence Operator → Term →
Operator is expected": ``R1 >= -5`` is an error, ``R1 >= [-5]`` is right, §9.1.1). An expression ends
where the grammar ends: after an operand, it goes on only if the next non-blank characters are a binary
operator (``X R1*SIN [R2*30]``, ``R1 = R1 - 1.5 Y R1`` is ``R1 = R1-1.5`` then ``Y R1``).

A value is *true* when its magnitude is at least 0.5 (§9.1.1).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

from cnc_gym.errors import ProgramError

#: A compiled expression: store → value.
Fn = Callable[[Any], float]
#: Largest parameter number (R0..R9999; the manual gives no count, and R1000+n receive the PLC's
#: transfer parameters, §4.2).
MAX_PARAMETER = 9999
#: Binary operators, longest first (so ``**`` is not read as ``*``, ``>=`` not as ``>``).
_OPERATORS = ("**", "==", "!=", ">=", "<=", "*", "/", "+", "-", "<", ">")
_COMPARISONS = frozenset({"==", "!=", ">=", "<=", "<", ">"})
_BLANKS = " \t"
_DIGITS = "0123456789"


def truth(value: float) -> bool:
    """TRUE iff |value| ≥ 0.5 (AMK AZ-MC1 programming manual §9.1.1)."""
    return value >= 0.5 or value <= -0.5


def math_error(message: str) -> ProgramError:
    return ProgramError(message, code="math-error")


# --------------------------------------------------------------------------- functions
def _positive(name: str, fn: Callable[[float], float]) -> Callable[[float], float]:
    def checked(x: float) -> float:
        if x <= 0.0:
            raise math_error(f"{name}[{x:g}]: the argument must be greater than 0")
        return fn(x)

    return checked


def _sqrt(x: float) -> float:
    if x < 0.0:
        raise math_error(f"SQRT[{x:g}]: the argument must not be negative")
    return math.sqrt(x)


def _unit_range(name: str, fn: Callable[[float], float]) -> Callable[[float], float]:
    def checked(x: float) -> float:
        if not -1.0 <= x <= 1.0:
            raise math_error(f"{name}[{x:g}]: the argument must be within -1 .. +1")
        return math.degrees(fn(x))

    return checked


def _tan(x: float) -> float:
    c = math.cos(math.radians(x))
    if abs(c) < 1e-12:
        raise math_error(f"TAN[{x:g}]: the tangent of ±90°, 270° … does not exist")
    return math.sin(math.radians(x)) / c


def _exp(base: float) -> Callable[[float], float]:
    def power(x: float) -> float:
        try:
            return math.pow(base, x)
        except OverflowError:
            raise math_error(f"{'EXP' if base == math.e else 'DEXP'}[{x:g}] overflows") from None

    return power


#: The DIN family's functions (§2.4.1.3): name → (number of arguments, function on floats). Angles are
#: degrees; INT cuts off the places after the decimal point, FRACT removes the integer part.
FUNCTIONS: dict[str, tuple[int, Callable[..., float]]] = {
    "ABS": (1, abs),
    "SQR": (1, lambda x: x * x),
    "SQRT": (1, _sqrt),
    "EXP": (1, _exp(math.e)),
    "LN": (1, _positive("LN", math.log)),
    "DEXP": (1, _exp(10.0)),
    "LOG": (1, _positive("LOG", math.log10)),
    "SIN": (1, lambda x: math.sin(math.radians(x))),
    "COS": (1, lambda x: math.cos(math.radians(x))),
    "TAN": (1, _tan),
    "ASIN": (1, _unit_range("ASIN", math.asin)),
    "ACOS": (1, _unit_range("ACOS", math.acos)),
    "ATAN": (1, lambda x: math.degrees(math.atan(x))),
    "INT": (1, lambda x: float(math.trunc(x))),
    "FRACT": (1, lambda x: x - math.trunc(x)),
}


# --------------------------------------------------------------------------- closures
def _num(v: float) -> Fn:
    return lambda s: v


def _param(n: int) -> Fn:
    return lambda s: s[n]


def _param_at(index: Fn) -> Fn:
    return lambda s: s.read(index(s))


def _indirect(n: int) -> Fn:
    return lambda s: s.read(s[n])


def _call(fn: Callable[[float], float], arg: Fn) -> Fn:
    return lambda s: fn(arg(s))


def _data(name: str, arg: Fn) -> Fn:
    return lambda s: s.data_function(name, arg(s))


def _neg(a: Fn) -> Fn:
    return lambda s: -a(s)


def _div(a: Fn, b: Fn) -> Fn:
    def div(s) -> float:
        d = b(s)
        if d == 0.0:
            raise math_error("division by zero")
        return a(s) / d

    return div


def _mod(a: Fn, b: Fn) -> Fn:
    def mod(s) -> float:
        d = b(s)
        if d == 0.0:
            raise math_error("MOD by zero")
        return math.fmod(a(s), d)

    return mod


def _pow(a: Fn, b: Fn) -> Fn:
    def power(s) -> float:
        x, y = a(s), b(s)
        try:
            return math.pow(x, y)
        except (ValueError, ZeroDivisionError):
            raise math_error(f"{x:g}**{y:g} is not a real number") from None
        except OverflowError:
            raise math_error(f"{x:g}**{y:g} overflows") from None

    return power


def _binary(op: str, a: Fn, b: Fn) -> Fn:
    if op == "+":
        return lambda s: a(s) + b(s)
    if op == "-":
        return lambda s: a(s) - b(s)
    if op == "*":
        return lambda s: a(s) * b(s)
    if op == "/":
        return _div(a, b)
    if op == "MOD":
        return _mod(a, b)
    if op == "**":
        return _pow(a, b)
    if op == "==":
        return lambda s: 1.0 if a(s) == b(s) else 0.0
    if op == "!=":
        return lambda s: 1.0 if a(s) != b(s) else 0.0
    if op == ">=":
        return lambda s: 1.0 if a(s) >= b(s) else 0.0
    if op == "<=":
        return lambda s: 1.0 if a(s) <= b(s) else 0.0
    if op == "<":
        return lambda s: 1.0 if a(s) < b(s) else 0.0
    return lambda s: 1.0 if a(s) > b(s) else 0.0


def value(fn: Fn, store) -> float:
    """Run a compiled expression: a finite float, or the ``math-error`` ProgramError."""
    try:
        result = fn(store)
    except OverflowError:
        raise math_error("the value overflows") from None
    if result - result != 0.0:  # inf or nan
        raise math_error("the value is not finite (overflow)")
    return result


def evaluate(node, variables, dialect=None, round_step=None) -> float:
    """:attr:`Language.evaluate <cnc_gym.gcode.dialect.Language.evaluate>`: the value of an expression word
    the reader made (``("din", fn, text)``)."""
    return value(node[1], variables)


# --------------------------------------------------------------------------- the parser
class ExpressionSyntaxError(ProgramError):
    """A syntax error in an expression (``column`` 1-based in the block's text)."""

    def __init__(self, message: str, column: int) -> None:
        super().__init__(message, code="syntax", column=column)


class Parser:
    """Reads expressions from one block's text (upper case, comments removed), from position ``pos``.

    ``functions``: the pure functions (name → (arity, fn)); ``data_functions``: names the parameter store
    answers at run time (the tool table's ``TLOC`` …).
    """

    def __init__(self, text: str, functions: Mapping[str, tuple[int, Callable[..., float]]],
                 data_functions: frozenset[str] = frozenset()) -> None:  # fmt: skip
        self.text = text
        self.pos = 0
        self.functions = functions
        self.data_functions = data_functions

    # ------------------------------------------------------------------ helpers
    def error(self, message: str, pos: int | None = None) -> ExpressionSyntaxError:
        return ExpressionSyntaxError(message, (self.pos if pos is None else pos) + 1)

    def skip_blanks(self) -> None:
        text, pos = self.text, self.pos
        while pos < len(text) and text[pos] in _BLANKS:
            pos += 1
        self.pos = pos

    def peek(self) -> str:
        return self.text[self.pos] if self.pos < len(self.text) else ""

    def at_end(self) -> bool:
        self.skip_blanks()
        return self.pos >= len(self.text)

    def expect(self, char: str, what: str) -> None:
        self.skip_blanks()
        if self.peek() != char:
            found = repr(self.peek()) if self.peek() else "the end of the block"
            raise self.error(f"expected {char!r} {what}, found {found}")
        self.pos += 1

    def _operator(self) -> str:
        """The binary operator at the position (after blanks), without consuming it."""
        self.skip_blanks()
        text, pos = self.text, self.pos
        if text.startswith("MOD", pos) and not (pos + 3 < len(text) and text[pos + 3].isalpha()):
            return "MOD"
        for op in _OPERATORS:
            if text.startswith(op, pos):
                return op
        return ""

    # ------------------------------------------------------------------ numbers and names
    def number(self) -> float | None:
        """An unsigned number at the position (``12``, ``1.5``, ``.5``, ``10.``), or None."""
        text, start = self.text, self.pos
        pos = start
        while pos < len(text) and text[pos] in _DIGITS:
            pos += 1
        if pos < len(text) and text[pos] == ".":
            pos += 1
            while pos < len(text) and text[pos] in _DIGITS:
                pos += 1
        if pos == start or text[start:pos] == ".":
            return None
        self.pos = pos
        return float(text[start:pos])

    def integer(self, what: str) -> int:
        """An unsigned integer literal (a parameter number, a program number)."""
        self.skip_blanks()
        start = self.pos
        text = self.text
        while self.pos < len(text) and text[self.pos] in _DIGITS:
            self.pos += 1
        if self.pos == start:
            raise self.error(f"{what}: expected a number")
        if self.pos < len(text) and text[self.pos] == ".":
            raise self.error(f"{what}: a whole number is expected, not a decimal")
        return int(text[start:self.pos])

    def name(self) -> str:
        text, start = self.text, self.pos
        pos = start
        while pos < len(text) and text[pos].isalpha():
            pos += 1
        self.pos = pos
        return text[start:pos]

    # ------------------------------------------------------------------ parameters
    def parameter_index(self, letter: str) -> tuple[Fn | None, int | None]:
        """After ``R``: a literal number (``R12``) or a bracketed expression (``R[R1+1]``)."""
        self.skip_blanks()
        if self.peek() == "[":
            self.pos += 1
            index = self.expression(unary=True)
            self.expect("]", f"to close {letter}[")
            return index, None
        number = self.integer(f"parameter {letter}")
        if number > MAX_PARAMETER:
            raise self.error(f"{letter}{number}: parameters are numbered 0..{MAX_PARAMETER}")
        return None, number

    # ------------------------------------------------------------------ the grammar
    def expression(self, *, unary: bool = True) -> Fn:
        """One whole expression (comparisons included); ``unary``: a sign may begin it."""
        left = self._additive(unary)
        op = self._operator()
        while op in _COMPARISONS:
            self.pos += len(op)
            right = self._additive(False)
            left = _binary(op, left, right)
            op = self._operator()
        return left

    def _additive(self, unary: bool) -> Fn:
        left = self._multiplicative(unary)
        op = self._operator()
        while op in ("+", "-"):
            self.pos += 1
            left = _binary(op, left, self._multiplicative(False))
            op = self._operator()
        return left

    def _multiplicative(self, unary: bool) -> Fn:
        left = self._signed(unary)
        op = self._operator()
        while op in ("*", "/", "MOD"):
            self.pos += len(op)
            left = _binary(op, left, self._signed(False))
            op = self._operator()
        return left

    def _signed(self, unary: bool) -> Fn:
        self.skip_blanks()
        sign = self.peek()
        if sign in ("-", "+"):
            if not unary:
                raise self.error(f"a signed value after an operator must be bracketed: write [{sign}…] "
                                 "(AMK AZ-MC1 programming manual §9.1.1: R1 >= [-5], not R1 >= -5)")
            self.pos += 1
            operand = self._power()
            return _neg(operand) if sign == "-" else operand
        return self._power()

    def _power(self) -> Fn:
        base = self._primary()
        if self._operator() == "**":
            self.pos += 2
            exponent = self._signed(False)  # right-associative: 2**3**2 = 2**9
            return _pow(base, exponent)
        return base

    def _primary(self) -> Fn:
        self.skip_blanks()
        start = self.pos
        char = self.peek()
        if char == "[":
            self.pos += 1
            inner = self.expression(unary=True)
            self.expect("]", "to close [")
            return inner
        number = self.number()
        if number is not None:
            return _num(number)
        if not char.isalpha():
            found = repr(char) if char else "the end of the block"
            raise self.error(f"expected a number, a parameter or [ ], found {found}")
        if char in "RP" and (self.pos + 1 >= len(self.text) or not self.text[self.pos + 1].isalpha()):
            self.pos += 1
            index, number_ = self.parameter_index(char)
            if char == "R":
                return _param(number_) if index is None else _param_at(index)  # type: ignore[arg-type]
            if index is not None:
                raise self.error("P takes a parameter number (P10: the parameter whose number R10 holds)",
                                 start)  # fmt: skip
            return _indirect(number_)  # type: ignore[arg-type]
        name = self.name()
        if name in self.functions or name in self.data_functions:
            self.expect("[", f"after {name} (function arguments stand in [ ])")
            arg = self.expression(unary=True)
            self.expect("]", f"to close {name}[")
            if name in self.data_functions:
                return _data(name, arg)
            return _call(self.functions[name][1], arg)
        raise self.error(f"unknown function or name {name!r}", start)


def literal_number(text: str) -> float | None:
    """A whole-text signed number (``-12.5``, ``+.5``), else None (the reader's quick test)."""
    body = text[1:] if text[:1] in "+-" else text
    if not body or body == "." or body.count(".") > 1 or not all(c in "0123456789." for c in body):
        return None
    return float(text)
