"""Macro expressions: a recursive-descent parser over the block text and an evaluator. Never eval().

Nodes are plain tuples (cheap to build, easy to test):

===========================  =======================================================
``("num", value)``           a constant
``("var", index_node)``      ``#i`` / ``#[expr]``
``("neg", node)``            unary minus
``("op", name, a, b)``       ``+ - * / MOD AND OR XOR``
``("fn", name, args)``       ``SIN[x]``, ``ATAN[y]/[x]`` (→ ``ATAN2``), ``POW[x,y]``
``("cmp", name, a, b)``      a condition of IF/WHILE: ``EQ NE GT GE LT LE``
``("and"|"or", a, b)``       conditions combined (dialects with ``condition_operators``)
===========================  =======================================================

Null ("vacant") semantics follow GSK §3.7.2: reading a null variable gives ``None``; ``#2=#1`` keeps
null; arithmetic treats null as 0 (``#1*5`` and ``#1+#1`` give 0). A unary sign on a bare null keeps it
null (so ``X-#1`` with #1 vacant drops the word, as ``X#1`` does). In conditions, EQ and NE tell null from 0
while GT GE LT LE read null as 0 (§3.7.2). Comparisons allow a relative difference of 1e-9 (the
controller computes with 8 significant digits, §3.7.4, so a loop counter summed from 0.1 steps must
still reach its bound).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.gcode.codes import round_to as _round_to

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect
    from cnc_gym.gcode.state import Variables as VariableStore

Node = tuple
MAX_OPERATORS = 200
#: Largest constant an expression may hold: "max ±99999999" (GSK 25i, 8 digits; §3.7.4). A
#: variable number and a GOTO target are constants too.
MAX_CONSTANT = 99_999_999.0

_MUL_WORDS = ("MOD", "AND")
_ADD_WORDS = ("XOR", "OR")
COMPARISONS = ("EQ", "NE", "GT", "GE", "LT", "LE")
#: Relative tolerance of EQ/NE/GT/GE/LT/LE (module docstring).
COMPARE_TOLERANCE = 1e-9


class ExpressionParser:
    """Parses expressions out of an (uppercased, space-free) block string starting at ``pos``."""

    def __init__(self, text: str, pos: int, dialect: Dialect) -> None:
        self.text = text
        self.pos = pos
        self.dialect = dialect
        self.depth = 0
        self.operators = 0
        #: Bracket depth at which AND/OR end an operand (a combined condition's comparison), or None.
        self._stop_depth: int | None = None

    # ------------------------------------------------------------------ helpers
    def _peek(self) -> str:
        return self.text[self.pos] if self.pos < len(self.text) else ""

    def _fail(self, message: str, code: str = "bad-expression") -> ProgramError:
        return self.dialect.error(message, code, column=self.pos + 1)

    def _count(self) -> None:
        # Bounds the tree depth (the evaluator recurses over it): a real macro line has a few dozen.
        self.operators += 1
        if self.operators > MAX_OPERATORS:
            raise self._fail(f"expression too long (more than {MAX_OPERATORS} operators)")

    def _open(self) -> None:
        self.depth += 1
        if self.depth > self.dialect.max_bracket_depth:
            raise self._fail(f"brackets nested deeper than {self.dialect.max_bracket_depth} levels",
                             "bracket-nesting")  # fmt: skip
        self.pos += 1

    def _close(self) -> None:
        if self._peek() != "]":
            got = self._peek() or "end of block"
            raise self._fail(f"expected ']' in expression, got {got!r}")
        self.depth -= 1
        self.pos += 1

    def _word(self) -> str:
        """The run of letters at pos (not consumed)."""
        end = self.pos
        text = self.text
        while end < len(text) and "A" <= text[end] <= "Z":
            end += 1
        return text[self.pos : end]

    # ------------------------------------------------------------------ grammar
    def bracketed(self) -> Node:
        """``[ expr ]`` starting at '['."""
        self._open()
        node = self.expression()
        self._close()
        return node

    def expression(self) -> Node:
        node = self.term()
        while True:
            c = self._peek()
            if c in ("+", "-") and c:
                self.pos += 1
                self._count()
                node = ("op", c, node, self.term())
                continue
            word = self._word()
            op = next((w for w in _ADD_WORDS if word.startswith(w)), None)
            if op is None or (op == "OR" and self._stop_depth == self.depth):
                return node
            self.pos += len(op)
            self._count()
            node = ("op", op, node, self.term())

    def term(self) -> Node:
        node = self.unary()
        while True:
            c = self._peek()
            if c in ("*", "/") and c:
                self.pos += 1
                self._count()
                node = ("op", c, node, self.unary())
                continue
            word = self._word()
            op = next((w for w in _MUL_WORDS if word.startswith(w)), None)
            if op is None or (op == "AND" and self._stop_depth == self.depth):
                return node
            self.pos += len(op)
            self._count()
            node = ("op", op, node, self.unary())

    def unary(self) -> Node:
        signs = 0
        while self._peek() in ("-", "+") and self._peek():
            if self.text[self.pos] == "-":
                signs += 1
            self.pos += 1
        node = self.primary()
        return ("neg", node) if signs % 2 else node

    def condition(self) -> Node:
        """``[ expr CMP expr ]`` starting at '[' (IF / WHILE); CMP is EQ NE GT GE LT LE (§3.7.5).

        With the dialect's condition operators (``Dialect.condition_operators``: Fanuc's AND, OR)
        comparisons combine, AND before OR: ``[#1 GT 0 AND #2 LT 5]``, ``[[#1 GT 0] OR [#2 EQ 1]]``. At
        the level of the comparison AND/OR are logical; inside an operand's own brackets they stay the
        bitwise operators (``[#1 AND 3] EQ 1``)."""
        self._open()
        node = self._logical_or() if self.dialect.condition_operators else self._comparison()
        self._close()
        return node

    def _comparison(self) -> Node:
        left = self.expression()
        word = self._word()[:2]
        if word not in COMPARISONS:
            got = self.text[self.pos : self.pos + 4] or "end of block"
            raise self._fail(f"a condition needs EQ, NE, GT, GE, LT or LE, got {got!r}")
        self.pos += 2
        self._count()
        right = self.expression()
        return ("cmp", word, left, right)

    def _logic_word(self) -> str | None:
        word = self._word()
        for op in ("AND", "OR"):
            if word.startswith(op) and op in self.dialect.condition_operators:
                return op
        return None

    def _logical_or(self) -> Node:
        node = self._logical_and()
        while self._logic_word() == "OR":
            self.pos += 2
            self._count()
            node = ("or", node, self._logical_and())
        return node

    def _logical_and(self) -> Node:
        node = self._logical_factor()
        while self._logic_word() == "AND":
            self.pos += 3
            self._count()
            node = ("and", node, self._logical_factor())
        return node

    def _logical_factor(self) -> Node:
        """A bracketed condition, or a comparison whose operands stop at a logical AND/OR."""
        if self._peek() == "[":
            saved = (self.pos, self.depth, self.operators)
            try:
                return self.condition()
            except ProgramError:
                self.pos, self.depth, self.operators = saved  # an arithmetic bracket: ``[#1+1] GT 2``
        outer, self._stop_depth = self._stop_depth, self.depth
        try:
            return self._comparison()
        finally:
            self._stop_depth = outer

    def number(self) -> float:
        text = self.text
        start = self.pos
        end = start
        while end < len(text) and ("0" <= text[end] <= "9" or text[end] == "."):
            end += 1
        literal = text[start:end]
        if literal.count(".") > 1 or literal == ".":
            raise self._fail(f"bad number {literal!r}", "bad-number")
        value = self.constant(literal)
        self.pos = end
        return value

    def constant(self, literal: str) -> float:
        """The value of an unsigned literal (ASCII digits, at most one point) of at most 8 integer digits
        (alarm 3 TOO MANY DIGITS): 1 followed by 400 zeros would be inf, and inf a crash wherever an
        integer is taken of it."""
        integer = literal.split(".", 1)[0].lstrip("0")
        if len(integer) > 8:
            shown = integer if len(integer) <= 20 else integer[:20] + "…"
            raise self._fail(f"constant {shown} has more than 8 digits (at most ±{MAX_CONSTANT:.0f})",
                             "too-many-digits")  # fmt: skip
        return float(literal)

    def variable(self) -> Node:
        """After '#': ``#123`` or ``#[expr]``."""
        self.pos += 1
        c = self._peek()
        if _is_digit(c):
            start = self.pos
            while _is_digit(self._peek()):
                self.pos += 1
            if self._peek() == ".":
                raise self._fail("a variable number must be an integer", "bad-variable")
            return ("var", ("num", self.constant(self.text[start : self.pos])))
        if c == "[":
            return ("var", self.bracketed())
        raise self._fail("'#' must be followed by a variable number or [expression]", "missing-operand")

    def primary(self) -> Node:
        c = self._peek()
        if _is_digit(c) or c == ".":
            return ("num", self.number())
        if c == "#":
            return self.variable()
        if c == "[":
            return self.bracketed()
        word = self._word()
        if word:
            name = next((f for f in sorted(self.dialect.functions, key=len, reverse=True)
                         if word.startswith(f)), None)  # fmt: skip
            if name is None or self.text[self.pos + len(name) : self.pos + len(name) + 1] != "[":
                raise self._fail(f"unknown function or word {word!r} in expression")
            self.pos += len(name)
            return self.function(name)
        if not c:
            raise self._fail("expression ends where an operand is expected", "missing-operand")
        raise self._fail(f"unexpected {c!r} in expression", "missing-operand")

    def function(self, name: str) -> Node:
        arity, _ = self.dialect.functions[name]
        self._open()
        args = [self.expression()]
        while self._peek() == ",":
            self.pos += 1
            args.append(self.expression())
        self._close()
        if name == "ATAN" and len(args) == 1 and self.text.startswith("/[", self.pos):
            # Two-argument form ATAN[y]/[x] (Fanuc Macro B; GSK precision table "ATAN b/c").
            self.pos += 1
            args.append(self.bracketed())
            name = "ATAN2"
            arity = 2
        if len(args) != arity:
            raise self._fail(f"{name} takes {arity} argument(s), got {len(args)}")
        return ("fn", name, tuple(args))


def evaluate(node: Node, variables: VariableStore, dialect: Dialect, round_step: float | None = None,
             ) -> float | None:  # fmt: skip
    """Value of ``node`` (None = null). ``round_step``: inside an address, ROUND rounds to that step."""
    kind = node[0]
    if kind == "num":
        return node[1]
    if kind == "var":
        index = node[1]
        if index[0] == "num":
            return variables.read(index[1])
        return variables.read(evaluate(index, variables, dialect, round_step))
    if kind == "neg":
        value = evaluate(node[1], variables, dialect, round_step)
        return None if value is None else -value
    if kind == "op":
        a = evaluate(node[2], variables, dialect, round_step) or 0.0
        b = evaluate(node[3], variables, dialect, round_step) or 0.0
        return _binary(node[1], a, b, dialect)
    if kind == "fn":
        name = node[1]
        args = [evaluate(a, variables, dialect, round_step) or 0.0 for a in node[2]]
        if name == "ROUND" and round_step is not None:
            return _round_to(args[0], round_step)
        try:
            result = dialect.functions[name][1](*args)
        except ZeroDivisionError:
            raise dialect.error(f"{name}[{_fmt(args)}]: division by zero", "division-by-zero") from None
        except (ValueError, OverflowError):
            raise dialect.error(f"{name}[{_fmt(args)}] is undefined", "math-domain") from None
        return _finite(result, dialect, name)
    raise AssertionError(f"bad expression node {node!r}")


def evaluate_condition(node: Node, variables: VariableStore, dialect: Dialect) -> bool:
    """Truth of a ``("cmp", …)`` node with GSK null semantics (module docstring), or of an ``("and"|"or",
    a, b)`` combination (both sides are evaluated, as a controller computing the truth values does)."""
    if node[0] in ("and", "or"):
        first = evaluate_condition(node[1], variables, dialect)
        second = evaluate_condition(node[2], variables, dialect)
        return (first and second) if node[0] == "and" else (first or second)
    _, op, left, right = node
    a = evaluate(left, variables, dialect)
    b = evaluate(right, variables, dialect)
    if op in ("EQ", "NE"):
        if a is None or b is None:
            same = a is None and b is None  # null equals only null (§3.7.2)
        else:
            same = abs(a - b) <= COMPARE_TOLERANCE * max(1.0, abs(a), abs(b))
        return same if op == "EQ" else not same
    a = a or 0.0
    b = b or 0.0
    margin = COMPARE_TOLERANCE * max(1.0, abs(a), abs(b))
    if op == "GT":
        return a - b > margin
    if op == "GE":
        return a - b >= -margin
    if op == "LT":
        return b - a > margin
    return b - a >= -margin  # LE


def _is_digit(c: str) -> bool:
    """An ASCII digit (str.isdigit also takes '²' and '١', which are not program text)."""
    return len(c) == 1 and "0" <= c <= "9"


def _binary(op: str, a: float, b: float, dialect: Dialect) -> float:
    if op == "+":
        result = a + b
    elif op == "-":
        result = a - b
    elif op == "*":
        result = a * b
    elif op == "/":
        if b == 0:
            raise dialect.error(f"division by zero ({_fmt([a])}/0)", "division-by-zero")
        result = a / b
    elif op == "MOD":
        if b == 0:
            raise dialect.error(f"division by zero ({_fmt([a])} MOD 0)", "division-by-zero")
        result = math.fmod(a, b)
    else:  # AND OR XOR: on 32-bit integers (§3.7.4)
        ia, ib = _int32(a, op, dialect), _int32(b, op, dialect)
        result = float(ia & ib if op == "AND" else ia | ib if op == "OR" else ia ^ ib)
    return _finite(result, dialect, op)


def _int32(x: float, op: str, dialect: Dialect) -> int:
    if x != int(x) or not -(2**31) <= x < 2**31:
        raise dialect.error(f"{op} needs 32-bit integers, got {_fmt([x])}", "math-domain")
    return int(x)


def _finite(x: float, dialect: Dialect, what: str) -> float:
    if not math.isfinite(x):
        raise dialect.error(f"{what}: result out of range", "overflow")
    return float(x)


def _fmt(values: list[float]) -> str:
    return ",".join(f"{v:g}" for v in values)
