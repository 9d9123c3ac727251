"""Syntec 8.20's subprogram calls (Syntec 8.20 mill programming manual §M code description, M98/M99) on
the Fanuc family's runner (``lang/fanuc/flow.py``, ``calls.py``):

* ``M98 P_ H_ L_``: P the program (left out: this program), H the sequence number to start at ("the number
  of ranking in specified program"), L the repeat count. The manual's examples call ``M98 H100`` — a
  block ``N100`` of the same file, placed after M30/M02 so it never runs in sequence — and return with
  M99;
* ``M99 P_``: back to the caller's block ``N_`` (the family's);
* G65/G66/G67 are the family's macro calls (P program, L repeats, argument words).

A label call runs the program from its block Nh to the end of that program (or its M99), repeated L
times; errors are reported with the dialect's own alarm numbers (only MAR-330..336 have one).
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.gcode.dialects.syntec.options import data
from cnc_gym.gcode.lang.fanuc.flow import FlowRunner
from cnc_gym.gcode.lang.fanuc.units import Frame, Unit

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam
    from cnc_gym.gcode.program import Block
    from cnc_gym.gcode.settings import FlowOptions


class SyntecRunner(FlowRunner):
    """The family's runner with label calls (``M98 H_``) and Syntec's alarm numbers."""

    def __init__(self, core: Seam, options: FlowOptions | None = None) -> None:
        super().__init__(core, options)
        self._whole: dict[int, Unit] = {}  # id of a label section → the program unit it is part of

    def run(self) -> None:
        try:
            super().run()
        except ProgramError as err:
            # The family's checks pass their reference controller's alarm numbers; Syntec numbers only
            # the MAR alarms of automatic tool length measurement.
            err.alarm = self.dialect.alarms.get(err.code)
            raise

    def subprogram_call(self, values: dict) -> None:
        """``M98 [P_] [H_] [L_]`` (module docstring)."""
        label = data(self.core).call_label
        data(self.core).call_label = None
        number = None
        if "P" in values:
            p = values["P"]
            if p != int(p) or not 1 <= p <= 9999:
                raise self.dialect.error(f"M98 P{p:g}: P is a program number 1..9999 (repeats: L)",
                                         "bad-call")  # fmt: skip
            number = int(p)
        elif label is None:
            raise self.dialect.error("M98 needs P (a program) or H (a sequence number of this program)",
                                     "missing-program-number")  # fmt: skip
        count = int(values.get("L", 1))
        if label is not None:
            label = self._sequence_number(label, "M98 H")
        self.core.state.flow_request = ("call_label", number, label, count)

    def _after(self, block: Block, pc: int, *, moved: bool) -> int:
        request = self.core.state.flow_request
        if request is None or request[0] != "call_label" or self.core.state.ended:
            return super()._after(block, pc, moved=moved)
        self.core.state.flow_request = None
        _, number, label, count = request
        if label is None:
            return self._push_subprogram(number, count, pc, by_code=False)
        return self._push_label(number, label, count, pc)

    def _push_label(self, number: int | None, label: int, count: int, pc: int) -> int:
        """Run program ``number`` (None: the calling program) from its block N``label``, ``count`` times."""
        if count == 0:
            return pc
        if self._sub_depth >= self.dialect.max_subprogram_nesting:
            raise self.dialect.error(f"M98 H{label}: subprograms nest at most "
                                     f"{self.dialect.max_subprogram_nesting} levels", "nesting")  # fmt: skip
        caller = self.frames[-1]
        unit = self._whole.get(id(caller.unit), caller.unit) if number is None else self.unit(number)
        start = unit.find(label, unit.start)
        if start is None:
            raise self.dialect.error(f"M98 H{label}: no block N{label} in {unit.name}", "sequence-not-found")
        # The section from N<label> to the end of its program, as a unit of its own (sequence numbers and
        # DO/END pairs are looked up inside it; a nested label call searches the whole program again).
        view = SimpleNamespace(blocks=unit.blocks, file=unit.file)
        section = Unit(view, unit.number, start, unit.end, unit.file_index)  # type: ignore[arg-type]
        self._whole[id(section)] = unit
        self._sub_depth += 1
        return self._enter(Frame(section, pc, count - 1, subprogram=True, modal_limit=caller.modal_limit,
                                 by_code=caller.by_code))  # fmt: skip

    def _return(self, pc: int, target: int | None) -> int:
        if len(self.frames) == 1 and self.options.main_m99 == "end":
            data(self.core).ended_by_code = True
        return super()._return(pc, target)


def subprogram_call(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M98 (module docstring): the call runs after the block's other commands."""
    core.state.flow.subprogram_call(values)


ACTIONS = {"subprogram_call": subprogram_call}
