"""Read phase: program text → :class:`Program` (a list of :class:`Block` with a program counter).

Lexical rules (GSK 25i, seed notes §1; the dialect supplies the number formats):

* a line is a block; ``;`` also ends a block (EOB, L392); a line holding only ``%`` is a tape mark and a
  second one ends the tape (text after it is not read);
* ``( … )`` is a comment; upper and lower case are the same; spaces and tabs are ignored;
* ``/`` or ``/n`` (n = 1..9, several as ``/1/3``) at the head of a block marks it for optional block
  skip; a ``/`` later in the block discards the rest of the block (L533-L535);
* ``O`` program number and ``N`` sequence number at the head; then words: an address letter and a number,
  ``#i``, ``#[e]``, ``[e]`` or a signed form of these; or one macro assignment ``#i = e``;
* literal numbers are truncated to the least input increment (L685-L690); without a decimal point they are
  in mm/inch/s (DPI = 1) or in least increments (DPI = 0), per the dialect.

Plain blocks (no ``#``, ``[``, ``/`` or keywords) go through one regex match and one ``findall``; the rest
through a small hand-written scanner that gives precise errors.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.gcode.expressions import ExpressionParser

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect

_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)"
# Hot-path patterns: deliberately loose ([0-9.]+); float() then rejects "1.2.3" and ".".
_PLAIN_BLOCK = re.compile(r"(?:[A-Z][-+]?[0-9.]+)+")
_PLAIN_WORD = re.compile(r"([A-Z])([-+]?[0-9.]+)")
_SPACES = re.compile(r"[ \t\r\f\v]+")
_NUMBER_AT = re.compile(_NUMBER)


class Block:
    """One block after reading.

    ``words``: ``(letter, value, text)`` tuples; ``value`` is a float for a literal (``text`` its
    digits, for decimal-point checks) or an expression node (``text`` None) evaluated at execution. A
    plain block (read on the hot path) keeps just ``(letter, digits)`` pairs; ``word[-1]`` is the text
    either way.
    ``assign``: ``(target_node, value_node)`` for a macro assignment block (then ``words`` is empty).
    ``skip``: bit mask of the block-skip switches (bit n for ``/n``) that suppress the block.
    ``gs``, ``ms``, ``values``: for a block without expressions, the words split once at read time (G
    numbers, M numbers, other addresses → value); None when the block has expressions.
    """

    __slots__ = ("assign", "gs", "has_expr", "line", "ms", "number", "skip", "values", "words")

    def __init__(self, line: int, words: tuple, *, skip: int = 0, has_expr: bool = False,
                 assign: tuple | None = None, number: int | None = None) -> None:  # fmt: skip
        self.line = line
        self.words = words
        self.skip = skip
        self.has_expr = has_expr
        self.assign = assign
        self.number = number
        if has_expr:
            self.gs = self.ms = self.values = None
        else:
            self.gs, self.ms, self.values = split_words(words)

    def __repr__(self) -> str:
        return f"Block(line={self.line}, words={self.words!r}, skip={self.skip}, assign={self.assign!r})"


def split_words(words) -> tuple[tuple | None, tuple | None, dict[str, float]]:
    """(G numbers or None, M numbers or None, {address: value}); a repeated address is an error."""
    values: dict[str, float] = {}
    gs = ms = None
    for letter, value, _ in words:
        if letter == "G":
            gs = [value] if gs is None else [*gs, value]
        elif letter == "M":
            ms = [value] if ms is None else [*ms, value]
        elif letter in values:
            # The manual's default is "the later one is valid" (L503, 1802#6 AD2 = 0); we take the
            # AD2 = 1 behaviour, an alarm, as with two G codes of one group (docs/gcode.md).
            raise ProgramError(f"address {letter} appears twice in the block", code="duplicate-word")
        else:
            values[letter] = value
    return gs, ms, values


@dataclass
class Program:
    """A read program: blocks in order, with sequence numbers indexed for a later GOTO."""

    blocks: list[Block]
    file: str = "<program>"
    program_number: int | None = None
    sequence_index: dict[int, list[int]] = field(default_factory=dict)


class Reader:
    """Turns program text into a :class:`Program` for one dialect."""

    def __init__(self, dialect: Dialect) -> None:
        self.dialect = dialect
        rules = dialect.addresses
        self._rules = rules
        self._length_letters = frozenset(a for a, r in rules.items() if r.unit == "length")
        self._decimals = max(0, round(-_log10(dialect.least_increment_mm)))
        self._increment = dialect.least_increment_mm
        self._max_words = dialect.max_words_per_block
        # Per letter: (low, high, point_allowed, is_length) for the hot loop.
        self._fast_rules = {a: (r.low, r.high, r.point_allowed, a in self._length_letters)
                            for a, r in rules.items()}  # fmt: skip

    def error(self, message: str, code: str, line: int, column: int | None = None, alarm: int | None = None):
        err = self.dialect.error(message, code, column=column, alarm=alarm)
        err.line = line
        return err

    # ------------------------------------------------------------------ program
    def read(self, text: str, file: str = "<program>") -> Program:
        blocks: list[Block] = []
        program_number = None
        seen_percent = False
        for line_no, raw in enumerate(text.splitlines(), start=1):
            stripped = raw.strip()
            if not stripped:
                continue
            if stripped.startswith("%"):
                if stripped.strip("%").strip() and not stripped[1:].lstrip().startswith("("):
                    raise self.error("'%' must stand alone on its line (tape start/end mark)",
                                     "bad-character", line_no)  # fmt: skip
                if seen_percent:
                    break  # second '%': end of tape
                seen_percent = True
                continue
            try:
                # Hot path inline: a plain line (no comment, ';', expression) is one regex match.
                if "(" not in stripped and ")" not in stripped and ";" not in stripped:
                    text_block = stripped.replace(" ", "").upper()
                    if "\t" in text_block:
                        text_block = _SPACES.sub("", text_block)
                    if _PLAIN_BLOCK.fullmatch(text_block):
                        blocks.append(self._plain_block(text_block, line_no))
                        continue
                blocks.extend(self.read_line(stripped, line_no))
            except ProgramError as exc:
                raise exc.located(file, line_no) from None
        program = Program(blocks, file=file)
        for index, block in enumerate(blocks):
            if block.number is not None:
                program.sequence_index.setdefault(block.number, []).append(index)
            if program_number is None and block.words and block.words[0][0] == "O":
                program_number = int(block.words[0][1])
        program.program_number = program_number
        return program

    def read_line(self, text: str, line: int) -> list[Block]:
        """Blocks of one source line (usually one; ``;`` separates several)."""
        if "(" in text or ")" in text:
            text = self._strip_comments(text, line)
        text = _SPACES.sub("", text).upper()
        if "%" in text:
            raise self.error("'%' must stand alone on its line (tape start/end mark)", "bad-character", line)
        if ";" in text:
            return [b for part in text.split(";") if part and (b := self.read_block(part, line)) is not None]
        if not text:
            return []
        block = self.read_block(text, line)
        return [block] if block is not None else []

    def _strip_comments(self, text: str, line: int) -> str:
        out = []
        depth_start = -1
        for i, c in enumerate(text):
            if depth_start >= 0:
                if c == ")":
                    depth_start = -1
                continue
            if c == "(":
                depth_start = i
            elif c == ")":
                raise self.error("')' without '('", "bad-character", line, i + 1)
            else:
                out.append(c)
        if depth_start >= 0:
            raise self.error("comment '(' is not closed on its line", "unclosed-comment", line,
                             depth_start + 1)  # fmt: skip
        return "".join(out)

    # ------------------------------------------------------------------ block
    def read_block(self, text: str, line: int) -> Block | None:
        if _PLAIN_BLOCK.fullmatch(text):
            return self._plain_block(text, line)
        return self._scan_block(text, line)

    def _plain_block(self, text: str, line: int) -> Block:
        """The hot path: letters and literal numbers only. Words are split and checked in one pass;
        ``Block.words`` keeps the ``(letter, digits)`` pairs for decimal-point checks."""
        rules = self._fast_rules
        pairs = _PLAIN_WORD.findall(text)
        if len(pairs) > self._max_words:
            raise self.error(f"{len(pairs)} words in one block (at most {self._max_words})", "too-many-words",
                             line)  # fmt: skip
        values: dict[str, float] = {}
        gs = ms = None
        for letter, digits in pairs:
            low, high, point_allowed, is_length = rules[letter]
            try:
                if "." in digits:
                    fraction = len(digits) - digits.index(".") - 1
                    if not point_allowed or (is_length and fraction > self._decimals):
                        value = self._literal(letter, digits, rules[letter], line)
                    else:
                        value = float(digits)
                elif is_length and not self.dialect.integer_is_unit:
                    value = self._literal(letter, digits, rules[letter], line)
                else:
                    value = float(digits)
            except ValueError:
                raise self.error(f"bad number {letter}{digits}", "bad-number", line) from None
            if not low <= value <= high:
                self._literal(letter, digits, rules[letter], line)  # raises with the right code
            if letter == "G":
                if gs is None:
                    gs = [value]
                else:
                    gs.append(value)
            elif letter == "M":
                if ms is None:
                    ms = [value]
                else:
                    ms.append(value)
            elif letter in values:
                raise self.error(f"address {letter} appears twice in the block", "duplicate-word", line)
            else:
                values[letter] = value
        number = None
        if "N" in values or "O" in values:
            head = pairs[0][0]
            if "O" in values and head != "O":
                raise self.error("O must be at the head of the block", "misplaced-word", line)
            if "N" in values:
                if not (head == "N" or (head == "O" and pairs[1][0] == "N")):
                    raise self.error("N must be at the head of the block", "misplaced-word", line)
                number = int(values.pop("N"))
        block = Block.__new__(Block)
        block.line = line
        block.words = pairs
        block.skip = 0
        block.has_expr = False
        block.assign = None
        block.number = number
        block.gs = gs
        block.ms = ms
        block.values = values
        return block

    def _literal(self, letter: str, digits: str, rule: tuple, line: int) -> float:
        low, high, point_allowed, is_length = rule
        has_point = "." in digits
        if has_point:
            if not point_allowed:
                raise self.error(f"{letter}{digits}: no decimal point allowed in {letter}",
                                 "decimal-point-not-allowed", line)  # fmt: skip
            if is_length:
                dot = digits.index(".")
                if len(digits) - dot - 1 > self._decimals:
                    # Finer than the least input increment: truncated (L685-L690), on the text, so
                    # 9.87654 becomes exactly 9.8765 (no binary rounding on the way).
                    digits = digits[: dot + 1 + self._decimals]
        value = float(digits)
        if is_length and not has_point and not self.dialect.integer_is_unit:
            value *= self._increment
        if not low <= value <= high:
            if value < 0 <= low:
                raise self.error(f"{letter}{digits}: {letter} cannot be negative", "bad-sign", line)
            alarm = self._rules[letter].alarm
            raise self.error(f"{letter}{digits}: out of range {low:g} to {high:g}", "value-out-of-range",
                             line, alarm=alarm)  # fmt: skip
        return value

    def _head(self, words: list, line: int) -> tuple[list, int | None]:
        """Take O (program number) and N (sequence number) off the head of a block."""
        number = None
        rest = list(words)
        if rest and rest[0][0] == "O":
            if not isinstance(rest[0][1], float):
                raise self.error("O cannot be a variable (L5158)", "variable-not-allowed", line)
            rest = rest[1:]
            if rest and rest[0][0] == "O":
                raise self.error("two program numbers O in one block", "duplicate-word", line)
        if rest and rest[0][0] == "N":
            if not isinstance(rest[0][1], float):
                raise self.error("N cannot be a variable (L5160)", "variable-not-allowed", line)
            number = int(rest[0][1])
            rest = rest[1:]
        for letter, _, _ in rest:
            if letter in "ON":
                raise self.error(f"{letter} must be at the head of the block", "misplaced-word", line)
        # O is kept as a word (recorded as the program number); N is dropped (kept in Block.number).
        head = [w for w in words[:1] if w[0] == "O"]
        return head + rest, number

    def _scan_block(self, text: str, line: int) -> Block | None:
        """Everything that is not plain: block skip, expressions, variables, assignments, keywords."""
        pos = 0
        skip = 0
        # Optional block skip: /, /n, /1/3 at the head (L520-L524).
        while pos < len(text) and text[pos] == "/":
            pos += 1
            if pos < len(text) and text[pos].isdigit():
                n = int(text[pos])
                if n == 0:
                    raise self.error("block skip switch must be 1 to 9", "bad-block-skip", line, pos + 1)
                pos += 1
            elif pos < len(text) and text[pos] == "#":
                raise self.error("a variable cannot follow '/' (L5159)", "variable-not-allowed", line,
                                 pos + 1)  # fmt: skip
            elif pos < len(text) and text[pos] == "/":
                raise self.error("'//n' is not a block skip; write /1/n (L522-L524)", "bad-block-skip", line,
                                 pos + 1)  # fmt: skip
            else:
                n = 1
            skip |= 1 << n
        if pos >= len(text):
            return Block(line, (), skip=skip) if skip else None
        words: list = []
        has_expr = False
        assign = None
        rules = self._fast_rules
        while pos < len(text):
            c = text[pos]
            if c == "/":
                break  # a slash inside the block: the rest of the block is ignored (L533-L535)
            if c == "#":
                if any(w[0] not in "ON" for w in words):
                    raise self.error("a macro assignment must be alone in its block", "bad-expression", line,
                                     pos + 1)  # fmt: skip
                assign, pos = self._assignment(text, pos, line)
                break
            if c == ",":
                raise self.error(f"chamfer/corner rounding ,{text[pos + 1:pos + 2]} is not implemented yet",
                                 "not-implemented", line, pos + 1)  # fmt: skip
            if not ("A" <= c <= "Z"):
                raise self.error(f"illegal character {c!r}", "bad-character", line, pos + 1)
            keyword = self._keyword(text, pos)
            if keyword:
                raise self.error(f"macro statement {keyword} is not implemented yet (macro control flow "
                                 "comes in a later issue)", "not-implemented", line, pos + 1)  # fmt: skip
            letter = c
            pos += 1
            value, text_digits, pos = self._value(letter, text, pos, line, rules[letter])
            if text_digits is None:
                has_expr = True
            words.append((letter, value, text_digits))
        if len(words) > self._max_words:
            raise self.error(f"{len(words)} words in one block (at most {self._max_words})", "too-many-words",
                             line)  # fmt: skip
        number = None
        if words and words[0][0] in "ON":
            words, number = self._head(words, line)
        elif any(w[0] in "ON" for w in words):
            self._head(words, line)  # raises misplaced-word
        if not words and assign is None and not skip and number is None:
            return None
        return Block(line, tuple(words), skip=skip, has_expr=has_expr, assign=assign, number=number)

    def _keyword(self, text: str, pos: int) -> str | None:
        end = pos
        while end < len(text) and "A" <= text[end] <= "Z":
            end += 1
        run = text[pos:end]
        if len(run) < 2:
            return None
        for keyword in sorted(self.dialect.keywords, key=len, reverse=True):
            if run.startswith(keyword):
                return keyword
        return None

    def _value(self, letter: str, text: str, pos: int, line: int, rule: tuple):
        """The value after an address letter: literal, #var, [expr], or a signed form. Returns
        (value, digits or None, new pos)."""
        start = pos
        match = _NUMBER_AT.match(text, pos)
        if match:
            end = match.end()
            if end < len(text) and (text[end] == "." or text[end].isdigit()):
                bad = _NUMBER_AT.match(text, end)
                tail = text[end : (bad.end() if bad else end + 1)]
                raise self.error(f"bad number {letter}{match.group()}{tail}", "bad-number", line, start)
            digits = match.group()
            return self._literal(letter, digits, rule, line), digits, end
        sign = ""
        if pos < len(text) and text[pos] in "+-":
            sign = text[pos]
            pos += 1
        c = text[pos] if pos < len(text) else ""
        if c in ("#", "["):
            parser = ExpressionParser(text, pos, self.dialect)
            node = parser.variable() if c == "#" else parser.bracketed()
            if sign == "-":
                node = ("neg", node)
            return node, None, parser.pos
        if sign:
            raise self.error(f"{letter}{sign}: sign without a number", "bad-number", line, start)
        if c == "." or c.isdigit():
            raise self.error(f"bad number after {letter}", "bad-number", line, start)
        raise self.error(f"address {letter} has no value", "missing-value", line, start)

    def _assignment(self, text: str, pos: int, line: int) -> tuple[tuple, int]:
        parser = ExpressionParser(text, pos, self.dialect)
        target = parser.variable()[1]
        if parser._peek() != "=":
            raise self.error("a '#' variable at the start of a block must be assigned: #i=<expression>",
                             "bad-expression", line, parser.pos + 1)  # fmt: skip
        parser.pos += 1
        value = parser.expression()
        if parser.pos < len(text) and text[parser.pos] != "/":
            raise self.error(f"unexpected {text[parser.pos:]!r} after the expression", "bad-expression", line,
                             parser.pos + 1)  # fmt: skip
        return (target, value), len(text)


def _log10(x: float) -> float:
    import math

    return math.log10(x)
