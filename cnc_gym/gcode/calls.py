"""Program flow: the program counter loop, Macro B statements, subprograms and macro calls (GSK 25i).

Seed notes §1.9, §6.5-§6.7; manual L461-L495 (subprograms), L5663-L5850 (GOTO, IF, WHILE), L5852-L6379
(calls). What runs where:

* :class:`Unit` — one program (``O`` number … next ``O``), in the main file or in another file of the
  program directory, with its sequence-number index and its DO/END table (checked when the unit is first
  entered: pairing, crossing, nesting at most 3, identifiers 1-3; alarm 96).
* :class:`Frame` — one level of the call stack: the running unit, where to return, repeats left, whether
  it holds its own locals (G65/G66/G- and M-code macro calls push #1-#33; M98, M- and T-code subprogram
  calls do not, L6364-L6379), and which G66 modal calls its moves trigger.
* :class:`FlowRunner` — the loop. Plain blocks go straight to :meth:`Interpreter.execute`; statements,
  assignments, calls and the requests M98/M99 leave (``Interpreter._flow``) come here.

Bounds: ``max_blocks`` executed blocks (runaway loops end with ``too-many-blocks``), ``max_seconds`` of CPU
time (``time-budget``) and ``max_segments`` tool-path segments (``segment-budget``), subprogram nesting 4
and macro nesting 4 (alarm 77), DO nesting 3 per level (alarm 96).
"""

from __future__ import annotations

import bisect
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.gcode.dialect import gkey
from cnc_gym.gcode.expressions import evaluate, evaluate_condition
from cnc_gym.gcode.reader import Block, Reader
from cnc_gym.toolpath import SegmentKind

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import MacroCalls
    from cnc_gym.gcode.interpreter import Interpreter
    from cnc_gym.gcode.reader import Program

#: Default bound on executed blocks (a runaway WHILE/GOTO loop ends with a clear error).
DEFAULT_MAX_BLOCKS = 2_000_000
#: Default bound on the CPU seconds one interpretation may take (2 000 000 blocks of a macro loop take
#: 10-20 s; the bound catches what the block count does not: heavy blocks).
DEFAULT_MAX_SECONDS = 60.0
#: Default bound on the segments of one tool path (about 0.6 kB each while it is built: ~1.2 GB).
DEFAULT_MAX_SEGMENTS = 2_000_000
#: The clock and the segment count are read once per this many blocks charged to the budget.
_CHECK_EVERY = 1024
#: Argument specification I (L5892-L5914): address → local variable.
ARGUMENT_SPEC_I = {
    "A": 1,
    "B": 2,
    "C": 3,
    "D": 7,
    "E": 8,
    "F": 9,
    "H": 11,
    "M": 13,
    "Q": 17,
    "R": 18,
    "S": 19,
    "T": 20,
    "U": 21,
    "V": 22,
    "W": 23,
    "X": 24,
    "Y": 25,
    "Z": 26,
}
_IJK = {"I": 0, "J": 1, "K": 2}
_DWELL = int(SegmentKind.DWELL)
#: Actions of codes whose axis words set something rather than move (no G66 call after their block).
_SETTING_ACTIONS = frozenset({"dwell", "g10", "g52", "g92", "g51", "g68", "g50_1", "g51_1"})


@dataclass
class FlowOptions:
    """Options of one run (``interpret(..., max_blocks=, program_dir=, macro_calls=, main_m99=)``).

    ``main_m99``: what M99 in the main program does. ``"end"`` (default): the program ends after one pass
    (a simulated episode is one part; docs/gcode.md). ``"restart"``: the controller's behaviour (L481), back
    to the start (or to ``Nn`` for ``M99 Pn``), so only a macro exit (a GOTO to M30) ends the run, else
    ``max_blocks`` does.
    """

    max_blocks: int = DEFAULT_MAX_BLOCKS
    max_seconds: float = DEFAULT_MAX_SECONDS
    max_segments: int = DEFAULT_MAX_SEGMENTS
    program_dir: str | None = None
    macro_calls: MacroCalls | None = None
    main_m99: str = "end"


