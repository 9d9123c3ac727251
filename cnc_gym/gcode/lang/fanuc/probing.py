"""G31 skip function of the Fanuc family, with a simulated probe (``interpret(..., skip_signal=)``).

Sections (§n) are those of the GSK 25i programming manual.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cnc_gym.toolpath import SegmentMode

if TYPE_CHECKING:
    from cnc_gym.gcode.codes import CodeSpec
    from cnc_gym.gcode.dialect import Seam


def skip(core: Seam, spec: CodeSpec, values: dict) -> None:
    """``G31 IP_`` (§3.2.8): a feed move like G01 that stops on the skip signal, then the next block
    runs from there (incremental from the break point; an absolute block moves only its own axes, §3.2.8).
    The signal is simulated (``Interpreter.skip_signal``: program coordinate → the probe's surface per
    axis): the move stops where it first reaches one of them; with none reached (or no signal configured)
    the move completes. #5061-#5063 get the stop point (the block end without a signal, §3.7.3), in work
    coordinates (``Interpreter.skip_position``, mm). Feed override is disabled on the move (§3.2.8:
    override, dry run and acc/dec off unless 1940#7 SKF): the segment is flagged OVERRIDE_LOCKED. Not
    allowed with cutter compensation (alarm 36)."""
    roles = core.dialect.roles
    if core.state.modal.get(roles.cutter_group, roles.cutter_cancel) != roles.cutter_cancel:  # type: ignore[arg-type]
        raise core.error("G31 in cutter compensation mode (cancel it with G40 first, GSK 25i §3.2.8)",
                         "g31-in-cutter-compensation")  # fmt: skip
    letters = core.dialect.axes
    target = core.resolve_target(*(values.get(letter) for letter in letters))
    if target != (None, None, None):
        start = core.program_position
        full = [start[a] if t is None else t for a, t in enumerate(target)]
        first = 1.0
        for letter, surface in core.state.skip_signal.items():
            a = letters.index(letter)
            travel = full[a] - start[a]
            if travel and 0.0 <= (surface - start[a]) / travel <= first:
                first = (surface - start[a]) / travel
        if first < 1.0:  # the signal stops the move there: every axis at the same fraction (a straight move)
            target = (start[0] + first * (full[0] - start[0]), start[1] + first * (full[1] - start[1]),
                      start[2] + first * (full[2] - start[2]))  # fmt: skip
        out = core.state.out
        modes = out.modes
        out.modes = modes | SegmentMode.OVERRIDE_LOCKED | (SegmentMode.EXACT_STOP if first < 1.0 else 0)
        try:
            core.move_linear(False, target)
        finally:
            out.modes = modes
    core.state.skip_position = core.program_position


ACTIONS = {"skip": skip}
