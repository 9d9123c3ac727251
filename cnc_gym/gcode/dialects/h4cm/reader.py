"""The H4C-M's lexical rules on the Fanuc family's reader (HUST H4C-M manual §2.3.5 decimal points,
§2.3.6 notes for edition, §3.41 G65 macro instructions):

* **a block holds at most 64 characters** (ERROR 8; §2.3.6 prints 80 bytes and "Err-18", a copy from
  another model, which chapter 6 contradicts);
* **N labels are strings**: "N10, N010, N0010 are three different block numbers", and a G65 branch
  ``P0010`` finds ``N0010`` only. ``Block.number`` holds the label's digits behind a leading 1 (N10 → 110,
  N010 → 1010), so the family's sequence index and its wrapping search tell them apart;
* **numbers without a decimal point** in a length address count least increments of the unit in force
  (4/3 format: ``X2`` is 0.002 mm; ``Dialect.integer_is_unit`` False, the family's least-unit reader); F is
  mm/min with or without a point;
* **variables** ``#1``-``#9999`` hold integers in least increments: ``G01 U#12`` moves #12 × 0.001 mm
  (:func:`evaluate`); F, S and the other plain addresses take a variable's integer as it is;
* **G65 is one macro instruction** ``G65 Lm P#i A#j B#k``, not a macro call: the reader turns the block
  into a statement ``("hust", m, p, a, b)`` that the runner executes (``macro.py``). There are no
  expressions, brackets, assignments or IF/WHILE in the language: such text is refused by name.

``( … )`` comments, ``;`` and ``/`` block skip are the family's (the manual documents no comment or skip
character; they are accepted as an extension, docs/h4cm.md).
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from cnc_gym.gcode.lang.fanuc import least_units
from cnc_gym.gcode.lang.fanuc.expressions import evaluate as family_evaluate
from cnc_gym.gcode.lang.fanuc.least_units import LeastUnitReader
from cnc_gym.gcode.program import PlainBlock, SpecialBlock

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect
    from cnc_gym.gcode.program import Block, Program

#: ERROR 8: more than 64 characters in one block.
MAX_BLOCK_CHARS = 64
#: G65 branch operations (L80-L86) take a label in P; L99 a number; the rest a result variable #i.
BRANCHES = frozenset(range(80, 87))
USER_ALARM = 99
#: Largest magnitude of a G65 constant and of a variable (±9 999 999, the 4/3 range ±9999.999).
MAX_INTEGER = 9_999_999

_G65 = re.compile(r"G0*65(?![0-9.])")
_HEAD = re.compile(r"((?:/[0-9]?)*)(?:N([0-9]+))?")
_WORD = re.compile(r"([A-Z])([^A-Z]*)")
_OPERAND = re.compile(r"([+-]?)(#?)([0-9]+)")
_DIGITS = re.compile(r"[0-9]+")


def label_key(digits: str) -> int:
    """The sequence-number key of an N label or a G65 branch target: its digit string behind a 1, so
    that ``N10`` (110) and ``N010`` (1010) differ."""
    return int("1" + digits)


def label_text(key: int) -> str:
    """The label a key stands for (``1010`` → ``N010``)."""
    return "N" + str(key)[1:]


def evaluate(node: tuple, variables, dialect: Dialect, round_step: float | None = None) -> float | None:
    """The family's least-unit evaluator (``lang/fanuc/least_units.py``: ``X2`` is 2 least increments of the
    unit in force); a variable read in a length word counts least increments too (``round_step``, the
    core's increment in force): ``U#12`` with #12 = 2500 is 2.5 mm."""
    if node[0] != "var" and not (node[0] == "neg" and node[1][0] == "var"):
        return least_units.evaluate(node, variables, dialect, round_step)
    value = family_evaluate(node, variables, dialect, None)
    if value is not None and round_step:
        return value * round_step
    return value


class HustReader(LeastUnitReader):
    """The family's least-unit reader with the H4C-M's block length, string labels and G65 statements."""

    def read(self, text: str, file: str = "<program>") -> Program:
        for number, raw in enumerate(text.splitlines(), start=1):
            if len(raw) > MAX_BLOCK_CHARS:
                length = len(raw.strip())
                if length > MAX_BLOCK_CHARS:
                    err = self.error(f"{length} characters in one block (at most {MAX_BLOCK_CHARS}, "
                                     "HUST H4C-M "
                                     "manual §2.3.6)", "block-too-long", number)  # fmt: skip
                    raise err.located(file, number)
        return super().read(text, file)

    def read_line(self, text: str, line: int) -> list[Block]:
        if "[" in text or "]" in text:
            raise self.error("the H4C-M has no expressions: a word is a number or a variable #n (arithmetic "
                             "is G65 Lm P#i A#j B#k)", "bad-expression", line)  # fmt: skip
        return super().read_line(text, line)

    def read_block(self, text: str, line: int) -> Block | None:
        if _G65.search(text):
            return self._g65(text, line)
        if "=" in text:
            raise self.error("the H4C-M has no assignment #i=…: set a variable with G65 L01 P#i A_",
                             "bad-expression", line)  # fmt: skip
        return super().read_block(text, line)

    def _plain_block(self, text: str, line: int) -> Block:
        if _G65.search(text):
            return self._g65(text, line)
        block = super()._plain_block(text, line)
        # A plain block keeps its (letter, digits) pairs, N included; a rescanned one got its key in _head.
        if isinstance(block, PlainBlock) and block.number is not None:
            block.number = self._label(next(w[1] for w in block.words if w[0] == "N"), line)
        return block

    def _head(self, words: list, line: int) -> tuple[list, int | None]:
        rest, number = super()._head(words, line)
        if number is not None:
            number = self._label(next(w[2] for w in words if w[0] == "N"), line)
        return rest, number

    def _label(self, digits: str, line: int) -> int:
        """An N label's key; the label is its digits as written, so a sign (``N+1``, ``N-0``) is refused."""
        if not _DIGITS.fullmatch(digits):
            raise self.error(f"N{digits}: a block label is digits only, as written (no sign, no point)",
                             "bad-sign" if digits[:1] in "+-" else "bad-number", line)  # fmt: skip
        return label_key(digits)

    # ------------------------------------------------------------------ G65
    def _g65(self, text: str, line: int) -> Block:
        """``[/][Nn] G65 Lm P… A… B…``: one macro instruction (§3.41) as a ``("hust", …)`` statement."""
        head = _HEAD.match(text)
        assert head is not None  # both groups are optional
        skip = 0
        for mark in re.findall(r"/([0-9]?)", head.group(1)):
            skip |= 1 << (int(mark) if mark else 1)
        number = label_key(head.group(2)) if head.group(2) is not None else None
        rest = text[head.end():]
        g65 = _G65.match(rest)
        if g65 is None:
            raise self.error("G65 must be the only code of its block, after N (G65 Lm P#i A#j B#k)",
                             "bad-macro-command", line)  # fmt: skip
        words: dict[str, str] = {}
        for letter, value in _WORD.findall(rest[g65.end():]):
            if letter not in "LPAB":
                raise self.error(f"address {letter} in a G65 block: a macro instruction is "
                                 "G65 Lm P#i A#j B#k "
                                 "and nothing else (one operation per block)", "bad-macro-command", line)
            if letter in words:
                raise self.error(f"address {letter} appears twice in the G65 block", "duplicate-word", line)
            words[letter] = value
        if "L" not in words:
            raise self.error("G65 needs L (the operation number 1-99)", "bad-macro-command", line)
        if not _DIGITS.fullmatch(words["L"]) or not 1 <= int(words["L"]) <= 99:
            raise self.error(f"G65 L{words['L']}: the operation number is 1-99 (no sign, no point)",
                             "bad-macro-command", line)  # fmt: skip
        op = int(words["L"])
        p = self._p_operand(op, words.get("P"), line)
        a = self._operand(op, "A", words.get("A"), line)
        b = self._operand(op, "B", words.get("B"), line)
        return SpecialBlock(line, (), kind="stmt", stmt=("hust", op, p, a, b), skip=skip, number=number)

    def _p_operand(self, op: int, text: str | None, line: int) -> tuple | None:
        if text is None:
            return None
        if op in BRANCHES:
            if not _DIGITS.fullmatch(text):
                raise self.error(f"G65 L{op:02d} P{text}: a branch target is a block label, digits as "
                                 "written "
                                 "on the N (P0010 finds N0010)", "bad-macro-command", line)  # fmt: skip
            return ("label", label_key(text))
        if op == USER_ALARM:
            if not _DIGITS.fullmatch(text):
                raise self.error(f"G65 L99 P{text}: the alarm number is a plain number 1-49",
                                 "bad-macro-command", line)  # fmt: skip
            return ("const", int(text))
        match = _OPERAND.fullmatch(text)
        if match is None or match.group(1) or not match.group(2):
            raise self.error(f"G65 L{op:02d} P{text}: P names the result variable, #1-#9999 (P#10)",
                             "bad-macro-command", line)  # fmt: skip
        return ("var", self._variable(int(match.group(3)), line), 1)

    def _operand(self, op: int, letter: str, text: str | None, line: int) -> tuple | None:
        if text is None:
            return None
        match = _OPERAND.fullmatch(text)
        if match is None:
            raise self.error(f"G65 L{op:02d} {letter}{text}: an operand is an integer constant or a variable "
                             "#j (A-#2 negates)", "bad-macro-command", line)  # fmt: skip
        sign = -1 if match.group(1) == "-" else 1
        value = int(match.group(3))
        if match.group(2):
            return ("var", self._variable(value, line), sign)
        if value > MAX_INTEGER:
            raise self.error(f"G65 {letter}{text}: a constant is -9999999..9999999",
                             "value-out-of-range", line)
        return ("const", sign * value)

    def _variable(self, index: int, line: int) -> int:
        low, high = self.dialect.variables[0]
        if not low <= index <= high:
            raise self.error(f"variable #{index} does not exist (#{low}-#{high})", "bad-variable", line)
        return index
