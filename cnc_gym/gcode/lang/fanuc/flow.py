"""Program flow of the Fanuc family: the program-counter loop, Macro B statements (GOTO, IF, WHILE/DO/END),
program units and files (§1.3.1 subprograms, §3.7.5 GOTO, IF, WHILE, §3.7.6-§3.7.7 calls). The language's
runner (:attr:`Language.runner <cnc_gym.gcode.dialect.Language.runner>`).

* :class:`~cnc_gym.gcode.lang.fanuc.units.Unit` — one program (``O`` number … next ``O``), in the main
  file or in another file of the program directory, with its sequence-number index and its DO/END table
  (checked when the unit is first entered: pairing, crossing, nesting at most 3, identifiers 1-3;
  alarm 96).
* :class:`~cnc_gym.gcode.lang.fanuc.units.Frame` — one level of the call stack (``calls.py``).
* :class:`FlowRunner` — the loop. Plain blocks go straight to the core's ``execute``; statements,
  assignments, calls and the requests M98/M99 leave (``State.flow_request``) come here.

Bounds: ``max_blocks`` executed blocks (runaway loops end with ``too-many-blocks``), ``max_seconds`` of CPU
time (``time-budget``) and ``max_segments`` tool-path segments (``segment-budget``), subprogram nesting 4
and macro nesting 4 (alarm 77), DO nesting 3 per level (alarm 96).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, cast

from cnc_gym.errors import ConfigError, ProgramError, notice_line
from cnc_gym.files import MAX_PROGRAM_BYTES, read_regular_file
from cnc_gym.gcode.codes import gkey
from cnc_gym.gcode.lang.fanuc.calls import CallConvention
from cnc_gym.gcode.lang.fanuc.expressions import evaluate, evaluate_condition
from cnc_gym.gcode.lang.fanuc.units import Frame, ModalCall, Unit
from cnc_gym.gcode.settings import FlowOptions
from cnc_gym.toolpath import SegmentKind

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import ProgramReader, Seam
    from cnc_gym.gcode.lang.fanuc.variables import VariableStore
    from cnc_gym.gcode.program import Block

_DWELL = int(SegmentKind.DWELL)
#: Actions of codes whose axis words set something rather than move (no G66 call after their block).
#: The clock and the segment count are read once per this many blocks charged to the budget.
_CHECK_EVERY = 1024

_SETTING_ACTIONS = frozenset({"dwell", "data_input", "local_origin", "floating_origin", "scaling", "rotation",
                              "mirror_cancel", "mirror"})


class FlowRunner(CallConvention):
    """Runs the core's program with calls and Macro B flow (module docstring)."""

    def __init__(self, core: Seam, options: FlowOptions | None = None) -> None:
        self.core = core
        self.options = options or FlowOptions()
        self.dialect = core.dialect
        self.calls = self.options.macro_calls or self.dialect.macro_calls
        self.reader: ProgramReader | None = None
        program = core.state.program
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
        core.state.flow = self
        core.state.flow_request = None
        #: The Fanuc family's variable store (locals per macro level).
        self._variables = cast("VariableStore", core.state.variables)

    # ------------------------------------------------------------------ the loop
    def run(self) -> None:
        """Run the main program (:meth:`_loop`), then note the programs of its file that never ran."""
        self._loop()
        self._note_uncalled()

    def _note_uncalled(self) -> None:
        """A note for each ``O`` program of the main file that was never called: the run ends with the main
        program, so text after an ``O`` boundary runs only when called (nothing is dropped unsaid)."""
        program = self.main_program
        first, last = program.main
        ran = f"the main program (lines {program.blocks[first].line}-{program.blocks[last - 1].line})" if (
            last > first) else "the main program (no block)"  # fmt: skip
        for number, (start, end) in program.units.items():
            if number in self.units or start == first or end <= start:
                continue
            blocks = program.blocks
            self.core.notice(f"program O{number:04d} (lines {blocks[start].line}-{blocks[end - 1].line}, "
                             f"{end - start} blocks) in this file was never called: the run ended with "
                             f"{ran}; call it with M98 P or G65 P, or make it the first program of the file",
                             "uncalled-program", line=blocks[start].line)  # fmt: skip

    def _loop(self) -> None:
        """The program-counter loop. Plain blocks take the fast path (straight to ``execute``); the budget
        of ``max_blocks`` is charged in bulk whenever control leaves the fast path (a straight run through
        a program is finite, so only jumps, loops and calls need the check)."""
        core = self.core
        st = core.state
        execute = core.execute
        skip_mask = st.skip_mask
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
                if st.flow_request is None and not st.ended:
                    continue
                slow = False
            else:
                slow = True
            budget -= pc - mark
            if budget < 0:
                runaway = self.dialect.error(
                    f"more than {self.options.max_blocks} blocks executed: a runaway loop? "
                    "(raise max_blocks if the program is really this long)",
                    "too-many-blocks",
                )
                raise runaway.located(unit.file, block.line)
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
        is checked in the loop itself. Also called through the seam's ``check_budget`` by blocks that make
        many moves (cycles.emit, NURBS curves)."""
        options = self.options
        if len(self.core.state.builder) > options.max_segments:
            raise self.dialect.error(f"the tool path has more than {options.max_segments} segments (raise "
                                     "max_segments if the program is really this long)", "segment-budget")
        if time.process_time() > self._deadline:
            raise self.dialect.error(f"interpretation took more than {options.max_seconds:g} s of CPU time "
                                     "(a runaway loop? raise max_seconds if the program is really this long)",
                                     "time-budget")  # fmt: skip

    def _special(self, block: Block, pc: int) -> int:
        kind = block.kind
        if kind == "assign" or kind == "stmt":
            self.core.state.out.line = block.line  # for #3006's stop and #4113/#4114
        if kind == "assign":
            target, value = block.assign
            variables = self._variables
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

        "A block containing a move command" (§3.7.6) is read from the block itself — a non-null axis word
        not taken by a code that only sets something (G04 G10 G52 G92 G51 G68 G50.1 G51.1) — or from the
        segments it produced (a move with no axis word of its own). The segments alone would miss moves
        that cutter compensation's look-ahead emits a block later."""
        core = self.core
        builder = core.state.builder
        before = len(builder)
        core.execute(block)
        moved = bool(self.modal_calls) and (
            self._has_move_command(block) or any(k != _DWELL for k in builder.kinds_since(before))
        )
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
                value = evaluate(value, self._variables, self.dialect)
                if value is None:
                    continue  # a null word is dropped (§3.7.2)
            if letter == "G":
                spec = self.dialect.gcodes.get(gkey(value))
                if spec is not None and spec.action in _SETTING_ACTIONS:
                    return False
            else:
                has_axis = True
        return has_axis

    def _after(self, block: Block, pc: int, *, moved: bool) -> int:
        core = self.core
        if core.state.ended:
            self._count_part()
            return -1
        request = core.state.flow_request
        core.state.flow_request = None
        if request is not None:
            if request[0] == "call":
                return self._push_subprogram(request[1], request[2], pc, by_code=False)
            if request[0] == "local":
                return self._push_subprogram(request[1], request[2], pc, by_code=False, local=True)
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
        system = self._variables.system
        if system is not None:
            system.count_part()

    # ------------------------------------------------------------------ statements
    def _statement(self, block: Block, pc: int) -> int:
        stmt = block.stmt
        op = stmt[0]
        variables = self._variables
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
        value = evaluate(target_node, self._variables, self.dialect)
        number = self._sequence_number(value, "GOTO")
        target = unit.find(number, here + 1)
        if target is None:
            raise self.dialect.error(f"GOTO{number}: no block N{number} in {unit.name}", "sequence-not-found")
        if not unit.loops(self.dialect).may_jump(here, target):
            raise self.dialect.error(
                f"GOTO{number} jumps into a DO range (only jumps out of one are allowed, GSK 25i §3.7.5)",
                "do-end",
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
            self._directory = self.options.program_files(self.main_program.file)
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
        outside = self.options.leaves_folder(path, self.main_program.file)
        if outside is not None:
            raise self.dialect.error(f"program O{number:04d}: {outside}", "program-not-found")
        try:
            raw = read_regular_file(path, limit=MAX_PROGRAM_BYTES, what="a called program")
        except OSError as exc:
            raise self.dialect.error(
                f"program O{number:04d}: cannot read {path} ({exc.strerror or exc})", "program-not-found"
            ) from None
        except ConfigError as exc:  # not a regular file, or over the size limit
            raise self.dialect.error(f"program O{number:04d}: {exc}", "program-not-found") from None
        try:
            text = raw.decode("utf-8-sig")
        except UnicodeDecodeError:
            text = raw.decode("latin-1")
        if self.reader is None:
            self.reader = self.dialect.language.reader(self.dialect, self.calls)
            self.reader.max_blocks = self.options.max_blocks
        program = self.reader.read(text, str(path))
        builder = self.core.state.builder
        for line, level, message, code in program.notices:
            builder.notice(notice_line(str(path), line, message, code, level))
        file_index = builder.file_index(str(path))
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
        self.core.state.out.file_index = unit.file_index
        self.core.state.file = unit.file

    # ------------------------------------------------------------------ subprograms (M98 / M99)
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
                self._variables.locals = dict(frame.args)
            return frame.unit.start
        self.frames.pop()
        if frame.macro:
            self._variables.pop_locals()
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
