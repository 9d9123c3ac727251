"""The Fanuc family's lexer and block reader: program text → :class:`~cnc_gym.gcode.program.Program` (the
default :attr:`Language.reader <cnc_gym.gcode.dialect.Language.reader>`).

Lexical rules (GSK 25i, §1.2.3; the dialect supplies the number formats):

* a line is a block; ``;`` also ends a block (EOB, §1.2); a line holding only ``%`` is a tape mark and a
  second one ends the tape (text after it is not read, and a note says so); text before a first ``%``
  that has program text after it is the leader section, skipped with a note;
* ``( … )`` is a comment; upper and lower case are the same; spaces and tabs are ignored;
* ``/`` or ``/n`` (n = 1..9, several as ``/1/3``) at the head of a block marks it for optional block
  skip; a ``/`` later in the block discards the rest of the block (§1.3.4);
* ``O`` program number and ``N`` sequence number at the head; then words: an address letter and a number,
  ``#i``, ``#[e]``, ``[e]`` or a signed form of these; or one macro assignment ``#i = e``;
* literal numbers are truncated to the least input increment (§2.5); without a decimal point they are
  in mm/inch/s (DPI = 1) or in least increments (DPI = 0), per the dialect.

Plain blocks (no ``#``, ``[``, ``/`` or keywords) go through one regex match and one ``findall``; the rest
through a small hand-written scanner that gives precise errors.

Macro statements (``IF[…]GOTOn``, ``IF[…]THEN #i=…``, ``GOTOn``, ``WHILE[…]DOm``, ``DOm``, ``ENDm``) become
blocks of kind ``"stmt"``; blocks that may call a macro (G65, G66, and the G/M/T codes the dialect's
:class:`~cnc_gym.gcode.dialect.MacroCalls` maps) are of kind ``"call"`` and keep their words in order
(argument specification II repeats I/J/K). A file may hold several programs, each starting at an ``O``
block; the first is the main program (:attr:`Program.units`).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.gcode.lang.fanuc.abbreviations import expand as expand_abbreviations
from cnc_gym.gcode.lang.fanuc.expressions import ExpressionParser
from cnc_gym.gcode.lang.fanuc.hints import SEMICOLON_COMMENT
from cnc_gym.gcode.program import Block, CommentedBlock, LiteralStore, Program, SpecialBlock, WordBlock
from cnc_gym.gcode.settings import DEFAULT_MAX_BLOCKS

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect
    from cnc_gym.gcode.settings import MacroCalls

_NUMBER = r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)"
# Hot-path patterns: deliberately loose ([0-9.]+); float() then rejects "1.2.3" and ".". The plain-block
# pattern is built per reader (_plain_block_pattern) so that it admits only words within the dialect's
# length limit (GSK alarm 13, docs/gsk25i_alarms.md E1): a longer literal falls to the scanner, which names it
# (``word-too-long``), and the hot path pays nothing for the check.
# A plain block's words as single strings (``"X12.5"``): a match without groups builds one string, where
# ``([A-Z])([-+]?[0-9.]+)`` built a tuple and two.
_PLAIN_WORD_TEXT = re.compile(r"[A-Z][-+]?[0-9.]+")


def _plain_block_pattern(max_word_length: int) -> re.Pattern:
    n = max_word_length - 1  # characters after the address letter
    return re.compile(rf"(?:[A-Z](?:[-+][0-9.]{{1,{n - 1}}}|[0-9.]{{1,{n}}}))+")
_BLANKS = " \t\r\f\v"
_NO_BLANKS = str.maketrans("", "", _BLANKS)
# Line breaks other than CR/LF that str.splitlines() would also split at (FS, GS, RS, NEL, U+2028/9): a
# block ends at a CR, LF or CRLF only, so line numbers are those of an editor.
_OTHER_BREAKS = re.compile("[\x1c-\x1e\x85\u2028\u2029]")
_LINE_BREAK = re.compile(r"\r\n|\r|\n")
_NUMBER_AT = re.compile(_NUMBER)
_CODE_WORD = re.compile(r"([GMT])([0-9.]+)")
#: Addresses of a call block that keep their own rules (the rest are arguments: any sign, decimal point).
_CALL_CONTROL = "GNOPL"
#: The alarm condition of a misplaced decimal point (a second point, a point without digits).
DECIMAL_POINT = "bad-number/decimal-point"
#: Most distinct plain words whose checked values the reader keeps at once (then it starts over).
_SEEN_WORDS = 1 << 14
#: About how many characters of the text are split into lines at once (a list of all the lines of a 1M-line
#: program would cost 80 bytes a line on top of the blocks).
_CHUNK_CHARS = 1 << 20


def text_lines(text: str):
    """The lines of ``text`` (a block ends at CR, LF or CRLF only), a chunk of about ``_CHUNK_CHARS``
    characters split at a time: the same lines as splitting the whole text, without a list of them all."""
    split = _LINE_BREAK.split if _OTHER_BREAKS.search(text) else str.splitlines
    size = len(text)
    start = 0
    while start < size:
        end = text.find("\n", start + _CHUNK_CHARS)
        end = size if end < 0 else end + 1  # a chunk ends after an LF, so no CRLF is cut in two
        lines = split(text[start:end])
        if split is not str.splitlines and end < size and lines and lines[-1] == "":
            lines.pop()  # re.split leaves an empty last piece after the chunk's final LF
        yield from lines
        start = end


class Reader:
    """Turns program text into a :class:`Program` for one dialect."""

    def __init__(self, dialect: Dialect, macro_calls: MacroCalls | None = None) -> None:
        self.dialect = dialect
        calls = macro_calls if macro_calls is not None else dialect.macro_calls
        # Codes that make a block a possible macro call (kind "call"): G65/G66 and the configured ones.
        roles = dialect.roles
        call_codes = {key / 10 for key in (roles.macro_call, roles.modal_call) if key is not None}  # G65, G66
        self._call_g = frozenset({*call_codes, *(float(g) for g in calls.g_macro)})
        self._call_m = frozenset(float(m) for m in (*calls.m_macro, *calls.m_sub))
        self._call_t = calls.t_sub is not None
        self._last_comment: str | None = None
        self._o_blocks: list[Block] = []
        # Plain words already checked in this file: word ("X12.5") → value.
        self._seen: dict[str, float] = {}
        # The numbers of this program's plain blocks.
        self._store = LiteralStore()
        #: Most blocks a program text may hold (the run's ``max_blocks``; ``interpret`` sets it).
        self.max_blocks = DEFAULT_MAX_BLOCKS
        rules = dialect.addresses
        self._rules = rules
        self._length_letters = frozenset(a for a, r in rules.items() if r.unit == "length")
        self._decimals = max(0, round(-_log10(dialect.least_increment_mm)))
        self._increment = dialect.least_increment_mm
        self._max_words = dialect.max_words_per_block
        self._max_word_length = dialect.max_word_length
        self._plain_pattern = _plain_block_pattern(dialect.max_word_length)
        # A longer block breaks the word-count or word-length limit: it goes to the scanner, which stops at
        # the first word too many (the regex would keep a stack entry per word of a 10 MB line).
        self._max_plain = dialect.max_words_per_block * dialect.max_word_length
        # Per letter: (low, high, point_allowed, is_length) for the hot loop.
        self._fast_rules = {a: (r.low, r.high, r.point_allowed, a in self._length_letters)
                            for a, r in rules.items()}  # fmt: skip
        # Macro arguments (G65 A1.0 D5.0 …, §3.7.6): every sign and a decimal point; lengths still follow
        # the increment and decimal-point mode.
        self._arg_rules = {a: (rule if a in _CALL_CONTROL else (-1e9, 1e9, True, rule[3]))
                           for a, rule in self._fast_rules.items()}  # fmt: skip
        # Codes that give their words their own number format (CodeSpec.address_rules: the step-over L of
        # the pocket cycles, G06.2's K and R): code number → the fast rules with those replaced. A block
        # naming one is read with them (a plain block pays one set test when it has a G code).
        self._override_rules: dict[float, dict] = {}
        for key, spec in dialect.gcodes.items():
            if spec.address_rules:
                merged = dict(self._fast_rules)
                for letter, rule in spec.address_rules.items():
                    merged[letter] = (rule.low, rule.high, rule.point_allowed, rule.unit == "length")
                self._override_rules[key / 10] = merged
        self._override_codes = frozenset(self._override_rules)
        # Letters a *modal* code gives its own format (the pocket cycles' L): a later block of the cycle
        # names no code, so a word that fails the address's own rule there is kept with the code's format
        # and checked when the block runs, against the code it then belongs to (``("deferred", …)`` node).
        self._deferred_letters: frozenset[str] = frozenset()
        lenient = dict(self._fast_rules)
        for spec in dialect.gcodes.values():
            if spec.address_rules and spec.group != 0:
                for letter, rule in spec.address_rules.items():
                    if rule.point_allowed and not self._fast_rules[letter][2]:
                        lenient[letter] = (rule.low, rule.high, True, rule.unit == "length")
                        self._deferred_letters |= {letter}
        # The R of a parameter-input block (G10 L50 mode) may exceed the R address's range: such a word
        # waits too, for transforms.parameter_block (any other block then raises the R rule's error).
        wide = dialect.parameter_input_r
        if wide is not None and "R" in lenient:
            low, high, point, is_length = lenient["R"]
            lenient["R"] = (min(low, wide.low), max(high, wide.high), point, is_length)
            self._deferred_letters |= {"R"}
        self._lenient_rules = lenient

    def too_many_blocks(self, count: int) -> ProgramError:
        """A program text of more blocks than a run may execute (``max_blocks``): refused while it is read,
        so that a huge file of short lines costs a bounded amount of memory."""
        return self.error(f"the program holds more than {self.max_blocks} blocks ({count} read so far), more "
                          "than a run may execute (max_blocks)", "too-many-blocks", 0)  # fmt: skip

    def _hinted(self, exc: ProgramError, raw: str) -> ProgramError:
        """The error with a hint when the line looks like another language's syntax (hints.py)."""
        hint = self.dialect.language.hint
        text = hint(raw) if hint is not None else None
        if text is None and ";" in raw and self._comment_after_semicolon(raw):
            text = SEMICOLON_COMMENT
        if text is not None and text not in exc.message:
            exc.message = f"{exc.message} ({text})"
            exc.args = (exc.message,)
        return exc

    def _comment_after_semicolon(self, raw: str) -> bool:
        """Whether the line reads up to a ';' and fails after it on words (``G01 X10 ; move``)."""
        o_blocks, comment = list(self._o_blocks), self._last_comment
        try:
            text = self._strip_comments(raw, 0).translate(_NO_BLANKS).upper()
        except ProgramError:
            return False
        if not text.isascii():
            return False  # the line's error is its illegal character (read_line), whatever follows a ';'
        try:
            for index, part in enumerate(text.split(";")):
                try:
                    if part:
                        self.read_block(part, 0)
                except ProgramError:
                    return index > 0 and re.search("[A-Z]{2}", part) is not None
            return False
        finally:
            self._o_blocks, self._last_comment = o_blocks, comment

    def error(self, message: str, code: str, line: int, column: int | None = None,
              alarm: str | int | None = None):  # fmt: skip
        err = self.dialect.error(message, code, column=column, alarm=alarm)
        err.line = line
        return err

    # ------------------------------------------------------------------ program
    def read(self, text: str, file: str = "<program>") -> Program:
        blocks: list[Block] = []
        self._o_blocks = []
        self._seen = {}
        program_number = None
        seen_percent = False
        colon = ":" in self.dialect.program_number_marks
        self._store = LiteralStore()
        # No line has a comment, ';' or a non-ASCII character: checked once for the whole text.
        simple = text.isascii() and "(" not in text and ")" not in text and ";" not in text
        leader = _leader_lines(text)
        notices = [_leader_notice(leader)] if leader else []
        numbered = enumerate(text_lines(text), start=1)
        for line_no, raw in numbered:
            if line_no <= leader:
                continue
            if not line_no & 0xFFFF and len(blocks) > self.max_blocks:
                raise self.too_many_blocks(len(blocks)).located(file, line_no)
            stripped = raw.strip(_BLANKS)
            if not stripped:
                continue
            if colon and stripped[0] == ":":
                stripped = "O" + stripped[1:]  # ``:1234`` is the program number O1234 (ISO code)
            if stripped.startswith("%"):
                if not _is_tape_mark(stripped):
                    error = self.error("'%' must stand alone on its line (tape start/end mark)",
                                       "bad-character", line_no)  # fmt: skip
                    raise self._hinted(error, raw).located(file, line_no)
                if seen_percent:
                    rest = [n for n, r in numbered if r.strip(_BLANKS)]  # the lines after it
                    if rest:
                        notices.append(_end_of_tape_notice(line_no, rest))
                    break  # second '%': end of tape
                seen_percent = True
                continue
            try:
                # Hot path inline: a plain line (no comment, ';', expression) is one regex match.
                if simple or (stripped.isascii() and "(" not in stripped and ")" not in stripped
                              and ";" not in stripped):  # fmt: skip
                    text_block = stripped.replace(" ", "").upper()
                    if "\t" in text_block:
                        text_block = text_block.translate(_NO_BLANKS)
                    if len(text_block) <= self._max_plain and self._plain_pattern.fullmatch(text_block):
                        blocks.append(self._plain_block(text_block, line_no))
                        continue
                blocks.extend(self.read_line(stripped, line_no))
            except ProgramError as exc:
                raise self._hinted(exc, raw).located(file, line_no) from None
        if len(blocks) > self.max_blocks:
            raise self.too_many_blocks(len(blocks)).located(file, blocks[self.max_blocks].line)
        self._seen = {}
        self._store = LiteralStore()  # the blocks keep the program's store; the reader lets go of it
        return self._indexed(Program(blocks, file=file, notices=notices), program_number)

    def _indexed(self, program: Program, program_number: int | None) -> Program:
        """``program`` with its sequence numbers indexed (for GOTO, M99 P) and its ``O`` programs found:
        their block ranges (``units``), the main program's extent and number."""
        blocks, file = program.blocks, program.file
        for index, block in enumerate(blocks):
            if block.number is not None:
                program.sequence_index.setdefault(block.number, []).append(index)
        # Program heads: the reader noted every O block (self._o_blocks); find their indices, stopping at
        # the last one (usually the first block).
        heads: list[tuple[int, int]] = []
        pending = {id(b): b for b in self._o_blocks}
        if pending:
            for index, block in enumerate(blocks):
                if id(block) in pending:
                    heads.append((index, int(float(block.words[0][1]))))
                    del pending[id(block)]
                    if not pending:
                        break
        self._o_blocks = []
        if heads:
            program_number = heads[0][1]
        program.program_number = program_number
        for k, (index, number) in enumerate(heads):
            end = heads[k + 1][0] if k + 1 < len(heads) else len(blocks)
            if number in program.units:
                err = self.error(f"program O{number:04d} is defined twice in this file", "duplicate-program",
                                 blocks[index].line)  # fmt: skip
                raise err.located(file, blocks[index].line)
            program.units[number] = (index, end)
        # The main program runs from the first block to the next O block after its own head.
        first_o = heads[0][0] if heads else len(blocks)
        later = [i for i, _ in heads if i > 0] if first_o == 0 else [first_o]
        program.main = (0, later[0] if later else len(blocks))
        return program

    def read_line(self, text: str, line: int) -> list[Block]:
        """Blocks of one source line (usually one; ``;`` separates several)."""
        self._last_comment = None
        if "(" in text or ")" in text:
            text = self._strip_comments(text, line)
        if not text.isascii():
            # Only ASCII letters and digits are program text (a comment may hold anything): '²' or '١'
            # would pass str.isdigit, and 'ı'.upper() is 'I'. Alarm 9 ILLEGAL CHARACTERS IN THE ADDRESS.
            column, char = next((i, c) for i, c in enumerate(text) if not c.isascii())
            raise self.error(f"illegal character {char!r} (U+{ord(char):04X})", "bad-character", line,
                             column + 1)  # fmt: skip
        # (str.translate, not re.sub, which keeps a list entry per match: 160 MB for a 6 MB line of words)
        text = text.translate(_NO_BLANKS).upper()
        if "%" in text:
            raise self.error("'%' must stand alone on its line (tape start/end mark)", "bad-character", line)
        if ";" in text:
            blocks = [b for part in text.split(";")
                      if part and (b := self.read_block(part, line)) is not None]  # fmt: skip
        elif not text:
            return []
        else:
            block = self.read_block(text, line)
            blocks = [block] if block is not None else []
        if self._last_comment is not None:
            # The message of #3000=n (…) / #3006=1 (…) (§3.7.3): the comment of an assignment line.
            for block in blocks:
                if block.assign is not None:
                    block.message = self._last_comment
            if self.dialect.comment_codes:  # a code that takes the comment as its argument (Haas G47)
                blocks = [CommentedBlock.of(b, self._last_comment) if self._takes_comment(b) else b
                          for b in blocks]  # fmt: skip
        return blocks

    def _takes_comment(self, block: Block) -> bool:
        codes = self.dialect.comment_codes
        return any(word[0] == "G" and isinstance(word[1], str | float)
                   and round(float(word[1]) * 10) in codes for word in block.words)  # fmt: skip

    def _strip_comments(self, text: str, line: int) -> str:
        out = []
        depth_start = -1
        for i, c in enumerate(text):
            if depth_start >= 0:
                if c == ")":
                    if self._last_comment is None:
                        self._last_comment = text[depth_start + 1 : i].strip()
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
        if len(text) <= self._max_plain and self._plain_pattern.fullmatch(text):
            return self._plain_block(text, line)
        return self._scan_block(text, line)

    def _plain_block(self, text: str, line: int) -> Block:
        """The hot path: letters and literal numbers only. Words are split and checked in one pass;
        ``Block.words`` keeps the ``(letter, digits)`` pairs for decimal-point checks. A word seen before in
        the file (G01, F1200, a repeated coordinate) takes its checked value from ``self._seen``."""
        words = _PLAIN_WORD_TEXT.findall(text)
        if len(words) > self._max_words:
            raise self.error(f"{len(words)} words in one block (at most {self._max_words})", "too-many-words",
                             line)  # fmt: skip
        values: dict[str, float] = {}
        gs = ms = None
        seen = self._seen
        for word in words:
            value = seen.get(word)
            letter = word[0]
            if value is None:
                value = self._plain_value((letter, word[1:]), text, line)
                if value is None:
                    return self._rescan(text, line)
                if len(seen) >= _SEEN_WORDS:
                    seen.clear()  # bounded: a program of all-different coordinates must not grow it per line
                seen[word] = value
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
                if letter in "IJK":
                    return self._rescan(text, line)  # argument specification II, if a call block
                raise self.error(f"address {letter} appears twice in the block", "duplicate-word", line)
            else:
                values[letter] = value
        if ((gs is not None and not self._call_g.isdisjoint(gs))
                or (ms is not None and not self._call_m.isdisjoint(ms)) or (self._call_t and "T" in values)):
            return self._rescan(text, line)  # a possible macro call: words kept in order
        if gs is not None and not self._override_codes.isdisjoint(gs):
            return self._rescan(text, line)  # a code with its own number formats (CodeSpec.address_rules)
        number = None
        has_o = False
        if "N" in values or "O" in values:
            has_o = "O" in values
            head = words[0][0]
            if "O" in values and head != "O":
                raise self.error("O must be at the head of the block", "misplaced-word", line)
            if "N" in values:
                if not (head == "N" or (head == "O" and words[1][0] == "N")):
                    raise self.error("N must be at the head of the block", "misplaced-word", line)
                number = int(values.pop("N"))
        block = self._store.add(line, text, gs, ms, values, number)
        if has_o:
            self._o_blocks.append(block)
        return block

    def _plain_value(self, pair: tuple[str, str], text: str, line: int) -> float | None:
        """A plain word's value after its address's rule; None: the block needs the scanner after all (macro
        arguments, a code's own number formats)."""
        letter, digits = pair
        rule = self._fast_rules.get(letter)
        if rule is None:
            raise self._unknown_address(letter, line)
        low, high, point_allowed, is_length = rule
        try:
            if digits[0] == "-" and low >= 0:
                self._literal(letter, digits, rule, line)  # raises bad-sign, also for "-0"
            if "." in digits:
                fraction = len(digits) - digits.index(".") - 1
                if not point_allowed or (is_length and fraction > self._decimals):
                    value = self._literal(letter, digits, rule, line)
                else:
                    value = float(digits)
            elif is_length and not self.dialect.integer_is_unit:
                value = self._literal(letter, digits, rule, line)
            else:
                value = float(digits)
            if not low <= value <= high:
                self._literal(letter, digits, rule, line)  # raises with the right code
        except ValueError:  # "1.2.3", ".": GSK/Fanuc alarm 7 ILLEGAL USE OF DECIMAL POINT
            raise self.error(f"bad number {letter}{digits}", "bad-number", line,
                             alarm=DECIMAL_POINT) from None  # fmt: skip
        except ProgramError:
            if (self._mentions_call(text) or self._code_rules(text) is not None
                    or letter in self._deferred_letters):  # fmt: skip
                # macro arguments have their own rules; so do the words of some codes (L2.5 in G110,
                # also in a later block of the modal cycle: checked when it runs)
                return None
            raise
        return value

    def _rescan(self, text: str, line: int) -> Block:
        """A plain line that needs the scanner after all (it is not empty, so it gives a block)."""
        block = self._scan_block(text, line)
        assert block is not None
        return block

    def _literal(self, letter: str, digits: str, rule: tuple, line: int) -> float:
        low, high, point_allowed, is_length = rule
        has_point = "." in digits
        if has_point and digits.count(".") > 1:
            # Before the truncation below, which would cut X1.23456.7 to X1.2345 (alarm 7 ILLEGAL USE OF
            # DECIMAL POINT).
            raise self.error(f"bad number {letter}{digits}: a second decimal point", "bad-number", line,
                             alarm=DECIMAL_POINT)  # fmt: skip
        if has_point:
            if not point_allowed:
                raise self.error(f"{letter}{digits}: no decimal point allowed in {letter}",
                                 "decimal-point-not-allowed", line)  # fmt: skip
            if is_length:
                dot = digits.index(".")
                if len(digits) - dot - 1 > self._decimals:
                    # Finer than the least input increment: truncated (§2.5), on the text, so
                    # 9.87654 becomes exactly 9.8765 (no binary rounding on the way).
                    digits = digits[: dot + 1 + self._decimals]
        value = float(digits)
        if is_length and not has_point and not self.dialect.integer_is_unit:
            value *= self._increment
        if digits[0] == "-" and low >= 0:  # "N-0", "S-0": a minus sign where the address has none
            raise self.error(f"{letter}{digits}: {letter} cannot be negative", "bad-sign", line)
        if not low <= value <= high:
            if value < 0 <= low:
                raise self.error(f"{letter}{digits}: {letter} cannot be negative", "bad-sign", line)
            alarm = self._rules[letter].alarm
            raise self.error(f"{letter}{digits}: out of range {low:g} to {high:g}", "value-out-of-range",
                             line, alarm=alarm)  # fmt: skip
        return value

    def _unknown_address(self, letter: str, line: int, column: int | None = None) -> ProgramError:
        """A letter that is no address of this controller (the H4C-M has no E: ``E1``, ``X1E3``)."""
        return self.error(f"{letter} is not an address of this controller", "unknown-address", line, column)

    def _head(self, words: list, line: int) -> tuple[list, int | None]:
        """Take O (program number) and N (sequence number) off the head of a block."""
        number = None
        rest = list(words)
        if rest and rest[0][0] == "O":
            if not isinstance(rest[0][1], float):
                raise self.error("O cannot be a variable (GSK 25i §3.7.2)", "variable-not-allowed", line)
            rest = rest[1:]
            if rest and rest[0][0] == "O":
                raise self.error("two program numbers O in one block", "duplicate-word", line)
        if rest and rest[0][0] == "N":
            if not isinstance(rest[0][1], float):
                raise self.error("N cannot be a variable (GSK 25i §3.7.2)", "variable-not-allowed", line)
            number = int(rest[0][1])
            rest = rest[1:]
        for letter, _, _ in rest:
            if letter in "ON":
                raise self.error(f"{letter} must be at the head of the block", "misplaced-word", line)
        # O is kept as a word (recorded as the program number); N is dropped (kept in Block.number).
        head = [w for w in words[:1] if w[0] == "O"]
        return head + rest, number

    def _code_rules(self, text: str) -> dict | None:
        """The fast rules of the codes in ``text`` that have their own number formats, or None."""
        if not self._override_codes:
            return None
        rules = None
        for letter, digits in _CODE_WORD.findall(text):
            if letter != "G":
                continue
            try:
                number = float(digits)
            except ValueError:
                continue
            if number in self._override_codes:
                if rules is None:
                    rules = dict(self._override_rules[number])
                else:  # two such codes in one block: the later one's formats for its own letters
                    rules.update({a: r for a, r in self._override_rules[number].items()
                                  if r != self._fast_rules[a]})  # fmt: skip
        return rules

    def _scan_block(self, text: str, line: int) -> Block | None:
        """Everything that is not plain: block skip, expressions, variables, assignments, keywords, calls."""
        if self.dialect.macro_abbreviations:
            text = expand_abbreviations(text, self.dialect.macro_abbreviations)  # WH[ … is WHILE[ …
        code_rules = self._code_rules(text)
        if not self._mentions_call(text):
            try:
                return self._scan(text, line, False, code_rules)
            except ProgramError:
                if code_rules is not None or not self._deferred_letters:
                    raise
                return self._scan(text, line, False, self._lenient_rules, defer=True)
        try:
            strict: Block | ProgramError | None = self._scan(text, line, False, code_rules)
        except ProgramError as exc:
            strict = exc
        block = self._scan(text, line, True)
        if block is None or block.kind != "call":
            if isinstance(strict, ProgramError):
                raise strict
            return strict
        block.stmt = ("strict", strict)
        return block

    def _mentions_call(self, text: str) -> bool:
        for letter, digits in _CODE_WORD.findall(text):
            try:
                value = float(digits)
            except ValueError:
                continue
            if (letter == "G" and value in self._call_g) or (letter == "M" and value in self._call_m):
                return True
            if letter == "T" and self._call_t:
                return True
        return False

    def _scan(self, text: str, line: int, relaxed: bool, code_rules: dict | None = None, *,
              defer: bool = False) -> Block | None:  # fmt: skip
        pos = 0
        skip = 0
        # Optional block skip: /, /n, /1/3 at the head (§1.3.4).
        while pos < len(text) and text[pos] == "/":
            pos += 1
            if pos < len(text) and "0" <= text[pos] <= "9":
                n = int(text[pos])
                if n == 0:
                    raise self.error("block skip switch must be 1 to 9", "bad-block-skip", line, pos + 1)
                pos += 1
            elif pos < len(text) and text[pos] == "#":
                raise self.error("a variable cannot follow '/' (GSK 25i §3.7.2)", "variable-not-allowed",
                                 line,
                                 pos + 1)  # fmt: skip
            elif pos < len(text) and text[pos] == "/":
                raise self.error("'//n' is not a block skip; write /1/n (GSK 25i §1.3.4)", "bad-block-skip",
                                 line,
                                 pos + 1)  # fmt: skip
            else:
                n = 1
            skip |= 1 << n
        if pos >= len(text):
            return WordBlock(line, (), skip=skip) if skip else None
        words: list = []
        has_expr = False
        assign = None
        stmt = None
        rules = self._arg_rules if relaxed else (code_rules or self._fast_rules)
        while pos < len(text):
            c = text[pos]
            if c == "/":
                break  # a slash inside the block: the rest of the block is ignored (§1.3.4)
            if c == "#":
                if any(w[0] not in "ON" for w in words):
                    raise self.error("a macro assignment must be alone in its block", "bad-expression", line,
                                     pos + 1)  # fmt: skip
                assign, pos = self._assignment(text, pos, line)
                break
            if c == ",":  # ,L chamfer / ,R corner rounding (transforms.py): the word is ",L" / ",R"
                letter = text[pos:pos + 2]
                if letter not in rules:
                    raise self.error(f"'{letter}' is not a chamfer/corner word of this controller",
                                     "bad-character", line, pos + 1)  # fmt: skip
                value, text_digits, pos = self._value(letter, text, pos + 2, line, rules[letter])
                has_expr = has_expr or text_digits is None
                words.append((letter, value, text_digits))
                continue
            if not ("A" <= c <= "Z"):
                if _is_digit(c) or c == ".":  # alarm 4 ADDRESS NOT FOUND
                    raise self.error(f"a number without an address at {text[pos:pos + 8]!r}",
                                     "missing-address", line, pos + 1)  # fmt: skip
                if c in "+-":  # alarm 6 ILLEGAL USE OF NEGATIVE SIGN
                    raise self.error(f"sign {c!r} not at the start of a number", "bad-sign", line, pos + 1)
                raise self.error(f"illegal character {c!r}", "bad-character", line, pos + 1)
            keyword = self._keyword(text, pos)
            if keyword:
                if any(w[0] not in "ON" for w in words):
                    raise self.error(f"macro statement {keyword} must be alone in its block (after O/N)",
                                     "bad-macro-command", line, pos + 1)  # fmt: skip
                stmt, pos = self._statement(keyword, text, pos, line)
                break
            letter = c
            rule = rules.get(letter)
            if rule is None:
                raise self._unknown_address(letter, line, pos + 1)
            pos += 1
            value, text_digits, pos = self._value(letter, text, pos, line, rule)
            if text_digits is None:
                has_expr = True
            words.append((letter, value, text_digits))
            if len(words) > self._max_words:  # stop here: no need to read a million more words
                raise self.error(f"more than {self._max_words} words in one block", "too-many-words", line)
        if defer:  # words that fail their address's own rule wait for the code they belong to
            for n, (letter, value, digits) in enumerate(words):
                if digits is not None and letter in self._deferred_letters:
                    try:
                        self._literal(letter, digits, self._fast_rules[letter], line)
                    except ProgramError as exc:
                        words[n] = (letter, ("deferred", value, digits, exc), None)
                        has_expr = True
        number = None
        if words and words[0][0] in "ON":
            words, number = self._head(words, line)
        elif any(w[0] in "ON" for w in words):
            self._head(words, line)  # raises misplaced-word
        if not words and assign is None and stmt is None and not skip and number is None:
            return None
        if words and words[0][0] == "O":
            block = self._finish_scan(line, words, skip, has_expr, assign, number, stmt, relaxed)
            if block is not None:
                self._o_blocks.append(block)
            return block
        return self._finish_scan(line, words, skip, has_expr, assign, number, stmt, relaxed)

    def _finish_scan(self, line: int, words: list, skip: int, has_expr: bool, assign: tuple | None,
                     number: int | None, stmt: tuple | None, relaxed: bool) -> Block | None:  # fmt: skip
        if stmt is not None:
            return SpecialBlock(line, tuple(words), skip=skip, number=number, kind="stmt", stmt=stmt)
        if assign is not None:
            return SpecialBlock(line, tuple(words), skip=skip, assign=assign, number=number, kind="assign")
        if relaxed and self._is_call(words):
            # Words stay in order for the arguments; split at run time if the block turns out ordinary.
            return SpecialBlock(line, tuple(words), skip=skip, number=number, kind="call")
        return WordBlock(line, tuple(words), skip=skip, has_expr=has_expr, assign=assign, number=number)

    def _is_call(self, words: list) -> bool:
        for letter, value, digits in words:
            if digits is None:
                continue  # a code from a variable is an ordinary code (docs/gcode.md)
            if (letter == "G" and value in self._call_g) or (letter == "M" and value in self._call_m):
                return True
            if letter == "T" and self._call_t:
                return True
        return False

    # ------------------------------------------------------------------ macro statements
    def _statement(self, keyword: str, text: str, pos: int, line: int) -> tuple[tuple, int]:
        """``IF[c]GOTOn``, ``IF[c]THEN #i=e``, ``GOTOn``, ``WHILE[c]DOm``, ``DOm``, ``ENDm``
        (§3.7.4-§3.7.5)."""
        parser = ExpressionParser(text, pos + len(keyword), self.dialect)
        if keyword == "IF":
            if parser._peek() != "[":
                raise self.error("IF needs a condition in brackets: IF[<condition>]GOTOn",
                                 "bad-macro-command", line, parser.pos + 1)  # fmt: skip
            condition = parser.condition()
            word = parser._word()
            if word.startswith("GOTO"):
                parser.pos += 4
                stmt: tuple = ("if_goto", condition, self._goto_target(parser, line))
            elif word.startswith("THEN"):
                parser.pos += 4
                if parser._peek() != "#":
                    raise self.error("THEN must be followed by an assignment #i=<expression>",
                                     "bad-macro-command", line, parser.pos + 1)  # fmt: skip
                assign, end = self._assignment(text, parser.pos, line)
                return ("if_then", condition, assign), end
            else:
                raise self.error("IF[<condition>] must be followed by GOTOn or THEN #i=<expression>",
                                 "bad-macro-command", line, parser.pos + 1)  # fmt: skip
        elif keyword == "GOTO":
            stmt = ("goto", self._goto_target(parser, line))
        elif keyword == "WHILE":
            if parser._peek() != "[":
                raise self.error("WHILE needs a condition in brackets: WHILE[<condition>]DOm",
                                 "bad-macro-command", line, parser.pos + 1)  # fmt: skip
            condition = parser.condition()
            if not parser._word().startswith("DO"):
                raise self.error("WHILE[<condition>] must be followed by DOm", "bad-macro-command", line,
                                 parser.pos + 1)  # fmt: skip
            parser.pos += 2
            stmt = ("while", condition, self._loop_number(parser, "DO", line))
        elif keyword == "DO":
            stmt = ("while", None, self._loop_number(parser, "DO", line))
        elif keyword == "END":
            stmt = ("end", self._loop_number(parser, "END", line))
        else:
            raise self.error(f"{keyword} without IF", "bad-macro-command", line, pos + 1)
        if parser.pos < len(text) and text[parser.pos] != "/":
            raise self.error(f"unexpected {text[parser.pos:]!r} after {keyword}", "bad-macro-command", line,
                             parser.pos + 1)  # fmt: skip
        return stmt, len(text)

    def _goto_target(self, parser: ExpressionParser, line: int) -> tuple:
        c = parser._peek()
        if _is_digit(c):
            start = parser.pos
            while _is_digit(parser._peek()):
                parser.pos += 1
            if parser._peek() == ".":
                raise self.error("a GOTO sequence number is an integer", "bad-number", line, parser.pos + 1)
            return ("num", parser.constant(parser.text[start : parser.pos]))
        if c == "#":
            return parser.variable()
        if c == "[":
            return parser.bracketed()
        raise self.error("GOTO needs a sequence number: GOTOn, GOTO#i or GOTO[<expression>]",
                         "missing-operand", line, parser.pos + 1)  # fmt: skip

    def _loop_number(self, parser: ExpressionParser, word: str, line: int) -> int:
        start = parser.pos
        while _is_digit(parser._peek()):
            parser.pos += 1
        digits = parser.text[start : parser.pos]
        if not digits:
            raise self.error(f"{word} needs its identifier 1, 2 or 3 ({word}1)", "do-end", line, start + 1)
        m = int(parser.constant(digits))
        if not 1 <= m <= 3:
            raise self.error(f"{word}{m}: the loop identifier is 1, 2 or 3 (GSK 25i §3.7.5)", "do-end", line,
                             start + 1, alarm="do-end/loop-number")  # fmt: skip
        return m

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
            if end < len(text) and (text[end] == "." or _is_digit(text[end])):
                bad = _NUMBER_AT.match(text, end)
                tail = text[end : (bad.end() if bad else end + 1)]
                # a second point (GSK/Fanuc alarm 7 ILLEGAL USE OF DECIMAL POINT), else bad-number's
                raise self.error(f"bad number {letter}{match.group()}{tail}", "bad-number", line, start,
                                 alarm=DECIMAL_POINT if "." in tail else None)  # fmt: skip
            digits = match.group()
            if len(digits) >= self._max_word_length:  # the address letter makes it one character longer
                raise self.error(f"{letter}{digits}: a word is at most {self._max_word_length} characters "
                                 f"({len(digits) + 1})", "word-too-long", line, start)  # fmt: skip
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
            raise self.error(f"{letter}{sign}: sign without a number", "bad-sign", line, start)  # alarm 6
        if c == "." or _is_digit(c):
            raise self.error(f"bad number after {letter}", "bad-number", line, start,
                             alarm=DECIMAL_POINT if c == "." else None)  # fmt: skip
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


