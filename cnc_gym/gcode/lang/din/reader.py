"""The DIN 66025 family's lexer and block reader: program text → :class:`DinProgram` (AMK AZ-MC1
programming manual §2 "Program structure", §7 "Subroutines", §8 "Parameters", §9 "Program control").

Lexical rules:

* the input is ASCII text; a line is a block (CR, LF or CRLF end it); upper and lower case are the same;
* ``( … )`` is a comment; comments nest (``(a (b) c)``) and the end of the line ends an unclosed one
  (§2.3.2), so round brackets never group arithmetic;
* ``/`` at the head of a block marks it for block skip (one level); then an optional block number
  ``N<int>`` (not a jump target: there is no GOTO; repeated and unordered numbers are fine);
* ``%<n>`` (blanks allowed: ``% 100``) starts the main program, ``%L<n>`` a local subroutine; local
  subroutines stand before the main program of their file; a file without ``%`` is one main program (the
  controller knows a program by its file name, §2.2);
* a word is an address and a value, blanks allowed between them: a number, or an expression
  (``X 100.0``, ``Z SIN [30]``, ``XR1``, ``T[TLOC[R1]]``, ``TTLOC[R1]``); the value ends where the grammar
  ends (``expressions.py``); ``LL`` is a two-letter address (a local call);
* ``R<n> = e`` (or ``R[e] = e``, ``P<n> = e``) assigns a parameter; assignments run before the block's
  other words (``R1 = R1 - 1.5 Y R1`` moves to the new R1); an assignment glued to a value
  (``X50R1=7``) is an error — a blank must separate them (§2.6);
* ``$<KEYWORD>`` is a control block, alone in its block but for N and ``/`` (§9); blanks between ``$``
  and the keyword are an error;
* numbers have no implied decimal point (``X1`` is 1 mm); lengths are rounded to the 0.1 µm resolution
  and limited to ±214 000 mm (§2.7), by the dialect's address rules.

Plain blocks (literal words only) go through one regex match and one ``findall``; the rest through the
scanner, which gives precise errors. The control blocks of each program unit are compiled to jump tables
once, as the file is read (``control.py``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.gcode.codes import round_to
from cnc_gym.gcode.lang.din import control
from cnc_gym.gcode.lang.din.expressions import ExpressionSyntaxError, Parser, literal_number
from cnc_gym.gcode.program import Block, Program, SpecialBlock, WordBlock, literal_block, split_words
from cnc_gym.gcode.settings import DEFAULT_MAX_BLOCKS

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import AddressRule
    from cnc_gym.gcode.dialect import Dialect
    from cnc_gym.gcode.settings import MacroCalls

_NUMBER = r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)"
#: A block of literal words only, none of them a parameter or call address (R, P, L): the hot path.
_PLAIN_BLOCK = re.compile(rf"(?:[ \t]*[A-KMNOQS-Z][ \t]*{_NUMBER})*[ \t]*")
#: The words of a line that matched _PLAIN_BLOCK, as text (its numbers are well formed: the loose [0-9.]+
#: splits them the same way, and faster).
_PLAIN_WORD = re.compile(r"[A-Z][ \t]*[-+]?[0-9.]+")
_BLANKS = " \t"
_HEADER = re.compile(r"%[ \t]*(L?)[ \t]*([0-9]*)[ \t]*")
#: Most digits of a program number (``%nnnnnnnn``, §2.2).
PROGRAM_DIGITS = 8
#: Addresses that take a literal whole number only (codes and the block number).
_LITERAL_ONLY = "GMN"
_LENGTH = "length"
#: Errors that get a hint when the line looks like another language.
_HINTED = frozenset({"syntax", "unknown-address"})
_WHOLE = "whole"
#: Decimal places a length literal keeps (0.1 µm in mm, §2.7); longer ones are rounded.
_DECIMALS = 4


def strip_comment(line: str) -> str:
    """The line without its comments: ``( … )`` nest, and the end of the line closes them (§2.3.2)."""
    if "(" not in line:
        if ")" in line:
            raise ProgramError("')' without '(' (comments are ( … ))", code="syntax",
                               column=line.index(")") + 1)  # fmt: skip
        return line
    out = []
    depth = 0
    for column, char in enumerate(line, 1):
        if char == "(":
            depth += 1
        elif char == ")":
            if depth == 0:
                raise ProgramError("')' without '(' (comments are ( … ))", code="syntax", column=column)
            depth -= 1
        elif depth == 0:
            out.append(char)
    return "".join(out)


@dataclass
class DinProgram(Program):
    """A read DIN file: its blocks, the main program's extent (``main``) and number
    (``program_number``, None without a ``%`` header), and its local subroutines ``%L<n>``
    (``local_units``: n → (first block, end))."""

    local_units: dict[int, tuple[int, int]] = field(default_factory=dict)
    #: Whether the file holds a ``%n`` main-program header.
    has_main_header: bool = False


class DinReader:
    """Reads DIN program text for one dialect (:attr:`Language.reader`).

    A dialect subclass names its own data functions (read from the parameter store at run time, e.g.
    the tool table's ``TLOC[n]``) and procedures (write commands alone in a block, ``TRESDEL[n]``).
    """

    #: Functions the parameter store answers at run time (``ParameterStore.data_function``).
    DATA_FUNCTIONS: frozenset[str] = frozenset()
    #: Write commands that stand alone in a block (``ParameterStore.procedure``).
    PROCEDURES: frozenset[str] = frozenset()

    def __init__(self, dialect: Dialect, macro_calls: MacroCalls | None = None) -> None:
        self.dialect = dialect
        self._rules: dict[str, AddressRule] = dict(dialect.addresses)
        self._letters = frozenset(self._rules) | frozenset(dialect.axes) | frozenset(dialect.other_axes)
        self._functions = dict(dialect.functions)
        self._increment = dialect.least_increment_mm
        # Each address's (number kind, low, high), for the hot path (N is the block number, not a word).
        self._kinds = {letter: (self._number_kind(letter, rule), rule.low, rule.high)
                       for letter, rule in self._rules.items() if letter != "N"}  # fmt: skip
        # Literal words already read in this file: text → (letter, value, digits); block numbers: text → n.
        self._seen: dict[str, tuple[str, float, str]] = {}
        self._numbers: dict[str, int] = {}
        #: Most blocks a program text may hold (the run's ``max_blocks``; ``interpret`` sets it).
        self.max_blocks = DEFAULT_MAX_BLOCKS

    # ------------------------------------------------------------------ the file
    def read(self, text: str, file: str = "<program>") -> DinProgram:
        blocks: list[Block] = []
        local_units: dict[int, tuple[int, int]] = {}
        headers: list[tuple[str, int | None, int, int]] = []  # (kind, number, first block, line)
        plain_block = _PLAIN_BLOCK.fullmatch
        plain = self._plain
        # Whole-text passes where they are cheaper than per-line ones: the character set, the line breaks
        # (CR, LF, CRLF), upper case, and whether any line has a comment at all.
        ascii_text = text.isascii()
        lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
        upper = text.upper().replace("\r\n", "\n").replace("\r", "\n").split("\n") if ascii_text else lines
        comments = "(" in text or ")" in text
        self._seen, self._numbers = {}, {}
        for lineno, raw in enumerate(lines, 1):
            if not lineno & 0xFFFF and len(blocks) > self.max_blocks:
                raise self._too_many_blocks(len(blocks), file, lineno)
            try:
                if not ascii_text and not raw.isascii():
                    bad = next(c for c in raw if not c.isascii())
                    raise ProgramError(f"character {bad!r} is not in the controller's ASCII character set",
                                       code="bad-character", column=raw.index(bad) + 1)  # fmt: skip
                line = upper[lineno - 1] if ascii_text else raw.upper()
                if comments and ("(" in line or ")" in line):
                    line = strip_comment(line)
                stripped = line.lstrip()
                if not stripped:
                    continue
                head = stripped[0]
                if head == "%":
                    self._unit_header(stripped.rstrip(), headers, len(blocks), lineno)
                    continue
                if head != "/" and plain_block(stripped):
                    block = plain(stripped, lineno, 0)
                else:
                    block = self.block(stripped, lineno)
                if block is not None:
                    blocks.append(block)
            except ProgramError as err:
                raise self._hinted(err, raw).located(file, lineno) from None
        self._seen, self._numbers = {}, {}
        if len(blocks) > self.max_blocks:
            raise self._too_many_blocks(len(blocks), file, blocks[self.max_blocks].line)
        main_start = next((start for kind, _, start, _ in headers if kind == "main"), None)
        program_number = next((number for kind, number, _, _ in headers if kind == "main"), None)
        # Units: each %L runs to the next header; the main program from its header (or the file's start)
        # to the end.
        bounds = [start for _, _, start, _ in headers] + [len(blocks)]
        for i, (kind, number, start, _line) in enumerate(headers):
            if kind == "L":
                local_units[number] = (start, bounds[i + 1])  # type: ignore[index]
        if main_start is None:
            if headers:
                last_line = headers[-1][3]
                raise ProgramError("the file holds local subroutines but no main program (%n after them)",
                                   code="program-structure", file=file, line=last_line)  # fmt: skip
            main = (0, len(blocks))
        else:
            main = (main_start, len(blocks))
        program = DinProgram(blocks, file, program_number, {}, {}, main, local_units=local_units,
                             has_main_header=main_start is not None)  # fmt: skip
        for start, end in (main, *local_units.values()):
            control.compile_unit(program, start, end)
        return program

    def _too_many_blocks(self, count: int, file: str, line: int) -> ProgramError:
        """A program text of more blocks than a run may execute (``max_blocks``), refused while it is read."""
        return ProgramError(f"the program holds more than {self.max_blocks} blocks ({count} read so far), "
                            "more than a run may execute (max_blocks)", code="too-many-blocks", file=file,
                            line=line)  # fmt: skip

    def _hinted(self, err: ProgramError, raw: str) -> ProgramError:
        """A syntax error with a hint when the line looks like another language's (``hints.py``)."""
        hint = self.dialect.language.hint
        text = hint(raw) if hint is not None and err.code in _HINTED else None
        if text is not None and text not in err.message:
            err.message = f"{err.message} ({text})"
            err.args = (err.message,)
        return err

    def _unit_header(self, text: str, headers: list, first_block: int, lineno: int) -> None:
        """A ``%n`` or ``%L<n>`` line: local subroutines first, then at most one main program (§7.1)."""
        kind, number = self._header(text)
        if first_block and not headers:
            raise ProgramError("blocks before the first % header: a file is local subroutines (%L<n>) and "
                               "then its main program (%<n>)", code="program-structure")  # fmt: skip
        if any(k == "main" for k, _, _, _ in headers):
            if kind == "L":
                raise ProgramError(f"%L{number}: local subroutines stand before the main program of their "
                                   "file (AMK AZ-MC1 programming manual §7.1)", code="program-structure")
            raise ProgramError("a second main program header: one file holds one main program (local "
                               "subroutines %L come before it)", code="program-structure")  # fmt: skip
        if kind == "L" and any(n == number for _, n, _, _ in headers):
            raise ProgramError(f"%L{number} is defined twice in this file", code="program-structure")
        headers.append((kind, number, first_block, lineno))

    def _header(self, text: str) -> tuple[str, int | None]:
        match = _HEADER.fullmatch(text)
        if match is None:
            raise ProgramError(f"bad program header {text!r}: %<number> (main program) or %L<number> (local "
                               "subroutine), then at most a comment", code="syntax")  # fmt: skip
        local, digits = match.groups()
        if len(digits) > PROGRAM_DIGITS:
            raise ProgramError(f"program number {digits}: at most {PROGRAM_DIGITS} digits", code="syntax")
        if local and not digits:
            raise ProgramError("%L needs the subroutine's number (%L007)", code="syntax")
        return ("L" if local else "main"), (int(digits) if digits else None)

    # ------------------------------------------------------------------ one block
    def block(self, line: str, lineno: int) -> Block | None:
        """One block from a comment-free, upper-case line (None: nothing but a skip mark or N)."""
        skip = 0
        body = line
        stripped = body.lstrip()
        if stripped[:1] == "/":
            skip = 1 << 1  # block-skip switch 1 (the panel's "Skip block"; one level)
            body = stripped[1:]
        if _PLAIN_BLOCK.fullmatch(body):
            return self._plain(body, lineno, skip)
        return self._scan(body, lineno, skip)

    def _plain(self, body: str, lineno: int, skip: int) -> Block | None:
        """A block of literal words (the hot path; ``body`` matched ``_PLAIN_BLOCK``): each checked by its
        address's precomputed rule, and split for the core (``gs``, ``ms``, ``values``) in the same pass.
        A word seen before in the file (G01, F1200, a repeated coordinate, a block number) is taken checked
        from ``self._seen`` (``self._numbers``)."""
        found = _PLAIN_WORD.findall(body)
        number = None
        if found and found[0][0] == "N":  # the block number, off the words (one N, at the head)
            head = found.pop(0)
            number = self._numbers.get(head)
            if number is None:
                number = self._numbers[head] = self._block_number(head[1:].lstrip(_BLANKS))
        words: list[tuple] = []
        values: dict[str, float] = {}
        gs = ms = None
        seen = self._seen
        for text in found:
            word = seen.get(text)
            if word is None:
                word = seen[text] = self._plain_word(text)
            words.append(word)
            letter, value, _ = word
            if letter == "G":
                gs = [value] if gs is None else [*gs, value]
            elif letter == "M":
                ms = [value] if ms is None else [*ms, value]
            elif letter in values:
                raise ProgramError(f"address {letter} appears twice in the block", code="duplicate-word")
            else:
                values[letter] = value
        if not words:
            return None
        return literal_block(lineno, tuple(words), gs, ms, values, number, skip)

    def _plain_word(self, text: str) -> tuple[str, float, str]:
        """A literal word ``(letter, value, digits)`` from its text, after its address's rule."""
        letter = text[0]
        digits = text[1:].lstrip(_BLANKS)
        kind = self._kinds.get(letter)
        if kind is None:
            if letter == "N":
                raise ProgramError("N (the block number) begins the block, once", code="syntax")
            raise self._unknown_address(letter)
        unit, low, high = kind
        value = float(digits)
        if unit is _LENGTH:
            point = digits.find(".")
            if point >= 0 and len(digits) - point > _DECIMALS + 1:
                value = round_to(value, self._increment)  # more places than the resolution keeps
        elif unit is _WHOLE and "." in digits:
            value = self._literal(letter, digits)  # raises: a whole number is expected
        if not low <= value <= high:
            value = self._literal(letter, digits)  # raises the range error
        return letter, value, digits

    def _make_block(self, lineno: int, words: list, skip: int, number: int | None, *,
                    has_expr: bool) -> Block:  # fmt: skip
        if not has_expr:
            split_words(words)  # a repeated address is an error at read time
        return WordBlock(lineno, tuple(words), skip=skip, has_expr=has_expr, number=number)

    @staticmethod
    def _number_kind(letter: str, rule: AddressRule) -> str:
        if rule.unit == "length":
            return _LENGTH
        return _WHOLE if rule.unit == "integer" or letter in _LITERAL_ONLY else "plain"

    def _block_number(self, digits: str) -> int:
        if not digits.isdigit() or len(digits) > 9:
            raise ProgramError(f"N{digits}: a block number is a whole number", code="syntax")
        return int(digits)

    def _literal(self, letter: str, digits: str) -> float:
        """A literal word's value after the address's rules (whole numbers, range, resolution)."""
        rule = self._rules.get(letter)
        if rule is None:
            raise self._unknown_address(letter)
        value = float(digits)
        if rule.unit == "integer" or letter in _LITERAL_ONLY:
            if "." in digits:
                raise ProgramError(f"{letter}{digits}: {letter} takes a whole number", code="syntax")
        elif rule.unit == "length":
            value = round_to(value, self._increment)
        if not rule.low <= value <= rule.high:
            raise ProgramError(f"{letter}{digits} is out of range {rule.low:g} to {rule.high:g}",
                               code="value-out-of-range", alarm=rule.alarm)  # fmt: skip
        return value

    def _unknown_address(self, letter: str) -> ProgramError:
        return ProgramError(f"unknown address {letter}", code="unknown-address")

    # ------------------------------------------------------------------ the scanner
    def _scan(self, body: str, lineno: int, skip: int) -> Block | None:
        parser = Parser(body, self._functions, self.DATA_FUNCTIONS)
        number = None
        parser.skip_blanks()
        if parser.peek() == "N":
            parser.pos += 1
            parser.skip_blanks()
            start = parser.pos
            if parser.number() is None:
                raise parser.error("N needs a block number")
            number = self._block_number(body[start:parser.pos])
            parser.skip_blanks()
        if parser.peek() == "$":
            return self._statement(parser, lineno, skip, number)
        words: list[tuple] = []
        assigns: list[tuple] = []
        call: tuple | None = None
        procedure: tuple | None = None
        has_expr = False
        while not parser.at_end():
            start = parser.pos
            char = parser.peek()
            if char == "$":
                raise parser.error("a control block ($…) stands alone in its block (only N and / before it)")
            if not char.isalpha():
                raise parser.error(f"unexpected {char!r}: a word begins with an address letter")
            name = body[start:start + 2]
            ident = parser.name()
            parser.pos = start
            if ident in self.PROCEDURES:
                parser.pos = start + len(ident)
                parser.expect("[", f"after {ident}")
                argument = parser.expression(unary=True)
                parser.expect("]", f"to close {ident}[")
                procedure = (ident, argument)
                continue
            if char in "RP" and self._is_assignment(parser, start):
                if start > 0 and body[start - 1] not in " \t":
                    raise parser.error("an assignment must be separated from the word before it by a blank "
                                       "(AMK AZ-MC1 programming manual §2.6: X50 R1=7, not X50R1=7)",
                                       start)  # fmt: skip
                assigns.append(self._assignment(parser, char))
                continue
            if name == "LL":
                parser.pos = start + 2
                call = ("local", self._call_number(parser, "LL"))
                continue
            if char == "L":
                parser.pos = start + 1
                call = ("global", self._call_number(parser, "L"))
                continue
            if char in "RP":
                raise parser.error(f"{char} is a parameter, not an address: assign it ({char}1 = …) or use "
                                   "it in a value (X R1)", start)  # fmt: skip
            if char not in self._letters:
                raise parser.error(f"unknown address {char}", start)
            if char == "N":
                raise parser.error("N (the block number) begins the block, once", start)
            parser.pos = start + 1
            parser.skip_blanks()
            value_start = parser.pos
            if parser.at_end():
                raise parser.error(f"address {char} needs a value", start)
            fn = parser.expression(unary=True)
            text = body[value_start:parser.pos].strip()
            literal = literal_number(text.replace(" ", "").replace("\t", ""))
            if literal is not None:
                words.append((char, self._literal(char, text.replace(" ", "").replace("\t", "")), text))
            else:
                if char in _LITERAL_ONLY:
                    raise parser.error(f"{char} takes a literal whole number, not an expression", start)
                if char not in self._rules:
                    raise self._unknown_address(char)
                words.append((char, ("din", fn, text), None))
                has_expr = True
        if procedure is not None:
            if words or assigns or call:
                raise ProgramError(f"{procedure[0]}[…] stands alone in its block", code="syntax")
            return SpecialBlock(lineno, (), kind="stmt", stmt=("proc", procedure[0], procedure[1]),
                                skip=skip, number=number)  # fmt: skip
        inner = self._make_block(lineno, words, skip, number, has_expr=has_expr) if words else None
        if call is not None:
            return SpecialBlock(lineno, (), kind="call", stmt=(call[0], call[1], inner), skip=skip,
                                number=number)  # fmt: skip
        if assigns:
            return SpecialBlock(lineno, (), kind="assign", stmt=("words", inner), assign=tuple(assigns),
                                skip=skip, number=number)  # fmt: skip
        return inner

    @staticmethod
    def _is_assignment(parser: Parser, start: int) -> bool:
        """``R<n> =``, ``R[e] =`` or ``P<n> =`` at ``start`` (a single ``=``, not ``==``)."""
        saved = parser.pos
        try:
            parser.pos = start + 1
            parser.parameter_index(parser.text[start])
            parser.skip_blanks()
            text, pos = parser.text, parser.pos
            return text.startswith("=", pos) and not text.startswith("==", pos)
        except ExpressionSyntaxError:
            return False
        finally:
            parser.pos = saved

    @staticmethod
    def _assignment(parser: Parser, letter: str) -> tuple:
        """``R<n> = e`` → (target, value, text): target ``("R", fn | n)`` or ``("P", n)``."""
        parser.pos += 1
        index, number = parser.parameter_index(letter)
        if letter == "P" and index is not None:
            raise parser.error("P takes a parameter number (P10 = …)")
        parser.expect("=", "in the assignment")
        start = parser.pos
        if parser.at_end():
            raise parser.error(f"{letter}{number if number is not None else '[…]'} = needs a value")
        value = parser.expression(unary=True)
        target = (letter, index if index is not None else number)
        return (target, value, parser.text[start:parser.pos].strip())

    @staticmethod
    def _call_number(parser: Parser, address: str) -> int:
        number = parser.integer(address)
        if number > 10**PROGRAM_DIGITS - 1:
            raise parser.error(f"{address}{number}: program numbers have at most {PROGRAM_DIGITS} digits")
        return number

    # ------------------------------------------------------------------ control blocks
    def _statement(self, parser: Parser, lineno: int, skip: int, number: int | None) -> SpecialBlock:
        parser.pos += 1
        if parser.peek() in (" ", "\t"):
            raise parser.error("no blank between $ and the keyword (AMK AZ-MC1 programming manual §9)")
        start = parser.pos
        keyword = parser.name()
        if keyword not in control.KEYWORDS:
            raise parser.error(f"unknown control statement ${keyword or parser.peek()} (the controller has "
                               f"{', '.join('$' + k for k in control.LISTED)})", start)  # fmt: skip
        keyword = control.ALIASES.get(keyword, keyword)
        args: tuple = ()
        if keyword in control.WITH_EXPRESSION:
            if parser.at_end():
                raise parser.error(f"${keyword} needs an expression")
            args = (parser.expression(unary=True),)
        elif keyword == "FOR":
            parser.skip_blanks()
            letter = parser.peek()
            if letter != "R":
                raise parser.error("$FOR needs a parameter: $FOR R1 = start, end, step")
            parser.pos += 1
            index, n = parser.parameter_index("R")
            parser.expect("=", "after the $FOR parameter")
            first = parser.expression(unary=True)
            parser.expect(",", "between the $FOR start and end")
            last = parser.expression(unary=True)
            parser.expect(",", "between the $FOR end and step")
            step = parser.expression(unary=True)
            args = (("R", index if index is not None else n), first, last, step)
        if not parser.at_end():
            raise parser.error(f"${keyword}: a control block holds nothing else (found "
                               f"{parser.text[parser.pos:].strip()!r})")  # fmt: skip
        return SpecialBlock(lineno, (), kind="stmt", stmt=(keyword, *args), skip=skip, number=number)
