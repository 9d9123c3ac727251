"""The Fanuc family's call convention: M98/M99 subprograms, G65/G66/G67 macro calls, calls by G, M and T
code (GSK 25i programming manual §1.3.1 subprograms, §3.7.6 macro calls).

* ``M98 P[count]oooo [L count]`` runs program O-oooo after the block's other commands; ``M99 [P n]``
  returns (to block Nn of the caller with P). A subprogram shares the caller's locals.
* ``G65 P L <arguments>`` pushes a new #1-#33 level holding the arguments (specifications I and II) and
  runs the program L times; ``G66`` arms a modal call run after every later block that moves; ``G67``
  drops the latest.
* Codes mapped by :class:`~cnc_gym.gcode.settings.MacroCalls` call like G65 (G and M codes), like M98
  (M codes) or as ``#149 = t; M98 P<t_sub>`` (T).

:class:`CallConvention` is the part of the runner (``flow.FlowRunner``) that carries these out; the
actions at the end are what the code tables name.

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from cnc_gym.errors import ProgramError
from cnc_gym.gcode.lang.fanuc.expressions import evaluate
from cnc_gym.gcode.lang.fanuc.units import Frame, ModalCall, Unit
from cnc_gym.gcode.program import Block, WordBlock

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Dialect, Seam
    from cnc_gym.gcode.lang.fanuc.variables import VariableStore
    from cnc_gym.gcode.settings import MacroCalls

#: Argument specification I (§3.7.6): address → local variable.
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


class CallConvention:
    """The call side of the runner: parses call blocks, pushes and pops frames (module docstring)."""

    core: Seam
    dialect: Dialect
    calls: MacroCalls
    frames: list[Frame]
    modal_calls: list[ModalCall]
    _sub_depth: int
    _macro_depth: int
    _variables: VariableStore

    def unit(self, number: int) -> Unit:
        raise NotImplementedError

    def _enter(self, frame: Frame) -> int:
        raise NotImplementedError

    def _ordinary(self, block: Block, pc: int) -> int:
        raise NotImplementedError

    def _count_part(self) -> None:
        raise NotImplementedError

    def _sequence_number(self, value: float | None, what: str) -> int:
        raise NotImplementedError

    def _find_in(self, unit: Unit, number: int, after: int) -> int:
        raise NotImplementedError

    def subprogram_call(self, values: dict) -> None:
        """M98 P[count]oooo [L count]: called after the block's other commands (§3.7.6)."""
        if "P" not in values:
            raise self.dialect.error("M98 needs P (the program number)", "missing-program-number")
        number, count = self._program_and_count(values, "M98")
        self.core.state.flow_request = ("call", number, count)

    def _program_and_count(self, values: dict, what: str) -> tuple[int, int]:
        """P and L of M98: with 4-digit program numbers a repeat count may lead P (``P51002``: O1002 five
        times); with longer program numbers (the O address's range, e.g. Fanuc's 8 digits) P is the number
        and only L counts."""
        p = values["P"]
        top = int(self.dialect.addresses["O"].high)
        if top > 9999:
            if p != int(p) or not 1 <= p <= top:
                raise self.dialect.error(f"{what} P{p:g}: P is a program number 1..{top} (repeats: L)",
                                         "bad-call")  # fmt: skip
            count = int(values.get("L", 1))
            if not 0 <= count <= 9999:
                raise self.dialect.error(f"{what} L{count}: the repeat count is 0..9999", "bad-call")
            return int(p), count
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
            raise self.dialect.error(f"{what} P{p}: at most 999 repeats (GSK 25i §1.3)", "bad-call")
        return number, max(count, 1)

    def _push_subprogram(self, number: int, count: int, pc: int, *, by_code: bool,
                         local: bool = False) -> int:  # fmt: skip
        """Enter program O``number`` (M98), or with ``local`` the running program from its block N``number``
        on (Haas M97: a frame over the same blocks; its M99 returns after the calling block), ``count``
        times."""
        if count == 0:
            return pc  # L0: not called
        if self._sub_depth >= self.dialect.max_subprogram_nesting:
            raise self.dialect.error(
                f"{'M97' if local else 'M98'} P{number}: subprograms nest at most "
                f"{self.dialect.max_subprogram_nesting} levels (GSK 25i §1.3)",
                "nesting",
            )
        caller = self.frames[-1]
        if local:
            unit = caller.unit.local(self._find_in(caller.unit, number, caller.unit.start))
        else:
            unit = self.unit(number)
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

    def local_subprogram_call(self, values: dict) -> None:
        """Haas M97 P<n> [L count]: the blocks from sequence number Nn of the running program on, up to an
        M99, as a subprogram (called after the block's other commands, like M98), L times."""
        if "P" not in values:
            raise self.dialect.error("M97 needs P (the sequence number where the local subprogram starts)",
                                     "bad-call")  # fmt: skip
        number = self._sequence_number(values["P"], "M97 P")
        count = values.get("L", 1.0)
        if count != int(count) or not 0 <= count <= 9999:
            raise self.dialect.error(f"M97 L{count:g}: the repeat count is 0..9999", "bad-call")
        self.core.state.flow_request = ("local", number, int(count))

    def subprogram_return(self, values: dict) -> None:
        """M99 [P n]: back to the caller (to its block Nn with P); in the main program see FlowOptions."""
        target = None
        if "P" in values:
            target = self._sequence_number(values["P"], "M99 P")
        self.core.state.flow_request = ("return", target)


    def _call_block(self, block: Block, pc: int) -> int:
        """A block holding G65, G66 or a G/M/T code the dialect maps to a call."""
        core = self.core
        roles = self.dialect.roles
        if core.state.nurbs.hpcc and core.state.modal.get(1) == roles.nurbs:  # G06.2 in force (nurbs.py)
            raise self.dialect.error("a macro or subprogram call in NURBS mode: no G, M or T codes until a "
                                     "group-01 code ends G06.2 (GSK 25i §3.2.5)",
                                     "nurbs-forbidden")  # fmt: skip
        words = self._evaluated(block.words)
        frame = self.frames[-1]
        gs = [w[1] for w in words if w[0] == "G"]
        ms = [w[1] for w in words if w[0] == "M"]
        calls = self.calls
        one_shot = None if roles.macro_call is None else roles.macro_call / 10  # G65
        modal = None if roles.modal_call is None else roles.modal_call / 10  # G66
        if one_shot in gs or modal in gs:
            code = one_shot if one_shot in gs else modal
            if one_shot in gs and modal in gs:
                raise self.dialect.error(f"G{one_shot:g} and G{modal:g} in one block", "group-conflict")
            others = [g for g in gs if g != code]
            if others:
                raise self.dialect.error(
                    f"G{code:g} takes no other G code in its block (G{others[0]:g}); the "
                    "words after it are arguments",
                    "bad-call",
                )
            values = {w[0]: w[1] for w in words if w[0] in "PL"}
            if "P" not in values:
                raise self.dialect.error(
                    f"G{code:g} needs P (the macro program number)", "missing-program-number"
                )
            number, count = self._macro_program(values, f"G{code:g}")
            args = self._arguments(words)
            if code == one_shot:
                return self._push_macro(
                    number, count, args, pc, modal_limit=frame.modal_limit, by_code=frame.by_code
                )
            self.unit(number)  # alarm 59 now, not at the first move
            self.modal_calls.append(ModalCall(number, count, args))
            core.state.modal[roles.modal_call_group] = roles.modal_call  # type: ignore[index,assignment]
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
                    # N_ G_ X_ Y_ … Mxx ≡ N_ G_ X_ Y_ … M98 Pxxxx: the block's other commands first (§3.7.6).
                    pc = self._run_without(strict, pc, "M", m)
                    if pc < 0:
                        return pc
                    return self._push_subprogram(calls.m_sub[int(m)], 1, pc, by_code=True)
            if calls.t_sub is not None:
                t = next((w[1] for w in words if w[0] == "T"), None)
                if t is not None:
                    # Tt ≡ #149=t; … M98 P9000 (§3.7.6).
                    core.state.variables.write(149.0, t)
                    pc = self._run_without(strict, pc, "T", None)
                    if pc < 0:
                        return pc
                    return self._push_subprogram(calls.t_sub, 1, pc, by_code=True)
        # A mapped code inside a program called by a code: an ordinary block (§3.7.6).
        strict = block.stmt[1]
        if isinstance(strict, ProgramError):
            raise strict
        if strict is None:
            return pc
        return self._ordinary(strict, pc)

    def _run_without(self, block: Block | None, pc: int, letter: str, value: float | None) -> int:
        """The block's other words, before a subprogram call by M or T code (§3.7.6)."""
        if block is None:
            return pc
        kept = tuple(w for w in block.words if not (w[0] == letter and (value is None or w[1] == value)))
        if not kept:
            return pc
        core = self.core
        core.execute(WordBlock(block.line, kept, skip=0, has_expr=True, number=block.number))
        if core.state.ended:
            self._count_part()
            return -1
        if core.state.flow_request is not None:
            core.state.flow_request = None
            raise self.dialect.error(
                f"M98/M99 cannot share a block with {letter}, which calls a subprogram here", "bad-call"
            )
        return pc

    def _evaluated(self, words: Sequence) -> list[tuple[str, float]]:
        """Call-block words → (letter, value) in order; a null variable drops its word (§3.7.2)."""
        out = []
        variables = self._variables
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
        top = max(9999, int(self.dialect.addresses["O"].high))
        if p != int(p) or not 1 <= p <= top:
            raise self.dialect.error(f"{what} P{p:g}: the macro program number is 1..{top}", "bad-call")
        count = 1
        if "L" in values:
            count = values["L"]
            if count != int(count) or not 1 <= count <= 9999:
                raise self.dialect.error(
                    f"{what} L{count:g}: the repeat count is 1..9999 (GSK 25i §3.7.6)", "bad-call"
                )
        return int(p), int(count)

    def _arguments(self, words: list, *, pl_is_error: bool = False) -> dict[int, float]:
        """Argument specifications I and II, mixed freely; a later word for the same variable wins
        (§3.7.6). I/J/K: a letter not after the previous one of its group starts the next group."""
        args: dict[int, float] = {}
        group = 0
        last = 3
        for letter, value in words:
            if letter in "GNO" or (letter in "PL" and not pl_is_error):
                continue
            if letter in "PL" and pl_is_error:
                raise self.dialect.error(f"address {letter} cannot be a macro argument (GSK 25i §3.7.6)",
                                         "bad-call")
            k = _IJK.get(letter)
            if k is not None:
                if k <= last:
                    group += 1
                    if group > 10:
                        raise self.dialect.error("more than 10 I/J/K argument groups (GSK 25i §3.7.6)",
                                                 "bad-call")
                last = k
                args[4 + 3 * (group - 1) + k] = value
                continue
            index = ARGUMENT_SPEC_I.get(letter)
            if index is None:
                raise self.dialect.error(f"address {letter} cannot be a macro argument (GSK 25i §3.7.6)",
                                         "bad-call")
            args[index] = value
        return args

    def _push_macro(
        self, number: int, count: int, args: dict[int, float], pc: int, *, modal_limit: int, by_code: bool
    ) -> int:
        if self._macro_depth >= self.dialect.max_macro_nesting:
            raise self.dialect.error(
                f"O{number:04d}: macro calls nest at most {self.dialect.max_macro_nesting} levels (GSK 25i "
                "§3.7.6)",
                "nesting",
            )
        unit = self.unit(number)
        self._macro_depth += 1
        self._variables.push_locals(args)
        return self._enter(
            Frame(unit, pc, count - 1, macro=True, modal_limit=modal_limit, by_code=by_code, args=args)
        )

    def cancel_modal_call(self) -> None:
        """G67: the latest G66 ends (§3.7.6)."""
        if self.modal_calls:
            self.modal_calls.pop()
        roles = self.dialect.roles
        key = roles.modal_call if self.modal_calls else roles.modal_call_cancel
        self.core.state.modal[roles.modal_call_group] = key  # type: ignore[index,assignment]

    def macro_call_from_variable(self, spec) -> None:
        raise self.dialect.error(
            f"{spec.name} must be written as a literal code (its block's words are arguments)", "bad-call"
        )


# ---------------------------------------------------------------------- actions
def subprogram_call(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M98: the call runs after the block's other commands."""
    core.state.flow.subprogram_call(values)


def local_subprogram_call(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M97 (Haas): a local subprogram call, run after the block's other commands."""
    core.state.flow.local_subprogram_call(values)


def subprogram_return(core: Seam, spec: CodeSpec, values: dict) -> None:
    """M99: back to the caller."""
    core.state.flow.subprogram_return(values)


def macro_call(core: Seam, spec: CodeSpec, values: dict) -> None:
    """G65/G66 reach an action only when written from a variable (``G#1``): refused (the reader sends
    literal G65/G66 blocks to the runner as call blocks)."""
    core.state.flow.macro_call_from_variable(spec)


def modal_call_cancel(core: Seam, spec: CodeSpec, values: dict | None = None) -> None:
    """G67: the latest G66 ends."""
    core.state.flow.cancel_modal_call()


ACTIONS = {"subprogram_call": subprogram_call, "subprogram_return": subprogram_return,
           "local_subprogram_call": local_subprogram_call,
           "macro_call": macro_call, "modal_call_cancel": modal_call_cancel}  # fmt: skip
