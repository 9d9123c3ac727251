"""A read program: the blocks the interpreter core runs, whatever the language that produced them.

A dialect's reader (its lexer, :attr:`Language.reader <cnc_gym.gcode.dialect.Language.reader>`) turns
program text into a :class:`Program` of :class:`Block` records; the core checks and executes the ordinary
blocks, the language's runner (control flow and calls) the statements, assignments and call blocks.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from cnc_gym.errors import ProgramError


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
    ``kind``: None (an ordinary block), ``"assign"`` (a macro assignment, in ``assign``), ``"stmt"`` (a macro
    statement, in ``stmt``) or ``"call"`` (may call a macro; words kept in order, arguments read without the
    addresses' own rules, evaluated at run time; ``stmt`` is then ``("strict", block or ProgramError)``,
    the block as an ordinary one, for where the code does not call).
    ``stmt``: ``("goto", target)``, ``("if_goto", cond, target)``, ``("if_then", cond, (target, value))``,
    ``("while", cond or None, m)`` (``DOm`` alone has no condition), ``("end", m)``.
    ``message``: the comment of an assignment block (``#3000=1 (TOOL NOT FOUND)``), else None.
    ``comment``: the comment of a block that holds a code taking it as an argument (:class:`CommentedBlock`).
    """

    __slots__ = ("assign", "gs", "has_expr", "line", "ms", "number", "skip", "values", "words")
    line: int
    words: Sequence  # (letter, value, text) tuples; a plain block keeps a list of (letter, digits) pairs
    skip: int
    has_expr: bool
    assign: Any  # (target node, value node) or None
    number: int | None
    gs: list | None
    ms: list | None
    values: Any  # dict[str, float], or None for a block with expressions
    # Ordinary blocks share these class-level defaults (no per-block stores on the read hot path);
    # :class:`SpecialBlock` gives statements, assignments and calls their own.
    kind: str | None = None
    stmt: Any = None  # a tuple whose shape depends on the statement (see above)
    message: str | None = None
    #: The block's comment where a code of the block takes it as an argument (Haas G47's text), else None.
    comment: str | None = None

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
        return (f"Block(line={self.line}, words={self.words!r}, skip={self.skip}, assign={self.assign!r}, "
                f"kind={self.kind!r}, stmt={self.stmt!r})")


class SpecialBlock(Block):
    """A block of kind ``"assign"``, ``"stmt"`` or ``"call"`` (see :class:`Block`)."""

    __slots__ = ("kind", "message", "stmt")

    def __init__(self, line: int, words: tuple, *, kind: str, stmt: tuple | None = None, skip: int = 0,
                 assign: tuple | None = None, number: int | None = None) -> None:  # fmt: skip
        super().__init__(line, words, skip=skip, has_expr=True, assign=assign, number=number)
        self.kind = kind
        self.stmt = stmt
        self.message = None


class CommentedBlock(Block):
    """A block whose comment is an argument of one of its codes (``Dialect.comment_codes``)."""

    __slots__ = ("comment",)

    @classmethod
    def of(cls, block: Block, comment: str) -> Block:
        """``block`` with ``comment`` (an ordinary block; statements and calls keep theirs unchanged)."""
        if type(block) is not Block:
            return block
        out = cls.__new__(cls)
        for name in Block.__slots__:
            setattr(out, name, getattr(block, name))
        out.comment = comment
        return out


def literal_block(line: int, words: Sequence, gs: list | None, ms: list | None, values: dict[str, float],
                  number: int | None = None, skip: int = 0) -> Block:  # fmt: skip
    """A block of literal words already split (a reader's hot path): no ``__init__``, no second split."""
    block = Block.__new__(Block)
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
