"""Program units and call frames of the Fanuc family's runner: one ``O`` program (:class:`Unit`) with its
sequence-number index and DO/END table (:class:`LoopTable`), one call level (:class:`Frame`), one G66
modal call (:class:`ModalCall`). Used by ``flow.py`` (the loop) and ``calls.py`` (the call convention).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Dialect
    from cnc_gym.gcode.program import Program


class LoopTable:
    """DO/END pairs of one unit: WHILE/DO index → END index and back, and each block's innermost DO."""

    def __init__(self, unit: Unit, max_depth: int, dialect: Dialect) -> None:
        self.do_end: dict[int, int] = {}
        self.end_do: dict[int, int] = {}
        self.inner: dict[int, int] = {}  # block index → index of the innermost enclosing WHILE/DO
        self.parent: dict[int, int] = {}  # WHILE/DO index → enclosing WHILE/DO index (-1 at top level)
        stack: list[tuple[int, int]] = []  # (m, index)
        blocks = unit.blocks

        def fail(index: int, message: str) -> ProgramError:
            err = dialect.error(message, "do-end")
            return err.located(unit.file, blocks[index].line)

        for index in range(unit.start, unit.end):
            block = blocks[index]
            if block.kind == "stmt":
                stmt = block.stmt
                if stmt[0] == "while":
                    m = stmt[2]
                    if any(mm == m for mm, _ in stack):
                        raise fail(index, f"DO{m} inside DO{m}: DO and END must pair one to one (GSK 25i "
                                          "§3.7.5)")
                    if len(stack) >= max_depth:
                        raise fail(index, f"DO{m}: DO loops nest at most {max_depth} deep (GSK 25i §3.7.5)")
                    if stack:
                        self.inner[index] = stack[-1][1]
                    self.parent[index] = stack[-1][1] if stack else -1
                    stack.append((m, index))
                    continue
                if stmt[0] == "end":
                    m = stmt[1]
                    if not stack or stack[-1][0] != m:
                        if any(mm == m for mm, _ in stack):
                            raise fail(
                                index,
                                f"END{m} closes DO{m} across DO{stack[-1][0]}: DO ranges may not "
                                "cross (GSK 25i §3.7.5)",
                            )
                        raise fail(index, f"END{m} without DO{m} before it (GSK 25i §3.7.5)")
                    _, do_index = stack.pop()
                    self.inner[index] = do_index
                    self.do_end[do_index] = index
                    self.end_do[index] = do_index
                    continue
            if stack:
                self.inner[index] = stack[-1][1]
        if stack:
            m, index = stack[-1]
            raise fail(index, f"DO{m} without END{m}")

    def may_jump(self, source: int, target: int) -> bool:
        """GOTO may leave DO ranges but not enter one (§3.7.5)."""
        target_loop = self.inner.get(target, -1)
        if target_loop == -1:
            return True
        loop = self.inner.get(source, -1)
        while loop != -1:
            if loop == target_loop:
                return True
            loop = self.parent[loop]
        return False


class Unit:
    """One program: blocks ``[start, end)`` of a read Program (``start`` is its O block, if any)."""

    __slots__ = ("_loops", "_sequence", "blocks", "end", "file", "file_index", "number", "start")

    def __init__(self, program: Program, number: int | None, start: int, end: int, file_index: int) -> None:
        self.blocks = program.blocks
        self.number = number
        self.start = start
        self.end = end
        self.file = program.file
        self.file_index = file_index
        self._loops: LoopTable | None = None
        self._sequence: dict[int, list[int]] | None = None

    @property
    def name(self) -> str:
        return "the main program" if self.number is None else f"O{self.number:04d}"

    def local(self, start: int) -> Unit:
        """The same program from block ``start`` on: the unit a local subprogram call (Haas M97) runs."""
        out = Unit.__new__(Unit)
        out.blocks, out.number, out.end = self.blocks, self.number, self.end
        out.file, out.file_index = self.file, self.file_index
        out.start = start
        out._loops = None
        out._sequence = None
        return out

    def loops(self, dialect: Dialect) -> LoopTable:
        if self._loops is None:
            self._loops = LoopTable(self, dialect.max_loop_nesting, dialect)
        return self._loops

    def find(self, number: int, after: int) -> int | None:
        """Index of the block with sequence number ``number``: the first at or after ``after``, else the
        first from the start of the unit (the search wraps, §3.7.5)."""
        if self._sequence is None:
            index: dict[int, list[int]] = {}
            for i in range(self.start, self.end):
                n = self.blocks[i].number
                if n is not None:
                    index.setdefault(n, []).append(i)
            self._sequence = index
        hits = self._sequence.get(number)
        if not hits:
            return None
        k = bisect.bisect_left(hits, after)
        return hits[k] if k < len(hits) else hits[0]


@dataclass
class Frame:
    """One call level. ``repeats``: passes left after the current one. ``macro``: holds its own locals.
    ``modal_limit``: moves here trigger G66 entry ``min(modal_limit, len(stack)) - 1``. ``by_code``: called
    by a G/M/T code (inside, those codes are ordinary). ``args``: locals a repeated macro pass starts with."""

    unit: Unit
    return_pc: int = -1
    repeats: int = 0
    macro: bool = False
    subprogram: bool = False
    modal_limit: int = 1 << 30
    by_code: bool = False
    args: dict[int, float] = field(default_factory=dict)


@dataclass
class ModalCall:
    """One G66 entry: program, repeat count and the arguments of the G66 block (§3.7.6)."""

    number: int
    count: int
    args: dict[int, float]