def _leader_notice(leader: int) -> tuple[int, str, str, str]:
    """The note that lines 1..``leader`` before the tape start were not read."""
    lines = (f"lines 1-{leader} before the tape start '%' (line {leader + 1}) are" if leader > 1
             else "line 1 before the tape start '%' (line 2) is")  # fmt: skip
    return (1, "note", f"{lines} the leader section, not read (the control skips what comes before the first "
            "'%' of a file)", "leader-skipped")  # fmt: skip


def _end_of_tape_notice(line: int, rest: list[int]) -> tuple[int, str, str, str]:
    """The note that the lines ``rest`` after the end-of-tape ``%`` of ``line`` were not read."""
    which = f"lines {rest[0]}-{rest[-1]} are" if len(rest) > 1 else f"line {rest[0]} is"
    return (line, "note", f"{which.rsplit(' ', 1)[0]} after the end-of-tape '%' (line {line}) "
            f"{which.rsplit(' ', 1)[1]} not read", "after-end-of-tape")


def _is_tape_mark(stripped: str) -> bool:
    """A ``%`` line: the tape start or end mark, alone or with an end of block or a comment after it."""
    rest = stripped.strip("%").strip(_BLANKS + ";")
    return stripped.startswith("%") and (not rest or stripped[1:].lstrip().startswith("("))


def _leader_lines(text: str) -> int:
    """How many lines come before the tape start: the first ``%`` line when text before it is not blank and
    program text follows it (a ``%`` with nothing after it is the end of the tape); else 0."""
    if "%" not in text:
        return 0
    first_text = None
    leader = None
    for index, raw in enumerate(text_lines(text)):
        stripped = raw.strip(_BLANKS)
        if not stripped:
            continue
        if leader is not None:  # text before the first mark: is there program text after it?
            if not stripped.startswith("%"):
                return leader
            continue
        if stripped.startswith("%") and _is_tape_mark(stripped):
            if first_text is None:
                return 0  # the file starts with its tape start
            leader = index
            continue
        if first_text is None:
            first_text = index
    return 0


def _is_digit(c: str) -> bool:
    """An ASCII digit (str.isdigit also takes '²' and '١', which are not program text)."""
    return len(c) == 1 and "0" <= c <= "9"


def _log10(x: float) -> float:
    import math

    return math.log10(x)
