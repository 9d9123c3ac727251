"""A read program: the blocks the interpreter core runs, whatever the language that produced them.

A dialect's reader (its lexer, :attr:`Language.reader <cnc_gym.gcode.dialect.Language.reader>`) turns
program text into a :class:`Program` of :class:`Block` records; the core checks and executes the ordinary
blocks, the language's runner (control flow and calls) the statements, assignments and call blocks.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import re
from array import array
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from cnc_gym.errors import ProgramError


class Block:
    """One block after reading: the interface the core and the runners use, whatever the reader built.

    ``words``: ``(letter, value, text)`` tuples; ``value`` is a float for a literal (``text`` its
    digits, for decimal-point checks) or an expression node (``text`` None) evaluated at execution. A
    plain block (read on the hot path) gives just ``(letter, digits)`` pairs; ``word[-1]`` is the text
    either way.
    ``assign``: ``(target_node, value_node)`` for a macro assignment block (then ``words`` is empty).
    ``skip``: bit mask of the block-skip switches (bit n for ``/n``) that suppress the block.
    :meth:`split`: for a block without expressions, its words split into G numbers, M numbers and the other
    addresses → value (``gs``, ``ms``, ``values``; None where the block has no G or M).
    ``kind``: None (an ordinary block), ``"assign"`` (a macro assignment, in ``assign``), ``"stmt"`` (a macro
    statement, in ``stmt``) or ``"call"`` (may call a macro; words kept in order, arguments read without the
    addresses' own rules, evaluated at run time; ``stmt`` is then ``("strict", block or ProgramError)``,
    the block as an ordinary one, for where the code does not call).
    ``stmt``: ``("goto", target)``, ``("if_goto", cond, target)``, ``("if_then", cond, (target, value))``,
    ``("while", cond or None, m)`` (``DOm`` alone has no condition), ``("end", m)``.
    ``message``: the comment of an assignment block (``#3000=1 (TOOL NOT FOUND)``), else None.

    Two kinds of record carry it: :class:`WordBlock` (its words as tuples, split once at read time) and
    :class:`PlainBlock` (a block of literal words only, kept as its text and its numbers in the program's
    :class:`LiteralStore`: about 250 bytes a line instead of 1 200, so that a huge program meets the
    segment budget before it runs out of memory); :class:`CommentedBlock` is a word block that also keeps
    its comment (``comment``) for a code that takes it as an argument.
    """

    __slots__ = ()
    number: int | None
    skip: int = 0
    has_expr: bool = False
    assign: Any = None  # (target node, value node) or None
    # Ordinary blocks share these class-level defaults; :class:`SpecialBlock` gives statements, assignments
    # and calls their own.
    kind: str | None = None
    stmt: Any = None  # a tuple whose shape depends on the statement (see above)
    message: str | None = None
    #: The block's comment where a code of the block takes it as an argument (Haas G47's text), else None.
    comment: str | None = None

    @property
    def line(self) -> int:
        """The block's line in its file (1-based)."""
        raise NotImplementedError

    @property
    def words(self) -> Sequence:
        """``(letter, value, text)`` tuples, or ``(letter, digits)`` pairs of a plain block."""
        raise NotImplementedError

    def split(self) -> tuple[list | None, list | None, dict[str, float]]:
        """``(gs, ms, values)`` of a block without expressions."""
        raise NotImplementedError

    def __repr__(self) -> str:
        return (f"{type(self).__name__}(line={self.line}, words={self.words!r}, skip={self.skip}, "
                f"assign={self.assign!r}, kind={self.kind!r}, stmt={self.stmt!r})")  # fmt: skip


class WordBlock(Block):
    """A block whose words are ``(letter, value, text)`` tuples (see :class:`Block`); a block without
    expressions keeps them split (``gs``, ``ms``, ``values``) from read time on."""

    __slots__ = ("assign", "gs", "has_expr", "line", "ms", "number", "skip", "values", "words")
    line: int  # slots where the interface has properties
    words: Sequence
    gs: list | None
    ms: list | None
    values: Any  # dict[str, float], or None for a block with expressions

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

    def split(self) -> tuple[list | None, list | None, dict[str, float]]:
        return self.gs, self.ms, self.values


class SpecialBlock(WordBlock):
    """A block of kind ``"assign"``, ``"stmt"`` or ``"call"`` (see :class:`Block`)."""

    __slots__ = ("kind", "message", "stmt")

    def __init__(self, line: int, words: tuple, *, kind: str, stmt: tuple | None = None, skip: int = 0,
                 assign: tuple | None = None, number: int | None = None) -> None:  # fmt: skip
        super().__init__(line, words, skip=skip, has_expr=True, assign=assign, number=number)
        self.kind = kind
        self.stmt = stmt
        self.message = None


class CommentedBlock(WordBlock):
    """A block whose comment is an argument of one of its codes (``Dialect.comment_codes``)."""

    __slots__ = ("comment",)

    @classmethod
    def of(cls, block: Block, comment: str) -> Block:
        """``block`` with ``comment`` (an ordinary block; statements and calls keep theirs unchanged). A line
        with a comment is never a plain block, so an ordinary one is a :class:`WordBlock`."""
        if type(block) is not WordBlock:
            return block
        out = cls.__new__(cls)
        for name in WordBlock.__slots__:
            setattr(out, name, getattr(block, name))
        out.comment = comment
        return out


#: A plain block's words: an address letter and a literal (the reader checked them).
_PLAIN_WORD = re.compile(r"([A-Z])([-+]?[0-9.]+)")


class LiteralStore:
    """The numbers of a program's plain blocks, 8 bytes each, and the word shapes the blocks share.

    A shape is ``(G numbers, M numbers, the other letters in order)``: the G and M lists are the block's own
    (codes repeat, so a few shapes serve a whole program; nothing changes a block's split lists in place),
    the other words' numbers sit in ``numbers`` from the block's offset on.
    """

    __slots__ = ("numbers", "shapes")

    #: Most shapes kept for sharing (then each block keeps its own: a program of all-different codes).
    MAX_SHAPES = 1 << 16

    def __init__(self) -> None:
        self.numbers = array("d")
        self.shapes: dict[tuple, tuple[list | None, list | None, tuple[str, ...]]] = {}

    def add(self, line: int, text: str, gs: list | None, ms: list | None, values: dict[str, float],
            number: int | None) -> PlainBlock:  # fmt: skip
        """A plain block of ``text`` (upper case, no blanks) whose words the reader split and checked."""
        numbers = self.numbers
        offset = len(numbers)
        numbers.extend(values.values())
        letters = tuple(values)
        key = (letters, None if gs is None else tuple(gs), None if ms is None else tuple(ms))
        shape = self.shapes.get(key)
        if shape is None:
            shape = (gs, ms, letters)
            if len(self.shapes) < self.MAX_SHAPES:
                self.shapes[key] = shape
        block = PlainBlock.__new__(PlainBlock)
        block.where = line << 32 | offset
        block.text = text.encode("ascii")
        block.numbers = numbers
        block.shape = shape
        block.number = number
        return block


class PlainBlock(Block):
    """A block of literal words only (the reader's hot path), kept as its text (ASCII bytes), its shape (the
    G and M numbers and the other letters, shared by the blocks of one shape) and its other numbers in the
    program's :class:`LiteralStore`; :meth:`split` builds ``values`` when it runs and ``words`` gives the
    ``(letter, digits)`` pairs again from the text. The line and the offset of its numbers share one
    integer (``where``): every object a line costs counts at a million lines. Made by
    :meth:`LiteralStore.add`."""

    __slots__ = ("number", "numbers", "shape", "text", "where")
    where: int  # the line << 32 | the offset of its numbers in the store
    text: bytes
    numbers: array
    shape: tuple[list | None, list | None, tuple[str, ...]]

    @property
    def line(self) -> int:
        return self.where >> 32

    @property
    def words(self) -> list[tuple[str, str]]:
        return _PLAIN_WORD.findall(self.text.decode("ascii"))

    def split(self) -> tuple[list | None, list | None, dict[str, float]]:
        # The G and M lists are the shape's (shared, never changed in place); the values a fresh dict, built
        # by index (slicing the array and zipping cost about twice as much per block).
        gs, ms, letters = self.shape
        numbers, at = self.numbers, self.where & 0xFFFFFFFF
        n = len(letters)
        if n == 2:
            return gs, ms, {letters[0]: numbers[at], letters[1]: numbers[at + 1]}
        if n == 3:
            return gs, ms, {letters[0]: numbers[at], letters[1]: numbers[at + 1], letters[2]: numbers[at + 2]}
        values = {}
        for letter in letters:
            values[letter] = numbers[at]
            at += 1
        return gs, ms, values



def literal_block(line: int, words: Sequence, gs: list | None, ms: list | None, values: dict[str, float],
                  number: int | None = None, skip: int = 0) -> WordBlock:  # fmt: skip
    """A block of literal words already split (a reader's hot path): no ``__init__``, no second split."""
    block = WordBlock.__new__(WordBlock)
    block.line = line
    block.words = words
    block.skip = skip
    block.has_expr = False
    block.assign = None
    block.number = number
    block.gs = gs
    block.ms = ms
    block.values = values
    return block


def split_words(words) -> tuple[list | None, list | None, dict[str, float]]:
    """(G numbers or None, M numbers or None, {address: value}); a repeated address is an error."""
    values: dict[str, float] = {}
    gs = ms = None
    for letter, value, _ in words:
        if letter == "G":
            gs = [value] if gs is None else [*gs, value]
        elif letter == "M":
            ms = [value] if ms is None else [*ms, value]
        elif letter in values:
            # The manual's default is "the later one is valid" (§1.3.2, 1802#6 AD2 = 0); we take the
            # AD2 = 1 behaviour, an alarm, as with two G codes of one group (docs/gcode.md).
            raise ProgramError(f"address {letter} appears twice in the block", code="duplicate-word")
        else:
            values[letter] = value
    return gs, ms, values


@dataclass
class Program:
    """A read program: blocks in order, with sequence numbers indexed for a later GOTO.

    ``units``: program number → ``(start, end)`` block indices of each ``O`` program in the text (start is
    the ``O`` block; end is the next ``O`` block or the end). ``main``: the extent of the first program
    (from block 0, whether or not it has an ``O`` number). ``notices``: the reader's notes about the text,
    ``(line, level, message, code)`` (text it did not read; a number format the program seems to mix, a
    ``warning``).
    """

    blocks: list[Block]
    file: str = "<program>"
    program_number: int | None = None
    sequence_index: dict[int, list[int]] = field(default_factory=dict)
    units: dict[int, tuple[int, int]] = field(default_factory=dict)
    main: tuple[int, int] = (0, 0)
    notices: list[tuple[int, str, str, str]] = field(default_factory=list)
