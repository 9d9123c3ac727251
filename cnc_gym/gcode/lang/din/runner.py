"""Program flow of the DIN family: the program-counter loop, the compiled control blocks (``control.py``),
parameter assignments and subroutine calls (AMK AZ-MC1 programming manual §7 "Subroutines", §9).

* ``LL<n>`` calls the local subroutine ``%L<n>`` of the running file; only the main program of a file
  calls its local subroutines (§7.1). A local subroutine ends with M29 or at the next ``%``.
* ``L<n>`` calls the *file* named n (``100``, ``100.nc`` …, in ``program_dir`` or the main program's
  folder): its main program (after its own local subroutines) is the global subroutine; it must end with
  M29 (§7.2). Data passes through the global R parameters; there are no arguments.
* Subroutines nest at most :data:`MAX_NESTING` deep (§7); M30 or M02 anywhere ends the whole program (§2.2,
  §12.3), and so does the end of the main program's text.

Bounds: ``max_blocks`` executed blocks (an endless ``$WHILE`` ends with ``too-many-blocks``),
``max_seconds`` of CPU time (``time-budget``), ``max_segments`` tool-path segments (``segment-budget``).
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import TYPE_CHECKING, cast

from cnc_gym.errors import ConfigError, ProgramError
from cnc_gym.files import MAX_PROGRAM_BYTES, read_regular_file
from cnc_gym.gcode.lang.din.expressions import truth, value
from cnc_gym.gcode.settings import FlowOptions

if TYPE_CHECKING:
    from cnc_gym.gcode.dialect import Seam
    from cnc_gym.gcode.lang.din.parameters import ParameterStore
    from cnc_gym.gcode.lang.din.reader import DinProgram
    from cnc_gym.gcode.program import Block

#: Subroutine levels below the main program (§7: "a maximum depth of 10").
MAX_NESTING = 10
#: ``$CASE`` matches when |case − switch| is below this (§9.1.2 "the absolute difference is < 0.00…"; the
#: conversion lost the last digit: we take the entry resolution of 4 decimal places).
CASE_TOLERANCE = 1e-4
#: File names a global call ``L<n>`` finds, besides the bare number (leading zeros allowed).
PROGRAM_SUFFIXES = ("", ".nc", ".din", ".txt", ".mpf", ".cnc")
_CHECK_EVERY = 10_000


class Unit:
    """One program unit: the main program of a file, a local subroutine, or a global subroutine file."""

    __slots__ = ("blocks", "end", "file", "file_index", "kind", "name", "program", "start")

    def __init__(self, program: DinProgram, start: int, end: int, kind: str, name: str,
                 file_index: int) -> None:  # fmt: skip
        self.program = program
        self.blocks = program.blocks
        self.file = program.file
        self.start = start
        self.end = end
        self.kind = kind  # "main" | "local" | "global"
        self.name = name
        self.file_index = file_index


class DinRunner:
    """The DIN family's :attr:`Language.runner` (module docstring)."""

    def __init__(self, core: Seam, options: FlowOptions | None = None) -> None:
        self.core = core
        self.options = options or FlowOptions()
        self.dialect = core.dialect
        st = core.state
        program = cast("DinProgram", st.program)
        number = getattr(program, "program_number", None)
        name = f"%{number}" if number is not None else "the main program"
        self.main = Unit(program, program.main[0], program.main[1], "main", name, 0)
        self.frames: list[tuple[Unit, int]] = [(self.main, -1)]
        self.store = cast("ParameterStore", st.variables)
        self._files: dict[int, DinProgram] = {}
        self._directory: dict[int, Path] | None = None
        self._deadline = time.process_time() + self.options.max_seconds
        st.flow = self
        st.flow_request = None

    # ------------------------------------------------------------------ the loop
    def run(self) -> None:
        """The program-counter loop: plain blocks go straight to the core; the budget of ``max_blocks`` is
        charged in bulk whenever control leaves the straight path."""
        core = self.core
        st = core.state
        execute = core.execute
        skip_mask = st.skip_mask
        budget = self.options.max_blocks
        next_check = budget - _CHECK_EVERY
        unit = self.main
        blocks, end = unit.blocks, unit.end
        pc = mark = unit.start
        while True:
            if pc >= end:
                budget -= pc - mark
                try:
                    pc = self._fall_off(unit)
                except ProgramError as err:
                    last = blocks[end - 1].line if end > unit.start else 0
                    raise err.located(unit.file, last) from None
                if pc < 0:
                    return
                mark = pc
                unit = self.frames[-1][0]
                blocks, end = unit.blocks, unit.end
                continue
            block = blocks[pc]
            pc += 1
            if block.skip & skip_mask:
                continue
            if block.kind is None:
                try:
                    execute(block)
                except ProgramError as err:
                    raise err.located(unit.file, block.line) from None
                if st.flow_request is None and not st.ended:
                    continue
            budget -= pc - mark
            if budget < 0:
                raise self.dialect.error(f"more than {self.options.max_blocks} blocks executed: an endless "
                                         "loop? (raise max_blocks if the program is really this long)",
                                         "too-many-blocks").located(unit.file, block.line)  # fmt: skip
            try:
                if budget < next_check:
                    next_check = budget - _CHECK_EVERY
                    self.check_bounds()
                pc = self._special(block, pc, unit)
            except ProgramError as err:
                raise err.located(unit.file, block.line) from None
            if pc < 0:
                return
            mark = pc
            unit = self.frames[-1][0]
            blocks, end = unit.blocks, unit.end

    def check_bounds(self) -> None:
        """The CPU-time and segment bounds (``max_seconds``, ``max_segments``)."""
        options = self.options
        if len(self.core.state.builder) > options.max_segments:
            raise self.dialect.error(f"the tool path has more than {options.max_segments} segments (raise "
                                     "max_segments if the program is really this long)", "segment-budget")
        if time.process_time() > self._deadline:
            raise self.dialect.error(f"interpretation took more than {options.max_seconds:g} s of CPU time "
                                     "(an endless loop? raise max_seconds if the program is really this "
                                     "long)", "time-budget")  # fmt: skip

    # ------------------------------------------------------------------ blocks that are not plain
    def _special(self, block: Block, pc: int, unit: Unit) -> int:
        st = self.core.state
        kind = block.kind
        if kind == "stmt":
            st.out.line = block.line
            return self._statement(block.stmt, pc)
        if kind == "assign":
            st.out.line = block.line
            store = self.store
            for (letter, index), expression, _text in block.assign:
                store[self._target(letter, index)] = value(expression, store)
            inner = block.stmt[1]
            if inner is None:
                return pc
            self.core.execute(inner)
        elif kind == "call":
            where, number, inner = block.stmt
            if inner is not None:
                self.core.execute(inner)
            if not st.ended and st.flow_request is None:
                return self._call(where, number, pc, unit)
        return self._after(pc, unit)

    def _after(self, pc: int, unit: Unit) -> int:
        """A block ended the program (M30/M02) or its subroutine (M29)."""
        st = self.core.state
        if st.ended:
            return -1
        request = st.flow_request
        st.flow_request = None
        if request is not None and request[0] == "return":
            if unit.kind == "main":
                raise self.dialect.error("M29 ends a subroutine; the main program ends with M30 or M02",
                                         "bad-subroutine-end")  # fmt: skip
            return self._return()
        return pc

    def _target(self, letter: str, index) -> int:
        store = self.store
        if letter == "P":
            return store.number(store[index], f"P{index} → R")
        if isinstance(index, int):
            return index
        return store.number(value(index, store))

    def _statement(self, op: tuple, pc: int) -> int:
        store = self.store
        kind = op[0]
        if kind == "jump":
            return op[1]
        if kind == "nop":
            return pc
        if kind == "while":
            return pc if truth(value(op[1], store)) else op[2]
        if kind == "enddo":
            return op[2] if truth(value(op[1], store)) else pc
        if kind == "if":
            for condition, body in op[1]:
                if truth(value(condition, store)):
                    return body
            return op[2]
        if kind == "for":
            _, (letter, index), first, last, step, exit_pc = op
            target = self._target(letter, index)
            store[target] = value(first, store)
            return pc if self._for_test(store[target], last, step) else exit_pc
        if kind == "endfor":
            _, (letter, index), last, step, body = op
            target = self._target(letter, index)
            store[target] = store[target] + value(step, store)
            return body if self._for_test(store[target], last, step) else pc
        if kind == "switch":
            selector = value(op[1], store)
            for case, body in op[2]:
                if abs(value(case, store) - selector) < CASE_TOLERANCE:
                    return body
            return op[3]
        if kind == "time":
            seconds = value(op[1], store)
            if seconds < 0:
                raise self.dialect.error(f"$TIME {seconds:g}: a dwell time cannot be negative", "bad-dwell")
            self.core.state.out.dwell(seconds)
            return pc
        if kind == "proc":
            store.procedure(op[1], value(op[2], store))
            return pc
        raise AssertionError(f"unknown control op {op!r}")  # pragma: no cover

    def _for_test(self, current: float, last, step) -> bool:
        store = self.store
        increment = value(step, store)
        if increment == 0.0:
            raise self.dialect.error("$FOR with step 0 never ends", "control-structure")
        bound = value(last, store)
        return current <= bound if increment > 0 else current >= bound

    # ------------------------------------------------------------------ calls
    def _call(self, where: str, number: int, pc: int, unit: Unit) -> int:
        if len(self.frames) > MAX_NESTING:
            raise self.dialect.error(f"subroutines nest at most {MAX_NESTING} levels deep (AMK AZ-MC1 "
                                     "programming manual §7)", "nesting")  # fmt: skip
        if where == "local":
            if unit.kind == "local":
                raise self.dialect.error(f"LL{number}: local subroutines are called from the main program of "
                                         "their file only (AMK AZ-MC1 programming manual §7.1)",
                                         "bad-call")  # fmt: skip
            span = unit.program.local_units.get(number)
            if span is None:
                raise self.dialect.error(f"LL{number}: no local subroutine %L{number} in {unit.file}",
                                         "program-not-found")  # fmt: skip
            callee = Unit(unit.program, span[0], span[1], "local", f"%L{number}", unit.file_index)
        else:
            program = self._load(number)
            index = self.core.state.builder.file_index(program.file)
            callee = Unit(program, program.main[0], program.main[1], "global", f"L{number}", index)
        self.frames.append((callee, pc))
        self._set_file(callee)
        return callee.start

    def _return(self) -> int:
        _callee, return_pc = self.frames.pop()
        self._set_file(self.frames[-1][0])
        return return_pc

    def _fall_off(self, unit: Unit) -> int:
        """The end of a unit's blocks without M29/M30: a local subroutine returns (the next ``%`` ends it);
        a global one must end with M29 (§7.2: "M29 must stand here"); the end of the main program's text
        ends the run (the manual asks for M30 or M02; the project accepts a program without one, as for
        every dialect, so snippets stay usable: docs/gcode.md)."""
        if unit.kind == "local":
            return self._return()
        if unit.kind == "global":
            raise self.dialect.error(f"global subroutine {unit.file} must end with M29 (AMK AZ-MC1 "
                                     "programming manual §7.2)", "bad-subroutine-end")  # fmt: skip
        return -1

    def _set_file(self, unit: Unit) -> None:
        st = self.core.state
        st.out.file_index = unit.file_index
        st.file = unit.file

    def _directory_files(self) -> dict[int, Path]:
        """Program number → file: the folder's files named by a number with a program suffix."""
        if self._directory is None:
            found: dict[int, Path] = {}
            for name, path in self.options.program_files(self.main.file).items():
                stem, suffix = os.path.splitext(name)
                if suffix in PROGRAM_SUFFIXES and stem.isdigit():
                    found.setdefault(int(stem), path)
            self._directory = found
        return self._directory

    def _load(self, number: int) -> DinProgram:
        program = self._files.get(number)
        if program is not None:
            return program
        path = self._directory_files().get(number)
        if path is None:
            where = self.options.program_dir or "the main program's folder"
            raise self.dialect.error(f"L{number}: no program file named {number} in {where}",
                                     "program-not-found")  # fmt: skip
        outside = self.options.leaves_folder(path, self.main.file)
        if outside is not None:
            raise self.dialect.error(f"L{number}: {outside}", "program-not-found")
        try:
            raw = read_regular_file(path, limit=MAX_PROGRAM_BYTES, what="a called program")
        except OSError as exc:
            raise self.dialect.error(f"L{number}: cannot read {path} ({exc.strerror or exc})",
                                     "program-not-found") from None  # fmt: skip
        except ConfigError as exc:  # not a regular file, or over the size limit
            raise self.dialect.error(f"L{number}: {exc}", "program-not-found") from None
        text = raw.decode("latin-1")
        reader = self.dialect.language.reader(self.dialect, None)
        reader.max_blocks = self.options.max_blocks
        program = cast("DinProgram", reader.read(text, str(path)))
        self._files[number] = program
        return program


__all__ = ["CASE_TOLERANCE", "MAX_NESTING", "DinRunner", "Unit"]