class LoopTable:
    """DO/END pairs of one unit: WHILE/DO index → END index and back, and each block's innermost DO."""

    def __init__(self, unit: Unit, max_depth: int, dialect) -> None:
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
                        raise fail(index, f"DO{m} inside DO{m}: DO and END must pair one to one (L5752)")
                    if len(stack) >= max_depth:
                        raise fail(index, f"DO{m}: DO loops nest at most {max_depth} deep (L5792)")
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
                                "cross (L5805)",
                            )
                        raise fail(index, f"END{m} without DO{m} before it (L5740)")
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
        """GOTO may leave DO ranges but not enter one (L5820-L5836)."""
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

    def loops(self, dialect) -> LoopTable:
        if self._loops is None:
            self._loops = LoopTable(self, dialect.max_loop_nesting, dialect)
        return self._loops

    def find(self, number: int, after: int) -> int | None:
        """Index of the block with sequence number ``number``: the first at or after ``after``, else the
        first from the start of the unit (the search wraps, L5678)."""
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
    """One G66 entry: program, repeat count and the arguments of the G66 block (L6136-L6175)."""

    number: int
    count: int
    args: dict[int, float]


class FlowRunner:
    """Runs an :class:`Interpreter`'s program with calls and Macro B flow (module docstring)."""

    def __init__(self, interp: Interpreter, options: FlowOptions | None = None) -> None:
        self.interp = interp
        self.options = options or FlowOptions()
        self.dialect = interp.dialect
        self.calls = self.options.macro_calls or self.dialect.macro_calls
        self.reader: Reader | None = None
        program = interp.program
        self.main_program = program
        self.main = Unit(program, program.program_number, program.main[0], program.main[1], 0)
        self.frames: list[Frame] = [Frame(self.main)]
        self.units: dict[int, Unit] = {}
        self.modal_calls: list[ModalCall] = []
        self.pc = 0
        self._directory: dict[str, Path] | None = None
        self._sub_depth = 0
        self._macro_depth = 0
        self._deadline = time.process_time() + self.options.max_seconds
        interp.macro = self
        interp._flow = None

    # ------------------------------------------------------------------ the loop
    def run(self) -> None:
        """The program-counter loop. Plain blocks take the fast path (straight to ``execute``); the budget
        of ``max_blocks`` is charged in bulk whenever control leaves the fast path (a straight run through
        a program is finite, so only jumps, loops and calls need the check)."""
        interp = self.interp
        execute = interp.execute
        skip_mask = interp.skip_mask
        budget = self.options.max_blocks
        next_check = budget - _CHECK_EVERY
        unit = self.main
        blocks, end = unit.blocks, unit.end
        pc = mark = unit.start
        watching = False  # G66 active: every block is checked for motion (the slow path)
        unit.loops(self.dialect)
        while True:
            if pc >= end:
                budget -= pc - mark
                try:
                    self.check_bounds()
                except ProgramError as err:
                    raise err.located(unit.file, blocks[end - 1].line if end > unit.start else 0) from None
                pc = mark = self._fall_off()
                if pc < 0:
                    return
                unit = self.frames[-1].unit
                blocks, end = unit.blocks, unit.end
                continue
            block = blocks[pc]
            pc += 1
            if block.skip & skip_mask:
                continue
            if block.kind is None and not watching:
                try:
                    execute(block)
                except ProgramError as err:
                    raise err.located(unit.file, block.line) from None
                if interp._flow is None and not interp.ended:
                    continue
                slow = False
            else:
                slow = True
            budget -= pc - mark
            if budget < 0:
                err = self.dialect.error(
                    f"more than {self.options.max_blocks} blocks executed: a runaway loop? "
                    "(raise max_blocks if the program is really this long)",
                    "too-many-blocks",
                )
                raise err.located(unit.file, block.line)
            if budget < next_check:
                next_check = budget - _CHECK_EVERY
                try:
                    self.check_bounds()
                except ProgramError as err:
                    raise err.located(unit.file, block.line) from None
            self.pc = pc
            try:
                pc = self._special(block, pc) if slow else self._after(block, pc, moved=False)
            except ProgramError as err:
                raise err.located(unit.file, block.line) from None
            if pc < 0:
                return
            mark = pc
            watching = bool(self.modal_calls)
            unit = self.frames[-1].unit
            blocks, end = unit.blocks, unit.end

    def check_bounds(self) -> None:
        """The CPU-time and segment bounds of the run (``max_seconds``, ``max_segments``); the block count
        is checked in the loop itself. Also called by blocks that make many moves (cycles.emit)."""
        options = self.options
        if len(self.interp.builder) > options.max_segments:
            raise self.dialect.error(f"the tool path has more than {options.max_segments} segments (raise "
                                     "max_segments if the program is really this long)", "segment-budget")
        if time.process_time() > self._deadline:
            raise self.dialect.error(f"interpretation took more than {options.max_seconds:g} s of CPU time "
                                     "(a runaway loop? raise max_seconds if the program is really this long)",
                                     "time-budget")  # fmt: skip

    def _special(self, block: Block, pc: int) -> int:
        kind = block.kind
        if kind == "assign" or kind == "stmt":
            self.interp.out.line = block.line  # for #3006's stop and #4113/#4114
        if kind == "assign":
            target, value = block.assign
            variables = self.interp.variables
            self.message = block.message
            variables.write(
                evaluate(target, variables, self.dialect), evaluate(value, variables, self.dialect)
            )
            return pc
        if kind == "stmt":
            return self._statement(block, pc)
        if kind == "call":
            return self._call_block(block, pc)
        return self._ordinary(block, pc)

    def _ordinary(self, block: Block, pc: int) -> int:
        """An ordinary block while G66 is active (or after a call block's own words): watch for motion.

        "A block containing a move command" (L6147) is read from the block itself — a non-null axis word
        not taken by a code that only sets something (G04 G10 G52 G92 G51 G68 G50.1 G51.1) — or from the
        segments it produced (a move with no axis word of its own). The segments alone would miss moves
        that cutter compensation's look-ahead emits a block later."""
        interp = self.interp
        kinds = interp.builder._rows["kind"]
        before = len(kinds)
        interp.execute(block)
        moved = bool(self.modal_calls) and (self._has_move_command(block)
                                            or any(k != _DWELL for k in kinds[before:]))  # fmt: skip
        return self._after(block, pc, moved=moved)

    def _has_move_command(self, block: Block) -> bool:
        axes = self.dialect.axes
        has_axis = False
        for word in block.words:
            letter, value = word[0], word[1]
            if letter not in axes and letter != "G":
                continue
            if isinstance(value, str):
                value = float(value)
            elif not isinstance(value, float):
                value = evaluate(value, self.interp.variables, self.dialect)
                if value is None:
                    continue  # a null word is dropped (L5136)
            if letter == "G":
                spec = self.dialect.gcodes.get(gkey(value))
                if spec is not None and spec.action in _SETTING_ACTIONS:
                    return False
            else:
                has_axis = True
        return has_axis

    def _after(self, block: Block, pc: int, *, moved: bool) -> int:
        interp = self.interp
        if interp.ended:
            self._count_part()
            return -1
        request = interp._flow
        interp._flow = None
        if request is not None:
            if request[0] == "call":
                return self._push_subprogram(request[1], request[2], pc, by_code=False)
            return self._return(pc, request[1])
        if moved and self.modal_calls:
            level = min(self.frames[-1].modal_limit, len(self.modal_calls)) - 1
            if level >= 0:
                call = self.modal_calls[level]
                return self._push_macro(
                    call.number,
                    call.count,
                    dict(call.args),
                    pc,
                    modal_limit=level,
                    by_code=self.frames[-1].by_code,
                )
        return pc

    def _count_part(self) -> None:
        system = self.interp.variables.system
        if system is not None:
            system.count_part()

    # ------------------------------------------------------------------ statements
    def _statement(self, block: Block, pc: int) -> int:
        stmt = block.stmt
        op = stmt[0]
        variables = self.interp.variables
        dialect = self.dialect
        unit = self.frames[-1].unit
        here = pc - 1
        if op == "while":
            condition = stmt[1]
            if condition is None or evaluate_condition(condition, variables, dialect):
                return pc
            return unit.loops(dialect).do_end[here] + 1
        if op == "end":
            return unit.loops(dialect).end_do[here]
        if op == "goto":
            return self._goto(stmt[1], unit, here)
        if op == "if_goto":
            if evaluate_condition(stmt[1], variables, dialect):
                return self._goto(stmt[2], unit, here)
            return pc
        if op == "if_then":
            if evaluate_condition(stmt[1], variables, dialect):
                target, value = stmt[2]
                self.message = block.message
                variables.write(evaluate(target, variables, dialect), evaluate(value, variables, dialect))
            return pc
        raise AssertionError(f"unknown statement {stmt!r}")

    def _goto(self, target_node: tuple, unit: Unit, here: int) -> int:
        value = evaluate(target_node, self.interp.variables, self.dialect)
        number = self._sequence_number(value, "GOTO")
        target = unit.find(number, here + 1)
        if target is None:
            raise self.dialect.error(f"GOTO{number}: no block N{number} in {unit.name}", "sequence-not-found")
        if not unit.loops(self.dialect).may_jump(here, target):
            raise self.dialect.error(
                f"GOTO{number} jumps into a DO range (only jumps out of one are allowed, L5826)", "do-end"
            )
        return target

    def _sequence_number(self, value: float | None, what: str) -> int:
        if value is None:
            raise self.dialect.error(f"{what}: the sequence number is null", "sequence-not-found")
        number = round(value)
        if abs(value - number) > 1e-6 or not 1 <= number <= 999999:
            raise self.dialect.error(
                f"{what}{value:g}: a sequence number is an integer 1..999999", "sequence-not-found"
            )
        return number

    # ------------------------------------------------------------------ units and files
    def unit(self, number: int) -> Unit:
        """Program ``O<number>``: in the main file, else in the program directory (alarm 59 if absent)."""
        unit = self.units.get(number)
        if unit is not None:
            return unit
        span = self.main_program.units.get(number)
        if span is not None:
            unit = Unit(self.main_program, number, span[0], span[1], 0)
        else:
            unit = self._load(number)
        unit.loops(self.dialect)  # DO/END checked before the first block runs
        self.units[number] = unit
        return unit

    def _directory_files(self) -> dict[str, Path]:
        if self._directory is None:
            folder = self.options.program_dir
            if folder is None:
                main = Path(self.main_program.file)
                folder = str(main.parent) if main.is_file() else None
            files: dict[str, Path] = {}
            if folder is not None and os.path.isdir(folder):
                for entry in sorted(os.listdir(folder)):
                    path = Path(folder) / entry
                    if path.is_file():
                        files.setdefault(entry.lower(), path)
            self._directory = files
        return self._directory

    def _load(self, number: int) -> Unit:
        files = self._directory_files()
        names = (
            f"o{number:04d}",
            f"o{number:04d}.nc",
            f"o{number}",
            f"o{number}.nc",
            f"{number:04d}.nc",
            f"{number}.nc",
        )
        path = next((files[n] for n in names if n in files), None)
        if path is None:
            where = self.options.program_dir or "the program's folder"
            raise self.dialect.error(
                f"program O{number:04d} not found (not in this file, no O{number:04d}[.nc] "
                f"or {number}.nc in {where})",
                "program-not-found",
            )
        try:
            raw = path.read_bytes()
        except OSError as exc:
            raise self.dialect.error(
                f"program O{number:04d}: cannot read {path} ({exc.strerror or exc})", "program-not-found"
            ) from None
        try:
            text = raw.decode("utf-8-sig")
        except UnicodeDecodeError:
            text = raw.decode("latin-1")
        if self.reader is None:
            self.reader = Reader(self.dialect, self.calls)
        program = self.reader.read(text, str(path))
        file_index = self.interp.builder.file_index(str(path))
        span = program.units.get(number)
        if span is None:
            if program.units:
                raise self.dialect.error(f"{path} does not hold program O{number:04d}", "program-not-found")
            span = (0, len(program.blocks))
        return Unit(program, number, span[0], span[1], file_index)

    def _enter(self, frame: Frame) -> int:
        self.frames.append(frame)
        self._set_file(frame.unit)
        return frame.unit.start

    def _set_file(self, unit: Unit) -> None:
        self.interp.out.file_index = unit.file_index
        self.interp.file = unit.file

    # ------------------------------------------------------------------ subprograms (M98 / M99)
    def subprogram_call(self, values: dict) -> None:
        """M98 P[count]oooo [L count]: called after the block's other commands (L5878)."""
        if "P" not in values:
            raise self.dialect.error("M98 needs P (the program number)", "missing-program-number")
        number, count = self._program_and_count(values, "M98")
        self.interp._flow = ("call", number, count)

    def _program_and_count(self, values: dict, what: str) -> tuple[int, int]:
        p = values["P"]
        if p != int(p) or p <= 0:
            raise self.dialect.error(
                f"{what} P{p:g}: P is a program number (1-9999, a repeat count may lead: "
                "P51002 = O1002 five times)",
                "bad-call",
            )
        p = int(p)
        if "L" in values:
            if p > 9999:
                raise self.dialect.error(
                    f"{what} P{p} L{values['L']:g}: give the repeat count either in P or in L", "bad-call"
                )
            count = int(values["L"])
            if not 0 <= count <= 9999:
                raise self.dialect.error(f"{what} L{count}: the repeat count is 0..9999", "bad-call")
            return p, count
        count, number = divmod(p, 10000)
        if number == 0:
            raise self.dialect.error(f"{what} P{p}: program number 0", "bad-call")
        if count > 999:
            raise self.dialect.error(f"{what} P{p}: at most 999 repeats (L469)", "bad-call")
        return number, max(count, 1)

    def _push_subprogram(self, number: int, count: int, pc: int, *, by_code: bool) -> int:
        if count == 0:
            return pc  # L0: not called
        if self._sub_depth >= self.dialect.max_subprogram_nesting:
            raise self.dialect.error(
                f"M98 P{number}: subprograms nest at most "
                f"{self.dialect.max_subprogram_nesting} levels (L465)",
                "nesting",
            )
        unit = self.unit(number)
        caller = self.frames[-1]
        self._sub_depth += 1
        return self._enter(
            Frame(
                unit,
                pc,
                count - 1,
                macro=False,
                subprogram=True,
                modal_limit=caller.modal_limit,
                by_code=by_code or caller.by_code,
            )
        )

    def subprogram_return(self, values: dict) -> None:
        """M99 [P n]: back to the caller (to its block Nn with P); in the main program see FlowOptions."""
        target = None
        if "P" in values:
            target = self._sequence_number(values["P"], "M99 P")
        self.interp._flow = ("return", target)

    def _return(self, pc: int, target: int | None) -> int:
        frame = self.frames[-1]
        if len(self.frames) == 1:
            if self.options.main_m99 == "end":
                return -1
            if target is None:
                return frame.unit.start
            return self._find_in(frame.unit, target, frame.unit.start)
        if frame.repeats > 0:
            frame.repeats -= 1
            if frame.macro:
                self.interp.variables.locals = dict(frame.args)
            return frame.unit.start
        self.frames.pop()
        if frame.macro:
            self.interp.variables.pop_locals()
            self._macro_depth -= 1
        if frame.subprogram:
            self._sub_depth -= 1
        caller = self.frames[-1]
        self._set_file(caller.unit)
        if target is None:
            return frame.return_pc
        return self._find_in(caller.unit, target, frame.return_pc)

    def _find_in(self, unit: Unit, number: int, after: int) -> int:
        index = unit.find(number, after)
        if index is None:
            raise self.dialect.error(
                f"M99 P{number}: no block N{number} in {unit.name}", "sequence-not-found"
            )
        return index

    def _fall_off(self) -> int:
        """The end of a unit's text: the main program ends; a subprogram returns as with M99."""
        if len(self.frames) == 1:
            return -1
        return self._return(0, None)

    # ------------------------------------------------------------------ macro calls
    def _call_block(self, block: Block, pc: int) -> int:
        """A block holding G65, G66 or a G/M/T code the dialect maps to a call."""
        interp = self.interp
        if interp.nurbs.hpcc and interp.modal.get(1) == 62:  # G06.2 in force (nurbs.py)
            raise self.dialect.error("a macro or subprogram call in NURBS mode: no G, M or T codes until a "
                                     "group-01 code ends G06.2 (L1281)", "nurbs-forbidden")  # fmt: skip
        words = self._evaluated(block.words)
        frame = self.frames[-1]
        gs = [w[1] for w in words if w[0] == "G"]
        ms = [w[1] for w in words if w[0] == "M"]
        calls = self.calls
        if 65.0 in gs or 66.0 in gs:
            code = 65 if 65.0 in gs else 66
            if 65.0 in gs and 66.0 in gs:
                raise self.dialect.error("G65 and G66 in one block", "group-conflict")
            others = [g for g in gs if g != code]
            if others:
                raise self.dialect.error(
                    f"G{code} takes no other G code in its block (G{others[0]:g}); the "
                    "words after it are arguments",
                    "bad-call",
                )
            values = {w[0]: w[1] for w in words if w[0] in "PL"}
            if "P" not in values:
                raise self.dialect.error(
                    f"G{code} needs P (the macro program number)", "missing-program-number"
                )
            number, count = self._macro_program(values, f"G{code}")
            args = self._arguments(words)
            if code == 65:
                return self._push_macro(
                    number, count, args, pc, modal_limit=frame.modal_limit, by_code=frame.by_code
                )
            self.unit(number)  # alarm 59 now, not at the first move
            self.modal_calls.append(ModalCall(number, count, args))
            interp.modal[12] = 660
            return pc
        if not frame.by_code:
            for g in gs:
                if int(g) == g and int(g) in calls.g_macro:
                    if len(gs) > 1:
                        raise self.dialect.error(
                            f"G{g:g} calls a macro; the block may hold no other G code", "bad-call"
                        )
                    args = self._arguments([w for w in words if w[0] != "G"], pl_is_error=True)
                    return self._push_macro(
                        calls.g_macro[int(g)], 1, args, pc, modal_limit=frame.modal_limit, by_code=True
                    )
            for m in ms:
                if int(m) == m and int(m) in calls.m_macro:
                    if gs:
                        raise self.dialect.error(
                            f"M{m:g} calls a macro; the block may hold no G code", "bad-call"
                        )
                    rest = [w for w in words if not (w[0] == "M" and w[1] == m)]
                    args = self._arguments(rest, pl_is_error=True)
                    return self._push_macro(
                        calls.m_macro[int(m)], 1, args, pc, modal_limit=frame.modal_limit, by_code=True
                    )
            strict = block.stmt[1]
            if isinstance(strict, ProgramError):
                raise strict
            for m in ms:
                if int(m) == m and int(m) in calls.m_sub:
                    # N_ G_ X_ Y_ … Mxx ≡ N_ G_ X_ Y_ … M98 Pxxxx: the block's other commands first (L6281).
                    pc = self._run_without(strict, pc, "M", m)
                    if pc < 0:
                        return pc
                    return self._push_subprogram(calls.m_sub[int(m)], 1, pc, by_code=True)
            if calls.t_sub is not None:
                t = next((w[1] for w in words if w[0] == "T"), None)
                if t is not None:
                    # Tt ≡ #149=t; … M98 P9000 (L6321-L6333).
                    interp.variables.write(149.0, t)
                    pc = self._run_without(strict, pc, "T", None)
                    if pc < 0:
                        return pc
                    return self._push_subprogram(calls.t_sub, 1, pc, by_code=True)
        # A mapped code inside a program called by a code: an ordinary block (L6265, L6331).
        strict = block.stmt[1]
        if isinstance(strict, ProgramError):
            raise strict
        if strict is None:
            return pc
        return self._ordinary(strict, pc)

    def _run_without(self, block: Block | None, pc: int, letter: str, value: float | None) -> int:
        """The block's other words, before a subprogram call by M or T code (L6281, L6321)."""
        if block is None:
            return pc
        kept = tuple(w for w in block.words if not (w[0] == letter and (value is None or w[1] == value)))
        if not kept:
            return pc
        interp = self.interp
        interp.execute(Block(block.line, kept, skip=0, has_expr=True, number=block.number))
        if interp.ended:
            self._count_part()
            return -1
        if interp._flow is not None:
            interp._flow = None
            raise self.dialect.error(
                f"M98/M99 cannot share a block with {letter}, which calls a subprogram here", "bad-call"
            )
        return pc

    def _evaluated(self, words: tuple) -> list[tuple[str, float]]:
        """Call-block words → (letter, value) in order; a null variable drops its word (L5136)."""
        out = []
        variables = self.interp.variables
        for word in words:
            letter, value = word[0], word[1]
            if not isinstance(value, float):
                value = evaluate(value, variables, self.dialect)
                if value is None:
                    continue
            out.append((letter, value))
        return out

    def _macro_program(self, values: dict, what: str) -> tuple[int, int]:
        p = values["P"]
        if p != int(p) or not 1 <= p <= 9999:
            raise self.dialect.error(f"{what} P{p:g}: the macro program number is 1..9999", "bad-call")
        count = 1
        if "L" in values:
            count = values["L"]
            if count != int(count) or not 1 <= count <= 9999:
                raise self.dialect.error(
                    f"{what} L{count:g}: the repeat count is 1..9999 (L6150)", "bad-call"
                )
        return int(p), int(count)

    def _arguments(self, words: list, *, pl_is_error: bool = False) -> dict[int, float]:
        """Argument specifications I and II, mixed freely; a later word for the same variable wins
        (L5892-L5968). I/J/K: a letter not after the previous one of its group starts the next group."""
        args: dict[int, float] = {}
        group = 0
        last = 3
        for letter, value in words:
            if letter in "GNO" or (letter in "PL" and not pl_is_error):
                continue
            if letter in "PL" and pl_is_error:
                raise self.dialect.error(f"address {letter} cannot be a macro argument (L5892)", "bad-call")
            k = _IJK.get(letter)
            if k is not None:
                if k <= last:
                    group += 1
                    if group > 10:
                        raise self.dialect.error("more than 10 I/J/K argument groups (L5916)", "bad-call")
                last = k
                args[4 + 3 * (group - 1) + k] = value
                continue
            index = ARGUMENT_SPEC_I.get(letter)
            if index is None:
                raise self.dialect.error(f"address {letter} cannot be a macro argument (L5892)", "bad-call")
            args[index] = value
        return args

    def _push_macro(
        self, number: int, count: int, args: dict[int, float], pc: int, *, modal_limit: int, by_code: bool
    ) -> int:
        if self._macro_depth >= self.dialect.max_macro_nesting:
            raise self.dialect.error(
                f"O{number:04d}: macro calls nest at most {self.dialect.max_macro_nesting} levels (L6160)",
                "nesting",
            )
        unit = self.unit(number)
        self._macro_depth += 1
        self.interp.variables.push_locals(args)
        return self._enter(
            Frame(unit, pc, count - 1, macro=True, modal_limit=modal_limit, by_code=by_code, args=args)
        )

    def cancel_modal_call(self) -> None:
        """G67: the latest G66 ends (L6199)."""
        if self.modal_calls:
            self.modal_calls.pop()
        self.interp.modal[12] = 660 if self.modal_calls else 670

    def macro_call_from_variable(self, spec) -> None:
        raise self.dialect.error(
            f"{spec.name} must be written as a literal code (its block's words are arguments)", "bad-call"
        )
